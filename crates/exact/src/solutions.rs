//! Exact solutions of lighting problems, used to validate every estimator.
//!
//! * [`Sobolev`]: an isotropic point source between two infinite parallel Lambertian planes.
//! * [`integrating_sphere_illuminance`]: a point source inside a closed Lambertian sphere.
//! * [`cie171_mean_indirect_illuminance`]: CIE 171:2006 case 5.8, closed room.
//! * [`point_source_illuminance`]: CIE 171:2006 case 5.2, direct illuminance from point sources.
//!
//! ## The Sobolev problem
//!
//! Plane 1 lies a distance h1 below the source, plane 2 a distance h2 above it (H = h1 + h2),
//! with reflectances rho1, rho2. Writing illuminances through their Hankel transforms
//! `Ê(k) = ∫ E(r) J0(kr) r dr`, the direct term has `Ê = I e^{-k h}`, and the transfer of
//! Lambertian exitance from one plane to the other — the kernel `H² / (π (s² + H²)²)` — has
//! transform `κ(k) = kH K1(kH)` (with κ(0) = 1: all flux leaving one plane reaches the other).
//! The two balance equations `Ê1 = I e^{-k h1} + rho2 κ Ê2`, `Ê2 = I e^{-k h2} + rho1 κ Ê1` give
//!
//! ```text
//! E1(r) = I ∫0^∞ [e^{-k h1} + rho2 κ(k) e^{-k h2}] / [1 − rho1 rho2 κ(k)²] J0(k r) k dk
//! ```
//!
//! and E2 by symmetry. (The formula printed in the source thesis lacks the κ factor on the rho1
//! term; it fails the checks below.) Checks in the tests: rho → 0 gives the direct term; the
//! single-bounce term agrees with an independent real-space quadrature of the Lambertian
//! transfer; values agree with SciPy's `quad` + `j0`/`k1` to 1e-9. Flux balance
//! `∫E1 dA = 2π I (1 + rho2) / (1 − rho1 rho2)` is the k = 0 value of the bracket.
//!
//! Numerics: the direct term `I h1 / (r² + h1²)^{3/2}` is taken out analytically; the rest
//! decays like `e^{-kH}` and is integrated over [0, 50/H] in panels of half a period of
//! J0(kr), each by adaptive Gauss–Kronrod, to an error estimate of 1e-10 of the r = 0
//! value. The returned error bound lets callers check the relative error (≤ 1e-6 for all
//! validation points).

use crate::quadrature::integrate;
use luxest_io::num::Real;
use std::f64::consts::PI;

/// Bessel function of the first kind of order 0.
///
/// |x| < 25: trapezoidal rule on `J0(x) = (1/2π) ∫ cos(x sin θ) dθ` with 64 points (the error is
/// 2 J64(x) < 1e-18); larger |x|: Hankel's asymptotic expansion (A&S 9.2.5), summed to its
/// smallest term (< 1e-20 for |x| ≥ 25).
pub fn bessel_j0(x: f64) -> f64 {
    let x = x.abs();
    if x < 25.0 {
        // By symmetry of cos(x sin θ) the 64 points reduce to 15 interior ones per quarter:
        // θ = 0 and π count twice (cos 0 = 1), θ = π/2 and 3π/2 twice (cos x), the rest 4 times.
        const M: usize = 64;
        let mut s = 2.0 + 2.0 * x.cos();
        for j in 1..M / 4 {
            s += 4.0 * (x * (2.0 * PI * j as f64 / M as f64).sin()).cos();
        }
        return s / M as f64;
    }
    let chi = x - PI / 4.0;
    let (mut p, mut q) = (1.0, 0.0);
    let mut term = 1.0f64;
    for k in 1..200 {
        // term_k = prod_{j<=k} (mu - (2j-1)^2) / (k! (8x)^k), mu = 0.
        let next = term * (-((2 * k - 1) as f64).powi(2)) / (k as f64 * 8.0 * x);
        if next.abs() > term.abs() || next.abs() < 1e-22 {
            break;
        }
        term = next;
        let sign = if (k / 2) % 2 == 0 { 1.0 } else { -1.0 };
        if k % 2 == 0 {
            p += sign * term;
        } else {
            q += sign * term;
        }
    }
    (2.0 / (PI * x)).sqrt() * (p * chi.cos() - q * chi.sin())
}

