//! Mitsuba 3's `blendbsdf`: f = (1 − w) f₁ + w f₂ with w in [0, 1]. Sampling picks the second
//! material with probability w and the first otherwise, then weighs the sampled direction by
//! the blend's f and pdf (both materials' densities: a one-sample mixture), except where the
//! sampled lobe is a delta lobe, which only the material that sampled it has.

use super::{eval_transport, pdf, sample, BsdfSample, Transport};
use crate::scene::Material;
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;

pub fn eval(
    (w, first, second): (f64, &Material, &Material),
    wo: Vec3,
    wi: Vec3,
    (ng, ns): (Vec3, Vec3),
    mode: Transport,
) -> Rgb {
    let w = w.clamp(0.0, 1.0);
    let mut f = Rgb::BLACK;
    if w < 1.0 {
        f = f + eval_transport(first, wo, wi, ng, ns, mode) * (1.0 - w);
    }
    if w > 0.0 {
        f = f + eval_transport(second, wo, wi, ng, ns, mode) * w;
    }
    f
}

pub fn density(
    (w, first, second): (f64, &Material, &Material),
    wo: Vec3,
    wi: Vec3,
    (ng, ns): (Vec3, Vec3),
) -> f64 {
    let w = w.clamp(0.0, 1.0);
    let mut p = 0.0;
    if w < 1.0 {
        p += pdf(first, wo, wi, ng, ns) * (1.0 - w);
    }
    if w > 0.0 {
        p += pdf(second, wo, wi, ng, ns) * w;
    }
    p
}

pub fn sample_blend(
    (w, first, second): (f64, &Material, &Material),
    wo: Vec3,
    (ng, ns): (Vec3, Vec3),
    u: (f64, f64),
    uc: f64,
    mode: Transport,
) -> Option<BsdfSample> {
    let w = w.clamp(0.0, 1.0);
    // Mitsuba's choice: the second material when uc ≤ w, uc rescaled to [0, 1] for the lobe
    // choice within the material chosen.
    let (chosen, probability, uc) = if w > 0.0 && (uc <= w || w >= 1.0) {
        (second, w, (uc / w).min(1.0))
    } else {
        (first, 1.0 - w, ((uc - w) / (1.0 - w)).clamp(0.0, 1.0))
    };
    let s = sample(chosen, wo, ng, ns, u, uc, mode)?;
    if s.delta {
        return Some(BsdfSample {
            pdf: s.pdf * probability,
            ..s
        });
    }
    let p = density((w, first, second), wo, s.wi, (ng, ns));
    if !(p > 0.0) {
        return None;
    }
    let f = eval((w, first, second), wo, s.wi, (ng, ns), mode);
    Some(BsdfSample {
        wi: s.wi,
        weight: f * (s.wi.dot(ns).abs() / p),
        pdf: p,
        delta: false,
    })
}
