//! EULUMDAT (`.ldt`) photometric files (Stockmar, "EULUMDAT — ein Leuchtendatenformat für den
//! europäischen Beleuchtungsplaner", 1990; the de-facto layout DIALux and Relux read).
//!
//! A fixed line layout; text fields occupy one line each, numbers one per line:
//!
//! | line | field |
//! |------|-------|
//! | 1 | manufacturer / database / version |
//! | 2 | Ityp: 0 point source without symmetry, 1 rotational, 2 linear, 3 point source other symmetry |
//! | 3 | Isym: 0 none, 1 rotational, 2 about C0–C180, 3 about C90–C270, 4 about both |
//! | 4, 5 | Mc number of C planes in 0–360°, Dc spacing (0: not equidistant) |
//! | 6, 7 | Ng number of γ angles, Dg spacing |
//! | 8–12 | report number, luminaire name, luminaire number, file name, date/user |
//! | 13–15 | luminaire length/diameter, width (0: circular), height (mm) |
//! | 16–21 | luminous area length/diameter, width (0: circular), height at C0, C90, C180, C270 (mm) |
//! | 22–25 | DFF downward flux fraction (%), LORL light output ratio (%), conversion factor for intensities, tilt during measurement (°) |
//! | 26 | n, number of lamp sets |
//! | 26a–f | n lines each: number of lamps (negative: absolute photometry), lamp type, total lamp flux (lm), colour, CRI group, wattage incl. ballast (W) |
//! | 27 | 10 direct ratios DR for room indices k = 0.6 … 5 |
//! | 28 | Mc C angles |
//! | 29 | Ng γ angles |
//! | 30 | intensities (cd/klm) for C planes Mc1 … Mc2, Ng values each |
//!
//! with (1-based plane indices, wrapping past Mc) Isym 0: Mc1 = 1, Mc2 = Mc; 1: 1, 1;
//! 2: 1, Mc/2 + 1; 3: 3Mc/4 + 1, Mc1 + Mc/2 (the planes 270° … 360°/0° … 90°); 4: 1, Mc/4 + 1.
//! From line 27 on the numbers are read as a stream, so files writing several per line parse too.
//! Decimal commas (`0,5`) are accepted.
//!
//! Candela (cd) = value (cd/klm) × Φ/1000 × conversion factor, Φ the first lamp set's total flux
//! (for absolute photometry the luminaire flux written in that field). Lengths: mm → m, `length`
//! along C0–C180 (local x), `width` along C90–C270 (local y), height the largest of the four.

use crate::error::PhotometryError;
use crate::ies::{parse_number, IntensityNames, Tok, Tokens};
use crate::photometry::{
    LampFlux, LuminousOpening, OpeningShape, Photometry, RawTable, SourceFormat, Symmetry,
};

struct Lines<'a> {
    name: &'a str,
    lines: Vec<&'a str>,
}

impl<'a> Lines<'a> {
    /// Line `n` (1-based) as text; a truncated-file error when absent.
    fn text(&self, n: usize, what: &str) -> Result<&'a str, PhotometryError> {
        if self.lines.iter().all(|l| l.trim().is_empty()) {
            return Err(PhotometryError::new(
                self.name,
                None,
                "empty file: not a EULUMDAT file",
            ));
        }
        self.lines.get(n - 1).map(|l| l.trim()).ok_or_else(|| {
            PhotometryError::new(
                self.name,
                Some(self.lines.len()),
                format!(
                    "truncated file: expected {what} on line {n}, the file has {} lines",
                    self.lines.len()
                ),
            )
        })
    }
    fn number(&self, n: usize, what: &str) -> Result<f64, PhotometryError> {
        let t = self.text(n, what)?;
        let t = decimal_comma(t);
        parse_number(&t)
            .map_err(|m| PhotometryError::new(self.name, Some(n), format!("{what}: {m}")))
    }
    fn integer(&self, n: usize, what: &str, lo: i64, hi: i64) -> Result<i64, PhotometryError> {
        let v = self.number(n, what)?;
        if v.fract() != 0.0 || v < lo as f64 || v > hi as f64 {
            return Err(PhotometryError::new(
                self.name,
                Some(n),
                format!("{what} must be an integer from {lo} to {hi}, found {v}"),
            ));
        }
        Ok(v as i64)
    }
}

fn decimal_comma(t: &str) -> std::borrow::Cow<'_, str> {
    if t.contains(',') && !t.contains('.') {
        std::borrow::Cow::Owned(t.replace(',', "."))
    } else {
        std::borrow::Cow::Borrowed(t)
    }
}

