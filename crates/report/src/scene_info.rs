//! The luminaire schedule and the calculation surfaces' requirements of a scene, read from its
//! compiled header as `scene-compile --info` prints it (`build/<scene>/scene.info.ron`).
//!
//! The header's type lives in `luxest-render`, which a report stage must not depend on (no
//! stage reaches the renderer's crate; a report needs no Embree). So this module reads the same
//! RON through a *partial view*: structs of the same names holding only the fields a report
//! needs; serde skips the others. `tests/lighting.rs` runs `scene-compile --info` on a real
//! scene and this reader on its output, so a change of the header that breaks the view fails a
//! test rather than a report.

use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_io::requirements::Requirements;
use luxest_io::{Error, Result};
use serde::Deserialize;
use std::path::Path;

/// The part of `SceneHeader` a report reads.
#[derive(Clone, Debug, Deserialize)]
pub struct SceneHeader {
    pub name: String,
    pub emitters: Vec<Emitter>,
    #[serde(default)]
    pub photometries: Vec<PhotometricTable>,
    #[serde(default)]
    pub sensors: Vec<SensorSet>,
}

/// The part of each sensor set a report reads: a calculation surface's requirements.
#[derive(Clone, Debug, Deserialize)]
pub struct SensorSet {
    pub name: String,
    #[serde(default)]
    pub requirements: Option<Requirements>,
}

/// The part of each emitter a report reads.
#[derive(Clone, Debug, Deserialize)]
pub enum Emitter {
    Point {
        name: String,
        flux_rgb: Rgb,
    },
    Area {
        name: String,
        flux_rgb: Rgb,
    },
    /// The environment; its flux is the light through the scene's bounding disk.
    Environment {
        name: String,
        flux_rgb: Rgb,
    },
    Luminaire {
        name: String,
        position: Vec3,
        photometry: u32,
        /// The scene's multiplier × its maintenance factor.
        multiplier: f64,
        #[serde(default = "one")]
        maintenance_factor: f64,
        flux_rgb: Rgb,
    },
}

fn one() -> f64 {
    1.0
}

/// The part of each photometric table a report reads.
#[derive(Clone, Debug, Deserialize)]
pub struct PhotometricTable {
    /// The file as the scene named it.
    pub source: String,
    /// ∫ I dΩ of the table, lm (one luminaire, multiplier 1).
    pub table_flux_lm: f64,
    pub file_flux_lm: Option<f64>,
    pub input_watts: Option<f64>,
}

/// Luminaires of one kind (same file, multiplier and maintenance factor), as a report lists
/// them.
#[derive(Clone, Debug, PartialEq)]
pub struct LuminaireGroup {
    pub file: String,
    /// The scene's multiplier (dimming, lamps), the maintenance factor excluded.
    pub multiplier: f64,
    pub maintenance_factor: f64,
    pub count: usize,
    /// The flux the file states for one luminaire (lamp lumens, or EULUMDAT's luminaire flux).
    pub file_flux_lm: Option<f64>,
    /// The table's flux, ∫ I dΩ, lm (multiplier 1, new).
    pub table_flux_lm: f64,
    /// Flux of one luminaire as computed: multiplier × maintenance factor × table flux, lm.
    pub flux_lm: f64,
    /// Input power of one luminaire as its file states it, W.
    pub input_watts: Option<f64>,
    pub names: Vec<String>,
}

/// What `(table)` in the schedule's lumens means.
pub const TABLE_LUMENS_NOTE: &str = "(table): the file states no lumens (absolute photometry); \
     the integral of its intensity table, ∫ I dΩ, is given.";

impl LuminaireGroup {
    /// The schedule's lumens: what the file states, or, for a file that states none (IES
    /// absolute photometry, lamp lumens −1), its table's integral marked `(table)` (see
    /// [`TABLE_LUMENS_NOTE`]).
    pub fn lumens_text(&self) -> String {
        match self.file_flux_lm {
            Some(f) => format!("{f:.0}"),
            None => format!("{:.0} (table)", self.table_flux_lm),
        }
    }
}

/// A placed luminaire (for the plots' marks).
#[derive(Clone, Debug, PartialEq)]
pub struct LuminairePlace {
    pub name: String,
    pub position: [f64; 3],
}

/// What the report says about a scene's light sources.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct LightSources {
    pub groups: Vec<LuminaireGroup>,
    pub places: Vec<LuminairePlace>,
    /// Emitters that are not goniometric luminaires: (name, flux lm).
    pub other: Vec<(String, f64)>,
}

impl LightSources {
    pub fn total_flux_lm(&self) -> f64 {
        self.groups
            .iter()
            .map(|g| g.flux_lm * g.count as f64)
            .sum::<f64>()
            + self.other.iter().map(|o| o.1).sum::<f64>()
    }
    /// Total input power when every luminaire's file states it, W.
    pub fn total_input_watts(&self) -> Option<f64> {
        self.groups
            .iter()
            .map(|g| g.input_watts.map(|w| w * g.count as f64))
            .sum()
    }
}

