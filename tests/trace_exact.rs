//! trace and aov-write against exact answers: white furnace, point source over a plane,
//! mirror, glass slab; energy bounds; determinism; outputs and errors.

use crate::util::{compile_text, repo_root, TempDir};
use luxest_io::header;
use luxest_io::progress::Progress;
use luxest_render::bsdf::fresnel_dielectric;
use luxest_render::compiled::CompiledScene;
use luxest_render::world::World;
use trace::{Film, Renderer};

fn render(scene: &std::path::Path, spp: u32, threads: usize) -> (World, Film) {
    let (world, cam) = trace::load(scene, None).unwrap();
    let mut film = Film::new(cam.width as usize, cam.height as usize);
    {
        let r = Renderer::new(&world, cam, 1, threads, 1024);
        r.advance(&mut film, spp, false, &Progress::off());
    }
    (world, film)
}

/// Every pixel within 4 standard errors (plus `rel` of the expectation for stated modelling
/// error) of `expected(x, y)`.
fn check(film: &Film, rel: f64, expected: impl Fn(usize, usize) -> f64) {
    let mean = film.mean();
    let se = film.standard_error();
    for y in 0..film.height {
        for x in 0..film.width {
            let i = y * film.width + x;
            let (v, e) = (mean[i].luminance(), expected(x, y));
            assert!(v.is_finite());
            assert!(
                (v - e).abs() <= 4.0 * se[i] + rel * e,
                "pixel ({x},{y}): {v} ± {} vs {e}",
                se[i]
            );
        }
    }
}

const CAMERA_INSIDE: &str = "camera: Camera(position: (0.1, -0.2, 0.05), look_at: (0.5, 0.3, 1.0), vfov_deg: 70.0, resolution: (12, 9)),";

#[test]
fn white_furnace_is_le_over_one_minus_rho() {
    // A closed Lambertian enclosure emitting Le everywhere: L = Le + rho L, so every pixel sees
    // Le / (1 - rho) exactly (any closed shape; here an icosphere seen from inside).
    let dir = TempDir::new("furnace");
    for rho in [0.5, 0.8] {
        let text = format!(
            r#"Scene({CAMERA_INSIDE}
            materials: {{ "w": Lambertian(reflectance: ({rho}, {rho}, {rho})) }},
            objects: [(shape: Sphere(radius: 1.0, subdivisions: 2), material: "w", flip_normals: true,
                       emission: Radiance((1.0, 1.0, 1.0)))])"#
        );
        let scene = compile_text(&dir, &format!("furnace-{rho}"), &text);
        // 1024 samples: the per-sample radiance is skewed (Russian roulette), and the z-test
        // needs enough samples for the sample variance to be reliable.
        let (_, film) = render(&scene, 1024, 2);
        check(&film, 0.0, |_, _| 1.0 / (1.0 - rho));
    }
}

#[test]
fn glossy_furnace_respects_energy_bounds() {
    // Energy conservation: with albedo at most d + s = 0.9, Le <= L <= Le / (1 - 0.9).
    let dir = TempDir::new("glossy-furnace");
    let text = format!(
        r#"Scene({CAMERA_INSIDE}
        materials: {{ "g": Glossy(diffuse: (0.3, 0.3, 0.3), specular: (0.6, 0.6, 0.6), roughness: 0.4) }},
        objects: [(shape: Sphere(radius: 1.0, subdivisions: 2), material: "g", flip_normals: true,
                   emission: Radiance((1.0, 1.0, 1.0)))])"#
    );
    let scene = compile_text(&dir, "glossy", &text);
    let (_, film) = render(&scene, 128, 2);
    let (mean, se) = (film.mean(), film.standard_error());
    for (m, s) in mean.iter().zip(&se) {
        let v = m.luminance();
        assert!(v >= 1.0 - 4.0 * s && v <= 10.0 + 4.0 * s, "{v} ± {s}");
        // And more than the diffuse part alone would give: the lobe reflects energy.
        assert!(v > 1.0 / (1.0 - 0.3) - 4.0 * s, "{v}");
    }
}

