//! Textured, cut-out and one-sided surfaces and textured emitters through every estimator:
//! each textured result is compared with what the same scene gives untextured with the
//! texel's value (an identity the texture lookup must keep), or with the exact direct light.

use crate::estimate_validation::below_square_emitter;
use crate::util::{compile_text, scene_compile, TempDir};
use estimate::local_estimate::{self as local, LocalConfig, Singularity};
use estimate::sensor_batches::Batches;
use luxest_io::image::RgbImage;
use luxest_io::progress::Progress;
use luxest_render::compiled::{CompiledScene, Emitter};
use luxest_render::world::{load_with_camera, Traversal, World};
use std::f64::consts::PI;
use std::path::Path;
use trace::{Film, Renderer};

/// A linear EXR texture of one row of grey texels.
fn grey_row(dir: &TempDir, name: &str, values: &[f32]) -> String {
    let mut image = RgbImage::new(values.len(), 1);
    for (p, &v) in image.pixels.iter_mut().zip(values) {
        *p = [v, v, v];
    }
    let path = dir.path().join(name);
    luxest_io::exr::write_rgb(&path, &image).unwrap();
    name.to_string()
}

/// A 2 m floor (u from 0 at x = −1 to 1 at x = +1) lit by a 1 cd point source 1 m above its
/// centre, seen from 2 m above; `material` and `surfaces` as given.
fn floor_scene(material: &str, surfaces: &str) -> String {
    format!(
        r#"Scene(
        camera: Camera(position: (0.0, 2.0, 0.0), look_at: (0.0, 0.0, 0.0), up: (0.0, 0.0, 1.0),
                       vfov_deg: 50.0, resolution: (16, 8)),
        materials: {{ "floor": {material} }},
        objects: [(shape: Quad(corner: (-1.0, 0.0, 1.0), u: (2.0, 0.0, 0.0), v: (0.0, 0.0, -2.0)),
                   material: "floor")],
        point_lights: [(position: (0.0, 1.0, 0.0), power: Intensity(1.0))],
        {surfaces})"#
    )
}

/// The x of the floor points seen through the corners of pixel (px, py), if all of them see
/// the floor (|x|, |z| < 1).
fn floor_corners(
    cam: &luxest_render::camera::PinholeCamera,
    px: usize,
    py: usize,
) -> Option<Vec<f64>> {
    let corners: Vec<(f64, f64)> = [0.0f64, 1.0]
        .iter()
        .flat_map(|&dx| {
            [0.0f64, 1.0].map(|dy| {
                let d = cam.direction(px as f64 + dx, py as f64 + dy);
                let t = -cam.position.y / d.y;
                (cam.position.x + t * d.x, cam.position.z + t * d.z)
            })
        })
        .collect();
    let inside = corners.iter().all(|&(x, z)| x.abs() < 1.0 && z.abs() < 1.0);
    inside.then(|| corners.iter().map(|c| c.0).collect())
}

/// The side (−1 or +1) of x = 0 on which the floor seen through pixel (px, py) lies, if the
/// whole pixel sees the floor on one side.
fn pixel_side(cam: &luxest_render::camera::PinholeCamera, px: usize, py: usize) -> Option<f64> {
    let xs = floor_corners(cam, px, py)?;
    let first = xs[0].signum();
    xs.iter().all(|x| x.signum() == first).then_some(first)
}

fn trace_film(scene: &Path, spp: u32) -> (luxest_render::camera::PinholeCamera, Film) {
    let (world, cam) = trace::load(scene, None).unwrap();
    let mut film = Film::new(cam.width as usize, cam.height as usize);
    {
        let r = Renderer::new(&world, cam, 1, 2, 1024);
        r.advance(&mut film, spp, false, &Progress::off());
    }
    (cam, film)
}

const LEFT: f32 = 0.2;
const RIGHT: f32 = 0.8;

