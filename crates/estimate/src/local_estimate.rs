//! The local estimate of illuminance at many sensor points at once.
//!
//! Light paths start at emitters chosen by flux (point sources isotropically, area emitters
//! with cosine-distributed directions from their front side), each carrying the flux weight
//! `Q = Φ_e / P(e)`. At every collision j on a non-specular surface, each sensor p facing it
//! receives `Q_j f(ω_in, ω_jp) cos_j cos_p / d² V(j, p)` — for a Lambertian surface
//! `f = rho/π` — through a batch of shadow rays. The path then continues by sampling the BSDF
//! with analog Russian roulette (survival probability = the sample's weight, capped at 1, so a
//! grey Lambertian wall keeps Q constant and ends the path with probability 1 − rho).
//! Specular collisions (mirror, dielectric) continue the path without a connection: a delta
//! BSDF has no value towards a given sensor.
//!
//! Direct light: for delta lights (point sources and goniometric luminaires) it is computed
//! exactly (`I(ω) cos_p / d² V`, no variance); for area emitters the emission point is the
//! zeroth collision, with kernel `cos_e cos_p/(π d²)`. Luminaires start light paths with
//! directions from their intensity table ([`luxest_render::luminaire`]).
//!
//! Sensor kinds: everywhere above, `cos_p` is the sensor's response g(ω) to light arriving from
//! ω — the cosine for planar sensors, `sin ε / π` for cylindrical and `(|ω_h| + f·ω_h)/π` for
//! semi-cylindrical ones (`SensorPoint::response`) — since every kind is E = ∫ L(ω) g(ω) dω and
//! the local estimate's connection estimates L(ω) dω. The near-field split (a backward estimate
//! sampling the cosine about the normal) applies to planar sensors only.
//!
//! Environment light ([`luxest_render::environment`]): light paths enter from the disk around
//! the scene and connect from their first collision on, as any other; the environment's direct
//! illuminance at a sensor has no emission vertex to connect from, so each batch estimates it
//! at every sensor with `environment_samples / batches` samples of
//! [`crate::transport::environment_illuminance`] (a direction from the map and one about the
//! sensor, by multiple importance sampling, with shadow rays to infinity): a sensor facing a
//! window sees the sky through it. Spot lights are delta lights like point sources.
//!
//! The walk and the exact point-source term are shared with the other estimators
//! ([`crate::transport`]): scattering uses the geometric normal. Standard errors come from
//! independent batches ([`crate::sensor_batches`]); all sums are f64. Direct simulation, the
//! baseline that counts photons instead of connecting, is [`crate::direct_simulation`].

use crate::sensor_batches::{self, BatchSums, Batches, SensorEstimates};
pub use crate::singularity::Singularity;
use crate::transport::{
    delta_light_illuminance, environment_illuminance, walk_light_path, LightVertex,
};
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_io::progress::Progress;
use luxest_render::bsdf::Transport;
use luxest_render::rt::Ray;
use luxest_render::sampling::Rng;
use luxest_render::scene::{Material, SensorPoint};
use luxest_render::shading::Shading;
use luxest_render::world::World;

/// The near-field split for sensors close to other surfaces: collisions closer than the
/// sensor's near-field radius (given per sensor to [`estimate`]) are left to a backward
/// estimate with `samples` samples per sensor (see [`crate::gather::near_field_sample`]); the
/// two parts partition the illuminance exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearField {
    pub samples: u64,
}

#[derive(Clone, Debug)]
pub struct LocalConfig {
    pub batches: Batches,
    /// The kernel's treatment near its singularity.
    pub singularity: Singularity,
    /// Safety bound on path length; with survival probability q the bias is at most q^max_depth.
    pub max_depth: u32,
    /// Near-field split, applied to the sensors with a near-field radius.
    pub near_field: Option<NearField>,
    /// Samples per sensor of the environment's direct illuminance, over all batches (each
    /// batch takes at least one); unused without an environment.
    pub environment_samples: u64,
}

/// Per-thread scratch buffers, reused across collisions.
#[derive(Default)]
struct Scratch {
    rays: Vec<Ray>,
    targets: Vec<(usize, Rgb)>,
    blocked: Vec<bool>,
}

/// Where a connection starts: a scattering collision or a point on an area emitter.
enum Source<'a> {
    Collision {
        material: &'a Material,
        wo: Vec3,
        shading: Shading,
    },
    Emitter {
        normal: Vec3,
    },
}