#[test]
fn point_source_over_a_lambertian_plane() {
    // Pixel radiance = rho/pi * I cos(theta) / d², box-filtered over the pixel.
    let dir = TempDir::new("point-plane");
    let text = r#"Scene(
        camera: Camera(position: (0.0, 2.0, -2.0), look_at: (0.0, 0.0, 0.0), vfov_deg: 30.0, resolution: (10, 8)),
        materials: { "w": Lambertian(reflectance: (0.6, 0.6, 0.6)) },
        objects: [(shape: Quad(corner: (-50.0, 0.0, 50.0), u: (100.0, 0.0, 0.0), v: (0.0, 0.0, -100.0)), material: "w")],
        point_lights: [(position: (0.3, 1.0, 0.2), power: Intensity(50.0))])"#;
    let scene = compile_text(&dir, "pp", text);
    let (_, film) = render(&scene, 64, 2);
    let compiled = CompiledScene::load(&scene).unwrap();
    let cam = luxest_render::camera::PinholeCamera::new(compiled.header.camera.as_ref().unwrap())
        .unwrap();
    check(&film, 0.002, |x, y| {
        // Box filter by an 8 x 8 midpoint rule over the pixel.
        let mut acc = 0.0;
        for a in 0..8 {
            for b in 0..8 {
                let d = cam.direction(
                    x as f64 + (a as f64 + 0.5) / 8.0,
                    y as f64 + (b as f64 + 0.5) / 8.0,
                );
                let t = -cam.position.y / d.y;
                let p = cam.position + d * t;
                let l = luxest_io::math::Vec3::new(0.3, 1.0, 0.2) - p;
                acc += 0.6 / std::f64::consts::PI * 50.0 * (l.y / l.length()) / l.length_squared();
            }
        }
        acc / 64.0
    });
}

#[test]
fn mirror_shows_the_emitter_times_its_reflectance() {
    let dir = TempDir::new("mirror");
    let text = r#"Scene(
        camera: Camera(position: (0.0, 0.0, 1.0), look_at: (0.1, 0.0, 0.0), vfov_deg: 20.0, resolution: (8, 6)),
        materials: { "m": Mirror(reflectance: (0.9, 0.8, 0.7)), "e": Lambertian(reflectance: (0.0, 0.0, 0.0)) },
        objects: [
            (shape: Quad(corner: (-50.0, -50.0, 0.0), u: (100.0, 0.0, 0.0), v: (0.0, 100.0, 0.0)), material: "m"),
            (shape: Quad(corner: (-50.0, -50.0, 2.0), u: (0.0, 100.0, 0.0), v: (100.0, 0.0, 0.0)), material: "e",
             emission: Radiance((2.0, 2.0, 2.0))),
        ])"#;
    let scene = compile_text(&dir, "mirror", text);
    let (_, film) = render(&scene, 16, 2);
    let y = luxest_io::color::Rgb([0.9, 0.8, 0.7]).luminance() * 2.0;
    check(&film, 1e-9, |_, _| y);
}

#[test]
fn glass_slab_transmits_one_minus_r_over_one_plus_r() {
    // Camera -> slab (n = 1.5, 0.1 m) -> emitter. With unpolarised Fresnel reflectance R at the
    // viewing angle on both faces and all internal reflections, T = (1 - R) / (1 + R).
    let dir = TempDir::new("slab");
    let text = r#"Scene(
        camera: Camera(position: (0.0, 0.0, 1.0), look_at: (0.0, 0.0, 0.0), vfov_deg: 40.0, resolution: (8, 6)),
        materials: { "g": Dielectric(ior: 1.5), "e": Lambertian(reflectance: (0.0, 0.0, 0.0)) },
        objects: [
            (shape: Box(size: (100.0, 100.0, 0.1)), transform: (translate: (0.0, 0.0, -0.05)), material: "g"),
            (shape: Quad(corner: (-50.0, -50.0, -1.0), u: (100.0, 0.0, 0.0), v: (0.0, 100.0, 0.0)), material: "e",
             emission: Radiance((1.0, 1.0, 1.0))),
        ])"#;
    let scene = compile_text(&dir, "slab", text);
    let (_, film) = render(&scene, 2048, 2);
    let compiled = CompiledScene::load(&scene).unwrap();
    let cam = luxest_render::camera::PinholeCamera::new(compiled.header.camera.as_ref().unwrap())
        .unwrap();
    check(&film, 0.002, |x, y| {
        let d = cam.direction(x as f64 + 0.5, y as f64 + 0.5);
        let (r, _) = fresnel_dielectric(-d.z, 1.5);
        (1.0 - r) / (1.0 + r)
    });
}