fn textured_floor(dir: &TempDir) -> std::path::PathBuf {
    grey_row(dir, "halves.exr", &[LEFT, RIGHT]);
    let text = floor_scene(
        "Lambertian(reflectance: (1.0, 1.0, 1.0))",
        r#"textures: { "halves": (path: "halves.exr", filter: Nearest) },
           surfaces: { "floor": (color: Some("halves")) },"#,
    );
    compile_text(dir, "textured", &text)
}

#[test]
fn trace_multiplies_the_reflectance_by_the_texel() {
    // Direct light from a point source only (the floor is alone): with the same samples, a
    // pixel of the textured floor is exactly the texel's value times the pixel of a white floor.
    let dir = TempDir::new("tex-trace");
    let textured = textured_floor(&dir);
    let white = compile_text(
        &dir,
        "white",
        &floor_scene("Lambertian(reflectance: (1.0, 1.0, 1.0))", ""),
    );
    let (cam, t) = trace_film(&textured, 16);
    let (_, w) = trace_film(&white, 16);
    let (tm, wm) = (t.mean(), w.mean());
    let mut checked = [0, 0];
    for py in 0..cam.height as usize {
        for px in 0..cam.width as usize {
            let Some(side) = pixel_side(&cam, px, py) else {
                continue;
            };
            let i = py * cam.width as usize + px;
            let rho = if side < 0.0 { LEFT } else { RIGHT } as f64;
            let (a, b) = (tm[i].luminance(), wm[i].luminance());
            assert!(b > 0.0);
            assert!(
                (a - rho * b).abs() <= 1e-6 * b,
                "pixel ({px},{py}): {a} vs {rho} × {b}"
            );
            checked[(side > 0.0) as usize] += 1;
        }
    }
    assert!(checked[0] >= 16 && checked[1] >= 16, "{checked:?}");
}

/// Mean luminance and its standard error over the pixels wholly on `side` of x = 0.
fn side_mean(
    cam: &luxest_render::camera::PinholeCamera,
    r: &estimate::image::ImageResult,
    side: f64,
) -> (f64, f64) {
    let (mut sum, mut var, mut n) = (0.0, 0.0, 0.0);
    for py in 0..r.height {
        for px in 0..r.width {
            if pixel_side(cam, px, py) == Some(side) {
                let i = py * r.width + px;
                sum += r.rgb[i].luminance();
                var += r.standard_error[i].powi(2);
                n += 1.0;
            }
        }
    }
    (sum / n, var.sqrt() / n)
}

#[test]
fn light_tracing_and_the_double_local_estimate_see_the_texture() {
    // Each half of the textured floor is the texel's value times the white floor's, within the
    // two estimates' standard errors (independent seeds).
    let dir = TempDir::new("tex-dle");
    let textured = textured_floor(&dir);
    let white = compile_text(
        &dir,
        "white",
        &floor_scene("Lambertian(reflectance: (1.0, 1.0, 1.0))", ""),
    );
    let dle = |scene: &Path, seed: u64| {
        let (world, cam) = load_with_camera(scene, None, Traversal::Robust).unwrap();
        let r = estimate::double_local_estimate::render(
            &world,
            &cam,
            &estimate::double_local_estimate::ImageConfig {
                paths: 20_000,
                pixel_samples: 1,
                seed,
                threads: 2,
                singularity: Singularity::Ball { eps: 1e-3 },
                max_depth: 100,
                mis_paths: 1,
            },
            &luxest_io::cli::Console::QUIET,
        );
        (cam, r)
    };
    let lt = |scene: &Path, seed: u64| {
        let (world, cam) = load_with_camera(scene, None, Traversal::Robust).unwrap();
        let r = estimate::light_tracing::render(
            &world,
            &cam,
            &estimate::light_tracing::LightTraceConfig {
                paths: 200_000,
                seed,
                threads: 2,
                max_depth: 100,
            },
            &Progress::off(),
        );
        (cam, r)
    };
    for (name, run) in [
        ("double local estimate", &dle as &dyn Fn(&Path, u64) -> _),
        ("light tracing", &lt),
    ] {
        let (cam, t) = run(&textured, 1);
        let (_, w) = run(&white, 2);
        for (side, rho) in [(-1.0, LEFT), (1.0, RIGHT)] {
            let (a, sa) = side_mean(&cam, &t, side);
            let (b, sb) = side_mean(&cam, &w, side);
            let rho = rho as f64;
            let se = (sa * sa + rho * rho * sb * sb).sqrt();
            assert!(
                (a - rho * b).abs() <= 4.0 * se,
                "{name}, side {side}: {a} ± {sa} vs {rho} × ({b} ± {sb})"
            );
        }
    }
}

