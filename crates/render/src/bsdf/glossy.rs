//! luxest's `Glossy` model: a Lambertian base plus an unweighted GGX lobe,
//! f = diffuse/π + specular · D_GGX(α = roughness²) G / (4 cos θo cos θi), in world space about
//! the shading normal turned to `wo`'s side (`n`; `g` the geometric normal on that side).

use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use std::f64::consts::PI;

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

/// The parameters of `Material::Glossy`.
pub struct Glossy<'a> {
    pub diffuse: &'a Rgb,
    pub specular: &'a Rgb,
    pub roughness: f64,
}

impl Glossy<'_> {
    pub fn eval(&self, wo: Vec3, wi: Vec3, n: Vec3) -> Rgb {
        let (co, ci) = (wo.dot(n), wi.dot(n));
        if co <= 0.0 || ci <= 0.0 {
            return Rgb::BLACK;
        }
        let alpha = self.roughness * self.roughness;
        let h = match (wo + wi).try_normalize() {
            Some(h) => h,
            None => return *self.diffuse * (1.0 / PI),
        };
        let spec =
            ggx_d(h.dot(n), alpha) * smith_g1(co, alpha) * smith_g1(ci, alpha) / (4.0 * co * ci);
        *self.diffuse * (1.0 / PI) + *self.specular * spec
    }

    fn lobe_probability(&self) -> Option<f64> {
        let (d, s) = (self.diffuse.luminance(), self.specular.luminance());
        (d + s > 0.0).then(|| d / (d + s))
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3, n: Vec3) -> f64 {
        let Some(pd) = self.lobe_probability() else {
            return 0.0;
        };
        // [`Glossy::sample`] rejects a direction below the shading normal's horizon (where `eval`
        // is zero), even above the geometric one: the specular lobe's density there is lost.
        if wi.dot(n) <= 0.0 {
            return 0.0;
        }
        let alpha = self.roughness * self.roughness;
        let diff = wi.dot(n) / PI;
        let spec = match (wo + wi).try_normalize() {
            Some(h) if h.dot(n) > 0.0 && wo.dot(h) > 0.0 => {
                ggx_d(h.dot(n), alpha) * h.dot(n) / (4.0 * wo.dot(h))
            }
            _ => 0.0,
        };
        pd * diff + (1.0 - pd) * spec
    }

    /// The sampled direction (world space), or `None` when the lobes have no weight.
    pub fn sample_direction(&self, wo: Vec3, n: Vec3, u: (f64, f64), uc: f64) -> Option<Vec3> {
        let pd = self.lobe_probability()?;
        Some(if uc < pd {
            super::to_world(n, crate::sampling::cosine_hemisphere(u.0, u.1))
        } else {
            // GGX normal distribution D(h) cos θh: tan²θh = α² u / (1 − u).
            let alpha = self.roughness * self.roughness;
            let tan2 = alpha * alpha * u.0 / (1.0 - u.0).max(1e-300);
            let cos_h = 1.0 / (1.0 + tan2).sqrt();
            let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
            let phi = 2.0 * PI * u.1;
            let h = super::to_world(n, Vec3::new(sin_h * phi.cos(), sin_h * phi.sin(), cos_h));
            super::reflect(wo, h)
        })
    }
}