#[test]
fn images_are_independent_of_threads_and_passes() {
    let scene = repo_root().join("scenes/cornell-box.ron");
    let dir = TempDir::new("det");
    let lxs = compile_text(&dir, "cb", &std::fs::read_to_string(&scene).unwrap());
    let (world, cam) = trace::load(&lxs, Some("24x16")).unwrap();
    let one = {
        let mut f = Film::new(24, 16);
        Renderer::new(&world, cam, 3, 1, 1024).advance(&mut f, 8, false, &Progress::off());
        f.sum
    };
    let split = {
        let mut f = Film::new(24, 16);
        let r = Renderer::new(&world, cam, 3, 2, 1024);
        r.advance(&mut f, 2, false, &Progress::off());
        r.advance(&mut f, 5, false, &Progress::off());
        r.advance(&mut f, 8, false, &Progress::off());
        f.sum
    };
    // Sums of the same samples in a different grouping agree to rounding.
    for (a, b) in one.iter().zip(&split) {
        for k in 0..3 {
            assert!(
                (a[k] - b[k]).abs() <= 1e-12 * a[k].abs().max(1.0),
                "{a:?} vs {b:?}"
            );
        }
    }
}

#[test]
fn cli_writes_snapshots_references_and_features() {
    let dir = TempDir::new("trace-cli");
    let text = std::fs::read_to_string(repo_root().join("scenes/cornell-box.ron")).unwrap();
    let lxs = compile_text(&dir, "cb", &text);
    let prefix = dir.path().join("img");
    let run = |args: &[&str]| {
        let argv = std::iter::once("trace").chain(args.iter().copied());
        let a = luxest_io::cli::parse::<trace::Args>(argv).unwrap().unwrap();
        trace::run(a)
    };
    run(&[
        lxs.to_str().unwrap(),
        "-o",
        prefix.to_str().unwrap(),
        "--spp",
        "4",
        "--snapshots",
        "1,2",
        "--resolution",
        "16x12",
        "--stderr",
    ])
    .unwrap();
    for spp in ["000001", "000002", "000004"] {
        let img =
            luxest_io::exr::read_rgb(&dir.path().join(format!("img_{spp}spp.hdr.exr"))).unwrap();
        assert_eq!((img.width, img.height), (16, 12));
        assert_eq!(
            img.attribute(header::SAMPLES),
            Some(spp.trim_start_matches('0'))
        );
        assert_eq!(img.attribute(header::ESTIMATOR), Some("path-tracing"));
        assert!(dir.path().join(format!("img_{spp}spp.se.exr")).is_file());
    }
    run(&[
        lxs.to_str().unwrap(),
        "-o",
        prefix.to_str().unwrap(),
        "--spp",
        "2",
        "--reference",
        "--resolution",
        "16x12",
    ])
    .unwrap();
    assert!(dir.path().join("img_ref.hdr.exr").is_file());
    run(&[
        lxs.to_str().unwrap(),
        "-o",
        prefix.to_str().unwrap(),
        "--time",
        "0.2",
        "--resolution",
        "16x12",
    ])
    .unwrap();
    // --spp 0 is a usage error (exit 2) stating the range.
    let argv = ["trace", lxs.to_str().unwrap(), "--spp", "0"];
    let err = luxest_io::cli::parse::<trace::Args>(argv).unwrap_err();
    assert_eq!(err.exit_code(), 2);
    assert!(
        err.to_string().contains("must be a whole number in [1, "),
        "{err}"
    );
    // Features with the same pixel sampling.
    let aov = |args: &[&str]| {
        let argv = std::iter::once("aov-write").chain(args.iter().copied());
        let a = luxest_io::cli::parse::<aov_write::Args>(argv)
            .unwrap()
            .unwrap();
        aov_write::run(a)
    };
    aov(&[
        lxs.to_str().unwrap(),
        "-o",
        prefix.to_str().unwrap(),
        "--spp",
        "4",
        "--snapshots",
        "1",
        "--resolution",
        "16x12",
        "--depth",
    ])
    .unwrap();
    for f in [
        "000001spp.alb",
        "000001spp.nrm",
        "000004spp.alb",
        "000004spp.nrm",
        "000004spp.z",
    ] {
        assert!(dir.path().join(format!("img_{f}.exr")).is_file(), "{f}");
    }
    let nrm = luxest_io::exr::read_rgb(&dir.path().join("img_000004spp.nrm.exr")).unwrap();
    for p in &nrm.pixels {
        // Unit where a surface is seen, zero where the ray leaves the open box.
        let len = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        assert!(
            (len - 1.0).abs() < 1e-5 || len == 0.0,
            "normals are unit or zero: {p:?}"
        );
    }
    // The back wall's albedo and normal, at the image centre column, top half.
    let alb = luxest_io::exr::read_rgb(&dir.path().join("img_000004spp.alb.exr")).unwrap();
    let c = alb.pixels[3 * 16 + 8];
    assert!(
        (c[0] - 0.725).abs() < 1e-6 && (c[1] - 0.71).abs() < 1e-6,
        "{c:?}"
    );
    let n = nrm.pixels[3 * 16 + 8];
    assert!((n[2] + 1.0).abs() < 1e-5, "back wall faces -z: {n:?}");
}

