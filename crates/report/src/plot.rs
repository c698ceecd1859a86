//! The isolux plot of a surface as PNG bytes, ready for the output plan: the field, contours,
//! legend in lx, outline and figures are `luxest_photometry::isolux`'s; this module adds the
//! luminaires' marks (their positions projected onto the surface) and encodes the PNG.

use crate::surface::Surface;
use luxest_io::{Error, Result};
use luxest_photometry::{render_isolux, GridStats, IsoluxOptions};
use std::path::Path;

/// Renders the plot of `surface` with `stats` in its figures line, the luminaires at world
/// `positions` marked where they project inside the rectangle.
pub fn isolux_png(
    surface: &Surface,
    stats: &GridStats,
    title: &str,
    luminaire_positions: &[[f64; 3]],
    file: &Path,
) -> Result<Vec<u8>> {
    let place = format!("surface \"{}\"", surface.name);
    let grid = surface
        .grid
        .calc_grid()
        .map_err(|e| Error::at(file, &place, e))?;
    let (lu, lv) = surface.grid.sides_m();
    let luminaires_st = luminaire_positions
        .iter()
        .map(|&p| surface.grid.local_st(p))
        .filter(|&(s, t)| (0.0..=lu).contains(&s) && (0.0..=lv).contains(&t))
        .collect();
    let opts = IsoluxOptions {
        levels_lx: None,
        plot_width_px: 720,
        title: title.to_string(),
        luminaires_st,
    };
    let img = render_isolux(&grid, &surface.values, Some(stats), &opts)
        .map_err(|e| Error::at(file, &place, e.0))?;
    img.encode_png()
        .map_err(|e| Error::at(file, &place, format!("cannot encode the isolux PNG: {e}")))
}
