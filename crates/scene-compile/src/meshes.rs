//! Loading of mesh files referenced by a scene: Wavefront OBJ (via `tobj`) and glTF 2.0
//! (`.gltf` with external or data-URI buffers, and `.glb`, via `gltf`).
//!
//! Errors name the mesh file and, for OBJ syntax errors, the line.

use crate::shapes::LocalMesh;
use luxest_io::math::{Affine, Vec3};
use luxest_io::{Error, Result};
use std::io::{BufRead, Read};
use std::path::Path;

/// A `BufRead` adapter that counts the newlines consumed, so that a parse error reported by
/// `tobj` (which reads line by line and stops at the first bad line) can be given a line number.
struct LineCounter<R> {
    inner: R,
    newlines: usize,
}

impl<R: BufRead> Read for LineCounter<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.newlines += buf[..n].iter().filter(|&&b| b == b'\n').count();
        Ok(n)
    }
}

impl<R: BufRead> BufRead for LineCounter<R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        self.inner.fill_buf()
    }
    fn consume(&mut self, amt: usize) {
        if let Ok(buf) = self.inner.fill_buf() {
            self.newlines += buf[..amt.min(buf.len())]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
        }
        self.inner.consume(amt);
    }
}

/// Loads every model of an OBJ file as one mesh (polygons triangulated, OBJ materials ignored).
pub fn load_obj(path: &Path) -> Result<LocalMesh> {
    let bytes = luxest_io::fsio::read_bytes(path)?;
    load_obj_bytes(path, &bytes)
}

/// The faces of an OBJ file that it assigns to the MTL material `usemtl` (`usemtl NAME` before
/// them), as one mesh; an error when there are none.
pub fn load_obj_usemtl(path: &Path, usemtl: &str) -> Result<LocalMesh> {
    let bytes = luxest_io::fsio::read_bytes(path)?;
    let text = String::from_utf8_lossy(&bytes);
    // Faces under another material become empty lines, so that line numbers stay the file's.
    let mut current: Option<&str> = None;
    let mut kept = String::with_capacity(text.len());
    let mut faces = 0usize;
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("usemtl") => current = Some(line.trim()["usemtl".len()..].trim()),
            Some("f") if current != Some(usemtl) => {
                kept.push('\n');
                continue;
            }
            Some("f") => faces += 1,
            _ => {}
        }
        kept.push_str(line);
        kept.push('\n');
    }
    if faces == 0 {
        return Err(Error::input(
            path,
            format!("no face of the OBJ file uses the material \"{usemtl}\""),
        ));
    }
    load_obj_bytes(path, kept.as_bytes())
}

