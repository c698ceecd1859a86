//! A reader of Stanford PLY triangle meshes (the mesh format of Mitsuba 3 scenes): `ascii 1.0`,
//! `binary_little_endian 1.0` and `binary_big_endian 1.0`; the `vertex` element's `x y z`,
//! optional `nx ny nz` and texture coordinates (`u v`, `s t` or `texture_u texture_v`, as
//! Mitsuba 3 reads them, unflipped), and the `face` element's index list (`vertex_indices` or
//! `vertex_index`), polygons fan-triangulated. Other elements and properties are skipped.
//!
//! Every count is checked against the bytes the file has before anything is allocated, and
//! every problem is one error naming the file and the place (`line 7`, `face 12`).

use crate::shapes::LocalMesh;
use luxest_io::math::Vec3;
use luxest_io::{Error, Result};
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Debug)]
enum Property {
    Scalar(Scalar, String),
    List(Scalar, Scalar, String),
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
}

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Little,
    Big,
}

/// Where the values of the body are read from.
struct Body<'a> {
    format: Format,
    bytes: &'a [u8],
    pos: usize,
    /// ASCII: the line the cursor is on (1-based), for messages.
    line: usize,
}

impl Body<'_> {
    fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    /// The next ASCII token (whitespace-separated), or None at the end.
    fn token(&mut self) -> Option<&str> {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            if self.bytes[self.pos] == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        (self.pos > start).then(|| std::str::from_utf8(&self.bytes[start..self.pos]).ok())?
    }

    fn value(&mut self, t: Scalar) -> std::result::Result<f64, String> {
        match self.format {
            Format::Ascii => {
                let line = self.line;
                let tok = self
                    .token()
                    .ok_or_else(|| "the file ends before the data does".to_string())?;
                let v: f64 = tok
                    .parse()
                    .map_err(|_| format!("line {line}: \"{tok}\" is not a number"))?;
                if t.is_integer() && v.fract() != 0.0 {
                    return Err(format!("line {line}: \"{tok}\" is not an integer"));
                }
                Ok(v)
            }
            Format::Little | Format::Big => {
                let n = t.size();
                if self.remaining() < n {
                    return Err("the file ends before the data does (truncated)".to_string());
                }
                let mut b = [0u8; 8];
                b[..n].copy_from_slice(&self.bytes[self.pos..self.pos + n]);
                self.pos += n;
                if self.format == Format::Big {
                    b[..n].reverse();
                }
                Ok(match t {
                    Scalar::I8 => b[0] as i8 as f64,
                    Scalar::U8 => b[0] as f64,
                    Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
                    Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
                    Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::F64 => f64::from_le_bytes(b),
                })
            }
        }
    }
}

/// Largest number of vertices or faces a PLY file may declare (the compiled scene indexes
/// vertices with u32).
const MAX_COUNT: u64 = 1 << 31;

/// Reads the PLY file at `path`.
pub fn load_ply(path: &Path) -> Result<LocalMesh> {
    let bytes = luxest_io::fsio::read_bytes(path)?;
    load_ply_bytes(path, &bytes)
}

