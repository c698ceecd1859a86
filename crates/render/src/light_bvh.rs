//! A bounding volume hierarchy over a scene's lights for next-event estimation with many
//! emitters: the light is chosen by its importance at the receiving point — an upper estimate
//! of the irradiance it can deliver there from its intensity bound, its distance and the cone
//! of directions it emits into — instead of by flux alone (the idea of pbrt-v4's
//! `BVHLightSampler`, after Conty Estevez and Kulla 2018, "Importance sampling of many lights
//! with adaptive tree splitting").
//!
//! Every light is summarised by [`LightBounds`]: an axis-aligned box, `phi` (the largest
//! intensity it radiates, cd: `L · A` for a Lambertian area emitter, `I` for a point source, the
//! table's peak for a goniometric luminaire), and an orientation bound — a cone of axis `w` and
//! half-angle `θ_o` containing the emitting normals (area emitters) or the directions of
//! emission (spots, luminaires), plus `θ_e`, how far beyond those directions it still emits
//! (π/2 for Lambertian surfaces, 0 for a spot's or luminaire's hard cone). The importance at a
//! point `p` is
//!
//! ```text
//! I(p) = phi · cos θ' / d²,   θ' = max(0, θ_w − θ_o − θ_b),   0 where θ' ≥ θ_e (and θ_e > 0)
//! ```
//!
//! with `d` the distance from the box centre, `θ_w` the angle between `w` and the direction
//! from the centre to `p`, and `θ_b` the half-angle of the box's bounding sphere seen from `p`;
//! inside that sphere every direction is possible and I = phi / r² (r its radius). With the
//! receiver's normal known, I is multiplied by cos(max(0, θ_i − θ_b)), θ_i the angle between
//! the normal (either side) and the direction to the centre. It is zero only where no point of
//! the box can emit towards `p`, so every light that contributes at `p` has a positive
//! probability: the estimate stays unbiased.
//!
//! Sampling descends from the root, choosing a child with probability proportional to its
//! importance and rescaling the one uniform number; [`LightBvh::pmf`] retraces the path from
//! the light's leaf to give the same probability (for multiple importance sampling). The tree
//! is built top-down by the surface-area-orientation heuristic (cost of a side: its `phi`
//! times the orientation measure of its cone times its box's surface area, over 12 buckets per
//! axis; at the median below depth 40).

use luxest_io::math::Vec3;
use std::f64::consts::PI;

/// What the light BVH knows of one light (or of a node: the union of its lights').
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    pub lo: Vec3,
    pub hi: Vec3,
    /// Bound of the intensity radiated in any direction, cd (luminance).
    pub phi: f64,
    /// Unit axis of the orientation cone.
    pub w: Vec3,
    /// cos θ_o: the cone around `w` containing every normal / emission direction.
    pub cos_o: f64,
    /// cos θ_e: how far beyond the cone light still leaves (cos(π/2) = 0 for Lambertian
    /// surfaces, 1 for a hard cone).
    pub cos_e: f64,
}

impl LightBounds {
    /// An isotropic point source of intensity `phi` at `p`.
    pub fn point(p: Vec3, phi: f64) -> LightBounds {
        LightBounds {
            lo: p,
            hi: p,
            phi,
            w: Vec3::new(0.0, 0.0, 1.0),
            cos_o: -1.0,
            cos_e: 0.0,
        }
    }

    /// A light within the box `lo..hi` that emits only into the cone of axis `w` and
    /// half-angle acos(`cos_o`) (a spot, a luminaire's table).
    pub fn cone(lo: Vec3, hi: Vec3, phi: f64, w: Vec3, cos_o: f64) -> LightBounds {
        LightBounds {
            lo,
            hi,
            phi,
            w,
            cos_o,
            cos_e: 1.0,
        }
    }

    /// A one-sided Lambertian emitter within `lo..hi`, its front normals within the cone
    /// (`w`, acos(`cos_o`)), of luminance × area `phi`.
    pub fn lambertian(lo: Vec3, hi: Vec3, phi: f64, w: Vec3, cos_o: f64) -> LightBounds {
        LightBounds {
            lo,
            hi,
            phi,
            w,
            cos_o,
            cos_e: 0.0,
        }
    }

    fn centre(&self) -> Vec3 {
        (self.lo + self.hi) * 0.5
    }

    fn surface_area(&self) -> f64 {
        let d = self.hi - self.lo;
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }

    /// The union: the box around both, the summed intensity bound, the cone containing both
    /// cones and the larger spread beyond it.
    pub fn union(&self, o: &LightBounds) -> LightBounds {
        let (w, cos_o) = cone_union((self.w, self.cos_o), (o.w, o.cos_o));
        LightBounds {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
            phi: self.phi + o.phi,
            w,
            cos_o,
            cos_e: self.cos_e.min(o.cos_e),
        }
    }

    /// The importance at the point `p` (see the module docs); 0 where nothing in the box can
    /// emit towards `p`.
    pub fn importance(&self, p: Vec3) -> f64 {
        let mut pair = Pair::default();
        let packed = Packed::new(self);
        pair.set(0, &packed);
        pair.set(1, &packed);
        pair.importance(p, None)[0]
    }
}

