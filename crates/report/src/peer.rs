//! A peer program's illuminances at the same grid points (e.g. Radiance's `rtrace -I`, written
//! by `pipelines/radiance_office.py`), and the point-by-point comparison the report shows.
//!
//! **File.** CSV with `# key: value` comment lines first (`program`, `settings`, `cpu_seconds`,
//! free-form `note`s), then the header `set,index,x,y,z,illuminance_lx,standard_error_lx` and
//! one row per point (the peer's own standard error, e.g. from runs with different seeds).
//!
//! **Check.** A point agrees when |E − E_peer| ≤ 1 % · |E_peer| + 3 σ with σ² = SE² + SE_peer²:
//! the two programs may differ by a 1 % modelling tolerance (interpolation of the intensity
//! table, the peer's own approximations) plus the combined Monte Carlo noise at 3 σ.

use crate::surface::Surface;
use luxest_io::{Error, Result};
use std::path::Path;

/// The CSV header line of a peer file.
pub const PEER_HEADER: &str = "set,index,x,y,z,illuminance_lx,standard_error_lx";

/// Relative modelling tolerance of the check.
pub const REL_TOLERANCE: f64 = 0.01;
/// Combined standard errors allowed on top of it.
pub const SIGMAS: f64 = 3.0;

/// One peer point.
#[derive(Clone, Debug, PartialEq)]
pub struct PeerPoint {
    pub set: String,
    /// The point's line in the file (1-based), for messages.
    pub line: usize,
    pub index: usize,
    pub position: [f64; 3],
    pub value: f64,
    pub std_error: f64,
}

/// A peer's results.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct PeerResults {
    /// `# key: value` lines in file order.
    pub meta: Vec<(String, String)>,
    pub points: Vec<PeerPoint>,
}

impl PeerResults {
    pub fn meta(&self, key: &str) -> Option<&str> {
        self.meta
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

/// Reads a peer file.
pub fn read(path: &Path) -> Result<PeerResults> {
    parse(path, &luxest_io::fsio::read_bytes(path)?)
}

/// [`read`] of the file's content `bytes`; `path` names it in errors.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<PeerResults> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| Error::input(path, format!("not UTF-8 text: {e}")))?;
    let mut out = PeerResults::default();
    let mut header_seen = false;
    for (n, line) in text.lines().enumerate() {
        let place = || format!("line {}", n + 1);
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if let Some(c) = line.strip_prefix('#') {
            if let Some((k, v)) = c.split_once(':') {
                out.meta.push((k.trim().to_string(), v.trim().to_string()));
            }
            continue;
        }
        if !header_seen {
            if line != PEER_HEADER {
                return Err(Error::at(
                    path,
                    place(),
                    format!("expected the header {PEER_HEADER}"),
                ));
            }
            header_seen = true;
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != 7 {
            return Err(Error::at(
                path,
                place(),
                format!("{} fields, expected 7", f.len()),
            ));
        }
        let real = |s: &str| {
            s.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| Error::at(path, place(), format!("not a finite number: {s:?}")))
        };
        out.points.push(PeerPoint {
            set: f[0].to_string(),
            line: n + 1,
            index: f[1]
                .parse()
                .map_err(|_| Error::at(path, place(), format!("not a point index: {:?}", f[1])))?,
            position: [real(f[2])?, real(f[3])?, real(f[4])?],
            value: real(f[5])?,
            std_error: real(f[6])?.abs(),
        });
    }
    if !header_seen {
        return Err(Error::input(path, format!("no header line {PEER_HEADER}")));
    }
    Ok(out)
}

/// One point of the comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct PointComparison {
    pub index: usize,
    pub luxest: f64,
    pub luxest_se: f64,
    pub peer: f64,
    pub peer_se: f64,
    /// (E − E_peer) / E_peer.
    pub rel_diff: f64,
    /// (E − E_peer) / σ_combined (0 when σ is 0).
    pub z: f64,
    /// |E − E_peer| ≤ 1 % · |E_peer| + 3 σ.
    pub agrees: bool,
}