/// [`load_ply`] of the file's content `bytes`; `path` names it in errors.
pub fn load_ply_bytes(path: &Path, bytes: &[u8]) -> Result<LocalMesh> {
    let fail = |place: String, msg: String| Error::at(path, place, format!("PLY: {msg}"));
    // The header: text lines up to `end_header`.
    let mut pos = 0;
    let mut line_no = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(Error::input(path, "PLY: the header has no end_header line"));
        };
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        line_no += 1;
        let place = format!("line {line_no}");
        let text = std::str::from_utf8(raw)
            .map_err(|_| fail(place.clone(), "the header is not text".into()))?
            .trim_end_matches('\r');
        let words: Vec<&str> = text.split_whitespace().collect();
        if line_no == 1 {
            if text.trim() != "ply" {
                return Err(Error::input(
                    path,
                    "not a PLY file (it does not start with \"ply\")",
                ));
            }
            continue;
        }
        match words.as_slice() {
            [] => {}
            ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, version] => {
                if *version != "1.0" {
                    return Err(fail(place, format!("format version {version}, only 1.0")));
                }
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    other => return Err(fail(place, format!("unknown format \"{other}\""))),
                });
            }
            ["element", name, count] => {
                let count: u64 = count
                    .parse()
                    .map_err(|_| fail(place.clone(), format!("element count \"{count}\"")))?;
                if count > MAX_COUNT {
                    return Err(fail(
                        place,
                        format!("{count} {name} elements, more than the {MAX_COUNT} supported"),
                    ));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            ["property", "list", count_type, item_type, name] => {
                let (Some(c), Some(i)) = (Scalar::parse(count_type), Scalar::parse(item_type))
                else {
                    return Err(fail(place, format!("unknown type in \"{text}\"")));
                };
                if !c.is_integer() {
                    return Err(fail(place, "a list's count must be an integer type".into()));
                }
                let Some(e) = elements.last_mut() else {
                    return Err(fail(place, "property before any element".into()));
                };
                e.properties.push(Property::List(c, i, name.to_string()));
            }
            ["property", ty, name] => {
                let Some(t) = Scalar::parse(ty) else {
                    return Err(fail(place, format!("unknown property type \"{ty}\"")));
                };
                let Some(e) = elements.last_mut() else {
                    return Err(fail(place, "property before any element".into()));
                };
                e.properties.push(Property::Scalar(t, name.to_string()));
            }
            ["end_header"] => break,
            _ => return Err(fail(place, format!("unexpected header line \"{text}\""))),
        }
    }
    let Some(format) = format else {
        return Err(Error::input(path, "PLY: the header has no format line"));
    };
    let mut body = Body {
        format,
        bytes,
        pos,
        line: line_no + 1,
    };
    let mut positions: Vec<Vec3> = Vec::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut uvs: Vec<[f64; 2]> = Vec::new();
    let mut has_normals = false;
    let mut has_uvs = false;
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut faces_seen = false;
    for e in &elements {
        // Every element takes at least one byte (ASCII: a digit; binary: its smallest
        // property), so a count beyond the bytes left is a lie: refused before allocating.
        let min_size = match format {
            Format::Ascii => 1,
            _ => e
                .properties
                .iter()
                .map(|p| match p {
                    Property::Scalar(t, _) => t.size(),
                    Property::List(c, _, _) => c.size(),
                })
                .sum::<usize>()
                .max(1),
        } as u64;
        if e.count.saturating_mul(min_size) > body.remaining() as u64 {
            return Err(Error::input(
                path,
                format!(
                    "PLY: the header declares {} {} elements, more than the {} bytes after it can \
                     hold",
                    e.count,
                    e.name,
                    body.remaining()
                ),
            ));
        }
        let names: Vec<&str> = e
            .properties
            .iter()
            .map(|p| match p {
                Property::Scalar(_, n) | Property::List(_, _, n) => n.as_str(),
            })
            .collect();
        let index = |n: &str| names.iter().position(|&m| m == n);
        match e.name.as_str() {
            "vertex" => {
                let (Some(x), Some(y), Some(z)) = (index("x"), index("y"), index("z")) else {
                    return Err(Error::input(path, "PLY: the vertex element has no x, y, z"));
                };
                let n = match (index("nx"), index("ny"), index("nz")) {
                    (Some(a), Some(b), Some(c)) => Some([a, b, c]),
                    _ => None,
                };
                let uv = [("u", "v"), ("s", "t"), ("texture_u", "texture_v")]
                    .iter()
                    .find_map(|(a, b)| Some([index(a)?, index(b)?]));
                has_normals = n.is_some();
                has_uvs = uv.is_some();
                positions.reserve(e.count as usize);
                let mut values = vec![0.0; e.properties.len()];
                for k in 0..e.count {
                    for (j, p) in e.properties.iter().enumerate() {
                        values[j] = match p {
                            Property::Scalar(t, _) => body.value(*t),
                            Property::List(c, i, _) => skip_list(&mut body, *c, *i).map(|_| 0.0),
                        }
                        .map_err(|m| fail(format!("vertex {k}"), m))?;
                    }
                    let p = Vec3::new(values[x], values[y], values[z]);
                    if !p.is_finite() {
                        return Err(fail(format!("vertex {k}"), "non-finite coordinate".into()));
                    }
                    positions.push(p);
                    if let Some([a, b, c]) = n {
                        normals.push(Vec3::new(values[a], values[b], values[c]));
                    }
                    if let Some([a, b]) = uv {
                        uvs.push([values[a], values[b]]);
                    }
                }
            }
            "face" => {
                faces_seen = true;
                let Some(list) = index("vertex_indices").or_else(|| index("vertex_index")) else {
                    return Err(Error::input(
                        path,
                        "PLY: the face element has no vertex_indices list",
                    ));
                };
                let nv = positions.len() as u64;
                for k in 0..e.count {
                    for (j, p) in e.properties.iter().enumerate() {
                        let place = || format!("face {k}");
                        match p {
                            Property::List(c, i, _) if j == list => {
                                let count = body.value(*c).map_err(|m| fail(place(), m))?;
                                if !(3.0..=1024.0).contains(&count) {
                                    return Err(fail(
                                        place(),
                                        format!("{count} vertices (a face needs 3 to 1024)"),
                                    ));
                                }
                                let mut idx = Vec::with_capacity(count as usize);
                                for _ in 0..count as usize {
                                    let v = body.value(*i).map_err(|m| fail(place(), m))?;
                                    if !(v >= 0.0 && (v as u64) < nv && i.is_integer()) {
                                        return Err(fail(
                                            place(),
                                            format!(
                                                "vertex index {v} is outside the {nv} vertices \
                                                 (the vertex element must come first)"
                                            ),
                                        ));
                                    }
                                    idx.push(v as u32);
                                }
                                for w in 1..idx.len() - 1 {
                                    triangles.push([idx[0], idx[w], idx[w + 1]]);
                                }
                            }
                            Property::List(c, i, _) => {
                                skip_list(&mut body, *c, *i).map_err(|m| fail(place(), m))?
                            }
                            Property::Scalar(t, _) => {
                                body.value(*t).map_err(|m| fail(place(), m))?;
                            }
                        }
                    }
                }
            }
            other => {
                for k in 0..e.count {
                    for p in &e.properties {
                        match p {
                            Property::Scalar(t, _) => body.value(*t).map(|_| ()),
                            Property::List(c, i, _) => skip_list(&mut body, *c, *i),
                        }
                        .map_err(|m| fail(format!("{other} {k}"), m))?;
                    }
                }
            }
        }
    }
    if positions.is_empty() {
        return Err(Error::input(path, "PLY: the file has no vertices"));
    }
    if !faces_seen || triangles.is_empty() {
        return Err(Error::input(path, "PLY: the file has no faces"));
    }
    if has_uvs && uvs.iter().flatten().any(|c| !c.is_finite()) {
        return Err(Error::input(path, "PLY: non-finite texture coordinate"));
    }
    // Texture coordinates as stored: Mitsuba 3 reads PLY's without flipping, and its (0, 0) is
    // the image's top-left corner, luxest's convention.
    Ok(LocalMesh {
        positions,
        normals: has_normals.then_some(normals),
        uvs: has_uvs.then_some(uvs),
        triangles,
    })
}

