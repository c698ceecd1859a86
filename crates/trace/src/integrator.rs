//! The path tracer: radiance along a camera ray.
//!
//! Unidirectional path tracing with next-event estimation (one light point per vertex, the
//! light chosen by the world's light sampler: by importance at the vertex through the light
//! BVH, or by flux) combined with BSDF sampling by multiple importance sampling (power heuristic) for
//! area emitters; point sources and goniometric luminaires, being deltas, are reached by
//! next-event estimation only (a luminaire's light point carries its intensity towards the
//! shading point). Russian roulette after every bounce as a weight window: survival probability
//! min(0.95, max throughput / 0.25), so paths whose throughput is still high go on, and
//! survivors carry a throughput of about 0.25 (starting roulette at the fourth vertex with
//! survival min(0.95, max throughput) cost 1.2× the CPU time to equal error on the Cornell box
//! and 3.3× on the 1M-triangle room: it cut the deep bounces that carry those rooms' indirect
//! light; docs/measurements.md has the window's width measured).
//! Scattering happens in the shading frame as Mitsuba 3's `path` does it
//! ([`luxest_render::shading`]): interpolated vertex normals and normal maps, the cosine about
//! the shading normal, no test against the geometric normal; rays leave on the geometric side
//! they point to.
//!
//! Environment light ([`luxest_render::environment`]): a path that leaves the scene gathers the
//! environment's radiance along its last direction, weighted by the power heuristic against
//! next-event estimation of the environment (at every non-delta vertex one direction drawn
//! from its map — through the window portals where the scene has any,
//! [`luxest_render::portal`] — besides the light point, tested with a shadow ray to infinity); a camera ray
//! or a specular bounce that escapes takes it with weight 1. Spot lights are point sources whose
//! light point carries the falloff towards the shading point.
//!
//! The features manifest selects a monomorphised variant: the code for point sources, area
//! emitters, specular materials, and for the environment, textures and one-sided surfaces, is
//! compiled out of the variants of scenes without them.

use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_render::bsdf::{self, Transport};
use luxest_render::rt::Ray;
use luxest_render::sampling::Sampler;
use luxest_render::shading::Shading;
use luxest_render::sobol::PixelSampler;
use luxest_render::world::World;
use std::borrow::Cow;

/// Rays traced, for rates; optionally every ray, to time raw Embree on the same rays.
#[derive(Default)]
pub struct RayLog {
    pub closest: u64,
    pub shadow: u64,
    pub record: bool,
    pub closest_rays: Vec<Ray>,
    pub shadow_rays: Vec<Ray>,
    /// The bounce each recorded ray belongs to (0: the camera ray and its shadow ray).
    pub closest_depths: Vec<u32>,
    pub shadow_depths: Vec<u32>,
}

/// Russian roulette's weight window: a path survives with probability
/// min(0.95, max throughput / RR_WEIGHT), so survivors carry about RR_WEIGHT.
const RR_WEIGHT: f64 = 0.25;

