//! Environment light and spot lights in every estimator, against closed forms, with the
//! estimator's own standard error as the tolerance: a sensor under an open sky (E = π L), a
//! diffuse plane under a constant sky seen by the camera (L = ρ L_sky: trace, light tracing,
//! double local estimate), a sensor in a black box lit through a square hole (E = L times the
//! hole's projected solid angle), a sensor and a plane under an environment map (E by
//! quadrature of the map, the plane's luminance ρ E / π), and a spot light over a plane (E = I₀ falloff(θ) cos θ / d², and the plane's
//! luminance ρ E / π in the camera's pixels).

use crate::util::{compile_text, TempDir};
use estimate::local_estimate::{self as local, LocalConfig, Singularity};
use estimate::sensor_batches::Batches;
use luxest_io::cli::Console;
use luxest_io::math::Vec3;
use luxest_io::progress::Progress;
use luxest_render::scene::SensorPoint;
use luxest_render::world::{load_with_camera, Traversal, World};
use std::f64::consts::PI;
use trace::{Film, Renderer};

/// Sky luminance of the constant environments, cd/m².
const SKY: f64 = 2.0;

fn world_at(path: &std::path::Path) -> World {
    World::new(luxest_render::compiled::CompiledScene::load(path).unwrap()).unwrap()
}

fn local_config(paths: u64, environment_samples: u64) -> LocalConfig {
    LocalConfig {
        batches: Batches {
            paths,
            batches: 16,
            seed: 4,
            threads: 2,
        },
        singularity: Singularity::Ball { eps: 1e-4 },
        max_depth: 1000,
        near_field: None,
        environment_samples,
    }
}

/// Local estimate and gather at the scene's sensors: (value, standard error) per estimator and
/// sensor (Y, lx).
fn sensor_estimates(world: &World, paths: u64, samples: u64) -> [Vec<(f64, f64)>; 2] {
    let sensors = estimate::all_sensors(world);
    let near = vec![0.0; sensors.len()];
    let le = local::estimate(
        world,
        &sensors,
        &near,
        &local_config(paths, samples),
        &Progress::off(),
    );
    let g = estimate::gather::estimate(
        world,
        &sensors,
        &estimate::gather::GatherConfig {
            samples,
            batches: 16,
            seed: 5,
            threads: 2,
            max_depth: 1000,
        },
        &Progress::off(),
    );
    [
        le.value
            .iter()
            .copied()
            .zip(le.standard_error.clone())
            .collect(),
        g.iter().map(|&(_, m, se)| (m, se)).collect(),
    ]
}

fn assert_close(what: &str, (v, se): (f64, f64), expected: f64, rel: f64) {
    assert!(
        v.is_finite() && (v - expected).abs() <= 4.0 * se + rel * expected,
        "{what}: {v} ± {se} vs {expected}"
    );
}

