//! Luminaires from photometric files and calculation surfaces, through scene-compile and every
//! estimator, against closed forms: a cos² luminaire over a black plane (direct illuminance
//! exact), between two reflecting planes (direct exact, the whole against the backward
//! estimator), in an integrating sphere (the indirect term depends only on the flux), cylindrical
//! and semi-cylindrical sensors, the path tracer's next-event estimation; IES and EULUMDAT files
//! of one distribution, symmetric files and their expanded forms; the EN 12464-1 grid layout;
//! malformed files.

use crate::util::{repo_root, scene_compile, TempDir};
use estimate::local_estimate::{self as local, LocalConfig, Singularity};
use estimate::sensor_batches::{Batches, SensorEstimates};
use luxest_io::cli::Console;
use luxest_io::math::Vec3;
use luxest_io::progress::Progress;
use luxest_render::compiled::{CompiledScene, Emitter};
use luxest_render::scene::SensorPoint;
use luxest_render::world::World;
use std::f64::consts::PI;

/// The fixtures' directory: scenes compiled "from" there find the photometric files by name.
fn fixtures() -> std::path::PathBuf {
    repo_root().join("crates/photometry/tests/fixtures")
}

fn compiled_from(text: &str) -> CompiledScene {
    let scene: luxest_render::scene::Scene =
        luxest_io::fsio::parse_ron(std::path::Path::new("test.ron"), text).unwrap();
    scene_compile::compile(&scene, &fixtures().join("test.ron"))
        .unwrap()
        .0
}

fn world_from(text: &str) -> World {
    World::new(compiled_from(text)).unwrap()
}

fn config(paths: u64, world: &World) -> LocalConfig {
    LocalConfig {
        batches: Batches {
            paths,
            batches: 32,
            seed: 7,
            threads: 2,
        },
        singularity: Singularity::Ball {
            eps: 1e-3 * world.room_scale,
        },
        max_depth: 100_000,
        near_field: None,
        environment_samples: 0,
    }
}

fn run(world: &World, paths: u64) -> (Vec<SensorPoint>, SensorEstimates) {
    let s = estimate::all_sensors(world);
    let near = vec![0.0; s.len()];
    let r = local::estimate(world, &s, &near, &config(paths, world), &Progress::off());
    (s, r)
}

/// I(ψ) = 1000 cd cos²ψ for ψ ≤ 90° (0 above): the distribution of `cos2.ies` / `cos2.ldt`.
fn cos2(psi_cos: f64) -> f64 {
    1000.0 * psi_cos.max(0.0).powi(2)
}

/// Bound of the bilinear interpolation error of the cos² table at 2.5° steps (cd):
/// Δγ²/8 · max|I''| with I'' = −2000 cos 2γ.
fn cos2_interpolation_bound() -> f64 {
    let d = 2.5f64.to_radians();
    d * d / 8.0 * 2000.0
}

/// Sensors on the floor y = 0 at the horizontal distances where a luminaire at height `h`
/// straight above `(x0, z0)` sees them at γ = 0°, 10°, 30°, 45°, 60°, 75° (table nodes), in
/// several azimuths.
fn floor_points(x0: f64, z0: f64, h: f64) -> Vec<(f64, f64)> {
    let mut v = Vec::new();
    for (k, g) in [0.0f64, 10.0, 30.0, 45.0, 60.0, 75.0].iter().enumerate() {
        let r = h * g.to_radians().tan();
        let phi = (37.0 * k as f64).to_radians();
        v.push((x0 + r * phi.cos(), z0 + r * phi.sin()));
    }
    v
}

fn points_ron(pts: &[(f64, f64)], y: f64, ny: f64) -> String {
    pts.iter()
        .map(|(x, z)| format!("(position: ({x}, {y}, {z}), normal: (0.0, {ny}, 0.0))"))
        .collect::<Vec<_>>()
        .join(", ")
}

const BIG_FLOOR: &str = r#"(shape: Quad(corner: (-1000.0, 0.0, 1000.0), u: (2000.0, 0.0, 0.0), v: (0.0, 0.0, -2000.0)), material: "floor")"#;

#[test]
fn cos2_luminaire_over_a_black_plane_gives_the_closed_form_exactly() {
    // E(r) = I0 cos²γ cos γ / (h² + r²): at table nodes the bilinear table is exact, and on a
    // black plane there is nothing but the (deterministic) direct term: SE = 0.
    let (x0, z0, h) = (0.3, -0.2, 2.0);
    let pts = floor_points(x0, z0, h);
    let text = format!(
        r#"Scene(materials: {{ "floor": Lambertian(reflectance: (0.0, 0.0, 0.0)) }},
        objects: [{BIG_FLOOR}],
        luminaires: [(file: "cos2.ies", position: ({x0}, {h}, {z0}))],
        sensors: [Points(name: "floor", points: [{}])])"#,
        points_ron(&pts, 0.0, 1.0)
    );
    let world = world_from(&text);
    assert!(world.scene.header.features.goniometric_luminaires);
    assert!(!world.scene.header.features.point_emitters);
    let (s, r) = run(&world, 2000);
    for (i, p) in s.iter().enumerate() {
        let d = Vec3::new(x0, h, z0) - p.position;
        let cos = d.y / d.length();
        let exact = cos2(cos) * cos / d.length_squared();
        assert!(
            (r.value[i] - exact).abs() <= 1e-9 * exact,
            "sensor {i}: {} vs {exact}",
            r.value[i]
        );
        assert_eq!(r.standard_error[i], 0.0);
        assert!((r.delta_light[i] - exact).abs() <= 1e-9 * exact);
    }
}