/// [`load_obj`] of the file's content `bytes`; `path` names it in errors.
pub fn load_obj_bytes(path: &Path, bytes: &[u8]) -> Result<LocalMesh> {
    let mut reader = LineCounter {
        inner: bytes,
        newlines: 0,
    };
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    // Material libraries are ignored: the scene assigns materials.
    let loaded = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    });
    let models = match loaded {
        Ok((models, _materials)) => models,
        Err(e) => {
            use tobj::LoadError::*;
            let per_line = matches!(
                e,
                ReadError
                    | UnrecognizedCharacter
                    | PositionParseError
                    | NormalParseError
                    | TexcoordParseError
                    | FaceParseError
                    | ColorParseError
                    | InvalidObjectName
                    | InvalidPolygon
                    | ScalingByZeroError
            );
            return Err(if per_line {
                Error::at(
                    path,
                    format!("line {}", reader.newlines.max(1)),
                    if matches!(e, ReadError) {
                        "malformed OBJ: not text (binary data or invalid UTF-8)".to_string()
                    } else {
                        format!("malformed OBJ: {e}")
                    },
                )
            } else if let (FaceVertexOutOfBounds, Some(line)) = (&e, face_line_out_of_range(bytes))
            {
                Error::at(path, format!("line {line}"), format!("malformed OBJ: {e}"))
            } else {
                Error::input(path, format!("malformed OBJ: {e}"))
            });
        }
    };
    let mut mesh = LocalMesh {
        normals: Some(Vec::new()),
        ..Default::default()
    };
    for model in models {
        let m = model.mesh;
        let nv = m.positions.len() / 3;
        let positions: Vec<Vec3> = m
            .positions
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0] as f64, c[1] as f64, c[2] as f64))
            .collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::at(
                path,
                format!("vertex {} of object '{}'", i + 1, model.name),
                "non-finite coordinate",
            ));
        }
        let normals = (m.normals.len() == m.positions.len()).then(|| {
            m.normals
                .chunks_exact(3)
                .map(|c| Vec3::new(c[0] as f64, c[1] as f64, c[2] as f64))
                .collect::<Vec<_>>()
        });
        // OBJ's v points up the image; luxest's (glTF's) points down (Mitsuba 3's loader flips
        // it the same way).
        let uvs = (m.texcoords.len() == 2 * nv).then(|| {
            m.texcoords
                .chunks_exact(2)
                .map(|c| [c[0] as f64, 1.0 - c[1] as f64])
                .collect::<Vec<_>>()
        });
        if let Some(uvs) = &uvs {
            if let Some(i) = uvs
                .iter()
                .position(|t| !(t[0].is_finite() && t[1].is_finite()))
            {
                return Err(Error::at(
                    path,
                    format!(
                        "texture coordinate of vertex {} of object '{}'",
                        i + 1,
                        model.name
                    ),
                    "non-finite value",
                ));
            }
        }
        if m.indices.iter().any(|&i| i as usize >= nv) {
            let message = format!("object '{}' has a face index out of range", model.name);
            return Err(match face_line_out_of_range(bytes) {
                Some(line) => Error::at(path, format!("line {line}"), message),
                None => Error::input(path, message),
            });
        }
        let triangles = m
            .indices
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        mesh.append(LocalMesh {
            positions,
            normals,
            uvs,
            triangles,
        });
    }
    if mesh.triangles.is_empty() {
        return Err(Error::input(path, "OBJ file contains no faces"));
    }
    Ok(mesh)
}

/// The line (1-based) of the first OBJ face that refers to a vertex the file does not have: an
/// index 0, beyond the file's vertex count, or a negative (relative) index before its first
/// vertex. Used to place the error when `tobj` reports an index out of range without a line.
fn face_line_out_of_range(bytes: &[u8]) -> Option<usize> {
    let text = String::from_utf8_lossy(bytes);
    let total = text
        .lines()
        .filter(|l| l.split_whitespace().next() == Some("v"))
        .count() as i64;
    let mut seen = 0i64;
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => seen += 1,
            Some("f") => {
                for w in words {
                    let Ok(i) = w.split('/').next().unwrap_or("").parse::<i64>() else {
                        return Some(n + 1);
                    };
                    let index = if i < 0 { seen + i + 1 } else { i };
                    if index < 1 || index > total {
                        return Some(n + 1);
                    }
                }
            }
            _ => {}
        }
    }
    None
}

