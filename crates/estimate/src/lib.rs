//! estimate: the local estimate of illuminance at sensor points, a backward reference
//! estimator, exact solutions and their comparison with results.
//!
//! Subcommands: `sensors` (local estimate), `gather` (backward reference estimator), `exact`
//! (print exact solutions), `compare` (results against an exact case, with a z-test).

pub mod compare;
pub mod gather;
pub mod image;
pub mod local;
pub use luxest_core::parallel;
pub mod placement;
pub mod singularity;

use clap::{Parser, Subcommand, ValueEnum};
use luxest_core::compiled::CompiledScene;
use luxest_core::meta::{RunInfo, PROGRAM_VERSION};
use luxest_core::scene::SensorPoint;
use luxest_core::sensors::{SensorResults, SensorSetResult, SensorValue};
use luxest_core::world::World;
use luxest_core::{Error, Result};
use singularity::Singularity;
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
    /// Independent batches (for the standard error).
    #[arg(long, default_value_t = 32)]
    pub batches: usize,
    #[command(flatten)]
    pub common: luxest_core::cli::CommonArgs,
    /// Safety bound on path length (the bias it causes is below q^max_depth for survival q).
    #[arg(long, default_value_t = 100_000)]
    pub max_depth: u32,
    /// Sensors on edges or in corners are evaluated this far off the adjacent surfaces, m
    /// [default: 1e-3 of the room scale, the smallest non-flat side of the bounding box].
    #[arg(long)]
    pub edge_offset: Option<f64>,
}

impl RunArgs {
    fn edge_offset(&self, world: &World) -> Result<f64> {
        let d = self
            .edge_offset
            .unwrap_or(DEFAULT_EDGE_OFFSET_FRACTION * world.room_scale);
        if d > 0.0 && d.is_finite() {
            Ok(d)
        } else {
            Err(Error::Usage(format!(
                "--edge-offset must be positive, got {d}"
            )))
        }
    }
}

/// Default kernel clamp radius for images, as a fraction of the room scale (images have no
/// near-field split, so a larger radius keeps pixels near edges from sparkling).
pub const DEFAULT_IMAGE_EPS_FRACTION: f64 = 1e-2;

/// Default near-field radius, as a fraction of the room scale.
pub const DEFAULT_NEAR_FRACTION: f64 = 1e-2;

