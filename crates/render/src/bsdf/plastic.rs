//! Plastics: a diffuse base under a dielectric coating of relative index η, Mitsuba 3's
//! `plastic` (smooth coating: a delta reflection lobe) and `roughplastic` (microfacet coating).
//!
//! Light refracted into the coating scatters diffusely at the base, and part of it is reflected
//! back down by the coating from inside (internal reflectance R_i, Mitsuba's `fdr_int`):
//! summed over these bounces the base's reflectance ρ becomes ρ / (1 − R_i) (Mitsuba's default)
//! or, with `nonlinear`, ρ / (1 − ρ R_i) (each bounce absorbed again by the base: darker, more
//! saturated). The diffuse lobe is then
//! f_d = ρ' / π · η⁻² · T(wo) · T(wi), with T = 1 − F for the smooth coating and the rough
//! coating's tabulated directional transmittance for the rough one; the coating's own lobe is
//! specular_reflectance · F (a delta reflection, or the microfacet lobe F D G / (4 cos cos)).
//!
//! The lobe is chosen with Mitsuba's probabilities: specular ∝ F(wo) s̄, diffuse ∝ (1 − F(wo))
//! (1 − s̄), where s̄ = mean(specular) / (mean(diffuse) + mean(specular)) over the RGB channels
//! (smooth); the rough plastic uses 1 − T(wo) for F(wo).
//!
//! The rough plastic's T(cos θ) and R_i are Mitsuba's quadratures ([`super::microfacet`]): T at
//! 64 cosines in [0, 1], interpolated linearly, and R_i = 2 mean(R(μ) μ) over the same cosines.
//! They depend on (distribution, α, η) only and are computed once per process for each
//! ([`tables`]). Directions are in the local frame of the surface (+z the normal on `wo`'s
//! side).

use super::microfacet::{
    fresnel, quadrature_nodes, reflect, reflectance, transmittance, Distribution,
};
use super::LocalSample;
use crate::scene::{Microfacet, MicrofacetDistribution};
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use std::cell::RefCell;
use std::f64::consts::PI;
use std::sync::{Arc, Mutex};

/// Cosines at which the rough coating's transmittance is tabulated (Mitsuba's
/// `MI_ROUGH_TRANSMITTANCE_RES`).
pub const TRANSMITTANCE_RES: usize = 64;

/// Hemispherical average of a smooth dielectric's Fresnel reflectance for light from a uniform
/// (cosine-weighted) diffuse field, relative index `eta`: Mitsuba's
/// `fresnel_diffuse_reflectance`, fits by d'Eon and Irving (η < 1) and Egan and Hilgeman (η ≥ 1).
pub fn fresnel_diffuse_reflectance(eta: f64) -> f64 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        // Horner's scheme in 1/η.
        [0.919317, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881]
            .iter()
            .rev()
            .fold(0.0, |acc, c| acc * inv + c)
    }
}

/// The rough coating's tables ([`tables`]).
#[derive(Debug)]
pub struct Tables {
    /// Directional transmittance into the coating at cos θ = max(1e-6, i / 63).
    pub external_transmittance: [f64; TRANSMITTANCE_RES],
    /// The coating's internal reflectance R_i (cosine-weighted hemispherical average).
    pub internal_reflectance: f64,
}

impl Tables {
    fn compute(d: &Distribution, eta: f64) -> Tables {
        let mut external_transmittance = [0.0; TRANSMITTANCE_RES];
        let mut internal = 0.0;
        let (outer, inner) = (quadrature_nodes(eta), quadrature_nodes(1.0 / eta));
        for (i, t) in external_transmittance.iter_mut().enumerate() {
            let mu = (i as f64 / (TRANSMITTANCE_RES - 1) as f64).max(1e-6);
            let wi = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            *t = transmittance(d, wi, eta, &outer);
            internal += reflectance(d, wi, 1.0 / eta, &inner) * mu;
        }
        Tables {
            external_transmittance,
            internal_reflectance: 2.0 * internal / TRANSMITTANCE_RES as f64,
        }
    }

    /// The transmittance at cosine `cos` (linear interpolation, as Mitsuba's `lerp_gather`).
    pub fn transmittance(&self, cos: f64) -> f64 {
        let x = cos * (TRANSMITTANCE_RES - 1) as f64;
        let i = (x as usize).min(TRANSMITTANCE_RES - 2);
        let (v0, v1) = (
            self.external_transmittance[i],
            self.external_transmittance[i + 1],
        );
        v0 + (v1 - v0) * (x - i as f64)
    }
}

