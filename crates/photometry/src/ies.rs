//! IES LM-63 photometric files (ANSI/IES LM-63-1986, -1991, -1995, -2002, -2019).
//!
//! Layout: a version line (`IESNA:LM-63-1995`, `IESNA:LM-63-2002`, `IES:LM-63-2019`, `IESNA91`;
//! absent in 1986 files, whose lines before `TILT=` are free text), keyword lines `[KEY] value`
//! (`[MORE]` continues the previous one), the `TILT=` line, then whitespace- (or comma-)
//! separated numbers, which may wrap across lines freely:
//!
//! ```text
//! #lamps  lumens/lamp  multiplier  #vertical  #horizontal  type  units  width  length  height
//! ballast-factor  future-use  input-watts
//! vertical angles (#vertical)    horizontal angles (#horizontal)
//! candela: #vertical values for each horizontal angle in turn
//! ```
//!
//! Supported: `TILT=NONE` (tilt tables, `TILT=INCLUDE` or a tilt file, are rejected: they only
//! matter for lamps whose output changes with burning position); photometric type C only
//! (type A and B give an "unsupported" error); units 1 = feet (× 0.3048 m), 2 = metres; vertical
//! angles from 0 or 90 to 90 or 180; horizontal angles 0 (rotational), 0–90 (quadrant), 0–180
//! (bilateral), 0–>180…360 (none), 90–270 (bilateral about the 90–270 plane, LM-63-2002 §5.11).
//!
//! Candela (cd) = file value × candela multiplier × ballast factor, and for 1986/1991 files also
//! × the ballast-lamp photometric factor (the field 1995 and 2002 call "future use" and 2019 the
//! "file generation type", which are not multipliers). Lumens per lamp = −1 means absolute
//! photometry (LM-63-2002 §5.4).

use crate::error::{show, PhotometryError};
use crate::photometry::{
    check_angles, LampFlux, LuminousOpening, Photometry, RawTable, SourceFormat, Symmetry,
};

/// Limits that keep a malformed count from allocating gigabytes (real files: ≤ 361 × 721).
const MAX_ANGLES: usize = 100_000;

/// A number token with the 1-based line it was found on.
pub(crate) struct Tok<'a> {
    pub text: &'a str,
    pub line: usize,
}

/// How a file format names its intensity table in error messages.
pub(crate) struct IntensityNames {
    /// The values, plural ("candela values"), and one of them ("candela value").
    pub values: &'static str,
    pub value: &'static str,
    /// The unit written after a value (with its leading space), or "".
    pub unit: &'static str,
    /// The table's expected shape from the header's counts.
    pub shape: String,
    /// What a surplus value means.
    pub mismatch: &'static str,
}

/// A cursor over number tokens, producing one-line errors with file and line.
pub(crate) struct Tokens<'a> {
    pub name: &'a str,
    pub toks: Vec<Tok<'a>>,
    pub pos: usize,
    /// Line reported when the file ends early (its last line).
    pub last_line: usize,
}

