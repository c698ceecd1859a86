//! A backward ("gathering") estimator of illuminance at a point, independent of the local
//! estimate and free of its singularity: used as the reference at edges and corners.
//!
//! E(p) = direct + ∫ L_r(ω) cos θ dω. Direct light: exact for point sources, light-sampled for
//! area emitters, and for the environment [`crate::transport::environment_illuminance`] (a
//! direction from the map and one about the normal, by multiple importance sampling).
//! Indirect light: a cosine-distributed direction from p (weight π) and a path traced from
//! there with next-event estimation at every vertex (a light point, and a direction drawn from
//! the environment's map) and analog Russian roulette; emission found by BSDF sampling, and the environment
//! met by a path that leaves the scene, are ignored (they are all counted by next-event
//! estimation), so the estimator needs a scene without specular paths, and is unbiased with
//! bounded variance wherever the sensor is.

use crate::transport::{delta_light_illuminance, environment_illuminance, scatter};
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_io::progress::Progress;
use luxest_render::bsdf::{self, Transport};
use luxest_render::parallel::{mean_and_standard_error, run_batches};
use luxest_render::sampling::{cosine_hemisphere, Rng};
use luxest_render::scene::SensorPoint;
use luxest_render::world::{SurfacePoint, World};
use std::f64::consts::PI;

#[derive(Clone, Debug)]
pub struct GatherConfig {
    /// Samples per sensor point.
    pub samples: u64,
    pub batches: usize,
    pub seed: u64,
    pub threads: usize,
    pub max_depth: u32,
}

/// Light arriving at `x` (surface normal `n`, towards directions on `n`'s side) from one
/// sampled light point, times `f cos` evaluated by `response(w_to_light)`: the next-event
/// estimate for area and point emitters. Point sources are skipped when `skip_points`.
fn next_event(
    world: &World,
    x: Vec3,
    n: Vec3,
    rng: &mut Rng,
    response: impl Fn(Vec3) -> Rgb,
    skip_points: bool,
) -> Rgb {
    if !world.has_light_points() {
        return Rgb::BLACK; // the environment alone: see `environment_next_event`
    }
    let l = world.sample_light_point(rng, x);
    let v = l.position - x;
    let d2 = v.length_squared();
    if d2 <= 0.0 {
        return Rgb::BLACK;
    }
    let d = d2.sqrt();
    let w = v / d;
    let geometric = match l.normal {
        Some(nl) => {
            let c = -nl.dot(w);
            if c <= 0.0 {
                return Rgb::BLACK;
            }
            c / d2
        }
        None if skip_points => return Rgb::BLACK,
        None => 1.0 / d2,
    };
    let r = response(w);
    if r.max_component() <= 0.0 {
        return Rgb::BLACK;
    }
    if world.occluded(world.offset(x, n, w), l.position) {
        return Rgb::BLACK;
    }
    l.emitted * r * (geometric / l.pdf)
}

/// Light arriving at `x` (surface normal `n`) from the environment along one direction drawn
/// from its map, times `f cos` evaluated by `response(w)`: the next-event estimate of the
/// environment (black without one).
fn environment_next_event(
    world: &World,
    x: Vec3,
    n: Vec3,
    rng: &mut Rng,
    response: impl Fn(Vec3) -> Rgb,
) -> Rgb {
    let Some(env) = world.environment() else {
        return Rgb::BLACK;
    };
    let es = env.sample(rng.next_f64(), rng.next_f64());
    let r = response(es.direction);
    if es.pdf <= 0.0
        || r.max_component() <= 0.0
        || !world.escapes(world.offset(x, n, es.direction), es.direction)
    {
        return Rgb::BLACK;
    }
    es.radiance * r * (1.0 / es.pdf)
}

