//! The camera path tracer's sampler: Owen-scrambled Sobol points, padded dimension by dimension
//! (Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4); the construction pbrt-v4's
//! `PaddedSobolSampler` uses).
//!
//! Sample `s` of pixel `p` is a function of `(seed, p, s)` only, as with the independent
//! generator it replaces, so images stay independent of threads, tiles and passes. Each
//! dimension (a 1D draw or a 2D pair) takes the first one or two Sobol dimensions at index `s`,
//! with two hash-seeded steps keyed by (seed, pixel, dimension):
//!
//! - the sample index is shuffled by a nested uniform (Owen) scramble of its bits. An aligned
//!   block of 2^k indices maps onto an aligned block of 2^k Sobol indices, so the first 2^k
//!   samples of every pixel are still a (0, k, 2)-net in each pair — whatever spp the run stops
//!   at, progressive snapshots included — while different dimensions are decorrelated;
//! - the point is Owen-scrambled, which keeps the net and makes every point uniform on
//!   [0, 1)^2, so each estimate stays unbiased.
//!
//! For smooth integrands the error of a 2^k-point set falls like N^-1.5 instead of N^-0.5; the
//! gain in a path tracer is in the first bounces (pixel area, light point, BSDF lobe).
//!
//! The first 2D draw of each Sobol bounce (the light point of next-event estimation) is not
//! padded: it takes Sobol dimensions 2 and 3 at the shuffled index of the draw before it (the
//! pixel position at bounce 0, the BSDF direction that led to bounce 1), with scrambles of its
//! own, so that the two draws are one 4D Sobol point: the light point is stratified jointly
//! with where the path came from, not paired with it at random. Each point stays uniform on
//! [0, 1)^4 (Owen scrambling), so estimates stay unbiased.
//! Dimensions are named, not counted: bounce `b` draws from dimensions `(b + 1) · 64 + k`, so a
//! branch that skips a draw never shifts the dimensions of the next bounce. From bounce
//! [`SOBOL_BOUNCES`] on, the draws come from an independent PCG stream keyed by
//! (seed, pixel, sample): there stratification no longer pays for its hashing.

use crate::sampling::{splitmix64, Rng, Sampler};

/// Bounces (from the camera vertex) whose draws are Sobol points; later ones use PCG.
pub const SOBOL_BOUNCES: u32 = 2;

/// Dimensions reserved per bounce; dimension 0 is the pixel position.
const DIMS_PER_BOUNCE: u32 = 64;

/// Generator matrix of Sobol dimension 1 (dimension 0 is the bit reversal of the index): the
/// Pascal matrix mod 2, column i = v_i with v_0 = 2^31, v_i = v_{i-1} ^ (v_{i-1} >> 1).
const SOBOL_1: [u32; 32] = {
    let mut v = [0u32; 32];
    v[0] = 1 << 31;
    let mut i = 1;
    while i < 32 {
        v[i] = v[i - 1] ^ (v[i - 1] >> 1);
        i += 1;
    }
    v
};

/// Generator matrix (columns v_0 … v_31) of the Sobol dimension with primitive polynomial of
/// degree `s` and inner coefficients `a` (bit s − 2 … bit 0: a_1 … a_{s−1}) and initial direction
/// numbers `m` (Joe and Kuo's tables): m_k = 2 a_1 m_{k−1} ⊕ … ⊕ 2^{s−1} a_{s−1} m_{k−s+1} ⊕
/// 2^s m_{k−s} ⊕ m_{k−s}, v_k = m_{k+1} · 2^{31−k}.
const fn direction_numbers(s: usize, a: u32, init: [u32; 3]) -> [u32; 32] {
    let mut m = [0u32; 32];
    let mut k = 0;
    while k < 32 {
        if k < s {
            m[k] = init[k];
        } else {
            let mut x = m[k - s] ^ (m[k - s] << s);
            let mut j = 1;
            while j < s {
                if (a >> (s - 1 - j)) & 1 == 1 {
                    x ^= m[k - j] << j;
                }
                j += 1;
            }
            m[k] = x;
        }
        k += 1;
    }
    let mut v = [0u32; 32];
    let mut k = 0;
    while k < 32 {
        v[k] = m[k] << (31 - k);
        k += 1;
    }
    v
}

