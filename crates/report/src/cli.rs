//! The `report` command line: reads sensor results, the compiled scene's header and optionally
//! a luminance image, writes the tables, isolux plots, the Markdown and the HTML report of every
//! calculation surface (see the crate docs).

use crate::markdown::{self, ReportContext, Signature, SurfaceReport};
use crate::surface::UncertaintyMethod;
use crate::{checks, daylight, html, input, luminance, peer, plot, scene_info, tables};
use clap::Parser;
use luxest_io::cli::Console;
use luxest_io::outputs::{path_component, OutputPlan};
use luxest_io::sensors::SensorResults;
use luxest_io::Result;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Lighting report of a scene's calculation surfaces: per surface a CSV and RON table, an
/// isolux PNG, and one Markdown and one self-contained HTML report with the luminaire schedule,
/// Eavg, Emin, Emax, U0, Ud (each ± its standard error) checked against the scene's
/// requirements, glare and daylight figures when the results carry them, the false-colour
/// luminance image, an optional peer comparison and the signature block.
///
/// `report ugr-table FILE` prints the CIE 190 UGR table of a luminaire file instead
/// (the `ugr_table` module).
#[derive(Parser, Debug)]
#[command(
    name = "report",
    version,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
pub struct Args {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Sensor results of `estimate sensors` (.sensors.ron).
    #[arg(required = true)]
    pub results: Option<PathBuf>,
    /// The compiled scene's header as `scene-compile --info SCENE.lxs` prints it, for the
    /// luminaire list and the luminaires' marks on the plots.
    #[arg(long)]
    pub scene_info: Option<PathBuf>,
    /// Output directory (default `reports/lighting/<scene>`).
    #[arg(short, long)]
    pub out: Option<PathBuf>,
    /// A peer program's illuminances at the same points (CSV, see `report::peer`), e.g.
    /// Radiance's from `pipelines/radiance_office.py`.
    #[arg(long)]
    pub peer: Option<PathBuf>,
    /// Fail (exit 1, after writing the report) if any point disagrees with the peer.
    #[arg(long, requires = "peer")]
    pub require_peer_agreement: bool,
    /// A luminance image of the room (OpenEXR, linear RGB in cd/m², from `trace` or `estimate
    /// image` on the same compiled scene): drawn in false colour with its cd/m² scale.
    #[arg(long, value_name = "EXR")]
    pub luminance: Option<PathBuf>,
    /// The signature block's designer (left blank to sign by hand when not given).
    #[arg(long)]
    pub designer: Option<String>,
    /// The signature block's date.
    #[arg(long)]
    pub date: Option<String>,
    /// The signature block's checker.
    #[arg(long)]
    pub checked_by: Option<String>,
    #[command(flatten)]
    pub console: Console,
}

/// The subcommands beside the report itself.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// The CIE 190 tabular UGR of a luminaire file (.ies or .ldt).
    UgrTable(crate::ugr_table::Args),
}

