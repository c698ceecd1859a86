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
//! The walk's step and the exact point-source term are shared with the other estimators
//! ([`crate::transport`]): scattering uses the geometric normal.
//!
//! Standard errors come from independent batches (see [`luxest_render::parallel`]). All sums are f64.

use crate::sensors::Estimate;
pub use crate::singularity::Singularity;
use crate::transport::{point_source_direct, scatter};
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_io::sensors::Part;
use luxest_render::bsdf::{self, Transport};
use luxest_render::parallel::{mean_and_standard_error, run_batches};
use luxest_render::rt::Ray;
use luxest_render::sampling::Rng;
use luxest_render::scene::SensorPoint;
use luxest_render::world::World;

/// How sensors receive light from the random walk.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Detector {
    /// The local estimate: a deterministic connection from every collision to every sensor.
    LocalEstimate(Singularity),
    /// Direct simulation (the baseline): a sensor counts the flux of the photons that land on
    /// its surface within `radius` of it, divided by the disk area π radius²; no connections,
    /// no exact direct term.
    Bins { radius: f64 },
}

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
    pub paths: u64,
    pub batches: usize,
    pub seed: u64,
    pub threads: usize,
    pub detector: Detector,
    /// Safety bound on path length; with survival probability q the bias is at most q^max_depth.
    pub max_depth: u32,
    /// Near-field split, applied to the sensors with a near-field radius.
    pub near_field: Option<NearField>,
}

/// Results per sensor point.
#[derive(Clone, Debug)]
pub struct LocalResult {
    /// Mean RGB illuminance, lx per channel.
    pub rgb: Vec<Rgb>,
    /// Mean photometric illuminance Y and its standard error, lx.
    pub value: Vec<f64>,
    pub standard_error: Vec<f64>,
    /// The exact direct part from delta lights (point sources, luminaires; included in
    /// `value`).
    pub direct_point: Vec<f64>,
    /// Per sensor, the direct part (light straight from the emitters, the exact delta-light
    /// term included) and the indirect part of `value`, each as (Y, standard error), lx; the
    /// local estimate only (empty for the direct simulation).
    pub direct: Vec<(f64, f64)>,
    pub indirect: Vec<(f64, f64)>,
    /// `batch_values[b][i]`: batch b's estimate of Y at sensor i (the exact direct part
    /// included), lx; `value` is their mean, `standard_error` their standard deviation / √B.
    pub batch_values: Vec<Vec<f64>>,
    pub seconds: f64,
    pub collisions: u64,
    pub shadow_rays: u64,
    /// Light paths that reached `max_depth` still carrying light: what they would have added
    /// is missing (the estimate is biased low), e.g. in a closed scene of reflectance 1.
    pub truncated: u64,
}

impl LocalResult {
    /// Per sensor: RGB, Y, the standard error of Y and (local estimate) the direct and
    /// indirect parts, the results contract's values.
    pub fn estimates(&self) -> Vec<Estimate> {
        let part = |p: Option<&(f64, f64)>| {
            p.map(|&(value, standard_error)| Part {
                value,
                standard_error,
            })
        };
        (0..self.value.len())
            .map(|i| Estimate {
                direct: part(self.direct.get(i)),
                indirect: part(self.indirect.get(i)),
                ..Estimate::from((self.rgb[i], self.value[i], self.standard_error[i]))
            })
            .collect()
    }
}

/// Per-thread scratch buffers, reused across collisions.
#[derive(Default)]
struct Scratch {
    rays: Vec<Ray>,
    targets: Vec<(usize, Rgb)>,
    blocked: Vec<bool>,
}

struct BatchSums {
    /// Per sensor: every contribution (flux sums; the near-field part scaled to `paths`).
    sums: Vec<[f64; 3]>,
    /// Per sensor: the direct ones among them (from emitter vertices and, in the near field,
    /// emitted radiance met first).
    direct: Vec<[f64; 3]>,
    collisions: u64,
    shadow_rays: u64,
    /// Light paths still going when they reached the path-length bound.
    truncated: u64,
}

