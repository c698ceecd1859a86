//! aov-write: the denoiser's auxiliary features, first-hit albedo and shading normal (and
//! optionally depth), averaged over exactly the pixel samples `trace` uses
//! ([`luxest_core::camera::pixel_jitter`] with the same seed), written in the Intel Open Image
//! Denoise training-toolkit layout: `<prefix>_<spp>spp.alb.exr`, `.nrm.exr` (and `_ref.`).
//!
//! Conventions (as OIDN expects): albedo in [0, 1] — the reflectance of diffuse surfaces, the
//! sum diffuse + specular of glossy ones, the reflectance of mirrors and 1 for dielectrics;
//! black where nothing is hit. Normals are world-space unit shading normals facing the camera,
//! components in [−1, 1]; zero where nothing is hit. Depth is the distance along the ray (m),
//! zero where nothing is hit.

use clap::Parser;
use luxest_core::camera::{pixel_jitter, PinholeCamera};
use luxest_core::color::Rgb;
use luxest_core::compiled::CompiledScene;
use luxest_core::exr_io::RgbImage;
use luxest_core::math::Vec3;
use luxest_core::meta::{RunInfo, PROGRAM_VERSION};
use luxest_core::parallel::{run_batches, thread_count};
use luxest_core::scene::Material;
use luxest_core::world::World;
use luxest_core::{Error, Result};
use std::path::{Path, PathBuf};

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
    pub common: luxest_core::cli::CommonArgs,
}

/// Albedo of a material as the denoiser sees it.
pub fn albedo(m: &Material) -> Rgb {
    match m {
        Material::Lambertian { reflectance } | Material::Mirror { reflectance } => *reflectance,
        Material::Glossy {
            diffuse, specular, ..
        } => *diffuse + *specular,
        Material::Dielectric { .. } => Rgb::WHITE,
    }
}

/// First-hit features of one camera ray: (albedo, normal facing the camera, depth).
pub fn first_hit(world: &World, origin: Vec3, dir: Vec3) -> (Rgb, Vec3, f64) {
    match world.intersect(origin, dir) {
        None => (Rgb::BLACK, Vec3::ZERO, 0.0),
        Some(sp) => {
            let n = if sp.ns.dot(dir) > 0.0 { -sp.ns } else { sp.ns };
            (albedo(world.material(sp.triangle)), n, sp.distance)
        }
    }
}

/// `<prefix>_<spp:06>spp.<feature>.exr` or `<prefix>_ref.<feature>.exr`.
pub fn image_path(prefix: &Path, spp: Option<u32>, feature: &str) -> PathBuf {
    let name = prefix
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tag = spp
        .map(|s| format!("{s:06}spp"))
        .unwrap_or_else(|| "ref".into());
    prefix.with_file_name(format!("{name}_{tag}.{feature}.exr"))
}

/// Feature sums per pixel.
struct Sums {
    albedo: Vec<[f64; 3]>,
    normal: Vec<[f64; 3]>,
    depth: Vec<f64>,
}

pub fn run(args: Args) -> Result<()> {
    if args.spp == 0 {
        return Err(Error::Usage("--spp must be positive".into()));
    }
    let compiled = CompiledScene::load(&args.scene)?;
    let mut camera = compiled
        .header
        .camera
        .clone()
        .ok_or_else(|| Error::input(&args.scene, "scene has no camera"))?;
    if let Some(r) = &args.resolution {
        let parsed = r
            .split_once('x')
            .and_then(|(a, b)| Some((a.parse::<u32>().ok()?, b.parse::<u32>().ok()?)));
        camera.resolution = match parsed {
            Some((a, b)) if a > 0 && b > 0 => (a, b),
            _ => {
                return Err(Error::Usage(format!(
                    "--resolution: expected WIDTHxHEIGHT, got '{r}'"
                )))
            }
        };
    }
    let world = World::new(compiled).map_err(|e| match e {
        Error::Usage(m) => Error::input(&args.scene, m),
        other => other,
    })?;
    let cam = PinholeCamera::new(&camera)
        .ok_or_else(|| Error::input(&args.scene, "degenerate camera"))?;
    let prefix = args
        .out
        .clone()
        .unwrap_or_else(|| args.scene.with_file_name(&world.scene.header.name));
    let (w, h) = (cam.width as usize, cam.height as usize);
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
    let threads = thread_count(args.common.threads);
    let mut sums = Sums {
        albedo: vec![[0.0; 3]; w * h],
        normal: vec![[0.0; 3]; w * h],
        depth: vec![0.0; w * h],
    };
    let mut done = 0u32;
    for &target in &counts {
        // Rows in parallel; each pixel's samples in order.
        let rows = run_batches(h, threads, "aov-write", |y| {
            (0..w)
                .map(|x| {
                    let pixel = y * w + x;
                    let (mut a, mut n, mut d) = (Rgb::BLACK, Vec3::ZERO, 0.0);
                    for s in done..target {
                        let (u, v) = pixel_jitter(args.common.seed, pixel as u64, s as u64);
                        let (sa, sn, sd) = first_hit(
                            &world,
                            cam.position,
                            cam.direction(x as f64 + u, y as f64 + v),
                        );
                        a = a + sa;
                        n += sn;
                        d += sd;
                    }
                    (a, n, d)
                })
                .collect::<Vec<_>>()
        });
        for (y, row) in rows.into_iter().enumerate() {
            for (x, (a, n, d)) in row.into_iter().enumerate() {
                let p = y * w + x;
                for k in 0..3 {
                    sums.albedo[p][k] += a.0[k];
                }
                sums.normal[p][0] += n.x;
                sums.normal[p][1] += n.y;
                sums.normal[p][2] += n.z;
                sums.depth[p] += d;
            }
        }
        done = target;
        let spp = (!(args.reference && target == args.spp)).then_some(target);
        let info = RunInfo {
            samples: target as u64,
            seed: args.common.seed,
            seconds: start.elapsed().as_secs_f64(),
            estimator: "first-hit-features".into(),
            scene_hash: world.scene.content_hash.clone(),
            program_version: PROGRAM_VERSION.into(),
        };
        let n = target as f64;
        let write = |feature: &str, pixels: Vec<[f32; 3]>| -> Result<()> {
            let mut img = RgbImage::new(w, h);
            img.pixels = pixels;
            img.attributes = info.to_attributes();
            img.attributes
                .push(("luxest.pixelFilter".into(), "box".into()));
            luxest_core::exr_io::write_rgb(&image_path(&prefix, spp, feature), &img)
        };
        write(
            "alb",
            sums.albedo
                .iter()
                .map(|a| a.map(|v| (v / n) as f32))
                .collect(),
        )?;
        // The mean of unit normals is renormalised (OIDN expects unit or zero normals).
        write(
            "nrm",
            sums.normal
                .iter()
                .map(|s| {
                    let v = Vec3::new(s[0], s[1], s[2]);
                    v.try_normalize().map(|u| u.to_f32()).unwrap_or([0.0; 3])
                })
                .collect(),
        )?;
        if args.depth {
            write(
                "z",
                sums.depth.iter().map(|&d| [(d / n) as f32; 3]).collect(),
            )?;
        }
    }
    eprintln!(
        "wrote {}_{}.{{alb,nrm{}}}.exr ({} spp, {:.2} s)",
        prefix.display(),
        if args.reference {
            "ref".to_string()
        } else {
            format!("{:06}spp", args.spp)
        },
        if args.depth { ",z" } else { "" },
        args.spp,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
