//! The double local estimate of a luminance image.
//!
//! The point each camera sample sees (after following mirror and glass bounces) becomes a
//! sensor with a BRDF: every collision j of every light path contributes to every such point
//! p the luminance `Q_j f_j cos_j cos_p / d² V(j, p) f_p(→ camera)`. Point-source light is
//! added exactly, emitters seen directly with their luminance.
//!
//! Naively that is (collisions × pixels) shadow rays. The work is organised so that it runs at
//! Embree's stream rate: light paths are traced first and their collisions stored (a few per
//! path); then each worker takes a tile of 16 × 16 pixels and, for every stored collision,
//! casts the tile's shadow rays towards it as one coherent stream (`rtcOccluded1M`). Pixels of
//! a tile are independent and collisions are visited in a fixed order, so the image is
//! bit-identical at any thread count. Per-pixel standard errors come from 8 batches of paths.

use crate::singularity::Singularity;
use crate::transport::{point_source_direct_to, scatter};
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_render::bsdf::{self, Transport};
use luxest_render::camera::{stratified_pixel_jitter, PinholeCamera};
use luxest_render::parallel::run_batches;
use luxest_render::rt::Ray;
use luxest_render::sampling::Rng;
use luxest_render::scene::Material;
use luxest_render::world::World;

pub const TILE: usize = 16;
/// Batches for the per-pixel standard error.
pub const BATCHES: usize = 8;

#[derive(Clone, Debug)]
pub struct ImageConfig {
    pub paths: u64,
    pub pixel_samples: u32,
    pub seed: u64,
    pub threads: usize,
    pub singularity: Singularity,
    pub max_depth: u32,
}

pub struct ImageResult {
    pub width: usize,
    pub height: usize,
    /// Mean luminance per pixel, cd/m² per channel.
    pub rgb: Vec<Rgb>,
    /// Standard error of the pixel's Y.
    pub standard_error: Vec<f64>,
    pub collisions: u64,
    pub shadow_rays: u64,
    pub seconds: f64,
}

/// A non-specular point seen by a camera sample.
#[derive(Clone, Copy)]
struct ViewPoint {
    pixel: usize,
    position: Vec3,
    ng: Vec3,
    /// Direction towards the camera (along the specular chain).
    wo: Vec3,
    material: u32,
    /// Throughput of the specular chain, divided by the samples per pixel.
    weight: Rgb,
}

/// A light-path vertex stored for connection.
#[derive(Clone, Copy)]
struct Record {
    position: Vec3,
    ng: Vec3,
    /// Direction the light came from (collisions), or the emitter normal (emission points).
    wo: Vec3,
    q: Rgb,
    /// Material triangle for collisions; `None` for emission points.
    triangle: Option<u32>,
}

/// Salt of the seed of the view points' random streams (one per pixel, for sampling the
/// specular bounces between the camera and the first non-specular surface), so that they never
/// coincide with the light paths' streams (the run's seed, streams 1..=batches).
const VIEW_POINT_SEED_SALT: u64 = 0x5eed_0f1e;

fn view_points(
    world: &World,
    cam: &PinholeCamera,
    cfg: &ImageConfig,
    emitted: &mut [Rgb],
) -> Vec<ViewPoint> {
    let (w, h) = (cam.width as usize, cam.height as usize);
    let spp = cfg.pixel_samples.max(1);
    let mut out = Vec::with_capacity(w * h);
    for (pixel, emitted_px) in emitted.iter_mut().enumerate() {
        let mut rng = Rng::new(cfg.seed ^ VIEW_POINT_SEED_SALT, pixel as u64);
        for k in 0..spp {
            // Stratified over the pixel (box filter): the view points are fixed for the run, so
            // their footprint error is not in the batches' standard error.
            let (u, v) = stratified_pixel_jitter(cfg.seed, pixel as u64, k, spp);
            let sx = (pixel % w) as f64 + u;
            let sy = (pixel / w) as f64 + v;
            let mut dir = cam.direction(sx, sy);
            let mut origin = cam.position;
            let mut weight = Rgb::splat(1.0 / spp as f64);
            for _ in 0..16 {
                let Some(sp) = world.intersect(origin, dir) else {
                    break;
                };
                *emitted_px =
                    *emitted_px + weight * world.emitted_radiance(sp.triangle, sp.ng, -dir);
                let m = world.material(sp.triangle);
                if !bsdf::is_delta(m) {
                    out.push(ViewPoint {
                        pixel,
                        position: sp.position,
                        ng: sp.ng,
                        wo: -dir,
                        material: sp.triangle,
                        weight,
                    });
                    break;
                }
                let Some(s) = bsdf::sample_flat(m, -dir, sp.ng, &mut rng, Transport::Radiance)
                else {
                    break;
                };
                weight = weight * s.weight;
                origin = world.offset(sp.position, sp.ng, s.wi);
                dir = s.wi;
            }
        }
    }
    out
}

