//! Parser tests: fixtures written from closed-form distributions by scenes/photometry/generate.py;
//! every intensity is checked against the formula recomputed here, symmetric files against their
//! expanded forms, IES against EULUMDAT, and malformed files against their one-line errors.

use crate::common::{fixture, get, Rng};
use luxest_photometry::ies::parse_ies_str;
use luxest_photometry::ldt::parse_ldt_str;
use luxest_photometry::{load, LampFlux, OpeningShape, Photometry, SourceFormat, Symmetry};
use std::path::Path;

fn text(name: &str) -> String {
    std::fs::read_to_string(fixture(name)).unwrap()
}

// The fixture formulas (as in generate.py), in candela.
fn cosn(_c: f64, g: f64) -> f64 {
    if g > 90.0 {
        return 0.0;
    }
    1000.0 * g.to_radians().cos().max(0.0).powi(2)
}
fn down_up(g: f64) -> f64 {
    let cg = g.to_radians().cos();
    if cg >= 0.0 {
        cg
    } else {
        -0.3 * cg
    }
}
fn quad(c: f64, g: f64) -> f64 {
    let s = g.to_radians().sin();
    800.0 * down_up(g) * (1.0 + 0.5 * s * s * c.to_radians().cos().powi(2))
}
fn bilat(c: f64, g: f64) -> f64 {
    800.0 * down_up(g) * (1.0 + 0.4 * g.to_radians().sin() * c.to_radians().cos())
}
fn bilat90(c: f64, g: f64) -> f64 {
    800.0 * down_up(g) * (1.0 + 0.4 * g.to_radians().sin() * c.to_radians().sin())
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-300)
}

/// Every table node of `p` (C in 15° steps, γ in the file's steps) against the formula.
fn assert_nodes(p: &Photometry, f: fn(f64, f64) -> f64, tol: f64) {
    for &g in p.gamma_angles_deg() {
        for k in 0..24 {
            let c = 15.0 * k as f64;
            let (got, want) = (p.intensity_cd(c, g), f(c, g));
            assert!(
                rel(got, want) <= tol || (got - want).abs() < 1e-9,
                "{}: I({c}, {g}) = {got}, formula {want}",
                p.name
            );
        }
    }
}

/// Two distributions agree to `tol` (relative) on a fine (C, γ) grid, beyond the table included.
fn assert_same(a: &Photometry, b: &Photometry, tol: f64) {
    for ci in 0..=720 {
        let c = ci as f64 * 0.5;
        for gi in 0..=720 {
            let g = gi as f64 * 0.25;
            let (x, y) = (a.intensity_cd(c, g), b.intensity_cd(c, g));
            assert!(
                rel(x, y) <= tol || (x - y).abs() < 1e-12,
                "{} vs {} at C {c} γ {g}: {x} vs {y}",
                a.name,
                b.name
            );
        }
    }
}

#[test]
fn cos2_ies_and_ldt_describe_the_same_distribution() {
    let (i, l) = (get("cos2.ies"), get("cos2.ldt"));
    assert_eq!(i.format, SourceFormat::Ies2002);
    assert_eq!(l.format, SourceFormat::Eulumdat);
    assert_eq!(
        (i.symmetry, l.symmetry),
        (Symmetry::Rotational, Symmetry::Rotational)
    );
    assert_nodes(&i, cosn, 1e-9);
    assert_nodes(&l, cosn, 1e-9);
    // The issue's round trip: the same illuminances to 1e-6 requires the same intensities.
    assert_same(&i, &l, 1e-6);
    // A downlight table stopping at 90°: nothing above.
    assert_eq!(i.intensity_cd(10.0, 90.1), 0.0);
    assert_eq!(l.intensity_cd(10.0, 170.0), 0.0);
    assert_eq!(
        i.lamp_flux,
        LampFlux::Relative {
            lamps: 1,
            total_lm: 2000.0
        }
    );
    assert_eq!(
        l.lamp_flux,
        LampFlux::Relative {
            lamps: 1,
            total_lm: 2000.0
        }
    );
    for p in [&i, &l] {
        assert_eq!(p.opening.shape, OpeningShape::Circular);
        assert!(
            (p.opening.length_m - 0.2).abs() < 1e-12 && (p.opening.width_m - 0.2).abs() < 1e-12
        );
    }
}

