//! What a run of each `estimate` subcommand will cost, predicted before it starts (the resource
//! rule, docs/architecture.md, *Command-line conventions*).
//!
//! The arguments fix how many light paths, backward samples, camera points and connections a
//! run makes; the scene fixes how long a path is and what a ray costs, which a short
//! calibration measures: light paths (and, for the backward estimators, walks from the sensors)
//! traced on random-number streams of their own, so that the run's results do not change.
//! Every walk is bounded by `--max-depth`, so the work is too; in a closed room of reflectance 1
//! every path reaches it (64 light paths of 100 000 collisions, and before the near field's
//! samples were tied to `--paths`, 20 000 backward walks of 100 000 bounces at every near-field
//! sensor: hours where the user asked for 64 paths). A run predicted to take longer than a
//! minute prints the plan first ([`luxest_io::limits::WorkPlan`]).
//!
//! The prediction counts ray casts: light-path collisions, backward bounces with their
//! next-event rays, camera rays, and connections (one shadow ray each, at most; the image's
//! roulette traces a fraction). Its time is ray casts times the calibration's seconds per ray
//! over the threads the work spreads over; connections, cast as coherent streams, are counted
//! at [`CONNECTION_COST`] of a ray.

use crate::double_local_estimate::{self, ImageConfig, ROUND_PATHS};
use crate::gather;
use crate::image::BATCHES;
use crate::transport::{walk_light_path, LightVertex};
use luxest_io::limits::WorkPlan;
use luxest_io::math::Vec3;
use luxest_render::camera::PinholeCamera;
use luxest_render::sampling::Rng;
use luxest_render::scene::SensorPoint;
use luxest_render::world::World;
use std::time::Instant;

/// Salt of the calibration's random streams (never the run's: seed, streams 1..=batches).
const CALIBRATION_SALT: u64 = 0x00ca_11b2_a7e0;
/// The calibration stops after this many collisions (or bounces) in all ...
const CALIBRATION_COLLISIONS: u64 = 1 << 17;
/// ... or this many paths, or once it has [`CALIBRATION_MIN_PATHS`] paths and has run
/// [`CALIBRATION_SECONDS`]: a few milliseconds for an ordinary scene, one capped path for a
/// closed room of reflectance 1.
const CALIBRATION_PATHS: u64 = 4096;
const CALIBRATION_MIN_PATHS: u64 = 32;
const CALIBRATION_SECONDS: f64 = 0.02;
/// Collision points kept for counting the sensors a collision connects to.
const CALIBRATION_POINTS: usize = 256;

/// Cost of one connection (its kernel, and a shadow ray cast in a stream where roulette and
/// facing keep it), as a fraction of a ray of the calibration: 0.33 measured for the image's
/// connections on the Cornell box 128² (1000 paths, --mis-paths 0), 0.5 for the local estimate
/// at 64 sensors of a closed room (64 paths, --max-depth 1000). Predictions from it came
/// within a factor of 1.5 of the runs' times.
pub const CONNECTION_COST: f64 = 0.4;

/// What the calibration measured.
#[derive(Clone, Debug)]
pub struct Calibration {
    /// Mean collisions of a light path (a path still going at the calibration's own bound,
    /// below --max-depth, is counted as reaching --max-depth: the most it can).
    pub light_path: f64,
    /// Seconds per ray cast (an intersection and its scattering step), on one thread.
    pub seconds_per_ray: f64,
    /// Collision points (position, geometric normal) of the calibration's paths.
    pub points: Vec<(Vec3, Vec3)>,
    /// Seconds the calibration took.
    pub seconds: f64,
}

/// Walks `count` units (`walk(rng, cap) -> (collisions, cut)`, `cut`: still going at `cap`)
/// within the calibration's budget; returns (units walked, mean length counted as above,
/// collisions traced, seconds).
fn pilot(
    max_depth: u32,
    rng: &mut Rng,
    mut walk: impl FnMut(&mut Rng, u32) -> (u64, bool),
) -> (u64, f64, u64, f64) {
    let start = Instant::now();
    let cap = max_depth.min(CALIBRATION_COLLISIONS as u32);
    let (mut units, mut traced, mut counted) = (0u64, 0u64, 0.0f64);
    while units < CALIBRATION_PATHS
        && traced < CALIBRATION_COLLISIONS
        && !(units >= CALIBRATION_MIN_PATHS && start.elapsed().as_secs_f64() >= CALIBRATION_SECONDS)
    {
        let (collisions, cut) = walk(rng, cap);
        units += 1;
        traced += collisions;
        counted += if cut && cap < max_depth {
            max_depth as f64
        } else {
            collisions as f64
        };
    }
    let mean = counted / units.max(1) as f64;
    (units, mean, traced, start.elapsed().as_secs_f64())
}