/// Default distance of edge/corner sensors from the adjacent surfaces, as a fraction of the
/// room scale.
pub const DEFAULT_EDGE_OFFSET_FRACTION: f64 = 1e-3;

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq)]
pub enum SingularityMode {
    Ball,
    Clamp,
    None,
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
        /// Number of light paths.
        #[arg(long, default_value_t = 100_000)]
        paths: u64,
        /// How the kernel singularity near sensor points is controlled.
        #[arg(long, value_enum, default_value_t = SingularityMode::Ball)]
        singularity: SingularityMode,
        /// Regularisation radius in m [default: 1e-3 of the room scale, the smallest non-flat
        /// side of the scene's bounding box].
        #[arg(long)]
        eps: Option<f64>,
        /// Near-field radius, m: for sensors with another surface this close, collisions
        /// nearer than this are estimated backwards instead [default: 1e-2 of the room scale].
        #[arg(long)]
        near_radius: Option<f64>,
        /// Backward samples per near-field sensor (0 disables the split).
        #[arg(long, default_value_t = 20_000)]
        near_samples: u64,
    },
    /// Double local estimate: a luminance image from the scene's camera (EXR, like trace's).
    Image {
        /// Compiled scene (build/<name>/scene.lxs).
        scene: PathBuf,
        /// Output [default: <scene dir>/<name>_<paths, 6 digits>le.hdr.exr].
        #[arg(short, long)]
        out: Option<PathBuf>,
        /// Also write the per-pixel standard error of Y as an EXR (R = G = B).
        #[arg(long)]
        stderr_out: Option<PathBuf>,
        /// Also write an sRGB PNG preview (exposure: 1 / the 99th percentile of Y).
        #[arg(long)]
        preview: Option<PathBuf>,
        /// Number of light paths.
        #[arg(long, default_value_t = 1_000)]
        paths: u64,
        /// Camera samples per pixel (stratified, box filter).
        #[arg(long, default_value_t = 1)]
        pixel_samples: u32,
        /// Override the camera resolution, WIDTHxHEIGHT.
        #[arg(long)]
        resolution: Option<String>,
        #[arg(long, value_enum, default_value_t = SingularityMode::Clamp)]
        singularity: SingularityMode,
        /// Regularisation radius in m [default: 1e-2 of the room scale].
        #[arg(long)]
        eps: Option<f64>,
        #[command(flatten)]
        common: luxest_core::cli::CommonArgs,
        #[arg(long, default_value_t = 100_000)]
        max_depth: u32,
    },
    /// Direct simulation baseline: photons counted in disks around the sensor points.
    Direct {
        #[command(flatten)]
        run: RunArgs,
        #[arg(long, default_value_t = 100_000)]
        paths: u64,
        /// Radius of the counting disk around each sensor, m.
        #[arg(long)]
        bin_radius: f64,
    },
    /// Backward (gathering) estimate at the sensor points: an independent reference that has
    /// no kernel singularity (scenes without specular paths).
    Gather {
        #[command(flatten)]
        run: RunArgs,
        /// Samples per sensor point.
        #[arg(long, default_value_t = 10_000)]
        samples: u64,
    },
    /// Print exact solutions.
    Exact {
        #[command(subcommand)]
        case: ExactCase,
    },
    /// Compare sensor results with an exact case; fails if any |z| exceeds --max-z.
    Compare {
        /// Sensor results (.sensors.ron).
        results: PathBuf,
        /// Case and parameters, e.g. `sobolev:I=100,h1=1,h2=1,rho1=0.5,rho2=0.5[,bin=R]` (bin:
        /// compare direct-simulation results with the mean over their counting disks),
        /// `sphere:I=100,R=1,rho=0.5[,x=..,y=..,z=..]`, `cie171-5.8:flux=1e4,area=96,rho=0.5,x=2,y=2,z=2`.
        #[arg(long)]
        case: String,
        #[arg(long, default_value_t = 4.0)]
        max_z: f64,
        /// Compare only these sensor sets (comma-separated names) [default: all].
        #[arg(long, value_delimiter = ',')]
        sets: Vec<String>,
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

/// Loads a compiled scene and checks that it has sensors.
pub fn load_world(path: &Path) -> Result<World> {
    let scene = CompiledScene::load(path)?;
    if scene.header.sensors.is_empty() {
        return Err(Error::input(
            path,
            "scene has no sensors (add Points or Grid sensors to the .ron)",
        ));
    }
    World::load_from(path, scene)
}

/// Every sensor point of the scene, set by set.
pub fn all_sensors(world: &World) -> Vec<SensorPoint> {
    world
        .scene
        .header
        .sensors
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .collect()
}

/// The sensors as evaluated: moved off adjacent surfaces by `delta`, flagged when another
/// surface lies within `near_radius` (see [`placement`]).
fn evaluation_points(world: &World, delta: f64, near_radius: f64) -> placement::Placement {
    let p = placement::place(world, &all_sensors(world), delta, near_radius);
    if p.moved > 0 {
        eprintln!("note: {} sensor(s) on edges or in corners are evaluated {delta:e} m off the adjacent surfaces", p.moved);
    }
    p
}

fn default_out(scene: &Path, name: &str) -> PathBuf {
    scene.with_file_name(format!("{name}.sensors.ron"))
}

/// Packs per-sensor values into the results contract and writes RON (and CSV).
fn write_results(
    world: &World,
    run: &RunArgs,
    info: RunInfo,
    singularity: String,
    values: &[(luxest_core::color::Rgb, f64, f64)],
) -> Result<PathBuf> {
    let mut k = 0;
    let sets = world
        .scene
        .header
        .sensors
        .iter()
        .map(|s| SensorSetResult {
            name: s.name.clone(),
            points: s
                .points
                .iter()
                .map(|p| {
                    let (rgb, value, standard_error) = values[k];
                    k += 1;
                    SensorValue {
                        position: p.position,
                        normal: p.normal,
                        value,
                        standard_error,
                        rgb,
                    }
                })
                .collect(),
        })
        .collect();
    if let Some((i, _)) = values
        .iter()
        .enumerate()
        .find(|(_, v)| !(v.1.is_finite() && v.2.is_finite()))
    {
        return Err(Error::input(
            &run.scene,
            format!("estimate at sensor {i} is not finite"),
        ));
    }
    let results = SensorResults {
        scene: world.scene.header.name.clone(),
        run: info,
        unit: "lx".into(),
        singularity,
        sets,
    };
    let out = run
        .out
        .clone()
        .unwrap_or_else(|| default_out(&run.scene, &world.scene.header.name));
    results.write_ron(&out)?;
    if let Some(csv) = &run.csv {
        results.write_csv(csv)?;
    }
    Ok(out)
}

fn check_run_args(run: &RunArgs) -> Result<()> {
    if run.batches < 2 {
        return Err(Error::Usage(
            "--batches must be at least 2 (the standard error needs them)".into(),
        ));
    }
    Ok(())
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
        } => {
            check_run_args(&run)?;
            if paths < run.batches as u64 {
                return Err(Error::Usage("--paths must be at least --batches".into()));
            }
            let world = load_world(&run.scene)?;
            let eps = eps.unwrap_or(DEFAULT_EPS_FRACTION * world.room_scale);
            if !(eps > 0.0 && eps.is_finite()) {
                return Err(Error::Usage(format!("--eps must be positive, got {eps}")));
            }
            let sing = match singularity {
                SingularityMode::Ball => Singularity::Ball { eps },
                SingularityMode::Clamp => Singularity::Clamp { eps },
                SingularityMode::None => Singularity::None,
            };
            let near_radius = near_radius.unwrap_or(DEFAULT_NEAR_FRACTION * world.room_scale);
            let placed = evaluation_points(&world, run.edge_offset(&world)?, near_radius);
            let sensors = placed.points;
            let near_field = (near_samples > 0).then_some(local::NearField {
                radius: near_radius,
                samples: near_samples,
            });
            let cfg = local::LocalConfig {
                paths,
                batches: run.batches,
                seed: run.common.seed,
                threads: parallel::thread_count(run.common.threads),
                detector: local::Detector::LocalEstimate(sing),
                max_depth: run.max_depth,
                near_field,
            };
            let r = local::estimate(&world, &sensors, &placed.near, &cfg);
            let info = RunInfo {
                samples: paths,
                seed: run.common.seed,
                seconds: r.seconds,
                estimator: "local-estimate".into(),
                scene_hash: world.scene.content_hash.clone(),
                program_version: PROGRAM_VERSION.into(),
            };
            let values: Vec<_> = (0..sensors.len())
                .map(|i| (r.rgb[i], r.value[i], r.standard_error[i]))
                .collect();
            let out = write_results(&world, &run, info, sing.to_string(), &values)?;
            eprintln!(
                "wrote {}: {} paths, {} collisions, {} shadow rays, {:.2} s",
                out.display(),
                paths,
                r.collisions,
                r.shadow_rays,
                r.seconds
            );
            Ok(())
        }
        Command::Direct {
            run,
            paths,
            bin_radius,
        } => {
            check_run_args(&run)?;
            if !(bin_radius > 0.0 && bin_radius.is_finite()) {
                return Err(Error::Usage(format!(
                    "--bin-radius must be positive, got {bin_radius}"
                )));
            }
            let world = load_world(&run.scene)?;
            let sensors = all_sensors(&world);
            let cfg = local::LocalConfig {
                paths,
                batches: run.batches,
                seed: run.common.seed,
                threads: parallel::thread_count(run.common.threads),
                detector: local::Detector::Bins { radius: bin_radius },
                max_depth: run.max_depth,
                near_field: None,
            };
            let r = local::estimate(&world, &sensors, &vec![false; sensors.len()], &cfg);
            let info = RunInfo {
                samples: paths,
                seed: run.common.seed,
                seconds: r.seconds,
                estimator: "direct-simulation".into(),
                scene_hash: world.scene.content_hash.clone(),
                program_version: PROGRAM_VERSION.into(),
            };
            let values: Vec<_> = (0..sensors.len())
                .map(|i| (r.rgb[i], r.value[i], r.standard_error[i]))
                .collect();
            let out = write_results(
                &world,
                &run,
                info,
                format!("bins(radius={bin_radius:e} m)"),
                &values,
            )?;
            eprintln!(
                "wrote {}: {} paths, {:.2} s",
                out.display(),
                paths,
                r.seconds
            );
            Ok(())
        }
        Command::Gather { run, samples } => {
            check_run_args(&run)?;
            let world = load_world(&run.scene)?;
            if world.scene.header.features.specular_paths {
                return Err(Error::input(
                    &run.scene,
                    "gather needs a scene without mirrors or dielectrics",
                ));
            }
            let sensors = evaluation_points(&world, run.edge_offset(&world)?, 0.0).points;
            let cfg = gather::GatherConfig {
                samples,
                batches: run.batches,
                seed: run.common.seed,
                threads: parallel::thread_count(run.common.threads),
                max_depth: run.max_depth,
            };
            let start = std::time::Instant::now();
            let values = gather::estimate(&world, &sensors, &cfg);
            let info = RunInfo {
                samples,
                seed: run.common.seed,
                seconds: start.elapsed().as_secs_f64(),
                estimator: "gather".into(),
                scene_hash: world.scene.content_hash.clone(),
                program_version: PROGRAM_VERSION.into(),
            };
            let out = write_results(
                &world,
                &run,
                info,
                "none (backward estimator)".into(),
                &values,
            )?;
            eprintln!("wrote {}", out.display());
            Ok(())
        }
        Command::Image {
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
        } => {
            if paths == 0 {
                return Err(Error::Usage("--paths must be positive".into()));
            }
            let (world, cam) = luxest_core::world::load_with_camera(&scene, resolution.as_deref())?;
            let eps = eps.unwrap_or(DEFAULT_IMAGE_EPS_FRACTION * world.room_scale);
            let sing = match singularity {
                SingularityMode::Ball => Singularity::Ball { eps },
                SingularityMode::Clamp => Singularity::Clamp { eps },
                SingularityMode::None => Singularity::None,
            };
            let cfg = image::ImageConfig {
                paths,
                pixel_samples,
                seed: common.seed,
                threads: parallel::thread_count(common.threads),
                singularity: sing,
                max_depth,
            };
            let r = image::render(&world, &cam, &cfg);
            if let Some(i) = r.rgb.iter().position(|c| !c.is_finite()) {
                return Err(Error::input(&scene, format!("pixel {i} is not finite")));
            }
            let info = RunInfo {
                samples: paths,
                seed: common.seed,
                seconds: r.seconds,
                estimator: "double-local-estimate".into(),
                scene_hash: world.scene.content_hash.clone(),
                program_version: PROGRAM_VERSION.into(),
            };
            let mut img = luxest_core::exr_io::RgbImage::new(r.width, r.height);
            img.pixels = r.rgb.iter().map(|c| c.0.map(|v| v as f32)).collect();
            img.attributes = info.to_attributes();
            img.attributes
                .push(("luxest.singularity".into(), sing.to_string()));
            img.attributes
                .push(("luxest.pixelSamples".into(), pixel_samples.to_string()));
            let out = out.unwrap_or_else(|| {
                scene.with_file_name(format!("{}_{paths:06}le.hdr.exr", world.scene.header.name))
            });
            luxest_core::exr_io::write_rgb(&out, &img)?;
            if let Some(p) = preview {
                luxest_core::exr_io::write_preview_png_auto(&p, &img)?;
            }
            if let Some(p) = stderr_out {
                let mut se = luxest_core::exr_io::RgbImage::new(r.width, r.height);
                se.pixels = r.standard_error.iter().map(|&v| [v as f32; 3]).collect();
                se.attributes = img.attributes.clone();
                luxest_core::exr_io::write_rgb(&p, &se)?;
            }
            eprintln!(
                "wrote {}: {}x{}, {} paths, {} collisions, {} shadow rays, {:.2} s ({:.1} M shadow rays/s)",
                out.display(),
                r.width,
                r.height,
                paths,
                r.collisions,
                r.shadow_rays,
                r.seconds,
                r.shadow_rays as f64 / r.seconds / 1e6
            );
            Ok(())
        }
        Command::Exact { case } => {
            print_exact(case);
            Ok(())
        }
        Command::Compare {
            results,
            case,
            max_z,
            sets,
        } => {
            let case =
                compare::Case::parse(&case).map_err(|m| Error::Usage(format!("--case: {m}")))?;
            compare::run(&results, &case, max_z, &sets)
        }
    }
}