fn light_records(world: &World, cfg: &ImageConfig, batch: usize, paths: u64) -> Vec<Record> {
    let mut rng = Rng::new(cfg.seed, batch as u64 + 1);
    let mut out = Vec::new();
    for _ in 0..paths {
        let e = world.sample_emission(&mut rng);
        let mut q = e.flux;
        let mut origin = e.position;
        if let Some(n) = e.normal {
            out.push(Record {
                position: e.position,
                ng: n,
                wo: n,
                q,
                triangle: None,
            });
            origin = world.offset(e.position, n, e.direction);
        }
        let mut dir = e.direction;
        for _ in 0..cfg.max_depth {
            let Some(sp) = world.intersect(origin, dir) else {
                break;
            };
            let m = world.material(sp.triangle);
            if !bsdf::is_delta(m) {
                out.push(Record {
                    position: sp.position,
                    ng: sp.ng,
                    wo: -dir,
                    q,
                    triangle: Some(sp.triangle),
                });
            }
            let Some((next_q, next_origin, next_dir)) =
                scatter(world, &sp, dir, q, Transport::Flux, &mut rng)
            else {
                break;
            };
            (q, origin, dir) = (next_q, next_origin, next_dir);
        }
    }
    out
}

/// Connection value from record `r` to view point `v` (without visibility).
fn contribution(
    world: &World,
    sing: &Singularity,
    r: &Record,
    v: &ViewPoint,
    m_v: &Material,
) -> Option<(Rgb, Vec3)> {
    let d = v.position - r.position;
    let d2 = d.length_squared();
    if d2 <= 0.0 {
        return None;
    }
    let dist = d2.sqrt();
    let w = d / dist; // from the record to the view point
                      // BRDF at the view point, light arriving from -w, leaving towards the camera.
    let f_v = bsdf::eval(m_v, v.wo, -w, v.ng, v.ng) * (w.dot(v.ng).abs());
    if f_v.max_component() <= 0.0 {
        return None;
    }
    let f_r = match r.triangle {
        None => {
            let c = r.ng.dot(w);
            if c <= 0.0 {
                return None;
            }
            Rgb::splat(c / std::f64::consts::PI)
        }
        Some(t) => bsdf::eval(world.material(t), r.wo, w, r.ng, r.ng) * w.dot(r.ng).abs(),
    };
    let c = r.q * f_r * f_v * v.weight * sing.inverse_square(d2);
    (c.max_component() > 0.0).then_some((c, w))
}

