//! `evaluate images`: every metric of [`crate::metrics`] for test images against one reference,
//! with each image's cost read from its header; written as CSV and RON.

use crate::metrics;
use luxest_io::cli::Console;
use luxest_io::exr::read_rgb_finite;
use luxest_io::fsio::write_ron_to;
use luxest_io::header;
use luxest_io::image::RgbImage;
use luxest_io::limits::WorkPlan;
use luxest_io::outputs::OutputPlan;
use luxest_io::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::{Duration, Instant};

/// The tonemap every display-referred metric (PSNR, SSIM, MS-SSIM, FLIP) sees, as recorded in
/// reports.
pub const TONEMAP: &str = "x = max(v, 0) * k per channel, k = the reference's autoexposure \
    0.18 / exp(mean ln(Y + 1e-4)) (a reference of mean Y below 1/32 brightened by 2^e first: \
    k = 2^e times that of 2^e Y); t = x / (1 + x); sRGB OETF; clamp [0, 1]";

/// Errors of one test image against the reference.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageRow {
    pub image: String,
    /// The estimator recorded in the image header, with `+denoise` appended for images denoised
    /// by a luxest model and `+oidn` for Intel Open Image Denoise ([`estimator_label`]).
    pub estimator: String,
    /// Samples per pixel (path tracing) or light paths (local estimates).
    pub samples: u64,
    pub render_seconds: f64,
    /// Seconds of the albedo/normal features a denoised image used (0 for other images).
    pub feature_seconds: f64,
    pub denoise_seconds: f64,
    /// render + features + denoise: the wall-clock cost of the image.
    pub total_seconds: f64,
    pub psnr_db: f64,
    pub ssim: f64,
    /// None when the image is too small for even one MS-SSIM level.
    pub ms_ssim: Option<f64>,
    pub flip: f64,
    pub rel_mse: f64,
    pub smape: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageReport {
    pub reference: String,
    pub reference_samples: u64,
    pub exposure: f64,
    pub tonemap: String,
    pub rel_mse_epsilon: f64,
    pub smape_epsilon: f64,
    pub rows: Vec<ImageRow>,
}

/// The samples (spp or light paths) of an image header; 0 when absent.
fn samples(path: &Path, image: &RgbImage) -> Result<u64> {
    Ok(header::parse(path, &image.attributes, header::SAMPLES)?.unwrap_or(0))
}

/// A seconds attribute of an image header; NaN when absent (an empty CSV cell).
fn seconds(path: &Path, image: &RgbImage, key: &str) -> Result<f64> {
    Ok(header::parse(path, &image.attributes, key)?.unwrap_or(f64::NAN))
}

/// Bytes `evaluate images` holds per pixel at its peak: the reference and a test image with
/// their tonemapped copies, the FLIP map and the metrics' working images (measured: a 2048²
/// image, with or without --flip-maps, peaked at 1.02 GB resident, 243 bytes per pixel).
pub const BYTES_PER_PIXEL: u64 = 256;

/// Scores `tests` against `reference`; `flip_maps` receives each FLIP error map when given.
/// Its progress and, when the first image predicts more than a minute for all, its plan are
/// shown through `console`.
pub fn score_images(
    reference_path: &Path,
    tests: &[impl AsRef<Path>],
    console: &Console,
    mut flip_map: impl FnMut(&Path, &RgbImage) -> Result<()>,
) -> Result<ImageReport> {
    let start = Instant::now();
    let reference = read_rgb_finite(reference_path)?;
    let exposure = metrics::autoexposure(&reference);
    let reference_display = metrics::tonemap(&reference, exposure);
    let mut rows = Vec::new();
    let progress = console.progress("evaluate images", Some(tests.len() as u64), "images");
    for (n, test_path) in tests.iter().enumerate() {
        let test_path = test_path.as_ref();
        let test = read_rgb_finite(test_path)?;
        if (test.width, test.height) != (reference.width, reference.height) {
            return Err(Error::input(
                test_path,
                format!(
                    "size {}x{} differs from the reference's {}x{} ({})",
                    test.width,
                    test.height,
                    reference.width,
                    reference.height,
                    reference_path.display()
                ),
            ));
        }
        let display = metrics::tonemap(&test, exposure);
        let flip = metrics::flip(&reference_display, &display);
        let mut map = RgbImage::new(test.width, test.height);
        for (p, &e) in map.pixels.iter_mut().zip(&flip.map) {
            *p = [e; 3];
        }
        flip_map(test_path, &map)?;
        let denoiser = test.attribute(header::DENOISER);
        let denoised = denoiser.is_some();
        let render_seconds = seconds(test_path, &test, header::SECONDS)?;
        let (feature_seconds, denoise_seconds) = if denoised {
            (
                seconds(test_path, &test, header::FEATURE_SECONDS)?,
                seconds(test_path, &test, header::DENOISE_SECONDS)?,
            )
        } else {
            (0.0, 0.0)
        };
        let estimator = test.attribute(header::ESTIMATOR).unwrap_or("unknown");
        rows.push(ImageRow {
            image: test_path.display().to_string(),
            estimator: estimator_label(estimator, denoiser),
            samples: samples(test_path, &test)?,
            render_seconds,
            feature_seconds,
            denoise_seconds,
            total_seconds: render_seconds + feature_seconds + denoise_seconds,
            psnr_db: metrics::psnr(&reference_display, &display),
            ssim: metrics::ssim(&reference_display, &display),
            ms_ssim: metrics::ms_ssim(&reference_display, &display),
            flip: flip.mean,
            rel_mse: metrics::rel_mse(&reference, &test),
            smape: metrics::smape(&reference, &test),
        });
        progress.inc(1);
        if n == 0 {
            // The resource rule: the first image (and the reference) is the calibration.
            let plan = work_plan(tests.len(), (test.width, test.height), start.elapsed());
            console.announce_during(&plan, &progress);
        }
    }
    progress.finish();
    Ok(ImageReport {
        reference: reference_path.display().to_string(),
        reference_samples: samples(reference_path, &reference)?,
        exposure,
        tonemap: TONEMAP.to_string(),
        rel_mse_epsilon: metrics::REL_MSE_EPSILON,
        smape_epsilon: metrics::SMAPE_EPSILON,
        rows,
    })
}

