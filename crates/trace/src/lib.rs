//! trace: camera path tracing of a compiled scene, progressive, with snapshots.
//!
//! Pixels are independent (box filter, one random stream per pixel sample: see
//! [`luxest_core::camera::pixel_jitter`] and [`sample_rng`]), so an image depends only on the
//! seed and the sample count — not on threads, tiles or how the run was split into passes.
//! Each pixel accumulates the RGB sum in f64 and the second moment of its luminance Y, from
//! which the per-pixel standard error is written on request.

pub mod integrator;

use clap::Parser;
use integrator::{kernel_for, Kernel, RayLog};
use luxest_core::camera::{pixel_jitter, PinholeCamera};
use luxest_core::color::Rgb;
use luxest_core::exr_io::RgbImage;
use luxest_core::meta::{RunInfo, PROGRAM_VERSION};
use luxest_core::parallel::{run_batches, thread_count};
use luxest_core::sampling::Rng;
use luxest_core::world::World;
use luxest_core::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Path-trace a compiled scene from its camera, with progressive snapshots.
#[derive(Parser, Debug)]
#[command(name = "trace", version, about)]
pub struct Args {
    /// Compiled scene (build/<name>/scene.lxs).
    pub scene: PathBuf,
    /// Output prefix: files are <prefix>_<spp, 6 digits>spp.hdr.exr (or <prefix>_ref.hdr.exr)
    /// [default: <scene dir>/<scene name>].
    #[arg(short, long)]
    pub out: Option<PathBuf>,
    /// Samples per pixel of the final image.
    #[arg(long, conflicts_with = "time")]
    pub spp: Option<u32>,
    /// Render for about this many seconds (doubling the samples per pass) instead of --spp.
    #[arg(long)]
    pub time: Option<f64>,
    /// Also write snapshots at these sample counts during the run (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub snapshots: Vec<u32>,
    /// Write the final image as the reference, <prefix>_ref.hdr.exr.
    #[arg(long)]
    pub reference: bool,
    /// Also write the per-pixel standard error of Y next to each image (.se.exr).
    #[arg(long)]
    pub stderr: bool,
    /// Override the camera resolution, WIDTHxHEIGHT.
    #[arg(long)]
    pub resolution: Option<String>,
    /// Also write an sRGB PNG preview of the final image.
    #[arg(long)]
    pub preview: Option<PathBuf>,
    /// Safety bound on path length (Russian roulette ends paths long before).
    #[arg(long, default_value_t = 1024)]
    pub max_depth: u32,
    #[command(flatten)]
    pub common: luxest_core::cli::CommonArgs,
}

/// Side of the square tiles handed to worker threads.
pub const TILE: usize = 16;

/// The random stream of sample `sample` of pixel `pixel` (after its camera jitter).
pub fn sample_rng(seed: u64, pixel: usize, sample: u32) -> Rng {
    Rng::new(seed, ((pixel as u64) << 24) | sample as u64)
}

/// Per-pixel accumulators.
pub struct Film {
    pub width: usize,
    pub height: usize,
    pub sum: Vec<[f64; 3]>,
    pub sum_y2: Vec<f64>,
    pub samples: u32,
}

impl Film {
    pub fn new(width: usize, height: usize) -> Film {
        Film {
            width,
            height,
            sum: vec![[0.0; 3]; width * height],
            sum_y2: vec![0.0; width * height],
            samples: 0,
        }
    }

    /// Mean radiance per pixel.
    pub fn mean(&self) -> Vec<Rgb> {
        let n = self.samples.max(1) as f64;
        self.sum.iter().map(|s| Rgb(s.map(|v| v / n))).collect()
    }

    /// Standard error of each pixel's mean luminance.
    pub fn standard_error(&self) -> Vec<f64> {
        let n = self.samples as f64;
        self.sum
            .iter()
            .zip(&self.sum_y2)
            .map(|(s, s2)| {
                if self.samples < 2 {
                    return f64::INFINITY;
                }
                let mean = Rgb(*s).luminance() / n;
                ((s2 / n - mean * mean).max(0.0) / (n - 1.0)).sqrt()
            })
            .collect()
    }
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

