//! Spot lights: a point source whose intensity falls off linearly in angle, as Mitsuba 3's
//! `spot` (`src/emitters/spot.cpp`).
//!
//! With θ the angle between the direction of emission and the cone's axis, c the cutoff and b
//! the beam width (radians), the intensity is I(θ) = I₀ · falloff(θ) with falloff 1 for θ ≤ b,
//! (c − θ)/(c − b) for b < θ < c and 0 beyond (at θ = c exactly: 0, as Mitsuba's strict
//! `cos θ > cos c`). The flux is the exact integral
//!
//! ```text
//! Φ = 2π I₀ ∫₀^c falloff(θ) sin θ dθ = 2π I₀ (1 − (sin c − sin b) / (c − b))
//! ```
//!
//! (by parts: ∫_b^c (c − θ) sin θ dθ = (c − b) cos b − (sin c − sin b)), and 2π I₀ (1 − cos c)
//! when b = c. Light paths leave in a direction uniform over the cone (Mitsuba's `sample_ray`),
//! weighted by the falloff.

use luxest_io::math::Vec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A spot light's cone in world space.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpotCone {
    /// Unit axis of the cone.
    pub direction: Vec3,
    /// Half-angle beyond which nothing is emitted, degrees in (0, 180].
    pub cutoff_deg: f64,
    /// Half-angle of the full-intensity core, degrees in [0, cutoff].
    pub beam_width_deg: f64,
}

impl SpotCone {
    /// Whether the angles and axis are usable: a one-line reason otherwise.
    pub fn check(&self) -> Result<(), String> {
        let (c, b) = (self.cutoff_deg, self.beam_width_deg);
        if !(c.is_finite() && c > 0.0 && c <= 180.0) {
            return Err(format!("spot cutoff_deg {c} is not in (0, 180]"));
        }
        if !(b.is_finite() && (0.0..=c).contains(&b)) {
            return Err(format!(
                "spot beam_width_deg {b} is not in [0, cutoff_deg = {c}]"
            ));
        }
        let unit = (self.direction.length() - 1.0).abs() < 1e-9;
        if !unit {
            return Err("spot direction is not a unit vector".into());
        }
        Ok(())
    }

    /// The falloff towards `toward` (any length; zero vector: 0), in [0, 1].
    #[inline]
    pub fn falloff(&self, toward: Vec3) -> f64 {
        let len = toward.length();
        if len <= 0.0 {
            return 0.0;
        }
        let cos = (self.direction.dot(toward) / len).clamp(-1.0, 1.0);
        let c = self.cutoff_deg.to_radians();
        let b = self.beam_width_deg.to_radians();
        if cos <= c.cos() {
            0.0
        } else if cos >= b.cos() {
            1.0
        } else {
            ((c - cos.acos()) / (c - b)).clamp(0.0, 1.0)
        }
    }

    /// Φ / I₀: the cone's flux per unit on-axis intensity, sr (see the module docs).
    pub fn solid_angle_factor(&self) -> f64 {
        let c = self.cutoff_deg.to_radians();
        let b = self.beam_width_deg.to_radians();
        if c - b <= 1e-12 {
            2.0 * PI * (1.0 - c.cos())
        } else {
            2.0 * PI * (1.0 - (c.sin() - b.sin()) / (c - b))
        }
    }

    /// The cone's solid angle 2π (1 − cos c), sr: the inverse density of [`Self::sample`].
    pub fn cone_solid_angle(&self) -> f64 {
        2.0 * PI * (1.0 - self.cutoff_deg.to_radians().cos())
    }