#[test]
fn aimed_tilted_and_rotated_luminaire_follows_its_axis() {
    // The cos² distribution about an axis a: I = I0 max(0, a·ω)². Aimed with `aim`, then (for a
    // rotationally symmetric file) neither rotation nor tilt about the C0 axis changes that
    // except through the nadir: with tilt t about the luminaire's x axis the nadir swings by t
    // towards C = 90°, which for the default frame is −z. Interpolation bounds the difference.
    let pos = Vec3::new(0.0, 2.0, 0.0);
    let cases = [
        // (aim, tilt, rotation, the resulting axis)
        (
            Vec3::new(0.0, -1.0, 0.0),
            0.0,
            40.0,
            Vec3::new(0.0, -1.0, 0.0),
        ),
        (
            Vec3::new(0.5, -1.0, 0.0),
            0.0,
            0.0,
            Vec3::new(0.5, -1.0, 0.0),
        ),
        (
            Vec3::new(0.0, -1.0, 0.0),
            30.0,
            0.0,
            Vec3::new(
                0.0,
                -(30f64.to_radians().cos()),
                -(30f64.to_radians().sin()),
            ),
        ),
    ];
    let grid: Vec<(f64, f64)> = (0..25)
        .map(|k| ((k % 5) as f64 - 2.0, (k / 5) as f64 - 2.0))
        .collect();
    for (aim, tilt, rot, axis) in cases {
        let text = format!(
            r#"Scene(materials: {{ "floor": Lambertian(reflectance: (0.0, 0.0, 0.0)) }},
            objects: [{BIG_FLOOR}],
            luminaires: [(file: "cos2.ies", position: (0.0, 2.0, 0.0), aim: ({}, {}, {}),
                          tilt_deg: {tilt}, rotation_deg: {rot})],
            sensors: [Points(name: "floor", points: [{}])])"#,
            aim.x,
            aim.y,
            aim.z,
            points_ron(&grid, 0.0, 1.0)
        );
        let world = world_from(&text);
        let (s, r) = run(&world, 100);
        let a = axis.try_normalize().unwrap();
        for (i, p) in s.iter().enumerate() {
            let w = p.position - pos;
            let d2 = w.length_squared();
            let cos_p = -w.y / d2.sqrt();
            let exact = cos2(a.dot(w) / d2.sqrt()) * cos_p / d2;
            let tol = cos2_interpolation_bound() * cos_p / d2 + 1e-12;
            assert!(
                (r.value[i] - exact).abs() <= tol,
                "aim {aim:?} tilt {tilt} rot {rot}, sensor {i}: {} vs {exact}",
                r.value[i]
            );
        }
    }
}

#[test]
fn ies_and_ldt_files_of_one_distribution_give_the_same_illuminances() {
    let pts: Vec<(f64, f64)> = (0..30)
        .map(|k| (0.37 * (k % 6) as f64 - 1.0, 0.41 * (k / 6) as f64 - 1.0))
        .collect();
    let values = |file: &str| {
        let text = format!(
            r#"Scene(materials: {{ "floor": Lambertian(reflectance: (0.0, 0.0, 0.0)) }},
            objects: [{BIG_FLOOR}],
            luminaires: [(file: "{file}", position: (0.1, 1.7, 0.2), rotation_deg: 23.0, tilt_deg: 12.0)],
            sensors: [Points(name: "floor", points: [{}])])"#,
            points_ron(&pts, 0.0, 1.0)
        );
        run(&world_from(&text), 100).1.value
    };
    for (ies, ldt) in [
        ("cos2.ies", "cos2.ldt"),
        ("bilat-full.ies", "bilat-full.ldt"),
        ("quad.ies", "quad.ldt"),
    ] {
        let (a, b) = (values(ies), values(ldt));
        for (i, (x, y)) in a.iter().zip(&b).enumerate() {
            assert!(*x > 0.0);
            assert!(
                (x - y).abs() <= 1e-6 * x.abs(),
                "{ies} vs {ldt}, sensor {i}: {x} vs {y}"
            );
        }
    }
}

#[test]
fn symmetric_files_and_their_expanded_forms_give_identical_results() {
    // The whole local estimate — direct term, emission sampling, reflections — on a grey floor
    // and wall, with the luminaire turned so that every C plane matters. The expanded tables
    // agree to rounding (1e-12), so the same seed gives the same paths and values to rounding.
    let values = |file: &str| {
        let text = format!(
            r#"Scene(materials: {{ "floor": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
            objects: [{BIG_FLOOR},
                (shape: Quad(corner: (2.0, 0.0, 5.0), u: (0.0, 0.0, -10.0), v: (0.0, 4.0, 0.0)), material: "floor")],
            luminaires: [(file: "{file}", position: (0.0, 2.5, 0.0), rotation_deg: 31.0, tilt_deg: 17.0)],
            calculation_surfaces: [(name: "wp", area: Floor(min: (-3.0, -3.0), max: (2.0, 3.0), y: 0.0),
                                    offset: 0.8, spacing: Counts(5, 6))])"#
        );
        let r = run(&world_from(&text), 4000).1;
        (r.value, r.standard_error)
    };
    for (sym, full) in [
        ("quad.ies", "quad-full.ies"),
        ("bilat.ies", "bilat-full.ies"),
        ("bilat90.ies", "bilat90-full.ies"),
        ("quad.ldt", "quad-full.ldt"),
        ("bilat.ldt", "bilat-full.ldt"),
        ("bilat90.ldt", "bilat90-full.ldt"),
    ] {
        let (a, sa) = values(sym);
        let (b, sb) = values(full);
        for i in 0..a.len() {
            assert!(a[i] > 0.0 && sa[i] > 0.0);
            assert!(
                (a[i] - b[i]).abs() <= 1e-9 * a[i] && (sa[i] - sb[i]).abs() <= 1e-6 * sa[i],
                "{sym} vs {full}, point {i}: {} ± {} vs {} ± {}",
                a[i],
                sa[i],
                b[i],
                sb[i]
            );
        }
    }
}

