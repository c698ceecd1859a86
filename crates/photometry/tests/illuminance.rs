//! Direct illuminance and the sensor kernels against closed forms.

use crate::common::{get, Rng};
use luxest_photometry::{
    direct_illuminance_lx, direct_sensor_illuminance_lx, Frame, Luminaire, Orientation, SensorKind,
};
use std::f64::consts::PI;
use std::sync::Arc;

/// E(r) on a horizontal plane h below a downlight I(γ) = I0 cos²γ: E = I0 cos²γ cos γ /(h² + r²),
/// cos γ = h/√(h² + r²). The file tabulates cos² γ every 2.5°, so the interpolated intensity is
/// within (Δγ²/8)·max|I''| ≤ (Δγ²/8)·n²·I0 of the formula; that bound, times cos γ/d², is the
/// tolerance. The same points are also compared, to rounding, with the table intensity at the
/// (C, γ) computed here by independent trigonometry.
#[test]
fn direct_illuminance_of_cos2_downlight_matches_closed_form() {
    let (i0, h) = (1000.0, 2.5);
    let tol_i = 2.5f64.to_radians().powi(2) / 8.0 * 4.0 * i0;
    for name in ["cos2.ies", "cos2.ldt"] {
        let p = get(name);
        let lum = [1.0, -2.0, 3.0];
        let f = Frame::default();
        let mut worst: f64 = 0.0;
        for k in 0..200 {
            let r = 0.05 * k as f64;
            let phi = 0.7 * k as f64;
            let pt = [lum[0] + r * phi.cos(), lum[1] + r * phi.sin(), lum[2] - h];
            let d2 = h * h + r * r;
            let cg = h / d2.sqrt();
            let want = i0 * cg * cg * cg / d2;
            let got = direct_illuminance_lx(&p, &f, lum, pt, [0.0, 0.0, 1.0]);
            assert!(
                (got - want).abs() <= tol_i * cg / d2 + 1e-12,
                "{name} r {r}: {got} vs {want}"
            );
            worst = worst.max((got - want).abs() / want);
            let c_deg = phi.to_degrees().rem_euclid(360.0);
            let g_deg = (r / h).atan().to_degrees();
            let exact = p.intensity_cd(c_deg, g_deg) * cg / d2;
            assert!(
                (got - exact).abs() <= 1e-12 * exact.max(1e-300),
                "{got} vs {exact}"
            );
        }
        eprintln!("{name}: worst relative deviation from the closed form {worst:.2e}");
        // A surface facing away receives nothing; a point above the downlight nothing either.
        assert_eq!(
            direct_illuminance_lx(&p, &f, lum, [1.0, -2.0, 0.0], [0.0, 0.0, -1.0]),
            0.0
        );
        assert_eq!(
            direct_illuminance_lx(&p, &f, lum, [1.0, -2.0, 5.0], [0.0, 0.0, -1.0]),
            0.0
        );
    }
}

/// A rotated and aimed luminaire: the illuminance at a world point equals the table intensity
/// at the (C, γ) the orientation maps it to, computed by hand for simple cases.
#[test]
fn orientation_moves_the_distribution() {
    let p = Arc::new(get("quad.ies"));
    // Rotation by 30° about the vertical: a point at world azimuth 50° sees C = 20°.
    let f = Orientation {
        rotation_deg: 30.0,
        ..Default::default()
    }
    .frame()
    .unwrap();
    let lum = Luminaire {
        photometry: p.clone(),
        position: [0.0; 3],
        frame: f,
        multiplier: 0.8,
    };
    let (r, h) = (1.3, 2.0);
    let a = 50f64.to_radians();
    let pt = [r * a.cos(), r * a.sin(), -h];
    let d2 = r * r + h * h;
    let want = 0.8 * p.intensity_cd(20.0, (r / h).atan().to_degrees()) * (h / d2.sqrt()) / d2;
    let got = lum.direct_illuminance_lx(pt, [0.0, 0.0, 1.0]);
    assert!((got - want).abs() < 1e-12 * want, "{got} vs {want}");
    // Aimed horizontally along +x: the nadir (γ = 0) now points along +x, so a wall point at
    // (d, 0, 0) with normal −x receives I(γ = 0)/d².
    let f = Orientation {
        aim: [1.0, 0.0, 0.0],
        ..Default::default()
    }
    .frame()
    .unwrap();
    let lum = Luminaire {
        photometry: p.clone(),
        position: [0.0; 3],
        frame: f,
        multiplier: 1.0,
    };
    let got = lum.direct_illuminance_lx([3.0, 0.0, 0.0], [-1.0, 0.0, 0.0]);
    assert!((got - p.intensity_cd(0.0, 0.0) / 9.0).abs() < 1e-12 * got);
    assert!((lum.flux_lm() - p.flux_from_table_lm()).abs() < 1e-12 * lum.flux_lm());
}

