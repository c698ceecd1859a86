//! PSNR of display-referred images.
//!
//! [`psnr`]: `10 log10(1 / MSE)`, data range 1, MSE over all pixels and channels;
//! `f64::INFINITY` for identical images. Checked against
//! `skimage.metrics.peak_signal_noise_ratio(data_range=1)` (scikit-image 0.26.0).

use super::{check_sizes, Display};

/// `10 log10(1 / MSE)`, MSE over all pixels and channels; `f64::INFINITY` for identical images.
pub fn psnr(reference: &Display, test: &Display) -> f64 {
    check_sizes(reference, test);
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
