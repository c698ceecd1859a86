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
    /// The daylight sky of the scene, when it has one: the unobstructed horizontal
    /// illuminance that daylight factors divide by.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sky: Option<SkyInfo>,
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

/// A daylight sky as the sensor results record it (`luxest_render::sky`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkyInfo {
    /// gensky's command line of the same sky and the solar position.
    pub description: String,
    /// Unobstructed global horizontal illuminance, lx: the sky's (integrated over the
    /// tabulated map the estimators use) plus the sun's direct part. Daylight factor =
    /// E / this (under an overcast sky, which has no sun).
    pub horizontal_illuminance_lux: f64,
    /// The sky's diffuse part of it, lx.
    pub sky_horizontal_illuminance_lux: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun: Option<SunInfo>,
}

/// The sun of a daylight sky.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SunInfo {
    /// Degrees above the horizon.
    pub altitude_deg: f64,
    /// Degrees west of south (gensky's convention).
    pub azimuth_deg: f64,
    /// On a plane facing the sun, lx.
    pub direct_normal_illuminance_lux: f64,
    /// On the unobstructed horizontal plane, lx.
    pub direct_horizontal_illuminance_lux: f64,
}

/// EN 17037 daylight-factor figures of a set of points (percent).
#[derive(Clone, Debug, PartialEq)]
pub struct DaylightFactors {
    /// The median: the value reached on half of the points (EN 17037's target D_T).
    pub median_percent: f64,
    /// The value reached on 95 % of the points (EN 17037's minimum target D_TM).
    pub p95_percent: f64,
    /// The smallest point's.
    pub min_percent: f64,
    pub mean_percent: f64,
}

/// Daylight factors (%) of illuminances `values` (lx) under a sky of unobstructed horizontal
/// illuminance `horizontal` (lx): D = 100 E / E_h; the median and the 95 %-fractile by linear
/// interpolation between order statistics (the fraction of points at or above a value). An
/// error for no points, a non-finite value, or a sky without light.
pub fn daylight_factors(
    values: &[f64],
    horizontal: f64,
) -> std::result::Result<DaylightFactors, String> {
    if values.is_empty() {
        return Err("daylight factors of no points".into());
    }
    if !(horizontal.is_finite() && horizontal > 0.0) {
        return Err(format!(
            "the sky's horizontal illuminance {horizontal} lx is not positive: no daylight factor"
        ));
    }
    if let Some(v) = values.iter().find(|v| !v.is_finite()) {
        return Err(format!("illuminance {v} is not finite"));
    }
    let mut d: Vec<f64> = values.iter().map(|e| 100.0 * e / horizontal).collect();
    d.sort_by(f64::total_cmp);
    // The value exceeded by a fraction f of the points: quantile 1 − f.
    let quantile = |q: f64| {
        let x = q * (d.len() - 1) as f64;
        let i = x.floor() as usize;
        let j = (i + 1).min(d.len() - 1);
        d[i] + (d[j] - d[i]) * (x - i as f64)
    };
    Ok(DaylightFactors {
        median_percent: quantile(0.5),
        p95_percent: quantile(0.05),
        min_percent: d[0],
        mean_percent: d.iter().sum::<f64>() / d.len() as f64,
    })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn daylight_factor_figures() {
        // 1 … 21 lx under 100 lx: D = 1 … 21 %; the median is the 11th, the 95 %-fractile
        // lies at 1 + 0.05 · 20 = 2 %.
        let e: Vec<f64> = (1..=21).rev().map(f64::from).collect();
        let d = daylight_factors(&e, 100.0).unwrap();
        assert_eq!(d.median_percent, 11.0);
        assert!((d.p95_percent - 2.0).abs() < 1e-12);
        assert_eq!(d.min_percent, 1.0);
        assert!((d.mean_percent - 11.0).abs() < 1e-12);
        assert!(daylight_factors(&e, 0.0)
            .unwrap_err()
            .contains("not positive"));
        assert!(daylight_factors(&[], 1.0).is_err());
        assert!(daylight_factors(&[f64::NAN], 1.0).is_err());
    }
}
