//! Luminaires from photometric files: validation, loading (IES LM-63 or EULUMDAT through
//! `luxest-photometry`), the flux check, and the compiled emitters and intensity tables.
//!
//! The compiled scene is self-contained: each distinct file's expanded C-γ table is stored once
//! in the header (`SceneHeader::photometries`, part of the content hash) and the luminaires
//! reference it by index. A luminaire emits `multiplier ×` the integral of its table — what the
//! intensities it radiates add up to, so the estimators conserve exactly that; the file's stated
//! flux is only checked against it (a warning beyond 1 %).

use crate::validate::Check;
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_io::{Error, Result};
use luxest_photometry::{LuminousOpening, Photometry, PhotometryError};
use luxest_render::compiled::{Emitter, PhotometricTable};
use luxest_render::luminaire::{frame_in_world, table_from_photometry};
use luxest_render::scene::{Luminaire, Opening};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Relative difference between the file's stated flux and the table integral beyond which
/// compiling warns.
pub const FLUX_WARN_REL: f64 = 0.01;

/// Largest number of point sources an area opening is divided into.
pub const MAX_OPENING_CELLS: u32 = 4096;

/// Default largest cell side of an area opening's subdivision, m.
pub const OPENING_CELL_M: f64 = 0.05;

/// The point sources of an area opening (see `scene::Opening`): cell centres of the rectangle
/// of `length` along the luminaire's local x (C0) and `width` along its local y (C90), centred
/// on `position`, in world space through `frame` (world = frame · local).
pub fn opening_points(
    position: Vec3,
    frame: &[[f64; 3]; 3],
    length: f64,
    width: f64,
    (nu, nv): (u32, u32),
) -> Vec<Vec3> {
    let x = Vec3::new(frame[0][0], frame[1][0], frame[2][0]);
    let y = Vec3::new(frame[0][1], frame[1][1], frame[2][1]);
    let mut points = Vec::with_capacity((nu * nv) as usize);
    for j in 0..nv {
        for i in 0..nu {
            let s = ((i as f64 + 0.5) / nu as f64 - 0.5) * length;
            let t = ((j as f64 + 0.5) / nv as f64 - 0.5) * width;
            points.push(position + x * s + y * t);
        }
    }
    points
}

/// Checks what does not need the file: finite placement, a usable aim, the multiplier, the
/// tint and the file's extension.
pub(crate) fn check(c: &Check, place: &str, l: &Luminaire) -> Result<()> {
    c.position(&format!("{place}.position"), l.position)?;
    c.nonzero_vec(&format!("{place}.aim"), l.aim)?;
    c.finite(&format!("{place}.tilt_deg"), l.tilt_deg)?;
    c.finite(&format!("{place}.rotation_deg"), l.rotation_deg)?;
    c.positive(&format!("{place}.multiplier"), l.multiplier, "multiplier")?;
    c.positive(
        &format!("{place}.maintenance_factor"),
        l.maintenance_factor,
        "maintenance factor",
    )?;
    if l.maintenance_factor > 1.0 {
        return Err(c.fail(
            &format!("{place}.maintenance_factor"),
            format!(
                "{} is above 1: a maintenance factor is the share of the new installation's light that remains",
                l.maintenance_factor
            ),
        ));
    }
    c.emission_rgb(&format!("{place}.color"), l.color)?;
    let ext = Path::new(&l.file)
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if let Opening::Area {
        length,
        width,
        cells,
    } = &l.opening
    {
        for (what, v) in [("length", length), ("width", width)] {
            if let Some(v) = v {
                c.positive(&format!("{place}.opening.{what}"), *v, "opening size")?;
            }
        }
        if let Some((a, b)) = cells {
            if *a == 0 || *b == 0 || (*a as u64) * (*b as u64) > MAX_OPENING_CELLS as u64 {
                return Err(c.fail(
                    &format!("{place}.opening.cells"),
                    format!("({a}, {b}): at least 1 x 1 and at most {MAX_OPENING_CELLS} cells"),
                ));
            }
        }
    }
    if !matches!(ext.as_deref(), Some("ies") | Some("ldt")) {
        return Err(c.fail(
            &format!("{place}.file"),
            format!(
                "\"{}\": expected a photometric file ending in .ies (IES LM-63) or .ldt (EULUMDAT)",
                l.file
            ),
        ));
    }
    Ok(())
}

/// A photometric file's error as the stages print it: `file: line N: problem`.
fn photometry_error(e: PhotometryError) -> Error {
    match e.line {
        Some(line) => Error::at(&e.file, format!("line {line}"), e.message),
        None => Error::input(&e.file, e.message),
    }
}

/// Loads and checks one photometric file: finite, non-negative table with positive flux.
/// Returns the photometry and, when the file states a flux that the table integral misses by
/// more than [`FLUX_WARN_REL`], a warning.
pub fn load_photometry(file: &Path) -> Result<(Photometry, Option<String>)> {
    let p = luxest_photometry::load(file).map_err(photometry_error)?;
    let (c, g) = (p.c_angles_deg(), p.gamma_angles_deg());
    for (i, c_deg) in c.iter().enumerate() {
        for (j, g_deg) in g.iter().enumerate() {
            let v = p.table_cd(i, j);
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::input(
                    file,
                    format!("intensity {v} cd at C = {c_deg}°, γ = {g_deg}° is not a finite non-negative number (overflow?)"),
                ));
            }
        }
    }
    let check = p.flux_check();
    if !(check.table_lm.is_finite() && check.table_lm > 0.0) {
        return Err(Error::input(
            file,
            format!(
                "the intensity table emits no light (its integral is {} lm)",
                check.table_lm
            ),
        ));
    }
    // The file's own flux: EULUMDAT's lamp flux × LORL (`declared_lm`); an IES file declares
    // only lamp lumens, which differ from the luminaire's flux by its light output ratio, so
    // absolute IES files (−1 lumens per lamp) and relative ones are not compared.
    let warning = match (check.declared_lm, check.rel_diff) {
        (Some(d), Some(r)) if r.abs() > FLUX_WARN_REL => Some(format!(
            "{}: the file states {d:.6} lm but its intensity table integrates to {:.6} lm ({:+.2} %); the luminaire emits the table integral (× multiplier)",
            file.display(),
            check.table_lm,
            100.0 * r
        )),
        _ => None,
    };
    Ok((p, warning))
}

