//! The OBJ+MTL importer: a Wavefront OBJ file and the MTL libraries it names (`mtllib`),
//! translated into an authored luxest scene with one object per MTL material the faces use
//! (`Shape::Obj` with `usemtl`).
//!
//! MTL has no physical model; the translation is stated here and in `docs/scene-format.md`:
//!
//! | MTL | luxest |
//! |---|---|
//! | `illum` 0, 1, or 2 with `Ks` 0 | `Lambertian(Kd)` |
//! | `illum` 2 with `Ks` > 0 | `Glossy(diffuse: Kd, specular: Ks, roughness: √α)`, α = √(2 / (Ns + 2)) (the Beckmann α of a Phong exponent, Walter et al. 2007, eq. 25); `Kd + Ks` must be ≤ 1 |
//! | `illum` 3, 5 or 8 with `Kd` 0 | `Mirror(Ks)` |
//! | `illum` 4, 6, 7 or 9 | `Dielectric(Ni)` |
//! | `Ke` > 0 | the material's objects emit `Radiance(Ke)`, cd/m² |
//!
//! | `map_Kd` | the surface's colour texture (multiplying `Kd`) |
//! | `d` < 1, `Tr` > 0, `map_d` | a stochastic cut-out of opacity `d` (× the `map_d` texture) |
//!
//! Textures are looked up with texture coordinates `vt` (v flipped, as Mitsuba 3's OBJ loader
//! does), wrapping, bilinear. `Ka`, `Tf` and `sharpness` have no meaning for a physically based
//! renderer and are left out with a warning; texture options and every other statement are
//! errors naming the MTL file and line.

use crate::import::{scene_relative, Imported};
use luxest_io::color::Rgb;
use luxest_io::{Error, Result};
use luxest_render::scene::OpacityChannel;
use luxest_render::scene::{
    Emission, Material, Object, Opacity, Shape, Surface, TextureDesc, Transform,
};
use luxest_render::texture::{Filter, Wrap};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// One `newmtl` block as read.
#[derive(Clone, Debug)]
struct Mtl {
    file: PathBuf,
    line: usize,
    kd: Rgb,
    ks: Rgb,
    ke: Rgb,
    ns: f64,
    ni: f64,
    d: f64,
    illum: i64,
    /// `map_Kd` and `map_d`: the file name and the statement's line.
    map_kd: Option<(String, usize)>,
    map_d: Option<(String, usize)>,
}

fn rgb_of(words: &[&str]) -> Option<Rgb> {
    let v: Vec<f64> = words
        .iter()
        .map(|w| w.parse().ok())
        .collect::<Option<_>>()?;
    match v.as_slice() {
        [a] => Some(Rgb::splat(*a)),
        [a, b, c] => Some(Rgb([*a, *b, *c])),
        _ => None,
    }
}