/// Runs the command line.
pub fn run(args: Args) -> Result<()> {
    if let Some(Command::UgrTable(a)) = args.command {
        return crate::ugr_table::run(a);
    }
    let Some(results_path) = args.results.clone() else {
        return Err(luxest_io::Error::Usage(
            "the following required arguments were not provided: <RESULTS>".into(),
        ));
    };
    let start = Instant::now();
    let results = SensorResults::read_ron(&results_path)?;
    let header = match &args.scene_info {
        Some(p) => {
            let (header, hash) = scene_info::read(p)?;
            scene_info::check_matches(p, &header, hash.as_deref(), &results_path, &results)?;
            Some(header)
        }
        None => None,
    };
    let sources = match (&args.scene_info, &header) {
        (Some(p), Some(h)) => Some(scene_info::light_sources(p, h)?),
        _ => None,
    };
    let surfaces = input::surfaces(&results_path, &results)?;
    let peer = match &args.peer {
        Some(p) => {
            let read = peer::read(p)?;
            let names: Vec<&str> = surfaces.iter().map(|s| s.name.as_str()).collect();
            peer::check_sets(p, &read, &names, &results_path)?;
            Some((p, read))
        }
        None => None,
    };

    let scene = path_component(&results.scene, &results_path, "scene")?;
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new("reports").join("lighting").join(scene));
    let mut names = Vec::new();
    for s in &surfaces {
        let stem = path_component(&s.name, &results_path, "set name")?;
        names.push((
            format!("{stem}.csv"),
            format!("{stem}.ron"),
            format!("{stem}.isolux.png"),
        ));
    }
    let md_path = dir.join("report.md");
    let html_path = dir.join("report.html");
    let luminance_png = "luminance.png";
    let mut outputs = vec![md_path.clone(), html_path.clone()];
    if args.luminance.is_some() {
        outputs.push(dir.join(luminance_png));
    }
    for (c, r, p) in &names {
        outputs.extend([dir.join(c), dir.join(r), dir.join(p)]);
    }
    let mut inputs = vec![results_path.clone()];
    inputs.extend(args.scene_info.clone());
    if let Some(p) = &args.peer {
        inputs.push(p.clone());
    }
    inputs.extend(args.luminance.clone());
    let mut plan = OutputPlan::new(&inputs, &outputs)?;

    let lum_positions: Vec<[f64; 3]> = sources
        .iter()
        .flat_map(|s| s.places.iter().map(|p| p.position))
        .collect();
    let mut computed = Vec::new();
    for (n, (s, (csv, ron, png))) in surfaces.iter().zip(&names).enumerate() {
        let (stats, method) = s.stats(&results_path)?;
        let uncertainty = match method {
            UncertaintyMethod::Jackknife { batches } => format!("jackknife over {batches} batches"),
            UncertaintyMethod::Independent => "independent points".to_string(),
        };
        args.console.note(format_args!(
            "report: surface {}/{} \"{}\": {} x {} points, Eavg {:.1} ± {:.1} lx, U0 {:.3} ± {:.3}",
            n + 1,
            surfaces.len(),
            s.name,
            s.grid.nu,
            s.grid.nv,
            stats.e_avg.value,
            stats.e_avg.std_error,
            stats.u0.value,
            stats.u0.std_error
        ));
        if stats.e_max.value <= 0.0 {
            args.console.note(format_args!(
                "warning: surface \"{}\" receives no light at any point: U0 and Ud are \
                 undefined (the tables show 0); is it facing away from the luminaires?",
                s.name
            ));
        }
        let rows = tables::rows(s);
        tables::write_csv_to(&mut plan, &dir.join(csv), &rows)?;
        tables::write_ron_to(
            &mut plan,
            &dir.join(ron),
            &tables::table(&results.scene, s, &stats, &uncertainty),
        )?;
        let title = format!("{}: {} {} illuminance (lx)", results.scene, s.name, s.kind);
        let bytes = plot::isolux_png(s, &stats, &title, &lum_positions, &results_path)?;
        plan.write_bytes(&dir.join(png), &bytes)?;
        let comparison = match &peer {
            Some((path, p)) => peer::compare(path, s, p)?,
            None => None,
        };
        let req = header
            .as_ref()
            .and_then(|h| scene_info::requirements(h, &s.name));
        let surface_checks = checks::surface(req, &stats);
        let daylight = match &results.sky {
            Some(sky) => {
                let f = daylight::figures(&results_path, &stats, sky)?;
                let c = req
                    .and_then(|r| r.daylight_factor.as_ref())
                    .map_or(Vec::new(), |t| daylight::checks(t, &f));
                Some((f, c))
            }
            None => None,
        };
        computed.push((stats, method, comparison, bytes, surface_checks, daylight));
    }
    for g in &results.glare {
        if !(g.ugr.is_finite() && g.standard_error.is_finite()) {
            return Err(luxest_io::Error::at(
                &results_path,
                format!("glare of observer \"{}\"", g.observer),
                format!(
                    "UGR {} ± {} is not a finite number",
                    g.ugr, g.standard_error
                ),
            ));
        }
    }
    let luminance = match &args.luminance {
        Some(p) => {
            let title = format!("{}: luminance (cd/m2)", results.scene);
            let l = luminance::render(p, &title, &results.run.scene_hash)?;
            plan.write_bytes(&dir.join(luminance_png), &l.png)?;
            Some((luminance_png.to_string(), l))
        }
        None => None,
    };

    let reports: Vec<SurfaceReport> = surfaces
        .iter()
        .zip(&names)
        .zip(&computed)
        .map(
            |((s, (csv, ron, png)), (stats, method, cmp, bytes, checks, daylight))| SurfaceReport {
                surface: s,
                stats,
                method: *method,
                png: png.clone(),
                csv: csv.clone(),
                ron: ron.clone(),
                png_bytes: bytes.clone(),
                comparison: cmp.clone(),
                checks: checks.clone(),
                daylight: daylight.clone(),
            },
        )
        .collect();
    let results_name = results_path.display().to_string();
    let peer_name = args.peer.as_ref().map(|p| p.display().to_string());
    let ctx = ReportContext {
        scene: &results.scene,
        results_file: &results_name,
        run: &results.run,
        singularity: &results.singularity,
        sources: sources.as_ref(),
        peer: match (&peer_name, &peer) {
            (Some(n), Some((_, p))) => Some((n.as_str(), p)),
            _ => None,
        },
        glare: &results.glare,
        glare_checks: results.glare.iter().map(checks::glare).collect(),
        sky: results.sky.as_ref(),
        luminance,
        signature: Signature {
            designer: args.designer.clone(),
            date: args.date.clone(),
            checked_by: args.checked_by.clone(),
        },
    };
    let text = markdown::render(&ctx, &reports);
    plan.write_bytes(&md_path, text.as_bytes())?;
    plan.write_bytes(&html_path, html::render(&ctx, &reports).as_bytes())?;
    plan.commit()?;
    args.console.note(format_args!(
        "report: wrote {} and {} ({} surface{}, {:.2} s)",
        html_path.display(),
        md_path.display(),
        surfaces.len(),
        if surfaces.len() == 1 { "" } else { "s" },
        start.elapsed().as_secs_f64()
    ));
    if args.require_peer_agreement {
        let failing: Vec<&str> = reports
            .iter()
            .filter_map(|r| r.comparison.as_ref())
            .filter(|c| !c.all_agree())
            .map(|c| c.surface.as_str())
            .collect();
        if !failing.is_empty() {
            return Err(luxest_io::Error::input(
                args.peer.as_deref().unwrap_or(Path::new("peer")),
                format!(
                    "points outside 1 % + 3 sigma on surface(s) {}",
                    failing.join(", ")
                ),
            ));
        }
    }
    Ok(())
}
