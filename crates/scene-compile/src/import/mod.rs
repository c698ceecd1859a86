//! Whole scenes in other formats, translated into an authored luxest scene
//! ([`luxest_render::scene::Scene`]) that then compiles exactly as a RON scene does: Mitsuba 3
//! XML ([`mitsuba_xml`]), glTF 2.0 ([`gltf_scene`]) and Wavefront OBJ with its MTL materials
//! ([`obj_scene`]). [`read_scene`] picks the reader by the file's extension.
//!
//! A translation refers to mesh and texture files by paths relative to the source file's
//! directory, as a RON scene in that directory would; [`export_ron`] writes it out (the
//! `--export-ron` option) with the paths made relative to where it is written, so that the
//! exported RON compiles to the same scene and can be edited.
//!
//! What an importer cannot represent faithfully is an error naming the file, the line (or the
//! glTF/MTL place) and the element, never a silent substitute; what it leaves out because it
//! does not change the image (a Mitsuba integrator, an MTL ambient colour) is a warning.
//!
//! Modules: [`mitsuba_xml`], [`mitsuba_tables`] (Mitsuba's named IORs and conductor presets),
//! [`gltf_scene`], [`obj_scene`].

pub mod gltf_scene;
pub mod mitsuba_tables;
pub mod mitsuba_xml;
pub mod obj_scene;

use luxest_io::{Error, Result};
use luxest_render::scene::{Scene, Shape};
use std::path::{Component, Path, PathBuf};

/// A scene read from a file, with what the reader left out.
#[derive(Clone, Debug)]
pub struct Imported {
    pub scene: Scene,
    /// One line each, naming the file and the place.
    pub warnings: Vec<String>,
}

/// The formats [`read_scene`] reads, by extension (case-insensitive).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceFormat {
    Ron,
    MitsubaXml,
    Gltf,
    Obj,
}

impl SourceFormat {
    /// The format of `path` by its extension; `None` for any other.
    pub fn of(path: &Path) -> Option<SourceFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "ron" => SourceFormat::Ron,
            "xml" => SourceFormat::MitsubaXml,
            "gltf" | "glb" => SourceFormat::Gltf,
            "obj" => SourceFormat::Obj,
            _ => return None,
        })
    }
}

/// Reads a scene file: RON as authored, or a Mitsuba 3 (`.xml`), glTF (`.gltf`, `.glb`) or
/// OBJ (`.obj`) scene translated.
pub fn read_scene(path: &Path) -> Result<Imported> {
    read_scene_with(path, &[])
}

/// [`read_scene`] with Mitsuba parameters (`-D name=value`); other formats refuse them.
pub fn read_scene_with(path: &Path, defines: &[(String, String)]) -> Result<Imported> {
    let format = SourceFormat::of(path).ok_or_else(|| {
        Error::input(
            path,
            "unknown scene format: the extension must be .ron (luxest), .xml (Mitsuba 3), \
             .gltf or .glb (glTF 2.0) or .obj (Wavefront OBJ with MTL)",
        )
    })?;
    if !defines.is_empty() && format != SourceFormat::MitsubaXml {
        return Err(Error::Usage(
            "-D/--define gives parameters of a Mitsuba 3 scene (.xml) only".into(),
        ));
    }
    match format {
        SourceFormat::Ron => Ok(Imported {
            scene: luxest_io::fsio::read_ron(path)?,
            warnings: Vec::new(),
        }),
        SourceFormat::MitsubaXml => mitsuba_xml::import_with(path, defines),
        SourceFormat::Gltf => gltf_scene::import(path),
        SourceFormat::Obj => obj_scene::import(path),
    }
}

/// A scene with nothing in it, for an importer to fill.
pub(crate) fn empty_scene() -> Scene {
    Scene {
        name: None,
        camera: None,
        materials: Default::default(),
        objects: Vec::new(),
        point_lights: Vec::new(),
        sensors: Vec::new(),
        luminaires: Vec::new(),
        calculation_surfaces: Vec::new(),
        textures: Default::default(),
        surfaces: Default::default(),
        environment: None,
        windows: Vec::new(),
        portals: Vec::new(),
        observers: Vec::new(),
    }
}

/// `target` relative to the directory `base`, both made absolute against the working
/// directory first (`..` where they part); `target` itself when they share no root.
pub fn relative_path(target: &Path, base: &Path) -> PathBuf {
    let absolute = |p: &Path| -> PathBuf {
        let p = if p.is_absolute() {
            p.to_path_buf()
        } else {
            std::env::current_dir().unwrap_or_default().join(p)
        };
        // Lexical normalisation: `a/./b/../c` is `a/c`.
        let mut out = PathBuf::new();
        for c in p.components() {
            match c {
                Component::CurDir => {}
                Component::ParentDir => {
                    out.pop();
                }
                other => out.push(other),
            }
        }
        out
    };
    let (t, b) = (absolute(target), absolute(base));
    let (tc, bc): (Vec<_>, Vec<_>) = (t.components().collect(), b.components().collect());
    let common = tc.iter().zip(&bc).take_while(|(x, y)| x == y).count();
    if common == 0 {
        return t;
    }
    let mut out = PathBuf::new();
    for _ in common..bc.len() {
        out.push("..");
    }
    for c in &tc[common..] {
        out.push(c);
    }
    out
}

/// The path text a scene stores for a file `full` (as found on disk) when the scene file is
/// `scene_file`: relative to the scene file's directory, `/`-separated.
pub fn scene_relative(full: &Path, scene_file: &Path) -> String {
    let dir = scene_file.parent().unwrap_or(Path::new("."));
    relative_path(full, dir)
        .to_string_lossy()
        .replace(std::path::MAIN_SEPARATOR, "/")
}

/// The scene `scene`, read from `source`, as RON to be written at `out`: every file path
/// rewritten relative to `out`'s directory.
pub fn export_ron(scene: &Scene, source: &Path, out: &Path) -> String {
    let src_dir = source.parent().unwrap_or(Path::new("."));
    let rebase = |p: &str| scene_relative(&src_dir.join(p), out);
    let mut s = scene.clone();
    for o in &mut s.objects {
        match &mut o.shape {
            Shape::Obj { path, .. }
            | Shape::Gltf { path, .. }
            | Shape::Ply { path }
            | Shape::Serialized { path, .. } => *path = rebase(path),
            _ => {}
        }
    }
    for l in &mut s.luminaires {
        l.file = rebase(&l.file);
    }
    if let Some(luxest_render::scene::Environment::Map { path, .. }) = &mut s.environment {
        *path = rebase(path);
    }
    for t in s.textures.values_mut() {
        t.path = rebase(&t.path);
    }
    format!(
        "// Translated by scene-compile {} from {}\n{}\n",
        env!("CARGO_PKG_VERSION"),
        source.display(),
        luxest_io::fsio::to_ron_string(&s)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_climb_and_descend() {
        assert_eq!(
            relative_path(Path::new("/a/b/m.obj"), Path::new("/a/c")),
            PathBuf::from("../b/m.obj")
        );
        assert_eq!(
            relative_path(Path::new("/a/b/./m.obj"), Path::new("/a/b")),
            PathBuf::from("m.obj")
        );
        assert_eq!(
            scene_relative(Path::new("/s/meshes/x.ply"), Path::new("/s/scene.xml")),
            "meshes/x.ply"
        );
    }
}
