//! Scattering by the material models of the scene format, shared by every estimator.
//!
//! Directions point away from the surface: `wo` towards where the path came from, `wi` the new
//! direction. `ng` is the unit geometric normal (the front side), `ns` the unit shading normal.
//! Reflection is two-sided: the frame is flipped to the side `wo` lies on. The dielectrics use
//! the front side to tell inside from outside (`ior` is the inside's index).
//!
//! `weight` of a sample is `f |cos θi| / pdf` (for delta lobes, the lobe's weight), so a path
//! throughput is a running product of weights.
//!
//! One file per model family, the Mitsuba 3 plugins they are named after:
//! - [`glossy`], luxest's `Glossy` (a diffuse base plus an unweighted GGX lobe);
//! - [`microfacet`], Mitsuba's GGX and Beckmann distributions, visible-normal sampling, Smith G;
//! - [`conductor`], `conductor` and `roughconductor` (complex index of refraction);
//! - [`plastic`], `plastic` and `roughplastic`;
//! - [`dielectric`], `dielectric`, `roughdielectric` and `thindielectric`;
//! - [`blend`], `blendbsdf`.
//!
//! Lambertian (`diffuse`), the ideal mirror and the smooth dielectric's sampling are here.

pub mod blend;
pub mod conductor;
pub mod dielectric;
pub mod glossy;
pub mod microfacet;
pub mod plastic;
#[cfg(test)]
mod testing;

pub use dielectric::{dielectric_side, fresnel_dielectric, DielectricSide};

use crate::scene::Material;
use conductor::Conductor;
use dielectric::Rough;
use glossy::Glossy;
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use microfacet::Distribution;
use plastic::Plastic;
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

/// A sample in a model's local frame (+z the normal on `wo`'s side), as [`BsdfSample`].
pub struct LocalSample {
    pub wi: Vec3,
    pub weight: Rgb,
    pub pdf: f64,
    pub delta: bool,
}

pub fn reflect(w: Vec3, n: Vec3) -> Vec3 {
    n * (2.0 * w.dot(n)) - w
}

/// Every lobe is a delta lobe: the material has no density over directions (`eval` and `pdf`
/// are zero everywhere), so next-event estimation and connections skip it.
/// Computes what a material's scattering looks up and computes once (a rough plastic's
/// coating tables), so that the first scattering event does not pay for it: the stages'
/// calibrations time samples after it.
pub fn prepare(m: &Material) {
    match m {
        Material::Plastic {
            roughness: Some(r),
            ior,
            ..
        } => {
            plastic::tables(r, *ior);
        }
        Material::Blend { first, second, .. } => {
            prepare(first);
            prepare(second);
        }
        _ => {}
    }
}

pub fn is_delta(m: &Material) -> bool {
    match m {
        Material::Mirror { .. } | Material::Dielectric { .. } | Material::ThinDielectric { .. } => {
            true
        }
        Material::Conductor { roughness, .. } => roughness.is_none(),
        Material::Blend { first, second, .. } => is_delta(first) && is_delta(second),
        Material::Lambertian { .. }
        | Material::Glossy { .. }
        | Material::Plastic { .. }
        | Material::RoughDielectric { .. } => false,
    }
}

/// Some lobe is a delta lobe (a smooth plastic's coating too): [`sample`] can return a delta
/// sample, so delta (specular) paths exist.
pub fn has_delta_lobe(m: &Material) -> bool {
    match m {
        Material::Plastic { roughness, .. } => roughness.is_none(),
        Material::Blend { first, second, .. } => has_delta_lobe(first) || has_delta_lobe(second),
        _ => is_delta(m),
    }
}

/// Some lobe transmits light through the surface.
pub fn transmits(m: &Material) -> bool {
    match m {
        Material::Dielectric { .. }
        | Material::RoughDielectric { .. }
        | Material::ThinDielectric { .. } => true,
        Material::Blend { first, second, .. } => transmits(first) || transmits(second),
        _ => false,
    }
}

/// Some lobe is a glossy (microfacet) lobe.
pub fn is_glossy(m: &Material) -> bool {
    match m {
        Material::Glossy { .. } | Material::RoughDielectric { .. } => true,
        Material::Conductor { roughness, .. } | Material::Plastic { roughness, .. } => {
            roughness.is_some()
        }
        Material::Blend { first, second, .. } => is_glossy(first) || is_glossy(second),
        _ => false,
    }
}