#[test]
fn scene_without_camera_is_an_error() {
    let dir = TempDir::new("nocam");
    let text = std::fs::read_to_string(repo_root().join("scenes/sobolev.ron")).unwrap();
    let lxs = compile_text(&dir, "s", &text);
    let argv = ["trace", lxs.to_str().unwrap(), "--spp", "1"];
    let a = luxest_io::cli::parse::<trace::Args>(argv).unwrap().unwrap();
    let e = trace::run(a).unwrap_err();
    assert_eq!(e.exit_code(), 1);
    assert!(e.to_string().contains("s.lxs: scene has no camera"), "{e}");
}

/// aov-write's emission image is the emission `trace` adds at its camera rays' first hits, at
/// the same pixel positions: every value is a whole number of the light's samples (k/n of its
/// radiance), the light is seen, and nowhere does the emission exceed the path-traced radiance
/// of the same seed and samples (it would at the light's edges if the positions differed).
#[test]
fn emission_feature_is_the_radiance_trace_sees_emitted() {
    let dir = TempDir::new("aov-emi");
    let text = std::fs::read_to_string(repo_root().join("scenes/cornell-box.ron")).unwrap();
    let lxs = compile_text(&dir, "cb", &text);
    let read = trace_and_features(&dir, &lxs, 4, 11);
    let (hdr, emi) = (read("hdr"), read("emi"));
    let light = [17.0f32, 12.0, 4.0];
    let (mut full, mut partial) = (0, 0);
    for (h, e) in hdr.pixels.iter().zip(&emi.pixels) {
        let k = e[0] / light[0] * 4.0;
        assert!(
            (k - k.round()).abs() < 1e-5,
            "{e:?} is not k/4 of the light"
        );
        for c in 0..3 {
            assert!(
                (e[c] - k.round() / 4.0 * light[c]).abs() < 1e-5 * light[c],
                "{e:?}: not the light's colour"
            );
            assert!(
                e[c] <= h[c] * (1.0 + 1e-6),
                "emission {e:?} above radiance {h:?}"
            );
        }
        match k.round() as i32 {
            4 => full += 1,
            1..=3 => partial += 1,
            _ => {}
        }
    }
    assert!(
        full > 4 && partial > 0,
        "light seen: {full} full, {partial} partial pixels"
    );
}

