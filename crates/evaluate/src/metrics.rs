//! Image error metrics, in f64, each checked against an established implementation.
//!
//! Two kinds of input:
//!
//! * [`Display`]: display-referred values in [0, 1] (sRGB-encoded, as shown on a monitor). PSNR,
//!   SSIM, MS-SSIM and FLIP take these. [`Display::from_rgb`] takes an [`RgbImage`]'s values as
//!   they are; [`tonemap`] makes one from linear radiance.
//! * [`RgbImage`]: linear (HDR) values. relMSE and SMAPE take these.
//!
//! All functions take a reference and a test image of the same size (checked by the caller; a
//! `debug_assert` here). Sums are accumulated in f64.
//!
//! # Tonemap
//!
//! [`autoexposure`]`(reference) = 0.18 / exp(mean over pixels of ln(max(Y, 0) + 1e-4))`, with
//! `Y = 0.2126 R + 0.7152 G + 0.0722 B` (Rec. 709 luminance). [`tonemap`]`(image, exposure)`:
//! per channel `x = max(v, 0) * exposure`, `t = x / (1 + x)` (Reinhard, per channel), then the
//! sRGB OETF of IEC 61966-2-1 (`12.92 t` for `t <= 0.0031308`, else `1.055 t^(1/2.4) - 0.055`),
//! clamped to [0, 1].
//!
//! # Metrics
//!
//! * [`psnr`]: `10 log10(1 / MSE)`, data range 1, MSE over all pixels and channels;
//!   `f64::INFINITY` for identical images. Checked against
//!   `skimage.metrics.peak_signal_noise_ratio(data_range=1)` (scikit-image 0.26.0).
//! * [`ssim`]: SSIM of Wang et al. 2004 per channel, then the mean over the 3 channels. Local
//!   statistics with a Gaussian window, sigma 1.5, truncated at 3.5 sigma (11 taps, normalised),
//!   applied separably with half-sample symmetric borders (`d c b a | a b c d`, scipy's
//!   `reflect`); population covariances; `C1 = 0.01^2`, `C2 = 0.03^2`; the SSIM map is averaged
//!   over the image less a 5-pixel border. Checked against
//!   `skimage.metrics.structural_similarity(gaussian_weights=True, sigma=1.5,
//!   use_sample_covariance=False, data_range=1.0, channel_axis=2)` (scikit-image 0.26.0). skimage
//!   refuses images with a side below 11 pixels; here the map is then averaged over the whole
//!   image (not checked against anything).
//! * [`ms_ssim`]: multi-scale SSIM as `pytorch_msssim.ms_ssim(data_range=1, size_average=True,
//!   win_size=11, win_sigma=1.5, K=(0.01, 0.03))` computes it (pytorch_msssim 1.0.0): 11-tap
//!   Gaussian window (sigma 1.5) applied without padding (only the fully covered positions);
//!   per channel and level the mean of the contrast-structure map `cs` (levels 1..L-1) and of the
//!   SSIM map (level L), each clamped below at 0 (relu); between levels a 2x2 average pool with
//!   `s % 2` zero padding on each side of a dimension of odd size `s`, the padding counted in the
//!   average (`avg_pool2d(kernel_size=2, padding=s % 2, count_include_pad=True)`); the result is
//!   the mean over channels of `prod_l value_l^weight_l`. Weights: `[0.0448, 0.2856, 0.3001,
//!   0.2363, 0.1333]` as they are when all 5 levels fit, i.e. when the smaller side exceeds 160
//!   (pytorch_msssim asserts `min(H, W) > (win_size - 1) * 2^4`); for smaller images the largest
//!   level count `L` with `min(H, W) > 10 * 2^(L-1)` and the first `L` weights renormalised to sum
//!   1 (the parity fixture runs pytorch_msssim's own code with these weights). `None` when not
//!   even one level fits (smaller side below 11).
//! * [`flip`]: LDR-FLIP (Andersson et al. 2020, "FLIP: A Difference Evaluator for Alternating
//!   Images"), as NVIDIA's flip_evaluator 1.7 computes it (`flip_evaluator.evaluate(reference,
//!   test, "LDR")`, inputs sRGB-encoded in [0, 1]) at its default viewing conditions: 0.7 m from
//!   a 0.7 m wide monitor of 3840 pixels, [`FLIP_PIXELS_PER_DEGREE`] = 67.0206451416 (their f32
//!   value of `0.7 * 3840 / 0.7 * pi / 180`). Colour pipeline: sRGB to linear, clamp to [0, 1],
//!   linear RGB to XYZ (D65) to YCxCz; separable spatial filtering with the contrast sensitivity
//!   functions (achromatic and red-green: one Gaussian each; blue-yellow: a sum of two Gaussians,
//!   filtered as two separable passes); back to linear RGB, clamped to [0, 1]; CIELab; Hunt
//!   adjustment (`a, b *= 0.01 L`); HyAB distance `|dL| + sqrt(da^2 + db^2)`, raised to 0.7 and
//!   mapped to [0, 1] with `cmax` (the distance of green and blue) and `pc = 0.4`, `pt = 0.95`.
//!   Feature pipeline: the achromatic channel normalised to [0, 1] (`(Y + 16) / 116`), filtered
//!   with first and second derivatives of a Gaussian (sigma `0.5 * 0.082 * ppd` pixels, radius
//!   `ceil(3 sigma)`, positive and negative weights normalised to +1 and -1); edge and point
//!   magnitudes; feature difference `(max(|d edge|, |d point|) / sqrt 2)^0.5`. Error per pixel
//!   `e_c^(1 - e_f)`; [`Flip::mean`] is the mean over pixels. All image filters clamp to the
//!   nearest edge pixel at the borders (as the C++ code does). flip_evaluator computes in f32;
//!   this code in f64.
//! * [`rel_mse`]: linear values, mean over pixels and channels of `(t - r)^2 / (r^2 + 0.01)`
//!   ([`REL_MSE_EPSILON`]).
//! * [`smape`]: linear values, mean over pixels and channels of
//!   `|t - r| / (|t| + |r| + 0.01)` ([`SMAPE_EPSILON`]).
//!
//! relMSE, SMAPE, the tonemap and the autoexposure are checked against numpy float64
//! transcriptions of these definitions. The parity test is `tests/metrics_parity.rs`, on the
//! fixtures written by `tests/fixtures/metrics/generate.py` (repository root); every value there
//! matches to 1e-4 (absolute).