/// The line `scene-compile --info` ends the header with, a RON comment: `// content hash H`.
pub const CONTENT_HASH_LINE: &str = "// content hash ";

/// Reads the header printed by `scene-compile --info` and the content hash its last line
/// states (`None` where the file has no such line).
pub fn read(path: &Path) -> Result<(SceneHeader, Option<String>)> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse(path, &text)
}

/// [`read`] of the file's `text`; `path` names it in errors.
pub fn parse(path: &Path, text: &str) -> Result<(SceneHeader, Option<String>)> {
    let header = luxest_io::fsio::parse_ron(path, text)?;
    let hash = text
        .lines()
        .rev()
        .find_map(|l| l.trim().strip_prefix(CONTENT_HASH_LINE.trim_end()))
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty());
    Ok((header, hash))
}

/// Refuses sensor results (`results`, read from `results_path`) that are not of the scene
/// the header at `path` describes: another scene's name, or the same name with another content
/// hash (another compile: the office with one luminaire fewer reported 4 luminaires beside
/// results of 5). A header without its content-hash line cannot be matched and is refused.
pub fn check_matches(
    path: &Path,
    header: &SceneHeader,
    hash: Option<&str>,
    results_path: &Path,
    results: &luxest_io::sensors::SensorResults,
) -> Result<()> {
    if header.name != results.scene {
        return Err(Error::input(
            path,
            format!(
                "describes scene \"{}\" but {} holds results for scene \"{}\"",
                header.name,
                results_path.display(),
                results.scene
            ),
        ));
    }
    let Some(hash) = hash else {
        return Err(Error::input(
            path,
            format!(
                "has no \"{}H\" line, so it cannot be matched to the results' scene hash; \
                 write it with scene-compile --info SCENE.lxs",
                CONTENT_HASH_LINE
            ),
        ));
    };
    if hash != results.run.scene_hash {
        return Err(Error::input(
            path,
            format!(
                "describes the compile of \"{}\" with content hash {hash}, but {} holds \
                 results of content hash {}: another compile of the scene; re-run the \
                 estimate or scene-compile --info on the scene it used",
                header.name,
                results_path.display(),
                results.run.scene_hash
            ),
        ));
    }
    Ok(())
}

/// The scene's luminaires grouped by file, multiplier and maintenance factor; `path` names the
/// file in errors.
pub fn light_sources(path: &Path, h: &SceneHeader) -> Result<LightSources> {
    group(path, h)
}

fn group(path: &Path, h: &SceneHeader) -> Result<LightSources> {
    let mut out = LightSources::default();
    for e in &h.emitters {
        match e {
            Emitter::Point { name, flux_rgb }
            | Emitter::Area { name, flux_rgb }
            | Emitter::Environment { name, flux_rgb } => {
                out.other.push((name.clone(), flux_rgb.luminance()))
            }
            Emitter::Luminaire {
                name,
                position,
                photometry,
                multiplier,
                maintenance_factor,
                ..
            } => {
                if !(maintenance_factor.is_finite()
                    && *maintenance_factor > 0.0
                    && *maintenance_factor <= 1.0)
                {
                    return Err(Error::at(
                        path,
                        format!("emitter \"{name}\""),
                        format!("maintenance factor {maintenance_factor} is not in (0, 1]"),
                    ));
                }
                let scene_multiplier = multiplier / maintenance_factor;
                let t = h.photometries.get(*photometry as usize).ok_or_else(|| {
                    Error::at(
                        path,
                        format!("emitter \"{name}\""),
                        format!(
                            "photometry {photometry} does not exist ({} tables)",
                            h.photometries.len()
                        ),
                    )
                })?;
                out.places.push(LuminairePlace {
                    name: name.clone(),
                    position: [position.x, position.y, position.z],
                });
                match out.groups.iter_mut().find(|g| {
                    g.file == t.source
                        && g.multiplier == scene_multiplier
                        && g.maintenance_factor == *maintenance_factor
                }) {
                    Some(g) => {
                        g.count += 1;
                        g.names.push(name.clone());
                    }
                    None => out.groups.push(LuminaireGroup {
                        file: t.source.clone(),
                        multiplier: scene_multiplier,
                        maintenance_factor: *maintenance_factor,
                        count: 1,
                        file_flux_lm: t.file_flux_lm,
                        table_flux_lm: t.table_flux_lm,
                        flux_lm: multiplier * t.table_flux_lm,
                        input_watts: t.input_watts,
                        names: vec![name.clone()],
                    }),
                }
            }
        }
    }
    Ok(out)
}

/// The requirements of the calculation surface named `surface`, if the header gives any.
pub fn requirements<'a>(h: &'a SceneHeader, surface: &str) -> Option<&'a Requirements> {
    h.sensors
        .iter()
        .find(|s| s.name == surface)
        .and_then(|s| s.requirements.as_ref())
}