/// `--min-samples N`: the albedo, normal and antialiased emission (`ema`) of a level below N are
/// exactly those of N samples of the same sequence (a run to N without the option), recorded as
/// such in the header; the emission (`emi`) keeps the level's own samples (it is what trace's
/// image of those samples contains); levels of N or more samples are as without the option.
#[test]
fn features_average_at_least_min_samples_and_the_emission_its_own() {
    let dir = TempDir::new("aov-min");
    let text = std::fs::read_to_string(repo_root().join("scenes/cornell-box.ron")).unwrap();
    let lxs = compile_text(&dir, "cb", &text);
    let run = |name: &str, extra: &[&str]| {
        let prefix = dir.path().join(name);
        let mut argv = vec![
            "aov-write",
            lxs.to_str().unwrap(),
            "--resolution",
            "32x24",
            "--seed",
            "5",
            "--threads",
            "2",
            "-o",
            prefix.to_str().unwrap(),
        ];
        argv.extend_from_slice(extra);
        aov_write::run(
            luxest_io::cli::parse::<aov_write::Args>(argv)
                .unwrap()
                .unwrap(),
        )
        .unwrap();
    };
    run(
        "a",
        &["--spp", "4", "--snapshots", "1,2", "--min-samples", "3"],
    );
    run(
        "b",
        &["--spp", "4", "--snapshots", "1,2,3", "--min-samples", "1"],
    );
    let read = |name: &str| luxest_io::exr::read_rgb(&dir.path().join(name)).unwrap();
    let samples = |name: &str| {
        read(name)
            .attribute(header::SAMPLES)
            .unwrap_or_default()
            .to_string()
    };
    for level in ["000001spp", "000002spp"] {
        for kind in ["alb", "nrm"] {
            let (a, b) = (
                read(&format!("a_{level}.{kind}.exr")),
                read(&format!("b_000003spp.{kind}.exr")),
            );
            assert_eq!(a.pixels, b.pixels, "{level}.{kind}");
            assert_eq!(samples(&format!("a_{level}.{kind}.exr")), "3");
        }
        let (a, b) = (
            read(&format!("a_{level}.emi.exr")),
            read(&format!("b_{level}.emi.exr")),
        );
        assert_eq!(a.pixels, b.pixels, "{level}.emi");
        assert_eq!(
            samples(&format!("a_{level}.emi.exr")),
            samples(&format!("b_{level}.emi.exr"))
        );
        // The antialiased emission is the emission of the features' samples.
        let (a, b) = (
            read(&format!("a_{level}.ema.exr")),
            read("b_000003spp.emi.exr"),
        );
        assert_eq!(a.pixels, b.pixels, "{level}.ema");
        assert_eq!(samples(&format!("a_{level}.ema.exr")), "3");
    }
    assert_eq!(
        read("a_000004spp.ema.exr").pixels,
        read("a_000004spp.emi.exr").pixels
    );
    for kind in ["alb", "nrm", "emi"] {
        let name = format!("000004spp.{kind}.exr");
        assert_eq!(
            read(&format!("a_{name}")).pixels,
            read(&format!("b_{name}")).pixels
        );
    }
    // Antialiased: a 1-spp albedo of one sample per pixel is one material's at every pixel; the
    // three-sample one mixes materials at edges.
    let one = read("b_000001spp.alb.exr");
    let three = read("a_000001spp.alb.exr");
    let mixed = |img: &luxest_io::image::RgbImage| {
        img.pixels
            .iter()
            .filter(|p| !one.pixels.iter().any(|q| q == *p))
            .count()
    };
    assert_eq!(mixed(&one), 0);
    assert!(
        mixed(&three) > 0,
        "no pixel of three samples mixes materials"
    );
}

