//! The Markdown report of a scene: run, luminaires, per-surface figures with their
//! uncertainties and plot, and the peer comparison when one is given.

use crate::peer::{PeerResults, SurfaceComparison, REL_TOLERANCE, SIGMAS};
use crate::scene_info::LightSources;
use crate::surface::{Surface, UncertaintyMethod};
use luxest_io::meta::RunInfo;
use luxest_photometry::{Estimate, GridStats};
use std::fmt::Write;

/// Everything the report says about one surface.
pub struct SurfaceReport<'a> {
    pub surface: &'a Surface,
    pub stats: &'a GridStats,
    pub method: UncertaintyMethod,
    /// File names (relative to the report) of the plot and the tables.
    pub png: String,
    pub csv: String,
    pub ron: String,
    pub comparison: Option<SurfaceComparison>,
}

/// The report's inputs besides the surfaces.
pub struct ReportContext<'a> {
    pub scene: &'a str,
    pub results_file: &'a str,
    pub run: &'a RunInfo,
    pub singularity: &'a str,
    pub sources: Option<&'a LightSources>,
    pub peer: Option<(&'a str, &'a PeerResults)>,
}

/// `value ± se unit (rel %)` with a precision that shows the standard error's first two digits.
pub fn format_estimate(e: Estimate, unit: &str) -> String {
    format_figure(e.value, e.std_error, unit)
}

/// [`format_estimate`] of a value and its standard error.
pub fn format_figure(value: f64, std_error: f64, unit: &str) -> String {
    let digits = if std_error > 0.0 {
        (1 - std_error.log10().floor() as i32).clamp(0, 6) as usize
    } else {
        3
    };
    let rel = if value != 0.0 {
        format!(" ({:.2} %)", 100.0 * (std_error / value).abs())
    } else {
        String::new()
    };
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    format!("{:.*} ± {:.*}{unit}{rel}", digits, value, digits, std_error)
}

fn group_digits(x: f64) -> String {
    format!("{x:.0}")
}

/// The whole Markdown text.
pub fn render(ctx: &ReportContext, surfaces: &[SurfaceReport]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Lighting report: {}\n", ctx.scene);
    let _ = writeln!(
        s,
        "Computed by luxest `{}` from `{}`: {} light paths, seed {}, {:.2} s wall clock \
         (scene hash `{}`, luxest {}); singularity handling {}. Illuminance in lx; \
         every Monte Carlo figure is given as value ± one standard error.\n",
        ctx.run.estimator,
        ctx.results_file,
        ctx.run.samples,
        ctx.run.seed,
        ctx.run.seconds,
        ctx.run.scene_hash,
        ctx.run.program_version,
        ctx.singularity
    );

    let _ = writeln!(s, "## Luminaires\n");
    match ctx.sources {
        None => {
            let _ = writeln!(
                s,
                "Not listed: the report was run without `--scene-info`.\n"
            );
        }
        Some(src) => {
            if src.groups.is_empty() && src.other.is_empty() {
                let _ = writeln!(s, "The scene has no light sources.\n");
            }
            if !src.groups.is_empty() {
                let _ = writeln!(
                    s,
                    "| photometric file | count | multiplier | flux per luminaire (lm) | input power per luminaire (W) | luminaires |\n|---|---:|---:|---:|---:|---|"
                );
                for g in &src.groups {
                    let _ = writeln!(
                        s,
                        "| `{}` | {} | {} | {:.1} | {} | {} |",
                        g.file,
                        g.count,
                        g.multiplier,
                        g.flux_lm,
                        g.input_watts
                            .map_or("not stated".to_string(), |w| format!("{w}")),
                        g.names.join(", ")
                    );
                }
                s.push('\n');
            }
            for (name, flux) in &src.other {
                let _ = writeln!(s, "- other emitter `{name}`: {flux:.1} lm");
            }
            if !src.other.is_empty() {
                s.push('\n');
            }
            let count: usize = src.groups.iter().map(|g| g.count).sum();
            let _ = writeln!(
                s,
                "Total: {} luminaire{}, {} lm{}.\n",
                count,
                if count == 1 { "" } else { "s" },
                group_digits(src.total_flux_lm()),
                match src.total_input_watts() {
                    Some(w) if count > 0 => format!(", {w:.1} W input power"),
                    _ => ", input power not stated in every file".to_string(),
                }
            );
        }
    }

    let _ = writeln!(s, "## Calculation surfaces\n");
    for r in surfaces {
        surface_section(&mut s, r);
    }

    if let Some((file, peer)) = ctx.peer {
        peer_section(&mut s, ctx, file, peer, surfaces);
    }
    s
}

