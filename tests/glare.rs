//! Glare: UGR at observers (`estimate sensors` → `SensorResults.glare`) against Radiance
//! `evalglare` numbers committed by pipelines/radiance_glare.py, a source's luminance and solid
//! angle against the closed form of its distribution, and observers placed where no eye can be
//! (one-line errors naming the scene).

use crate::util::{estimate_sensors, repo_root, scene_compile, TempDir};
use luxest_io::sensors::SensorResults;

/// The committed evalglare UGR of `scene` per (observer, view) from the peer's CSV.
fn evalglare(scene: &str) -> Vec<(String, [f64; 3], f64)> {
    let path = repo_root().join(format!("reports/lighting/glare/{scene}.csv"));
    let text = std::fs::read_to_string(&path).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let n = |i: usize| f[i].parse::<f64>().unwrap();
            (f[0].to_string(), [n(1), n(2), n(3)], n(6))
        })
        .collect()
}

fn estimate_glare(dir: &TempDir, scene: &str, paths: &str) -> SensorResults {
    let ron = repo_root().join(format!("scenes/{scene}.ron"));
    let lxs = dir.path().join(format!("{scene}.lxs"));
    scene_compile(&[ron.to_str().unwrap(), "-o", lxs.to_str().unwrap(), "-q"]).unwrap();
    estimate_sensors(&lxs, paths, &["-q"])
}

/// The downlight lobby: luxest's UGR within ±1 of evalglare's on the same room (plus 3 σ of
/// luxest's background), at every observer and view.
#[test]
fn ugr_agrees_with_evalglare_in_the_downlight_lobby() {
    let dir = TempDir::new("glare-peer");
    let r = estimate_glare(&dir, "glare-downlights", "20000");
    let peer = evalglare("glare-downlights");
    assert_eq!(r.glare.len(), peer.len());
    for (g, (name, view, ugr)) in r.glare.iter().zip(&peer) {
        assert_eq!(&g.observer, name);
        let v: [f64; 3] = g.view.into();
        assert!(
            (0..3).all(|k| (v[k] - view[k]).abs() < 1e-6),
            "{v:?} {view:?}"
        );
        let d = (g.ugr - ugr).abs();
        assert!(
            d <= 1.0 + 3.0 * g.standard_error,
            "{name}: luxest {} ± {} evalglare {ugr}",
            g.ugr,
            g.standard_error
        );
        assert!(g.standard_error > 0.0 && g.standard_error < 0.2);
    }
}

/// A source's luminance and solid angle against the closed form: the downlight's file tabulates
/// I = A cos³γ every 5° (interpolated linearly in γ between, as LM-63 prescribes) from a 150 mm
/// disk, so from an eye at distance D under the angle γ it has L = I(γ) / (π r² cos γ) and
/// ω = π r² cos γ / D² (the far field of a small disk).
#[test]
fn a_downlights_luminance_is_its_closed_form() {
    let dir = TempDir::new("glare-disk");
    let r = estimate_glare(&dir, "glare-downlights", "2000");
    let a = 762.4931532; // cd, the file's [MORE] keyword
    let radius: f64 = 0.075;
    let g = &r.glare[0]; // "door" at (0.3, 1.6, 2.5) looking +x
    let s = g.sources.iter().find(|s| s.luminaire == "d22").unwrap();
    let (dx, dy): (f64, f64) = (2.5 - 0.3, 2.69 - 1.6);
    let d = (dx * dx + dy * dy).sqrt();
    let cos_g = dy / d;
    let area = std::f64::consts::PI * radius * radius;
    let gamma = cos_g.acos().to_degrees();
    let g0 = (gamma / 5.0).floor() * 5.0;
    let f = |g: f64| a * g.to_radians().cos().powi(3);
    let intensity = f(g0) + (f(g0 + 5.0) - f(g0)) * (gamma - g0) / 5.0;
    let l = intensity / (area * cos_g);
    assert!(
        (s.luminance / l - 1.0).abs() < 0.01,
        "{} vs {l}",
        s.luminance
    );
    let omega = area * cos_g / (d * d);
    assert!(
        (s.solid_angle_sr / omega - 1.0).abs() < 1e-6,
        "{} vs {omega}",
        s.solid_angle_sr
    );
    // Guth above the line of sight: τ = 0 (straight ahead and up), σ = atan(dy / dx).
    let sigma = dy.atan2(dx).to_degrees();
    let p = ((35.2 - 1.22) * 1e-3 * sigma + 21e-5 * sigma * sigma).exp();
    assert!((s.position_index / p - 1.0).abs() < 1e-9);
}

