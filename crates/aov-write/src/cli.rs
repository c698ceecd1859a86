//! The `aov-write` command line: arguments, and the run from a compiled scene to its feature
//! images.

use crate::features::FeatureFilm;
use clap::Parser;
use luxest_io::cli::CommonArgs;
use luxest_io::exr::write_rgb_to;
use luxest_io::header;
use luxest_io::image::RgbImage;
use luxest_io::meta::RunInfo;
use luxest_io::naming::{image_path, Kind, Level};
use luxest_io::num::Count;
use luxest_io::outputs::{check_prefix, OutputPlan};
use luxest_io::{Error, Result};
use luxest_render::world::{load_with_camera, Traversal};
use std::path::PathBuf;

/// The estimator name recorded in the features' headers.
pub const ESTIMATOR: &str = header::estimator::FIRST_HIT_FEATURES;

/// Write albedo / normal / emission (/ depth) feature images with trace's pixel sampling.
#[derive(Parser, Debug)]
#[command(name = "aov-write", version, about)]
pub struct Args {
    /// Compiled scene (build/<name>/scene.lxs).
    pub scene: PathBuf,
    /// Output prefix [default: <scene dir>/<scene name>].
    #[arg(short, long)]
    pub out: Option<PathBuf>,
    /// Samples per pixel (the final image).
    #[arg(long, value_parser = SPP)]
    pub spp: u32,
    /// Also write the features at these sample counts (as trace's snapshots; each at least 1
    /// and at most --spp).
    #[arg(long, value_delimiter = ',', value_parser = SPP)]
    pub snapshots: Vec<u32>,
    /// Write the final images as the reference (_ref).
    #[arg(long)]
    pub reference: bool,
    /// Albedo, normal and depth average at least this many samples per pixel: the features of
    /// an image of s < N samples are those of N samples, the first s of them trace's own, so
    /// that they are antialiased (as Intel Open Image Denoise recommends) at the cost of N
    /// first hits per pixel. The emission (`emi`) always averages exactly the image's samples
    /// (a denoiser subtracts it from trace's radiance of those samples); `ema` is the emission
    /// over as many samples as the albedo (what a denoiser adds back). `luxest.samples` records
    /// the samples of each feature image. 1: every image's features of its own samples. The
    /// default is what the committed model takes (its metadata `luxest.feature_samples`).
    #[arg(long, value_parser = SPP, default_value_t = DEFAULT_MIN_SAMPLES)]
    pub min_samples: u32,
    /// Also write depth (.z.exr, R = G = B = distance in m).
    #[arg(long)]
    pub depth: bool,
    /// Override the camera resolution, WIDTHxHEIGHT (must match trace's).
    #[arg(long)]
    pub resolution: Option<String>,
    #[command(flatten)]
    pub common: CommonArgs,
}

/// The default of `--min-samples`: the least samples per pixel of albedo and normal that the
/// committed denoiser `models/default.onnx` takes (its metadata `luxest.feature_samples`,
/// checked by training/tests/test_training.py), so that aov-write's features as written by
/// default are what `denoise` accepts; `FEATURE_SPP` in pipelines/presets.mk is the pipelines'.
pub const DEFAULT_MIN_SAMPLES: u32 = 16;

/// Samples per pixel: at least one.
const SPP: Count<u32> = Count::range(1, u32::MAX as u64, "samples per pixel");

