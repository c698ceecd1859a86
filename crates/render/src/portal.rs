//! Portals: rectangles (window openings) through which the environment lights an interior, and
//! portal-masked sampling of the environment from a point (Bitterli, Novák and Jarosz 2015,
//! "Portal-masked environment map sampling").
//!
//! A portal is the rectangle `corner + s u + t v` (s, t in [0, 1], `u ⊥ v`), two-sided. In a
//! portal's frame (x along u, y along v, z along one of its normals) a direction d with
//! d_z > 0 has the *rectified* coordinates α = atan(d_x / d_z), β = atan(d_y / d_z) in
//! (−π/2, π/2)². From a point at distance D on the −z side, the directions through the
//! rectangle are exactly an axis-aligned rectangle [α0, α1] × [β0, β1] in these coordinates
//! (α depends on the hit point's x alone, β on its y alone). Each portal keeps, for each of its
//! two sides, a table of N × N cells over (α, β) holding the environment's luminance (the map
//! alone, without a sun disk) times the Jacobian dω / dα dβ = (1 + x²)(1 + y²) / (1 + x² + y²)^{3/2}
//! (x = tan α, y = tan β), as a piecewise-constant function f, and its summed-area table (the
//! integral of f from the corner (−π/2, −π/2), at the cell corners; between them, bilinear
//! interpolation of it is exact for a piecewise-constant f).
//!
//! From a point p, portal k's weight is I_k = ∫∫ f over p's rectangle (four summed-area lookups:
//! about the environment's luminance integral over the portal's solid angle). A portal is drawn
//! with probability I_k / Σ I, then α from the marginal ∫ f dβ over [β0, β1] (piecewise linear
//! in α: binary search over the column boundaries, then the column's linear piece), then β from
//! the column's cells within [β0, β1] (per-column prefix sums, binary search). The density in
//! (α, β) is f / I_k; in solid angle f / (I_k J). A direction through several portals (a
//! non-convex room) sums the portals' shares: the pdf is the whole mixture's, exactly.
//!
//! Where Σ I is zero (a point in the plane of every portal, such as the wall holding the
//! windows, or portals behind which the environment is black), there is nothing to draw:
//! [`PortalSampler::rectangles`] returns `None`, and `World::sample_environment` draws nothing
//! there (density 0: BSDF sampling alone finds that point's sky).

use crate::environment::EnvironmentLight;
use luxest_io::math::Vec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_2;
use std::f64::consts::PI;

/// A portal as authored (scene field `portals`) and compiled (header `portals`): the rectangle
/// `corner + s u + t v`, world space.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Portal {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub corner: Vec3,
    pub u: Vec3,
    pub v: Vec3,
}

impl Portal {
    /// Why this portal is not a rectangle of positive, finite area (`None`: it is one).
    pub fn problem(&self) -> Option<String> {
        if !(self.corner.is_finite() && self.u.is_finite() && self.v.is_finite()) {
            return Some("corner, u and v must be finite".into());
        }
        let (lu, lv) = (self.u.length(), self.v.length());
        if !(lu > 0.0 && lv > 0.0) {
            return Some("u and v must be non-zero".into());
        }
        if self.u.dot(self.v).abs() > 1e-6 * lu * lv {
            return Some("u and v must be perpendicular (a portal is a rectangle)".into());
        }
        None
    }
}

/// Cells per side of each portal side's table.
pub const RESOLUTION: usize = 128;

/// Sub-samples per cell side averaged into a table cell.
const SUBSAMPLES: usize = 2;

/// One side's table: f per cell, its summed-area table and per-column prefix sums (grid units:
/// a cell is 1 × 1).
#[derive(Clone, Debug)]
struct Table {
    n: usize,
    /// f at cell (i along α, j along β), index i * n + j (columns contiguous).
    f: Vec<f64>,
    /// Summed area at corner (i, j), index i * (n + 1) + j, i and j in 0..=n.
    sat: Vec<f64>,
    /// Per column i, the prefix sums of its cells along β: index i * (n + 1) + j.
    prefix: Vec<f64>,
}