type Key = (MicrofacetDistribution, u64, u64);

static TABLES: Mutex<Vec<(Key, Arc<Tables>)>> = Mutex::new(Vec::new());

thread_local! {
    /// This thread's copy of the references in [`TABLES`]: the renderers' threads look tables
    /// up without a lock.
    static LOCAL: RefCell<Vec<(Key, Arc<Tables>)>> = const { RefCell::new(Vec::new()) };
}

/// The tables of a rough coating, computed at the first request in the process and shared.
pub fn tables(r: &Microfacet, eta: f64) -> Arc<Tables> {
    let d = Distribution::new(r);
    let key = (d.kind, d.alpha.to_bits(), eta.to_bits());
    LOCAL.with(|local| {
        if let Some((_, t)) = local.borrow().iter().find(|(k, _)| *k == key) {
            return t.clone();
        }
        let t = {
            let mut all = TABLES.lock().unwrap_or_else(|e| e.into_inner());
            match all.iter().find(|(k, _)| *k == key) {
                Some((_, t)) => t.clone(),
                None => {
                    let t = Arc::new(Tables::compute(&d, eta));
                    all.push((key, t.clone()));
                    t
                }
            }
        };
        local.borrow_mut().push((key, t.clone()));
        t
    })
}

/// The parameters of `Material::Plastic`.
pub struct Plastic<'a> {
    pub diffuse_reflectance: &'a Rgb,
    pub specular_reflectance: &'a Rgb,
    pub eta: f64,
    pub nonlinear: bool,
    pub roughness: Option<&'a Microfacet>,
}

fn mean(c: &Rgb) -> f64 {
    (c.0[0] + c.0[1] + c.0[2]) / 3.0
}

