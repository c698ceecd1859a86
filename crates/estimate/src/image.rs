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
//!
//! Pixel footprint: the camera points are drawn anew for every [`ROUND_PATHS`] light paths
//! (`pixel_samples` of them per pixel, stratified over the pixel), and a round's light paths
//! connect to its own points only. Each light path with the points it sees is then an unbiased
//! sample of the box-filtered pixel, so the image converges to the same pixel values as
//! `trace` as the path count grows (one fixed point per pixel could not), and the footprint's
//! variation is part of the batches' standard error.

use crate::singularity::Singularity;
use crate::transport::{point_source_direct_to, walk_light_path, LightVertex};
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_render::bsdf::{self, Transport};
use luxest_render::camera::{stratified_pixel_jitter, PinholeCamera};
use luxest_render::parallel::run_batches;
use luxest_render::rt::Ray;
use luxest_render::sampling::{splitmix64, Rng};
use luxest_render::scene::Material;
use luxest_render::world::World;

pub const TILE: usize = 16;
/// Batches for the per-pixel standard error.
pub const BATCHES: usize = 8;
/// Light paths that share one draw of camera points. Redrawing costs a tile's camera rays (and
/// the exact delta-light terms) per round, about 1 % of the connections' shadow rays at 3
/// collisions per path.
pub const ROUND_PATHS: u64 = 32;

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
    /// Index of the light path within its batch (its round is `path / ROUND_PATHS`).
    path: u64,
}

/// Russian roulette threshold of the connections, as a multiple of the pixel's running mean
/// connected light per path (see `render`). Measured on the Cornell box 256², 2000 paths
/// (docs/measurements.md): 0 (off) 240 M shadow rays, relMSE 2.13e-3 in 25.1 CPU-s; 1: 125 M,
/// 2.17e-3 in 18.7; 3: 71 M, 2.35e-3 in 15.3 (1.5x the efficiency of no roulette); 10: 45 M,
/// 3.07e-3 in 13.9. The rest of the time is evaluating every pair's contribution.
pub const RR_ALPHA: f64 = 3.0;
/// Salt of the connections' roulette numbers.
const RR_SALT: u64 = 0x00c0_ffee_5a17;

/// Salt of the seed of the view points' random streams (one per pixel, for sampling the
/// specular bounces between the camera and the first non-specular surface), so that they never
/// coincide with the light paths' streams (the run's seed, streams 1..=batches).
const VIEW_POINT_SEED_SALT: u64 = 0x5eed_0f1e;

