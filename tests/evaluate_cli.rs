//! The evaluate stage end to end: image reports (values against the scikit-image / FLIP
//! fixtures of tests/fixtures/metrics, costs from header attributes), sensor reports against a
//! closed-form exact value, and errors on bad input.

use crate::util::{evaluate, repo_root, TempDir};
use luxest_io::exr::{read_rgb, write_rgb};
use luxest_io::header;
use luxest_io::image::RgbImage;
use luxest_io::math::Vec3;
use luxest_io::meta::RunInfo;
use luxest_io::sensors::{SensorResults, SensorSetResult, SensorValue};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

fn metrics_fixture(name: &str) -> PathBuf {
    repo_root().join("tests/fixtures/metrics").join(name)
}

fn expected(key: &str) -> f64 {
    let text = std::fs::read_to_string(metrics_fixture("expected.txt")).unwrap();
    text.lines()
        .find_map(|l| l.strip_prefix(key)?.strip_prefix(' ')?.trim().parse().ok())
        .unwrap_or_else(|| panic!("no {key} in expected.txt"))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Splits a CSV line, honouring double-quoted fields.
fn split_csv(line: &str) -> Vec<String> {
    let (mut fields, mut field, mut quoted) = (Vec::new(), String::new(), false);
    for c in line.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => fields.push(std::mem::take(&mut field)),
            _ => field.push(c),
        }
    }
    fields.push(field);
    fields
}

/// Rows of a CSV file as header -> value maps.
fn read_csv(path: &Path) -> Vec<HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = split_csv(lines.next().unwrap());
    lines
        .map(|l| {
            let row = split_csv(l);
            assert_eq!(row.len(), header.len(), "{l}");
            header.iter().cloned().zip(row).collect()
        })
        .collect()
}

fn num(row: &HashMap<String, String>, key: &str) -> f64 {
    row[key]
        .parse()
        .unwrap_or_else(|_| panic!("{key} = {:?}", row[key]))
}

#[test]
fn image_report_matches_the_reference_implementations_and_adds_up_costs() {
    let dir = TempDir::new("eval-images");
    let reference = metrics_fixture("hdr_ref.exr");
    // The fixture's test image, once as a noisy render and once as a denoised one.
    let mut noisy = read_rgb(&metrics_fixture("hdr_test.exr")).unwrap();
    noisy.attributes.clear();
    noisy.set_attribute(header::ESTIMATOR, "path-tracing");
    noisy.set_attribute(header::SAMPLES, 16);
    noisy.set_attribute(header::SECONDS, 2);
    let noisy_path = dir.path().join("x_000016spp.hdr.exr");
    write_rgb(&noisy_path, &noisy).unwrap();
    let mut denoised = noisy.clone();
    denoised.set_attribute(header::DENOISER, "m.onnx");
    denoised.set_attribute(header::FEATURE_SECONDS, 1.25);
    denoised.set_attribute(header::DENOISE_SECONDS, 0.5);
    let dn_path = dir.path().join("x_000016spp.dn.exr");
    write_rgb(&dn_path, &denoised).unwrap();

    let csv = dir.path().join("r.csv");
    let ron = dir.path().join("r.ron");
    let maps = dir.path().join("maps");
    evaluate(&[
        "images",
        "--reference",
        s(&reference),
        s(&noisy_path),
        s(&dn_path),
        "-o",
        s(&csv),
        "--ron",
        s(&ron),
        "--flip-maps",
        s(&maps),
    ])
    .unwrap();
    let rows = read_csv(&csv);
    assert_eq!(rows.len(), 2);
    for (row, key, want) in [
        (&rows[0], "psnr_db", expected("hdr.tm.psnr")),
        (&rows[0], "ssim", expected("hdr.tm.ssim")),
        (&rows[0], "ms_ssim", expected("hdr.tm.ms_ssim")),
        (&rows[0], "flip", expected("hdr.tm.flip")),
        (&rows[0], "rel_mse", expected("hdr.rel_mse")),
        (&rows[0], "smape", expected("hdr.smape")),
    ] {
        let got = num(row, key);
        assert!((got - want).abs() <= 1e-4, "{key}: {got} vs {want}");
    }
    assert_eq!(rows[0]["estimator"], "path-tracing");
    assert_eq!(rows[1]["estimator"], "path-tracing+denoise");
    assert_eq!(num(&rows[0], "total_seconds"), 2.0);
    assert_eq!(num(&rows[1], "total_seconds"), 3.75);
    assert_eq!(num(&rows[1], "samples"), 16.0);
    let report: evaluate::images::ImageReport = luxest_io::fsio::read_ron(&ron).unwrap();
    assert_eq!(report.rows.len(), 2);
    assert!((report.exposure - expected("hdr.autoexposure")).abs() < 1e-9);
    let map = read_rgb(&maps.join("x_000016spp.hdr.flip.exr")).unwrap();
    let max = map.pixels.iter().map(|p| p[0] as f64).fold(0.0, f64::max);
    assert!(
        (max - expected("hdr.tm.flip_map_max")).abs() <= 1e-4,
        "{max}"
    );
    assert!(maps.join("x_000016spp.dn.flip.png").is_file());
}