impl BatchSums {
    /// Adds contribution `c` to sensor `i` (and to its direct part when `direct`).
    fn add(&mut self, i: usize, c: Rgb, direct: bool) {
        add(&mut self.sums[i], c);
        if direct {
            add(&mut self.direct[i], c);
        }
    }
}

/// Adds an RGB contribution to an f64 accumulator.
fn add(acc: &mut [f64; 3], c: Rgb) {
    for (a, v) in acc.iter_mut().zip(c.0) {
        *a += v;
    }
}

/// Where a connection starts: a scattering collision or a point on an area emitter.
enum Source<'a> {
    Collision {
        material: &'a luxest_render::scene::Material,
        wo: Vec3,
        ng: Vec3,
        ns: Vec3,
    },
    Emitter {
        normal: Vec3,
    },
}

/// Adds the contributions of one vertex at `x` (with geometric normal `ng`) carrying flux `q`
/// to every sensor that sees it.
#[allow(clippy::too_many_arguments)]
fn connect(
    world: &World,
    sensors: &[SensorPoint],
    skip_within: &[f64],
    singularity: &Singularity,
    x: Vec3,
    ng: Vec3,
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
                ng,
                ns,
            } => {
                let f = bsdf::eval(material, *wo, w, *ng, *ns);
                f * w.dot(*ns).abs()
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

/// Direct simulation: the photon arriving at `x` (travelling along `dir`) on a surface with
/// normal `ng` deposits its flux `q` into every bin it lands in.
fn deposit(
    sensors: &[SensorPoint],
    radius: f64,
    x: Vec3,
    ng: Vec3,
    dir: Vec3,
    q: Rgb,
    out: &mut BatchSums,
) {
    let inv_area = 1.0 / (std::f64::consts::PI * radius * radius);
    for (i, s) in sensors.iter().enumerate() {
        let v = x - s.position;
        if v.length_squared() < radius * radius
            && ng.dot(s.normal).abs() > 0.999
            && v.dot(s.normal).abs() < 1e-3 * radius
            && dir.dot(s.normal) < 0.0
        {
            out.add(i, q * inv_area, false);
        }
    }
}

fn run_batch(
    world: &World,
    sensors: &[SensorPoint],
    near_radius: &[f64],
    cfg: &LocalConfig,
    batch: usize,
    paths: u64,
) -> BatchSums {
    let skip_within: Vec<f64> = near_radius
        .iter()
        .enumerate()
        .map(|(i, &r)| match cfg.near_field {
            // The backward near-field estimate samples the cosine about the normal: planar only.
            Some(_) if sensors[i].kind.is_planar() => r,
            _ => 0.0,
        })
        .collect();
    let mut rng = Rng::new(cfg.seed, batch as u64 + 1);
    let mut out = BatchSums {
        sums: vec![[0.0; 3]; sensors.len()],
        direct: vec![[0.0; 3]; sensors.len()],
        collisions: 0,
        shadow_rays: 0,
        truncated: 0,
    };
    let mut scratch = Scratch::default();
    for _ in 0..paths {
        let e = world.sample_emission(&mut rng);
        let mut q = e.flux;
        let mut origin = e.position;
        if let Some(n) = e.normal {
            if let Detector::LocalEstimate(sing) = &cfg.detector {
                let src = Source::Emitter { normal: n };
                connect(
                    world,
                    sensors,
                    &skip_within,
                    sing,
                    e.position,
                    n,
                    &src,
                    q,
                    &mut scratch,
                    &mut out,
                );
            }
            origin = world.offset(e.position, n, e.direction);
        }
        let mut dir = e.direction;
        let mut going = true;
        // A point light or luminaire source may sit on a surface: its first ray starts beyond.
        let mut from_source = e.normal.is_none();
        for _ in 0..cfg.max_depth {
            let hit = if from_source {
                world.intersect_from_source(origin, dir)
            } else {
                world.intersect(origin, dir)
            };
            from_source = false;
            let Some(sp) = hit else {
                going = false;
                break;
            };
            out.collisions += 1;
            let material = world.material(sp.triangle);
            let wo = -dir;
            match &cfg.detector {
                Detector::LocalEstimate(sing) if !bsdf::is_delta(material) => {
                    let src = Source::Collision {
                        material,
                        wo,
                        ng: sp.ng,
                        ns: sp.ng,
                    };
                    connect(
                        world,
                        sensors,
                        &skip_within,
                        sing,
                        sp.position,
                        sp.ng,
                        &src,
                        q,
                        &mut scratch,
                        &mut out,
                    );
                }
                Detector::LocalEstimate(_) => {}
                Detector::Bins { radius } => {
                    deposit(sensors, *radius, sp.position, sp.ng, dir, q, &mut out)
                }
            }
            let Some(s) = scatter(world, &sp, dir, q, Transport::Flux, &mut rng) else {
                going = false;
                break;
            };
            (q, origin, dir) = (s.beta, s.origin, s.dir);
        }
        out.truncated += u64::from(going);
    }
    if let (Detector::LocalEstimate(_), Some(nf)) = (&cfg.detector, cfg.near_field) {
        let samples = (nf.samples / cfg.batches.max(2) as u64).max(1);
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
                }
                // Stored as a sum over `paths` so that the common division gives the mean.
                let scale = paths as f64 / samples as f64;
                out.add(i, emitted * scale, true);
                out.add(i, reflected * scale, false);
            }
        }
    }
    out
}