#[test]
fn a_textured_emitter_lights_a_sensor_as_its_mean_luminance_does() {
    // A 1 m square lamp 1 m above an upward sensor, its halves at 100 and 300 cd/m²: by
    // symmetry the sensor gets what a uniform 200 cd/m² lamp gives it (exact), and the lamp's
    // flux is π A · 200 lm.
    let dir = TempDir::new("tex-emitter");
    grey_row(&dir, "lamp.exr", &[1.0, 3.0]);
    let text = r#"Scene(
        materials: { "black": Lambertian(reflectance: (0.0, 0.0, 0.0)) },
        objects: [(shape: Quad(corner: (-0.5, 1.0, -0.5), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, 1.0)),
                   material: "black", emission: Texture(texture: "lamp", scale: (100.0, 100.0, 100.0)))],
        sensors: [Points(name: "below", points: [(position: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0))])],
        textures: { "lamp": (path: "lamp.exr", filter: Nearest) },
    )"#;
    let scene = compile_text(&dir, "lamp", text);
    let compiled = CompiledScene::load(&scene).unwrap();
    let Emitter::Area { flux_rgb, .. } = &compiled.header.emitters[0] else {
        panic!("an area emitter")
    };
    let flux = flux_rgb.luminance();
    assert!(
        (flux / (PI * 200.0) - 1.0).abs() < 0.02,
        "{flux} vs {}",
        PI * 200.0
    );
    let world = World::new(compiled).unwrap();
    let sensors = estimate::all_sensors(&world);
    let r = local::estimate(
        &world,
        &sensors,
        &[0.0],
        &LocalConfig {
            batches: Batches {
                paths: 400_000,
                batches: 32,
                seed: 5,
                threads: 2,
            },
            singularity: Singularity::Ball { eps: 1e-3 },
            max_depth: 10,
            near_field: None,
            environment_samples: 0,
        },
        &Progress::off(),
    );
    let e = r.estimates()[0];
    let exact = below_square_emitter(200.0, 1.0, 1.0);
    assert!(
        (e.value - exact).abs() <= 4.0 * e.standard_error,
        "{} ± {} vs {exact}",
        e.value,
        e.standard_error
    );
}

/// A black 2 m square 1 m below a 1 cd source 2 m above a grid of upward sensors, with the
/// given surface; the sensors' illuminance and the unoccluded one.
fn under_occluder(dir: &TempDir, surfaces: &str, counts: u32) -> (Vec<f64>, Vec<f64>) {
    let text = format!(
        r#"Scene(
        materials: {{ "screen": Lambertian(reflectance: (0.0, 0.0, 0.0)) }},
        objects: [(shape: Quad(corner: (-1.0, 1.0, 1.0), u: (2.0, 0.0, 0.0), v: (0.0, 0.0, -2.0)),
                   material: "screen")],
        point_lights: [(position: (0.0, 2.0, 0.0), power: Intensity(1.0))],
        sensors: [Grid(name: "floor", corner: (-0.8, 0.0, -0.8), u: (1.6, 0.0, 0.0), v: (0.0, 0.0, 1.6),
                       counts: ({counts}, {counts}), normal: (0.0, 1.0, 0.0))],
        {surfaces})"#
    );
    let scene = compile_text(dir, "occluder", &text);
    let world = World::new(CompiledScene::load(&scene).unwrap()).unwrap();
    let sensors = estimate::all_sensors(&world);
    let r = local::estimate(
        &world,
        &sensors,
        &vec![0.0; sensors.len()],
        &LocalConfig {
            batches: Batches {
                paths: 64,
                batches: 8,
                seed: 1,
                threads: 2,
            },
            singularity: Singularity::Ball { eps: 1e-3 },
            max_depth: 10,
            near_field: None,
            environment_samples: 0,
        },
        &Progress::off(),
    );
    let open = sensors
        .iter()
        .map(|s| {
            let v = luxest_io::math::Vec3::new(0.0, 2.0, 0.0) - s.position;
            let d2 = v.length_squared();
            v.y / d2.sqrt() / d2
        })
        .collect();
    let got = r.estimates().iter().map(|e| e.value).collect();
    (got, open)
}

