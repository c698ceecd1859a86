//! denoise: noisy radiance (hdr) plus albedo and normal features → a denoised radiance image,
//! with a U-Net exported by `training/export.py`, run through ONNX Runtime (`ort`, library
//! loaded at run time).
//!
//! The model contract (ARCHITECTURE.md, Models; training/transfer.py): input `input` float32
//! NCHW with the channels named in the metadata key `luxest.channels` (hdr[,alb[,nrm]]), raw
//! linear values, any H and W; input `exposure` float32 (N,), the autoexposure of the *whole*
//! image ([`RgbImage::autoexposure`]); output `output` float32 N×3×H×W linear radiance. The
//! transfer function and the padding to multiples of 16 are inside the graph.
//!
//! Large images are denoised in tiles: each tile's core is extended by `overlap` pixels of
//! context on every side (clipped at the image border) and only the core is kept. Tile origins
//! and the overlap are multiples of 16, so every tile sees the same pooling grid as the whole
//! image; with an overlap at least the network's receptive-field radius the tiled result equals
//! the whole-image result to rounding (tested). Because the exposure is computed once for the
//! whole image, tiles never disagree on brightness.

pub mod cli;

use luxest_core::exr_io::RgbImage;
use luxest_core::{Error, Result};
use ort::environment::Environment;
use ort::session::Session;
use ort::value::{Tensor, ValueType};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// One input feature of a model, in the order the model's channels expect them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feature {
    Hdr,
    Alb,
    Nrm,
}

impl Feature {
    /// The feature's name in file names (`<img>_<spp>spp.<name>.exr`) and model metadata.
    pub fn name(self) -> &'static str {
        match self {
            Feature::Hdr => "hdr",
            Feature::Alb => "alb",
            Feature::Nrm => "nrm",
        }
    }
    fn parse(s: &str) -> Option<Feature> {
        match s.trim() {
            "hdr" => Some(Feature::Hdr),
            "alb" => Some(Feature::Alb),
            "nrm" => Some(Feature::Nrm),
            _ => None,
        }
    }
}

/// Tiling of large images: cores of `tile`² pixels with `overlap` pixels of context.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tiling {
    pub tile: usize,
    pub overlap: usize,
}

impl Default for Tiling {
    /// 768² cores with 96 pixels of context: the default U-Net's receptive-field radius is
    /// below 96 (tested), and one such tile needs about 0.6 GB of activations.
    fn default() -> Tiling {
        Tiling {
            tile: 768,
            overlap: 96,
        }
    }
}

impl Tiling {
    pub fn validate(&self) -> Result<()> {
        if self.tile == 0 || !self.tile.is_multiple_of(16) || !self.overlap.is_multiple_of(16) {
            return Err(Error::Usage(format!(
                "--tile ({}) must be a positive multiple of 16 and --overlap ({}) a multiple of 16",
                self.tile, self.overlap
            )));
        }
        Ok(())
    }
}

/// The ONNX Runtime library: `ORT_DYLIB_PATH`, else the copy scripts/setup.sh installs.
pub fn runtime_library_path() -> PathBuf {
    match std::env::var_os("ORT_DYLIB_PATH") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => {
            let home = std::env::var_os("HOME").unwrap_or_default();
            Path::new(&home).join(".cache/luxest/onnxruntime/libonnxruntime.so")
        }
    }
}

/// Loads ONNX Runtime once per process.
fn environment() -> Result<&'static Environment> {
    static ENV: OnceLock<std::result::Result<Environment, String>> = OnceLock::new();
    let path = runtime_library_path();
    ENV.get_or_init(|| {
        if !path.is_file() {
            return Err(
                "ONNX Runtime library not found (run scripts/setup.sh, or set ORT_DYLIB_PATH)"
                    .to_string(),
            );
        }
        let builder =
            ort::init_from(&path).map_err(|e| format!("cannot load ONNX Runtime: {e}"))?;
        builder
            .with_name("luxest-denoise")
            .build()
            .map_err(|e| format!("cannot start ONNX Runtime: {e}"))
    })
    .as_ref()
    .map_err(|m| Error::input(&path, m.clone()))
}

/// A loaded denoising model.
pub struct Denoiser {
    session: Session,
    features: Vec<Feature>,
    path: PathBuf,
}

fn tensor_shape(v: &ValueType) -> Option<Vec<i64>> {
    match v {
        ValueType::Tensor { ty, shape, .. } if *ty == ort::value::TensorElementType::Float32 => {
            Some(shape.to_vec())
        }
        _ => None,
    }
}