#[test]
fn sensor_under_an_open_sky_receives_pi_l() {
    // Sensors on and above a grey plane, facing up, see the sky's whole hemisphere and nothing
    // else: E = π L exactly (the plane's light never reaches an upward-facing sensor on it).
    let dir = TempDir::new("env-open");
    let text = format!(
        r#"Scene(
        materials: {{ "ground": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
        objects: [(shape: Quad(corner: (-2, 0, 2), u: (4, 0, 0), v: (0, 0, -4)), material: "ground")],
        environment: Some(Constant(({SKY}, {SKY}, {SKY}))),
        sensors: [Points(name: "up", points: [
            (position: (0, 0, 0), normal: (0, 1, 0)),
            (position: (1, 0, 0.5), normal: (0, 1, 0)),
            (position: (0, 0.5, 0), normal: (0, 1, 0))])])"#
    );
    let world = world_at(&compile_text(&dir, "open", &text));
    let [le, g] = sensor_estimates(&world, 20_000, 20_000);
    for (k, (a, b)) in le.into_iter().zip(g).enumerate() {
        assert_close(&format!("local estimate, sensor {k}"), a, PI * SKY, 0.0);
        assert_close(&format!("gather, sensor {k}"), b, PI * SKY, 0.0);
    }
}

/// The projected solid angle of the rectangle [0, a] × [0, b] at height h over a point under
/// its corner, facing it: π times the form factor (Howell's catalogue, C-11).
fn corner_rectangle(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a / h, b / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    0.5 * (x / sx * (y / sx).atan() + y / sy * (x / sy).atan())
}

#[test]
fn sensor_in_a_black_box_sees_the_sky_through_its_hole() {
    // A black 2 m cube with a 1 m square hole in the middle of its ceiling; a sensor in the
    // middle of the floor, facing up: E = L × the hole's projected solid angle (four corner
    // rectangles of 0.5 m × 0.5 m at h = 2 m). Nothing inside reflects.
    let dir = TempDir::new("env-box");
    let q = |c: (f64, f64, f64), u: (f64, f64, f64), v: (f64, f64, f64)| {
        format!(
            r#"(shape: Quad(corner: ({}, {}, {}), u: ({}, {}, {}), v: ({}, {}, {})), material: "black")"#,
            c.0, c.1, c.2, u.0, u.1, u.2, v.0, v.1, v.2
        )
    };
    let objects = [
        q((-1.0, -1.0, -1.0), (2.0, 0.0, 0.0), (0.0, 0.0, 2.0)), // floor
        q((-1.0, -1.0, -1.0), (0.0, 2.0, 0.0), (2.0, 0.0, 0.0)), // walls
        q((-1.0, -1.0, 1.0), (2.0, 0.0, 0.0), (0.0, 2.0, 0.0)),
        q((-1.0, -1.0, -1.0), (0.0, 0.0, 2.0), (0.0, 2.0, 0.0)),
        q((1.0, -1.0, -1.0), (0.0, 2.0, 0.0), (0.0, 0.0, 2.0)),
        q((-1.0, 1.0, -1.0), (0.0, 0.0, 0.5), (2.0, 0.0, 0.0)), // ceiling around the hole
        q((-1.0, 1.0, 0.5), (0.0, 0.0, 0.5), (2.0, 0.0, 0.0)),
        q((-1.0, 1.0, -0.5), (0.0, 0.0, 1.0), (0.5, 0.0, 0.0)),
        q((0.5, 1.0, -0.5), (0.0, 0.0, 1.0), (0.5, 0.0, 0.0)),
    ]
    .join(",\n");
    let text = format!(
        r#"Scene(
        materials: {{ "black": Lambertian(reflectance: (0, 0, 0)) }},
        objects: [{objects}],
        environment: Some(Constant(({SKY}, {SKY}, {SKY}))),
        sensors: [Points(name: "floor", points: [(position: (0, -1, 0), normal: (0, 1, 0))])])"#
    );
    let world = world_at(&compile_text(&dir, "box", &text));
    let expected = SKY * 4.0 * corner_rectangle(0.5, 0.5, 2.0);
    let [le, g] = sensor_estimates(&world, 2_000, 100_000);
    assert_close("local estimate", le[0], expected, 0.0);
    assert_close("gather", g[0], expected, 0.0);
    // The test can fail: the standard error is a few per cent of the value.
    assert!(le[0].1 < 0.05 * expected, "{:?}", le[0]);

    // Grey walls: the sky's light reflected inside the box reaches the sensor by light paths
    // entering through the hole (local estimate) and by backward paths with next-event
    // estimation of the sky (gather), two independent estimates of the same illuminance.
    let grey = text.replace("reflectance: (0, 0, 0)", "reflectance: (0.6, 0.6, 0.6)");
    let world = world_at(&compile_text(&dir, "grey-box", &grey));
    let [le, g] = sensor_estimates(&world, 60_000, 30_000);
    let se = (le[0].1.powi(2) + g[0].1.powi(2)).sqrt();
    assert!(
        (le[0].0 - g[0].0).abs() <= 4.0 * se && le[0].0 > 1.2 * expected,
        "grey box: local {:?} vs gather {:?} (direct alone {expected})",
        le[0],
        g[0]
    );
}

