//! A calculation surface as the report sees it: the grid's layout, the point values with their
//! standard errors and, when the estimator wrote them, the per-batch values; and the figures
//! (Eavg, Emin, Emax, U0, Ud) with their uncertainties computed from them.

use luxest_io::{Error, Result};
use luxest_photometry::{CalcGrid, GridSpec, GridStats, Spacing};
use std::path::Path;

/// The layout of a surface's grid in world space (as `scene-compile` laid it out).
#[derive(Clone, Debug, PartialEq)]
pub struct GridGeometry {
    /// Corner of the whole rectangle (work-plane height included, margin not), m.
    pub origin: [f64; 3],
    /// The rectangle's full edges, m.
    pub u: [f64; 3],
    pub v: [f64; 3],
    /// Border excluded on every side, m.
    pub margin_m: f64,
    /// Points along u and v; point k = j · nu + i is the centre of cell (i, j).
    pub nu: usize,
    pub nv: usize,
}

fn length(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

impl GridGeometry {
    /// The photometry crate's grid with the same points (the counts given, no offset: the
    /// origin already lies in the surface).
    pub fn calc_grid(&self) -> std::result::Result<CalcGrid, String> {
        CalcGrid::new(GridSpec {
            origin: self.origin,
            edge_u: self.u,
            edge_v: self.v,
            offset_m: 0.0,
            margin_m: self.margin_m,
            spacing: Spacing::Counts(self.nu, self.nv),
        })
        .map_err(|e| e.0)
    }

    /// Point spacing along u and v, m.
    pub fn spacing_m(&self) -> (f64, f64) {
        (
            (length(self.u) - 2.0 * self.margin_m) / self.nu as f64,
            (length(self.v) - 2.0 * self.margin_m) / self.nv as f64,
        )
    }

    /// Sides of the whole rectangle, m.
    pub fn sides_m(&self) -> (f64, f64) {
        (length(self.u), length(self.v))
    }

    /// A world position in the rectangle's own coordinates (s along u, t along v, m).
    pub fn local_st(&self, p: [f64; 3]) -> (f64, f64) {
        let d = [0, 1, 2].map(|k| p[k] - self.origin[k]);
        let (lu, lv) = self.sides_m();
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        (dot(d, self.u) / lu, dot(d, self.v) / lv)
    }
}

/// One calculation surface's results.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    pub name: String,
    /// What the points measure, in words (`planar`, `cylindrical`, ...).
    pub kind: String,
    pub grid: GridGeometry,
    pub positions: Vec<[f64; 3]>,
    /// Illuminance, lx.
    pub values: Vec<f64>,
    /// Standard errors of `values`, lx.
    pub std_errors: Vec<f64>,
    /// `batches[b][k]`: batch b's estimate at point k (independent batches), lx.
    pub batches: Option<Vec<Vec<f64>>>,
}

/// How the figures' standard errors were obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UncertaintyMethod {
    /// Delete-one-batch jackknife over B independent batches (correlations included).
    Jackknife { batches: usize },
    /// Per-point standard errors propagated with the points assumed independent.
    Independent,
}

impl Surface {
    /// Checks the surface's numbers; `file` names the results file in errors.
    pub fn validate(&self, file: &Path) -> Result<()> {
        let place = format!("set \"{}\"", self.name);
        let n = self.grid.nu * self.grid.nv;
        if n == 0 {
            return Err(Error::at(file, place, "grid has no points"));
        }
        if self.values.len() != n || self.std_errors.len() != n || self.positions.len() != n {
            return Err(Error::at(
                file,
                place,
                format!(
                    "grid is {} x {} = {n} points but the set holds {} values",
                    self.grid.nu,
                    self.grid.nv,
                    self.values.len()
                ),
            ));
        }
        if let Some(k) = (0..n).find(|&k| {
            !self.values[k].is_finite()
                || !self.std_errors[k].is_finite()
                || self.std_errors[k] < 0.0
                || self.positions[k].iter().any(|x| !x.is_finite())
        }) {
            return Err(Error::at(
                file,
                format!("{place}, point {k}"),
                "value, standard error or position is not a finite number (or the error is negative)",
            ));
        }
        if let Some(b) = &self.batches {
            if b.len() < 2 {
                return Err(Error::at(
                    file,
                    place,
                    format!("need at least 2 batches, got {}", b.len()),
                ));
            }
            if let Some((i, bad)) = b.iter().enumerate().find(|(_, x)| x.len() != n) {
                return Err(Error::at(
                    file,
                    format!("{place}, batch {i}"),
                    format!("holds {} values for {n} points", bad.len()),
                ));
            }
            if let Some((i, k)) = b
                .iter()
                .enumerate()
                .find_map(|(i, x)| x.iter().position(|v| !v.is_finite()).map(|k| (i, k)))
            {
                return Err(Error::at(
                    file,
                    format!("{place}, batch {i}, point {k}"),
                    "batch value is not a finite number",
                ));
            }
            // estimate sensors writes each value as the mean of its batches: a value edited
            // (or from another run) would be shown beside figures computed from the batches.
            if let Some(k) = (0..n).find(|&k| {
                let mean = b.iter().map(|x| x[k]).sum::<f64>() / b.len() as f64;
                (self.values[k] - mean).abs() > 1e-9 * self.values[k].abs().max(mean.abs())
            }) {
                return Err(Error::at(
                    file,
                    format!("{place}, point {k}"),
                    format!(
                        "value {} is not the mean of its {} batch values; the results were \
                         edited or mixed",
                        self.values[k],
                        b.len()
                    ),
                ));
            }
        }
        // Illuminance is a sum of non-negative contributions.
        if let Some(k) = (0..n).find(|&k| self.values[k] < 0.0) {
            return Err(Error::at(
                file,
                format!("{place}, point {k}"),
                format!("illuminance {} lx is negative", self.values[k]),
            ));
        }
        self.grid
            .calc_grid()
            .map_err(|e| Error::at(file, place, e))?;
        Ok(())
    }

    /// The figures with their standard errors (jackknife over batches when present).
    pub fn stats(&self, file: &Path) -> Result<(GridStats, UncertaintyMethod)> {
        let place = format!("set \"{}\"", self.name);
        match &self.batches {
            Some(b) => GridStats::from_batches(b)
                .map(|s| (s, UncertaintyMethod::Jackknife { batches: b.len() }))
                .map_err(|e| Error::at(file, place, e.0)),
            None => GridStats::from_independent(&self.values, &self.std_errors)
                .map(|s| (s, UncertaintyMethod::Independent))
                .map_err(|e| Error::at(file, place, e.0)),
        }
    }
}
