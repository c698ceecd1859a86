//! Scattering by the four material models of the scene format, shared by every estimator.
//!
//! Directions point away from the surface: `wo` towards where the path came from, `wi` the new
//! direction. `ng` is the unit geometric normal (the front side), `ns` the unit shading normal.
//! Reflection is two-sided: the frame is flipped to the side `wo` lies on. The dielectric uses
//! the front side to tell inside from outside (`ior` is the inside's index).
//!
//! `weight` of a sample is `f |cos θi| / pdf` (for delta lobes, the lobe's weight), so a path
//! throughput is a running product of weights.

use crate::scene::Material;
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use std::f64::consts::PI;

/// Whether the path carries radiance (from the camera) or importance/flux (from the lights):
/// refraction scales radiance by (η_o/η_i)² but not flux.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    Radiance,
    Flux,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    pub wi: Vec3,
    pub weight: Rgb,
    /// Solid-angle density; for delta lobes the discrete probability of the lobe.
    pub pdf: f64,
    pub delta: bool,
}

pub fn reflect(w: Vec3, n: Vec3) -> Vec3 {
    n * (2.0 * w.dot(n)) - w
}

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

/// The interface of a dielectric of index `ior` (inside relative to the side `ng` points to),
/// as [`sample`] sees it.
pub fn dielectric_side(wo: Vec3, ng: Vec3, ns: Vec3, ior: f64) -> DielectricSide {
    let (n, eta) = if wo.dot(ng) > 0.0 {
        (ns, ior)
    } else {
        (-ns, 1.0 / ior)
    };
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

pub fn is_delta(m: &Material) -> bool {
    matches!(m, Material::Mirror { .. } | Material::Dielectric { .. })
}

/// The albedo that Russian roulette and diffuse connections use: the reflectance of the
/// diffuse part (Lambertian reflectance, Glossy diffuse), zero for delta materials.
pub fn diffuse_reflectance(m: &Material) -> Rgb {
    match m {
        Material::Lambertian { reflectance } => *reflectance,
        Material::Glossy { diffuse, .. } => *diffuse,
        _ => Rgb::BLACK,
    }
}

/// Frame oriented to the side of `wo`: (geometric, shading) normals.
fn facing(wo: Vec3, ng: Vec3, ns: Vec3) -> (Vec3, Vec3) {
    if wo.dot(ng) < 0.0 {
        (-ng, -ns)
    } else {
        (ng, ns)
    }
}

/// The geometric normal `ng` of a two-sided surface turned to the side of `wo` (the normal
/// every BSDF here scatters about).
#[inline]
pub fn facing_normal(wo: Vec3, ng: Vec3) -> Vec3 {
    facing(wo, ng, ng).0
}

fn ggx_d(n_dot_h: f64, alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let c2 = n_dot_h * n_dot_h;
    let t = c2 * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

fn smith_g1(n_dot_v: f64, alpha: f64) -> f64 {
    let c2 = n_dot_v * n_dot_v;
    let tan2 = (1.0 - c2).max(0.0) / c2.max(1e-300);
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// BSDF value f(wo, wi) (per sr, without the cosine); zero for delta materials.
pub fn eval(m: &Material, wo: Vec3, wi: Vec3, ng: Vec3, ns: Vec3) -> Rgb {
    let (g, n) = facing(wo, ng, ns);
    if wi.dot(g) <= 0.0 {
        return Rgb::BLACK;
    }
    match m {
        Material::Lambertian { reflectance } => *reflectance * (1.0 / PI),
        Material::Glossy {
            diffuse,
            specular,
            roughness,
        } => {
            let (co, ci) = (wo.dot(n), wi.dot(n));
            if co <= 0.0 || ci <= 0.0 {
                return Rgb::BLACK;
            }
            let alpha = roughness * roughness;
            let h = match (wo + wi).try_normalize() {
                Some(h) => h,
                None => return *diffuse * (1.0 / PI),
            };
            let spec = ggx_d(h.dot(n), alpha) * smith_g1(co, alpha) * smith_g1(ci, alpha)
                / (4.0 * co * ci);
            *diffuse * (1.0 / PI) + *specular * spec
        }
        Material::Mirror { .. } | Material::Dielectric { .. } => Rgb::BLACK,
    }
}

fn glossy_lobe_probability(diffuse: &Rgb, specular: &Rgb) -> Option<f64> {
    let (d, s) = (diffuse.luminance(), specular.luminance());
    (d + s > 0.0).then(|| d / (d + s))
}

/// Solid-angle density with which [`sample`] produces `wi`; zero for delta materials.
pub fn pdf(m: &Material, wo: Vec3, wi: Vec3, ng: Vec3, ns: Vec3) -> f64 {
    let (g, n) = facing(wo, ng, ns);
    if wi.dot(g) <= 0.0 {
        return 0.0;
    }
    match m {
        Material::Lambertian { .. } => wi.dot(n).max(0.0) / PI,
        Material::Glossy {
            diffuse,
            specular,
            roughness,
        } => {
            let Some(pd) = glossy_lobe_probability(diffuse, specular) else {
                return 0.0;
            };
            // [`sample`] rejects a direction below the shading normal's horizon (where `eval` is
            // zero), even above the geometric one: the specular lobe's density there is lost.
            if wi.dot(n) <= 0.0 {
                return 0.0;
            }
            let alpha = roughness * roughness;
            let diff = wi.dot(n) / PI;
            let spec = match (wo + wi).try_normalize() {
                Some(h) if h.dot(n) > 0.0 && wo.dot(h) > 0.0 => {
                    ggx_d(h.dot(n), alpha) * h.dot(n) / (4.0 * wo.dot(h))
                }
                _ => 0.0,
            };
            pd * diff + (1.0 - pd) * spec
        }
        Material::Mirror { .. } | Material::Dielectric { .. } => 0.0,
    }
}

/// `(eval, pdf)` in one pass (next-event estimation with MIS needs both).
pub fn eval_and_pdf(m: &Material, wo: Vec3, wi: Vec3, ng: Vec3, ns: Vec3) -> (Rgb, f64) {
    match m {
        Material::Lambertian { reflectance } => {
            let (g, n) = facing(wo, ng, ns);
            if wi.dot(g) <= 0.0 {
                return (Rgb::BLACK, 0.0);
            }
            (*reflectance * (1.0 / PI), wi.dot(n).max(0.0) / PI)
        }
        _ => (eval(m, wo, wi, ng, ns), pdf(m, wo, wi, ng, ns)),
    }
}

/// Local direction around unit `n` from tangent-space coordinates.
fn to_world(n: Vec3, local: Vec3) -> Vec3 {
    let (t, b) = n.orthonormal_basis();
    t * local.x + b * local.y + n * local.z
}

/// Samples a new direction. `u` picks the direction, `uc` the lobe. `None` when the path
/// cannot continue (absorbed, or sampled below the geometric surface).
pub fn sample(
    m: &Material,
    wo: Vec3,
    ng: Vec3,
    ns: Vec3,
    u: (f64, f64),
    uc: f64,
    mode: Transport,
) -> Option<BsdfSample> {
    match m {
        Material::Lambertian { reflectance } => {
            let (g, n) = facing(wo, ng, ns);
            let wi = to_world(n, crate::sampling::cosine_hemisphere(u.0, u.1));
            if wi.dot(g) <= 0.0 {
                return None;
            }
            Some(BsdfSample {
                wi,
                weight: *reflectance,
                pdf: wi.dot(n) / PI,
                delta: false,
            })
        }
        Material::Mirror { reflectance } => {
            let (g, n) = facing(wo, ng, ns);
            let wi = reflect(wo, n);
            (wi.dot(g) > 0.0).then_some(BsdfSample {
                wi,
                weight: *reflectance,
                pdf: 1.0,
                delta: true,
            })
        }
        Material::Dielectric { ior } => {
            let DielectricSide {
                n,
                eta,
                cos_o,
                reflectance: f,
                cos_t,
            } = dielectric_side(wo, ng, ns, *ior);
            if uc < f {
                let wi = reflect(wo, n);
                return Some(BsdfSample {
                    wi,
                    weight: Rgb::WHITE,
                    pdf: f,
                    delta: true,
                });
            }
            // Refraction: wi = -wo/eta + (cos_o/eta - cos_t) n.
            let wi = (-wo) * (1.0 / eta) + n * (cos_o / eta - cos_t);
            let wi = wi.try_normalize()?;
            let scale = match mode {
                // Radiance arriving from the wi side is compressed into the denser medium.
                Transport::Radiance => 1.0 / (eta * eta),
                Transport::Flux => 1.0,
            };
            Some(BsdfSample {
                wi,
                weight: Rgb::splat(scale),
                pdf: 1.0 - f,
                delta: true,
            })
        }
        Material::Glossy {
            diffuse,
            specular,
            roughness,
        } => {
            let pd = glossy_lobe_probability(diffuse, specular)?;
            let (g, n) = facing(wo, ng, ns);
            let wi = if uc < pd {
                to_world(n, crate::sampling::cosine_hemisphere(u.0, u.1))
            } else {
                // GGX normal distribution D(h) cos θh: tan²θh = α² u / (1 − u).
                let alpha = roughness * roughness;
                let tan2 = alpha * alpha * u.0 / (1.0 - u.0).max(1e-300);
                let cos_h = 1.0 / (1.0 + tan2).sqrt();
                let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
                let phi = 2.0 * PI * u.1;
                let h = to_world(n, Vec3::new(sin_h * phi.cos(), sin_h * phi.sin(), cos_h));
                reflect(wo, h)
            };
            if wi.dot(g) <= 0.0 || wi.dot(n) <= 0.0 {
                return None;
            }
            let p = pdf(m, wo, wi, ng, ns);
            if p.is_nan() || p <= 0.0 {
                return None;
            }
            let f = eval(m, wo, wi, ng, ns);
            Some(BsdfSample {
                wi,
                weight: f * (wi.dot(n) / p),
                pdf: p,
                delta: false,
            })
        }
    }
}

/// [`sample`] on a flat-shaded surface (shading normal = geometric normal `ng`), drawing its
/// uniform numbers from `rng`: the 2D direction sample, then the lobe choice — except for a
/// Lambertian surface, which has one lobe and draws no third number (in the path tracer's first
/// bounces every draw is an Owen-scrambled Sobol dimension, which costs hashing).
#[inline]
pub fn sample_flat(
    m: &Material,
    wo: Vec3,
    ng: Vec3,
    rng: &mut impl crate::sampling::Sampler,
    mode: Transport,
) -> Option<BsdfSample> {
    let u = rng.next_2d();
    let uc = match m {
        Material::Lambertian { .. } => 0.0,
        _ => rng.next_f64(),
    };
    sample(m, wo, ng, ng, u, uc, mode)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use luxest_io::chi2::{ChiSquareTest, Discrete, Sphere};

    const UP: Vec3 = Vec3::new(0.0, 0.0, 1.0);

    fn glossy() -> Material {
        Material::Glossy {
            diffuse: Rgb::splat(0.2),
            specular: Rgb::splat(0.7),
            roughness: 0.5,
        }
    }

    #[test]
    fn lambertian_weight_is_the_reflectance_and_two_sided() {
        let m = Material::Lambertian {
            reflectance: Rgb([0.2, 0.5, 0.9]),
        };
        let mut r = Rng::new(1, 0);
        for wo in [Vec3::new(0.3, 0.1, 0.9), Vec3::new(0.3, 0.1, -0.9)] {
            let wo = wo.try_normalize().unwrap();
            let s = sample(
                &m,
                wo,
                UP,
                UP,
                r.next_2d(),
                r.next_f64(),
                Transport::Radiance,
            )
            .unwrap();
            assert_eq!(s.weight, Rgb([0.2, 0.5, 0.9]));
            assert!(s.wi.z * wo.z > 0.0, "reflection stays on the side of wo");
            let f = eval(&m, wo, s.wi, UP, UP);
            assert!((f.0[1] - 0.5 / PI).abs() < 1e-15);
        }
    }

    /// Directions [`sample`]d from `m` as seen from each `wo` (geometric normal [`UP`], shading
    /// normal `ns`) against [`pdf`] over the whole sphere, one chi-square test each; the density
    /// a sample reports must be `pdf`'s too.
    fn assert_sampling_matches_pdf(m: &Material, cases: &[(Vec3, Vec3)], seed: u64) {
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
                let p = pdf(m, wo, s.wi, UP, ns);
                assert!((s.pdf - p).abs() <= 1e-12 * p, "{} vs {p}", s.pdf);
                Some(s.wi)
            };
            ChiSquareTest::new(Sphere)
                .tests(cases.len())
                .run(&mut draw, |wi| pdf(m, wo, wi, UP, ns))
                .unwrap_or_else(|r| panic!("wo {wo:?}, ns {ns:?}: {r:?}"));
        }
    }

    #[test]
    fn lambertian_sampling_matches_its_density() {
        let m = Material::Lambertian {
            reflectance: Rgb::splat(0.5),
        };
        let tilted = Vec3::new(0.4, 0.0, 1.0);
        let cases = [
            (Vec3::new(0.3, 0.1, 0.9), UP),
            (Vec3::new(0.3, 0.1, -0.9), UP),
            (Vec3::new(0.99, 0.0, 0.05), UP),
            // A shading normal off the geometric one: directions below the surface are lost;
            // and `wo` between the two horizons.
            (Vec3::new(-0.5, 0.2, 0.6), tilted),
            (Vec3::new(-0.95, 0.1, 0.2), tilted),
        ];
        assert_sampling_matches_pdf(&m, &cases, 11);
    }

    #[test]
    fn glossy_sampling_matches_its_density() {
        let rough = glossy();
        let smoother = Material::Glossy {
            diffuse: Rgb::splat(0.1),
            specular: Rgb::splat(0.8),
            roughness: 0.3,
        };
        let tilted = Vec3::new(0.4, 0.0, 1.0);
        let cases = [
            (Vec3::new(0.5, 0.0, 0.8), UP),
            (Vec3::new(0.5, 0.3, -0.8), UP),
            (Vec3::new(0.98, 0.0, 0.2), UP),
            // The shading normal's horizon cuts the specular lobe above the geometric one: the
            // cut part has no density (the last case rejects a pdf giving it one at p ≈ 1e-35).
            (Vec3::new(-0.5, 0.2, 0.6), tilted),
            (Vec3::new(-0.95, 0.1, 0.2), tilted),
            (Vec3::new(0.3, 0.0, 0.9), Vec3::new(1.0, 0.0, 1.0)),
        ];
        assert_sampling_matches_pdf(&rough, &cases, 12);
        assert_sampling_matches_pdf(&smoother, &cases[..1], 13);
    }

    #[test]
    fn dielectric_chooses_reflection_with_the_fresnel_reflectance() {
        // A delta BSDF has no density over directions: what it samples is the lobe, reflection
        // with probability F, from outside and from inside the glass.
        let m = Material::Dielectric { ior: 1.5 };
        let cases = [Vec3::new(0.8, 0.0, 0.6), Vec3::new(0.3, 0.2, -0.9)];
        for (k, wo) in cases.into_iter().enumerate() {
            let wo = wo.try_normalize().unwrap();
            let f = dielectric_side(wo, UP, UP, 1.5).reflectance;
            assert!(f > 0.0 && f < 1.0);
            let mut r = Rng::new(14, k as u64);
            ChiSquareTest::new(Discrete(2))
                .samples(20_000)
                .tests(cases.len())
                .run(
                    || {
                        let s = sample(&m, wo, UP, UP, r.next_2d(), r.next_f64(), Transport::Flux)?;
                        Some(usize::from(s.wi.z * wo.z < 0.0))
                    },
                    |lobe| [f, 1.0 - f][lobe],
                )
                .unwrap();
        }
    }

    #[test]
    fn glossy_is_reciprocal_and_bounded_by_its_reflectances() {
        let m = glossy();
        let mut r = Rng::new(6, 0);
        for _ in 0..100 {
            let a = crate::sampling::cosine_hemisphere(r.next_f64(), r.next_f64());
            let b = crate::sampling::cosine_hemisphere(r.next_f64(), r.next_f64());
            let (fa, fb) = (eval(&m, a, b, UP, UP), eval(&m, b, a, UP, UP));
            assert!((fa.0[0] - fb.0[0]).abs() <= 1e-12 * fa.0[0].abs().max(1.0));
        }
        // Directional albedo (mean weight) must not exceed diffuse + specular = 0.9.
        for cos in [1.0, 0.5, 0.1] {
            let wo = Vec3::new((1.0f64 - cos * cos).sqrt(), 0.0, cos);
            let n = 100_000;
            let mut sum = 0.0;
            for _ in 0..n {
                if let Some(s) = sample(
                    &m,
                    wo,
                    UP,
                    UP,
                    r.next_2d(),
                    r.next_f64(),
                    Transport::Radiance,
                ) {
                    sum += s.weight.0[0];
                }
            }
            let albedo = sum / n as f64;
            assert!(
                albedo > 0.2 && albedo < 0.9 + 0.01,
                "albedo {albedo} at cos {cos}"
            );
        }
    }

    #[test]
    fn dielectric_fresnel_and_refraction() {
        let (f, _) = fresnel_dielectric(1.0, 1.5);
        assert!((f - 0.04).abs() < 1e-12);
        // Total internal reflection beyond the critical angle asin(1/1.5) = 41.8 deg.
        assert_eq!(fresnel_dielectric(0.5, 1.0 / 1.5).0, 1.0);
        let m = Material::Dielectric { ior: 1.5 };
        let wo = Vec3::new(0.6, 0.0, 0.8);
        // Transmission branch: Snell's law sin θt = sin θo / 1.5.
        let s = sample(&m, wo, UP, UP, (0.5, 0.5), 0.99, Transport::Radiance).unwrap();
        assert!(s.wi.z < 0.0);
        assert!((s.wi.x.abs() - 0.6 / 1.5).abs() < 1e-12);
        assert!((s.weight.0[0] - 1.0 / 2.25).abs() < 1e-12);
        let s = sample(&m, wo, UP, UP, (0.5, 0.5), 0.99, Transport::Flux).unwrap();
        assert_eq!(s.weight, Rgb::WHITE);
        // Reflection branch.
        let s = sample(&m, wo, UP, UP, (0.5, 0.5), 0.0, Transport::Radiance).unwrap();
        assert!((s.wi - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-12);
    }

    #[test]
    fn mirror_reflects_about_the_normal() {
        let m = Material::Mirror {
            reflectance: Rgb::splat(0.9),
        };
        let wo = Vec3::new(0.6, 0.0, -0.8);
        let s = sample(&m, wo, UP, UP, (0.1, 0.2), 0.3, Transport::Flux).unwrap();
        assert!((s.wi - Vec3::new(-0.6, 0.0, -0.8)).length() < 1e-12);
        assert!(s.delta && s.weight == Rgb::splat(0.9));
    }
}
