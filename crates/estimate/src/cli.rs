//! The `estimate` command line: its arguments, and each subcommand's run from arguments to
//! output files. The estimators themselves are [`crate::local_estimate`],
//! [`crate::direct_simulation`], [`crate::gather`], [`crate::double_local_estimate`] and
//! [`crate::light_tracing`].

use crate::direct_simulation::{self, DirectSimulationConfig};
use crate::double_local_estimate::{self, ImageConfig};
use crate::image::{self, ImageResult};
use crate::light_tracing::{self, LightTraceConfig};
use crate::local_estimate::{self, LocalConfig, NearField};
use crate::placement::Placement;
use crate::sensor_batches::{Batches, SensorEstimates};
use crate::sensors::{
    all_sensors, evaluation_points, load_world, record_evaluation_points, results, Estimate,
};
use crate::singularity::Singularity;
use crate::{exact_table, gather, glare, work};
use clap::{Parser, Subcommand, ValueEnum};
use luxest_io::cli::{CommonArgs, Console};
use luxest_io::exr::write_rgb_to;
use luxest_io::header;
use luxest_io::header::estimator;
use luxest_io::image::RgbImage;
use luxest_io::meta::RunInfo;
use luxest_io::naming::{self, image_path, Kind, Level};
use luxest_io::num::{Count, Real};
use luxest_io::outputs::{Format, OutputPlan};
use luxest_io::png::write_preview_png_auto_to;
use luxest_io::sensors::SensorResults;
use luxest_io::{Error, Result};
use luxest_render::world::{load_with_camera, Traversal, World};
use std::path::{Path, PathBuf};

/// Local estimates of illuminance, exact solutions and validation.
#[derive(Parser, Debug)]
#[command(name = "estimate", version, about)]
pub struct Args {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(clap::Args, Debug, Clone)]
pub struct RunArgs {
    /// Compiled scene (build/<name>/scene.lxs).
    pub scene: PathBuf,
    /// Output sensor results (.ron) [default: <scene dir>/<name>.sensors.ron].
    #[arg(short, long)]
    pub out: Option<PathBuf>,
    /// Also write the results as CSV to this file.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Independent batches (for the standard error), 2 to 2^20.
    #[arg(long, default_value_t = 32, value_parser = Count::<usize>::range(2, 1 << 20, "batches"))]
    pub batches: usize,
    #[command(flatten)]
    pub common: CommonArgs,
    /// Safety bound on path length, 1 to 2^20 (the bias it causes is below q^max_depth for
    /// survival q).
    #[arg(long, default_value_t = 100_000, value_parser = MAX_DEPTH)]
    pub max_depth: u32,
    /// Sensors on edges or in corners are evaluated this far off the adjacent surfaces, m
    /// [default: 1e-3 of the room scale, the smallest non-flat side of the bounding box; at
    /// most a tenth of it] (sensors and gather; estimate direct counts at the authored points).
    #[arg(long, value_parser = Real::positive("m"))]
    pub edge_offset: Option<f64>,
    /// The environment sampled through the scene's portals (its open windows and `portals`)
    /// at the sensors (`auto`, the default), or over the whole sky (`off`); refused where the
    /// scene has no portals, and by estimate direct.
    #[arg(long, value_enum)]
    pub portals: Option<Portals>,
}

/// Refuses an explicit `--portals` on a world without portals (before `set_portals`), else
/// applies it (`auto` when not given).
fn apply_portals(world: &mut World, portals: Option<Portals>) -> Result<()> {
    if portals.is_some() && world.portal_count() == 0 {
        return Err(no_effect(
            "--portals",
            "on a scene without portals (no open rectangular windows, no `portals`, or no environment)",
        ));
    }
    world.set_portals(portals != Some(Portals::Off));
    Ok(())
}

/// Whether a stage samples the environment through the scene's portals.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq)]
pub enum Portals {
    Auto,
    Off,
}