    /// Adds samples `film.samples .. target` to every pixel; returns the rays traced.
    pub fn advance(&self, film: &mut Film, target: u32, record: bool) -> RayLog {
        let (w, h) = (film.width, film.height);
        let tiles_x = w.div_ceil(TILE);
        let tiles = tiles_x * h.div_ceil(TILE);
        let from = film.samples;
        let results = run_batches(tiles, self.threads, "trace", |t| {
            let (tx, ty) = (t % tiles_x, t / tiles_x);
            let mut log = RayLog {
                record,
                ..Default::default()
            };
            let mut out = Vec::with_capacity(TILE * TILE);
            for y in ty * TILE..((ty + 1) * TILE).min(h) {
                for x in tx * TILE..((tx + 1) * TILE).min(w) {
                    let pixel = y * w + x;
                    let (mut sum, mut sum_y2) = ([0.0; 3], 0.0);
                    for s in from..target {
                        let (u, v) = pixel_jitter(self.seed, pixel as u64, s as u64);
                        let dir = self.camera.direction(x as f64 + u, y as f64 + v);
                        let mut rng = sample_rng(self.seed, pixel, s);
                        let l = (self.kernel)(
                            self.world,
                            self.camera.position,
                            dir,
                            &mut rng,
                            self.max_depth,
                            &mut log,
                        );
                        for (a, c) in sum.iter_mut().zip(l.0) {
                            *a += c;
                        }
                        sum_y2 += l.luminance() * l.luminance();
                    }
                    out.push((pixel, sum, sum_y2));
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
        }
        film.samples = target;
        total
    }
}

/// `<prefix>_<spp:06>spp.<feature>.exr` or `<prefix>_ref.<feature>.exr` (the OIDN layout).
pub fn image_path(prefix: &Path, spp: Option<u32>, feature: &str) -> PathBuf {
    let name = prefix
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tag = match spp {
        Some(s) => format!("{s:06}spp"),
        None => "ref".into(),
    };
    prefix.with_file_name(format!("{name}_{tag}.{feature}.exr"))
}

pub use luxest_core::world::{load_with_camera as load, parse_resolution};

fn write_image(
    path: &Path,
    film: &Film,
    info: &RunInfo,
    stderr: bool,
    preview: Option<&Path>,
) -> Result<()> {
    let mean = film.mean();
    if let Some(i) = mean.iter().position(|c| !c.is_finite()) {
        return Err(Error::input(path, format!("pixel {i} is not finite")));
    }
    let mut img = RgbImage::new(film.width, film.height);
    img.pixels = mean.iter().map(|c| c.0.map(|v| v as f32)).collect();
    img.attributes = info.to_attributes();
    img.attributes
        .push(("luxest.pixelFilter".into(), "box".into()));
    luxest_core::exr_io::write_rgb(path, &img)?;
    if let Some(p) = preview {
        luxest_core::exr_io::write_preview_png_auto(p, &img)?;
    }
    if stderr {
        let se_path = path.with_file_name(
            path.file_name()
                .unwrap()
                .to_string_lossy()
                .replace(".hdr.exr", ".se.exr"),
        );
        img.pixels = film
            .standard_error()
            .iter()
            .map(|&v| [v as f32; 3])
            .collect();
        luxest_core::exr_io::write_rgb(&se_path, &img)?;
    }
    Ok(())
}

/// Runs the command line.
pub fn run(args: Args) -> Result<()> {
    if args.spp.is_none() && args.time.is_none() {
        return Err(Error::Usage("give --spp N or --time SECONDS".into()));
    }
    if args.spp == Some(0) || args.time.is_some_and(|t| t.is_nan() || t <= 0.0) {
        return Err(Error::Usage("--spp and --time must be positive".into()));
    }
    let (world, camera) = load(&args.scene, args.resolution.as_deref())?;
    let prefix = args
        .out
        .clone()
        .unwrap_or_else(|| args.scene.with_file_name(&world.scene.header.name));
    let renderer = Renderer::new(
        &world,
        camera,
        args.common.seed,
        thread_count(args.common.threads),
        args.max_depth,
    );
    let mut film = Film::new(camera.width as usize, camera.height as usize);
    let mut snapshots: Vec<u32> = args.snapshots.iter().copied().filter(|&s| s > 0).collect();
    snapshots.sort_unstable();
    snapshots.dedup();
    let start = Instant::now();
    let info = |film: &Film| RunInfo {
        samples: film.samples as u64,
        seed: args.common.seed,
        seconds: start.elapsed().as_secs_f64(),
        estimator: "path-tracing".into(),
        scene_hash: world.scene.content_hash.clone(),
        program_version: PROGRAM_VERSION.into(),
    };
    let mut next_snapshot = 0;
    let mut pass = |film: &mut Film, target: u32| -> Result<()> {
        renderer.advance(film, target, false);
        while next_snapshot < snapshots.len() && snapshots[next_snapshot] <= film.samples {
            if snapshots[next_snapshot] == film.samples {
                write_image(
                    &image_path(&prefix, Some(film.samples), "hdr"),
                    film,
                    &info(film),
                    args.stderr,
                    None,
                )?;
            }
            next_snapshot += 1;
        }
        Ok(())
    };
    match (args.spp, args.time) {
        (Some(spp), _) => {
            for &s in snapshots.iter().filter(|&&s| s < spp) {
                pass(&mut film, s)?;
            }
            pass(&mut film, spp)?;
        }
        (None, Some(limit)) => {
            // Doubling passes (snapshot counts included) while the next one is predicted to fit.
            let mut target = 1;
            loop {
                let elapsed = start.elapsed().as_secs_f64();
                if film.samples > 0 {
                    let predicted = elapsed * (target - film.samples) as f64 / film.samples as f64;
                    if elapsed + predicted > limit {
                        break;
                    }
                }
                let stop = snapshots
                    .iter()
                    .copied()
                    .find(|&s| s > film.samples && s < target)
                    .unwrap_or(target);
                pass(&mut film, stop)?;
                if stop == target {
                    target *= 2;
                }
            }
        }
        (None, None) => unreachable!("checked above"),
    }
    let final_path = image_path(&prefix, (!args.reference).then_some(film.samples), "hdr");
    if args.reference || !snapshots.contains(&film.samples) || args.preview.is_some() {
        write_image(
            &final_path,
            &film,
            &info(&film),
            args.stderr,
            args.preview.as_deref(),
        )?;
    }
    eprintln!(
        "wrote {} ({} spp, {:.2} s)",
        final_path.display(),
        film.samples,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
