//! The `denoise` command line: one or more noisy `<img>_<spp>spp.hdr.exr` in, each
//! `<img>_<spp>spp.dn.exr` out, features found next to them by the OIDN naming.

use crate::{feature_path, output_path, Denoiser, Feature, Tiling};
use clap::Parser;
use luxest_core::cli::CommonArgs;
use luxest_core::exr_io::{read_rgb_finite, write_preview_png_auto, write_rgb, RgbImage};
use luxest_core::parallel::thread_count;
use luxest_core::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Denoise path-traced (or local-estimate) radiance images with an ONNX U-Net.
///
/// Each NOISY file `<img>.hdr.exr` needs the features the model takes next to it
/// (`<img>.alb.exr`, `<img>.nrm.exr`, as aov-write names them) unless --alb/--nrm name them;
/// the result is `<img>.dn.exr` with the input's header attributes plus luxest.denoiser,
/// luxest.denoiseSeconds (wall-clock seconds of inference, excluding I/O) and
/// luxest.featureSeconds (the render seconds recorded in the feature images, i.e. what the
/// albedo and normal cost), so that the image's whole cost can be added up.
#[derive(Parser, Debug)]
#[command(name = "denoise", version)]
pub struct Args {
    /// Noisy radiance images, `<img>.hdr.exr`.
    #[arg(required = true)]
    pub noisy: Vec<PathBuf>,
    /// The ONNX model (training/export.py).
    #[arg(long, default_value = "models/default.onnx")]
    pub model: PathBuf,
    /// Output file (only with one input) [default: <img>.dn.exr next to the input].
    #[arg(short, long)]
    pub out: Option<PathBuf>,
    /// Write outputs into this directory instead of next to the inputs.
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
    /// Albedo image (only with one input) [default: <img>.alb.exr].
    #[arg(long)]
    pub alb: Option<PathBuf>,
    /// Normal image (only with one input) [default: <img>.nrm.exr].
    #[arg(long)]
    pub nrm: Option<PathBuf>,
    /// Tile core size in pixels (a multiple of 16); larger images are denoised in tiles.
    #[arg(long, default_value_t = Tiling::default().tile)]
    pub tile: usize,
    /// Context around each tile in pixels (a multiple of 16).
    #[arg(long, default_value_t = Tiling::default().overlap)]
    pub overlap: usize,
    /// Also write an sRGB PNG preview of each output next to it (`.dn.png`).
    #[arg(long)]
    pub preview: bool,
    /// --seed is accepted like every stage's; inference is deterministic and uses no randomness.
    #[command(flatten)]
    pub common: CommonArgs,
}

pub fn run(args: Args) -> Result<()> {
    let tiling = Tiling {
        tile: args.tile,
        overlap: args.overlap,
    };
    tiling.validate()?;
    let single = args.noisy.len() == 1;
    if !single && (args.out.is_some() || args.alb.is_some() || args.nrm.is_some()) {
        return Err(Error::Usage(
            "-o/--out, --alb and --nrm need exactly one input image".into(),
        ));
    }
    let mut denoiser = Denoiser::load(&args.model, thread_count(args.common.threads))?;
    let model_name = args
        .model
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    for noisy in &args.noisy {
        let out = match (&args.out, &args.out_dir) {
            (Some(o), _) => o.clone(),
            (None, dir) => {
                let o = output_path(noisy).ok_or_else(|| {
                    Error::Usage(format!(
                        "{}: input name must end in .hdr.exr (or give -o)",
                        noisy.display()
                    ))
                })?;
                match dir {
                    Some(d) => d.join(o.file_name().unwrap_or_default()),
                    None => o,
                }
            }
        };
        let mut images = Vec::new();
        let mut paths = Vec::new();
        for &feature in denoiser.features() {
            let path = match feature {
                Feature::Hdr => Some(noisy.clone()),
                Feature::Alb => args.alb.clone().or_else(|| feature_path(noisy, feature)),
                Feature::Nrm => args.nrm.clone().or_else(|| feature_path(noisy, feature)),
            };
            let path = path.ok_or_else(|| {
                Error::input(
                    noisy,
                    format!(
                        "the model needs the {} feature; name it with --{}",
                        feature.name(),
                        feature.name()
                    ),
                )
            })?;
            if !path.is_file() {
                return Err(Error::input(
                    &path,
                    format!(
                        "missing {} feature image (the model {model_name} takes {})",
                        feature.name(),
                        names(denoiser.features())
                    ),
                ));
            }
            images.push(read_checked(&path)?);
            paths.push(path);
        }
        let (w, h) = (images[0].width, images[0].height);
        for (image, path) in images.iter().zip(&paths).skip(1) {
            if (image.width, image.height) != (w, h) {
                return Err(Error::input(
                    path,
                    format!(
                        "size {}x{} differs from the noisy image's {w}x{h} ({})",
                        image.width,
                        image.height,
                        noisy.display()
                    ),
                ));
            }
        }
        let start = Instant::now();
        let refs: Vec<&RgbImage> = images.iter().collect();
        let mut result = denoiser.denoise(&refs, tiling)?;
        let seconds = start.elapsed().as_secs_f64();
        result.attributes = images[0].attributes.clone();
        // The features' cost (aov-write's seconds) is part of the denoised image's cost.
        let feature_seconds = images[1..]
            .iter()
            .filter_map(|i| i.attribute("luxest.seconds")?.parse::<f64>().ok())
            .fold(0.0, f64::max);
        result.attributes.retain(|(k, _)| {
            !matches!(
                k.as_str(),
                "luxest.denoiser" | "luxest.denoiseSeconds" | "luxest.featureSeconds"
            )
        });
        result
            .attributes
            .push(("luxest.featureSeconds".into(), format!("{feature_seconds}")));
        result
            .attributes
            .push(("luxest.denoiser".into(), model_name.clone()));
        result
            .attributes
            .push(("luxest.denoiseSeconds".into(), format!("{seconds}")));
        write_rgb(&out, &result)?;
        if args.preview {
            write_preview_png_auto(&out.with_extension("png"), &result)?;
        }
        eprintln!(
            "denoise: wrote {} ({w}x{h}, {:.1} ms/megapixel)",
            out.display(),
            1e3 * seconds / (w * h) as f64 * 1e6
        );
    }
    Ok(())
}

fn names(features: &[Feature]) -> String {
    features
        .iter()
        .map(|f| f.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Reads an input image: finite and not empty, naming the file otherwise.
fn read_checked(path: &Path) -> Result<RgbImage> {
    let image = read_rgb_finite(path)?;
    if image.width == 0 || image.height == 0 {
        return Err(Error::input(path, "image is empty"));
    }
    Ok(image)
}