impl Table {
    fn build(n: usize, f_at: impl Fn(f64, f64) -> f64) -> Table {
        let delta = PI / n as f64;
        let k = SUBSAMPLES;
        let mut f = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                let mut sum = 0.0;
                for a in 0..k {
                    for b in 0..k {
                        let alpha = -FRAC_PI_2 + (i as f64 + (a as f64 + 0.5) / k as f64) * delta;
                        let beta = -FRAC_PI_2 + (j as f64 + (b as f64 + 0.5) / k as f64) * delta;
                        sum += f_at(alpha, beta);
                    }
                }
                let v = sum / (k * k) as f64;
                f[i * n + j] = if v.is_finite() && v > 0.0 { v } else { 0.0 };
            }
        }
        let m = n + 1;
        let mut prefix = vec![0.0; n * m];
        for i in 0..n {
            for j in 0..n {
                prefix[i * m + j + 1] = prefix[i * m + j] + f[i * n + j];
            }
        }
        let mut sat = vec![0.0; m * m];
        for i in 0..n {
            for j in 0..=n {
                sat[(i + 1) * m + j] = sat[i * m + j] + prefix[i * m + j];
            }
        }
        Table { n, f, sat, prefix }
    }

    /// The summed area at grid coordinates (x, y) in [0, n]², bilinear between corners.
    fn area(&self, x: f64, y: f64) -> f64 {
        let m = self.n + 1;
        let i = (x.floor() as usize).min(self.n - 1);
        let j = (y.floor() as usize).min(self.n - 1);
        let (fx, fy) = (x - i as f64, y - j as f64);
        let s = |a: usize, b: usize| self.sat[a * m + b];
        let lo = s(i, j) * (1.0 - fx) + s(i + 1, j) * fx;
        let hi = s(i, j + 1) * (1.0 - fx) + s(i + 1, j + 1) * fx;
        lo * (1.0 - fy) + hi * fy
    }

    /// ∫ f dy over [y0, y1] from x = 0 to x (grid units).
    fn marginal(&self, x: f64, y0: f64, y1: f64) -> f64 {
        self.area(x, y1) - self.area(x, y0)
    }

    /// ∫ f dy over [0, y] in column i.
    fn column(&self, i: usize, y: f64) -> f64 {
        let m = self.n + 1;
        let j = (y.floor() as usize).min(self.n - 1);
        self.prefix[i * m + j] + (y - j as f64) * self.f[i * self.n + j]
    }

    fn cell(&self, x: f64, y: f64) -> f64 {
        let i = (x.floor() as usize).min(self.n - 1);
        let j = (y.floor() as usize).min(self.n - 1);
        self.f[i * self.n + j]
    }

    /// The row and fraction of grid coordinate y, for [`Self::marginal_at`].
    fn row(&self, y: f64) -> (usize, f64) {
        let j = (y.floor() as usize).min(self.n - 1);
        (j, y - j as f64)
    }

    /// [`Self::marginal`] at the column boundary x = i, with y0 and y1 given by [`Self::row`].
    fn marginal_at(&self, i: usize, (j0, f0): (usize, f64), (j1, f1): (usize, f64)) -> f64 {
        let s = &self.sat[i * (self.n + 1)..(i + 1) * (self.n + 1)];
        let a1 = s[j1] + f1 * (s[j1 + 1] - s[j1]);
        let a0 = s[j0] + f0 * (s[j0 + 1] - s[j0]);
        a1 - a0
    }

    /// (x, y) in [x0, x1] × [y0, y1] for two uniform numbers, given the rectangle's integral
    /// `total` (> 0).
    fn sample(&self, [x0, x1, y0, y1]: [f64; 4], total: f64, u1: f64, u2: f64) -> (f64, f64) {
        let g0 = self.marginal(x0, y0, y1);
        let target = g0 + u1 * total;
        let (r0, r1) = (self.row(y0), self.row(y1));
        // The last column boundary in (x0, x1) at or below the target.
        let (mut lo, mut hi) = (x0.floor() as usize, (x1.ceil() as usize).min(self.n));
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if self.marginal_at(mid, r0, r1) <= target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let i = lo.min(self.n - 1);
        let xl = (i as f64).max(x0);
        let gl = self.marginal(xl, y0, y1);
        let slope = self.marginal_at(i + 1, r0, r1) - self.marginal_at(i, r0, r1);
        let x = if slope > 0.0 {
            xl + (target - gl) / slope
        } else {
            xl
        };
        let x = x.min(x1.min((i + 1) as f64)).max(x0.max(i as f64));
        // β in column i.
        let c0 = self.column(i, y0);
        let c1 = self.column(i, y1);
        let t = c0 + u2 * (c1 - c0);
        let m = self.n + 1;
        let (mut lo, mut hi) = (y0.floor() as usize, (y1.ceil() as usize).min(self.n));
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if self.prefix[i * m + mid] <= t {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let j = lo.min(self.n - 1);
        let yl = (j as f64).max(y0);
        let fj = self.f[i * self.n + j];
        let y = if fj > 0.0 {
            yl + (t - self.column(i, yl)) / fj
        } else {
            yl
        };
        (x, y.min(y1.min((j + 1) as f64)).max(y0.max(j as f64)))
    }
}

