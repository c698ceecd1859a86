//! The C-γ coordinate system of photometry and the placement of a luminaire in the world.
//!
//! **Convention** (CIE 121 / EN 13032-1 type C, as IES LM-63 type C and EULUMDAT use it): in the
//! luminaire's local frame, γ = 0° points straight down along −z (nadir), γ = 180° up along +z;
//! the half-plane C = 0° contains +x, C = 90° contains +y, C increasing counter-clockwise seen
//! from above (from +z). The unit direction of (C, γ) is
//!
//! ```text
//! d(C, γ) = (sin γ cos C, sin γ sin C, −cos γ)
//! ```
//!
//! and back: γ = acos(−d_z), C = atan2(d_y, d_x) mod 360°.
//!
//! **Orientation.** A luminaire's local frame is placed in the world by the rotation
//! `M = R_aim · R_x(tilt) · R_z(rotation)`, applied to local directions (world = M · local):
//! first a rotation by `rotation_deg` about the local vertical axis (turns the C = 0 plane),
//! then a tilt by `tilt_deg` about the local x axis (positive tilt swings the nadir towards +y,
//! the C = 90° side), then the smallest rotation taking the nadir (0, 0, −1) to `aim` (a rotation
//! by 180° about x when `aim` is straight up). With the defaults (aim = nadir, no tilt, no
//! rotation) the local frame is the world frame, with world +z up.

use crate::photometry::Photometry;
use std::sync::Arc;

/// Unit direction in the luminaire frame for angles (C, γ) in degrees.
pub fn direction_from_c_gamma(c_deg: f64, gamma_deg: f64) -> [f64; 3] {
    let (c, g) = (c_deg.to_radians(), gamma_deg.to_radians());
    [g.sin() * c.cos(), g.sin() * c.sin(), -g.cos()]
}

/// Angles (C, γ) in degrees, C in [0, 360), γ in [0, 180], of a direction in the luminaire frame
/// (need not be normalised; the zero vector gives (0, 0)).
pub fn c_gamma_from_direction(d: [f64; 3]) -> (f64, f64) {
    let len = norm(d);
    if len == 0.0 || !len.is_finite() {
        return (0.0, 0.0);
    }
    let gamma = (-d[2] / len).clamp(-1.0, 1.0).acos().to_degrees();
    let mut c = d[1].atan2(d[0]).to_degrees();
    if c < 0.0 {
        c += 360.0;
    }
    if c >= 360.0 {
        c -= 360.0;
    }
    (c, gamma)
}

/// Aim, tilt and rotation of a luminaire (see the module docs for the order of the rotations).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orientation {
    /// World direction the luminaire's nadir (γ = 0) points to; default (0, 0, −1).
    pub aim: [f64; 3],
    /// Tilt about the luminaire's local x axis, degrees.
    pub tilt_deg: f64,
    /// Rotation about the luminaire's vertical axis (turns the C planes), degrees.
    pub rotation_deg: f64,
}

impl Default for Orientation {
    fn default() -> Self {
        Orientation {
            aim: [0.0, 0.0, -1.0],
            tilt_deg: 0.0,
            rotation_deg: 0.0,
        }
    }
}

impl Orientation {
    /// The local-to-world rotation; an error when `aim` is zero or not finite.
    pub fn frame(&self) -> Result<Frame, String> {
        let len = norm(self.aim);
        if !(len > 0.0
            && len.is_finite()
            && self.tilt_deg.is_finite()
            && self.rotation_deg.is_finite())
        {
            return Err(format!(
                "luminaire orientation: aim must be a non-zero finite vector and angles finite (aim {:?}, tilt {}, rotation {})",
                self.aim, self.tilt_deg, self.rotation_deg
            ));
        }
        let a = scale(self.aim, 1.0 / len);
        let rz = rot_z(self.rotation_deg.to_radians());
        let rx = rot_x(self.tilt_deg.to_radians());
        let ra = rotation_taking_nadir_to(a);
        Ok(Frame {
            m: matmul(ra, matmul(rx, rz)),
        })
    }
}

