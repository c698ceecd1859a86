//! What the material tests share: the chi-square test of [`super::sample`] against
//! [`super::pdf`] (with the sample's own density and weight checked against `pdf` and `eval`),
//! the directional albedo by Monte Carlo with its standard error, and by quadrature of `eval`.

use super::{eval_transport, pdf, sample, Transport};
use crate::sampling::Rng;
use crate::scene::Material;
use luxest_io::chi2::{ChiSquareTest, Sphere};
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use std::f64::consts::PI;

pub const UP: Vec3 = Vec3::new(0.0, 0.0, 1.0);

/// A unit direction at cosine `cos` from +z, in the xz-plane (x ≥ 0).
pub fn at_cos(cos: f64) -> Vec3 {
    Vec3::new((1.0 - cos * cos).max(0.0).sqrt(), 0.0, cos)
}

/// Relative difference |a − b| / max(|a|, |b|) (0 when both are 0).
pub fn relative(a: f64, b: f64) -> f64 {
    let scale = a.abs().max(b.abs());
    if scale == 0.0 {
        0.0
    } else {
        (a - b).abs() / scale
    }
}

/// Directions [`sample`]d from `m` as seen from each `wo` (geometric normal [`UP`], shading
/// normal `ns`) against [`pdf`] over the whole sphere, one chi-square test each of a family of
/// `tests`. Delta samples count as rejected: `pdf` integrates to the probability of the
/// non-delta lobes. Each sample's density must be `pdf`'s, and its weight `eval |cos| / pdf`
/// (relative `tolerance`).
pub fn assert_sampling_matches_pdf(
    m: &Material,
    cases: &[(Vec3, Vec3)],
    seed: u64,
    tests: usize,
    tolerance: f64,
) {
    // Microfacet lobes are narrow: 16 × 16 midpoints per bin integrate those of α ≥ 0.15 to
    // 1e-4.
    assert_sampling_matches_pdf_integrated(m, cases, seed, (tests, 16), tolerance);
}

/// [`assert_sampling_matches_pdf`] with `integration × integration` midpoints per bin.
pub fn assert_sampling_matches_pdf_integrated(
    m: &Material,
    cases: &[(Vec3, Vec3)],
    seed: u64,
    (tests, integration): (usize, usize),
    tolerance: f64,
) {
    for (k, &(wo, ns)) in cases.iter().enumerate() {
        let (wo, ns) = (wo.try_normalize().unwrap(), ns.try_normalize().unwrap());
        let mut r = Rng::new(seed, k as u64);
        let mut draw = || {
            let s = sample(
                m,
                wo,
                UP,
                ns,
                r.next_2d(),
                r.next_f64(),
                Transport::Radiance,
            )?;
            if s.delta {
                return None;
            }
            let p = pdf(m, wo, s.wi, UP, ns);
            assert!(relative(s.pdf, p) <= tolerance, "pdf {} vs {p}", s.pdf);
            let f = eval_transport(m, wo, s.wi, UP, ns, Transport::Radiance);
            let expected = f * (s.wi.dot(ns).abs() / p);
            for c in 0..3 {
                assert!(
                    relative(s.weight.0[c], expected.0[c]) <= tolerance,
                    "weight {:?} vs eval cos / pdf {expected:?} at {:?}",
                    s.weight,
                    s.wi
                );
            }
            Some(s.wi)
        };
        ChiSquareTest::new(Sphere)
            .integration(integration)
            .tests(tests)
            .run(&mut draw, |wi| pdf(m, wo, wi, UP, ns))
            .unwrap_or_else(|r| panic!("{m:?}: wo {wo:?}, ns {ns:?}: {r:?}"));
    }
}

/// Directional albedo seen from `wo` (normal [`UP`]) by Monte Carlo: the mean sample weight
/// over `n` samples (rejected ones count as zero), and its standard error, per channel.
pub fn albedo_mc(m: &Material, wo: Vec3, n: usize, seed: u64, mode: Transport) -> (Rgb, Rgb) {
    let mut r = Rng::new(seed, 0);
    let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
    for _ in 0..n {
        if let Some(s) = sample(m, wo, UP, UP, r.next_2d(), r.next_f64(), mode) {
            for c in 0..3 {
                sum[c] += s.weight.0[c];
                sum2[c] += s.weight.0[c] * s.weight.0[c];
            }
        }
    }
    let n = n as f64;
    let mean = sum.map(|s| s / n);
    let se = std::array::from_fn(|c| ((sum2[c] / n - mean[c] * mean[c]).max(0.0) / n).sqrt());
    (Rgb(mean), Rgb(se))
}

/// Directional albedo seen from `wo` (normal [`UP`]) by the midpoint rule on a `k × 4k` grid
/// in (cos θ, φ) over the whole sphere: ∫ f |cos θ| dω from `eval` alone.
pub fn albedo_quadrature(m: &Material, wo: Vec3, k: usize, mode: Transport) -> Rgb {
    let mut sum = [0.0f64; 3];
    let (nc, nphi) = (2 * k, 4 * k);
    let cell = (2.0 / nc as f64) * (2.0 * PI / nphi as f64);
    for i in 0..nc {
        let c = -1.0 + (i as f64 + 0.5) * 2.0 / nc as f64;
        let s = (1.0 - c * c).max(0.0).sqrt();
        for j in 0..nphi {
            let phi = (j as f64 + 0.5) * 2.0 * PI / nphi as f64;
            let wi = Vec3::new(s * phi.cos(), s * phi.sin(), c);
            let f = eval_transport(m, wo, wi, UP, UP, mode);
            for (s, f) in sum.iter_mut().zip(f.0) {
                *s += f * c.abs() * cell;
            }
        }
    }
    Rgb(sum)
}

/// Asserts `mc` (mean, standard error) agrees with `expected` within `z` standard errors plus
/// `slack` (the quadrature's own error), per channel.
pub fn assert_agrees(what: &str, (mean, se): (Rgb, Rgb), expected: Rgb, z: f64, slack: f64) {
    for c in 0..3 {
        let d = (mean.0[c] - expected.0[c]).abs();
        assert!(
            d <= z * se.0[c] + slack,
            "{what}: channel {c}: Monte Carlo {} ± {} vs {}",
            mean.0[c],
            se.0[c],
            expected.0[c]
        );
    }
}
