//! Conductors with a complex index of refraction η + ik per RGB channel: Mitsuba 3's `conductor`
//! (a smooth, delta reflector) and `roughconductor` (a microfacet reflector, [`super::microfacet`],
//! f = F(wo·h) D(h) G(wo, wi, h) / (4 cos θo cos θi)), both scaled by `specular_reflectance`.
//! Directions are in the local frame of the surface (+z the normal on `wo`'s side).

use super::microfacet::{reflect, Distribution};
use super::LocalSample;
use crate::scene::Microfacet;
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;

/// Fresnel reflectance of a conductor of complex relative index η + ik for unpolarised light at
/// incidence cosine `cos_i` (Mitsuba's `fresnel_conductor`, after K. D. Möller, *Optics*, 1988).
pub fn fresnel_conductor(cos_i: f64, eta: f64, k: f64) -> f64 {
    let c2 = cos_i * cos_i;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let temp1 = eta * eta - k * k - s2;
    let a2pb2 = (temp1 * temp1 + 4.0 * k * k * eta * eta).max(0.0).sqrt();
    let a = (0.5 * (a2pb2 + temp1)).max(0.0).sqrt();
    let term1 = a2pb2 + c2;
    let term2 = 2.0 * cos_i * a;
    let rs = (term1 - term2) / (term1 + term2);
    let term3 = a2pb2 * c2 + s4;
    let term4 = term2 * s2;
    let rp = rs * (term3 - term4) / (term3 + term4);
    0.5 * (rs + rp)
}

/// [`fresnel_conductor`] per channel, times `specular_reflectance`.
pub fn reflectance(cos_i: f64, eta: &Rgb, k: &Rgb, specular_reflectance: &Rgb) -> Rgb {
    Rgb(std::array::from_fn(|c| {
        specular_reflectance.0[c] * fresnel_conductor(cos_i, eta.0[c], k.0[c])
    }))
}

/// The parameters of `Material::Conductor`.
pub struct Conductor<'a> {
    pub eta: &'a Rgb,
    pub k: &'a Rgb,
    pub specular_reflectance: &'a Rgb,
}

