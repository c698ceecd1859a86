//! What the forward (local estimate, double local estimate) and backward (gather) estimators
//! share: one step of a random walk, and the exact direct light of point sources.
//!
//! A walk scatters with the geometric normal: interpolated shading normals are a rendering
//! device that breaks energy conservation (a cosine lobe about a tilted normal dips below the
//! surface), which would bias illuminance. Delta lights — isotropic point sources and
//! goniometric luminaires ([`luxest_render::luminaire`]) — are never hit by a walk, so their
//! direct contribution is always computed exactly, with a visibility ray: `I(ω) g(ω) / d²` for a
//! sensor of response g (the cosine for planar sensors), `f I(ω) cos / d²` for reflected light.
//! Spot lights are delta lights whose intensity carries the cone's falloff.
//!
//! The environment ([`luxest_render::environment`]) starts light paths on a disk outside the
//! scene: the walk's first collision is reached from it ([`Arrival::Environment`]) and there is
//! no emission vertex to connect. Its direct light at a receiver is therefore estimated at the
//! receiver: [`environment_illuminance`] at a sensor and [`environment_reflected`] at a point
//! the camera sees, each combining a direction drawn from the map with one drawn about the
//! receiver (the sensor's response, or the BSDF) by the balance heuristic, with a shadow ray to
//! infinity.

use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_render::bsdf::{self, Transport};
use luxest_render::sampling::{cosine_hemisphere, uniform_sphere, Rng};
use luxest_render::scene::IlluminanceKind;
use luxest_render::scene::SensorPoint;
use luxest_render::shading::Shading;
use luxest_render::world::{SurfacePoint, World};

/// A non-specular vertex of a light path (what connections start from).
#[derive(Clone, Copy, Debug)]
pub enum LightVertex {
    /// The emission point of an area emitter (front normal `normal`).
    Emission { position: Vec3, normal: Vec3 },
    /// A collision on a non-specular surface, the light arriving along `dir`; `depth` counts
    /// the path's collisions before it (specular ones included).
    Collision {
        sp: SurfacePoint,
        dir: Vec3,
        arrival: Arrival,
        depth: u32,
    },
}

/// How a light path reached a collision: what multiple importance sampling between connection
/// strategies needs to know of the vertex before it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Arrival {
    /// Straight from a delta light (isotropic point source, goniometric luminaire), whose
    /// direct light the estimators compute exactly.
    DeltaLight,
    /// Straight from the environment, whose direct light the estimators estimate at the
    /// receivers ([`environment_illuminance`], [`environment_reflected`]).
    Environment,
    /// After a specular bounce (no connection can end at a delta vertex).
    Specular,
    /// Sampled at the non-specular vertex `from` (an area emitter's emission point or a
    /// collision) with solid-angle density `pdf`, the roulette's survival probability included.
    Sampled { from: Vec3, pdf: f64 },
}

/// A step of a random walk: the new throughput, ray origin and direction, and the density of
/// the direction (solid angle, times the roulette's survival probability; 0 for a direction
/// sampled from a delta lobe).
pub struct Scattered {
    pub beta: Rgb,
    pub origin: Vec3,
    pub dir: Vec3,
    pub pdf: f64,
}

/// How a light path ended: its collisions (specular ones included) and whether it reached
/// `max_depth` still carrying light (what it would have added is missing: the estimate is
/// biased low, e.g. in a closed scene of reflectance 1).
#[derive(Clone, Copy, Debug, Default)]
pub struct PathEnd {
    pub collisions: u64,
    pub truncated: bool,
}

/// A vertex of a light path as the walk meets it: a connection vertex, or a collision on a
/// specular surface (where no connection can start: a delta BSDF has no value towards a given
/// point).
enum Step {
    Vertex(LightVertex),
    Specular { sp: SurfacePoint, dir: Vec3 },
}

