//! The double local estimate of a luminance image.
//!
//! The point each camera sample sees (after following mirror and glass bounces) becomes a
//! sensor with a BRDF: every collision j of every light path contributes to every such point
//! p the luminance `Q_j f_j cos_j cos_p / d² V(j, p) f_p(→ camera)`. (A material with both,
//! such as a smooth plastic, is such a point for its density and is followed through its delta
//! lobe.) Point-source light is
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
//!
//! The kernel singularity: multiple importance sampling with light tracing. A path
//! `… y → x → camera`, x seen directly, is produced by two strategies from the same light
//! paths: the connection of the light vertex y to the camera point x (density `s p_cam(x)` per
//! light path, with s camera points per pixel and p_cam the camera ray's area density, see
//! `PinholeCamera::area_density`), and light tracing, which samples x from y (density
//! `p_y(y→x) cos_x / d²`, the roulette's survival included) and connects x to the camera. Each
//! gets its balance-heuristic weight, so the connection's `1/d²` becomes
//! `p_cam s / (d² p_cam s + p_y cos_x)`: bounded as d → 0 and unbiased, with no eps. Points seen
//! through mirrors or glass cannot be reached by light tracing; for them the connection keeps
//! its full weight and the `Singularity` treatment. A collision reached straight from a delta
//! light is left to the exact direct term. `--mis-paths 0` gives the plain connection with the
//! `Singularity` treatment everywhere (measured in docs/measurements.md).
//!
//! Diffuse (Lambertian or emitter) pairs, nearly all pairs of a room, take a short path that
//! needs no BSDF call: per record and per view point the constant factors are computed once.
//!
//! The environment: a camera ray (or its specular chain) that leaves the scene sees it; its
//! light reflected at a view point towards the camera is estimated there, once per round, by
//! [`crate::transport::environment_reflected`] (a direction from the map and one from the BSDF,
//! balance heuristic), so light tracing leaves collisions reached straight from the
//! environment to it, as it leaves those reached from delta lights to the exact term; light
//! paths from the environment connect from their first collision on.

use crate::image::{ImageResult, BATCHES};
use crate::light_tracing::connect_to_camera;
use crate::singularity::Singularity;
use crate::transport::{
    delta_light_reflected, environment_reflected, survival, walk_light_path, Arrival, LightVertex,
};
use luxest_io::cli::Console;
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_io::progress::Progress;
use luxest_render::bsdf::{self, Transport};
use luxest_render::camera::{pixel_jitter, PinholeCamera};
use luxest_render::parallel::run_batches;
use luxest_render::rt::Ray;
use luxest_render::sampling::{splitmix64, Rng};
use luxest_render::scene::Material;
use luxest_render::world::World;
use std::f64::consts::PI;

/// Side of the square tiles of pixels whose shadow rays are cast as one stream.
pub const TILE: usize = 16;
/// Light paths that share one draw of camera points. Redrawing costs a tile's camera rays (and
/// the exact delta-light terms) per round, about 1 % of the connections' shadow rays at 3
/// collisions per path.
pub const ROUND_PATHS: u64 = 32;

/// Bytes of a stored light-path vertex: every batch's are held until they are connected.
pub const RECORD_BYTES: u64 = std::mem::size_of::<Record>() as u64;
/// Bytes a tile in work keeps per camera point of a round: the point, the input and result of
/// its exact delta-light term, its pixel within the tile.
pub const VIEW_POINT_BYTES: u64 = (std::mem::size_of::<ViewPoint>()
    + std::mem::size_of::<(Vec3, Vec3, Vec3, u32, Rgb)>()
    + std::mem::size_of::<Rgb>()
    + std::mem::size_of::<usize>()) as u64;

#[derive(Clone, Debug)]
pub struct ImageConfig {
    pub paths: u64,
    pub pixel_samples: u32,
    pub seed: u64,
    pub threads: usize,
    pub singularity: Singularity,
    pub max_depth: u32,
    /// Light-tracing paths per light path, combined with the connections by multiple
    /// importance sampling at the points the camera sees directly (see the module docs); 0:
    /// the plain connection with `singularity` everywhere.
    pub mis_paths: u32,
}

