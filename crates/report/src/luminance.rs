//! The false-colour luminance image of the room: an OpenEXR image the DAG renders (`trace` or
//! `estimate image`, linear RGB in cd/m² per channel), read here, its photometric luminance
//! Y (cd/m²) drawn on a logarithmic false-colour scale with its bar in cd/m²
//! (`luxest_photometry::falsecolour`), encoded as PNG for the reports.
//!
//! An image of another compile of the scene (its `luxest.sceneHash` attribute differs from the
//! results') is refused, like a scene header of another compile.

use luxest_io::color::Rgb;
use luxest_io::{header, Error, Result};
use luxest_photometry::falsecolour::{render_falsecolour, FalseColourOptions};
use std::path::Path;

/// The drawn image and what the report says about it.
#[derive(Clone, Debug, PartialEq)]
pub struct LuminanceImage {
    pub png: Vec<u8>,
    /// Size of the rendered image, px.
    pub width: usize,
    pub height: usize,
    /// The colour scale's range, cd/m².
    pub lo: f64,
    pub hi: f64,
    /// Median and largest pixel luminance, cd/m².
    pub median: f64,
    pub max: f64,
    /// The estimator and sample count its header states, e.g. `double-local-estimate, 300
    /// light paths`.
    pub provenance: String,
    /// The image file as given.
    pub source: String,
}

/// Reads `path` and draws it; `scene_hash` is the results' (checked when the image states one).
pub fn render(path: &Path, title: &str, scene_hash: &str) -> Result<LuminanceImage> {
    let img = luxest_io::exr::read_rgb_finite(path)?;
    if let Some(h) = img.attribute(header::SCENE_HASH) {
        if h != scene_hash {
            return Err(Error::input(
                path,
                format!(
                    "is an image of the scene compile with content hash {h}, but the results \
                     are of {scene_hash}: render it from the same scene.lxs"
                ),
            ));
        }
    }
    let lum: Vec<f64> = img
        .pixels
        .iter()
        .map(|p| Rgb(p.map(f64::from)).luminance().max(0.0))
        .collect();
    let opts = FalseColourOptions {
        title: title.to_string(),
        range_cd_m2: None,
        min_width_px: 640,
    };
    let fc = render_falsecolour(img.width, img.height, &lum, &opts)
        .map_err(|e| Error::input(path, e.0))?;
    let png = fc
        .raster
        .encode_png()
        .map_err(|e| Error::input(path, format!("cannot encode the false-colour PNG: {e}")))?;
    let mut sorted = lum.clone();
    sorted.sort_by(f64::total_cmp);
    let provenance = match (
        img.attribute(header::ESTIMATOR),
        img.attribute(header::SAMPLES),
    ) {
        (Some(e), Some(n)) if e == header::estimator::PATH_TRACING => {
            format!("{e}, {n} samples per pixel")
        }
        (Some(e), Some(n)) if e == header::estimator::DOUBLE_LOCAL_ESTIMATE => {
            format!("{e}, {n} light paths")
        }
        (Some(e), Some(n)) => format!("{e}, {n} samples"),
        (Some(e), None) => e.to_string(),
        _ => "estimator not stated".to_string(),
    };
    Ok(LuminanceImage {
        png,
        width: img.width,
        height: img.height,
        lo: fc.lo,
        hi: fc.hi,
        median: sorted[sorted.len() / 2],
        max: sorted[sorted.len() - 1],
        provenance,
        source: path.display().to_string(),
    })
}