#[test]
fn two_reflecting_planes_direct_part_exact_and_local_estimate_matches_gathering() {
    // Sobolev's geometry with a cos² luminaire at the origin between the floor y = −1 and the
    // ceiling y = +1 (rho = 0.5 both): the direct part is the closed form (the ceiling gets none:
    // the distribution stops at 90°); the total is checked against the backward (gathering)
    // estimator, which reaches the luminaire by next-event estimation only.
    let h = 1.0;
    let pts = floor_points(0.0, 0.0, h);
    let text = format!(
        r#"Scene(materials: {{ "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
        objects: [
            (shape: Quad(corner: (-1000.0, -1.0, 1000.0), u: (2000.0, 0.0, 0.0), v: (0.0, 0.0, -2000.0)), material: "w"),
            (shape: Quad(corner: (-1000.0, 1.0, 1000.0), u: (0.0, 0.0, -2000.0), v: (2000.0, 0.0, 0.0)), material: "w"),
        ],
        luminaires: [(file: "cos2.ies", position: (0.0, 0.0, 0.0))],
        sensors: [Points(name: "floor", points: [{}]), Points(name: "ceiling", points: [{}])])"#,
        points_ron(&pts, -1.0, 1.0),
        points_ron(&pts[..3], 1.0, -1.0)
    );
    let world = world_from(&text);
    let (s, r) = run(&world, 40_000);
    for (i, p) in s.iter().enumerate() {
        let d = -p.position;
        let cos = (d.dot(p.normal) / d.length()).max(0.0);
        let exact = cos2(d.y / d.length()) * cos / d.length_squared();
        assert!(
            (r.delta_light[i] - exact).abs() <= 1e-9 * exact.max(1e-300),
            "sensor {i}: direct {} vs {exact}",
            r.delta_light[i]
        );
        assert!(r.value[i] > r.delta_light[i] && r.standard_error[i] > 0.0);
    }
    let gather = estimate::gather::estimate(
        &world,
        &s,
        &estimate::gather::GatherConfig {
            samples: 20_000,
            batches: 32,
            seed: 3,
            threads: 2,
            max_depth: 100_000,
        },
        &Progress::off(),
    );
    for (i, g) in gather.iter().enumerate() {
        let z = (r.value[i] - g.1) / (r.standard_error[i].powi(2) + g.2.powi(2)).sqrt();
        assert!(
            z.abs() <= 4.0,
            "sensor {i}: local {} ± {} vs gather {} ± {} (z = {z})",
            r.value[i],
            r.standard_error[i],
            g.1,
            g.2
        );
    }
}

#[test]
fn integrating_sphere_indirect_depends_only_on_the_flux() {
    // A closed Lambertian sphere (R = 1, rho = 0.6) with an asymmetric luminaire off-centre and
    // tilted: the wall's indirect illuminance is rho Φ / (4π R² (1 − rho)) everywhere, whatever
    // the distribution (Φ = the table integral). Light paths start from the intensity table, so
    // this checks that emission sampling conserves the flux. Tessellation (icosphere level 6:
    // area 7.5e-5 below 4πR²) allows 1e-3 relative.
    let rho = 0.6;
    let text = format!(
        r#"Scene(materials: {{ "wall": Lambertian(reflectance: ({rho}, {rho}, {rho})) }},
        objects: [(shape: Sphere(radius: 1.0, subdivisions: 6), material: "wall", flip_normals: true)],
        luminaires: [(file: "bilat.ies", position: (0.2, 0.1, -0.3), aim: (0.3, -1.0, 0.2), tilt_deg: 20.0)],
        sensors: [Points(name: "wall", points: [
            (position: (0.0, -0.9999, 0.0), normal: (0.0, 1.0, 0.0)),
            (position: (0.0, 0.9999, 0.0), normal: (0.0, -1.0, 0.0)),
            (position: (0.9999, 0.0, 0.0), normal: (-1.0, 0.0, 0.0)),
            (position: (0.0, 0.0, 0.9999), normal: (0.0, 0.0, -1.0)),
            (position: (0.57729, 0.57729, 0.57729), normal: (-0.57735, -0.57735, -0.57735)),
            (position: (-0.70704, -0.70704, 0.0), normal: (0.70711, 0.70711, 0.0)),
        ])])"#
    );
    let world = world_from(&text);
    let flux: f64 = world
        .scene
        .header
        .emitters
        .iter()
        .map(Emitter::flux_lm)
        .sum();
    let table = &world.scene.header.photometries[0];
    assert!((flux - table.table_flux_lm).abs() <= 1e-12 * flux);
    let exact = luxest_exact::solutions::integrating_sphere_indirect(flux / (4.0 * PI), 1.0, rho);
    let (_, r) = run(&world, 40_000);
    for i in 0..r.value.len() {
        let indirect = r.value[i] - r.delta_light[i];
        let z = (indirect - exact) / r.standard_error[i];
        assert!(
            (indirect - exact).abs() <= 4.0 * r.standard_error[i] + 1e-3 * exact,
            "sensor {i}: indirect {indirect} ± {} vs {exact} (z = {z})",
            r.standard_error[i]
        );
        assert!(r.standard_error[i] < 0.02 * exact);
    }
}

#[test]
fn emission_weights_average_to_the_luminaire_flux() {
    // E[Q] over light paths = Φ: the flux estimator of the emission sampling is unbiased.
    let text = format!(
        r#"Scene(materials: {{ "floor": Lambertian(reflectance: (0.0, 0.0, 0.0)) }},
        objects: [{BIG_FLOOR}],
        luminaires: [(file: "bilat90.ies", position: (0.0, 2.0, 0.0), multiplier: 0.8, tilt_deg: 33.0)])"#
    );
    let world = world_from(&text);
    let flux = world.scene.header.emitters[0].flux_lm();
    let mut rng = luxest_render::sampling::Rng::new(5, 1);
    let n = 200_000;
    let (mut s, mut s2) = (0.0, 0.0);
    for _ in 0..n {
        let e = world.sample_emission(&mut rng);
        let q = e.flux.luminance();
        // The direction carries light only where the table is non-zero.
        assert!(q >= 0.0 && q.is_finite());
        s += q;
        s2 += q * q;
    }
    let mean = s / n as f64;
    let se = ((s2 / n as f64 - mean * mean) / (n as f64 - 1.0)).sqrt();
    assert!(
        (mean - flux).abs() <= 4.0 * se + 1e-12 * flux,
        "{mean} ± {se} vs {flux}"
    );
}

#[test]
fn cylindrical_and_semi_cylindrical_sensors_match_their_closed_forms() {
    // E_cyl = I sin ε / (π d²), E_sc = I (|ω_h| + f·ω_h) / (π d²) (ε from the vertical axis,
    // ω_h the horizontal part of the direction to the luminaire), with the cos² luminaire
    // at table-node angles; a black floor: the direct term is the whole.
    let (h, y) = (2.0, 1.2);
    let text = format!(
        r#"Scene(materials: {{ "floor": Lambertian(reflectance: (0.0, 0.0, 0.0)) }},
        objects: [{BIG_FLOOR}],
        luminaires: [(file: "cos2.ies", position: (0.0, {}, 0.0))],
        calculation_surfaces: [
            (name: "cyl", area: Floor(min: (-2.0, -1.5), max: (2.0, 1.5), y: 0.0), offset: {y}, margin: 0.0,
             spacing: Counts(4, 3), kind: Cylindrical()),
            (name: "semi", area: Floor(min: (-2.0, -1.5), max: (2.0, 1.5), y: 0.0), offset: {y}, margin: 0.0,
             spacing: Counts(4, 3), kind: SemiCylindrical(facing: (1.0, 0.0, 1.0))),
        ])"#,
        y + h
    );
    let world = world_from(&text);
    let (s, r) = run(&world, 100);
    let lum = Vec3::new(0.0, y + h, 0.0);
    let f = Vec3::new(1.0, 0.0, 1.0).try_normalize().unwrap();
    for (i, p) in s.iter().enumerate() {
        assert!((p.position.y - y).abs() < 1e-12);
        let d = lum - p.position;
        let w = d / d.length();
        let i_cd = 1000.0 * w.y * w.y; // γ is the angle from the nadir: cos γ = w.y.
        let wh = Vec3::new(w.x, 0.0, w.z);
        let g = if i < 12 {
            wh.length() / PI
        } else {
            (wh.length() + f.dot(wh)) / PI
        };
        let exact = i_cd * g / d.length_squared();
        let tol = cos2_interpolation_bound() * g / d.length_squared() + 1e-12;
        assert!(
            (r.value[i] - exact).abs() <= tol,
            "sensor {i} ({}): {} vs {exact}",
            if i < 12 { "cyl" } else { "semi" },
            r.value[i]
        );
    }
}