/// Modified Bessel function of the second kind of order 1, for x > 0.
///
/// Trapezoidal rule on `K1(x) = ∫0^∞ e^{-x cosh t} cosh t dt`; the integrand is analytic in
/// the strip |Im t| < π/2, so the error falls like e^{-π²/h}: step h = 1/4 gives ~1e-17 for
/// x <= 1, and the step shrinks like 1/sqrt(x) for larger x, where the peak at t = 0 narrows.
pub fn bessel_k1(x: f64) -> f64 {
    bessel_k(1.0, x)
}

/// `x K1(x)`, the Hankel transform of the plane-to-plane Lambertian transfer; 1 at x = 0.
pub fn kappa(x: f64) -> f64 {
    if x <= 0.0 {
        1.0
    } else {
        x * bessel_k1(x)
    }
}

/// The Sobolev problem's parameters (SI/photometric units: cd, m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sobolev {
    pub intensity_cd: f64,
    /// Distance from the source down to plane 1, m.
    pub h1: f64,
    /// Distance from the source up to plane 2, m.
    pub h2: f64,
    pub rho1: f64,
    pub rho2: f64,
}

/// A positive intensity, cd.
pub const POSITIVE_CD: Real = Real::positive("cd");
/// A positive flux, lm.
pub const POSITIVE_LM: Real = Real::positive("lm");
/// A positive length, m.
pub const POSITIVE_M: Real = Real::positive("m");
/// A positive area, m².
pub const POSITIVE_M2: Real = Real::positive("m²");
/// A reflectance of an open configuration (light can leave): [0, 1].
pub const REFLECTANCE: Real = Real::closed(0.0, 1.0, "");
/// A reflectance of a closed room or sphere: [0, 1), since at 1 no light is ever absorbed and
/// the steady state is infinite.
pub const CLOSED_REFLECTANCE: Real = Real::closed_open(0.0, 1.0, "");

/// Checks the parameters of [`integrating_sphere_indirect`]: `rho` below 1 (closed sphere).
pub fn check_integrating_sphere(intensity_cd: f64, radius: f64, rho: f64) -> Result<(), String> {
    POSITIVE_CD.check_named("intensity", intensity_cd)?;
    POSITIVE_M.check_named("radius", radius)?;
    CLOSED_REFLECTANCE.check_named("rho", rho)?;
    Ok(())
}

/// Checks the parameters of [`cie171_mean_indirect_illuminance`]: `rho` below 1 (closed room).
pub fn check_cie171(flux_lm: f64, area_m2: f64, rho: f64) -> Result<(), String> {
    POSITIVE_LM.check_named("flux", flux_lm)?;
    POSITIVE_M2.check_named("area", area_m2)?;
    CLOSED_REFLECTANCE.check_named("rho", rho)?;
    Ok(())
}

/// An illuminance with the numerical integration's error bound (lx).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExactValue {
    pub value: f64,
    pub error_bound: f64,
}

impl Sobolev {
    /// The parameters' domain: I, h1, h2 finite and positive; each reflectance in [0, 1] and
    /// rho1 rho2 < 1 (two mirrors facing each other never let the light go: the series of
    /// interreflections diverges). The error names the parameter and its range.
    pub fn check(&self) -> Result<(), String> {
        POSITIVE_CD.check_named("intensity", self.intensity_cd)?;
        POSITIVE_M.check_named("h1", self.h1)?;
        POSITIVE_M.check_named("h2", self.h2)?;
        REFLECTANCE.check_named("rho1", self.rho1)?;
        REFLECTANCE.check_named("rho2", self.rho2)?;
        if self.rho1 * self.rho2 >= 1.0 {
            return Err(format!(
                "rho1 rho2 must be below 1 (the interreflections never end), got {} x {}",
                self.rho1, self.rho2
            ));
        }
        Ok(())
    }

    /// The same problem seen from plane 2 (swap the planes).
    pub fn swapped(&self) -> Sobolev {
        Sobolev {
            h1: self.h2,
            h2: self.h1,
            rho1: self.rho2,
            rho2: self.rho1,
            ..*self
        }
    }

    /// Direct illuminance on plane 1 at distance r from the foot of the source.
    pub fn direct1(&self, r: f64) -> f64 {
        self.intensity_cd * self.h1 / (r * r + self.h1 * self.h1).powf(1.5)
    }

