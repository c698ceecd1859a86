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
        if !(pdf_m > 0.0) {
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
        // cancel against the visible normals' density and the lobe choice.
        let g1 = self.d.smith_g1(wi, m);
        if !(g1 > 0.0 && pdf > 0.0) {
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