fn horizontal_normal(phi: f64) -> [f64; 3] {
    [phi.cos(), phi.sin(), 0.0]
}

/// The cylindrical and semi-cylindrical responses against their definitions: the mean of the
/// cosine response over the (half) cylinder's normals, integrated by the midpoint rule with
/// 20 000 steps (error O(1/N²) on the smooth parts; the kink costs O(1/N²) too: < 1e-7).
#[test]
fn cylinder_kernels_equal_the_average_over_their_normals() {
    let mut rng = Rng(9);
    let axis = [0.0, 0.0, 1.0];
    let n = 20_000;
    for _ in 0..200 {
        // A random unit direction towards the source.
        let z = 2.0 * rng.uniform() - 1.0;
        let t = 2.0 * PI * rng.uniform();
        let s = (1.0 - z * z).sqrt();
        let w = [s * t.cos(), s * t.sin(), z];
        let face = 2.0 * PI * rng.uniform();
        let mut full = 0.0;
        let mut half = 0.0;
        for k in 0..n {
            let phi = (k as f64 + 0.5) / n as f64 * 2.0 * PI;
            let cosine =
                (horizontal_normal(phi)[0] * w[0] + horizontal_normal(phi)[1] * w[1]).max(0.0);
            full += cosine;
            let phi_h = face - PI / 2.0 + (k as f64 + 0.5) / n as f64 * PI;
            let nh = horizontal_normal(phi_h);
            half += (nh[0] * w[0] + nh[1] * w[1]).max(0.0);
        }
        let full = full / n as f64; // (1/2π)∫ dφ
        let half = half / n as f64; // (1/π)∫ over π
        let cyl = SensorKind::Cylindrical { axis }.response(w);
        let semi = SensorKind::SemiCylindrical {
            axis,
            facing: horizontal_normal(face),
        }
        .response(w);
        assert!((cyl - full).abs() < 1e-7, "{cyl} vs {full}");
        assert!((semi - half).abs() < 1e-7, "{semi} vs {half}");
    }
}

/// Point-source closed forms: E_z = I sin ε /(π d²); E_sc = I (1 + cos α) cos²ε' sin ε' /(π H²)
/// (CIE 136 / EN 13201-3 form, ε' from the vertical, H the height of the source above the point).
#[test]
fn cylindrical_illuminance_from_a_point_source() {
    let p = get("cos2.ies");
    let f = Frame::default();
    let lum = [0.0, 0.0, 3.0];
    let pt = [1.5, 0.8, 1.2];
    let v = [lum[0] - pt[0], lum[1] - pt[1], lum[2] - pt[2]];
    let d2: f64 = v.iter().map(|x| x * x).sum();
    let d = d2.sqrt();
    let hh = v[2];
    let sin_e = (v[0] * v[0] + v[1] * v[1]).sqrt() / d; // from the vertical axis
    let i = p.intensity_cd(
        v[1].atan2(v[0]).to_degrees() + 180.0,
        (sin_e).asin().to_degrees(),
    );
    let axis = [0.0, 0.0, 1.0];
    let ez = direct_sensor_illuminance_lx(&p, &f, lum, pt, &SensorKind::Cylindrical { axis });
    assert!((ez - i * sin_e / (PI * d2)).abs() < 1e-12 * ez, "{ez}");
    // Semi-cylinder facing −x: α between −x and the horizontal direction to the source.
    let facing = [-1.0, 0.0, 0.0];
    let cos_a = -v[0] / (v[0] * v[0] + v[1] * v[1]).sqrt();
    let cos_e = hh / d;
    let want = i * (1.0 + cos_a) * cos_e * cos_e * sin_e / (PI * hh * hh);
    let esc = direct_sensor_illuminance_lx(
        &p,
        &f,
        lum,
        pt,
        &SensorKind::SemiCylindrical { axis, facing },
    );
    assert!((esc - want).abs() < 1e-12 * want, "{esc} vs {want}");
    // Facing the source gets more than facing away; the cylinder lies between their mean.
    let away = direct_sensor_illuminance_lx(
        &p,
        &f,
        lum,
        pt,
        &SensorKind::SemiCylindrical {
            axis,
            facing: [1.0, 0.0, 0.0],
        },
    );
    assert!(away < esc);
    assert!(((away + esc) / 2.0 - ez).abs() < 1e-12 * ez);
}