    /// Total illuminance on plane 1 at distance r from the foot of the source.
    pub fn illuminance1(&self, r: f64) -> ExactValue {
        let (v, e) = self.reflected1(r.abs());
        ExactValue {
            value: self.direct1(r) + v,
            error_bound: e,
        }
    }

    /// Total illuminance on plane 2.
    pub fn illuminance2(&self, r: f64) -> ExactValue {
        self.swapped().illuminance1(r)
    }

    /// Luminous flux received by plane 1, `2π I (1 + rho2) / (1 − rho1 rho2)`.
    pub fn flux1(&self) -> f64 {
        2.0 * PI * self.intensity_cd * (1.0 + self.rho2) / (1.0 - self.rho1 * self.rho2)
    }

    /// The reflected part of E1 (everything but the direct term) and its error bound.
    fn reflected1(&self, r: f64) -> (f64, f64) {
        let (h1, h2, r1, r2) = (self.h1, self.h2, self.rho1, self.rho2);
        if r2 == 0.0 {
            return (0.0, 0.0);
        }
        let big_h = h1 + h2;
        // Bracket minus the direct e^{-k h1}: [r1 r2 κ² e^{-k h1} + r2 κ e^{-k h2}] / [1 − r1 r2 κ²].
        let rest = |k: f64| {
            let kap = kappa(k * big_h);
            let den = 1.0 - r1 * r2 * kap * kap;
            (r1 * r2 * kap * kap * (-k * h1).exp() + r2 * kap * (-k * h2).exp()) / den
        };
        let (v, e) = inverse_hankel(rest, r, big_h);
        (self.intensity_cd * v, self.intensity_cd * e)
    }
}

/// `∫0^∞ f(k) J0(k r) k dk` for a transform `f` that decays at least like `e^{-k H}`, with its
/// error bound: integrated over [0, 50/H] in panels of half a period of J0(kr), each by
/// adaptive Gauss–Kronrod, to an error estimate of 1e-10 of the r = 0 value.
fn inverse_hankel(f: impl Fn(f64) -> f64, r: f64, big_h: f64) -> (f64, f64) {
    let k_max = 50.0 / big_h;
    // Scale for the tolerance: the integral at r = 0 (positive integrand).
    let (scale, _) = integrate(&mut |k| f(k) * k, 0.0, k_max, 1e-8 / (big_h * big_h));
    let panel = if r > 0.0 {
        (PI / r).min(0.5 / big_h)
    } else {
        0.5 / big_h
    };
    // At most 1e6 panels (r up to 3e5 H): beyond, the J0 oscillations are far below the
    // tolerance anyway, and the work stays bounded for any r.
    let n = (k_max / panel).ceil().clamp(1.0, 1e6) as usize;
    // The Gauss-Kronrod difference overestimates the Kronrod error by orders of magnitude, so
    // this bound is conservative (the tests compare with SciPy to 1e-9).
    let tol = 1e-10 * scale.abs() / n as f64;
    let (mut sum, mut err) = (0.0, 0.0);
    for i in 0..n {
        let a = i as f64 * k_max / n as f64;
        let b = (i + 1) as f64 * k_max / n as f64;
        let (v, e) = integrate(&mut |k| f(k) * k * bessel_j0(k * r), a, b, tol);
        sum += v;
        err += e;
    }
    // Round-off of the panel sum.
    err += 1e-16 * n as f64 * scale.abs();
    (sum, err)
}

/// The Gamma function for x > 0 (Lanczos, g = 7, 9 terms: relative error below 1e-14).
pub fn gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return PI / ((PI * x).sin() * gamma(1.0 - x));
    }
    let x = x - 1.0;
    let mut a = C[0];
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    let t = x + G + 0.5;
    (2.0 * PI).sqrt() * t.powf(x + 0.5) * (-t).exp() * a
}

/// Modified Bessel function of the second kind of real order nu ≥ 0, for x > 0: the
/// trapezoidal rule on `K_ν(x) = ∫0^∞ e^{-x cosh t} cosh(νt) dt`, with the step and the
/// error of [`bessel_k1`].
pub fn bessel_k(nu: f64, x: f64) -> f64 {
    assert!(x > 0.0, "K_nu is defined for x > 0");
    if x > 700.0 {
        return 0.0;
    }
    let h: f64 = 0.25 / x.sqrt().max(1.0);
    let mut s = 0.5 * (-x).exp();
    let mut t = h;
    loop {
        let c = t.cosh();
        // cosh(νt) is c itself for ν = 1 (kappa's K1, in the Sobolev integrands' inner loop).
        let v = (-x * c).exp() * if nu == 1.0 { c } else { (nu * t).cosh() };
        s += v;
        if x * c > 745.0 || (v < 1e-300 && x * c > 1.0) {
            break;
        }
        t += h;
    }
    s * h
}

