//! Calculation surfaces (work planes and other grids, EN 12464-1): validation and expansion
//! into compiled sensor sets whose points remember their grid cell.
//!
//! The layout is `luxest_photometry::CalcGrid`'s: the rectangle moved by `offset` along its
//! normal u × v, a `margin` excluded on every side, spacing p = 0.2 · 5^(log10 d) m (d the
//! longer side of the calculation area) unless given, ⌈L/p⌉ points per side at the cell
//! centres. Point k = j · nu + i is cell (i, j), i along u; the set's `grid` is (nu, nv) and its
//! `calculation_grid` the layout, so a report can rebuild the grid from the sensor results.

use crate::validate::Check;
use luxest_io::math::Vec3;
use luxest_io::{Error, Result};
use luxest_photometry::{CalcGrid, GridSpec, Spacing};
use luxest_render::compiled::{GridLayout, SensorSet};
use luxest_render::scene::{
    CalculationSurface, GridSpacing, IlluminanceKind, SensorPoint, SurfaceArea,
};
use std::path::Path;

/// Largest number of points on one calculation surface.
pub const MAX_POINTS: usize = 1 << 22;

/// The rectangle (origin, u, v) of a surface's area.
fn rectangle(area: &SurfaceArea) -> (Vec3, Vec3, Vec3) {
    match area {
        SurfaceArea::Rectangle { origin, u, v } => (*origin, *u, *v),
        SurfaceArea::Floor { min, max, y } => (
            Vec3::new(min.0, *y, max.1),
            Vec3::new(max.0 - min.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, -(max.1 - min.1)),
        ),
    }
}

/// The sensor kind with unit axis and a unit facing direction perpendicular to the axis.
pub(crate) fn normalised_kind(
    c: &Check,
    place: &str,
    kind: &IlluminanceKind,
) -> Result<IlluminanceKind> {
    Ok(match kind {
        IlluminanceKind::Planar => IlluminanceKind::Planar,
        IlluminanceKind::Cylindrical { axis } => IlluminanceKind::Cylindrical {
            axis: c.nonzero_vec(&format!("{place}.axis"), *axis)?,
        },
        IlluminanceKind::SemiCylindrical { axis, facing } => {
            let a = c.nonzero_vec(&format!("{place}.axis"), *axis)?;
            let f = c.nonzero_vec(&format!("{place}.facing"), *facing)?;
            let f = (f - a * a.dot(f))
                .try_normalize()
                .filter(|h| h.dot(f) > 1e-6)
                .ok_or_else(|| c.fail(&format!("{place}.facing"), "is parallel to the axis"))?;
            IlluminanceKind::SemiCylindrical { axis: a, facing: f }
        }
    })
}

fn spec(s: &CalculationSurface) -> GridSpec {
    let (o, u, v) = rectangle(&s.area);
    GridSpec {
        origin: o.into(),
        edge_u: u.into(),
        edge_v: v.into(),
        offset_m: s.offset,
        margin_m: s.margin,
        spacing: match s.spacing {
            GridSpacing::Standard => Spacing::Standard,
            GridSpacing::Metres(p) => Spacing::Given(p),
            GridSpacing::Counts(a, b) => Spacing::Counts(a as usize, b as usize),
        },
    }
}

/// Validates a surface (finite numbers, perpendicular non-zero edges, a margin that leaves an
/// area, a positive spacing, a usable sensor kind) and lays out its grid.
pub(crate) fn check(c: &Check, place: &str, s: &CalculationSurface) -> Result<CalcGrid> {
    if let SurfaceArea::Floor { min, max, .. } = &s.area {
        // Corners the wrong way round turned the plane over: its points went below the floor,
        // facing down, and read 0 lx without a word.
        for (axis, lo, hi) in [("x", min.0, max.0), ("z", min.1, max.1)] {
            if lo >= hi {
                return Err(c.fail(
                    &format!("{place}.area"),
                    format!(
                        "Floor min.{axis} {} is not below max.{axis} {}",
                        luxest_io::num::show(lo),
                        luxest_io::num::show(hi)
                    ),
                ));
            }
        }
    }
    let (o, u, v) = rectangle(&s.area);
    c.position(&format!("{place}.area"), o)?;
    c.nonzero_vec(&format!("{place}.area.u"), u)?;
    c.nonzero_vec(&format!("{place}.area.v"), v)?;
    c.finite(&format!("{place}.offset"), s.offset)?;
    c.finite(&format!("{place}.margin"), s.margin)?;
    if let GridSpacing::Metres(p) = s.spacing {
        c.positive(&format!("{place}.spacing"), p, "spacing")?;
    }
    normalised_kind(c, &format!("{place}.kind"), &s.kind)?;
    if let Some((field, msg)) = s.requirements.as_ref().and_then(|r| r.invalid()) {
        return Err(c.fail(&format!("{place}.requirements.{field}"), msg));
    }
    let grid = CalcGrid::new(spec(s)).map_err(|e| c.fail(place, e.0))?;
    if grid.len() > MAX_POINTS {
        return Err(c.fail(
            &format!("{place}.spacing"),
            format!("{} x {} points exceed {MAX_POINTS}", grid.nu, grid.nv),
        ));
    }
    Ok(grid)
}

/// The compiled sensor set of a (validated) calculation surface.
pub fn expand(path: &Path, place: &str, s: &CalculationSurface) -> Result<SensorSet> {
    let c = Check { path };
    let grid = check(&c, place, s)?;
    let kind = normalised_kind(&c, &format!("{place}.kind"), &s.kind)?;
    let normal = Vec3::from(grid.normal);
    // Cylindrical sensors keep their axis as the "normal" (what placement and reports see).
    let point_normal = match kind {
        IlluminanceKind::Planar => normal,
        IlluminanceKind::Cylindrical { axis } | IlluminanceKind::SemiCylindrical { axis, .. } => {
            axis
        }
    };
    let points = grid
        .points()
        .into_iter()
        .map(|p| SensorPoint {
            position: Vec3::from(p),
            normal: point_normal,
            kind,
        })
        .collect::<Vec<_>>();
    if points.iter().any(|p| !p.position.is_finite()) {
        return Err(Error::at(path, place, "grid points are not finite"));
    }
    let sp = &grid.spec;
    Ok(SensorSet {
        name: s.name.clone(),
        grid: Some((grid.nu as u32, grid.nv as u32)),
        points,
        calculation_grid: Some(GridLayout {
            origin: Vec3::from(sp.origin) + normal * sp.offset_m,
            u: Vec3::from(sp.edge_u),
            v: Vec3::from(sp.edge_v),
            margin_m: sp.margin_m,
            nu: grid.nu as u32,
            nv: grid.nv as u32,
        }),
        requirements: s.requirements.clone(),
    })
}
