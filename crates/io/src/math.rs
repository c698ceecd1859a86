//! Small linear algebra for scene assembly and estimators.
//!
//! Everything here is `f64`: geometry is *stored* as `f32` (that is what Embree traces), but
//! transforms, areas, kernels and accumulators are computed in double precision so that scenes
//! scaled to millimetres or kilometres keep their relative accuracy.

use serde::{Deserialize, Serialize};
use std::ops::{Add, AddAssign, Div, Index, Mul, Neg, Sub};

/// A 3-vector of `f64` (a point, a direction or a normal, by context).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(from = "[f64; 3]", into = "[f64; 3]")]
pub struct Vec3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

impl From<[f64; 3]> for Vec3 {
    fn from(a: [f64; 3]) -> Self {
        Vec3::new(a[0], a[1], a[2])
    }
}
impl From<Vec3> for [f64; 3] {
    fn from(v: Vec3) -> Self {
        [v.x, v.y, v.z]
    }
}
impl From<[f32; 3]> for Vec3 {
    fn from(a: [f32; 3]) -> Self {
        Vec3::new(a[0] as f64, a[1] as f64, a[2] as f64)
    }
}

impl Vec3 {
    pub const ZERO: Vec3 = Vec3 {
        x: 0.0,
        y: 0.0,
        z: 0.0,
    };

    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Vec3 { x, y, z }
    }
    pub fn splat(v: f64) -> Self {
        Vec3::new(v, v, v)
    }
    pub fn dot(self, o: Vec3) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    pub fn cross(self, o: Vec3) -> Vec3 {
        Vec3::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    pub fn length_squared(self) -> f64 {
        self.dot(self)
    }
    pub fn length(self) -> f64 {
        self.length_squared().sqrt()
    }
    /// The unit vector along `self`; `None` for a zero or non-finite vector.
    pub fn try_normalize(self) -> Option<Vec3> {
        let l = self.length();
        if l > 0.0 && l.is_finite() {
            Some(self / l)
        } else {
            None
        }
    }
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }
    pub fn min(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x.min(o.x), self.y.min(o.y), self.z.min(o.z))
    }
    pub fn max(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x.max(o.x), self.y.max(o.y), self.z.max(o.z))
    }
    pub fn max_abs_component(self) -> f64 {
        self.x.abs().max(self.y.abs()).max(self.z.abs())
    }
    pub fn to_f32(self) -> [f32; 3] {
        [self.x as f32, self.y as f32, self.z as f32]
    }
    /// An orthonormal basis `(t, b)` completing the unit normal `n` (Duff et al., JCGT 2017).
    pub fn orthonormal_basis(self) -> (Vec3, Vec3) {
        let n = self;
        let sign = 1f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let bt = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        (t, bt)
    }
}

