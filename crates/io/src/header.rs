//! Every `luxest.*` header key the stages exchange, and the one way to read and write them.
//!
//! EXR images carry their run metadata as string attributes under these names (see
//! [`crate::meta::RunInfo`] for the six every Monte Carlo image has); ONNX models carry
//! [`CHANNELS`] in their metadata. The Python side (`training/`, `pipelines/`) reads the same keys;
//! `tests/fixtures/contract/header.{exr,json}`, written from this module, ties the two together.
//! No other Rust source spells a `luxest.` key (checked by `tests/architecture.rs`).
//!
//! Values are text: integers in decimal, seconds as Rust's shortest round-trip `f64` formatting.

use crate::error::{Error, Result};
use std::fmt::Display;
use std::path::Path;
use std::str::FromStr;

/// Samples per pixel (camera estimators) or light paths (local estimates).
pub const SAMPLES: &str = "luxest.samples";
/// The seed of all random numbers of the run.
pub const SEED: &str = "luxest.seed";
/// Wall-clock seconds spent rendering (excluding I/O).
pub const SECONDS: &str = "luxest.seconds";
/// Estimator name: `path-tracing`, `first-hit-features`, `double-local-estimate`, ...
pub const ESTIMATOR: &str = "luxest.estimator";
/// Content hash of the compiled scene.
pub const SCENE_HASH: &str = "luxest.sceneHash";
/// Version of the program that wrote the file.
pub const VERSION: &str = "luxest.version";
/// Pixel reconstruction filter of camera estimators (`box`).
pub const PIXEL_FILTER: &str = "luxest.pixelFilter";
/// How the double local estimate handled the point-source singularity.
pub const SINGULARITY: &str = "luxest.singularity";
/// Camera samples per pixel of the double local estimate (its view points).
pub const PIXEL_SAMPLES: &str = "luxest.pixelSamples";
/// What denoised the image: the file name of a luxest ONNX model, or
/// [`OIDN_DENOISER_PREFIX`] and the version for Intel Open Image Denoise.
pub const DENOISER: &str = "luxest.denoiser";
/// How [`DENOISER`] names Intel Open Image Denoise: `oidn-<version>` (the peer of `make eval`,
/// pipelines/oidn_denoise.py).
pub const OIDN_DENOISER_PREFIX: &str = "oidn-";
/// Wall-clock seconds of denoising inference (excluding I/O).
pub const DENOISE_SECONDS: &str = "luxest.denoiseSeconds";
/// CPU seconds of denoising inference: the process's user + system time over it, all threads.
pub const DENOISE_CPU_SECONDS: &str = "luxest.denoiseCpuSeconds";
/// Render seconds of the albedo/normal feature images a denoised image used.
pub const FEATURE_SECONDS: &str = "luxest.featureSeconds";
/// ONNX model metadata: the input features in order, comma-separated (`hdr,alb,nrm`).
pub const CHANNELS: &str = "luxest.channels";

/// Every key above, in the order of this file.
pub const ALL: [&str; 14] = [
    SAMPLES,
    SEED,
    SECONDS,
    ESTIMATOR,
    SCENE_HASH,
    VERSION,
    PIXEL_FILTER,
    SINGULARITY,
    PIXEL_SAMPLES,
    DENOISER,
    DENOISE_SECONDS,
    DENOISE_CPU_SECONDS,
    FEATURE_SECONDS,
    CHANNELS,
];

/// ONNX model metadata beside [`CHANNELS`] (`training/export.py` writes them;
/// `luxest_contract`'s keys of the same names, tied by `tests/fixtures/contract/model_meta.json`).
pub mod model {
    /// The least samples per pixel of the albedo and normal features the model was trained for
    /// (`aov-write --min-samples`), decimal; `1`: features of any count. `denoise` refuses
    /// features of fewer samples.
    pub const FEATURE_SAMPLES: &str = "luxest.feature_samples";
    /// The mean luminance `v` whose octave `[v, 2v)` the model's input radiance is scaled into by
    /// a power of two (`luxest_io::exposure::range_exponent`); absent: only dim images are
    /// brightened (`dim_exponent`).
    pub const MEAN_LUMINANCE: &str = "luxest.mean_luminance";
}