/// The round trip: an LDT and an IES file describing the same distribution give the same
/// illuminances to 1e-6, here on a 2 m x 2 m plane 1.5 m below, the luminaire rotated and tilted.
#[test]
fn ies_and_ldt_give_the_same_illuminances() {
    let f = Orientation {
        tilt_deg: 12.0,
        rotation_deg: 33.0,
        ..Default::default()
    }
    .frame()
    .unwrap();
    for (a, b) in [
        ("cos2.ies", "cos2.ldt"),
        ("quad.ies", "quad.ldt"),
        ("bilat90.ies", "bilat90-full.ldt"),
    ] {
        let (pa, pb) = (get(a), get(b));
        let mut n = 0;
        for i in 0..41 {
            for j in 0..41 {
                let pt = [-1.0 + 0.05 * i as f64, -1.0 + 0.05 * j as f64, -1.5];
                let ea = direct_illuminance_lx(&pa, &f, [0.0; 3], pt, [0.0, 0.0, 1.0]);
                let eb = direct_illuminance_lx(&pb, &f, [0.0; 3], pt, [0.0, 0.0, 1.0]);
                assert!(
                    (ea - eb).abs() <= 1e-6 * ea.max(eb),
                    "{a} vs {b} at {pt:?}: {ea} vs {eb}"
                );
                n += usize::from(ea > 0.0);
            }
        }
        assert!(n > 1600);
    }
}

/// Projected areas of the opening shapes against hand-computed silhouettes for simple directions,
/// and a disc's flat area.
#[test]
fn luminous_opening_projected_areas() {
    use luxest_photometry::{LuminousOpening, OpeningShape};
    let rect = LuminousOpening::from_ies(0.6, 1.2, 0.0);
    assert_eq!(rect.shape, OpeningShape::Rectangular);
    let d = luxest_photometry::direction_from_c_gamma(30.0, 60.0);
    assert!((rect.projected_area_m2(d).unwrap() - 0.72 * 0.5).abs() < 1e-12);
    let boxy = LuminousOpening::from_ies(0.2, 0.4, 0.1);
    // Seen along +x (C = 0, γ = 90): the w × h side.
    assert!((boxy.projected_area_m2([1.0, 0.0, 0.0]).unwrap() - 0.02).abs() < 1e-12);
    let sphere = LuminousOpening::from_ies(-0.3, -0.3, -0.3);
    assert_eq!(sphere.shape, OpeningShape::Sphere);
    for d in [[0.0, 0.0, -1.0], [0.6, 0.0, 0.8], [0.0, 1.0, 0.0]] {
        assert!((sphere.projected_area_m2(d).unwrap() - PI * 0.0225).abs() < 1e-12);
    }
    let cyl = LuminousOpening::from_ies(-0.2, -0.2, 0.5);
    assert_eq!(cyl.shape, OpeningShape::VerticalCylinder);
    assert!((cyl.projected_area_m2([1.0, 0.0, 0.0]).unwrap() - 0.1).abs() < 1e-12);
    assert!(LuminousOpening::from_ies(0.0, 0.0, 0.0)
        .projected_area_m2(d)
        .is_none());
    // A disc of diameter 0.4 (sampling.rs tests its points against their density).
    let disc = LuminousOpening::from_ies(-0.4, -0.4, 0.0);
    assert!((disc.flat_area_m2().unwrap() - PI * 0.04).abs() < 1e-15);
}
