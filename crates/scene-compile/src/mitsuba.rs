//! Export of a compiled scene as a Mitsuba 3 scene (`scene-compile --export-mitsuba DIR`), so
//! that any luxest scene can be cross-checked with Mitsuba and Mitsuba can be a column of the
//! benchmarks.
//!
//! What is written: `scene.xml` and one Wavefront OBJ per (material, emitter) group of
//! triangles, in world coordinates (the compiled scene's triangles, winding kept, so that
//! Mitsuba's face normals are luxest's geometric normals; triangles with vertex normals are
//! written with `vn` in files of their own, the others with `face_normals` set, as Mitsuba
//! would otherwise compute vertex normals for them). The mapping, chosen to be exact for RGB
//! rendering:
//!
//! | luxest | Mitsuba 3 |
//! |---|---|
//! | `Lambertian` (two-sided) | `twosided` `diffuse` |
//! | `Mirror` | `twosided` `conductor`, `material="none"` (Fresnel 1), `specular_reflectance` |
//! | `Dielectric` (ior inside / outside) | `dielectric`, `int_ior = ior`, `ext_ior = 1` |
//! | `Glossy` = diffuse/π + specular · GGX(α = roughness²) | `twosided` `blendbsdf` of weight ½ over `diffuse` (2 · diffuse) and `roughconductor` (`ggx`, α, `material="none"`, 2 · specular): the sum of the two lobes |
//! | `Conductor` (η + ik per channel) | `twosided` `conductor`, or `roughconductor` with `distribution` and `alpha`; `eta`, `k`, `specular_reflectance` |
//! | `Plastic` (ior = int / ext) | `twosided` `plastic`, or `roughplastic` with `distribution` and `alpha`; `diffuse_reflectance`, `specular_reflectance`, `int_ior = ior`, `ext_ior = 1`, `nonlinear` |
//! | `RoughDielectric` | `roughdielectric`, `distribution`, `alpha`, `int_ior = ior`, `ext_ior = 1` |
//! | `ThinDielectric` | `thindielectric`, `int_ior = ior`, `ext_ior = 1` |
//! | `Blend` | `blendbsdf` with `weight`, over the two materials' own elements |
//! | area emitter (front side, luminance L) | `area` emitter, `radiance` = L |
//! | point source (intensity I per channel) | `point` emitter, `intensity` = I |
//! | spot light (on-axis intensity I₀, cutoff, beam width) | `spot` emitter, `intensity` = I₀, `cutoff_angle`, `beam_width`, `to_world` a `lookat` along the axis |
//! | constant environment (radiance L) | `constant` emitter, `radiance` = L |
//! | environment map (texels, scale, rotation) | `envmap` emitter reading `environment.exr` (the compiled texels, written as f32 RGB), `scale`, `to_world` the rotation as a 4 × 4 `matrix` |
//! | colour texture of a material or emitter (multiplying a colour) | `bitmap` (`raw`, the filter, wrap mode and `to_uv` of the texture) reading an EXR of the texels times that colour, one per parameter |
//! | roughness texture (multiplying α) | `bitmap` `alpha` of the baked α per texel |
//! | one-sided surface | the model without `twosided` |
//! | normal map (`normal_scale` (a, b)) | `normalmap` (outside `twosided`) reading an EXR of the texels c with 2c − 1 scaled by (a, b, 1) |
//! | cut-out (opacity) | `mask` with the opacity (a constant, or a `bitmap` of value × alpha, thresholded per texel where there is a cut-off) |
//! | texture coordinates | `vt` in the OBJ files (v flipped, as Mitsuba's loader flips it back) |
//! | camera (pinhole, vertical field of view) | `perspective`, `fov_axis="y"`, `look_at` with the same up vector; `hdrfilm` with a `box` filter |
//!
//! Goniometric luminaires have no Mitsuba equivalent and are refused. The integrator is `path`
//! (`max_depth` −1, `rr_depth` 5), the sampler `independent`; both are plain text in the XML.

use luxest_io::math::Vec3;
use luxest_io::{Error, Result};
use luxest_render::compiled::{CompiledScene, Emitter, NO_EMITTER};
use luxest_render::scene::{Material, Microfacet, MicrofacetDistribution};
use luxest_render::texture::{Filter, Texture, Wrap};
use luxest_render::world::opacity_of;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// The files of the export: (file name within the export directory, contents).
pub type ExportFiles = Vec<(String, Vec<u8>)>;