#[test]
fn cut_outs_let_light_through_where_they_are_transparent() {
    // Opacity texture (0 | 1) with cut-off ½: the left half of the screen is not there, so
    // sensors left of x = 0 (whose line to the source crosses the screen at x/2) get the open
    // illuminance and the others none.
    let dir = TempDir::new("tex-cutout");
    grey_row(&dir, "alpha.exr", &[0.0, 1.0]);
    let (got, open) = under_occluder(
        &dir,
        r#"textures: { "alpha": (path: "alpha.exr", filter: Nearest) },
           surfaces: { "screen": (opacity: Some((texture: Some("alpha"), cutoff: Some(0.5)))) },"#,
        8,
    );
    for (k, (g, o)) in got.iter().zip(&open).enumerate() {
        let left = k % 8 < 4;
        let expected = if left { *o } else { 0.0 };
        assert!(
            (g - expected).abs() <= 1e-9 * o,
            "sensor {k}: {g} vs {expected}"
        );
    }
}

#[test]
fn stochastic_opacity_passes_its_share_of_the_light() {
    // Constant opacity 0.3 without a cut-off: each shadow ray passes with probability 0.7, so
    // about 70 % of 400 sensors are lit (binomial: ±4σ = ±0.092).
    let dir = TempDir::new("tex-stochastic");
    let (got, open) = under_occluder(
        &dir,
        r#"surfaces: { "screen": (opacity: Some((value: 0.3))) },"#,
        20,
    );
    let lit = got
        .iter()
        .zip(&open)
        .filter(|(g, o)| {
            assert!(**g == 0.0 || (*g - *o).abs() <= 1e-9 * *o, "{g} vs {o}");
            **g > 0.0
        })
        .count();
    let share = lit as f64 / got.len() as f64;
    assert!(
        (share - 0.7).abs() <= 4.0 * (0.21f64 / 400.0).sqrt(),
        "{share}"
    );
}

