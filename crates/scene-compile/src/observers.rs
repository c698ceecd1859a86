//! Glare observers (`scene::Observer`) compiled into the header's `GlareSetup`: names unique,
//! positions in the world, lines of sight normalised, every luminaire with a luminous area, and
//! each eye in open space.
//!
//! **Open space.** From the eye, 26 rays (the directions to the faces, edges and corners of a
//! cube about it) are traced through the compiled geometry: a ray that hits the back of a
//! surface (its geometric normal, u × v for a quad, along the ray) or leaves the scene counts
//! against the eye. An eye for which more than half of the rays do is inside an object (a
//! solid desk, a thick wall) or outside the room (behind the inward-facing walls), and the
//! scene is refused. A room whose surfaces face away from its interior fails the check too,
//! as it renders wrongly anyway for one-sided materials; windows let a few rays out and pass.

use crate::validate::Check;
use luxest_io::math::Vec3;
use luxest_io::{Error, Result};
use luxest_render::compiled::{CompiledObserver, CompiledScene, GlareSetup, LuminousArea};
use luxest_render::rt::RayTracer;
use luxest_render::scene::{Luminaire, Observer};
use std::path::Path;

/// The glare setup of a scene (`None` without observers). `first_luminaire` is the emitter
/// index of the first luminaire, `openings` their IES signed dimensions (scene order).
pub fn compile(
    path: &Path,
    observers: &[Observer],
    luminaires: &[Luminaire],
    first_luminaire: usize,
    openings: &[[f64; 3]],
) -> Result<Option<GlareSetup>> {
    if observers.is_empty() {
        return Ok(None);
    }
    let c = Check { path };
    let mut out = Vec::with_capacity(observers.len());
    for (i, o) in observers.iter().enumerate() {
        let place = format!("observers[{i}]");
        if o.name.trim().is_empty() {
            return Err(c.fail(&format!("{place}.name"), "must not be empty"));
        }
        if observers[..i].iter().any(|p| p.name == o.name) {
            return Err(c.fail(
                &format!("{place}.name"),
                format!("observer \"{}\" is named twice", o.name),
            ));
        }
        c.position(&format!("{place}.position"), o.position)?;
        if o.views.is_empty() {
            return Err(c.fail(&format!("{place}.views"), "give at least one line of sight"));
        }
        let views = o
            .views
            .iter()
            .enumerate()
            .map(|(k, v)| c.nonzero_vec(&format!("{place}.views[{k}]"), *v))
            .collect::<Result<Vec<Vec3>>>()?;
        if let Some(l) = o.ugr_limit {
            if !(l.is_finite() && l >= 0.0) {
                return Err(c.fail(
                    &format!("{place}.ugr_limit"),
                    format!("{l} is not a finite, non-negative UGR"),
                ));
            }
        }
        out.push(CompiledObserver {
            name: o.name.clone(),
            position: o.position,
            views,
            ugr_limit: o.ugr_limit,
        });
    }
    let mut areas = Vec::with_capacity(openings.len());
    for (i, (l, dims)) in luminaires.iter().zip(openings).enumerate() {
        let opening = luxest_photometry::LuminousOpening::from_ies(dims[0], dims[1], dims[2]);
        if opening.projected_area_m2([0.0, 0.0, -1.0]).is_none()
            && opening.projected_area_m2([1.0, 0.0, 0.0]).is_none()
        {
            return Err(c.fail(
                &format!("luminaires[{i}]"),
                format!(
                    "{} gives no luminous area, which the observers' UGR needs: give the \
                     luminaire opening: Area(length: .., width: ..)",
                    l.file
                ),
            ));
        }
        areas.push(LuminousArea {
            emitter: (first_luminaire + i) as u32,
            ies_dimensions_m: *dims,
        });
    }
    Ok(Some(GlareSetup {
        observers: out,
        openings: areas,
    }))
}

/// The 26 directions from the centre of a cube to its faces, edges and corners (unit).
fn probe_directions() -> Vec<Vec3> {
    let mut v = Vec::with_capacity(26);
    for x in -1i32..=1 {
        for y in -1i32..=1 {
            for z in -1i32..=1 {
                if (x, y, z) != (0, 0, 0) {
                    v.extend(Vec3::new(x as f64, y as f64, z as f64).try_normalize());
                }
            }
        }
    }
    v
}

/// Refuses an observer whose eye is not in open space (see the module docs).
pub fn check_open_space(path: &Path, scene: &CompiledScene) -> Result<()> {
    let Some(glare) = &scene.header.glare else {
        return Ok(());
    };
    let tracer = RayTracer::for_scene(scene, true)?;
    let dirs = probe_directions();
    for o in &glare.observers {
        let bad = dirs
            .iter()
            .filter(
                |&&d| match tracer.intersect(o.position, d, 0.0, f64::INFINITY) {
                    None => true,
                    Some(h) => h.geometric_normal.dot(d) > 0.0,
                },
            )
            .count();
        if 2 * bad > dirs.len() {
            let p = o.position;
            return Err(Error::input(
                path,
                format!(
                    "observer \"{}\": the eye at ({}, {}, {}) is inside an object or outside \
                     the room ({bad} of {} rays from it meet the back of a surface or leave the \
                     scene)",
                    o.name,
                    p.x,
                    p.y,
                    p.z,
                    dirs.len()
                ),
            ));
        }
    }
    Ok(())
}
