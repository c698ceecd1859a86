//! The Markdown report of a scene (kept beside the HTML report for diffs, with the same
//! tables): run, luminaire schedule, per-surface figures with their uncertainties, requirement
//! checks and plot, glare, daylight, the luminance image, the peer comparison when one is given
//! and the signature block. [`ReportContext`] and [`SurfaceReport`] are what both reports print.

use crate::checks::Check;
use crate::daylight::DaylightFigures;
use crate::luminance::LuminanceImage;
use crate::peer::{PeerResults, SurfaceComparison, REL_TOLERANCE, SIGMAS};
use crate::scene_info::LightSources;
use crate::surface::{Surface, UncertaintyMethod};
use luxest_io::meta::RunInfo;
use luxest_io::sensors::{GlareResult, SkyInfo};
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
    /// The isolux plot's PNG (the HTML report embeds it).
    pub png_bytes: Vec<u8>,
    pub comparison: Option<SurfaceComparison>,
    /// The surface's figures against its requirements.
    pub checks: Vec<Check>,
    /// Daylight factors (with a sky in the results) and their checks against the target.
    pub daylight: Option<(DaylightFigures, Vec<Check>)>,
}

impl SurfaceReport<'_> {
    /// How the standard errors were obtained, in a sentence (with the minimum's caveat).
    pub fn method_text(&self) -> String {
        format!(
            "{}{}",
            match self.method {
                UncertaintyMethod::Jackknife { batches } => format!(
                    "Standard errors by the delete-one-batch jackknife over {batches} independent batches of light paths (correlations between points included)."
                ),
                UncertaintyMethod::Independent => "Standard errors propagated from the per-point standard errors with the points assumed independent (the results carry no per-batch values), which underestimates them when points share light paths.".to_string(),
            },
            if self.stats.min_is_ambiguous(2.0) {
                " Another point lies within 2 combined standard errors of the minimum, so Emin, U0 and Ud and their standard errors are approximate (a minimum of noisy values is biased low)."
            } else {
                ""
            }
        )
    }
}

/// Who signs the report (empty fields are left to fill in by hand).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Signature {
    pub designer: Option<String>,
    pub date: Option<String>,
    pub checked_by: Option<String>,
}

/// The report's inputs besides the surfaces.
pub struct ReportContext<'a> {
    pub scene: &'a str,
    pub results_file: &'a str,
    pub run: &'a RunInfo,
    pub singularity: &'a str,
    pub sources: Option<&'a LightSources>,
    pub peer: Option<(&'a str, &'a PeerResults)>,
    /// UGR per observer and line of sight, and each one's check against its limit.
    pub glare: &'a [GlareResult],
    pub glare_checks: Vec<Option<Check>>,
    pub sky: Option<&'a SkyInfo>,
    /// The false-colour luminance image: its file name in the report's folder, and it.
    pub luminance: Option<(String, LuminanceImage)>,
    pub signature: Signature,
}

/// `value ± se unit (rel %)` with a precision that shows the standard error's first two digits.
pub fn format_estimate(e: Estimate, unit: &str) -> String {
    format_figure(e.value, e.std_error, unit)
}

/// `value ± se` with the precision of [`format_figure`], without the relative error (for
/// figures on a log scale such as UGR, where a relative error means little).
pub fn format_plain(value: f64, std_error: f64) -> String {
    let digits = if std_error > 0.0 {
        (1 - std_error.log10().floor() as i32).clamp(0, 6) as usize
    } else {
        3
    };
    format!("{:.*} ± {:.*}", digits, value, digits, std_error)
}

/// [`format_estimate`] of a value and its standard error.
pub fn format_figure(value: f64, std_error: f64, unit: &str) -> String {
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
    format!("{}{unit}{rel}", format_plain(value, std_error))
}

fn group_digits(x: f64) -> String {
    format!("{x:.0}")
}

/// `Total: 5 luminaires, 14720 lm, 150.0 W input power.`
pub fn total_line(src: &LightSources) -> String {
    let count: usize = src.groups.iter().map(|g| g.count).sum();
    format!(
        "Total: {} luminaire{}, {} lm{}.",
        count,
        if count == 1 { "" } else { "s" },
        group_digits(src.total_flux_lm()),
        match src.total_input_watts() {
            Some(w) if count > 0 => format!(", {w:.1} W input power"),
            _ => ", input power not stated in every file".to_string(),
        }
    )
}

fn check_line(s: &mut String, what: &str, c: &Check) {
    let value = match c.value {
        Some(v) => format_estimate(v, c.unit),
        None => "undefined (no light)".to_string(),
    };
    let _ = writeln!(
        s,
        "| {what} | {} | {value} | {} | **{}** |",
        c.figure,
        c.requirement_text(),
        c.verdict_text()
    );
}