/// Sobol dimensions 2 (x² + x + 1, m = 1, 3) and 3 (x³ + x + 1, m = 1, 3, 1).
const SOBOL_2: [u32; 32] = direction_numbers(2, 1, [1, 3, 0]);
const SOBOL_3: [u32; 32] = direction_numbers(3, 1, [1, 3, 1]);

/// A generator matrix applied a byte at a time, bit-reversed (see [`SOBOL_1_REV_BYTES`]).
const fn reversed_byte_tables(columns: [u32; 32]) -> [[u32; 256]; 4] {
    let mut t = [[0u32; 256]; 4];
    let mut b = 0;
    while b < 4 {
        let mut v = 0;
        while v < 256 {
            let mut x = 0;
            let mut j = 0;
            while j < 8 {
                if v & (1 << j) != 0 {
                    x ^= columns[8 * b + j].reverse_bits();
                }
                j += 1;
            }
            t[b][v] = x;
            v += 1;
        }
        b += 1;
    }
    t
}

const SOBOL_2_REV_BYTES: [[u32; 256]; 4] = reversed_byte_tables(SOBOL_2);
const SOBOL_3_REV_BYTES: [[u32; 256]; 4] = reversed_byte_tables(SOBOL_3);

/// A bit-reversed Sobol dimension of index `i` from its byte tables.
#[inline]
fn apply_reversed(t: &[[u32; 256]; 4], i: u32) -> u32 {
    let [b0, b1, b2, b3] = i.to_le_bytes();
    t[0][b0 as usize] ^ t[1][b1 as usize] ^ t[2][b2 as usize] ^ t[3][b3 as usize]
}

/// [`SOBOL_1`] applied a byte at a time, bit-reversed: entry `[b][v]` is the XOR of the
/// reversed columns of the set bits of byte value `v` at byte `b` of the index (the shuffled
/// indices use all 32 bits). Reversed because the Owen scramble works on reversed bits: the
/// table saves a bit reversal per draw (x86 has no instruction for one).
const SOBOL_1_REV_BYTES: [[u32; 256]; 4] = reversed_byte_tables(SOBOL_1);

/// Sobol dimension 1 of index `i`, as 32 fraction bits, bit-reversed.
#[inline]
fn sobol_1_reversed(i: u32) -> u32 {
    apply_reversed(&SOBOL_1_REV_BYTES, i)
}

/// Sobol dimension 1 of index `i`, as 32 fraction bits.
#[cfg(test)]
fn sobol_1(i: u32) -> u32 {
    sobol_1_reversed(i).reverse_bits()
}

/// Laine and Karras' hash-based permutation with Burley's constants: bit j of the result
/// depends only on bits 0..=j of `x` (and the seed), so on reversed bits it is an Owen scramble.
#[inline]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Nested uniform (Owen) scramble of 32 fraction bits: each bit flipped by a hash of the bits
/// above it.
#[inline]
pub fn owen_scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

#[inline]
fn unit(x: u32) -> f64 {
    x as f64 * (1.0 / 4_294_967_296.0)
}

/// The draws of one camera sample (see the module docs).
pub struct PixelSampler {
    /// Hash of (seed, pixel): the key of every dimension's scrambles.
    key: u64,
    /// The sample index, bit-reversed (what the index shuffle scrambles).
    reversed_index: u32,
    dimension: u32,
    /// The independent stream for bounces from [`SOBOL_BOUNCES`] on.
    rng: Rng,
    sobol: bool,
    /// The shuffled index of the last 2D draw, and whether the next 2D draw continues it in
    /// Sobol dimensions 2 and 3 (the first 2D draw of each Sobol bounce).
    last_index: Option<u32>,
    pair_next: bool,
}

impl PixelSampler {
    /// Sample `sample` of pixel `pixel`; its first draw is the pixel position
    /// ([`PixelSampler::pixel_position`]).
    pub fn new(seed: u64, pixel: u64, sample: u32) -> PixelSampler {
        PixelSampler {
            key: splitmix64(seed ^ splitmix64(pixel.wrapping_mul(0x9E37_79B9_7F4A_7C15))),
            reversed_index: sample.reverse_bits(),
            dimension: 0,
            rng: Rng::new(seed, (pixel << 24) | sample as u64),
            sobol: true,
            last_index: None,
            pair_next: false,
        }
    }

