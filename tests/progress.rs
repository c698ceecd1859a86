//! Progress on long runs (`luxest_io::progress`), seen from outside as a user sees it: every
//! stage run as its binary would (`util::stage_process`), with stderr a pipe (a log) and the
//! display chosen by `--quiet` and `LUXEST_PROGRESS` / `LUXEST_PROGRESS_INTERVAL`.
//!
//! - Progress changes no output: the files of a run with progress drawn (a log's lines every
//!   10 ms, or the terminal's frames) equal those of a `--quiet` run, bit for bit, but for the
//!   recorded seconds.
//! - A log gets plain periodic lines (no carriage returns or escape sequences), and a short run
//!   none.
//! - `--quiet` prints nothing but errors: no progress, plan, note or `wrote` line, and errors
//!   all the same.

use crate::util::{compile_text, repo_root, stage_process, TempDir};
use luxest_io::exr::read_rgb;
use luxest_io::header;
use luxest_io::sensors::SensorResults;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

/// A grey room lit by a ceiling lamp, with a camera, a floor grid and a sensor by a wall (the
/// local estimate's near field): every estimator of `estimate` runs on it.
const ROOM: &str = r#"Scene(
    name: "room",
    camera: Camera(position: (2.0, 1.5, 0.3), look_at: (2.0, 1.0, 4.0), up: (0.0, 1.0, 0.0), vfov_deg: 60.0, resolution: (32, 24)),
    materials: { "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) },
    objects: [
        (name: "room", shape: Box(size: (4.0, 3.0, 4.0)), transform: (translate: (2.0, 1.5, 2.0)), material: "w", flip_normals: true),
        (name: "lamp", shape: Quad(corner: (1.5, 2.999, 1.5), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, 1.0)), material: "w", emission: Flux(lumens: 1000.0)),
    ],
    sensors: [
        Grid(name: "floor", corner: (0.5, 0.0, 0.5), u: (3.0, 0.0, 0.0), v: (0.0, 0.0, 3.0), counts: (3, 3), normal: (0.0, 1.0, 0.0)),
        Points(name: "by-the-wall", points: [(position: (0.1, 0.0, 2.0), normal: (0.0, 1.0, 0.0))]),
    ],
)"#;

/// How a run shows its progress.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Shown {
    /// `--quiet`.
    Quiet,
    /// A log's lines, one every 10 ms and always a last one (`LUXEST_PROGRESS=lines`,
    /// interval 0).
    Lines,
    /// The terminal's frames, whatever stderr is (`LUXEST_PROGRESS=bar`).
    Bar,
    /// As a user's run in a log gets it: stderr a pipe, no override but the interval.
    Log { interval: &'static str },
}

/// Runs `stage` on `args` as its binary does, stderr read back; returns the exit status and
/// the stderr text.
fn run(stage: &str, args: &[&str], shown: Shown) -> (i32, String) {
    let mut args: Vec<&str> = args.to_vec();
    if shown == Shown::Quiet {
        args.push("--quiet");
    }
    let mut c = stage_process(stage, &args);
    c.env_remove("LUXEST_PROGRESS")
        .env_remove("LUXEST_PROGRESS_INTERVAL");
    match shown {
        Shown::Quiet => {}
        Shown::Lines => {
            c.env("LUXEST_PROGRESS", "lines")
                .env("LUXEST_PROGRESS_INTERVAL", "0");
        }
        Shown::Bar => {
            c.env("LUXEST_PROGRESS", "bar");
        }
        Shown::Log { interval } => {
            c.env("LUXEST_PROGRESS_INTERVAL", interval);
        }
    }
    let out = c.stderr(Stdio::piped()).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Every file under `dir`, relative to it, sorted.
fn files(dir: &Path) -> Vec<PathBuf> {
    fn walk(root: &Path, d: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out)
            } else {
                out.push(p.strip_prefix(root).unwrap().to_path_buf())
            }
        }
    }
    let mut v = Vec::new();
    walk(dir, dir, &mut v);
    v.sort();
    v
}