#[test]
fn sensor_under_an_environment_map_matches_its_quadrature() {
    // An upward sensor on a plane under a rotated, non-uniform map: E = ∫ L(ω) cos θ dω over
    // the upper hemisphere, by the midpoint rule on a fine (cos θ, φ) grid.
    let dir = TempDir::new("env-map");
    let (w, h) = (16, 8);
    let pixels: Vec<[f32; 3]> = (0..w * h)
        .map(|k| {
            let (i, j) = (k % w, k / w);
            let v = 0.5 + 0.2 * i as f32 + if (i, j) == (3, 2) { 30.0 } else { 0.0 };
            [v, 0.8 * v, 0.3 * v + 0.1 * j as f32]
        })
        .collect();
    let image = luxest_io::image::RgbImage {
        width: w,
        height: h,
        pixels,
        attributes: Vec::new(),
    };
    luxest_io::exr::write_rgb(&dir.path().join("sky.exr"), &image).unwrap();
    let (s, c) = 25f64.to_radians().sin_cos();
    let text = format!(
        r#"Scene(
        camera: Some(Camera(position: (0.01, 3, 0.02), look_at: (0, 0, 0), up: (0, 0, -1), vfov_deg: 25.0, resolution: (8, 6))),
        materials: {{ "ground": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
        objects: [(shape: Quad(corner: (-2, 0, 2), u: (4, 0, 0), v: (0, 0, -4)), material: "ground")],
        environment: Some(Map(path: "sky.exr", scale: 1.5,
            to_world: (({c}, 0, {s}), (0, 1, 0), ({ms}, 0, {c})))),
        sensors: [Points(name: "up", points: [(position: (0, 0, 0), normal: (0, 1, 0))])])"#,
        ms = -s
    );
    let scene = compile_text(&dir, "map", &text);
    let world = world_at(&scene);
    let env = world.environment().unwrap();
    let (nt, np) = (400, 800);
    let mut exact = 0.0;
    for a in 0..nt {
        let ct = (a as f64 + 0.5) / nt as f64;
        let st = (1.0 - ct * ct).sqrt();
        for b in 0..np {
            let phi = 2.0 * PI * (b as f64 + 0.5) / np as f64;
            let wdir = Vec3::new(st * phi.cos(), ct, st * phi.sin());
            exact += env.radiance(wdir).luminance() * ct;
        }
    }
    exact *= 2.0 * PI / (nt * np) as f64;
    let [le, g] = sensor_estimates(&world, 20_000, 40_000);
    // The quadrature's own error is below 1e-3 of the value.
    assert_close("local estimate", le[0], exact, 1e-3);
    assert_close("gather", g[0], exact, 1e-3);

    // The plane's luminance seen from above is ρ E / π everywhere: trace (the map's next-event
    // directions and escaping paths by MIS), light tracing (light paths drawn from the map) and
    // the double local estimate (the map's light reflected at the points the camera sees).
    let expected = 0.5 * exact / PI;
    let (world, cam) = trace::load(&scene, None).unwrap();
    let mut film = Film::new(cam.width as usize, cam.height as usize);
    Renderer::new(&world, cam, 2, 2, 1000).advance(&mut film, 128, false, &Progress::off());
    let mean: Vec<f64> = film.mean().iter().map(|c| c.luminance()).collect();
    check_image("trace", &mean, &film.standard_error(), expected, 4.0);
    let (world, cam) = load_with_camera(&scene, None, Traversal::Robust).unwrap();
    let lt = estimate::light_tracing::render(
        &world,
        &cam,
        &estimate::light_tracing::LightTraceConfig {
            paths: 300_000,
            seed: 3,
            threads: 2,
            max_depth: 1000,
        },
        &Progress::off(),
    );
    let mean: Vec<f64> = lt.rgb.iter().map(|c| c.luminance()).collect();
    check_image("light tracing", &mean, &lt.standard_error, expected, 8.0);
    let dle = estimate::double_local_estimate::render(
        &world,
        &cam,
        &estimate::double_local_estimate::ImageConfig {
            paths: 4_000,
            pixel_samples: 1,
            seed: 4,
            threads: 2,
            singularity: Singularity::Ball { eps: 1e-3 },
            max_depth: 1000,
            mis_paths: 1,
        },
        &Console::QUIET,
    );
    let mean: Vec<f64> = dle.rgb.iter().map(|c| c.luminance()).collect();
    check_image(
        "double local estimate",
        &mean,
        &dle.standard_error,
        expected,
        8.0,
    );
}

const PLANE_UNDER_SKY: &str = r#"Scene(
    camera: Some(Camera(position: (0.01, 3, 0.02), look_at: (0, 0, 0), up: (0, 0, -1), vfov_deg: 25.0, resolution: (8, 6))),
    materials: { "grey": Lambertian(reflectance: (0.5, 0.5, 0.5)) },
    objects: [(shape: Quad(corner: (-1, 0, 1), u: (2, 0, 0), v: (0, 0, -2)), material: "grey")],
    environment: Some(Constant((2, 2, 2))))"#;

