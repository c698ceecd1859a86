//! The file names the stages exchange, composed and parsed in one place.
//!
//! Images follow the Intel Open Image Denoise training-toolkit layout, one 3-channel feature per
//! file:
//!
//! ```text
//! <name>_<spp, 6 digits>spp.<kind>.exr   a camera estimate at spp samples per pixel (path tracing)
//! <name>_ref.<kind>.exr                  the same at reference quality
//! <name>_<paths, 6 digits>le.<kind>.exr  a local-estimate image from `paths` light paths (double
//!                                        local estimate or light tracing: `luxest.estimator`)
//! ```
//!
//! `<kind>` is one of [`Kind`]; a PNG preview replaces the final `.exr` by `.png`. Sensor results
//! are `<name>.sensors.ron` (and `.csv`). The Python side reads and writes the same names;
//! `tests/fixtures/contract/naming.json`, written from this module, ties the two together.

use std::fmt;
use std::path::{Path, PathBuf};

/// What one image file holds: the `<kind>` in `<name>_<level>.<kind>.exr`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// Linear radiance (or luminance) RGB.
    Hdr,
    /// First-hit albedo.
    Alb,
    /// First-hit shading normal, facing the camera.
    Nrm,
    /// First-hit distance.
    Depth,
    /// First-hit emitted radiance: the emitters the camera sees directly, averaged over exactly
    /// the image's pixel samples (what a denoiser subtracts from the image).
    Emission,
    /// The same emitted radiance averaged over at least aov-write's `--min-samples` (antialiased
    /// like the albedo and normal): what a denoiser adds back.
    EmissionAntialiased,
    /// Per-pixel standard error of the luminance of the matching `hdr` image.
    StandardError,
    /// A denoised `hdr` image.
    Denoised,
}

impl Kind {
    pub const ALL: [Kind; 8] = [
        Kind::Hdr,
        Kind::Alb,
        Kind::Nrm,
        Kind::Depth,
        Kind::Emission,
        Kind::EmissionAntialiased,
        Kind::StandardError,
        Kind::Denoised,
    ];

    /// The kind's tag in file names (and in a model's `luxest.channels` metadata).
    pub fn tag(self) -> &'static str {
        match self {
            Kind::Hdr => "hdr",
            Kind::Alb => "alb",
            Kind::Nrm => "nrm",
            Kind::Depth => "z",
            Kind::Emission => "emi",
            Kind::EmissionAntialiased => "ema",
            Kind::StandardError => "se",
            Kind::Denoised => "dn",
        }
    }

    /// The kind of a tag, if it is one.
    pub fn from_tag(tag: &str) -> Option<Kind> {
        Kind::ALL.into_iter().find(|k| k.tag() == tag)
    }
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.tag())
    }
}

/// How many samples an image took: the `<level>` in `<name>_<level>.<kind>.exr`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Level {
    /// `<spp, 6 digits>spp`: samples per pixel of a camera estimator.
    Spp(u64),
    /// `ref`: the reference image of a dataset.
    Reference,
    /// `<paths, 6 digits>le`: light paths of the double local estimate.
    LightPaths(u64),
}

impl fmt::Display for Level {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Level::Spp(n) => write!(f, "{n:06}spp"),
            Level::Reference => f.write_str("ref"),
            Level::LightPaths(n) => write!(f, "{n:06}le"),
        }
    }
}

impl Level {
    /// Parses `000004spp`, `ref` or `001000le` (at least 6 digits, as written).
    pub fn parse(s: &str) -> Option<Level> {
        let digits = |d: &str| {
            (d.len() >= 6 && d.bytes().all(|b| b.is_ascii_digit()))
                .then(|| d.parse().ok())
                .flatten()
        };
        if s == "ref" {
            Some(Level::Reference)
        } else if let Some(d) = s.strip_suffix("spp") {
            digits(d).map(Level::Spp)
        } else {
            s.strip_suffix("le").and_then(digits).map(Level::LightPaths)
        }
    }

    /// Samples per pixel or light paths; `None` for a reference.
    pub fn samples(self) -> Option<u64> {
        match self {
            Level::Spp(n) | Level::LightPaths(n) => Some(n),
            Level::Reference => None,
        }
    }
}

/// The parts of an image file name `<name>_<level>.<kind>.exr`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ImageName {
    pub name: String,
    pub level: Level,
    pub kind: Kind,
}

impl ImageName {
    pub fn new(name: &str, level: Level, kind: Kind) -> ImageName {
        ImageName {
            name: name.to_string(),
            level,
            kind,
        }
    }

    /// `<name>_<level>.<kind>.exr`.
    pub fn file_name(&self) -> String {
        format!("{}_{}.{}.exr", self.name, self.level, self.kind)
    }

    /// Parses a file name (or the last component of a path); `None` when it does not follow the
    /// layout.
    pub fn parse(file_name: &str) -> Option<ImageName> {
        let file_name = file_name.rsplit(['/', '\\']).next()?;
        let (stem, kind) = split_kind(file_name)?;
        let (name, level) = stem.rsplit_once('_')?;
        if name.is_empty() {
            return None;
        }
        Some(ImageName::new(name, Level::parse(level)?, kind))
    }