impl<'a> Tokens<'a> {
    pub fn err(&self, line: Option<usize>, msg: impl Into<String>) -> PhotometryError {
        PhotometryError::new(self.name, line, msg)
    }
    pub fn remaining(&self) -> usize {
        self.toks.len() - self.pos
    }
    /// The next number, finite; `what` names the field for the error message.
    pub fn number(&mut self, what: &str) -> Result<(f64, usize), PhotometryError> {
        let Some(t) = self.toks.get(self.pos) else {
            return Err(self.err(
                Some(self.last_line),
                format!("truncated file: expected {what}, found the end of the file"),
            ));
        };
        self.pos += 1;
        let v = parse_number(t.text)
            .map_err(|m| PhotometryError::new(self.name, Some(t.line), format!("{what}: {m}")))?;
        Ok((v, t.line))
    }
    /// The next number, which must be an integer in [lo, hi].
    pub fn integer(
        &mut self,
        what: &str,
        lo: i64,
        hi: i64,
    ) -> Result<(i64, usize), PhotometryError> {
        let (v, line) = self.number(what)?;
        if v.fract() != 0.0 || v < lo as f64 || v > hi as f64 {
            return Err(self.err(
                Some(line),
                format!("{what} must be an integer from {lo} to {hi}, found {v}"),
            ));
        }
        Ok((v as i64, line))
    }
    /// `n` numbers; checks first that the file has that many left (a truncated-file error
    /// otherwise) so a wrong count never allocates more than the file holds.
    pub fn numbers(&mut self, n: usize, what: &str) -> Result<Vec<(f64, usize)>, PhotometryError> {
        if self.remaining() < n {
            return Err(self.err(
                Some(self.last_line),
                format!(
                    "truncated file: expected {n} {what}, the file has only {} values left",
                    self.remaining()
                ),
            ));
        }
        (0..n).map(|_| self.number(what)).collect()
    }
    /// The intensity table that follows the angles and ends the file: one row per plane of
    /// `planes`, one value per angle of `gamma`, each non-negative (`at` names a value's
    /// angles in the error) and scaled by `factor`; nothing may follow it.
    pub fn intensity_table(
        &mut self,
        planes: &[f64],
        gamma: &[f64],
        factor: f64,
        names: IntensityNames,
        at: impl Fn(f64, f64) -> String,
    ) -> Result<Vec<Vec<f64>>, PhotometryError> {
        let need = planes.len() * gamma.len();
        if self.remaining() < need {
            return Err(self.err(
                Some(self.last_line),
                format!(
                    "truncated file: expected {need} {} ({}), found {}",
                    names.values,
                    names.shape,
                    self.remaining()
                ),
            ));
        }
        let mut rows = Vec::with_capacity(planes.len());
        for &c in planes {
            let mut row = Vec::with_capacity(gamma.len());
            for &g in gamma {
                let (v, line) = self.number(names.value)?;
                if v < 0.0 {
                    let m = format!("negative {} {v}{} ({})", names.value, names.unit, at(c, g));
                    return Err(self.err(Some(line), m));
                }
                row.push(v * factor);
            }
            rows.push(row);
        }
        if let Some(t) = self.toks.get(self.pos) {
            return Err(self.err(
                Some(t.line),
                format!(
                    "unexpected value '{}' after the {need} {}: {}",
                    show(t.text),
                    names.values,
                    names.mismatch
                ),
            ));
        }
        Ok(rows)
    }
    /// `n` angles in degrees (`what` angles), increasing within [0, `hi`], and what `ends` makes
    /// of the first and last (its message is reported at the first angle's line); with the
    /// angles' line numbers.
    pub fn angles<T>(
        &mut self,
        n: usize,
        what: &str,
        hi: f64,
        ends: impl FnOnce(f64, f64) -> Result<T, String>,
    ) -> Result<(Vec<f64>, Vec<usize>, T), PhotometryError> {
        let toks = self.numbers(n, &format!("{what} angles"))?;
        let a: Vec<f64> = toks.iter().map(|t| t.0).collect();
        check_angles(&a, 0.0, hi, what).map_err(|(k, m)| self.err(Some(toks[k].1), m))?;
        let (first, last) = (toks.first(), toks.last());
        let ends = ends(first.map_or(0.0, |t| t.0), last.map_or(0.0, |t| t.0))
            .map_err(|m| self.err(first.map(|t| t.1), m))?;
        Ok((a, toks.iter().map(|t| t.1).collect(), ends))
    }
}

/// Parses a decimal number as photometric files write it; errors for junk and non-finite values.
pub(crate) fn parse_number(s: &str) -> Result<f64, String> {
    // Rust accepts "inf"/"NaN"; the standards do not. Only digits, signs, '.', 'e'/'E' pass.
    if s.is_empty()
        || !s
            .bytes()
            .all(|b| b.is_ascii_digit() || matches!(b, b'+' | b'-' | b'.' | b'e' | b'E'))
    {
        return Err(format!("expected a number, found '{}'", show(s)));
    }
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("non-finite number '{}'", show(s))),
        Err(_) => Err(format!("expected a number, found '{}'", show(s))),
    }
}

