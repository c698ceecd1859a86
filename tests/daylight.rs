//! Daylight end to end (scene-compile → estimate sensors): skies and the sun through windows
//! against closed forms and quadratures computed here, bad sky and window input as one-line
//! errors, and a small committed case against Radiance (reports/lighting/daylight/, written by
//! pipelines/radiance_daylight.py).

use crate::util::{compile_text, estimate_sensors, repo_root, scene_compile, TempDir};
use luxest_io::math::Vec3;
use luxest_io::sensors::SensorResults;
use luxest_render::sky::{Sky, SkyKind, SunAngles};
use std::f64::consts::PI;

/// A closed black box of 1 m with a `hole` × `hole` window centred in its ceiling (y = 1), a
/// sensor facing up at (0.5, 0.2, 0.5), under `sky` (RON).
fn box_with_roof_window(hole: f64, sky: &str) -> String {
    let a = 0.5 - hole / 2.0;
    format!(
        r#"Scene(
    materials: {{ "black": Lambertian(reflectance: (0, 0, 0)) }},
    objects: [
        (shape: Quad(corner: (0, 0, 0), u: (0, 0, 1), v: (1, 0, 0)), material: "black"),
        (name: Some("roof"), shape: Quad(corner: (0, 1, 0), u: (1, 0, 0), v: (0, 0, 1)), material: "black"),
        (shape: Quad(corner: (0, 0, 0), u: (0, 1, 0), v: (0, 0, 1)), material: "black"),
        (shape: Quad(corner: (1, 0, 0), u: (0, 0, 1), v: (0, 1, 0)), material: "black"),
        (shape: Quad(corner: (0, 0, 0), u: (1, 0, 0), v: (0, 1, 0)), material: "black"),
        (shape: Quad(corner: (0, 0, 1), u: (0, 1, 0), v: (1, 0, 0)), material: "black"),
    ],
    windows: [(corner: ({a}, 1, {a}), u: ({hole}, 0, 0), v: (0, 0, {hole}))],
    environment: Some(Sky({sky})),
    sensors: [Points(name: "eye", points: [(position: (0.5, 0.2, 0.5), normal: (0, 1, 0))])],
)"#
    )
}

/// The one sensor's illuminance and standard error.
fn run(dir: &TempDir, name: &str, scene: &str, paths: &str) -> (f64, f64, SensorResults) {
    let r = estimate_sensors(&compile_text(dir, name, scene), paths, &[]);
    let p = &r.sets[0].points[0];
    (p.value, p.standard_error, r)
}

/// View factor from a point to a parallel rectangle with a corner straight above it (sides a,
/// b at height c), times π: ∫ cos θ dω.
fn corner_factor(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    0.5 * (x / sx * (y / sx).atan() + y / sy * (x / sy).atan())
}

#[test]
fn uniform_sky_through_a_roof_window_gives_the_view_factor() {
    // E = L ∫_hole cos θ dω = L π F: four corner rectangles of 0.2 m × 0.2 m at 0.8 m. Black
    // walls: no interreflection; below the hole the sky is uniform to 1e-6 (gensky's blend
    // into the ground only acts near the horizon).
    let dir = TempDir::new("daylight-hole");
    let l = 1000.0;
    let scene = box_with_roof_window(
        0.4,
        &format!("(kind: Uniform, zenith_luminance: Some({l}))"),
    );
    let (e, se, r) = run(&dir, "hole", &scene, "20000");
    let exact = l * 4.0 * corner_factor(0.2, 0.2, 0.8);
    assert!(
        (e - exact).abs() < 4.0 * se + 1e-3 * exact,
        "{e} ± {se} vs {exact}"
    );
    // The results carry the sky's E_h: skybright.cal blends the sky (L) into the ground
    // (G = 0.2 L) with weights a = (μ + 1.01)^10, b = 1/a (μ = cos θ), so
    // E_h = 2π ∫₀¹ (a L + b G)/(a + b) μ dμ, by the midpoint rule here; about 0.3 % below π L.
    let sky = r.sky.expect("a sky");
    let n = 100_000;
    let g = 0.2 * l;
    let e_h: f64 = (0..n)
        .map(|i| {
            let mu = (i as f64 + 0.5) / n as f64;
            let a = (mu + 1.01f64).powi(10);
            let b = 1.0 / a;
            (a * l + b * g) / (a + b) * mu
        })
        .sum::<f64>()
        * 2.0
        * PI
        / n as f64;
    assert!(e_h < 0.998 * PI * l);
    assert!(
        (sky.horizontal_illuminance_lux - e_h).abs() < 2e-4 * e_h,
        "{sky:?} vs {e_h}"
    );
    assert!(sky.description.contains("-u -b"), "{}", sky.description);
}

