//! MS-SSIM of display-referred images.
//!
//! [`ms_ssim`]: multi-scale SSIM as `pytorch_msssim.ms_ssim(data_range=1, size_average=True,
//! win_size=11, win_sigma=1.5, K=(0.01, 0.03))` computes it (pytorch_msssim 1.0.0): 11-tap
//! Gaussian window (sigma 1.5) applied without padding (only the fully covered positions);
//! per channel and level the mean of the contrast-structure map `cs` (levels 1..L-1) and of the
//! SSIM map (level L), each clamped below at 0 (relu); between levels a 2x2 average pool with
//! `s % 2` zero padding on each side of a dimension of odd size `s`, the padding counted in the
//! average (`avg_pool2d(kernel_size=2, padding=s % 2, count_include_pad=True)`); the result is
//! the mean over channels of `prod_l value_l^weight_l`. Weights: `[0.0448, 0.2856, 0.3001,
//! 0.2363, 0.1333]` as they are when all 5 levels fit, i.e. when the smaller side exceeds 160
//! (pytorch_msssim asserts `min(H, W) > (win_size - 1) * 2^4`); for smaller images the largest
//! level count `L` with `min(H, W) > 10 * 2^(L-1)` and the first `L` weights renormalised to sum
//! 1 (the parity fixture runs pytorch_msssim's own code with these weights). `None` when not
//! even one level fits (smaller side below 11).

use super::filter::filter_valid;
use super::ssim::{SSIM_C1, SSIM_C2};
use super::{check_sizes, Display};

/// MS-SSIM level weights (Wang et al. 2003, as pytorch_msssim's default).
pub const MS_SSIM_WEIGHTS: [f64; 5] = [0.0448, 0.2856, 0.3001, 0.2363, 0.1333];

/// The number of MS-SSIM levels for an image whose smaller side is `min_side`: the largest `L`
/// in 1..=5 with `min_side > 10 * 2^(L-1)`, or 0 when none fits.
pub fn ms_ssim_levels(min_side: usize) -> usize {
    (1..=5usize)
        .filter(|&l| min_side > 10 << (l - 1))
        .max()
        .unwrap_or(0)
}

/// The level weights used for `levels` levels: the defaults for 5, else the first `levels`
/// renormalised to sum 1.
pub fn ms_ssim_weights(levels: usize) -> Vec<f64> {
    let w = &MS_SSIM_WEIGHTS[..levels.min(5)];
    if levels >= 5 {
        return w.to_vec();
    }
    let s: f64 = w.iter().sum();
    w.iter().map(|v| v / s).collect()
}

/// pytorch_msssim's window: 11 taps, sigma 1.5, in f32 as there (its float32 `torch.exp`, a
/// sum that equals the correctly rounded one, then the f32 division), bit for bit. The bits
/// matter: SSIM's variances `E[x^2] - E[x]^2` cancel, so a kernel whose sum is off by one f32
/// ulp (a naive f32 sum) moves MS-SSIM by up to 5e-6.
fn msssim_kernel() -> Vec<f64> {
    let g: Vec<f32> = (-5i32..=5)
        .map(|i| {
            let c = i as f32;
            let e = -(c * c) / (2.0f32 * 1.5 * 1.5);
            (e as f64).exp() as f32
        })
        .collect();
    let s = g.iter().map(|v| *v as f64).sum::<f64>() as f32;
    g.into_iter().map(|v| (v / s) as f64).collect()
}

/// Per-channel (mean SSIM, mean cs) of one level, valid filtering.
fn msssim_level(a: &[f64], b: &[f64], w: usize, h: usize, kernel: &[f64]) -> (f64, f64) {
    let f = |p: &[f64]| filter_valid(p, w, h, kernel);
    let prod = |p: &[f64], q: &[f64]| p.iter().zip(q).map(|(x, y)| x * y).collect::<Vec<f64>>();
    let (mu1, _, _) = f(a);
    let (mu2, _, _) = f(b);
    let (s11, _, _) = f(&prod(a, a));
    let (s22, _, _) = f(&prod(b, b));
    let (s12, _, _) = f(&prod(a, b));
    let n = mu1.len();
    let (mut ssim_sum, mut cs_sum) = (0.0, 0.0);
    for i in 0..n {
        let (m1, m2) = (mu1[i], mu2[i]);
        let sigma1 = s11[i] - m1 * m1;
        let sigma2 = s22[i] - m2 * m2;
        let sigma12 = s12[i] - m1 * m2;
        let cs = (2.0 * sigma12 + SSIM_C2) / (sigma1 + sigma2 + SSIM_C2);
        ssim_sum += (2.0 * m1 * m2 + SSIM_C1) / (m1 * m1 + m2 * m2 + SSIM_C1) * cs;
        cs_sum += cs;
    }
    (ssim_sum / n as f64, cs_sum / n as f64)
}

/// 2x2 average pool, zero padding `s % 2` on both sides of a dimension of size `s`, the padding
/// counted in the average (torch `avg_pool2d(kernel_size=2, padding=s % 2)`).
fn avg_pool(src: &[f64], w: usize, h: usize) -> (Vec<f64>, usize, usize) {
    let (px, py) = (w % 2, h % 2);
    let nw = (w + 2 * px - 2) / 2 + 1;
    let nh = (h + 2 * py - 2) / 2 + 1;
    let mut out = vec![0.0; nw * nh];
    for oy in 0..nh {
        for ox in 0..nw {
            let mut sum = 0.0;
            for dy in 0..2 {
                for dx in 0..2 {
                    let y = (2 * oy + dy) as isize - py as isize;
                    let x = (2 * ox + dx) as isize - px as isize;
                    if y >= 0 && x >= 0 && (y as usize) < h && (x as usize) < w {
                        sum += src[y as usize * w + x as usize];
                    }
                }
            }
            out[oy * nw + ox] = sum / 4.0;
        }
    }
    (out, nw, nh)
}

/// MS-SSIM (see the module documentation); `None` when the smaller side is below 11 pixels.
pub fn ms_ssim(reference: &Display, test: &Display) -> Option<f64> {
    check_sizes(reference, test);
    let levels = ms_ssim_levels(reference.width.min(reference.height));
    if levels == 0 {
        return None;
    }
    let weights = ms_ssim_weights(levels);
    let kernel = msssim_kernel();
    let mut total = 0.0;
    for c in 0..3 {
        let (mut a, mut b) = (reference.channel(c), test.channel(c));
        let (mut w, mut h) = (reference.width, reference.height);
        let mut value = 1.0;
        for (level, weight) in weights.iter().enumerate() {
            let (s, cs) = msssim_level(&a, &b, w, h, &kernel);
            if level + 1 < levels {
                value *= cs.max(0.0).powf(*weight);
                let (na, nw, nh) = avg_pool(&a, w, h);
                let (nb, _, _) = avg_pool(&b, w, h);
                (a, b, w, h) = (na, nb, nw, nh);
            } else {
                value *= s.max(0.0).powf(*weight);
            }
        }
        total += value;
    }
    Some(total / 3.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn avg_pool_counts_padding() {
        // 3 x 2 image: odd width pads x by 1 on both sides; even height, no padding in y.
        let src = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let (out, w, h) = avg_pool(&src, 3, 2);
        assert_eq!((w, h), (2, 1));
        assert_eq!(out, vec![(1.0 + 4.0) / 4.0, (2.0 + 3.0 + 5.0 + 6.0) / 4.0]);
    }
}