/// A portal's frame and its two sides' tables.
#[derive(Clone, Debug)]
struct PortalTables {
    corner: Vec3,
    ex: Vec3,
    ey: Vec3,
    ez: Vec3,
    width: f64,
    height: f64,
    /// Side 0: directions along +ez; side 1: along −ez.
    sides: [Table; 2],
}

/// What a point sees of one portal: the side, its rectangle in grid units and its integral.
#[derive(Clone, Copy, Debug)]
pub struct PortalView {
    side: usize,
    rect: [f64; 4],
    /// ∫∫ f dα dβ over the rectangle (the grid integral times the cell area).
    weight: f64,
}

/// The portals of a scene with their tables, for one environment.
#[derive(Clone, Debug)]
pub struct PortalSampler {
    portals: Vec<PortalTables>,
    /// Cell side in α and β, rad.
    delta: f64,
}

/// dω / dα dβ at the rectified coordinates of the local direction d (d.z > 0).
fn jacobian(d: Vec3) -> f64 {
    let z2 = d.z * d.z;
    (z2 + d.x * d.x) * (z2 + d.y * d.y) / d.z
}

/// The most portals a scene may have (their views at a point are kept on the stack).
pub const MAX_PORTALS: usize = 32;

/// The views of a point on every portal, and their total weight.
pub struct Views {
    views: [PortalView; MAX_PORTALS],
    count: usize,
    total: f64,
}

impl PortalSampler {
    /// Tables of `resolution`² cells per side for each portal, from the environment's map
    /// (its sun disk is sampled on its own).
    /// At most [`MAX_PORTALS`] portals are used (the first ones).
    pub fn new(env: &EnvironmentLight, portals: &[Portal], resolution: usize) -> PortalSampler {
        let n = resolution.max(1);
        let tables = portals
            .iter()
            .take(MAX_PORTALS)
            .map(|p| {
                let width = p.u.length();
                let height = p.v.length();
                let ex = p.u / width;
                let ey = p.v / height;
                let ez = ex.cross(ey);
                let side = |s: f64| {
                    Table::build(n, |alpha: f64, beta: f64| {
                        let (sa, ca) = alpha.sin_cos();
                        let (sb, cb) = beta.sin_cos();
                        let local = Vec3::new(sa * cb, ca * sb, ca * cb);
                        let len = local.length();
                        let d = local / len;
                        let world = ex * d.x + ey * d.y + ez * (s * d.z);
                        env.sky_radiance(world).luminance() * jacobian(d)
                    })
                };
                PortalTables {
                    corner: p.corner,
                    ex,
                    ey,
                    ez,
                    width,
                    height,
                    sides: [side(1.0), side(-1.0)],
                }
            })
            .collect();
        PortalSampler {
            portals: tables,
            delta: PI / n as f64,
        }
    }

    /// The number of portals.
    pub fn len(&self) -> usize {
        self.portals.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.portals.is_empty()
    }