/// Parses a EULUMDAT file from text; `name` is used in error messages. Never panics.
pub fn parse_ldt_str(name: &str, text: &str) -> Result<Photometry, PhotometryError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let unified = crate::unify_line_ends(text);
    let text = unified.as_ref();
    let l = Lines {
        name,
        lines: text.lines().collect(),
    };
    let err = |line: usize, m: String| PhotometryError::new(name, Some(line), m);
    let mut keywords = Vec::new();
    keywords.push((
        "MANUFAC".to_string(),
        l.text(1, "manufacturer")?.to_string(),
    ));
    let _ityp = l.integer(2, "type indicator Ityp", 0, 3)?;
    let isym = l.integer(3, "symmetry indicator Isym", 0, 4)?;
    let mc = l.integer(4, "number of C planes Mc", 1, 721)? as usize;
    let _dc = l.number(5, "C-plane spacing Dc")?;
    let ng = l.integer(6, "number of gamma angles Ng", 2, 361)? as usize;
    let _dg = l.number(7, "gamma spacing Dg")?;
    for (n, key) in [
        (8, "TEST"),
        (9, "LUMINAIRE"),
        (10, "LUMCAT"),
        (11, "FILENAME"),
        (12, "DATE"),
    ] {
        keywords.push((key.to_string(), l.text(n, key)?.to_string()));
    }
    let mut mm = [0.0; 9];
    let names = [
        "luminaire length",
        "luminaire width",
        "luminaire height",
        "luminous area length",
        "luminous area width",
        "luminous area height C0",
        "luminous area height C90",
        "luminous area height C180",
        "luminous area height C270",
    ];
    for (k, v) in mm.iter_mut().enumerate() {
        *v = l.number(13 + k, names[k])?;
        if *v < 0.0 {
            return Err(err(
                13 + k,
                format!("{} must not be negative, found {v} mm", names[k]),
            ));
        }
    }
    let dff = l.number(22, "downward flux fraction DFF")?;
    let lorl = l.number(23, "light output ratio LORL")?;
    for (n, v, what) in [(22, dff, "DFF"), (23, lorl, "LORL")] {
        if !(0.0..=100.0).contains(&v) {
            return Err(err(
                n,
                format!("{what} must be a percentage from 0 to 100, found {v}"),
            ));
        }
    }
    let conversion = l.number(24, "conversion factor for luminous intensities")?;
    if conversion <= 0.0 {
        return Err(err(
            24,
            format!("conversion factor must be positive, found {conversion}"),
        ));
    }
    let _tilt = l.number(25, "tilt during measurement")?;
    let n_sets = l.integer(26, "number of lamp sets", 1, 20)? as usize;
    let base = 27;
    let lamps = l.number(base, "number of lamps")?;
    if lamps == 0.0 || lamps.fract() != 0.0 || lamps.abs() > 1e6 {
        return Err(err(
            base,
            format!("number of lamps must be a non-zero integer, found {lamps}"),
        ));
    }
    keywords.push((
        "LAMP".to_string(),
        l.text(base + n_sets, "lamp type")?.to_string(),
    ));
    let flux = l.number(base + 2 * n_sets, "total luminous flux of lamps")?;
    if flux <= 0.0 {
        return Err(err(
            base + 2 * n_sets,
            format!("lamp flux must be positive, found {flux} lm"),
        ));
    }
    keywords.push((
        "COLOUR".to_string(),
        l.text(base + 3 * n_sets, "colour appearance")?.to_string(),
    ));
    keywords.push((
        "CRI".to_string(),
        l.text(base + 4 * n_sets, "colour rendering group")?
            .to_string(),
    ));
    let watts = l.number(base + 5 * n_sets, "wattage including ballast")?;
    if watts < 0.0 {
        return Err(err(
            base + 5 * n_sets,
            format!("wattage must not be negative, found {watts} W"),
        ));
    }
    // The other lamp sets must still be well-formed lines.
    l.text(base + 6 * n_sets - 1, "lamp set data")?;

    let (symmetry, mc1, n_planes) = match isym {
        0 => (Symmetry::None, 1, mc),
        1 => (Symmetry::Rotational, 1, 1),
        2 if mc % 2 == 0 => (Symmetry::Bilateral0To180, 1, mc / 2 + 1),
        3 if mc % 4 == 0 => (Symmetry::Bilateral90To270, 3 * mc / 4 + 1, mc / 2 + 1),
        4 if mc % 4 == 0 => (Symmetry::Quadrant, 1, mc / 4 + 1),
        _ => {
            return Err(err(
                4,
                format!(
                    "Mc = {mc} C planes cannot hold symmetry Isym = {isym} (Mc must divide by {})",
                    if isym == 2 { 2 } else { 4 }
                ),
            ))
        }
    };
    // From the direct ratios on: a number stream.
    let first_stream = base + 6 * n_sets; // 1-based line of the first direct ratio
    let mut owned: Vec<(String, usize)> = Vec::new();
    for (i, line) in l.lines.iter().enumerate().skip(first_stream - 1) {
        for t in line.split_whitespace() {
            owned.push((decimal_comma(t).into_owned(), i + 1));
        }
    }
    let mut ts = Tokens {
        name,
        toks: owned
            .iter()
            .map(|(t, n)| Tok {
                text: t.as_str(),
                line: *n,
            })
            .collect(),
        pos: 0,
        last_line: l.lines.len(),
    };
    ts.numbers(10, "direct ratios")?;
    let (c_all, c_lines, ()) = ts.angles(mc, "C", 360.0, |first, last| {
        if first == 0.0 && last < 360.0 {
            Ok(())
        } else {
            Err(format!(
                "C angles must start at 0 and stay below 360, found {first} to {last}"
            ))
        }
    })?;
    // As for IES type C files: a table from 10° left straight down at 0 cd without a word.
    // (Its end is not checked: older files may stop short of 90 or 180.)
    let (gamma, _, ()) = ts.angles(ng, "gamma", 180.0, |first, _| {
        if first == 0.0 || first == 90.0 {
            Ok(())
        } else {
            Err(format!(
                "gamma angles must start at 0 or 90, found {first} (the table would leave the \
                 directions below it dark)"
            ))
        }
    })?;

    // The stored planes' angles, with Isym 3's 270..360..90 unwrapped to -90..90.
    let mut c_given = Vec::with_capacity(n_planes);
    for k in 0..n_planes {
        let idx = (mc1 - 1 + k) % mc;
        let mut a = c_all[idx];
        if isym == 3 && a >= 180.0 {
            a -= 360.0;
        }
        c_given.push(a);
    }
    let expected_end = match isym {
        2 => Some(180.0),
        3 => Some(90.0),
        4 => Some(90.0),
        _ => None,
    };
    if let Some(end) = expected_end {
        let (a, b) = (c_given[0], c_given[n_planes - 1]);
        let start = if isym == 3 { -90.0 } else { 0.0 };
        if (a - start).abs() > 1e-6 || (b - end).abs() > 1e-6 {
            return Err(ts.err(
                Some(c_lines[0]),
                format!(
                    "symmetry Isym = {isym} needs the stored C planes to span {} to {end}, but the C angles give {} to {}",
                    if isym == 3 { 270.0 } else { 0.0 },
                    if a < 0.0 { a + 360.0 } else { a },
                    b
                ),
            ));
        }
    }
    let factor = flux / 1000.0 * conversion;
    let rows = ts.intensity_table(
        &c_given,
        &gamma,
        factor,
        IntensityNames {
            values: "intensities",
            value: "luminous intensity",
            unit: " cd/klm",
            shape: format!("{n_planes} C planes x {ng} gamma angles"),
            mismatch: "Mc, Ng or Isym do not match the table",
        },
        |c, g| format!("C {}, gamma {g}", if c < 0.0 { c + 360.0 } else { c }),
    )?;

    let lamp_flux = if lamps < 0.0 {
        LampFlux::Absolute {
            luminaire_lm: Some(flux),
        }
    } else {
        LampFlux::Relative {
            lamps: lamps as u32,
            total_lm: flux,
        }
    };
    let shape = match (mm[3] > 0.0, mm[4] > 0.0) {
        (false, _) => OpeningShape::Point,
        (true, false) => OpeningShape::Circular,
        (true, true) => OpeningShape::Rectangular,
    };
    let height = mm[5..9].iter().copied().fold(0.0, f64::max) / 1000.0;
    let opening = LuminousOpening {
        shape,
        length_m: mm[3] / 1000.0,
        width_m: if mm[4] > 0.0 {
            mm[4] / 1000.0
        } else {
            mm[3] / 1000.0
        },
        height_m: height,
    };
    let table = RawTable {
        symmetry,
        c_deg: c_given,
        gamma_deg: gamma,
        rows,
    };
    // Installed power: the lamp sets' wattage when given.
    let input_watts = (watts > 0.0).then_some(watts);
    let mut p = Photometry::from_parts(
        name,
        SourceFormat::Eulumdat,
        keywords,
        lamp_flux,
        opening,
        input_watts,
        factor,
        table,
    )
    .map_err(|m| ts.err(Some(c_lines[0]), m))?;
    p.ldt_lor_percent = Some(lorl);
    p.ldt_dff_percent = Some(dff);
    Ok(p)
}

/// Reads and parses a EULUMDAT file.
pub fn read_ldt(path: &std::path::Path) -> Result<Photometry, PhotometryError> {
    let text = crate::read_text(path)?;
    parse_ldt_str(&path.display().to_string(), &text)
}
