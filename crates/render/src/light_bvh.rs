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
//! with `d` the distance from the box centre (at least the box's half diagonal), `θ_w` the
//! angle between `w` and the direction from the centre to `p`, and `θ_b` the half-angle of the
//! box's bounding sphere seen from `p` (π inside it). It is zero only where no point of the
//! box can emit towards `p`, so every light that contributes at `p` has a positive
//! probability: the estimate stays unbiased.
//!
//! Sampling descends from the root, choosing a child with probability proportional to its
//! importance and rescaling the one uniform number; [`LightBvh::pmf`] retraces the path from
//! the light's leaf to give the same probability (for multiple importance sampling). The tree
//! is built top-down by the surface-area-orientation heuristic (cost of a side: its `phi`
//! times the orientation measure of its cone times its box's surface area, over 12 buckets per
//! axis).

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
        Packed::new(self).importance(p)
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

    /// See [`LightBounds::importance`].
    #[inline]
    fn importance(&self, p: Vec3) -> f64 {
        let to_p = p - self.centre;
        let dist2 = to_p.length_squared();
        if dist2 <= self.r2 {
            // Inside the bounding sphere every direction is possible (θ_b = π): θ' = 0.
            return if self.r2 > 0.0 {
                self.phi / self.r2
            } else {
                0.0 // a point source at the receiver itself lights nothing there
            };
        }
        let inv_d = 1.0 / dist2.sqrt();
        let cos_w = (self.w.dot(to_p) * inv_d).clamp(-1.0, 1.0);
        let cos_p = if cos_w >= self.cos_o {
            1.0 // p lies within the cone: θ_x = 0
        } else {
            let sin_w = (1.0 - cos_w * cos_w).max(0.0).sqrt();
            // θ_x = θ_w − θ_o > 0, then θ' = max(0, θ_x − θ_b).
            let sin_x = sin_w * self.cos_o - cos_w * self.sin_o;
            let cos_x = cos_w * self.cos_o + sin_w * self.sin_o;
            let sin_b = self.r * inv_d;
            let cos_b = (1.0 - sin_b * sin_b).max(0.0).sqrt();
            if cos_x >= cos_b {
                1.0
            } else {
                cos_x * cos_b + sin_x * sin_b
            }
        };
        if self.cos_e >= 1.0 {
            // A hard cone: light only where θ' = 0.
            if cos_p < 1.0 {
                return 0.0;
            }
        } else if cos_p <= self.cos_e {
            return 0.0;
        }
        self.phi * cos_p * (inv_d * inv_d)
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

#[derive(Clone, Debug)]
enum Children {
    Leaf(u32),
    /// Indices of the two children.
    Inner(u32, u32),
}

#[derive(Clone, Debug)]
struct Node {
    bounds: Packed,
    children: Children,
    parent: u32,
}

/// The light BVH: built once per scene from the lights' bounds, shared by all threads.
#[derive(Clone, Debug)]
pub struct LightBvh {
    nodes: Vec<Node>,
    /// Per light index (the emitter index the bounds were given with), its leaf node.
    leaf_of: Vec<Option<u32>>,
}

const NO_PARENT: u32 = u32::MAX;
const BUCKETS: usize = 12;

impl LightBvh {
    /// The tree over `lights`: (bounds, light index). Lights with `phi <= 0` or non-finite
    /// bounds are left out (they are never chosen, and their pmf is 0); `None` when none is
    /// left.
    pub fn new(lights: &[(LightBounds, u32)]) -> Option<LightBvh> {
        let mut items: Vec<(LightBounds, u32)> = lights
            .iter()
            .filter(|(b, _)| {
                b.phi > 0.0 && b.phi.is_finite() && b.lo.is_finite() && b.hi.is_finite()
            })
            .copied()
            .collect();
        if items.is_empty() {
            return None;
        }
        let max_index = items.iter().map(|(_, i)| *i).max().unwrap_or(0) as usize;
        let mut bvh = LightBvh {
            nodes: Vec::with_capacity(2 * items.len()),
            leaf_of: vec![None; max_index + 1],
        };
        bvh.build(&mut items, NO_PARENT);
        Some(bvh)
    }

    /// Builds the subtree over `items`, returning its node index.
    fn build(&mut self, items: &mut [(LightBounds, u32)], parent: u32) -> u32 {
        let index = self.nodes.len() as u32;
        let bounds = items[1..]
            .iter()
            .fold(items[0].0, |acc, (b, _)| acc.union(b));
        if items.len() == 1 {
            self.nodes.push(Node {
                bounds: Packed::new(&bounds),
                children: Children::Leaf(items[0].1),
                parent,
            });
            self.leaf_of[items[0].1 as usize] = Some(index);
            return index;
        }
        self.nodes.push(Node {
            bounds: Packed::new(&bounds),
            children: Children::Leaf(u32::MAX),
            parent,
        });
        let mid = split(items);
        let (left, right) = items.split_at_mut(mid);
        let a = self.build(left, index);
        let b = self.build(right, index);
        self.nodes[index as usize].children = Children::Inner(a, b);
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

    /// A light chosen for the receiver `p` with the uniform number `u` in [0, 1): (light
    /// index, its probability); `None` when no light can reach `p`.
    pub fn sample(&self, p: Vec3, mut u: f64) -> Option<(usize, f64)> {
        let mut node = 0usize;
        let mut pmf = 1.0;
        loop {
            match self.nodes[node].children {
                Children::Leaf(light) => return Some((light as usize, pmf)),
                Children::Inner(a, b) => {
                    let ia = self.nodes[a as usize].bounds.importance(p);
                    let ib = self.nodes[b as usize].bounds.importance(p);
                    let total = ia + ib;
                    if total.is_nan() || total <= 0.0 {
                        return None;
                    }
                    let pa = ia / total;
                    if u < pa {
                        u = (u / pa).min(ONE_MINUS_EPSILON);
                        pmf *= pa;
                        node = a as usize;
                    } else {
                        let pb = ib / total;
                        u = ((u - pa) / pb).clamp(0.0, ONE_MINUS_EPSILON);
                        pmf *= pb;
                        node = b as usize;
                    }
                }
            }
        }
    }

    /// The probability with which [`LightBvh::sample`] chooses light `light` for the receiver
    /// `p` (0 for a light not in the tree or out of reach of `p`).
    pub fn pmf(&self, light: usize, p: Vec3) -> f64 {
        let Some(Some(leaf)) = self.leaf_of.get(light) else {
            return 0.0;
        };
        let mut pmf = 1.0;
        let mut child = *leaf;
        let mut parent = self.nodes[child as usize].parent;
        while parent != NO_PARENT {
            let Children::Inner(a, b) = self.nodes[parent as usize].children else {
                unreachable!("a parent is an inner node")
            };
            let ia = self.nodes[a as usize].bounds.importance(p);
            let ib = self.nodes[b as usize].bounds.importance(p);
            let total = ia + ib;
            if total.is_nan() || total <= 0.0 {
                return 0.0;
            }
            pmf *= if child == a { ia } else { ib } / total;
            child = parent;
            parent = self.nodes[parent as usize].parent;
        }
        pmf
    }
}

/// The largest f64 below 1.
const ONE_MINUS_EPSILON: f64 = 1.0 - f64::EPSILON / 2.0;

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

    fn receivers() -> Vec<Vec3> {
        vec![
            Vec3::new(0.1, 0.0, 0.2),
            Vec3::new(6.0, 0.0, 0.1),
            Vec3::new(12.0, 1.0, 4.0),
            Vec3::new(-0.5, 1.5, 2.0),
            Vec3::new(3.0, 2.95, 2.0),
        ]
    }

    #[test]
    fn the_pmf_sums_to_one_at_every_receiver() {
        let ls = lights();
        let bvh = LightBvh::new(&ls).unwrap();
        assert_eq!(bvh.len(), ls.len());
        for p in receivers() {
            let total: f64 = ls.iter().map(|(_, i)| bvh.pmf(*i as usize, p)).sum();
            assert!((total - 1.0).abs() < 1e-12, "at {p:?}: {total}");
            // Indices not in the tree are never chosen.
            assert_eq!(bvh.pmf(1, p), 0.0);
            assert_eq!(bvh.pmf(10_000, p), 0.0);
        }
    }

    #[test]
    fn sampled_lights_follow_the_pmf() {
        // Chi-square of the chosen light's index against `pmf`, at each receiver; the pmf
        // `sample` returns is the one `pmf` retraces.
        let ls = lights();
        let n = 2 * ls.len();
        let bvh = LightBvh::new(&ls).unwrap();
        let rs = receivers();
        for (k, &p) in rs.iter().enumerate() {
            let mut rng = Rng::new(31, k as u64);
            ChiSquareTest::new(Discrete(n))
                .samples(40_000)
                .tests(rs.len())
                .run(
                    || {
                        let (i, pmf) = bvh.sample(p, rng.next_f64())?;
                        assert!((pmf - bvh.pmf(i, p)).abs() <= 1e-12 * pmf, "{i} at {p:?}");
                        Some(i)
                    },
                    |i| bvh.pmf(i, p),
                )
                .unwrap();
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
            for (corners, n, quad_bounds, k) in &quads {
                let front = corners.iter().any(|c| n.dot(p - *c) > 1e-9);
                // Behind the plane by more than the box's bounding sphere: nothing of the box
                // can face p.
                let (lo, hi) = (quad_bounds.lo, quad_bounds.hi);
                let r = 0.5 * (hi - lo).length();
                let behind = n.dot(p - (lo + hi) * 0.5) < -r - 1e-9;
                let pmf = bvh.pmf(*k as usize, p);
                if front {
                    lit += 1;
                    assert!(pmf > 0.0, "quad {k} lights {p:?} but has pmf 0");
                } else if behind {
                    unlit += 1;
                    assert_eq!(pmf, 0.0, "quad {k} faces away from {p:?}");
                }
            }
            let cos = spot_axis.dot(unit(p - spot_at));
            let pmf = bvh.pmf(40, p);
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
    fn parses_the_sampler_names() {
        assert_eq!("bvh".parse::<LightSampler>(), Ok(LightSampler::Bvh));
        assert_eq!("power".parse::<LightSampler>(), Ok(LightSampler::Power));
        assert!("uniform".parse::<LightSampler>().is_err());
    }
}