/// The comparison of one surface.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceComparison {
    pub surface: String,
    pub points: Vec<PointComparison>,
}

impl SurfaceComparison {
    pub fn all_agree(&self) -> bool {
        self.points.iter().all(|p| p.agrees)
    }
    pub fn max_abs_rel_diff(&self) -> f64 {
        self.points
            .iter()
            .map(|p| p.rel_diff.abs())
            .fold(0.0, f64::max)
    }
    pub fn mean_rel_diff(&self) -> f64 {
        self.points.iter().map(|p| p.rel_diff).sum::<f64>() / self.points.len().max(1) as f64
    }
}

/// Refuses a peer file with a point of a set that is none of `surfaces` (a misspelt or another
/// scene's set would be left out of the comparison without a word), naming its line and the
/// surfaces of `results`; a file of points of these surfaces only passes.
pub fn check_sets(
    path: &Path,
    peer: &PeerResults,
    surfaces: &[&str],
    results: &Path,
) -> Result<()> {
    match peer
        .points
        .iter()
        .find(|p| !surfaces.contains(&p.set.as_str()))
    {
        None => Ok(()),
        Some(p) => Err(Error::at(
            path,
            format!("line {}", p.line),
            format!(
                "set \"{}\" is no surface of {} (its surfaces: {})",
                p.set,
                results.display(),
                surfaces.join(", ")
            ),
        )),
    }
}

/// Compares a surface with the peer's points of the same set (matched by index; positions must
/// agree to 1 mm). `None` when the peer has no point of this surface.
pub fn compare(
    path: &Path,
    surface: &Surface,
    peer: &PeerResults,
) -> Result<Option<SurfaceComparison>> {
    let mine: Vec<&PeerPoint> = peer
        .points
        .iter()
        .filter(|p| p.set == surface.name)
        .collect();
    if mine.is_empty() {
        return Ok(None);
    }
    let n = surface.values.len();
    if mine.len() != n {
        return Err(Error::at(
            path,
            format!("set \"{}\"", surface.name),
            format!("{} peer points for a surface of {n}", mine.len()),
        ));
    }
    let mut points = Vec::with_capacity(n);
    for p in mine {
        let k = p.index;
        if k >= n {
            return Err(Error::at(
                path,
                format!("set \"{}\", point {k}", surface.name),
                format!("no such point (the surface has {n})"),
            ));
        }
        let q = surface.positions[k];
        let d = (0..3)
            .map(|a| (q[a] - p.position[a]).abs())
            .fold(0.0, f64::max);
        if d > 1e-3 {
            return Err(Error::at(
                path,
                format!("set \"{}\", point {k}", surface.name),
                format!(
                    "position ({}, {}, {}) differs from luxest's ({}, {}, {}) by {d} m",
                    p.position[0], p.position[1], p.position[2], q[0], q[1], q[2]
                ),
            ));
        }
        let (e, s) = (surface.values[k], surface.std_errors[k]);
        let sigma = (s * s + p.std_error * p.std_error).sqrt();
        let diff = e - p.value;
        points.push(PointComparison {
            index: k,
            luxest: e,
            luxest_se: s,
            peer: p.value,
            peer_se: p.std_error,
            rel_diff: if p.value != 0.0 { diff / p.value } else { 0.0 },
            z: if sigma > 0.0 { diff / sigma } else { 0.0 },
            agrees: diff.abs() <= REL_TOLERANCE * p.value.abs() + SIGMAS * sigma,
        });
    }
    points.sort_by_key(|p| p.index);
    if points.windows(2).any(|w| w[0].index == w[1].index) {
        return Err(Error::at(
            path,
            format!("set \"{}\"", surface.name),
            "a point index appears twice",
        ));
    }
    Ok(Some(SurfaceComparison {
        surface: surface.name.clone(),
        points,
    }))
}