/// Every pixel within `z` of its standard errors of `expected`, and the image's mean within 4
/// standard errors of the mean.
fn check_image(what: &str, mean: &[f64], se: &[f64], expected: f64, z: f64) {
    for (k, (m, s)) in mean.iter().zip(se).enumerate() {
        assert!(
            m.is_finite() && (m - expected).abs() <= z * s,
            "{what}: pixel {k}: {m} ± {s} vs {expected}"
        );
    }
    let n = mean.len() as f64;
    let avg = mean.iter().sum::<f64>() / n;
    let se_avg = (se.iter().map(|s| s * s).sum::<f64>()).sqrt() / n;
    assert!(
        (avg - expected).abs() <= 4.0 * se_avg,
        "{what}: image mean {avg} ± {se_avg} vs {expected}"
    );
}

#[test]
fn diffuse_plane_under_a_constant_sky_has_rho_l_in_every_image_estimator() {
    // A grey plane alone under the sky: its upper hemisphere is all sky, so it reflects
    // ρ L_sky = 1 cd/m² towards the camera above it, which sees nothing else.
    let dir = TempDir::new("env-plane");
    let scene = compile_text(&dir, "plane", PLANE_UNDER_SKY);
    let expected = 0.5 * SKY;

    let (world, cam) = trace::load(&scene, None).unwrap();
    let mut film = Film::new(cam.width as usize, cam.height as usize);
    Renderer::new(&world, cam, 2, 2, 1000).advance(&mut film, 256, false, &Progress::off());
    let mean: Vec<f64> = film.mean().iter().map(|c| c.luminance()).collect();
    check_image("trace", &mean, &film.standard_error(), expected, 4.0);

    let (world, cam) = load_with_camera(&scene, None, Traversal::Robust).unwrap();
    let lt = estimate::light_tracing::render(
        &world,
        &cam,
        &estimate::light_tracing::LightTraceConfig {
            paths: 400_000,
            seed: 3,
            threads: 2,
            max_depth: 1000,
        },
        &Progress::off(),
    );
    let mean: Vec<f64> = lt.rgb.iter().map(|c| c.luminance()).collect();
    // 8 batches: z follows Student's t with 7 degrees of freedom.
    check_image("light tracing", &mean, &lt.standard_error, expected, 8.0);

    let dle = estimate::double_local_estimate::render(
        &world,
        &cam,
        &estimate::double_local_estimate::ImageConfig {
            paths: 4_000,
            pixel_samples: 1,
            seed: 4,
            threads: 2,
            singularity: Singularity::Ball { eps: 1e-3 },
            max_depth: 1000,
            mis_paths: 1,
        },
        &Console::QUIET,
    );
    let mean: Vec<f64> = dle.rgb.iter().map(|c| c.luminance()).collect();
    check_image(
        "double local estimate",
        &mean,
        &dle.standard_error,
        expected,
        8.0,
    );
}