/// Runs the command line.
pub fn run(args: Args) -> Result<()> {
    if let Some(&s) = args.snapshots.iter().find(|&&s| s > args.spp) {
        return Err(Error::Usage(format!(
            "--snapshots: {s} exceeds --spp {}; a snapshot is taken on the way to the final \
             images",
            args.spp
        )));
    }
    if let Some(out) = &args.out {
        let level = match args.reference {
            true => Level::Reference,
            false => Level::Spp(args.spp as u64),
        };
        check_prefix(out, "-o/--out", &image_path(out, level, Kind::Alb))?;
    }
    let (world, cam) = load_with_camera(&args.scene, args.resolution.as_deref(), Traversal::Fast)?;
    let prefix = args
        .out
        .clone()
        .unwrap_or_else(|| args.scene.with_file_name(&world.scene.header.name));
    let mut counts: Vec<u32> = args.snapshots.clone();
    counts.push(args.spp);
    counts.sort_unstable();
    counts.dedup();
    let start = std::time::Instant::now();
    let threads = args.common.thread_count();
    luxest_io::limits::check_image(
        "feature film",
        cam.width.into(),
        cam.height.into(),
        crate::features::BYTES_PER_PIXEL,
    )
    .map_err(Error::Usage)?;
    let mut film = FeatureFilm::new(cam.width as usize, cam.height as usize);
    let final_level = if args.reference {
        Level::Reference
    } else {
        Level::Spp(args.spp as u64)
    };
    let level_of = |target: u32| {
        if target == args.spp {
            final_level
        } else {
            Level::Spp(target as u64)
        }
    };
    let mut kinds = vec![
        Kind::Alb,
        Kind::Emission,
        Kind::EmissionAntialiased,
        Kind::Nrm,
    ];
    if args.depth {
        kinds.push(Kind::Depth);
    }
    // Every image of the run, checked against the scene and each other before any work; all
    // appear together at the end.
    let outputs: Vec<PathBuf> = counts
        .iter()
        .flat_map(|&t| kinds.iter().map(move |&k| (t, k)))
        .map(|(t, k)| image_path(&prefix, level_of(t), k))
        .collect();
    let mut plan = OutputPlan::new([&args.scene], &outputs)?;
    // The samples each image of a level averages: the emission exactly the level's, the other
    // features at least --min-samples. One film advances through every such count in order and
    // each image is taken where its count is reached.
    let samples_of = |target: u32, kind: Kind| {
        if kind == Kind::Emission {
            target
        } else {
            target.max(args.min_samples)
        }
    };
    let mut checkpoints: Vec<u32> = counts
        .iter()
        .flat_map(|&t| kinds.iter().map(move |&k| (t, k)))
        .map(|(t, k)| samples_of(t, k))
        .collect();
    checkpoints.sort_unstable();
    checkpoints.dedup();
    let console = args.common.console;
    let last = checkpoints.last().copied().unwrap_or(0);
    console.announce(&film.plan(&world, &cam, threads, last));
    let progress = console.progress(
        "aov-write",
        Some(cam.width as u64 * cam.height as u64 * last as u64),
        "samples",
    );
    for &samples in &checkpoints {
        film.advance(
            &world,
            &cam,
            (args.common.seed, threads),
            samples,
            &progress,
        );
        let info = RunInfo::new(
            ESTIMATOR,
            samples as u64,
            args.common.seed,
            start.elapsed().as_secs_f64(),
            &world.scene.content_hash,
        );
        // Each kind's image is made once per count and written for every level that takes it
        // there (the levels below --min-samples share their albedo and normal).
        for &kind in &kinds {
            let levels: Vec<Level> = counts
                .iter()
                .filter(|&&t| samples_of(t, kind) == samples)
                .map(|&t| level_of(t))
                .collect();
            if levels.is_empty() {
                continue;
            }
            let mut img = RgbImage::new(film.width, film.height);
            img.pixels = match kind {
                Kind::Alb => film.albedo(),
                Kind::Nrm => film.normal(),
                Kind::Emission | Kind::EmissionAntialiased => film.emission(),
                _ => film.depth(),
            };
            img.attributes = info.to_attributes();
            img.set_attribute(header::PIXEL_FILTER, "box");
            for level in levels {
                write_rgb_to(&mut plan, &image_path(&prefix, level, kind), &img)?;
            }
        }
    }
    progress.finish();
    plan.commit()?;
    console.note(format_args!(
        "wrote {}_{}.{{alb,emi,ema,nrm{}}}.exr ({} spp, {:.2} s)",
        prefix.display(),
        final_level,
        if args.depth { ",z" } else { "" },
        args.spp,
        start.elapsed().as_secs_f64()
    ));
    Ok(())
}