/// The compiled luminaires of a scene: emitters (in scene order) and the distinct tables.
pub struct CompiledLuminaires {
    pub emitters: Vec<Emitter>,
    pub tables: Vec<PhotometricTable>,
    pub warnings: Vec<String>,
    /// Per luminaire (scene order), its luminous opening's IES signed dimensions (width,
    /// length, height), m: the `Opening::Area` rectangle, else the file's (for glare).
    pub openings: Vec<[f64; 3]>,
}

/// Loads every luminaire's file (each distinct file once) and builds its emitter.
pub fn compile(scene_path: &Path, luminaires: &[Luminaire]) -> Result<CompiledLuminaires> {
    let mut out = CompiledLuminaires {
        emitters: Vec::new(),
        tables: Vec::new(),
        warnings: Vec::new(),
        openings: Vec::new(),
    };
    // Per distinct file: its table's index and its luminous opening (length, width), m.
    let mut by_file: BTreeMap<PathBuf, (u32, LuminousOpening)> = BTreeMap::new();
    let dir = scene_path.parent().unwrap_or(Path::new("."));
    for (i, l) in luminaires.iter().enumerate() {
        let place = format!("luminaires[{i}]");
        let full = dir.join(&l.file);
        if !full.is_file() {
            let problem = match luxest_io::fsio::non_file_kind(&full) {
                Some(kind) => format!(
                    "{} is {kind}, not a regular file, as a photometric file must be",
                    full.display()
                ),
                None => format!("photometric file {} not found", full.display()),
            };
            return Err(Error::at(scene_path, format!("{place}.file"), problem));
        }
        let (index, file_opening) = match by_file.get(&full) {
            Some(&k) => k,
            None => {
                let (p, warning) = load_photometry(&full)?;
                out.warnings.extend(warning);
                let k = out.tables.len() as u32;
                out.tables.push(table_from_photometry(&l.file, &p));
                let entry = (k, p.opening);
                by_file.insert(full.clone(), entry);
                entry
            }
        };
        let frame = frame_in_world(l.aim, l.tilt_deg, l.rotation_deg)
            .map_err(|m| Error::at(scene_path, &place, m))?;
        let color_rgb = l.color.with_luminance(1.0).expect("validated");
        // The maintenance factor scales the intensities like the multiplier.
        let multiplier = l.multiplier * l.maintenance_factor;
        let flux_lm = multiplier * out.tables[index as usize].table_flux_lm;
        let flux_rgb: Rgb = color_rgb * flux_lm;
        if !(flux_rgb.is_finite() && flux_lm > 0.0) {
            return Err(Error::at(
                scene_path,
                format!("{place}.multiplier"),
                format!("the luminaire's flux {flux_lm} lm is not finite and positive"),
            ));
        }
        // The bound every other emitter has (a 1e300 cd table gave Eavg inf ± NaN).
        let peak_cd = multiplier
            * out.tables[index as usize]
                .cd
                .iter()
                .fold(0.0f64, |m, &v| m.max(v));
        if flux_lm > crate::validate::MAX_EMISSION || peak_cd > crate::validate::MAX_EMISSION {
            return Err(Error::at(
                scene_path,
                format!("{place}.multiplier"),
                format!(
                    "the luminaire's peak intensity {} cd or flux {} lm (its table × \
                     multiplier) exceeds {}, beyond which the estimators' arithmetic and f32 \
                     images overflow",
                    luxest_io::num::show(peak_cd),
                    luxest_io::num::show(flux_lm),
                    luxest_io::num::show(crate::validate::MAX_EMISSION)
                ),
            ));
        }
        let (file_length, file_width) = (file_opening.length_m, file_opening.width_m);
        out.openings.push(match &l.opening {
            Opening::Point => file_opening.ies_signed(),
            Opening::Area { length, width, .. } => [
                width.unwrap_or(file_width),
                length.unwrap_or(file_length),
                0.0,
            ],
        });
        let opening_points = match &l.opening {
            Opening::Point => Vec::new(),
            Opening::Area {
                length,
                width,
                cells,
            } => {
                let length = length.unwrap_or(file_length);
                let width = width.unwrap_or(file_width);
                if !(length > 0.0 && width > 0.0) {
                    return Err(Error::at(
                        scene_path,
                        format!("{place}.opening"),
                        format!(
                            "{} gives no luminous rectangle (length {length} m, width {width} m): give Area(length: .., width: ..)",
                            l.file
                        ),
                    ));
                }
                let per_side = |side: f64| (side / OPENING_CELL_M).ceil().clamp(1.0, 64.0) as u32;
                let cells = cells.unwrap_or((per_side(length), per_side(width)));
                opening_points(l.position, &frame, length, width, cells)
            }
        };
        out.emitters.push(Emitter::Luminaire {
            name: l.name.clone().unwrap_or_else(|| place.clone()),
            position: l.position,
            frame,
            photometry: index,
            multiplier,
            maintenance_factor: l.maintenance_factor,
            color_rgb,
            flux_rgb,
            opening_points,
        });
    }
    Ok(out)
}
