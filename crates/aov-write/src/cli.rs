//! The `aov-write` command line: arguments, and the run from a compiled scene to its feature
//! images.

use crate::features::FeatureFilm;
use clap::Parser;
use luxest_io::cli::CommonArgs;
use luxest_io::exr_io::{write_rgb, RgbImage};
use luxest_io::header;
use luxest_io::meta::RunInfo;
use luxest_io::naming::{image_path, Kind, Level};
use luxest_io::{Error, Result};
use luxest_render::world::load_with_camera;
use std::path::PathBuf;

/// The estimator name recorded in the features' headers.
pub const ESTIMATOR: &str = "first-hit-features";

/// Write albedo / normal (/ depth) feature images with trace's pixel sampling.
#[derive(Parser, Debug)]
#[command(name = "aov-write", version, about)]
pub struct Args {
    /// Compiled scene (build/<name>/scene.lxs).
    pub scene: PathBuf,
    /// Output prefix [default: <scene dir>/<scene name>].
    #[arg(short, long)]
    pub out: Option<PathBuf>,
    /// Samples per pixel (the final image).
    #[arg(long)]
    pub spp: u32,
    /// Also write the features at these sample counts (as trace's snapshots).
    #[arg(long, value_delimiter = ',')]
    pub snapshots: Vec<u32>,
    /// Write the final images as the reference (_ref).
    #[arg(long)]
    pub reference: bool,
    /// Also write depth (.z.exr, R = G = B = distance in m).
    #[arg(long)]
    pub depth: bool,
    /// Override the camera resolution, WIDTHxHEIGHT (must match trace's).
    #[arg(long)]
    pub resolution: Option<String>,
    #[command(flatten)]
    pub common: CommonArgs,
}

/// Runs the command line.
pub fn run(args: Args) -> Result<()> {
    if args.spp == 0 {
        return Err(Error::Usage("--spp must be positive".into()));
    }
    let (world, cam) = load_with_camera(&args.scene, args.resolution.as_deref())?;
    let prefix = args
        .out
        .clone()
        .unwrap_or_else(|| args.scene.with_file_name(&world.scene.header.name));
    let mut counts: Vec<u32> = args
        .snapshots
        .iter()
        .copied()
        .filter(|&s| s > 0 && s < args.spp)
        .collect();
    counts.push(args.spp);
    counts.sort_unstable();
    counts.dedup();
    let start = std::time::Instant::now();
    let threads = args.common.thread_count();
    let mut film = FeatureFilm::new(cam.width as usize, cam.height as usize);
    let final_level = if args.reference {
        Level::Reference
    } else {
        Level::Spp(args.spp as u64)
    };
    for &target in &counts {
        film.advance(&world, &cam, args.common.seed, threads, target);
        let level = if target == args.spp {
            final_level
        } else {
            Level::Spp(target as u64)
        };
        let info = RunInfo::new(
            ESTIMATOR,
            target as u64,
            args.common.seed,
            start.elapsed().as_secs_f64(),
            &world.scene.content_hash,
        );
        let write = |kind: Kind, pixels: Vec<[f32; 3]>| -> Result<()> {
            let mut img = RgbImage::new(film.width, film.height);
            img.pixels = pixels;
            img.attributes = info.to_attributes();
            img.set_attribute(header::PIXEL_FILTER, "box");
            write_rgb(&image_path(&prefix, level, kind), &img)
        };
        write(Kind::Alb, film.albedo())?;
        write(Kind::Nrm, film.normal())?;
        if args.depth {
            write(Kind::Depth, film.depth())?;
        }
    }
    eprintln!(
        "wrote {}_{}.{{alb,nrm{}}}.exr ({} spp, {:.2} s)",
        prefix.display(),
        final_level,
        if args.depth { ",z" } else { "" },
        args.spp,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