/// The albedo that Russian roulette and diffuse connections use: the reflectance of the
/// diffuse part (Lambertian reflectance, Glossy diffuse, a plastic's base, a blend's mix of its
/// materials'), zero for purely specular or glossy materials.
pub fn diffuse_reflectance(m: &Material) -> Rgb {
    match m {
        Material::Lambertian { reflectance } => *reflectance,
        Material::Glossy { diffuse, .. } => *diffuse,
        Material::Plastic {
            diffuse_reflectance,
            ..
        } => *diffuse_reflectance,
        Material::Blend {
            weight,
            first,
            second,
        } => {
            let w = weight.clamp(0.0, 1.0);
            diffuse_reflectance(first) * (1.0 - w) + diffuse_reflectance(second) * w
        }
        Material::Mirror { .. }
        | Material::Dielectric { .. }
        | Material::Conductor { .. }
        | Material::RoughDielectric { .. }
        | Material::ThinDielectric { .. } => Rgb::BLACK,
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

/// An orthonormal frame about the unit normal `n`.
#[derive(Clone, Copy)]
struct Frame {
    t: Vec3,
    b: Vec3,
    n: Vec3,
}

impl Frame {
    fn new(n: Vec3) -> Frame {
        let (t, b) = n.orthonormal_basis();
        Frame { t, b, n }
    }
    fn local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }
    fn world(&self, v: Vec3) -> Vec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

/// A reflecting model's frame: the geometric normal on `wo`'s side and the local frame about
/// the shading normal on that side.
fn reflecting(wo: Vec3, ng: Vec3, ns: Vec3) -> (Vec3, Frame) {
    let (g, n) = facing(wo, ng, ns);
    (g, Frame::new(n))
}

/// A reflecting model evaluated in its local frame; `None` (no scattering) when `wi` is below
/// the geometric surface.
fn in_reflecting_frame<T>(
    (wo, wi, ng, ns): (Vec3, Vec3, Vec3, Vec3),
    f: impl FnOnce(Vec3, Vec3) -> T,
) -> Option<T> {
    let (g, frame) = reflecting(wo, ng, ns);
    (wi.dot(g) > 0.0).then(|| f(frame.local(wo), frame.local(wi)))
}

/// The rough dielectric's interface seen from `wo` and its local frame, and whether `wi` leaves
/// on the side the local frame says (reflection above, transmission below) for the geometric
/// normal too.
fn rough_dielectric(
    wo: Vec3,
    wi: Vec3,
    (ng, ns): (Vec3, Vec3),
    ior: f64,
    roughness: &crate::scene::Microfacet,
) -> Option<(Rough, Vec3, Vec3)> {
    let (n, eta) = dielectric::side(wo, ng, ns, ior);
    let frame = Frame::new(n);
    let (wo_l, wi_l) = (frame.local(wo), frame.local(wi));
    let g = facing_normal(wo, ng);
    ((wi.dot(g) > 0.0) == (wi_l.z > 0.0)).then(|| {
        (
            Rough {
                d: Distribution::new(roughness),
                eta,
            },
            wo_l,
            wi_l,
        )
    })
}

fn conductor<'a>(eta: &'a Rgb, k: &'a Rgb, specular_reflectance: &'a Rgb) -> Conductor<'a> {
    Conductor {
        eta,
        k,
        specular_reflectance,
    }
}

/// The plastic model of `Material::Plastic`'s fields.
fn plastic<'a>(
    diffuse_reflectance: &'a Rgb,
    specular_reflectance: &'a Rgb,
    ior: f64,
    nonlinear: bool,
    roughness: &'a Option<crate::scene::Microfacet>,
) -> Plastic<'a> {
    Plastic {
        diffuse_reflectance,
        specular_reflectance,
        eta: ior,
        nonlinear,
        roughness: roughness.as_ref(),
    }
}

/// BSDF value f(wo, wi) (per sr, without the cosine) for radiance transport; zero for delta
/// materials.
pub fn eval(m: &Material, wo: Vec3, wi: Vec3, ng: Vec3, ns: Vec3) -> Rgb {
    eval_transport(m, wo, wi, ng, ns, Transport::Radiance)
}