/// A rotation from the luminaire frame to the world: `m` is row-major, world = m · local.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub m: [[f64; 3]; 3],
}

impl Default for Frame {
    fn default() -> Self {
        Frame {
            m: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        }
    }
}

impl Frame {
    /// A local (luminaire) vector in world coordinates.
    pub fn to_world(&self, v: [f64; 3]) -> [f64; 3] {
        let m = &self.m;
        [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
    }
    /// A world vector in local (luminaire) coordinates (the transpose, as `m` is orthonormal).
    pub fn to_local(&self, v: [f64; 3]) -> [f64; 3] {
        let m = &self.m;
        [
            m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
            m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
            m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2],
        ]
    }
}

/// A luminaire placed in a scene: its photometry (shared between identical luminaires), the
/// position of its photometric centre (m), its frame, and a multiplier (maintenance factor ×
/// any dimming) applied to every intensity.
#[derive(Debug, Clone)]
pub struct Luminaire {
    pub photometry: Arc<Photometry>,
    pub position: [f64; 3],
    pub frame: Frame,
    pub multiplier: f64,
}

impl Luminaire {
    /// Intensity (cd) towards a world direction (need not be normalised).
    pub fn intensity_toward_cd(&self, world_dir: [f64; 3]) -> f64 {
        self.multiplier
            * self
                .photometry
                .intensity_dir_cd(self.frame.to_local(world_dir))
    }
    /// The luminaire's emitted flux (lm): the multiplier times the integral of its table.
    pub fn flux_lm(&self) -> f64 {
        self.multiplier * self.photometry.flux_from_table_lm()
    }
    /// Direct illuminance (lx) at `point` on a surface with unit `normal`, no visibility.
    pub fn direct_illuminance_lx(&self, point: [f64; 3], normal: [f64; 3]) -> f64 {
        self.multiplier
            * crate::illuminance::direct_illuminance_lx(
                &self.photometry,
                &self.frame,
                self.position,
                point,
                normal,
            )
    }
}

pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
pub(crate) fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}
pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

type M3 = [[f64; 3]; 3];

fn matmul(a: M3, b: M3) -> M3 {
    let mut r = [[0.0; 3]; 3];
    for (i, row) in r.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    r
}

