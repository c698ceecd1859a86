//! Sensor results: the contract between `estimate sensors` and the stages that read illuminance
//! at points (`evaluate`, `estimate compare`). RON (always) and CSV (on request).

use crate::color::Rgb;
use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::meta::RunInfo;
use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorResults {
    pub scene: String,
    pub run: RunInfo,
    /// Unit of `value` and `standard_error`: "lx" (photometric: Y of the RGB illuminance).
    pub unit: String,
    /// How the kernel singularity was controlled, e.g. `ball(eps=0.001 m)`.
    pub singularity: String,
    pub sets: Vec<SensorSetResult>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSetResult {
    pub name: String,
    pub points: Vec<SensorValue>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorValue {
    pub position: Vec3,
    pub normal: Vec3,
    /// Illuminance (Y), lx.
    pub value: f64,
    /// Standard error of `value` from independent batches, lx.
    pub standard_error: f64,
    /// RGB illuminance, lx per channel.
    pub rgb: Rgb,
}

impl SensorResults {
    pub fn write_ron(&self, path: &Path) -> Result<()> {
        crate::fsio::write_ron(path, self)
    }

    pub fn read_ron(path: &Path) -> Result<SensorResults> {
        crate::fsio::read_ron(path)
    }

    /// One row per sensor point.
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        crate::fsio::write_atomically(path, |w| {
            let io = |e| Error::io(path, e);
            writeln!(
                w,
                "set,index,x,y,z,nx,ny,nz,value_{u},standard_error_{u},r,g,b",
                u = self.unit
            )
            .map_err(io)?;
            for s in &self.sets {
                for (i, p) in s.points.iter().enumerate() {
                    writeln!(
                        w,
                        "{},{},{},{},{},{},{},{},{:e},{:e},{:e},{:e},{:e}",
                        s.name,
                        i,
                        p.position.x,
                        p.position.y,
                        p.position.z,
                        p.normal.x,
                        p.normal.y,
                        p.normal.z,
                        p.value,
                        p.standard_error,
                        p.rgb.0[0],
                        p.rgb.0[1],
                        p.rgb.0[2]
                    )
                    .map_err(io)?;
                }
            }
            Ok(())
        })
    }
}