/// A non-specular point seen by a camera sample.
#[derive(Clone, Copy)]
struct ViewPoint {
    pixel: usize,
    position: Vec3,
    ng: Vec3,
    /// The mesh's shading normal ([`luxest_render::shading`]).
    ns: Vec3,
    /// Direction towards the camera (along the specular chain).
    wo: Vec3,
    /// The triangle and texture coordinates of the point.
    material: u32,
    uv: [f64; 2],
    /// Throughput of the specular chain, divided by the samples per pixel.
    weight: Rgb,
    /// Samples per pixel times the camera's area density at the point, for multiple importance
    /// sampling; `None` without it (points seen through specular bounces, or `--mis-paths 0`).
    camera_pdf: Option<f64>,
    /// The short path of a flat Lambertian point: the normal on the camera's side and
    /// `weight · reflectance / π`.
    diffuse: Option<(Vec3, Rgb)>,
}

/// A light-path vertex stored for connection.
#[derive(Clone, Copy)]
struct Record {
    position: Vec3,
    ng: Vec3,
    /// The mesh's shading normal (`ng` for emission points).
    ns: Vec3,
    /// Direction the light came from (collisions), or the emitter normal (emission points).
    wo: Vec3,
    q: Rgb,
    /// Material triangle for collisions; `None` for emission points.
    triangle: Option<u32>,
    /// Texture coordinates of collisions.
    uv: [f64; 2],
    /// Index of the light path within its batch (its round is `path / ROUND_PATHS`).
    path: u64,
    /// Whether the light path may go on from here (the depth bound), for light tracing's
    /// density.
    can_continue: bool,
    /// The short path of an emission point or a flat Lambertian collision: the normal on the
    /// light's side, `q · reflectance / π` (`q / π` for emission), and light tracing's
    /// solid-angle density per cosine times its paths per light path
    /// (`mis_paths · survival / π`; 0 when the path cannot go on).
    diffuse: Option<(Vec3, Rgb, f64)>,
}

/// Russian roulette threshold of the connections, as a multiple of the pixel's light-traced
/// luminance (with MIS) or of its running mean connected light per path (see `render`).
/// Measured on the Cornell box 256² (docs/measurements.md). Without MIS, 2000 paths: 0 (off)
/// 240 M shadow rays, relMSE 2.13e-3 in 25.1 CPU-s; 1: 125 M, 2.17e-3 in 18.7; 3: 71 M,
/// 2.35e-3 in 15.3 (1.5x the efficiency of no roulette); 10: 45 M, 3.07e-3 in 13.9. With MIS
/// (300 paths, 10 000 light-tracing paths each, two seeds), relMSE × CPU-s: 1: 6.1e-3, 3:
/// 6.0e-3, 10: 8.5e-3; the running-mean threshold 7.0e-3.
pub const RR_ALPHA: f64 = 3.0;
/// Paths of a batch connected without roulette before its threshold is set (measured on the
/// Cornell box: a threshold from the first path alone doubled the relMSE at equal paths).
const RR_WARMUP: u64 = ROUND_PATHS;
/// Salt of the streams of the environment's direct term at the view points.
const ENVIRONMENT_SALT: u64 = 0x00e4_7a1b_5c3d;
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
    // Sized before the run (crate::work::image_plan): a round's points of the tile at once.
    let mut out = Vec::with_capacity(pixels.len() * spp as usize);
    let mut emitted = vec![Rgb::BLACK; pixels.len()];
    for (&pixel, emitted_px) in pixels.iter().zip(emitted.iter_mut()) {
        let mut rng = Rng::new(round_seed ^ VIEW_POINT_SEED_SALT, pixel as u64);
        for k in 0..spp {
            // Sample round·spp + k of the pixel's Owen-scrambled Sobol sequence: the rounds'
            // points stratify the pixel together (their footprint error falls faster than
            // with independent points).
            let (u, v) = pixel_jitter(
                cfg.seed ^ VIEW_POINT_SEED_SALT,
                pixel as u64,
                round * spp as u64 + k as u64,
            );
            let sx = (pixel % w) as f64 + u;
            let sy = (pixel / w) as f64 + v;
            let mut dir = cam.direction(sx, sy);
            let mut origin = cam.position;
            let mut weight = Rgb::splat(1.0 / spp as f64);
            for bounce in 0..16 {
                let Some(sp) = world.intersect(origin, dir) else {
                    *emitted_px = *emitted_px + weight * world.environment_radiance(dir);
                    break;
                };
                // Emitters seen directly are light tracing's when it runs (its emission points
                // sample the emitter's image with far more points than the pixels get here).
                if cfg.mis_paths == 0 || bounce > 0 {
                    *emitted_px = *emitted_px + weight * world.emitted_radiance(&sp, -dir);
                }
                let m = world.material_seen(&sp, -dir);
                let m = &*m;
                let shading = world.shading_of(&sp, -dir);
                if !bsdf::is_delta(m) {
                    let wo = -dir;
                    out.push(ViewPoint {
                        pixel,
                        position: sp.position,
                        ng: sp.ng,
                        ns: sp.ns,
                        wo,
                        material: sp.triangle,
                        uv: sp.uv,
                        weight,
                        camera_pdf: (cfg.mis_paths > 0 && bounce == 0)
                            .then(|| spp as f64 * cam.area_density(sp.position, sp.ng)),
                        diffuse: match m {
                            Material::Lambertian { reflectance } if shading.is_flat() => Some((
                                bsdf::facing_normal(wo, sp.ng),
                                weight * *reflectance * (1.0 / PI),
                            )),
                            _ => None,
                        },
                    });
                    // A material with a delta lobe besides (a smooth plastic's coating, a
                    // blend's mirror): the view point takes what has a density, the path goes
                    // on through the delta lobe alone.
                    if !bsdf::has_delta_lobe(m) {
                        break;
                    }
                }
                let Some(s) = shading.sample(m, -dir, &mut rng, Transport::Radiance) else {
                    break;
                };
                if !s.delta {
                    break;
                }
                weight = weight * s.weight;
                origin = world.offset(sp.position, sp.ng, s.wi);
                dir = s.wi;
            }
        }
    }
    (out, emitted)
}