fn print_exact(case: ExactCase) {
    match case {
        ExactCase::Sobolev {
            intensity,
            h1,
            h2,
            rho1,
            rho2,
            r,
        } => {
            let s = luxest_core::exact::Sobolev {
                intensity_cd: intensity,
                h1,
                h2,
                rho1,
                rho2,
            };
            println!("Sobolev problem: I = {intensity} cd, h1 = {h1} m, h2 = {h2} m, rho1 = {rho1}, rho2 = {rho2}");
            println!(
                "flux onto plane 1: {:.9e} lm, onto plane 2: {:.9e} lm",
                s.flux1(),
                s.swapped().flux1()
            );
            println!(
                "{:>10} {:>18} {:>18} {:>18} {:>10}",
                "r (m)", "E1 (lx)", "E1 direct", "E2 (lx)", "err.bound"
            );
            for r in r {
                let (e1, e2) = (s.illuminance1(r), s.illuminance2(r));
                println!(
                    "{:>10} {:>18.10e} {:>18.10e} {:>18.10e} {:>10.1e}",
                    r,
                    e1.value,
                    s.direct1(r),
                    e2.value,
                    e1.error_bound.max(e2.error_bound)
                );
            }
        }
        ExactCase::Sphere {
            intensity,
            radius,
            rho,
        } => {
            let ind = luxest_core::exact::integrating_sphere_indirect(intensity, radius, rho);
            let direct = intensity / (radius * radius);
            println!("Integrating sphere, central source: I = {intensity} cd, R = {radius} m, rho = {rho}");
            println!("direct {direct:.10e} lx + indirect {ind:.10e} lx = {:.10e} lx everywhere on the wall", direct + ind);
        }
        ExactCase::Cie171 { flux, area, rho } => {
            let e = luxest_core::exact::cie171_mean_indirect_illuminance(flux, area, rho);
            println!("CIE 171:2006 5.8: flux {flux} lm, S_T = {area} m², rho = {rho}: mean indirect illuminance {e:.10e} lx");
        }
    }
}