/// An integrating sphere of radius 1 m with a 100 cd isotropic source at its centre and
/// rho = 0.5 has E = I / R² + rho Φ / (4π R² (1 − rho)) = 100 + 100 = 200 lx everywhere on
/// its wall.
#[test]
fn sensor_report_gives_z_scores_against_the_exact_value() {
    let dir = TempDir::new("eval-sensors");
    let point =
        |p: Vec3, value: f64, se: f64| SensorValue::new(p, -p, value, se, Default::default());
    let results = SensorResults {
        scene: "sphere".into(),
        run: RunInfo::new("local-estimate", 1000, 1, 0.5, "0"),
        unit: "lx".into(),
        singularity: "ball".into(),
        sets: vec![SensorSetResult {
            name: "wall".into(),
            grid: None,
            kind: None,
            batches: Vec::new(),
            points: vec![
                point(Vec3::new(1.0, 0.0, 0.0), 202.0, 1.0),
                point(Vec3::new(0.0, -1.0, 0.0), 199.0, 0.5),
            ],
        }],
        glare: Vec::new(),
    };
    let ron_in = dir.path().join("s.sensors.ron");
    results.write_ron(&ron_in).unwrap();
    let csv = dir.path().join("s.csv");
    let ron = dir.path().join("s.ron");
    evaluate(&[
        "sensors",
        s(&ron_in),
        "--case",
        "sphere:I=100,R=1,rho=0.5",
        "-o",
        s(&csv),
        "--ron",
        s(&ron),
    ])
    .unwrap();
    let rows = read_csv(&csv);
    assert_eq!(rows.len(), 2);
    assert!((num(&rows[0], "exact_lx") - 200.0).abs() < 1e-9);
    assert!((num(&rows[0], "z") - 2.0).abs() < 1e-9);
    assert!((num(&rows[1], "z") + 2.0).abs() < 1e-9);
    assert!((num(&rows[1], "relative_error") + 0.005).abs() < 1e-12);
    let report: evaluate::sensors::SensorReport = luxest_io::fsio::read_ron(&ron).unwrap();
    assert_eq!(report.points, 2);
    assert!((report.max_abs_z - 2.0).abs() < 1e-9);
    assert!((report.mean_z_squared - 4.0).abs() < 1e-9);
    let rms = ((0.01f64.powi(2) + 0.005f64.powi(2)) / 2.0).sqrt();
    assert!((report.rms_relative_error - rms).abs() < 1e-12);

    // The z-test: |z| = 2 passes --max-z 2.5 and fails --max-z 1.5 with one line naming the file.
    let case = "sphere:I=100,R=1,rho=0.5";
    evaluate(&["sensors", s(&ron_in), "--case", case, "--max-z", "2.5"]).unwrap();
    let (code, msg) =
        evaluate(&["sensors", s(&ron_in), "--case", case, "--max-z", "1.5"]).unwrap_err();
    assert_eq!(code, 1);
    assert!(
        msg.contains("s.sensors.ron") && msg.contains("validation failed: 2 of 2 values"),
        "{msg}"
    );
    // --sets restricts the comparison and names a missing set.
    evaluate(&["sensors", s(&ron_in), "--case", case, "--sets", "wall"]).unwrap();
    let (code, msg) =
        evaluate(&["sensors", s(&ron_in), "--case", case, "--sets", "floor"]).unwrap_err();
    assert_eq!(code, 1);
    assert!(msg.contains("no sensor set named \"floor\""), "{msg}");
    let (code, _) = evaluate(&["sensors", s(&ron_in), "--case", "sphere:I=1"]).unwrap_err();
    assert_eq!(code, 2);
}