#[test]
fn symmetric_files_expand_identically_to_their_full_forms() {
    for (name, f, sym) in [
        ("quad", quad as fn(f64, f64) -> f64, Symmetry::Quadrant),
        ("bilat", bilat, Symmetry::Bilateral0To180),
        ("bilat90", bilat90, Symmetry::Bilateral90To270),
    ] {
        let si = get(&format!("{name}.ies"));
        let fi = get(&format!("{name}-full.ies"));
        let sl = get(&format!("{name}.ldt"));
        let fl = get(&format!("{name}-full.ldt"));
        assert_eq!(si.symmetry, sym);
        assert_eq!(sl.symmetry, sym);
        assert_eq!(fi.symmetry, Symmetry::None);
        assert_eq!(fl.symmetry, Symmetry::None);
        for p in [&si, &fi, &sl, &fl] {
            assert_nodes(p, f, 1e-9);
        }
        // Identical tables give identical interpolation: demand agreement to rounding.
        assert_same(&si, &fi, 1e-12);
        assert_same(&sl, &fl, 1e-12);
        assert_same(&si, &sl, 1e-6);
        assert_eq!(si.c_angles_deg(), fi.c_angles_deg());
    }
    // A full file without the closing 360° plane wraps from 345° back to 0°.
    assert_same(&get("bilat-open.ies"), &get("bilat-full.ies"), 1e-12);
}

#[test]
fn multipliers_are_applied() {
    // The fixtures store I / (multiplier 2 × ballast factor 0.9); the nodes matched the formula.
    let p = get("quad.ies");
    assert!((p.applied_factor - 1.8).abs() < 1e-15);
    assert_eq!(
        p.lamp_flux,
        LampFlux::Relative {
            lamps: 1,
            total_lm: 3000.0
        }
    );
    let l = get("quad.ldt");
    assert!((l.applied_factor - 3.0).abs() < 1e-15); // 3000 lm / 1000
}

/// Flux of I0 cos^n γ over the lower hemisphere is 2π I0 / (n + 1). The table integral is exact
/// for the bilinear surface, so it differs from the closed form only by the interpolation error,
/// bounded by 2π (Δγ²/8) max|∂²I/∂γ²| ≤ 2π (Δγ²/8) n² I0.
#[test]
fn cos2_table_flux_matches_closed_form_within_interpolation_bound() {
    let (i0, n) = (1000.0, 2.0);
    let want = 2.0 * std::f64::consts::PI * i0 / (n + 1.0);
    let dg = 2.5f64.to_radians();
    let bound = 2.0 * std::f64::consts::PI * dg * dg / 8.0 * n * n * i0;
    for p in [get("cos2.ies"), get("cos2.ldt")] {
        let got = p.flux_from_table_lm();
        assert!(
            (got - want).abs() <= bound,
            "{}: {got} vs {want} ± {bound}",
            p.name
        );
        // The bound is not vacuous: 0.29 % of the flux.
        assert!(bound / want < 0.003);
    }
    let c = get("cos2.ldt").flux_check();
    // LORL 100 % of 2000 lm declared; the table holds 2π·1000/3 ≈ 2094 lm.
    assert_eq!(c.declared_lm, Some(2000.0));
    assert!((c.rel_diff.unwrap() - (c.table_lm - 2000.0) / 2000.0).abs() < 1e-15);
    assert!((c.lor.unwrap() - c.table_lm / 2000.0).abs() < 1e-15);
}

#[test]
fn examples_parse_and_their_flux_is_as_designed() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/photometry");
    let t = load(&root.join("troffer-600-led.ies")).unwrap();
    assert_eq!(t.symmetry, Symmetry::Quadrant);
    assert_eq!(t.lamp_flux, LampFlux::Absolute { luminaire_lm: None });
    assert_eq!(t.opening.shape, OpeningShape::Rectangular);
    assert_eq!(t.input_watts, Some(29.0));
    assert_eq!(t.keyword("lumcat"), Some("LX-T600-36"));
    assert!(
        t.keyword("OTHER").unwrap().contains("A = "),
        "[MORE] continues [OTHER]"
    );
    // Designed for 3600 lm (fine midpoint rule of the formula); 5° table steps cost < 1 %.
    assert!(
        rel(t.flux_from_table_lm(), 3600.0) < 0.01,
        "{}",
        t.flux_from_table_lm()
    );
    let p = load(&root.join("pendant-linear-4000.ldt")).unwrap();
    assert_eq!(p.symmetry, Symmetry::Quadrant);
    let c = p.flux_check();
    eprintln!(
        "troffer: table flux {:.1} lm; pendant: {c:?}",
        t.flux_from_table_lm()
    );
    assert_eq!(c.declared_lm, Some(3600.0));
    assert!(c.rel_diff.unwrap().abs() < 1e-8, "{c:?}");
    assert!(
        p.intensity_cd(0.0, 180.0) > 0.0,
        "the pendant has an uplight part"
    );
}

