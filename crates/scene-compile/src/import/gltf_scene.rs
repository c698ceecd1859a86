//! The glTF 2.0 importer: a `.gltf` or `.glb` file's default scene translated into an authored
//! luxest scene — one object per triangle primitive (`Shape::Gltf` with `primitive`, the
//! node's world transform as the object's matrix), a material per glTF material, the first
//! perspective camera and the point lights of `KHR_lights_punctual`.
//!
//! Materials (PBR metallic-roughness; glTF's α is roughness², GGX):
//!
//! | glTF | luxest |
//! |---|---|
//! | `metallicFactor` 0 | `Plastic(diffuse_reflectance: baseColorFactor, ior: 1.5, roughness: GGX α = roughness²)` (glTF's dielectric: F0 = 0.04 over a diffuse base; smooth at roughness 0) |
//! | `metallicFactor` 1, roughness > 0 | `Glossy(diffuse: 0, specular: baseColorFactor, roughness: roughnessFactor)` (GGX with α = roughness², F = baseColor at every angle in place of Schlick's) |
//! | `metallicFactor` 1, roughness 0 | `Mirror(baseColorFactor)` |
//! | `metallicFactor` m in (0, 1) | `Blend(weight: m, first: the dielectric, second: the metal)` |
//! | `emissiveFactor` × `KHR_materials_emissive_strength` | `Radiance`, cd/m² |
//! | `baseColorTexture` | the surface's colour texture (multiplying baseColor) |
//! | `normalTexture` (`scale` s) | the surface's normal map (linear), `normal_scale` (s, −s) |
//! | `emissiveTexture` | `Emission::Texture` scaled by the emissive factor |
//! | `alphaMode` `MASK` / `BLEND` | a cut-out of opacity baseColor alpha × the texture's alpha, at `alphaCutoff` / stochastic |
//!
//! Textures are external image files (embedded images are errors), `TEXCOORD_0` only, with the
//! sampler's wrap mode (the same along s and t) and magnification filter.
//! `metallicRoughnessTexture` and a camera other than perspective are errors; extensions
//! the importer does not read are named in a warning (an error when the file requires them).
//! `doubleSided` is not used: a single-sided glTF material means back faces are culled, which
//! a closed mesh never shows, and luxest shades both sides. A camera's image is 720 pixels high
//! with the camera's aspect ratio (glTF gives none; 16:9 without one).

use crate::import::{scene_relative, Imported};
use crate::meshes::{gltf_nodes, open_gltf};
use luxest_io::color::Rgb;
use luxest_io::math::{Affine, Vec3};
use luxest_io::{Error, Result};
use luxest_render::scene::OpacityChannel;
use luxest_render::scene::{
    Camera, Emission, Material, Microfacet, MicrofacetDistribution, Object, Opacity, PointLight,
    PointPower, Shape, Surface, TextureDesc, Transform,
};
use luxest_render::texture::{Encoding, Filter, Wrap};
use std::collections::BTreeMap;
use std::path::Path;

/// Image height of an imported glTF camera, pixels.
pub const CAMERA_HEIGHT: u32 = 720;

/// The extensions this importer reads.
const SUPPORTED_EXTENSIONS: [&str; 2] = ["KHR_lights_punctual", "KHR_materials_emissive_strength"];

fn material_place(m: &gltf::Material) -> String {
    match (m.index(), m.name()) {
        (Some(i), Some(n)) => format!("material {i} ({n:?})"),
        (Some(i), None) => format!("material {i}"),
        (None, _) => "the default material".into(),
    }
}

