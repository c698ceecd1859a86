//! The scene's sensor points as the estimators see them, and their estimates packed into the
//! sensor-results contract ([`luxest_io::sensors::SensorResults`]).

use crate::placement;
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_io::meta::RunInfo;
use luxest_io::sensors::{Part, SensorGrid, SensorResults, SensorSetResult, SensorValue};
use luxest_io::{Error, Result};
use luxest_render::compiled::CompiledScene;
use luxest_render::compiled::SensorSet;
use luxest_render::scene::{IlluminanceKind, SensorPoint};
use luxest_render::world::{Traversal, World};
use std::path::Path;

/// Loads a compiled scene and checks that it has sensors.
pub fn load_world(path: &Path) -> Result<World> {
    let scene = CompiledScene::load(path)?;
    if scene.header.sensors.is_empty() && scene.header.glare.is_none() {
        return Err(Error::input(
            path,
            "scene has no sensors (add Points or Grid sensors or observers to the .ron)",
        ));
    }
    World::load_from(path, scene, Traversal::Robust)
}

/// Every sensor point of the scene, set by set.
pub fn all_sensors(world: &World) -> Vec<SensorPoint> {
    world
        .scene
        .header
        .sensors
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .collect()
}

/// The sensors as evaluated: moved off adjacent surfaces by `delta`, each with its near-field
/// radius (`near_radius` when another surface is that close; see [`placement`]); how many
/// were moved is `moved`, which the stage notes.
pub fn evaluation_points(world: &World, delta: f64, near_radius: f64) -> placement::Placement {
    placement::place(world, &all_sensors(world), delta, near_radius)
}

/// One sensor's estimate (lx): RGB illuminance, its photometric value Y and Y's standard
/// error; the direct and indirect parts when the estimator separates them; the point where it
/// was evaluated when that is not the authored one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    pub rgb: Rgb,
    pub value: f64,
    pub standard_error: f64,
    pub direct: Option<Part>,
    pub indirect: Option<Part>,
    pub evaluated_at: Option<Vec3>,
}

impl From<(Rgb, f64, f64)> for Estimate {
    fn from((rgb, value, standard_error): (Rgb, f64, f64)) -> Self {
        Estimate {
            rgb,
            value,
            standard_error,
            direct: None,
            indirect: None,
            evaluated_at: None,
        }
    }
}

/// Records where each estimate was evaluated (`evaluated[i]`, in [`all_sensors`] order) when
/// the point differs from the authored sensor.
pub fn record_evaluation_points(world: &World, values: &mut [Estimate], evaluated: &[SensorPoint]) {
    for ((v, authored), e) in values.iter_mut().zip(all_sensors(world)).zip(evaluated) {
        if e.position != authored.position {
            v.evaluated_at = Some(e.position);
        }
    }
}

/// Packs per-sensor estimates (in [`all_sensors`] order) into the results contract; a
/// non-finite estimate is an error naming `scene_path`.
pub fn results(
    scene_path: &Path,
    world: &World,
    run: RunInfo,
    singularity: String,
    values: &[Estimate],
) -> Result<SensorResults> {
    let finite = |v: &Estimate| {
        v.value.is_finite()
            && v.standard_error.is_finite()
            && [v.direct, v.indirect]
                .iter()
                .flatten()
                .all(|p| p.value.is_finite() && p.standard_error.is_finite())
    };
    if let Some(i) = values.iter().position(|v| !finite(v)) {
        return Err(Error::input(
            scene_path,
            format!("estimate at sensor {i} is not finite"),
        ));
    }
    let mut values = values.iter();
    let sets = world
        .scene
        .header
        .sensors
        .iter()
        .map(|s| SensorSetResult {
            name: s.name.clone(),
            grid: grid_of(s),
            kind: kind_of(s),
            batches: Vec::new(),
            points: s
                .points
                .iter()
                .zip(values.by_ref())
                .map(|(p, e)| SensorValue {
                    evaluated_at: e.evaluated_at,
                    direct: e.direct,
                    indirect: e.indirect,
                    ..SensorValue::new(p.position, p.normal, e.value, e.standard_error, e.rgb)
                })
                .collect(),
        })
        .collect();
    Ok(SensorResults {
        scene: world.scene.header.name.clone(),
        run,
        unit: "lx".into(),
        singularity,
        sets,
        glare: Vec::new(),
        sky: world.scene.header.emitters.iter().find_map(|e| match e {
            luxest_render::compiled::Emitter::Environment { sky, .. } => sky.clone(),
            _ => None,
        }),
    })
}

/// The grid layout of a compiled sensor set, for the results (reports rebuild grids from it).
fn grid_of(s: &SensorSet) -> Option<SensorGrid> {
    let g = s.calculation_grid.as_ref()?;
    Some(SensorGrid {
        nu: g.nu,
        nv: g.nv,
        origin: g.origin,
        u: g.u,
        v: g.v,
        margin_m: g.margin_m,
    })
}

/// The set's illuminance kind in words when it is not planar (sets hold one kind; a `Points`
/// list mixing kinds is reported as `mixed`).
fn kind_of(s: &SensorSet) -> Option<String> {
    let name = |k: &IlluminanceKind| match k {
        IlluminanceKind::Planar => "planar",
        IlluminanceKind::Cylindrical { .. } => "cylindrical",
        IlluminanceKind::SemiCylindrical { .. } => "semi-cylindrical",
    };
    let first = name(&s.points.first()?.kind);
    let same = s.points.iter().all(|p| name(&p.kind) == first);
    match (same, first) {
        (true, "planar") => None,
        (true, k) => Some(k.to_string()),
        (false, _) => Some("mixed".to_string()),
    }
}

/// Adds the per-batch estimates (`batch_values[b][i]` for sensor i in [`all_sensors`] order)
/// to the results, split by set.
pub fn attach_batches(results: &mut SensorResults, batch_values: &[Vec<f64>]) {
    let mut start = 0;
    for set in &mut results.sets {
        let n = set.points.len();
        set.batches = batch_values
            .iter()
            .map(|b| b[start..start + n].to_vec())
            .collect();
        start += n;
    }
}

/// Refuses sensors other than planar for the estimators that sample or count about the normal
/// (the backward `gather` and the photon-counting `direct`): they cannot measure cylindrical
/// illuminance. The local estimate handles every kind.
pub fn require_planar(scene_path: &Path, world: &World, what: &str) -> Result<()> {
    for set in &world.scene.header.sensors {
        if let Some(k) = kind_of(set) {
            return Err(Error::input(
                scene_path,
                format!(
                    "sensor set \"{}\" measures {k} illuminance, which {what} cannot estimate (use estimate sensors)",
                    set.name
                ),
            ));
        }
    }
    Ok(())
}
