//! Seeded random numbers and the sampling routines every estimator shares.
//!
//! The generator is PCG32 (O'Neill 2014, "PCG: A Family of Simple Fast Space-Efficient
//! Statistically Good Algorithms"), with a stream id so that each pixel, tile or light-path batch
//! gets its own independent sequence: results then depend on the seed only, never on the thread
//! count or the scheduling order.

use luxest_io::math::Vec3;
use std::f64::consts::PI;

#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

const PCG_MULT: u64 = 6364136223846793005;

impl Rng {
    /// A generator for `(seed, stream)`; different streams are independent sequences.
    pub fn new(seed: u64, stream: u64) -> Rng {
        let mut r = Rng {
            state: 0,
            inc: (stream << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(splitmix64(seed));
        r.next_u32();
        r
    }
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG_MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }
    pub fn next_u64(&mut self) -> u64 {
        ((self.next_u32() as u64) << 32) | self.next_u32() as u64
    }
    /// Uniform in [0, 1) with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    /// Two uniform numbers in [0, 1).
    pub fn next_2d(&mut self) -> (f64, f64) {
        (self.next_f64(), self.next_f64())
    }
}

/// A source of uniform numbers in [0, 1) for the sampling routines: the independent [`Rng`], or
/// the path tracer's low-discrepancy [`crate::sobol::PixelSampler`].
pub trait Sampler {
    fn next_f64(&mut self) -> f64;
    /// Two numbers meant as one 2D sample (a low-discrepancy sampler stratifies them jointly).
    fn next_2d(&mut self) -> (f64, f64);
}

impl Sampler for Rng {
    #[inline]
    fn next_f64(&mut self) -> f64 {
        Rng::next_f64(self)
    }
    #[inline]
    fn next_2d(&mut self) -> (f64, f64) {
        Rng::next_2d(self)
    }
}

/// SplitMix64 finaliser (Steele et al. 2014), used to spread user seeds over the state space.
pub fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E3779B97F4A7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
    z ^ (z >> 31)
}

/// A discrete distribution proportional to non-negative weights.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    cdf: Vec<f64>,
    total: f64,
}

impl Distribution1D {
    /// `None` if the weights are empty, negative, non-finite or sum to zero.
    pub fn new(weights: &[f64]) -> Option<Distribution1D> {
        if weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
            return None;
        }
        let mut acc = 0.0;
        let mut cdf: Vec<f64> = weights
            .iter()
            .map(|w| {
                acc += w;
                acc
            })
            .collect();
        if acc <= 0.0 || !acc.is_finite() {
            return None;
        }
        for c in &mut cdf {
            *c /= acc;
        }
        *cdf.last_mut().unwrap() = 1.0;
        Some(Distribution1D { cdf, total: acc })
    }
    /// Builds from a stored cumulative distribution (last entry 1).
    pub fn from_cdf(cdf: Vec<f64>) -> Option<Distribution1D> {
        let ok = !cdf.is_empty()
            && cdf.windows(2).all(|w| w[0] <= w[1])
            && cdf[0] >= 0.0
            && (cdf[cdf.len() - 1] - 1.0).abs() < 1e-9;
        ok.then_some(Distribution1D { cdf, total: 1.0 })
    }
    pub fn len(&self) -> usize {
        self.cdf.len()
    }
    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }
    /// Sum of the original weights.
    pub fn total(&self) -> f64 {
        self.total
    }
    pub fn cdf(&self) -> &[f64] {
        &self.cdf
    }
    pub fn pmf(&self, i: usize) -> f64 {
        self.cdf[i] - if i == 0 { 0.0 } else { self.cdf[i - 1] }
    }
    /// Index with probability `pmf(index)` for `u` uniform in [0, 1), never a zero-weight entry.
    pub fn sample(&self, u: f64) -> (usize, f64) {
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .min(self.cdf.len() - 1);
        (i, self.pmf(i))
    }
}

/// Barycentric coordinates `(b1, b2)` of a uniformly distributed point on a triangle
/// (the square-root parameterisation; the point is `a + b1 (b - a) + b2 (c - a)`).
pub fn uniform_triangle(u1: f64, u2: f64) -> (f64, f64) {
    let s = u1.sqrt();
    (s * (1.0 - u2), s * u2)
}