/// [`LightBounds`] as sampling reads it: the box as its bounding sphere, the cone's sine
/// precomputed.
#[derive(Clone, Copy, Debug)]
struct Packed {
    centre: Vec3,
    /// Radius of the box's bounding sphere (half its diagonal), and its square.
    r: f64,
    r2: f64,
    phi: f64,
    w: Vec3,
    cos_o: f64,
    sin_o: f64,
    cos_e: f64,
}

impl Packed {
    fn new(b: &LightBounds) -> Packed {
        let r = 0.5 * (b.hi - b.lo).length();
        Packed {
            centre: b.centre(),
            r,
            r2: r * r,
            phi: b.phi,
            w: b.w,
            cos_o: b.cos_o,
            sin_o: (1.0 - b.cos_o * b.cos_o).max(0.0).sqrt(),
            cos_e: b.cos_e,
        }
    }
}

/// The smallest cone (axis, cos of the half-angle) containing both cones, or the whole sphere
/// (cos = −1).
fn cone_union((wa, ca): (Vec3, f64), (wb, cb): (Vec3, f64)) -> (Vec3, f64) {
    let (ta, tb) = (ca.clamp(-1.0, 1.0).acos(), cb.clamp(-1.0, 1.0).acos());
    // Make `a` the wider cone.
    let (wa, ta, wb, tb) = if tb > ta {
        (wb, tb, wa, ta)
    } else {
        (wa, ta, wb, tb)
    };
    if ta >= PI {
        return (wa, -1.0);
    }
    let td = wa.dot(wb).clamp(-1.0, 1.0).acos();
    if td + tb <= ta {
        return (wa, ta.cos());
    }
    let t = 0.5 * (ta + td + tb);
    if t >= PI {
        return (wa, -1.0);
    }
    // Turn wa towards wb by t − ta.
    let rot = t - ta;
    let axis = wa.cross(wb);
    let Some(axis) = axis.try_normalize() else {
        // Opposite axes (td = π; the equal case is contained above): the whole sphere.
        return (wa, -1.0);
    };
    // Rodrigues' rotation of wa about `axis` (perpendicular to wa) by `rot`.
    let w = wa * rot.cos() + axis.cross(wa) * rot.sin();
    let w = w.try_normalize().unwrap_or(wa);
    (w, t.cos())
}

/// The orientation measure of a cone (θ_o, θ_e): the solid angle it emits into, weighted by
/// the cosine falloff beyond θ_o (the SAOH's M_Ω).
fn orientation_measure(b: &LightBounds) -> f64 {
    let t_o = b.cos_o.clamp(-1.0, 1.0).acos();
    let t_e = b.cos_e.clamp(-1.0, 1.0).acos();
    let t_w = (t_o + t_e).min(PI);
    let (s_o, c_o) = (t_o.sin(), t_o.cos());
    2.0 * PI * (1.0 - c_o)
        + 0.5 * PI * (2.0 * t_w * s_o - (t_o - 2.0 * t_w).cos() - 2.0 * t_o * s_o + c_o)
}

/// A node of the tree as it is built.
#[derive(Clone, Debug)]
struct BuildNode {
    bounds: LightBounds,
    /// `None` for a leaf.
    children: Option<(usize, usize)>,
    light: u32,
}

/// The bounds of an inner node's two children side by side (lane 0, lane 1), so that both
/// importances are computed together.
#[derive(Clone, Copy, Debug, Default)]
struct Pair {
    cx: [f64; 2],
    cy: [f64; 2],
    cz: [f64; 2],
    r: [f64; 2],
    r2: [f64; 2],
    phi: [f64; 2],
    wx: [f64; 2],
    wy: [f64; 2],
    wz: [f64; 2],
    cos_o: [f64; 2],
    sin_o: [f64; 2],
    cos_e: [f64; 2],
}

impl Pair {
    fn set(&mut self, k: usize, b: &Packed) {
        self.cx[k] = b.centre.x;
        self.cy[k] = b.centre.y;
        self.cz[k] = b.centre.z;
        self.r[k] = b.r;
        self.r2[k] = b.r2;
        self.phi[k] = b.phi;
        self.wx[k] = b.w.x;
        self.wy[k] = b.w.y;
        self.wz[k] = b.w.z;
        self.cos_o[k] = b.cos_o;
        self.sin_o[k] = b.sin_o;
        self.cos_e[k] = b.cos_e;
    }