#[test]
fn versions_and_units() {
    let base = text("cos2.ies");
    let body = base.split_once('\n').unwrap().1;
    for (tag, fmt) in [
        ("IESNA:LM-63-1995", SourceFormat::Ies1995),
        ("IES:LM-63-2019", SourceFormat::Ies2019),
        ("IESNA91", SourceFormat::Ies1991),
        // Spellings found in the wild: a space after the colon, no colon (read as a 1986 file
        // before, whose line 2 then scaled the intensities), IES: for 2002, LM-63-1991.
        ("IESNA: LM-63-2002", SourceFormat::Ies2002),
        ("IESNA LM-63-2002", SourceFormat::Ies2002),
        ("IES:LM-63-2002", SourceFormat::Ies2002),
        ("iesna:lm-63-1995", SourceFormat::Ies1995),
        ("IESNA:LM-63-1991", SourceFormat::Ies1991),
    ] {
        let p = parse_ies_str("v.ies", &format!("{tag}\n{body}")).unwrap();
        assert_eq!(p.format, fmt);
        assert_nodes(&p, cosn, 1e-9);
    }
    // 1986: no version line, free text before TILT.
    let p = parse_ies_str(
        "v.ies",
        &format!(
            "Some manufacturer\nfree text\n{}",
            &body[body.find("TILT").unwrap()..]
        ),
    )
    .unwrap();
    assert_eq!(p.format, SourceFormat::Ies1986);
    assert!(p.keywords.is_empty());
    // A 1986 file whose free text names its standard is still a 1986 file.
    let p = parse_ies_str(
        "v.ies",
        &format!(
            "IESNA LM-63-1986 Acme
{}",
            &body[body.find("TILT").unwrap()..]
        ),
    )
    .unwrap();
    assert_eq!(p.format, SourceFormat::Ies1986);
    // The ballast-lamp factor multiplies in 1991 files only; in 2002 the field is "future use".
    let halved = body.replace("\n1 1 0\n", "\n1 0.5 0\n");
    let p91 = parse_ies_str("v.ies", &format!("IESNA91\n{halved}")).unwrap();
    let p02 = parse_ies_str("v.ies", &format!("IESNA:LM-63-2002\n{halved}")).unwrap();
    assert!((p91.intensity_cd(0.0, 0.0) - 500.0).abs() < 1e-9);
    assert!((p02.intensity_cd(0.0, 0.0) - 1000.0).abs() < 1e-9);
    // Feet: opening diameter 0.2 ft = 0.06096 m; keywords and [MORE] continuation.
    let feet = base.replace(" 1 1 2 -0.2 -0.2 0", " 1 1 1 -0.2 -0.2 0");
    assert_ne!(feet, base);
    let p = parse_ies_str("f.ies", &feet).unwrap();
    assert!((p.opening.length_m - 0.06096).abs() < 1e-12);
    let more = base.replace(
        "[MANUFAC] synthetic",
        "[MANUFAC] synthetic\n[MORE] and more",
    );
    let p = parse_ies_str("k.ies", &more).unwrap();
    assert!(p
        .keywords
        .iter()
        .any(|(k, v)| k == "MANUFAC" && v == "synthetic and more"));
    // Comma separators and CRLF line ends are tolerated.
    let p = parse_ies_str("c.ies", &base.replace(' ', ",").replace('\n', "\r\n")).unwrap();
    assert_nodes(&p, cosn, 1e-9);
}

/// Replaces the `k`-th whitespace token of 1-based line `line`.
fn edit(text: &str, line: usize, k: usize, new: &str) -> String {
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut toks: Vec<String> = lines[line - 1]
        .split_whitespace()
        .map(String::from)
        .collect();
    toks[k] = new.to_string();
    lines[line - 1] = toks.join(" ");
    lines.join("\n") + "\n"
}