#[test]
fn work_plane_grid_follows_en_12464_1() {
    // A 6 × 4 m floor, work plane at 0.75 m, 0.5 m margin: calculation area 5 × 3 m, d = 5 m,
    // p = 0.2 · 5^(log10 5) m, ⌈5/p⌉ × ⌈3/p⌉ points at the cell centres.
    let text = r#"Scene(materials: { "floor": Lambertian(reflectance: (0.5, 0.5, 0.5)) },
        objects: [(shape: Quad(corner: (0.0, 0.0, 4.0), u: (6.0, 0.0, 0.0), v: (0.0, 0.0, -4.0)), material: "floor")],
        point_lights: [(position: (3.0, 2.8, 2.0), power: Intensity(100.0))],
        calculation_surfaces: [(name: "work-plane", area: Floor(min: (0.0, 0.0), max: (6.0, 4.0), y: 0.0), offset: 0.75)])"#;
    let scene = compiled_from(text);
    assert!(!scene.header.features.goniometric_luminaires);
    let set = &scene.header.sensors[0];
    let p = 0.2 * 5f64.powf(5f64.log10());
    let (nu, nv) = ((5.0 / p).ceil() as u32, (3.0 / p).ceil() as u32);
    assert_eq!((nu, nv), (9, 5));
    assert_eq!(set.grid, Some((nu, nv)));
    let layout = set.calculation_grid.as_ref().unwrap();
    assert_eq!((layout.nu, layout.nv), (nu, nv));
    assert_eq!(set.points.len(), (nu * nv) as usize);
    for j in 0..nv {
        for i in 0..nu {
            let k = (j * nu + i) as usize;
            let want = Vec3::new(
                0.5 + (i as f64 + 0.5) * 5.0 / nu as f64,
                0.75,
                4.0 - 0.5 - (j as f64 + 0.5) * 3.0 / nv as f64,
            );
            assert!((set.points[k].position - want).length() < 1e-12, "{k}");
            assert!((set.points[k].normal - Vec3::new(0.0, 1.0, 0.0)).length() < 1e-15);
        }
    }
}

#[test]
fn malformed_photometric_files_are_one_line_errors_and_leave_nothing() {
    let dir = TempDir::new("bad-photometry");
    let cos2 = std::fs::read_to_string(fixtures().join("cos2.ies")).unwrap();
    let scene = |file: &str| {
        format!(
            r#"Scene(materials: {{ "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
            objects: [(shape: Quad(corner: (0.0, 0.0, 0.0), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, -1.0)), material: "w")],
            luminaires: [(file: "{file}", position: (0.0, 2.0, 0.0))])"#
        )
    };
    // Truncated table, negative candela, missing file, wrong extension, zero multiplier.
    let truncated: String = cos2.lines().take(14).collect::<Vec<_>>().join("\n");
    dir.write("truncated.ies", truncated);
    dir.write(
        "negative.ies",
        cos2.replacen("998.097349", "-998.097349", 1),
    );
    dir.write("l.txt", "x");
    // Non-monotonic angles, a wrong count, a truncated EULUMDAT file: named with their line.
    dir.write(
        "nonmono.ies",
        cos2.replacen("0 2.5 5 7.5", "0 5 2.5 7.5", 1),
    );
    dir.write(
        "counts.ies",
        cos2.replacen("1 2000 1 37 1 1 2", "1 2000 1 38 1 1 2", 1),
    );
    let ldt = std::fs::read_to_string(fixtures().join("cos2.ldt")).unwrap();
    let short_ldt: String = ldt.lines().take(30).map(|l| format!("{l}\n")).collect();
    dir.write("trunc.ldt", short_ldt);
    let cases = [
        ("truncated.ies", "truncated.ies"),
        ("negative.ies", "negative.ies"),
        ("missing.ies", "not found"),
        ("l.txt", ".ies (IES LM-63) or .ldt"),
        (
            "nonmono.ies",
            "nonmono.ies: line 9: vertical angles not strictly increasing",
        ),
        (
            "counts.ies",
            "counts.ies: line 13: vertical angles not strictly increasing",
        ),
        ("trunc.ldt", "trunc.ldt: line 30: truncated file"),
    ];
    for (file, expect) in cases {
        let ron = dir.write("s.ron", scene(file));
        let out = dir.path().join("s.lxs");
        let (code, msg) =
            scene_compile(&[ron.to_str().unwrap(), "-o", out.to_str().unwrap()]).expect_err(file);
        assert_eq!(code, 1, "{file}: {msg}");
        assert!(!msg.contains('\n') && msg.contains(expect), "{file}: {msg}");
        assert!(!out.exists(), "{file}: output left behind");
    }
    let ron = dir.write(
        "m.ron",
        scene("x.ies").replace(
            "position: (0.0, 2.0, 0.0)",
            "position: (0.0, 2.0, 0.0), multiplier: 0.0",
        ),
    );
    let (_, msg) = scene_compile(&[ron.to_str().unwrap(), "--check"]).unwrap_err();
    assert!(msg.contains("luminaires[0].multiplier"), "{msg}");
    // A maintenance factor is a share of the new installation's light: in (0, 1].
    for mf in ["0.0", "1.25", "inf"] {
        let ron = dir.write(
            "mf.ron",
            scene("x.ies").replace(
                "position: (0.0, 2.0, 0.0)",
                &format!("position: (0.0, 2.0, 0.0), maintenance_factor: {mf}"),
            ),
        );
        let (code, msg) = scene_compile(&[ron.to_str().unwrap(), "--check"]).unwrap_err();
        assert_eq!(code, 1, "{mf}: {msg}");
        assert!(
            !msg.contains('\n') && msg.contains("luminaires[0].maintenance_factor"),
            "{mf}: {msg}"
        );
    }
    // A calculation surface's requirements must be numbers it can reach.
    for (req, field) in [
        ("(em_lux: -500.0)", "requirements.em_lux"),
        ("(u0: 1.5)", "requirements.u0"),
        (
            "(daylight_factor: (median_percent: 2.0, min_percent: 0.0))",
            "requirements.daylight_factor.min_percent",
        ),
    ] {
        let ron = dir.write(
            "req.ron",
            scene("x.ies").replace(
                "luminaires: [",
                &format!(
                    "calculation_surfaces: [(name: \"wp\", area: Floor(min: (0.0, 0.0), \
                     max: (2.0, 2.0), y: 0.0), requirements: {req})], luminaires: ["
                ),
            ),
        );
        let (code, msg) = scene_compile(&[ron.to_str().unwrap(), "--check"]).unwrap_err();
        assert_eq!(code, 1, "{req}: {msg}");
        assert!(
            !msg.contains('\n') && msg.contains(&format!("calculation_surfaces[0].{field}")),
            "{req}: {msg}"
        );
    }
    // The table × multiplier is bounded like every emitter (1e300 cd gave Eavg inf ± NaN).
    dir.write("cos2.ies", &cos2);
    let ron = dir.write(
        "big.ron",
        scene("cos2.ies").replace(
            "position: (0.0, 2.0, 0.0)",
            "position: (0.0, 2.0, 0.0), multiplier: 1e30",
        ),
    );
    let (code, msg) = scene_compile(&[ron.to_str().unwrap(), "--check"]).unwrap_err();
    assert_eq!(code, 1, "{msg}");
    assert!(
        msg.contains("luminaires[0].multiplier") && msg.contains("exceeds 1e25"),
        "{msg}"
    );
}