    /// Both children's importance at `p` (see [`LightBounds::importance`]), times the
    /// receiver's cosine bound when its normal `n` is given, without branches, the two lanes
    /// together.
    #[inline]
    fn importance(&self, p: Vec3, n: Option<Vec3>) -> [f64; 2] {
        use lanes::F2;
        let (zero, one) = (F2::splat(0.0), F2::splat(1.0));
        let dx = F2::splat(p.x) - F2::load(&self.cx);
        let dy = F2::splat(p.y) - F2::load(&self.cy);
        let dz = F2::splat(p.z) - F2::load(&self.cz);
        let dist2 = dx * dx + dy * dy + dz * dz;
        let r2 = F2::load(&self.r2);
        let inside = dist2.le(r2);
        let inv_d = one / dist2.max(F2::splat(f64::MIN_POSITIVE)).sqrt();
        let wdot = F2::load(&self.wx) * dx + F2::load(&self.wy) * dy + F2::load(&self.wz) * dz;
        let cos_w = (wdot * inv_d).min(one).max(F2::splat(-1.0));
        let sin_w = (one - cos_w * cos_w).max(zero).sqrt();
        let (cos_o, sin_o) = (F2::load(&self.cos_o), F2::load(&self.sin_o));
        // θ_x = max(0, θ_w − θ_o), then θ' = max(0, θ_x − θ_b).
        let in_cone = cos_w.ge(cos_o);
        let sin_x = sin_w * cos_o - cos_w * sin_o;
        let cos_x = cos_w * cos_o + sin_w * sin_o;
        let sin_b = (F2::load(&self.r) * inv_d).min(one);
        let cos_b = (one - sin_b * sin_b).max(zero).sqrt();
        let full = in_cone.or(cos_x.ge(cos_b));
        let cos_p = F2::select(full, one, cos_x * cos_b + sin_x * sin_b);
        // A hard cone (cos θ_e = 1) emits only where θ' = 0; otherwise up to θ_e.
        let cos_e = F2::load(&self.cos_e);
        let dark = F2::select(cos_e.ge(one), cos_p.lt(one), cos_p.le(cos_e));
        let phi = F2::load(&self.phi);
        let outside = F2::select(dark, zero, phi * cos_p * (inv_d * inv_d));
        // Inside the bounding sphere every direction is possible: phi / r²; a point source at
        // the receiver itself lights nothing there.
        let within = F2::select(
            r2.gt(zero),
            phi / r2.max(F2::splat(f64::MIN_POSITIVE)),
            zero,
        );
        let importance = F2::select(inside, within, outside);
        match n {
            None => importance.to_array(),
            Some(n) => {
                // cos θ'_i = cos(max(0, θ_i − θ_b)), θ_i between the normal (either side) and
                // the direction to the centre; 1 inside the sphere (sin θ_b = 1 there).
                let ndot = F2::splat(n.x) * dx + F2::splat(n.y) * dy + F2::splat(n.z) * dz;
                let c = ndot * inv_d;
                let cos_i = c.max(zero - c).min(one);
                let sin_i = (one - cos_i * cos_i).max(zero).sqrt();
                let cos_pi = F2::select(cos_i.ge(cos_b), one, cos_i * cos_b + sin_i * sin_b);
                (importance * F2::select(inside, one, cos_pi.max(zero))).to_array()
            }
        }
    }
}

/// Two f64 lanes: SSE2 on x86-64 (every x86-64 processor has it), plain arrays elsewhere.
mod lanes {
    #[cfg(target_arch = "x86_64")]
    use std::arch::x86_64::*;

    /// Two f64 values; comparisons give lane masks that [`F2::select`] and [`F2::or`] take.
    #[cfg(target_arch = "x86_64")]
    #[derive(Clone, Copy)]
    pub struct F2(__m128d);

    #[cfg(not(target_arch = "x86_64"))]
    #[derive(Clone, Copy)]
    pub struct F2([f64; 2]);

    macro_rules! binary {
        ($trait:ident, $method:ident, $intrinsic:ident, $op:tt) => {
            impl std::ops::$trait for F2 {
                type Output = F2;
                #[inline]
                fn $method(self, o: F2) -> F2 {
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: SSE2 is part of the x86-64 baseline.
                    unsafe {
                        F2($intrinsic(self.0, o.0))
                    }
                    #[cfg(not(target_arch = "x86_64"))]
                    F2([self.0[0] $op o.0[0], self.0[1] $op o.0[1]])
                }
            }
        };
    }
    binary!(Add, add, _mm_add_pd, +);
    binary!(Sub, sub, _mm_sub_pd, -);
    binary!(Mul, mul, _mm_mul_pd, *);
    binary!(Div, div, _mm_div_pd, /);