/// The texture a glTF texture reference names, registered in `textures` on first use; its
/// name. Only external image files (a URI, not a data URI or a buffer view) can be referred to.
fn texture(
    path: &Path,
    place: &str,
    which: &str,
    tex: gltf::Texture,
    tex_coord: u32,
    encoding: Option<Encoding>,
    textures: &mut BTreeMap<String, TextureDesc>,
) -> Result<String> {
    let fail = |msg: String| Error::at(path, place, format!("{which}: {msg}"));
    if tex_coord != 0 {
        return Err(fail(format!(
            "TEXCOORD_{tex_coord} is not supported (only TEXCOORD_0)"
        )));
    }
    let uri = match tex.source().source() {
        gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => uri,
        _ => {
            return Err(fail(
                "images embedded in the file are not supported (only external image files)".into(),
            ))
        }
    };
    let full = path.parent().unwrap_or(Path::new(".")).join(uri);
    if !full.is_file() {
        return Err(fail(format!("image {} not found", full.display())));
    }
    let sampler = tex.sampler();
    use gltf::texture::WrappingMode;
    let wrap = |m: WrappingMode| match m {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::MirroredRepeat => Wrap::Mirror,
        WrappingMode::ClampToEdge => Wrap::Clamp,
    };
    let (ws, wt) = (wrap(sampler.wrap_s()), wrap(sampler.wrap_t()));
    if ws != wt {
        return Err(fail(format!(
            "different wrap modes along s and t ({ws:?}, {wt:?}) are not supported"
        )));
    }
    let filter = match sampler.mag_filter() {
        Some(gltf::texture::MagFilter::Nearest) => Filter::Nearest,
        _ => Filter::Bilinear,
    };
    let desc = TextureDesc {
        checkerboard: None,
        path: scene_relative(&full, path),
        encoding,
        wrap: ws,
        filter,
        uv_transform: None,
    };
    let mut name = desc.path.clone();
    loop {
        match textures.get(&name) {
            Some(d) if *d == desc => return Ok(name),
            Some(_) => name.push('\''),
            None => break,
        }
    }
    textures.insert(name.clone(), desc);
    Ok(name)
}

/// The luxest material, surface and emission of a glTF material.
fn material(
    path: &Path,
    m: &gltf::Material,
    warnings: &mut Vec<String>,
    textures: &mut BTreeMap<String, TextureDesc>,
) -> Result<(Material, Option<Surface>, Option<Emission>)> {
    let place = material_place(m);
    let fail = |msg: String| Error::at(path, &place, msg);
    let pbr = m.pbr_metallic_roughness();
    if pbr.metallic_roughness_texture().is_some() {
        return Err(fail(
            "metallicRoughnessTexture is not supported (luxest's roughness texture reads the \
             first channel; glTF's roughness is the second)"
                .into(),
        ));
    }
    if m.occlusion_texture().is_some() {
        warnings.push(format!(
            "{}: {place}: occlusionTexture ignored (a path tracer computes occlusion)",
            path.display()
        ));
    }
    let color = match pbr.base_color_texture() {
        Some(info) => Some(texture(
            path,
            &place,
            "baseColorTexture",
            info.texture(),
            info.tex_coord(),
            None,
            textures,
        )?),
        None => None,
    };
    let mut normal_scale = [1.0, 1.0];
    let normal = match m.normal_texture() {
        Some(n) => {
            let scale = n.scale() as f64;
            if !scale.is_finite() {
                return Err(fail(format!("normalTexture scale {scale} is not finite")));
            }
            // glTF's tangent-space y points towards decreasing v; luxest's (Mitsuba's) y is
            // normal × ∂p/∂u, towards increasing v where the mapping is not mirrored.
            normal_scale = [scale, -scale];
            Some(texture(
                path,
                &place,
                "normalTexture",
                n.texture(),
                n.tex_coord(),
                Some(Encoding::Linear),
                textures,
            )?)
        }
        None => None,
    };
    let [r, g, b, alpha] = pbr.base_color_factor();
    // MASK: opaque where base colour alpha × the texture's alpha reaches the cutoff; BLEND:
    // a stochastic cut-out of that opacity.
    let opacity = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => None,
        mode => Some(Opacity {
            texture: color.clone(),
            channel: OpacityChannel::Alpha,
            value: alpha as f64,
            cutoff: (mode == gltf::material::AlphaMode::Mask)
                .then(|| m.alpha_cutoff().unwrap_or(0.5) as f64),
        }),
    };
    let base = Rgb([r as f64, g as f64, b as f64]);
    let metallic = pbr.metallic_factor() as f64;
    let roughness = pbr.roughness_factor() as f64;
    if !(0.0..=1.0).contains(&metallic) || !(0.0..=1.0).contains(&roughness) {
        return Err(fail(format!(
            "metallicFactor {metallic} and roughnessFactor {roughness} must lie in [0, 1]"
        )));
    }
    // The dielectric half of glTF's model: a diffuse base under a coating of index 1.5
    // (F0 = 0.04), GGX with α = roughness².
    let dielectric = Material::Plastic {
        diffuse_reflectance: base,
        specular_reflectance: Rgb::WHITE,
        ior: 1.5,
        nonlinear: false,
        roughness: (roughness > 0.0).then_some(Microfacet {
            distribution: MicrofacetDistribution::Ggx,
            alpha: roughness * roughness,
        }),
    };
    // The metal half: reflectance baseColor, the same lobe.
    let metal = if roughness == 0.0 {
        Material::Mirror { reflectance: base }
    } else {
        Material::Glossy {
            diffuse: Rgb::splat(0.0),
            specular: base,
            roughness,
        }
    };
    let model = if metallic == 0.0 {
        dielectric
    } else if metallic == 1.0 {
        metal
    } else {
        Material::Blend {
            weight: metallic,
            first: Box::new(dielectric),
            second: Box::new(metal),
        }
    };
    let [er, eg, eb] = m.emissive_factor();
    let strength = m.emissive_strength().unwrap_or(1.0) as f64;
    let emissive = Rgb([er as f64, eg as f64, eb as f64]) * strength;
    let emission = match m.emissive_texture() {
        Some(info) if emissive.max_component() > 0.0 => Some(Emission::Texture {
            texture: texture(
                path,
                &place,
                "emissiveTexture",
                info.texture(),
                info.tex_coord(),
                None,
                textures,
            )?,
            scale: emissive,
        }),
        _ if emissive.max_component() > 0.0 => Some(Emission::Radiance(emissive)),
        _ => None,
    };
    let textured = color.is_some() || normal.is_some() || opacity.is_some();
    let surface = textured.then_some(Surface {
        color,
        roughness: None,
        opacity,
        normal,
        normal_scale,
        two_sided: true,
    });
    Ok((model, surface, emission))
}

