//! Shading frames as Mitsuba 3 defines them: the normal every BSDF scatters about at a surface
//! point — the interpolated vertex normal of a smooth mesh, perturbed by a normal map — and the
//! rules that tie it to the geometric normal, per kind of path.
//!
//! - Camera paths (radiance), as Mitsuba's `path`: the BSDF is evaluated and sampled in the
//!   shading frame alone — its sidedness, the two-sided flip, the cosine |wi · n| — with no test
//!   against the geometric normal (a direction below the geometric surface is traced as it is,
//!   its ray offset to the side it leaves on).
//! - Light paths (flux), as Mitsuba's `ptracer`: the same BSDF in importance mode, zero where
//!   either direction lies on different sides of the geometric and the shading surface (no light
//!   leaks), times the adjoint BSDF's correction for shading normals (Veach 1997, eq. 5.19,
//!   Mitsuba's `correction`) |wo · ns| |wi · ng| / (|wi · ns| |wo · ng|) — `wo` towards the
//!   light, `wi` the new direction. Both use the mesh's shading normal `ns`, not the normal
//!   map's (the map is part of the BSDF in Mitsuba).
//! - Normal maps, as Mitsuba's `normalmap` with its defaults (`flip_invalid_normals`,
//!   `use_shadowing_function`): the texel c decodes to (2c − 1), x and y scaled by the
//!   surface's `normal_scale`; where `wo` lies on different sides of `ns` and that normal, its x
//!   and y are negated; normalised, it is expressed in the frame (s, ns × s, ns) with s = ∂p/∂u
//!   made perpendicular to `ns`. A direction `wi` on different sides of `ns` and the mapped
//!   normal scatters nothing; otherwise the BSDF value is multiplied by Estevez et al.'s
//!   shadowing term 2 / (1 + √(1 + α² tan² θ)), α² = min(tan² θ_map / 8, 1), θ of `wi` about
//!   `ns` and θ_map of the mapped normal.
//!
//! On a flat triangle without a normal map every rule reduces to the geometric normal, and the
//! values are those of the BSDF about `ng` exactly.

use crate::bsdf::{self, BsdfSample, Transport};
use crate::sampling::Sampler;
use crate::scene::Material;
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;

/// The normals at a surface point seen from `wo`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shading {
    /// Unit geometric normal (the front side).
    pub ng: Vec3,
    /// Unit shading normal of the mesh (interpolated vertex normals; `ng` on flat triangles).
    pub ns: Vec3,
    /// The unit normal the BSDF scatters about: `ns`, or the normal map's.
    pub n: Vec3,
    /// α² of the normal map's shadowing term; `None` without a normal map.
    map_alpha2: Option<f64>,
}

impl Shading {
    /// A flat surface: every normal is `ng`.
    #[inline]
    pub fn flat(ng: Vec3) -> Shading {
        Shading {
            ng,
            ns: ng,
            n: ng,
            map_alpha2: None,
        }
    }

    /// A smooth surface without a normal map.
    #[inline]
    pub fn smooth(ng: Vec3, ns: Vec3) -> Shading {
        Shading {
            ng,
            ns,
            n: ns,
            map_alpha2: None,
        }
    }

    /// A normal-mapped surface: `texel` the map's linear RGB at the point, `scale` the
    /// surface's `normal_scale`, `dp_du` the mesh's ∂p/∂u there, `wo` the direction the path
    /// arrives from. The mesh's shading frame when the texel decodes to a zero vector.
    pub fn mapped(
        (ng, ns): (Vec3, Vec3),
        texel: [f32; 4],
        scale: [f64; 2],
        dp_du: Vec3,
        wo: Vec3,
    ) -> Shading {
        let decode = |c: f32| 2.0 * c as f64 - 1.0;
        let mut local = Vec3::new(
            decode(texel[0]) * scale[0],
            decode(texel[1]) * scale[1],
            decode(texel[2]),
        );
        let s = (dp_du - ns * ns.dot(dp_du))
            .try_normalize()
            .unwrap_or_else(|| ns.orthonormal_basis().0);
        let t = ns.cross(s);
        let wo_local = Vec3::new(wo.dot(s), wo.dot(t), wo.dot(ns));
        if wo_local.z * wo_local.dot(local) <= 0.0 {
            local = Vec3::new(-local.x, -local.y, local.z);
        }
        let Some(local) = local.try_normalize() else {
            return Shading::smooth(ng, ns);
        };
        let n = (s * local.x + t * local.y + ns * local.z)
            .try_normalize()
            .unwrap_or(ns);
        Shading {
            ng,
            ns,
            n,
            map_alpha2: Some((0.125 * tan2(local.z)).min(1.0)),
        }
    }