    #[cfg(target_arch = "x86_64")]
    impl F2 {
        #[inline]
        pub fn load(a: &[f64; 2]) -> F2 {
            // SAFETY: SSE2 is part of the x86-64 baseline; the unaligned load reads the array.
            unsafe { F2(_mm_loadu_pd(a.as_ptr())) }
        }
        #[inline]
        pub fn splat(v: f64) -> F2 {
            // SAFETY: as above.
            unsafe { F2(_mm_set1_pd(v)) }
        }
        #[inline]
        pub fn to_array(self) -> [f64; 2] {
            let mut a = [0.0; 2];
            // SAFETY: as above; the unaligned store writes the array.
            unsafe { _mm_storeu_pd(a.as_mut_ptr(), self.0) };
            a
        }
        #[inline]
        pub fn sqrt(self) -> F2 {
            // SAFETY: as above.
            unsafe { F2(_mm_sqrt_pd(self.0)) }
        }
        #[inline]
        pub fn min(self, o: F2) -> F2 {
            // SAFETY: as above.
            unsafe { F2(_mm_min_pd(self.0, o.0)) }
        }
        #[inline]
        pub fn max(self, o: F2) -> F2 {
            // SAFETY: as above.
            unsafe { F2(_mm_max_pd(self.0, o.0)) }
        }
        #[inline]
        pub fn le(self, o: F2) -> F2 {
            // SAFETY: as above.
            unsafe { F2(_mm_cmple_pd(self.0, o.0)) }
        }
        #[inline]
        pub fn lt(self, o: F2) -> F2 {
            // SAFETY: as above.
            unsafe { F2(_mm_cmplt_pd(self.0, o.0)) }
        }
        #[inline]
        pub fn ge(self, o: F2) -> F2 {
            // SAFETY: as above.
            unsafe { F2(_mm_cmpge_pd(self.0, o.0)) }
        }
        #[inline]
        pub fn gt(self, o: F2) -> F2 {
            // SAFETY: as above.
            unsafe { F2(_mm_cmpgt_pd(self.0, o.0)) }
        }
        /// The lanes where either mask is set.
        #[inline]
        pub fn or(self, o: F2) -> F2 {
            // SAFETY: as above.
            unsafe { F2(_mm_or_pd(self.0, o.0)) }
        }
        /// `a` where `mask` is set, else `b`.
        #[inline]
        pub fn select(mask: F2, a: F2, b: F2) -> F2 {
            // SAFETY: as above.
            unsafe {
                F2(_mm_or_pd(
                    _mm_and_pd(mask.0, a.0),
                    _mm_andnot_pd(mask.0, b.0),
                ))
            }
        }
    }

    #[cfg(not(target_arch = "x86_64"))]
    impl F2 {
        #[inline]
        pub fn load(a: &[f64; 2]) -> F2 {
            F2(*a)
        }
        #[inline]
        pub fn splat(v: f64) -> F2 {
            F2([v, v])
        }
        #[inline]
        pub fn to_array(self) -> [f64; 2] {
            self.0
        }
        fn map(self, f: impl Fn(f64) -> f64) -> F2 {
            F2([f(self.0[0]), f(self.0[1])])
        }
        fn zip(self, o: F2, f: impl Fn(f64, f64) -> f64) -> F2 {
            F2([f(self.0[0], o.0[0]), f(self.0[1], o.0[1])])
        }
        fn mask(b: bool) -> f64 {
            if b {
                1.0
            } else {
                0.0
            }
        }
        pub fn sqrt(self) -> F2 {
            self.map(f64::sqrt)
        }
        pub fn min(self, o: F2) -> F2 {
            self.zip(o, |a, b| if a < b { a } else { b })
        }
        pub fn max(self, o: F2) -> F2 {
            self.zip(o, |a, b| if a > b { a } else { b })
        }
        pub fn le(self, o: F2) -> F2 {
            self.zip(o, |a, b| Self::mask(a <= b))
        }
        pub fn lt(self, o: F2) -> F2 {
            self.zip(o, |a, b| Self::mask(a < b))
        }
        pub fn ge(self, o: F2) -> F2 {
            self.zip(o, |a, b| Self::mask(a >= b))
        }
        pub fn gt(self, o: F2) -> F2 {
            self.zip(o, |a, b| Self::mask(a > b))
        }
        pub fn or(self, o: F2) -> F2 {
            self.zip(o, |a, b| Self::mask(a != 0.0 || b != 0.0))
        }
        pub fn select(mask: F2, a: F2, b: F2) -> F2 {
            F2([0, 1].map(|k| if mask.0[k] != 0.0 { a.0[k] } else { b.0[k] }))
        }
    }
}

/// An inner node: its children's bounds and indices ([`LEAF`] marks a light index).
#[derive(Clone, Copy, Debug)]
struct Inner {
    pair: Pair,
    child: [u32; 2],
    /// The parent inner node and the lane this node is in there ([`NO_PARENT`] at the root).
    parent: (u32, u32),
}

/// The light BVH: built once per scene from the lights' bounds, shared by all threads.
#[derive(Clone, Debug)]
pub struct LightBvh {
    /// Inner nodes, the root first; empty when the tree is one light.
    inner: Vec<Inner>,
    /// The root: an inner node's index, or [`LEAF`] | a light index.
    root: u32,
    /// Per light index (the emitter index the bounds were given with), its parent inner node
    /// and lane ([`NO_PARENT`] for a tree of one light); `None` for lights not in the tree.
    leaf_of: Vec<Option<(u32, u32)>>,
}

const NO_PARENT: u32 = u32::MAX;
const LEAF: u32 = 1 << 31;
const BUCKETS: usize = 12;

