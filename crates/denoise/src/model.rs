//! The ONNX model through ONNX Runtime: loading it (once per process, the library found at run
//! time), checking it against the model contract, and running it over an image in tiles.

use luxest_io::exposure::{dim_exponent, range_exponent};
use luxest_io::header;
use luxest_io::image::RgbImage;
use luxest_io::progress::Progress;

use luxest_io::{Error, Result};
use ort::environment::Environment;
use ort::session::Session;
use ort::value::{Tensor, ValueType};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crate::feature::{names, Feature};
use crate::tiling::{spans, Tiling};

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

/// The names of the model graph's tensors (`training/export.py` names them through
/// `luxest_contract`'s `INPUT_TENSOR`, `EXPOSURE_TENSOR`, `OUTPUT_TENSOR`; tied by
/// `tests/fixtures/contract/tensors.json`).
pub mod tensor {
    /// Input: float32 NCHW, the raw linear features named in `luxest.channels`.
    pub const INPUT: &str = "input";
    /// Input: float32 (N,), the autoexposure of each whole image.
    pub const EXPOSURE: &str = "exposure";
    /// Output: float32 N×3×H×W, the denoised linear radiance.
    pub const OUTPUT: &str = "output";

    /// Every tensor name: the inputs, then the output.
    pub const ALL: [&str; 3] = [INPUT, EXPOSURE, OUTPUT];
}

/// A loaded denoising model.
pub struct Denoiser {
    session: Session,
    features: Vec<Feature>,
    path: PathBuf,
    feature_samples: u64,
    mean_luminance: Option<f64>,
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
        let bytes = luxest_io::fsio::read_bytes(model)?;
        let ort_err = |e: &dyn std::fmt::Display| Error::input(model, format!("{e}"));
        let session = Session::builder(env)
            .map_err(|e| ort_err(&e))?
            .with_intra_threads(threads.max(1))
            .map_err(|e| ort_err(&e))?
            // Idle pool threads sleep instead of spinning between operators: spinning counts
            // as CPU time and steals the cores from the other threads of a shared machine
            // (docs/measurements.md, *denoise*).
            .with_intra_op_spinning(false)
            .map_err(|e| ort_err(&e))?
            .with_inter_threads(1)
            .map_err(|e| ort_err(&e))?
            .commit_from_memory(&bytes)
            .map_err(|e| load_error(model, &bytes, &e.to_string()))?;

        let input = session.inputs().iter().find(|o| o.name() == tensor::INPUT);
        let input_shape = input
            .and_then(|o| tensor_shape(o.dtype()))
            .filter(|s| s.len() == 4)
            .ok_or_else(|| {
                Error::input(
                    model,
                    format!(
                        "model has no float32 NCHW input named `{}` (see models/README.md)",
                        tensor::INPUT
                    ),
                )
            })?;
        let exposure_ok = session
            .inputs()
            .iter()
            .find(|o| o.name() == tensor::EXPOSURE)
            .and_then(|o| tensor_shape(o.dtype()))
            .is_some_and(|s| s.len() == 1);
        if !exposure_ok {
            return Err(Error::input(
                model,
                format!(
                    "model has no float32 (N,) input named `{}` (exported before the \
                     whole-image exposure contract? re-export it with training/export.py)",
                    tensor::EXPOSURE
                ),
            ));
        }
        if let Some(extra) = session
            .inputs()
            .iter()
            .find(|o| o.name() != tensor::INPUT && o.name() != tensor::EXPOSURE)
        {
            return Err(Error::input(
                model,
                format!("model has an unexpected input `{}`", extra.name()),
            ));
        }
        let output_ok = session
            .outputs()
            .iter()
            .find(|o| o.name() == tensor::OUTPUT)
            .and_then(|o| tensor_shape(o.dtype()))
            .is_some_and(|s| s.len() == 4 && (s[1] == 3 || s[1] < 0));
        if !output_ok {
            return Err(Error::input(
                model,
                format!(
                    "model has no float32 N×3×H×W output named `{}`",
                    tensor::OUTPUT
                ),
            ));
        }

