//! Shading normals (interpolated vertex normals) and normal maps in every image estimator,
//! against closed forms: a Lambertian floor lit by a point source, whose vertex normals (or a
//! constant normal map) tilt its shading normal. Path tracing (`trace`, the double local
//! estimate's view points) follows Mitsuba 3's `path`: the cosine law of the shading normal;
//! light tracing follows its `ptracer`: with vertex normals Veach's adjoint correction makes
//! it the same image, with a normal map (a non-reciprocal BSDF in Mitsuba) the cosine and
//! shadowing term fall on the camera's direction instead.

use crate::util::{compile_text, TempDir};
use luxest_io::image::RgbImage;
use luxest_io::math::Vec3;
use luxest_io::progress::Progress;
use luxest_render::camera::PinholeCamera;
use luxest_render::world::{load_with_camera, Traversal};
use std::f64::consts::PI;
use std::path::Path;
use trace::{Film, Renderer};

const RHO: f64 = 0.6;
const LIGHT: Vec3 = Vec3::new(0.0, 1.0, 0.0);
/// The shading normal's tilt towards +x, degrees.
const TILT: f64 = 30.0;

fn tilted() -> Vec3 {
    let t = TILT.to_radians();
    Vec3::new(t.sin(), t.cos(), 0.0)
}

/// A 2 m floor (OBJ, u along +x) with vertex normals `vn` if given, lit by a 1 cd point source
/// 1 m above its centre, seen from 2 m above; `surfaces` as given.
fn floor(dir: &TempDir, name: &str, vn: Option<Vec3>, surfaces: &str) -> std::path::PathBuf {
    let mut obj = String::from("v -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\n");
    obj += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
    let faces = match vn {
        Some(n) => {
            obj += &format!("vn {} {} {}\n", n.x, n.y, n.z);
            "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n"
        }
        None => "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n",
    };
    obj += faces;
    std::fs::write(dir.path().join(format!("{name}.obj")), obj).unwrap();
    let text = format!(
        r#"Scene(
        camera: Camera(position: (0.0, 2.0, 0.0), look_at: (0.0, 0.0, 0.0), up: (0.0, 0.0, 1.0),
                       vfov_deg: 50.0, resolution: (12, 12)),
        materials: {{ "floor": Lambertian(reflectance: ({RHO}, {RHO}, {RHO})) }},
        objects: [(shape: Obj(path: "{name}.obj"), material: "floor")],
        point_lights: [(position: (0.0, 1.0, 0.0), power: Intensity(1.0))],
        {surfaces})"#
    );
    compile_text(dir, name, &text)
}

/// A 1 × 1 linear EXR normal map encoding the unit vector `n` (tangent space) as (n + 1) / 2.
fn constant_map(dir: &TempDir, n: Vec3) -> &'static str {
    let mut image = RgbImage::new(1, 1);
    image.pixels[0] = [n.x, n.y, n.z].map(|c| ((c + 1.0) / 2.0) as f32);
    luxest_io::exr::write_rgb(&dir.path().join("tilt.exr"), &image).unwrap();
    r#"textures: { "tilt": (path: "tilt.exr") }, surfaces: { "floor": (normal: Some("tilt")) },"#
}

/// Estevez et al.'s shadowing term of Mitsuba's `normalmap` for a map normal tilted by TILT
/// and a direction at cosine `c` to the surface normal.
fn shadowing(c: f64) -> f64 {
    let alpha2 = (0.125 * TILT.to_radians().tan().powi(2)).min(1.0);
    let tan2 = (1.0 - c * c) / (c * c);
    2.0 / (1.0 + (1.0 + alpha2 * tan2).sqrt())
}

/// The mean over pixel (px, py) (16 × 16 points) of `f(x)` at the floor points x it sees;
/// `None` unless the whole pixel sees the floor.
fn pixel_mean(cam: &PinholeCamera, px: usize, py: usize, f: &dyn Fn(Vec3) -> f64) -> Option<f64> {
    let mut sum = 0.0;
    for j in 0..16 {
        for i in 0..16 {
            let d = cam.direction(
                px as f64 + (i as f64 + 0.5) / 16.0,
                py as f64 + (j as f64 + 0.5) / 16.0,
            );
            let x = cam.position + d * (-cam.position.y / d.y);
            if x.x.abs() >= 1.0 || x.z.abs() >= 1.0 {
                return None;
            }
            sum += f(x);
        }
    }
    Some(sum / 256.0)
}

/// Luminance towards the camera by the cosine law of `n` at the light (path tracing).
fn cosine_law(n: Vec3, mapped: bool) -> impl Fn(Vec3) -> f64 {
    move |x: Vec3| {
        let v = LIGHT - x;
        let d2 = v.length_squared();
        let w = v * (1.0 / d2.sqrt());
        let s = if mapped { shadowing(w.y) } else { 1.0 };
        RHO / PI * w.dot(n).max(0.0) * s / d2
    }
}

