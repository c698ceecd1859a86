//! The estimate stage's command line: outputs, metadata, errors; and the double local estimate
//! image against an exact solution.

use crate::util::{compile_text, estimate, evaluate, TempDir};
use luxest_exact::solutions::Sobolev;
use luxest_io::header;
use luxest_io::sensors::SensorResults;

const SOBOLEV: &str = r#"Scene(
    camera: Camera(position: (0.0, 0.0, 0.0), look_at: (0.0, -1.0, 0.0), up: (0.0, 0.0, 1.0),
                   vfov_deg: 60.0, resolution: (12, 10)),
    materials: { "p": Lambertian(reflectance: (0.5, 0.5, 0.5)) },
    objects: [
        (shape: Quad(corner: (-1000.0, -1.0, 1000.0), u: (2000.0, 0.0, 0.0), v: (0.0, 0.0, -2000.0)), material: "p"),
        (shape: Quad(corner: (-1000.0, 1.0, -1000.0), u: (2000.0, 0.0, 0.0), v: (0.0, 0.0, 2000.0)), material: "p"),
    ],
    point_lights: [(position: (0.0, 0.0, 0.0), power: Intensity(100.0))],
    sensors: [Points(name: "p1", points: [(position: (0.0, -1.0, 0.0), normal: (0.0, 1.0, 0.0)),
                                          (position: (1.0, -1.0, 0.0), normal: (0.0, 1.0, 0.0))])],
)"#;

fn exact() -> Sobolev {
    Sobolev {
        intensity_cd: 100.0,
        h1: 1.0,
        h2: 1.0,
        rho1: 0.5,
        rho2: 0.5,
    }
}

/// The exact box-filtered luminance rho1/π · E1(r) of pixel (x, y) of [`SOBOLEV`]'s camera (at
/// the source, looking straight down at plane 1): the mean over a 4 × 4 grid in the pixel.
fn exact_pixel(x: usize, y: usize) -> f64 {
    let cam = luxest_render::camera::PinholeCamera::new(&luxest_render::scene::Camera {
        position: luxest_io::math::Vec3::ZERO,
        look_at: luxest_io::math::Vec3::new(0.0, -1.0, 0.0),
        up: luxest_io::math::Vec3::new(0.0, 0.0, 1.0),
        vfov_deg: 60.0,
        resolution: (12, 10),
    })
    .unwrap();
    let s = exact();
    let mut l = 0.0;
    for a in 0..4 {
        for b in 0..4 {
            let d = cam.direction(
                x as f64 + (a as f64 + 0.5) / 4.0,
                y as f64 + (b as f64 + 0.5) / 4.0,
            );
            let t = 1.0 / -d.y;
            let r = (d.x * t).hypot(d.z * t);
            l += 0.5 / std::f64::consts::PI * s.illuminance1(r).value / 16.0;
        }
    }
    l
}