/// The backward walk from the surface point `first`, reached along `dir`: at most `max_depth`
/// vertices, analog Russian roulette; `at_vertex(sp, dir, beta, rng)` is called at each vertex
/// before the walk scatters from it. Returns the vertices visited.
fn backward_walk(
    world: &World,
    first: SurfacePoint,
    dir: Vec3,
    rng: &mut Rng,
    max_depth: u32,
    mut at_vertex: impl FnMut(&SurfacePoint, Vec3, Rgb, &mut Rng),
) -> u32 {
    let mut beta = Rgb::WHITE;
    let mut sp = first;
    let mut dir = dir;
    for depth in 0..max_depth {
        at_vertex(&sp, dir, beta, rng);
        let Some(s) = scatter(world, &sp, dir, beta, Transport::Radiance, rng) else {
            return depth + 1;
        };
        beta = s.beta;
        dir = s.dir;
        match world.intersect(s.origin, dir) {
            Some(next) => sp = next,
            None => return depth + 1,
        }
    }
    max_depth
}

/// Reflected radiance leaving the surface point `sp` towards `-dir` (emission at `sp`
/// excluded), by a path with next-event estimation at every vertex.
fn reflected_radiance(
    world: &World,
    first: SurfacePoint,
    dir: Vec3,
    rng: &mut Rng,
    max_depth: u32,
) -> Rgb {
    let mut l = Rgb::BLACK;
    backward_walk(world, first, dir, rng, max_depth, |sp, dir, beta, rng| {
        let wo = -dir;
        let m = world.material_seen(sp, wo);
        let m = &*m;
        let ng = bsdf::facing_normal(wo, sp.ng);
        let shading = world.shading_of(sp, wo);
        let f_cos = |w: Vec3| shading.eval(m, wo, w, Transport::Radiance);
        let radiance = next_event(world, sp.position, ng, rng, f_cos, false)
            + environment_next_event(world, sp.position, ng, rng, f_cos);
        l = l + beta * radiance;
    });
    l
}

/// The vertices of one backward path from sensor `s` as [`sample_once`] (`radius` infinite)
/// and [`near_field_sample`] (its near-field radius) make it, without their next-event
/// estimates: what such a sample costs, for the work estimate (`crate::work`).
pub fn backward_path_length(
    world: &World,
    s: &SensorPoint,
    radius: f64,
    rng: &mut Rng,
    max_depth: u32,
) -> u32 {
    let (origin, dir) = sensor_ray(world, s, rng);
    match world.intersect_from_sensor(origin, dir, radius) {
        Some(sp) => backward_walk(world, sp, dir, rng, max_depth, |_, _, _, _| {}),
        None => 0,
    }
}

/// A cosine-distributed direction about `n` and the ray origin just off the sensor.
fn sensor_ray(world: &World, s: &SensorPoint, rng: &mut Rng) -> (Vec3, Vec3) {
    let n = s.normal;
    let local = cosine_hemisphere(rng.next_f64(), rng.next_f64());
    let (t, b) = n.orthonormal_basis();
    let dir = t * local.x + b * local.y + n * local.z;
    (world.offset(s.position, n, dir), dir)
}

fn sample_once(world: &World, s: &SensorPoint, rng: &mut Rng, max_depth: u32) -> Rgb {
    let n = s.normal;
    // Direct light from the environment, then from area emitters (point sources are added
    // exactly by the caller).
    let mut e = environment_illuminance(world, s, rng, &mut 0);
    e = e + next_event(
        world,
        s.position,
        n,
        rng,
        |w| Rgb::splat(n.dot(w).max(0.0)),
        true,
    );
    // Indirect: cosine-sampled direction, weight pi.
    let (origin, dir) = sensor_ray(world, s, rng);
    if let Some(sp) = world.intersect_from_sensor(origin, dir, f64::INFINITY) {
        e = e + reflected_radiance(world, sp, dir, rng, max_depth) * PI;
    }
    e
}