fn trace_image(scene: &Path, spp: u32) -> (PinholeCamera, Vec<f64>) {
    let (world, cam) = trace::load(scene, None).unwrap();
    let mut film = Film::new(cam.width as usize, cam.height as usize);
    Renderer::new(&world, cam, 1, 2, 1024).advance(&mut film, spp, false, &Progress::off());
    (cam, film.mean().iter().map(|c| c.luminance()).collect())
}

fn light_tracing(scene: &Path, paths: u64) -> (PinholeCamera, estimate::image::ImageResult) {
    let (world, cam) = load_with_camera(scene, None, Traversal::Robust).unwrap();
    let r = estimate::light_tracing::render(
        &world,
        &cam,
        &estimate::light_tracing::LightTraceConfig {
            paths,
            seed: 5,
            threads: 2,
            max_depth: 100,
        },
        &Progress::off(),
    );
    (cam, r)
}

/// Checks every pixel that wholly sees the floor against `expected` (relative `tol`); returns
/// how many were checked.
fn check_pixels(
    what: &str,
    cam: &PinholeCamera,
    image: &[f64],
    expected: &dyn Fn(Vec3) -> f64,
    tol: f64,
) -> usize {
    let mut checked = 0;
    for py in 0..cam.height as usize {
        for px in 0..cam.width as usize {
            let Some(e) = pixel_mean(cam, px, py, expected) else {
                continue;
            };
            let v = image[py * cam.width as usize + px];
            assert!(
                (v - e).abs() <= tol * e,
                "{what}: pixel ({px},{py}) {v} vs {e}"
            );
            checked += 1;
        }
    }
    checked
}

/// Mean over the pixels that wholly see the floor on the `side` (−1, +1) of x = 0 (both
/// sides for 0) of the light-tracing image and of `expected`, with the image mean's standard
/// error.
fn floor_mean(
    cam: &PinholeCamera,
    r: &estimate::image::ImageResult,
    expected: &dyn Fn(Vec3) -> f64,
    side: f64,
) -> (f64, f64, f64) {
    let (mut sum, mut var, mut e, mut n) = (0.0, 0.0, 0.0, 0.0);
    for py in 0..r.height {
        for px in 0..r.width {
            let on_side = pixel_mean(cam, px, py, &|x| f64::from(u8::from(x.x * side >= 0.0)));
            if on_side != Some(1.0) {
                continue;
            }
            if let Some(x) = pixel_mean(cam, px, py, expected) {
                let i = py * r.width + px;
                sum += r.rgb[i].luminance();
                var += r.standard_error[i].powi(2);
                e += x;
                n += 1.0;
            }
        }
    }
    (sum / n, var.sqrt() / n, e / n)
}

#[test]
fn vertex_normals_give_the_cosine_law_of_the_shading_normal_in_trace_and_light_tracing() {
    let dir = TempDir::new("normals-vertex");
    let smooth = floor(&dir, "smooth", Some(tilted()), "");
    let expected = cosine_law(tilted(), false);
    let (cam, image) = trace_image(&smooth, 64);
    let checked = check_pixels("trace", &cam, &image, &expected, 4e-3);
    assert!(checked >= 60, "{checked}");
    // The flat floor is the geometric normal's cosine law: not the same image.
    let flat = floor(&dir, "flat", None, "");
    let (_, flat_image) = trace_image(&flat, 64);
    check_pixels(
        "flat trace",
        &cam,
        &flat_image,
        &cosine_law(Vec3::new(0.0, 1.0, 0.0), false),
        4e-3,
    );
    // Light paths with Veach's correction: the same image within its standard errors.
    let (cam, lt) = light_tracing(&smooth, 300_000);
    let (mean, se, e) = floor_mean(&cam, &lt, &expected, 0.0);
    assert!(
        (mean - e).abs() < 4.0 * se && se < 0.01 * e,
        "light tracing {mean} ± {se} vs {e}"
    );
}