/// Parses an IES LM-63 file from text; `name` is used in error messages. Never panics.
pub fn parse_ies_str(name: &str, text: &str) -> Result<Photometry, PhotometryError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let unified = crate::unify_line_ends(text);
    let text = unified.as_ref();
    let lines: Vec<&str> = text.lines().collect();
    let err = |line: Option<usize>, m: String| PhotometryError::new(name, line, m);
    if lines.iter().all(|l| l.trim().is_empty()) {
        return Err(err(None, "empty file: not an IES LM-63 file".into()));
    }
    // The version line, read without its spaces and colons: files in the wild write
    // `IESNA: LM-63-2002`, `IESNA LM-63-2002` (which was read as a 1986 file, whose line 2 then
    // set the candela multiplier: 1.5 times the intensities) or `IESNA:LM-63-1991`.
    let first: String = lines[0]
        .trim()
        .to_ascii_uppercase()
        .chars()
        .filter(|c| !c.is_whitespace() && *c != ':')
        .collect();
    let version = first
        .strip_prefix("IESNALM-63-")
        .or_else(|| first.strip_prefix("IESLM-63-"));
    let (format, mut k) = match version {
        Some(v) if v.starts_with("1995") => (SourceFormat::Ies1995, 1),
        Some(v) if v.starts_with("2002") => (SourceFormat::Ies2002, 1),
        Some(v) if v.starts_with("2019") => (SourceFormat::Ies2019, 1),
        Some(v) if v.starts_with("1991") => (SourceFormat::Ies1991, 1),
        // LM-63-1986 has no version line: such a first line is the free text it begins with.
        Some(v) if v.starts_with("1986") => (SourceFormat::Ies1986, 0),
        Some(_) => {
            return Err(err(
                Some(1),
                format!("unknown LM-63 version line '{}'", show(lines[0].trim())),
            ))
        }
        None if first.starts_with("IESNA91") => (SourceFormat::Ies1991, 1),
        None if ["IESNA:", "IES:"]
            .iter()
            .any(|p| lines[0].trim().to_ascii_uppercase().starts_with(p)) =>
        {
            return Err(err(
                Some(1),
                format!("unknown LM-63 version line '{}'", show(lines[0].trim())),
            ))
        }
        None => (SourceFormat::Ies1986, 0),
    };

    // Keywords (or 1986 free text) up to the TILT line.
    let mut keywords: Vec<(String, String)> = Vec::new();
    let tilt_line = loop {
        let Some(line) = lines.get(k) else {
            return Err(err(
                Some(lines.len()),
                "missing TILT= line (LM-63 requires TILT=NONE before the photometric data)".into(),
            ));
        };
        let t = line.trim();
        if t.len() >= 4 && t.is_char_boundary(4) && t[..4].eq_ignore_ascii_case("TILT") {
            let rest = t[4..].trim_start();
            if let Some(v) = rest.strip_prefix('=') {
                break (k, v.trim());
            }
        }
        if let Some(body) = t.strip_prefix('[') {
            if let Some((key, value)) = body.split_once(']') {
                let (key, value) = (key.trim().to_string(), value.trim().to_string());
                if key.eq_ignore_ascii_case("MORE") {
                    if let Some(last) = keywords.last_mut() {
                        last.1.push(' ');
                        last.1.push_str(&value);
                    }
                } else {
                    keywords.push((key, value));
                }
            }
        }
        k += 1;
    };
    let (tilt_idx, tilt) = tilt_line;
    if !tilt.eq_ignore_ascii_case("NONE") {
        let what = if tilt.eq_ignore_ascii_case("INCLUDE") {
            "TILT=INCLUDE (a lamp tilt table) is not supported; only TILT=NONE".to_string()
        } else {
            format!(
                "TILT={} (an external tilt file) is not supported; only TILT=NONE",
                show(tilt)
            )
        };
        return Err(err(Some(tilt_idx + 1), what));
    }

    let mut toks = Vec::new();
    for (i, line) in lines.iter().enumerate().skip(tilt_idx + 1) {
        for t in line.split(|c: char| c.is_whitespace() || c == ',') {
            if !t.is_empty() {
                toks.push(Tok {
                    text: t,
                    line: i + 1,
                });
            }
        }
    }
    let mut ts = Tokens {
        name,
        toks,
        pos: 0,
        last_line: lines.len(),
    };

    let (n_lamps, _) = ts.integer("number of lamps", 1, 1_000_000)?;
    let (lumens, lumens_line) = ts.number("lumens per lamp")?;
    if !(lumens > 0.0 || lumens == -1.0) {
        return Err(ts.err(
            Some(lumens_line),
            format!(
                "lumens per lamp must be positive, or -1 for absolute photometry; found {lumens}"
            ),
        ));
    }
    let (multiplier, ml) = ts.number("candela multiplier")?;
    if multiplier <= 0.0 {
        return Err(ts.err(
            Some(ml),
            format!("candela multiplier must be positive, found {multiplier}"),
        ));
    }
    let (n_vert, _) = ts.integer("number of vertical angles", 2, MAX_ANGLES as i64)?;
    let (n_horiz, _) = ts.integer("number of horizontal angles", 1, MAX_ANGLES as i64)?;
    let (ptype, pl) = ts.integer("photometric type", 1, 3)?;
    if ptype != 1 {
        let t = if ptype == 2 { "B" } else { "A" };
        return Err(ts.err(
            Some(pl),
            format!("photometric type {t} ({ptype}) is not supported; only type C (1)"),
        ));
    }
    let (units, _) = ts.integer("units type (1 = feet, 2 = metres)", 1, 2)?;
    let to_m = if units == 1 { 0.3048 } else { 1.0 };
    let (width, _) = ts.number("luminous opening width")?;
    let (length, _) = ts.number("luminous opening length")?;
    let (height, _) = ts.number("luminous opening height")?;
    let (ballast, bl) = ts.number("ballast factor")?;
    if ballast <= 0.0 {
        return Err(ts.err(
            Some(bl),
            format!("ballast factor must be positive, found {ballast}"),
        ));
    }
    let (future, fl) = ts.number("ballast-lamp factor / future use / file generation type")?;
    let lamp_factor = match format {
        SourceFormat::Ies1986 | SourceFormat::Ies1991 => {
            if future <= 0.0 {
                return Err(ts.err(
                    Some(fl),
                    format!("ballast-lamp photometric factor must be positive, found {future}"),
                ));
            }
            future
        }
        _ => 1.0,
    };
    let (watts, wl) = ts.number("input watts")?;
    if watts < 0.0 {
        return Err(ts.err(
            Some(wl),
            format!("input watts must not be negative, found {watts}"),
        ));
    }

    let (n_vert, n_horiz) = (n_vert as usize, n_horiz as usize);
    let (gamma, _, ()) = ts.angles(n_vert, "vertical", 180.0, |first, last| {
        if (first == 0.0 || first == 90.0) && (last == 90.0 || last == 180.0) {
            Ok(())
        } else {
            Err(format!(
                "type C vertical angles must run from 0 or 90 to 90 or 180, found {first} to {last}"
            ))
        }
    })?;
    let (c, c_lines, symmetry) = ts.angles(n_horiz, "horizontal", 360.0, |c0, c_last| {
        Ok(if n_horiz == 1 && c0 == 0.0 {
            Symmetry::Rotational
        } else if c0 == 0.0 && c_last == 90.0 {
            Symmetry::Quadrant
        } else if c0 == 0.0 && c_last == 180.0 {
            Symmetry::Bilateral0To180
        } else if c0 == 0.0 && c_last > 180.0 {
            Symmetry::None
        } else if c0 == 90.0 && c_last == 270.0 {
            Symmetry::Bilateral90To270
        } else {
            return Err(format!(
                "horizontal angles {c0} to {c_last}: type C files must give 0 (rotational), 0-90, 0-180, 0-360 or 90-270"
            ));
        })
    })?;
    let factor = multiplier * ballast * lamp_factor;
    let rows = ts.intensity_table(
        &c,
        &gamma,
        factor,
        IntensityNames {
            values: "candela values",
            value: "candela value",
            unit: "",
            shape: format!("{n_horiz} horizontal x {n_vert} vertical angles"),
            mismatch: "the angle counts do not match the table",
        },
        |hc, g| format!("horizontal angle {hc}, vertical angle {g}"),
    )?;
    if symmetry == Symmetry::None && c[n_horiz - 1] == 360.0 {
        // LM-63: the 360° plane repeats the 0° plane.
        let (a, b) = (&rows[0], &rows[n_horiz - 1]);
        if let Some(j) = (0..n_vert)
            .find(|&j| (a[j] - b[j]).abs() > 1e-6 * a[j].abs().max(b[j].abs()).max(1e-12))
        {
            return Err(ts.err(
                Some(c_lines[n_horiz - 1]),
                format!(
                    "the 360° plane must repeat the 0° plane, but at vertical angle {} they differ ({} vs {} cd)",
                    gamma[j],
                    a[j] / factor,
                    b[j] / factor
                ),
            ));
        }
    }

    let lamp_flux = if lumens == -1.0 {
        LampFlux::Absolute { luminaire_lm: None }
    } else {
        LampFlux::Relative {
            lamps: n_lamps as u32,
            total_lm: lumens * n_lamps as f64,
        }
    };
    let opening = LuminousOpening::from_ies(width * to_m, length * to_m, height * to_m);
    let table = RawTable {
        symmetry,
        c_deg: c,
        gamma_deg: gamma,
        rows,
    };
    Photometry::from_parts(
        name,
        format,
        keywords,
        lamp_flux,
        opening,
        (watts > 0.0).then_some(watts),
        factor,
        table,
    )
    .map_err(|m| ts.err(Some(c_lines[0]), m))
}

/// Reads and parses an IES file.
pub fn read_ies(path: &std::path::Path) -> Result<Photometry, PhotometryError> {
    let text = crate::read_text(path)?;
    parse_ies_str(&path.display().to_string(), &text)
}