fn power_heuristic(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

/// Signature of a radiance kernel.
pub type Kernel = fn(&World, Vec3, Vec3, &mut PixelSampler, u32, &mut RayLog) -> Rgb;

/// Radiance arriving at `origin` from direction `dir`.
pub fn radiance<const POINT: bool, const AREA: bool, const SPECULAR: bool, const EXTRA: bool>(
    world: &World,
    origin: Vec3,
    dir: Vec3,
    rng: &mut PixelSampler,
    max_depth: u32,
    log: &mut RayLog,
) -> Rgb {
    let mut l = Rgb::BLACK;
    let mut beta = Rgb::WHITE;
    let (mut origin, mut dir) = (origin, dir);
    // Solid-angle pdf of the BSDF sample that produced `dir`, and whether it was a delta.
    let mut bsdf_pdf = 0.0;
    let mut delta = true;
    // The vertex `dir` leaves from and its geometric normal (the receiver of the light choice
    // there).
    let mut from_vertex = origin;
    let mut from_normal = None;
    for depth in 0..max_depth {
        rng.start_bounce(depth);
        log.closest += 1;
        if log.record {
            log.closest_depths.push(depth);
            log.closest_rays.push(Ray {
                origin,
                direction: dir,
                tnear: 0.0,
                tfar: f64::INFINITY,
            });
        }
        let Some(sp) = world.intersect(origin, dir) else {
            if EXTRA && world.environment().is_some() {
                let le = world.environment_radiance(dir);
                let w = if delta {
                    1.0
                } else {
                    power_heuristic(bsdf_pdf, world.environment_pdf(from_vertex, dir))
                };
                l = l + beta * le * w;
            }
            break;
        };
        let wo = -dir;
        if AREA {
            let emission = if EXTRA {
                world.emission(&sp, wo)
            } else {
                world.emission_plain(sp.triangle, sp.ng, wo)
            };
            if let Some((e, le)) = emission {
                {
                    let w = if delta {
                        1.0
                    } else {
                        let cos_l = sp.ng.dot(wo).abs();
                        let light_pdf = world.light_point_pdf_facing(e, from_vertex, from_normal)
                            * sp.distance
                            * sp.distance
                            / cos_l;
                        power_heuristic(bsdf_pdf, light_pdf)
                    };
                    l = l + beta * le * w;
                }
            }
        }
        let m = if EXTRA {
            world.material_seen(&sp, wo)
        } else {
            Cow::Borrowed(world.material(sp.triangle))
        };
        let m = &*m;
        // The frame scattering happens in; flat scenes' kernels use none (`f_cos` and the
        // sampling below call the BSDF about the geometric normal, as they always did).
        let shading = if EXTRA {
            world.shading_of(&sp, wo)
        } else {
            Shading::flat(sp.ng)
        };
        let f_cos = |w: Vec3| {
            if EXTRA {
                shading.eval_and_pdf(m, wo, w, Transport::Radiance)
            } else {
                let (f, p) = bsdf::eval_and_pdf(m, wo, w, sp.ng, sp.ng);
                (f * w.dot(sp.ng).abs(), p)
            }
        };
        let is_delta = SPECULAR && bsdf::is_delta(m);
        if !is_delta && (POINT || AREA) {
            // Next-event estimation.
            let lp = world.sample_light_point_facing(rng, sp.position, Some(sp.ng));
            let v = lp.position - sp.position;
            let d2 = v.length_squared();
            if d2 > 0.0 {
                let d = d2.sqrt();
                let w = v / d;
                let (f, bp) = f_cos(w);
                if f.max_component() > 0.0 {
                    let contribution = match lp.normal {
                        Some(nl) if AREA => {
                            let cos_l = -nl.dot(w);
                            if cos_l > 0.0 {
                                let light_pdf = lp.pdf * d2 / cos_l;
                                f * lp.emitted * (power_heuristic(light_pdf, bp) / light_pdf)
                            } else {
                                Rgb::BLACK
                            }
                        }
                        None if POINT => f * lp.emitted * (1.0 / (d2 * lp.pdf)),
                        _ => Rgb::BLACK,
                    };
                    if contribution.max_component() > 0.0 {
                        log.shadow += 1;
                        let from = world.offset(sp.position, sp.ng, w);
                        if log.record {
                            log.shadow_depths.push(depth);
                            log.shadow_rays.push(Ray {
                                origin: from,
                                direction: w,
                                tnear: 0.0,
                                tfar: d,
                            });
                        }
                        if !world.occluded(from, lp.position) {
                            l = l + beta * contribution;
                        }
                    }
                }
            }
        }
        if let (true, false, true) = (EXTRA, is_delta, world.environment().is_some()) {
            // Next-event estimation of the environment: one direction from its map (through
            // the portals, where the scene has any), besides the light point above.
            let (u1, u2) = rng.next_2d();
            // None at a point that sees no portal (BSDF sampling alone finds its sky).
            if let Some(es) = world.sample_environment(sp.position, u1, u2) {
                let w = es.direction;
                let (f, bp) = f_cos(w);
                if es.pdf > 0.0 && f.max_component() > 0.0 {
                    let contribution = f * es.radiance * (power_heuristic(es.pdf, bp) / es.pdf);
                    log.shadow += 1;
                    let from = world.offset(sp.position, sp.ng, w);
                    if log.record {
                        log.shadow_depths.push(depth);
                        log.shadow_rays.push(Ray {
                            origin: from,
                            direction: w,
                            tnear: 0.0,
                            tfar: f64::INFINITY,
                        });
                    }
                    if world.escapes(from, w) {
                        l = l + beta * contribution;
                    }
                }
            }
        }
        let sampled = if EXTRA {
            shading.sample(m, wo, rng, Transport::Radiance)
        } else {
            bsdf::sample_flat(m, wo, sp.ng, rng, Transport::Radiance)
        };
        let Some(s) = sampled else {
            break;
        };
        beta = beta * s.weight;
        bsdf_pdf = s.pdf;
        delta = s.delta;
        if depth >= 1 {
            let q = (beta.max_component() / RR_WEIGHT).min(0.95);
            if q <= 0.0 || rng.next_f64() >= q {
                break;
            }
            beta = beta * (1.0 / q);
        }
        if beta.max_component() <= 0.0 {
            break;
        }
        origin = world.offset(sp.position, sp.ng, s.wi);
        from_vertex = sp.position;
        from_normal = Some(sp.ng);
        dir = s.wi;
    }
    l
}

/// The kernel variant for a scene's features.
pub fn kernel_for(world: &World) -> Kernel {
    let f = &world.scene.header.features;
    // A luminaire is a delta light like an isotropic point: the same next-event code serves
    // it (`sample_light_point` returns its intensity towards the receiver).
    let delta_lights = f.point_emitters || f.goniometric_luminaires;
    // Textures, one-sided surfaces, the environment and shading normals (vertex normals,
    // normal maps): compiled out where the scene has none.
    let env = f.environment || f.textures || f.one_sided || f.smooth_normals || f.normal_maps;
    match (delta_lights, f.area_emitters, f.specular_paths) {
        (true, true, true) => with_environment::<true, true, true>(env),
        (true, true, false) => with_environment::<true, true, false>(env),
        (true, false, true) => with_environment::<true, false, true>(env),
        (true, false, false) => with_environment::<true, false, false>(env),
        (false, true, true) => with_environment::<false, true, true>(env),
        (false, true, false) => with_environment::<false, true, false>(env),
        (false, false, true) => with_environment::<false, false, true>(env),
        (false, false, false) => with_environment::<false, false, false>(env),
    }
}

/// The variant with or without the code for the environment, textures and one-sided surfaces.
fn with_environment<const POINT: bool, const AREA: bool, const SPECULAR: bool>(
    env: bool,
) -> Kernel {
    if env {
        radiance::<POINT, AREA, SPECULAR, true>
    } else {
        radiance::<POINT, AREA, SPECULAR, false>
    }
}