#[test]
fn sensor_results_record_evaluated_points_and_the_direct_and_indirect_parts() {
    // A 4 m room with a point source at its centre: a sensor in a floor corner and one on a
    // floor edge are evaluated off the walls (recorded), the one mid-floor where authored; the
    // direct part is the exact I cos / d² (Flux 1000 lm isotropic: I = 1000 / 4π cd).
    let dir = TempDir::new("est-parts");
    let text = r#"Scene(
    materials: { "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) },
    objects: [(name: "room", shape: Box(size: (4.0, 4.0, 4.0)), material: "w", flip_normals: true)],
    point_lights: [(name: "s", position: (0.0, 0.0, 0.0), power: Flux(1000.0))],
    sensors: [Points(name: "floor", points: [
        (position: (2.0, -2.0, 2.0), normal: (0.0, 1.0, 0.0)),
        (position: (0.0, -2.0, 2.0), normal: (0.0, 1.0, 0.0)),
        (position: (0.5, -2.0, 0.0), normal: (0.0, 1.0, 0.0))])],
)"#;
    let scene = compile_text(&dir, "room", text);
    let out = dir.path().join("r.sensors.ron");
    let csv = dir.path().join("r.csv");
    estimate(&[
        "sensors",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
        "--paths",
        "20000",
    ])
    .unwrap();
    let r = SensorResults::read_ron(&out).unwrap();
    let points = &r.sets[0].points;
    let intensity = 1000.0 / (4.0 * std::f64::consts::PI);
    for (k, p) in points.iter().enumerate() {
        let at = p.evaluated_at.unwrap_or(p.position);
        assert_eq!(
            p.evaluated_at.is_some(),
            k < 2,
            "point {k}: {:?}",
            p.evaluated_at
        );
        let moved = (at - p.position).length();
        assert!(moved < 0.02, "point {k} moved {moved} m");
        let d = at.length();
        let exact_direct = intensity * (-at.y / d) / (d * d);
        let (direct, indirect) = (p.direct.unwrap(), p.indirect.unwrap());
        assert!(
            (direct.value - exact_direct).abs() <= 1e-9 * exact_direct,
            "point {k}: direct {} vs {exact_direct}",
            direct.value
        );
        assert!((direct.value + indirect.value - p.value).abs() <= 1e-9 * p.value);
        assert!(indirect.value > 0.0 && indirect.standard_error > 0.0);
    }
    let text = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let row: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
    assert_eq!(header.len(), row.len());
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let ex: f64 = row[col("evaluated_x")].parse().unwrap();
    assert_eq!(ex, points[0].evaluated_at.unwrap().x);
    let direct: f64 = row[col("direct_lx")].parse().unwrap();
    assert_eq!(direct, points[0].direct.unwrap().value);
}

#[test]
fn sensors_write_ron_and_csv_with_metadata() {
    let dir = TempDir::new("est");
    let scene = compile_text(&dir, "sob", SOBOLEV);
    let out = dir.path().join("r.sensors.ron");
    let csv = dir.path().join("r.csv");
    estimate(&[
        "sensors",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
        "--paths",
        "20000",
        "--seed",
        "5",
    ])
    .unwrap();
    let r = SensorResults::read_ron(&out).unwrap();
    assert_eq!(r.run.samples, 20_000);
    assert_eq!(r.run.seed, 5);
    assert_eq!(r.run.estimator, "local-estimate");
    assert_eq!(r.unit, "lx");
    assert_eq!(r.run.scene_hash.len(), 32);
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 3);
    assert!(text.starts_with("set,index,x,y,z,nx,ny,nz,value_lx,standard_error_lx,r,g,b"));
    // The z-test of `evaluate sensors` passes on correct results and fails (exit 1) against a
    // wrong case.
    let out = out.to_str().unwrap();
    let case = "sobolev:I=100,h1=1,h2=1,rho1=0.5,rho2=0.5";
    evaluate(&["sensors", out, "--case", case, "--max-z", "4"]).unwrap();
    let wrong = "sobolev:I=100,h1=1,h2=1,rho1=0.9,rho2=0.9";
    let (code, msg) = evaluate(&["sensors", out, "--case", wrong, "--max-z", "4"]).unwrap_err();
    assert_eq!(code, 1);
    assert!(msg.contains("validation failed"), "{msg}");
}

#[test]
fn bad_input_is_reported() {
    let dir = TempDir::new("est-bad");
    let no_sensors = SOBOLEV.split("    sensors:").next().unwrap().to_string() + ")";
    let scene = compile_text(&dir, "nos", &no_sensors);
    let out = dir.path().join("x.sensors.ron");
    let (code, msg) = estimate(&[
        "sensors",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ])
    .unwrap_err();
    assert_eq!(code, 1);
    assert!(msg.contains("nos.lxs: scene has no sensors"), "{msg}");
    assert!(!out.exists());
    let junk = dir.write("junk.lxs", "not a scene");
    let (code, msg) = estimate(&["sensors", junk.to_str().unwrap()]).unwrap_err();
    assert_eq!(code, 1);
    assert!(
        msg.contains("junk.lxs: not a luxest compiled scene"),
        "{msg}"
    );
    let scene = compile_text(&dir, "sob", SOBOLEV);
    let (code, _) =
        estimate(&["image", scene.to_str().unwrap(), "--resolution", "0x5"]).unwrap_err();
    assert_eq!(code, 2);
    let (code, _) = estimate(&["sensors", scene.to_str().unwrap(), "--batches", "1"]).unwrap_err();
    assert_eq!(code, 2);
    estimate(&["exact", "sobolev", "--r", "0,1"]).unwrap();
}