impl Conductor<'_> {
    /// The rough conductor's f (the smooth one has none).
    pub fn eval(&self, r: &Microfacet, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::BLACK;
        }
        let Some(h) = (wo + wi).try_normalize() else {
            return Rgb::BLACK;
        };
        let d = Distribution::new(r);
        let dh = d.d(h);
        if dh == 0.0 {
            return Rgb::BLACK;
        }
        let value = dh * d.g(wo, wi, h) / (4.0 * wo.z * wi.z);
        reflectance(wo.dot(h), self.eta, self.k, self.specular_reflectance) * value
    }

    /// The rough conductor's density: visible normals, D(h) G1(wo, h) / (4 cos θo).
    pub fn pdf(r: &Microfacet, wo: Vec3, wi: Vec3) -> f64 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let Some(h) = (wo + wi).try_normalize() else {
            return 0.0;
        };
        if wo.dot(h) <= 0.0 || wi.dot(h) <= 0.0 {
            return 0.0;
        }
        let d = Distribution::new(r);
        d.d(h) * d.smith_g1_sampled(wo, h) / (4.0 * wo.z)
    }

    pub fn sample(
        &self,
        roughness: Option<&Microfacet>,
        wo: Vec3,
        u: (f64, f64),
    ) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let Some(r) = roughness else {
            return Some(LocalSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: reflectance(wo.z, self.eta, self.k, self.specular_reflectance),
                pdf: 1.0,
                delta: true,
            });
        };
        let d = Distribution::new(r);
        let (m, pdf_m) = d.sample(wo, u);
        let wi = reflect(wo, m);
        if pdf_m.is_nan() || pdf_m <= 0.0 || wi.z <= 0.0 {
            return None;
        }
        // f cos θi / pdf = F G1(wi, m): D and G1(wo, m) cancel against the visible normals
        // (up to the masking ratio, see `microfacet`).
        let weight = reflectance(wo.dot(m), self.eta, self.k, self.specular_reflectance)
            * (d.smith_g1(wi, m) * d.masking_ratio(wo, m));
        Some(LocalSample {
            wi,
            weight,
            pdf: pdf_m / (4.0 * wi.dot(m)),
            delta: false,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::super::{eval, sample, Transport};
    use super::*;
    use crate::scene::{Material, MicrofacetDistribution};

    const GOLD_ETA: Rgb = Rgb([0.143, 0.374, 1.442]);
    const GOLD_K: Rgb = Rgb([3.983, 2.385, 1.603]);

    fn rough(distribution: MicrofacetDistribution, alpha: f64) -> Material {
        Material::Conductor {
            eta: GOLD_ETA,
            k: GOLD_K,
            specular_reflectance: Rgb([0.9, 1.0, 0.8]),
            roughness: Some(Microfacet {
                distribution,
                alpha,
            }),
        }
    }

    #[test]
    fn fresnel_matches_the_dielectric_and_normal_incidence() {
        // k = 0 is a dielectric interface; at normal incidence F = ((η−1)² + k²) / ((η+1)² + k²).
        for (cos, eta) in [(1.0, 1.5), (0.7, 1.5), (0.2, 2.4), (0.5, 1.33)] {
            let f = fresnel_conductor(cos, eta, 0.0);
            let d = super::super::fresnel_dielectric(cos, eta).0;
            assert!((f - d).abs() < 1e-12, "cos {cos} η {eta}: {f} vs {d}");
        }
        for (eta, k) in [(0.143, 3.983), (1.5, 2.0), (0.0, 1.0)] {
            let f = fresnel_conductor(1.0, eta, k);
            let e = ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k);
            assert!((f - e).abs() < 1e-12, "η {eta} k {k}: {f} vs {e}");
        }
        // Mitsuba's `material="none"` (η = 0, k = 1) reflects everything at every angle.
        assert!((fresnel_conductor(0.3, 0.0, 1.0) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn smooth_conductor_reflects_its_fresnel_reflectance_on_both_sides() {
        let m = Material::Conductor {
            eta: GOLD_ETA,
            k: GOLD_K,
            specular_reflectance: Rgb([1.0, 0.5, 1.0]),
            roughness: None,
        };
        for wo in [Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.6, 0.0, -0.8)] {
            let s = sample(&m, wo, UP, UP, (0.3, 0.4), 0.5, Transport::Radiance).unwrap();
            assert!(s.delta && s.pdf == 1.0);
            assert!((s.wi - Vec3::new(-0.6, 0.0, wo.z)).length() < 1e-12);
            for c in 0..3 {
                let e = [1.0, 0.5, 1.0][c] * fresnel_conductor(0.8, GOLD_ETA.0[c], GOLD_K.0[c]);
                assert!((s.weight.0[c] - e).abs() < 1e-12);
            }
            assert_eq!(eval(&m, wo, s.wi, UP, UP), Rgb::BLACK);
        }
    }

    /// Rough conductors' chi-square tests: each material from four directions, the shading
    /// normal tilted in the last.
    const SAMPLING_TESTS: usize = 3 * 4;

    fn assert_rough_sampling(m: &Material, seed: u64) {
        let tilted = Vec3::new(0.4, 0.0, 1.0);
        let cases = [
            (Vec3::new(0.0, 0.0, 1.0), UP),
            (Vec3::new(0.5, 0.3, -0.8), UP),
            (Vec3::new(0.97, 0.0, 0.25), UP),
            (Vec3::new(-0.5, 0.2, 0.6), tilted),
        ];
        assert_sampling_matches_pdf(m, &cases, seed, SAMPLING_TESTS, 1e-9);
    }

    #[test]
    fn ggx_conductor_sampling_matches_its_density() {
        assert_rough_sampling(&rough(MicrofacetDistribution::Ggx, 0.3), 20);
    }

    #[test]
    fn narrow_ggx_conductor_sampling_matches_its_density() {
        assert_rough_sampling(&rough(MicrofacetDistribution::Ggx, 0.15), 21);
    }

    #[test]
    fn beckmann_conductor_sampling_matches_its_density() {
        assert_rough_sampling(&rough(MicrofacetDistribution::Beckmann, 0.5), 22);
    }

    /// Directional albedo by sampling equals the quadrature of `eval` (and stays below 1), and
    /// `eval` is reciprocal.
    fn assert_energy_and_reciprocity(m: &Material, seed: u64) {
        for cos in [0.9, 0.4] {
            let wo = at_cos(cos);
            let mc = albedo_mc(m, wo, 50_000, seed, Transport::Radiance);
            let quad = albedo_quadrature(m, wo, 150, Transport::Radiance);
            assert_agrees(&format!("{m:?} cos {cos}"), mc, quad, 4.0, 2e-3);
            for c in 0..3 {
                assert!(mc.0 .0[c] <= 1.0 + 3.0 * mc.1 .0[c], "albedo {:?}", mc.0);
            }
        }
        let mut r = crate::sampling::Rng::new(seed, 1);
        for _ in 0..200 {
            let a = crate::sampling::uniform_sphere(r.next_f64(), r.next_f64());
            let b = crate::sampling::uniform_sphere(r.next_f64(), r.next_f64());
            let (fa, fb) = (eval(m, a, b, UP, UP), eval(m, b, a, UP, UP));
            for c in 0..3 {
                assert!(relative(fa.0[c], fb.0[c]) < 1e-12, "{fa:?} vs {fb:?}");
            }
        }
    }

    #[test]
    fn ggx_conductor_conserves_energy_and_is_reciprocal() {
        assert_energy_and_reciprocity(&rough(MicrofacetDistribution::Ggx, 0.4), 30);
    }

    #[test]
    fn beckmann_conductor_conserves_energy_and_is_reciprocal() {
        assert_energy_and_reciprocity(&rough(MicrofacetDistribution::Beckmann, 0.3), 31);
    }

    /// Mitsuba's `none` (η = 0, k = 1): F = 1, so all the albedo lacks of 1 is what the
    /// single-scattering model loses.
    #[test]
    fn lossless_conductor_albedo_stays_below_one() {
        let m = Material::Conductor {
            eta: Rgb::splat(0.0),
            k: Rgb::splat(1.0),
            specular_reflectance: Rgb::WHITE,
            roughness: Some(Microfacet {
                distribution: MicrofacetDistribution::Ggx,
                alpha: 0.6,
            }),
        };
        assert_energy_and_reciprocity(&m, 32);
    }
}