impl RunArgs {
    /// How a forward estimator's `paths` light paths are split, seeded and run.
    fn batches(&self, paths: u64) -> Batches {
        Batches {
            paths,
            batches: self.batches,
            seed: self.common.seed,
            threads: self.common.thread_count(),
        }
    }
    /// Loads the scene and checks that every batch's sums for every sensor point fit in the
    /// memory available (--batches 2^20 over a 1000-point grid would need 67 GB).
    fn load(&self) -> Result<World> {
        let mut world = load_world(&self.scene)?;
        apply_portals(&mut world, self.portals)?;
        let points: usize = world
            .scene
            .header
            .sensors
            .iter()
            .map(|s| s.points.len())
            .sum();
        luxest_io::limits::check_allocation(
            &format!("--batches {} over {points} sensor points", self.batches),
            self.batches as u128 * points as u128,
            crate::sensor_batches::BYTES_PER_BATCH_POINT,
        )
        .map_err(Error::Usage)?;
        Ok(world)
    }
    /// What a work plan needs of the run: seed, --max-depth, threads and batches.
    fn plan_terms(&self) -> (u64, u32, usize, usize) {
        (
            self.common.seed,
            self.max_depth,
            self.common.thread_count(),
            self.batches.max(2),
        )
    }
    /// `count` (`--paths` or `--samples`, named `what`) must fill every batch.
    fn check(&self, what: &str, count: u64) -> Result<()> {
        if count < self.batches as u64 {
            return Err(Error::Usage(format!(
                "{what} {count} is less than --batches {}: every batch needs at least one",
                self.batches
            )));
        }
        Ok(())
    }

    /// The sensor results (at `--out` or `<scene dir>/<name>.sensors.ron`) and the CSV on
    /// request, planned against the scene before any work: the RON path and the plan.
    fn plan(&self, world: &World) -> Result<(PathBuf, OutputPlan)> {
        let out = self.out.clone().unwrap_or_else(|| {
            naming::sensors_path(
                self.scene.parent().unwrap_or(Path::new("")),
                &world.scene.header.name,
            )
        });
        let plan = OutputPlan::new([&self.scene], std::iter::once(&out).chain(&self.csv))?;
        if self.out.is_some() {
            Format::Ron.check(&out, "-o/--out")?;
        }
        if let Some(csv) = &self.csv {
            Format::Csv.check(csv, "--csv")?;
        }
        Ok((out, plan))
    }

    /// The run metadata of an estimate of this run.
    fn info(&self, world: &World, estimator: &str, samples: u64, seconds: f64) -> RunInfo {
        RunInfo::new(
            estimator,
            samples,
            self.common.seed,
            seconds,
            &world.scene.content_hash,
        )
    }

    fn edge_offset(&self, world: &World) -> Result<f64> {
        let d = self
            .edge_offset
            .unwrap_or(DEFAULT_EDGE_OFFSET_FRACTION * world.room_scale);
        if !(d > 0.0 && d.is_finite()) {
            return Err(Error::Usage(format!(
                "--edge-offset must be positive, got {d}"
            )));
        }
        // Sensors move this far off their edges: beyond a tenth of the room they end up far
        // from where they were authored, or outside the room (1e300 aborted the process).
        let most = MAX_EDGE_OFFSET_FRACTION * world.room_scale;
        if d > most {
            return Err(Error::Usage(format!(
                "--edge-offset {} m exceeds {} m, a tenth of the scene's room scale",
                luxest_io::num::show(d),
                luxest_io::num::show(most)
            )));
        }
        Ok(d)
    }
}

/// Path-length bound of every estimator: 0 would give nothing but the direct light, or black.
pub const MAX_DEPTH: Count<u32> = Count::range(1, 1 << 20, "bounces");

/// Light paths or samples: at least one.
const PATHS: Count<u64> = Count::at_least_one("paths");

/// A length in m: finite and > 0 (a negative or NaN radius silently disabled what it sets).
const LENGTH: Real = Real::positive("m");

/// Default kernel clamp radius for images, as a fraction of the room scale (images have no
/// near-field split, so a larger radius keeps pixels near edges from sparkling).
pub const DEFAULT_IMAGE_EPS_FRACTION: f64 = 1e-2;

/// Default light-tracing paths per light path of `estimate image`. Measured on the Cornell box
/// 256² (docs/measurements.md), relMSE × CPU-s, two seeds, 3 M light-tracing paths: 30 light
/// paths × 100 000: 2.4e-2, 3.4e-2; 100 × 30 000: 1.0e-2, 1.1e-2; 300 × 10 000: 6.3e-3,
/// 6.2e-3; 1000 × 3 000: 7.1e-3, 5.7e-3 (light tracing alone 1.9e-2, 1.8e-2; the plain
/// estimate, 300 paths: 9.6e-2, 4.9e-2).
pub const DEFAULT_MIS_PATHS: u32 = 10_000;

