//! Reliability that only a process of its own can show: a stage killed mid-write, run under a
//! file-size or memory limit, or read on its stderr (what it says first, and before a long
//! run). Each stage runs as its binary would (`util::stage_process`).

use crate::util::{compile_text, limited_stage_process, stage_process, TempDir};
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

/// A small open scene with two floor sensors, for runs that only need to start.
const PLAIN: &str = r#"Scene(
    materials: { "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) },
    objects: [(name: "floor", shape: Quad(corner: (0.0, 0.0, 0.0), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, -1.0)), material: "w")],
    point_lights: [(position: (0.5, 1.0, -0.5), power: Intensity(10.0))],
    sensors: [Points(name: "s", points: [(position: (0.5, 0.0, -0.5), normal: (0.0, 1.0, 0.0)), (position: (0.2, 0.0, -0.2), normal: (0.0, 1.0, 0.0))])],
)"#;

/// The lines the child writes on stderr, as they come (a thread reads them).
fn stderr_lines(child: &mut Child) -> std::sync::mpsc::Receiver<String> {
    let stderr = child.stderr.take().expect("stderr piped");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    rx
}

/// The first line containing `needle` within `timeout`, with every line before it.
fn wait_for_line(
    lines: &std::sync::mpsc::Receiver<String>,
    needle: &str,
    timeout: Duration,
) -> (Option<String>, Vec<String>) {
    let deadline = Instant::now() + timeout;
    let mut before = Vec::new();
    loop {
        match lines.recv_timeout(deadline.saturating_duration_since(Instant::now())) {
            Ok(l) if l.contains(needle) => return (Some(l), before),
            Ok(l) => before.push(l),
            Err(_) => return (None, before),
        }
    }
}

/// Ends a child that is still running (SIGKILL) and reaps it.
fn end(mut child: Child) {
    let _ = child.kill();
    let _ = child.wait();
}

/// Round two, "hangs from the new defaults": a run predicted to take longer than a minute says
/// so first, in one line with its work in the arguments' terms and the options that set it,
/// before it starts. In a closed room of reflectance 1 every path runs to --max-depth (100 000
/// collisions): 64 light paths with 20 000 near-field samples per near sensor (the old default)
/// ran over 400 s without a word, and the image's default 10 000 light-tracing paths per light
/// path multiply its 8 paths.
#[test]
fn long_runs_state_their_plan_before_they_start() {
    let dir = TempDir::new("rel-plan");
    let lxs = compile_text(&dir, "white", &crate::reliability::white_room());
    let lxs = lxs.to_str().unwrap();
    let ron = dir.path().join("w.ron");
    let exr = dir.path().join("w.exr");
    let prefix = dir.path().join("w");
    let prefix = prefix.to_str().unwrap();
    let one = ["--threads", "1"];
    let sensors = [
        &["sensors", lxs, "--paths", "64", "--near-samples", "20000"][..],
        &one,
        &["-o", ron.to_str().unwrap()],
    ]
    .concat();
    let image = [
        &["image", lxs, "--paths", "8"][..],
        &one,
        &["-o", exr.to_str().unwrap()],
    ]
    .concat();
    // The camera stages: their paths end by roulette, but a million samples per pixel are
    // hours all the same.
    let camera = |resolution| {
        [
            &[lxs, "--spp", "1000000", "--resolution", resolution][..],
            &one,
            &["-o", prefix],
        ]
        .concat()
    };
    let cases: [(&str, Vec<&str>, &[&str]); 4] = [
        (
            "estimate",
            sensors,
            &[
                "estimate sensors: plan: 64 light paths of ~1.0e5 collisions",
                "20000 near-field samples at each of",
                "--near-samples",
            ],
        ),
        (
            "estimate",
            image,
            &[
                "estimate image: plan: 8 light paths of ~1.0e5 collisions",
                "10000 light-tracing paths per light path (--mis-paths)",
            ],
        ),
        (
            "trace",
            camera("64x64"),
            &["trace: plan: 64x64 pixels x 1000000 samples of ~", "--spp"],
        ),
        (
            "aov-write",
            camera("256x256"),
            &[
                "aov-write: plan: 256x256 pixels x 1000000 first hits",
                "--min-samples",
            ],
        ),
    ];
    for (stage, args, wants) in cases {
        let mut child = stage_process(stage, &args)
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let lines = stderr_lines(&mut child);
        let (plan, _) = wait_for_line(&lines, ": plan: ", Duration::from_secs(60));
        end(child);
        let plan = plan.unwrap_or_else(|| panic!("{args:?}: no plan before the run"));
        for want in wants {
            assert!(plan.contains(want), "{want:?} in {plan}");
        }
        // Printed only for runs predicted beyond a minute: minutes or hours, not seconds.
        assert!(!plan.contains(" s on 1 thread"), "{plan}");
        assert_eq!(dir.files().len(), 2, "only the scene: {:?}", dir.files());
    }
}

/// The files of `dir` whose names start with `prefix`.
fn named(dir: &Path, prefix: &str) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(prefix))
        .collect()
}

