//! Sensor results: the contract between `estimate`, which writes illuminance at points, and
//! the stages that read it (`evaluate sensors`). RON (always) and CSV (on request).

use crate::color::Rgb;
use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::meta::RunInfo;
use crate::outputs::OutputPlan;
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
    /// The unified glare rating at every observer and line of sight of the scene (`estimate
    /// sensors`; see [`GlareResult`]); absent when the scene has no observers.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub glare: Vec<GlareResult>,
}

/// The unified glare rating (CIE 117) seen by one observer along one line of sight:
/// UGR = 8 log10(0.25 / L_b · Σ L² ω / p²) over `sources` (`luxest_photometry::ugr`).
///
/// UGR below the formula's range: with no source in view (Σ = 0) `ugr` is 0 and `note` says
/// so (never −∞ or NaN); a value below 10 is kept as computed (EN 12464-1 and CIE tables print
/// it as "<10").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GlareResult {
    /// The observer's name in the scene.
    pub observer: String,
    /// Eye position, m.
    pub position: Vec3,
    /// Line of sight (unit).
    pub view: Vec3,
    pub ugr: f64,
    /// Standard error of `ugr`, propagated from the background luminance's.
    pub standard_error: f64,
    /// L_b = indirect illuminance at the eye (on the plane facing `view`) / π, cd/m², with its
    /// standard error from the same batches.
    pub background_luminance: Part,
    /// The task area's limit UGR_L (EN 12464-1) when the scene gives one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limit: Option<f64>,
    /// Every luminaire in the field of view and not hidden, with its terms.
    pub sources: Vec<GlareSource>,
    /// Why `ugr` is not the formula's value (no source in view), when it is not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// One luminaire's terms in a [`GlareResult`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GlareSource {
    /// The luminaire's name in the scene.
    pub luminaire: String,
    /// Luminance towards the eye, cd/m².
    pub luminance: f64,
    /// Solid angle of its visible luminous area, sr.
    pub solid_angle_sr: f64,
    /// Guth position index.
    pub position_index: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSetResult {
    pub name: String,
    /// For a grid (a `Grid` sensor or a calculation surface): its layout; point k = j · nu + i
    /// is the centre of cell (i, j), i along u.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grid: Option<SensorGrid>,
    /// What the points measure when it is not planar illuminance: `cylindrical` or
    /// `semi-cylindrical` (`None`: planar, on each point's `normal`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<String>,
    pub points: Vec<SensorValue>,
    /// On request (`estimate sensors --batch-values`): `batches[b][k]` is independent batch b's
    /// estimate of Y (lx) at point k. Each point's `value` is the mean over the batches and its
    /// `standard_error` their standard deviation / √B, so statistics of several points (a
    /// grid's Emin, U0) can propagate their uncertainty through the batches, correlations
    /// between points included.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub batches: Vec<Vec<f64>>,
}

/// The layout of a sensor grid in world space.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorGrid {
    /// Points along u and v.
    pub nu: u32,
    pub nv: u32,
    /// Corner of the whole rectangle (a work plane's height included, the margin not), m.
    pub origin: Vec3,
    /// The rectangle's full edges, m.
    pub u: Vec3,
    pub v: Vec3,
    /// Border excluded on every side (0 for a `Grid` sensor), m; the points lie at
    /// origin + (margin + (i + ½)(|u| − 2 margin)/nu) û + (margin + (j + ½)(|v| − 2 margin)/nv) v̂.
    pub margin_m: f64,
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
    /// Where the estimator evaluated the illuminance, when that is not `position`: a sensor on
    /// an edge or in a corner is moved off the adjacent surfaces (see `estimate`'s placement).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub evaluated_at: Option<Vec3>,
    /// The direct part of `value` (light arriving straight from the emitters), when the
    /// estimator separates it (the local estimate does).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direct: Option<Part>,
    /// The indirect part of `value` (light reflected at least once); `direct.value +
    /// indirect.value = value`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect: Option<Part>,
}

/// A part of an illuminance (Y, lx) with its own standard error from the same independent
/// batches as the whole.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Part {
    pub value: f64,
    pub standard_error: f64,
}

impl SensorValue {
    /// A point's result without the optional fields.
    pub fn new(position: Vec3, normal: Vec3, value: f64, standard_error: f64, rgb: Rgb) -> Self {
        SensorValue {
            position,
            normal,
            value,
            standard_error,
            rgb,
            evaluated_at: None,
            direct: None,
            indirect: None,
        }
    }
}

impl SensorResults {
    /// Writes the results alone (tools and tests; stages use [`SensorResults::write_ron_to`]).
    pub fn write_ron(&self, path: &Path) -> Result<()> {
        crate::fsio::write_ron(path, self)
    }

    /// Writes the results as the planned output `path`.
    pub fn write_ron_to(&self, plan: &mut OutputPlan, path: &Path) -> Result<()> {
        crate::fsio::write_ron_to(plan, path, self)
    }

    pub fn read_ron(path: &Path) -> Result<SensorResults> {
        crate::fsio::read_ron(path)
    }

    /// The CSV alone, atomically (tools and tests; stages use [`SensorResults::write_csv_to`]).
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        let mut plan = OutputPlan::new(Vec::<&Path>::new(), [path])?;
        self.write_csv_to(&mut plan, path)?;
        plan.commit()
    }

    /// One row per sensor point, as the planned output `path`.
    pub fn write_csv_to(&self, plan: &mut OutputPlan, path: &Path) -> Result<()> {
        plan.write(path, |w| {
            let io = |e| Error::io(path, e);
            writeln!(
                w,
                "set,index,x,y,z,nx,ny,nz,value_{u},standard_error_{u},r,g,b,\
                 evaluated_x,evaluated_y,evaluated_z,direct_{u},direct_standard_error_{u},\
                 indirect_{u},indirect_standard_error_{u}",
                u = self.unit
            )
            .map_err(io)?;
            for s in &self.sets {
                for (i, p) in s.points.iter().enumerate() {
                    write!(
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
                    // The evaluated point (the position itself when not moved); the parts
                    // left empty when the estimator does not separate them.
                    let e = p.evaluated_at.unwrap_or(p.position);
                    let part = |q: Option<Part>| {
                        q.map_or(",".to_string(), |q| {
                            format!("{:e},{:e}", q.value, q.standard_error)
                        })
                    };
                    writeln!(
                        w,
                        ",{},{},{},{},{}",
                        e.x,
                        e.y,
                        e.z,
                        part(p.direct),
                        part(p.indirect)
                    )
                    .map_err(io)?;
                }
            }
            Ok(())
        })
    }
}
