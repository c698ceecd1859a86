//! The renderer: adds samples to a [`Film`] tile by tile on worker threads.
//!
//! Pixels are independent (box filter, one sampler per pixel sample: see [`pixel_sampler`],
//! whose first draw is [`luxest_render::camera::pixel_jitter`]), so an image depends only on
//! the seed and the sample count — not on threads, tiles or how the run was split into passes.

use crate::film::Film;
use crate::integrator::{kernel_for, Kernel, RayLog};
use luxest_io::color::Rgb;
use luxest_io::limits::WorkPlan;
use luxest_io::progress::Progress;
use luxest_render::camera::PinholeCamera;
use luxest_render::parallel::run_batches;
use luxest_render::sobol::PixelSampler;
use luxest_render::world::World;

/// Salt of the calibration's samples (never a pixel sample of the run).
const CALIBRATION_SALT: u64 = 0x00ca_11b2_a7e1;

/// Side of the square tiles handed to worker threads.
pub const TILE: usize = 16;

/// The sampler of sample `sample` of pixel `pixel`: its first draw is the pixel position
/// ([`pixel_jitter`]), the rest feed the path.
pub fn pixel_sampler(seed: u64, pixel: usize, sample: u32) -> PixelSampler {
    PixelSampler::new(seed, pixel as u64, sample)
}

/// A scene prepared for tracing.
pub struct Renderer<'a> {
    pub world: &'a World,
    pub camera: PinholeCamera,
    pub seed: u64,
    pub threads: usize,
    pub max_depth: u32,
    kernel: Kernel,
}

impl<'a> Renderer<'a> {
    pub fn new(
        world: &'a World,
        camera: PinholeCamera,
        seed: u64,
        threads: usize,
        max_depth: u32,
    ) -> Renderer<'a> {
        Renderer {
            world,
            camera,
            seed,
            threads,
            max_depth,
            kernel: kernel_for(world),
        }
    }

    /// The plan of a run to `spp` samples per pixel (the resource rule): pixel samples of the
    /// image spread over it, traced on streams of their own and timed, give the seconds per
    /// sample and the rays of a path.
    pub fn plan(&self, spp: u32) -> WorkPlan {
        let (w, h) = (self.camera.width as u64, self.camera.height as u64);
        let pixels = w * h;
        let mut log = RayLog::default();
        let (per_sample, spent) = luxest_io::limits::seconds_per_unit(|k| {
            // A stride coprime with nearly every image size spreads the samples over it.
            let pixel = (k * 7919) % pixels;
            let (x, y) = ((pixel % w) as usize, (pixel / w) as usize);
            self.sample(
                self.seed ^ CALIBRATION_SALT,
                pixel as usize,
                (x, y),
                k as u32,
                &mut log,
            );
        });
        let samples = (pixels * spp as u64) as f64;
        let rays_per_sample = (log.closest + log.shadow) as f64 / (spent / per_sample).max(1.0);
        let tiles = (w as usize).div_ceil(TILE) * (h as usize).div_ceil(TILE);
        let threads = self.threads.min(tiles).max(1);
        WorkPlan {
            stage: "trace".into(),
            work: format!("{w}x{h} pixels x {spp} samples of ~{rays_per_sample:.1} rays"),
            units: samples * rays_per_sample,
            unit: "ray casts",
            seconds: samples * per_sample / threads as f64,
            threads,
            memory_bytes: pixels as u128 * luxest_render::world::FILM_BYTES_PER_PIXEL as u128,
            calibration_seconds: spent,
            levers: "--spp, --resolution and --threads".into(),
        }
    }

    /// The radiance of sample `s` of pixel number `pixel`, at (x, y), on the streams of `seed`.
    fn sample(
        &self,
        seed: u64,
        pixel: usize,
        (x, y): (usize, usize),
        s: u32,
        log: &mut RayLog,
    ) -> Rgb {
        let mut rng = pixel_sampler(seed, pixel, s);
        let (u, v) = rng.pixel_position();
        let dir = self.camera.direction(x as f64 + u, y as f64 + v);
        (self.kernel)(
            self.world,
            self.camera.position,
            dir,
            &mut rng,
            self.max_depth,
            log,
        )
    }

    /// Adds samples `film.samples .. target` to every pixel, counting them on `progress`;
    /// returns the rays traced.
    pub fn advance(
        &self,
        film: &mut Film,
        target: u32,
        record: bool,
        progress: &Progress,
    ) -> RayLog {
        let (w, h) = (film.width, film.height);
        let tiles_x = w.div_ceil(TILE);
        let tiles = tiles_x * h.div_ceil(TILE);
        let from = film.samples;
        let results = run_batches(tiles, self.threads, |t| {
            let (tx, ty) = (t % tiles_x, t / tiles_x);
            let mut log = RayLog {
                record,
                ..Default::default()
            };
            let mut out = Vec::with_capacity(TILE * TILE);
            let mut tally = progress.tally();
            for y in ty * TILE..((ty + 1) * TILE).min(h) {
                for x in tx * TILE..((tx + 1) * TILE).min(w) {
                    let pixel = y * w + x;
                    let (mut sum, mut sum_y2) = ([0.0; 3], 0.0);
                    for s in from..target {
                        let l = self.sample(self.seed, pixel, (x, y), s, &mut log);
                        for (a, c) in sum.iter_mut().zip(l.0) {
                            *a += c;
                        }
                        sum_y2 += l.luminance() * l.luminance();
                    }
                    out.push((pixel, sum, sum_y2));
                    tally.add(target.saturating_sub(from) as u64);
                }
            }
            (out, log)
        });
        let mut total = RayLog {
            record,
            ..Default::default()
        };
        for (pixels, log) in results {
            for (p, s, s2) in pixels {
                for (a, c) in film.sum[p].iter_mut().zip(s) {
                    *a += c;
                }
                film.sum_y2[p] += s2;
            }
            total.closest += log.closest;
            total.shadow += log.shadow;
            total.closest_rays.extend(log.closest_rays);
            total.shadow_rays.extend(log.shadow_rays);
            total.closest_depths.extend(log.closest_depths);
            total.shadow_depths.extend(log.shadow_depths);
        }
        film.samples = target;
        total
    }
}
