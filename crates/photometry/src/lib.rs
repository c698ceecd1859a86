//! Luminaire photometry for luxest: what a lighting engineer brings (a manufacturer's photometric
//! file) and what they sign (work-plane figures and an isolux plot).
//!
//! - [`ies`] and [`ldt`] parse IES LM-63 (1986/1991, 1995, 2002, 2019) and EULUMDAT files into one
//!   [`Photometry`]: a goniometric intensity table in candela over the full C-γ sphere, bilinearly
//!   interpolated as both standards prescribe.
//! - [`frame`] fixes the C-γ coordinate convention, maps directions to (C, γ) and back, and orients
//!   a luminaire in the world ([`Orientation`], [`Frame`], [`Luminaire`]).
//! - [`sampling`] draws emission directions proportional to the tabulated intensity.
//! - [`illuminance`] holds the point-to-point kernels: planar, cylindrical and semi-cylindrical
//!   illuminance, and the direct illuminance from a luminaire treated as a point (far field).
//! - [`grid`] lays out calculation grids (EN 12464-1 rule) and computes Eavg, Emin, Emax, U0, Ud
//!   with Monte Carlo uncertainties propagated from the per-point estimates.
//! - [`isolux`] renders a false-colour isolux PNG with contours, legend and outline;
//!   [`falsecolour`] a luminance image on a logarithmic false-colour scale with its cd/m² bar.
//! - [`ugr`] computes the unified glare rating (CIE 117): Guth's position index, a luminaire's
//!   luminance and solid angle seen from an eye, UGR with its standard error; [`ugr_table`] the
//!   tabular UGR of a luminaire (CIE 190).
//! - [`photometry`] holds the distribution both parsers produce, [`error`] the crate's one error
//!   type.
//!
//! Units: metres, degrees in files and in the (C, γ) API, radians nowhere in the public API except
//! solid angles (steradians), candela, lumen, lux. All accumulation is in f64.
//!
//! Parsers never panic: any input, including random bytes, yields either a [`Photometry`] or a
//! one-line [`PhotometryError`] naming the file and, where known, the line.
//!
//! ```
//! use luxest_photometry::{load, CalcGrid, GridSpec, GridStats, IntensitySampler, Luminaire, Orientation};
//! use std::{path::Path, sync::Arc};
//!
//! let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/photometry");
//! let troffer = Arc::new(load(&dir.join("troffer-600-led.ies")).unwrap());
//! assert!((troffer.flux_from_table_lm() - 3600.0).abs() < 1e-3); // lm, the luminaire's output
//!
//! // A luminaire 3 m up, aimed straight down, rotated 90° about its vertical axis.
//! let frame = Orientation { rotation_deg: 90.0, ..Default::default() }.frame().unwrap();
//! let lum = Luminaire { photometry: troffer.clone(), position: [3.0, 2.0, 3.0], frame, multiplier: 0.8 };
//!
//! // EN 12464-1 work plane: 0.75 m high, 0.5 m margin, standard spacing (9 x 5 points here).
//! let grid = CalcGrid::new(GridSpec::work_plane(0.0, 0.0, 6.0, 4.0, 0.75, 0.5)).unwrap();
//! let e: Vec<f64> = grid.points().iter().map(|&p| lum.direct_illuminance_lx(p, grid.normal)).collect();
//! let stats = GridStats::from_independent(&e, &vec![0.0; e.len()]).unwrap();
//! assert_eq!(stats.n_points, 45);
//!
//! // Emission sampling in the luminaire frame; world direction = frame.to_world(dir).
//! let sampler = IntensitySampler::new(&troffer).unwrap();
//! let s = sampler.sample(0.3, 0.7);
//! let weight_lm = s.intensity_cd / s.pdf_sr; // E[weight] = sampler.total_lm()
//! assert!(weight_lm > 0.0 && lum.frame.to_world(s.dir)[2] < 0.0);
//! ```