/// The plan of scoring `images` images of `width` x `height` pixels, the first of which took
/// `first` (with the reference's reading).
fn work_plan(images: usize, (width, height): (usize, usize), first: Duration) -> WorkPlan {
    let first = first.as_secs_f64();
    let pixels = width as u64 * height as u64;
    WorkPlan {
        stage: "evaluate images".into(),
        work: format!("{images} images of {width}x{height} pixels (the first one's size)"),
        units: (pixels * images as u64) as f64,
        unit: "pixels",
        seconds: first * images as f64,
        threads: 1,
        memory_bytes: pixels as u128 * BYTES_PER_PIXEL as u128,
        calibration_seconds: first,
        levers: "the images given".into(),
    }
}

fn csv_number(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else {
        format!("{v:e}")
    }
}

impl ImageReport {
    /// Writes the report as CSV, the planned output `path`.
    pub fn write_csv_to(&self, plan: &mut OutputPlan, path: &Path) -> Result<()> {
        plan.write(path, |w| {
            let io = |e| Error::io(path, e);
            writeln!(w, "image,reference,estimator,samples,render_seconds,feature_seconds,denoise_seconds,total_seconds,psnr_db,ssim,ms_ssim,flip,rel_mse,smape").map_err(io)?;
            for r in &self.rows {
                writeln!(
                    w,
                    "{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                    r.image,
                    self.reference,
                    r.estimator,
                    r.samples,
                    csv_number(r.render_seconds),
                    csv_number(r.feature_seconds),
                    csv_number(r.denoise_seconds),
                    csv_number(r.total_seconds),
                    csv_number(r.psnr_db),
                    csv_number(r.ssim),
                    r.ms_ssim.map(csv_number).unwrap_or_default(),
                    csv_number(r.flip),
                    csv_number(r.rel_mse),
                    csv_number(r.smape)
                )
                .map_err(io)?;
            }
            Ok(())
        })
    }
    /// Writes the report as RON, the planned output `path`.
    pub fn write_ron_to(&self, plan: &mut OutputPlan, path: &Path) -> Result<()> {
        write_ron_to(plan, path, self)
    }
}

/// The estimator label of an image: the header's estimator, `+oidn` appended when the denoiser
/// header names Intel Open Image Denoise 1.x (`oidn-<version>`, pipelines/oidn_denoise.py),
/// `+oidn<major>` for a later major release (`+oidn2` for `oidn-2.5.1`: both releases are
/// scored side by side in one report), `+denoise` for any other denoiser (a luxest model's file
/// name).
pub fn estimator_label(estimator: &str, denoiser: Option<&str>) -> String {
    match denoiser {
        None => estimator.to_string(),
        Some(d) => match d.strip_prefix(header::OIDN_DENOISER_PREFIX) {
            Some(version) => match version.split('.').next() {
                Some(major) if major != "1" && !major.is_empty() => {
                    format!("{estimator}+oidn{major}")
                }
                _ => format!("{estimator}+oidn"),
            },
            None => format!("{estimator}+denoise"),
        },
    }
}

#[cfg(test)]
mod label_tests {
    use super::*;

    #[test]
    fn denoised_images_are_labelled_by_their_denoiser() {
        assert_eq!(estimator_label("path-tracing", None), "path-tracing");
        assert_eq!(
            estimator_label("path-tracing", Some("default.onnx")),
            "path-tracing+denoise"
        );
        assert_eq!(
            estimator_label("double-local-estimate", Some("oidn-1.4.3")),
            "double-local-estimate+oidn"
        );
        assert_eq!(
            estimator_label("path-tracing", Some("oidn-2.5.1")),
            "path-tracing+oidn2"
        );
    }
}