/// f(wo, wi) for a path of the given transport mode: light paths (flux, `wo` towards the light)
/// evaluate the adjoint BSDF, which differs from the radiance BSDF by the refraction's
/// (η_o/η_i)² (the rough dielectric's transmission); reflection is symmetric.
pub fn eval_transport(
    m: &Material,
    wo: Vec3,
    wi: Vec3,
    ng: Vec3,
    ns: Vec3,
    mode: Transport,
) -> Rgb {
    let at = (wo, wi, ng, ns);
    match m {
        Material::Lambertian { reflectance } => {
            if wi.dot(facing_normal(wo, ng)) <= 0.0 {
                return Rgb::BLACK;
            }
            *reflectance * (1.0 / PI)
        }
        Material::Glossy {
            diffuse,
            specular,
            roughness,
        } => {
            let (g, n) = facing(wo, ng, ns);
            if wi.dot(g) <= 0.0 {
                return Rgb::BLACK;
            }
            Glossy {
                diffuse,
                specular,
                roughness: *roughness,
            }
            .eval(wo, wi, n)
        }
        Material::Conductor {
            eta,
            k,
            specular_reflectance,
            roughness: Some(r),
        } => in_reflecting_frame(at, |wo, wi| {
            conductor(eta, k, specular_reflectance).eval(r, wo, wi)
        })
        .unwrap_or(Rgb::BLACK),
        Material::Plastic {
            diffuse_reflectance,
            specular_reflectance,
            ior,
            nonlinear,
            roughness,
        } => in_reflecting_frame(at, |wo, wi| {
            plastic(
                diffuse_reflectance,
                specular_reflectance,
                *ior,
                *nonlinear,
                roughness,
            )
            .eval(wo, wi)
        })
        .unwrap_or(Rgb::BLACK),
        Material::RoughDielectric { ior, roughness } => {
            match rough_dielectric(wo, wi, (ng, ns), *ior, roughness) {
                Some((rough, wo_l, wi_l)) => Rgb::splat(rough.eval(wo_l, wi_l, mode)),
                None => Rgb::BLACK,
            }
        }
        Material::Blend {
            weight,
            first,
            second,
        } => blend::eval((*weight, first, second), wo, wi, (ng, ns), mode),
        Material::Mirror { .. }
        | Material::Dielectric { .. }
        | Material::ThinDielectric { .. }
        | Material::Conductor {
            roughness: None, ..
        } => Rgb::BLACK,
    }
}

/// Solid-angle density with which [`sample`] produces `wi`; zero for delta materials.
pub fn pdf(m: &Material, wo: Vec3, wi: Vec3, ng: Vec3, ns: Vec3) -> f64 {
    let at = (wo, wi, ng, ns);
    match m {
        Material::Lambertian { .. } => {
            let (g, n) = facing(wo, ng, ns);
            if wi.dot(g) <= 0.0 {
                return 0.0;
            }
            wi.dot(n).max(0.0) / PI
        }
        Material::Glossy {
            diffuse,
            specular,
            roughness,
        } => {
            let (g, n) = facing(wo, ng, ns);
            if wi.dot(g) <= 0.0 {
                return 0.0;
            }
            Glossy {
                diffuse,
                specular,
                roughness: *roughness,
            }
            .pdf(wo, wi, n)
        }
        Material::Conductor {
            roughness: Some(r), ..
        } => in_reflecting_frame(at, |wo, wi| Conductor::pdf(r, wo, wi)).unwrap_or(0.0),
        Material::Plastic {
            diffuse_reflectance,
            specular_reflectance,
            ior,
            nonlinear,
            roughness,
        } => in_reflecting_frame(at, |wo, wi| {
            plastic(
                diffuse_reflectance,
                specular_reflectance,
                *ior,
                *nonlinear,
                roughness,
            )
            .pdf(wo, wi)
        })
        .unwrap_or(0.0),
        Material::RoughDielectric { ior, roughness } => {
            match rough_dielectric(wo, wi, (ng, ns), *ior, roughness) {
                Some((rough, wo_l, wi_l)) => rough.pdf(wo_l, wi_l),
                None => 0.0,
            }
        }
        Material::Blend {
            weight,
            first,
            second,
        } => blend::density((*weight, first, second), wo, wi, (ng, ns)),
        Material::Mirror { .. }
        | Material::Dielectric { .. }
        | Material::ThinDielectric { .. }
        | Material::Conductor {
            roughness: None, ..
        } => 0.0,
    }
}

/// `(eval, pdf)` in one pass (next-event estimation with MIS needs both).
pub fn eval_and_pdf(m: &Material, wo: Vec3, wi: Vec3, ng: Vec3, ns: Vec3) -> (Rgb, f64) {
    eval_and_pdf_transport(m, wo, wi, ng, ns, Transport::Radiance)
}

