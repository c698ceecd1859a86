//! The pinhole camera of the scene format: pixel coordinates to world-space rays.
//!
//! Pixel (0, 0) is the top-left; a point `(x + u, y + v)` with u, v in [0, 1) lies inside
//! pixel (x, y). The vertical field of view spans the image height.

use crate::scene::Camera;
use crate::sobol::PixelSampler;
use luxest_io::math::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct PinholeCamera {
    pub position: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_half: f64,
    pub width: u32,
    pub height: u32,
}

impl PinholeCamera {
    /// Builds the camera frame; `None` if look-at/up are degenerate (scene-compile rejects those).
    pub fn new(c: &Camera) -> Option<PinholeCamera> {
        let forward = (c.look_at - c.position).try_normalize()?;
        let right = forward.cross(c.up).try_normalize()?;
        let up = right.cross(forward);
        Some(PinholeCamera {
            position: c.position,
            forward,
            right,
            up,
            tan_half: (c.vfov_deg.to_radians() * 0.5).tan(),
            width: c.resolution.0,
            height: c.resolution.1,
        })
    }

    /// Unit direction of the ray through image point (sx, sy) in pixel units.
    pub fn direction(&self, sx: f64, sy: f64) -> Vec3 {
        let aspect = self.width as f64 / self.height as f64;
        let px = (2.0 * sx / self.width as f64 - 1.0) * self.tan_half * aspect;
        let py = (1.0 - 2.0 * sy / self.height as f64) * self.tan_half;
        (self.forward + self.right * px + self.up * py)
            .try_normalize()
            .expect("finite camera ray")
    }

    /// The angle one pixel subtends at the image centre, radians: a camera ray's footprint
    /// grows by this much per metre travelled (for texture filtering).
    pub fn pixel_spread(&self) -> f64 {
        2.0 * self.tan_half / self.height as f64
    }

    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// Where the ray from the camera towards `p` crosses the image: the image point (sx, sy)
    /// in pixel units (the inverse of [`PinholeCamera::direction`]) and cos θ between the ray
    /// and the forward axis; `None` behind the camera or outside the image.
    pub fn project(&self, p: Vec3) -> Option<(f64, f64, f64)> {
        let d = p - self.position;
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let aspect = self.width as f64 / self.height as f64;
        let px = d.dot(self.right) / z / (self.tan_half * aspect);
        let py = d.dot(self.up) / z / self.tan_half;
        let sx = (px + 1.0) * 0.5 * self.width as f64;
        let sy = (1.0 - py) * 0.5 * self.height as f64;
        let inside =
            (0.0..self.width as f64).contains(&sx) && (0.0..self.height as f64).contains(&sy);
        inside.then(|| (sx, sy, z / d.length()))
    }

    /// `1 / (d² A_p cos³ θ)` for the point `x`, with d = |x − c|, θ the angle between x − c and
    /// the axis, A_p = [`Self::pixel_area`]: the pinhole's importance times the geometry term,
    /// less the cosine at x (the image-plane area element is `cos_x dA / (d² cos³ θ)`). `None`
    /// behind the camera. Light tracing's camera connection and [`Self::area_density`] share it.
    pub fn footprint(&self, x: Vec3) -> Option<f64> {
        let v = x - self.position;
        let d2 = v.length_squared();
        let cos_theta = v.dot(self.forward) / d2.sqrt();
        (cos_theta > 0.0).then(|| 1.0 / (d2 * self.pixel_area() * cos_theta.powi(3)))
    }

    /// Density per unit area at the surface point `x` (unit geometric normal `ng`) of the point
    /// that a camera ray of x's pixel, uniform over the pixel, hits: `|cos_x|` times
    /// [`Self::footprint`]. Zero behind the camera.
    pub fn area_density(&self, x: Vec3, ng: Vec3) -> f64 {
        self.footprint(x).map_or(0.0, |g| {
            let v = x - self.position;
            (ng.dot(v) / v.length()).abs() * g
        })
    }

    /// The area of one pixel on the image plane at unit distance from the pinhole (the
    /// importance of a pinhole camera is 1 / (this area · cos⁴ θ)).
    pub fn pixel_area(&self) -> f64 {
        let aspect = self.width as f64 / self.height as f64;
        (2.0 * self.tan_half * aspect / self.width as f64)
            * (2.0 * self.tan_half / self.height as f64)
    }
}