/// `x^μ K_μ(x) / (2^{μ−1} Γ(μ))` for μ > 0: 1 at x = 0, e^{-x} for μ = 1/2, κ(x) for μ = 1.
/// The Hankel transform of a cosⁿ luminaire's direct illuminance on a plane at distance h is
/// `I0/(n + 1) · cosn_transform((n + 1)/2, k h)`.
pub fn cosn_transform(mu: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    // ln of the value, so that large x^μ and small K_μ do not overflow.
    let k = bessel_k(mu, x);
    if k == 0.0 {
        return 0.0;
    }
    (mu * x.ln() + k.ln() - (mu - 1.0) * 2f64.ln() - gamma(mu).ln()).exp()
}

/// Sobolev's two planes lit by a cosⁿ luminaire at the origin aimed at plane 1 (I0 cosⁿψ, ψ
/// from the normal of plane 1, nothing towards plane 2). Plane 1 gets the direct term
/// `I0 h1^{n+1} / (r² + h1²)^{(n+3)/2}`, whose Hankel transform is `D̂(k) = I0/(n+1) ·
/// cosn_transform((n+1)/2, k h1)` (Gradshteyn–Ryzhik 6.565.4), and the balance equations
/// `Ê1 = D̂ + rho2 κ Ê2`, `Ê2 = rho1 κ Ê1` give
///
/// ```text
/// E1(r) = direct + ∫ D̂ rho1 rho2 κ² / (1 − rho1 rho2 κ²) J0(kr) k dk
/// E2(r) =          ∫ D̂ rho1 κ      / (1 − rho1 rho2 κ²) J0(kr) k dk
/// ```
///
/// (n = 0 is the lower half of Sobolev's isotropic source: D̂ = I0 e^{-k h1}.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CosnSobolev {
    pub i0_cd: f64,
    pub n: f64,
    pub h1: f64,
    pub h2: f64,
    pub rho1: f64,
    pub rho2: f64,
}

/// The exponent of the cosⁿ luminaire of [`CosnSobolev`]: [0, 20].
pub const COSN_SOBOLEV_EXPONENT: Real = Real::closed(0.0, 20.0, "");

impl CosnSobolev {
    /// The parameters' domain, as [`Sobolev::check`], and n in [0, 20].
    pub fn check(&self) -> Result<(), String> {
        Sobolev {
            intensity_cd: self.i0_cd,
            h1: self.h1,
            h2: self.h2,
            rho1: self.rho1,
            rho2: self.rho2,
        }
        .check()?;
        COSN_SOBOLEV_EXPONENT.check_named("n", self.n)?;
        Ok(())
    }

    /// Direct illuminance on plane 1 at distance r from the foot of the luminaire.
    pub fn direct1(&self, r: f64) -> f64 {
        let h = self.h1;
        self.i0_cd * h.powf(self.n + 1.0) / (r * r + h * h).powf(0.5 * (self.n + 3.0))
    }

    /// The transform of the direct term, D̂(k).
    fn direct_transform(&self, k: f64) -> f64 {
        self.i0_cd / (self.n + 1.0) * cosn_transform(0.5 * (self.n + 1.0), k * self.h1)
    }

    /// Total illuminance on plane 1 (below the luminaire).
    pub fn illuminance1(&self, r: f64) -> ExactValue {
        let (r1, r2, big_h) = (self.rho1, self.rho2, self.h1 + self.h2);
        let (v, e) = if r1 * r2 == 0.0 {
            (0.0, 0.0)
        } else {
            inverse_hankel(
                |k| {
                    let kap = kappa(k * big_h);
                    let q = r1 * r2 * kap * kap;
                    self.direct_transform(k) * q / (1.0 - q)
                },
                r.abs(),
                big_h,
            )
        };
        ExactValue {
            value: self.direct1(r) + v,
            error_bound: e,
        }
    }

