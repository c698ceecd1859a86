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
        d.d(h) * d.smith_g1(wo, h) / (4.0 * wo.z)
    }

    pub fn sample(&self, roughness: Option<&Microfacet>, wo: Vec3, u: (f64, f64)) -> Option<LocalSample> {
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
        if !(pdf_m > 0.0) || wi.z <= 0.0 {
            return None;
        }
        // f cos θi / pdf = F G1(wi, m): D and G1(wo, m) cancel against the visible normals.
        let weight =
            reflectance(wo.dot(m), self.eta, self.k, self.specular_reflectance) * d.smith_g1(wi, m);
        Some(LocalSample {
            wi,
            weight,
            pdf: pdf_m / (4.0 * wi.dot(m)),
            delta: false,
        })
    }
}
