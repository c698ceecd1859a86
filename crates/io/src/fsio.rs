//! File helpers shared by every stage: atomic writes and RON reading/writing with errors that
//! name the file and the line.
//!
//! An output is first written to a hidden temporary file in the destination directory and then
//! renamed over the destination, so a stage that fails half-way never leaves a partial artifact
//! that `make` would take as up to date. Stages write through an [`OutputPlan`], which also
//! checks outputs against inputs and commits all outputs of a run together.

use crate::error::{Error, Result};
use crate::outputs::OutputPlan;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes `path` alone, atomically, through a one-output [`OutputPlan`] (so it refuses to
/// replace a directory, a device node or a symbolic link): the content produced by `fill` goes to
/// a temporary file renamed into place only if `fill` succeeds. A stage plans all its outputs
/// together instead (see [`crate::outputs`]).
pub fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> Result<()>,
) -> Result<()> {
    let mut plan = OutputPlan::new(Vec::<PathBuf>::new(), [path])?;
    plan.write(path, fill)?;
    plan.commit()
}

/// Writes `bytes` to `path` atomically.
pub fn write_bytes_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomically(path, |w| w.write_all(bytes).map_err(|e| Error::io(path, e)))
}

/// What `path` is when it cannot be read as an input *file*: `None` for a regular file (also
/// through a symbolic link) and for a path that does not exist (the caller says "not found" in
/// its own words), else `a directory`, `a device node` (`/dev/null` reads as empty, other
/// devices endlessly), `a FIFO` (reading one waits for a writer forever) or `a socket`.
pub fn non_file_kind(path: &Path) -> Option<&'static str> {
    non_regular(std::fs::metadata(path).ok()?.file_type())
}

/// What a file type other than a regular file is (`a directory`, `a symbolic link` for the type
/// of a link itself, `a device node`, `a FIFO`, `a socket`); `None` for a regular file.
pub fn non_regular(t: std::fs::FileType) -> Option<&'static str> {
    use std::os::unix::fs::FileTypeExt;
    if t.is_file() {
        None
    } else if t.is_dir() {
        Some("a directory")
    } else if t.is_symlink() {
        Some("a symbolic link")
    } else if t.is_char_device() || t.is_block_device() {
        Some("a device node")
    } else if t.is_fifo() {
        Some("a FIFO")
    } else if t.is_socket() {
        Some("a socket")
    } else {
        Some("not a regular file")
    }
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

/// Deserialises a map that refuses a key given twice (serde's maps keep the last value
/// silently): `#[serde(deserialize_with = "luxest_io::fsio::unique_keys")]`. In RON the error
/// carries the file, line and column of the map.
pub fn unique_keys<'de, D, K, V>(deserializer: D) -> std::result::Result<BTreeMap<K, V>, D::Error>
where
    D: serde::Deserializer<'de>,
    K: serde::Deserialize<'de> + Ord + std::fmt::Debug,
    V: serde::Deserialize<'de>,
{
    struct Visit<K, V>(std::marker::PhantomData<(K, V)>);
    impl<'de, K, V> serde::de::Visitor<'de> for Visit<K, V>
    where
        K: serde::Deserialize<'de> + Ord + std::fmt::Debug,
        V: serde::Deserialize<'de>,
    {
        type Value = BTreeMap<K, V>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a map with unique keys")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(
            self,
            mut map: A,
        ) -> std::result::Result<Self::Value, A::Error> {
            let mut out = BTreeMap::new();
            while let Some(key) = map.next_key::<K>()? {
                if out.contains_key(&key) {
                    return Err(serde::de::Error::custom(format!(
                        "duplicate key {key:?} (each key may appear once)"
                    )));
                }
                let value = map.next_value()?;
                out.insert(key, value);
            }
            Ok(out)
        }
    }
    deserializer.deserialize_map(Visit(std::marker::PhantomData))
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

/// Writes `value` as pretty RON, atomically and alone (tools and tests; stages use
/// [`write_ron_to`]).
pub fn write_ron<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let mut text = to_ron_string(value);
    text.push('\n');
    write_bytes_atomically(path, text.as_bytes())
}

/// Writes `value` as pretty RON as the planned output `path`.
pub fn write_ron_to<T: Serialize>(plan: &mut OutputPlan, path: &Path, value: &T) -> Result<()> {
    let mut text = to_ron_string(value);
    text.push('\n');
    plan.write_bytes(path, text.as_bytes())
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
        // Neither the temporary nor the folder the write made is left behind.
        assert!(!dir.exists(), "{} left behind", dir.display());
        write_bytes_atomically(&path, b"whole").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"whole");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn duplicate_map_keys_are_refused_with_the_place() {
        #[derive(serde::Deserialize, Debug)]
        #[allow(dead_code)]
        struct S {
            #[serde(deserialize_with = "unique_keys")]
            m: BTreeMap<String, f64>,
        }
        let text = "S(\n  m: {\n    \"a\": 1.0,\n    \"a\": 2.0,\n  },\n)";
        let msg = parse_ron::<S>(Path::new("x.ron"), text)
            .unwrap_err()
            .to_string();
        assert!(
            msg.starts_with("x.ron:4:") && msg.contains("duplicate key \"a\""),
            "{msg}"
        );
        let ok = parse_ron::<S>(Path::new("x.ron"), "S(m: {\"a\": 1.0, \"b\": 2.0})").unwrap();
        assert_eq!(ok.m.len(), 2);
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
