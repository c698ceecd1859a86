//! A reader of Mitsuba's `.serialized` meshes, versions 3 and 4 (the format Mitsuba 0.5/0.6
//! wrote and Mitsuba 3 still reads; its description is in Mitsuba 3's
//! `src/shapes/serialized.cpp`): a file of one or more zlib-compressed triangle meshes, each
//! `u16 0x041C, u16 version` then a DEFLATE stream of `u32 flags`, (version 4) a
//! NUL-terminated name, `u64` vertex and triangle counts, positions, optional normals
//! (flag 0x1), texture coordinates (0x2) and colours (0x8), single or double precision
//! (0x2000), and `u32` vertex indices; a dictionary of the meshes' offsets (`u64` in version 4,
//! `u32` in 3) and their count (`u32`) ends the file. Version 5 files are refused.
//!
//! Every count is checked against what the compressed bytes can hold before anything is
//! allocated; every problem is one error naming the file.

use crate::shapes::LocalMesh;
use luxest_io::math::Vec3;
use luxest_io::{Error, Result};
use std::path::Path;

const MAGIC: u16 = 0x041C;
/// DEFLATE expands by at most 1032:1; a stream claiming more than this is a lie.
const MAX_RATIO: usize = 1100;

/// Reads mesh `index` of the `.serialized` file at `path`.
pub fn load_serialized(path: &Path, index: u32) -> Result<LocalMesh> {
    let bytes = luxest_io::fsio::read_bytes(path)?;
    load_serialized_bytes(path, &bytes, index)
}

/// [`load_serialized`] of the file's content `bytes`; `path` names it in errors.
pub fn load_serialized_bytes(path: &Path, bytes: &[u8], index: u32) -> Result<LocalMesh> {
    let fail = |msg: String| Error::input(path, format!("serialized mesh: {msg}"));
    let u16_at = |i: usize| {
        bytes
            .get(i..i + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
    };
    let (Some(magic), Some(version)) = (u16_at(0), u16_at(2)) else {
        return Err(fail("the file is shorter than its header".into()));
    };
    if magic != MAGIC {
        return Err(fail(format!(
            "not a Mitsuba serialized file (magic 0x{magic:04X}, not 0x041C)"
        )));
    }
    if version != 3 && version != 4 {
        return Err(fail(format!(
            "format version {version} is not supported (versions 3 and 4)"
        )));
    }
    // The stream of mesh `index`: [start, end) from the dictionary at the end of the file.
    let (start, end) = if bytes.len() < 8 {
        return Err(fail(
            "the file is shorter than a header and a dictionary".into(),
        ));
    } else {
        let n = bytes.len();
        let count = u32::from_le_bytes(bytes[n - 4..].try_into().expect("4 bytes")) as usize;
        let width = if version == 4 { 8 } else { 4 };
        let table_len = count
            .checked_mul(width)
            .filter(|&t| t + 4 <= n)
            .ok_or_else(|| {
                fail(format!(
                    "the dictionary claims {count} meshes, more than the file can hold"
                ))
            })?;
        let table = n - 4 - table_len;
        if index as usize >= count {
            return Err(fail(format!(
                "shape_index {index} is out of range: the file has {count} meshes"
            )));
        }
        let offset = |i: usize| -> u64 {
            let at = table + i * width;
            if width == 8 {
                u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"))
            } else {
                u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes")) as u64
            }
        };
        let start = offset(index as usize);
        let end = if (index as usize) + 1 < count {
            offset(index as usize + 1)
        } else {
            table as u64
        };
        if !(start < end && end <= table as u64) {
            return Err(fail(format!(
                "mesh {index} lies at bytes {start}..{end}, outside the file's {table} bytes of \
                 meshes"
            )));
        }
        (start as usize, end as usize)
    };
    let chunk = &bytes[start..end];
    if chunk.len() < 4 || u16::from_le_bytes([chunk[0], chunk[1]]) != MAGIC {
        return Err(fail(format!("mesh {index} does not start with a header")));
    }
    let limit = (chunk.len() - 4).saturating_mul(MAX_RATIO).max(1 << 16);
    let data = miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(&chunk[4..], limit)
        .map_err(|e| {
            fail(format!(
                "mesh {index}: corrupt compressed data ({:?})",
                e.status
            ))
        })?;
    parse_legacy(&data, version).map_err(|m| fail(format!("mesh {index}: {m}")))
}

/// A little-endian reader over decompressed bytes.
struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
}

impl Cursor<'_> {
    fn take(&mut self, n: usize) -> std::result::Result<&[u8], String> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|&e| e <= self.data.len())
            .ok_or_else(|| "the mesh data ends early (truncated)".to_string())?;
        let s = &self.data[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    fn u32(&mut self) -> std::result::Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn u64(&mut self) -> std::result::Result<u64, String> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    /// `n` values of `dims` floats each, f32 or f64, as f64.
    fn floats(
        &mut self,
        n: usize,
        dims: usize,
        double: bool,
    ) -> std::result::Result<Vec<f64>, String> {
        let size = if double { 8 } else { 4 };
        let raw = self.take(n.checked_mul(dims * size).ok_or("count overflows")?)?;
        Ok(raw
            .chunks_exact(size)
            .map(|c| {
                if double {
                    f64::from_le_bytes(c.try_into().expect("8 bytes"))
                } else {
                    f32::from_le_bytes(c.try_into().expect("4 bytes")) as f64
                }
            })
            .collect())
    }
}