    /// Whether every normal is the geometric one (a flat triangle without a normal map).
    #[inline]
    pub fn is_flat(&self) -> bool {
        self.map_alpha2.is_none() && self.ns == self.ng
    }

    /// Whether a normal map perturbs the shading normal here.
    #[inline]
    pub fn is_mapped(&self) -> bool {
        self.map_alpha2.is_some()
    }

    /// The normal map's factor for the direction `wi`: zero on different sides of `ns` and the
    /// mapped normal, else the shadowing term; 1 without a map.
    #[inline]
    fn map_factor(&self, wi: Vec3) -> f64 {
        let Some(alpha2) = self.map_alpha2 else {
            return 1.0;
        };
        let c = wi.dot(self.ns);
        if c * wi.dot(self.n) <= 0.0 {
            return 0.0;
        }
        let t2 = tan2(c);
        if alpha2 == 0.0 {
            return 1.0;
        }
        2.0 / (1.0 + (1.0 + alpha2 * t2).sqrt())
    }

    /// The light-path factor for arriving from `wo` and leaving along `wi`: zero where either
    /// direction lies on different sides of the geometric and the shading surface, else the
    /// adjoint BSDF's shading-normal correction (module docs). 1 on flat surfaces.
    #[inline]
    pub fn adjoint(&self, wo: Vec3, wi: Vec3) -> f64 {
        if self.ns == self.ng {
            return 1.0;
        }
        let (o_g, o_s, i_g, i_s) = (
            wo.dot(self.ng),
            wo.dot(self.ns),
            wi.dot(self.ng),
            wi.dot(self.ns),
        );
        if o_g * o_s <= 0.0 || i_g * i_s <= 0.0 {
            return 0.0;
        }
        ((o_s * i_g) / (i_s * o_g)).abs()
    }

    /// f(wo, wi) |wi · n| with every rule of the path's kind (`mode`), and the density with
    /// which [`Shading::sample`] draws `wi` (0 where the value is forced to zero).
    #[inline]
    pub fn eval_and_pdf(&self, m: &Material, wo: Vec3, wi: Vec3, mode: Transport) -> (Rgb, f64) {
        let (f, pdf) = bsdf::eval_and_pdf_transport(m, wo, wi, self.n, self.n, mode);
        let mut k = wi.dot(self.n).abs();
        if self.map_alpha2.is_some() {
            k *= self.map_factor(wi);
        }
        if mode == Transport::Flux {
            k *= self.adjoint(wo, wi);
        }
        if k == 0.0 {
            return (Rgb::BLACK, 0.0);
        }
        (f * k, pdf)
    }

    /// f(wo, wi) |wi · n| ([`Shading::eval_and_pdf`] without the density).
    #[inline]
    pub fn eval(&self, m: &Material, wo: Vec3, wi: Vec3, mode: Transport) -> Rgb {
        let f = bsdf::eval_transport(m, wo, wi, self.n, self.n, mode);
        let mut k = wi.dot(self.n).abs();
        if self.map_alpha2.is_some() {
            k *= self.map_factor(wi);
        }
        if mode == Transport::Flux {
            k *= self.adjoint(wo, wi);
        }
        f * k
    }

    /// Samples the BSDF about `n` (as [`bsdf::sample_flat`]) with the rules of `mode`; `None`
    /// where the path ends.
    #[inline]
    pub fn sample(
        &self,
        m: &Material,
        wo: Vec3,
        rng: &mut impl Sampler,
        mode: Transport,
    ) -> Option<BsdfSample> {
        let mut s = bsdf::sample_flat(m, wo, self.n, rng, mode)?;
        let mut k = 1.0;
        if self.map_alpha2.is_some() {
            k *= self.map_factor(s.wi);
        }
        if mode == Transport::Flux {
            k *= self.adjoint(wo, s.wi);
        }
        if k == 0.0 {
            return None;
        }
        if k != 1.0 {
            s.weight = s.weight * k;
        }
        Some(s)
    }