use luxest_core::exr_io::{srgb_encode, RgbImage};

/// Epsilon in the denominator of [`rel_mse`].
pub const REL_MSE_EPSILON: f64 = 0.01;
/// Epsilon in the denominator of [`smape`].
pub const SMAPE_EPSILON: f64 = 0.01;
/// MS-SSIM level weights (Wang et al. 2003, as pytorch_msssim's default).
pub const MS_SSIM_WEIGHTS: [f64; 5] = [0.0448, 0.2856, 0.3001, 0.2363, 0.1333];
/// FLIP's default pixels per degree: flip_evaluator's `calculatePPD(0.7, 3840, 0.7)` evaluated in
/// f32 (0.7 m viewing distance, 3840 pixels across a 0.7 m wide monitor).
pub const FLIP_PIXELS_PER_DEGREE: f64 = 67.020_645_141_601_56;

/// A display-referred image, values in [0, 1], row-major, f64.
#[derive(Clone, Debug, PartialEq)]
pub struct Display {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f64; 3]>,
}

impl Display {
    /// The image's values as they are (no tonemap, no clamp).
    pub fn from_rgb(image: &RgbImage) -> Display {
        Display {
            width: image.width,
            height: image.height,
            pixels: image
                .pixels
                .iter()
                .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
                .collect(),
        }
    }

    /// One channel as a plane, row-major.
    fn channel(&self, c: usize) -> Vec<f64> {
        self.pixels.iter().map(|p| p[c]).collect()
    }
}

fn debug_check_sizes(rw: usize, rh: usize, tw: usize, th: usize, rn: usize, tn: usize) {
    debug_assert!(
        rw == tw && rh == th,
        "image sizes differ: {rw} x {rh} and {tw} x {th}"
    );
    debug_assert!(
        rn == rw * rh && tn == tw * th,
        "pixel count is not width * height"
    );
}

fn check_display(reference: &Display, test: &Display) {
    debug_check_sizes(
        reference.width,
        reference.height,
        test.width,
        test.height,
        reference.pixels.len(),
        test.pixels.len(),
    );
}

fn check_rgb(reference: &RgbImage, test: &RgbImage) {
    debug_check_sizes(
        reference.width,
        reference.height,
        test.width,
        test.height,
        reference.pixels.len(),
        test.pixels.len(),
    );
}

// ------------------------------------------------------------------------------------ tonemap

/// `0.18 / exp(mean over pixels of ln(max(Y, 0) + 1e-4))`, `Y = 0.2126 R + 0.7152 G + 0.0722 B`,
/// accumulated in f64; 1 for an empty image. The same exposure the denoiser uses
/// ([`RgbImage::autoexposure`], shared with training/transfer.py).
pub fn autoexposure(reference: &RgbImage) -> f64 {
    reference.autoexposure()
}

