//! The per-surface tables: one row per grid point, as CSV (for spreadsheets) and RON (with the
//! grid and the figures, for programs). Both are read back by [`read_csv`] and [`read_ron`].
//!
//! CSV columns: `index,i,j,x,y,z,illuminance_lx,standard_error_lx` (k = j · nu + i, positions in
//! m). Numbers are written in Rust's shortest round-trip form, so reading gives the same f64.

use crate::surface::Surface;
use luxest_io::outputs::OutputPlan;
use luxest_io::{Error, Result};
use luxest_photometry::{Estimate, GridStats};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The CSV header line.
pub const CSV_HEADER: &str = "index,i,j,x,y,z,illuminance_lx,standard_error_lx";

/// One grid point's row.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointRow {
    pub index: usize,
    pub i: usize,
    pub j: usize,
    pub position: (f64, f64, f64),
    pub illuminance_lx: f64,
    pub standard_error_lx: f64,
}

/// A value with its standard error, as the RON table stores it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Figure {
    pub value: f64,
    pub standard_error: f64,
}

impl From<Estimate> for Figure {
    fn from(e: Estimate) -> Figure {
        Figure {
            value: e.value,
            standard_error: e.std_error,
        }
    }
}

/// The figures of a surface (lx, U0 and Ud dimensionless).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Figures {
    pub e_avg_lx: Figure,
    pub e_min_lx: Figure,
    pub e_max_lx: Figure,
    pub u0: Figure,
    pub ud: Figure,
    /// How the standard errors were obtained (`jackknife over B batches` or `independent`).
    pub uncertainty: String,
}

/// The RON table of one surface.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceTable {
    pub scene: String,
    pub surface: String,
    pub kind: String,
    pub nu: usize,
    pub nv: usize,
    pub spacing_m: (f64, f64),
    pub margin_m: f64,
    pub figures: Figures,
    pub points: Vec<PointRow>,
}

/// The rows of a surface.
pub fn rows(surface: &Surface) -> Vec<PointRow> {
    let nu = surface.grid.nu;
    (0..surface.values.len())
        .map(|k| {
            let p = surface.positions[k];
            PointRow {
                index: k,
                i: k % nu,
                j: k / nu,
                position: (p[0], p[1], p[2]),
                illuminance_lx: surface.values[k],
                standard_error_lx: surface.std_errors[k],
            }
        })
        .collect()
}

/// The RON table of a surface with its figures.
pub fn table(scene: &str, surface: &Surface, stats: &GridStats, uncertainty: &str) -> SurfaceTable {
    SurfaceTable {
        scene: scene.to_string(),
        surface: surface.name.clone(),
        kind: surface.kind.clone(),
        nu: surface.grid.nu,
        nv: surface.grid.nv,
        spacing_m: surface.grid.spacing_m(),
        margin_m: surface.grid.margin_m,
        figures: Figures {
            e_avg_lx: stats.e_avg.into(),
            e_min_lx: stats.e_min.into(),
            e_max_lx: stats.e_max.into(),
            u0: stats.u0.into(),
            ud: stats.ud.into(),
            uncertainty: uncertainty.to_string(),
        },
        points: rows(surface),
    }
}

/// The CSV text of the rows.
pub fn csv_text(rows: &[PointRow]) -> String {
    let mut s = String::with_capacity(64 * (rows.len() + 1));
    s.push_str(CSV_HEADER);
    s.push('\n');
    for r in rows {
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{}\n",
            r.index,
            r.i,
            r.j,
            r.position.0,
            r.position.1,
            r.position.2,
            r.illuminance_lx,
            r.standard_error_lx
        ));
    }
    s
}

/// Writes the CSV as the planned output `path`.
pub fn write_csv_to(plan: &mut OutputPlan, path: &Path, rows: &[PointRow]) -> Result<()> {
    plan.write_bytes(path, csv_text(rows).as_bytes())
}

/// Writes the RON table as the planned output `path`.
pub fn write_ron_to(plan: &mut OutputPlan, path: &Path, table: &SurfaceTable) -> Result<()> {
    luxest_io::fsio::write_ron_to(plan, path, table)
}

/// Reads a RON table.
pub fn read_ron(path: &Path) -> Result<SurfaceTable> {
    luxest_io::fsio::read_ron(path)
}

/// Reads a CSV table written by [`write_csv_to`].
pub fn read_csv(path: &Path) -> Result<Vec<PointRow>> {
    let bytes = luxest_io::fsio::read_bytes(path)?;
    let text = std::str::from_utf8(&bytes)
        .map_err(|e| Error::input(path, format!("not UTF-8 text: {e}")))?;
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim() == CSV_HEADER => {}
        _ => {
            return Err(Error::at(
                path,
                "line 1",
                format!("expected the header {CSV_HEADER}"),
            ))
        }
    }
    let mut out = Vec::new();
    for (n, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let place = || format!("line {}", n + 1);
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != 8 {
            return Err(Error::at(
                path,
                place(),
                format!("{} fields, expected 8", f.len()),
            ));
        }
        let int = |s: &str| {
            s.parse::<usize>()
                .map_err(|_| Error::at(path, place(), format!("not a point index: {s:?}")))
        };
        let real = |s: &str| {
            s.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| Error::at(path, place(), format!("not a finite number: {s:?}")))
        };
        out.push(PointRow {
            index: int(f[0])?,
            i: int(f[1])?,
            j: int(f[2])?,
            position: (real(f[3])?, real(f[4])?, real(f[5])?),
            illuminance_lx: real(f[6])?,
            standard_error_lx: real(f[7])?,
        });
    }
    Ok(out)
}