/// Most backward samples per near-field sensor by default (the default is --paths, at most
/// this). A fixed 20 000 made the near field's work independent of --paths: in a closed room of
/// reflectance 1, where every walk runs to --max-depth, 64 light paths took seconds and their
/// near field hours.
pub const DEFAULT_NEAR_SAMPLES: u64 = 20_000;

/// Default near-field radius, as a fraction of the room scale. Chosen by measurement on the
/// Cornell box's 88 lit sensors (docs/measurements.md): 1e-2 left sensors just beyond it (8 mm
/// from a block face) with 10 times the median relative error and 5 times the CPU time for
/// every sensor to reach 1 %; radii proportional to each sensor's distance to the nearest
/// surface (3 and 10 times it) did better, one radius of 1e-1 best of all.
pub const DEFAULT_NEAR_FRACTION: f64 = 1e-1;

/// Default distance of edge/corner sensors from the adjacent surfaces, as a fraction of the
/// room scale.
pub const DEFAULT_EDGE_OFFSET_FRACTION: f64 = 1e-3;

/// Largest `--edge-offset`, as a fraction of the room scale.
pub const MAX_EDGE_OFFSET_FRACTION: f64 = 0.1;

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq)]
pub enum SingularityMode {
    Ball,
    Clamp,
    None,
}

impl SingularityMode {
    /// The singularity treatment with regularisation radius `eps` (m), which must be positive.
    fn with_eps(self, eps: f64) -> Result<Singularity> {
        if !(eps > 0.0 && eps.is_finite()) {
            return Err(Error::Usage(format!("--eps must be positive, got {eps}")));
        }
        Ok(match self {
            SingularityMode::Ball => Singularity::Ball { eps },
            SingularityMode::Clamp => Singularity::Clamp { eps },
            SingularityMode::None => Singularity::None,
        })
    }
}

/// Default kernel regularisation radius, as a fraction of the scene's room scale (the smallest
/// non-flat side of its bounding box; chosen from the corner measurement in the README).
pub const DEFAULT_EPS_FRACTION: f64 = 1e-3;

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Local estimate of illuminance at all sensor points of a scene.
    Sensors {
        #[command(flatten)]
        run: RunArgs,
        /// Number of light paths (at least --batches).
        #[arg(long, default_value_t = 100_000, value_parser = PATHS)]
        paths: u64,
        /// How the kernel singularity near sensor points is controlled.
        #[arg(long, value_enum, default_value_t = SingularityMode::Ball)]
        singularity: SingularityMode,
        /// Regularisation radius in m [default: 1e-3 of the room scale, the smallest non-flat
        /// side of the scene's bounding box].
        #[arg(long, value_parser = LENGTH)]
        eps: Option<f64>,
        /// Near-field radius, m: for sensors with another surface this close, collisions
        /// nearer than this are estimated backwards instead [default: 1e-1 of the room scale;
        /// --near-samples 0 turns the split off].
        #[arg(long, value_parser = LENGTH)]
        near_radius: Option<f64>,
        /// Backward samples per near-field sensor (0 disables the split) [default: --paths, at
        /// most 20 000, so that the near field's work grows with the light paths' and never
        /// exceeds about twice theirs].
        #[arg(long)]
        near_samples: Option<u64>,
        /// Also write every batch's estimate per point (`batches[b][k]` of each set), from
        /// which statistics over several points (a grid's Emin, U0) get their uncertainty.
        #[arg(long)]
        batch_values: bool,
    },
    /// Double local estimate: a luminance image from the scene's camera (EXR, like trace's).
    Image(ImageArgs),
    /// Direct simulation baseline: photons counted in disks around the sensor points.
    Direct {
        #[command(flatten)]
        run: RunArgs,
        /// Number of light paths (at least --batches).
        #[arg(long, default_value_t = 100_000, value_parser = PATHS)]
        paths: u64,
        /// Radius of the counting disk around each sensor, m.
        #[arg(long, value_parser = LENGTH)]
        bin_radius: f64,
    },
    /// Backward (gathering) estimate at the sensor points: an independent reference that has
    /// no kernel singularity (scenes without specular paths).
    Gather {
        #[command(flatten)]
        run: RunArgs,
        /// Samples per sensor point (at least --batches).
        #[arg(long, default_value_t = 10_000, value_parser = PATHS)]
        samples: u64,
    },
    /// Print exact solutions.
    Exact {
        #[command(subcommand)]
        case: ExactCase,
    },
}