pub mod error;
pub mod falsecolour;
pub mod frame;
pub mod grid;
pub mod ies;
pub mod illuminance;
pub mod isolux;
pub mod ldt;
pub mod photometry;
pub mod sampling;
pub mod ugr;
pub mod ugr_table;

pub use error::PhotometryError;
pub use frame::{c_gamma_from_direction, direction_from_c_gamma, Frame, Luminaire, Orientation};
pub use grid::{CalcGrid, Estimate, GridError, GridSpec, GridStats, Spacing};
pub use illuminance::{direct_illuminance_lx, direct_sensor_illuminance_lx, SensorKind};
pub use isolux::{render_isolux, IsoluxOptions, SrgbRaster};
pub use photometry::{
    FluxCheck, LampFlux, LuminousOpening, OpeningShape, Photometry, SourceFormat, Symmetry,
};
pub use sampling::{IntensitySample, IntensitySampler};
pub use ugr::{GlareLuminaire, GlareTerm, SolidAngle, Ugr};
pub use ugr_table::{ugr_table, UgrTable};

use std::path::Path;

/// Reads a photometric file, choosing the parser by extension: `.ies` (IES LM-63) or `.ldt`
/// (EULUMDAT), case-insensitive. The bytes are decoded as UTF-8 where valid and otherwise
/// byte-for-byte as Latin-1 (manufacturers' files often carry Latin-1 `°` or `µ`).
pub fn load(path: &Path) -> Result<Photometry, PhotometryError> {
    let name = path.display().to_string();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let text = read_text(path)?;
    match ext.as_deref() {
        Some("ies") => ies::parse_ies_str(&name, &text),
        Some("ldt") => ldt::parse_ldt_str(&name, &text),
        _ => Err(PhotometryError::new(
            &name,
            None,
            "unknown photometric file type: expected extension .ies (IES LM-63) or .ldt (EULUMDAT)",
        )),
    }
}

/// Reads a file as text (see [`text_of`]).
pub(crate) fn read_text(path: &Path) -> Result<String, PhotometryError> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path)
        .map_err(|e| PhotometryError::new(&name, None, format!("cannot read: {e}")))?;
    text_of(&name, bytes)
}

/// A photometric file's bytes as text: UTF-8 when valid, else Latin-1 (older files are). A
/// file with a control character other than tabs, line and page ends (and a trailing DOS end
/// mark, ^Z) is not text: a binary file (an image, a compiled scene given by mistake) is named
/// as such with the first such byte, rather than as an IES file "missing TILT=".
pub fn text_of(name: &str, bytes: Vec<u8>) -> Result<String, PhotometryError> {
    let body = bytes.strip_suffix(b"\x1a").unwrap_or(&bytes);
    if let Some(at) = body
        .iter()
        .position(|&b| (b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r' | 0x0b | 0x0c)) || b == 0x7f)
    {
        let line = 1 + body[..at].iter().filter(|&&b| b == b'\n').count();
        return Err(PhotometryError::new(
            name,
            Some(line),
            format!(
                "not a text file: byte {at} is 0x{:02x}, a control character (a binary file? \
                 photometric files are text)",
                body[at]
            ),
        ));
    }
    Ok(match String::from_utf8(bytes) {
        Ok(s) => s,
        Err(e) => e.into_bytes().iter().map(|&b| b as char).collect(),
    })
}

/// `text` with its lines split by `\n`: a file from classic Mac OS ends lines with CR alone,
/// which `str::lines` does not split (an IES file was "missing TILT=" on line 1, an EULUMDAT
/// file "truncated" at 1 line). Only a file without any LF is converted: CRLF files, and
/// CR CR LF ones (a CRLF file through text-mode FTP), whose trailing CRs each line's trim
/// removes, keep their lines and line numbers.
pub(crate) fn unify_line_ends(text: &str) -> std::borrow::Cow<'_, str> {
    if text.contains('\r') && !text.contains('\n') {
        std::borrow::Cow::Owned(text.replace('\r', "\n"))
    } else {
        std::borrow::Cow::Borrowed(text)
    }
}