fn expect_err(
    r: Result<Photometry, luxest_photometry::PhotometryError>,
    name: &str,
    line: Option<usize>,
    has: &str,
) {
    let e = r
        .err()
        .unwrap_or_else(|| panic!("{name}: parsed, expected an error containing '{has}'"));
    let s = e.to_string();
    assert_eq!(e.line, line, "{s}");
    assert!(s.starts_with(name), "{s}");
    assert!(s.contains(has), "'{s}' lacks '{has}'");
    assert!(!s.contains('\n'), "{s}");
}

#[test]
fn malformed_ies_files_give_one_line_errors_with_file_and_line() {
    let b = text("cos2.ies");
    let n = b.lines().count(); // 17: tag, 4 keywords, TILT, 2 header lines, 4+1 angle lines, 4 candela lines
    assert_eq!(n, 17);
    let no_tilt: String = b
        .lines()
        .filter(|l| !l.starts_with("TILT"))
        .map(|l| format!("{l}\n"))
        .collect();
    let cases: Vec<(String, Option<usize>, &str)> = vec![
        (String::new(), None, "empty file"),
        (
            b.replace("IESNA:LM-63-2002", "IESNA:LM-63-2030"),
            Some(1),
            "unknown LM-63 version",
        ),
        (
            b.replace("IESNA:LM-63-2002", "IESNA LM-63-2030"),
            Some(1),
            "unknown LM-63 version",
        ),
        (
            b.replace("IESNA:LM-63-2002", "IESNA:PHOTOMETRY"),
            Some(1),
            "unknown LM-63 version",
        ),
        (no_tilt, Some(16), "missing TILT"),
        (
            b.replace("TILT=NONE", "TILT=INCLUDE"),
            Some(6),
            "TILT=INCLUDE",
        ),
        (
            b.replace("TILT=NONE", "TILT=lamp.tlt"),
            Some(6),
            "external tilt file",
        ),
        (edit(&b, 7, 5, "2"), Some(7), "type B (2) is not supported"),
        (edit(&b, 7, 5, "3"), Some(7), "type A (3) is not supported"),
        (edit(&b, 7, 6, "3"), Some(7), "units type"),
        (
            edit(&b, 7, 1, "0"),
            Some(7),
            "lumens per lamp must be positive",
        ),
        (
            edit(&b, 7, 2, "-1"),
            Some(7),
            "candela multiplier must be positive",
        ),
        (
            edit(&b, 7, 3, "38"),
            Some(13),
            "not strictly increasing (90 then 0)",
        ),
        (edit(&b, 7, 3, "36"), Some(9), "from 0 or 90 to 90 or 180"),
        (edit(&b, 7, 3, "3.5"), Some(7), "must be an integer"),
        (
            edit(&b, 7, 4, "2"),
            Some(14),
            "horizontal angle 1000 outside [0, 360]",
        ),
        (edit(&b, 9, 3, "2.5"), Some(9), "not strictly increasing"),
        (edit(&b, 12, 6, "200"), Some(12), "outside [0, 180]"),
        (
            edit(&b, 13, 0, "45"),
            Some(13),
            "horizontal angles 45 to 45",
        ),
        (edit(&b, 15, 2, "-5"), Some(15), "negative candela value -5"),
        (
            edit(&b, 15, 2, "nan"),
            Some(15),
            "expected a number, found 'nan'",
        ),
        (
            edit(&b, 15, 2, "inf"),
            Some(15),
            "expected a number, found 'inf'",
        ),
        (edit(&b, 15, 2, "1e999"), Some(15), "non-finite number"),
        (
            edit(&b, 15, 2, "12x"),
            Some(15),
            "expected a number, found '12x'",
        ),
        (
            format!("{b}7\n"),
            Some(18),
            "unexpected value '7' after the 37 candela values",
        ),
        (
            b.lines().take(16).map(|l| format!("{l}\n")).collect(),
            Some(16),
            "truncated file: expected 37 candela values",
        ),
        (
            b.lines().take(7).map(|l| format!("{l}\n")).collect(),
            Some(7),
            "truncated file: expected ballast factor",
        ),
        (
            b.lines().take(6).map(|l| format!("{l}\n")).collect(),
            Some(6),
            "truncated file: expected number of lamps",
        ),
    ];
    for (t, line, has) in cases {
        expect_err(parse_ies_str("bad.ies", &t), "bad.ies", line, has);
    }
    // A 360° plane that does not repeat the 0° plane.
    let full = text("bilat-full.ies");
    let lines: Vec<&str> = full.lines().collect();
    let last = lines.len();
    expect_err(
        parse_ies_str("bad.ies", &edit(&full, last - 3, 0, "1")),
        "bad.ies",
        Some(14),
        "360° plane must repeat",
    );
}

