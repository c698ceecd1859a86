//! Run metadata carried by every Monte Carlo artifact (EXR headers, sensor results), so that any
//! output can be traced back to the samples, seed, time, estimator, scene and program behind it.

use crate::error::Result;
use crate::header;
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

impl RunInfo {
    /// The run info of this program's run: `estimator` drew `samples` with `seed` in `seconds`
    /// on the scene with content hash `scene_hash`.
    pub fn new(
        estimator: &str,
        samples: u64,
        seed: u64,
        seconds: f64,
        scene_hash: &str,
    ) -> RunInfo {
        RunInfo {
            samples,
            seed,
            seconds,
            estimator: estimator.to_string(),
            scene_hash: scene_hash.to_string(),
            program_version: PROGRAM_VERSION.to_string(),
        }
    }

    /// The header attributes of the run (keys from [`crate::header`]).
    pub fn to_attributes(&self) -> Vec<(String, String)> {
        let mut attributes = Vec::new();
        self.write_attributes(&mut attributes);
        attributes
    }

    /// Sets the run's header attributes in `attributes`, replacing earlier values.
    pub fn write_attributes(&self, attributes: &mut Vec<(String, String)>) {
        header::set(attributes, header::SAMPLES, self.samples);
        header::set(attributes, header::SEED, self.seed);
        header::set(attributes, header::SECONDS, self.seconds);
        header::set(attributes, header::ESTIMATOR, &self.estimator);
        header::set(attributes, header::SCENE_HASH, &self.scene_hash);
        header::set(attributes, header::VERSION, &self.program_version);
    }

    /// Reads the run info back from attributes; `path` names the file in errors.
    pub fn from_attributes(path: &Path, attributes: &[(String, String)]) -> Result<RunInfo> {
        Ok(RunInfo {
            samples: header::require(path, attributes, header::SAMPLES)?,
            seed: header::require(path, attributes, header::SEED)?,
            seconds: header::require(path, attributes, header::SECONDS)?,
            estimator: header::require(path, attributes, header::ESTIMATOR)?,
            scene_hash: header::require(path, attributes, header::SCENE_HASH)?,
            program_version: header::require(path, attributes, header::VERSION)?,
        })
    }
}

/// The first bytes of a compiled scene (`luxest_render::compiled`, which owns the format).
pub const COMPILED_MAGIC: &[u8; 8] = b"LUXSCENE";

/// The content hash a compiled scene records in its preamble (magic, schema u32, reserved u32,
/// xxh3-128 of the body as little-endian u128), as [`RunInfo::scene_hash`] spells it: what the
/// stages that do not load scenes (`evaluate`) compare results with. The body is not re-hashed
/// here; the stages that load the scene verify it.
pub fn compiled_scene_hash(path: &Path) -> Result<String> {
    use crate::error::Error;
    use std::io::Read;
    let mut preamble = [0u8; 32];
    let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    match f.read_exact(&mut preamble) {
        Ok(()) if &preamble[..8] == COMPILED_MAGIC => {}
        Err(e) if e.kind() != std::io::ErrorKind::UnexpectedEof => return Err(Error::io(path, e)),
        _ => {
            return Err(Error::input(
                path,
                "not a luxest compiled scene (bad magic); run scene-compile on the .ron scene",
            ))
        }
    }
    let hash = u128::from_le_bytes(preamble[16..32].try_into().expect("16 bytes"));
    Ok(format!("{hash:032x}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attributes_round_trip() {
        let info = RunInfo::new("path-tracing", 64, 7, 1.5e-3, "0123abcd");
        let back = RunInfo::from_attributes(Path::new("a.exr"), &info.to_attributes()).unwrap();
        assert_eq!(back, info);
        assert_eq!(back.program_version, PROGRAM_VERSION);
        let mut partial = info.to_attributes();
        header::remove(&mut partial, header::SEED);
        let e = RunInfo::from_attributes(Path::new("a.exr"), &partial).unwrap_err();
        assert!(e.to_string().contains(header::SEED));
    }
}
