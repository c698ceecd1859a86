//! Dielectric interfaces: the smooth `Dielectric` (Mitsuba 3's `dielectric`), the rough one
//! (`roughdielectric`: microfacet reflection and refraction after Walter et al., "Microfacet
//! Models for Refraction through Rough Surfaces", EGSR 2007, with visible-normal sampling), and
//! the thin sheet (`thindielectric`).
//!
//! Inside and outside: the geometric normal points outside; `ior` is the inside's index relative
//! to the outside, and η below is the index of the side light enters relative to the side of
//! `wo`. Refraction scales radiance by 1/η² and leaves flux as it is ([`super::Transport`]).
//!
//! The thin sheet: a slab whose two faces reflect R = F(|cos θ|) each; the light bouncing
//! between them sums to R' = R + T² R (1 + R² + …) = 2R / (1 + R) reflected and 1 − R'
//! transmitted, straight through (the two refractions cancel; no absorption).

use super::microfacet::{fresnel, reflect, refract, Distribution};
use super::{LocalSample, Transport};
use luxest_io::math::Vec3;

/// Exact Fresnel reflectance of a smooth dielectric for unpolarised light; `cos_i` > 0 on the
/// incident side, `eta` = η_transmitted / η_incident. Returns (F, cos_t); F = 1 under total
/// internal reflection.
pub fn fresnel_dielectric(cos_i: f64, eta: f64) -> (f64, f64) {
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    (0.5 * (rs * rs + rp * rp), cos_t)
}

/// A smooth dielectric interface as seen from `wo`: the shading normal on `wo`'s side (the side
/// follows the geometric normal), the relative index of refraction, the cosine on that side, and
/// the Fresnel reflectance with the transmitted cosine ([`fresnel_dielectric`]).
pub struct DielectricSide {
    pub n: Vec3,
    pub eta: f64,
    pub cos_o: f64,
    pub reflectance: f64,
    pub cos_t: f64,
}

/// The shading normal on `wo`'s side and η (the far side's index relative to `wo`'s), the side
/// told by the geometric normal `ng`.
pub fn side(wo: Vec3, ng: Vec3, ns: Vec3, ior: f64) -> (Vec3, f64) {
    if wo.dot(ng) > 0.0 {
        (ns, ior)
    } else {
        (-ns, 1.0 / ior)
    }
}

/// The interface of a dielectric of index `ior` (inside relative to the side `ng` points to),
/// as [`super::sample`] sees it.
pub fn dielectric_side(wo: Vec3, ng: Vec3, ns: Vec3, ior: f64) -> DielectricSide {
    let (n, eta) = side(wo, ng, ns, ior);
    let cos_o = wo.dot(n).max(0.0);
    let (reflectance, cos_t) = fresnel_dielectric(cos_o, eta);
    DielectricSide {
        n,
        eta,
        cos_o,
        reflectance,
        cos_t,
    }
}

/// The thin sheet's reflectance 2R / (1 + R) at incidence cosine `cos` (either side).
pub fn thin_reflectance(cos: f64, ior: f64) -> f64 {
    let r = fresnel(cos.abs(), ior).0;
    r * 2.0 / (1.0 + r)
}

/// A rough interface of relative index `eta` (of the far side relative to `wo`'s), in the local
/// frame where `wo.z` > 0.
pub struct Rough {
    pub d: Distribution,
    pub eta: f64,
}

impl Rough {
    /// The microfacet normal that scatters `wo` into `wi` (reflection when `wi.z` > 0), turned
    /// to the upper side, and the Jacobian |dω_m / dω_i|.
    fn half_vector(&self, wo: Vec3, wi: Vec3) -> Option<(Vec3, f64)> {
        let reflected = wi.z > 0.0;
        let m = (wo + wi * if reflected { 1.0 } else { self.eta }).try_normalize()?;
        let m = if m.z < 0.0 { -m } else { m };
        let (om, im) = (wo.dot(m), wi.dot(m));
        let jacobian = if reflected {
            1.0 / (4.0 * im)
        } else {
            self.eta * self.eta * im / ((om + self.eta * im) * (om + self.eta * im))
        };
        Some((m, jacobian.abs()))
    }