#[derive(Subcommand, Debug)]
pub enum ExactCase {
    /// Point source between two parallel Lambertian planes: E1(r), E2(r).
    Sobolev {
        #[arg(long, default_value_t = 100.0)]
        intensity: f64,
        #[arg(long, default_value_t = 1.0)]
        h1: f64,
        #[arg(long, default_value_t = 1.0)]
        h2: f64,
        #[arg(long, default_value_t = 0.5)]
        rho1: f64,
        #[arg(long, default_value_t = 0.5)]
        rho2: f64,
        /// Distances from the foot of the source, m.
        #[arg(long, value_delimiter = ',', default_value = "0,0.5,1,2,4,8")]
        r: Vec<f64>,
    },
    /// Integrating sphere with a central source: direct, indirect and total at the wall.
    Sphere {
        #[arg(long, default_value_t = 100.0)]
        intensity: f64,
        #[arg(long, default_value_t = 1.0)]
        radius: f64,
        #[arg(long, default_value_t = 0.5)]
        rho: f64,
    },
    /// CIE 171:2006 case 5.8: mean indirect illuminance in a closed room.
    Cie171 {
        #[arg(long, default_value_t = 10_000.0)]
        flux: f64,
        #[arg(long, default_value_t = 96.0)]
        area: f64,
        #[arg(long, default_value_t = 0.5)]
        rho: f64,
    },
}

/// `estimate image`: the double local estimate (or light tracing) of the camera's image.
#[derive(clap::Args, Debug, Clone)]
pub struct ImageArgs {
    /// Compiled scene (build/<name>/scene.lxs).
    pub scene: PathBuf,
    /// Output [default: <scene dir>/<name>_<paths, 6 digits>le.hdr.exr].
    #[arg(short, long)]
    pub out: Option<PathBuf>,
    /// Also write the per-pixel standard error of Y as an EXR (R = G = B).
    #[arg(long)]
    pub stderr_out: Option<PathBuf>,
    /// Also write an sRGB PNG preview (exposure: 1 / the 99th percentile of Y).
    #[arg(long)]
    pub preview: Option<PathBuf>,
    /// Number of light paths connected to the pixels' points (light tracing adds
    /// --mis-paths per path).
    #[arg(long, default_value_t = 300, value_parser = PATHS)]
    pub paths: u64,
    /// Camera samples per pixel (box filter), at least 1, drawn anew for every 32 light
    /// paths (the rounds' points together stratify the pixel).
    #[arg(long, default_value_t = 1, value_parser = Count::<u32>::range(1, u32::MAX as u64, "samples per pixel"))]
    pub pixel_samples: u32,
    /// Override the camera resolution, WIDTHxHEIGHT.
    #[arg(long)]
    pub resolution: Option<String>,
    /// The kernel singularity's treatment where light tracing cannot take over: at points
    /// seen through mirrors or glass, and everywhere with --mis-paths 0 [default: clamp]
    /// (with --mis-paths above 0 in a scene without mirrors or glass it has no effect and
    /// is refused, as is --eps).
    #[arg(long, value_enum)]
    pub singularity: Option<SingularityMode>,
    /// Regularisation radius in m [default: 1e-2 of the room scale].
    #[arg(long, value_parser = LENGTH)]
    pub eps: Option<f64>,
    #[command(flatten)]
    pub common: CommonArgs,
    /// Safety bound on path length, 1 to 2^20.
    #[arg(long, default_value_t = 100_000, value_parser = MAX_DEPTH)]
    pub max_depth: u32,
    /// Light-tracing paths per light path, combined with the connections by multiple
    /// importance sampling at the points the camera sees directly (unbiased at edges and
    /// corners); 0: the plain double local estimate, --singularity everywhere (biased
    /// near edges and corners).
    #[arg(long, default_value_t = DEFAULT_MIS_PATHS, value_parser = Count::<u32>::range(0, 1 << 20, "light-tracing paths per light path"))]
    pub mis_paths: u32,
    /// Light tracing instead (a baseline): every light-path vertex is connected to the
    /// camera itself, not to the points the pixels see (the local estimate at the camera);
    /// --mis-paths, --pixel-samples, --singularity and --eps do not apply (refused). Scenes
    /// whose camera would see mirrors or glass are refused.
    #[arg(long, conflicts_with_all = ["mis_paths", "pixel_samples", "singularity", "eps"])]
    pub light_tracing: bool,
    /// The environment sampled through the scene's portals at the points the camera sees
    /// (`auto`, the default), or over the whole sky (`off`); refused where the scene has no
    /// portals, and with --light-tracing.
    #[arg(long, value_enum, conflicts_with = "light_tracing")]
    pub portals: Option<Portals>,
}

