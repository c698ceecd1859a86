//! Errors of linear (HDR) values, which need no tonemap:
//!
//! * [`rel_mse`]: mean over pixels and channels of `(t - r)^2 / (r^2 + 0.01)`
//!   ([`REL_MSE_EPSILON`]).
//! * [`smape`]: mean over pixels and channels of `|t - r| / (|t| + |r| + 0.01)`
//!   ([`SMAPE_EPSILON`]).

use super::check_sizes;
use luxest_io::image::RgbImage;

/// Epsilon in the denominator of [`rel_mse`].
pub const REL_MSE_EPSILON: f64 = 0.01;
/// Epsilon in the denominator of [`smape`].
pub const SMAPE_EPSILON: f64 = 0.01;

fn mean_over_channels(
    reference: &RgbImage,
    test: &RgbImage,
    term: impl Fn(f64, f64) -> f64,
) -> f64 {
    check_sizes(reference, test);
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