/// Traces one light path from an emitter chosen by flux (at most `max_depth` collisions) and
/// calls `visit(vertex, q)` at every vertex a connection can start from — the emission point of
/// an area emitter, and every collision on a non-specular surface — with the flux weight `q`
/// arriving there. The walk is [`scatter`]'s (analog Russian roulette, geometric normals).
pub fn walk_light_path(
    world: &World,
    rng: &mut Rng,
    max_depth: u32,
    mut visit: impl FnMut(LightVertex, Rgb),
) -> PathEnd {
    walk(world, rng, max_depth, |step, q| {
        if let Step::Vertex(v) = step {
            visit(v, q);
        }
    })
}

/// The same walk (the same random numbers) as [`walk_light_path`], calling `land(sp, dir, q)`
/// at every collision, specular ones included, with the direction `dir` the light arrived
/// along: where a photon lands, for direct simulation.
pub fn walk_photon(
    world: &World,
    rng: &mut Rng,
    max_depth: u32,
    mut land: impl FnMut(&SurfacePoint, Vec3, Rgb),
) -> PathEnd {
    walk(world, rng, max_depth, |step, q| match step {
        Step::Vertex(LightVertex::Collision { sp, dir, .. }) | Step::Specular { sp, dir } => {
            land(&sp, dir, q)
        }
        Step::Vertex(LightVertex::Emission { .. }) => {}
    })
}

/// The light-path walk behind [`walk_light_path`] and [`walk_photon`].
fn walk(world: &World, rng: &mut Rng, max_depth: u32, mut visit: impl FnMut(Step, Rgb)) -> PathEnd {
    let e = world.sample_emission(rng);
    let mut q = e.flux;
    let mut origin = e.position;
    let mut arrival = if e.environment {
        Arrival::Environment
    } else {
        Arrival::DeltaLight
    };
    if let Some(n) = e.normal {
        visit(
            Step::Vertex(LightVertex::Emission {
                position: e.position,
                normal: n,
            }),
            q,
        );
        origin = world.offset(e.position, n, e.direction);
        // Area emitters emit with a cosine distribution.
        arrival = Arrival::Sampled {
            from: e.position,
            pdf: n.dot(e.direction) / std::f64::consts::PI,
        };
    }
    let mut dir = e.direction;
    // A point light or luminaire source may sit on a surface: its first ray starts beyond.
    let mut from_source = e.normal.is_none() && !e.environment;
    let mut end = PathEnd::default();
    for depth in 0..max_depth {
        let hit = if from_source {
            world.intersect_from_source(origin, dir)
        } else {
            world.intersect(origin, dir)
        };
        from_source = false;
        let Some(sp) = hit else {
            return end;
        };
        end.collisions += 1;
        let delta = bsdf::is_delta(&world.material_seen(&sp, -dir));
        let step = if delta {
            Step::Specular { sp, dir }
        } else {
            Step::Vertex(LightVertex::Collision {
                sp,
                dir,
                arrival,
                depth,
            })
        };
        visit(step, q);
        let Some(s) = scatter(world, &sp, dir, q, Transport::Flux, rng) else {
            return end;
        };
        // The sample's lobe, not the material, tells: a smooth plastic's coating or a blend's
        // mirror is a delta lobe of a material that also has a density.
        arrival = if s.pdf == 0.0 {
            Arrival::Specular
        } else {
            Arrival::Sampled {
                from: sp.position,
                pdf: s.pdf,
            }
        };
        (q, origin, dir) = (s.beta, s.origin, s.dir);
    }
    end.truncated = true;
    end
}

/// One step of a random walk: samples the BSDF in the shading frame at `sp` (with the light
/// paths' rules for `Transport::Flux`, [`luxest_render::shading`]) for a path that arrived
/// along `dir` with throughput `beta`, applies analog Russian roulette (survival
/// probability = the sample's weight, at most 1, see [`survival`]); `None` when the path ends.
pub fn scatter(
    world: &World,
    sp: &SurfacePoint,
    dir: Vec3,
    beta: Rgb,
    mode: Transport,
    rng: &mut Rng,
) -> Option<Scattered> {
    let m = world.material_seen(sp, -dir);
    let s = world.shading_of(sp, -dir).sample(&m, -dir, rng, mode)?;
    let survival = survival(s.weight);
    if survival <= 0.0 || rng.next_f64() >= survival {
        return None;
    }
    Some(Scattered {
        beta: beta * s.weight * (1.0 / survival),
        origin: world.offset(sp.position, sp.ng, s.wi),
        dir: s.wi,
        pdf: if s.delta { 0.0 } else { s.pdf * survival },
    })
}

