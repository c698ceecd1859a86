//! Light tracing: the classical local estimate *at the camera*, a baseline for the double local
//! estimate's images.
//!
//! Light paths are traced from the emitters exactly as for the local estimate (flux weight Q,
//! BSDF sampling with analog Russian roulette). Every non-specular vertex x — a collision, or
//! the emission point of an area emitter — is connected to the pinhole camera at c: when the
//! segment is unoccluded and x projects into the image, the pixel it lands in receives
//!
//! ```text
//! Q · f(ω_in, x→c) cos_x / (d² · A_p · cos³ θ)
//! ```
//!
//! with `f cos_x` the BSDF times the cosine at x (for an emission point, the Lambertian
//! emitter's `cos_e / π`), d = |x − c|, θ the angle between x − c and the camera's axis, and
//! A_p the pixel's area on the image plane at unit distance. This is the pinhole's importance
//! `1 / (A_p cos⁴ θ)` times the geometry term `cos_x cos θ / d²`; its expectation is the
//! box-filtered luminance of the pixel (the image-plane area element is `cos_x dA / (d² cos³ θ)`).
//!
//! Specular surfaces cannot be connected to a pinhole (a delta BSDF has no value towards it),
//! so a scene whose camera sees mirrors or glass is refused; point sources are invisible to the
//! camera, as in `trace`.
//!
//! The environment: its light paths enter from the disk around the scene and connect from
//! their first collision on (the sky lighting a surface the camera sees); the sky the camera
//! sees directly cannot be reached from a light path, so each batch adds it with
//! [`BACKGROUND_SAMPLES`] camera rays per pixel (the environment's radiance along each that
//! leaves the scene). Per-pixel standard errors come from [`BATCHES`] independent batches;
//! the image is bit-identical at any thread count.

use crate::image::{ImageResult, BATCHES};
use crate::transport::{walk_light_path, LightVertex};
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_io::progress::Progress;
use luxest_render::bsdf::Transport;
use luxest_render::camera::{pixel_jitter, PinholeCamera};
use luxest_render::parallel::{mean_and_standard_error, run_batches};
use luxest_render::sampling::Rng;
use luxest_render::world::World;

/// Camera rays per pixel and batch for the environment seen directly.
pub const BACKGROUND_SAMPLES: u32 = 4;

/// Salt of the background camera rays' pixel positions.
const BACKGROUND_SALT: u64 = 0x00ba_c6a0_0d5e;

#[derive(Clone, Debug)]
pub struct LightTraceConfig {
    pub paths: u64,
    pub seed: u64,
    pub threads: usize,
    pub max_depth: u32,
}

/// One batch's pixel sums (f64) and counters.
struct BatchFilm {
    sums: Vec<[f64; 3]>,
    vertices: u64,
    shadow_rays: u64,
}

/// A light-path vertex connected to the pinhole camera.
pub(crate) struct CameraLink {
    /// The pixel the vertex lands in.
    pub pixel: usize,
    /// What the vertex's flux weight is multiplied by to give the pixel's luminance:
    /// `f cos_x / (d² A_p cos³ θ)` (see the module docs).
    pub value: Rgb,
    /// The density per unit area with which a camera ray of that pixel hits the vertex
    /// ([`PinholeCamera::area_density`]), for multiple importance sampling.
    pub camera_pdf: f64,
}

/// Connects vertex `x` (geometric normal `ng`, value `f_cos(w)` of BSDF × cosine towards the
/// unit direction w to the camera) to the camera, counting the shadow ray in `shadow_rays`;
/// `None` outside the image, with no light towards the camera, or blocked.
pub(crate) fn connect_to_camera(
    world: &World,
    cam: &PinholeCamera,
    x: Vec3,
    ng: Vec3,
    f_cos: impl Fn(Vec3) -> Rgb,
    shadow_rays: &mut u64,
) -> Option<CameraLink> {
    let (sx, sy, _) = cam.project(x)?;
    let v = cam.position - x;
    let d2 = v.length_squared();
    let w = v / d2.sqrt();
    let f = f_cos(w);
    if f.max_component() <= 0.0 {
        return None;
    }
    *shadow_rays += 1;
    if world.occluded(world.offset(x, ng, w), cam.position) {
        return None;
    }
    // The pinhole's importance times the geometry term, without the cosine at x (in f).
    let g = cam.footprint(x)?;
    Some(CameraLink {
        pixel: sy as usize * cam.width as usize + sx as usize,
        value: f * g,
        camera_pdf: w.dot(ng).abs() * g,
    })
}