#[test]
fn background_pixels_show_the_sky_in_every_image_estimator() {
    // A camera looking past a small plane at the sky: its corner pixels see only the sky, L.
    let dir = TempDir::new("env-background");
    let text = PLANE_UNDER_SKY.replace("vfov_deg: 25.0", "vfov_deg: 120.0");
    let scene = compile_text(&dir, "background", &text);
    let (world, cam) = load_with_camera(&scene, None, Traversal::Robust).unwrap();
    let corner = 0; // pixel (0, 0): 60° off the axis, beyond the plane
    let lt = estimate::light_tracing::render(
        &world,
        &cam,
        &estimate::light_tracing::LightTraceConfig {
            paths: 1000,
            seed: 3,
            threads: 2,
            max_depth: 10,
        },
        &Progress::off(),
    );
    assert!(
        (lt.rgb[corner].luminance() - SKY).abs() < 1e-9,
        "{:?}",
        lt.rgb[corner]
    );
    let dle = estimate::double_local_estimate::render(
        &world,
        &cam,
        &estimate::double_local_estimate::ImageConfig {
            paths: 64,
            pixel_samples: 1,
            seed: 4,
            threads: 2,
            singularity: Singularity::Ball { eps: 1e-3 },
            max_depth: 10,
            mis_paths: 1,
        },
        &Console::QUIET,
    );
    assert!(
        (dle.rgb[corner].luminance() - SKY).abs() < 1e-9,
        "{:?}",
        dle.rgb[corner]
    );
    let (world, cam) = trace::load(&scene, None).unwrap();
    let mut film = Film::new(cam.width as usize, cam.height as usize);
    Renderer::new(&world, cam, 2, 2, 10).advance(&mut film, 4, false, &Progress::off());
    assert!((film.mean()[corner].luminance() - SKY).abs() < 1e-9);
    // aov-write's emission feature is the part of trace's image a denoiser leaves alone: the
    // sky seen directly is in it.
    let hit = aov_write::features::first_hit(&world, cam.position, cam.direction(0.5, 0.5), 0.0);
    assert!((hit.emission.luminance() - SKY).abs() < 1e-12, "{hit:?}");
}

/// A spot at (0, 2, 0) aiming down, 100 cd on its axis, cutoff 30°, beam 20°, over a plane.
const SPOT: &str = r#"point_lights: [(position: (0, 2, 0), power: Intensity(100.0),
        spot: Some((direction: (0, -1, 0), cutoff_deg: 30.0, beam_width_deg: 20.0)))]"#;

/// Illuminance of the spot on the plane y = 0 at horizontal distance r from its foot.
fn spot_illuminance(r: f64) -> f64 {
    let d = (r * r + 4.0).sqrt();
    let theta = (r / 2.0).atan().to_degrees();
    let falloff = if theta <= 20.0 {
        1.0
    } else if theta < 30.0 {
        (30.0 - theta) / 10.0
    } else {
        0.0
    };
    100.0 * falloff * (2.0 / d) / (d * d)
}