const CHECK_HEAD: &str =
    "| where | figure | value ± standard error | required | verdict |\n|---|---|---|---|---|";

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

    let checks = crate::html::all_checks(ctx, surfaces);
    if checks.is_empty() {
        let _ = writeln!(s, "The scene states no requirements: nothing is checked.\n");
    } else {
        let failed = checks.iter().filter(|c| !c.pass).count();
        let _ = writeln!(
            s,
            "**{}**: {} of {} requirements met.\n",
            if failed == 0 { "PASS" } else { "FAIL" },
            checks.len() - failed,
            checks.len()
        );
    }

    let _ = writeln!(s, "## Luminaire schedule\n");
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
                    "| luminaires | photometric file | lumens (file) | count | multiplier | maintenance factor | flux per luminaire (lm) | total flux (lm) | input power per luminaire (W) |\n|---|---|---:|---:|---:|---:|---:|---:|---:|"
                );
                for g in &src.groups {
                    let _ = writeln!(
                        s,
                        "| {} | `{}` | {} | {} | {} | {} | {:.1} | {:.0} | {} |",
                        g.names.join(", "),
                        g.file,
                        g.lumens_text(),
                        g.count,
                        g.multiplier,
                        g.maintenance_factor,
                        g.flux_lm,
                        g.flux_lm * g.count as f64,
                        g.input_watts
                            .map_or("not stated".to_string(), |w| format!("{w}")),
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
            if src.groups.iter().any(|g| g.file_flux_lm.is_none()) {
                let _ = writeln!(s, "{}\n", crate::scene_info::TABLE_LUMENS_NOTE);
            }
            let _ = writeln!(s, "{}\n", total_line(src));
        }
    }

    let _ = writeln!(s, "## Calculation surfaces\n");
    for r in surfaces {
        surface_section(&mut s, r);
    }
    if !ctx.glare.is_empty() {
        glare_section(&mut s, ctx);
    }
    if let Some(sky) = ctx.sky {
        daylight_section(&mut s, sky, surfaces);
    }
    if let Some((file, l)) = &ctx.luminance {
        let _ = writeln!(s, "## Luminance\n");
        let _ = writeln!(
            s,
            "False-colour luminance of the room from `{}` ({} × {} px, {}), on a logarithmic scale from {} to {} cd/m²; median {:.1} cd/m², largest {:.0} cd/m².\n\n![false-colour luminance]({file})\n",
            l.source, l.width, l.height, l.provenance, l.lo, l.hi, l.median, l.max
        );
    }

    if let Some((file, peer)) = ctx.peer {
        peer_section(&mut s, ctx, file, peer, surfaces);
    }
    let sig = &ctx.signature;
    let _ = writeln!(s, "## Signatures\n\n| | name | signature |\n|---|---|---|");
    for (what, v) in [
        ("Designer", &sig.designer),
        ("Date", &sig.date),
        ("Checked by", &sig.checked_by),
    ] {
        let _ = writeln!(s, "| {what} | {} | |", v.as_deref().unwrap_or(""));
    }
    s
}

fn glare_section(s: &mut String, ctx: &ReportContext) {
    let _ = writeln!(s, "## Glare (UGR)\n");
    let _ = writeln!(
        s,
        "Unified glare rating (CIE 117) per observer and line of sight; background luminance L_b = indirect vertical illuminance at the eye / π. Values below 10 are printed as computed (tables print \"<10\").\n"
    );
    let _ = writeln!(
        s,
        "| observer | eye (m) | line of sight | UGR ± SE | L_b (cd/m²) | luminaires seen | UGR_L | verdict |\n|---|---|---|---:|---:|---:|---:|---|"
    );
    for (g, c) in ctx.glare.iter().zip(&ctx.glare_checks) {
        let _ = writeln!(
            s,
            "| {} | ({:.2}, {:.2}, {:.2}) | ({:.2}, {:.2}, {:.2}) | {} | {} | {} | {} | {} |",
            g.observer,
            g.position.x,
            g.position.y,
            g.position.z,
            g.view.x,
            g.view.y,
            g.view.z,
            format_plain(g.ugr, g.standard_error),
            format_plain(
                g.background_luminance.value,
                g.background_luminance.standard_error
            ),
            g.sources.len(),
            g.limit.map_or("none".to_string(), |l| format!("{l}")),
            c.as_ref().map_or("not checked".to_string(), |c| format!(
                "**{}**",
                c.verdict_text()
            ))
        );
    }
    s.push('\n');
}

fn daylight_section(s: &mut String, sky: &SkyInfo, surfaces: &[SurfaceReport]) {
    let _ = writeln!(s, "## Daylight\n");
    let _ = writeln!(s, "{}\n", crate::daylight::sky_sentence(sky));
    let _ = writeln!(
        s,
        "| surface | DF median | DF min | DF mean |\n|---|---:|---:|---:|"
    );
    for r in surfaces {
        if let Some((f, _)) = &r.daylight {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} |",
                r.surface.name,
                format_estimate(f.median, "%"),
                format_estimate(f.min, "%"),
                format_estimate(f.mean, "%")
            );
        }
    }
    s.push('\n');
    let mut head = false;
    for r in surfaces {
        for c in r.daylight.iter().flat_map(|d| &d.1) {
            if !head {
                let _ = writeln!(s, "{CHECK_HEAD}");
                head = true;
            }
            check_line(s, &r.surface.name, c);
        }
    }
    if head {
        s.push('\n');
    }
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
    let _ = writeln!(s, "{}\n", r.method_text());
    if !r.checks.is_empty() {
        let _ = writeln!(s, "{CHECK_HEAD}");
        for c in &r.checks {
            check_line(s, &r.surface.name, c);
        }
        s.push('\n');
    }
    let _ = writeln!(s, "![isolux plot of {}]({})\n", r.surface.name, r.png);
}

/// `w` with its first letter upper-case.
pub fn capitalise(w: &str) -> String {
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