fn rot_z(t: f64) -> M3 {
    let (s, c) = t.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

fn rot_x(t: f64) -> M3 {
    let (s, c) = t.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

/// The smallest rotation taking (0, 0, −1) to the unit vector `a` (Rodrigues' formula).
fn rotation_taking_nadir_to(a: [f64; 3]) -> M3 {
    let n = [0.0, 0.0, -1.0];
    let c = dot(n, a);
    if c > 1.0 - 1e-15 {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    if c < -1.0 + 1e-15 {
        // Straight up: half a turn about x.
        return rot_x(std::f64::consts::PI);
    }
    let v = cross(n, a);
    // k = 1 / (1 + c). Near straight up 1 + c cancels (an aim 1e-7 off vertical lost 2 % of
    // it to rounding, and R was no rotation: RᵀR − I = 0.1, intensities off by 0.7 %); there
    // (1 + c)(1 − c) = |v|² gives it from v, exactly as consistent with v as R needs.
    let k = if c < 0.0 {
        (1.0 - c) / dot(v, v)
    } else {
        1.0 / (1.0 + c)
    };
    // R = I + [v]x + [v]x^2 / (1 + c)
    [
        [
            1.0 - k * (v[1] * v[1] + v[2] * v[2]),
            k * v[0] * v[1] - v[2],
            k * v[0] * v[2] + v[1],
        ],
        [
            k * v[0] * v[1] + v[2],
            1.0 - k * (v[0] * v[0] + v[2] * v[2]),
            k * v[1] * v[2] - v[0],
        ],
        [
            k * v[0] * v[2] - v[1],
            k * v[1] * v[2] + v[0],
            1.0 - k * (v[0] * v[0] + v[1] * v[1]),
        ],
    ]
}

#[cfg(test)]
mod tests {

    /// The rotation taking the nadir to an aim is a rotation (RᵀR = I) and takes the nadir to
    /// the aim, also for aims a hair off straight up, where 1 + cos cancels.
    #[test]
    fn nadir_rotation_stays_orthogonal_near_straight_up() {
        for a in [
            [1e-7, 0.0, 1.0],
            [0.0, 1e-7, 1.0],
            [3e-8, -2e-8, 1.0],
            [1e-6, 0.0, 1.0],
            [0.6, 0.0, -0.8],
            [0.0, 0.8, 0.6],
        ] {
            let l = dot(a, a).sqrt();
            let a = [a[0] / l, a[1] / l, a[2] / l];
            let r = rotation_taking_nadir_to(a);
            for i in 0..3 {
                for j in 0..3 {
                    let rtr: f64 = (0..3).map(|k| r[k][i] * r[k][j]).sum();
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((rtr - want).abs() < 1e-12, "{a:?}: RᵀR[{i}][{j}] = {rtr}");
                }
                let rn: f64 = (0..3).map(|k| r[i][k] * [0.0, 0.0, -1.0][k]).sum();
                // Aims within 4.5e-8 rad of vertical are taken as vertical (that branch).
                assert!((rn - a[i]).abs() < 1e-7, "{a:?}: (R n)[{i}] = {rn}");
            }
        }
    }

    use super::*;

    fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() <= tol)
    }

    #[test]
    fn c_gamma_round_trip_and_axes() {
        assert!(close(
            direction_from_c_gamma(0.0, 0.0),
            [0.0, 0.0, -1.0],
            1e-15
        ));
        assert!(close(
            direction_from_c_gamma(0.0, 90.0),
            [1.0, 0.0, 0.0],
            1e-15
        ));
        assert!(close(
            direction_from_c_gamma(90.0, 90.0),
            [0.0, 1.0, 0.0],
            1e-15
        ));
        assert!(close(
            direction_from_c_gamma(33.0, 180.0),
            [0.0, 0.0, 1.0],
            1e-15
        ));
        for c in [0.0, 10.0, 89.0, 181.0, 359.5] {
            for g in [1.0, 45.0, 90.0, 179.0] {
                let (c2, g2) = c_gamma_from_direction(direction_from_c_gamma(c, g));
                assert!(
                    (c2 - c).abs() < 1e-9 && (g2 - g).abs() < 1e-9,
                    "{c} {g} -> {c2} {g2}"
                );
            }
        }
    }

    #[test]
    fn orientation_aims_nadir_and_is_orthonormal() {
        for aim in [
            [1.0, 0.0, 0.0],
            [0.3, -0.4, 0.5],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -2.0],
        ] {
            for (tilt, rot) in [(0.0, 0.0), (20.0, 0.0), (0.0, 35.0), (-15.0, 120.0)] {
                let f = Orientation {
                    aim,
                    tilt_deg: tilt,
                    rotation_deg: rot,
                }
                .frame()
                .unwrap();
                let m = f.m;
                for i in 0..3 {
                    for j in 0..3 {
                        let d: f64 = (0..3).map(|k| m[i][k] * m[j][k]).sum();
                        assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
                    }
                }
                let v = [0.2, -0.7, 0.4];
                assert!(close(f.to_local(f.to_world(v)), v, 1e-12));
                if tilt == 0.0 {
                    let a = scale(aim, 1.0 / norm(aim));
                    assert!(close(f.to_world([0.0, 0.0, -1.0]), a, 1e-12));
                }
            }
        }
        // Positive tilt swings the nadir towards +y; rotation turns C = 0 from +x towards +y.
        let f = Orientation {
            tilt_deg: 30.0,
            ..Default::default()
        }
        .frame()
        .unwrap();
        let d = f.to_world([0.0, 0.0, -1.0]);
        assert!(close(d, [0.0, 0.5, -(0.75f64).sqrt()], 1e-12));
        let f = Orientation {
            rotation_deg: 90.0,
            ..Default::default()
        }
        .frame()
        .unwrap();
        assert!(close(f.to_world([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], 1e-12));
        assert!(Orientation {
            aim: [0.0; 3],
            ..Default::default()
        }
        .frame()
        .is_err());
    }
}
