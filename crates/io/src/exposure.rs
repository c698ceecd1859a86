//! The exposure contract shared by Rust and Python: the autoexposure `k` of a whole image
//! (the denoiser's input transfer and the evaluation tonemap use it; `luxest_contract.exposure`
//! computes the same, tied by `tests/fixtures/contract/exposure.json`), and the power of two by
//! which the denoiser brightens a dim image before it, or scales any image into the octave of
//! mean luminance its model records (docs/architecture.md, *Exposure and tonemap*).

use crate::color::Rgb;
use crate::image::RgbImage;

impl RgbImage {
    /// The autoexposure shared by the denoiser and the evaluation tonemap (training/transfer.py):
    /// `0.18 / exp(mean over pixels of ln(max(Y, 0) + 1e-4))`, Y the Rec. 709 luminance,
    /// accumulated in f64. It maps the image's log-average luminance to middle grey.
    pub fn autoexposure(&self) -> f64 {
        self.autoexposure_scaled(1.0)
    }
    /// The [`RgbImage::autoexposure`] of the image's pixels times `scale` (each Y times `scale`
    /// in f64; the image is not changed): what the denoiser gives a model fed the image scaled
    /// (see [`dim_exponent`]).
    pub fn autoexposure_scaled(&self, scale: f64) -> f64 {
        const KEY: f64 = 0.18;
        const EPS: f64 = 1e-4;
        if self.pixels.is_empty() {
            return 1.0;
        }
        let sum: f64 = self
            .pixels
            .iter()
            .map(|p| (Rgb(p.map(f64::from)).luminance() * scale).max(0.0) + EPS)
            .map(f64::ln)
            .sum();
        KEY / (sum / self.pixels.len() as f64).exp()
    }
}

/// The mean luminance below which the denoiser brightens its input: 1/32, below the darkest
/// training image of the committed models (mean luminance 0.6) by a factor of 19 and where the
/// autoexposure's `1e-4` is still small against the image (docs/architecture.md, *Exposure and
/// tonemap*).
pub const DIM_LUMINANCE: f64 = 1.0 / 32.0;

/// The power of two `e` by which the denoiser multiplies the radiance it gives a model (the
/// output is divided by `2^e`): the least `e ≥ 0` with `2^e · L ≥ DIM_LUMINANCE`, `L` the mean
/// over pixels of the Rec. 709 luminance of `max(hdr − emission, 0)` (per channel, f64: the
/// radiance a model with the `emi` feature denoises; `max(hdr, 0)` without `emission`); 0 for an
/// image that is black or not dim. The autoexposure's `1e-4` (a black pixel's floor) makes a
/// model's input depend on the radiance's unit: an image 100 times dimmer than the Cornell box
/// lost 10 dB at 256 spp before this, while a brighter one denoises alike (docs/measurements.md,
/// *Dim images*). Powers of two are exact in f32, so images differing by one are denoised alike.
pub fn dim_exponent(hdr: &RgbImage, emission: Option<&RgbImage>) -> i32 {
    let mean = filtered_luminance(hdr, emission);
    if mean.is_nan() || mean <= 0.0 || mean >= DIM_LUMINANCE {
        return 0;
    }
    // The least e with mean · 2^e ≥ DIM_LUMINANCE (below 200: a positive mean of f32 values is at
    // least 2^-149 over the pixel count).
    let mut e = 0;
    while mean * 2f64.powi(e) < DIM_LUMINANCE {
        e += 1;
    }
    e
}

/// The mean over pixels of the Rec. 709 luminance of `max(hdr − emission, 0)` (per channel, f64;
/// `max(hdr, 0)` without `emission`): the radiance a model with the `emi` feature denoises, the
/// mean [`dim_exponent`] and [`range_exponent`] bring into range; 0 for an empty image.
pub fn filtered_luminance(hdr: &RgbImage, emission: Option<&RgbImage>) -> f64 {
    if hdr.pixels.is_empty() {
        return 0.0;
    }
    let dimmed = |h: &[f32; 3], e: &[f32; 3]| {
        Rgb(std::array::from_fn(|c| {
            (h[c] as f64 - e[c] as f64).max(0.0)
        }))
        .luminance()
    };
    let sum: f64 = match emission {
        Some(emi) => hdr
            .pixels
            .iter()
            .zip(&emi.pixels)
            .map(|(h, e)| dimmed(h, e))
            .sum(),
        None => hdr.pixels.iter().map(|h| dimmed(h, &[0.0; 3])).sum(),
    };
    sum / hdr.pixels.len() as f64
}