/// Uniformly distributed points on a triangle mesh (an area emitter) from one 2D sample, so that
/// a low-discrepancy sampler's stratification of that sample carries over to the surface.
///
/// A mesh of two triangles `(a, b, c)`, `(a, c, d)` that form a parallelogram (a quad
/// light, fan-triangulated) maps the sample affinely onto it, `a + s (b − a) + t (d − a)`:
/// the 2D strata become strata of equal area on the light. Any other mesh picks its triangle
/// by area with the first coordinate and reuses that coordinate, rescaled within the chosen
/// triangle's interval, for the point on it ([`uniform_triangle`]). Either way the density is
/// one over the total area.
#[derive(Clone, Debug)]
pub struct TriangleMeshSampler {
    choice: Distribution1D,
    parallelogram: bool,
}

impl TriangleMeshSampler {
    /// From the triangles' corners and edges `(a, b − a, c − a)`; `None` if they have no area.
    pub fn new(triangles: &[[Vec3; 3]]) -> Option<TriangleMeshSampler> {
        let areas: Vec<f64> = triangles
            .iter()
            .map(|[_, e1, e2]| 0.5 * e1.cross(*e2).length())
            .collect();
        let choice = Distribution1D::new(&areas)?;
        let parallelogram = match triangles {
            // (a, b, c) and (a, c, d) with d − a = c − b: the second triangle's first edge is
            // the first one's second, and its second edge closes the parallelogram.
            [[a0, e01, e02], [a1, e11, e12]] => {
                let scale = e01.length().max(e02.length());
                let close = |p: Vec3, q: Vec3| (p - q).max_abs_component() <= 1e-9 * scale;
                close(*a0, *a1) && close(*e02, *e11) && close(*e12, *e02 - *e01)
            }
            _ => false,
        };
        Some(TriangleMeshSampler {
            choice,
            parallelogram,
        })
    }

    /// Whether the mesh is mapped as one parallelogram.
    pub fn is_parallelogram(&self) -> bool {
        self.parallelogram
    }

    /// A point for `(u1, u2)` uniform in [0, 1)²: its triangle and barycentric coordinates
    /// (b1, b2) there (the point is `a + b1 (b − a) + b2 (c − a)`).
    #[inline]
    pub fn sample(&self, u1: f64, u2: f64) -> (usize, f64, f64) {
        if self.parallelogram {
            // a + s (b − a) + t (d − a) lies in (a, b, c) at (s − t, t) when s ≥ t, else in
            // (a, c, d) at (s, t − s).
            let (s, t) = (u1, u2);
            return if s >= t { (0, s - t, t) } else { (1, s, t - s) };
        }
        let (i, p) = self.choice.sample(u1);
        let lo = if i == 0 { 0.0 } else { self.choice.cdf[i - 1] };
        let v = ((u1 - lo) / p).clamp(0.0, 1.0 - f64::EPSILON / 2.0);
        let (b1, b2) = uniform_triangle(v, u2);
        (i, b1, b2)
    }
}

/// sin and cos of x for |x| <= π/4 by their Taylor polynomials to x^15 / x^16 (truncation
/// error below 5e-17): a hot path of the samplers, several times faster than libm's sincos.
#[inline]
pub fn sin_cos_quarter(x: f64) -> (f64, f64) {
    // Coefficients (−1)^k/(2k+1)! and (−1)^k/(2k)!, Horner form in x².
    let x2 = x * x;
    let s = x
        * (1.0
            + x2 * (-0.16666666666666666
                + x2 * (0.008333333333333333
                    + x2 * (-0.0001984126984126984
                        + x2 * (2.7557319223985893e-06
                            + x2 * (-2.505210838544172e-08
                                + x2 * (1.6059043836821613e-10
                                    + x2 * (-7.647163731819816e-13))))))));
    let c = 1.0
        + x2 * (-0.5
            + x2 * (0.041666666666666664
                + x2 * (-0.001388888888888889
                    + x2 * (2.48015873015873e-05
                        + x2 * (-2.755731922398589e-07
                            + x2 * (2.08767569878681e-09
                                + x2 * (-1.1470745597729725e-11
                                    + x2 * (4.779477332387385e-14))))))));
    (s, c)
}