/// Runs the command line.
pub fn run(args: Args) -> Result<()> {
    match args.command {
        Command::Sensors {
            run,
            paths,
            singularity,
            eps,
            near_radius,
            near_samples,
            batch_values,
        } => sensors(
            &run,
            paths,
            singularity,
            eps,
            (near_radius, near_samples),
            batch_values,
        ),
        Command::Direct {
            run,
            paths,
            bin_radius,
        } => direct(&run, paths, bin_radius),
        Command::Gather { run, samples } => gather(&run, samples),
        Command::Image(image) => image_run(image),
        Command::Exact { case } => exact_table::print(case),
    }
}

/// `estimate image`: the double local estimate of the camera's image, or light tracing.
fn image_run(args: ImageArgs) -> Result<()> {
    let ImageArgs {
        scene,
        out,
        stderr_out,
        preview,
        paths,
        pixel_samples,
        resolution,
        singularity,
        eps,
        common,
        max_depth,
        mis_paths,
        light_tracing,
        portals,
    } = args;
    let explicit = singularity.is_some() || eps.is_some();
    let singularity = singularity.unwrap_or(SingularityMode::Clamp);
    check_eps(singularity, eps)?;
    let (mut world, cam) = load_with_camera(&scene, resolution.as_deref(), Traversal::Robust)?;
    apply_portals(&mut world, portals)?;
    if explicit && mis_paths > 0 && !world.scene.header.features.specular_paths {
        return Err(no_effect(
            "--singularity/--eps",
            &format!(
                "with --mis-paths above 0 in {}: it has no mirrors or glass, so light \
                 tracing takes over at every point the camera sees (--mis-paths 0 gives \
                 the plain estimate that uses them)",
                scene.display()
            ),
        ));
    }
    luxest_io::limits::check_image(
        "image film",
        cam.width.into(),
        cam.height.into(),
        image::BYTES_PER_PIXEL,
    )
    .map_err(Error::Usage)?;
    let eps = eps.unwrap_or(DEFAULT_IMAGE_EPS_FRACTION * world.room_scale);
    let console = common.console;
    let cfg = ImageConfig {
        paths,
        pixel_samples,
        seed: common.seed,
        threads: common.thread_count(),
        singularity: singularity.with_eps(eps)?,
        max_depth,
        mis_paths,
    };
    let prefix = scene.with_file_name(&world.scene.header.name);
    let out = out.unwrap_or_else(|| image_path(&prefix, Level::LightPaths(paths), Kind::Hdr));
    // All outputs, checked against the scene and each other before the render.
    let outputs = std::iter::once(&out).chain(&stderr_out).chain(&preview);
    let mut plan = OutputPlan::new([&scene], outputs)?;
    for (path, format, option) in [
        (Some(&out), Format::Exr, "-o/--out"),
        (stderr_out.as_ref(), Format::Exr, "--stderr-out"),
        (preview.as_ref(), Format::Png, "--preview"),
    ] {
        if let Some(path) = path {
            format.check(path, option)?;
        }
    }
    let outputs = ImageOutputs {
        out: &out,
        stderr_out: stderr_out.as_deref(),
        preview: preview.as_deref(),
    };
    let info = |estimator: &str, seconds: f64| {
        RunInfo::new(
            estimator,
            paths,
            common.seed,
            seconds,
            &world.scene.content_hash,
        )
    };
    if light_tracing {
        if world.scene.header.features.specular_paths {
            return Err(Error::input(
                &scene,
                "light tracing cannot connect mirrors or glass to a pinhole camera (use trace or estimate image without --light-tracing)",
            ));
        }
        if paths < image::BATCHES as u64 {
            return Err(Error::Usage(format!(
                "--paths must be at least {} for --light-tracing (one per batch)",
                image::BATCHES
            )));
        }
        let lt = LightTraceConfig {
            paths,
            seed: common.seed,
            threads: common.thread_count(),
            max_depth,
        };
        console.announce(&work::light_tracing_plan(
            &world,
            &cam,
            paths,
            (lt.seed, max_depth, lt.threads),
        ));
        let progress = console.progress("estimate image --light-tracing", Some(paths), "paths");
        let r = light_tracing::render(&world, &cam, &lt, &progress);
        progress.finish();
        let info = info(estimator::LIGHT_TRACING, r.seconds);
        write_image(&mut plan, &scene, &r, info, None, outputs, console)
    } else {
        console.announce(&work::image_plan(&world, &cam, &cfg).map_err(Error::Usage)?);
        let r = double_local_estimate::render(&world, &cam, &cfg, &console);
        let info = info(estimator::DOUBLE_LOCAL_ESTIMATE, r.seconds);
        write_image(&mut plan, &scene, &r, info, Some(&cfg), outputs, console)
    }
}