impl Denoiser {
    /// Loads `model` and checks it against the contract above; `threads` is ONNX Runtime's
    /// intra-op thread count.
    pub fn load(model: &Path, threads: usize) -> Result<Denoiser> {
        let env = environment()?;
        let bytes = luxest_core::fsio::read_bytes(model)?;
        let ort_err = |e: &dyn std::fmt::Display| Error::input(model, format!("{e}"));
        let session = Session::builder(env)
            .map_err(|e| ort_err(&e))?
            .with_intra_threads(threads.max(1))
            .map_err(|e| ort_err(&e))?
            .with_inter_threads(1)
            .map_err(|e| ort_err(&e))?
            .commit_from_memory(&bytes)
            .map_err(|e| Error::input(model, format!("not a loadable ONNX model: {e}")))?;

        let input = session.inputs().iter().find(|o| o.name() == "input");
        let input_shape = input
            .and_then(|o| tensor_shape(o.dtype()))
            .filter(|s| s.len() == 4)
            .ok_or_else(|| {
                Error::input(
                    model,
                    "model has no float32 NCHW input named `input` (see models/README.md)",
                )
            })?;
        let exposure_ok = session
            .inputs()
            .iter()
            .find(|o| o.name() == "exposure")
            .and_then(|o| tensor_shape(o.dtype()))
            .is_some_and(|s| s.len() == 1);
        if !exposure_ok {
            return Err(Error::input(
                model,
                "model has no float32 (N,) input named `exposure` (exported before the \
                 whole-image exposure contract? re-export it with training/export.py)",
            ));
        }
        if let Some(extra) = session
            .inputs()
            .iter()
            .find(|o| o.name() != "input" && o.name() != "exposure")
        {
            return Err(Error::input(
                model,
                format!("model has an unexpected input `{}`", extra.name()),
            ));
        }
        let output_ok = session
            .outputs()
            .iter()
            .find(|o| o.name() == "output")
            .and_then(|o| tensor_shape(o.dtype()))
            .is_some_and(|s| s.len() == 4 && (s[1] == 3 || s[1] < 0));
        if !output_ok {
            return Err(Error::input(
                model,
                "model has no float32 N×3×H×W output named `output`",
            ));
        }

        let channels = session
            .metadata()
            .ok()
            .and_then(|m| m.custom("luxest.channels"));
        let features: Vec<Feature> = match channels {
            Some(list) => list
                .split(',')
                .map(|s| {
                    Feature::parse(s).ok_or_else(|| {
                        Error::input(
                            model,
                            format!("metadata luxest.channels names an unknown feature `{s}`"),
                        )
                    })
                })
                .collect::<Result<_>>()?,
            None => match input_shape[1] {
                3 => vec![Feature::Hdr],
                6 => vec![Feature::Hdr, Feature::Alb],
                9 => vec![Feature::Hdr, Feature::Alb, Feature::Nrm],
                _ => {
                    return Err(Error::input(
                        model,
                        "model metadata lacks luxest.channels and its input has no fixed \
                         3, 6 or 9 channels",
                    ))
                }
            },
        };
        if features.first() != Some(&Feature::Hdr) {
            return Err(Error::input(
                model,
                "metadata luxest.channels must start with hdr",
            ));
        }
        if input_shape[1] >= 0 && input_shape[1] as usize != 3 * features.len() {
            return Err(Error::input(
                model,
                format!(
                    "input has {} channels but luxest.channels lists {} features",
                    input_shape[1],
                    features.len()
                ),
            ));
        }
        Ok(Denoiser {
            session,
            features,
            path: model.to_path_buf(),
        })
    }

    /// The features the model takes, in channel order (always starting with hdr).
    pub fn features(&self) -> &[Feature] {
        &self.features
    }

    /// Denoises one image. `inputs` holds one image per feature of [`Denoiser::features`], in
    /// that order, all of the same size and finite (the caller checks and names the files).
    pub fn denoise(&mut self, inputs: &[&RgbImage], tiling: Tiling) -> Result<RgbImage> {
        assert_eq!(inputs.len(), self.features.len());
        let (width, height) = (inputs[0].width, inputs[0].height);
        let exposure = inputs[0].autoexposure() as f32;
        let mut out = RgbImage::new(width, height);
        for (y0, y1) in spans(height, tiling.tile) {
            for (x0, x1) in spans(width, tiling.tile) {
                // The core [x0, x1) × [y0, y1) with its context, clipped to the image.
                let (cx0, cy0) = (
                    x0.saturating_sub(tiling.overlap),
                    y0.saturating_sub(tiling.overlap),
                );
                let cx1 = (x1 + tiling.overlap).min(width);
                let cy1 = (y1 + tiling.overlap).min(height);
                let tile = self.run(inputs, exposure, (cx0, cy0, cx1, cy1))?;
                let tw = cx1 - cx0;
                for y in y0..y1 {
                    for x in x0..x1 {
                        out.pixels[y * width + x] = tile[(y - cy0) * tw + (x - cx0)];
                    }
                }
            }
        }
        if let Some((x, y)) = out.first_non_finite() {
            return Err(Error::input(
                &self.path,
                format!("model produced a non-finite value at pixel ({x}, {y})"),
            ));
        }
        Ok(out)
    }