fn matrix_of(a: &Affine) -> [[f64; 4]; 3] {
    [
        [a.m[0][0], a.m[0][1], a.m[0][2], a.t.x],
        [a.m[1][0], a.m[1][1], a.m[1][2], a.t.y],
        [a.m[2][0], a.m[2][1], a.m[2][2], a.t.z],
    ]
}

/// Translates the glTF file `path`.
pub fn import(path: &Path) -> Result<Imported> {
    let bytes = luxest_io::fsio::read_bytes(path)?;
    let file = open_gltf(path, &bytes)?;
    let doc = &file.document;
    let mut warnings = Vec::new();
    for ext in doc.extensions_required() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            return Err(Error::input(
                path,
                format!("the file requires the extension {ext}, which the importer does not read"),
            ));
        }
    }
    let unread: Vec<&str> = doc
        .extensions_used()
        .filter(|e| !SUPPORTED_EXTENSIONS.contains(e))
        .collect();
    if !unread.is_empty() {
        warnings.push(format!(
            "{}: extensions not read (their effect is missing): {}",
            path.display(),
            unread.join(", ")
        ));
    }
    let shape_path = scene_relative(path, path);
    let mut scene = super::empty_scene();
    // Material name and emission by glTF material index (None: the default material).
    let mut materials: BTreeMap<Option<usize>, (String, Option<Emission>)> = BTreeMap::new();
    for (node, world) in gltf_nodes(path, &file)? {
        let node_name = match node.name() {
            Some(n) => format!("{n} (node {})", node.index()),
            None => format!("node {}", node.index()),
        };
        if let Some(cam) = node.camera() {
            match cam.projection() {
                gltf::camera::Projection::Perspective(p) if scene.camera.is_none() => {
                    let aspect = p.aspect_ratio().map_or(16.0 / 9.0, |a| a as f64);
                    if !(aspect.is_finite() && aspect > 0.0) {
                        return Err(Error::at(
                            path,
                            format!("camera {}", cam.index()),
                            format!("aspectRatio {aspect} must be positive"),
                        ));
                    }
                    let position = world.apply_point(Vec3::ZERO);
                    let forward = world.apply_vector(Vec3::new(0.0, 0.0, -1.0));
                    scene.camera = Some(Camera {
                        position,
                        look_at: position + forward,
                        up: world.apply_vector(Vec3::new(0.0, 1.0, 0.0)),
                        vfov_deg: (p.yfov() as f64).to_degrees(),
                        resolution: (
                            (CAMERA_HEIGHT as f64 * aspect).round().max(1.0) as u32,
                            CAMERA_HEIGHT,
                        ),
                    });
                }
                gltf::camera::Projection::Perspective(_) => warnings.push(format!(
                    "{}: camera {}: a second camera, ignored (luxest renders one)",
                    path.display(),
                    cam.index()
                )),
                gltf::camera::Projection::Orthographic(_) => {
                    return Err(Error::at(
                        path,
                        format!("camera {}", cam.index()),
                        "orthographic cameras are not supported (luxest's camera is a pinhole)",
                    ))
                }
            }
        }
        if let Some(light) = node.light() {
            use gltf::khr_lights_punctual::Kind;
            let place = format!("light {}", light.index());
            match light.kind() {
                Kind::Point => {
                    let [r, g, b] = light.color();
                    let color = Rgb([r as f64, g as f64, b as f64]);
                    let intensity = light.intensity() as f64 * color.luminance();
                    if light.range().is_some() {
                        warnings.push(format!(
                            "{}: {place}: range ignored (luxest's point lights follow the \
                             inverse-square law everywhere)",
                            path.display()
                        ));
                    }
                    scene.point_lights.push(PointLight {
                        name: Some(light.name().map_or(place.clone(), str::to_string)),
                        position: world.apply_point(Vec3::ZERO),
                        power: PointPower::Intensity(intensity),
                        color,
                        spot: None,
                    });
                }
                Kind::Spot { .. } => {
                    return Err(Error::at(
                        path,
                        place,
                        "spot lights are not supported: glTF's smooth angular falloff is not the \
                         linear one of luxest's (Mitsuba's) spot",
                    ))
                }
                Kind::Directional => {
                    return Err(Error::at(
                        path,
                        place,
                        "directional lights are not supported (luxest has no light at infinity)",
                    ))
                }
            }
        }
        let Some(mesh) = node.mesh() else { continue };
        for prim in mesh.primitives() {
            let m = prim.material();
            let key = m.index();
            if let std::collections::btree_map::Entry::Vacant(slot) = materials.entry(key) {
                let (model, surface, emission) =
                    material(path, &m, &mut warnings, &mut scene.textures)?;
                let mut name = match (key, m.name()) {
                    (Some(_), Some(n)) => n.to_string(),
                    (Some(i), None) => format!("material {i}"),
                    (None, _) => "default".to_string(),
                };
                while scene.materials.contains_key(&name) {
                    name.push('\'');
                }
                scene.materials.insert(name.clone(), model);
                if let Some(surface) = surface {
                    scene.surfaces.insert(name.clone(), surface);
                }
                slot.insert((name, emission));
            }
            let (name, emission) = materials[&key].clone();
            scene.objects.push(Object {
                name: Some(format!(
                    "{node_name} mesh {} primitive {}",
                    mesh.index(),
                    prim.index()
                )),
                shape: Shape::Gltf {
                    path: shape_path.clone(),
                    primitive: Some((mesh.index() as u32, prim.index() as u32)),
                },
                transform: Transform {
                    matrix: (world != Affine::IDENTITY).then(|| matrix_of(&world)),
                    ..Transform::default()
                },
                material: name,
                emission,
                flip_normals: false,
                face_normals: false,
                compute_normals: false,
            });
        }
    }
    if scene.objects.is_empty() {
        return Err(Error::input(path, "the glTF scene has no meshes"));
    }
    Ok(Imported { scene, warnings })
}