#[test]
fn compiled_scene_is_self_contained_and_hashes_the_table() {
    // The table travels in the compiled file: compile from a copy, delete the copy, load;
    // a different table gives a different content hash.
    let dir = TempDir::new("self-contained");
    let text = |file: &str| {
        format!(
            r#"Scene(materials: {{ "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
            objects: [(shape: Quad(corner: (0.0, 0.0, 0.0), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, -1.0)), material: "w")],
            luminaires: [(file: "{file}", position: (0.0, 2.0, 0.0))])"#
        )
    };
    let mut hashes = Vec::new();
    for f in ["quad.ies", "bilat.ies"] {
        std::fs::copy(fixtures().join(f), dir.path().join(f)).unwrap();
        let ron = dir.write("s.ron", text(f));
        let out = dir.path().join("s.lxs");
        scene_compile(&[ron.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]).unwrap();
        std::fs::remove_file(dir.path().join(f)).unwrap();
        let s = CompiledScene::load(&out).unwrap();
        assert_eq!(s.header.photometries.len(), 1);
        World::new(s.clone()).unwrap();
        hashes.push(s.content_hash);
    }
    assert_ne!(hashes[0], hashes[1]);
}

/// A Lambertian floor (rho = 0.6) under the cos² luminaire, seen from above: the only light
/// is direct (a plane cannot light itself).
const FLOOR_VIEW: &str = r#"Scene(
    camera: Camera(position: (0.0, 2.0, -2.0), look_at: (0.0, 0.0, 0.0), vfov_deg: 30.0, resolution: (10, 8)),
    materials: { "w": Lambertian(reflectance: (0.6, 0.6, 0.6)) },
    objects: [(shape: Quad(corner: (-50.0, 0.0, 50.0), u: (100.0, 0.0, 0.0), v: (0.0, 0.0, -100.0)), material: "w")],
    luminaires: [(file: "cos2.ies", position: (0.3, 1.0, 0.2))])"#;

/// Checks an image of [`FLOOR_VIEW`] against L = rho/π · I0 cos²γ cos θ / d², box-filtered over
/// each pixel (8 × 8 midpoint rule), within 4 standard errors plus the table's interpolation
/// bound and 0.2 % for the quadrature. With `pixel_samples`, the image's standard error leaves
/// out the pixel sampling (as the double local estimate's does): 4 σ_px/√n is added, σ_px the
/// spread of L over the pixel.
fn check_floor_view(
    scene: &std::path::Path,
    width: usize,
    height: usize,
    mean: &[f64],
    se: &[f64],
    pixel_samples: Option<u32>,
) {
    let compiled = CompiledScene::load(scene).unwrap();
    let cam = luxest_render::camera::PinholeCamera::new(compiled.header.camera.as_ref().unwrap())
        .unwrap();
    let lum = Vec3::new(0.3, 1.0, 0.2);
    for y in 0..height {
        for x in 0..width {
            let (mut acc, mut acc2, mut bound) = (0.0, 0.0, 0.0);
            for a in 0..8 {
                for b in 0..8 {
                    let d = cam.direction(
                        x as f64 + (a as f64 + 0.5) / 8.0,
                        y as f64 + (b as f64 + 0.5) / 8.0,
                    );
                    let p = cam.position + d * (-cam.position.y / d.y);
                    let l = lum - p;
                    let cos = l.y / l.length();
                    let v = 0.6 / PI * cos2(cos) * cos / l.length_squared();
                    acc += v;
                    acc2 += v * v;
                    bound += 0.6 / PI * cos2_interpolation_bound() * cos / l.length_squared();
                }
            }
            let (e, bound) = (acc / 64.0, bound / 64.0);
            let spread = pixel_samples
                .map(|n| 4.0 * (acc2 / 64.0 - e * e).max(0.0).sqrt() / (n as f64).sqrt())
                .unwrap_or(0.0);
            let i = y * width + x;
            let v = mean[i];
            assert!(
                (v - e).abs() <= 4.0 * se[i] + bound + spread + 0.002 * e,
                "pixel ({x},{y}): {v} ± {} vs {e}",
                se[i]
            );
        }
    }
}

