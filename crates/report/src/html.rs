//! The HTML report: one self-contained file (`report.html`: CSS inline, every image a PNG
//! data URI, no script, no external font or file) with what a lighting designer signs, in
//! this order:
//!
//! 1. the scene and the run (estimator, light paths, seed, scene hash, program version) and a
//!    summary line: how many requirements are met;
//! 2. per calculation surface its figures (Ē, Emin, Emax, U0, Ud, each ± its standard error),
//!    the requirements with a pass / fail mark, and its isolux plot;
//! 3. glare: UGR per observer and line of sight with its limit UGR_L and a mark (when the
//!    results carry glare ratings);
//! 4. daylight: the sky, and per surface the daylight factor's median, minimum and mean with
//!    the EN 17037 target and marks (when the results carry a sky);
//! 5. the luminaire schedule (file, the file's lumens, count, multiplier, maintenance factor,
//!    flux per luminaire and in total, input power);
//! 6. the false-colour luminance image of the room with its cd/m² scale (when one is given);
//! 7. the signature block: designer, date, checked by.
//!
//! Marks are `<span class="mark pass">PASS</span>` (white on green, #1a7f37) and
//! `<span class="mark fail">FAIL</span>` (white on red, #c62828), colours the false-colour
//! scales do not use, so a screenshot shows where they are; the page is 1000 px wide.

use crate::checks::Check;
use crate::markdown::{format_estimate, format_plain, ReportContext, SurfaceReport};
use std::fmt::Write;

/// The marks' background colours (sRGB), as the CSS gives them.
pub const PASS_RGB: [u8; 3] = [0x1a, 0x7f, 0x37];
pub const FAIL_RGB: [u8; 3] = [0xc6, 0x28, 0x28];