/// A batch's light paths: the vertices to connect, and the light-tracing film (luminance
/// times the connected paths per pixel; empty without light tracing) with its shadow rays.
struct LightBatch {
    records: Vec<Record>,
    film: Vec<Rgb>,
    shadow_rays: u64,
}

/// Salt of the light-tracing paths' random streams (the connected light paths use the run's
/// seed, streams 1..=batches).
const LIGHT_TRACING_SALT: u64 = 0x0071_7e5a_1c7d;

fn light_records(
    world: &World,
    cam: &PinholeCamera,
    cfg: &ImageConfig,
    (batch, paths): (usize, u64),
    progress: &Progress,
) -> LightBatch {
    let mut rng = Rng::new(cfg.seed, batch as u64 + 1);
    let mut records = Vec::new();
    let mut tally = progress.tally();
    // Light tracing's density of a path counts its `mis_paths` samples per light path.
    let k = cfg.mis_paths as f64;
    for path in 0..paths {
        walk_light_path(world, &mut rng, cfg.max_depth, |v, q| {
            records.push(match v {
                LightVertex::Emission { position, normal } => {
                    let can_continue = cfg.max_depth >= 1;
                    Record {
                        position,
                        ng: normal,
                        ns: normal,
                        wo: normal,
                        q,
                        triangle: None,
                        uv: [0.0, 0.0],
                        path,
                        can_continue,
                        diffuse: Some((
                            normal,
                            q * (1.0 / PI),
                            if can_continue { k / PI } else { 0.0 },
                        )),
                    }
                }
                LightVertex::Collision { sp, dir, depth, .. } => {
                    let can_continue = depth + 1 < cfg.max_depth;
                    let wo = -dir;
                    let flat = world.shading_of(&sp, wo).is_flat();
                    Record {
                        position: sp.position,
                        ng: sp.ng,
                        ns: sp.ns,
                        wo,
                        q,
                        triangle: Some(sp.triangle),
                        uv: sp.uv,
                        path,
                        can_continue,
                        diffuse: match &*world.material_seen(&sp, wo) {
                            Material::Lambertian { reflectance } if flat => Some((
                                bsdf::facing_normal(wo, sp.ng),
                                q * *reflectance * (1.0 / PI),
                                if can_continue {
                                    k * survival(*reflectance) / PI
                                } else {
                                    0.0
                                },
                            )),
                            _ => None,
                        },
                    }
                }
            })
        });
        tally.add(1);
    }
    drop(tally);
    let (film, shadow_rays) = light_tracing(world, cam, cfg, (batch, paths), progress);
    LightBatch {
        records,
        film,
        shadow_rays,
    }
}