/// An option that would change nothing in the combination given is a usage error (exit 2,
/// one line naming it), not silently ignored; each is accepted where it does apply.
#[test]
fn options_without_effect_are_refused() {
    let dir = TempDir::new("est-no-effect");
    let scene = compile_text(&dir, "sob", SOBOLEV);
    let scene = scene.to_str().unwrap();
    let out = dir.path().join("o.sensors.ron");
    let out = out.to_str().unwrap();
    let image_out = format!("{out}.exr");
    let sensors = [
        "sensors",
        scene,
        "--paths",
        "64",
        "--batches",
        "2",
        "-o",
        out,
    ];
    let direct = [
        "direct",
        scene,
        "--paths",
        "64",
        "--batches",
        "2",
        "-o",
        out,
    ];
    let image = [
        "image",
        scene,
        "--paths",
        "64",
        "--resolution",
        "6x5",
        "-o",
        &image_out,
    ];
    let with = |base: &[&str], extra: &[&str]| -> Vec<String> {
        base.iter().chain(extra).map(|a| a.to_string()).collect()
    };
    let mut cases: Vec<(Vec<String>, &str)> = vec![
        (
            with(&sensors, &["--singularity", "none", "--eps", "0.1"]),
            "--eps has no effect with --singularity none",
        ),
        (
            with(
                &image,
                &["--singularity", "none", "--eps", "0.1", "--mis-paths", "0"],
            ),
            "--eps has no effect with --singularity none",
        ),
        (
            with(&sensors, &["--near-samples", "0", "--near-radius", "0.5"]),
            "--near-radius has no effect with --near-samples 0",
        ),
        (
            with(&direct, &["--bin-radius", "0.1", "--edge-offset", "0.01"]),
            "--edge-offset has no effect on estimate direct",
        ),
        // The scene has no mirrors or glass: with light tracing on (--mis-paths above 0, the
        // default) the kernel's treatment is used nowhere.
        (
            with(&image, &["--singularity", "ball"]),
            "--singularity/--eps has no effect with --mis-paths above 0 in",
        ),
        (
            with(&image, &["--eps", "0.01", "--mis-paths", "5"]),
            "it has no mirrors or glass",
        ),
    ];
    for extra in [
        ["--mis-paths", "3"],
        ["--pixel-samples", "2"],
        ["--singularity", "ball"],
        ["--eps", "0.1"],
    ] {
        let mut args = with(&image, &["--light-tracing"]);
        args.extend(extra.map(String::from));
        cases.push((args, "cannot be used with"));
    }
    let run = |args: &[String]| estimate(&args.iter().map(String::as_str).collect::<Vec<_>>());
    for (args, want) in &cases {
        let (code, msg) = run(args).expect_err(&format!("{args:?}"));
        assert_eq!(code, 2, "{args:?}: {msg}");
        assert!(msg.contains(want), "{args:?}: {msg}");
        assert!(!msg.trim().contains('\n'), "one line: {msg}");
        assert!(!std::path::Path::new(out).exists(), "{args:?} wrote {out}");
        assert!(!std::path::Path::new(&image_out).exists(), "{args:?}");
    }
    // Where they apply, the same options are accepted.
    run(&with(&sensors, &["--singularity", "clamp", "--eps", "0.1"])).unwrap();
    run(&with(
        &sensors,
        &["--near-samples", "10", "--near-radius", "0.5"],
    ))
    .unwrap();
    run(&with(&direct, &["--bin-radius", "0.1"])).unwrap();
    run(&with(&image, &["--light-tracing"])).unwrap();
    run(&with(
        &image,
        &["--singularity", "ball", "--eps", "0.01", "--mis-paths", "0"],
    ))
    .unwrap();
}