impl LightBvh {
    /// The tree over `lights`: (bounds, light index below 2^31). Lights with `phi <= 0` or
    /// non-finite bounds are left out (they are never chosen, and their pmf is 0); `None` when
    /// none is left.
    pub fn new(lights: &[(LightBounds, u32)]) -> Option<LightBvh> {
        let mut items: Vec<(LightBounds, u32)> = lights
            .iter()
            .filter(|(b, i)| {
                b.phi > 0.0
                    && b.phi.is_finite()
                    && b.lo.is_finite()
                    && b.hi.is_finite()
                    && *i < LEAF
            })
            .copied()
            .collect();
        if items.is_empty() {
            return None;
        }
        let mut nodes = Vec::with_capacity(2 * items.len());
        build(&mut nodes, &mut items, 0);
        let max_index = items.iter().map(|(_, i)| *i).max().unwrap_or(0) as usize;
        let mut bvh = LightBvh {
            inner: Vec::with_capacity(items.len()),
            root: 0,
            leaf_of: vec![None; max_index + 1],
        };
        bvh.root = bvh.flatten(&nodes, 0, (NO_PARENT, 0));
        Some(bvh)
    }

    /// Appends the subtree of build node `n` (whose parent is `parent`); returns its encoding.
    fn flatten(&mut self, nodes: &[BuildNode], n: usize, parent: (u32, u32)) -> u32 {
        let node = &nodes[n];
        let Some((a, b)) = node.children else {
            self.leaf_of[node.light as usize] = Some(parent);
            return LEAF | node.light;
        };
        let index = self.inner.len() as u32;
        let mut pair = Pair::default();
        pair.set(0, &Packed::new(&nodes[a].bounds));
        pair.set(1, &Packed::new(&nodes[b].bounds));
        self.inner.push(Inner {
            pair,
            child: [0, 0],
            parent,
        });
        let ca = self.flatten(nodes, a, (index, 0));
        let cb = self.flatten(nodes, b, (index, 1));
        self.inner[index as usize].child = [ca, cb];
        index
    }

    /// The number of lights in the tree.
    pub fn len(&self) -> usize {
        self.leaf_of.iter().filter(|l| l.is_some()).count()
    }

    /// Whether the tree has no light (never: [`LightBvh::new`] returns `None` then).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// A light chosen for the receiver `p` (of unit normal `n`, either side, when given) with
    /// the uniform number `u` in [0, 1): (light index, its probability); `None` when no light
    /// can reach `p`.
    pub fn sample(&self, p: Vec3, n: Option<Vec3>, mut u: f64) -> Option<(usize, f64)> {
        let mut node = self.root;
        let mut pmf = 1.0;
        while node & LEAF == 0 {
            let inner = &self.inner[node as usize];
            let [ia, ib] = inner.pair.importance(p, n);
            let total = ia + ib;
            if total.is_nan() || total <= 0.0 {
                return None;
            }
            let pa = ia / total;
            if u < pa {
                u = (u / pa).min(ONE_MINUS_EPSILON);
                pmf *= pa;
                node = inner.child[0];
            } else {
                let pb = ib / total;
                u = ((u - pa) / pb).clamp(0.0, ONE_MINUS_EPSILON);
                pmf *= pb;
                node = inner.child[1];
            }
        }
        Some(((node & !LEAF) as usize, pmf))
    }

    /// The probability with which [`LightBvh::sample`] chooses light `light` for the receiver
    /// `p` (normal `n`) (0 for a light not in the tree or out of reach of `p`).
    pub fn pmf(&self, light: usize, p: Vec3, n: Option<Vec3>) -> f64 {
        let Some(Some((mut parent, mut lane))) = self.leaf_of.get(light) else {
            return 0.0;
        };
        let mut pmf = 1.0;
        while parent != NO_PARENT {
            let node = &self.inner[parent as usize];
            let i = node.pair.importance(p, n);
            let total = i[0] + i[1];
            if total.is_nan() || total <= 0.0 {
                return 0.0;
            }
            pmf *= i[lane as usize] / total;
            (parent, lane) = node.parent;
        }
        pmf
    }
}

/// Below this depth the tree splits by the SAOH; deeper, at the median along the widest axis of
/// the centroids, so that no input makes the tree (and the recursion) deeper than this plus
/// log2 of the light count.
const MAX_SAOH_DEPTH: usize = 40;

/// Builds the subtree over `items` (at `depth`) into `nodes`, returning its index.
fn build(nodes: &mut Vec<BuildNode>, items: &mut [(LightBounds, u32)], depth: usize) -> usize {
    let index = nodes.len();
    let bounds = items[1..]
        .iter()
        .fold(items[0].0, |acc, (b, _)| acc.union(b));
    nodes.push(BuildNode {
        bounds,
        children: None,
        light: items[0].1,
    });
    if items.len() > 1 {
        let mid = if depth < MAX_SAOH_DEPTH {
            split(items)
        } else {
            median_split(items)
        };
        let (left, right) = items.split_at_mut(mid);
        let a = build(nodes, left, depth + 1);
        let b = build(nodes, right, depth + 1);
        nodes[index].children = Some((a, b));
    }
    index
}

/// The largest f64 below 1.
const ONE_MINUS_EPSILON: f64 = 1.0 - f64::EPSILON / 2.0;