#[test]
fn a_one_sided_surface_is_black_from_the_back() {
    // Seen from below and lit from below, a floor reflects only if it is two-sided.
    let dir = TempDir::new("tex-one-sided");
    let below = |two_sided: bool| {
        format!(
            r#"Scene(
            camera: Camera(position: (0.0, -2.0, 0.0), look_at: (0.0, 0.0, 0.0), up: (0.0, 0.0, 1.0),
                           vfov_deg: 30.0, resolution: (4, 4)),
            materials: {{ "floor": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
            objects: [(shape: Quad(corner: (-1.0, 0.0, 1.0), u: (2.0, 0.0, 0.0), v: (0.0, 0.0, -2.0)),
                       material: "floor")],
            point_lights: [(position: (0.0, -1.0, 0.0), power: Intensity(1.0))],
            surfaces: {{ "floor": (two_sided: {two_sided}) }})"#
        )
    };
    let one = compile_text(&dir, "one", &below(false));
    let two = compile_text(&dir, "two", &below(true));
    let (_, a) = trace_film(&one, 4);
    let (_, b) = trace_film(&two, 4);
    assert!(a.mean().iter().all(|p| p.max_component() == 0.0));
    assert!(b.mean().iter().all(|p| p.luminance() > 0.0));
}

#[test]
fn textured_surfaces_need_texture_coordinates_and_existing_textures() {
    let dir = TempDir::new("tex-errors");
    grey_row(&dir, "t.exr", &[0.5]);
    let scene = |shape: &str, texture_path: &str, color: &str| {
        format!(
            r#"Scene(
            materials: {{ "m": Lambertian(reflectance: (1.0, 1.0, 1.0)) }},
            objects: [(shape: {shape}, material: "m")],
            point_lights: [(position: (0.0, 2.0, 0.0), power: Intensity(1.0))],
            textures: {{ "t": (path: "{texture_path}") }},
            surfaces: {{ "m": (color: Some("{color}")) }})"#
        )
    };
    let fail = |name: &str, text: String| -> String {
        let ron = dir.write(&format!("{name}.ron"), text);
        let out = dir.path().join(format!("{name}.lxs"));
        let (code, msg) =
            scene_compile(&[ron.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]).unwrap_err();
        assert_eq!(code, 1, "{msg}");
        assert!(!out.exists());
        assert_eq!(msg.lines().count(), 1, "{msg}");
        msg
    };
    let sphere = "Sphere(radius: 1.0, subdivisions: 1)";
    let quad = "Quad(corner: (0.0, 0.0, 0.0), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, 1.0))";
    let m = fail("no-uv", scene(sphere, "t.exr", "t"));
    assert!(
        m.contains("objects[0]") && m.contains("no texture coordinates"),
        "{m}"
    );
    let m = fail("unknown", scene(quad, "t.exr", "u"));
    assert!(
        m.contains("surfaces[\"m\"].color") && m.contains("unknown texture"),
        "{m}"
    );
    let m = fail("missing", scene(quad, "gone.exr", "t"));
    assert!(
        m.contains("textures[\"t\"].path") && m.contains("not found"),
        "{m}"
    );
    dir.write("bad.exr", b"not an image");
    let m = fail("corrupt", scene(quad, "bad.exr", "t"));
    assert!(m.contains("bad.exr"), "{m}");
    // A surface entry for a material that does not exist.
    let text = scene(quad, "t.exr", "t").replace(r#"surfaces: { "m""#, r#"surfaces: { "n""#);
    let m = fail("orphan", text);
    assert!(m.contains("surfaces[\"n\"]"), "{m}");
}

#[test]
fn feature_albedo_filters_a_minified_texture_over_the_pixel() {
    // A 512² checkerboard of single texels (0 | 1) on the 2 m floor, 16 pixels across: one
    // pixel covers tens of texels, so the filtered albedo of one ray through a pixel centre is
    // their mean, ½; looked up at the finest level it is one bilinear lookup of 0s and 1s.
    let dir = TempDir::new("tex-aov");
    let n = 512;
    let mut image = RgbImage::new(n, n);
    for (k, p) in image.pixels.iter_mut().enumerate() {
        let v = ((k % n + k / n) % 2) as f32;
        *p = [v, v, v];
    }
    luxest_io::exr::write_rgb(&dir.path().join("checker.exr"), &image).unwrap();
    let text = floor_scene(
        "Lambertian(reflectance: (1.0, 1.0, 1.0))",
        r#"textures: { "checker": (path: "checker.exr") },
           surfaces: { "floor": (color: Some("checker")) },"#,
    );
    let scene = compile_text(&dir, "checker", &text);
    let (world, cam) = load_with_camera(&scene, None, Traversal::Fast).unwrap();
    let mut points = Vec::new();
    for py in 0..cam.height as usize {
        for px in 0..cam.width as usize {
            if floor_corners(&cam, px, py).is_none() {
                continue;
            }
            let d = cam.direction(px as f64 + 0.5, py as f64 + 0.5);
            let filtered = aov_write::first_hit(&world, cam.position, d, cam.pixel_spread());
            let point = aov_write::first_hit(&world, cam.position, d, 0.0);
            if filtered.depth == 0.0 {
                continue;
            }
            let (f, p) = (filtered.albedo.luminance(), point.albedo.luminance());
            assert!(
                (f - 0.5).abs() < 0.05,
                "pixel ({px},{py}): filtered albedo {f}"
            );
            points.push(p);
        }
    }
    assert!(points.len() >= 32, "{}", points.len());
    // Unfiltered, the pixels alias: their albedos scatter over [0, 1] (a uniform spread has a
    // standard deviation of 0.29; the filtered ones are within 0.05 of ½).
    let mean = points.iter().sum::<f64>() / points.len() as f64;
    let sd = (points.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / points.len() as f64).sqrt();
    assert!(sd > 0.15, "finest-level albedo spread {sd}");
}

#[test]
fn the_mitsuba_export_writes_textures_cut_outs_and_sidedness() {
    // What Mitsuba 3 needs to render the textured scene as luxest does: texture coordinates in
    // the OBJ, the colour texture baked with its constant into a bitmap, a mask for the
    // cut-out, no `twosided` around a one-sided material.
    let dir = TempDir::new("tex-export");
    grey_row(&dir, "halves.exr", &[LEFT, RIGHT]);
    let text = floor_scene(
        "Lambertian(reflectance: (0.5, 0.5, 0.5))",
        r#"textures: { "halves": (path: "halves.exr", filter: Nearest, wrap: Clamp) },
           surfaces: { "floor": (color: Some("halves"), two_sided: false,
                                 opacity: Some((texture: Some("halves"), cutoff: Some(0.5)))) },"#,
    );
    let ron = dir.write("export.ron", text);
    let out = dir.path().join("export.lxs");
    let mitsuba = dir.path().join("mitsuba");
    scene_compile(&[
        ron.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--export-mitsuba",
        mitsuba.to_str().unwrap(),
        "-q",
    ])
    .unwrap();
    let xml = std::fs::read_to_string(mitsuba.join("scene.xml")).unwrap();
    assert!(xml.contains(r#"<bsdf type="mask">"#), "{xml}");
    assert!(!xml.contains("twosided"), "{xml}");
    assert!(
        xml.contains(r#"<string name="filter_type" value="nearest"/>"#),
        "{xml}"
    );
    assert!(
        xml.contains(r#"<string name="wrap_mode" value="clamp"/>"#),
        "{xml}"
    );
    let obj = std::fs::read_to_string(mitsuba.join("mesh_000.obj")).unwrap();
    assert_eq!(
        obj.lines().filter(|l| l.starts_with("vt ")).count(),
        4,
        "{obj}"
    );
    assert!(obj.lines().any(|l| l.starts_with("f 1/1 ")), "{obj}");
    // The baked reflectance: texel × 0.5; the baked opacity: texel ≥ ½.
    let read = |name: &str| {
        let file = xml
            .split('"')
            .find(|f| f.starts_with(name) && f.ends_with(".exr"))
            .unwrap_or_else(|| panic!("no {name}*.exr in {xml}"))
            .to_string();
        luxest_io::exr::read_rgb(&mitsuba.join(file)).unwrap()
    };
    let reflectance = read("material_000_reflectance");
    assert_eq!(reflectance.pixels[0][0], LEFT * 0.5);
    assert_eq!(reflectance.pixels[1][0], RIGHT * 0.5);
    let opacity = read("opacity_000");
    assert_eq!((opacity.pixels[0][0], opacity.pixels[1][0]), (0.0, 1.0));
}

#[test]
fn a_blend_of_mirror_and_matte_in_a_white_furnace_is_exact() {
    // A convex object under a constant sky L = 1 reflects, where it is seen, exactly the
    // albedo of its material: (1 − w) ρ + w for a blend of weight w of a matte ρ and a perfect
    // mirror, through both the delta and the diffuse member (a renderer that weighs a delta
    // sample with the other member's density — Mitsuba 3's blendbsdf does — misses it).
    let dir = TempDir::new("blend-furnace");
    let (w, rho) = (0.3, 0.5);
    let text = format!(
        r#"Scene(
        camera: Camera(position: (0.0, 0.0, -4.0), look_at: (0.0, 0.0, 0.0), vfov_deg: 30.0,
                       resolution: (16, 16)),
        materials: {{ "b": Blend(weight: {w}, first: Lambertian(reflectance: ({rho}, {rho}, {rho})),
                                 second: Mirror(reflectance: (1.0, 1.0, 1.0))) }},
        objects: [(shape: Sphere(radius: 1.0, subdivisions: 3), material: "b")],
        environment: Some(Constant((1.0, 1.0, 1.0))))"#
    );
    let scene = compile_text(&dir, "blend", &text);
    let (cam, film) = trace_film(&scene, 256);
    let (mean, se) = (film.mean(), film.standard_error());
    let expected = (1.0 - w) * rho + w;
    let mut checked = 0;
    for py in 0..cam.height as usize {
        for px in 0..cam.width as usize {
            // Pixels whose corners all see a sphere of radius 0.9 (inside the icosphere).
            let inside =
                [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                    .iter()
                    .all(|&(dx, dy)| {
                        let d = cam.direction(px as f64 + dx, py as f64 + dy);
                        let o = cam.position;
                        let b = o.dot(d);
                        b * b - (o.length_squared() - 0.81) > 0.0
                    });
            if !inside {
                continue;
            }
            let i = py * cam.width as usize + px;
            let v = mean[i].luminance();
            assert!(
                (v - expected).abs() <= 4.0 * se[i] + 1e-9,
                "pixel ({px},{py}): {v} ± {} vs {expected}",
                se[i]
            );
            checked += 1;
        }
    }
    assert!(checked >= 40, "{checked}");
}

#[test]
fn an_imported_checkerboard_is_mitsubas() {
    // Mitsuba 3's checkerboard (src/textures/checkerboard.cpp): color0 where uv − ⌊uv⌋ > ½ holds
    // for both coordinates or for neither, color1 elsewhere, after to_uv. Imported from XML and
    // looked up at the hit's texture coordinates, away from the lines where the halves meet.
    let dir = TempDir::new("checkerboard");
    let xml = dir.write(
        "checker.xml",
        r#"<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
  <shape type="rectangle">
    <bsdf type="twosided"><bsdf type="diffuse">
      <texture type="checkerboard" name="reflectance">
        <rgb name="color0" value="0.8, 0.7, 0.6"/><rgb name="color1" value="0.1, 0.2, 0.3"/>
        <transform name="to_uv"><scale x="3" y="2"/></transform>
      </texture></bsdf></bsdf>
  </shape>
  <emitter type="point"><point name="position" value="0, 0, 2"/><rgb name="intensity" value="1, 1, 1"/></emitter>
</scene>"#,
    );
    let out = dir.path().join("checker.lxs");
    scene_compile(&[xml.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]).unwrap();
    let world = World::new(CompiledScene::load(&out).unwrap()).unwrap();
    let frac = |x: f64| x - x.floor();
    for &(u, v) in &[
        (0.05, 0.05),
        (0.2, 0.1),
        (0.4, 0.6),
        (0.7, 0.9),
        (0.95, 0.3),
        (0.55, 0.45),
    ] {
        let (su, sv) = (3.0 * u, 2.0 * v);
        if [su, sv]
            .iter()
            .any(|&x| (frac(x) - 0.5).abs() < 1e-6 || frac(x) < 1e-6)
        {
            continue;
        }
        let same = (frac(su) > 0.5) == (frac(sv) > 0.5);
        let expected = if same {
            [0.8, 0.7, 0.6]
        } else {
            [0.1, 0.2, 0.3]
        };
        let up = luxest_io::math::Vec3::new(0.0, 0.0, 1.0);
        let m = world.material_at(0, [u, v], up, up);
        let luxest_render::scene::Material::Lambertian { reflectance } = &*m else {
            panic!("a diffuse material: {m:?}")
        };
        for c in 0..3 {
            assert!(
                (reflectance.0[c] - expected[c]).abs() < 1e-6,
                "uv ({u}, {v}): {reflectance:?} vs {expected:?}"
            );
        }
    }
}