/// Light tracing's share: `mis_paths` light paths per connected path, every collision seen
/// directly by the camera connected to it with its balance-heuristic weight; the luminance of
/// each is divided by `mis_paths` (the pixels are later divided by the connected paths).
fn light_tracing(
    world: &World,
    cam: &PinholeCamera,
    cfg: &ImageConfig,
    (batch, paths): (usize, u64),
    progress: &Progress,
) -> (Vec<Rgb>, u64) {
    let mut shadow_rays = 0;
    if cfg.mis_paths == 0 {
        return (Vec::new(), shadow_rays);
    }
    let mut film = vec![Rgb::BLACK; cam.width as usize * cam.height as usize];
    let k = cfg.mis_paths as f64;
    let spp = cfg.pixel_samples.max(1) as f64;
    let mut rng = Rng::new(cfg.seed ^ LIGHT_TRACING_SALT, batch as u64 + 1);
    let mut tally = progress.tally();
    for _ in 0..paths * cfg.mis_paths as u64 {
        tally.add(1);
        walk_light_path(world, &mut rng, cfg.max_depth, |v, q| {
            let (sp, dir, arrival) = match v {
                LightVertex::Emission { position, normal } => {
                    // The emitter seen directly: light tracing's alone.
                    let f_cos = |w: Vec3| Rgb::splat(normal.dot(w).max(0.0) / PI);
                    if let Some(link) =
                        connect_to_camera(world, cam, position, normal, f_cos, &mut shadow_rays)
                    {
                        film[link.pixel] = film[link.pixel] + q * link.value * (1.0 / k);
                    }
                    return;
                }
                LightVertex::Collision {
                    sp, dir, arrival, ..
                } => (sp, dir, arrival),
            };
            if matches!(arrival, Arrival::DeltaLight | Arrival::Environment) {
                return; // the exact direct term's, or the environment's at the view points
            }
            let (wo, ng) = (-dir, sp.ng);
            let m = world.material_seen(&sp, wo);
            let m = &*m;
            // A light path's vertex: the adjoint BSDF (wo towards the light).
            let shading = world.shading_of(&sp, wo);
            let f_cos = |w: Vec3| shading.eval(m, wo, w, Transport::Flux);
            if let Some(link) =
                connect_to_camera(world, cam, sp.position, ng, f_cos, &mut shadow_rays)
            {
                let weight = match arrival {
                    Arrival::Sampled { from, pdf } => {
                        let p = k * pdf * dir.dot(ng).abs() / (sp.position - from).length_squared();
                        p / (p + spp * link.camera_pdf)
                    }
                    _ => 1.0,
                };
                film[link.pixel] = film[link.pixel] + q * link.value * (weight / k);
            }
        });
    }
    (film, shadow_rays)
}