const CSS: &str = "\
body{margin:0;background:#fff;color:#1a1a1a;font:14px/1.45 'DejaVu Sans',Arial,Helvetica,sans-serif}
main{width:960px;margin:0;padding:20px 20px 32px 20px}
h1{font-size:24px;margin:0 0 8px 0}
h2{font-size:19px;margin:26px 0 8px 0;border-bottom:2px solid #1a1a1a}
h3{font-size:16px;margin:18px 0 6px 0}
p{margin:6px 0}
table{border-collapse:collapse;margin:6px 0 10px 0}
th,td{border:1px solid #9a9a9a;padding:3px 8px;text-align:left;vertical-align:middle}
th{background:#ececec}
td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
.mark{display:inline-block;min-width:64px;padding:2px 6px;color:#fff;font-weight:bold;text-align:center}
.pass{background:#1a7f37}
.fail{background:#c62828}
.note{color:#555;font-size:12px}
img{display:block;margin:8px 0}
.sign td{height:44px;min-width:230px}
.sign th{width:120px}
";

/// Escapes text for HTML.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            _ => o.push(c),
        }
    }
    o
}

/// Standard base64 (RFC 4648, with padding).
pub fn base64(bytes: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut o = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                o.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                o.push('=');
            }
        }
    }
    o
}

fn img(png: &[u8], alt: &str) -> String {
    format!(
        "<img alt=\"{}\" src=\"data:image/png;base64,{}\">",
        escape(alt),
        base64(png)
    )
}

/// The mark of a check.
pub fn mark(c: &Check) -> String {
    format!(
        "<span class=\"mark {}\">{}</span>{}",
        if c.pass { "pass" } else { "fail" },
        if c.pass { "PASS" } else { "FAIL" },
        if c.close {
            " <span class=\"note\">within 2 SE</span>"
        } else {
            ""
        }
    )
}

fn check_row(s: &mut String, what: &str, c: &Check) {
    let value = match c.value {
        Some(v) => format_estimate(v, c.unit),
        None => "undefined (no light)".to_string(),
    };
    let _ = writeln!(
        s,
        "<tr><td>{}</td><td>{}</td><td class=\"num\">{}</td><td>{}</td><td>{}</td></tr>",
        escape(what),
        escape(&c.figure),
        escape(&value),
        escape(&c.requirement_text()),
        mark(c)
    );
}

const CHECK_HEAD: &str =
    "<tr><th>where</th><th>figure</th><th>value ± standard error</th><th>required</th><th>verdict</th></tr>";

/// Every check of the report, in the order the document shows them.
pub fn all_checks<'a>(ctx: &'a ReportContext, surfaces: &'a [SurfaceReport]) -> Vec<&'a Check> {
    let mut out: Vec<&Check> = surfaces.iter().flat_map(|r| r.checks.iter()).collect();
    out.extend(ctx.glare_checks.iter().flatten());
    out.extend(
        surfaces
            .iter()
            .filter_map(|r| r.daylight.as_ref())
            .flat_map(|d| d.1.iter()),
    );
    out
}

/// The whole HTML document.
pub fn render(ctx: &ReportContext, surfaces: &[SurfaceReport]) -> String {
    let mut s = String::new();
    let title = format!("Lighting report: {}", ctx.scene);
    let _ = writeln!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n<style>\n{CSS}</style>\n</head>\n<body>\n<main>",
        escape(&title)
    );
    let _ = writeln!(s, "<h1>{}</h1>", escape(&title));
    let _ = writeln!(
        s,
        "<p>Scene <b>{}</b>, computed by luxest {} with the {} from <code>{}</code>: {} light paths, seed {}, {:.2} s wall clock; scene content hash <code>{}</code>; singularity handling {}. Illuminance in lx, luminance in cd/m²; every Monte Carlo figure is value ± one standard error.</p>",
        escape(ctx.scene),
        escape(&ctx.run.program_version),
        escape(&ctx.run.estimator),
        escape(ctx.results_file),
        ctx.run.samples,
        ctx.run.seed,
        ctx.run.seconds,
        escape(&ctx.run.scene_hash),
        escape(ctx.singularity)
    );
    let checks = all_checks(ctx, surfaces);
    if checks.is_empty() {
        let _ = writeln!(
            s,
            "<p>The scene states no requirements: nothing is checked.</p>"
        );
    } else {
        let failed = checks.iter().filter(|c| !c.pass).count();
        let _ = writeln!(
            s,
            "<p><span class=\"mark {}\">{}</span> {} of {} requirements met.</p>",
            if failed == 0 { "pass" } else { "fail" },
            if failed == 0 { "PASS" } else { "FAIL" },
            checks.len() - failed,
            checks.len()
        );
    }

    let _ = writeln!(s, "<h2>Calculation surfaces</h2>");
    for r in surfaces {
        surface_section(&mut s, r);
    }
    if !ctx.glare.is_empty() {
        glare_section(&mut s, ctx);
    }
    if let Some(sky) = ctx.sky {
        daylight_section(&mut s, sky, surfaces);
    }
    schedule_section(&mut s, ctx);
    if let Some((_, l)) = &ctx.luminance {
        let _ = writeln!(s, "<h2>Luminance</h2>");
        let _ = writeln!(
            s,
            "<p>False-colour luminance of the room from <code>{}</code> ({} × {} px, {}), on a logarithmic scale from {} to {} cd/m²; median {:.1} cd/m², largest {:.0} cd/m².</p>",
            escape(&l.source),
            l.width,
            l.height,
            escape(&l.provenance),
            l.lo,
            l.hi,
            l.median,
            l.max
        );
        let _ = writeln!(s, "{}", img(&l.png, "false-colour luminance image"));
    }
    let sig = &ctx.signature;
    let _ = writeln!(s, "<h2>Signatures</h2>");
    let _ = writeln!(s, "<table class=\"sign\">");
    for (what, v) in [
        ("Designer", &sig.designer),
        ("Date", &sig.date),
        ("Checked by", &sig.checked_by),
    ] {
        let _ = writeln!(
            s,
            "<tr><th>{what}</th><td>{}</td><td class=\"note\">signature</td></tr>",
            escape(v.as_deref().unwrap_or(""))
        );
    }
    let _ = writeln!(s, "</table>\n</main>\n</body>\n</html>");
    s
}