/// The header keys that record wall-clock or CPU time: the only difference allowed.
const TIMES: [&str; 3] = [
    header::SECONDS,
    header::DENOISE_SECONDS,
    header::DENOISE_CPU_SECONDS,
];

/// Asserts that the outputs `a/<f>` and `b/<f>` are the same: EXR pixels bit for bit with the
/// same header but for [`TIMES`], sensor results equal but for `run.seconds`, any other file
/// byte for byte.
fn assert_same_output(a: &Path, b: &Path, f: &Path, case: &str) {
    let (pa, pb) = (a.join(f), b.join(f));
    let name = f.to_string_lossy();
    if name.ends_with(".exr") {
        let (mut x, mut y) = (read_rgb(&pa).unwrap(), read_rgb(&pb).unwrap());
        for img in [&mut x, &mut y] {
            img.attributes.retain(|(k, _)| !TIMES.contains(&k.as_str()));
        }
        let bits = |i: &luxest_io::image::RgbImage| -> Vec<u32> {
            i.pixels.iter().flatten().map(|v| v.to_bits()).collect()
        };
        assert_eq!(bits(&x), bits(&y), "{case}: {name}: pixels differ");
        assert_eq!(x.attributes, y.attributes, "{case}: {name}: headers differ");
    } else if name.ends_with(".ron") && std::fs::read_to_string(&pa).unwrap().contains("run:") {
        let (mut x, mut y) = (
            SensorResults::read_ron(&pa).unwrap(),
            SensorResults::read_ron(&pb).unwrap(),
        );
        x.run.seconds = 0.0;
        y.run.seconds = 0.0;
        assert_eq!(x, y, "{case}: {name}: results differ");
    } else {
        assert!(
            std::fs::read(&pa).unwrap() == std::fs::read(&pb).unwrap(),
            "{case}: {name}: bytes differ"
        );
    }
}

