//! Portal-masked environment sampling (`luxest_render::portal`) end to end: a daylit room's image
//! is the same with and without portals within its noise, with less noise with them; the
//! world's environment sampler returns the density `environment_pdf` gives; bad portals are
//! one-line errors.

use crate::util::{compile_text, scene_compile, TempDir};
use luxest_io::math::Vec3;
use luxest_io::progress::Progress;
use luxest_render::sampling::Rng;
use trace::{Film, Renderer};

/// A 2 m × 1 m × 2 m grey room with a 0.6 m × 0.5 m open window
/// in the wall z = 2 and a 0.4 m × 0.4 m roof window given as a portal only (a hole in the
/// ceiling's quads), under `sky`; camera inside looking at the floor under the window.
fn room(portals: bool, sky: &str) -> String {
    let roof_portal = if portals {
        "portals: [(name: Some(\"roof\"), corner: (0.8, 1.0, 0.8), u: (0.4, 0.0, 0.0), v: (0.0, 0.0, 0.4))],"
    } else {
        ""
    };
    format!(
        r#"Scene(
    camera: Camera(position: (1.0, 0.7, 0.2), look_at: (1.0, 0.0, 1.0), vfov_deg: 50.0, resolution: (8, 6)),
    materials: {{ "grey": Lambertian(reflectance: (0.5, 0.5, 0.5)) }},
    objects: [
        (shape: Quad(corner: (0, 0, 0), u: (0, 0, 2), v: (2, 0, 0)), material: "grey"),
        (shape: Quad(corner: (0, 1, 0), u: (0.8, 0, 0), v: (0, 0, 2)), material: "grey"),
        (shape: Quad(corner: (1.2, 1, 0), u: (0.8, 0, 0), v: (0, 0, 2)), material: "grey"),
        (shape: Quad(corner: (0.8, 1, 0), u: (0.4, 0, 0), v: (0, 0, 0.8)), material: "grey"),
        (shape: Quad(corner: (0.8, 1, 1.2), u: (0.4, 0, 0), v: (0, 0, 0.8)), material: "grey"),
        (shape: Quad(corner: (0, 0, 0), u: (0, 1, 0), v: (0, 0, 2)), material: "grey"),
        (shape: Quad(corner: (2, 0, 0), u: (0, 0, 2), v: (0, 1, 0)), material: "grey"),
        (shape: Quad(corner: (0, 0, 0), u: (2, 0, 0), v: (0, 1, 0)), material: "grey"),
        (name: Some("south"), shape: Quad(corner: (0, 0, 2), u: (0, 1, 0), v: (2, 0, 0)), material: "grey"),
    ],
    windows: [(corner: (0.7, 0.3, 2), u: (0, 0.5, 0), v: (0.6, 0, 0))],
    {roof_portal}
    environment: Some(Sky({sky})),
)"#
    )
}

fn render(lxs: &std::path::Path, portals: bool, spp: u32) -> Film {
    let (mut world, cam) = trace::load(lxs, None).unwrap();
    world.set_portals(portals);
    assert_eq!(world.portal_count(), if portals { 2 } else { 0 });
    let mut film = Film::new(cam.width as usize, cam.height as usize);
    Renderer::new(&world, cam, 3, 2, 1024).advance(&mut film, spp, false, &Progress::off());
    film
}

/// The clear sky with the sun low in the south (+z), shining through the wall window.
const SUNNY: &str = "(kind: Clear, angles: Some((altitude: 30.0, azimuth: 0.0)))";

/// The overcast sky.
const OVERCAST: &str = "(kind: Overcast, horizontal_illuminance: Some(10000.0))";

#[test]
fn daylit_room_is_the_same_with_and_without_portals() {
    let dir = TempDir::new("portals-room");
    let lxs = compile_text(&dir, "room", &room(true, SUNNY));
    let with = render(&lxs, true, 256);
    let without = render(&lxs, false, 256);
    let (m1, s1) = (with.mean(), with.standard_error());
    let (m0, s0) = (without.mean(), without.standard_error());
    let (mut sum1, mut sum0, mut var1, mut var0) = (0.0, 0.0, 0.0, 0.0);
    for i in 0..m1.len() {
        let (a, b) = (m1[i].luminance(), m0[i].luminance());
        let se = (s1[i] * s1[i] + s0[i] * s0[i]).sqrt();
        assert!(
            a.is_finite() && (a - b).abs() <= 4.5 * se,
            "pixel {i}: {a} ± {} with portals, {b} ± {} without",
            s1[i],
            s0[i]
        );
        sum1 += a;
        sum0 += b;
        var1 += s1[i] * s1[i];
        var0 += s0[i] * s0[i];
    }
    let se = (var1 + var0).sqrt();
    assert!(
        (sum1 - sum0).abs() <= 4.0 * se,
        "image sums {sum1} vs {sum0} ± {se}"
    );
}