/// The roulette's survival probability of a walk that sampled a direction of weight
/// `f cos / pdf`.
#[inline]
pub fn survival(weight: Rgb) -> f64 {
    weight.max_component().min(1.0)
}

/// The response of sensor `s` to light from `v` (not normalised, length `d`): for planar
/// sensors computed as `n·v / d`, as it always was, so their results do not change by a bit.
fn response_toward(s: &SensorPoint, v: Vec3, d: f64) -> f64 {
    match s.kind {
        IlluminanceKind::Planar => s.normal.dot(v) / d,
        _ => s.response(v / d),
    }
}

/// Exact direct illuminance from the delta lights (point sources, luminaires), RGB, with
/// visibility.
pub fn delta_light_illuminance(world: &World, sensors: &[SensorPoint]) -> Vec<Rgb> {
    let emitters = world.scene.header.emitters.len();
    sensors
        .iter()
        .map(|s| {
            let mut e = Rgb::BLACK;
            for ei in 0..emitters {
                world.for_each_delta_source(ei, s.position, |position, intensity_rgb| {
                    let v = position - s.position;
                    let d2 = v.length_squared();
                    let cos = response_toward(s, v, d2.sqrt());
                    if cos > 0.0 && d2 > 0.0 {
                        let from = position;
                        let blocked = world.occluded(from, s.position);
                        if !blocked {
                            e = e + intensity_rgb * (cos / d2);
                        }
                    }
                });
            }
            e
        })
        .collect()
}

/// Exact delta-light (point source, luminaire) luminance towards the camera at view points
/// given as (position, (geometric normal, mesh shading normal), direction to the camera,
/// (triangle, texture coordinates), weight).
pub type ViewedPoint = (Vec3, (Vec3, Vec3), Vec3, (u32, [f64; 2]), Rgb);

/// [`delta_light_illuminance`]'s counterpart for view points: the luminance they reflect.
pub fn delta_light_reflected(world: &World, points: &[ViewedPoint]) -> Vec<Rgb> {
    let emitters = world.scene.header.emitters.len();
    points
        .iter()
        .map(|&(x, (ng, ns), wo, (triangle, uv), weight)| {
            let m = world.material_at(triangle, uv, wo, ns);
            let m = &*m;
            let shading = world.shading(triangle, uv, (ng, ns), wo);
            let mut l = Rgb::BLACK;
            for ei in 0..emitters {
                world.for_each_delta_source(ei, x, |position, intensity_rgb| {
                    let v = position - x;
                    let d2 = v.length_squared();
                    if d2 <= 0.0 {
                        return;
                    }
                    let w = v / d2.sqrt();
                    let f = shading.eval(m, wo, w, Transport::Radiance);
                    if f.max_component() > 0.0 && !world.occluded(world.offset(x, ng, w), position)
                    {
                        l = l + intensity_rgb * f * (1.0 / d2);
                    }
                });
            }
            l * weight
        })
        .collect()
}

/// A direction about a sensor for its environment term, with its solid-angle density:
/// cosine-distributed about the normal for planar sensors, uniform over the sphere for the
/// others (which respond to light from every side).
fn sensor_direction(s: &SensorPoint, rng: &mut Rng) -> (Vec3, f64) {
    if s.kind.is_planar() {
        let local = cosine_hemisphere(rng.next_f64(), rng.next_f64());
        let (t, b) = s.normal.orthonormal_basis();
        (
            t * local.x + b * local.y + s.normal * local.z,
            local.z / std::f64::consts::PI,
        )
    } else {
        (
            uniform_sphere(rng.next_f64(), rng.next_f64()),
            0.25 / std::f64::consts::PI,
        )
    }
}