#[test]
fn double_local_estimate_image_matches_the_exact_luminance() {
    // Camera at the source looking straight down at plane 1: each pixel sees a Lambertian
    // point whose luminance is rho1/pi * E1(r) exactly. Per-pixel z-test with the image's own
    // standard error (direct light is exact, so the error is that of the reflected part).
    // The plain estimate (--mis-paths 0) with the raw kernel: plane 2's collisions are at
    // least h1 + h2 from plane 1's points and plane 1's own contribute nothing (cos = 0), so
    // the kernel is bounded here.
    let dir = TempDir::new("dle");
    let scene = compile_text(&dir, "sob", SOBOLEV);
    let out = dir.path().join("sob_004000le.hdr.exr");
    let se_out = dir.path().join("sob_004000le.se.exr");
    estimate(&[
        "image",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--stderr-out",
        se_out.to_str().unwrap(),
        "--paths",
        "4000",
        "--singularity",
        "none",
        "--mis-paths",
        "0",
        "--pixel-samples",
        "16",
    ])
    .unwrap();
    let img = luxest_io::exr::read_rgb(&out).unwrap();
    let se = luxest_io::exr::read_rgb(&se_out).unwrap();
    assert_eq!((img.width, img.height), (12, 10));
    assert_eq!(
        img.attribute(header::ESTIMATOR),
        Some("double-local-estimate")
    );
    assert_eq!(img.attribute(header::SAMPLES), Some("4000"));
    for y in 0..10 {
        for x in 0..12 {
            let exact_l = exact_pixel(x, y);
            let i = y * 12 + x;
            let v = luxest_io::color::Rgb(img.pixels[i].map(|c| c as f64)).luminance();
            let sigma = se.pixels[i][0] as f64;
            // 16 stratified samples per pixel: the sampling error of the pixel footprint is
            // below 0.5% (the direct term varies by < 8% across a pixel).
            assert!(
                (v - exact_l).abs() <= 4.0 * sigma + 0.005 * exact_l,
                "pixel ({x},{y}): {v} ± {sigma} vs {exact_l}"
            );
        }
    }
}

#[test]
fn light_tracing_image_matches_the_exact_box_filtered_luminance() {
    // The same view of Sobolev's plane 1 from the source, by light tracing: each pixel's value
    // is the box filter of rho1/pi * E1(r) over the pixel (4 x 4 midpoint rule: the direct
    // term varies by < 8 % across a pixel, so its error is far below 0.3 %).
    // The image's standard errors come from 8 batches (Student's t, 7 degrees of freedom):
    // each pixel within 8 of them plus the quadrature, and the mean z² below 3 (7/5 expected).
    let dir = TempDir::new("lt");
    let scene = compile_text(&dir, "sob", SOBOLEV);
    let out = dir.path().join("sob_lt.hdr.exr");
    let se_out = dir.path().join("sob_lt.se.exr");
    let run = |paths: &str| {
        estimate(&[
            "image",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--stderr-out",
            se_out.to_str().unwrap(),
            "--paths",
            paths,
            "--light-tracing",
        ])
    };
    run("250000").unwrap();
    let img = luxest_io::exr::read_rgb(&out).unwrap();
    let se = luxest_io::exr::read_rgb(&se_out).unwrap();
    assert_eq!(img.attribute(header::ESTIMATOR), Some("light-tracing"));
    assert_eq!(img.attribute(header::SAMPLES), Some("250000"));
    assert_eq!(img.attribute(header::PIXEL_SAMPLES), None);
    let mut z2 = 0.0;
    for y in 0..10 {
        for x in 0..12 {
            let exact_l = exact_pixel(x, y);
            let i = y * 12 + x;
            let v = luxest_io::color::Rgb(img.pixels[i].map(|c| c as f64)).luminance();
            let sigma = se.pixels[i][0] as f64;
            assert!(
                sigma > 0.0 && (v - exact_l).abs() <= 8.0 * sigma + 0.003 * exact_l,
                "pixel ({x},{y}): {v} ± {sigma} vs {exact_l}"
            );
            z2 += ((v - exact_l) / sigma).powi(2) / 120.0;
        }
    }
    assert!(z2 < 3.0, "mean z² {z2} (7/5 expected)");
    // Fewer paths than batches cannot give a standard error.
    let e = run("7").unwrap_err();
    assert_eq!(e.0, 2, "{}", e.1);
    assert!(e.1.contains("--paths must be at least 8"), "{}", e.1);
}