/// Connection value from record `r` to view point `v` (without visibility) and the unit
/// direction from the record to the view point.
#[inline]
fn contribution(
    world: &World,
    sing: &Singularity,
    mis_paths: f64,
    r: &Record,
    v: &ViewPoint,
    m_v: &Material,
) -> Option<(Rgb, Vec3)> {
    let d = v.position - r.position;
    let d2 = d.length_squared();
    if d2 <= 0.0 {
        return None;
    }
    if let (Some((n_r, qf, k_r)), Some((n_v, fv))) = (r.diffuse, v.diffuse) {
        // Both diffuse: cos_r · d and cos_v · d without a square root.
        let cr = n_r.dot(d);
        let cv = -n_v.dot(d);
        if cr <= 0.0 || cv <= 0.0 {
            return None;
        }
        let g = cr * cv;
        let kernel = match v.camera_pdf {
            // g / d⁴ · s p_cam / (s p_cam + k_r g / d⁴)
            Some(pc) => g * pc / (d2 * d2 * pc + k_r * g),
            None => g / d2 * sing.inverse_square(d2),
        };
        let c = qf * fv * kernel;
        return (c.max_component() > 0.0).then(|| (c, d * (1.0 / d2.sqrt())));
    }
    let dist = d2.sqrt();
    let w = d / dist; // from the record to the view point
                      // BRDF at the view point, light arriving from -w, leaving towards the camera.
    let shading_v = world.shading(v.material, v.uv, (v.ng, v.ns), v.wo);
    let f_v = shading_v.eval(m_v, v.wo, -w, Transport::Radiance);
    if f_v.max_component() <= 0.0 {
        return None;
    }
    // BRDF × cosine at the record, and light tracing's solid-angle density towards w.
    let (f_r, pdf_r) = match r.triangle {
        None => {
            let c = r.ng.dot(w);
            if c <= 0.0 {
                return None;
            }
            (Rgb::splat(c / PI), c / PI)
        }
        Some(t) => {
            let m = world.material_at(t, r.uv, r.wo, r.ns);
            let shading = world.shading(t, r.uv, (r.ng, r.ns), r.wo);
            let (f, p) = shading.eval_and_pdf(&m, r.wo, w, Transport::Flux);
            let pdf = if p > 0.0 {
                p * survival(f * (1.0 / p))
            } else {
                0.0
            };
            (f, pdf)
        }
    };
    let pdf_r = if r.can_continue {
        mis_paths * pdf_r
    } else {
        0.0
    };
    let kernel = match v.camera_pdf {
        Some(pc) => {
            let p_light = pdf_r * w.dot(v.ng).abs() / d2;
            pc / (d2 * (pc + p_light))
        }
        None => sing.inverse_square(d2),
    };
    let c = r.q * f_r * f_v * v.weight * kernel;
    (c.max_component() > 0.0).then_some((c, w))
}

/// The `luxest.singularity` header value of an image rendered with `cfg`.
pub fn singularity_header(cfg: &ImageConfig) -> String {
    if cfg.mis_paths > 0 {
        format!(
            "mis(light tracing, {} paths per path); behind mirrors and glass: {}",
            cfg.mis_paths, cfg.singularity
        )
    } else {
        cfg.singularity.to_string()
    }
}