/// The byte range an accessor reads must lie in its buffer view, and the view in its buffer:
/// otherwise the reader silently yields nothing and the error would blame a missing attribute.
fn check_accessor(
    path: &Path,
    place: &str,
    what: &str,
    accessor: &gltf::Accessor,
    buffers: &[Vec<u8>],
) -> Result<()> {
    use gltf::accessor::{DataType, Dimensions};
    let at = || format!("{place} {what} (accessor {})", accessor.index());
    // What the reader will read it as: it assumes these types (a mismatch trips the gltf
    // crate's assertions, or reads garbage without them; found by the gltf fuzz target).
    let (dims, dims_name, types, types_name): (Dimensions, &str, &[DataType], &str) = match what {
        "Positions" | "Normals" => (Dimensions::Vec3, "VEC3", &[DataType::F32], "FLOAT"),
        "indices" => (
            Dimensions::Scalar,
            "SCALAR",
            &[DataType::U8, DataType::U16, DataType::U32],
            "UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT",
        ),
        // Other attributes are not read.
        _ => (accessor.dimensions(), "", &[accessor.data_type()][..], ""),
    };
    if accessor.dimensions() != dims || !types.contains(&accessor.data_type()) {
        return Err(Error::at(
            path,
            at(),
            format!(
                "is {:?} {:?}, but must be {dims_name} of {types_name}",
                accessor.dimensions(),
                accessor.data_type()
            ),
        ));
    }
    if accessor.sparse().is_some() {
        return Err(Error::at(path, at(), "sparse accessors are not supported"));
    }
    // Zero-filled accessors have no view; the reader handles them.
    let Some(view) = accessor.view() else {
        return Ok(());
    };
    let (count, size) = (accessor.count() as u128, accessor.size() as u128);
    if let Some(s) = view.stride().filter(|&s| (s as u128) < size) {
        return Err(Error::at(
            path,
            at(),
            format!(
                "buffer view {} has a stride of {s} bytes, less than its {size}-byte elements",
                view.index()
            ),
        ));
    }
    let stride = view.stride().map_or(size, |s| s as u128);
    let need = if count == 0 {
        0
    } else {
        accessor.offset() as u128 + stride * (count - 1) + size
    };
    if need > view.length() as u128 {
        return Err(Error::at(
            path,
            format!("{place} {what} (accessor {})", accessor.index()),
            format!(
                "{count} elements need {need} bytes, but buffer view {} has {}",
                view.index(),
                view.length()
            ),
        ));
    }
    let buffer_len = buffers.get(view.buffer().index()).map_or(0, Vec::len) as u128;
    let view_end = view.offset() as u128 + view.length() as u128;
    if view_end > buffer_len {
        return Err(Error::at(
            path,
            format!("buffer view {}", view.index()),
            format!(
                "ends at byte {view_end}, beyond the {buffer_len} bytes of buffer {}",
                view.buffer().index()
            ),
        ));
    }
    Ok(())
}

/// Decodes standard base64 (RFC 4648), as used by glTF data URIs.
fn decode_base64(s: &str) -> Option<Vec<u8>> {
    let val = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let bytes: Vec<u8> = s.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
    let data = match bytes.iter().position(|&b| b == b'=') {
        Some(p) if bytes[p..].iter().all(|&b| b == b'=') => &bytes[..p],
        Some(_) => return None,
        None => &bytes[..],
    };
    let mut out = Vec::with_capacity(data.len() * 3 / 4);
    for chunk in data.chunks(4) {
        if chunk.len() == 1 {
            return None;
        }
        let mut acc = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            acc |= val(c)? << (18 - 6 * i);
        }
        out.extend_from_slice(&acc.to_be_bytes()[1..chunk.len()]);
    }
    Some(out)
}

/// Every accessor a mesh primitive names exists: the gltf crate's own validation indexes the
/// POSITION accessor before checking that it exists (a panic; found by the gltf fuzz target).
fn check_accessor_indices(path: &Path, root: &gltf::json::Root) -> Result<()> {
    let n = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let named = prim.attributes.values().chain(&prim.indices).chain(
                prim.targets.iter().flatten().flat_map(|t| {
                    [&t.positions, &t.normals, &t.tangents]
                        .into_iter()
                        .flatten()
                }),
            );
            if let Some(i) = named.map(|i| i.value()).find(|&i| i >= n) {
                return Err(Error::at(
                    path,
                    format!("mesh {m} primitive {p}"),
                    format!("refers to accessor {i}, but the file has {n}"),
                ));
            }
        }
    }
    Ok(())
}