/// Round two, "left behind": a process killed mid-write (SIGKILL) leaves its temporary
/// `.NAME.tmp-PID-N@HOST` and never a partial final file; the next run in that folder removes
/// it, also a run that only reads from there (a stale temporary stayed until a run wrote into
/// the same folder).
#[test]
fn a_temporary_left_by_a_killed_run_is_removed_by_the_next_run_in_its_folder() {
    let dir = TempDir::new("rel-killed");
    let lxs = compile_text(&dir, "plain", PLAIN);
    let out = dir.path().join("o.ron");
    let marker = dir.path().join("writing");
    let child = stage_process(
        "slow-writer",
        &[out.to_str().unwrap(), marker.to_str().unwrap()],
    )
    .spawn()
    .unwrap();
    let start = Instant::now();
    while !marker.exists() {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the writer never started"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let pid = child.id();
    end(child);
    let temps = named(dir.path(), ".o.ron.tmp-");
    assert_eq!(temps.len(), 1, "{temps:?}");
    assert!(
        temps[0].starts_with(&format!(".o.ron.tmp-{pid}-0")),
        "{temps:?}"
    );
    assert!(!out.exists(), "no partial final file");
    // A run reading the scene from that folder, writing elsewhere.
    let elsewhere = TempDir::new("rel-killed-out");
    crate::util::estimate(&[
        "sensors",
        lxs.to_str().unwrap(),
        "--paths",
        "64",
        "--batches",
        "2",
        "-o",
        elsewhere.path().join("x.ron").to_str().unwrap(),
    ])
    .unwrap();
    assert_eq!(named(dir.path(), ".o.ron.tmp-"), Vec::<String>::new());
}

/// Round two, "left behind": a write beyond the file-size limit (`ulimit -f`) is an error of
/// that write, one line naming the file, and the run leaves nothing: the signal SIGXFSZ used to
/// end the process on the spot, leaving the temporary behind.
#[test]
fn a_file_size_limit_fails_the_write_in_one_line_and_leaves_nothing() {
    let dir = TempDir::new("rel-fsize");
    let src = crate::util::repo_root().join("scenes/cornell-box.ron");
    let out = dir.path().join("out").join("cb.lxs");
    let output = limited_stage_process(
        "-f 4",
        "scene-compile",
        &[src.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"],
    )
    .output()
    .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(
        output.status.code(),
        Some(1),
        "{:?}: {stderr}",
        output.status
    );
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].starts_with(&format!("error: {}", out.display()))
            && lines[0].contains("File too large"),
        "{stderr}"
    );
    assert_eq!(
        dir.files(),
        Vec::<std::path::PathBuf>::new(),
        "nothing left behind"
    );
}

/// Round two, "abort on memory": `estimate image --pixel-samples 4294967295 --resolution 1x1`
/// grew to 17.8 GB and, under a memory limit, aborted in the allocator (exit 134). Its camera
/// points are sized before they are allocated, against the least of the machine's available
/// memory and the process's own limits: a usage error stating both sizes. Under a 4 GiB
/// address-space limit, 40 million camera points (more than the limit, less than many machines
/// have) are refused with the limit named.
#[test]
fn camera_points_are_sized_under_the_processs_memory_limit() {
    let dir = TempDir::new("rel-memory");
    let src = crate::util::repo_root().join("scenes/cornell-box.ron");
    let lxs = dir.path().join("cb.lxs");
    crate::util::scene_compile(&[src.to_str().unwrap(), "-o", lxs.to_str().unwrap(), "-q"])
        .unwrap();
    let exr = dir.path().join("x.exr");
    let available = luxest_io::limits::available_memory().unwrap_or(u64::MAX) as u128;
    let bytes = estimate::double_local_estimate::VIEW_POINT_BYTES as u128;
    for samples in ["4294967295", "40000000"] {
        let output = limited_stage_process(
            "-v 4194304",
            "estimate",
            &[
                "image",
                lxs.to_str().unwrap(),
                "--paths",
                "10",
                "--pixel-samples",
                samples,
                "--resolution",
                "1x1",
                "--threads",
                "1",
                "-o",
                exr.to_str().unwrap(),
            ],
        )
        .output()
        .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(
            output.status.code(),
            Some(2),
            "{samples}: {:?}: {stderr}",
            output.status
        );
        assert!(
            stderr.contains(&format!(
                "--pixel-samples {samples} over a tile of 1 pixels on 1 thread needs"
            )) && stderr.contains("of memory, more than the"),
            "{stderr}"
        );
        let needed = samples.parse::<u128>().unwrap() * bytes;
        if needed < available {
            assert!(stderr.contains("ulimit -v"), "the limit named: {stderr}");
        }
        assert!(!exr.exists());
    }
}

/// Round two, "unclear first lines": `denoise a b` printed `denoise: a.dn.exr (…)` first,
/// although nothing is written when b is bad; the first line is now b's error, and the lines
/// of the images denoised come only once all are written.
#[test]
fn denoise_says_first_what_failed() {
    use luxest_io::exr::write_rgb;
    use luxest_io::image::RgbImage;
    let dir = TempDir::new("rel-dn-first");
    let model = crate::util::repo_root().join("tests/fixtures/denoise/tiny.onnx");
    let mut img = RgbImage::new(8, 8);
    img.pixels.iter_mut().for_each(|p| *p = [0.5; 3]);
    for name in ["a", "b"] {
        for kind in ["hdr", "alb", "nrm"] {
            write_rgb(
                &dir.path().join(format!("{name}_000001spp.{kind}.exr")),
                &img,
            )
            .unwrap();
        }
    }
    let a = dir.path().join("a_000001spp.hdr.exr");
    let b = dir.path().join("b_000001spp.hdr.exr");
    std::fs::write(&b, b"not an image").unwrap();
    let output = stage_process(
        "denoise",
        &[
            a.to_str().unwrap(),
            b.to_str().unwrap(),
            "--model",
            model.to_str().unwrap(),
            "--threads",
            "1",
        ],
    )
    .output()
    .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    let first = stderr.lines().next().unwrap_or_default();
    assert!(
        first.starts_with(&format!("error: {}", b.display())),
        "{stderr}"
    );
    assert!(!stderr.contains("denoise: "), "{stderr}");
    assert!(!dir.path().join("a_000001spp.dn.exr").exists());
}