/// Per channel `x = max(v, 0) * exposure`, `t = x / (1 + x)`, the sRGB OETF, clamped to [0, 1].
pub fn tonemap(image: &RgbImage, exposure: f64) -> Display {
    let map = |v: f32| {
        let x = (v as f64).max(0.0) * exposure;
        srgb_encode(x / (1.0 + x))
    };
    Display {
        width: image.width,
        height: image.height,
        pixels: image
            .pixels
            .iter()
            .map(|p| [map(p[0]), map(p[1]), map(p[2])])
            .collect(),
    }
}

// --------------------------------------------------------------------------------------- PSNR

/// `10 log10(1 / MSE)`, MSE over all pixels and channels; `f64::INFINITY` for identical images.
pub fn psnr(reference: &Display, test: &Display) -> f64 {
    check_display(reference, test);
    let n = 3 * reference.pixels.len();
    if n == 0 {
        return f64::INFINITY;
    }
    let sum: f64 = reference
        .pixels
        .iter()
        .zip(&test.pixels)
        .map(|(r, t)| (0..3).map(|c| (t[c] - r[c]) * (t[c] - r[c])).sum::<f64>())
        .sum();
    let mse = sum / n as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        -10.0 * mse.log10()
    }
}

// ------------------------------------------------------------------------------ filter helpers

/// How a 1-D filter reads outside the image.
#[derive(Clone, Copy)]
enum Border {
    /// Half-sample symmetric: `d c b a | a b c d | d c b a` (scipy.ndimage `reflect`).
    Reflect,
    /// The nearest edge sample (FLIP).
    Clamp,
}

fn border_index(i: isize, n: usize, border: Border) -> usize {
    let n = n as isize;
    match border {
        Border::Clamp => i.clamp(0, n - 1) as usize,
        Border::Reflect => {
            let period = 2 * n;
            let m = i.rem_euclid(period);
            (if m < n { m } else { period - 1 - m }) as usize
        }
    }
}

/// Correlates a `w` x `h` plane with `kernel` (odd length, centred) along x (`along_x`) or y;
/// output of the same size.
fn filter_1d(
    src: &[f64],
    w: usize,
    h: usize,
    kernel: &[f64],
    along_x: bool,
    border: Border,
) -> Vec<f64> {
    let r = (kernel.len() / 2) as isize;
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut acc = 0.0;
            for (k, weight) in kernel.iter().enumerate() {
                let d = k as isize - r;
                let i = if along_x {
                    y * w + border_index(x as isize + d, w, border)
                } else {
                    border_index(y as isize + d, h, border) * w + x
                };
                acc += weight * src[i];
            }
            out[y * w + x] = acc;
        }
    }
    out
}

/// Separable filter, first along y then along x (scipy's axis order).
fn filter_2d(src: &[f64], w: usize, h: usize, kernel: &[f64], border: Border) -> Vec<f64> {
    let tmp = filter_1d(src, w, h, kernel, false, border);
    filter_1d(&tmp, w, h, kernel, true, border)
}

/// Correlation without padding: only positions the kernel covers fully, first along y then x
/// (pytorch_msssim). A dimension shorter than the kernel is left unfiltered, as there.
fn filter_valid(src: &[f64], w: usize, h: usize, kernel: &[f64]) -> (Vec<f64>, usize, usize) {
    let k = kernel.len();
    let (mut cur, mut cw, mut ch) = (src.to_vec(), w, h);
    if ch >= k {
        let nh = ch - k + 1;
        let mut out = vec![0.0; cw * nh];
        for y in 0..nh {
            for x in 0..cw {
                out[y * cw + x] = (0..k).map(|j| kernel[j] * cur[(y + j) * cw + x]).sum();
            }
        }
        cur = out;
        ch = nh;
    }
    if cw >= k {
        let nw = cw - k + 1;
        let mut out = vec![0.0; nw * ch];
        for y in 0..ch {
            for x in 0..nw {
                out[y * nw + x] = (0..k).map(|j| kernel[j] * cur[y * cw + x + j]).sum();
            }
        }
        cur = out;
        cw = nw;
    }
    (cur, cw, ch)
}

fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len() as f64
}

// --------------------------------------------------------------------------------------- SSIM

const SSIM_C1: f64 = 0.01 * 0.01;
const SSIM_C2: f64 = 0.03 * 0.03;

/// scipy.ndimage's Gaussian kernel: sigma 1.5, radius `int(3.5 * 1.5 + 0.5)` = 5, normalised.
fn scipy_gaussian_kernel() -> Vec<f64> {
    let sigma: f64 = 1.5;
    let radius = (3.5 * sigma + 0.5) as i32;
    let k: Vec<f64> = (-radius..=radius)
        .map(|x| (-0.5 / (sigma * sigma) * (x * x) as f64).exp())
        .collect();
    let s: f64 = k.iter().sum();
    k.into_iter().map(|v| v / s).collect()
}