/// Connects vertex `x` carrying flux `q` to the camera and adds it to the film.
fn splat(
    world: &World,
    cam: &PinholeCamera,
    x: Vec3,
    ng: Vec3,
    q: Rgb,
    f_cos: impl Fn(Vec3) -> Rgb,
    film: &mut BatchFilm,
) {
    if let Some(link) = connect_to_camera(world, cam, x, ng, f_cos, &mut film.shadow_rays) {
        let c = q * link.value;
        for (a, v) in film.sums[link.pixel].iter_mut().zip(c.0) {
            *a += v;
        }
    }
}

fn run_batch(
    world: &World,
    cam: &PinholeCamera,
    cfg: &LightTraceConfig,
    (batch, paths): (usize, u64),
    progress: &Progress,
) -> BatchFilm {
    let mut tally = progress.tally();
    let mut rng = Rng::new(cfg.seed, batch as u64 + 1);
    let mut film = BatchFilm {
        sums: vec![[0.0; 3]; cam.width as usize * cam.height as usize],
        vertices: 0,
        shadow_rays: 0,
    };
    for _ in 0..paths {
        walk_light_path(world, &mut rng, cfg.max_depth, |v, q| {
            film.vertices += 1;
            match v {
                LightVertex::Emission { position, normal } => {
                    let f_cos = |w: Vec3| Rgb::splat(normal.dot(w).max(0.0) / std::f64::consts::PI);
                    splat(world, cam, position, normal, q, f_cos, &mut film);
                }
                LightVertex::Collision { sp, dir, .. } => {
                    let (wo, ng) = (-dir, sp.ng);
                    let m = world.material_seen(&sp, wo);
                    let m = &*m;
                    // The adjoint BSDF (wo towards the light), with the light paths' rules for
                    // shading normals.
                    let shading = world.shading_of(&sp, wo);
                    let f_cos = |w: Vec3| shading.eval(m, wo, w, Transport::Flux);
                    splat(world, cam, sp.position, ng, q, f_cos, &mut film);
                }
            }
        });
        tally.add(1);
    }
    if world.environment().is_some() {
        // Stored as a sum over the batch's paths, as the connections are.
        let scale = paths.max(1) as f64 / BACKGROUND_SAMPLES as f64;
        for (pixel, sum) in film.sums.iter_mut().enumerate() {
            let (x, y) = (pixel % cam.width as usize, pixel / cam.width as usize);
            for k in 0..BACKGROUND_SAMPLES {
                let sample = batch as u64 * BACKGROUND_SAMPLES as u64 + k as u64;
                let (u, v) = pixel_jitter(cfg.seed ^ BACKGROUND_SALT, pixel as u64, sample);
                let dir = cam.direction(x as f64 + u, y as f64 + v);
                if world.intersect(cam.position, dir).is_none() {
                    let l = world.environment_radiance(dir) * scale;
                    for (a, c) in sum.iter_mut().zip(l.0) {
                        *a += c;
                    }
                }
            }
        }
    }
    film
}

/// Renders the camera's image by light tracing (see the module docs), counting its `paths`
/// light paths on `progress`.
pub fn render(
    world: &World,
    cam: &PinholeCamera,
    cfg: &LightTraceConfig,
    progress: &Progress,
) -> ImageResult {
    let start = std::time::Instant::now();
    let per_batch =
        |b: usize| cfg.paths / BATCHES as u64 + u64::from((b as u64) < cfg.paths % BATCHES as u64);
    let films = run_batches(BATCHES, cfg.threads, |b| {
        run_batch(world, cam, cfg, (b, per_batch(b)), progress)
    });
    let n = cam.width as usize * cam.height as usize;
    let mut rgb = vec![Rgb::BLACK; n];
    let mut standard_error = vec![0.0; n];
    // The estimate is the mean over all paths; the standard error comes from the batches'
    // means (batches are equal to within one path; the stage asks for at least one per batch).
    let total = cfg.paths.max(1) as f64;
    for p in 0..n {
        let ys: Vec<f64> = films
            .iter()
            .enumerate()
            .filter(|(b, _)| per_batch(*b) > 0)
            .map(|(b, f)| Rgb(f.sums[p]).luminance() / per_batch(b) as f64)
            .collect();
        standard_error[p] = mean_and_standard_error(&ys).1;
        rgb[p] = films
            .iter()
            .fold(Rgb::BLACK, |a, f| a + Rgb(f.sums[p]) * (1.0 / total));
    }
    ImageResult {
        width: cam.width as usize,
        height: cam.height as usize,
        rgb,
        standard_error,
        collisions: films.iter().map(|f| f.vertices).sum(),
        shadow_rays: films.iter().map(|f| f.shadow_rays).sum(),
        seconds: start.elapsed().as_secs_f64(),
    }
}