impl Plastic<'_> {
    /// Mitsuba's `specular_sampling_weight`: mean(specular) / (mean(diffuse) + mean(specular)).
    pub fn specular_sampling_weight(&self) -> f64 {
        let (d, s) = (
            mean(self.diffuse_reflectance),
            mean(self.specular_reflectance),
        );
        if d + s > 0.0 {
            s / (d + s)
        } else {
            0.5
        }
    }

    /// The base's reflectance with the internal bounces: ρ / (1 − R_i) or ρ / (1 − ρ R_i).
    fn diffuse(&self, internal_reflectance: f64) -> Rgb {
        Rgb(self.diffuse_reflectance.0.map(|rho| {
            rho / (1.0
                - if self.nonlinear {
                    rho * internal_reflectance
                } else {
                    internal_reflectance
                })
        }))
    }

    /// The probability of sampling the coating's lobe, given the coating's reflectance at wo.
    fn specular_probability(&self, coating_reflectance: f64) -> f64 {
        let ssw = self.specular_sampling_weight();
        let ps = coating_reflectance * ssw;
        let pd = (1.0 - coating_reflectance) * (1.0 - ssw);
        if ps + pd > 0.0 {
            ps / (ps + pd)
        } else {
            0.0
        }
    }

    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::BLACK;
        }
        let inv_eta2 = 1.0 / (self.eta * self.eta);
        match self.roughness {
            None => {
                let fi = fresnel(wo.z, self.eta).0;
                let fo = fresnel(wi.z, self.eta).0;
                let ri = fresnel_diffuse_reflectance(1.0 / self.eta);
                self.diffuse(ri) * (inv_eta2 * (1.0 - fi) * (1.0 - fo) / PI)
            }
            Some(r) => {
                let t = tables(r, self.eta);
                let d = Distribution::new(r);
                let h = (wo + wi)
                    .try_normalize()
                    .unwrap_or(Vec3::new(0.0, 0.0, 1.0));
                let spec =
                    fresnel(wo.dot(h), self.eta).0 * d.d(h) * d.g(wo, wi, h) / (4.0 * wo.z * wi.z);
                let diff = inv_eta2 * t.transmittance(wo.z) * t.transmittance(wi.z) / PI;
                *self.specular_reflectance * spec + self.diffuse(t.internal_reflectance) * diff
            }
        }
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f64 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        match self.roughness {
            None => (1.0 - self.specular_probability(fresnel(wo.z, self.eta).0)) * wi.z / PI,
            Some(r) => {
                let t = tables(r, self.eta);
                let ps = self.specular_probability(1.0 - t.transmittance(wo.z));
                let d = Distribution::new(r);
                let h = (wo + wi)
                    .try_normalize()
                    .unwrap_or(Vec3::new(0.0, 0.0, 1.0));
                let spec = d.d(h) * d.smith_g1_sampled(wo, h) / (4.0 * wo.z);
                ps * spec + (1.0 - ps) * wi.z / PI
            }
        }
    }

    pub fn sample(&self, wo: Vec3, u: (f64, f64), uc: f64) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        match self.roughness {
            None => {
                let fi = fresnel(wo.z, self.eta).0;
                let ps = self.specular_probability(fi);
                if uc < ps {
                    return Some(LocalSample {
                        wi: Vec3::new(-wo.x, -wo.y, wo.z),
                        weight: *self.specular_reflectance * (fi / ps),
                        pdf: ps,
                        delta: true,
                    });
                }
                let wi = crate::sampling::cosine_hemisphere(u.0, u.1);
                if wi.z <= 0.0 {
                    return None;
                }
                let fo = fresnel(wi.z, self.eta).0;
                let ri = fresnel_diffuse_reflectance(1.0 / self.eta);
                let pd = 1.0 - ps;
                Some(LocalSample {
                    wi,
                    weight: self.diffuse(ri)
                        * ((1.0 - fi) * (1.0 - fo) / (self.eta * self.eta * pd)),
                    pdf: pd * wi.z / PI,
                    delta: false,
                })
            }
            Some(r) => {
                let t = tables(r, self.eta);
                let ps = self.specular_probability(1.0 - t.transmittance(wo.z));
                let wi = if uc < ps {
                    reflect(wo, Distribution::new(r).sample(wo, u).0)
                } else {
                    crate::sampling::cosine_hemisphere(u.0, u.1)
                };
                let pdf = self.pdf(wo, wi);
                if wi.z <= 0.0 || pdf.is_nan() || pdf <= 0.0 {
                    return None;
                }
                Some(LocalSample {
                    wi,
                    weight: self.eval(wo, wi) * (wi.z / pdf),
                    pdf,
                    delta: false,
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::super::{eval, Transport};
    use super::*;
    use crate::scene::Material;

    fn plastic(nonlinear: bool, roughness: Option<(MicrofacetDistribution, f64)>) -> Material {
        Material::Plastic {
            diffuse_reflectance: Rgb([0.7, 0.4, 0.1]),
            specular_reflectance: Rgb([1.0, 0.9, 0.8]),
            ior: 1.5,
            nonlinear,
            roughness: roughness.map(|(distribution, alpha)| Microfacet {
                distribution,
                alpha,
            }),
        }
    }

    /// The plastics' chi-square tests: each material from four directions, the shading normal
    /// tilted in the last. The smooth coating's delta samples count as rejected.
    const SAMPLING_TESTS: usize = 4 * 4;

    fn assert_sampling(m: &Material, seed: u64) {
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
    fn smooth_plastic_sampling_matches_its_density() {
        assert_sampling(&plastic(false, None), 50);
    }

    #[test]
    fn ggx_plastic_sampling_matches_its_density() {
        assert_sampling(
            &plastic(false, Some((MicrofacetDistribution::Ggx, 0.2))),
            51,
        );
    }

    #[test]
    fn beckmann_plastic_sampling_matches_its_density() {
        assert_sampling(
            &plastic(true, Some((MicrofacetDistribution::Beckmann, 0.4))),
            52,
        );
    }

    #[test]
    fn diffuse_only_plastic_sampling_matches_its_density() {
        // No specular reflectance: the coating's lobe is never chosen.
        let m = Material::Plastic {
            diffuse_reflectance: Rgb::splat(0.5),
            specular_reflectance: Rgb::BLACK,
            ior: 1.5,
            nonlinear: false,
            roughness: Some(Microfacet {
                distribution: MicrofacetDistribution::Ggx,
                alpha: 0.3,
            }),
        };
        assert_sampling(&m, 53);
    }

    /// The smooth plastic's directional albedo in closed form: the coating reflects s F(θo),
    /// the base returns ρ' η⁻² (1 − F(θo)) ∫ (1 − F(μ)) 2μ dμ (the integral by the midpoint
    /// rule), ρ' = ρ / (1 − R_i) or ρ / (1 − ρ R_i).
    #[test]
    fn smooth_plastic_albedo_is_its_closed_form() {
        let eta = 1.5;
        let n = 200_000;
        let transmitted: f64 = (0..n)
            .map(|i| {
                let mu = (i as f64 + 0.5) / n as f64;
                (1.0 - fresnel(mu, eta).0) * 2.0 * mu / n as f64
            })
            .sum();
        let ri = fresnel_diffuse_reflectance(1.0 / eta);
        for (k, nonlinear) in [false, true].into_iter().enumerate() {
            let m = plastic(nonlinear, None);
            for cos in [1.0, 0.5, 0.15] {
                let wo = at_cos(cos);
                let fo = fresnel(cos, eta).0;
                let expected = Rgb(std::array::from_fn(|c| {
                    let rho = [0.7, 0.4, 0.1][c];
                    let rho_eff = rho / (1.0 - if nonlinear { rho * ri } else { ri });
                    [1.0, 0.9, 0.8][c] * fo + rho_eff * (1.0 - fo) * transmitted / (eta * eta)
                }));
                let mc = albedo_mc(&m, wo, 100_000, 60 + k as u64, Transport::Radiance);
                assert_agrees(
                    &format!("nonlinear {nonlinear}, cos {cos}"),
                    mc,
                    expected,
                    4.0,
                    1e-9,
                );
                for c in 0..3 {
                    assert!(expected.0[c] <= 1.0);
                }
            }
        }
    }

    /// The rough plastic's albedo by sampling equals the quadrature of `eval`, stays below 1,
    /// and `eval` is reciprocal.
    fn assert_energy_and_reciprocity(m: &Material, seed: u64) {
        for cos in [0.9, 0.3] {
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
    fn smooth_plastic_is_reciprocal() {
        let m = plastic(true, None);
        let mut r = crate::sampling::Rng::new(70, 0);
        for _ in 0..200 {
            let a = crate::sampling::uniform_sphere(r.next_f64(), r.next_f64());
            let b = crate::sampling::uniform_sphere(r.next_f64(), r.next_f64());
            let (fa, fb) = (eval(&m, a, b, UP, UP), eval(&m, b, a, UP, UP));
            for c in 0..3 {
                assert!(relative(fa.0[c], fb.0[c]) < 1e-12, "{fa:?} vs {fb:?}");
            }
        }
    }

    #[test]
    fn ggx_plastic_conserves_energy_and_is_reciprocal() {
        assert_energy_and_reciprocity(
            &plastic(false, Some((MicrofacetDistribution::Ggx, 0.3))),
            71,
        );
    }

    #[test]
    fn beckmann_plastic_conserves_energy_and_is_reciprocal() {
        assert_energy_and_reciprocity(
            &plastic(true, Some((MicrofacetDistribution::Beckmann, 0.25))),
            72,
        );
    }

    /// A nearly smooth coating's tables approach the smooth interface's: transmittance 1 − F(μ),
    /// and internal reflectance Mitsuba's sum over its 64 cosines of F(μ, 1/η) μ, which is
    /// 2 ∫ F(μ, 1/η) μ dμ (midpoint rule) within 2 %.
    #[test]
    fn tables_of_a_smooth_coating_are_the_fresnel_averages() {
        let eta = 1.5;
        let t = tables(
            &Microfacet {
                distribution: MicrofacetDistribution::Ggx,
                alpha: 1e-3,
            },
            eta,
        );
        for i in [8, 32, 63] {
            let mu = i as f64 / 63.0;
            let smooth = 1.0 - fresnel(mu, eta).0;
            assert!(
                (t.external_transmittance[i] - smooth).abs() < 1e-3,
                "μ {mu}: {} vs {smooth}",
                t.external_transmittance[i]
            );
        }
        // Mitsuba's sum: 2 × the mean of F μ over the 64 cosines (1.5 % below the integral).
        let sum: f64 = (0..TRANSMITTANCE_RES)
            .map(|i| {
                let mu = (i as f64 / 63.0).max(1e-6);
                2.0 * fresnel(mu, 1.0 / eta).0 * mu / TRANSMITTANCE_RES as f64
            })
            .sum();
        assert!(
            (t.internal_reflectance - sum).abs() < 2e-3 * sum,
            "{} vs {sum}",
            t.internal_reflectance
        );
        let n = 100_000;
        let ri: f64 = (0..n)
            .map(|i| {
                let mu = (i as f64 + 0.5) / n as f64;
                fresnel(mu, 1.0 / eta).0 * 2.0 * mu / n as f64
            })
            .sum();
        assert!((sum - ri).abs() < 0.02 * ri, "{sum} vs {ri}");
        // Mitsuba's fit of the same average.
        assert!((fresnel_diffuse_reflectance(1.0 / eta) - ri).abs() < 0.002 * ri);
    }
}