#[test]
fn spot_illuminance_on_a_plane_is_its_falloff_over_distance_squared() {
    // Sensors inside the beam, on the ramp and outside the cone, on a black floor: the delta
    // term is exact (no variance).
    let dir = TempDir::new("spot-sensors");
    let rs = [0.0, 0.5, 0.85, 1.0, 1.5];
    let points: Vec<String> = rs
        .iter()
        .map(|r| format!("(position: ({r}, 0, 0), normal: (0, 1, 0))"))
        .collect();
    let text = format!(
        r#"Scene(
        materials: {{ "black": Lambertian(reflectance: (0, 0, 0)) }},
        objects: [(shape: Quad(corner: (-5, 0, 5), u: (10, 0, 0), v: (0, 0, -10)), material: "black")],
        {SPOT},
        sensors: [Points(name: "floor", points: [{}])])"#,
        points.join(", ")
    );
    let world = world_at(&compile_text(&dir, "spot", &text));
    let [le, g] = sensor_estimates(&world, 1000, 1000);
    for (k, &r) in rs.iter().enumerate() {
        let e = spot_illuminance(r);
        assert!(
            (le[k].0 - e).abs() <= 1e-9 * e.max(1.0),
            "r = {r}: {:?} vs {e}",
            le[k]
        );
        assert!(
            (g[k].0 - e).abs() <= 1e-9 * e.max(1.0),
            "r = {r}: {:?} vs {e}",
            g[k]
        );
    }
    // The compiled flux is the falloff's exact integral: 2π I₀ (1 − (sin c − sin b)/(c − b)).
    let (c, b) = (30f64.to_radians(), 20f64.to_radians());
    let flux = 2.0 * PI * 100.0 * (1.0 - (c.sin() - b.sin()) / (c - b));
    let compiled = world.scene.header.emitters[0].flux_lm();
    assert!(
        (compiled - flux).abs() < 1e-9 * flux,
        "{compiled} vs {flux}"
    );
}

#[test]
fn spot_lit_plane_has_rho_e_over_pi_in_trace_and_light_tracing() {
    // A grey plane under the spot, seen from above: each pixel's luminance is the box filter
    // of ρ E / π over its footprint (here by 16 × 16 rays per pixel against the plane); light
    // tracing exercises the spot's emission sampling, trace its next-event estimation.
    let dir = TempDir::new("spot-image");
    let text = format!(
        r#"Scene(
        camera: Some(Camera(position: (0.01, 4, 0.02), look_at: (0, 0, 0), up: (0, 0, -1), vfov_deg: 50.0, resolution: (12, 12))),
        materials: {{ "grey": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
        objects: [(shape: Quad(corner: (-5, 0, 5), u: (10, 0, 0), v: (0, 0, -10)), material: "grey")],
        {SPOT})"#
    );
    let scene = compile_text(&dir, "spot-image", &text);
    let (world, cam) = load_with_camera(&scene, None, Traversal::Robust).unwrap();
    let (w, h) = (cam.width as usize, cam.height as usize);
    let n = 16;
    let expected: Vec<f64> = (0..w * h)
        .map(|p| {
            let mut sum = 0.0;
            for a in 0..n {
                for b in 0..n {
                    let sx = (p % w) as f64 + (a as f64 + 0.5) / n as f64;
                    let sy = (p / w) as f64 + (b as f64 + 0.5) / n as f64;
                    let d = cam.direction(sx, sy);
                    let t = -cam.position.y / d.y;
                    let x = cam.position + d * t;
                    sum += 0.5 / PI * spot_illuminance((x.x * x.x + x.z * x.z).sqrt());
                }
            }
            sum / (n * n) as f64
        })
        .collect();
    // A pixel on the cone's edge may be lit on a sliver only a few samples find: an absolute
    // floor of 1e-3 of the brightest pixel.
    let floor = 1e-3 * expected.iter().fold(0.0f64, |a, &b| a.max(b));
    let lt = estimate::light_tracing::render(
        &world,
        &cam,
        &estimate::light_tracing::LightTraceConfig {
            paths: 400_000,
            seed: 8,
            threads: 2,
            max_depth: 1,
        },
        &Progress::off(),
    );
    for (k, e) in expected.iter().enumerate() {
        let (v, s) = (lt.rgb[k].luminance(), lt.standard_error[k]);
        // 8 batches (Student's t, 7 degrees of freedom); 2e-3 for the reference's quadrature.
        assert!(
            (v - e).abs() <= 8.0 * s + 2e-3 * e + floor,
            "light tracing pixel {k}: {v} ± {s} vs {e}"
        );
    }
    let (world, cam) = trace::load(&scene, None).unwrap();
    let mut film = Film::new(w, h);
    Renderer::new(&world, cam, 2, 2, 1).advance(&mut film, 64, false, &Progress::off());
    let (mean, se) = (film.mean(), film.standard_error());
    for (k, e) in expected.iter().enumerate() {
        let v = mean[k].luminance();
        assert!(
            (v - e).abs() <= 4.0 * se[k] + 2e-3 * e + floor,
            "trace pixel {k}: {v} ± {} vs {e}",
            se[k]
        );
    }
}

#[test]
fn sensor_points_in_the_open_see_the_sky_from_every_side_they_face() {
    // A cylindrical sensor high above a small plane: its response integrates to
    // ∫ |sin ε| / π dω = π over the whole sphere, so E = π L (the plane subtends almost
    // nothing: 4 m² at 100 m, a relative effect below 1e-4 at ρ = 0).
    let dir = TempDir::new("env-cylindrical");
    let text = format!(
        r#"Scene(
        materials: {{ "black": Lambertian(reflectance: (0, 0, 0)) }},
        objects: [(shape: Quad(corner: (-1, 0, 1), u: (2, 0, 0), v: (0, 0, -2)), material: "black")],
        environment: Some(Constant(({SKY}, {SKY}, {SKY}))),
        sensors: [Points(name: "c", points: [(position: (0, 100, 0), normal: (0, 1, 0), kind: Cylindrical(axis: (0, 1, 0)))])])"#
    );
    let world = world_at(&compile_text(&dir, "cyl", &text));
    let sensors: Vec<SensorPoint> = estimate::all_sensors(&world);
    let le = local::estimate(
        &world,
        &sensors,
        &[0.0],
        &local_config(1000, 20_000),
        &Progress::off(),
    );
    assert_close(
        "cylindrical",
        (le.value[0], le.standard_error[0]),
        PI * SKY,
        1e-4,
    );
}

