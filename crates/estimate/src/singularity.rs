//! Control of the local-estimate kernel's singularity.
//!
//! The kernel `cos_j cos_p / d²` is unbounded when a collision lands close to the sensor point
//! (edges and corners, where another surface meets the sensor's). Its variance is then
//! infinite. Two remedies, both trading a bias of order eps for bounded variance:
//!
//! * `Ball` (Budak et al., 2023): closer than `30 eps`, the inverse square is replaced by its
//!   mean over a ball of radius eps around the sensor point,
//!   `⟨1/|x−y|²⟩ = 3/(4ε³) [ (ε² − d²)/d · ln((d + ε)/|d − ε|) + 2ε ]`
//!   (3/ε² at d = 0; it equals `1/d² (1 + (ε/d)²/5 + …)` far away, so switching at 30 ε changes
//!   the kernel by 2e-4 of itself).
//! * `Clamp`: `1 / max(d², ε²)`.
//! * `None`: the raw kernel (unbiased, unbounded variance at edges).

use std::fmt;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Singularity {
    None,
    Clamp { eps: f64 },
    Ball { eps: f64 },
}

/// Distance, in units of eps, beyond which the ball average is replaced by the plain 1/d².
pub const BALL_SWITCH: f64 = 30.0;

/// Mean of 1/|x − y|² over y uniform in a ball of radius `eps` whose centre is `d` from x.
pub fn ball_mean_inverse_square(d: f64, eps: f64) -> f64 {
    if d < 1e-9 * eps {
        return 3.0 / (eps * eps);
    }
    let diff = (d - eps).abs();
    let log_term = if diff == 0.0 {
        0.0 // (ε² − d²) ln(...) → 0 as d → ε
    } else {
        (eps * eps - d * d) / d * ((d + eps) / diff).ln()
    };
    3.0 / (4.0 * eps * eps * eps) * (log_term + 2.0 * eps)
}

impl Singularity {
    /// The (possibly regularised) inverse square distance for squared distance `d2`.
    pub fn inverse_square(&self, d2: f64) -> f64 {
        match *self {
            Singularity::None => 1.0 / d2,
            Singularity::Clamp { eps } => 1.0 / d2.max(eps * eps),
            Singularity::Ball { eps } => {
                if d2 >= (BALL_SWITCH * eps) * (BALL_SWITCH * eps) {
                    1.0 / d2
                } else {
                    ball_mean_inverse_square(d2.sqrt(), eps)
                }
            }
        }
    }
}

impl fmt::Display for Singularity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Singularity::None => write!(f, "none"),
            Singularity::Clamp { eps } => write!(f, "clamp(eps={eps:e} m)"),
            Singularity::Ball { eps } => write!(f, "ball(eps={eps:e} m)"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent check: in spherical coordinates centred at x, ∫_ball dV / r² = ∫ dΩ L(Ω),
    /// L the length of the ray from x inside the ball; axisymmetric, so a 1-D integral over μ.
    fn ball_mean_by_chords(d: f64, eps: f64) -> f64 {
        let mut chord = |mu: f64| {
            // Ray x + t w, x = (d, 0, 0) relative to the centre, w·x̂ = μ: |x + t w|² = ε².
            let b = d * mu;
            let c = d * d - eps * eps;
            let disc = b * b - c;
            if disc <= 0.0 {
                return 0.0;
            }
            let (t0, t1) = (-b - disc.sqrt(), -b + disc.sqrt());
            (t1.max(0.0) - t0.max(0.0)).max(0.0)
        };
        // From outside, only the cone towards the centre (sin θ < ε/d) meets the ball.
        let upper = if d > eps {
            -(1.0 - (eps / d).powi(2)).sqrt()
        } else {
            1.0
        };
        let (v, _) = luxest_exact::quadrature::integrate(&mut chord, -1.0, upper, 1e-13);
        2.0 * std::f64::consts::PI * v / (4.0 / 3.0 * std::f64::consts::PI * eps.powi(3))
    }

    #[test]
    fn ball_mean_matches_chord_integration() {
        let eps = 0.1;
        for d in [0.0, 0.03, 0.099, 0.1, 0.101, 0.15, 0.5, 3.0] {
            let exact = ball_mean_by_chords(d, eps);
            let formula = ball_mean_inverse_square(d, eps);
            assert!(
                (formula / exact - 1.0).abs() < 1e-7,
                "d={d}: {formula} vs {exact}"
            );
        }
    }

    #[test]
    fn ball_mean_tends_to_inverse_square_far_away() {
        let eps = 1e-3;
        for ratio in [5.0, 30.0, 100.0] {
            let d = ratio * eps;
            let rel = ball_mean_inverse_square(d, eps) * d * d - 1.0;
            let predicted = 0.2 / (ratio * ratio);
            assert!(
                (rel - predicted).abs() < 0.05 * predicted,
                "d/eps={ratio}: {rel} vs {predicted}"
            );
        }
        // Continuity at the switch to 1/d² is within 2.3e-4.
        let s = Singularity::Ball { eps };
        let d = BALL_SWITCH * eps;
        let below = s.inverse_square((d * (1.0 - 1e-12)).powi(2));
        let above = s.inverse_square((d * (1.0 + 1e-12)).powi(2));
        assert!((below / above - 1.0).abs() < 2.3e-4);
    }

    #[test]
    fn clamp_bounds_the_kernel() {
        let s = Singularity::Clamp { eps: 0.01 };
        assert_eq!(s.inverse_square(0.0), 1e4);
        assert_eq!(s.inverse_square(4.0), 0.25);
    }
}