/// Adds the contributions of one vertex at `(x, ng)` (position, geometric normal) carrying
/// flux `q` to every sensor that sees it.
#[allow(clippy::too_many_arguments)]
fn connect(
    world: &World,
    sensors: &[SensorPoint],
    skip_within: &[f64],
    singularity: &Singularity,
    (x, ng): (Vec3, Vec3),
    source: &Source,
    q: Rgb,
    scratch: &mut Scratch,
    out: &mut BatchSums,
) {
    let direct = matches!(source, Source::Emitter { .. });
    scratch.rays.clear();
    scratch.targets.clear();
    let min_d2 = (1e-12 * world.diagonal).powi(2);
    for (i, s) in sensors.iter().enumerate() {
        let v = s.position - x;
        let d2 = v.length_squared();
        if d2 <= min_d2 || d2 < skip_within[i] * skip_within[i] {
            // The direction is undefined (a set of measure zero), or the near field is
            // estimated backwards.
            continue;
        }
        let d = d2.sqrt();
        let w = v / d;
        // The sensor's response to light arriving from −w (the cosine −n·w for planar sensors).
        let cos_p = s.response(-w);
        if cos_p <= 0.0 {
            continue;
        }
        let f_cos = match source {
            Source::Collision {
                material,
                wo,
                shading,
            } => {
                // The adjoint BSDF (wo towards the light), with the light paths' rules for
                // shading normals.
                shading.eval(material, *wo, w, Transport::Flux)
            }
            Source::Emitter { normal } => {
                let c = normal.dot(w);
                if c <= 0.0 {
                    continue;
                }
                Rgb::splat(c / std::f64::consts::PI)
            }
        };
        let contribution = q * f_cos * (cos_p * singularity.inverse_square(d2));
        if contribution.max_component() <= 0.0 {
            continue;
        }
        let origin = world.offset(x, ng, w);
        let to = s.position - origin;
        let len = to.length();
        let eps = world.margin(origin, s.position);
        if len <= 2.0 * eps {
            // Closer than the scene's resolution: nothing can be in between.
            out.add(i, contribution, direct);
            continue;
        }
        // The margin at both ends skips the surfaces the sensor lies on (edges, corners).
        scratch.rays.push(Ray {
            origin,
            direction: to / len,
            tnear: eps,
            tfar: len - eps,
        });
        scratch.targets.push((i, contribution));
    }
    out.shadow_rays += scratch.rays.len() as u64;
    world
        .tracer
        .occluded_many(&scratch.rays, &mut scratch.blocked);
    for ((i, c), blocked) in scratch.targets.iter().zip(&scratch.blocked) {
        if !blocked {
            out.add(*i, *c, direct);
        }
    }
}

fn run_batch(
    world: &World,
    sensors: &[SensorPoint],
    skip_within: &[f64],
    cfg: &LocalConfig,
    (batch, paths): (usize, u64),
    progress: &Progress,
) -> BatchSums {
    let mut rng = Rng::new(cfg.batches.seed, batch as u64 + 1);
    let mut out = BatchSums::new(sensors.len());
    let mut scratch = Scratch::default();
    let sing = &cfg.singularity;
    let mut tally = progress.tally();
    for _ in 0..paths {
        let end = walk_light_path(world, &mut rng, cfg.max_depth, |v, q| {
            let material;
            let (at, src) = match v {
                LightVertex::Emission { position, normal } => {
                    ((position, normal), Source::Emitter { normal })
                }
                LightVertex::Collision { sp, dir, .. } => {
                    material = world.material_seen(&sp, -dir);
                    let src = Source::Collision {
                        material: &material,
                        wo: -dir,
                        shading: world.shading_of(&sp, -dir),
                    };
                    ((sp.position, sp.ng), src)
                }
            };
            connect(
                world,
                sensors,
                skip_within,
                sing,
                at,
                &src,
                q,
                &mut scratch,
                &mut out,
            );
        });
        out.collisions += end.collisions;
        out.truncated += u64::from(end.truncated);
        tally.add(1);
    }
    if let Some(nf) = cfg.near_field {
        let samples = (nf.samples / cfg.batches.count() as u64).max(1);
        for (i, s) in sensors.iter().enumerate() {
            if skip_within[i] > 0.0 {
                let (mut emitted, mut reflected) = (Rgb::BLACK, Rgb::BLACK);
                for _ in 0..samples {
                    let (e, r) = crate::gather::near_field_sample(
                        world,
                        s,
                        skip_within[i],
                        &mut rng,
                        cfg.max_depth,
                    );
                    (emitted, reflected) = (emitted + e, reflected + r);
                    tally.add(1);
                }
                // Stored as a sum over `paths` so that the common division gives the mean.
                let scale = paths as f64 / samples as f64;
                out.add(i, emitted * scale, true);
                out.add(i, reflected * scale, false);
            }
        }
    }
    if world.environment().is_some() {
        let samples = (cfg.environment_samples / cfg.batches.count() as u64).max(1);
        // Stored as a sum over the batch's paths, which the common division turns into the mean.
        let scale = paths.max(1) as f64 / samples as f64;
        for (i, s) in sensors.iter().enumerate() {
            let mut e = Rgb::BLACK;
            for _ in 0..samples {
                e = e + environment_illuminance(world, s, &mut rng, &mut out.shadow_rays);
            }
            out.add(i, e * scale, true);
        }
    }
    out
}

/// Runs the local estimate for `sensors`, with the near-field split (when configured) for
/// each planar sensor `i` with `near_radius[i] > 0`; counts on `progress` every light path and
/// every near-field sample ([`progress_total`] in all).
pub fn estimate(
    world: &World,
    sensors: &[SensorPoint],
    near_radius: &[f64],
    cfg: &LocalConfig,
    progress: &Progress,
) -> SensorEstimates {
    let delta_light = delta_light_illuminance(world, sensors);
    // The backward near-field estimate samples the cosine about the normal: planar only.
    let skip_within: Vec<f64> = near_radius
        .iter()
        .zip(sensors)
        .map(|(&r, s)| match cfg.near_field {
            Some(_) if s.kind.is_planar() => r,
            _ => 0.0,
        })
        .collect();
    sensor_batches::run(
        &cfg.batches,
        sensors.len(),
        &delta_light,
        true,
        |b, paths| run_batch(world, sensors, &skip_within, cfg, (b, paths), progress),
    )
}

/// The paths [`estimate`] counts on its progress: the light paths, and the near field's
/// backward samples (each batch takes at least one per near-field sensor).
pub fn progress_total(sensors: &[SensorPoint], near_radius: &[f64], cfg: &LocalConfig) -> u64 {
    let Some(nf) = cfg.near_field else {
        return cfg.batches.paths;
    };
    let near = sensors
        .iter()
        .zip(near_radius)
        .filter(|(s, &r)| r > 0.0 && s.kind.is_planar())
        .count() as u64;
    let count = cfg.batches.count() as u64;
    cfg.batches.paths + near * (nf.samples / count).max(1) * count
}