#[test]
fn malformed_ldt_files_give_one_line_errors_with_file_and_line() {
    let b = text("cos2.ldt");
    assert_eq!(b.lines().count(), 140);
    let set = |line: usize, v: &str| {
        let mut l: Vec<&str> = b.lines().collect();
        l[line - 1] = v;
        l.join("\r\n") + "\r\n"
    };
    let cases: Vec<(String, Option<usize>, &str)> = vec![
        (String::new(), None, "empty file: not a EULUMDAT file"),
        ("\r\n\r\n".into(), None, "empty file"),
        (
            set(3, "5"),
            Some(3),
            "symmetry indicator Isym must be an integer from 0 to 4",
        ),
        (set(4, "abc"), Some(4), "expected a number, found 'abc'"),
        (
            set(3, "2").replace("\r\n24\r\n15\r\n", "\r\n23\r\n15\r\n"),
            Some(4),
            "cannot hold symmetry Isym = 2",
        ),
        (set(23, "120"), Some(23), "LORL must be a percentage"),
        (set(29, "0"), Some(29), "lamp flux must be positive"),
        (
            set(27, "0"),
            Some(27),
            "number of lamps must be a non-zero integer",
        ),
        (set(50, "200"), Some(51), "C angles not strictly increasing"),
        (set(80, "NaN"), Some(80), "expected a number, found 'NaN'"),
        (set(103, "190"), Some(103), "outside [0, 180]"),
        // A table that does not start at 0 (or 90) left straight down at 0 cd.
        (
            set(67, "1"),
            Some(67),
            "gamma angles must start at 0 or 90, found 1 (the table",
        ),
        (set(120, "-1"), Some(120), "negative luminous intensity -1"),
        (
            format!("{b}5\r\n"),
            Some(141),
            "unexpected value '5' after the 37 intensities",
        ),
        (
            b.lines().take(130).map(|l| format!("{l}\r\n")).collect(),
            Some(130),
            "truncated file: expected 37 intensities",
        ),
        (
            b.lines().take(20).map(|l| format!("{l}\r\n")).collect(),
            Some(20),
            "expected luminous area height C270 on line 21",
        ),
        (
            set(3, "2"),
            Some(140),
            "expected 481 intensities (13 C planes x 37 gamma angles), found 37",
        ),
        (
            set(3, "2").replace("\r\n180\r\n", "\r\n181\r\n"),
            Some(43),
            "needs the stored C planes to span 0 to 180",
        ),
    ];
    for (t, line, has) in cases {
        expect_err(parse_ldt_str("bad.ldt", &t), "bad.ldt", line, has);
    }
}