    /// Total illuminance on plane 2 (above the luminaire: reflected light only).
    pub fn illuminance2(&self, r: f64) -> ExactValue {
        let (r1, r2, big_h) = (self.rho1, self.rho2, self.h1 + self.h2);
        if r1 == 0.0 {
            return ExactValue {
                value: 0.0,
                error_bound: 0.0,
            };
        }
        let (value, error_bound) = inverse_hankel(
            |k| {
                let kap = kappa(k * big_h);
                self.direct_transform(k) * r1 * kap / (1.0 - r1 * r2 * kap * kap)
            },
            r.abs(),
            big_h,
        );
        ExactValue { value, error_bound }
    }
}

/// Mean of a radially symmetric illuminance `e(r)` over the disk of radius `b` centred at
/// distance `r0` from the symmetry axis (the expectation of a counting bin in direct
/// simulation). Nested 15-point Gauss–Kronrod in polar coordinates about the disk centre,
/// accurate while e varies smoothly on the scale of b.
pub fn disk_average(e: impl Fn(f64) -> f64, r0: f64, b: f64) -> f64 {
    use crate::quadrature::gauss_kronrod_15;
    let mut outer = |s: f64| {
        let mut inner = |phi: f64| e((r0 * r0 + s * s + 2.0 * r0 * s * phi.cos()).max(0.0).sqrt());
        s * gauss_kronrod_15(&mut inner, 0.0, PI).0
    };
    2.0 * gauss_kronrod_15(&mut outer, 0.0, b).0 / (PI * b * b)
}

/// Illuminance (lx) at a point of the wall of a closed Lambertian sphere of radius R and
/// reflectance rho, from an isotropic source of intensity I inside: the direct term
/// `I cos θ / d²` plus the uniform indirect term `rho Φ / (4π R² (1 − rho))`, Φ = 4π I.
/// `source` and `point` are relative to the centre; the wall normal points to the centre.
pub fn integrating_sphere_illuminance(
    intensity_cd: f64,
    radius: f64,
    rho: f64,
    source: luxest_io::math::Vec3,
    point: luxest_io::math::Vec3,
) -> f64 {
    sphere_wall(point, |normal| {
        point_source_illuminance(intensity_cd, source, point, normal)
            + integrating_sphere_indirect(intensity_cd, radius, rho)
    })
}

/// `illuminance(normal)` at a wall point of a sphere centred at the origin, whose normal
/// points to the centre.
fn sphere_wall(
    point: luxest_io::math::Vec3,
    illuminance: impl FnOnce(luxest_io::math::Vec3) -> f64,
) -> f64 {
    illuminance(
        (-point)
            .try_normalize()
            .expect("point must not be the centre"),
    )
}

/// The uniform indirect illuminance of an integrating sphere, `rho Φ / (4π R² (1 − rho))`.
pub fn integrating_sphere_indirect(intensity_cd: f64, radius: f64, rho: f64) -> f64 {
    let flux = 4.0 * PI * intensity_cd;
    rho * flux / (4.0 * PI * radius * radius * (1.0 - rho))
}

/// CIE 171:2006 case 5.8: mean indirect illuminance over the surfaces of a closed room of total
/// surface area `area_m2` and uniform reflectance rho lit by flux Φ: `rho Φ / (S_T (1 − rho))`.
pub fn cie171_mean_indirect_illuminance(flux_lm: f64, area_m2: f64, rho: f64) -> f64 {
    rho * flux_lm / (area_m2 * (1.0 - rho))
}

/// CIE 171:2006 case 5.2: direct illuminance `I cos θ / d²` (lx) at `point` with unit `normal`
/// from an isotropic point source at `source` (zero if the source is behind the surface).
pub fn point_source_illuminance(
    intensity_cd: f64,
    source: luxest_io::math::Vec3,
    point: luxest_io::math::Vec3,
    normal: luxest_io::math::Vec3,
) -> f64 {
    let d = source - point;
    let d2 = d.length_squared();
    let cos = normal.dot(d) / d2.sqrt();
    if cos > 0.0 {
        intensity_cd * cos / d2
    } else {
        0.0
    }
}

/// The exponent of a cosⁿ luminaire: [0, 100].
pub const COSN_EXPONENT: Real = Real::closed(0.0, 100.0, "");

/// Flux of a luminaire radiating I(ψ) = I0 cosⁿψ into the lower hemisphere (ψ from its nadir,
/// none above): Φ = 2π I0 / (n + 1) lm.
pub fn cosn_luminaire_flux(i0_cd: f64, n: f64) -> f64 {
    2.0 * PI * i0_cd / (n + 1.0)
}