/// Reads an MTL library into `out`; warnings for what it leaves out.
fn read_mtl(
    path: &Path,
    out: &mut BTreeMap<String, Mtl>,
    warnings: &mut Vec<String>,
) -> Result<()> {
    let bytes = luxest_io::fsio::read_bytes(path)?;
    let text = std::str::from_utf8(&bytes)
        .map_err(|_| Error::input(path, "malformed MTL: not UTF-8 text"))?;
    let mut current: Option<String> = None;
    let mut ignored = BTreeSet::new();
    for (n, line) in text.lines().enumerate() {
        let n = n + 1;
        let place = format!("line {n}");
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some((&key, args)) = words.split_first() else {
            continue;
        };
        if key.starts_with('#') {
            continue;
        }
        if key == "newmtl" {
            let name = line.trim()["newmtl".len()..].trim().to_string();
            if out.contains_key(&name) {
                return Err(Error::at(
                    path,
                    place,
                    format!("material \"{name}\" defined twice"),
                ));
            }
            out.insert(
                name.clone(),
                Mtl {
                    file: path.to_path_buf(),
                    line: n,
                    kd: Rgb::splat(0.0),
                    ks: Rgb::splat(0.0),
                    ke: Rgb::splat(0.0),
                    ns: 0.0,
                    ni: 1.0,
                    d: 1.0,
                    illum: 2,
                    map_kd: None,
                    map_d: None,
                },
            );
            current = Some(name);
            continue;
        }
        let Some(m) = current.as_ref().and_then(|c| out.get_mut(c)) else {
            return Err(Error::at(
                path,
                place,
                format!("\"{key}\" before any newmtl"),
            ));
        };
        let bad = |what: &str| Error::at(path, format!("line {n}"), format!("{key}: {what}"));
        let number = || -> Result<f64> {
            match args {
                [v] => v
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| bad("not a finite number")),
                _ => Err(bad("expects one number")),
            }
        };
        match key {
            "Kd" | "Ks" | "Ke" => {
                let c = rgb_of(args)
                    .filter(|c| c.is_finite() && c.min_component() >= 0.0)
                    .ok_or_else(|| bad("expects one or three non-negative numbers"))?;
                match key {
                    "Kd" => m.kd = c,
                    "Ks" => m.ks = c,
                    _ => m.ke = c,
                }
            }
            "Ns" => m.ns = number()?,
            "Ni" => m.ni = number()?,
            "d" => m.d = number()?,
            "Tr" => m.d = 1.0 - number()?,
            "illum" => {
                m.illum = number()? as i64;
            }
            "map_Kd" | "map_d" => {
                // Options (-s, -o, -clamp, -bm, …) would change the lookup: refused.
                let file = match args {
                    [f] if !f.starts_with('-') => f.to_string(),
                    _ => {
                        return Err(bad(
                            "expects a file name alone (texture options are not supported)",
                        ))
                    }
                };
                if key == "map_Kd" {
                    m.map_kd = Some((file, n));
                } else {
                    m.map_d = Some((file, n));
                }
            }
            "Ka" | "Tf" | "sharpness" => {
                if ignored.insert(key) {
                    warnings.push(format!(
                        "{}: line {n}: {key} ignored (no meaning for a physically based renderer)",
                        path.display()
                    ));
                }
            }
            "bump" | "map_Bump" | "map_bump" | "norm" | "map_Kn" => {
                // The MTL specification's `bump` is a height map, yet exporters write tangent-
                // space normal maps under it and under `norm`, in either y convention (OpenGL
                // or DirectX): which one a file means cannot be told from it.
                return Err(Error::at(
                    path,
                    place,
                    format!(
                        "MTL statement \"{key}\" is ambiguous (a height map or a normal map, y \
                         up or down) and is not imported: give the scene's `normal` map in RON"
                    ),
                ));
            }
            _ => {
                return Err(Error::at(
                    path,
                    place,
                    format!("MTL statement \"{key}\" is not supported"),
                ))
            }
        }
    }
    Ok(())
}