/// The usage error for `option`, given where it has no effect (`context`): options that would
/// change nothing are refused rather than ignored, so that a user never believes a setting
/// was used.
fn no_effect(option: &str, context: &str) -> Error {
    Error::Usage(format!("{option} has no effect {context}; leave it out"))
}

/// `--eps` with `--singularity none`: the raw kernel has no radius to set.
fn check_eps(singularity: SingularityMode, eps: Option<f64>) -> Result<()> {
    match (singularity, eps) {
        (SingularityMode::None, Some(_)) => Err(no_effect(
            "--eps",
            "with --singularity none (the raw kernel has no radius)",
        )),
        _ => Ok(()),
    }
}

/// A warning on stderr when light paths reached --max-depth still carrying light: the light
/// they would have added is missing from the results (e.g. a closed scene of reflectance 1,
/// where paths never end by themselves).
fn warn_truncated(console: Console, r: &SensorEstimates, paths: u64, max_depth: u32) {
    if r.truncated > 0 {
        console.note(format_args!(
            "warning: {} of {paths} light paths reached --max-depth {max_depth} still carrying \
             light; what they would have added is missing (biased low): raise --max-depth, or \
             look for reflectances near 1 in a closed scene",
            r.truncated
        ));
    }
}

/// A note on stderr when sensors on edges or in corners are evaluated `delta` m off the
/// adjacent surfaces (`placed`, [`evaluation_points`]).
fn note_moved(console: Console, placed: &Placement, delta: f64) {
    if placed.moved > 0 {
        console.note(format_args!(
            "note: {} sensor(s) on edges or in corners are evaluated {delta:e} m off the \
             adjacent surfaces",
            placed.moved
        ));
    }
}

