//! Textures and surfaces of an authored scene: their validation, loading the image files the
//! scene names, and the compiled per-material [`CompiledSurface`] table.

use crate::validate::Check;
use luxest_io::color::Rgb;
use luxest_io::num::show;
use luxest_io::texture_image::{ImageFormat, Samples, TextureImage};
use luxest_io::Error;
use luxest_io::Result;
use luxest_render::compiled::{CompiledOpacity, CompiledSurface, TextureInfo};
use luxest_render::sampling::uniform_triangle;
use luxest_render::scene::{Emission, Material, Scene, Surface, TextureDesc};
use luxest_render::texture::{Filter, Texture, TextureOptions, Wrap};
use std::collections::BTreeMap;
use std::path::Path;

/// Checks the `textures` and `surfaces` tables: every surface belongs to a material, every
/// texture named exists, opacities and cut-offs lie in [0, 1].
pub(crate) fn check(c: &Check, scene: &Scene) -> Result<()> {
    for (name, t) in &scene.textures {
        match (&t.checkerboard, t.path.is_empty()) {
            (None, true) => {
                return Err(c.fail(
                    &format!("textures[\"{name}\"]"),
                    "needs a path (or a checkerboard)",
                ))
            }
            (Some(_), false) => {
                return Err(c.fail(
                    &format!("textures[\"{name}\"]"),
                    "has both a path and a checkerboard",
                ))
            }
            (Some(colors), true) => {
                for (k, color) in colors.iter().enumerate() {
                    c.rgb_in(
                        &format!("textures[\"{name}\"].checkerboard[{k}]"),
                        *color,
                        0.0,
                        f64::MAX,
                        "checkerboard colour",
                    )?;
                }
            }
            (None, false) => {}
        }
        if let Some(m) = &t.uv_transform {
            if !m.0.iter().flatten().all(|v| v.is_finite()) {
                return Err(c.fail(
                    &format!("textures[\"{name}\"].uv_transform"),
                    "has a non-finite entry",
                ));
            }
        }
    }
    for (material, s) in &scene.surfaces {
        let place = format!("surfaces[\"{material}\"]");
        if !scene.materials.contains_key(material) {
            return Err(c.fail(&place, format!("no material is named \"{material}\"")));
        }
        for (field, t) in [
            ("color", &s.color),
            ("roughness", &s.roughness),
            ("normal", &s.normal),
        ] {
            if let Some(t) = t {
                c.texture_name(scene, &format!("{place}.{field}"), t)?;
            }
        }
        if s.roughness.is_some() {
            let m = &scene.materials[material];
            if !roughness_texturable(m) {
                return Err(c.fail(
                    &format!("{place}.roughness"),
                    format!(
                        "material \"{material}\" ({:?}) has no microfacet roughness a texture \
                         can scale (Glossy, rough Conductor and RoughDielectric have; a Plastic's \
                         coating is precomputed for its one α)",
                        m.kind()
                    ),
                ));
            }
        }
        if let Some(o) = &s.opacity {
            if let Some(t) = &o.texture {
                c.texture_name(scene, &format!("{place}.opacity.texture"), t)?;
            }
            for (field, v) in [("value", Some(o.value)), ("cutoff", o.cutoff)] {
                if let Some(v) = v {
                    if !(0.0..=1.0).contains(&v) {
                        return Err(c.fail(
                            &format!("{place}.opacity.{field}"),
                            format!("must lie in [0, 1], got {}", show(v)),
                        ));
                    }
                }
            }
        }
    }
    Ok(())
}

/// Whether a roughness texture can scale the material's α (recursively for blends: either
/// member).
fn roughness_texturable(m: &Material) -> bool {
    match m {
        Material::Glossy { .. }
        | Material::RoughDielectric { .. }
        | Material::Conductor {
            roughness: Some(_), ..
        } => true,
        Material::Blend { first, second, .. } => {
            roughness_texturable(first) || roughness_texturable(second)
        }
        _ => false,
    }
}

/// The textures a scene uses, loaded: their table entries, their pixels, and their indices by
/// name. Textures no surface or emission names are left out (and reported in `warnings`).
pub struct Loaded {
    pub infos: Vec<TextureInfo>,
    pub textures: Vec<Texture>,
    pub index: BTreeMap<String, u32>,
}

/// Texture names a surface or an emission refers to.
fn referenced(scene: &Scene) -> std::collections::BTreeSet<&str> {
    let surfaces = scene.surfaces.values().flat_map(|s| {
        [
            s.color.as_deref(),
            s.roughness.as_deref(),
            s.normal.as_deref(),
            s.opacity.as_ref().and_then(|o| o.texture.as_deref()),
        ]
    });
    let emissions = scene.objects.iter().map(|o| match &o.emission {
        Some(Emission::Texture { texture, .. }) => Some(texture.as_str()),
        _ => None,
    });
    surfaces.chain(emissions).flatten().collect()
}