/// The luxest material of an MTL material, with its surface (textures, transparency) when it
/// has one; `textures` collects the textures it uses.
fn material(
    name: &str,
    m: &Mtl,
    scene_file: &Path,
    textures: &mut BTreeMap<String, TextureDesc>,
) -> Result<(Material, Option<Surface>)> {
    let at = |msg: String| Error::at(&m.file, format!("line {} (newmtl {name})", m.line), msg);
    let mut texture = |map: &Option<(String, usize)>| -> Result<Option<String>> {
        let Some((file, line)) = map else {
            return Ok(None);
        };
        let full = m.file.parent().unwrap_or(Path::new(".")).join(file);
        if !full.is_file() {
            return Err(Error::at(
                &m.file,
                format!("line {line}"),
                format!("texture {} not found", full.display()),
            ));
        }
        let path = scene_relative(&full, scene_file);
        textures.entry(path.clone()).or_insert(TextureDesc {
            checkerboard: None,
            path: path.clone(),
            encoding: None,
            wrap: Wrap::Repeat,
            filter: Filter::Bilinear,
            uv_transform: None,
        });
        Ok(Some(path))
    };
    let color = texture(&m.map_kd)?;
    let opacity_texture = texture(&m.map_d)?;
    let glass = matches!(m.illum, 4 | 6 | 7 | 9);
    if !(0.0..=1.0).contains(&m.d) {
        return Err(at(format!("d = {} is outside [0, 1]", m.d)));
    }
    // Transparency (d < 1 or map_d) of an opaque model: a stochastic cut-out of opacity d.
    let transparent = !glass && (m.d < 1.0 || opacity_texture.is_some());
    let opacity = transparent.then_some(Opacity {
        texture: opacity_texture,
        // MTL's map_d is a scalar map: its alpha where it has one, else its grey level.
        channel: OpacityChannel::Auto,
        value: m.d,
        cutoff: None,
    });
    let zero = |c: Rgb| c.max_component() == 0.0;
    let model = match m.illum {
        0 | 1 => Material::Lambertian { reflectance: m.kd },
        2 if zero(m.ks) => Material::Lambertian { reflectance: m.kd },
        2 => {
            if let Some(c) = (0..3).find(|&c| m.kd.0[c] + m.ks.0[c] > 1.0) {
                return Err(at(format!(
                    "Kd + Ks = {} in channel {c} exceeds 1: luxest's Glossy (diffuse + \
                     specular) would create energy; scale them down",
                    m.kd.0[c] + m.ks.0[c]
                )));
            }
            let alpha = (2.0 / (m.ns.max(0.0) + 2.0)).sqrt();
            Material::Glossy {
                diffuse: m.kd,
                specular: m.ks,
                roughness: alpha.sqrt(),
            }
        }
        3 | 5 | 8 if zero(m.kd) => Material::Mirror { reflectance: m.ks },
        3 | 5 | 8 => {
            return Err(at(format!(
                "illum {} with a diffuse Kd is not supported (a mirror has Kd 0)",
                m.illum
            )))
        }
        _ if glass => {
            if color.is_some() {
                return Err(at(
                    "map_Kd on glass (illum 4, 6, 7, 9) is not supported".into()
                ));
            }
            Material::Dielectric { ior: m.ni }
        }
        other => return Err(at(format!("illum {other} is not supported"))),
    };
    let textured = color.is_some() || opacity.is_some();
    let surface = textured.then_some(Surface {
        color,
        roughness: None,
        opacity,
        normal: None,
        normal_scale: [1.0, 1.0],
        two_sided: true,
    });
    Ok((model, surface))
}

/// Translates the OBJ file `path` and its MTL libraries.
pub fn import(path: &Path) -> Result<Imported> {
    let bytes = luxest_io::fsio::read_bytes(path)?;
    let text = String::from_utf8_lossy(&bytes);
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut warnings = Vec::new();
    let mut mtls = BTreeMap::new();
    let mut used: Vec<String> = Vec::new();
    let mut current: Option<String> = None;
    for (n, line) in text.lines().enumerate() {
        let n = n + 1;
        let mut words = line.split_whitespace();
        match words.next() {
            Some("mtllib") => {
                for lib in words {
                    let full = dir.join(lib);
                    if !full.is_file() {
                        return Err(Error::at(
                            path,
                            format!("line {n}"),
                            format!("MTL library {} not found", full.display()),
                        ));
                    }
                    read_mtl(&full, &mut mtls, &mut warnings)?;
                }
            }
            Some("usemtl") => current = Some(line.trim()["usemtl".len()..].trim().to_string()),
            Some("f") => match &current {
                None => {
                    return Err(Error::at(
                        path,
                        format!("line {n}"),
                        "a face before any usemtl has no material",
                    ))
                }
                Some(m) if !used.contains(m) => {
                    if !mtls.contains_key(m) {
                        return Err(Error::at(
                            path,
                            format!("line {n}"),
                            format!("usemtl \"{m}\": no MTL library defines it"),
                        ));
                    }
                    used.push(m.clone());
                }
                Some(_) => {}
            },
            _ => {}
        }
    }
    if used.is_empty() {
        return Err(Error::input(path, "the OBJ file has no faces"));
    }
    let file = scene_relative(path, path);
    let mut scene = super::empty_scene();
    for name in &used {
        let m = &mtls[name];
        let (model, surface) = material(name, m, path, &mut scene.textures)?;
        scene.materials.insert(name.clone(), model);
        if let Some(surface) = surface {
            scene.surfaces.insert(name.clone(), surface);
        }
        scene.objects.push(Object {
            name: Some(name.clone()),
            shape: Shape::Obj {
                path: file.clone(),
                usemtl: Some(name.clone()),
            },
            transform: Transform::default(),
            material: name.clone(),
            emission: (m.ke.max_component() > 0.0).then_some(Emission::Radiance(m.ke)),
            flip_normals: false,
            face_normals: false,
            compute_normals: false,
        });
    }
    Ok(Imported { scene, warnings })
}