#[test]
fn path_tracer_next_event_sees_the_luminaire_distribution() {
    // The luminaire is a delta light, reached by next-event estimation only.
    use trace::{Film, Renderer};
    let dir = TempDir::new("trace-luminaire");
    std::fs::copy(fixtures().join("cos2.ies"), dir.path().join("cos2.ies")).unwrap();
    let scene = crate::util::compile_text(&dir, "lum", FLOOR_VIEW);
    let (world, cam) = trace::load(&scene, None).unwrap();
    let mut film = Film::new(cam.width as usize, cam.height as usize);
    {
        let r = Renderer::new(&world, cam, 1, 2, 1024);
        r.advance(&mut film, 64, false, &Progress::off());
    }
    let mean: Vec<f64> = film.mean().iter().map(|c| c.luminance()).collect();
    check_floor_view(
        &scene,
        film.width,
        film.height,
        &mean,
        &film.standard_error(),
        None,
    );
}

#[test]
fn double_local_estimate_image_sees_the_luminaire_distribution() {
    // The luminaire's direct term at every pixel's visible point is exact; light paths from
    // the table land on the floor, whose connections to points of the same plane vanish.
    let dir = TempDir::new("dle-luminaire");
    std::fs::copy(fixtures().join("cos2.ies"), dir.path().join("cos2.ies")).unwrap();
    let scene = crate::util::compile_text(&dir, "lum", FLOOR_VIEW);
    let (world, cam) = luxest_render::world::load_with_camera(
        &scene,
        None,
        luxest_render::world::Traversal::Robust,
    )
    .unwrap();
    let r = estimate::double_local_estimate::render(
        &world,
        &cam,
        &estimate::double_local_estimate::ImageConfig {
            paths: 2000,
            pixel_samples: 64,
            seed: 1,
            threads: 2,
            singularity: Singularity::Ball { eps: 1e-3 },
            max_depth: 1000,
            mis_paths: 100,
        },
        &Console::QUIET,
    );
    let mean: Vec<f64> = r.rgb.iter().map(|c| c.luminance()).collect();
    check_floor_view(
        &scene,
        r.width,
        r.height,
        &mean,
        &r.standard_error,
        Some(64),
    );
}

#[test]
fn area_opening_integrates_the_distribution_over_the_rectangle() {
    // Area form: every point of the 0.6 × 0.4 m opening radiates I(ω)/A per unit area, so
    // E(p) = (1/A) ∫∫ I0 cos²ψ cos θ / d² dA (ψ from the nadir, θ at the sensor, both the
    // angle to the vertical for a horizontal opening over a horizontal floor). Compiled with
    // 40 × 40 point sources; the reference is a 400 × 400 midpoint rule computed here. The
    // opening is rotated by 30° about the vertical, so length and width must follow the C axes.
    let (h, len, wid, rot) = (0.5f64, 0.6, 0.4, 30.0f64);
    let pts: Vec<(f64, f64)> = vec![
        (0.0, 0.0),
        (0.25, 0.0),
        (0.0, -0.3),
        (0.4, 0.35),
        (1.5, 1.0),
    ];
    let text = format!(
        r#"Scene(materials: {{ "floor": Lambertian(reflectance: (0.0, 0.0, 0.0)) }},
        objects: [{BIG_FLOOR}],
        luminaires: [(file: "cos2.ies", position: (0.0, {h}, 0.0), rotation_deg: {rot},
                      opening: Area(length: {len}, width: {wid}, cells: (40, 40)))],
        sensors: [Points(name: "floor", points: [{}])])"#,
        points_ron(&pts, 0.0, 1.0)
    );
    let world = world_from(&text);
    let (s, r) = run(&world, 100);
    // Local x (C0) is world +x turned by `rot` towards C90 = −z.
    let (c, sn) = (rot.to_radians().cos(), rot.to_radians().sin());
    let (ex, ey) = (Vec3::new(c, 0.0, -sn), Vec3::new(-sn, 0.0, -c));
    let n = 400;
    for (k, p) in s.iter().enumerate() {
        let (mut e, mut bound) = (0.0, 0.0);
        for i in 0..n {
            for j in 0..n {
                let a = ((i as f64 + 0.5) / n as f64 - 0.5) * len;
                let b = ((j as f64 + 0.5) / n as f64 - 0.5) * wid;
                let src = Vec3::new(0.0, h, 0.0) + ex * a + ey * b;
                let d = src - p.position;
                let cos = d.y / d.length();
                e += cos2(cos) * cos / d.length_squared();
                bound += cos2_interpolation_bound() * cos / d.length_squared();
            }
        }
        let (e, bound) = (e / (n * n) as f64, bound / (n * n) as f64);
        assert!(
            (r.value[k] - e).abs() <= bound + 2e-4 * e,
            "sensor {k}: {} vs {e} (bound {bound})",
            r.value[k]
        );
        assert_eq!(r.standard_error[k], 0.0);
    }
    // Directly below, at 0.5 m from a 0.6 m opening, the near field differs from the point
    // form by several per cent; far away (sensor 4, 1.9 m) by much less.
    let point = cos2(1.0) / (h * h);
    assert!(r.value[0] < 0.95 * point, "{} vs {point}", r.value[0]);
}

#[test]
fn area_opening_conserves_the_flux_in_the_integrating_sphere() {
    // The sphere test with the area form: light paths start at a uniformly chosen source of
    // the opening; the indirect illuminance still depends only on the flux.
    let rho = 0.5;
    let text = format!(
        r#"Scene(materials: {{ "wall": Lambertian(reflectance: ({rho}, {rho}, {rho})) }},
        objects: [(shape: Sphere(radius: 1.0, subdivisions: 6), material: "wall", flip_normals: true)],
        luminaires: [(file: "bilat.ies", position: (0.1, 0.3, 0.0), tilt_deg: 25.0,
                      opening: Area(length: 0.5, width: 0.3, cells: (5, 3)))],
        sensors: [Points(name: "wall", points: [
            (position: (0.0, -0.9999, 0.0), normal: (0.0, 1.0, 0.0)),
            (position: (0.0, 0.9999, 0.0), normal: (0.0, -1.0, 0.0)),
            (position: (0.9999, 0.0, 0.0), normal: (-1.0, 0.0, 0.0)),
            (position: (-0.70704, -0.70704, 0.0), normal: (0.70711, 0.70711, 0.0)),
        ])])"#
    );
    let world = world_from(&text);
    let flux = world.scene.header.emitters[0].flux_lm();
    let exact = luxest_exact::solutions::integrating_sphere_indirect(flux / (4.0 * PI), 1.0, rho);
    let (_, r) = run(&world, 40_000);
    for i in 0..r.value.len() {
        let indirect = r.value[i] - r.delta_light[i];
        assert!(
            (indirect - exact).abs() <= 4.0 * r.standard_error[i] + 1e-3 * exact,
            "sensor {i}: indirect {indirect} ± {} vs {exact}",
            r.standard_error[i]
        );
    }
}

