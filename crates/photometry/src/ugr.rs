//! Discomfort glare: the unified glare rating (UGR) of CIE 117-1995, as EN 12464-1 limits it.
//!
//! ```text
//! UGR = 8 log10( 0.25 / L_b · Σ L_i² ω_i / p_i² )
//! ```
//!
//! with L_b the background luminance (cd/m²; CIE 117: the indirect illuminance at the eye / π),
//! and per glare source i its luminance L_i towards the eye (cd/m²), the solid angle ω_i of its
//! luminous area seen from the eye (sr) and its position index p_i.
//!
//! **Position index.** Above the line of sight: Guth's formula as the IES Lighting Handbook
//! states it (a fit of the Luckiesh–Guth table that CIE 117 tabulates),
//!
//! ```text
//! ln p = (35.2 − 0.31889 τ − 1.22 e^(−2τ/9)) · 10⁻³ σ + (21 + 0.26667 τ − 0.002963 τ²) · 10⁻⁵ σ²
//! ```
//!
//! with σ the angle between the line of sight and the direction to the source and τ the angle
//! between the vertical plane through the line of sight and the plane through the line of sight
//! and the source (both in degrees; τ = 0 straight above, 90° level beside the line of sight).
//! Below the line of sight (CIE 117 gives no index there): the formula of Iwata & Osterhaus
//! (2010) in the form Radiance's `evalglare` 3.05 applies, β = atan(tan σ · √(1 + 0.3225 cos² τ)),
//! ln p = 6.49·10⁻³ β + 21·10⁻⁵ β². As in `evalglare`, p is capped at 16, and a source at
//! σ ≥ 90° (behind the plane of the eye perpendicular to the line of sight) is not in the field
//! of view and does not count ([`position_index`] returns `None`). `evalglare` cuts nothing
//! else by default (its `-g` field-of-view cuts are options), so neither does this module.
//!
//! **Luminance and solid angle.** A luminaire with a flat luminous opening of area A seen from
//! the eye at distance D along the unit direction d (luminaire frame) has the projected area
//! A_p = A |d_z| ([`crate::LuminousOpening::projected_area_m2`]) and the luminance
//! L = I(−d) / A_p, the file's intensity towards the eye over the projected area. Observers sit
//! close to luminaires, so at an observer ([`SolidAngle::Exact`]) a flat opening is divided into
//! cells, each with its own direction, luminance, solid angle and position index, and the
//! luminaire's term is their sum (a 1.5 m pendant 1.5 m away spans 30° of elevation); the
//! tabular method keeps the far-field centre term ([`SolidAngle::FarField`]).
//!
//! **Uncertainty.** Only L_b carries Monte Carlo error (the sources are computed exactly), so
//! the standard error of UGR is 8 / ln 10 · s(L_b) / L_b (first order).
//!
//! **No source in view.** With Σ = 0 the formula is −∞: [`Ugr::value`] is then 0 and
//! [`Ugr::note`] says why (as `evalglare` reports 0); a value below 10 is kept as computed
//! (EN 12464-1 and CIE tables print such values as "<10").

use crate::frame::Frame;
use crate::photometry::{LuminousOpening, OpeningShape, Photometry};
use std::f64::consts::LN_10;

/// Cap of the position index (as `evalglare`).
pub const MAX_POSITION_INDEX: f64 = 16.0;

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = norm(a);
    (n > 0.0 && n.is_finite()).then(|| a.map(|x| x / n))
}

/// Guth's position index above the line of sight for the angles τ and σ in degrees.
pub fn guth_position_index(tau_deg: f64, sigma_deg: f64) -> f64 {
    let (t, s) = (tau_deg, sigma_deg);
    let a = (35.2 - 0.31889 * t - 1.22 * (-2.0 * t / 9.0).exp()) * 1e-3;
    let b = (21.0 + 0.26667 * t - 0.002963 * t * t) * 1e-5;
    (a * s + b * s * s).exp()
}

/// The position index below the line of sight (Iwata & Osterhaus 2010, `evalglare`'s form).
pub fn iwata_position_index(tau_deg: f64, sigma_deg: f64) -> f64 {
    let c = tau_deg.to_radians().cos();
    let beta = (sigma_deg.to_radians().tan() * (1.0 + 0.3225 * c * c).sqrt())
        .atan()
        .to_degrees();
    (6.49e-3 * beta + 21e-5 * beta * beta).exp()
}