    /// The sub-pixel position, uniform over [0, 1)² (the box filter): dimension 0.
    pub fn pixel_position(&mut self) -> (f64, f64) {
        self.dimension = 0;
        self.sobol_2d()
    }

    /// Moves to the dimensions of bounce `bounce` (0 for the camera ray's hit).
    #[inline]
    pub fn start_bounce(&mut self, bounce: u32) {
        self.sobol = bounce < SOBOL_BOUNCES;
        self.pair_next = self.sobol;
        self.dimension = (bounce + 1) * DIMS_PER_BOUNCE;
    }

    /// The shuffled index and the two scramble seeds of the next dimension. The shuffle is
    /// `owen_scramble(index, h)` with the index's reversal done once per sample.
    #[inline]
    fn next_dimension(&mut self) -> (u32, u32, u32) {
        let h = splitmix64(self.key ^ self.dimension as u64);
        self.dimension += 1;
        let index = laine_karras(self.reversed_index, h as u32).reverse_bits();
        (index, (h >> 32) as u32, splitmix64(h) as u32)
    }

    /// Sobol dimension 0 of shuffled index `i` (its bit reversal), Owen-scrambled:
    /// `owen_scramble(i.reverse_bits(), seed)` without the two reversals that cancel.
    #[inline]
    fn dimension_0(i: u32, seed: u32) -> f64 {
        unit(laine_karras(i, seed).reverse_bits())
    }

    fn sobol_2d(&mut self) -> (f64, f64) {
        let (i, s0, s1) = self.next_dimension();
        if let (true, Some(j)) = (std::mem::take(&mut self.pair_next), self.last_index) {
            // Dimensions 2 and 3 of the previous 2D draw's point: the two draws are one 4D
            // Sobol point (the light point of a bounce with the direction that led there).
            return (
                unit(laine_karras(apply_reversed(&SOBOL_2_REV_BYTES, j), s0).reverse_bits()),
                unit(laine_karras(apply_reversed(&SOBOL_3_REV_BYTES, j), s1).reverse_bits()),
            );
        }
        self.last_index = Some(i);
        (
            Self::dimension_0(i, s0),
            unit(laine_karras(sobol_1_reversed(i), s1).reverse_bits()),
        )
    }
}

