//! SSIM of display-referred images.
//!
//! [`ssim`]: SSIM of Wang et al. 2004 per channel, then the mean over the 3 channels. Local
//! statistics with a Gaussian window, sigma 1.5, truncated at 3.5 sigma (11 taps, normalised),
//! applied separably with half-sample symmetric borders (`d c b a | a b c d`, scipy's
//! `reflect`); population covariances; `C1 = 0.01^2`, `C2 = 0.03^2`; the SSIM map is averaged
//! over the image less a 5-pixel border. Checked against
//! `skimage.metrics.structural_similarity(gaussian_weights=True, sigma=1.5,
//! use_sample_covariance=False, data_range=1.0, channel_axis=2)` (scikit-image 0.26.0). skimage
//! refuses images with a side below 11 pixels; here the map is then averaged over the whole
//! image (not checked against anything).

use super::filter::{filter_2d, mean, Border};
use super::{check_sizes, Display};

pub(super) const SSIM_C1: f64 = 0.01 * 0.01;
pub(super) const SSIM_C2: f64 = 0.03 * 0.03;

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
    check_sizes(reference, test);
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