    /// Grid coordinate of the angle a in (−π/2, π/2).
    fn grid(&self, a: f64, n: usize) -> f64 {
        ((a + FRAC_PI_2) / self.delta).clamp(0.0, n as f64)
    }

    /// What `from` sees of every portal; `None` where their total weight is zero.
    pub fn rectangles(&self, from: Vec3) -> Option<Views> {
        let empty = PortalView {
            side: 0,
            rect: [0.0; 4],
            weight: 0.0,
        };
        let mut views = [empty; MAX_PORTALS];
        let mut total = 0.0;
        for (p, slot) in self.portals.iter().zip(views.iter_mut()) {
            let r = from - p.corner;
            let (px, py, pz) = (r.dot(p.ex), r.dot(p.ey), r.dot(p.ez));
            // The point on the −z side looks through along +ez (side 0).
            let (side, dist) = if pz < 0.0 { (0, -pz) } else { (1, pz) };
            let table = &p.sides[side];
            let n = table.n;
            let mut view = PortalView { side, ..empty };
            if dist > 0.0 && dist.is_finite() {
                let x0 = self.grid((-px / dist).atan(), n);
                let x1 = self.grid(((p.width - px) / dist).atan(), n);
                let y0 = self.grid((-py / dist).atan(), n);
                let y1 = self.grid(((p.height - py) / dist).atan(), n);
                if x1 > x0 && y1 > y0 {
                    let g = table.marginal(x1, y0, y1) - table.marginal(x0, y0, y1);
                    let w = g * self.delta * self.delta;
                    if w > 0.0 && w.is_finite() {
                        view.rect = [x0, x1, y0, y1];
                        view.weight = w;
                        total += w;
                    }
                }
            }
            *slot = view;
        }
        (total > 0.0).then_some(Views {
            views,
            count: self.portals.len(),
            total,
        })
    }

    /// A unit direction through a portal for two uniform numbers, given `from`'s views (from
    /// [`Self::rectangles`]); its density is [`Self::pdf`].
    pub fn sample(&self, views: &Views, u1: f64, u2: f64) -> Vec3 {
        // The portal, u1 reused within its share.
        let mut target = u1 * views.total;
        let mut k = 0;
        for (i, v) in views.views[..views.count].iter().enumerate() {
            if v.weight > 0.0 {
                k = i;
                if target < v.weight {
                    break;
                }
                target -= v.weight;
            }
        }
        let v = &views.views[k];
        let r = (target / v.weight).clamp(0.0, 1.0 - f64::EPSILON / 2.0);
        let p = &self.portals[k];
        let table = &p.sides[v.side];
        let grid_total = v.weight / (self.delta * self.delta);
        let (x, y) = table.sample(v.rect, grid_total, r, u2);
        let alpha = -FRAC_PI_2 + x * self.delta;
        let beta = -FRAC_PI_2 + y * self.delta;
        let (sa, ca) = alpha.sin_cos();
        let (sb, cb) = beta.sin_cos();
        let local = Vec3::new(sa * cb, ca * sb, ca * cb);
        let s = if v.side == 0 { 1.0 } else { -1.0 };
        let w = p.ex * local.x + p.ey * local.y + p.ez * (s * local.z);
        w / w.length()
    }