/// Issue 53's first test: a run with its progress drawn writes what a quiet run writes. The
/// log's lines every 10 ms read the counters from their own thread as often as they can, the
/// terminal's frames draw as a terminal gets them; neither touches a random number or the
/// order of the work.
#[test]
fn outputs_are_identical_with_and_without_progress() {
    let dir = TempDir::new("progress-same");
    let lxs = compile_text(&dir, "room", ROOM);
    let lxs = lxs.to_str().unwrap();
    // The denoiser's and the evaluator's inputs: the denoise fixtures.
    let fixtures = repo_root().join("tests/fixtures/denoise");
    let input = dir.path().join("in");
    std::fs::create_dir_all(&input).unwrap();
    for kind in ["hdr", "alb", "nrm", "expected", "kpn.expected"] {
        let name = format!("tiles_000001spp.{kind}.exr");
        std::fs::copy(fixtures.join(&name), input.join(&name)).unwrap();
    }
    let image = |kind: &str| {
        input
            .join(format!("tiles_000001spp.{kind}.exr"))
            .to_string_lossy()
            .into_owned()
    };
    let model = fixtures.join("tiny.onnx").to_string_lossy().into_owned();
    let threads = ["--threads", "2"];
    // (stage, the progress's label, arguments with OUT for the run's output directory)
    let cases: Vec<(&str, &str, Vec<String>)> = vec![
        (
            "trace",
            "trace",
            [lxs, "--spp", "64", "--snapshots", "4,16", "--stderr"]
                .into_iter()
                .chain(["-o", "OUT/t", "--preview", "OUT/t.png"])
                .map(String::from)
                .collect(),
        ),
        (
            "aov-write",
            "aov-write",
            [
                lxs,
                "--spp",
                "4",
                "--snapshots",
                "1",
                "--depth",
                "-o",
                "OUT/t",
            ]
            .map(String::from)
            .to_vec(),
        ),
        (
            "estimate",
            "estimate sensors",
            ["sensors", lxs, "--paths", "3000", "--batches", "8"]
                .into_iter()
                .chain(["--batch-values", "-o", "OUT/s.ron", "--csv", "OUT/s.csv"])
                .map(String::from)
                .collect(),
        ),
        (
            "estimate",
            "estimate direct",
            [
                "direct",
                lxs,
                "--paths",
                "3000",
                "--bin-radius",
                "0.3",
                "-o",
                "OUT/d.ron",
            ]
            .map(String::from)
            .to_vec(),
        ),
        (
            "estimate",
            "estimate gather",
            ["gather", lxs, "--samples", "64", "-o", "OUT/g.ron"]
                .map(String::from)
                .to_vec(),
        ),
        (
            "estimate",
            "estimate image: connections",
            ["image", lxs, "--paths", "64", "--mis-paths", "16"]
                .into_iter()
                .chain(["-o", "OUT/i.exr", "--stderr-out", "OUT/i.se.exr"])
                .map(String::from)
                .collect(),
        ),
        (
            "estimate",
            "estimate image --light-tracing",
            [
                "image",
                lxs,
                "--light-tracing",
                "--paths",
                "5000",
                "-o",
                "OUT/lt.exr",
            ]
            .map(String::from)
            .to_vec(),
        ),
        (
            "denoise",
            "denoise",
            [
                image("hdr"),
                "--model".into(),
                model,
                "--tile".into(),
                "32".into(),
                "--overlap".into(),
                "32".into(),
                "-o".into(),
                "OUT/dn.exr".into(),
            ]
            .to_vec(),
        ),
        (
            "evaluate",
            "evaluate images",
            [
                "images".into(),
                "--reference".into(),
                image("expected"),
                image("hdr"),
                image("kpn.expected"),
                "-o".into(),
                "OUT/e.csv".into(),
                "--ron".into(),
                "OUT/e.ron".into(),
                "--flip-maps".into(),
                "OUT/flip".into(),
            ]
            .to_vec(),
        ),
    ];
    for (n, (stage, label, args)) in cases.iter().enumerate() {
        let mut outs = Vec::new();
        for shown in [Shown::Quiet, Shown::Lines, Shown::Bar] {
            let out = dir.path().join(format!("{n}-{shown:?}"));
            std::fs::create_dir_all(&out).unwrap();
            let out_s = out.to_string_lossy();
            let args: Vec<String> = args.iter().map(|a| a.replace("OUT", &out_s)).collect();
            let args: Vec<&str> = args.iter().map(String::as_str).chain(threads).collect();
            let (code, stderr) = run(stage, &args, shown);
            let case = format!("{stage} {shown:?} {args:?}");
            assert_eq!(code, 0, "{case}: {stderr}");
            match shown {
                Shown::Quiet => assert_eq!(stderr, "", "{case}"),
                Shown::Lines => {
                    assert!(!stderr.contains('\r'), "{case}: {stderr:?}");
                    let done = format!("{label}: 100% (");
                    assert!(
                        stderr
                            .lines()
                            .any(|l| l.starts_with(&done) && l.ends_with(", done")),
                        "{case}: no last line of its progress: {stderr}"
                    );
                }
                _ => {}
            }
            outs.push(out);
        }
        let names = files(&outs[0]);
        assert!(!names.is_empty(), "{stage} {args:?}: no output");
        for other in &outs[1..] {
            assert_eq!(files(other), names, "{stage} {args:?}");
            for f in &names {
                assert_same_output(&outs[0], other, f, &format!("{stage} {args:?}"));
            }
        }
    }
}