const ROOM: &str = r#"Scene(
    materials: { "w": Lambertian(reflectance: (0.5, 0.5, 0.5)) },
    objects: [
        (shape: Quad(corner: (0.0, 0.0, 0.0), u: (0.0, 0.0, 4.0), v: (4.0, 0.0, 0.0)), material: "w"),
        (shape: Quad(corner: (0.0, 3.0, 0.0), u: (4.0, 0.0, 0.0), v: (0.0, 0.0, 4.0)), material: "w"),
        (shape: Quad(corner: (0.0, 0.0, 0.0), u: (0.0, 3.0, 0.0), v: (0.0, 0.0, 4.0)), material: "w"),
        (shape: Quad(corner: (4.0, 0.0, 0.0), u: (0.0, 0.0, 4.0), v: (0.0, 3.0, 0.0)), material: "w"),
        (shape: Quad(corner: (0.0, 0.0, 0.0), u: (4.0, 0.0, 0.0), v: (0.0, 3.0, 0.0)), material: "w"),
        (shape: Quad(corner: (0.0, 0.0, 4.0), u: (0.0, 3.0, 0.0), v: (4.0, 0.0, 0.0)), material: "w"),
        (name: "desk", shape: Box(size: (1.0, 0.7, 1.0)), transform: (translate: (2.0, 0.35, 2.0)), material: "w"),
    ],
    luminaires: [(file: "LUM", position: (2.0, 2.99, 2.0))],
    observers: [OBS],
)"#;

fn room(dir: &TempDir, observer: &str) -> (std::path::PathBuf, Result<(), (u8, String)>) {
    let lum = repo_root().join("scenes/photometry/troffer-600-led.ies");
    let text = ROOM
        .replace("LUM", lum.to_str().unwrap())
        .replace("OBS", observer);
    let ron = dir.write("room.ron", text);
    let out = dir.path().join("room.lxs");
    let r = scene_compile(&[ron.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]);
    (ron, r)
}

#[test]
fn observers_where_no_eye_can_be_are_refused() {
    let dir = TempDir::new("glare-bad");
    let cases = [
        ("(name: \"in-desk\", position: (2.0, 0.3, 2.0), views: [(1.0, 0.0, 0.0)])", "inside an object or outside the room"),
        ("(name: \"outside\", position: (6.0, 1.2, 2.0), views: [(1.0, 0.0, 0.0)])", "inside an object or outside the room"),
        ("(name: \"blind\", position: (1.0, 1.2, 1.0), views: [])", "at least one line of sight"),
        ("(name: \"zero\", position: (1.0, 1.2, 1.0), views: [(0.0, 0.0, 0.0)])", "zero vector"),
        ("(name: \"nan\", position: (1.0, 1.2, 1.0), views: [(1.0, 0.0, 0.0)], ugr_limit: Some(-1.0))", "non-negative UGR"),
    ];
    for (obs, want) in cases {
        let (ron, r) = room(&dir, obs);
        let (code, msg) = r.expect_err(obs);
        assert_eq!(code, 1, "{msg}");
        assert!(
            msg.contains(want) && msg.contains(ron.to_str().unwrap()),
            "{msg}"
        );
        assert_eq!(msg.lines().count(), 1, "{msg}");
    }
    // An eye in open space compiles, and its UGR is finite.
    let (_, r) = room(
        &dir,
        "(name: \"ok\", position: (0.5, 1.2, 0.5), views: [(1.0, 0.0, 1.0)])",
    );
    r.unwrap();
    let g = &estimate_sensors(&dir.path().join("room.lxs"), "2000", &["-q"]).glare[0];
    assert!(g.ugr.is_finite() && g.sources.len() == 1, "{g:?}");
}