/// Reorders `items` (at least two) by their centres along the widest axis of the centres and
/// returns the middle.
fn median_split(items: &mut [(LightBounds, u32)]) -> usize {
    let (mut lo, mut hi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
    for (b, _) in items.iter() {
        lo = lo.min(b.centre());
        hi = hi.max(b.centre());
    }
    let e = hi - lo;
    let key = |b: &LightBounds| {
        let c = b.centre();
        if e.x >= e.y && e.x >= e.z {
            c.x
        } else if e.y >= e.z {
            c.y
        } else {
            c.z
        }
    };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| key(&a.0).total_cmp(&key(&b.0)));
    mid
}

/// Reorders `items` (at least two) and returns the split point: the bucket boundary of least
/// SAOH cost over the three axes, or the middle of the list when all centroids coincide.
fn split(items: &mut [(LightBounds, u32)]) -> usize {
    let centre = |b: &LightBounds| b.centre();
    let (mut clo, mut chi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
    for (b, _) in items.iter() {
        clo = clo.min(centre(b));
        chi = chi.max(centre(b));
    }
    let extent = chi - clo;
    let axis_of = |v: Vec3, a: usize| [v.x, v.y, v.z][a];
    let max_extent = extent.x.max(extent.y).max(extent.z);
    let mut best: Option<(f64, usize, usize)> = None; // (cost, axis, buckets left of the split)
    for axis in 0..3 {
        let e = axis_of(extent, axis);
        if e.is_nan() || e <= 0.0 {
            continue;
        }
        let bucket = |b: &LightBounds| {
            let t = (axis_of(centre(b), axis) - axis_of(clo, axis)) / e;
            ((t * BUCKETS as f64) as usize).min(BUCKETS - 1)
        };
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        for (b, _) in items.iter() {
            let k = bucket(b);
            buckets[k] = Some(buckets[k].map_or(*b, |acc| acc.union(b)));
        }
        // A thin box is penalised along its short axes (max extent / this extent).
        let kr = max_extent / e;
        let cost_of = |b: &Option<LightBounds>| {
            b.map_or(0.0, |b| b.phi * orientation_measure(&b) * b.surface_area())
        };
        for k in 1..BUCKETS {
            let union = |r: std::ops::Range<usize>| {
                buckets[r]
                    .iter()
                    .flatten()
                    .fold(None, |acc: Option<LightBounds>, b| {
                        Some(acc.map_or(*b, |a| a.union(b)))
                    })
            };
            let (left, right) = (union(0..k), union(k..BUCKETS));
            if left.is_none() || right.is_none() {
                continue;
            }
            let cost = kr * (cost_of(&left) + cost_of(&right));
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, k));
            }
        }
    }
    match best {
        Some((_, axis, k)) => {
            let e = axis_of(extent, axis);
            let in_left = |b: &LightBounds| {
                let t = (axis_of(centre(b), axis) - axis_of(clo, axis)) / e;
                ((t * BUCKETS as f64) as usize).min(BUCKETS - 1) < k
            };
            let mut mid = 0;
            for i in 0..items.len() {
                if in_left(&items[i].0) {
                    items.swap(i, mid);
                    mid += 1;
                }
            }
            mid
        }
        None => items.len() / 2,
    }
}

/// How next-event estimation chooses its light ([`crate::world::World::set_light_sampler`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LightSampler {
    /// By importance at the receiver, through the [`LightBvh`].
    #[default]
    Bvh,
    /// In proportion to the lights' flux, the same at every receiver.
    Power,
}

