//! The `evaluate` command line.

use crate::report::{score_images, score_sensors};
use clap::{Parser, Subcommand};
use luxest_core::cli::CommonArgs;
use luxest_core::exr_io::{write_preview_png, write_rgb};
use luxest_core::{Error, Result};
use std::path::{Path, PathBuf};

/// Error of images against a reference, and of sensor results against exact values.
#[derive(Parser, Debug)]
#[command(name = "evaluate", version)]
pub struct Args {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// PSNR, SSIM, MS-SSIM, FLIP (tonemapped; see --help of the report), relMSE and SMAPE
    /// (linear) of each TEST image against REFERENCE; writes a CSV and a RON report.
    Images {
        /// Reference image (e.g. `<img>_ref.hdr.exr`).
        #[arg(long)]
        reference: PathBuf,
        /// Images to score (noisy `.hdr.exr`, denoised `.dn.exr`, local-estimate images).
        #[arg(required = true)]
        tests: Vec<PathBuf>,
        /// CSV report.
        #[arg(short, long)]
        out: PathBuf,
        /// Also write the report as RON.
        #[arg(long)]
        ron: Option<PathBuf>,
        /// Write each image's FLIP error map into this directory (`<image>.flip.exr` and a
        /// grey-scale `.flip.png`).
        #[arg(long)]
        flip_maps: Option<PathBuf>,
        /// --seed/--threads are accepted like every stage's; evaluation is deterministic.
        #[command(flatten)]
        common: CommonArgs,
    },
    /// Per-point error, z-score and summary of sensor RESULTS against an exact case
    /// (the case syntax of `estimate compare --case`).
    Sensors {
        /// Sensor results (.sensors.ron).
        results: PathBuf,
        /// e.g. `sobolev:I=100,h1=1,h2=1,rho1=0.5,rho2=0.5`, `sphere:I=100,R=1,rho=0.5`.
        #[arg(long)]
        case: String,
        /// CSV report.
        #[arg(short, long)]
        out: PathBuf,
        /// Also write the report as RON.
        #[arg(long)]
        ron: Option<PathBuf>,
        #[command(flatten)]
        common: CommonArgs,
    },
}

fn stem(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    name.strip_suffix(".exr").unwrap_or(&name).to_string()
}

pub fn run(args: Args) -> Result<()> {
    match args.command {
        Command::Images {
            reference,
            tests,
            out,
            ron,
            flip_maps,
            common: _,
        } => {
            let report = score_images(&reference, &tests, |test, map| match &flip_maps {
                Some(dir) => {
                    let base = stem(test);
                    write_rgb(&dir.join(format!("{base}.flip.exr")), map)?;
                    write_preview_png(&dir.join(format!("{base}.flip.png")), map, 1.0)
                }
                None => Ok(()),
            })?;
            report.write_csv(&out)?;
            if let Some(r) = ron {
                report.write_ron(&r)?;
            }
            for r in &report.rows {
                eprintln!(
                    "evaluate: {}: PSNR {:.2} dB, SSIM {:.4}, FLIP {:.4}, relMSE {:.3e}",
                    r.image, r.psnr_db, r.ssim, r.flip, r.rel_mse
                );
            }
            Ok(())
        }
        Command::Sensors {
            results,
            case,
            out,
            ron,
            common: _,
        } => {
            let report = score_sensors(&results, &case)?;
            report.write_csv(&out)?;
            if let Some(r) = ron {
                report.write_ron(&r)?;
            }
            eprintln!(
                "evaluate: {}: {} points, max |z| {:.2}, RMS relative error {:.3e}",
                results.display(),
                report.points,
                report.max_abs_z,
                report.rms_relative_error
            );
            if report.points == 0 {
                return Err(Error::input(&results, "no points"));
            }
            Ok(())
        }
    }
}