#[test]
fn portals_cut_the_noise_of_skylight() {
    // The point of portals: the image's variance under the overcast sky, at the same samples,
    // is a fraction of what sampling the whole sky gives.
    let dir = TempDir::new("portals-noise");
    let lxs = compile_text(&dir, "room", &room(true, OVERCAST));
    let var = |portals: bool| -> f64 {
        let film = render(&lxs, portals, 64);
        film.standard_error().iter().map(|s| s * s).sum()
    };
    let (with, without) = (var(true), var(false));
    assert!(
        with < 0.25 * without,
        "variance {with} with portals, {without} without"
    );
}

#[test]
fn sampled_directions_carry_the_density_environment_pdf_gives() {
    let dir = TempDir::new("portals-pdf");
    let lxs = compile_text(&dir, "room", &room(true, SUNNY));
    let (world, _) = trace::load(&lxs, None).unwrap();
    let mut r = Rng::new(8, 1);
    for k in 0..4000 {
        let from = if k % 100 == 0 {
            // In the plane of the wall window: no portal rectangle there but the roof's.
            Vec3::new(0.2 + 1.6 * r.next_f64(), 0.05 + 0.9 * r.next_f64(), 2.0)
        } else {
            Vec3::new(2.0 * r.next_f64(), r.next_f64(), 2.0 * r.next_f64())
        };
        let s = world
            .sample_environment(from, r.next_f64(), r.next_f64())
            .unwrap();
        assert!((s.direction.length() - 1.0).abs() < 1e-9);
        let p = world.environment_pdf(from, s.direction);
        assert!(
            s.pdf > 0.0 && (p - s.pdf).abs() <= 1e-9 * s.pdf,
            "from {from:?}: sampled pdf {} vs environment_pdf {p}",
            s.pdf
        );
    }
    // On the edge where the ceiling meets the window wall, in the plane of both portals: no
    // direction is drawn, and the density of every direction is 0 (BSDF sampling's alone).
    let edge = Vec3::new(1.5, 1.0, 2.0);
    assert!(world.sample_environment(edge, 0.3, 0.6).is_none());
    assert_eq!(world.environment_pdf(edge, Vec3::new(0.0, -0.6, -0.8)), 0.0);
    // Without portals the whole sky is sampled there.
    let mut world = world;
    world.set_portals(false);
    assert!(world.sample_environment(edge, 0.3, 0.6).is_some());
}

#[test]
fn bad_portals_are_one_line_errors() {
    let dir = TempDir::new("portals-bad");
    let text = room(false, OVERCAST).replace(
        "environment:",
        "portals: [(corner: (0, 1, 0), u: (1, 0, 0), v: (0.5, 0, 1))],\n    environment:",
    );
    let ron = dir.write("skew.ron", &text);
    let out = dir.path().join("skew.lxs");
    let e = scene_compile(&[ron.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]).unwrap_err();
    let (code, m) = e;
    assert!(
        code == 1
            && m.contains("portals[0]")
            && m.contains("perpendicular")
            && !m.trim().contains('\n'),
        "{m}"
    );
}

#[test]
fn portals_option_is_refused_where_it_has_no_effect() {
    // The room without its window (the scene has no portal): an explicit --portals is refused
    // with a one-line usage error; with the window it runs.
    let dir = TempDir::new("portals-cli");
    let closed = room(false, OVERCAST).replace(
        "windows: [(corner: (0.7, 0.3, 2), u: (0, 0.5, 0), v: (0.6, 0, 0))],",
        "",
    );
    let trace = |lxs: &std::path::Path, out: &str| {
        let out = dir.path().join(out);
        let argv = [
            "trace",
            lxs.to_str().unwrap(),
            "--spp",
            "1",
            "--portals",
            "off",
            "-o",
            out.to_str().unwrap(),
        ];
        let a = luxest_io::cli::parse::<trace::Args>(argv).unwrap().unwrap();
        trace::run(a)
    };
    let e = trace(&compile_text(&dir, "closed", &closed), "closed").unwrap_err();
    let m = e.to_string();
    assert!(
        e.exit_code() == 2 && m.contains("--portals") && !m.contains('\n'),
        "{m}"
    );
    trace(&compile_text(&dir, "open", &room(false, OVERCAST)), "open").unwrap();
}
