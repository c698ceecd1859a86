//! Error reports: every metric of [`crate::metrics`] for test images against one reference,
//! and exact-value comparisons of sensor results; written as CSV and RON.

use crate::metrics;
use luxest_core::exact_case::Case;
use luxest_core::exr_io::{read_rgb_finite, RgbImage};
use luxest_core::fsio::{write_atomically, write_ron};
use luxest_core::sensors::SensorResults;
use luxest_core::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The tonemap every display-referred metric (PSNR, SSIM, MS-SSIM, FLIP) sees, as recorded in
/// reports.
pub const TONEMAP: &str = "x = max(v, 0) * k per channel, k = the reference's autoexposure \
    0.18 / exp(mean ln(Y + 1e-4)); t = x / (1 + x); sRGB OETF; clamp [0, 1]";

/// Errors of one test image against the reference.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageRow {
    pub image: String,
    /// luxest.estimator of the image, with `+denoise` appended for denoised images.
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

/// luxest.samples of an image header, 0 when absent.
fn samples(image: &RgbImage) -> u64 {
    image
        .attribute("luxest.samples")
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

fn attr_f64(image: &RgbImage, key: &str) -> f64 {
    image
        .attribute(key)
        .and_then(|v| v.parse().ok())
        .unwrap_or(f64::NAN)
}

/// Scores `tests` against `reference`; `flip_maps` receives each FLIP error map when given.
pub fn score_images(
    reference_path: &Path,
    tests: &[impl AsRef<Path>],
    mut flip_map: impl FnMut(&Path, &RgbImage) -> Result<()>,
) -> Result<ImageReport> {
    let reference = read_rgb_finite(reference_path)?;
    let exposure = reference.autoexposure();
    let reference_display = metrics::tonemap(&reference, exposure);
    let mut rows = Vec::new();
    for test_path in tests {
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
        let denoised = test.attribute("luxest.denoiser").is_some();
        let render_seconds = attr_f64(&test, "luxest.seconds");
        let (feature_seconds, denoise_seconds) = if denoised {
            (
                attr_f64(&test, "luxest.featureSeconds"),
                attr_f64(&test, "luxest.denoiseSeconds"),
            )
        } else {
            (0.0, 0.0)
        };
        let estimator = test.attribute("luxest.estimator").unwrap_or("unknown");
        rows.push(ImageRow {
            image: test_path.display().to_string(),
            estimator: if denoised {
                format!("{estimator}+denoise")
            } else {
                estimator.to_string()
            },
            samples: samples(&test),
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
    }
    Ok(ImageReport {
        reference: reference_path.display().to_string(),
        reference_samples: samples(&reference),
        exposure,
        tonemap: TONEMAP.to_string(),
        rel_mse_epsilon: metrics::REL_MSE_EPSILON,
        smape_epsilon: metrics::SMAPE_EPSILON,
        rows,
    })
}

fn csv_number(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else {
        format!("{v:e}")
    }
}

impl ImageReport {
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        write_atomically(path, |w| {
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
    pub fn write_ron(&self, path: &Path) -> Result<()> {
        write_ron(path, self)
    }
}

/// One sensor point against its exact value.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SensorRow {
    pub label: String,
    pub exact: f64,
    pub estimate: f64,
    pub standard_error: f64,
    pub z: f64,
    pub relative_error: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SensorReport {
    pub results: String,
    pub case: String,
    pub unit: String,
    pub estimator: String,
    pub samples: u64,
    pub seconds: f64,
    pub singularity: String,
    pub points: usize,
    pub max_abs_z: f64,
    /// Root mean square of the relative errors.
    pub rms_relative_error: f64,
    /// Mean of z²: about 1 for an unbiased estimate with honest standard errors.
    pub mean_z_squared: f64,
    pub rows: Vec<SensorRow>,
}

/// Compares sensor results with the exact values of `case` (see `luxest_core::exact_case`).
pub fn score_sensors(path: &Path, case_spec: &str) -> Result<SensorReport> {
    let case =
        Case::parse(case_spec).map_err(|m| Error::Usage(format!("--case {case_spec}: {m}")))?;
    let results = SensorResults::read_ron(path)?;
    let rows: Vec<SensorRow> = case
        .rows(&results)
        .into_iter()
        .map(|r| SensorRow {
            z: r.z(),
            relative_error: r.relative_error(),
            label: r.label,
            exact: r.exact,
            estimate: r.estimate,
            standard_error: r.standard_error,
        })
        .collect();
    if rows.is_empty() {
        return Err(Error::input(path, "no sensor points to compare"));
    }
    let n = rows.len() as f64;
    Ok(SensorReport {
        results: path.display().to_string(),
        case: case_spec.to_string(),
        unit: results.unit.clone(),
        estimator: results.run.estimator.clone(),
        samples: results.run.samples,
        seconds: results.run.seconds,
        singularity: results.singularity.clone(),
        points: rows.len(),
        max_abs_z: rows.iter().map(|r| r.z.abs()).fold(0.0, f64::max),
        rms_relative_error: (rows.iter().map(|r| r.relative_error.powi(2)).sum::<f64>() / n).sqrt(),
        mean_z_squared: rows.iter().map(|r| r.z * r.z).sum::<f64>() / n,
        rows,
    })
}

impl SensorReport {
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        write_atomically(path, |w| {
            let io = |e| Error::io(path, e);
            writeln!(
                w,
                "results,case,point,exact_{u},estimate_{u},standard_error_{u},z,relative_error",
                u = self.unit
            )
            .map_err(io)?;
            for r in &self.rows {
                writeln!(
                    w,
                    "{},\"{}\",\"{}\",{:e},{:e},{:e},{},{:e}",
                    self.results,
                    self.case,
                    r.label,
                    r.exact,
                    r.estimate,
                    r.standard_error,
                    r.z,
                    r.relative_error
                )
                .map_err(io)?;
            }
            Ok(())
        })
    }
    pub fn write_ron(&self, path: &Path) -> Result<()> {
        write_ron(path, self)
    }
}