fn surface_section(s: &mut String, r: &SurfaceReport) {
    let g = &r.surface.grid;
    let (su, sv) = g.spacing_m();
    let (lu, lv) = g.sides_m();
    let st = r.stats;
    let _ = writeln!(s, "<h3>{}</h3>", escape(&r.surface.name));
    let _ = writeln!(
        s,
        "<p>{} illuminance on a {:.2} m × {:.2} m rectangle, {:.2} m margin excluded: {} × {} = {} points at {:.3} m × {:.3} m spacing. {}</p>",
        escape(&crate::markdown::capitalise(&r.surface.kind)),
        lu,
        lv,
        g.margin_m,
        g.nu,
        g.nv,
        st.n_points,
        su,
        sv,
        escape(&r.method_text())
    );
    let lit = st.e_max.value > 0.0;
    let ratio = |e| {
        if lit {
            format_estimate(e, "")
        } else {
            "undefined (no light)".to_string()
        }
    };
    let _ = writeln!(
        s,
        "<table>\n<tr><th>figure</th><th>value ± standard error (relative)</th></tr>"
    );
    for (figure, value) in [
        ("Ē", format_estimate(st.e_avg, "lx")),
        ("Emin", format_estimate(st.e_min, "lx")),
        ("Emax", format_estimate(st.e_max, "lx")),
        ("U0 = Emin/Ē", ratio(st.u0)),
        ("Ud = Emin/Emax", ratio(st.ud)),
    ] {
        let _ = writeln!(
            s,
            "<tr><td>{figure}</td><td class=\"num\">{}</td></tr>",
            escape(&value)
        );
    }
    let _ = writeln!(s, "</table>");
    if r.checks.is_empty() {
        let _ = writeln!(
            s,
            "<p class=\"note\">No requirements stated for this surface.</p>"
        );
    } else {
        let _ = writeln!(s, "<table>\n{CHECK_HEAD}");
        for c in &r.checks {
            check_row(s, &r.surface.name, c);
        }
        let _ = writeln!(s, "</table>");
    }
    let _ = writeln!(
        s,
        "{}",
        img(&r.png_bytes, &format!("isolux plot of {}", r.surface.name))
    );
    if let Some(c) = &r.comparison {
        let agree = c.points.iter().filter(|p| p.agrees).count();
        let _ = writeln!(
            s,
            "<p>Peer comparison: {agree} of {} points within {:.0} % + {:.0}σ of the peer's; mean relative difference {:+.2} % (point by point in report.md).</p>",
            c.points.len(),
            100.0 * crate::peer::REL_TOLERANCE,
            crate::peer::SIGMAS,
            100.0 * c.mean_rel_diff()
        );
    }
}

fn glare_section(s: &mut String, ctx: &ReportContext) {
    let _ = writeln!(s, "<h2>Glare (UGR)</h2>");
    let _ = writeln!(
        s,
        "<p>Unified glare rating (CIE 117) per observer and line of sight: UGR = 8 log10(0.25 / L_b · Σ L² ω / p²), background luminance L_b = indirect vertical illuminance at the eye / π. Values below 10 are printed as computed (tables print “&lt;10”).</p>"
    );
    let _ = writeln!(s, "<table>\n<tr><th>observer</th><th>eye (m)</th><th>line of sight</th><th>UGR ± SE</th><th>L_b (cd/m²)</th><th>luminaires seen</th><th>UGR_L</th><th>verdict</th></tr>");
    for (g, c) in ctx.glare.iter().zip(&ctx.glare_checks) {
        let _ = writeln!(
            s,
            "<tr><td>{}</td><td class=\"num\">({:.2}, {:.2}, {:.2})</td><td class=\"num\">({:.2}, {:.2}, {:.2})</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td>{}</td></tr>",
            escape(&g.observer),
            g.position.x,
            g.position.y,
            g.position.z,
            g.view.x,
            g.view.y,
            g.view.z,
            escape(&format_plain(g.ugr, g.standard_error)),
            escape(&format_plain(
                g.background_luminance.value,
                g.background_luminance.standard_error
            )),
            g.sources.len(),
            g.limit.map_or("none".to_string(), |l| format!("{l}")),
            c.as_ref().map_or("not checked".to_string(), mark)
        );
    }
    let _ = writeln!(s, "</table>");
}