impl std::str::FromStr for LightSampler {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "bvh" => Ok(LightSampler::Bvh),
            "power" => Ok(LightSampler::Power),
            _ => Err(format!("expected bvh or power, got '{s}'")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use luxest_io::chi2::{ChiSquareTest, Discrete};

    fn unit(v: Vec3) -> Vec3 {
        v.try_normalize().unwrap()
    }

    /// A mix of lights: a row of small downward quads (ceiling troffers), a large dim wall
    /// facing +x, isotropic points, a spot aiming down and a luminaire-like cone.
    fn lights() -> Vec<(LightBounds, u32)> {
        let mut v = Vec::new();
        let down = Vec3::new(0.0, -1.0, 0.0);
        for i in 0..9 {
            for j in 0..3 {
                let c = Vec3::new(1.5 * i as f64, 3.0, 2.0 * j as f64);
                let h = Vec3::new(0.3, 0.0, 0.3);
                v.push(LightBounds::lambertian(c - h, c + h, 500.0, down, 1.0));
            }
        }
        v.push(LightBounds::lambertian(
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(-1.0, 3.0, 5.0),
            40.0,
            Vec3::new(1.0, 0.0, 0.0),
            1.0,
        ));
        v.push(LightBounds::point(Vec3::new(4.0, 1.0, 1.0), 80.0));
        v.push(LightBounds::point(Vec3::new(9.0, 2.5, 3.0), 5.0));
        v.push(LightBounds::cone(
            Vec3::new(6.0, 2.8, 0.0),
            Vec3::new(6.0, 2.8, 0.0),
            3000.0,
            down,
            30f64.to_radians().cos(),
        ));
        v.push(LightBounds::cone(
            Vec3::new(2.0, 2.7, 3.0),
            Vec3::new(2.4, 2.7, 3.4),
            900.0,
            unit(Vec3::new(0.2, -1.0, 0.0)),
            70f64.to_radians().cos(),
        ));
        // A light given twice the index space: indices need not be dense.
        v.iter()
            .enumerate()
            .map(|(k, b)| (*b, 2 * k as u32))
            .collect()
    }

    /// Receiving points with a unit normal each.
    fn receivers() -> Vec<(Vec3, Vec3)> {
        vec![
            (Vec3::new(0.1, 0.0, 0.2), Vec3::new(0.0, 1.0, 0.0)),
            (Vec3::new(6.0, 0.0, 0.1), Vec3::new(0.0, 1.0, 0.0)),
            (Vec3::new(12.0, 1.0, 4.0), unit(Vec3::new(-1.0, 0.2, 0.0))),
            (Vec3::new(-0.5, 1.5, 2.0), Vec3::new(1.0, 0.0, 0.0)),
            (Vec3::new(3.0, 2.95, 2.0), Vec3::new(0.0, -1.0, 0.0)),
        ]
    }

    #[test]
    fn the_pmf_sums_to_one_at_every_receiver() {
        let ls = lights();
        let bvh = LightBvh::new(&ls).unwrap();
        assert_eq!(bvh.len(), ls.len());
        for (p, n) in receivers() {
            for n in [None, Some(n)] {
                let total: f64 = ls.iter().map(|(_, i)| bvh.pmf(*i as usize, p, n)).sum();
                assert!((total - 1.0).abs() < 1e-12, "at {p:?}, {n:?}: {total}");
                // Indices not in the tree are never chosen.
                assert_eq!(bvh.pmf(1, p, n), 0.0);
                assert_eq!(bvh.pmf(10_000, p, n), 0.0);
            }
        }
    }

    #[test]
    fn sampled_lights_follow_the_pmf() {
        // Chi-square of the chosen light's index against `pmf`, at each receiver, without and
        // with its normal; the pmf `sample` returns is the one `pmf` retraces.
        let ls = lights();
        let bins = 2 * ls.len();
        let bvh = LightBvh::new(&ls).unwrap();
        let rs = receivers();
        for (k, &(p, normal)) in rs.iter().enumerate() {
            for n in [None, Some(normal)] {
                let mut rng = Rng::new(31, k as u64);
                ChiSquareTest::new(Discrete(bins))
                    .samples(20_000)
                    .tests(2 * rs.len())
                    .run(
                        || {
                            let (i, pmf) = bvh.sample(p, n, rng.next_f64())?;
                            let retraced = bvh.pmf(i, p, n);
                            assert!((pmf - retraced).abs() <= 1e-12 * pmf, "{i} at {p:?}");
                            Some(i)
                        },
                        |i| bvh.pmf(i, p, n),
                    )
                    .unwrap();
            }
        }
    }

    #[test]
    fn every_light_that_reaches_a_point_has_a_positive_probability() {
        // One-sided square emitters of random orientation: a receiver in front of any corner
        // is lit, so its pmf must be positive there; behind the plane by more than the bounding
        // sphere, 0. Spots: inside the
        // cone positive, outside 0.
        let mut rng = Rng::new(7, 1);
        let mut next = || 2.0 * rng.next_f64() - 1.0;
        let mut quads = Vec::new();
        for k in 0..40u32 {
            let c = Vec3::new(4.0 * next(), 4.0 * next(), 4.0 * next());
            let n = unit(Vec3::new(next(), next(), next()));
            let (t, b) = n.orthonormal_basis();
            let corners: Vec<Vec3> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .iter()
                .map(|(s, u)| c + t * (0.2 * s) + b * (0.2 * u))
                .collect();
            let (lo, hi) = corners
                .iter()
                .fold((corners[0], corners[0]), |(l, h), p| (l.min(*p), h.max(*p)));
            quads.push((corners, n, LightBounds::lambertian(lo, hi, 1.0, n, 1.0), k));
        }
        let spot_axis = unit(Vec3::new(0.3, -1.0, 0.2));
        let spot_at = Vec3::new(0.5, 5.0, 0.5);
        let cos_cut = 25f64.to_radians().cos();
        let mut ls: Vec<(LightBounds, u32)> = quads.iter().map(|q| (q.2, q.3)).collect();
        ls.push((
            LightBounds::cone(spot_at, spot_at, 10.0, spot_axis, cos_cut),
            40,
        ));
        let bvh = LightBvh::new(&ls).unwrap();
        let (mut lit, mut unlit, mut in_cone) = (0, 0, 0);
        for _ in 0..400 {
            let p = Vec3::new(6.0 * next(), 6.0 * next(), 6.0 * next());
            let receiver_normal = unit(Vec3::new(next(), next(), next()));
            for (corners, n, quad_bounds, k) in &quads {
                let front = corners.iter().any(|c| n.dot(p - *c) > 1e-9);
                // Behind the plane by more than the box's bounding sphere: nothing of the box
                // can face p.
                let (lo, hi) = (quad_bounds.lo, quad_bounds.hi);
                let r = 0.5 * (hi - lo).length();
                let behind = n.dot(p - (lo + hi) * 0.5) < -r - 1e-9;
                let pmf = bvh.pmf(*k as usize, p, None);
                let facing = bvh.pmf(*k as usize, p, Some(receiver_normal));
                if front {
                    lit += 1;
                    assert!(pmf > 0.0, "quad {k} lights {p:?} but has pmf 0");
                    // Any receiver normal: the quad lies off its tangent plane.
                    assert!(facing > 0.0, "quad {k} lights {p:?} (facing) but has pmf 0");
                } else if behind {
                    unlit += 1;
                    assert_eq!(pmf, 0.0, "quad {k} faces away from {p:?}");
                }
            }
            let cos = spot_axis.dot(unit(p - spot_at));
            let pmf = bvh.pmf(40, p, Some(receiver_normal));
            if cos > cos_cut + 1e-9 {
                in_cone += 1;
                assert!(pmf > 0.0, "the spot reaches {p:?}");
            } else if cos < cos_cut - 1e-9 {
                assert_eq!(pmf, 0.0, "the spot misses {p:?}");
            }
        }
        assert!(
            lit > 1000 && unlit > 1000 && in_cone > 0,
            "{lit} {unlit} {in_cone}"
        );
    }

    #[test]
    fn importance_of_a_point_source_is_its_intensity_over_distance_squared() {
        let b = LightBounds::point(Vec3::new(1.0, 2.0, 3.0), 50.0);
        let p = Vec3::new(1.0, 2.0, 7.0);
        assert!((b.importance(p) - 50.0 / 16.0).abs() < 1e-12);
        // A downward Lambertian patch seen straight from below: phi / d²; beside it, in its
        // plane: nothing.
        let q = LightBounds::lambertian(
            Vec3::new(0.0, 3.0, 0.0),
            Vec3::new(0.0, 3.0, 0.0),
            10.0,
            Vec3::new(0.0, -1.0, 0.0),
            1.0,
        );
        assert!((q.importance(Vec3::new(0.0, 1.0, 0.0)) - 2.5).abs() < 1e-12);
        assert_eq!(q.importance(Vec3::new(2.0, 3.0, 0.0)), 0.0);
        assert_eq!(q.importance(Vec3::new(0.0, 4.0, 0.0)), 0.0);
    }

    #[test]
    fn the_union_of_cones_contains_both() {
        let mut rng = Rng::new(3, 3);
        for _ in 0..200 {
            let mut dir = || {
                unit(Vec3::new(
                    rng.next_f64() - 0.5,
                    rng.next_f64() - 0.5,
                    rng.next_f64() - 0.5,
                ))
            };
            let (wa, wb) = (dir(), dir());
            let (ca, cb) = (rng.next_f64() * 2.0 - 1.0, rng.next_f64());
            let (w, c) = cone_union((wa, ca), (wb, cb));
            if c <= -1.0 {
                continue; // the whole sphere
            }
            // Each cone's axis and its rim lie inside the union (acos near 1 is accurate to
            // about 1e-8).
            for (wx, cx) in [(wa, ca), (wb, cb)] {
                let tx = cx.acos();
                let td = w.dot(wx).clamp(-1.0, 1.0).acos();
                assert!(td + tx <= c.acos() + 1e-6, "{wx:?} {cx} in {w:?} {c}");
            }
        }
    }

    #[test]
    fn many_lights_in_a_line_build_and_sample() {
        // 5000 points on a line with intensities over 30 decades (the SAOH peels one light at a
        // time off such a row; the median split bounds the depth): the pmf still sums to 1
        // and sampling returns the retraced pmf.
        let ls: Vec<(LightBounds, u32)> = (0..5000)
            .map(|k| {
                let p = Vec3::new(0.01 * k as f64, 1.0, 0.0);
                (
                    LightBounds::point(p, 10f64.powf(30.0 * k as f64 / 5000.0)),
                    k,
                )
            })
            .collect();
        let bvh = LightBvh::new(&ls).unwrap();
        let p = Vec3::new(20.0, 0.0, 0.5);
        let total: f64 = (0..5000).map(|k| bvh.pmf(k, p, None)).sum();
        assert!((total - 1.0).abs() < 1e-9, "{total}");
        let mut rng = Rng::new(1, 2);
        for _ in 0..100 {
            let (i, pmf) = bvh.sample(p, None, rng.next_f64()).unwrap();
            assert!((pmf - bvh.pmf(i, p, None)).abs() <= 1e-12 * pmf);
        }
    }

    #[test]
    fn parses_the_sampler_names() {
        assert_eq!("bvh".parse::<LightSampler>(), Ok(LightSampler::Bvh));
        assert_eq!("power".parse::<LightSampler>(), Ok(LightSampler::Power));
        assert!("uniform".parse::<LightSampler>().is_err());
    }
}