#[test]
fn mitsuba_export_writes_spots_and_environments() {
    // The spot as Mitsuba's `spot` looking along its axis, the map as `envmap` with its texels
    // in environment.exr and its rotation as a 4 × 4 matrix, a constant sky as `constant`.
    let dir = TempDir::new("env-export");
    let pixels: Vec<[f32; 3]> = (0..12).map(|k| [k as f32 + 0.5, 1.0, 2.0]).collect();
    let image = luxest_io::image::RgbImage {
        width: 4,
        height: 3,
        pixels: pixels.clone(),
        attributes: Vec::new(),
    };
    luxest_io::exr::write_rgb(&dir.path().join("sky.exr"), &image).unwrap();
    let scene = |env: &str| {
        format!(
            r#"Scene(
            materials: {{ "grey": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
            objects: [(shape: Quad(corner: (-2, 0, 2), u: (4, 0, 0), v: (0, 0, -4)), material: "grey")],
            {SPOT},
            environment: Some({env}))"#
        )
    };
    let export = |name: &str, text: &str| {
        let path = compile_text(&dir, name, text);
        let compiled = luxest_render::compiled::CompiledScene::load(&path).unwrap();
        scene_compile::mitsuba::export(&compiled, &path).unwrap()
    };
    let files = export(
        "map",
        &scene(r#"Map(path: "sky.exr", scale: 3.0, to_world: ((0, 0, 1), (0, 1, 0), (-1, 0, 0)))"#),
    );
    let xml = String::from_utf8(files[0].1.clone()).unwrap();
    assert!(
        xml.contains(r#"<emitter type="spot"><transform name="to_world"><lookat origin="0e0, 2e0, 0e0" target="0e0, 1e0, 0e0""#),
        "{xml}"
    );
    assert!(xml.contains(r#"<float name="cutoff_angle" value="3e1"/><float name="beam_width" value="2e1"/><rgb name="intensity" value="1e2, 1e2, 1e2"/>"#));
    assert!(xml.contains(r#"<emitter type="envmap"><string name="filename" value="environment.exr"/><float name="scale" value="3e0"/><transform name="to_world"><matrix value="0e0 0e0 1e0 0 0e0 1e0 0e0 0 -1e0 0e0 0e0 0 0 0 0 1"/>"#), "{xml}");
    let (_, exr) = files
        .iter()
        .find(|(name, _)| name == "environment.exr")
        .unwrap();
    let back = luxest_io::exr::read_rgb_bytes(std::path::Path::new("environment.exr"), exr.clone())
        .unwrap();
    assert_eq!((back.width, back.height, back.pixels), (4, 3, pixels));
    let files = export("constant", &scene("Constant((1.5, 2, 2.5))"));
    let xml = String::from_utf8(files[0].1.clone()).unwrap();
    assert!(
        xml.contains(
            r#"<emitter type="constant"><rgb name="radiance" value="1.5e0, 2e0, 2.5e0"/></emitter>"#
        ),
        "{xml}"
    );
}

#[test]
fn bad_environments_and_spots_are_one_line_errors() {
    // Each: exit code 1, one line naming the file and the problem, no output.
    let dir = TempDir::new("env-errors");
    dir.write("garbage.exr", b"not an exr at all");
    let image = luxest_io::image::RgbImage {
        width: 3,
        height: 2,
        pixels: vec![[0.0; 3]; 6],
        attributes: Vec::new(),
    };
    luxest_io::exr::write_rgb(&dir.path().join("black.exr"), &image).unwrap();
    let base = |extra: &str| {
        format!(
            r#"Scene(
            materials: {{ "grey": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
            objects: [(shape: Quad(corner: (-2, 0, 2), u: (4, 0, 0), v: (0, 0, -4)), material: "grey")],
            {extra})"#
        )
    };
    let cases = [
        (
            r#"environment: Some(Map(path: "missing.exr"))"#,
            "missing.exr not found",
        ),
        (
            r#"environment: Some(Map(path: "garbage.exr"))"#,
            "garbage.exr: not a readable OpenEXR file",
        ),
        (
            r#"environment: Some(Map(path: "black.exr"))"#,
            "black.exr: environment map is black",
        ),
        (
            r#"environment: Some(Map(path: "black.exr", to_world: ((1, 0, 0), (0, 2, 0), (0, 0, 1))))"#,
            "environment.to_world: environment to_world",
        ),
        (
            r#"environment: Some(Map(path: "black.exr", scale: -1))"#,
            "environment.scale: the map's scale must be positive",
        ),
        (
            r#"environment: Some(Constant((0, 0, 0)))"#,
            "environment.Constant: emitter has zero power",
        ),
        (
            r#"point_lights: [(position: (0, 1, 0), power: Intensity(1.0),
                spot: Some((direction: (0, -1, 0), cutoff_deg: 20.0, beam_width_deg: 25.0)))]"#,
            "point_lights[0].spot.beam_width_deg: the beam width must be in [0, cutoff_deg = 20]",
        ),
        (
            r#"point_lights: [(position: (0, 1, 0), power: Intensity(1.0),
                spot: Some((direction: (0, 0, 0), cutoff_deg: 20.0, beam_width_deg: 10.0)))]"#,
            "point_lights[0].spot.direction: must not be the zero vector",
        ),
        (
            r#"point_lights: [(position: (0, 1, 0), power: Intensity(1.0),
                spot: Some((direction: (0, -1, 0), cutoff_deg: 200.0, beam_width_deg: 10.0)))]"#,
            "point_lights[0].spot.cutoff_deg: the cutoff must be in (0, 180]",
        ),
    ];
    for (k, (extra, want)) in cases.iter().enumerate() {
        let path = dir.write(&format!("bad{k}.ron"), base(extra));
        let out = dir.path().join(format!("bad{k}.lxs"));
        let (code, msg) =
            crate::util::scene_compile(&[path.to_str().unwrap(), "-o", out.to_str().unwrap()])
                .expect_err("bad input must fail");
        assert_eq!(code, 1, "{msg}");
        assert!(!msg.contains('\n') && msg.contains(want), "case {k}: {msg}");
        assert!(!out.exists());
    }
}