/// The angles (τ, σ) in degrees and whether the source lies above the line of sight, for the
/// unit line of sight `view`, the observer's `up` (any vector not along `view`) and the
/// direction `to_source` from the eye (any length); `None` when a vector is degenerate.
pub fn glare_angles(view: [f64; 3], up: [f64; 3], to_source: [f64; 3]) -> Option<(f64, f64, bool)> {
    let v = unit(view)?;
    let d = unit(to_source)?;
    // The up direction made perpendicular to the line of sight, and the right-hand side.
    let u = unit(sub(up, v.map(|x| x * dot(up, v))))?;
    let r = cross(v, u);
    let (fwd, h, t) = (dot(d, v), dot(d, u), dot(d, r));
    let sigma = fwd.clamp(-1.0, 1.0).acos().to_degrees();
    let tau = t.abs().atan2(h.abs()).to_degrees();
    Some((tau, sigma, h >= 0.0))
}

/// The position index of a source in direction `to_source` from the eye (see the module docs),
/// or `None` when it is not in the field of view (σ ≥ 90°) or a vector is degenerate.
pub fn position_index(view: [f64; 3], up: [f64; 3], to_source: [f64; 3]) -> Option<f64> {
    let (tau, sigma, above) = glare_angles(view, up, to_source)?;
    if sigma >= 90.0 {
        return None;
    }
    let p = if above {
        guth_position_index(tau, sigma)
    } else {
        iwata_position_index(tau, sigma)
    };
    Some(p.min(MAX_POSITION_INDEX))
}

/// Solid angle (sr) of the triangle (a, b, c) seen from the origin (Van Oosterom & Strackee 1983).
pub fn triangle_solid_angle_sr(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let (la, lb, lc) = (norm(a), norm(b), norm(c));
    let num = dot(a, cross(b, c)).abs();
    let den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    2.0 * num.atan2(den)
}

/// Solid angle (sr) of the planar rectangle `centre ± half_u ± half_v` seen from `eye`.
pub fn rectangle_solid_angle_sr(
    eye: [f64; 3],
    centre: [f64; 3],
    half_u: [f64; 3],
    half_v: [f64; 3],
) -> f64 {
    let c = sub(centre, eye);
    let corner = |su: f64, sv: f64| [0, 1, 2].map(|k| c[k] + su * half_u[k] + sv * half_v[k]);
    let (p0, p1, p2, p3) = (
        corner(-1.0, -1.0),
        corner(1.0, -1.0),
        corner(1.0, 1.0),
        corner(-1.0, 1.0),
    );
    triangle_solid_angle_sr(p0, p1, p2) + triangle_solid_angle_sr(p0, p2, p3)
}

/// One glare source's terms in the UGR sum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlareTerm {
    /// Luminance towards the eye, cd/m².
    pub luminance: f64,
    /// Solid angle of the (visible) luminous area, sr.
    pub solid_angle_sr: f64,
    /// Position index p ≥ 1.
    pub position_index: f64,
}

impl GlareTerm {
    /// L² ω / p².
    pub fn weight(&self) -> f64 {
        (self.luminance / self.position_index).powi(2) * self.solid_angle_sr
    }
}

/// A unified glare rating with its standard error.
#[derive(Clone, Debug, PartialEq)]
pub struct Ugr {
    /// UGR (0 when no source is in view, see [`Ugr::note`]).
    pub value: f64,
    /// Its standard error from the background luminance's.
    pub standard_error: f64,
    /// Σ L² ω / p² (cd²/m⁴·sr).
    pub sum: f64,
    /// Set when the formula is out of its range: no source in view (Σ = 0).
    pub note: Option<String>,
}

/// UGR from the background luminance `lb` (cd/m², > 0) with its standard error `lb_se` and the
/// sources' terms; `Err` when `lb` is not finite and positive.
pub fn ugr(lb: f64, lb_se: f64, terms: &[GlareTerm]) -> Result<Ugr, String> {
    if !(lb.is_finite() && lb > 0.0) {
        return Err(format!(
            "background luminance {lb} cd/m² is not positive: UGR is undefined (the room \
             reflects no light to the eye)"
        ));
    }
    let sum: f64 = terms.iter().map(GlareTerm::weight).sum();
    if !sum.is_finite() {
        return Err("a glare source's luminance or solid angle is not finite".into());
    }
    let standard_error = 8.0 / LN_10 * lb_se.max(0.0) / lb;
    if sum <= 0.0 {
        return Ok(Ugr {
            value: 0.0,
            standard_error: 0.0,
            sum,
            note: Some(
                "no glare source in the field of view (UGR formula undefined; reported as 0)"
                    .into(),
            ),
        });
    }
    Ok(Ugr {
        value: 8.0 * (0.25 / lb * sum).log10(),
        standard_error,
        sum,
        note: None,
    })
}