    /// Whether a direction within the cone about the unit direction `d` of half-angle cosine
    /// `cos_max` may pass through a portal the views see (conservative: `false` means none
    /// does). In a portal's rectified coordinates, a direction within chord c = √(2 (1 −
    /// cos_max)) of d differs from it by at most asin(c / ρ) in α (ρ = √(1 − d_y²), the length
    /// of d's projection on the xz-plane) and asin(c / √(1 − d_x²)) in β; a cone reaching the
    /// portal's plane within c of grazing counts as passing.
    pub fn cone_may_pass(&self, views: &Views, d: Vec3, cos_max: f64) -> bool {
        let c = (2.0 * (1.0 - cos_max)).max(0.0).sqrt();
        let margin = |rho: f64| if c < rho { (c / rho).asin() } else { PI };
        self.portals
            .iter()
            .zip(&views.views[..views.count])
            .any(|(p, v)| {
                if v.weight <= 0.0 {
                    return false;
                }
                let s = if v.side == 0 { 1.0 } else { -1.0 };
                let l = Vec3::new(d.dot(p.ex), d.dot(p.ey), s * d.dot(p.ez));
                if l.z <= -c {
                    return false;
                }
                if l.z <= c {
                    return true;
                }
                let a = (l.x / l.z).atan();
                let b = (l.y / l.z).atan();
                let (ma, mb) = (
                    margin((1.0 - l.y * l.y).max(0.0).sqrt()),
                    margin((1.0 - l.x * l.x).max(0.0).sqrt()),
                );
                let angle = |g: f64| -FRAC_PI_2 + g * self.delta;
                let [x0, x1, y0, y1] = v.rect;
                a >= angle(x0) - ma
                    && a <= angle(x1) + ma
                    && b >= angle(y0) - mb
                    && b <= angle(y1) + mb
            })
    }

    /// Solid-angle density with which [`Self::sample`] returns the unit direction `w` from the
    /// point whose views these are.
    pub fn pdf(&self, views: &Views, w: Vec3) -> f64 {
        let mut pdf = 0.0;
        for (p, v) in self.portals.iter().zip(&views.views) {
            if v.weight <= 0.0 {
                continue;
            }
            let s = if v.side == 0 { 1.0 } else { -1.0 };
            let d = Vec3::new(w.dot(p.ex), w.dot(p.ey), s * w.dot(p.ez));
            if d.z <= 0.0 {
                continue;
            }
            let table = &p.sides[v.side];
            let n = table.n;
            let x = ((d.x / d.z).atan() + FRAC_PI_2) / self.delta;
            let y = ((d.y / d.z).atan() + FRAC_PI_2) / self.delta;
            let [x0, x1, y0, y1] = v.rect;
            if !(x >= x0 && x <= x1 && y >= y0 && y <= y1) {
                continue;
            }
            let f = table.cell(x.min(n as f64), y.min(n as f64));
            // f / I_k in (α, β), times the portal's probability I_k / Σ I, over J.
            pdf += f / (views.total * jacobian(d));
        }
        pdf
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use luxest_io::chi2::{ChiSquareTest, Rectangle};
    use luxest_io::color::Rgb;

    /// A 32 × 17 map with a bright spot and a gradient, rotated a little.
    fn env() -> EnvironmentLight {
        let (w, h) = (32, 17);
        let mut t = Vec::new();
        for j in 0..h {
            for i in 0..w {
                let v = 0.3
                    + 0.05 * i as f32
                    + 0.2 * j as f32
                    + if (i, j) == (9, 6) { 30.0 } else { 0.0 };
                t.push([v, 0.8 * v, 0.6 * v]);
            }
        }
        let (s, c) = 0.3f64.sin_cos();
        let rot = [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]];
        EnvironmentLight::map((w, h, t), 2.0, rot, (Vec3::ZERO, 10.0)).unwrap()
    }

    /// Two windows: one in the wall z = 4 (normal −z after the cross product of u, v), one in
    /// the ceiling y = 3.
    fn portals() -> Vec<Portal> {
        vec![
            Portal {
                name: None,
                corner: Vec3::new(0.75, 0.9, 4.0),
                u: Vec3::new(0.0, 1.5, 0.0),
                v: Vec3::new(1.5, 0.0, 0.0),
            },
            Portal {
                name: None,
                corner: Vec3::new(3.0, 3.0, 1.0),
                u: Vec3::new(1.0, 0.0, 0.0),
                v: Vec3::new(0.0, 0.0, 2.0),
            },
        ]
    }

    /// The point of portal k at (s, t), the unit direction to it from `from`, and the density
    /// factor dω/dA times the portal's area (so that p(s, t) = p(ω) · factor).
    fn through(p: &Portal, from: Vec3, s: f64, t: f64) -> (Vec3, f64) {
        let x = p.corner + p.u * s + p.v * t;
        let d = x - from;
        let r2 = d.length_squared();
        let w = d / r2.sqrt();
        let n = p.u.cross(p.v);
        let area = n.length();
        let cos = (w.dot(n) / area).abs();
        (w, cos / r2 * area)
    }