        let channels = session
            .metadata()
            .ok()
            .and_then(|m| m.custom(header::CHANNELS));
        let features: Vec<Feature> = match channels {
            Some(list) => list
                .split(',')
                .map(|s| {
                    Feature::parse(s).ok_or_else(|| {
                        Error::input(
                            model,
                            format!(
                                "metadata {} names an unknown feature `{s}`",
                                header::CHANNELS
                            ),
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
                    "input has {} channels, but its features {} need {} (3 per feature)",
                    input_shape[1],
                    names(&features),
                    3 * features.len()
                ),
            ));
        }
        let meta = |key: &str| session.metadata().ok().and_then(|m| m.custom(key));
        let feature_samples = match meta(header::model::FEATURE_SAMPLES) {
            Some(v) => v
                .trim()
                .parse::<u64>()
                .ok()
                .filter(|&n| n >= 1)
                .ok_or_else(|| {
                    Error::input(
                        model,
                        format!(
                            "metadata {} = `{v}`: expected a sample count of at least 1",
                            header::model::FEATURE_SAMPLES
                        ),
                    )
                })?,
            None => 1,
        };
        let mean_luminance = match meta(header::model::MEAN_LUMINANCE) {
            Some(v) => Some(
                v.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite() && *x > 0.0)
                    .ok_or_else(|| {
                        Error::input(
                            model,
                            format!(
                                "metadata {} = `{v}`: expected a positive luminance",
                                header::model::MEAN_LUMINANCE
                            ),
                        )
                    })?,
            ),
            None => None,
        };
        Ok(Denoiser {
            session,
            features,
            path: model.to_path_buf(),
            feature_samples,
            mean_luminance,
        })
    }

    /// The least samples per pixel of the albedo and normal images the model takes (its
    /// metadata `luxest.feature_samples`; 1 when absent: any).
    pub fn feature_samples(&self) -> u64 {
        self.feature_samples
    }

    /// The mean luminance whose octave the model's input radiance is scaled into (its metadata
    /// `luxest.mean_luminance`), or None: only dim images are brightened.
    pub fn mean_luminance(&self) -> Option<f64> {
        self.mean_luminance
    }

    /// The features the model takes, in channel order (always starting with hdr).
    pub fn features(&self) -> &[Feature] {
        &self.features
    }

    /// Seconds per pixel of [`Denoiser::denoise`] on this machine and model, timed on a
    /// synthetic 128² image (a grey wall, facing the camera, no emitter): the calibration of a
    /// denoise run's plan. Small images pay the graph's fixed costs per pixel, so the figure
    /// errs on the long side.
    pub fn seconds_per_pixel(&mut self, tiling: Tiling) -> Result<f64> {
        let side = 128;
        let image = |v: [f32; 3]| {
            let mut img = RgbImage::new(side, side);
            img.pixels.iter_mut().for_each(|p| *p = v);
            img
        };
        let inputs: Vec<RgbImage> = self
            .features
            .iter()
            .map(|f| match f {
                Feature::Hdr | Feature::Alb => image([0.5; 3]),
                Feature::Nrm => image([0.0, 0.0, 1.0]),
                Feature::Emi | Feature::Ema => image([0.0; 3]),
            })
            .collect();
        let refs: Vec<&RgbImage> = inputs.iter().collect();
        let start = std::time::Instant::now();
        self.denoise(&refs, tiling, &Progress::off())?;
        Ok(start.elapsed().as_secs_f64() / (side * side) as f64)
    }