/// Traces light paths on streams of their own (see the module documentation).
pub fn calibrate(world: &World, seed: u64, max_depth: u32) -> Calibration {
    let start = Instant::now();
    if world.scene.header.emitters.is_empty() {
        return Calibration {
            light_path: 0.0,
            seconds_per_ray: 0.0,
            points: Vec::new(),
            seconds: 0.0,
        };
    }
    let mut rng = Rng::new(seed ^ CALIBRATION_SALT, 1);
    let mut points = Vec::new();
    let (paths, light_path, traced, seconds) = pilot(max_depth, &mut rng, |rng, cap| {
        let end = walk_light_path(world, rng, cap, |v, _| {
            if let LightVertex::Collision { sp, .. } = v {
                if points.len() < CALIBRATION_POINTS {
                    points.push((sp.position, sp.ng));
                }
            }
        });
        (end.collisions, end.truncated)
    });
    Calibration {
        light_path,
        // Every path casts one ray more than it has collisions (the one that leaves).
        seconds_per_ray: seconds / (traced + paths).max(1) as f64,
        points,
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// Mean bounces of the backward walks from `sensors` (with near-field radius `radius[i]`, or
/// infinite), on streams of their own; the seconds it took.
fn backward_length(
    world: &World,
    sensors: &[(SensorPoint, f64)],
    seed: u64,
    max_depth: u32,
) -> (f64, f64) {
    if sensors.is_empty() {
        return (0.0, 0.0);
    }
    let mut rng = Rng::new(seed ^ CALIBRATION_SALT, 2);
    let mut next = 0;
    let (_, mean, _, seconds) = pilot(max_depth, &mut rng, |rng, cap| {
        let (s, radius) = &sensors[next % sensors.len()];
        next += 1;
        let n = gather::backward_path_length(world, s, *radius, rng, cap);
        (n as u64, n == cap)
    });
    (mean, seconds)
}

/// Mean number of `sensors` a collision of the calibration faces (the connections the local
/// estimate makes from it, before visibility).
fn connections_per_collision(cal: &Calibration, sensors: &[SensorPoint]) -> f64 {
    if cal.points.is_empty() {
        return sensors.len() as f64;
    }
    let faced: usize = cal
        .points
        .iter()
        .map(|&(x, ng)| {
            sensors
                .iter()
                .filter(|s| {
                    let v = s.position - x;
                    v.dot(ng) > 0.0 && s.response(-v) > 0.0
                })
                .count()
        })
        .sum();
    faced as f64 / cal.points.len() as f64
}

/// The plan of `estimate sensors`: `paths` light paths, each vertex connected to the sensors
/// it faces; `near_samples` backward samples at each of the sensors with a near-field radius.
pub fn sensors_plan(
    world: &World,
    sensors: &[SensorPoint],
    near_radius: &[f64],
    paths: u64,
    near_samples: u64,
    (seed, max_depth, threads, batches): (u64, u32, usize, usize),
) -> WorkPlan {
    let cal = calibrate(world, seed, max_depth);
    let near: Vec<(SensorPoint, f64)> = sensors
        .iter()
        .zip(near_radius)
        .filter(|(s, &r)| r > 0.0 && s.kind.is_planar() && near_samples > 0)
        .map(|(s, &r)| (*s, r))
        .collect();
    let (near_path, near_seconds) = backward_length(world, &near, seed, max_depth);
    let c = connections_per_collision(&cal, sensors);
    let vertices = paths as f64 * (cal.light_path + 1.0);
    // A near-field sample: an emitter point and a cosine-sampled ray, then per bounce an
    // intersection and a next-event ray.
    let walks = near.len() as f64 * near_samples as f64;
    let backward = walks * (2.0 + 2.0 * near_path);
    // The sky's direct light: one sample of two shadow rays per sensor and light path (the
    // `environment_samples` estimate sensors gives the local estimate).
    let sky = if world.environment().is_some() {
        2.0 * sensors.len() as f64 * paths as f64
    } else {
        0.0
    };
    let units = vertices * (1.0 + c) + backward + sky;
    let cost = vertices * (1.0 + c * CONNECTION_COST) + backward + sky;
    let parallel = threads.min(batches).max(1);
    let mut work = format!(
        "{paths} light paths of ~{} collisions, each vertex connected to ~{} of {} sensors",
        luxest_io::limits::show_count(cal.light_path),
        luxest_io::limits::show_count(c),
        sensors.len()
    );
    if !near.is_empty() {
        work += &format!(
            ", {near_samples} near-field samples at each of {} sensors of ~{} bounces",
            near.len(),
            luxest_io::limits::show_count(near_path)
        );
    }
    if sky > 0.0 {
        work += &format!(", {paths} samples of the sky's direct light at each sensor");
    }
    WorkPlan {
        stage: "estimate sensors".into(),
        work,
        units,
        unit: "ray casts",
        seconds: cost * cal.seconds_per_ray / parallel as f64,
        threads: parallel,
        memory_bytes: batch_memory(batches, sensors.len()),
        calibration_seconds: cal.seconds + near_seconds,
        levers: "--paths, --near-samples, --max-depth and --threads".into(),
    }
}

/// The plan of `estimate gather`: `samples` backward paths at every sensor.
pub fn gather_plan(
    world: &World,
    sensors: &[SensorPoint],
    samples: u64,
    (seed, max_depth, threads, batches): (u64, u32, usize, usize),
) -> WorkPlan {
    let all: Vec<(SensorPoint, f64)> = sensors.iter().map(|s| (*s, f64::INFINITY)).collect();
    let start = Instant::now();
    let (path, _) = backward_length(world, &all, seed, max_depth);
    let cal = calibrate(world, seed, max_depth.min(64));
    let walks = sensors.len() as f64 * samples as f64;
    let units = walks * (2.0 + 2.0 * path);
    let parallel = threads.min(batches).max(1);
    WorkPlan {
        stage: "estimate gather".into(),
        work: format!(
            "{samples} backward samples at each of {} sensors, of ~{} bounces",
            sensors.len(),
            luxest_io::limits::show_count(path)
        ),
        units,
        unit: "ray casts",
        seconds: units * cal.seconds_per_ray / parallel as f64,
        threads: parallel,
        memory_bytes: batch_memory(batches, sensors.len()),
        calibration_seconds: start.elapsed().as_secs_f64(),
        levers: "--samples, --max-depth and --threads".into(),
    }
}

/// The plan of `estimate direct`: `paths` light paths whose collisions are counted in disks.
pub fn direct_plan(
    world: &World,
    sensors: usize,
    paths: u64,
    (seed, max_depth, threads, batches): (u64, u32, usize, usize),
) -> WorkPlan {
    let cal = calibrate(world, seed, max_depth);
    let units = paths as f64 * (cal.light_path + 1.0);
    let parallel = threads.min(batches).max(1);
    WorkPlan {
        stage: "estimate direct".into(),
        work: format!(
            "{paths} light paths of ~{} collisions",
            luxest_io::limits::show_count(cal.light_path)
        ),
        units,
        unit: "ray casts",
        seconds: units * cal.seconds_per_ray / parallel as f64,
        threads: parallel,
        memory_bytes: batch_memory(batches, sensors),
        calibration_seconds: cal.seconds,
        levers: "--paths, --max-depth and --threads".into(),
    }
}

/// The sensor estimators' per-batch sums over `sensors` points.
fn batch_memory(batches: usize, sensors: usize) -> u128 {
    batches as u128 * sensors as u128 * crate::sensor_batches::BYTES_PER_BATCH_POINT
}

/// Camera points of every round of the double local estimate, per pixel: `pixel_samples` of
/// them per round of [`ROUND_PATHS`] light paths, rounds counted per batch.
fn image_rounds(paths: u64) -> u64 {
    let per_batch = paths.div_ceil(BATCHES as u64);
    BATCHES as u64 * per_batch.div_ceil(ROUND_PATHS).max(1)
}

/// The work and memory of `estimate image` (the double local estimate, `cfg`): its memory,
/// refused here when it cannot fit, then its plan.
pub fn image_plan(
    world: &World,
    cam: &PinholeCamera,
    cfg: &ImageConfig,
) -> Result<WorkPlan, String> {
    let cal = calibrate(world, cfg.seed, cfg.max_depth);
    let pixels = cam.width as u64 * cam.height as u64;
    let spp = cfg.pixel_samples.max(1) as u64;
    let tile_pixels =
        pixels.min((double_local_estimate::TILE * double_local_estimate::TILE) as u64);
    let tiles = (cam.width as usize).div_ceil(double_local_estimate::TILE)
        * (cam.height as usize).div_ceil(double_local_estimate::TILE);
    let tile_threads = cfg.threads.min(tiles).max(1);
    // Camera points: every tile in work keeps a round's points of its pixels.
    luxest_io::limits::check_allocation(
        &format!(
            "--pixel-samples {} over a tile of {tile_pixels} pixels on {tile_threads} thread{}",
            cfg.pixel_samples,
            if tile_threads == 1 { "" } else { "s" }
        ),
        tile_threads as u128 * tile_pixels as u128 * spp as u128,
        double_local_estimate::VIEW_POINT_BYTES as u128,
    )?;
    // The light paths' vertices of every batch, kept until they are connected.
    let records = cfg.paths as f64 * (cal.light_path + 1.0);
    luxest_io::limits::check_allocation(
        &format!(
            "--paths {} of ~{} collisions each (their vertices, kept for the connections)",
            cfg.paths,
            luxest_io::limits::show_count(cal.light_path)
        ),
        records.min(u128::MAX as f64 / 2.0) as u128,
        double_local_estimate::RECORD_BYTES as u128,
    )?;
    let memory = records as u128 * double_local_estimate::RECORD_BYTES as u128
        + tile_threads as u128
            * tile_pixels as u128
            * spp as u128
            * double_local_estimate::VIEW_POINT_BYTES as u128
        + pixels as u128 * crate::image::BYTES_PER_PIXEL as u128;
    // Light paths and light tracing run by batch, the camera points and connections by tile.
    let light_threads = cfg.threads.clamp(1, BATCHES) as f64;
    let light_tracing = cfg.paths as f64 * cfg.mis_paths as f64 * (cal.light_path + 1.0) * 2.0;
    let camera = (image_rounds(cfg.paths) * pixels * spp) as f64;
    let connections = records * (pixels * spp) as f64;
    let units = records + light_tracing + camera + connections;
    let seconds = ((records + light_tracing) / light_threads
        + (camera + connections * CONNECTION_COST) / tile_threads as f64)
        * cal.seconds_per_ray;
    let mut work = format!(
        "{} light paths of ~{} collisions connected to {pixels} pixels x {spp} camera points",
        cfg.paths,
        luxest_io::limits::show_count(cal.light_path)
    );
    if cfg.mis_paths > 0 {
        work += &format!(
            ", {} light-tracing paths per light path (--mis-paths)",
            cfg.mis_paths
        );
    }
    Ok(WorkPlan {
        stage: "estimate image".into(),
        work,
        units,
        unit: "ray casts",
        seconds,
        threads: cfg.threads.min(tiles.max(BATCHES)).max(1),
        memory_bytes: memory,
        calibration_seconds: cal.seconds,
        levers: "--paths, --mis-paths, --pixel-samples, --resolution, --max-depth and --threads"
            .into(),
    })
}

/// The plan of `estimate image --light-tracing`: `paths` light paths, each vertex connected to
/// the camera.
pub fn light_tracing_plan(
    world: &World,
    cam: &PinholeCamera,
    paths: u64,
    (seed, max_depth, threads): (u64, u32, usize),
) -> WorkPlan {
    let cal = calibrate(world, seed, max_depth);
    let units = paths as f64 * (cal.light_path + 1.0) * 2.0;
    let parallel = threads.clamp(1, BATCHES);
    WorkPlan {
        stage: "estimate image --light-tracing".into(),
        work: format!(
            "{paths} light paths of ~{} collisions, each connected to the camera",
            luxest_io::limits::show_count(cal.light_path)
        ),
        units,
        unit: "ray casts",
        seconds: units * cal.seconds_per_ray / parallel as f64,
        threads: parallel,
        memory_bytes: (cam.width as u128 * cam.height as u128)
            * crate::image::BYTES_PER_PIXEL as u128,
        calibration_seconds: cal.seconds,
        levers: "--paths, --max-depth and --threads".into(),
    }
}