fn rgb(name: &str, c: [f64; 3]) -> String {
    format!(
        r#"<rgb name="{name}" value="{:e}, {:e}, {:e}"/>"#,
        c[0], c[1], c[2]
    )
}

fn vec3(v: Vec3) -> String {
    format!("{:e}, {:e}, {:e}", v.x, v.y, v.z)
}

/// How a material's textured parameters are written: its colour texture baked with each
/// colour it multiplies (Mitsuba's `bitmap` has no scale), its roughness texture baked into α.
struct Maps<'a> {
    color: Option<&'a Texture>,
    roughness: Option<&'a Texture>,
    /// File-name stem of the baked textures of this material.
    stem: String,
    files: &'a mut ExportFiles,
}

impl Maps<'_> {
    /// A colour parameter: `c`, times the colour texture when there is one.
    fn color(&mut self, name: &str, c: [f64; 3]) -> String {
        match self.color {
            None => rgb(name, c),
            Some(t) => {
                let file = format!("{}_{}_{}.exr", self.stem, name, self.files.len());
                let element = bitmap(name, &file, t);
                self.files
                    .push((file, bake(t, |v| [0, 1, 2].map(|i| v[i] as f64 * c[i]))));
                element
            }
        }
    }

    /// The `alpha` of a microfacet model: α times the roughness texture's first channel (`f`
    /// maps the product to Mitsuba's α).
    fn alpha(&mut self, alpha: f64, f: fn(f64) -> f64) -> String {
        match self.roughness {
            None => format!(r#"<float name="alpha" value="{:e}"/>"#, f(alpha)),
            Some(t) => {
                let file = format!("{}_alpha_{}.exr", self.stem, self.files.len());
                let element = bitmap("alpha", &file, t);
                self.files
                    .push((file, bake(t, |v| [f(alpha * v[0] as f64); 3])));
                element
            }
        }
    }
}

/// A `bitmap` texture element reading `file` (linear values), with `t`'s lookup options.
fn bitmap(name: &str, file: &str, t: &Texture) -> String {
    let m = t.uv_transform().0;
    format!(
        r#"<texture type="bitmap" name="{name}"><string name="filename" value="{file}"/><boolean name="raw" value="true"/><string name="filter_type" value="{}"/><string name="wrap_mode" value="{}"/><transform name="to_uv"><matrix value="{:e} {:e} 0 {:e} {:e} {:e} 0 {:e} 0 0 1 0 0 0 0 1"/></transform></texture>"#,
        match t.filter() {
            Filter::Bilinear => "bilinear",
            Filter::Nearest => "nearest",
        },
        match t.wrap() {
            Wrap::Repeat => "repeat",
            Wrap::Mirror => "mirror",
            Wrap::Clamp => "clamp",
        },
        m[0][0],
        m[0][1],
        m[0][2],
        m[1][0],
        m[1][1],
        m[1][2]
    )
}

/// The finest level of `t` with each texel (linear RGBA) mapped by `f`, as an f32 RGB EXR.
fn bake(t: &Texture, f: impl Fn([f32; 4]) -> [f64; 3]) -> Vec<u8> {
    let (w, h) = (t.width(), t.height());
    let mut image = luxest_io::image::RgbImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            image.pixels[y * w + x] = f(t.texel(0, x, y)).map(|v| v as f32);
        }
    }
    luxest_io::exr::encode_rgb(Path::new("texture.exr"), &image)
        .expect("an in-memory EXR of a decoded texture encodes")
}