#[test]
fn a_constant_normal_map_tilts_the_cosine_law_as_mitsubas_normalmap() {
    let dir = TempDir::new("normals-map");
    let t = TILT.to_radians();
    let map = constant_map(&dir, Vec3::new(t.sin(), 0.0, t.cos()));
    // u runs along +x: the map's tangent-space x is world +x, so the normal tilts towards +x.
    let scene = floor(&dir, "mapped", None, map);
    let path_traced = cosine_law(tilted(), true);
    let (cam, image) = trace_image(&scene, 64);
    assert!(check_pixels("trace", &cam, &image, &path_traced, 4e-3) >= 60);
    // The double local estimate's view points are camera-path vertices: exact for the point
    // source.
    let (world, dcam) = load_with_camera(&scene, None, Traversal::Robust).unwrap();
    let dle = estimate::double_local_estimate::render(
        &world,
        &dcam,
        &estimate::double_local_estimate::ImageConfig {
            paths: 2_000,
            pixel_samples: 64,
            seed: 3,
            threads: 2,
            singularity: estimate::local_estimate::Singularity::Ball { eps: 1e-3 },
            max_depth: 100,
            mis_paths: 1,
        },
        &luxest_io::cli::Console::QUIET,
    );
    let y: Vec<f64> = dle.rgb.iter().map(|c| c.luminance()).collect();
    assert!(check_pixels("double local estimate", &dcam, &y, &path_traced, 4e-3) >= 60);
    // Light tracing evaluates Mitsuba's normalmap in importance mode: the geometric cosine at
    // the light, the mapped cosine and shadowing term towards the camera.
    let n = tilted();
    let light_traced = |x: Vec3| {
        let v = LIGHT - x;
        let d2 = v.length_squared();
        let wl = v * (1.0 / d2.sqrt());
        let c = cam.position - x;
        let wc = c * (1.0 / c.length());
        RHO / PI * wl.y * wc.dot(n).max(0.0) * shadowing(wc.y) / (wc.y * d2)
    };
    // The denoiser's normal feature is the mapped normal (facing the ray).
    let hit = aov_write::features::first_hit(&world, dcam.position, dcam.direction(6.0, 6.0), 0.0);
    assert!((hit.normal - tilted()).length() < 1e-6, "{:?}", hit.normal);
    let (lcam, lt) = light_tracing(&scene, 300_000);
    for side in [-1.0, 1.0] {
        let (mean, se, e) = floor_mean(&lcam, &lt, &light_traced, side);
        assert!(
            (mean - e).abs() < 4.0 * se && se < 0.01 * e,
            "light tracing, side {side}: {mean} ± {se} vs {e}"
        );
        // The two definitions differ by ±10–20 % on either side of the light.
        let (_, _, other) = floor_mean(&lcam, &lt, &path_traced, side);
        assert!((other - e).abs() > 10.0 * se, "side {side}: {other} vs {e}");
    }
}

#[test]
fn sensors_see_the_shading_normals_cosine_law_in_the_local_estimate_and_gather() {
    // A sensor 0.5 m above the floor's centre facing down receives the luminance the floor
    // reflects, L(x) = ρ/π I (w·ns)/d², over its solid angle: E = ∫ L cos_x cos_s / r² dA. The
    // local estimate's light paths reach it through Veach's adjoint correction, gather's
    // backward paths through the shading-frame BSDF; both give the quadrature.
    let dir = TempDir::new("normals-sensor");
    let sensor = Vec3::new(0.0, 0.5, 0.0);
    let scene = floor(
        &dir,
        "sensor",
        Some(tilted()),
        r#"sensors: [Points(name: "s", points: [(position: (0.0, 0.5, 0.0), normal: (0.0, -1.0, 0.0))])],"#,
    );
    // Midpoint rule on 400 × 400 cells of the 2 m × 2 m floor: cos_x cos_s / r² = (0.5 / r)² / r².
    let quadrature = |law: &dyn Fn(Vec3) -> f64| {
        let n = 400;
        let mut e = 0.0;
        for j in 0..n {
            for i in 0..n {
                let x = Vec3::new(
                    -1.0 + 2.0 * (i as f64 + 0.5) / n as f64,
                    0.0,
                    -1.0 + 2.0 * (j as f64 + 0.5) / n as f64,
                );
                let r2 = (sensor - x).length_squared();
                e += law(x) * (0.5 * 0.5 / r2) / r2;
            }
        }
        e * 4.0 / (n * n) as f64
    };
    let e = quadrature(&cosine_law(tilted(), false));
    let world = luxest_render::world::World::new(
        luxest_render::compiled::CompiledScene::load(&scene).unwrap(),
    )
    .unwrap();
    let sensors = estimate::all_sensors(&world);
    let le = estimate::local_estimate::estimate(
        &world,
        &sensors,
        &[0.0],
        &estimate::local_estimate::LocalConfig {
            batches: estimate::sensor_batches::Batches {
                paths: 200_000,
                batches: 16,
                seed: 4,
                threads: 2,
            },
            singularity: estimate::local_estimate::Singularity::Ball { eps: 1e-4 },
            max_depth: 100,
            near_field: None,
            environment_samples: 0,
        },
        &Progress::off(),
    );
    let (v, se) = (le.value[0], le.standard_error[0]);
    assert!(
        (v - e).abs() < 4.0 * se && se < 0.02 * e,
        "local estimate {v} ± {se} vs {e}"
    );
    let g = estimate::gather::estimate(
        &world,
        &sensors,
        &estimate::gather::GatherConfig {
            samples: 20_000,
            batches: 16,
            seed: 5,
            threads: 2,
            max_depth: 100,
        },
        &Progress::off(),
    );
    let (_, m, se) = g[0];
    assert!(
        (m - e).abs() < 4.0 * se && se < 0.02 * e,
        "gather {m} ± {se} vs {e}"
    );
    // The geometric normal's law is another number: the test tells them apart.
    let ef = quadrature(&cosine_law(Vec3::new(0.0, 1.0, 0.0), false));
    assert!(
        (ef - e).abs() > 10.0 * se.max(le.standard_error[0]),
        "{ef} vs {e}"
    );
}