/// The density of [`sensor_direction`] for `w`.
fn sensor_direction_pdf(s: &SensorPoint, w: Vec3) -> f64 {
    if s.kind.is_planar() {
        s.normal.dot(w).max(0.0) / std::f64::consts::PI
    } else {
        0.25 / std::f64::consts::PI
    }
}

/// One sample of the direct illuminance from the environment at sensor `s` (RGB, lx; black
/// without an environment): E = ∫ L(ω) g(ω) V(ω) dω, from a direction drawn from the map (through
/// the window portals where the scene has any: [`World::sample_environment`]) and
/// one drawn about the sensor ([`sensor_direction`]), combined by the balance heuristic, each
/// tested with a shadow ray to infinity. Two shadow rays at most; `shadow_rays` counts them.
pub fn environment_illuminance(
    world: &World,
    s: &SensorPoint,
    rng: &mut Rng,
    shadow_rays: &mut u64,
) -> Rgb {
    let Some(env) = world.environment() else {
        return Rgb::BLACK;
    };
    let mut e = Rgb::BLACK;
    let mut seen = |w: Vec3| {
        *shadow_rays += 1;
        world.escapes(world.offset(s.position, s.normal, w), w)
    };
    // None where the portals are in use and the sensor sees none (density 0 there).
    if let Some(from_map) = world.sample_environment(s.position, rng.next_f64(), rng.next_f64()) {
        let g = s.response(from_map.direction);
        if g > 0.0 && from_map.pdf > 0.0 && seen(from_map.direction) {
            let p_s = sensor_direction_pdf(s, from_map.direction);
            e = e + from_map.radiance * (g / (from_map.pdf + p_s));
        }
    }
    let (w, p_s) = sensor_direction(s, rng);
    let g = s.response(w);
    if g > 0.0 && p_s > 0.0 {
        let l = env.radiance(w);
        if l.max_component() > 0.0 && seen(w) {
            e = e + l * (g / (p_s + world.environment_pdf(s.position, w)));
        }
    }
    e
}

/// One sample of the environment's light reflected at the surface point `x` (shading frame
/// `shading`, material `m`) towards `wo` (RGB luminance; black without an environment): a
/// direction drawn from the map (through the portals, as above) and one drawn from the BSDF,
/// combined by the balance heuristic
/// (a delta lobe's sample has weight 1: the map cannot draw it), each with a shadow ray to
/// infinity.
pub fn environment_reflected(
    world: &World,
    (x, shading, wo): (Vec3, &Shading, Vec3),
    m: &luxest_render::scene::Material,
    rng: &mut Rng,
) -> Rgb {
    let Some(env) = world.environment() else {
        return Rgb::BLACK;
    };
    let mut l = Rgb::BLACK;
    let ng = shading.ng;
    let seen = |w: Vec3| world.escapes(world.offset(x, ng, w), w);
    if let Some(from_map) = world.sample_environment(x, rng.next_f64(), rng.next_f64()) {
        let w = from_map.direction;
        let (f, p_b) = shading.eval_and_pdf(m, wo, w, Transport::Radiance);
        if f.max_component() > 0.0 && from_map.pdf > 0.0 && seen(w) {
            l = l + f * from_map.radiance * (1.0 / (from_map.pdf + p_b));
        }
    }
    if let Some(b) = shading.sample(m, wo, rng, Transport::Radiance) {
        let radiance = env.radiance(b.wi);
        if radiance.max_component() > 0.0 && b.weight.max_component() > 0.0 {
            let weight = if b.delta {
                1.0
            } else {
                b.pdf / (b.pdf + world.environment_pdf(x, b.wi))
            };
            if weight > 0.0 && seen(b.wi) {
                l = l + b.weight * radiance * weight;
            }
        }
    }
    l
}