/// The binary glTF header (magic `glTF`, version, total length) checked before the gltf crate
/// reads it: a total length below the 12-byte header underflows its arithmetic (a panic where
/// overflow checks are on; found by the `gltf` fuzz target).
fn check_glb_header(path: &Path, bytes: &[u8]) -> Result<()> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    if bytes.len() < 12 {
        return Err(Error::input(
            path,
            format!(
                "malformed glTF: binary header truncated at {} bytes",
                bytes.len()
            ),
        ));
    }
    let word = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().expect("4 bytes"));
    let (version, length) = (word(4), word(8));
    if version != 2 {
        return Err(Error::input(
            path,
            format!("malformed glTF: binary glTF version {version}, only 2 is supported"),
        ));
    }
    if !(20..=bytes.len() as u64).contains(&(length as u64)) {
        return Err(Error::input(
            path,
            format!(
                "malformed glTF: binary header gives a total length of {length} bytes; the file \
                 has {} and the headers alone need 20",
                bytes.len()
            ),
        ));
    }
    Ok(())
}

/// A glTF node as messages name it: `node 3 ("Cube")`, or `node 3` without a name.
fn node_place(node: &gltf::Node) -> String {
    match node.name() {
        Some(name) => format!("node {} ({name:?})", node.index()),
        None => format!("node {}", node.index()),
    }
}

/// A node's own transform (its `matrix`, or its translation, rotation and scale), refused
/// with the node and the property when an element is not finite: a NaN in a matrix was
/// reported only after the object's transform, as a coordinate outside the world.
fn node_transform(path: &Path, node: &gltf::Node) -> Result<Affine> {
    let bad = |property: String, v: f32| {
        Err(Error::at(
            path,
            node_place(node),
            format!("{property} is {v}; a transform must be finite"),
        ))
    };
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            for (k, v) in matrix.iter().flatten().enumerate() {
                if !v.is_finite() {
                    return bad(format!("matrix[{k}]"), *v);
                }
            }
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let parts: [(&str, &[f32]); 3] = [
                ("translation", &translation),
                ("rotation", &rotation),
                ("scale", &scale),
            ];
            for (name, values) in parts {
                if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                    return bad(format!("{name}[{i}]"), values[i]);
                }
            }
        }
    }
    let local = Affine::from_cols4(node.transform().matrix());
    if !local.m.iter().flatten().all(|v| v.is_finite()) || !local.t.is_finite() {
        return Err(Error::at(
            path,
            node_place(node),
            "its transform exceeds f64 (finite elements, an infinite product)",
        ));
    }
    Ok(local)
}

/// Loads all triangle meshes of a glTF file's default scene, node transforms applied.
pub fn load_gltf(path: &Path) -> Result<LocalMesh> {
    let bytes = luxest_io::fsio::read_bytes(path)?;
    load_gltf_bytes(path, &bytes)
}

/// One primitive (`mesh`, `primitive`) of a glTF file, in its mesh's frame (no node transform).
pub fn load_gltf_primitive(path: &Path, mesh: u32, primitive: u32) -> Result<LocalMesh> {
    let bytes = luxest_io::fsio::read_bytes(path)?;
    let file = open_gltf(path, &bytes)?;
    let place = format!("mesh {mesh} primitive {primitive}");
    let prim = file
        .document
        .meshes()
        .nth(mesh as usize)
        .and_then(|m| m.primitives().nth(primitive as usize))
        .ok_or_else(|| Error::at(path, &place, "the file has no such primitive"))?;
    let m = primitive_mesh(
        path,
        &file.buffers,
        mesh as usize,
        &prim,
        &Affine::IDENTITY,
        "the mesh",
    )?;
    if m.triangles.is_empty() {
        return Err(Error::at(path, place, "primitive has no triangles"));
    }
    Ok(m)
}

/// A parsed and checked glTF file with its buffers loaded.
pub struct GltfFile {
    pub document: gltf::Document,
    pub buffers: Vec<Vec<u8>>,
}