    /// A direction uniformly distributed over the cone (density 1 / [`Self::cone_solid_angle`]).
    pub fn sample(&self, u1: f64, u2: f64) -> Vec3 {
        let cos_c = self.cutoff_deg.to_radians().cos();
        let z = 1.0 - u1 * (1.0 - cos_c);
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * u2;
        let (t, b) = self.direction.orthonormal_basis();
        t * (r * phi.cos()) + b * (r * phi.sin()) + self.direction * z
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use luxest_io::chi2::{ChiSquareTest, Sphere};

    fn cone() -> SpotCone {
        SpotCone {
            direction: Vec3::new(0.0, 0.0, 1.0),
            cutoff_deg: 40.0,
            beam_width_deg: 25.0,
        }
    }

    #[test]
    fn falloff_is_mitsubas_linear_ramp() {
        let s = cone();
        let at = |deg: f64| {
            let t = deg.to_radians();
            s.falloff(Vec3::new(t.sin(), 0.0, t.cos()) * 3.0)
        };
        assert_eq!(at(0.0), 1.0);
        assert_eq!(at(24.9), 1.0);
        assert!((at(30.0) - 10.0 / 15.0).abs() < 1e-12, "{}", at(30.0));
        assert!((at(37.0) - 3.0 / 15.0).abs() < 1e-12);
        assert_eq!(at(40.1), 0.0);
        assert_eq!(at(120.0), 0.0);
    }

    #[test]
    fn flux_factor_is_the_integral_of_the_falloff() {
        // Midpoint rule over θ with 200 000 steps against the closed form.
        for s in [
            cone(),
            SpotCone {
                beam_width_deg: 40.0,
                ..cone()
            },
            SpotCone {
                beam_width_deg: 0.0,
                cutoff_deg: 150.0,
                ..cone()
            },
        ] {
            let n = 200_000;
            let c = s.cutoff_deg.to_radians();
            let h = c / n as f64;
            let sum: f64 = (0..n)
                .map(|k| {
                    let t = (k as f64 + 0.5) * h;
                    s.falloff(Vec3::new(t.sin(), 0.0, t.cos())) * t.sin() * h
                })
                .sum();
            let numeric = 2.0 * PI * sum;
            assert!(
                (numeric - s.solid_angle_factor()).abs() < 1e-8,
                "{numeric} vs {}",
                s.solid_angle_factor()
            );
        }
    }

    #[test]
    fn emission_sampling_follows_the_uniform_cone() {
        let s = SpotCone {
            direction: Vec3::new(0.3, -0.5, 0.8).try_normalize().unwrap(),
            ..cone()
        };
        let mut r = Rng::new(11, 0);
        let (t, b) = s.direction.orthonormal_basis();
        let omega = s.cone_solid_angle();
        let cos_c = s.cutoff_deg.to_radians().cos();
        // The test's sphere is about +z: express samples in the cone's frame; bins in cos θ
        // with an edge at the cutoff integrate the pdf's step exactly.
        let mut cos_edges = vec![-1.0];
        cos_edges.extend((0..=16).map(|k| cos_c + (1.0 - cos_c) * k as f64 / 16.0));
        let phi_edges = (0..=32).map(|k| 2.0 * PI * k as f64 / 32.0).collect();
        ChiSquareTest::new(Sphere)
            .edges(cos_edges, phi_edges)
            .run(
                || {
                    let w = s.sample(r.next_f64(), r.next_f64());
                    Some(Vec3::new(w.dot(t), w.dot(b), w.dot(s.direction)))
                },
                |w| if w.z > cos_c { 1.0 / omega } else { 0.0 },
            )
            .unwrap();
    }

    #[test]
    fn emission_weights_average_to_the_flux() {
        // E[falloff(ω) / pdf(ω)] = Φ / I₀, within 4 standard errors.
        let s = cone();
        let mut r = Rng::new(5, 1);
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..n {
            let w = s.sample(r.next_f64(), r.next_f64());
            let x = s.falloff(w) * s.cone_solid_angle();
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
        assert!(
            (mean - s.solid_angle_factor()).abs() < 4.0 * se,
            "{mean} ± {se} vs {}",
            s.solid_angle_factor()
        );
    }
}