    /// Where the ray from `from` along w crosses portal k: (s, t) if inside.
    fn crossing(p: &Portal, from: Vec3, w: Vec3) -> Option<(f64, f64)> {
        let n = p.u.cross(p.v);
        let denom = w.dot(n);
        if denom == 0.0 {
            return None;
        }
        let t = (p.corner - from).dot(n) / denom;
        if t <= 0.0 {
            return None;
        }
        let x = from + w * t - p.corner;
        let s = x.dot(p.u) / p.u.length_squared();
        let tt = x.dot(p.v) / p.v.length_squared();
        ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&tt)).then_some((s, tt))
    }

    /// Bin edges on [0, 2] × [0, 1] (portal k at x in [k, k + 1]) along the tables' cell
    /// edges as seen from `from` (α depends on s alone, β on t alone), each piece split in 3.
    fn cell_edges(sampler: &PortalSampler, from: Vec3) -> (Vec<f64>, Vec<f64>) {
        let mut xs = vec![0.0, 2.0];
        let mut ys = vec![0.0, 1.0];
        for (k, p) in sampler.portals.iter().enumerate() {
            let r = from - p.corner;
            let (px, py, pz) = (r.dot(p.ex), r.dot(p.ey), r.dot(p.ez));
            let n = p.sides[0].n;
            for i in 1..n {
                let t = (-FRAC_PI_2 + i as f64 * sampler.delta).tan();
                let s = (px + pz.abs() * t) / p.width;
                if s > 0.0 && s < 1.0 {
                    xs.push(k as f64 + s);
                }
                let t = (py + pz.abs() * t) / p.height;
                if t > 0.0 && t < 1.0 {
                    ys.push(t);
                }
            }
            xs.push(1.0);
        }
        let split = |mut e: Vec<f64>| {
            e.sort_by(f64::total_cmp);
            e.dedup();
            let mut out = vec![e[0]];
            for w in e.windows(2) {
                for j in 1..=3 {
                    out.push(w[0] + (w[1] - w[0]) * j as f64 / 3.0);
                }
            }
            *out.last_mut().unwrap() = *e.last().unwrap();
            out
        };
        (split(xs), split(ys))
    }

    #[test]
    fn sampling_follows_its_pdf_on_the_portals() {
        // Each sample is mapped to the point where it crosses a portal, (s, t) for the first,
        // (1 + s, t) for the second, in the rectangle [0, 2] × [0, 1]; the pdf there is the
        // solid-angle pdf times dω/dA times the portal's area. A coarse table (8 cells per side)
        // with bins along its cell edges would be exact; uniform bins with a fine midpoint rule
        // are within the test's tolerance. Points on both sides of the portals.
        let env = env();
        let ps = portals();
        let sampler = PortalSampler::new(&env, &ps, 8);
        let points = [
            Vec3::new(3.0, 1.2, 2.0),
            Vec3::new(1.0, 0.3, 3.5),
            Vec3::new(2.0, 2.0, 5.0),
        ];
        for (k, &from) in points.iter().enumerate() {
            let views = sampler.rectangles(from).expect("the portals are seen");
            let (xs, ys) = cell_edges(&sampler, from);
            let mut r = Rng::new(11, k as u64);
            ChiSquareTest::new(Rectangle {
                x: [0.0, 2.0],
                y: [0.0, 1.0],
            })
            .edges(xs, ys)
            .samples(150_000)
            .tests(points.len())
            .run(
                || {
                    let w = sampler.sample(&views, r.next_f64(), r.next_f64());
                    assert!((w.length() - 1.0).abs() < 1e-9);
                    // The first portal crossed (they do not overlap from these points).
                    ps.iter()
                        .enumerate()
                        .find_map(|(i, p)| crossing(p, from, w).map(|(s, t)| [i as f64 + s, t]))
                },
                |[x, y]| {
                    let i = (x.floor() as usize).min(1);
                    let (w, factor) = through(&ps[i], from, x - i as f64, y);
                    sampler.pdf(&views, w) * factor
                },
            )
            .unwrap();
        }
    }

    #[test]
    fn weights_integrate_the_radiance_through_the_portals() {
        // E[Y(L(ω)) / p(ω)] = ∫ over both portals' solid angles of Y(L) dω, the latter by the
        // midpoint rule over the portals' areas (dω = cos / r² dA).
        let env = env();
        let ps = portals();
        let sampler = PortalSampler::new(&env, &ps, RESOLUTION);
        let from = Vec3::new(2.5, 1.0, 2.0);
        let views = sampler.rectangles(from).unwrap();
        let mut r = Rng::new(5, 5);
        let n = 200_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let w = sampler.sample(&views, r.next_f64(), r.next_f64());
            let p = sampler.pdf(&views, w);
            assert!(p > 0.0);
            let x = env.radiance(w).luminance() / p;
            s1 += x;
            s2 += x * x;
        }
        let mean = s1 / n as f64;
        let se = ((s2 / n as f64 - mean * mean) / n as f64).sqrt();
        let m = 400;
        let mut exact = 0.0;
        for p in &ps {
            for a in 0..m {
                for b in 0..m {
                    let (s, t) = ((a as f64 + 0.5) / m as f64, (b as f64 + 0.5) / m as f64);
                    let (w, factor) = through(p, from, s, t);
                    exact += env.radiance(w).luminance() * factor / (m * m) as f64;
                }
            }
        }
        assert!(
            (mean - exact).abs() < 4.0 * se + 1e-3 * exact,
            "{mean} ± {se} vs {exact}"
        );
    }

    #[test]
    fn cones_that_pass_a_portal_are_never_ruled_out() {
        // Random cones from random points: when any of 64 directions inside a cone crosses a
        // portal, `cone_may_pass` must say so; and it rules out some cones.
        let env = env();
        let ps = portals();
        let sampler = PortalSampler::new(&env, &ps, 16);
        let mut r = Rng::new(3, 9);
        let (mut passing, mut ruled_out) = (0, 0);
        for _ in 0..3000 {
            let from = Vec3::new(6.0 * r.next_f64(), 3.0 * r.next_f64(), 5.0 * r.next_f64());
            let Some(views) = sampler.rectangles(from) else {
                continue;
            };
            let d = crate::sampling::uniform_sphere(r.next_f64(), r.next_f64());
            let cos_max = (0.5 + 10.0 * r.next_f64()).to_radians().cos();
            let (t, b) = d.orthonormal_basis();
            let crosses = (0..64).any(|_| {
                let ct = 1.0 - r.next_f64() * (1.0 - cos_max);
                let st = (1.0 - ct * ct).sqrt();
                let phi = 2.0 * PI * r.next_f64();
                let w = t * (st * phi.cos()) + b * (st * phi.sin()) + d * ct;
                ps.iter().any(|p| crossing(p, from, w).is_some())
            });
            let may = sampler.cone_may_pass(&views, d, cos_max);
            assert!(
                !crosses || may,
                "from {from:?}, cone {d:?} crosses a portal"
            );
            passing += crosses as usize;
            ruled_out += !may as usize;
        }
        assert!(
            passing > 50 && ruled_out > 1000,
            "{passing} pass, {ruled_out} ruled out"
        );
    }

    #[test]
    fn points_in_a_portal_plane_see_nothing_and_rectangles_are_checked() {
        let env = EnvironmentLight::constant(Rgb::splat(1.0), (Vec3::ZERO, 10.0));
        let ps = portals();
        let sampler = PortalSampler::new(&env, &ps[..1], 16);
        assert!(sampler.rectangles(Vec3::new(2.0, 1.0, 4.0)).is_none());
        assert!(ps[0].problem().is_none());
        let skew = Portal {
            v: Vec3::new(1.5, 0.1, 0.0),
            ..ps[0].clone()
        };
        assert!(skew.problem().unwrap().contains("perpendicular"));
        let flat = Portal {
            u: Vec3::ZERO,
            ..ps[0].clone()
        };
        assert!(flat.problem().is_some());
    }
}