/// [`eval_and_pdf`] for a path of the given transport mode ([`eval_transport`]).
pub fn eval_and_pdf_transport(
    m: &Material,
    wo: Vec3,
    wi: Vec3,
    ng: Vec3,
    ns: Vec3,
    mode: Transport,
) -> (Rgb, f64) {
    match m {
        Material::Lambertian { reflectance } => {
            let (g, n) = facing(wo, ng, ns);
            if wi.dot(g) <= 0.0 {
                return (Rgb::BLACK, 0.0);
            }
            (*reflectance * (1.0 / PI), wi.dot(n).max(0.0) / PI)
        }
        _ => (
            eval_transport(m, wo, wi, ng, ns, mode),
            pdf(m, wo, wi, ng, ns),
        ),
    }
}

/// Local direction around unit `n` from tangent-space coordinates.
fn to_world(n: Vec3, local: Vec3) -> Vec3 {
    let (t, b) = n.orthonormal_basis();
    t * local.x + b * local.y + n * local.z
}

/// A reflecting model's local sample in world space; `None` below the geometric surface.
fn reflected(
    wo: Vec3,
    ng: Vec3,
    ns: Vec3,
    f: impl FnOnce(Vec3) -> Option<LocalSample>,
) -> Option<BsdfSample> {
    let (g, frame) = reflecting(wo, ng, ns);
    let s = f(frame.local(wo))?;
    let wi = frame.world(s.wi);
    (wi.dot(g) > 0.0).then_some(BsdfSample {
        wi,
        weight: s.weight,
        pdf: s.pdf,
        delta: s.delta,
    })
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
            let model = Glossy {
                diffuse,
                specular,
                roughness: *roughness,
            };
            let (g, n) = facing(wo, ng, ns);
            let wi = model.sample_direction(wo, n, u, uc)?;
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
        Material::Conductor {
            eta,
            k,
            specular_reflectance,
            roughness,
        } => reflected(wo, ng, ns, |wo| {
            conductor(eta, k, specular_reflectance).sample(roughness.as_ref(), wo, u)
        }),
        Material::Plastic {
            diffuse_reflectance,
            specular_reflectance,
            ior,
            nonlinear,
            roughness,
        } => reflected(wo, ng, ns, |wo| {
            plastic(
                diffuse_reflectance,
                specular_reflectance,
                *ior,
                *nonlinear,
                roughness,
            )
            .sample(wo, u, uc)
        }),
        Material::RoughDielectric { ior, roughness } => {
            let (n, eta) = dielectric::side(wo, ng, ns, *ior);
            let frame = Frame::new(n);
            let rough = Rough {
                d: Distribution::new(roughness),
                eta,
            };
            let s = rough.sample(frame.local(wo), u, uc, mode)?;
            let wi = frame.world(s.wi);
            let g = facing_normal(wo, ng);
            ((wi.dot(g) > 0.0) == (s.wi.z > 0.0)).then_some(BsdfSample {
                wi,
                weight: s.weight,
                pdf: s.pdf,
                delta: false,
            })
        }
        Material::ThinDielectric { ior } => {
            let (g, n) = facing(wo, ng, ns);
            let r = dielectric::thin_reflectance(wo.dot(n), *ior);
            if uc < r {
                let wi = reflect(wo, n);
                return (wi.dot(g) > 0.0).then_some(BsdfSample {
                    wi,
                    weight: Rgb::WHITE,
                    pdf: r,
                    delta: true,
                });
            }
            // Straight through: the sheet's two refractions cancel.
            Some(BsdfSample {
                wi: -wo,
                weight: Rgb::WHITE,
                pdf: 1.0 - r,
                delta: true,
            })
        }
        Material::Blend {
            weight,
            first,
            second,
        } => blend::sample_blend((*weight, first, second), wo, (ng, ns), u, uc, mode),
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

    #[derive(serde::Deserialize)]
    enum RowKind {
        Eval,
        Sample,
    }

    #[derive(serde::Deserialize)]
    enum Mode {
        Radiance,
        Flux,
    }

    #[derive(serde::Deserialize)]
    struct Row {
        kind: RowKind,
        mode: Mode,
        wo: Vec3,
        wi: Vec3,
        u: (f64, f64),
        uc: f64,
        value: Rgb,
        pdf: f64,
    }

    #[derive(serde::Deserialize)]
    struct Case {
        name: String,
        material: Material,
        rows: Vec<Row>,
    }

    /// Mitsuba 3's eval, pdf and sample of every new material at fixed directions and uniform
    /// numbers (`tests/data/mitsuba_bsdf.ron`, written by `tests/data/mitsuba_bsdf.py`) against
    /// luxest's: the same formulas, so within Mitsuba's single precision (relative 1e-4; the
    /// rough plastic's tables are Mitsuba's quadratures, recomputed here in double precision).
    /// Beckmann densities and sample weights within 0.4 %: luxest's density is its sampler's own
    /// (the exact G1), Mitsuba's uses its 0.35 % fit (`microfacet`'s module docs).
    #[test]
    fn agrees_with_mitsuba() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mitsuba_bsdf.ron");
        let cases: Vec<Case> = ron::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-4 * a.abs().max(b.abs()) + 1e-6;
        let mut checked = 0;
        // The largest relative differences of eval, of pdf and sample weight (GGX and the
        // rest), and of Beckmann densities, reported on stderr.
        let mut worst = [0.0f64; 3];
        let rel = |a: f64, b: f64| {
            let s = a.abs().max(b.abs());
            if s > 1e-6 {
                (a - b).abs() / s
            } else {
                0.0
            }
        };
        for case in &cases {
            let m = &case.material;
            let mut beckmann = false;
            m.for_each(&mut |m| {
                if let Material::Conductor {
                    roughness: Some(r), ..
                }
                | Material::Plastic {
                    roughness: Some(r), ..
                }
                | Material::RoughDielectric { roughness: r, .. } = m
                {
                    beckmann |= r.distribution == crate::scene::MicrofacetDistribution::Beckmann;
                }
            });
            let tolerance = if beckmann { 4e-3 } else { 1e-4 };
            let density_close =
                |a: f64, b: f64| (a - b).abs() <= tolerance * a.abs().max(b.abs()) + 1e-6;
            for row in &case.rows {
                let mode = match row.mode {
                    Mode::Radiance => Transport::Radiance,
                    Mode::Flux => Transport::Flux,
                };
                let at = format!(
                    "{}: wo {:?}, wi {:?}, u {:?} {}",
                    case.name, row.wo, row.wi, row.u, row.uc
                );
                match row.kind {
                    RowKind::Eval => {
                        // Mitsuba's eval includes the cosine of the new direction.
                        let f = eval_transport(m, row.wo, row.wi, UP, UP, mode) * row.wi.z.abs();
                        let p = pdf(m, row.wo, row.wi, UP, UP);
                        worst[if beckmann { 2 } else { 1 }] =
                            worst[if beckmann { 2 } else { 1 }].max(rel(p, row.pdf));
                        for c in 0..3 {
                            worst[0] = worst[0].max(rel(f.0[c], row.value.0[c]));
                            assert!(
                                close(f.0[c], row.value.0[c]),
                                "{at}: eval {f:?} vs Mitsuba {:?}",
                                row.value
                            );
                        }
                        assert!(
                            density_close(p, row.pdf),
                            "{at}: pdf {p} vs Mitsuba {}",
                            row.pdf
                        );
                    }
                    RowKind::Sample => {
                        let s = sample(m, row.wo, UP, UP, row.u, row.uc, mode);
                        if row.value.max_component() == 0.0 {
                            assert!(
                                s.is_none_or(|s| s.weight.max_component() == 0.0),
                                "{at}: {s:?} where Mitsuba's sample is invalid"
                            );
                            continue;
                        }
                        let s =
                            s.unwrap_or_else(|| panic!("{at}: no sample where Mitsuba has one"));
                        assert!(
                            (s.wi - row.wi).length() < 1e-4,
                            "{at}: direction {:?} vs Mitsuba {:?}",
                            s.wi,
                            row.wi
                        );
                        for c in 0..3 {
                            assert!(
                                density_close(s.weight.0[c], row.value.0[c]),
                                "{at}: weight {:?} vs Mitsuba {:?}",
                                s.weight,
                                row.value
                            );
                        }
                        assert!(
                            density_close(s.pdf, row.pdf),
                            "{at}: pdf {} vs Mitsuba {}",
                            s.pdf,
                            row.pdf
                        );
                    }
                }
                checked += 1;
            }
        }
        eprintln!(
            "{checked} rows: largest relative difference of eval {:.1e}, of pdf {:.1e} \
             (Beckmann {:.1e})",
            worst[0], worst[1], worst[2]
        );
        assert!(checked > 500, "{checked} rows");
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
