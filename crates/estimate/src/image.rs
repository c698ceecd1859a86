//! A luminance image with per-pixel standard errors: what both image estimators, the double
//! local estimate ([`crate::double_local_estimate`]) and light tracing
//! ([`crate::light_tracing`]), return, and the batches and memory bound they share.

use luxest_io::color::Rgb;

/// Bytes per pixel an image estimator keeps at most (the double local estimate, which keeps
/// the most): per batch a light-tracing film and the tiles' sums (RGB, f64), the light-traced
/// luminance (f64), then the image and its standard error. Checked against the memory
/// available before rendering.
pub const BYTES_PER_PIXEL: u64 = 2 * BATCHES as u64 * 24 + 8 + 32;
/// Batches for the per-pixel standard error.
pub const BATCHES: usize = 8;

/// An estimated luminance image.
pub struct ImageResult {
    pub width: usize,
    pub height: usize,
    /// Mean luminance per pixel, cd/m² per channel.
    pub rgb: Vec<Rgb>,
    /// Standard error of the pixel's Y.
    pub standard_error: Vec<f64>,
    pub collisions: u64,
    pub shadow_rays: u64,
    pub seconds: f64,
}