/// The SSIM map of one channel (same size as the input), skimage's way.
fn ssim_map(a: &[f64], b: &[f64], w: usize, h: usize, kernel: &[f64]) -> Vec<f64> {
    let f = |p: &[f64]| filter_2d(p, w, h, kernel, Border::Reflect);
    let prod = |p: &[f64], q: &[f64]| p.iter().zip(q).map(|(x, y)| x * y).collect::<Vec<f64>>();
    let ux = f(a);
    let uy = f(b);
    let uxx = f(&prod(a, a));
    let uyy = f(&prod(b, b));
    let uxy = f(&prod(a, b));
    (0..w * h)
        .map(|i| {
            let vx = uxx[i] - ux[i] * ux[i];
            let vy = uyy[i] - uy[i] * uy[i];
            let vxy = uxy[i] - ux[i] * uy[i];
            let a1 = 2.0 * ux[i] * uy[i] + SSIM_C1;
            let a2 = 2.0 * vxy + SSIM_C2;
            let b1 = ux[i] * ux[i] + uy[i] * uy[i] + SSIM_C1;
            let b2 = vx + vy + SSIM_C2;
            (a1 * a2) / (b1 * b2)
        })
        .collect()
}

/// Mean SSIM over the 3 channels (see the module documentation).
pub fn ssim(reference: &Display, test: &Display) -> f64 {
    check_display(reference, test);
    let (w, h) = (reference.width, reference.height);
    if w == 0 || h == 0 {
        return 1.0;
    }
    let kernel = scipy_gaussian_kernel();
    let pad = kernel.len() / 2;
    let crop = w > 2 * pad && h > 2 * pad;
    let mut total = 0.0;
    for c in 0..3 {
        let s = ssim_map(&reference.channel(c), &test.channel(c), w, h, &kernel);
        total += if crop {
            let mut sum = 0.0;
            for y in pad..h - pad {
                sum += s[y * w + pad..y * w + w - pad].iter().sum::<f64>();
            }
            sum / ((w - 2 * pad) * (h - 2 * pad)) as f64
        } else {
            mean(&s)
        };
    }
    total / 3.0
}

// ------------------------------------------------------------------------------------ MS-SSIM

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
    check_display(reference, test);
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

// --------------------------------------------------------------------------------------- FLIP

/// A FLIP evaluation.
#[derive(Clone, Debug, PartialEq)]
pub struct Flip {
    /// Mean of the error map.
    pub mean: f64,
    /// Error per pixel in [0, 1], row-major.
    pub map: Vec<f32>,
}

const FLIP_QC: f64 = 0.7;
const FLIP_PC: f64 = 0.4;
const FLIP_PT: f64 = 0.95;
const FLIP_W: f64 = 0.082;
const FLIP_QF: f64 = 0.5;
/// D65 reference white of FLIP's XYZ <-> YCxCz / CIELab conversions.
const FLIP_WHITE: [f64; 3] = [0.950428545, 1.0, 1.088900371];
const FLIP_INV_WHITE: [f64; 3] = [1.052156925, 1.0, 0.918357670];

fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_rgb_to_xyz(c: [f64; 3]) -> [f64; 3] {
    const M: [[f64; 3]; 3] = [
        [
            10135552.0 / 24577794.0,
            8788810.0 / 24577794.0,
            4435075.0 / 24577794.0,
        ],
        [
            2613072.0 / 12288897.0,
            8788810.0 / 12288897.0,
            887015.0 / 12288897.0,
        ],
        [
            1425312.0 / 73733382.0,
            8788810.0 / 73733382.0,
            70074185.0 / 73733382.0,
        ],
    ];
    mat3(&M, c)
}

fn xyz_to_linear_rgb(c: [f64; 3]) -> [f64; 3] {
    const M: [[f64; 3]; 3] = [
        [3.241003275, -1.537398934, -0.498615861],
        [-0.969224334, 1.875930071, 0.041554224],
        [0.055639423, -0.204011202, 1.057148933],
    ];
    mat3(&M, c)
}

fn mat3(m: &[[f64; 3]; 3], c: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|r| m[r][0] * c[0] + m[r][1] * c[1] + m[r][2] * c[2])
}