fn skip_list(body: &mut Body, count: Scalar, item: Scalar) -> std::result::Result<(), String> {
    let n = body.value(count)?;
    if !(0.0..=1e6).contains(&n) {
        return Err(format!("a list of {n} items"));
    }
    for _ in 0..n as usize {
        body.value(item)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
                          property float u\nproperty float v\nelement face 1\n\
                          property list uchar int vertex_indices\nend_header\n";

    #[test]
    fn ascii_and_binary_read_the_same_quad() {
        let ascii = format!(
            "ply\nformat ascii 1.0\ncomment a unit square\n{HEADER}0 0 0 0 0\n1 0 0 1 0\n\
             1 1 0 1 1\n0 1 0 0 1\n4 0 1 2 3\n"
        );
        let a = load_ply_bytes(Path::new("a.ply"), ascii.as_bytes()).unwrap();
        let mut bin = format!("ply\nformat binary_little_endian 1.0\n{HEADER}").into_bytes();
        for p in [
            [0f32, 0., 0., 0., 0.],
            [1., 0., 0., 1., 0.],
            [1., 1., 0., 1., 1.],
            [0., 1., 0., 0., 1.],
        ] {
            for c in p {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
        bin.push(4);
        for i in 0i32..4 {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        let b = load_ply_bytes(Path::new("b.ply"), &bin).unwrap();
        for m in [&a, &b] {
            assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
            assert_eq!(m.positions[2], Vec3::new(1.0, 1.0, 0.0));
            assert_eq!(m.uvs.as_ref().unwrap()[1], [1.0, 0.0]);
            assert!(m.normals.is_none());
        }
    }

    #[test]
    fn bad_files_are_one_line_errors() {
        let cases: [(&str, &[u8]); 4] = [
            ("not a PLY", b"solid stl\n"),
            ("no end_header", b"ply\nformat ascii 1.0\n"),
            (
                "more than the",
                b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nend_header\n",
            ),
            (
                "outside the 1 vertices",
                b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n3 0 1 2\n",
            ),
        ];
        for (want, bytes) in cases {
            let e = load_ply_bytes(Path::new("m.ply"), bytes)
                .unwrap_err()
                .to_string();
            assert!(e.contains(want) && e.starts_with("m.ply"), "{want}: {e}");
        }
    }
}