/// Parses a glTF file (`bytes`, named `path`; external buffers relative to it) and loads its
/// buffers, refusing what the gltf crate would panic on.
pub fn open_gltf(path: &Path, bytes: &[u8]) -> Result<GltfFile> {
    check_glb_header(path, bytes)?;
    let malformed = |e: gltf::Error| Error::input(path, format!("malformed glTF: {e}"));
    let raw = gltf::Gltf::from_slice_without_validation(bytes).map_err(malformed)?;
    check_accessor_indices(path, raw.document.as_json())?;
    let gltf = gltf::Gltf {
        document: gltf::Document::from_json(raw.document.into_json()).map_err(malformed)?,
        blob: raw.blob,
    };
    let base = path.parent().unwrap_or(Path::new("."));
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    for buffer in gltf.document.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => gltf.blob.clone().ok_or_else(|| {
                Error::input(
                    path,
                    "glTF refers to a binary chunk that the file does not have",
                )
            })?,
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let payload = uri.split_once(";base64,").map(|(_, d)| d);
                payload.and_then(decode_base64).ok_or_else(|| {
                    Error::at(
                        path,
                        format!("buffer {}", buffer.index()),
                        "malformed base64 data URI",
                    )
                })?
            }
            gltf::buffer::Source::Uri(uri) => {
                let file = base.join(uri);
                if let Some(kind) = luxest_io::fsio::non_file_kind(&file) {
                    // A FIFO would block the read forever, a device give nonsense.
                    return Err(Error::at(
                        path,
                        format!("buffer {}", buffer.index()),
                        format!("{} is {kind}, not a regular file", file.display()),
                    ));
                }
                std::fs::read(&file).map_err(|e| {
                    Error::at(
                        path,
                        format!("buffer {}", buffer.index()),
                        format!("{}: {e}", file.display()),
                    )
                })?
            }
        };
        if data.len() < buffer.length() {
            return Err(Error::at(
                path,
                format!("buffer {}", buffer.index()),
                format!(
                    "has {} bytes, the file declares {}",
                    data.len(),
                    buffer.length()
                ),
            ));
        }
        buffers.push(data);
    }
    Ok(GltfFile {
        document: gltf.document,
        buffers,
    })
}

/// Every node of the file's default scene (or its first) with its world transform, parents
/// before children; refuses cycles, nodes with two parents and non-finite transforms.
pub fn gltf_nodes<'a>(path: &Path, file: &'a GltfFile) -> Result<Vec<(gltf::Node<'a>, Affine)>> {
    let scene = file
        .document
        .default_scene()
        .or_else(|| file.document.scenes().next())
        .ok_or_else(|| Error::input(path, "glTF file has no scene"))?;
    let mut stack: Vec<(gltf::Node, Affine)> =
        scene.nodes().map(|n| (n, Affine::IDENTITY)).collect();
    // The node hierarchy must be a forest (glTF 2.0, 3.5.3): a node reached twice is a cycle
    // (0 -> 1 -> 0, or its own child) or a node with two parents, either of which would make
    // this walk endless or duplicate geometry.
    let mut visited = vec![false; file.document.nodes().count()];
    let mut out = Vec::new();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(Error::at(
                path,
                format!("node {}", node.index()),
                "is reached twice in the node hierarchy (a cycle, or a node with two parents)",
            ));
        }
        let world = parent.compose(&node_transform(path, &node)?);
        if !world.m.iter().flatten().all(|v| v.is_finite()) || !world.t.is_finite() {
            return Err(Error::at(
                path,
                node_place(&node),
                "its transform composed with its parents' exceeds f64 (each is finite, their \
                 product is not)",
            ));
        }
        for child in node.children() {
            stack.push((child, world));
        }
        out.push((node, world));
    }
    Ok(out)
}