/// A uniformly distributed point on the unit disk by Shirley and Chiu's concentric mapping
/// ("A Low Distortion Map Between Disk and Square", 1997).
#[inline]
pub fn concentric_disk(u1: f64, u2: f64) -> (f64, f64) {
    let (a, b) = (2.0 * u1 - 1.0, 2.0 * u2 - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    if a.abs() > b.abs() {
        let (s, c) = sin_cos_quarter(PI / 4.0 * (b / a));
        (a * c, a * s)
    } else {
        // φ = π/2 − θ: cos φ = sin θ, sin φ = cos θ.
        let (s, c) = sin_cos_quarter(PI / 4.0 * (a / b));
        (b * s, b * c)
    }
}

/// A direction on the hemisphere around +z with density cos(theta)/pi (Malley's method on the
/// concentric disk).
#[inline]
pub fn cosine_hemisphere(u1: f64, u2: f64) -> Vec3 {
    let (x, y) = concentric_disk(u1, u2);
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    Vec3::new(x, y, z)
}

/// A direction uniformly distributed on the unit sphere (density 1/(4 pi)).
pub fn uniform_sphere(u1: f64, u2: f64) -> Vec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use luxest_io::chi2::{ChiSquareTest, Discrete, Hemisphere, Rectangle, Sphere};

    #[test]
    fn same_seed_same_sequence_and_streams_differ() {
        let a: Vec<u32> = (0..8)
            .scan(Rng::new(7, 3), |r, _| Some(r.next_u32()))
            .collect();
        let b: Vec<u32> = (0..8)
            .scan(Rng::new(7, 3), |r, _| Some(r.next_u32()))
            .collect();
        let c: Vec<u32> = (0..8)
            .scan(Rng::new(7, 4), |r, _| Some(r.next_u32()))
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn successive_uniform_floats_are_uniform_in_the_square() {
        // Pairs of successive numbers: uniform each, and independent of the one before.
        let mut r = Rng::new(1, 0);
        let mut next = || {
            let x = r.next_f64();
            assert!((0.0..1.0).contains(&x));
            x
        };
        ChiSquareTest::new(Rectangle::UNIT)
            .run(|| Some([next(), next()]), |_| 1.0)
            .unwrap();
    }

    #[test]
    fn discrete_distribution_matches_weights() {
        let w = [1.0, 0.0, 3.0, 6.0, 0.5];
        let d = Distribution1D::new(&w).unwrap();
        let mut r = Rng::new(2, 0);
        ChiSquareTest::new(Discrete(w.len()))
            .run(
                || {
                    let (i, p) = d.sample(r.next_f64());
                    assert!(p > 0.0, "sampled a zero-weight entry");
                    Some(i)
                },
                |i| w[i] / w.iter().sum::<f64>(),
            )
            .unwrap();
        assert!(Distribution1D::new(&[0.0, 0.0]).is_none());
        assert!(Distribution1D::new(&[1.0, f64::NAN]).is_none());
    }

    #[test]
    fn cosine_hemisphere_matches_its_density() {
        let mut r = Rng::new(3, 0);
        ChiSquareTest::new(Hemisphere)
            .run(
                || {
                    let d = cosine_hemisphere(r.next_f64(), r.next_f64());
                    assert!((d.length() - 1.0).abs() < 1e-12);
                    Some(d)
                },
                |d| d.z / PI,
            )
            .unwrap();
    }

    #[test]
    fn polynomial_sin_cos_is_exact_to_rounding() {
        for i in 0..=1000 {
            let x = (i as f64 / 1000.0 - 0.5) * PI / 2.0;
            let (s, c) = sin_cos_quarter(x);
            assert!(
                (s - x.sin()).abs() < 3e-16 && (c - x.cos()).abs() < 3e-16,
                "{x}"
            );
        }
    }

    #[test]
    fn uniform_sphere_is_uniform() {
        let mut r = Rng::new(4, 0);
        ChiSquareTest::new(Sphere)
            .run(
                || Some(uniform_sphere(r.next_f64(), r.next_f64())),
                |_| 1.0 / (4.0 * PI),
            )
            .unwrap();
    }

    /// Which of the 4^levels congruent triangles of the midpoint subdivision, repeated `levels`
    /// times, holds the point of barycentric coordinates (b0, b1, b2): all have equal area.
    fn subtriangle(mut b: [f64; 3], levels: u32) -> usize {
        let mut index = 0;
        for _ in 0..levels {
            // A corner triangle where one coordinate exceeds 1/2, else the middle (inverted) one.
            let k = b.iter().position(|&x| x > 0.5).unwrap_or(3);
            b = match k {
                3 => b.map(|x| 1.0 - 2.0 * x),
                _ => std::array::from_fn(|i| 2.0 * b[i] - f64::from(i == k)),
            };
            index = 4 * index + k;
        }
        index
    }

    /// A mesh's triangles as (a, b − a, c − a) from corner triples.
    fn mesh(corners: &[[[f64; 3]; 3]]) -> Vec<[Vec3; 3]> {
        corners
            .iter()
            .map(|c| {
                let [a, b, c] = c.map(Vec3::from);
                [a, b - a, c - a]
            })
            .collect()
    }

    #[test]
    fn mesh_sampler_maps_a_quad_uniformly_onto_the_parallelogram() {
        // A skewed parallelogram a, b, c = b + d − a, d, fan-triangulated from a.
        let (a, b, d) = ([0.1, 0.2, 0.3], [1.1, 0.4, 0.3], [0.4, 1.2, 0.5]);
        let c = [b[0] + d[0] - a[0], b[1] + d[1] - a[1], b[2] + d[2] - a[2]];
        let tris = mesh(&[[a, b, c], [a, c, d]]);
        let m = TriangleMeshSampler::new(&tris).unwrap();
        assert!(m.is_parallelogram());
        let (a, eb, ed) = (
            Vec3::from(a),
            Vec3::from(b) - Vec3::from(a),
            Vec3::from(d) - Vec3::from(a),
        );
        let n = eb.cross(ed);
        let mut r = Rng::new(6, 0);
        // The point's parallelogram coordinates (s, t), recovered from its position, are
        // uniform on the unit square: density 1.
        ChiSquareTest::new(Rectangle::UNIT)
            .run(
                || {
                    let (i, b1, b2) = m.sample(r.next_f64(), r.next_f64());
                    let [o, e1, e2] = tris[i];
                    let q = o + e1 * b1 + e2 * b2 - a;
                    let s = q.cross(ed).dot(n) / n.length_squared();
                    let t = eb.cross(q).dot(n) / n.length_squared();
                    Some([s, t])
                },
                |_| 1.0,
            )
            .unwrap();
        // A quad that is not a parallelogram is not mapped as one.
        let bent = mesh(&[
            [[0.0; 3], [1.0, 0.0, 0.0], [1.2, 1.0, 0.0]],
            [[0.0; 3], [1.2, 1.0, 0.0], [0.0, 1.0, 0.0]],
        ]);
        assert!(!TriangleMeshSampler::new(&bent).unwrap().is_parallelogram());
    }

    #[test]
    fn mesh_sampler_is_uniform_over_a_general_mesh() {
        // Three triangles of areas 1/2, 1 and 1/8: each of their 16 equal sub-triangles has
        // probability (its triangle's area / 1.625) / 16.
        let tris = mesh(&[
            [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [0.0, 1.0, 1.0]],
            [[0.0, 0.0, 2.0], [0.5, 0.0, 2.0], [0.0, 0.5, 2.0]],
        ]);
        let areas = [0.5, 1.0, 0.125];
        let m = TriangleMeshSampler::new(&tris).unwrap();
        assert!(!m.is_parallelogram());
        let mut r = Rng::new(7, 0);
        ChiSquareTest::new(Discrete(48))
            .run(
                || {
                    let (i, b1, b2) = m.sample(r.next_f64(), r.next_f64());
                    Some(16 * i + subtriangle([1.0 - b1 - b2, b1, b2], 2))
                },
                |k| areas[k / 16] / 1.625 / 16.0,
            )
            .unwrap();
    }

    #[test]
    fn uniform_triangle_is_uniform() {
        let mut r = Rng::new(5, 0);
        ChiSquareTest::new(Discrete(64))
            .run(
                || {
                    let (b1, b2) = uniform_triangle(r.next_f64(), r.next_f64());
                    Some(subtriangle([1.0 - b1 - b2, b1, b2], 3))
                },
                |_| 1.0 / 64.0,
            )
            .unwrap();
    }
}
