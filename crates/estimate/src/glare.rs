//! The unified glare rating at the scene's observers (`scene::Observer`), as `estimate sensors`
//! writes it into the results' `glare` (`luxest_io::sensors::GlareResult`).
//!
//! Per observer and line of sight: the local estimate evaluates one more sensor point, at the
//! eye facing the line of sight ([`points`]); its indirect part (light reflected at least once)
//! over π is the background luminance L_b of CIE 117, with its standard error from the same
//! batches. Each luminaire is a glare source (`luxest_photometry::ugr`, `SolidAngle::Exact`):
//! its opening summed cell by cell, each cell's luminance its intensity towards the eye over the
//! projected luminous area, with its own solid angle and Guth position index (the observer's up
//! is +y); the solid angle times the share of [`VISIBILITY_SAMPLES`]² points on the opening the
//! eye sees through the scene (shadow rays).

use crate::sensors::Estimate;
use luxest_io::math::Vec3;
use luxest_io::sensors::{GlareResult, GlareSource, Part};
use luxest_io::{Error, Result};
use luxest_photometry::ugr::{ugr, GlareLuminaire, SolidAngle};
use luxest_photometry::{Frame, LuminousOpening, OpeningShape};
use luxest_render::compiled::Emitter;
use luxest_render::luminaire::photometry_from_table;
use luxest_render::scene::SensorPoint;
use luxest_render::world::World;
use std::path::Path;

/// Points per side of the grid on a luminaire's opening that visibility is tested at.
pub const VISIBILITY_SAMPLES: usize = 5;

const UP: [f64; 3] = [0.0, 1.0, 0.0];

/// The sensor points the background needs: per observer and line of sight, planar illuminance
/// at the eye facing the line of sight (observer order, views in order).
pub fn points(world: &World) -> Vec<SensorPoint> {
    let Some(g) = &world.scene.header.glare else {
        return Vec::new();
    };
    g.observers
        .iter()
        .flat_map(|o| o.views.iter().map(|&v| SensorPoint::planar(o.position, v)))
        .collect()
}

/// The share of the opening the eye sees: points of a grid on it (inside the ellipse for a
/// round opening; the centre alone for a solid shape) not hidden by the scene.
fn visible_share(
    world: &World,
    eye: Vec3,
    centre: Vec3,
    frame: &Frame,
    o: &LuminousOpening,
) -> f64 {
    let n = VISIBILITY_SAMPLES;
    let flat = matches!(
        o.shape,
        OpeningShape::Rectangular | OpeningShape::Circular | OpeningShape::Elliptical
    );
    let mut samples = Vec::new();
    if flat {
        let round = o.shape != OpeningShape::Rectangular;
        for i in 0..n {
            for j in 0..n {
                let (s, t) = (
                    (i as f64 + 0.5) / n as f64 - 0.5,
                    (j as f64 + 0.5) / n as f64 - 0.5,
                );
                if round && s * s + t * t > 0.25 {
                    continue;
                }
                let w = frame.to_world([s * o.length_m, t * o.width_m, 0.0]);
                samples.push(centre + Vec3::from(w));
            }
        }
    } else {
        samples.push(centre);
    }
    let seen = samples.iter().filter(|&&p| !world.occluded(eye, p)).count();
    seen as f64 / samples.len() as f64
}

/// The glare results from the estimates at [`points`] (same order); errors name `scene_path`.
pub fn results(scene_path: &Path, world: &World, at_eye: &[Estimate]) -> Result<Vec<GlareResult>> {
    let header = &world.scene.header;
    let Some(g) = &header.glare else {
        return Ok(Vec::new());
    };
    let tables = header
        .photometries
        .iter()
        .map(photometry_from_table)
        .collect::<std::result::Result<Vec<_>, String>>()
        .map_err(|m| Error::input(scene_path, m))?;
    let mut out = Vec::new();
    let mut values = at_eye.iter();
    for o in &g.observers {
        for &view in &o.views {
            let e = values
                .next()
                .ok_or_else(|| Error::input(scene_path, "fewer estimates than observer views"))?;
            let Some(indirect) = e.indirect else {
                return Err(Error::input(
                    scene_path,
                    "the estimator gives no indirect part, which the background luminance needs",
                ));
            };
            let lb = Part {
                value: indirect.value / std::f64::consts::PI,
                standard_error: indirect.standard_error / std::f64::consts::PI,
            };
            let mut sources = Vec::new();
            let mut terms = Vec::new();
            for area in &g.openings {
                let Some(Emitter::Luminaire {
                    name,
                    position,
                    frame,
                    photometry,
                    multiplier,
                    ..
                }) = header.emitters.get(area.emitter as usize)
                else {
                    return Err(Error::input(
                        scene_path,
                        format!(
                            "glare opening of emitter {} is not a luminaire",
                            area.emitter
                        ),
                    ));
                };
                let d = area.ies_dimensions_m;
                let opening = LuminousOpening::from_ies(d[0], d[1], d[2]);
                let frame = Frame { m: *frame };
                let lum = GlareLuminaire {
                    photometry: &tables[*photometry as usize],
                    opening,
                    frame: &frame,
                    multiplier: *multiplier,
                    centre: (*position).into(),
                };
                let visible = visible_share(world, o.position, *position, &frame, &opening);
                let term = lum
                    .term(
                        o.position.into(),
                        view.into(),
                        UP,
                        visible,
                        SolidAngle::Exact,
                    )
                    .map_err(|m| Error::input(scene_path, format!("luminaire \"{name}\": {m}")))?;
                if let Some(t) = term {
                    sources.push(GlareSource {
                        luminaire: name.clone(),
                        luminance: t.luminance,
                        solid_angle_sr: t.solid_angle_sr,
                        position_index: t.position_index,
                    });
                    terms.push(t);
                }
            }
            let u = ugr(lb.value, lb.standard_error, &terms).map_err(|m| {
                Error::input(
                    scene_path,
                    format!(
                        "observer \"{}\" looking along ({}, {}, {}): {m}",
                        o.name, view.x, view.y, view.z
                    ),
                )
            })?;
            out.push(GlareResult {
                observer: o.name.clone(),
                position: o.position,
                view,
                ugr: u.value,
                standard_error: u.standard_error,
                background_luminance: lb,
                limit: o.ugr_limit,
                sources,
                note: u.note,
            });
        }
    }
    Ok(out)
}
