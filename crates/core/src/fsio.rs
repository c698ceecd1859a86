//! File helpers shared by every stage: atomic writes and RON reading/writing with errors that
//! name the file and the line.
//!
//! An output is first written to a hidden temporary file in the destination directory and then
//! renamed over the destination, so a stage that fails half-way never leaves a partial artifact
//! that `make` would take as up to date.

use crate::error::{Error, Result};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The temporary sibling `dir/.name.tmp-<pid>` used while writing `path`.
fn temp_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

/// Writes `path` atomically: the content produced by `fill` goes to a temporary file which is
/// renamed into place only if `fill` succeeds; on any failure the temporary is removed.
pub fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> Result<()>,
) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    let tmp = temp_sibling(path);
    let result = (|| {
        let file = std::fs::File::create(&tmp).map_err(|e| Error::io(path, e))?;
        let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
        fill(&mut w)?;
        let file = w
            .into_inner()
            .map_err(|e| Error::io(path, e.into_error()))?;
        file.sync_all().map_err(|e| Error::io(path, e))?;
        std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Writes `bytes` to `path` atomically.
pub fn write_bytes_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomically(path, |w| w.write_all(bytes).map_err(|e| Error::io(path, e)))
}

/// Reads a whole file, naming it in the error.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| Error::io(path, e))
}

/// Parses RON text; errors carry `file:line:col`. Optional fields may be written bare
/// (`name: "floor"`) or as `Some("floor")`.
pub fn parse_ron<T: DeserializeOwned>(path: &Path, text: &str) -> Result<T> {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(text)
        .map_err(|e| {
            let place = format!(
                "{}:{}:{}",
                path.display(),
                e.span.start.line,
                e.span.start.col
            );
            Error::input(place, e.code.to_string())
        })
}

/// Reads and parses a RON file.
pub fn read_ron<T: DeserializeOwned>(path: &Path) -> Result<T> {
    let bytes = read_bytes(path)?;
    let text = std::str::from_utf8(&bytes)
        .map_err(|e| Error::input(path, format!("not UTF-8 text: {e}")))?;
    parse_ron(path, text)
}

/// Serialises `value` as pretty RON.
pub fn to_ron_string<T: Serialize>(value: &T) -> String {
    let config = ron::ser::PrettyConfig::new()
        .depth_limit(4)
        .struct_names(true);
    // Serialising our own plain data types cannot fail.
    ron::ser::to_string_pretty(value, config).expect("RON serialisation of plain data")
}

/// Writes `value` as pretty RON, atomically.
pub fn write_ron<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let mut text = to_ron_string(value);
    text.push('\n');
    write_bytes_atomically(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_nothing() {
        let dir = std::env::temp_dir().join(format!("luxest-fsio-{}", std::process::id()));
        let path = dir.join("out.bin");
        let r = write_atomically(&path, |w| {
            w.write_all(b"half").unwrap();
            Err(Error::input(&path, "simulated failure"))
        });
        assert!(r.is_err());
        assert!(!path.exists());
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            0,
            "temporary file left behind"
        );
        write_bytes_atomically(&path, b"whole").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"whole");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn ron_errors_name_line_and_column() {
        #[derive(serde::Deserialize, Debug)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct S {
            a: f64,
        }
        let e = parse_ron::<S>(Path::new("x.ron"), "S(\n  a: 1.0,\n  b: 2.0,\n)").unwrap_err();
        let msg = e.to_string();
        assert!(msg.starts_with("x.ron:3:"), "{msg}");
        assert!(msg.contains('b'), "{msg}");
    }
}
