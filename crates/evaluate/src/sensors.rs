//! `evaluate sensors`: sensor results against the exact values of an analytic case
//! ([`luxest_exact::cases`]): per point the error and its z-score (error / the estimate's own
//! standard error), and a summary; written as CSV and RON, printed as a table, and, with a
//! largest allowed |z|, a z-test that fails the run.

use luxest_exact::cases::Case;
use luxest_io::fsio::write_ron_to;
use luxest_io::outputs::OutputPlan;
use luxest_io::sensors::SensorResults;
use luxest_io::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

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

/// Compares sensor results with the exact values of `case` (see `luxest_exact::cases`); with
/// `sets` not empty, only the points of those sensor sets.
pub fn score_sensors(
    path: &Path,
    case_spec: &str,
    sets: &[String],
    scene: Option<&Path>,
) -> Result<SensorReport> {
    let case =
        Case::parse(case_spec).map_err(|m| Error::Usage(format!("--case {case_spec}: {m}")))?;
    let mut results = SensorResults::read_ron(path)?;
    check_results(path, &results)?;
    if let Some(scene) = scene {
        let hash = luxest_io::meta::compiled_scene_hash(scene)?;
        if hash != results.run.scene_hash {
            return Err(Error::input(
                path,
                format!(
                    "results are of scene hash {}, but {} has hash {hash}: they are of another \
                     scene or an older compile of it; re-run the estimate",
                    results.run.scene_hash,
                    scene.display()
                ),
            ));
        }
    }
    if !sets.is_empty() {
        if let Some(name) = sets
            .iter()
            .find(|n| !results.sets.iter().any(|s| &s.name == *n))
        {
            return Err(Error::input(
                path,
                format!("no sensor set named \"{name}\""),
            ));
        }
        results.sets.retain(|s| sets.contains(&s.name));
    }
    case.check_geometry(&results)
        .map_err(|(place, problem)| Error::at(path, place, problem))?;
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

/// Sensor results must be what an estimate can produce: finite values with finite, positive
/// standard errors (a z-score needs one), and a recorded scene hash; a NaN would pass any
/// z-test and a zero standard error would make every error infinitely significant.
fn check_results(path: &Path, results: &SensorResults) -> Result<()> {
    if results.run.scene_hash.trim().is_empty() {
        return Err(Error::input(
            path,
            "results carry no scene hash (run.scene_hash): cannot tell which scene they are of",
        ));
    }
    for set in &results.sets {
        for (i, p) in set.points.iter().enumerate() {
            let place = format!("sets[\"{}\"].points[{i}]", set.name);
            if !p.value.is_finite() {
                return Err(Error::at(
                    path,
                    place,
                    format!("value {} is not a finite number", p.value),
                ));
            }
            if !(p.standard_error.is_finite() && p.standard_error > 0.0) {
                return Err(Error::at(
                    path,
                    place,
                    format!(
                        "standard error {} must be a finite number > 0 (a z-score divides by it)",
                        p.standard_error
                    ),
                ));
            }
        }
    }
    Ok(())
}

impl SensorReport {
    /// Writes the report as CSV, the planned output `path`.
    pub fn write_csv_to(&self, plan: &mut OutputPlan, path: &Path) -> Result<()> {
        plan.write(path, |w| {
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
    /// Writes the report as RON, the planned output `path`.
    pub fn write_ron_to(&self, plan: &mut OutputPlan, path: &Path) -> Result<()> {
        write_ron_to(plan, path, self)
    }

    /// The comparison as a table for people (machines read the CSV or RON); rows with
    /// |z| > `max_z` are flagged.
    pub fn table(&self, max_z: Option<f64>) -> String {
        let mut t = format!(
            "{} — {} {} samples, {:.2} s, singularity {}, case {}\n",
            self.results, self.estimator, self.samples, self.seconds, self.singularity, self.case
        );
        t += &format!(
            "  {:<34} {:>14} {:>14} {:>11} {:>7} {:>10}\n",
            "point", "exact", "estimate", "std.err", "z", "rel.err"
        );
        for r in &self.rows {
            let flag = if max_z.is_some_and(|m| r.z.abs() > m) {
                "  <-- |z| too large"
            } else {
                ""
            };
            t += &format!(
                "  {:<34} {:>14.6e} {:>14.6e} {:>11.3e} {:>7.2} {:>10.2e}{flag}\n",
                r.label, r.exact, r.estimate, r.standard_error, r.z, r.relative_error
            );
        }
        t
    }

    /// The z-test: an error naming the results file when any |z| exceeds `max_z`.
    pub fn z_test(&self, max_z: f64) -> Result<()> {
        let bad = self.rows.iter().filter(|r| r.z.abs() > max_z).count();
        if bad > 0 {
            return Err(Error::input(
                Path::new(&self.results),
                format!(
                    "validation failed: {bad} of {} values have |z| > {max_z}",
                    self.rows.len()
                ),
            ));
        }
        Ok(())
    }
}