    /// [`bsdf::sample`] with explicit random numbers, about `n`, with the rules of `mode`.
    pub fn sample_with(
        &self,
        m: &Material,
        wo: Vec3,
        u: (f64, f64),
        uc: f64,
        mode: Transport,
    ) -> Option<BsdfSample> {
        let mut s = bsdf::sample(m, wo, self.n, self.n, u, uc, mode)?;
        let mut k = self.map_factor(s.wi);
        if mode == Transport::Flux {
            k *= self.adjoint(wo, s.wi);
        }
        if k == 0.0 {
            return None;
        }
        s.weight = s.weight * k;
        Some(s)
    }
}

/// tan² θ of a unit vector whose cosine with the axis is `c` (∞ at c = 0).
#[inline]
fn tan2(c: f64) -> f64 {
    let c2 = c * c;
    (1.0 - c2).max(0.0) / c2
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    const UP: Vec3 = Vec3::new(0.0, 0.0, 1.0);

    fn unit(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::new(x, y, z).try_normalize().unwrap()
    }

    fn lambert(r: f64) -> Material {
        Material::Lambertian {
            reflectance: Rgb::splat(r),
        }
    }

    #[test]
    fn a_flat_frame_is_the_bsdf_about_the_geometric_normal() {
        let s = Shading::flat(UP);
        let m = lambert(0.6);
        let wo = unit(0.3, -0.2, 0.9);
        let wi = unit(-0.5, 0.1, 0.4);
        for mode in [Transport::Radiance, Transport::Flux] {
            let (f, p) = s.eval_and_pdf(&m, wo, wi, mode);
            let (g, q) = bsdf::eval_and_pdf_transport(&m, wo, wi, UP, UP, mode);
            assert_eq!(f, g * wi.dot(UP));
            assert_eq!(p, q);
        }
    }

    #[test]
    fn the_adjoint_correction_is_veachs_and_stops_leaks() {
        let ns = unit(0.3, 0.0, 1.0);
        let s = Shading::smooth(UP, ns);
        let wo = unit(-0.2, 0.4, 0.8);
        let wi = unit(0.6, -0.3, 0.5);
        let expected = (wo.dot(ns) * wi.dot(UP) / (wi.dot(ns) * wo.dot(UP))).abs();
        assert!((s.adjoint(wo, wi) - expected).abs() < 1e-15);
        // Above the geometric surface, below the shading one: no light passes.
        let leak = unit(-0.95, 0.0, 0.1);
        assert!(leak.dot(UP) > 0.0 && leak.dot(ns) < 0.0);
        assert_eq!(s.adjoint(wo, leak), 0.0);
        assert_eq!(s.adjoint(leak, wi), 0.0);
        let m = lambert(0.5);
        assert_eq!(s.eval(&m, wo, leak, Transport::Flux), Rgb::BLACK);
        // A camera path has no such test: the value about ns alone (zero only below ns).
        let above = unit(0.95, 0.0, -0.1);
        assert!(above.dot(ns) > 0.0 && above.dot(UP) < 0.0);
        let f = s.eval(&m, wo, above, Transport::Radiance);
        assert!((f.0[0] - 0.5 / std::f64::consts::PI * above.dot(ns)).abs() < 1e-15);
    }

    /// Reciprocity of the adjoint: f*(wo → wi) = f(wi → wo) |wo·ns||wi·ng| / (|wi·ns||wo·ng|)
    /// (Veach eq. 5.19): with the cosines each estimator applies, the light path's weight of
    /// (wo, wi) equals the camera path's weight of (wi, wo) times |wi·ng| / |wo·ng|.
    #[test]
    fn light_and_camera_weights_are_adjoint() {
        let ns = unit(-0.2, 0.25, 1.0);
        let s = Shading::smooth(UP, ns);
        let m = lambert(0.7);
        let mut rng = Rng::new(3, 1);
        for _ in 0..50 {
            let a = crate::sampling::cosine_hemisphere(rng.next_f64(), rng.next_f64());
            let b = crate::sampling::cosine_hemisphere(rng.next_f64(), rng.next_f64());
            let light = s.eval(&m, a, b, Transport::Flux).0[0];
            let camera = s.eval(&m, b, a, Transport::Radiance).0[0];
            if light == 0.0 {
                continue;
            }
            let ratio = light / (camera * b.dot(UP).abs() / a.dot(UP).abs());
            assert!((ratio - 1.0).abs() < 1e-12, "{ratio}");
        }
    }

    #[test]
    fn a_flat_normal_map_texel_changes_nothing_but_the_shadowing_term_is_one() {
        let wo = unit(0.1, 0.7, 0.4);
        let s = Shading::mapped(
            (UP, UP),
            [0.5, 0.5, 1.0, 1.0],
            [1.0, 1.0],
            Vec3::new(1.0, 0.0, 0.0),
            wo,
        );
        assert!((s.n - UP).length() < 1e-15);
        let m = lambert(0.4);
        let wi = unit(-0.3, 0.2, 0.6);
        let (f, _) = s.eval_and_pdf(&m, wo, wi, Transport::Radiance);
        assert!((f.0[1] - 0.4 / std::f64::consts::PI * wi.dot(UP)).abs() < 1e-15);
    }

    #[test]
    fn the_map_frame_follows_du_and_flips_for_the_other_side() {
        // Texel (x, y, z) = (0.6, 0, 0.8) with ∂p/∂u along +y: the normal tilts towards +y.
        let texel = [0.8, 0.5, 0.9, 1.0];
        let dp_du = Vec3::new(0.0, 2.0, 0.0);
        let wo = unit(0.0, 0.3, 1.0);
        let s = Shading::mapped((UP, UP), texel, [1.0, 1.0], dp_du, wo);
        let expected = unit(0.0, 0.6, 0.8);
        assert!((s.n - expected).length() < 1e-6, "{:?}", s.n);
        // From a direction on the other side of the mapped normal (but above ns): x, y negated.
        let grazing = unit(0.0, -1.0, 0.05);
        let f = Shading::mapped((UP, UP), texel, [1.0, 1.0], dp_du, grazing);
        let flipped = unit(0.0, -0.6, 0.8);
        assert!((f.n - flipped).length() < 1e-6, "{:?}", f.n);
        // The y axis is ns × s: texel y tilts towards −x for ∂p/∂u along +y.
        let y = Shading::mapped((UP, UP), [0.5, 0.8, 0.9, 1.0], [1.0, 1.0], dp_du, wo);
        assert!(y.n.x < -0.5 && y.n.y.abs() < 1e-12, "{:?}", y.n);
        // glTF's convention, scale (1, −1): towards +x.
        let g = Shading::mapped((UP, UP), [0.5, 0.8, 0.9, 1.0], [1.0, -1.0], dp_du, wo);
        assert!(g.n.x > 0.5, "{:?}", g.n);
    }

    #[test]
    fn the_shadowing_term_is_estevezs() {
        // Map normal at 30° from ns: tan² = 1/3, α² = 1/24.
        let t = (30f64).to_radians();
        let texel = [(t.sin() + 1.0) / 2.0, 0.5, (t.cos() + 1.0) / 2.0, 1.0];
        let wo = unit(0.2, 0.0, 1.0);
        let s = Shading::mapped(
            (UP, UP),
            texel.map(|v| v as f32),
            [1.0, 1.0],
            Vec3::new(1.0, 0.0, 0.0),
            wo,
        );
        let wi = Vec3::new(0.8, 0.0, 0.6);
        let alpha2 = 0.125 * t.tan().powi(2);
        let tan2_wi = (0.8f64 / 0.6).powi(2);
        let expected = 2.0 / (1.0 + (1.0 + alpha2 * tan2_wi).sqrt());
        assert!((s.map_factor(wi) - expected).abs() < 1e-6);
        // Below the mapped normal but above ns: nothing.
        let below = unit(-0.9, 0.0, 0.3);
        assert!(below.dot(s.n) < 0.0 && below.dot(UP) > 0.0);
        assert_eq!(s.map_factor(below), 0.0);
    }
}