/// Features through perfect specular surfaces (Intel Open Image Denoise's recommendation): the
/// Cornell box with every diffuse reflectance 0.6, its back wall a mirror of reflectance 0.5 and
/// its tall block glass, at one sample per pixel. A pixel seeing the mirror has the albedo of
/// what the mirror shows times 0.5 (0.3, or 0 where it shows the open front), never the
/// mirror's own 0.5; glass shows a Fresnel blend of what lies behind and in front of it, not
/// 1; the light seen in the mirror is in the emission image at half its radiance, and the
/// emission nowhere exceeds the radiance trace sees through the same samples (it adds exactly
/// that term: the mirror's reflection is not sampled, and Russian roulette starts later).
#[test]
fn features_follow_mirrors_and_glass() {
    let dir = TempDir::new("aov-delta");
    let mut text = std::fs::read_to_string(repo_root().join("scenes/cornell-box.ron")).unwrap();
    for (name, old) in [
        ("white", "(0.725, 0.71, 0.68)"),
        ("red", "(0.63, 0.065, 0.05)"),
        ("green", "(0.14, 0.45, 0.091)"),
        ("light", "(0.78, 0.78, 0.78)"),
    ] {
        let line = format!("\"{name}\": Lambertian(reflectance: {old}),");
        assert!(text.contains(&line), "{line}");
        text = text.replace(
            &line,
            &format!("\"{name}\": Lambertian(reflectance: (0.6, 0.6, 0.6)),"),
        );
    }
    text = text.replace(
        "materials: {",
        "materials: {\n        \"mirror\": Mirror(reflectance: (0.5, 0.5, 0.5)),\n        \"glass\": Dielectric(ior: 1.5),",
    );
    // The back wall's and the tall block's faces: the material line after each name.
    let mut out = String::new();
    let mut pending = None;
    for line in text.lines() {
        if line.contains("name: \"back-wall\"") {
            pending = Some("mirror");
        } else if line.contains("name: \"tall-block-") {
            pending = Some("glass");
        }
        match pending {
            Some(m) if line.contains("material: \"white\"") => {
                out.push_str(&line.replace("white", m));
                pending = None;
            }
            _ => out.push_str(line),
        }
        out.push('\n');
    }
    let lxs = compile_text(&dir, "cb", &out);
    let read = trace_and_features(&dir, &lxs, 1, 3);
    let (hdr, alb, emi) = (read("hdr"), read("alb"), read("emi"));
    let near = |a: f32, b: f32| (a - b).abs() < 1e-6;
    let in_mirror = alb.pixels.iter().filter(|a| near(a[0], 0.3)).count();
    assert!(
        in_mirror > alb.pixels.len() / 20,
        "{in_mirror} pixels show 0.5 times a 0.6 surface"
    );
    for a in &alb.pixels {
        assert!(!near(a[0], 0.5), "the mirror's own reflectance as albedo");
    }
    // Glass's own albedo (1) only where a path runs out of delta vertices inside it.
    let above = alb.pixels.iter().filter(|a| a[0] > 0.6 + 1e-6).count();
    assert!(
        above <= 3,
        "{above} pixels with an albedo above every surface's (glass as 1?)"
    );
    let light = [17.0f32, 12.0, 4.0];
    let mut mirrored = 0;
    for (h, e) in hdr.pixels.iter().zip(&emi.pixels) {
        for c in 0..3 {
            assert!(
                e[c] <= h[c] * (1.0 + 1e-6),
                "emission {e:?} above radiance {h:?}"
            );
        }
        if (0..3).all(|c| near(e[c] / light[c], 0.5)) {
            mirrored += 1;
        }
    }
    assert!(
        mirrored > 0,
        "the light seen in the mirror, at half its radiance"
    );
}

/// `trace` and then `aov-write` of `lxs` with the same arguments (`spp` samples, `seed`, 64×48,
/// prefix `img` in `dir`); returns a reader of the images of that sample count by kind (`hdr`,
/// `alb`, `emi`, ...).
fn trace_and_features(
    dir: &TempDir,
    lxs: &std::path::Path,
    spp: u32,
    seed: u64,
) -> impl Fn(&str) -> luxest_io::image::RgbImage {
    let prefix = dir.path().join("img");
    let (spp_arg, seed_arg) = (spp.to_string(), seed.to_string());
    let args = [
        lxs.to_str().unwrap(),
        "-o",
        prefix.to_str().unwrap(),
        "--spp",
        &spp_arg,
        "--resolution",
        "64x48",
        "--seed",
        &seed_arg,
    ];
    let argv = std::iter::once("trace").chain(args.iter().copied());
    trace::run(luxest_io::cli::parse::<trace::Args>(argv).unwrap().unwrap()).unwrap();
    let argv = std::iter::once("aov-write").chain(args.iter().copied());
    aov_write::run(
        luxest_io::cli::parse::<aov_write::Args>(argv)
            .unwrap()
            .unwrap(),
    )
    .unwrap();
    move |kind: &str| {
        use luxest_io::naming::{image_path, Kind, Level};
        let kind = Kind::from_tag(kind).unwrap();
        let path = image_path(&prefix, Level::Spp(spp.into()), kind);
        luxest_io::exr::read_rgb(&path).unwrap()
    }
}
