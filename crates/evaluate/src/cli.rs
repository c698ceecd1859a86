//! The `evaluate` command line.

use crate::images::score_images;
use crate::sensors::score_sensors;
use clap::{Parser, Subcommand};
use luxest_io::cli::CommonArgs;
use luxest_io::exr::write_rgb_to;
use luxest_io::naming::{flip_map_path, preview_path};
use luxest_io::num::Real;
use luxest_io::outputs::{Format, OutputPlan};
use luxest_io::png::write_preview_png_to;
use luxest_io::{Error, Result};
use std::path::PathBuf;

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
    #[command(mut_arg("seed", |a| a.help("Accepted like every stage's; evaluation is deterministic and draws no random numbers")))]
    #[command(mut_arg("threads", |a| a.help("Accepted like every stage's; evaluation runs on one thread")))]
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
        #[command(flatten)]
        common: CommonArgs,
    },
    /// Per-point error, z-score and summary of sensor RESULTS against an exact case; prints the
    /// table, writes it as CSV (and RON), and with --max-z fails if any |z| exceeds it.
    #[command(mut_arg("seed", |a| a.help("Accepted like every stage's; evaluation is deterministic and draws no random numbers")))]
    #[command(mut_arg("threads", |a| a.help("Accepted like every stage's; evaluation runs on one thread")))]
    Sensors {
        /// Sensor results (.sensors.ron).
        results: PathBuf,
        /// Case and parameters, e.g. `sobolev:I=100,h1=1,h2=1,rho1=0.5,rho2=0.5[,bin=R]` (bin:
        /// compare direct-simulation results with the mean over their counting disks),
        /// `sphere:I=100,R=1,rho=0.5[,x=..,y=..,z=..]`, `cie171-5.8:flux=1e4,area=96,rho=0.5,x=2,y=2,z=2`;
        /// an I0 cosⁿ luminaire (nadir −y): `cosn-plane:I0=1000,n=2,h=1[,bin=R]`,
        /// `cosn-sobolev:I0=1000,n=2,h1=1,h2=1,rho1=0.5,rho2=0.5[,bin=R]`,
        /// `cosn-sphere:I0=1000,n=2,R=1,rho=0.5[,x=..,y=..,z=..]`.
        #[arg(long)]
        case: String,
        /// CSV report.
        #[arg(short, long)]
        out: Option<PathBuf>,
        /// The z-test: exit 1 if any point's |z| exceeds this.
        #[arg(long, value_parser = Real::positive("standard errors"))]
        max_z: Option<f64>,
        /// Compare only these sensor sets (comma-separated names) [default: all].
        #[arg(long, value_delimiter = ',')]
        sets: Vec<String>,
        /// The compiled scene of the case: refuse results whose scene hash is not this scene's
        /// (results of another scene, or of an older compile of this one).
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Also write the report as RON.
        #[arg(long)]
        ron: Option<PathBuf>,
        #[command(flatten)]
        common: CommonArgs,
    },
}

pub fn run(args: Args) -> Result<()> {
    match args.command {
        Command::Images {
            reference,
            tests,
            out,
            ron,
            flip_maps,
            common,
        } => {
            // Every output of the run, checked against the images before any is written.
            let maps: Vec<PathBuf> = flip_maps
                .iter()
                .flat_map(|dir| tests.iter().map(move |t| flip_map_path(dir, t)))
                .flat_map(|p| [preview_path(&p), p])
                .collect();
            let outputs = std::iter::once(out.clone()).chain(ron.clone()).chain(maps);
            let inputs = std::iter::once(&reference).chain(&tests);
            let mut plan = OutputPlan::new(inputs, outputs)?;
            check_report_formats(Some(&out), ron.as_ref())?;
            let console = common.console;
            let report =
                score_images(&reference, &tests, &console, |test, map| match &flip_maps {
                    Some(dir) => {
                        let path = flip_map_path(dir, test);
                        write_rgb_to(&mut plan, &path, map)?;
                        write_preview_png_to(&mut plan, &preview_path(&path), map, 1.0)
                    }
                    None => Ok(()),
                })?;
            report.write_csv_to(&mut plan, &out)?;
            if let Some(r) = &ron {
                report.write_ron_to(&mut plan, r)?;
            }
            plan.commit()?;
            for r in &report.rows {
                console.note(format_args!(
                    "evaluate: {}: PSNR {:.2} dB, SSIM {:.4}, FLIP {:.4}, relMSE {:.3e}",
                    r.image, r.psnr_db, r.ssim, r.flip, r.rel_mse
                ));
            }
            Ok(())
        }
        Command::Sensors {
            results,
            case,
            out,
            max_z,
            sets,
            scene,
            ron,
            common,
        } => {
            if max_z.is_some_and(|z| z.is_nan() || z <= 0.0) {
                return Err(Error::Usage("--max-z must be positive".into()));
            }
            let inputs = std::iter::once(&results).chain(&scene);
            let mut plan = OutputPlan::new(inputs, out.iter().chain(&ron))?;
            check_report_formats(out.as_ref(), ron.as_ref())?;
            let report = score_sensors(&results, &case, &sets, scene.as_deref())?;
            if let Some(out) = &out {
                report.write_csv_to(&mut plan, out)?;
            }
            if let Some(r) = &ron {
                report.write_ron_to(&mut plan, r)?;
            }
            // The table first: a failed write to stdout leaves no report files behind.
            luxest_io::cli::print(&report.table(max_z))?;
            plan.commit()?;
            common.console.note(format_args!(
                "evaluate: {}: {} points, max |z| {:.2}, RMS relative error {:.3e}",
                results.display(),
                report.points,
                report.max_abs_z,
                report.rms_relative_error
            ));
            match max_z {
                Some(z) => report.z_test(z),
                None => Ok(()),
            }
        }
    }
}

/// The report files' endings, checked after the output plan (which refuses an input or a
/// non-regular file first): -o a CSV table, --ron a RON document.
fn check_report_formats(csv: Option<&PathBuf>, ron: Option<&PathBuf>) -> Result<()> {
    if let Some(c) = csv {
        Format::Csv.check(c, "-o/--out")?;
    }
    if let Some(r) = ron {
        Format::Ron.check(r, "--ron")?;
    }
    Ok(())
}