/// One triangle primitive with the transform `world` applied (`frame` names it in messages).
pub fn primitive_mesh(
    path: &Path,
    buffers: &[Vec<u8>],
    mesh_index: usize,
    prim: &gltf::Primitive,
    world: &Affine,
    frame: &str,
) -> Result<LocalMesh> {
    let place = format!("mesh {mesh_index} primitive {}", prim.index());
    if prim.mode() != gltf::mesh::Mode::Triangles {
        return Err(Error::at(
            path,
            place,
            format!(
                "primitive mode {:?} is not supported (only triangles)",
                prim.mode()
            ),
        ));
    }
    for (semantic, accessor) in prim.attributes() {
        check_accessor(path, &place, &format!("{semantic:?}"), &accessor, buffers)?;
    }
    if let Some(indices) = prim.indices() {
        check_accessor(path, &place, "indices", &indices, buffers)?;
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| d.as_slice()));
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(|| Error::at(path, &place, "primitive has no POSITION attribute"))?
        .map(Vec3::from)
        .collect();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(Error::at(
            path,
            format!("{place} vertex {i}"),
            "non-finite coordinate",
        ));
    }
    let nv = positions.len() as u32;
    let indices: Vec<u32> = match reader.read_indices() {
        Some(ix) => ix.into_u32().collect(),
        None => (0..nv).collect(),
    };
    if !indices.len().is_multiple_of(3) || indices.iter().any(|&i| i >= nv) {
        return Err(Error::at(
            path,
            place,
            "index list is not a whole number of in-range triangles",
        ));
    }
    let normals = reader
        .read_normals()
        .map(|n| n.map(Vec3::from).collect::<Vec<_>>());
    let normals = normals.filter(|n| n.len() == positions.len());
    let uvs = reader
        .read_tex_coords(0)
        .map(|t| {
            t.into_f32()
                .map(|[u, v]| [u as f64, v as f64])
                .collect::<Vec<_>>()
        })
        .filter(|t| t.len() == positions.len());
    if let Some(i) = uvs.as_ref().and_then(|t| {
        t.iter()
            .position(|t| !(t[0].is_finite() && t[1].is_finite()))
    }) {
        return Err(Error::at(
            path,
            format!("{place} vertex {i}"),
            "non-finite TEXCOORD_0",
        ));
    }
    let det = world.determinant();
    let positions: Vec<Vec3> = positions
        .into_iter()
        .map(|p| world.apply_point(p))
        .collect();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(Error::at(
            path,
            format!("{place} vertex {i}"),
            format!("exceeds f64 after the transform of {frame}"),
        ));
    }
    let normals = normals.map(|n| {
        n.into_iter()
            .map(|v| world.apply_normal(v) * det.signum())
            .collect::<Vec<_>>()
    });
    let mut triangles: Vec<[u32; 3]> = indices
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    if det < 0.0 {
        triangles.iter_mut().for_each(|t| t.swap(1, 2));
    }
    Ok(LocalMesh {
        positions,
        normals,
        uvs,
        triangles,
    })
}

/// [`load_gltf`] of the file's content `bytes`; `path` names it in errors and locates external
/// buffers.
pub fn load_gltf_bytes(path: &Path, bytes: &[u8]) -> Result<LocalMesh> {
    let file = open_gltf(path, bytes)?;
    let mut mesh = LocalMesh {
        normals: Some(Vec::new()),
        ..Default::default()
    };
    for (node, world) in gltf_nodes(path, &file)? {
        let Some(gmesh) = node.mesh() else { continue };
        for prim in gmesh.primitives() {
            mesh.append(primitive_mesh(
                path,
                &file.buffers,
                gmesh.index(),
                &prim,
                &world,
                &node_place(&node),
            )?);
        }
    }
    if mesh.triangles.is_empty() {
        return Err(Error::input(path, "glTF scene contains no triangles"));
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_decodes_rfc4648_vectors() {
        for (enc, dec) in [
            ("", ""),
            ("Zg==", "f"),
            ("Zm8=", "fo"),
            ("Zm9v", "foo"),
            ("Zm9vYmFy", "foobar"),
        ] {
            assert_eq!(decode_base64(enc).unwrap(), dec.as_bytes());
        }
        assert!(decode_base64("Zm9v!").is_none());
        assert!(decode_base64("Z").is_none());
    }
}