    /// Denoises one image, counting its pixels on `progress` tile by tile. `inputs` holds one
    /// image per feature of [`Denoiser::features`], in that order, all of the same size and
    /// finite (the caller checks and names the files).
    pub fn denoise(
        &mut self,
        inputs: &[&RgbImage],
        tiling: Tiling,
        progress: &Progress,
    ) -> Result<RgbImage> {
        assert_eq!(inputs.len(), self.features.len());
        let (width, height) = (inputs[0].width, inputs[0].height);
        // Radiance near the f32 limit (finite, valid input) would overflow inside the model's
        // f32 arithmetic, and its exposure (0.18 / 3.4e38) is subnormal. The model is
        // scale-equivariant through its exposure input (it sees hdr x exposure and returns its
        // result / exposure), so the hdr image is scaled by an exact power of two 2^-k into
        // range and the exposure by 2^k: the model's input is bit-identical, and the result is
        // scaled back by 2^k in f64.
        let peak = inputs
            .iter()
            .zip(&self.features)
            .filter(|(_, f)| f.is_radiance())
            .flat_map(|(image, _)| image.pixels.iter().flatten())
            .fold(0.0f64, |m, v| m.max((*v as f64).abs()));
        let k = if peak > LARGEST_MODEL_INPUT {
            (peak / LARGEST_MODEL_INPUT).log2().ceil() as i32
        } else {
            0
        };
        // A dim image (mean luminance below DIM_LUMINANCE) is brightened by a power of two
        // instead, with the exposure of the brightened image: the autoexposure's 1e-4 would
        // otherwise make the model's input depend on the radiance's unit (luxest_io::exposure::
        // dim_exponent); a model that records a mean luminance gets every image scaled into
        // its octave, bright ones dimmed (range_exponent). Exclusive with the above: an image
        // near the limit is scaled by it (its mean is far above any recorded luminance).
        let (hdr_scale, exposure) = if k > 0 {
            let s = 2f64.powi(-k);
            (s, inputs[0].autoexposure() / s)
        } else {
            let emission = self
                .features
                .iter()
                .position(|f| *f == Feature::Emi)
                .map(|i| inputs[i]);
            let e = match self.mean_luminance {
                Some(low) => range_exponent(inputs[0], emission, low),
                None => dim_exponent(inputs[0], emission),
            };
            let s = 2f64.powi(e);
            (s, inputs[0].autoexposure_scaled(s))
        };
        let exposure = exposure as f32;
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
                let tile = self.run(inputs, hdr_scale, exposure, (cx0, cy0, cx1, cy1))?;
                let tw = cx1 - cx0;
                for y in y0..y1 {
                    for x in x0..x1 {
                        out.pixels[y * width + x] = tile[(y - cy0) * tw + (x - cx0)];
                    }
                }
                progress.inc(((x1 - x0) * (y1 - y0)) as u64);
            }
        }
        if let Some((x, y)) = out.first_non_finite() {
            return Err(Error::input(
                &self.path,
                format!("model produced a non-finite value at pixel ({x}, {y})"),
            ));
        }
        if hdr_scale != 1.0 {
            for (i, p) in out.pixels.iter_mut().enumerate() {
                for c in p.iter_mut() {
                    let v = *c as f64 / hdr_scale;
                    if v.abs() > f32::MAX as f64 {
                        // Usage carries no file; the caller names the input image.
                        return Err(Error::Usage(format!(
                            "the denoised value {v:.3e} at pixel ({}, {}) exceeds the largest \
                             32-bit float (3.403e38): the input's radiance reaches {peak:.3e}, \
                             too close to the limit of the EXR format to denoise",
                            i % width,
                            i / width
                        )));
                    }
                    *c = v as f32;
                }
            }
        }
        Ok(out)
    }

    /// Runs the model on the region (x0, y0, x1, y1) of the inputs; returns its pixels.
    fn run(
        &mut self,
        inputs: &[&RgbImage],
        hdr_scale: f64,
        exposure: f32,
        (x0, y0, x1, y1): (usize, usize, usize, usize),
    ) -> Result<Vec<[f32; 3]>> {
        let (w, h) = (x1 - x0, y1 - y0);
        let plane = w * h;
        let mut data = vec![0f32; 3 * inputs.len() * plane];
        for (f, (image, feature)) in inputs.iter().zip(&self.features).enumerate() {
            for y in 0..h {
                let row = &image.pixels[(y0 + y) * image.width + x0..][..w];
                // Only radiance is scaled (by a power of two: exact, in f64 since a dim image's
                // 2^e may exceed f32's range); surface features are not.
                if feature.is_radiance() && hdr_scale != 1.0 {
                    for (x, p) in row.iter().enumerate() {
                        for c in 0..3 {
                            data[(3 * f + c) * plane + y * w + x] =
                                (p[c] as f64 * hdr_scale) as f32;
                        }
                    }
                } else {
                    for (x, p) in row.iter().enumerate() {
                        for c in 0..3 {
                            data[(3 * f + c) * plane + y * w + x] = p[c];
                        }
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
            .run(ort::inputs![tensor::INPUT => input, tensor::EXPOSURE => exposure])
            .map_err(|e| err(&e))?;
        let (shape, values) = outputs[tensor::OUTPUT]
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

/// The feature names, comma-separated.
/// The `ir_version` of an ONNX ModelProto: protobuf field 1, a varint, written first.
fn onnx_ir_version(bytes: &[u8]) -> Option<u64> {
    if bytes.first() != Some(&0x08) {
        return None;
    }
    let mut v = 0u64;
    for (i, b) in bytes[1..].iter().take(10).enumerate() {
        v |= ((b & 0x7f) as u64) << (7 * i);
        if b & 0x80 == 0 {
            return Some(v);
        }
    }
    None
}

/// One line for a model ONNX Runtime cannot load. Its own message for a too new IR version is a
/// C++ signature of hundreds of characters; name the file's IR version and the supported one.
fn load_error(model: &Path, bytes: &[u8], message: &str) -> Error {
    if message.contains("IR version") {
        let supported = message
            .split("max supported IR version:")
            .nth(1)
            .and_then(|t| {
                t.trim_start()
                    .split(|c: char| !c.is_ascii_digit())
                    .next()
                    .map(str::to_string)
            })
            .filter(|t| !t.is_empty());
        let found = onnx_ir_version(bytes).map_or("unknown".to_string(), |v| v.to_string());
        return Error::input(
            model,
            format!(
                "ONNX IR version {found} is not supported by this ONNX Runtime (it reads IR \
                 versions up to {}); re-export the model with training/export.py",
                supported.as_deref().unwrap_or("an older one")
            ),
        );
    }
    let first = message.lines().next().unwrap_or(message);
    let short: String = first.chars().take(200).collect();
    Error::input(model, format!("not a loadable ONNX model: {short}"))
}

/// Largest radiance handed to the model unscaled: 2^100 (1.3e30), eight orders of magnitude
/// below the f32 maximum, room for the network's intermediate sums and products.
const LARGEST_MODEL_INPUT: f64 = 1.2676506002282294e30;