/// Renders the double-local-estimate image of the scene's camera.
pub fn render(world: &World, cam: &PinholeCamera, cfg: &ImageConfig) -> ImageResult {
    let start = std::time::Instant::now();
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mut emitted = vec![Rgb::BLACK; w * h];
    let views = view_points(world, cam, cfg, &mut emitted);
    // Exact point-source light at the view points.
    let direct = point_source_direct_to(
        world,
        &views
            .iter()
            .map(|v| (v.position, v.ng, v.wo, v.material, v.weight))
            .collect::<Vec<_>>(),
    );
    let per_batch =
        |b: usize| cfg.paths / BATCHES as u64 + u64::from((b as u64) < cfg.paths % BATCHES as u64);
    let records = run_batches(BATCHES, cfg.threads, "light paths", |b| {
        light_records(world, cfg, b, per_batch(b))
    });
    let collisions: u64 = records.iter().map(|r| r.len() as u64).sum();

    // Tiles of the image, each with the indices of its view points.
    let tiles_x = w.div_ceil(TILE);
    let tiles_y = h.div_ceil(TILE);
    let mut tile_views: Vec<Vec<usize>> = vec![Vec::new(); tiles_x * tiles_y];
    for (i, v) in views.iter().enumerate() {
        let (x, y) = (v.pixel % w, v.pixel / w);
        tile_views[(y / TILE) * tiles_x + x / TILE].push(i);
    }
    let tile_results = run_batches(
        tile_views.len(),
        cfg.threads,
        "double local estimate",
        |t| {
            let idx = &tile_views[t];
            // Per batch, per view point in this tile.
            let mut acc = vec![vec![Rgb::BLACK; idx.len()]; BATCHES];
            let mut rays = Vec::with_capacity(idx.len());
            let mut targets = Vec::with_capacity(idx.len());
            let mut blocked = Vec::new();
            let mut shadow_rays = 0u64;
            for (b, recs) in records.iter().enumerate() {
                for r in recs {
                    rays.clear();
                    targets.clear();
                    for (k, &vi) in idx.iter().enumerate() {
                        let v = &views[vi];
                        let m_v = world.material(v.material);
                        if let Some((c, dir_to_view)) =
                            contribution(world, &cfg.singularity, r, v, m_v)
                        {
                            // Cast from the view point towards the record (coherent across the
                            // tile), measured from the offset origin so it stops short of it.
                            let origin = world.offset(v.position, v.ng, -dir_to_view);
                            let to = r.position - origin;
                            let len = to.length();
                            let eps = world.margin(v.position, r.position);
                            if len > 2.0 * eps {
                                rays.push(Ray {
                                    origin,
                                    direction: to / len,
                                    tnear: eps,
                                    tfar: len - eps,
                                });
                                targets.push((k, c));
                            }
                        }
                    }
                    shadow_rays += rays.len() as u64;
                    world.tracer.occluded_many(&rays, &mut blocked);
                    for ((k, c), bl) in targets.iter().zip(&blocked) {
                        if !bl {
                            acc[b][*k] = acc[b][*k] + *c;
                        }
                    }
                }
            }
            (acc, shadow_rays)
        },
    );

    // Combine: per pixel and batch, mean over the batch's paths.
    let mut batch_pixels = vec![vec![Rgb::BLACK; w * h]; BATCHES];
    let mut shadow_rays = 0;
    for (t, (acc, rays)) in tile_results.into_iter().enumerate() {
        shadow_rays += rays;
        for (b, vals) in acc.into_iter().enumerate() {
            let n = per_batch(b).max(1) as f64;
            for (k, c) in vals.into_iter().enumerate() {
                let p = views[tile_views[t][k]].pixel;
                batch_pixels[b][p] = batch_pixels[b][p] + c * (1.0 / n);
            }
        }
    }
    let mut fixed = emitted;
    for (v, d) in views.iter().zip(&direct) {
        fixed[v.pixel] = fixed[v.pixel] + *d;
    }
    let mut rgb = vec![Rgb::BLACK; w * h];
    let mut standard_error = vec![0.0; w * h];
    for p in 0..w * h {
        let ys: Vec<f64> = (0..BATCHES)
            .map(|b| batch_pixels[b][p].luminance())
            .collect();
        let (_, se) = luxest_render::parallel::mean_and_standard_error(&ys);
        let mut m = Rgb::BLACK;
        for bp in &batch_pixels {
            m = m + bp[p] * (1.0 / BATCHES as f64);
        }
        rgb[p] = m + fixed[p];
        standard_error[p] = se;
    }
    ImageResult {
        width: w,
        height: h,
        rgb,
        standard_error,
        collisions,
        shadow_rays,
        seconds: start.elapsed().as_secs_f64(),
    }
}
