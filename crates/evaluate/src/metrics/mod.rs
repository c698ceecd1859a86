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
//! * [`psnr`](psnr::psnr), [`ssim`](ssim::ssim), [`ms_ssim`](ms_ssim::ms_ssim),
//!   [`flip`](flip::flip): display-referred, each in its module with its exact definition and
//!   the implementation it is checked against (scikit-image 0.26.0, pytorch_msssim 1.0.0,
//!   flip_evaluator 1.7);
//! * [`rel_mse`](linear::rel_mse), [`smape`](linear::smape): linear values ([`linear`]).
//!
//! relMSE, SMAPE, the tonemap and the autoexposure are checked against numpy float64
//! transcriptions of these definitions. The parity test is `tests/metrics_parity.rs`, on the
//! fixtures written by `tests/fixtures/metrics/generate.py` (repository root); every value there
//! matches to 1e-4 (absolute).

mod filter;
pub mod flip;
pub mod linear;
pub mod ms_ssim;
pub mod psnr;
pub mod ssim;

pub use flip::{flip, flip_with_ppd, Flip, FLIP_PIXELS_PER_DEGREE};
pub use linear::{rel_mse, smape, REL_MSE_EPSILON, SMAPE_EPSILON};
pub use ms_ssim::{ms_ssim, ms_ssim_levels, ms_ssim_weights, MS_SSIM_WEIGHTS};
pub use psnr::psnr;
pub use ssim::ssim;

use luxest_io::color::srgb_encode;
use luxest_io::exposure::dim_exponent;
use luxest_io::image::RgbImage;

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
        Display::mapped(image, |v| v as f64)
    }

    /// `f` of every value of the image, channel by channel.
    fn mapped(image: &RgbImage, f: impl Fn(f32) -> f64) -> Display {
        Display {
            width: image.width,
            height: image.height,
            pixels: image.pixels.iter().map(|p| p.map(&f)).collect(),
        }
    }

    /// One channel as a plane, row-major.
    fn channel(&self, c: usize) -> Vec<f64> {
        self.pixels.iter().map(|p| p[c]).collect()
    }
}

/// Width, height and pixel count of an image, for the size checks.
trait Dims {
    fn dims(&self) -> (usize, usize, usize);
}

impl Dims for Display {
    fn dims(&self) -> (usize, usize, usize) {
        (self.width, self.height, self.pixels.len())
    }
}

impl Dims for RgbImage {
    fn dims(&self) -> (usize, usize, usize) {
        (self.width, self.height, self.pixels.len())
    }
}

/// Debug builds check that a reference and a test image have the same, consistent size.
fn check_sizes(reference: &impl Dims, test: &impl Dims) {
    let ((rw, rh, rn), (tw, th, tn)) = (reference.dims(), test.dims());
    debug_assert!(
        rw == tw && rh == th,
        "image sizes differ: {rw} x {rh} and {tw} x {th}"
    );
    debug_assert!(
        rn == rw * rh && tn == tw * th,
        "pixel count is not width * height"
    );
}

// ------------------------------------------------------------------------------------ tonemap

/// `0.18 / exp(mean over pixels of ln(max(Y, 0) + 1e-4))`, `Y = 0.2126 R + 0.7152 G + 0.0722 B`,
/// accumulated in f64; 1 for an empty image. The same exposure the denoiser uses
/// ([`RgbImage::autoexposure`], shared with training/transfer.py). A dim reference (mean
/// luminance below [`luxest_io::exposure::DIM_LUMINANCE`]) is exposed as the denoiser brightens it: `2^e` times the
/// autoexposure of the reference times `2^e` (`e` its [`dim_exponent`]), so that the tonemap and
/// every metric on it are the same in any unit of radiance (the `1e-4` floor would otherwise
/// make a dim reference and its test images all nearly black); `e` is 0 for every image `make
/// eval` scores.
pub fn autoexposure(reference: &RgbImage) -> f64 {
    let s = 2f64.powi(dim_exponent(reference, None));
    s * reference.autoexposure_scaled(s)
}

/// Per channel `x = max(v, 0) * exposure`, `t = x / (1 + x)`, the sRGB OETF, clamped to [0, 1].
pub fn tonemap(image: &RgbImage, exposure: f64) -> Display {
    let map = |v: f32| {
        let x = (v as f64).max(0.0) * exposure;
        srgb_encode(x / (1.0 + x))
    };
    Display::mapped(image, map)
}

#[cfg(test)]
mod tests {
    use super::*;
    use luxest_io::exposure::DIM_LUMINANCE;

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
        // A dim uniform image (Y = 1e-3 < 1/32) is exposed as 32 times it: 32 · 0.18 / (0.032 + 1e-4).
        grey.pixels = vec![[1e-3; 3]; 6];
        let y = 1e-3f32 as f64;
        let k = 32.0 * 0.18 / (32.0 * y + 1e-4);
        assert!((autoexposure(&grey) - k).abs() < 1e-12 * k);
    }

    #[test]
    fn metrics_of_dim_images_do_not_depend_on_the_unit() {
        // A reference of mean luminance 0.01 (dim) and a noisy test image, then both 2^-40 and
        // 2^-90 times as bright: the same exposed values to the bit, so the same metrics.
        let (w, h) = (24, 16);
        let mut reference = RgbImage::new(w, h);
        let mut test = RgbImage::new(w, h);
        for (i, (r, t)) in reference
            .pixels
            .iter_mut()
            .zip(test.pixels.iter_mut())
            .enumerate()
        {
            let v = 0.02 * (1.0 + (i % 7) as f32) / 4.0;
            *r = [v, 0.5 * v, 0.25 * v];
            *t = r.map(|c| c * (1.0 + 0.3 * ((i * 37 % 11) as f32 / 11.0 - 0.5)));
        }
        let mean = reference
            .pixels
            .iter()
            .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
            .sum::<f32>()
            / (w * h) as f32;
        assert!(mean < DIM_LUMINANCE as f32);
        let scores = |s: f32| {
            let (r, t) = (reference.clone(), test.clone());
            let scale = |mut im: RgbImage| {
                im.pixels.iter_mut().for_each(|p| *p = p.map(|c| c * s));
                im
            };
            let (r, t) = (scale(r), scale(t));
            let k = autoexposure(&r);
            (psnr(&tonemap(&r, k), &tonemap(&t, k)), k * s as f64)
        };
        let (p0, k0) = scores(1.0);
        for e in [-40, -90] {
            let (p, k) = scores(2f32.powi(e));
            assert_eq!(p, p0, "2^{e}");
            assert!((k / k0 - 1.0).abs() < 1e-12, "2^{e}: {k} vs {k0}");
        }
        assert!(p0.is_finite() && p0 < 40.0, "{p0}");
    }
}