#[test]
fn sun_and_clear_sky_through_a_roof_window() {
    // The sun 80° high straight south shines through the 0.4 m hole onto the sensor: E = the
    // sun's direct normal illuminance × sin 80° + the clear sky's luminance over the hole,
    // integrated here by the midpoint rule on the hole (cos θ dω = c² dA / r⁴).
    let dir = TempDir::new("daylight-sun");
    let scene = box_with_roof_window(
        0.4,
        "(kind: Clear, angles: Some((altitude: 80.0, azimuth: 0.0)))",
    );
    let (e, se, r) = run(&dir, "sun", &scene, "20000");
    let model = Sky {
        kind: SkyKind::Clear,
        sun: true,
        date: None,
        angles: Some(SunAngles {
            altitude: 80.0,
            azimuth: 0.0,
        }),
        zenith_luminance: None,
        horizontal_illuminance: None,
        turbidity: 2.45,
        ground_reflectance: 0.2,
        up: Vec3::new(0.0, 1.0, 0.0),
        north: Vec3::new(0.0, 0.0, -1.0),
        resolution: 512,
    }
    .model()
    .unwrap();
    let n = 200;
    let (c, h) = (0.8, 0.4);
    let mut sky = 0.0;
    for i in 0..n {
        for j in 0..n {
            let x = -h / 2.0 + h * (i as f64 + 0.5) / n as f64;
            let z = -h / 2.0 + h * (j as f64 + 0.5) / n as f64;
            let r2 = x * x + z * z + c * c;
            let w = Vec3::new(x, c, z) * (1.0 / r2.sqrt());
            sky += model.luminance(w) * c * c / (r2 * r2) * (h / n as f64).powi(2);
        }
    }
    let sun = r.sky.as_ref().unwrap().sun.as_ref().expect("a sun");
    let exact = sky + sun.direct_normal_illuminance_lux * 80f64.to_radians().sin();
    assert!(sun.direct_normal_illuminance_lux > 10.0 * sky);
    assert!(
        (e - exact).abs() < 4.0 * se + 2e-3 * exact,
        "{e} ± {se} vs {exact} (sky {sky})"
    );
}

#[test]
fn bad_skies_and_windows_are_one_line_errors() {
    let dir = TempDir::new("daylight-bad");
    for (name, scene, want) in [
        (
            "zero-window",
            box_with_roof_window(0.0, "(kind: Uniform, zenith_luminance: Some(1.0))"),
            "zero area",
        ),
        (
            "polar-night",
            box_with_roof_window(
                0.4,
                "(kind: Overcast, date: Some((month: 12, day: 21, hour: 12.0, latitude: 80.0, \
                 longitude: 0.0, meridian: 0.0)))",
            ),
            "polar night",
        ),
        (
            "bad-date",
            box_with_roof_window(
                0.4,
                "(kind: Clear, date: Some((month: 2, day: 30, hour: 12.0, latitude: 50.0, \
                 longitude: 0.0, meridian: 0.0)))",
            ),
            "date out of range",
        ),
    ] {
        let ron = dir.write(&format!("{name}.ron"), scene);
        let out = dir.path().join(format!("{name}.lxs"));
        let (code, msg) =
            scene_compile(&[ron.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]).unwrap_err();
        assert_eq!(code, 1, "{msg}");
        assert!(
            msg.contains(want) && msg.contains(&format!("{name}.ron")) && msg.lines().count() == 1,
            "{msg}"
        );
        assert!(!out.exists());
    }
}

#[test]
fn one_window_room_agrees_with_radiance_at_three_points() {
    // The one-window room under the overcast sky, three of its work-plane points (near the
    // window, the middle, the back), against the committed Radiance values of the same points
    // (reports/lighting/daylight/daylit-room-one-window.radiance.csv): 2 % + 3σ.
    let root = repo_root();
    let scene = std::fs::read_to_string(root.join("scenes/daylit-room-one-window.ron")).unwrap();
    let csv = std::fs::read_to_string(
        root.join("reports/lighting/daylight/daylit-room-one-window.radiance.csv"),
    )
    .unwrap();
    let peer: Vec<(Vec3, f64, f64)> = csv
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("set,"))
        .map(|l| {
            let f: Vec<f64> = l.split(',').skip(2).map(|x| x.parse().unwrap()).collect();
            (Vec3::new(f[0], f[1], f[2]), f[3], f[4])
        })
        .collect();
    let picked = [0usize, 22, 40];
    let points: Vec<String> = picked
        .iter()
        .map(|&k| {
            let p = peer[k].0;
            format!(
                "(position: ({:?}, {:?}, {:?}), normal: (0, 1, 0))",
                p.x, p.y, p.z
            )
        })
        .collect();
    let start = scene.find("calculation_surfaces").unwrap();
    let text = format!(
        "{}sensors: [Points(name: \"probe\", points: [{}])],\n)\n",
        &scene[..start],
        points.join(", ")
    );
    let dir = TempDir::new("daylight-radiance");
    let r = estimate_sensors(&compile_text(&dir, "room", &text), "60000", &[]);
    for (p, &k) in r.sets[0].points.iter().zip(&picked) {
        let (_, e_r, se_r) = peer[k];
        let allowed = 0.02 * e_r + 3.0 * p.standard_error.hypot(se_r);
        assert!(
            (p.value - e_r).abs() <= allowed,
            "point {k}: luxest {} ± {} vs Radiance {e_r} ± {se_r}",
            p.value,
            p.standard_error
        );
        assert!(
            p.standard_error < 0.05 * e_r,
            "point {k}: too noisy to test"
        );
    }
}