/// Illuminance (lx) at `point` on a surface with unit `normal` from a cosⁿ luminaire at `source`
/// hanging straight down (nadir −y, luxest's y-up world): E = I0 cosⁿψ cos θ / d², with
/// cos ψ = −(point − source)·ŷ / d (0 above the luminaire's horizontal plane) and θ the angle
/// of incidence (0 when light arrives from behind). No visibility.
pub fn cosn_luminaire_illuminance(
    i0_cd: f64,
    n: f64,
    source: luxest_io::math::Vec3,
    point: luxest_io::math::Vec3,
    normal: luxest_io::math::Vec3,
) -> f64 {
    let d = point - source;
    let dist = d.length();
    let cos_psi = -d.y / dist;
    if cos_psi <= 0.0 {
        return 0.0;
    }
    point_source_illuminance(i0_cd * cos_psi.powf(n), source, point, normal)
}

/// Illuminance (lx) on the wall of an integrating sphere of radius R (centred at the origin)
/// and reflectance rho with a cosⁿ luminaire inside: the direct term
/// [`cosn_luminaire_illuminance`] plus the uniform indirect term rho Φ / (4π R² (1 − rho)),
/// which depends on the flux alone (every first reflection spreads uniformly over a sphere).
pub fn integrating_sphere_cosn_illuminance(
    i0_cd: f64,
    n: f64,
    radius: f64,
    rho: f64,
    source: luxest_io::math::Vec3,
    point: luxest_io::math::Vec3,
) -> f64 {
    let flux = cosn_luminaire_flux(i0_cd, n);
    sphere_wall(point, |normal| {
        cosn_luminaire_illuminance(i0_cd, n, source, point, normal)
            + integrating_sphere_indirect(flux / (4.0 * PI), radius, rho)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use luxest_io::math::Vec3;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    #[test]
    fn bessel_functions_match_reference_values() {
        // Reference values: mpmath besselj(0, x) / besselk(1, x) at 30 digits.
        let j0 = [
            (0.0, 1.0),
            (1.0, 0.7651976865579666),
            (2.5, -0.048383776468198),
            (10.0, -0.24593576445134835),
            (24.9, 0.0832459683530155),
            (25.1, 0.10827567149994945),
            (100.0, 0.019985850304223122),
            (1234.5, -0.013550379618035721),
        ];
        for (x, v) in j0 {
            assert!(
                (bessel_j0(x) - v).abs() < 1e-14,
                "J0({x}) = {} vs {v}",
                bessel_j0(x)
            );
        }
        let k1 = [
            (1e-6, 999999.9999927843),
            (0.1, 9.853844780870606),
            (1.0, 0.6019072301972346),
            (2.0, 0.13986588181652243),
            (10.0, 1.8648773453825585e-05),
            (50.0, 3.4441022267175555e-23),
        ];
        for (x, v) in k1 {
            assert!(
                rel(bessel_k1(x), v) < 1e-13,
                "K1({x}) = {} vs {v}",
                bessel_k1(x)
            );
        }
    }

    #[test]
    fn sobolev_without_reflection_is_the_direct_term() {
        let s = Sobolev {
            intensity_cd: 100.0,
            h1: 1.0,
            h2: 2.0,
            rho1: 0.7,
            rho2: 0.0,
        };
        for r in [0.0, 0.3, 5.0] {
            let e = s.illuminance1(r);
            assert_eq!(e.value, 100.0 / (r * r + 1.0f64).powf(1.5));
        }
    }

    /// Single-bounce illuminance on plane 1 at distance r, from plane 2 (reflectance 1) lit
    /// directly, by real-space quadrature: the azimuthal integral of the Lambertian kernel
    /// H²/(π(|x−y|²+H²)²) is 2π A H² / (π (A² − B²)^{3/2}) with A = s² + r² + H², B = 2 s r,
    /// leaving a 1-D integral over s = h2 tan u.
    fn single_bounce_real_space(i: f64, h1: f64, h2: f64, r: f64) -> f64 {
        let big_h = h1 + h2;
        let mut f = |u: f64| {
            let s = h2 * u.tan();
            let ds = h2 / (u.cos() * u.cos());
            let e2 = i * h2 / (s * s + h2 * h2).powf(1.5);
            let a = s * s + r * r + big_h * big_h;
            let b = 2.0 * s * r;
            let phi_integral = 2.0 * a * big_h * big_h / (a * a - b * b).powf(1.5);
            e2 * phi_integral * s * ds
        };
        integrate(&mut f, 0.0, PI / 2.0, 1e-14).0
    }

    #[test]
    fn gamma_and_real_order_bessel_k_match_closed_forms() {
        let sqrt_pi = PI.sqrt();
        for (x, v) in [
            (0.5, sqrt_pi),
            (1.5, sqrt_pi / 2.0),
            (4.5, 3.5 * 2.5 * 1.5 * 0.5 * sqrt_pi),
            (1.0, 1.0),
            (5.0, 24.0),
            (0.25, 3.625_609_908_221_908),
        ] {
            assert!(rel(gamma(x), v) < 1e-13, "Γ({x}) = {} vs {v}", gamma(x));
        }
        for x in [1e-4, 0.1, 1.0, 3.0, 20.0] {
            let half = (PI / (2.0 * x)).sqrt() * (-x).exp();
            assert!(rel(bessel_k(0.5, x), half) < 1e-13, "K_1/2({x})");
            assert!(
                rel(bessel_k(1.5, x), half * (1.0 + 1.0 / x)) < 1e-13,
                "K_3/2({x})"
            );
            assert!(rel(bessel_k(1.0, x), bessel_k1(x)) < 1e-14, "K_1({x})");
            assert!(
                rel(cosn_transform(0.5, x), (-x).exp()) < 1e-12,
                "f_1/2({x})"
            );
            assert!(rel(cosn_transform(1.0, x), kappa(x)) < 1e-12, "f_1({x})");
        }
        // The small-x limit is 1 (every order).
        for mu in [0.5, 1.0, 1.5, 2.5] {
            assert!((cosn_transform(mu, 1e-7) - 1.0).abs() < 1e-6, "f_{mu}(0)");
        }
    }

    /// Single-bounce illuminance on plane 2 at distance r from the axis, from plane 1
    /// (reflectance 1) lit directly by the cosⁿ luminaire, by the real-space quadrature of
    /// [`single_bounce_real_space`].
    fn cosn_single_bounce_real_space(i0: f64, n: f64, h1: f64, h2: f64, r: f64) -> f64 {
        let big_h = h1 + h2;
        let mut f = |u: f64| {
            let s = h1 * u.tan();
            let ds = h1 / (u.cos() * u.cos());
            let e1 = i0 * h1.powf(n + 1.0) / (s * s + h1 * h1).powf(0.5 * (n + 3.0));
            let a = s * s + r * r + big_h * big_h;
            let b = 2.0 * s * r;
            let phi_integral = 2.0 * a * big_h * big_h / (a * a - b * b).powf(1.5);
            e1 * phi_integral * s * ds
        };
        // Split where the kernel peaks (s = r), so that the adaptive rule cannot step over it.
        let u_r = (r / h1).atan();
        integrate(&mut f, 0.0, u_r, 1e-14).0 + integrate(&mut f, u_r, PI / 2.0, 1e-14).0
    }

    #[test]
    fn cosn_sobolev_single_bounce_matches_real_space_quadrature() {
        // rho2 = 0: plane 1 gets the direct term only, plane 2 one reflection from plane 1.
        for n in [1.0, 2.0, 5.0] {
            for (h1, h2) in [(1.0, 1.0), (0.5, 1.5), (2.0, 0.25)] {
                let c = CosnSobolev {
                    i0_cd: 1000.0,
                    n,
                    h1,
                    h2,
                    rho1: 0.6,
                    rho2: 0.0,
                };
                for r in [0.0, 0.5, 2.0, 6.0] {
                    assert_eq!(c.illuminance1(r).value, c.direct1(r));
                    let e = c.illuminance2(r);
                    let want = 0.6 * cosn_single_bounce_real_space(1000.0, n, h1, h2, r);
                    assert!(
                        rel(e.value, want) < 1e-9 && e.error_bound < 1e-9 * want,
                        "n={n} h=({h1},{h2}) r={r}: {} vs {want}",
                        e.value
                    );
                }
            }
        }
    }

    #[test]
    fn cosn_sobolev_with_n0_halves_add_up_to_sobolev() {
        // An isotropic source is a downward n = 0 luminaire plus an upward one: Sobolev's E1 is
        // the downward half's E1 plus the upward half's E2 (planes swapped), for any reflectances.
        for (h1, h2, rho1, rho2) in [
            (1.0, 1.0, 0.5, 0.5),
            (0.5, 1.5, 0.3, 0.8),
            (1.0, 1.0, 0.9, 0.9),
        ] {
            let s = Sobolev {
                intensity_cd: 100.0,
                h1,
                h2,
                rho1,
                rho2,
            };
            let down = CosnSobolev {
                i0_cd: 100.0,
                n: 0.0,
                h1,
                h2,
                rho1,
                rho2,
            };
            let up = CosnSobolev {
                h1: h2,
                h2: h1,
                rho1: rho2,
                rho2: rho1,
                ..down
            };
            for r in [0.0, 1.0, 4.0] {
                let want = s.illuminance1(r).value;
                let got = down.illuminance1(r).value + up.illuminance2(r).value;
                assert!(rel(got, want) < 1e-9, "r={r}: {got} vs {want}");
            }
        }
        let bad = CosnSobolev {
            i0_cd: 1.0,
            n: 30.0,
            h1: 1.0,
            h2: 1.0,
            rho1: 0.5,
            rho2: 0.5,
        };
        assert!(bad.check().unwrap_err().contains("n: must be"));
    }

    #[test]
    fn sobolev_single_bounce_matches_real_space_quadrature() {
        // With rho1 = 0 the light reflects once, from plane 2: E1 = direct + rho2 * B(r).
        for (h1, h2) in [(1.0, 1.0), (0.5, 1.5), (2.0, 0.25)] {
            let s = Sobolev {
                intensity_cd: 100.0,
                h1,
                h2,
                rho1: 0.0,
                rho2: 0.8,
            };
            for r in [0.0, 0.5, 2.0, 6.0] {
                let e = s.illuminance1(r);
                let expected = s.direct1(r) + 0.8 * single_bounce_real_space(100.0, h1, h2, r);
                assert!(
                    rel(e.value, expected) < 1e-9,
                    "h=({h1},{h2}) r={r}: {} vs {expected}",
                    e.value
                );
            }
        }
    }

    #[test]
    fn sobolev_matches_scipy_reference_values() {
        // Values from SciPy quad of the same integral with scipy.special.j0/k1 (limit=2000,
        // epsabs=1e-14), independent of this module's Bessel functions and quadrature.
        let cases = [
            // (h1, h2, rho1, rho2, r, E1 / I)
            (1.0, 1.0, 0.5, 0.5, 0.0, 1.1320323814543345),
            (1.0, 1.0, 0.5, 0.5, 2.0, 0.16336057929859715),
            (1.0, 1.0, 0.99, 0.99, 0.0, 1.6859242711257143),
            (1.0, 1.0, 0.99, 0.99, 4.0, 0.38734766252386593),
            (1.0, 1.0, 0.99, 0.99, 8.0, 0.2224589646469802),
            (0.5, 1.5, 0.3, 0.8, 1.0, 0.4911743196424916),
        ];
        for (h1, h2, rho1, rho2, r, v) in cases {
            let s = Sobolev {
                intensity_cd: 1.0,
                h1,
                h2,
                rho1,
                rho2,
            };
            let e = s.illuminance1(r);
            assert!(
                rel(e.value, v) < 1e-9,
                "{h1} {h2} {rho1} {rho2} r={r}: {} vs {v}",
                e.value
            );
            assert!(e.error_bound < 1e-6 * e.value, "error bound {e:?}");
        }
    }

    #[test]
    fn disk_average_of_a_quadratic_is_exact() {
        // e(r) = r²: mean over the disk = r0² + b²/2.
        let v = disk_average(|r| r * r, 1.5, 0.3);
        assert!((v - (2.25 + 0.045)).abs() < 1e-12);
    }

    #[test]
    fn integrating_sphere_and_cie_room_formulas() {
        // At the point nearest a central source: I/R² plus the uniform term.
        let e =
            integrating_sphere_illuminance(100.0, 2.0, 0.5, Vec3::ZERO, Vec3::new(0.0, -2.0, 0.0));
        assert!(rel(e, 25.0 + 0.5 * 400.0 * PI / (16.0 * PI * 0.5)) < 1e-15);
        assert!(
            rel(
                cie171_mean_indirect_illuminance(10000.0, 96.0, 0.5),
                10000.0 / 96.0
            ) < 1e-15
        );
        let behind = point_source_illuminance(
            1.0,
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::ZERO,
            Vec3::new(0.0, 1.0, 0.0),
        );
        assert_eq!(behind, 0.0);
    }
}