/// Runs the local estimate for `sensors`, with the near-field split (when configured) for
/// each sensor `i` with `near_radius[i] > 0`.
pub fn estimate(
    world: &World,
    sensors: &[SensorPoint],
    near_radius: &[f64],
    cfg: &LocalConfig,
) -> LocalResult {
    let start = std::time::Instant::now();
    let direct = match cfg.detector {
        Detector::LocalEstimate(_) => point_source_direct(world, sensors),
        Detector::Bins { .. } => vec![Rgb::BLACK; sensors.len()],
    };
    let batches = cfg.batches.max(2);
    let per_batch =
        |b: usize| cfg.paths / batches as u64 + u64::from((b as u64) < cfg.paths % batches as u64);
    let results = run_batches(batches, cfg.threads, "local estimate", |b| {
        run_batch(world, sensors, near_radius, cfg, b, per_batch(b))
    });
    let n = sensors.len();
    let mut rgb = vec![Rgb::BLACK; n];
    let mut value = vec![0.0; n];
    let mut standard_error = vec![0.0; n];
    let mut batch_values = vec![vec![0.0; n]; batches];
    let split = matches!(cfg.detector, Detector::LocalEstimate(_));
    let (mut direct_part, mut indirect_part) = (Vec::new(), Vec::new());
    for i in 0..n {
        let mut ys = Vec::with_capacity(batches);
        let (mut ys_direct, mut ys_indirect) = (Vec::new(), Vec::new());
        let mut acc = [0.0; 3];
        for (b, r) in results.iter().enumerate() {
            let paths = per_batch(b).max(1) as f64;
            let e = r.sums[i].map(|s| s / paths);
            add(&mut acc, Rgb(e) * (1.0 / batches as f64));
            ys.push(Rgb(e).luminance());
            if split {
                let d = Rgb(r.direct[i].map(|s| s / paths)).luminance();
                ys_direct.push(d);
                ys_indirect.push(Rgb(e).luminance() - d);
            }
        }
        if split {
            let (md, sed) = mean_and_standard_error(&ys_direct);
            direct_part.push((md + direct[i].luminance(), sed));
            indirect_part.push(mean_and_standard_error(&ys_indirect));
        }
        let (m, se) = mean_and_standard_error(&ys);
        for (b, y) in ys.iter().enumerate() {
            batch_values[b][i] = y + direct[i].luminance();
        }
        rgb[i] = Rgb(acc) + direct[i];
        value[i] = m + direct[i].luminance();
        standard_error[i] = se;
    }
    LocalResult {
        rgb,
        value,
        standard_error,
        direct_point: direct.iter().map(Rgb::luminance).collect(),
        direct: direct_part,
        indirect: indirect_part,
        batch_values,
        seconds: start.elapsed().as_secs_f64(),
        collisions: results.iter().map(|r| r.collisions).sum(),
        shadow_rays: results.iter().map(|r| r.shadow_rays).sum(),
        truncated: results.iter().map(|r| r.truncated).sum(),
    }
}