/// A luminaire as a glare source: its photometry, luminous opening, frame, multiplier and the
/// centre of its opening (m), in any world frame (the eye, view and up given in the same).
#[derive(Clone, Copy, Debug)]
pub struct GlareLuminaire<'a> {
    pub photometry: &'a Photometry,
    pub opening: LuminousOpening,
    pub frame: &'a Frame,
    pub multiplier: f64,
    pub centre: [f64; 3],
}

/// How [`GlareLuminaire::term`] sizes the solid angle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolidAngle {
    /// A flat opening (rectangle, disk, ellipse) divided into cells no larger than a tenth of
    /// the distance to the eye (at most 32 per side), each with its own luminance I(ω_i)/A_p,
    /// solid angle and position index, so that a large luminaire close to the eye counts as
    /// the sum of its parts (other shapes: the centre, A_p / D²). The returned term carries the
    /// summed ω, the ω-weighted mean luminance and the position index that makes L² ω / p²
    /// equal the sum.
    Exact,
    /// The far-field centre term: A_p / D², the luminance and position index towards the
    /// centre (the CIE 117 / CIE 190 tabular method).
    FarField,
}

impl GlareLuminaire<'_> {
    /// The source's UGR terms seen from `eye` looking along `view` (`up`: the observer's up),
    /// with `visible` the fraction of its opening not hidden (1: all of it); `None` when it is
    /// outside the field of view, dark towards the eye or seen edge-on. `Err` when the opening
    /// has no area (a point or a shape not modelled): UGR needs the luminous area.
    pub fn term(
        &self,
        eye: [f64; 3],
        view: [f64; 3],
        up: [f64; 3],
        visible: f64,
        solid_angle: SolidAngle,
    ) -> Result<Option<GlareTerm>, String> {
        let to_source = sub(self.centre, eye);
        let d2 = dot(to_source, to_source);
        if d2.is_nan() || d2 <= 0.0 || visible <= 0.0 {
            return Ok(None);
        }
        let toward_eye = self.frame.to_local(to_source.map(|x| -x / d2.sqrt()));
        let Some(area) = self.opening.projected_area_m2(toward_eye) else {
            return Err(format!(
                "{}: the file gives no luminous area ({:?} opening), which UGR needs: give the \
                 luminaire an opening: Area(length: .., width: ..)",
                self.photometry.name, self.opening.shape
            ));
        };
        let flat = matches!(
            self.opening.shape,
            OpeningShape::Rectangular | OpeningShape::Circular | OpeningShape::Elliptical
        );
        let visible = visible.min(1.0);
        if solid_angle == SolidAngle::Exact && flat {
            // Cell by cell: part of a luminaire beside the eye may be in view when its centre
            // is not.
            return Ok(self.subdivided(eye, view, up, d2.sqrt()).map(|mut t| {
                t.solid_angle_sr *= visible;
                t
            }));
        }
        let Some(p) = position_index(view, up, to_source) else {
            return Ok(None);
        };
        let intensity = self.multiplier * self.photometry.intensity_dir_cd(toward_eye);
        if area <= 1e-9 * self.opening.length_m.max(self.opening.width_m).powi(2)
            || intensity <= 0.0
        {
            return Ok(None);
        }
        Ok(Some(GlareTerm {
            luminance: intensity / area,
            solid_angle_sr: area / d2 * visible,
            position_index: p,
        }))
    }

    /// The sum over the cells of a flat opening (see [`SolidAngle::Exact`]); `None` when no
    /// cell is in view and lit towards the eye.
    fn subdivided(
        &self,
        eye: [f64; 3],
        view: [f64; 3],
        up: [f64; 3],
        dist: f64,
    ) -> Option<GlareTerm> {
        let o = &self.opening;
        let cells = |side: f64| ((side / (0.1 * dist)).ceil() as usize).clamp(1, 32);
        let (nl, nw) = (cells(o.length_m), cells(o.width_m));
        let round = o.shape != OpeningShape::Rectangular;
        let mut inside = Vec::with_capacity(nl * nw);
        for i in 0..nl {
            for j in 0..nw {
                let (s, t) = (
                    (i as f64 + 0.5) / nl as f64 - 0.5,
                    (j as f64 + 0.5) / nw as f64 - 0.5,
                );
                if !round || s * s + t * t <= 0.25 {
                    inside.push([s * o.length_m, t * o.width_m, 0.0]);
                }
            }
        }
        if inside.is_empty() {
            inside.push([0.0; 3]);
        }
        let full = o.flat_area_m2()?;
        let cell_area = full / inside.len() as f64;
        let (mut sum, mut omega, mut l_omega) = (0.0, 0.0, 0.0);
        for local in inside {
            let w = self.frame.to_world(local);
            let c = [0, 1, 2].map(|k| self.centre[k] + w[k]);
            let to_cell = sub(c, eye);
            let d2 = dot(to_cell, to_cell);
            let Some(p) = position_index(view, up, to_cell) else {
                continue;
            };
            let toward_eye = self.frame.to_local(to_cell.map(|x| -x / d2.sqrt()));
            let cos = toward_eye[2].abs();
            let intensity = self.multiplier * self.photometry.intensity_dir_cd(toward_eye);
            if cos <= 0.0 || intensity <= 0.0 {
                continue;
            }
            let l = intensity / (full * cos);
            let om = cell_area * cos / d2;
            sum += (l / p).powi(2) * om;
            omega += om;
            l_omega += l * om;
        }
        (sum > 0.0).then(|| {
            let luminance = l_omega / omega;
            GlareTerm {
                luminance,
                solid_angle_sr: omega,
                position_index: (luminance * luminance * omega / sum).sqrt(),
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Luckiesh–Guth position index table (CIE 117-1995, IES Lighting Handbook), entries at
    /// (T/R, H/R) with its p: Guth's formula is a fit to it within a few per cent.
    #[test]
    fn guth_formula_reproduces_the_luckiesh_guth_table() {
        // (T/R, H/R, p): the T/R = 0 column and the H/R = 0 row of the table.
        let table = [
            (0.0, 0.0, 1.00),
            (0.0, 0.3, 1.90),
            (0.0, 0.5, 2.86),
            (0.0, 0.8, 5.00),
            (0.0, 1.0, 7.00),
            (0.0, 1.5, 13.15),
            (0.5, 0.0, 1.43),
            (1.0, 0.0, 2.11),
        ];
        for (t, h, p_table) in table {
            // Line of sight +x, up +z; the source R = 1 ahead, T to the side, H above.
            let p = position_index([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, t, h]).unwrap();
            let rel = (p / p_table - 1.0).abs();
            assert!(
                rel < 0.045,
                "T/R {t} H/R {h}: p {p:.3} vs table {p_table} ({rel:.3})"
            );
        }
    }

    #[test]
    fn position_index_geometry() {
        let (v, up) = ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
        // On the line of sight p = 1; behind the eye no index.
        assert!((position_index(v, up, [0.0, 3.0, 0.0]).unwrap() - 1.0).abs() < 1e-12);
        assert!(position_index(v, up, [0.0, -1.0, 0.5]).is_none());
        assert!(position_index(v, up, [1.0, 0.0, 0.0]).is_none()); // σ = 90°
                                                                   // Straight above at 45°: τ = 0, σ = 45°.
        let (tau, sigma, above) = glare_angles(v, up, [0.0, 1.0, 1.0]).unwrap();
        assert!(tau.abs() < 1e-9 && (sigma - 45.0).abs() < 1e-9 && above);
        let p45 = (0.03398 * 45.0 + 21e-5 * 2025.0f64).exp();
        assert!((position_index(v, up, [0.0, 1.0, 1.0]).unwrap() - p45).abs() < 1e-9);
        // Symmetric left/right; below the line of sight Iwata's index, at least Guth's level one.
        let l = position_index(v, up, [-0.7, 1.0, 0.4]).unwrap();
        let r = position_index(v, up, [0.7, 1.0, 0.4]).unwrap();
        assert!((l - r).abs() < 1e-12);
        let below = position_index(v, up, [0.0, 1.0, -0.5]).unwrap();
        let c = 0.5f64.atan().tan() * 1.3225f64.sqrt();
        let beta = c.atan().to_degrees();
        assert!((below - (6.49e-3 * beta + 21e-5 * beta * beta).exp()).abs() < 1e-12);
        // Capped near 90°.
        assert_eq!(position_index(v, up, [0.0, 0.01, 1.0]).unwrap(), 16.0);
    }

    #[test]
    fn rectangle_solid_angle_matches_closed_form() {
        // A 2a × 2b rectangle at distance d on its axis: Ω = 4 asin(ab / √((a²+d²)(b²+d²))).
        let (a, b, d): (f64, f64, f64) = (0.3, 0.6, 1.7);
        let exact = 4.0 * (a * b / ((a * a + d * d) * (b * b + d * d)).sqrt()).asin();
        let o = rectangle_solid_angle_sr([0.0; 3], [0.0, 0.0, d], [a, 0.0, 0.0], [0.0, b, 0.0]);
        assert!((o - exact).abs() < 1e-12, "{o} {exact}");
        // Far away it tends to A cosθ / D².
        let far = rectangle_solid_angle_sr(
            [0.0; 3],
            [0.0, 300.0, 400.0],
            [0.1, 0.0, 0.0],
            [0.0, 0.1, 0.0],
        );
        let approx = 0.04 * 0.8 / 250_000.0;
        assert!((far / approx - 1.0).abs() < 1e-4);
    }

    #[test]
    fn ugr_formula_and_its_error() {
        // One source L = 10 000 cd/m², ω = 0.01 sr, p = 2, L_b = 40 cd/m²:
        // 0.25/40 · 1e8 · 0.01 / 4 = 1562.5 → UGR = 8 log10 1562.5 = 25.5535.
        let t = GlareTerm {
            luminance: 1e4,
            solid_angle_sr: 0.01,
            position_index: 2.0,
        };
        let u = ugr(40.0, 0.4, &[t]).unwrap();
        assert!((u.value - 8.0 * 1562.5f64.log10()).abs() < 1e-12);
        // First-order error: 8/ln10 · 1 % = 0.03474; check it against a finite difference.
        let up = ugr(40.4, 0.0, &[t]).unwrap().value;
        assert!(
            ((u.value - up) - u.standard_error).abs() < 2e-4,
            "{}",
            u.standard_error
        );
        // Doubling L_b lowers UGR by 8 log10 2.
        let half = ugr(80.0, 0.0, &[t]).unwrap().value;
        assert!((u.value - half - 8.0 * 2f64.log10()).abs() < 1e-12);
        // No source: 0 with a note; no background: an error, never NaN.
        let none = ugr(40.0, 0.4, &[]).unwrap();
        assert_eq!(none.value, 0.0);
        assert!(none.note.is_some());
        assert!(ugr(0.0, 0.0, &[t]).is_err());
        assert!(ugr(f64::NAN, 0.0, &[t]).is_err());
    }

    /// A uniform-luminance opening close to the eye, cell by cell: luminance I0/A everywhere,
    /// the summed solid angle the exact one of the rectangle, and a large luminaire straddling
    /// the plane beside the eye counted by its half in view.
    #[test]
    fn a_close_lambertian_panel_is_summed_cell_by_cell() {
        // I = I0 cos γ (γ < 90°) in every C plane: L = I0 / A from every direction.
        let g: Vec<f64> = (0..=36).map(|k| k as f64 * 5.0).collect();
        let row: Vec<f64> = g
            .iter()
            .map(|&x| {
                if x < 90.0 {
                    1000.0 * x.to_radians().cos()
                } else {
                    0.0
                }
            })
            .collect();
        let c = [0.0, 90.0, 180.0, 270.0];
        let p = Photometry::from_table("lambert", &c, &g, &vec![row; 4]).unwrap();
        let opening = LuminousOpening::from_ies(0.6, 1.2, 0.0);
        let frame = Frame::default();
        let lum = GlareLuminaire {
            photometry: &p,
            opening,
            frame: &frame,
            multiplier: 1.0,
            centre: [0.0, 1.0, 0.8],
        };
        let (eye, view, up) = ([0.0; 3], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
        let t = lum
            .term(eye, view, up, 1.0, SolidAngle::Exact)
            .unwrap()
            .unwrap();
        // The bilinear cos γ between 5° samples is within 0.4 % of cos γ.
        assert!(
            (t.luminance / (1000.0 / 0.72) - 1.0).abs() < 4e-3,
            "{}",
            t.luminance
        );
        let exact = rectangle_solid_angle_sr(eye, lum.centre, [0.6, 0.0, 0.0], [0.0, 0.3, 0.0]);
        assert!(
            (t.solid_angle_sr / exact - 1.0).abs() < 5e-3,
            "{} {exact}",
            t.solid_angle_sr
        );
        assert!(t.position_index > 1.0 && t.position_index < MAX_POSITION_INDEX);
        // Centred beside the eye (σ = 90° at the centre): the far-field term has none, the
        // cells in front count.
        let beside = GlareLuminaire {
            centre: [0.0, 0.0, 0.8],
            ..lum
        };
        assert!(beside
            .term(eye, view, up, 1.0, SolidAngle::FarField)
            .unwrap()
            .is_none());
        let half = beside
            .term(eye, view, up, 1.0, SolidAngle::Exact)
            .unwrap()
            .unwrap();
        let front =
            rectangle_solid_angle_sr(eye, [0.0, 0.15, 0.8], [0.6, 0.0, 0.0], [0.0, 0.15, 0.0]);
        assert!(
            (half.solid_angle_sr / front - 1.0).abs() < 0.02,
            "{} {front}",
            half.solid_angle_sr
        );
    }
}