fn xyz_to_ycxcz(c: [f64; 3]) -> [f64; 3] {
    let x = c[0] * FLIP_INV_WHITE[0];
    let y = c[1] * FLIP_INV_WHITE[1];
    let z = c[2] * FLIP_INV_WHITE[2];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_xyz(c: [f64; 3]) -> [f64; 3] {
    let y = (c[0] + 16.0) / 116.0;
    let x = y + c[1] / 500.0;
    let z = y - c[2] / 200.0;
    [x * FLIP_WHITE[0], y * FLIP_WHITE[1], z * FLIP_WHITE[2]]
}

fn xyz_to_cielab(c: [f64; 3]) -> [f64; 3] {
    let delta = 6.0 / 29.0;
    let delta_cube = delta * delta * delta;
    let factor = 1.0 / (3.0 * delta * delta);
    let term = 4.0 / 29.0;
    let f = |v: f64| {
        if v > delta_cube {
            v.cbrt()
        } else {
            factor * v + term
        }
    };
    let x = f(c[0] * FLIP_INV_WHITE[0]);
    let y = f(c[1] * FLIP_INV_WHITE[1]);
    let z = f(c[2] * FLIP_INV_WHITE[2]);
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// CIELab with the Hunt adjustment: a and b scaled by `0.01 L`.
fn hunt(lab: [f64; 3]) -> [f64; 3] {
    [lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]]
}

fn hyab(a: [f64; 3], b: [f64; 3]) -> f64 {
    (a[0] - b[0]).abs() + ((a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// `HyAB(green, blue)^0.7` in Hunt-adjusted CIELab: the largest colour distance.
fn flip_cmax() -> f64 {
    let lab = |rgb: [f64; 3]| hunt(xyz_to_cielab(linear_rgb_to_xyz(rgb)));
    hyab(lab([0.0, 1.0, 0.0]), lab([0.0, 0.0, 1.0])).powf(FLIP_QC)
}

/// The separated CSF filters: (achromatic, red-green, blue-yellow part 1, blue-yellow part 2).
fn flip_spatial_filters(ppd: f64) -> [Vec<f64>; 4] {
    use std::f64::consts::PI;
    // (a, b) of the Gaussians: achromatic, red-green, blue-yellow (two).
    const A1: [f64; 3] = [1.0, 1.0, 34.1];
    const B1: [f64; 3] = [0.0047, 0.0053, 0.04];
    const A2Z: f64 = 13.5;
    const B2Z: f64 = 0.025;
    let max_b = 0.04f64; // the largest scale parameter (b1 of blue-yellow)
    let radius = (3.0 * (max_b / (2.0 * PI * PI)).sqrt() * ppd).ceil() as i64;
    let gaussian = |x2: f64, a: f64, b: f64| a * (PI / b).sqrt() * (-PI * PI * x2 / b).exp();
    let gaussian_sqrt =
        |x2: f64, a: f64, b: f64| (a * (PI / b).sqrt()).sqrt() * (-PI * PI * x2 / b).exp();
    let mut f: [Vec<f64>; 4] = Default::default();
    for i in -radius..=radius {
        let x = i as f64 / ppd;
        let x2 = x * x;
        f[0].push(gaussian(x2, A1[0], B1[0]));
        f[1].push(gaussian(x2, A1[1], B1[1]));
        f[2].push(gaussian_sqrt(x2, A1[2], B1[2]));
        f[3].push(gaussian_sqrt(x2, A2Z, B2Z));
    }
    let sums: Vec<f64> = f.iter().map(|k| k.iter().sum()).collect();
    let norm_z = 1.0 / (sums[2] * sums[2] + sums[3] * sums[3]).sqrt();
    let norms = [1.0 / sums[0], 1.0 / sums[1], norm_z, norm_z];
    for (k, n) in f.iter_mut().zip(norms) {
        k.iter_mut().for_each(|v| *v *= n);
    }
    f
}

/// The feature filters: (Gaussian, first derivative, second derivative).
fn flip_feature_filters(ppd: f64) -> [Vec<f64>; 3] {
    let sd = 0.5 * FLIP_W * ppd;
    let radius = (3.0 * sd).ceil() as i64;
    let mut g = Vec::new();
    let mut dg = Vec::new();
    let mut ddg = Vec::new();
    for i in -radius..=radius {
        let x = i as f64;
        let gv = (-(x * x) / (2.0 * sd * sd)).exp();
        g.push(gv);
        dg.push(-x * gv);
        ddg.push((x * x / (sd * sd) - 1.0) * gv);
    }
    let g_sum: f64 = g.iter().sum();
    let pos = |k: &[f64]| k.iter().filter(|v| **v > 0.0).sum::<f64>();
    let neg = |k: &[f64]| -k.iter().filter(|v| **v <= 0.0).sum::<f64>();
    let (dp, dn, ddp, ddn) = (pos(&dg), neg(&dg), pos(&ddg), neg(&ddg));
    g.iter_mut().for_each(|v| *v /= g_sum);
    dg.iter_mut()
        .for_each(|v| *v /= if *v > 0.0 { dp } else { dn });
    ddg.iter_mut()
        .for_each(|v| *v /= if *v > 0.0 { ddp } else { ddn });
    [g, dg, ddg]
}

/// Spatially filtered, Hunt-adjusted CIELab of a YCxCz image given as three planes.
fn flip_filtered_lab(
    ycxcz: &[Vec<f64>; 3],
    w: usize,
    h: usize,
    f: &[Vec<f64>; 4],
) -> Vec<[f64; 3]> {
    let sep = |p: &[f64], k: &[f64]| {
        let tmp = filter_1d(p, w, h, k, true, Border::Clamp);
        filter_1d(&tmp, w, h, k, false, Border::Clamp)
    };
    let y = sep(&ycxcz[0], &f[0]);
    let cx = sep(&ycxcz[1], &f[1]);
    let cz1 = sep(&ycxcz[2], &f[2]);
    let cz2 = sep(&ycxcz[2], &f[3]);
    (0..w * h)
        .map(|i| {
            let rgb = xyz_to_linear_rgb(ycxcz_to_xyz([y[i], cx[i], cz1[i] + cz2[i]]))
                .map(|v| v.clamp(0.0, 1.0));
            hunt(xyz_to_cielab(linear_rgb_to_xyz(rgb)))
        })
        .collect()
}

/// Edge and point magnitudes of the normalised achromatic channel.
fn flip_features(y: &[f64], w: usize, h: usize, f: &[Vec<f64>; 3]) -> (Vec<f64>, Vec<f64>) {
    let gray: Vec<f64> = y.iter().map(|v| (v + 16.0) / 116.0).collect();
    let along_x = |p: &[f64], k: &[f64]| filter_1d(p, w, h, k, true, Border::Clamp);
    let along_y = |p: &[f64], k: &[f64]| filter_1d(p, w, h, k, false, Border::Clamp);
    let gx = along_x(&gray, &f[0]);
    let dx = along_y(&along_x(&gray, &f[1]), &f[0]);
    let ddx = along_y(&along_x(&gray, &f[2]), &f[0]);
    let dy = along_y(&gx, &f[1]);
    let ddy = along_y(&gx, &f[2]);
    let edge = dx.iter().zip(&dy).map(|(a, b)| a.hypot(*b)).collect();
    let point = ddx.iter().zip(&ddy).map(|(a, b)| a.hypot(*b)).collect();
    (edge, point)
}

fn flip_ycxcz_planes(image: &Display) -> [Vec<f64>; 3] {
    let mut planes: [Vec<f64>; 3] = Default::default();
    for p in &image.pixels {
        let linear = p.map(|v| srgb_to_linear(v).clamp(0.0, 1.0));
        let c = xyz_to_ycxcz(linear_rgb_to_xyz(linear));
        for k in 0..3 {
            planes[k].push(c[k]);
        }
    }
    planes
}

/// LDR-FLIP of sRGB-encoded display images at [`FLIP_PIXELS_PER_DEGREE`].
pub fn flip(reference: &Display, test: &Display) -> Flip {
    flip_with_ppd(reference, test, FLIP_PIXELS_PER_DEGREE)
}

/// LDR-FLIP at `ppd` pixels per degree of visual angle.
pub fn flip_with_ppd(reference: &Display, test: &Display, ppd: f64) -> Flip {
    check_display(reference, test);
    let (w, h) = (reference.width, reference.height);
    if w == 0 || h == 0 {
        return Flip {
            mean: 0.0,
            map: Vec::new(),
        };
    }
    let ref_ycxcz = flip_ycxcz_planes(reference);
    let test_ycxcz = flip_ycxcz_planes(test);

    let spatial = flip_spatial_filters(ppd);
    let ref_lab = flip_filtered_lab(&ref_ycxcz, w, h, &spatial);
    let test_lab = flip_filtered_lab(&test_ycxcz, w, h, &spatial);
    let cmax = flip_cmax();
    let pccmax = FLIP_PC * cmax;

    let feature = flip_feature_filters(ppd);
    let (ref_edge, ref_point) = flip_features(&ref_ycxcz[0], w, h, &feature);
    let (test_edge, test_point) = flip_features(&test_ycxcz[0], w, h, &feature);

    let mut map = Vec::with_capacity(w * h);
    let mut sum = 0.0;
    for i in 0..w * h {
        let d = hyab(ref_lab[i], test_lab[i]).powf(FLIP_QC);
        let color = if d < pccmax {
            d * FLIP_PT / pccmax
        } else {
            FLIP_PT + (d - pccmax) / (cmax - pccmax) * (1.0 - FLIP_PT)
        };
        let edge = (ref_edge[i] - test_edge[i]).abs();
        let point = (ref_point[i] - test_point[i]).abs();
        let feature = (edge.max(point) / std::f64::consts::SQRT_2).powf(FLIP_QF);
        let e = color.powf(1.0 - feature);
        sum += e;
        map.push(e as f32);
    }
    Flip {
        mean: sum / (w * h) as f64,
        map,
    }
}

// ------------------------------------------------------------------------- relMSE and SMAPE

fn mean_over_channels(
    reference: &RgbImage,
    test: &RgbImage,
    term: impl Fn(f64, f64) -> f64,
) -> f64 {
    check_rgb(reference, test);
    let n = 3 * reference.pixels.len();
    if n == 0 {
        return 0.0;
    }
    let sum: f64 = reference
        .pixels
        .iter()
        .zip(&test.pixels)
        .map(|(r, t)| (0..3).map(|c| term(r[c] as f64, t[c] as f64)).sum::<f64>())
        .sum();
    sum / n as f64
}

/// Linear values: mean over pixels and channels of `(t - r)^2 / (r^2 + 0.01)`.
pub fn rel_mse(reference: &RgbImage, test: &RgbImage) -> f64 {
    mean_over_channels(reference, test, |r, t| {
        (t - r) * (t - r) / (r * r + REL_MSE_EPSILON)
    })
}

/// Linear values: mean over pixels and channels of `|t - r| / (|t| + |r| + 0.01)`.
pub fn smape(reference: &RgbImage, test: &RgbImage) -> f64 {
    mean_over_channels(reference, test, |r, t| {
        (t - r).abs() / (t.abs() + r.abs() + SMAPE_EPSILON)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic structured image with values in [0, 1].
    fn pattern(w: usize, h: usize, seed: u64) -> Display {
        let mut state = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut pixels = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let u = x as f64 / w as f64;
                let v = y as f64 / h as f64;
                let edge = if x > w / 2 { 0.3 } else { 0.0 };
                pixels.push([
                    (0.2 + 0.5 * u + edge + 0.05 * next()).clamp(0.0, 1.0),
                    (0.1 + 0.6 * v + 0.05 * next()).clamp(0.0, 1.0),
                    (0.5 + 0.3 * (6.0 * u + 3.0 * v).sin() + 0.05 * next()).clamp(0.0, 1.0),
                ]);
            }
        }
        Display {
            width: w,
            height: h,
            pixels,
        }
    }

    fn rgb(d: &Display, scale: f32) -> RgbImage {
        let mut image = RgbImage::new(d.width, d.height);
        image.pixels = d
            .pixels
            .iter()
            .map(|p| p.map(|v| v as f32 * scale))
            .collect();
        image
    }

    #[test]
    fn identical_images() {
        let a = pattern(40, 33, 1);
        assert_eq!(psnr(&a, &a), f64::INFINITY);
        assert!((ssim(&a, &a) - 1.0).abs() < 1e-12);
        assert!((ms_ssim(&a, &a).unwrap() - 1.0).abs() < 1e-12);
        let f = flip(&a, &a);
        assert_eq!(f.mean, 0.0);
        assert!(f.map.iter().all(|v| *v == 0.0));
        let r = rgb(&a, 20.0);
        assert_eq!(rel_mse(&r, &r), 0.0);
        assert_eq!(smape(&r, &r), 0.0);
    }

    #[test]
    fn symmetric_metrics() {
        let (a, b) = (pattern(37, 45, 2), pattern(37, 45, 3));
        assert_eq!(psnr(&a, &b), psnr(&b, &a));
        assert!((ssim(&a, &b) - ssim(&b, &a)).abs() < 1e-12);
        assert!((ms_ssim(&a, &b).unwrap() - ms_ssim(&b, &a).unwrap()).abs() < 1e-12);
        assert!((flip(&a, &b).mean - flip(&b, &a).mean).abs() < 1e-12);
        let (ra, rb) = (rgb(&a, 10.0), rgb(&b, 10.0));
        assert!((smape(&ra, &rb) - smape(&rb, &ra)).abs() < 1e-15);
    }

    #[test]
    fn ranges_and_ordering() {
        let a = pattern(50, 40, 4);
        let mut b = a.clone();
        let mut c = a.clone();
        for (i, p) in b.pixels.iter_mut().enumerate() {
            let d = if i % 2 == 0 { 0.02 } else { -0.02 };
            *p = p.map(|v| (v + d).clamp(0.0, 1.0));
        }
        for (i, p) in c.pixels.iter_mut().enumerate() {
            let d = if i % 2 == 0 { 0.2 } else { -0.2 };
            *p = p.map(|v| (v + d).clamp(0.0, 1.0));
        }
        assert!(psnr(&a, &b) > psnr(&a, &c));
        assert!(ssim(&a, &b) > ssim(&a, &c));
        assert!(ms_ssim(&a, &b).unwrap() > ms_ssim(&a, &c).unwrap());
        let (fb, fc) = (flip(&a, &b), flip(&a, &c));
        assert!(fb.mean < fc.mean);
        assert!(fc.map.iter().all(|v| (0.0..=1.0).contains(v)));
        assert_eq!(fc.map.len(), 50 * 40);
        let mean: f64 = fc.map.iter().map(|v| *v as f64).sum::<f64>() / fc.map.len() as f64;
        assert!((mean - fc.mean).abs() < 1e-6);
    }

    #[test]
    fn ms_ssim_level_count() {
        assert_eq!(ms_ssim_levels(10), 0);
        assert_eq!(ms_ssim_levels(11), 1);
        assert_eq!(ms_ssim_levels(20), 1);
        assert_eq!(ms_ssim_levels(21), 2);
        assert_eq!(ms_ssim_levels(160), 4);
        assert_eq!(ms_ssim_levels(161), 5);
        assert_eq!(ms_ssim_levels(4000), 5);
        assert_eq!(ms_ssim_weights(5), MS_SSIM_WEIGHTS.to_vec());
        let w2 = ms_ssim_weights(2);
        assert!((w2.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert!((w2[0] / w2[1] - 0.0448 / 0.2856).abs() < 1e-12);
        let small = pattern(10, 30, 5);
        assert_eq!(ms_ssim(&small, &small), None);
        let one = pattern(11, 30, 5);
        assert!(ms_ssim(&one, &pattern(11, 30, 6)).is_some());
    }

    #[test]
    fn avg_pool_counts_padding() {
        // 3 x 2 image: odd width pads x by 1 on both sides; even height, no padding in y.
        let src = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let (out, w, h) = avg_pool(&src, 3, 2);
        assert_eq!((w, h), (2, 1));
        assert_eq!(out, vec![(1.0 + 4.0) / 4.0, (2.0 + 3.0 + 5.0 + 6.0) / 4.0]);
    }

    #[test]
    fn reflect_border() {
        assert_eq!(border_index(-1, 4, Border::Reflect), 0);
        assert_eq!(border_index(-2, 4, Border::Reflect), 1);
        assert_eq!(border_index(4, 4, Border::Reflect), 3);
        assert_eq!(border_index(5, 4, Border::Reflect), 2);
        assert_eq!(border_index(-5, 2, Border::Reflect), 0); // b a a b | a b
        assert_eq!(border_index(-3, 2, Border::Reflect), 1);
        assert_eq!(border_index(-3, 4, Border::Clamp), 0);
        assert_eq!(border_index(9, 4, Border::Clamp), 3);
    }

    #[test]
    fn tonemap_and_exposure() {
        let mut image = RgbImage::new(2, 1);
        image.pixels = vec![[0.0, -1.0, 1.0], [1e6, 0.5, 0.002]];
        let d = tonemap(&image, 1.0);
        assert_eq!(d.pixels[0][0], 0.0);
        assert_eq!(d.pixels[0][1], 0.0);
        assert!((d.pixels[0][2] - srgb_encode(0.5)).abs() < 1e-15);
        assert!(d.pixels[1][0] <= 1.0 && d.pixels[1][0] > 0.999);
        let x = 0.002f32 as f64;
        let t = x / (1.0 + x);
        assert!((d.pixels[1][2] - 12.92 * t).abs() < 1e-15);
        // A uniform image of luminance Y gets exposure 0.18 / (Y + 1e-4).
        let mut grey = RgbImage::new(3, 2);
        grey.pixels = vec![[0.5; 3]; 6];
        assert!((autoexposure(&grey) - 0.18 / (0.5f64 + 1e-4)).abs() < 1e-12);
    }

    #[test]
    fn rel_mse_and_smape_values() {
        let mut r = RgbImage::new(1, 1);
        r.pixels = vec![[1.0, 0.0, 2.0]];
        let mut t = RgbImage::new(1, 1);
        t.pixels = vec![[2.0, 0.1, 2.0]];
        let expected_rel = (1.0 / 1.01 + 0.01 / 0.01 + 0.0) / 3.0;
        assert!((rel_mse(&r, &t) - expected_rel).abs() < 1e-7);
        let expected_smape = (1.0 / 3.01 + 0.1 / 0.11 + 0.0) / 3.0;
        assert!((smape(&r, &t) - expected_smape).abs() < 1e-7);
    }
}