#[test]
fn bad_input_gives_one_line_errors_and_no_report() {
    let dir = TempDir::new("eval-errors");
    let reference = metrics_fixture("hdr_ref.exr");
    let out = dir.path().join("r.csv");
    let check = |args: &[&str], code: u8, needles: &[&str]| {
        let (c, msg) = evaluate(args).expect_err("must fail");
        assert_eq!(c, code, "{msg}");
        assert!(!msg.trim().contains('\n'), "one line: {msg}");
        for n in needles {
            assert!(msg.contains(n), "{msg:?} should mention {n:?}");
        }
    };
    let small = dir.path().join("small.exr");
    write_rgb(&small, &RgbImage::new(8, 8)).unwrap();
    check(
        &[
            "images",
            "--reference",
            s(&reference),
            s(&small),
            "-o",
            s(&out),
        ],
        1,
        &["small.exr", "8x8", "64x48"],
    );
    let mut nan = read_rgb(&reference).unwrap();
    nan.pixels[64 * 2 + 7][0] = f32::INFINITY;
    let nan_path = dir.path().join("nan.exr");
    write_rgb(&nan_path, &nan).unwrap();
    check(
        &[
            "images",
            "--reference",
            s(&reference),
            s(&nan_path),
            "-o",
            s(&out),
        ],
        1,
        &["nan.exr", "pixel (7, 2)"],
    );
    let junk = dir.write("junk.exr", "not an image");
    check(
        &["images", "--reference", s(&junk), s(&small), "-o", s(&out)],
        1,
        &["junk.exr"],
    );
    check(
        &[
            "images",
            "--reference",
            s(&reference),
            "/nonexistent/t.exr",
            "-o",
            s(&out),
        ],
        1,
        &["/nonexistent/t.exr"],
    );
    let sensors = dir.write("bad.sensors.ron", "SensorResults(");
    check(
        &[
            "sensors",
            s(&sensors),
            "--case",
            "sphere:I=100,R=1,rho=0.5",
            "-o",
            s(&out),
        ],
        1,
        &["bad.sensors.ron"],
    );
    check(
        &["sensors", s(&sensors), "--case", "cube", "-o", s(&out)],
        2,
        &["cube"],
    );
    // The report files must end like what is written there, checked before the results are
    // read (these are malformed: the ending's usage error comes first).
    let ron = dir.path().join("r.ron");
    for (flag, path, want) in [("-o", &ron, "-o/--out"), ("--ron", &out, "--ron")] {
        let args = ["sensors", s(&sensors), "--case", "cube", flag, s(path)];
        check(
            &args,
            2,
            &[&format!("{want} {}: this writes", path.display())],
        );
    }
    assert!(!out.exists() && !ron.exists());
}

/// evaluate and denoise accept --seed and --threads like every stage, and their --help says
/// what the options do there (it said "Seed of all random numbers" and "Worker threads" where
/// neither is used).
#[test]
fn help_says_what_seed_and_threads_do_where_they_do_nothing() {
    use clap::CommandFactory;
    let help = |cmd: &clap::Command, id: &str| {
        let arg = cmd.get_arguments().find(|a| a.get_id() == id).unwrap();
        arg.get_help().map(|h| h.to_string()).unwrap_or_default()
    };
    let evaluate = evaluate::cli::Args::command();
    for sub in ["images", "sensors"] {
        let cmd = evaluate.find_subcommand(sub).unwrap();
        assert!(
            help(cmd, "seed").contains("draws no random numbers"),
            "{sub}"
        );
        assert!(help(cmd, "threads").contains("runs on one thread"), "{sub}");
    }
    let denoise = denoise::cli::Args::command();
    assert!(help(&denoise, "seed").contains("draws no random numbers"));
    // denoise does use its threads (the inference's), and says so.
    assert!(help(&denoise, "threads").starts_with("Worker threads"));
}