/// The camera points of `pixels` for round `round` (`pixel_samples` per pixel, stratified over
/// the pixel), and per listed pixel the emitted luminance its samples see directly.
fn view_points(
    world: &World,
    cam: &PinholeCamera,
    cfg: &ImageConfig,
    pixels: &[usize],
    round: u64,
) -> (Vec<ViewPoint>, Vec<Rgb>) {
    let w = cam.width as usize;
    let spp = cfg.pixel_samples.max(1);
    // Every round has its own jitter and specular-bounce streams.
    let round_seed = cfg.seed ^ luxest_render::sampling::splitmix64(round ^ VIEW_POINT_SEED_SALT);
    let mut out = Vec::with_capacity(pixels.len());
    let mut emitted = vec![Rgb::BLACK; pixels.len()];
    for (&pixel, emitted_px) in pixels.iter().zip(emitted.iter_mut()) {
        let mut rng = Rng::new(round_seed ^ VIEW_POINT_SEED_SALT, pixel as u64);
        for k in 0..spp {
            let (u, v) = stratified_pixel_jitter(round_seed, pixel as u64, k, spp);
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
    (out, emitted)
}

fn light_records(world: &World, cfg: &ImageConfig, batch: usize, paths: u64) -> Vec<Record> {
    let mut rng = Rng::new(cfg.seed, batch as u64 + 1);
    let mut out = Vec::new();
    for path in 0..paths {
        walk_light_path(world, &mut rng, cfg.max_depth, |v, q| {
            out.push(match v {
                LightVertex::Emission { position, normal } => Record {
                    position,
                    ng: normal,
                    wo: normal,
                    q,
                    triangle: None,
                    path,
                },
                LightVertex::Collision { sp, dir } => Record {
                    position: sp.position,
                    ng: sp.ng,
                    wo: -dir,
                    q,
                    triangle: Some(sp.triangle),
                    path,
                },
            })
        });
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
    let per_batch =
        |b: usize| cfg.paths / BATCHES as u64 + u64::from((b as u64) < cfg.paths % BATCHES as u64);
    let records = run_batches(BATCHES, cfg.threads, "light paths", |b| {
        light_records(world, cfg, b, per_batch(b))
    });
    let collisions: u64 = records.iter().map(|r| r.len() as u64).sum();
    let rounds_per_batch = per_batch(0).div_ceil(ROUND_PATHS).max(1);

    let tiles_x = w.div_ceil(TILE);
    let tiles_y = h.div_ceil(TILE);
    let tile_results = run_batches(
        tiles_x * tiles_y,
        cfg.threads,
        "double local estimate",
        |t| {
            let (x0, y0) = ((t % tiles_x) * TILE, (t / tiles_x) * TILE);
            let pixels: Vec<usize> = (y0..(y0 + TILE).min(h))
                .flat_map(|y| (x0..(x0 + TILE).min(w)).map(move |x| y * w + x))
                .collect();
            let tile_width = (x0 + TILE).min(w) - x0;
            let local = |p: usize| (p / w - y0) * tile_width + (p % w - x0);
            // Per batch, per pixel of this tile: sums over the batch's paths.
            let mut acc = vec![vec![Rgb::BLACK; pixels.len()]; BATCHES];
            let mut rays = Vec::with_capacity(pixels.len());
            let mut targets = Vec::with_capacity(pixels.len());
            let mut blocked = Vec::new();
            let mut shadow_rays = 0u64;
            for (b, recs) in records.iter().enumerate() {
                let n = per_batch(b);
                let mut next = 0;
                // Per pixel of the tile: this batch's connection contributions so far (Y).
                let mut connected = vec![0.0f64; pixels.len()];
                for r in 0..n.div_ceil(ROUND_PATHS).max(1) {
                    // This round's paths, its camera points and their path-independent terms
                    // (emitters seen directly, exact delta lights), counted once per path.
                    let paths_in_round = (n - (r * ROUND_PATHS).min(n)).clamp(1, ROUND_PATHS);
                    let round = b as u64 * rounds_per_batch + r;
                    // Russian roulette on the connections: a pair whose contribution c is
                    // below the threshold tau of its pixel is traced with probability c / tau
                    // and then counts c / (c / tau) = tau. tau is RR_ALPHA times the mean per
                    // path, so far in this batch, of the pixel's connected light (the exact
                    // terms left out; none in the first round), per camera point; unbiased for
                    // any tau that depends only on earlier paths.
                    let done = (r * ROUND_PATHS).min(n);
                    let spp = cfg.pixel_samples.max(1) as f64;
                    let tau: Vec<f64> = connected
                        .iter()
                        .map(|y| {
                            if done > 0 {
                                RR_ALPHA * y / (done as f64 * spp)
                            } else {
                                0.0
                            }
                        })
                        .collect();
                    let (views, emitted) = view_points(world, cam, cfg, &pixels, round);
                    let view_local: Vec<usize> = views.iter().map(|v| local(v.pixel)).collect();
                    let direct = point_source_direct_to(
                        world,
                        &views
                            .iter()
                            .map(|v| (v.position, v.ng, v.wo, v.material, v.weight))
                            .collect::<Vec<_>>(),
                    );
                    let weight = paths_in_round as f64;
                    for (k, e) in emitted.iter().enumerate() {
                        acc[b][k] = acc[b][k] + *e * weight;
                    }
                    for (&k, d) in view_local.iter().zip(&direct) {
                        acc[b][k] = acc[b][k] + *d * weight;
                    }
                    let end = (r + 1) * ROUND_PATHS;
                    while next < recs.len() && recs[next].path < end {
                        let rec = &recs[next];
                        let record_key = splitmix64(
                            cfg.seed ^ splitmix64(((b as u64) << 40) ^ next as u64 ^ RR_SALT),
                        );
                        next += 1;
                        rays.clear();
                        targets.clear();
                        for (i, (v, &k)) in views.iter().zip(&view_local).enumerate() {
                            let m_v = world.material(v.material);
                            if let Some((c, dir_to_view)) =
                                contribution(world, &cfg.singularity, rec, v, m_v)
                            {
                                let y = c.luminance();
                                let c = if y < tau[k] {
                                    let h = splitmix64(record_key ^ (i as u64));
                                    let u = (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
                                    if u * tau[k] >= y {
                                        continue;
                                    }
                                    c * (tau[k] / y)
                                } else {
                                    c
                                };
                                // Cast from the view point towards the record (coherent across
                                // the tile), measured from the offset origin so it stops short.
                                let origin = world.offset(v.position, v.ng, -dir_to_view);
                                let to = rec.position - origin;
                                let len = to.length();
                                let eps = world.margin(v.position, rec.position);
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
                                connected[*k] += c.luminance();
                            }
                        }
                    }
                }
            }
            (pixels, acc, shadow_rays)
        },
    );

    // Combine: per pixel and batch, the mean over the batch's paths.
    let mut batch_pixels = vec![vec![Rgb::BLACK; w * h]; BATCHES];
    let mut shadow_rays = 0;
    for (pixels, acc, rays) in tile_results {
        shadow_rays += rays;
        for (b, vals) in acc.into_iter().enumerate() {
            let n = per_batch(b).max(1) as f64;
            for (&p, c) in pixels.iter().zip(vals) {
                batch_pixels[b][p] = c * (1.0 / n);
            }
        }
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
        rgb[p] = m;
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