    /// Runs the model on the region (x0, y0, x1, y1) of the inputs; returns its pixels.
    fn run(
        &mut self,
        inputs: &[&RgbImage],
        exposure: f32,
        (x0, y0, x1, y1): (usize, usize, usize, usize),
    ) -> Result<Vec<[f32; 3]>> {
        let (w, h) = (x1 - x0, y1 - y0);
        let plane = w * h;
        let mut data = vec![0f32; 3 * inputs.len() * plane];
        for (f, image) in inputs.iter().enumerate() {
            for y in 0..h {
                let row = &image.pixels[(y0 + y) * image.width + x0..][..w];
                for (x, p) in row.iter().enumerate() {
                    for c in 0..3 {
                        data[(3 * f + c) * plane + y * w + x] = p[c];
                    }
                }
            }
        }
        let err =
            |e: &dyn std::fmt::Display| Error::input(&self.path, format!("inference failed: {e}"));
        let input =
            Tensor::from_array(([1usize, 3 * inputs.len(), h, w], data)).map_err(|e| err(&e))?;
        let exposure = Tensor::from_array(([1usize], vec![exposure])).map_err(|e| err(&e))?;
        let outputs = self
            .session
            .run(ort::inputs!["input" => input, "exposure" => exposure])
            .map_err(|e| err(&e))?;
        let (shape, values) = outputs["output"]
            .try_extract_tensor::<f32>()
            .map_err(|e| err(&e))?;
        if **shape != [1, 3, h as i64, w as i64] {
            return Err(Error::input(
                &self.path,
                format!(
                    "model output has shape {:?}, expected [1, 3, {h}, {w}]",
                    &**shape
                ),
            ));
        }
        Ok((0..plane)
            .map(|i| [values[i], values[plane + i], values[2 * plane + i]])
            .collect())
    }
}

/// Splits 0..n into consecutive spans of at most `size` (the last may be shorter).
fn spans(n: usize, size: usize) -> Vec<(usize, usize)> {
    (0..n.div_ceil(size))
        .map(|i| (i * size, ((i + 1) * size).min(n)))
        .collect()
}

/// The feature files of a noisy image `<stem>.hdr.exr`: `<stem>.<feature>.exr`.
pub fn feature_path(hdr: &Path, feature: Feature) -> Option<PathBuf> {
    let name = hdr.file_name()?.to_str()?;
    let stem = name.strip_suffix(".hdr.exr")?;
    Some(hdr.with_file_name(format!("{stem}.{}.exr", feature.name())))
}

/// The output of a noisy image `<stem>.hdr.exr`: `<stem>.dn.exr`.
pub fn output_path(hdr: &Path) -> Option<PathBuf> {
    let name = hdr.file_name()?.to_str()?;
    let stem = name.strip_suffix(".hdr.exr")?;
    Some(hdr.with_file_name(format!("{stem}.dn.exr")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_cover_without_overlap() {
        assert_eq!(spans(10, 4), vec![(0, 4), (4, 8), (8, 10)]);
        assert_eq!(spans(8, 8), vec![(0, 8)]);
        assert!(spans(0, 8).is_empty());
    }

    #[test]
    fn feature_and_output_names_follow_the_oidn_layout() {
        let p = Path::new("data/x/gen0001_000004spp.hdr.exr");
        assert_eq!(
            feature_path(p, Feature::Nrm).unwrap(),
            Path::new("data/x/gen0001_000004spp.nrm.exr")
        );
        assert_eq!(
            output_path(p).unwrap(),
            Path::new("data/x/gen0001_000004spp.dn.exr")
        );
        assert!(output_path(Path::new("a.exr")).is_none());
    }

    #[test]
    fn tiling_must_align_to_the_pooling_grid() {
        assert!(Tiling {
            tile: 100,
            overlap: 16
        }
        .validate()
        .is_err());
        assert!(Tiling {
            tile: 64,
            overlap: 8
        }
        .validate()
        .is_err());
        assert!(Tiling::default().validate().is_ok());
    }
}