#[test]
fn file_flux_differing_from_the_table_integral_is_warned_about() {
    // cos2.ldt declares 2000 lm × LORL 100 %; its table integrates to about 2π·1000/3 ≈ 2094 lm
    // (+4.7 %): a warning stating both and the difference. With the intensities scaled to
    // 2000 lm there is none.
    let dir = TempDir::new("flux-warning");
    let ldt = std::fs::read_to_string(fixtures().join("cos2.ldt")).unwrap();
    let table_lm = scene_compile::luminaires::load_photometry(&fixtures().join("cos2.ldt"))
        .unwrap()
        .0
        .flux_from_table_lm();
    let mut lines: Vec<String> = ldt.lines().map(str::to_string).collect();
    // Line 24 is the conversion factor of the intensities: scale the table to 2000 lm.
    assert_eq!(
        lines[23].trim(),
        "1",
        "the conversion factor is line 24 of EULUMDAT"
    );
    lines[23] = format!("{}", 2000.0 / table_lm);
    dir.write("matching.ldt", lines.join("\r\n"));
    std::fs::copy(fixtures().join("cos2.ldt"), dir.path().join("cos2.ldt")).unwrap();
    let warnings = |file: &str| {
        let ron = dir.write(
            "s.ron",
            format!(
                r#"Scene(materials: {{ "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
                objects: [(shape: Quad(corner: (0.0, 0.0, 0.0), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, -1.0)), material: "w")],
                luminaires: [(file: "{file}", position: (0.0, 2.0, 0.0))])"#
            ),
        );
        scene_compile::compile_file(&ron).unwrap().1.warnings
    };
    let w = warnings("cos2.ldt");
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("cos2.ldt")
            && w[0].contains("2000")
            && w[0].contains(&format!("{:+.2} %", 100.0 * (table_lm - 2000.0) / 2000.0)),
        "{}",
        w[0]
    );
    assert!(warnings("matching.ldt").is_empty());
}

#[test]
fn estimate_sensors_writes_grid_layouts_kinds_and_batch_values() {
    // The command line end to end: a work plane and a cylindrical grid under a luminaire;
    // the results carry each grid's layout, the kind, and with --batch-values the per-batch
    // estimates whose mean and spread are the value and its standard error.
    let dir = TempDir::new("batch-values");
    std::fs::copy(fixtures().join("bilat.ies"), dir.path().join("bilat.ies")).unwrap();
    let scene = crate::util::compile_text(
        &dir,
        "room",
        r#"Scene(materials: { "w": Lambertian(reflectance: (0.6, 0.6, 0.6)) },
        objects: [(shape: Box(size: (4.0, 3.0, 3.0)), transform: (translate: (2.0, 1.5, 1.5)), material: "w", flip_normals: true)],
        luminaires: [(file: "bilat.ies", position: (2.0, 2.9, 1.5))],
        calculation_surfaces: [
            (name: "work-plane", area: Floor(min: (0.0, 0.0), max: (4.0, 3.0), y: 0.0), offset: 0.75),
            (name: "cylindrical", area: Floor(min: (0.0, 0.0), max: (4.0, 3.0), y: 0.0), offset: 1.2,
             spacing: Counts(3, 2), kind: Cylindrical()),
        ])"#,
    );
    let out = dir.path().join("room.sensors.ron");
    crate::util::estimate(&[
        "sensors",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--paths",
        "4000",
        "--batches",
        "8",
        "--batch-values",
        "--threads",
        "2",
    ])
    .unwrap();
    let r = luxest_io::sensors::SensorResults::read_ron(&out).unwrap();
    assert_eq!(r.sets.len(), 2);
    let wp = &r.sets[0];
    let g = wp.grid.as_ref().unwrap();
    // 4 × 3 m less 0.5 m margins: 3 × 2 m, p = 0.2·5^log10(3) m.
    let p = 0.2 * 5f64.powf(3f64.log10());
    assert_eq!(
        (g.nu, g.nv),
        ((3.0 / p).ceil() as u32, (2.0 / p).ceil() as u32)
    );
    assert_eq!(g.margin_m, 0.5);
    assert!((g.origin - Vec3::new(0.0, 0.75, 3.0)).length() < 1e-12);
    assert_eq!(wp.points.len(), (g.nu * g.nv) as usize);
    assert_eq!(wp.kind, None);
    assert_eq!(r.sets[1].kind.as_deref(), Some("cylindrical"));
    for set in &r.sets {
        assert_eq!(set.batches.len(), 8);
        for (k, pt) in set.points.iter().enumerate() {
            let ys: Vec<f64> = set.batches.iter().map(|b| b[k]).collect();
            let mean = ys.iter().sum::<f64>() / 8.0;
            let var = ys.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / 7.0;
            assert!((mean - pt.value).abs() <= 1e-9 * pt.value, "{k}");
            assert!(
                (var.sqrt() / 8f64.sqrt() - pt.standard_error).abs() <= 1e-6 * pt.standard_error
            );
            assert!(pt.value > 0.0 && pt.standard_error > 0.0);
        }
    }
    // Without the flag the file stays as it was.
    crate::util::estimate(&[
        "sensors",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--paths",
        "400",
        "--batches",
        "4",
    ])
    .unwrap();
    let r = luxest_io::sensors::SensorResults::read_ron(&out).unwrap();
    assert!(r
        .sets
        .iter()
        .all(|s| s.batches.is_empty() && s.grid.is_some()));
    // The backward estimator samples about the normal: it refuses cylindrical sensors.
    for extra in [&["gather"][..], &["direct", "--bin-radius", "0.1"]] {
        let mut args = extra.to_vec();
        args.extend([scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
        let (code, msg) = crate::util::estimate(&args).unwrap_err();
        assert_eq!(code, 1);
        assert!(
            msg.contains("\"cylindrical\" measures cylindrical illuminance"),
            "{msg}"
        );
    }
}

#[test]
fn cosn_sphere_validation_case_passes_through_evaluate() {
    // The `make validate` case: scene-compile, estimate sensors and evaluate sensors --case
    // cosn-sphere with the cos² luminaire off-centre in the sphere; evaluate fails the run if
    // any |z| > 4. The table's interpolation error (≤ 0.05 % of the values) stays far below the
    // standard error of this run (about 1 %).
    let dir = TempDir::new("cosn-sphere");
    std::fs::copy(fixtures().join("cos2.ies"), dir.path().join("cos2.ies")).unwrap();
    let scene = crate::util::compile_text(
        &dir,
        "sphere",
        r#"Scene(materials: { "wall": Lambertian(reflectance: (0.5, 0.5, 0.5)) },
        objects: [(shape: Sphere(radius: 1.0, subdivisions: 6), material: "wall", flip_normals: true)],
        luminaires: [(file: "cos2.ies", position: (0.2, 0.1, -0.3))],
        sensors: [Points(name: "wall", points: [
            (position: (0.0, -0.9999, 0.0), normal: (0.0, 1.0, 0.0)),
            (position: (0.0, 0.9999, 0.0), normal: (0.0, -1.0, 0.0)),
            (position: (0.9999, 0.0, 0.0), normal: (-1.0, 0.0, 0.0)),
            (position: (0.0, 0.0, 0.9999), normal: (0.0, 0.0, -1.0)),
            (position: (-0.70704, -0.70704, 0.0), normal: (0.70711, 0.70711, 0.0)),
        ])])"#,
    );
    let out = dir.path().join("sphere.sensors.ron");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let (scene, out) = (s(&scene), s(&out));
    crate::util::estimate(&["sensors", &scene, "-o", &out, "--paths", "40000"]).unwrap();
    let case = "cosn-sphere:I0=1000,n=2,R=1,rho=0.5,x=0.2,y=0.1,z=-0.3";
    crate::util::evaluate(&["sensors", &out, "--case", case, "--max-z", "4"]).unwrap();
    // And the case is not vacuous: the same results fail against another flux.
    let wrong = "cosn-sphere:I0=1000,n=2.2,R=1,rho=0.5,x=0.2,y=0.1,z=-0.3";
    crate::util::evaluate(&["sensors", &out, "--case", wrong, "--max-z", "4"]).unwrap_err();
}