/// Loads every texture the scene refers to.
pub fn load(path: &Path, scene: &Scene, warnings: &mut Vec<String>) -> Result<Loaded> {
    let used = referenced(scene);
    let mut loaded = Loaded {
        infos: Vec::new(),
        textures: Vec::new(),
        index: BTreeMap::new(),
    };
    for (name, desc) in &scene.textures {
        if !used.contains(name.as_str()) {
            warnings.push(format!("{}: textures[\"{name}\"]: unused", path.display()));
            continue;
        }
        let texture = match &desc.checkerboard {
            Some(colors) => checkerboard(colors, desc)
                .map_err(|m| Error::at(path, format!("textures[\"{name}\"]"), m))?,
            None => {
                let place = format!("textures[\"{name}\"].path");
                let file = crate::resolve_file(path, &place, &desc.path, "texture")?;
                load_one(&file, desc)?
            }
        };
        loaded
            .index
            .insert(name.clone(), loaded.textures.len() as u32);
        loaded.infos.push(TextureInfo {
            name: name.clone(),
            source: if desc.checkerboard.is_some() {
                "checkerboard".into()
            } else {
                desc.path.clone()
            },
            width: texture.width() as u32,
            height: texture.height() as u32,
        });
        loaded.textures.push(texture);
    }
    Ok(loaded)
}

/// One texture file, decoded with the scene's options (sRGB for 8-bit formats and linear for
/// EXR unless the scene says otherwise).
fn load_one(file: &Path, desc: &TextureDesc) -> Result<Texture> {
    let options = TextureOptions {
        encoding: desc.encoding,
        wrap: desc.wrap,
        filter: desc.filter,
        uv_transform: desc.uv_transform.unwrap_or_default(),
    };
    Texture::load(file, &options)
}

/// Mitsuba 3's `checkerboard` as a texture: 2 × 2 texels (first, second; second, first) looked
/// up by the nearest texel and repeated, which is the checkerboard exactly (each half of the
/// unit interval is one texel; Mitsuba's `uv − ⌊uv⌋ > ½` and the nearest texel differ only on
/// the lines u, v = ½).
fn checkerboard(colors: &[Rgb; 2], desc: &TextureDesc) -> std::result::Result<Texture, String> {
    let [a, b] = colors.map(|c| c.0.map(|v| v as f32));
    let samples = [a, b, b, a].concat();
    let image = TextureImage {
        width: 2,
        height: 2,
        channels: 3,
        samples: Samples::F32(samples),
        format: ImageFormat::Exr,
    };
    let options = TextureOptions {
        encoding: None,
        wrap: Wrap::Repeat,
        filter: Filter::Nearest,
        uv_transform: desc.uv_transform.unwrap_or_default(),
    };
    Texture::from_image(&image, &options)
}

/// The compiled surface of every material, in the materials' order; empty when no material
/// has a `surfaces` entry.
pub fn surfaces(scene: &Scene, loaded: &Loaded) -> Vec<CompiledSurface> {
    if scene.surfaces.is_empty() {
        return Vec::new();
    }
    let tex = |t: &Option<String>| t.as_ref().map(|n| loaded.index[n]);
    scene
        .materials
        .keys()
        .map(|m| match scene.surfaces.get(m) {
            None => CompiledSurface {
                color: None,
                roughness: None,
                opacity: None,
                normal: None,
                normal_scale: [1.0, 1.0],
                two_sided: true,
            },
            Some(s) => compile_surface(s, &tex),
        })
        .collect()
}

fn compile_surface(s: &Surface, tex: &dyn Fn(&Option<String>) -> Option<u32>) -> CompiledSurface {
    CompiledSurface {
        color: tex(&s.color),
        roughness: tex(&s.roughness),
        opacity: s.opacity.as_ref().map(|o| CompiledOpacity {
            texture: tex(&o.texture),
            channel: o.channel,
            value: o.value,
            cutoff: o.cutoff,
        }),
        normal: tex(&s.normal),
        normal_scale: s.normal_scale,
        two_sided: s.two_sided,
    }
}

/// Sample points per side of the unit square mapped onto a triangle when averaging an emitter's texture
/// (`STRATA²` points per triangle, at most [`MAX_LOOKUPS`] lookups per emitter).
const STRATA: usize = 8;
const MAX_LOOKUPS: usize = 1 << 22;

/// The mean of `texture` over triangles (corner texture coordinates, area), weighted by area:
/// a textured emitter's luminance factor averaged over its surface, for its flux. Each
/// triangle is sampled on a stratified grid of barycentric points (fewer when there are
/// millions of triangles); the emitter's flux only weighs it among the emitters, the estimators
/// stay unbiased with any weight.
pub fn mean_over(texture: &Texture, triangles: &[([[f64; 2]; 3], f64)]) -> Rgb {
    let strata = STRATA
        .min(((MAX_LOOKUPS / triangles.len().max(1)) as f64).sqrt() as usize)
        .max(1);
    let (mut sum, mut area) = (Rgb::BLACK, 0.0);
    for (uv, a) in triangles {
        let mut s = Rgb::BLACK;
        for i in 0..strata {
            for j in 0..strata {
                // The unit square's cell centre, mapped to the triangle preserving area.
                let (b1, b2) = uniform_triangle(
                    (i as f64 + 0.5) / strata as f64,
                    (j as f64 + 0.5) / strata as f64,
                );
                let w = 1.0 - b1 - b2;
                let p = [
                    uv[0][0] * w + uv[1][0] * b1 + uv[2][0] * b2,
                    uv[0][1] * w + uv[1][1] * b1 + uv[2][1] * b2,
                ];
                let [r, g, b, _] = texture.eval(p, 0.0);
                s = s + Rgb([r as f64, g as f64, b as f64]);
            }
        }
        sum = sum + s * (a / (strata * strata) as f64);
        area += a;
    }
    if area > 0.0 {
        sum * (1.0 / area)
    } else {
        Rgb::BLACK
    }
}
