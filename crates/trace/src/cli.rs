//! The `trace` command line: arguments, and the run from a compiled scene to its images.

use crate::film::Film;
use crate::output::{image_files, write_image};
use crate::progressive::{run_passes, Budget};
use crate::renderer::Renderer;
use clap::{Parser, ValueEnum};
use luxest_io::cli::CommonArgs;
use luxest_io::meta::RunInfo;
use luxest_io::naming::{image_path, Kind, Level};
use luxest_io::num::{Count, Real};
use luxest_io::outputs::{check_prefix, Format, OutputPlan};
use luxest_io::{Error, Result};
use luxest_render::light_bvh::LightSampler;
use std::path::PathBuf;
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
    #[arg(long, conflicts_with = "time", value_parser = Count::<u32>::range(1, u32::MAX as u64, "samples per pixel"))]
    pub spp: Option<u32>,
    /// Render for about this many seconds (doubling the samples per pass) instead of --spp;
    /// at most 1e6 s (11.6 days).
    #[arg(long, value_parser = Real::positive("s").at_most(MAX_SECONDS))]
    pub time: Option<f64>,
    /// Also write snapshots at these sample counts during the run (comma-separated; each at
    /// least 1 and at most --spp).
    #[arg(long, value_delimiter = ',', value_parser = Count::<u32>::range(1, u32::MAX as u64, "samples per pixel"))]
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
    /// Safety bound on path length, 1 to 2^20 (Russian roulette ends paths long before).
    #[arg(long, default_value_t = 1024, value_parser = MAX_DEPTH)]
    pub max_depth: u32,
    /// How next-event estimation chooses its light: `bvh` (by importance at the shading
    /// point, through a light BVH) or `power` (in proportion to flux).
    #[arg(long, default_value = "bvh", value_parser = clap::value_parser!(LightSampler))]
    pub light_sampler: LightSampler,
    /// Next-event estimation of the environment through the scene's portals (its open windows
    /// and `portals`): `auto` (the default) uses them, `off` samples the whole sky; refused
    /// where the scene has none.
    #[arg(long, value_enum)]
    pub portals: Option<Portals>,
    #[command(flatten)]
    pub common: CommonArgs,
}

/// Whether `trace` samples the environment through the scene's portals.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq)]
pub enum Portals {
    Auto,
    Off,
}

/// Longest render time --time accepts, s: a bound that makes `--time inf` (which never ended)
/// a usage error.
pub const MAX_SECONDS: f64 = 1e6;

/// Path-length bound: 0 would give a black image without a word.
pub const MAX_DEPTH: Count<u32> = Count::range(1, 1 << 20, "bounces");

/// The estimator name recorded in image headers.
pub const ESTIMATOR: &str = luxest_io::header::estimator::PATH_TRACING;