fn parse_legacy(data: &[u8], version: u16) -> std::result::Result<LocalMesh, String> {
    let mut c = Cursor { data, pos: 0 };
    let flags = c.u32()?;
    if version == 4 {
        // The mesh's name, NUL-terminated.
        let len = c.data[c.pos..]
            .iter()
            .position(|&b| b == 0)
            .ok_or("the mesh name is not terminated")?;
        c.take(len + 1)?;
    }
    let (nv, nf) = (c.u64()?, c.u64()?);
    let double = flags & 0x2000 != 0;
    let size = if double { 8 } else { 4 };
    // Positions alone need 3 floats per vertex, faces 12 bytes each.
    let left = (data.len() - c.pos) as u64;
    if nv.saturating_mul(3 * size) > left || nf.saturating_mul(12) > left || nv > u32::MAX as u64 {
        return Err(format!(
            "{nv} vertices and {nf} triangles do not fit in the {left} bytes of mesh data"
        ));
    }
    let (nv, nf) = (nv as usize, nf as usize);
    let vec3s = |v: Vec<f64>| -> Vec<Vec3> {
        v.chunks_exact(3)
            .map(|p| Vec3::new(p[0], p[1], p[2]))
            .collect()
    };
    let positions = vec3s(c.floats(nv, 3, double)?);
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {i}: non-finite coordinate"));
    }
    let normals = if flags & 0x1 != 0 {
        Some(vec3s(c.floats(nv, 3, double)?))
    } else {
        None
    };
    let uvs = if flags & 0x2 != 0 {
        let t = c.floats(nv, 2, double)?;
        if t.iter().any(|x| !x.is_finite()) {
            return Err("non-finite texture coordinate".into());
        }
        Some(t.chunks_exact(2).map(|t| [t[0], t[1]]).collect())
    } else {
        None
    };
    if flags & 0x8 != 0 {
        // Vertex colours: read past (nothing in luxest uses them, nor Mitsuba 3 without a
        // mesh_attribute texture).
        c.floats(nv, 3, double)?;
    }
    let raw = c.take(nf * 12)?;
    let mut triangles = Vec::with_capacity(nf);
    for (k, t) in raw.chunks_exact(12).enumerate() {
        let i = |j: usize| u32::from_le_bytes(t[4 * j..4 * j + 4].try_into().expect("4 bytes"));
        let tri = [i(0), i(1), i(2)];
        if tri.iter().any(|&v| v as usize >= nv) {
            return Err(format!(
                "triangle {k} refers to a vertex beyond the {nv} vertices"
            ));
        }
        triangles.push(tri);
    }
    if triangles.is_empty() {
        return Err("the mesh has no triangles".into());
    }
    Ok(LocalMesh {
        positions,
        normals,
        uvs,
        triangles,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file of two version-4 meshes: a triangle, then a quad with normals and UVs.
    fn file() -> Vec<u8> {
        let mesh = |flags: u32, name: &str, pos: &[f32], extra: &[f32], tris: &[u32]| {
            let mut raw = flags.to_le_bytes().to_vec();
            raw.extend_from_slice(name.as_bytes());
            raw.push(0);
            raw.extend_from_slice(&((pos.len() / 3) as u64).to_le_bytes());
            raw.extend_from_slice(&((tris.len() / 3) as u64).to_le_bytes());
            for v in pos.iter().chain(extra) {
                raw.extend_from_slice(&v.to_le_bytes());
            }
            for i in tris {
                raw.extend_from_slice(&i.to_le_bytes());
            }
            let mut out = vec![0x1C, 0x04, 4, 0];
            out.extend(miniz_oxide::deflate::compress_to_vec_zlib(&raw, 6));
            out
        };
        let a = mesh(
            0x1000,
            "tri",
            &[0., 0., 0., 1., 0., 0., 0., 1., 0.],
            &[],
            &[0, 1, 2],
        );
        let b = mesh(
            0x1003,
            "quad",
            &[0., 0., 0., 2., 0., 0., 2., 2., 0., 0., 2., 0.],
            &[
                0., 0., 1., 0., 0., 1., 0., 0., 1., 0., 0., 1., // normals
                0., 0., 1., 0., 1., 1., 0., 1., // uvs
            ],
            &[0, 1, 2, 0, 2, 3],
        );
        let mut f = a.clone();
        f.extend(&b);
        f.extend_from_slice(&0u64.to_le_bytes());
        f.extend_from_slice(&(a.len() as u64).to_le_bytes());
        f.extend_from_slice(&2u32.to_le_bytes());
        f
    }

    #[test]
    fn reads_each_mesh_of_a_version_4_file() {
        let f = file();
        let p = Path::new("m.serialized");
        let a = load_serialized_bytes(p, &f, 0).unwrap();
        assert_eq!(a.triangles, vec![[0, 1, 2]]);
        assert!(a.normals.is_none() && a.uvs.is_none());
        let b = load_serialized_bytes(p, &f, 1).unwrap();
        assert_eq!(b.triangles.len(), 2);
        assert_eq!(b.positions[2], Vec3::new(2.0, 2.0, 0.0));
        assert_eq!(b.normals.unwrap()[3], Vec3::new(0.0, 0.0, 1.0));
        assert_eq!(b.uvs.unwrap()[2], [1.0, 1.0]);
        let e = load_serialized_bytes(p, &f, 2).unwrap_err().to_string();
        assert!(e.contains("shape_index 2 is out of range"), "{e}");
        // Truncated: the dictionary no longer matches.
        let e = load_serialized_bytes(p, &f[..f.len() - 9], 0)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("m.serialized: serialized mesh:"), "{e}");
    }
}