/// `estimate sensors`: the local estimate at every sensor point.
fn sensors(
    run: &RunArgs,
    paths: u64,
    singularity: SingularityMode,
    eps: Option<f64>,
    (near_radius, near_samples): (Option<f64>, Option<u64>),
    batch_values: bool,
) -> Result<()> {
    run.check("--paths", paths)?;
    check_eps(singularity, eps)?;
    let near_samples = near_samples.unwrap_or(paths.min(DEFAULT_NEAR_SAMPLES));
    if near_samples == 0 && near_radius.is_some() {
        return Err(no_effect(
            "--near-radius",
            "with --near-samples 0 (the near-field split is off)",
        ));
    }
    let world = run.load()?;
    let (out, mut plan) = run.plan(&world)?;
    let sing = singularity.with_eps(eps.unwrap_or(DEFAULT_EPS_FRACTION * world.room_scale))?;
    let near_radius = near_radius.unwrap_or(DEFAULT_NEAR_FRACTION * world.room_scale);
    let console = run.common.console;
    let edge_offset = run.edge_offset(&world)?;
    let mut placed = evaluation_points(&world, edge_offset, near_radius);
    note_moved(console, &placed, edge_offset);
    // The observers' eyes (glare): evaluated after the scene's sensors, reported apart.
    let sensor_count = placed.points.len();
    let eyes = crate::placement::place(&world, &glare::points(&world), edge_offset, near_radius);
    placed.points.extend(eyes.points);
    placed.near_radius.extend(eyes.near_radius);
    let near_field = (near_samples > 0).then_some(NearField {
        samples: near_samples,
    });
    let cfg = LocalConfig {
        batches: run.batches(paths),
        singularity: sing,
        max_depth: run.max_depth,
        near_field,
        // The sky's direct term: one sample (two shadow rays at most) per sensor and light path,
        // about what the light paths' connections to each sensor cost.
        environment_samples: paths,
    };
    // Each batch takes at least one near-field sample per sensor.
    let near_total = match cfg.near_field {
        Some(nf) => (nf.samples / cfg.batches.count() as u64).max(1) * cfg.batches.count() as u64,
        None => 0,
    };
    console.announce(&work::sensors_plan(
        &world,
        &placed.points,
        &placed.near_radius,
        paths,
        near_total,
        run.plan_terms(),
    ));
    let progress = console.progress(
        "estimate sensors",
        Some(local_estimate::progress_total(
            &placed.points,
            &placed.near_radius,
            &cfg,
        )),
        "paths",
    );
    let r = local_estimate::estimate(&world, &placed.points, &placed.near_radius, &cfg, &progress);
    progress.finish();
    warn_truncated(console, &r, paths, run.max_depth);
    let info = run.info(&world, estimator::LOCAL_ESTIMATE, paths, r.seconds);
    let batches = batch_values.then_some(r.batch_values.as_slice());
    let mut values = r.estimates();
    let at_eye = values.split_off(sensor_count);
    record_evaluation_points(&world, &mut values, &placed.points);
    let mut results = results(&run.scene, &world, info, sing.to_string(), &values)?;
    results.glare = glare::results(&run.scene, &world, &at_eye)?;
    for g in &results.glare {
        console.note(format_args!(
            "glare: observer \"{}\" along ({:.3}, {:.3}, {:.3}): UGR {:.2} ± {:.2} (L_b {:.2} cd/m², {} sources)",
            g.observer, g.view.x, g.view.y, g.view.z, g.ugr, g.standard_error,
            g.background_luminance.value, g.sources.len()
        ));
    }
    write_results(&mut plan, &out, run, results, batches)?;
    console.note(format_args!(
        "wrote {}: {} paths, {} collisions, {} shadow rays, {:.2} s",
        out.display(),
        paths,
        r.collisions,
        r.shadow_rays,
        r.seconds
    ));
    Ok(())
}

/// `estimate direct`: the direct-simulation baseline, photons counted in disks.
fn direct(run: &RunArgs, paths: u64, bin_radius: f64) -> Result<()> {
    run.check("--paths", paths)?;
    if run.portals.is_some() {
        return Err(no_effect(
            "--portals",
            "on estimate direct (its light paths leave the sky through the bounding disk)",
        ));
    }
    if run.edge_offset.is_some() {
        return Err(no_effect(
            "--edge-offset",
            "on estimate direct (it counts photons in disks around the authored sensor points)",
        ));
    }
    let world = run.load()?;
    crate::sensors::require_planar(&run.scene, &world, "estimate direct")?;
    let (out, mut plan) = run.plan(&world)?;
    let sensors = all_sensors(&world);
    let cfg = DirectSimulationConfig {
        batches: run.batches(paths),
        radius: bin_radius,
        max_depth: run.max_depth,
    };
    let console = run.common.console;
    console.announce(&work::direct_plan(
        &world,
        sensors.len(),
        paths,
        run.plan_terms(),
    ));
    let progress = console.progress("estimate direct", Some(paths), "paths");
    let r = direct_simulation::estimate(&world, &sensors, &cfg, &progress);
    progress.finish();
    warn_truncated(console, &r, paths, run.max_depth);
    let info = run.info(&world, estimator::DIRECT_SIMULATION, paths, r.seconds);
    let singularity = format!("bins(radius={bin_radius:e} m)");
    let values = r.estimates();
    let results = results(&run.scene, &world, info, singularity, &values)?;
    write_results(&mut plan, &out, run, results, None)?;
    console.note(format_args!(
        "wrote {}: {} paths, {:.2} s",
        out.display(),
        paths,
        r.seconds
    ));
    Ok(())
}