/// Near-field part of the illuminance at a sensor: light whose last scattering (or emission)
/// happened on a surface closer than `radius` along the line of sight. Together with the local
/// estimate restricted to collisions at least `radius` away, it partitions E exactly (the
/// local estimate's visibility term makes "collision j" equal "first surface seen towards j").
/// Returns its two parts: emitted radiance met first (direct light) and reflected (indirect).
///
/// The direct part combines two strategies by multiple importance sampling (balance
/// heuristic): the cosine-sampled ray (good where an emitter fills much of the hemisphere, a
/// sensor close to a large luminous surface) and a sampled point of an area emitter within
/// `radius` (good for an emitter small against its distance: a cosine-sampled ray all but never
/// meets a 1 mm lamp 1 cm away, which left such sensors at 0 ± 0).
pub fn near_field_sample(
    world: &World,
    s: &SensorPoint,
    radius: f64,
    rng: &mut Rng,
    max_depth: u32,
) -> (Rgb, Rgb) {
    let n = s.normal;
    // Strategy 2: a point of an area emitter, chosen among the area emitters alone (point
    // sources are exact elsewhere), counted when it lies within the radius and is seen; scenes
    // without area emitters draw nothing for it.
    let mut emitted = Rgb::BLACK;
    let l = world.sample_area_light_point(rng);
    if let Some((l, nl)) = l.and_then(|l| l.normal.map(|nl| (l, nl))) {
        let v = l.position - s.position;
        let d2 = v.length_squared();
        if d2 > 0.0 && d2 < radius * radius {
            let d = d2.sqrt();
            let w = v / d;
            let (cos_p, cos_e) = (n.dot(w), -nl.dot(w));
            if cos_p > 0.0
                && cos_e > 0.0
                && !world.occluded(world.offset(s.position, n, w), l.position)
            {
                // Solid-angle densities of the two strategies for this direction.
                let p_light = l.pdf * d2 / cos_e;
                let p_cos = cos_p / PI;
                emitted = l.emitted * (cos_p / (p_light + p_cos));
            }
        }
    }
    // Strategy 1: the cosine-sampled ray; it also starts the reflected part.
    let (origin, dir) = sensor_ray(world, s, rng);
    let Some(sp) = world.intersect_from_sensor(origin, dir, radius) else {
        return (emitted, Rgb::BLACK);
    };
    let d2 = (sp.position - s.position).length_squared();
    if d2 >= radius * radius {
        return (emitted, Rgb::BLACK);
    }
    if let Some((e, radiance)) = world.emission(&sp, -dir) {
        let cos_e = sp.ng.dot(-dir).abs();
        let p_cos = n.dot(dir).max(0.0) / PI;
        let p_light = world.area_light_point_pdf(e) * d2 / cos_e;
        if p_cos > 0.0 {
            emitted = emitted + radiance * (PI * p_cos / (p_cos + p_light));
        }
    }
    (
        emitted,
        reflected_radiance(world, sp, dir, rng, max_depth) * PI,
    )
}

/// Per sensor: (RGB mean, Y mean, Y standard error); counts every sample on `progress`
/// ([`progress_total`] in all).
pub fn estimate(
    world: &World,
    sensors: &[SensorPoint],
    cfg: &GatherConfig,
    progress: &Progress,
) -> Vec<(Rgb, f64, f64)> {
    let direct = delta_light_illuminance(world, sensors);
    let batches = cfg.batches.max(2);
    let per_batch = (cfg.samples / batches as u64).max(1);
    let results = run_batches(batches, cfg.threads, |b| {
        let mut rng = Rng::new(cfg.seed, b as u64 + 1);
        let mut tally = progress.tally();
        sensors
            .iter()
            .map(|s| {
                let mut acc = Rgb::BLACK;
                for _ in 0..per_batch {
                    acc = acc + sample_once(world, s, &mut rng, cfg.max_depth);
                    tally.add(1);
                }
                acc * (1.0 / per_batch as f64)
            })
            .collect::<Vec<Rgb>>()
    });
    (0..sensors.len())
        .map(|i| {
            let ys: Vec<f64> = results.iter().map(|r| r[i].luminance()).collect();
            let mut rgb = Rgb::BLACK;
            for r in &results {
                rgb = rgb + r[i] * (1.0 / batches as f64);
            }
            let (m, se) = mean_and_standard_error(&ys);
            (rgb + direct[i], m + direct[i].luminance(), se)
        })
        .collect()
}

/// The samples [`estimate`] counts on its progress at `sensors` sensor points.
pub fn progress_total(sensors: usize, cfg: &GatherConfig) -> u64 {
    let batches = cfg.batches.max(2) as u64;
    sensors as u64 * (cfg.samples / batches).max(1) * batches
}