/// The BSDF element of a material (two-sided models wrapped in `twosided` when `two_sided`).
fn bsdf(m: &Material, maps: &mut Maps, two_sided: bool) -> String {
    let wrap = |inner: String| {
        if two_sided {
            format!(r#"<bsdf type="twosided">{inner}</bsdf>"#)
        } else {
            inner
        }
    };
    match m {
        Material::Lambertian { reflectance } => wrap(format!(
            r#"<bsdf type="diffuse">{}</bsdf>"#,
            maps.color("reflectance", reflectance.0)
        )),
        Material::Mirror { reflectance } => wrap(format!(
            r#"<bsdf type="conductor"><string name="material" value="none"/>{}</bsdf>"#,
            maps.color("specular_reflectance", reflectance.0)
        )),
        Material::Dielectric { ior } => format!(
            r#"<bsdf type="dielectric"><float name="int_ior" value="{ior:e}"/><float name="ext_ior" value="1"/></bsdf>"#
        ),
        Material::Glossy {
            diffuse,
            specular,
            roughness,
        } => wrap(format!(
            r#"<bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="diffuse">{}</bsdf><bsdf type="roughconductor"><string name="distribution" value="ggx"/>{}<string name="material" value="none"/>{}</bsdf></bsdf>"#,
            maps.color("reflectance", diffuse.0.map(|v| 2.0 * v)),
            maps.alpha(*roughness, |r| r * r),
            rgb("specular_reflectance", specular.0.map(|v| 2.0 * v))
        )),
        Material::Conductor {
            eta,
            k,
            specular_reflectance,
            roughness,
        } => wrap(format!(
            r#"<bsdf type="{}">{}{}{}{}</bsdf>"#,
            if roughness.is_some() {
                "roughconductor"
            } else {
                "conductor"
            },
            microfacet(roughness.as_ref(), maps),
            rgb("eta", eta.0),
            rgb("k", k.0),
            maps.color("specular_reflectance", specular_reflectance.0)
        )),
        Material::Plastic {
            diffuse_reflectance,
            specular_reflectance,
            ior,
            nonlinear,
            roughness,
        } => wrap(format!(
            r#"<bsdf type="{}">{}{}{}<float name="int_ior" value="{ior:e}"/><float name="ext_ior" value="1"/><boolean name="nonlinear" value="{nonlinear}"/></bsdf>"#,
            if roughness.is_some() {
                "roughplastic"
            } else {
                "plastic"
            },
            microfacet(roughness.as_ref(), maps),
            maps.color("diffuse_reflectance", diffuse_reflectance.0),
            rgb("specular_reflectance", specular_reflectance.0)
        )),
        Material::RoughDielectric { ior, roughness } => format!(
            r#"<bsdf type="roughdielectric">{}<float name="int_ior" value="{ior:e}"/><float name="ext_ior" value="1"/></bsdf>"#,
            microfacet(Some(roughness), maps)
        ),
        Material::ThinDielectric { ior } => format!(
            r#"<bsdf type="thindielectric"><float name="int_ior" value="{ior:e}"/><float name="ext_ior" value="1"/></bsdf>"#
        ),
        // Each blended material keeps its own element (a two-sided reflector stays wrapped in
        // `twosided`; Mitsuba's `twosided` cannot hold a transmitting blend).
        Material::Blend {
            weight,
            first,
            second,
        } => format!(
            r#"<bsdf type="blendbsdf"><float name="weight" value="{weight:e}"/>{}{}</bsdf>"#,
            bsdf(first, maps, two_sided),
            bsdf(second, maps, two_sided)
        ),
    }
}

/// The `distribution` and `alpha` of a microfacet model (nothing for a smooth one).
fn microfacet(r: Option<&Microfacet>, maps: &mut Maps) -> String {
    match r {
        Some(r) => format!(
            r#"<string name="distribution" value="{}"/>{}"#,
            match r.distribution {
                MicrofacetDistribution::Ggx => "ggx",
                MicrofacetDistribution::Beckmann => "beckmann",
            },
            maps.alpha(r.alpha, |a| a)
        ),
        None => String::new(),
    }
}

/// The Mitsuba 3 scene of `scene` (see the module docs); `path` names the compiled scene in
/// errors.
pub fn export(scene: &CompiledScene, path: &Path) -> Result<ExportFiles> {
    let h = &scene.header;
    if let Some(Emitter::Luminaire { name, .. }) = h
        .emitters
        .iter()
        .find(|e| matches!(e, Emitter::Luminaire { .. }))
    {
        return Err(Error::input(
            path,
            format!("luminaire \"{name}\": Mitsuba 3 has no goniometric emitter to export it to"),
        ));
    }
    if h.emitters
        .iter()
        .any(|e| matches!(e, Emitter::Environment { sun: Some(_), .. }))
    {
        return Err(Error::input(
            path,
            "the sky's sun: Mitsuba 3 has no distant disk emitter to export it to",
        ));
    }
    let mut xml = String::new();
    let _ = writeln!(
        xml,
        "<!-- Mitsuba 3 scene exported by luxest scene-compile {} from \"{}\" (content hash {}) -->",
        env!("CARGO_PKG_VERSION"),
        h.name,
        scene.content_hash
    );
    let _ = writeln!(xml, r#"<scene version="3.0.0">"#);
    let _ = writeln!(
        xml,
        r#"  <default name="spp" value="64"/>
  <integrator type="path"><integer name="max_depth" value="-1"/><integer name="rr_depth" value="5"/></integrator>"#
    );
    if let Some(c) = &h.camera {
        let _ = writeln!(
            xml,
            r#"  <sensor type="perspective">
    <string name="fov_axis" value="y"/><float name="fov" value="{:e}"/>
    <transform name="to_world"><lookat origin="{}" target="{}" up="{}"/></transform>
    <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
    <film type="hdrfilm"><integer name="width" value="{}"/><integer name="height" value="{}"/><rfilter type="box"/><string name="pixel_format" value="rgb"/><string name="component_format" value="float32"/></film>
  </sensor>"#,
            c.vfov_deg,
            vec3(c.position),
            vec3(c.look_at),
            vec3(c.up),
            c.resolution.0,
            c.resolution.1
        );
    }
    let mut files = Vec::new();
    for e in &h.emitters {
        match e {
            Emitter::Point {
                position,
                intensity_rgb,
                spot: None,
                ..
            } => {
                let _ = writeln!(
                    xml,
                    r#"  <emitter type="point"><point name="position" value="{}"/>{}</emitter>"#,
                    vec3(*position),
                    rgb("intensity", intensity_rgb.0)
                );
            }
            Emitter::Point {
                position,
                intensity_rgb,
                spot: Some(cone),
                ..
            } => {
                // Mitsuba's spot points along its local +z: look from the position along the
                // axis, with any up vector not parallel to it.
                let up = cone.direction.orthonormal_basis().0;
                let _ = writeln!(
                    xml,
                    r#"  <emitter type="spot"><transform name="to_world"><lookat origin="{}" target="{}" up="{}"/></transform><float name="cutoff_angle" value="{:e}"/><float name="beam_width" value="{:e}"/>{}</emitter>"#,
                    vec3(*position),
                    vec3(*position + cone.direction),
                    vec3(up),
                    cone.cutoff_deg,
                    cone.beam_width_deg,
                    rgb("intensity", intensity_rgb.0)
                );
            }
            Emitter::Environment {
                radiance_rgb,
                map: None,
                ..
            } => {
                let _ = writeln!(
                    xml,
                    r#"  <emitter type="constant">{}</emitter>"#,
                    rgb("radiance", radiance_rgb.0)
                );
            }
            Emitter::Environment {
                radiance_rgb,
                map: Some(m),
                ..
            } => {
                let file = "environment.exr";
                let image = luxest_io::image::RgbImage {
                    width: m.width as usize,
                    height: m.height as usize,
                    pixels: scene.environment_texels.clone(),
                    attributes: Vec::new(),
                };
                files.push((
                    file.to_string(),
                    luxest_io::exr::encode_rgb(Path::new(file), &image)?,
                ));
                let r = m.to_world;
                let matrix = format!(
                    "{:e} {:e} {:e} 0 {:e} {:e} {:e} 0 {:e} {:e} {:e} 0 0 0 0 1",
                    r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2]
                );
                let _ = writeln!(
                    xml,
                    r#"  <emitter type="envmap"><string name="filename" value="{file}"/><float name="scale" value="{:e}"/><transform name="to_world"><matrix value="{matrix}"/></transform></emitter>"#,
                    radiance_rgb.0[0]
                );
            }
            Emitter::Area { .. } | Emitter::Luminaire { .. } => {}
        }
    }
    // Triangles grouped by (material, emitter, smooth), in order of first appearance.
    let mut groups: BTreeMap<(u32, u32, bool), Vec<usize>> = BTreeMap::new();
    for (t, (&m, &e)) in scene
        .triangle_material
        .iter()
        .zip(&scene.triangle_emitter)
        .enumerate()
    {
        let smooth = h.features.smooth_normals
            && scene.indices[t]
                .iter()
                .all(|&v| scene.normals[v as usize] != [0.0; 3]);
        groups.entry((m, e, smooth)).or_default().push(t);
    }
    for (g, ((m, e, smooth), triangles)) in groups.iter().enumerate() {
        let material = &h.materials[*m as usize];
        let file = format!("mesh_{g:03}.obj");
        let mut obj = format!(
            "# luxest scene \"{}\": material \"{}\"{}\n",
            h.name,
            material.name,
            if *e == NO_EMITTER { "" } else { ", emitter" }
        );
        // Only the vertices this group uses, renumbered from 1.
        let mut index = BTreeMap::new();
        let mut faces = String::new();
        for &t in triangles {
            let mut f = [0usize; 3];
            for (k, &v) in scene.indices[t].iter().enumerate() {
                let next = index.len() + 1;
                f[k] = *index.entry(v).or_insert(next);
            }
            let _ = writeln!(faces, "f {} {} {}", f[0], f[1], f[2]);
        }
        let mut by_new: Vec<(usize, u32)> = index.iter().map(|(&v, &n)| (n, v)).collect();
        by_new.sort_unstable();
        for &(_, v) in &by_new {
            let p = scene.positions[v as usize];
            let _ = writeln!(obj, "v {} {} {}", p[0], p[1], p[2]);
        }
        if h.features.uvs {
            // Mitsuba's OBJ loader flips v, as luxest's does.
            for &(_, v) in &by_new {
                let t = scene.uvs[v as usize];
                let _ = writeln!(obj, "vt {} {}", t[0], 1.0 - t[1]);
            }
        }
        if *smooth {
            for &(_, v) in &by_new {
                let n = scene.normals[v as usize];
                let _ = writeln!(obj, "vn {} {} {}", n[0], n[1], n[2]);
            }
        }
        if h.features.uvs || *smooth {
            let corner = |i: &str| match (h.features.uvs, *smooth) {
                (true, true) => format!("{i}/{i}/{i}"),
                (true, false) => format!("{i}/{i}"),
                _ => format!("{i}//{i}"),
            };
            faces = faces
                .lines()
                .map(|l| {
                    let f: Vec<&str> = l.split(' ').collect();
                    format!("f {} {} {}\n", corner(f[1]), corner(f[2]), corner(f[3]))
                })
                .collect();
        }
        obj.push_str(&faces);
        let surface = h.surfaces.get(*m as usize);
        let texture = |t: Option<u32>| t.map(|t| &scene.textures[t as usize]);
        let emitter = match h.emitters.get(*e as usize) {
            Some(Emitter::Area {
                radiance_rgb,
                texture: t,
                ..
            }) => {
                let mut maps = Maps {
                    color: texture(*t),
                    roughness: None,
                    stem: format!("emitter_{g:03}"),
                    files: &mut files,
                };
                format!(
                    r#"<emitter type="area">{}</emitter>"#,
                    maps.color("radiance", radiance_rgb.0)
                )
            }
            _ => String::new(),
        };
        let mut maps = Maps {
            color: texture(surface.and_then(|s| s.color)),
            roughness: texture(surface.and_then(|s| s.roughness)),
            stem: format!("material_{g:03}"),
            files: &mut files,
        };
        let mut element = bsdf(
            &material.model,
            &mut maps,
            surface.is_none_or(|s| s.two_sided),
        );
        if let Some((t, scale)) = surface.and_then(|s| Some((texture(s.normal)?, s.normal_scale))) {
            // Mitsuba decodes 2c − 1 and normalises: the texels baked with luxest's scale of x
            // and y (linear in c, so bilinear lookups agree), stored as floats.
            let file = format!("normal_{g:03}.exr");
            let baked = bake(t, |v| {
                let d = |c: f32| 2.0 * c as f64 - 1.0;
                let n = [d(v[0]) * scale[0], d(v[1]) * scale[1], d(v[2])];
                n.map(|x| (x + 1.0) / 2.0)
            });
            files.push((file.clone(), baked));
            element = format!(
                r#"<bsdf type="normalmap">{}{element}</bsdf>"#,
                bitmap("normalmap", &file, t)
            );
        }
        if let Some(o) = surface.and_then(|s| s.opacity.as_ref()) {
            // Mitsuba's `mask` is stochastic: a cut-off is baked into the texels (exact for
            // nearest lookups; at texel edges a bilinear lookup of the thresholded texels
            // differs from thresholding the bilinear lookup).
            let opacity = match texture(o.texture) {
                None => format!(r#"<float name="opacity" value="{:e}"/>"#, o.value),
                Some(t) => {
                    let file = format!("opacity_{g:03}.exr");
                    let (value, cutoff, alpha) = (o.value, o.cutoff, t.has_alpha());
                    let baked = bake(t, |v| {
                        let a = value * opacity_of(v, alpha, o.channel);
                        [match cutoff {
                            Some(c) => f64::from(u8::from(a >= c)),
                            None => a,
                        }; 3]
                    });
                    files.push((file.clone(), baked));
                    bitmap("opacity", &file, t)
                }
            };
            element = format!(r#"<bsdf type="mask">{opacity}{element}</bsdf>"#);
        }
        let _ = writeln!(
            xml,
            r#"  <shape type="obj"><string name="filename" value="{file}"/><boolean name="face_normals" value="{}"/>{element}{emitter}</shape>"#,
            !smooth
        );
        files.push((file, obj.into_bytes()));
    }
    let _ = writeln!(xml, "</scene>");
    files.insert(0, ("scene.xml".to_string(), xml.into_bytes()));
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn element(ron: &str) -> String {
        let mut files = Vec::new();
        let mut maps = Maps {
            color: None,
            roughness: None,
            stem: "m".into(),
            files: &mut files,
        };
        let m = luxest_io::fsio::parse_ron::<Material>(Path::new("test.ron"), ron).unwrap();
        bsdf(&m, &mut maps, true)
    }

    /// Each Mitsuba material is written as its plugin with its parameters. (These elements,
    /// loaded by Mitsuba 3.9's `mi.load_string`, evaluate as the plugin dictionaries of
    /// `crates/render/tests/data/mitsuba_bsdf.py` do.)
    #[test]
    fn the_mitsuba_materials_export_as_their_plugins() {
        let gold = element(
            "Conductor(eta: (0.2, 0.4, 1.4), k: (4.0, 2.4, 1.6), roughness: Some((distribution: Beckmann, alpha: 0.2)))",
        );
        assert_eq!(
            gold,
            r#"<bsdf type="twosided"><bsdf type="roughconductor"><string name="distribution" value="beckmann"/><float name="alpha" value="2e-1"/><rgb name="eta" value="2e-1, 4e-1, 1.4e0"/><rgb name="k" value="4e0, 2.4e0, 1.6e0"/><rgb name="specular_reflectance" value="1e0, 1e0, 1e0"/></bsdf></bsdf>"#
        );
        let smooth = element("Conductor(eta: (0.0, 0.0, 0.0), k: (1.0, 1.0, 1.0))");
        assert!(
            smooth.starts_with(r#"<bsdf type="twosided"><bsdf type="conductor"><rgb name="eta""#)
        );
        let plastic = element(
            "Plastic(diffuse_reflectance: (0.5, 0.1, 0.1), nonlinear: true, roughness: Some((distribution: Ggx, alpha: 0.3)))",
        );
        assert!(plastic.contains(r#"<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="3e-1"/>"#));
        assert!(plastic.contains(r#"<boolean name="nonlinear" value="true"/>"#));
        assert!(plastic.contains(&format!(
            r#"<float name="int_ior" value="{:e}"/><float name="ext_ior" value="1"/>"#,
            1.49 / 1.000277
        )));
        assert_eq!(
            element("RoughDielectric(ior: 1.5, roughness: (distribution: Ggx, alpha: 0.1))"),
            r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" value="1e-1"/><float name="int_ior" value="1.5e0"/><float name="ext_ior" value="1"/></bsdf>"#
        );
        assert_eq!(
            element("ThinDielectric(ior: 1.5)"),
            r#"<bsdf type="thindielectric"><float name="int_ior" value="1.5e0"/><float name="ext_ior" value="1"/></bsdf>"#
        );
        let blend = element(
            "Blend(weight: 0.25, first: ThinDielectric(ior: 1.5), second: Lambertian(reflectance: (0.5, 0.5, 0.5)))",
        );
        assert_eq!(
            blend,
            format!(
                r#"<bsdf type="blendbsdf"><float name="weight" value="2.5e-1"/>{}{}</bsdf>"#,
                element("ThinDielectric(ior: 1.5)"),
                element("Lambertian(reflectance: (0.5, 0.5, 0.5))")
            )
        );
    }
}
