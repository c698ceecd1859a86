//! Point-to-point illuminance kernels: what one connection from a sensor point to a light source
//! (or to a luminous surface element) contributes to planar, cylindrical and semi-cylindrical
//! illuminance.
//!
//! For light arriving at a point from the unit direction ω (pointing *from the point towards the
//! source*), every illuminance kind is E = ∫ L(ω) g(ω) dω with a geometric response g; from a
//! point source of intensity I at distance d it is E = (I / d²) · g(ω). The responses
//! (CIE S 017:2020 17-21-062, 17-21-089; EN 12464-1:2021 §4.3.5; EN 12464-2; CIE 136):
//!
//! - **planar**, unit normal n: g = max(0, n·ω) (the cosine law).
//! - **cylindrical** (mean illuminance over the curved surface of a vanishingly small cylinder
//!   with unit axis a, usually vertical): with ε the angle between ω and a,
//!   g = sin ε / π = |ω_h| / π, ω_h = ω − (a·ω) a. Derivation: the cylinder (radius r, height h)
//!   intercepts the flux through its silhouette 2 r h sin ε out of a lateral area 2π r h.
//!   Equivalently (1/2π) ∫₀^{2π} max(0, n(φ)·ω) dφ over its horizontal normals n(φ).
//! - **semi-cylindrical** (curved surface of a small half cylinder with axis a facing the
//!   horizontal unit direction f): g = (|ω_h| + f·ω) / π = sin ε (1 + cos α) / π, α the angle
//!   between f and ω_h; (1/π) ∫_{−π/2}^{π/2} max(0, n(φ)·ω) dφ over the normals of the half.
//!   For a point source at height H above the point's plane this is the standard
//!   E_sc = I (1 + cos α) cos² ε' sin ε' / (π H²) with ε' measured from the vertical.
//!
//! [`direct_illuminance_lx`] treats the luminaire as a point at its photometric centre (the far
//! field assumption of the photometric file itself, valid beyond about five times the luminous
//! opening's largest dimension) and checks no visibility: the caller multiplies by it.

use crate::frame::{dot, norm, scale, sub, Frame};
use crate::photometry::Photometry;
use std::f64::consts::PI;

/// The kind of illuminance a sensor measures (see the module docs for the responses).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SensorKind {
    /// Planar illuminance on a surface with unit normal `normal` (one-sided).
    Planar { normal: [f64; 3] },
    /// Cylindrical illuminance about the unit `axis` (vertical: (0, 0, 1)).
    Cylindrical { axis: [f64; 3] },
    /// Semi-cylindrical illuminance about the unit `axis`, the half cylinder facing the unit
    /// `facing` direction (perpendicular to the axis).
    SemiCylindrical { axis: [f64; 3], facing: [f64; 3] },
}

impl SensorKind {
    /// The geometric response g(ω) ≥ 0 for light arriving from unit direction `to_source`.
    pub fn response(&self, to_source: [f64; 3]) -> f64 {
        match *self {
            SensorKind::Planar { normal } => dot(normal, to_source).max(0.0),
            SensorKind::Cylindrical { axis } => {
                let h = sub(to_source, scale(axis, dot(axis, to_source)));
                norm(h) / PI
            }
            SensorKind::SemiCylindrical { axis, facing } => {
                let h = sub(to_source, scale(axis, dot(axis, to_source)));
                ((norm(h) + dot(facing, h)) / PI).max(0.0)
            }
        }
    }
}

/// Direct illuminance (lx) at `point` on a surface with unit `normal` from a luminaire at
/// `luminaire_pos` with local-to-world `frame`: E = I(ω_local) max(0, n·ω) / d², ω the unit
/// direction from the point to the luminaire and ω_local = frame⁻¹(−ω) the emission direction.
/// No visibility test. Returns 0 when the point coincides with the luminaire.
pub fn direct_illuminance_lx(
    photometry: &Photometry,
    frame: &Frame,
    luminaire_pos: [f64; 3],
    point: [f64; 3],
    normal: [f64; 3],
) -> f64 {
    direct_sensor_illuminance_lx(
        photometry,
        frame,
        luminaire_pos,
        point,
        &SensorKind::Planar { normal },
    )
}

/// Direct illuminance (lx) of any [`SensorKind`] at `point`: E = I(ω_local) g(ω) / d².
pub fn direct_sensor_illuminance_lx(
    photometry: &Photometry,
    frame: &Frame,
    luminaire_pos: [f64; 3],
    point: [f64; 3],
    sensor: &SensorKind,
) -> f64 {
    let to_lum = sub(luminaire_pos, point);
    let d2 = dot(to_lum, to_lum);
    if d2 <= 0.0 || !d2.is_finite() {
        return 0.0;
    }
    let w = scale(to_lum, 1.0 / d2.sqrt());
    let g = sensor.response(w);
    if g <= 0.0 {
        return 0.0;
    }
    let emit_local = frame.to_local(scale(w, -1.0));
    photometry.intensity_dir_cd(emit_local) * g / d2
}