/// `estimate gather`: the backward reference estimator.
fn gather(run: &RunArgs, samples: u64) -> Result<()> {
    run.check("--samples", samples)?;
    let world = run.load()?;
    crate::sensors::require_planar(&run.scene, &world, "estimate gather")?;
    if world.scene.header.features.specular_paths {
        return Err(Error::input(
            &run.scene,
            "gather needs a scene without mirrors or dielectrics",
        ));
    }
    let (out, mut plan) = run.plan(&world)?;
    let console = run.common.console;
    let edge_offset = run.edge_offset(&world)?;
    let placed = evaluation_points(&world, edge_offset, 0.0);
    note_moved(console, &placed, edge_offset);
    let sensors = placed.points;
    let cfg = gather::GatherConfig {
        samples,
        batches: run.batches,
        seed: run.common.seed,
        threads: run.common.thread_count(),
        max_depth: run.max_depth,
    };
    let per_sensor = (samples / cfg.batches.max(2) as u64).max(1) * cfg.batches.max(2) as u64;
    console.announce(&work::gather_plan(
        &world,
        &sensors,
        per_sensor,
        run.plan_terms(),
    ));
    let start = std::time::Instant::now();
    let progress = console.progress(
        "estimate gather",
        Some(gather::progress_total(sensors.len(), &cfg)),
        "samples",
    );
    let mut values: Vec<Estimate> = gather::estimate(&world, &sensors, &cfg, &progress)
        .into_iter()
        .map(Estimate::from)
        .collect();
    progress.finish();
    record_evaluation_points(&world, &mut values, &sensors);
    let info = run.info(
        &world,
        estimator::GATHER,
        samples,
        start.elapsed().as_secs_f64(),
    );
    let singularity = "none (backward estimator)".to_string();
    let results = results(&run.scene, &world, info, singularity, &values)?;
    write_results(&mut plan, &out, run, results, None)?;
    console.note(format_args!("wrote {}", out.display()));
    Ok(())
}

/// Writes the sensor results as RON to the planned `out`, with the per-batch estimates when
/// given, and, on request, CSV; commits both together.
fn write_results(
    plan: &mut OutputPlan,
    out: &Path,
    run: &RunArgs,
    mut results: SensorResults,
    batches: Option<&[Vec<f64>]>,
) -> Result<()> {
    if let Some(b) = batches {
        crate::sensors::attach_batches(&mut results, b);
    }
    results.write_ron_to(plan, out)?;
    if let Some(csv) = &run.csv {
        results.write_csv_to(plan, csv)?;
    }
    plan.commit()
}

/// Where `estimate image` writes: the image, and on request its standard error and a preview.
#[derive(Clone, Copy)]
struct ImageOutputs<'a> {
    out: &'a Path,
    stderr_out: Option<&'a Path>,
    preview: Option<&'a Path>,
}

/// Writes a rendered image of `estimate image` (the double local estimate with its `cfg`, or
/// the light tracer) with its standard error and preview on request, all committed together.
fn write_image(
    plan: &mut OutputPlan,
    scene: &Path,
    r: &ImageResult,
    info: RunInfo,
    cfg: Option<&ImageConfig>,
    outputs: ImageOutputs,
    console: Console,
) -> Result<()> {
    let ImageOutputs {
        out,
        stderr_out,
        preview,
    } = outputs;
    if let Some(i) = r.rgb.iter().position(|c| !c.is_finite()) {
        return Err(Error::input(scene, format!("pixel {i} is not finite")));
    }
    let paths = info.samples;
    let mut img = RgbImage::new(r.width, r.height);
    img.pixels = r.rgb.iter().map(|c| c.0.map(|v| v as f32)).collect();
    img.attributes = info.to_attributes();
    if let Some(cfg) = cfg {
        img.set_attribute(
            header::SINGULARITY,
            double_local_estimate::singularity_header(cfg),
        );
        img.set_attribute(header::PIXEL_SAMPLES, cfg.pixel_samples);
    }
    write_rgb_to(plan, out, &img)?;
    if let Some(p) = preview {
        write_preview_png_auto_to(plan, p, &img)?;
    }
    if let Some(p) = stderr_out {
        let mut se = RgbImage::new(r.width, r.height);
        se.pixels = r.standard_error.iter().map(|&v| [v as f32; 3]).collect();
        se.attributes = img.attributes.clone();
        write_rgb_to(plan, p, &se)?;
    }
    plan.commit()?;
    console.note(format_args!(
        "wrote {}: {}x{}, {} paths, {} collisions, {} shadow rays, {:.2} s ({:.1} M shadow rays/s)",
        out.display(),
        r.width,
        r.height,
        paths,
        r.collisions,
        r.shadow_rays,
        r.seconds,
        r.shadow_rays as f64 / r.seconds / 1e6
    ));
    Ok(())
}