impl Add for Vec3 {
    type Output = Vec3;
    fn add(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl AddAssign for Vec3 {
    fn add_assign(&mut self, o: Vec3) {
        *self = *self + o;
    }
}
impl Sub for Vec3 {
    type Output = Vec3;
    fn sub(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl Neg for Vec3 {
    type Output = Vec3;
    fn neg(self) -> Vec3 {
        Vec3::new(-self.x, -self.y, -self.z)
    }
}
impl Mul<f64> for Vec3 {
    type Output = Vec3;
    fn mul(self, s: f64) -> Vec3 {
        Vec3::new(self.x * s, self.y * s, self.z * s)
    }
}
impl Mul<Vec3> for f64 {
    type Output = Vec3;
    fn mul(self, v: Vec3) -> Vec3 {
        v * self
    }
}
impl Div<f64> for Vec3 {
    type Output = Vec3;
    fn div(self, s: f64) -> Vec3 {
        Vec3::new(self.x / s, self.y / s, self.z / s)
    }
}
impl Index<usize> for Vec3 {
    type Output = f64;
    fn index(&self, i: usize) -> &f64 {
        match i {
            0 => &self.x,
            1 => &self.y,
            2 => &self.z,
            _ => panic!("Vec3 index {i} out of range"),
        }
    }
}

/// An affine transform `p -> M p + t` with its inverse-transpose for normals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    /// Row-major 3x3 linear part.
    pub m: [[f64; 3]; 3],
    pub t: Vec3,
}

impl Default for Affine {
    fn default() -> Self {
        Affine::IDENTITY
    }
}

impl Affine {
    pub const IDENTITY: Affine = Affine {
        m: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        t: Vec3::ZERO,
    };

    pub fn scale(s: Vec3) -> Affine {
        Affine {
            m: [[s.x, 0.0, 0.0], [0.0, s.y, 0.0], [0.0, 0.0, s.z]],
            t: Vec3::ZERO,
        }
    }
    pub fn translate(t: Vec3) -> Affine {
        Affine {
            t,
            ..Affine::IDENTITY
        }
    }
    /// Rotation by `deg` degrees about the coordinate axis `axis` (0 = x, 1 = y, 2 = z), right-handed.
    pub fn rotate_axis(axis: usize, deg: f64) -> Affine {
        let (s, c) = deg.to_radians().sin_cos();
        let m = match axis {
            0 => [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
            1 => [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
            _ => [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
        };
        Affine { m, t: Vec3::ZERO }
    }
    /// Row-major 4x4 matrix (last row ignored, assumed `0 0 0 1`).
    pub fn from_rows4(r: [[f64; 4]; 4]) -> Affine {
        Affine {
            m: [
                [r[0][0], r[0][1], r[0][2]],
                [r[1][0], r[1][1], r[1][2]],
                [r[2][0], r[2][1], r[2][2]],
            ],
            t: Vec3::new(r[0][3], r[1][3], r[2][3]),
        }
    }
    /// Column-major 4x4 matrix as stored by glTF.
    pub fn from_cols4(c: [[f32; 4]; 4]) -> Affine {
        let mut r = [[0.0; 4]; 4];
        for (j, col) in c.iter().enumerate() {
            for (i, v) in col.iter().enumerate() {
                r[i][j] = *v as f64;
            }
        }
        Affine::from_rows4(r)
    }
    /// `self * o`: apply `o` first, then `self`.
    pub fn compose(&self, o: &Affine) -> Affine {
        let mut m = [[0.0; 3]; 3];
        for (i, row) in m.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = (0..3).map(|k| self.m[i][k] * o.m[k][j]).sum();
            }
        }
        Affine {
            m,
            t: self.apply_vector(o.t) + self.t,
        }
    }
    pub fn apply_point(&self, p: Vec3) -> Vec3 {
        self.apply_vector(p) + self.t
    }
    pub fn apply_vector(&self, v: Vec3) -> Vec3 {
        let m = &self.m;
        Vec3::new(
            m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
            m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z,
        )
    }
    pub fn determinant(&self) -> f64 {
        let m = &self.m;
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }
    /// Transforms a normal by the cofactor matrix (the inverse-transpose times the determinant),
    /// which is defined even for singular matrices; the caller normalises.
    pub fn apply_normal(&self, n: Vec3) -> Vec3 {
        let m = &self.m;
        let c0 = Vec3::new(m[0][0], m[1][0], m[2][0]);
        let c1 = Vec3::new(m[0][1], m[1][1], m[2][1]);
        let c2 = Vec3::new(m[0][2], m[1][2], m[2][2]);
        // Rows of the cofactor matrix are cross products of the columns.
        let r0 = c1.cross(c2);
        let r1 = c2.cross(c0);
        let r2 = c0.cross(c1);
        // The inverse has rows r0, r1, r2 (over det), so the inverse-transpose has them as columns.
        r0 * n.x + r1 * n.y + r2 * n.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-12
    }

    #[test]
    fn rotation_is_right_handed() {
        let r = Affine::rotate_axis(2, 90.0);
        assert!(close(
            r.apply_vector(Vec3::new(1.0, 0.0, 0.0)),
            Vec3::new(0.0, 1.0, 0.0)
        ));
        let r = Affine::rotate_axis(0, 90.0);
        assert!(close(
            r.apply_vector(Vec3::new(0.0, 1.0, 0.0)),
            Vec3::new(0.0, 0.0, 1.0)
        ));
        let r = Affine::rotate_axis(1, 90.0);
        assert!(close(
            r.apply_vector(Vec3::new(0.0, 0.0, 1.0)),
            Vec3::new(1.0, 0.0, 0.0)
        ));
    }

    #[test]
    fn normals_stay_perpendicular_under_nonuniform_scale() {
        let a = Affine::rotate_axis(1, 30.0).compose(&Affine::scale(Vec3::new(3.0, 0.5, 2.0)));
        // A plane spanned by u, v with normal u x v.
        let u = Vec3::new(1.0, 2.0, 0.5);
        let v = Vec3::new(-0.3, 0.1, 1.0);
        let n = u.cross(v);
        let nt = a.apply_normal(n);
        assert!(nt.dot(a.apply_vector(u)).abs() < 1e-9);
        assert!(nt.dot(a.apply_vector(v)).abs() < 1e-9);
        // Same orientation as the transformed tangent frame.
        assert!(nt.dot(a.apply_vector(u).cross(a.apply_vector(v))) > 0.0);
    }

    #[test]
    fn compose_applies_right_operand_first() {
        let t = Affine::translate(Vec3::new(1.0, 0.0, 0.0));
        let s = Affine::scale(Vec3::splat(2.0));
        let p = Vec3::new(1.0, 1.0, 1.0);
        assert!(close(
            t.compose(&s).apply_point(p),
            Vec3::new(3.0, 2.0, 2.0)
        ));
        assert!(close(
            s.compose(&t).apply_point(p),
            Vec3::new(4.0, 2.0, 2.0)
        ));
    }

    #[test]
    fn basis_is_orthonormal() {
        for n in [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(0.3, -0.8, 0.1),
        ] {
            let n = n.try_normalize().unwrap();
            let (t, b) = n.orthonormal_basis();
            assert!((t.length() - 1.0).abs() < 1e-12 && (b.length() - 1.0).abs() < 1e-12);
            assert!(t.dot(n).abs() < 1e-12 && b.dot(n).abs() < 1e-12 && t.dot(b).abs() < 1e-12);
            assert!(close(t.cross(b), n));
        }
    }
}