impl Sampler for PixelSampler {
    #[inline]
    fn next_f64(&mut self) -> f64 {
        if self.sobol {
            let (i, s0, _) = self.next_dimension();
            Self::dimension_0(i, s0)
        } else {
            self.rng.next_f64()
        }
    }
    #[inline]
    fn next_2d(&mut self) -> (f64, f64) {
        if self.sobol {
            self.sobol_2d()
        } else {
            self.rng.next_2d()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sobol_dimension_one_matches_its_direction_numbers() {
        // The first points of Sobol dimension 1 in index order (not Gray-code order):
        // 0, 1/2, 3/4, 1/4, 5/8, 1/8, 3/8, 7/8.
        let expect = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875];
        for (i, e) in expect.iter().enumerate() {
            assert_eq!(unit(sobol_1(i as u32)), *e, "index {i}");
        }
        // The byte tables against the bit-by-bit product with the generator matrix.
        let mut r = Rng::new(3, 0);
        for _ in 0..1000 {
            let i = r.next_u32();
            let x = (0..32)
                .filter(|k| i >> k & 1 == 1)
                .fold(0, |x, k| x ^ SOBOL_1[k]);
            assert_eq!(sobol_1(i), x, "index {i}");
        }
    }

    #[test]
    fn sobol_dimensions_two_and_three_are_the_published_sequence() {
        // The first points of Sobol dimensions 2 and 3 in Gray-code order (index n ⊕ n/2), as
        // Joe and Kuo's and Bratley and Fox's tables list them.
        let expect = [
            (0.0, 0.0),
            (0.5, 0.5),
            (0.25, 0.25),
            (0.75, 0.75),
            (0.625, 0.875),
            (0.125, 0.375),
        ];
        let point =
            |v: &[u32; 32], i: u32| (0..32).filter(|k| i >> k & 1 == 1).fold(0, |x, k| x ^ v[k]);
        for (n, &(d2, d3)) in expect.iter().enumerate() {
            let g = n as u32 ^ (n as u32 >> 1);
            assert_eq!(
                (unit(point(&SOBOL_2, g)), unit(point(&SOBOL_3, g))),
                (d2, d3),
                "n {n}"
            );
        }
        let mut r = Rng::new(4, 0);
        for _ in 0..1000 {
            let i = r.next_u32();
            assert_eq!(
                apply_reversed(&SOBOL_2_REV_BYTES, i).reverse_bits(),
                point(&SOBOL_2, i)
            );
            assert_eq!(
                apply_reversed(&SOBOL_3_REV_BYTES, i).reverse_bits(),
                point(&SOBOL_3, i)
            );
        }
        // Each dimension alone stratifies: its first 2^k points fall one in each 1/2^k interval.
        for v in [&SOBOL_2, &SOBOL_3] {
            let mut cells: Vec<u32> = (0..1u32 << 10).map(|i| point(v, i) >> 22).collect();
            cells.sort_unstable();
            assert_eq!(cells, (0..1u32 << 10).collect::<Vec<_>>());
        }
    }

    #[test]
    fn a_bounce_first_2d_draw_continues_the_previous_point_in_four_dimensions() {
        // ∫ over [0, 1)^4 of exp(x0 x2 + x1 x3), whose variance is mostly in the interaction of
        // the two pairs: the pixel position with the first 2D draw of bounce 0 (one 4D Sobol
        // point) against the pixel position with the second (padded: independent pairing).
        let exact = {
            // ∫∫ e^{ab} da db over [0, 1)² = Σ 1 / (k! (k + 1)²), squared.
            let (mut sum, mut fact) = (0.0, 1.0);
            for k in 0..30 {
                if k > 0 {
                    fact *= k as f64;
                }
                sum += 1.0 / (fact * ((k + 1) * (k + 1)) as f64);
            }
            sum * sum
        };
        let rms = |n: u32, paired: bool| {
            let reps = 64u64;
            let se: f64 = (0..reps)
                .map(|pixel| {
                    let mean = (0..n)
                        .map(|s| {
                            let mut p = PixelSampler::new(11, pixel, s);
                            let (x0, x1) = p.pixel_position();
                            p.start_bounce(0);
                            let first = p.next_2d();
                            let (x2, x3) = if paired { first } else { p.next_2d() };
                            (x0 * x2 + x1 * x3).exp()
                        })
                        .sum::<f64>()
                        / n as f64;
                    (mean - exact).powi(2)
                })
                .sum();
            (se / reps as f64).sqrt()
        };
        let (paired, padded) = (rms(256, true), rms(256, false));
        // Unbiased, and the joint point integrates the interaction several times better (the
        // RMS of 64 replicates is itself uncertain by ~9 %).
        assert!(
            paired < padded / 3.0,
            "paired {paired:e}, padded {padded:e}"
        );
        assert!(
            rms(1024, true) < paired / 2.0,
            "paired error must keep falling"
        );
    }

    #[test]
    fn draws_are_the_scrambles_they_stand_for() {
        // The reversal-saving forms against the definitions: index shuffle
        // owen_scramble(index, h), dimension 0 owen_scramble(reverse(i), s0), dimension 1
        // owen_scramble(sobol_1(i), s1).
        let mut r = Rng::new(5, 0);
        for _ in 0..1000 {
            let (index, h, s0, s1) = (r.next_u32(), r.next_u32(), r.next_u32(), r.next_u32());
            assert_eq!(
                laine_karras(index.reverse_bits(), h).reverse_bits(),
                owen_scramble(index, h)
            );
            assert_eq!(
                PixelSampler::dimension_0(index, s0),
                unit(owen_scramble(index.reverse_bits(), s0))
            );
            let x = (0..32)
                .filter(|k| index >> k & 1 == 1)
                .fold(0, |x, k| x ^ SOBOL_1[k]);
            assert_eq!(
                laine_karras(sobol_1_reversed(index), s1).reverse_bits(),
                owen_scramble(x, s1)
            );
        }
    }

    #[test]
    fn owen_scramble_keeps_aligned_blocks() {
        // Every aligned block of 2^k values maps onto an aligned block of 2^k values.
        for seed in [1u32, 0xdead_beef, 12345] {
            for k in [1u32, 3, 6] {
                for block in 0..4u32 {
                    let mut out: Vec<u32> = (0..1 << k)
                        .map(|i| owen_scramble((block << k) | i, seed))
                        .collect();
                    out.sort_unstable();
                    let base = out[0] & !((1 << k) - 1);
                    let want: Vec<u32> = (0..1 << k).map(|i| base | i).collect();
                    assert_eq!(out, want, "seed {seed} k {k} block {block}");
                }
            }
        }
    }

    /// RMS error over `reps` pixels of the `n`-sample estimate of the integral of a smooth
    /// function over the unit square, ∫∫ e^x sin(πy) = 2(e − 1)/π, with bounce 0's first 2D
    /// draw of each sample from `draw`.
    fn rms_error(n: u32, reps: u64, draw: impl Fn(u64, u32) -> (f64, f64)) -> f64 {
        let exact = 2.0 * (std::f64::consts::E - 1.0) / std::f64::consts::PI;
        let se: f64 = (0..reps)
            .map(|pixel| {
                let mean = (0..n)
                    .map(|s| {
                        let (x, y) = draw(pixel, s);
                        x.exp() * (std::f64::consts::PI * y).sin()
                    })
                    .sum::<f64>()
                    / n as f64;
                (mean - exact).powi(2)
            })
            .sum();
        (se / reps as f64).sqrt()
    }

    #[test]
    fn error_falls_faster_than_with_independent_samples_on_a_smooth_integrand() {
        let sobol = |pixel: u64, s: u32| {
            let mut p = PixelSampler::new(7, pixel, s);
            p.start_bounce(0);
            p.next_2d()
        };
        let independent = |pixel: u64, s: u32| Rng::new(7, (pixel << 24) | s as u64).next_2d();
        let reps = 128;
        let (s16, s256) = (rms_error(16, reps, sobol), rms_error(256, reps, sobol));
        let (i16, i256) = (
            rms_error(16, reps, independent),
            rms_error(256, reps, independent),
        );
        // Independent sampling: RMS error ∝ N^-1/2, a factor 4 from 16 to 256 samples (the RMS
        // of 128 replicates is itself uncertain by ~6 %, hence the band).
        assert!(
            (3.0..5.3).contains(&(i16 / i256)),
            "independent: {i16:e} -> {i256:e}"
        );
        // Owen-scrambled Sobol: ∝ N^-3/2 for a smooth integrand, a factor 64; at least 24.
        assert!(s16 / s256 > 24.0, "sobol: {s16:e} -> {s256:e}");
        assert!(
            s256 < i256 / 20.0,
            "at 256 samples: sobol {s256:e}, independent {i256:e}"
        );
    }

    #[test]
    fn first_power_of_two_samples_form_a_net() {
        // Any 2^k prefix of a dimension's 2D points has one point in each of the 2^k
        // elementary boxes of every shape 2^a x 2^(k-a).
        let k = 6u32;
        let n = 1u32 << k;
        for pixel in [0u64, 7, 1000] {
            let pts: Vec<(f64, f64)> = (0..n)
                .map(|s| {
                    let mut p = PixelSampler::new(42, pixel, s);
                    p.start_bounce(1);
                    p.next_f64();
                    p.next_2d()
                })
                .collect();
            for a in 0..=k {
                let (nx, ny) = (1u32 << a, 1u32 << (k - a));
                let mut seen = vec![false; n as usize];
                for &(x, y) in &pts {
                    let cell = (y * ny as f64) as usize * nx as usize + (x * nx as f64) as usize;
                    assert!(!seen[cell], "pixel {pixel}: two points in a {nx}x{ny} box");
                    seen[cell] = true;
                }
            }
        }
    }
}