/// The sub-pixel position (u, v) in [0, 1)² of sample `sample` of pixel `pixel`: the first
/// dimension of the path tracer's [`PixelSampler`] (an Owen-scrambled Sobol point, a function of
/// (seed, pixel, sample) only), so that the progressive stages (trace, aov-write) see through
/// the same positions, independently of order, threads and passes. The pixel filter is a box:
/// positions are uniform over the pixel, and the first 2^k samples of a pixel stratify it.
pub fn pixel_jitter(seed: u64, pixel: u64, sample: u64) -> (f64, f64) {
    PixelSampler::new(seed, pixel, sample as u32).pixel_position()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use luxest_io::chi2::{ChiSquareTest, Rectangle, Sphere};
    use std::f64::consts::TAU;

    #[test]
    fn project_inverts_direction() {
        let cam = PinholeCamera::new(&Camera {
            position: Vec3::new(0.3, 1.0, -2.0),
            look_at: Vec3::new(0.1, 0.2, 0.5),
            up: Vec3::new(0.0, 1.0, 0.0),
            vfov_deg: 50.0,
            resolution: (40, 30),
        })
        .unwrap();
        for (sx, sy) in [(0.5, 0.5), (39.9, 0.01), (20.0, 15.0), (3.25, 28.75)] {
            let d = cam.direction(sx, sy);
            let (x, y, cos) = cam.project(cam.position + d * 3.7).unwrap();
            assert!(
                (x - sx).abs() < 1e-9 && (y - sy).abs() < 1e-9,
                "{sx},{sy} -> {x},{y}"
            );
            assert!((cos - d.dot(cam.forward())).abs() < 1e-12);
        }
        assert!(cam.project(cam.position - cam.forward()).is_none());
        // The image plane at unit distance is 2 tan(fov/2) high.
        let h = 2.0 * (25f64).to_radians().tan();
        assert!((cam.pixel_area() - (h * 40.0 / 30.0 / 40.0) * (h / 30.0)).abs() < 1e-15);
    }

    #[test]
    fn centre_and_corners_follow_the_field_of_view() {
        let cam = PinholeCamera::new(&Camera {
            position: Vec3::ZERO,
            look_at: Vec3::new(0.0, 0.0, 1.0),
            up: Vec3::new(0.0, 1.0, 0.0),
            vfov_deg: 90.0,
            resolution: (200, 100),
        })
        .unwrap();
        let c = cam.direction(100.0, 50.0);
        assert!((c - Vec3::new(0.0, 0.0, 1.0)).length() < 1e-12);
        // Top edge centre: 45 degrees up.
        let t = cam.direction(100.0, 0.0);
        assert!((t.y - t.z).abs() < 1e-12 && t.y > 0.0);
        // Right-handed image: x grows to the right of the viewer looking along +z with y up,
        // which is -x in world space.
        let r = cam.direction(200.0, 50.0);
        assert!(r.x < 0.0 && (r.x.abs() / r.z - 2.0).abs() < 1e-12);
    }

    #[test]
    fn jitter_is_uniform_and_reproducible() {
        assert_eq!(pixel_jitter(1, 2, 3), pixel_jitter(1, 2, 3));
        assert_ne!(pixel_jitter(1, 2, 3), pixel_jitter(1, 2, 4));
        // Owen-scrambled Sobol points are more even than independent ones: the test cannot
        // reject them for that, only for a wrong density.
        let mut s = 0;
        ChiSquareTest::new(Rectangle::UNIT)
            .resolution(8, 8)
            .samples(64_000)
            .run(
                || {
                    s += 1;
                    let (u, v) = pixel_jitter(7, s % 97, s);
                    Some([u, v])
                },
                |_| 1.0,
            )
            .unwrap();
    }

    #[test]
    fn rays_through_uniform_image_points_have_the_pinhole_density() {
        // A point uniform over the image gives a ray direction of solid-angle density
        // 1 / (A cos³ θ), A the image's area on the plane at unit distance ([`pixel_area`] times
        // the pixel count; the plane's area element is dω / cos³ θ), and none outside the image.
        let cam = PinholeCamera::new(&Camera {
            position: Vec3::new(0.5, -1.0, 2.0),
            look_at: Vec3::new(0.5, -1.0, 3.0),
            up: Vec3::new(0.0, 1.0, 0.0),
            vfov_deg: 100.0,
            resolution: (40, 30),
        })
        .unwrap();
        let area = cam.pixel_area() * 40.0 * 30.0;
        // Bins on the image's cap (its corners are 63° off the axis, cos θ = 0.45), one below.
        let cos_theta = std::iter::once(-1.0).chain((0..=16).map(|k| 0.4 + 0.6 * k as f64 / 16.0));
        let phi = (0..=32).map(|k| TAU * k as f64 / 32.0);
        let mut r = Rng::new(8, 0);
        ChiSquareTest::new(Sphere)
            .edges(cos_theta.collect(), phi.collect())
            .integration(16)
            .run(
                || Some(cam.direction(40.0 * r.next_f64(), 30.0 * r.next_f64())),
                |w| match cam.project(cam.position + w) {
                    Some((_, _, cos)) => 1.0 / (area * cos.powi(3)),
                    None => 0.0,
                },
            )
            .unwrap();
    }
}