/// Runs the command line.
pub fn run(args: Args) -> Result<()> {
    let budget = match (args.spp, args.time) {
        (Some(spp), _) => Budget::Samples(spp),
        (None, Some(t)) => Budget::Seconds(t),
        (None, None) => return Err(Error::Usage("give --spp N or --time SECONDS".into())),
    };
    let mut snapshots: Vec<u32> = args.snapshots.clone();
    snapshots.sort_unstable();
    snapshots.dedup();
    if let (Some(spp), Some(&last)) = (args.spp, snapshots.last()) {
        if last > spp {
            return Err(Error::Usage(format!(
                "--snapshots: {last} exceeds --spp {spp}; a snapshot is taken on the way to the \
                 final image"
            )));
        }
    }
    if let Some(out) = &args.out {
        let level = match (args.reference, args.spp) {
            (true, _) => Level::Reference,
            (false, spp) => Level::Spp(spp.unwrap_or(1) as u64),
        };
        check_prefix(out, "-o/--out", &image_path(out, level, Kind::Hdr))?;
    }
    let (mut world, camera) = crate::load(&args.scene, args.resolution.as_deref())?;
    world.set_light_sampler(args.light_sampler);
    if args.portals.is_some() && world.portal_count() == 0 {
        return Err(Error::Usage(
            "--portals has no effect on a scene without portals (no open rectangular windows, \
             no `portals`, or no environment); leave it out"
                .into(),
        ));
    }
    world.set_portals(args.portals != Some(Portals::Off));
    let prefix = args
        .out
        .clone()
        .unwrap_or_else(|| args.scene.with_file_name(&world.scene.header.name));
    // Every output known before the run (snapshots, the final image when its samples are
    // fixed, the preview) is checked against the scene and each other before any work.
    let final_level = |samples: u32| {
        if args.reference {
            Level::Reference
        } else {
            Level::Spp(samples as u64)
        }
    };
    let mut outputs = Vec::new();
    for &s in &snapshots {
        outputs.extend(image_files(
            &image_path(&prefix, Level::Spp(s as u64), Kind::Hdr),
            args.stderr,
        )?);
    }
    if let Some(spp) = args
        .spp
        .filter(|s| args.reference || !snapshots.contains(s))
    {
        outputs.extend(image_files(
            &image_path(&prefix, final_level(spp), Kind::Hdr),
            args.stderr,
        )?);
    }
    outputs.extend(args.preview.clone());
    let mut plan = OutputPlan::new([&args.scene], &outputs)?;
    if let Some(preview) = &args.preview {
        Format::Png.check(preview, "--preview")?;
    }
    let renderer = Renderer::new(
        &world,
        camera,
        args.common.seed,
        args.common.thread_count(),
        args.max_depth,
    );
    let console = args.common.console;
    if let Some(spp) = args.spp {
        // A --time run is as long as asked; a --spp run says first when it is long.
        console.announce(&renderer.plan(spp));
    }
    let mut film = Film::new(camera.width as usize, camera.height as usize);
    let pixels = camera.width as u64 * camera.height as u64;
    let progress = console.progress("trace", args.spp.map(|spp| pixels * spp as u64), "samples");
    if let Some(seconds) = args.time {
        progress.set_time_budget(seconds);
    }
    let start = Instant::now();
    let info = |film: &Film| {
        RunInfo::new(
            ESTIMATOR,
            film.samples as u64,
            args.common.seed,
            start.elapsed().as_secs_f64(),
            &world.scene.content_hash,
        )
    };
    let samples = run_passes(
        budget,
        &snapshots,
        || start.elapsed().as_secs_f64(),
        |target| {
            renderer.advance(&mut film, target, false, &progress);
            if snapshots.contains(&target) {
                let path = image_path(&prefix, Level::Spp(target as u64), Kind::Hdr);
                write_image(&mut plan, &path, &film, &info(&film), args.stderr, None)?;
            }
            Ok(())
        },
    )?;
    progress.finish();
    let final_path = image_path(&prefix, final_level(samples), Kind::Hdr);
    if args.reference || !snapshots.contains(&samples) {
        if args.spp.is_none() {
            // A --time run's final samples are known only now.
            for f in image_files(&final_path, args.stderr)? {
                plan.add_output(&f)?;
            }
        }
        write_image(
            &mut plan,
            &final_path,
            &film,
            &info(&film),
            args.stderr,
            args.preview.as_deref(),
        )?;
    } else if let Some(p) = &args.preview {
        // The final image is the last snapshot, already written; only its preview is left.
        let img = crate::output::mean_image(&final_path, &film, &info(&film))?;
        luxest_io::png::write_preview_png_auto_to(&mut plan, p, &img)?;
    }
    let unreached: Vec<String> = snapshots
        .iter()
        .filter(|&&s| s > samples)
        .map(|s| s.to_string())
        .collect();
    if !unreached.is_empty() {
        console.note(format_args!(
            "warning: snapshots {} not written: the --time budget ended at {samples} spp",
            unreached.join(",")
        ));
    }
    // All images of the run appear together (a failure leaves none of them).
    plan.commit()?;
    console.note(format_args!(
        "wrote {} ({} spp, {:.2} s)",
        final_path.display(),
        samples,
        start.elapsed().as_secs_f64()
    ));
    Ok(())
}
