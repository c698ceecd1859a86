//! The report's input: the sensor results of `estimate sensors`. Every sensor set that carries
//! a grid layout (a calculation surface, or a `Grid` sensor) is a surface of the report; its
//! point k = j · nu + i is the centre of cell (i, j). With `estimate sensors --batch-values`
//! the sets also carry every independent batch's estimate per point, from which the figures'
//! uncertainties are propagated (jackknife, correlations included).
//!
//! Refused with one line naming the file: results without any grid, a set whose point count
//! differs from its grid's, positions that are not the grid's, batch lists of the wrong size,
//! and non-finite numbers.

use crate::surface::{GridGeometry, Surface};
use luxest_io::math::Vec3;
use luxest_io::sensors::SensorResults;
use luxest_io::{Error, Result};
use std::path::Path;

/// The surfaces (sets with a grid) of `results`, read from `path`, in the results' order.
pub fn surfaces(path: &Path, results: &SensorResults) -> Result<Vec<Surface>> {
    let a = |v: Vec3| [v.x, v.y, v.z];
    let mut out = Vec::new();
    for set in &results.sets {
        let Some(g) = &set.grid else {
            continue; // a plain list of points, not a grid
        };
        let surface = Surface {
            name: set.name.clone(),
            kind: set.kind.clone().unwrap_or_else(|| "planar".to_string()),
            grid: GridGeometry {
                origin: a(g.origin),
                u: a(g.u),
                v: a(g.v),
                margin_m: g.margin_m,
                nu: g.nu as usize,
                nv: g.nv as usize,
            },
            positions: set.points.iter().map(|p| a(p.position)).collect(),
            values: set.points.iter().map(|p| p.value).collect(),
            std_errors: set.points.iter().map(|p| p.standard_error).collect(),
            batches: (!set.batches.is_empty()).then(|| set.batches.clone()),
        };
        surface.validate(path)?;
        check_positions(path, &surface)?;
        out.push(surface);
    }
    if out.is_empty() {
        return Err(Error::input(
            path,
            format!(
                "no calculation grid: none of the sensor sets ({}) carries a grid layout",
                results
                    .sets
                    .iter()
                    .map(|s| format!("\"{}\"", s.name))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
    }
    Ok(out)
}

/// The points must lie where the grid puts them (to 1 mm): results whose positions disagree
/// with their own layout are not a grid the report can draw.
fn check_positions(path: &Path, s: &Surface) -> Result<()> {
    let g = s
        .grid
        .calc_grid()
        .map_err(|e| Error::at(path, format!("set \"{}\"", s.name), e))?;
    for (k, (p, q)) in s.positions.iter().zip(g.points()).enumerate() {
        let d = (0..3).map(|a| (p[a] - q[a]).abs()).fold(0.0, f64::max);
        if d > 1e-3 {
            return Err(Error::at(
                path,
                format!("set \"{}\", point {k}", s.name),
                format!(
                    "position ({}, {}, {}) is not the grid's ({}, {}, {})",
                    p[0], p[1], p[2], q[0], q[1], q[2]
                ),
            ));
        }
    }
    Ok(())
}