/// The values of [`ESTIMATOR`]: which estimator made an image or sensor results (also
/// `RunInfo::estimator` in sensor results). `evaluate` labels denoised images
/// `<estimator>+denoise`, `<estimator>+oidn` (OIDN 1.x) or `<estimator>+oidn2` (OIDN 2.x). Python's `luxest_contract` has the same names,
/// tied by `tests/fixtures/contract/estimators.json`.
pub mod estimator {
    /// `trace`: path tracing.
    pub const PATH_TRACING: &str = "path-tracing";
    /// `aov-write`: the first-hit features (albedo, normal, emission, depth).
    pub const FIRST_HIT_FEATURES: &str = "first-hit-features";
    /// `estimate sensors`: the local estimate.
    pub const LOCAL_ESTIMATE: &str = "local-estimate";
    /// `estimate direct`: the direct-simulation baseline.
    pub const DIRECT_SIMULATION: &str = "direct-simulation";
    /// `estimate gather`.
    pub const GATHER: &str = "gather";
    /// `estimate image`: the double local estimate.
    pub const DOUBLE_LOCAL_ESTIMATE: &str = "double-local-estimate";
    /// `estimate image --light-tracing`.
    pub const LIGHT_TRACING: &str = "light-tracing";

    /// Every estimator name above, in the order of this module.
    pub const ALL: [&str; 7] = [
        PATH_TRACING,
        FIRST_HIT_FEATURES,
        LOCAL_ESTIMATE,
        DIRECT_SIMULATION,
        GATHER,
        DOUBLE_LOCAL_ESTIMATE,
        LIGHT_TRACING,
    ];
}

/// The value of `key` in a list of (name, value) attributes.
pub fn get<'a>(attributes: &'a [(String, String)], key: &str) -> Option<&'a str> {
    attributes
        .iter()
        .find(|(n, _)| n == key)
        .map(|(_, v)| v.as_str())
}

/// The value of `key` parsed as `T`; `None` when absent, an error naming `path` when malformed.
pub fn parse<T: FromStr>(
    path: &Path,
    attributes: &[(String, String)],
    key: &str,
) -> Result<Option<T>> {
    get(attributes, key)
        .map(|v| {
            v.trim().parse().map_err(|_| {
                Error::input(
                    path,
                    format!(
                        "header attribute {key} = `{v}` is not a valid {}",
                        std::any::type_name::<T>()
                    ),
                )
            })
        })
        .transpose()
}

/// The value of `key` parsed as `T`; an error naming `path` when absent or malformed.
pub fn require<T: FromStr>(path: &Path, attributes: &[(String, String)], key: &str) -> Result<T> {
    parse(path, attributes, key)?
        .ok_or_else(|| Error::input(path, format!("missing header attribute {key}")))
}

/// Sets `key` to `value`, replacing an earlier value.
pub fn set(attributes: &mut Vec<(String, String)>, key: &str, value: impl Display) {
    let value = value.to_string();
    match attributes.iter_mut().find(|(n, _)| n == key) {
        Some(slot) => slot.1 = value,
        None => attributes.push((key.to_string(), value)),
    }
}

/// Removes `key` if present.
pub fn remove(attributes: &mut Vec<(String, String)>, key: &str) {
    attributes.retain(|(n, _)| n != key);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_distinct_and_namespaced() {
        let mut keys = ALL.to_vec();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), ALL.len());
        assert!(ALL.iter().all(|k| k.starts_with("luxest.")));
    }

    #[test]
    fn set_replaces_and_parse_reports_malformed_values() {
        let mut a = Vec::new();
        set(&mut a, SAMPLES, 4);
        set(&mut a, SAMPLES, 16);
        set(&mut a, SECONDS, 0.25);
        assert_eq!(a.len(), 2);
        let p = Path::new("x.exr");
        assert_eq!(require::<u64>(p, &a, SAMPLES).unwrap(), 16);
        assert_eq!(parse::<f64>(p, &a, SECONDS).unwrap(), Some(0.25));
        assert_eq!(parse::<u64>(p, &a, SEED).unwrap(), None);
        let e = require::<u64>(p, &a, SEED).unwrap_err().to_string();
        assert!(e.contains("x.exr") && e.contains("missing header attribute luxest.seed"));
        set(&mut a, SEED, "x");
        let e = parse::<u64>(p, &a, SEED).unwrap_err().to_string();
        assert!(e.contains("luxest.seed = `x` is not a valid u64"), "{e}");
        remove(&mut a, SEED);
        assert_eq!(get(&a, SEED), None);
    }
}