#[test]
fn cosn_sobolev_validation_case_passes_through_evaluate() {
    // The `make validate` case: the cos² luminaire between Sobolev's planes (h1 = 0.5 below,
    // h2 = 1 above, rho 0.5 and 0.7); exact values from the Hankel solution of luxest-exact.
    // Plane 1 gets the tabulated direct term (interpolation error ≤ 0.05 % of I0 at 2.5°
    // steps, below this run's standard errors of ~0.3 %) plus the indirect light.
    let dir = TempDir::new("cosn-sobolev");
    std::fs::copy(fixtures().join("cos2.ies"), dir.path().join("cos2.ies")).unwrap();
    let plane = |y: f64, ny: f64| {
        [0.0, 0.4, 1.0, 2.5]
            .iter()
            .map(|r| format!("(position: ({r}, {y}, 0.0), normal: (0.0, {ny}, 0.0))"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let scene = crate::util::compile_text(
        &dir,
        "sobolev",
        &format!(
            r#"Scene(materials: {{ "p1": Lambertian(reflectance: (0.5, 0.5, 0.5)),
                                   "p2": Lambertian(reflectance: (0.7, 0.7, 0.7)) }},
            objects: [(shape: Quad(corner: (-1000.0, -0.5, 1000.0), u: (2000.0, 0.0, 0.0), v: (0.0, 0.0, -2000.0)), material: "p1"),
                      (shape: Quad(corner: (-1000.0, 1.0, -1000.0), u: (2000.0, 0.0, 0.0), v: (0.0, 0.0, 2000.0)), material: "p2")],
            luminaires: [(file: "cos2.ies", position: (0.0, 0.0, 0.0))],
            sensors: [Points(name: "p1", points: [{}]), Points(name: "p2", points: [{}])])"#,
            plane(-0.5, 1.0),
            plane(1.0, -1.0)
        ),
    );
    let out = dir.path().join("sobolev.sensors.ron");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let (scene, out) = (s(&scene), s(&out));
    crate::util::estimate(&["sensors", &scene, "-o", &out, "--paths", "40000"]).unwrap();
    let case = "cosn-sobolev:I0=1000,n=2,h1=0.5,h2=1,rho1=0.5,rho2=0.7";
    crate::util::evaluate(&["sensors", &out, "--case", case, "--max-z", "4"]).unwrap();
    // Not vacuous: the same results fail against another exponent.
    let wrong = "cosn-sobolev:I0=1000,n=2.2,h1=0.5,h2=1,rho1=0.5,rho2=0.7";
    crate::util::evaluate(&["sensors", &out, "--case", wrong, "--max-z", "4"]).unwrap_err();
}

#[test]
fn luminaire_estimates_do_not_depend_on_the_thread_count() {
    // Randomness is keyed by (seed, batch): one and two threads give the same numbers, with
    // luminaires (area form included) in the light paths and the direct term.
    let text = format!(
        r#"Scene(materials: {{ "floor": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
        objects: [{BIG_FLOOR},
            (shape: Quad(corner: (2.0, 0.0, 5.0), u: (0.0, 0.0, -10.0), v: (0.0, 4.0, 0.0)), material: "floor")],
        luminaires: [(file: "bilat.ies", position: (0.0, 2.5, 0.0), tilt_deg: 17.0),
                     (file: "quad.ldt", position: (1.0, 2.0, 1.0), opening: Area(length: 0.4, width: 0.2, cells: (4, 2)))],
        calculation_surfaces: [(name: "wp", area: Floor(min: (-3.0, -3.0), max: (2.0, 3.0), y: 0.0),
                                offset: 0.8, spacing: Counts(4, 5), kind: SemiCylindrical(facing: (1.0, 0.0, 0.0)))])"#
    );
    let world = world_from(&text);
    let s = estimate::all_sensors(&world);
    let near = vec![0.0; s.len()];
    let mut cfg = config(3000, &world);
    cfg.batches.threads = 1;
    let a = local::estimate(&world, &s, &near, &cfg, &Progress::off());
    cfg.batches.threads = 2;
    let b = local::estimate(&world, &s, &near, &cfg, &Progress::off());
    assert_eq!(a.value, b.value);
    assert_eq!(a.standard_error, b.standard_error);
    assert!(a.standard_error.iter().all(|&e| e > 0.0));
}