    /// Parses the file name of `path`.
    pub fn of_path(path: &Path) -> Option<ImageName> {
        ImageName::parse(path.file_name()?.to_str()?)
    }

    /// The same image's file of another kind.
    pub fn with_kind(&self, kind: Kind) -> ImageName {
        ImageName {
            kind,
            ..self.clone()
        }
    }
}

/// `<prefix>_<level>.<kind>.exr`, `prefix` being `<dir>/<name>`.
pub fn image_path(prefix: &Path, level: Level, kind: Kind) -> PathBuf {
    let name = prefix
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    prefix.with_file_name(ImageName::new(&name, level, kind).file_name())
}

/// Splits `<stem>.<kind>.exr` into its stem and kind.
pub fn split_kind(file_name: &str) -> Option<(&str, Kind)> {
    let (stem, tag) = file_name.strip_suffix(".exr")?.rsplit_once('.')?;
    Some((stem, Kind::from_tag(tag)?))
}

/// The file next to `path` (`<stem>.<kind>.exr`, any stem) holding the same image's `kind`;
/// `None` when `path` is not named `<stem>.<kind>.exr`.
pub fn sibling(path: &Path, kind: Kind) -> Option<PathBuf> {
    let (stem, _) = split_kind(path.file_name()?.to_str()?)?;
    Some(path.with_file_name(format!("{stem}.{kind}.exr")))
}

/// The PNG preview of an image: its name with `.png` for the final `.exr`.
pub fn preview_path(image: &Path) -> PathBuf {
    image.with_extension("png")
}

/// The FLIP error map of a test image, in `dir`: `<test name without .exr>.flip.exr`.
pub fn flip_map_path(dir: &Path, test: &Path) -> PathBuf {
    let name = test
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = name.strip_suffix(".exr").unwrap_or(&name);
    dir.join(format!("{stem}.flip.exr"))
}

/// The sensor results of scene `name` in `dir`: `<dir>/<name>.sensors.ron`.
pub fn sensors_path(dir: &Path, name: &str) -> PathBuf {
    dir.join(format!("{name}.sensors.ron"))
}

/// The CSV copy of sensor results: `<name>.sensors.csv` next to `<name>.sensors.ron`.
pub fn sensors_csv_path(ron: &Path) -> PathBuf {
    ron.with_extension("csv")
}

/// The scene name of a sensor-results file `<name>.sensors.ron`.
pub fn parse_sensors_name(file_name: &str) -> Option<&str> {
    file_name
        .rsplit(['/', '\\'])
        .next()?
        .strip_suffix(".sensors.ron")
        .filter(|n| !n.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_compose_and_parse_back() {
        let cases = [
            ("gen0001_000004spp.hdr.exr", Level::Spp(4), Kind::Hdr),
            ("cornell-box_ref.alb.exr", Level::Reference, Kind::Alb),
            (
                "cornell_box_001000le.hdr.exr",
                Level::LightPaths(1000),
                Kind::Hdr,
            ),
            ("a_1234567spp.dn.exr", Level::Spp(1_234_567), Kind::Denoised),
            ("x_000001spp.z.exr", Level::Spp(1), Kind::Depth),
        ];
        for (file, level, kind) in cases {
            let parsed = ImageName::parse(file).unwrap();
            assert_eq!((parsed.level, parsed.kind), (level, kind), "{file}");
            assert_eq!(parsed.file_name(), file);
        }
        assert_eq!(
            ImageName::parse("cornell_box_001000le.hdr.exr")
                .unwrap()
                .name,
            "cornell_box"
        );
        for bad in [
            "a_4spp.hdr.exr",
            "a_000004spp.foo.exr",
            "a_000004spp.hdr.png",
            "_ref.hdr.exr",
            "aref.hdr.exr",
            "a_00000xspp.hdr.exr",
        ] {
            assert_eq!(ImageName::parse(bad), None, "{bad}");
        }
    }

    #[test]
    fn paths_and_siblings() {
        let p = image_path(Path::new("out/room"), Level::Spp(16), Kind::Nrm);
        assert_eq!(p, Path::new("out/room_000016spp.nrm.exr"));
        assert_eq!(
            sibling(Path::new("d/x.hdr.exr"), Kind::Denoised).unwrap(),
            Path::new("d/x.dn.exr")
        );
        assert_eq!(sibling(Path::new("d/x.exr"), Kind::Alb), None);
        assert_eq!(
            preview_path(Path::new("d/x_ref.dn.exr")),
            Path::new("d/x_ref.dn.png")
        );
        assert_eq!(
            flip_map_path(Path::new("m"), Path::new("d/x_ref.dn.exr")),
            Path::new("m/x_ref.dn.flip.exr")
        );
        let s = sensors_path(Path::new("b"), "room");
        assert_eq!(s, Path::new("b/room.sensors.ron"));
        assert_eq!(sensors_csv_path(&s), Path::new("b/room.sensors.csv"));
        assert_eq!(parse_sensors_name("b/room.sensors.ron"), Some("room"));
    }
}