/// Issue 53's second test: a log (stderr not a terminal) gets a plain line of progress every
/// interval — no carriage-return frames, no escape sequences — once the run lasts that long,
/// and a last line at its end; a run shorter than the interval prints its `wrote` line alone.
#[test]
fn a_log_gets_periodic_plain_lines_and_a_short_run_none() {
    let dir = TempDir::new("progress-log");
    let lxs = compile_text(&dir, "room", ROOM);
    let prefix = dir.path().join("t");
    let args = |spp: &'static str| {
        vec![
            lxs.to_string_lossy().into_owned(),
            "--spp".into(),
            spp.into(),
            "--resolution".into(),
            "64x48".into(),
            "--threads".into(),
            "2".into(),
            "-o".into(),
            prefix.to_string_lossy().into_owned(),
        ]
    };
    // Long enough for several 20 ms intervals on any machine.
    let long = args("256");
    let long: Vec<&str> = long.iter().map(String::as_str).collect();
    let start = Instant::now();
    let (code, stderr) = run("trace", &long, Shown::Log { interval: "0.02" });
    let seconds = start.elapsed().as_secs_f64();
    assert_eq!(code, 0, "{stderr}");
    assert!(
        !stderr.contains('\r') && !stderr.contains('\x1b'),
        "{stderr:?}"
    );
    let progress: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("trace: "))
        .collect();
    assert!(progress.len() >= 2, "{seconds:.2} s: {stderr}");
    for line in &progress[..progress.len() - 1] {
        assert!(
            line.contains("% (")
                && line.contains(" of 786k samples), ")
                && line.contains(" samples/s, ")
                && line.contains(" elapsed"),
            "{line}"
        );
    }
    assert!(
        progress
            .last()
            .unwrap()
            .starts_with("trace: 100% (786k of 786k samples), ")
            && progress.last().unwrap().ends_with(" elapsed, done"),
        "{stderr}"
    );
    assert!(
        stderr.lines().last().unwrap().starts_with("wrote "),
        "{stderr}"
    );
    // Under the default interval (30 s) a short run's log holds its result alone.
    let short = args("1");
    let short: Vec<&str> = short.iter().map(String::as_str).collect();
    let (code, stderr) = run("trace", &short, Shown::Log { interval: "30" });
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("wrote "), "{stderr}");
}

/// Issue 53's third test: `--quiet` prints nothing but errors. Every stage's successful quiet
/// run is silent (`outputs_are_identical_with_and_without_progress`); here the plan of a run
/// predicted to take hours is silenced too, while a usage error and a failure to read still
/// print their one line, on every stage.
#[test]
fn quiet_prints_nothing_but_errors() {
    let dir = TempDir::new("progress-quiet");
    let white = compile_text(&dir, "white", &crate::reliability::white_room());
    let white = white.to_str().unwrap();
    let ron = dir.path().join("w.ron");
    // Hours in a closed room of reflectance 1: without --quiet its plan comes within a second
    // (tests/reliability_processes.rs); with it, nothing comes at all.
    let mut child = stage_process(
        "estimate",
        &[
            "sensors",
            white,
            "--paths",
            "64",
            "--threads",
            "1",
            "-o",
            ron.to_str().unwrap(),
            "--quiet",
        ],
    )
    .env("LUXEST_PROGRESS", "lines")
    .env("LUXEST_PROGRESS_INTERVAL", "0")
    .stderr(Stdio::piped())
    .spawn()
    .unwrap();
    std::thread::sleep(Duration::from_secs(3));
    let _ = child.kill();
    let out = child.wait_with_output().unwrap();
    assert_eq!(String::from_utf8_lossy(&out.stderr), "");

    let missing = dir.path().join("missing.lxs");
    let missing = missing.to_str().unwrap();
    let scene_ron = dir.path().join("white.ron");
    let cases: [(&str, Vec<&str>, i32); 8] = [
        ("scene-compile", vec!["nowhere.ron"], 1),
        ("trace", vec![missing, "--spp", "1"], 1),
        ("trace", vec![white, "--spp", "0"], 2),
        ("aov-write", vec![missing, "--spp", "1"], 1),
        ("estimate", vec!["sensors", missing], 1),
        (
            "denoise",
            vec!["nowhere.hdr.exr", "--model", "nowhere.onnx"],
            1,
        ),
        (
            "evaluate",
            vec!["images", "--reference", missing, missing, "-o", "x.csv"],
            1,
        ),
        (
            "report",
            vec![scene_ron.to_str().unwrap(), "-o", "nowhere"],
            1,
        ),
    ];
    for (stage, args, want) in cases {
        let (code, stderr) = run(stage, &args, Shown::Quiet);
        assert_eq!(code, want, "{stage} {args:?}: {stderr}");
        assert!(stderr.starts_with("error: "), "{stage} {args:?}: {stderr}");
        if want == 1 {
            assert_eq!(stderr.lines().count(), 1, "{stage} {args:?}: {stderr}");
        }
    }
}