fn daylight_section(s: &mut String, sky: &luxest_io::sensors::SkyInfo, surfaces: &[SurfaceReport]) {
    let _ = writeln!(s, "<h2>Daylight</h2>");
    let _ = writeln!(s, "<p>{}</p>", escape(&crate::daylight::sky_sentence(sky)));
    let _ = writeln!(
        s,
        "<table>\n<tr><th>surface</th><th>DF median</th><th>DF min</th><th>DF mean</th></tr>"
    );
    for r in surfaces {
        if let Some((f, _)) = &r.daylight {
            let _ = writeln!(
                s,
                "<tr><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td></tr>",
                escape(&r.surface.name),
                escape(&format_estimate(f.median, "%")),
                escape(&format_estimate(f.min, "%")),
                escape(&format_estimate(f.mean, "%"))
            );
        }
    }
    let _ = writeln!(s, "</table>");
    let checks: Vec<(&str, &Check)> = surfaces
        .iter()
        .filter_map(|r| Some((r.surface.name.as_str(), &r.daylight.as_ref()?.1)))
        .flat_map(|(n, cs)| cs.iter().map(move |c| (n, c)))
        .collect();
    if !checks.is_empty() {
        let _ = writeln!(s, "<table>\n{CHECK_HEAD}");
        for (n, c) in checks {
            check_row(s, n, c);
        }
        let _ = writeln!(s, "</table>");
    }
}

fn schedule_section(s: &mut String, ctx: &ReportContext) {
    let _ = writeln!(s, "<h2>Luminaire schedule</h2>");
    let Some(src) = ctx.sources else {
        let _ = writeln!(
            s,
            "<p>Not listed: the report was run without <code>--scene-info</code>.</p>"
        );
        return;
    };
    if !src.groups.is_empty() {
        let _ = writeln!(s, "<table>\n<tr><th>luminaires</th><th>photometric file</th><th>lumens (file)</th><th>count</th><th>multiplier</th><th>maintenance factor</th><th>flux per luminaire (lm)</th><th>total flux (lm)</th><th>input power per luminaire (W)</th></tr>");
        for g in &src.groups {
            let _ = writeln!(
                s,
                "<tr><td>{}</td><td><code>{}</code></td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{:.1}</td><td class=\"num\">{:.0}</td><td class=\"num\">{}</td></tr>",
                escape(&g.names.join(", ")),
                escape(&g.file),
                g.lumens_text(),
                g.count,
                g.multiplier,
                g.maintenance_factor,
                g.flux_lm,
                g.flux_lm * g.count as f64,
                g.input_watts
                    .map_or("not stated".to_string(), |w| format!("{w}"))
            );
        }
        let _ = writeln!(s, "</table>");
    }
    for (name, flux) in &src.other {
        let _ = writeln!(
            s,
            "<p>Other emitter <code>{}</code>: {flux:.1} lm.</p>",
            escape(name)
        );
    }
    if src.groups.iter().any(|g| g.file_flux_lm.is_none()) {
        let _ = writeln!(
            s,
            "<p class=\"note\">{}</p>",
            escape(crate::scene_info::TABLE_LUMENS_NOTE)
        );
    }
    let _ = writeln!(s, "<p>{}</p>", escape(&crate::markdown::total_line(src)));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_and_escaping_follow_their_standards() {
        // RFC 4648 §10 test vectors.
        for (i, o) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(i.as_bytes()), o);
        }
        assert_eq!(escape("<a & \"b\">"), "&lt;a &amp; &quot;b&quot;&gt;");
    }
}