/// Random bytes, random token mutations and every truncation of valid files never panic, and
/// every error is one line naming the file.
#[test]
fn parsers_never_panic() {
    let mut rng = Rng(7);
    let check = |r: Result<Photometry, luxest_photometry::PhotometryError>| {
        if let Err(e) = r {
            let s = e.to_string();
            assert!(s.starts_with("fz") && !s.contains('\n'), "{s}");
        }
    };
    let junk = [
        "-1",
        "0",
        "1e308",
        "-0",
        "360",
        "90",
        "1000000",
        "x",
        "",
        "\n",
        "[",
        "TILT=NONE",
        "1.5",
        "99999999999",
    ];
    for base in [
        "cos2.ies",
        "quad.ies",
        "bilat90.ies",
        "cos2.ldt",
        "bilat90.ldt",
        "quad.ldt",
    ] {
        let b = text(base);
        let is_ies = base.ends_with(".ies");
        let parse = |t: &str| {
            if is_ies {
                parse_ies_str("fz", t)
            } else {
                parse_ldt_str("fz", t)
            }
        };
        for cut in (0..b.len()).step_by(7) {
            if b.is_char_boundary(cut) {
                check(parse(&b[..cut]));
            }
        }
        let toks: Vec<&str> = b.split_inclusive(char::is_whitespace).collect();
        for _ in 0..1500 {
            let mut t: Vec<String> = toks.iter().map(|s| s.to_string()).collect();
            for _ in 0..1 + rng.below(3) {
                let k = rng.below(t.len());
                match rng.below(4) {
                    0 => t[k] = format!("{} ", junk[rng.below(junk.len())]),
                    1 => {
                        t.remove(k);
                    }
                    2 => {
                        let d = t[k].clone();
                        t.insert(k, d);
                    }
                    _ => t[k] = format!("{} ", (rng.next() as i64 as f64) / 1e15),
                }
            }
            check(parse(&t.concat()));
        }
    }
    for _ in 0..3000 {
        let n = rng.below(400);
        let bytes: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
        let s = String::from_utf8_lossy(&bytes);
        check(parse_ies_str("fz", &s));
        check(parse_ldt_str("fz", &s));
        check(parse_ies_str(
            "fz",
            &format!("IESNA:LM-63-2002\nTILT=NONE\n{s}"),
        ));
    }
}

#[test]
fn bilateral_90_270_without_a_180_plane_wraps_through_0() {
    // Planes 90, 135, 225, 270 (no 180): mirrored about 90–270 they give 45 (from 135) and
    // 315 (from 225); C = 0 lies midway between 315 and 45.
    let rows = [[100.0, 50.0], [200.0, 80.0], [300.0, 90.0], [400.0, 120.0]];
    let mut t = String::from(
        "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 4 1 2 0 0 0\n1 1 0\n0 90\n90 135 225 270\n",
    );
    for r in rows {
        t += &format!("{} {}\n", r[0], r[1]);
    }
    let p = parse_ies_str("w.ies", &t).unwrap();
    assert_eq!(p.symmetry, Symmetry::Bilateral90To270);
    for (j, g) in [(0, 0.0), (1, 90.0)] {
        let (r135, r225) = (rows[1][j], rows[2][j]);
        assert!((p.intensity_cd(0.0, g) - 0.5 * (r135 + r225)).abs() < 1e-9);
        // C = 20: 65/90 of the way from 315 (row 225) to 45 (row 135).
        let f = 65.0 / 90.0;
        assert!((p.intensity_cd(20.0, g) - (r225 * (1.0 - f) + r135 * f)).abs() < 1e-9);
        assert!((p.intensity_cd(135.0, g) - r135).abs() < 1e-12);
        assert!((p.intensity_cd(45.0, g) - r135).abs() < 1e-12);
    }
}

#[test]
fn table_round_trip_is_exact() {
    for name in ["quad.ies", "bilat90.ldt", "cos2.ies"] {
        let p = get(name);
        let (c, g, rows) = p.to_table();
        let q = Photometry::from_table("copy", &c, &g, &rows).unwrap();
        assert_same(&p, &q, 0.0);
        assert_eq!(p.flux_from_table_lm(), q.flux_from_table_lm());
    }
}

/// Files with classic Mac OS line ends (CR alone), or CR CR LF, read like their LF versions.
#[test]
fn cr_only_and_cr_cr_lf_line_ends_read_like_lf() {
    for (name, parse) in [
        (
            "cos2.ies",
            parse_ies_str as fn(&str, &str) -> Result<luxest_photometry::Photometry, _>,
        ),
        ("cos2.ldt", parse_ldt_str),
    ] {
        let lf = text(name).replace("\r\n", "\n");
        // CR alone (classic Mac OS), and CR CR LF (a CRLF file through text-mode FTP).
        let cr = lf.replace('\n', "\r");
        let crcrlf = lf.replace('\n', "\r\r\n");
        let a = parse(name, &lf).unwrap();
        for other in [&cr, &crcrlf] {
            let b = parse(name, other).unwrap();
            for (c, g) in [(0.0, 0.0), (45.0, 30.0), (180.0, 60.0)] {
                assert_eq!(
                    a.intensity_cd(c, g),
                    b.intensity_cd(c, g),
                    "{name} C {c} γ {g}"
                );
            }
        }
        assert!(a.intensity_cd(0.0, 0.0) > 0.0);
    }
}