fn surface_section(s: &mut String, r: &SurfaceReport) {
    let g = &r.surface.grid;
    let (su, sv) = g.spacing_m();
    let (lu, lv) = g.sides_m();
    let st = r.stats;
    let _ = writeln!(s, "### {}\n", r.surface.name);
    let _ = writeln!(
        s,
        "{} illuminance on a {:.2} m × {:.2} m rectangle, {:.2} m margin excluded: {} × {} = {} points at {:.3} m × {:.3} m spacing (cell centres). Tables: [`{}`]({}), [`{}`]({}).\n",
        capitalise(&r.surface.kind),
        lu,
        lv,
        g.margin_m,
        g.nu,
        g.nv,
        st.n_points,
        su,
        sv,
        r.csv,
        r.csv,
        r.ron,
        r.ron
    );
    let _ = writeln!(
        s,
        "| figure | value ± standard error (relative) |\n|---|---|"
    );
    let _ = writeln!(s, "| Eavg | {} |", format_estimate(st.e_avg, "lx"));
    let _ = writeln!(s, "| Emin | {} |", format_estimate(st.e_min, "lx"));
    let _ = writeln!(s, "| Emax | {} |", format_estimate(st.e_max, "lx"));
    // Without light anywhere on the surface the ratios are 0/0 (they read 0.000 ± 0.000).
    let (u0, ud) = if st.e_max.value > 0.0 {
        (format_estimate(st.u0, ""), format_estimate(st.ud, ""))
    } else {
        let none = "undefined: no point of the surface receives light".to_string();
        (none.clone(), none)
    };
    let _ = writeln!(s, "| U0 = Emin/Eavg | {u0} |");
    let _ = writeln!(s, "| Ud = Emin/Emax | {ud} |\n");
    let _ = writeln!(
        s,
        "{}{}\n",
        match r.method {
            UncertaintyMethod::Jackknife { batches } => format!(
                "Standard errors by the delete-one-batch jackknife over {batches} independent batches of light paths (correlations between points included)."
            ),
            UncertaintyMethod::Independent => "Standard errors propagated from the per-point standard errors with the points assumed independent (the results carry no per-batch values), which underestimates them when points share light paths.".to_string(),
        },
        if st.min_is_ambiguous(2.0) {
            " Another point lies within 2 combined standard errors of the minimum, so Emin, U0 and Ud and their standard errors are approximate (a minimum of noisy values is biased low)."
        } else {
            ""
        }
    );
    let _ = writeln!(s, "![isolux plot of {}]({})\n", r.surface.name, r.png);
}

fn capitalise(w: &str) -> String {
    let mut c = w.chars();
    match c.next() {
        Some(f) => f.to_uppercase().collect::<String>() + c.as_str(),
        None => String::new(),
    }
}

fn peer_section(
    s: &mut String,
    ctx: &ReportContext,
    file: &str,
    peer: &PeerResults,
    surfaces: &[SurfaceReport],
) {
    let name = peer.meta("name").unwrap_or("peer");
    let program = peer.meta("program").unwrap_or(name);
    let _ = writeln!(s, "## Comparison with {program}\n");
    let _ = writeln!(s, "From `{file}`.");
    if let Some(set) = peer.meta("settings") {
        let _ = writeln!(s, "Settings: `{set}`.");
    }
    for (k, v) in &peer.meta {
        if k == "note" {
            let _ = writeln!(s, "{v}");
        }
    }
    let _ = writeln!(
        s,
        "\nRun times: luxest {:.2} s wall clock ({}); {name} {}.\n",
        ctx.run.seconds,
        ctx.run.estimator,
        match (peer.meta("cpu_seconds"), peer.meta("wall_seconds")) {
            (Some(c), Some(w)) => format!("{c} CPU s ({w} s wall clock)"),
            (Some(c), None) => format!("{c} CPU s"),
            (None, Some(w)) => format!("{w} s wall clock"),
            _ => "not stated".to_string(),
        }
    );
    let _ = writeln!(
        s,
        "Check per point: |E_luxest − E_peer| ≤ {:.0} % · E_peer + {:.0} σ, σ² = SE_luxest² + SE_peer².\n",
        100.0 * REL_TOLERANCE,
        SIGMAS
    );
    for r in surfaces {
        let Some(c) = &r.comparison else { continue };
        let failing = c.points.iter().filter(|p| !p.agrees).count();
        let _ = writeln!(
            s,
            "### {}: {}\n\n{} of {} points agree; mean relative difference {:+.2} %, largest |relative difference| {:.2} %.\n",
            c.surface,
            if c.all_agree() { "PASS" } else { "FAIL" },
            c.points.len() - failing,
            c.points.len(),
            100.0 * c.mean_rel_diff(),
            100.0 * c.max_abs_rel_diff()
        );
        let _ = writeln!(
            s,
            "| point | i | j | luxest (lx) | {name} (lx) | difference | z | check |\n|---:|---:|---:|---:|---:|---:|---:|---|"
        );
        let nu = r.surface.grid.nu;
        for p in &c.points {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.1} ± {:.1} | {:.1} ± {:.1} | {:+.2} % | {:+.2} | {} |",
                p.index,
                p.index % nu,
                p.index / nu,
                p.luxest,
                p.luxest_se,
                p.peer,
                p.peer_se,
                100.0 * p.rel_diff,
                p.z,
                if p.agrees { "ok" } else { "**outside**" }
            );
        }
        s.push('\n');
    }
}