/// The power of two `e` by which the denoiser multiplies the radiance it gives a model whose
/// metadata records the mean luminance `low` (`luxest.mean_luminance`): the `e`, negative for a
/// bright image, with `low ≤ 2^e · L < 2 · low`, `L` = [`filtered_luminance`]; 0 for a black
/// image. Images that differ by a power of two, dim or bright, then give the model the same
/// input: the autoexposure's `1e-4` floor (a black pixel's) weighs the same against every image,
/// where unscaled it weighs ever less against a brighter one and a model's input would depend on
/// the radiance's unit (docs/architecture.md, *Exposure and tonemap*). `luxest_contract.
/// range_exponent` computes the same (`tests/fixtures/contract/exposure.json`).
pub fn range_exponent(hdr: &RgbImage, emission: Option<&RgbImage>, low: f64) -> i32 {
    let mean = filtered_luminance(hdr, emission);
    if !(mean > 0.0 && mean.is_finite()) {
        return 0;
    }
    // |e| stays below 300: a positive mean of f32 values lies in [2^-149 / pixels, 2^128].
    let mut e = 0;
    while mean * 2f64.powi(e) < low {
        e += 1;
    }
    while mean * 2f64.powi(e) >= 2.0 * low {
        e -= 1;
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    fn uniform(w: usize, h: usize, v: f32) -> RgbImage {
        let mut img = RgbImage::new(w, h);
        img.pixels.fill([v; 3]);
        img
    }

    #[test]
    fn dim_exponent_is_the_least_power_of_two_reaching_the_threshold() {
        // A uniform grey of luminance Y (the Rec. 709 weights sum to 1).
        assert_eq!(dim_exponent(&uniform(4, 5, 1e-3), None), 5); // 0.016 < 1/32 <= 0.032
        assert_eq!(dim_exponent(&uniform(2, 2, 1.0 / 32.0), None), 0);
        assert_eq!(dim_exponent(&uniform(2, 2, 1.0 / 64.0), None), 1);
        assert_eq!(dim_exponent(&uniform(2, 2, 1e-30), None), 95); // 2^95 1e-30 = 0.0396
        assert_eq!(dim_exponent(&uniform(3, 3, 0.0), None), 0); // black: nothing to brighten
        assert_eq!(dim_exponent(&uniform(3, 3, -1e-3), None), 0); // negative counts as 0
        assert_eq!(dim_exponent(&RgbImage::new(0, 0), None), 0);
        // An emitter beside a dim wall: without the emission the mean is bright; the model
        // denoises hdr − emission, whose mean 0.75e-6 needs 2^16.
        let mut hdr = uniform(2, 2, 1e-6);
        hdr.pixels[0] = [100.0; 3];
        let mut emi = RgbImage::new(2, 2);
        emi.pixels[0] = [100.0; 3];
        assert_eq!(dim_exponent(&hdr, None), 0);
        assert_eq!(dim_exponent(&hdr, Some(&emi)), 16);
    }

    #[test]
    fn range_exponent_brings_the_mean_into_its_octave() {
        // Uniform grey v: L = v exactly, so e is the integer with low <= 2^e v < 2 low.
        for (v, e) in [
            (1.5f32, -4),
            (0.07, 0),
            (0.2, -1),
            (0.03, 2),
            (1000.0, -13),
            (1e-6, 16),
        ] {
            assert_eq!(
                range_exponent(&uniform(3, 2, v), None, 1.0 / 16.0),
                e,
                "{v}"
            );
        }
        assert_eq!(range_exponent(&uniform(3, 2, 0.0), None, 1.0 / 16.0), 0);
        // The emission is left out of the mean, as in dim_exponent.
        let hdr = uniform(2, 1, 3.0);
        let mut emi = uniform(2, 1, 0.0);
        emi.pixels[0] = [3.0; 3];
        assert!((filtered_luminance(&hdr, Some(&emi)) - 1.5).abs() < 1e-12);
        assert_eq!(range_exponent(&hdr, Some(&emi), 1.0 / 16.0), -4);
    }

    #[test]
    fn autoexposure_scaled_is_that_of_the_scaled_image() {
        let mut img = RgbImage::new(3, 2);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = [i as f32 * 1e-4, 0.0, 2e-3 * i as f32];
        }
        let mut scaled = img.clone();
        for p in &mut scaled.pixels {
            *p = p.map(|c| c * 1024.0);
        }
        assert_eq!(img.autoexposure_scaled(1024.0), scaled.autoexposure());
        assert_eq!(img.autoexposure_scaled(1.0), img.autoexposure());
    }
}