/// Renders the double-local-estimate image of the scene's camera. Its two stretches of work
/// show their progress through `console`: the light paths (and light tracing's paths), then
/// the connections, tile by tile (in pixels).
pub fn render(
    world: &World,
    cam: &PinholeCamera,
    cfg: &ImageConfig,
    console: &Console,
) -> ImageResult {
    let start = std::time::Instant::now();
    let (w, h) = (cam.width as usize, cam.height as usize);
    let per_batch =
        |b: usize| cfg.paths / BATCHES as u64 + u64::from((b as u64) < cfg.paths % BATCHES as u64);
    let progress = console.progress(
        "estimate image: light paths",
        Some(cfg.paths * (1 + cfg.mis_paths as u64)),
        "paths",
    );
    let light = run_batches(BATCHES, cfg.threads, |b| {
        light_records(world, cam, cfg, (b, per_batch(b)), &progress)
    });
    progress.finish();
    let mut records = Vec::with_capacity(BATCHES);
    let mut films = Vec::with_capacity(BATCHES);
    let mut shadow_rays = 0;
    for l in light {
        records.push(l.records);
        films.push(l.film);
        shadow_rays += l.shadow_rays;
    }
    let mis_paths = cfg.mis_paths as f64;
    // Light tracing's share of every pixel (Y), the scale of the connections' roulette.
    let light_traced = (cfg.mis_paths > 0).then(|| {
        let mut y = vec![0.0; w * h];
        for film in &films {
            for (m, c) in y.iter_mut().zip(film) {
                *m += c.luminance() / cfg.paths.max(1) as f64;
            }
        }
        y
    });
    let collisions: u64 = records.iter().map(|r| r.len() as u64).sum();
    let rounds_per_batch = per_batch(0).div_ceil(ROUND_PATHS).max(1);

    let tiles_x = w.div_ceil(TILE);
    let tiles_y = h.div_ceil(TILE);
    let progress = console.progress(
        "estimate image: connections",
        Some((w * h) as u64),
        "pixels",
    );
    let tile_results = run_batches(tiles_x * tiles_y, cfg.threads, |t| {
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
            let mut tau = vec![0.0f64; pixels.len()];
            let mut tau_path = 0;
            if let Some(lt) = &light_traced {
                for (t, &p) in tau.iter_mut().zip(&pixels) {
                    *t = RR_ALPHA * lt[p] / cfg.pixel_samples.max(1) as f64;
                }
            }
            for r in 0..n.div_ceil(ROUND_PATHS).max(1) {
                // This round's paths, its camera points and their path-independent terms
                // (emitters seen directly, exact delta lights), counted once per path.
                let paths_in_round = (n - (r * ROUND_PATHS).min(n)).clamp(1, ROUND_PATHS);
                let round = b as u64 * rounds_per_batch + r;
                let (views, emitted) = view_points(world, cam, cfg, &pixels, round);
                let view_local: Vec<usize> = views.iter().map(|v| local(v.pixel)).collect();
                let direct = delta_light_reflected(
                    world,
                    &views
                        .iter()
                        .map(|v| (v.position, (v.ng, v.ns), v.wo, (v.material, v.uv), v.weight))
                        .collect::<Vec<_>>(),
                );
                let weight = paths_in_round as f64;
                for (k, e) in emitted.iter().enumerate() {
                    acc[b][k] = acc[b][k] + *e * weight;
                }
                for (&k, d) in view_local.iter().zip(&direct) {
                    acc[b][k] = acc[b][k] + *d * weight;
                }
                if world.environment().is_some() {
                    // One sample per camera point and round, on a stream of the round's own.
                    let mut rng = Rng::new(
                        cfg.seed ^ splitmix64(round ^ ENVIRONMENT_SALT),
                        pixels[0] as u64,
                    );
                    for (v, &k) in views.iter().zip(&view_local) {
                        let m = world.material(v.material);
                        let shading = world.shading(v.material, v.uv, (v.ng, v.ns), v.wo);
                        let l =
                            environment_reflected(world, (v.position, &shading, v.wo), m, &mut rng);
                        acc[b][k] = acc[b][k] + l * v.weight * weight;
                    }
                }
                let end = (r + 1) * ROUND_PATHS;
                while next < recs.len() && recs[next].path < end {
                    let rec = &recs[next];
                    // Russian roulette on the connections: a pair whose contribution c is
                    // below the threshold tau of its pixel is traced with probability
                    // c / tau and then counts c / (c / tau) = tau; unbiased for any tau
                    // independent of the roulette's own random number. tau is RR_ALPHA
                    // times, per camera point, the pixel's light-traced luminance (with
                    // MIS, known before any connection), or else the mean per path of its
                    // connected light over this batch's earlier paths, from the batch's
                    // RR_WARMUP-th path on (a mean over fewer paths is too noisy: it
                    // promotes small contributions to a large tau).
                    if rec.path != tau_path && light_traced.is_none() {
                        tau_path = rec.path;
                        let scale = if rec.path >= RR_WARMUP {
                            RR_ALPHA / (rec.path as f64 * cfg.pixel_samples.max(1) as f64)
                        } else {
                            0.0
                        };
                        for (t, y) in tau.iter_mut().zip(&connected) {
                            *t = y * scale;
                        }
                    }
                    let record_key = splitmix64(
                        cfg.seed ^ splitmix64(((b as u64) << 40) ^ next as u64 ^ RR_SALT),
                    );
                    next += 1;
                    rays.clear();
                    targets.clear();
                    for (i, (v, &k)) in views.iter().zip(&view_local).enumerate() {
                        let m_v = world.material_at(v.material, v.uv, v.wo, v.ns);
                        if let Some((c, dir_to_view)) =
                            contribution(world, &cfg.singularity, mis_paths, rec, v, &m_v)
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
        progress.inc(pixels.len() as u64);
        (pixels, acc, shadow_rays)
    });
    progress.finish();

    // Combine: per pixel and batch, the mean over the batch's paths (the light-tracing films
    // are the batches' accumulators: at most BYTES_PER_PIXEL at any time).
    drop(records);
    let mut batch_pixels = films;
    for film in batch_pixels.iter_mut() {
        film.resize(w * h, Rgb::BLACK);
    }
    for (pixels, acc, rays) in tile_results {
        shadow_rays += rays;
        for (b, vals) in acc.into_iter().enumerate() {
            for (&p, c) in pixels.iter().zip(vals) {
                batch_pixels[b][p] = batch_pixels[b][p] + c;
            }
        }
    }
    for (b, film) in batch_pixels.iter_mut().enumerate() {
        let n = per_batch(b).max(1) as f64;
        for c in film.iter_mut() {
            *c = *c * (1.0 / n);
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
