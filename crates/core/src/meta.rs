//! Run metadata carried by every Monte Carlo artifact (EXR headers, sensor results), so that any
//! output can be traced back to the samples, seed, time, estimator, scene and program behind it.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The program version recorded in artifacts.
pub const PROGRAM_VERSION: &str = env!("CARGO_PKG_VERSION");

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunInfo {
    /// Samples per pixel (camera estimators) or light paths (local estimates).
    pub samples: u64,
    pub seed: u64,
    /// Wall-clock seconds spent rendering (excluding I/O).
    pub seconds: f64,
    /// Estimator name, e.g. `path-tracing`, `local-estimate`, `double-local-estimate`.
    pub estimator: String,
    /// Content hash of the compiled scene.
    pub scene_hash: String,
    pub program_version: String,
}

/// Attribute names used in EXR headers.
const KEYS: [&str; 6] = [
    "luxest.samples",
    "luxest.seed",
    "luxest.seconds",
    "luxest.estimator",
    "luxest.sceneHash",
    "luxest.version",
];

impl RunInfo {
    pub fn to_attributes(&self) -> Vec<(String, String)> {
        let values = [
            self.samples.to_string(),
            self.seed.to_string(),
            format!("{}", self.seconds),
            self.estimator.clone(),
            self.scene_hash.clone(),
            self.program_version.clone(),
        ];
        KEYS.iter().map(|k| k.to_string()).zip(values).collect()
    }

    /// Reads the run info back from attributes; `path` names the file in errors.
    pub fn from_attributes(path: &Path, attrs: &[(String, String)]) -> Result<RunInfo> {
        let get = |k: &str| {
            attrs
                .iter()
                .find(|(n, _)| n == k)
                .map(|(_, v)| v.as_str())
                .ok_or_else(|| Error::input(path, format!("missing header attribute {k}")))
        };
        let num = |k: &str| -> Result<u64> {
            get(k)?
                .parse()
                .map_err(|_| Error::input(path, format!("header attribute {k} is not an integer")))
        };
        Ok(RunInfo {
            samples: num(KEYS[0])?,
            seed: num(KEYS[1])?,
            seconds: get(KEYS[2])?.parse().map_err(|_| {
                Error::input(
                    path,
                    format!("header attribute {} is not a number", KEYS[2]),
                )
            })?,
            estimator: get(KEYS[3])?.to_string(),
            scene_hash: get(KEYS[4])?.to_string(),
            program_version: get(KEYS[5])?.to_string(),
        })
    }
}