    /// f(wo, wi) (per sr, without the cosine), transmission scaled for `mode`.
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: Transport) -> f64 {
        if wo.z <= 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let Some((m, _)) = self.half_vector(wo, wi) else {
            return 0.0;
        };
        let d = self.d.d(m);
        let f = fresnel(wo.dot(m), self.eta).0;
        let g = self.d.g(wo, wi, m);
        let cos_io = wo.z * wi.z.abs();
        if wi.z > 0.0 {
            f * d * g / (4.0 * cos_io)
        } else {
            let scale = match mode {
                Transport::Radiance => 1.0 / (self.eta * self.eta),
                Transport::Flux => 1.0,
            };
            let (om, im) = (wo.dot(m), wi.dot(m));
            let denom = om + self.eta * im;
            (scale * (1.0 - f) * d * g * self.eta * self.eta * om * im / (cos_io * denom * denom))
                .abs()
        }
    }

    /// The density of [`Rough::sample`].
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f64 {
        if wo.z <= 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let Some((m, jacobian)) = self.half_vector(wo, wi) else {
            return 0.0;
        };
        if wo.dot(m) <= 0.0 || wi.dot(m) * wi.z <= 0.0 {
            return 0.0;
        }
        let f = fresnel(wo.dot(m), self.eta).0;
        let lobe = if wi.z > 0.0 { f } else { 1.0 - f };
        self.d.pdf(wo, m) * lobe * jacobian
    }

    /// A visible normal, then reflection with probability F and refraction otherwise; `None`
    /// when the scattered direction leaves on the wrong side of the macro-surface.
    pub fn sample(&self, wo: Vec3, u: (f64, f64), uc: f64, mode: Transport) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let (m, pdf_m) = self.d.sample(wo, u);
        if pdf_m.is_nan() || pdf_m <= 0.0 {
            return None;
        }
        let (f, cos_t, eta_it, eta_ti) = fresnel(wo.dot(m), self.eta);
        let (wi, pdf, scale) = if uc <= f {
            let wi = reflect(wo, m);
            (wi, pdf_m * f / (4.0 * wi.dot(m)), 1.0)
        } else {
            let wi = refract(wo, m, cos_t, eta_ti);
            let (om, im) = (wo.dot(m), wi.dot(m));
            let denom = om + eta_it * im;
            let jacobian = (eta_it * eta_it * im / (denom * denom)).abs();
            let scale = match mode {
                Transport::Radiance => eta_ti * eta_ti,
                Transport::Flux => 1.0,
            };
            if wi.z >= 0.0 {
                return None;
            }
            (wi, pdf_m * (1.0 - f) * jacobian, scale)
        };
        if uc <= f && wi.z <= 0.0 {
            return None;
        }
        // f |cos θi| / pdf = G1(wi, m) (times the radiance scaling): D, F and G1(wo, m)
        // cancel against the visible normals' density and the lobe choice (up to the masking
        // ratio, see `microfacet`).
        let g1 = self.d.smith_g1(wi, m) * self.d.masking_ratio(wo, m);
        if g1 <= 0.0 || pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        Some(LocalSample {
            wi,
            weight: luxest_io::color::Rgb::splat(g1 * scale),
            pdf,
            delta: false,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::super::{eval_transport, sample, Transport};
    use super::*;
    use crate::sampling::Rng;
    use crate::scene::{Material, Microfacet, MicrofacetDistribution};
    use luxest_io::chi2::{ChiSquareTest, Discrete};

    fn rough(distribution: MicrofacetDistribution, alpha: f64, ior: f64) -> Material {
        Material::RoughDielectric {
            ior,
            roughness: Microfacet {
                distribution,
                alpha,
            },
        }
    }

    /// The rough dielectrics' chi-square tests: each from outside, inside, grazing, and with
    /// a tilted shading normal.
    const SAMPLING_TESTS: usize = 3 * 4;

    fn assert_sampling(m: &Material, seed: u64) {
        let tilted = Vec3::new(0.4, 0.0, 1.0);
        let cases = [
            (Vec3::new(0.3, 0.1, 0.9), UP),
            (Vec3::new(0.5, 0.3, -0.8), UP),
            (Vec3::new(0.97, 0.0, 0.25), UP),
            (Vec3::new(-0.5, 0.2, 0.6), tilted),
        ];
        assert_sampling_matches_pdf(m, &cases, seed, SAMPLING_TESTS, 1e-9);
    }

    #[test]
    fn ggx_dielectric_sampling_matches_its_density() {
        assert_sampling(&rough(MicrofacetDistribution::Ggx, 0.3, 1.5), 80);
    }

    #[test]
    fn beckmann_dielectric_sampling_matches_its_density() {
        assert_sampling(&rough(MicrofacetDistribution::Beckmann, 0.25, 1.33), 81);
    }

    #[test]
    fn dense_ggx_dielectric_sampling_matches_its_density() {
        // Strong total internal reflection from inside.
        assert_sampling(&rough(MicrofacetDistribution::Ggx, 0.5, 2.4), 82);
    }

    /// In flux transport a dielectric conserves energy: reflected plus transmitted flux by
    /// sampling equals the quadrature of `eval` over the sphere, at most 1 (the rest is the
    /// single-scattering model's loss). In radiance transport the transmitted part is scaled
    /// by 1/η².
    fn assert_energy(m: &Material, seed: u64) {
        for (wo, mode) in [
            (at_cos(0.8), Transport::Flux),
            (at_cos(0.35), Transport::Radiance),
            (-at_cos(0.9), Transport::Flux),
            (-at_cos(0.5), Transport::Radiance),
        ] {
            let mc = albedo_mc(m, wo, 50_000, seed, mode);
            let quad = albedo_quadrature(m, wo, 150, mode);
            assert_agrees(&format!("{m:?} wo {wo:?} {mode:?}"), mc, quad, 4.0, 3e-3);
            if mode == Transport::Flux {
                assert!(mc.0 .0[0] <= 1.0 + 3.0 * mc.1 .0[0], "albedo {:?}", mc.0);
            }
        }
    }

    #[test]
    fn ggx_dielectric_conserves_energy() {
        assert_energy(&rough(MicrofacetDistribution::Ggx, 0.3, 1.5), 83);
    }

    #[test]
    fn beckmann_dielectric_conserves_energy() {
        assert_energy(&rough(MicrofacetDistribution::Beckmann, 0.3, 1.33), 84);
    }

    /// Reflection is reciprocal; transmission's radiance BSDF is the adjoint of its flux BSDF:
    /// f_radiance(wo, wi) = f_flux(wi, wo) (Veach's thesis, §5.2).
    #[test]
    fn rough_dielectric_radiance_is_the_adjoint_of_flux() {
        for m in [
            rough(MicrofacetDistribution::Ggx, 0.3, 1.5),
            rough(MicrofacetDistribution::Beckmann, 0.4, 1.33),
        ] {
            let mut r = Rng::new(85, 0);
            let mut transmitted = 0;
            for _ in 0..400 {
                // Pairs in the lobes: b sampled from a.
                let a = crate::sampling::uniform_sphere(r.next_f64(), r.next_f64());
                let Some(s) = sample(
                    &m,
                    a,
                    UP,
                    UP,
                    r.next_2d(),
                    r.next_f64(),
                    Transport::Radiance,
                ) else {
                    continue;
                };
                let b = s.wi;
                let f = eval_transport(&m, a, b, UP, UP, Transport::Radiance).0[0];
                let g = eval_transport(&m, b, a, UP, UP, Transport::Flux).0[0];
                assert!(relative(f, g) < 1e-10, "{a:?} {b:?}: {f} vs {g}");
                transmitted += usize::from(a.z * b.z < 0.0 && f > 0.0);
            }
            assert!(transmitted > 100);
        }
    }

    /// The thin sheet: reflection with probability R' = 2R / (1 + R), transmission straight
    /// through otherwise, every weight 1 (R + T = 1: nothing absorbed), from either side.
    #[test]
    fn thin_dielectric_reflects_its_summed_reflectance_and_absorbs_nothing() {
        // Normal incidence on glass: R = 0.04, R' = 0.08 / 1.04.
        assert!((thin_reflectance(1.0, 1.5) - 0.08 / 1.04).abs() < 1e-12);
        let m = Material::ThinDielectric { ior: 1.5 };
        let cases = [
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::new(0.3, 0.2, -0.9),
            at_cos(0.1),
        ];
        for (k, wo) in cases.into_iter().enumerate() {
            let wo = wo.try_normalize().unwrap();
            let r = thin_reflectance(wo.z, 1.5);
            let mut rng = Rng::new(86, k as u64);
            ChiSquareTest::new(Discrete(2))
                .samples(20_000)
                .tests(cases.len())
                .run(
                    || {
                        let s = sample(
                            &m,
                            wo,
                            UP,
                            UP,
                            rng.next_2d(),
                            rng.next_f64(),
                            Transport::Radiance,
                        )
                        .expect("a thin sheet never absorbs");
                        assert!(s.delta && s.weight == luxest_io::color::Rgb::WHITE);
                        let reflected = s.wi.z * wo.z > 0.0;
                        let expected = if reflected {
                            Vec3::new(-wo.x, -wo.y, wo.z)
                        } else {
                            -wo
                        };
                        assert!((s.wi - expected).length() < 1e-12);
                        assert!((s.pdf - if reflected { r } else { 1.0 - r }).abs() < 1e-12);
                        Some(usize::from(!reflected))
                    },
                    |lobe| [r, 1.0 - r][lobe],
                )
                .unwrap();
        }
    }
}
