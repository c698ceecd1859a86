//! scene-compile: authored scene (RON + mesh files) → one compiled scene file.
//!
//! The compiled scene ([`luxest_render::compiled`]) is world space, self-contained (no references
//! to source files), carries a schema version, a content hash and a features manifest. This
//! crate owns everything about *reading authored input*: RON parsing, validation, tessellation
//! of analytic shapes, OBJ and glTF loading, transforms, dropping degenerate triangles, the
//! emitter table (with luminaires from photometric files, [`luminaires`]) and the sensor
//! expansion (with calculation surfaces, [`surfaces`]).
//!
//! Modules: [`cli`] (arguments and run), [`import`] (whole scenes from Mitsuba 3 XML, glTF and
//! OBJ+MTL, translated into an authored scene), [`validate`], [`shapes`] (tessellation),
//! [`meshes`] (OBJ and glTF), [`ply`] (PLY meshes), [`serialized`] (Mitsuba's serialized
//! meshes), [`luminaires`], [`observers`] (glare observers), [`environment`] (the
//! environment emitter and its map), [`surfaces`], [`textures`] (bitmap textures and the
//! per-material surfaces), [`windows`] (openings cut from wall quads), [`mitsuba`] (export to
//! Mitsuba 3); this file assembles the
//! world-space scene.

pub mod cli;
pub mod environment;
pub mod import;
pub mod luminaires;
pub mod meshes;
pub mod mitsuba;
pub mod observers;
pub mod ply;
pub mod serialized;
pub mod shapes;
pub mod surfaces;
pub mod textures;
pub mod validate;
pub mod windows;

pub use cli::{run, Args};

use luxest_io::math::Vec3;
use luxest_io::num::show;
use luxest_io::{Error, Result};
use luxest_render::bsdf;
use luxest_render::compiled::{
    CompiledScene, Emitter, Features, GridLayout, NamedMaterial, ObjectRange, SceneHeader,
    SensorSet, SpotCone, Stats, NO_EMITTER,
};
use luxest_render::portal::Portal;
use luxest_render::scene::{Emission, Material, PointPower, Scene, Sensor, SensorPoint, Shape};
use shapes::LocalMesh;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// What compiling produced besides the scene.
#[derive(Debug, Default)]
pub struct Report {
    /// Human-readable warnings (dropped degenerate triangles, unused materials).
    pub warnings: Vec<String>,
}

/// The scene's name: its `name`, or the file stem. It names the default output directory
/// `build/<name>/`, so [`validate::check_scene`] refuses a `name` that is not a plain file name.
pub fn scene_name(scene: &Scene, path: &Path) -> String {
    scene.name.clone().unwrap_or_else(|| {
        path.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene".into())
    })
}

/// The files a scene refers to (meshes, photometric files), resolved as compiling resolves
/// them: relative to the scene file's directory. A compile's output must be none of them.
pub fn referenced_files(scene: &Scene, path: &Path) -> Vec<PathBuf> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let meshes = scene.objects.iter().filter_map(|o| match &o.shape {
        Shape::Obj { path, .. }
        | Shape::Gltf { path, .. }
        | Shape::Ply { path }
        | Shape::Serialized { path, .. } => Some(dir.join(path)),
        _ => None,
    });
    let photometry = scene.luminaires.iter().map(|l| dir.join(&l.file));
    let environment = match &scene.environment {
        Some(luxest_render::scene::Environment::Map { path, .. }) => Some(dir.join(path)),
        _ => None,
    };
    meshes.chain(photometry).chain(environment).collect()
}

/// Reads (a RON scene, or one [`import`] translates), validates and compiles a scene file.
pub fn compile_file(path: &Path) -> Result<(CompiledScene, Report)> {
    let imported = import::read_scene(path)?;
    let (compiled, mut report) = compile(&imported.scene, path)?;
    report.warnings.splice(0..0, imported.warnings);
    Ok((compiled, report))
}

/// World-space geometry being assembled.
#[derive(Default)]
struct Builder {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    /// Per vertex; zero for meshes without texture coordinates.
    uvs: Vec<[f32; 2]>,
    indices: Vec<[u32; 3]>,
    triangle_material: Vec<u32>,
    triangle_emitter: Vec<u32>,
    dropped: u64,
    bounds_min: Vec3,
    bounds_max: Vec3,
    total_area: f64,
}

/// Twice the area of the triangle over its two edge lengths: the sine of the angle between the
/// edges. Below this the triangle is numerically a line and is dropped.
const DEGENERATE_SINE: f64 = 1e-9;

/// How one object's local mesh enters the world.
struct Placement<'a> {
    /// Where the object is in the scene file, for messages.
    place: &'a str,
    transform: luxest_io::math::Affine,
    flip: bool,
    material: u32,
    emitter: u32,
}

impl Builder {
    /// Transforms `mesh` to world space and appends its non-degenerate triangles; returns
    /// (triangles added, their area, triangles dropped).
    fn add(&mut self, path: &Path, mesh: LocalMesh, at: &Placement) -> Result<(u32, f64, u64)> {
        let (place, transform, flip) = (at.place, &at.transform, at.flip);
        let det = transform.determinant();
        // Mirroring transforms reverse the winding; undo that so the front side stays the one
        // the author meant, and flip on request.
        let reverse = (det < 0.0) != flip;
        let normal_sign = if flip { -1.0 } else { 1.0 } * det.signum();
        let base = self.positions.len();
        if base + mesh.positions.len() > u32::MAX as usize - 1 {
            return Err(Error::at(path, place, "scene exceeds 2^32 vertices"));
        }
        for (i, p) in mesh.positions.iter().enumerate() {
            let w = transform.apply_point(*p).to_f32();
            if let Some(c) = w
                .iter()
                .map(|&c| c as f64)
                .find(|&c| validate::beyond_world(c))
            {
                return Err(Error::at(
                    path,
                    place,
                    format!(
                        "vertex {i}: {} after the object's transform (scale, rotation, \
                         translation)",
                        validate::out_of_world(c)
                    ),
                ));
            }
            self.positions.push(w);
        }
        match &mesh.normals {
            Some(ns) => self.normals.extend(ns.iter().map(|n| {
                let w = transform.apply_normal(*n) * normal_sign;
                w.try_normalize().map(|u| u.to_f32()).unwrap_or([0.0; 3])
            })),
            None => self
                .normals
                .extend(std::iter::repeat_n([0.0f32; 3], mesh.positions.len())),
        }
        match &mesh.uvs {
            Some(t) => self
                .uvs
                .extend(t.iter().map(|&[u, v]| [u as f32, v as f32])),
            None => self
                .uvs
                .extend(std::iter::repeat_n([0.0f32; 2], mesh.positions.len())),
        }
        let (mut added, mut area, mut dropped) = (0u32, 0.0, 0u64);
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| Vec3::from(self.positions[base + i as usize]));
            let (e1, e2) = (b - a, c - a);
            let cross = e1.cross(e2).length();
            if !(cross.is_finite() && cross > DEGENERATE_SINE * e1.length() * e2.length()) {
                dropped += 1;
                continue;
            }
            let mut tri = t.map(|i| base as u32 + i);
            if reverse {
                tri.swap(1, 2);
            }
            for p in [a, b, c] {
                self.bounds_min = self.bounds_min.min(p);
                self.bounds_max = self.bounds_max.max(p);
            }
            self.indices.push(tri);
            self.triangle_material.push(at.material);
            self.triangle_emitter.push(at.emitter);
            area += 0.5 * cross;
            added += 1;
        }
        self.dropped += dropped;
        self.total_area += area;
        Ok((added, area, dropped))
    }
}

/// A file the scene names (`p`, relative to the scene file) at `place`: a mesh, texture or
/// photometric file (`what`). It must be a regular file.
pub(crate) fn resolve_file(scene_path: &Path, place: &str, p: &str, what: &str) -> Result<PathBuf> {
    let full = scene_path.parent().unwrap_or(Path::new(".")).join(p);
    if full.is_file() {
        Ok(full)
    } else if let Some(kind) = luxest_io::fsio::non_file_kind(&full) {
        // It exists (a directory, /dev/null, a FIFO): "not found" would send the user
        // looking for a file that is there.
        let expected = if kind == "a directory" {
            format!("a {what} file")
        } else {
            format!("a regular file, as a {what} must be")
        };
        Err(Error::at(
            scene_path,
            place,
            format!("{} is {kind}, not {expected}", full.display()),
        ))
    } else {
        Err(Error::at(
            scene_path,
            place,
            format!("{what} file {} not found", full.display()),
        ))
    }
}

fn object_mesh(scene_path: &Path, place: &str, shape: &Shape) -> Result<LocalMesh> {
    let resolve = |p: &str| resolve_file(scene_path, &format!("{place}.shape.path"), p, "mesh");
    Ok(match shape {
        Shape::Quad { corner, u, v } => shapes::quad(*corner, *u, *v),
        Shape::Polygon { vertices } => shapes::polygon(vertices),
        Shape::Box { size } => shapes::cuboid(*size),
        Shape::Sphere {
            radius,
            subdivisions,
        } => shapes::icosphere(*radius, *subdivisions),
        Shape::Obj { path, usemtl } => match usemtl {
            Some(m) => meshes::load_obj_usemtl(&resolve(path)?, m)?,
            None => meshes::load_obj(&resolve(path)?)?,
        },
        Shape::Gltf { path, primitive } => match primitive {
            Some((m, p)) => meshes::load_gltf_primitive(&resolve(path)?, *m, *p)?,
            None => meshes::load_gltf(&resolve(path)?)?,
        },
        Shape::Ply { path } => ply::load_ply(&resolve(path)?)?,
        Shape::Serialized { path, shape_index } => {
            serialized::load_serialized(&resolve(path)?, *shape_index)?
        }
    })
}

fn expand_sensor(path: &Path, place: &str, s: &Sensor) -> Result<SensorSet> {
    let c = validate::Check { path };
    Ok(match s {
        Sensor::Points { name, points } => SensorSet {
            name: name.clone(),
            grid: None,
            points: points
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    Ok(SensorPoint {
                        position: p.position,
                        normal: p.normal.try_normalize().expect("validated"),
                        kind: surfaces::normalised_kind(
                            &c,
                            &format!("{place}.points[{i}].kind"),
                            &p.kind,
                        )?,
                    })
                })
                .collect::<Result<Vec<_>>>()?,
            calculation_grid: None,
            requirements: None,
        },
        Sensor::Grid {
            name,
            corner,
            u,
            v,
            counts,
            normal,
        } => {
            let n = normal
                .unwrap_or_else(|| u.cross(*v))
                .try_normalize()
                .expect("validated");
            let (nu, nv) = *counts;
            let mut points = Vec::with_capacity((nu * nv) as usize);
            for j in 0..nv {
                for i in 0..nu {
                    let s = (i as f64 + 0.5) / nu as f64;
                    let t = (j as f64 + 0.5) / nv as f64;
                    points.push(SensorPoint::planar(*corner + *u * s + *v * t, n));
                }
            }
            // A rectangular grid's layout, for reports (a parallelogram has none).
            let rectangular = u.dot(*v).abs() <= 1e-12 * u.length() * v.length();
            SensorSet {
                name: name.clone(),
                grid: Some(*counts),
                points,
                calculation_grid: rectangular.then_some(GridLayout {
                    origin: *corner,
                    u: *u,
                    v: *v,
                    margin_m: 0.0,
                    nu: counts.0,
                    nv: counts.1,
                }),
                requirements: None,
            }
        }
    })
}

/// The fraction of light in channel `c` a reflecting material returns at normal incidence, for
/// the warning on scenes where nothing absorbs (dielectrics: 0 here; that check counts them as
/// lossless).
fn lossless_albedo(m: &Material, c: usize) -> f64 {
    match m {
        Material::Lambertian { reflectance } | Material::Mirror { reflectance } => reflectance.0[c],
        Material::Glossy {
            diffuse, specular, ..
        } => diffuse.0[c] + specular.0[c],
        Material::Conductor {
            eta,
            k,
            specular_reflectance,
            ..
        } => specular_reflectance.0[c] * bsdf::conductor::fresnel_conductor(1.0, eta.0[c], k.0[c]),
        Material::Plastic {
            diffuse_reflectance,
            specular_reflectance,
            ior,
            ..
        } => {
            let f0 = bsdf::fresnel_dielectric(1.0, *ior).0;
            f0 * specular_reflectance.0[c] + (1.0 - f0) * diffuse_reflectance.0[c]
        }
        Material::Blend {
            weight,
            first,
            second,
        } => (1.0 - weight) * lossless_albedo(first, c) + weight * lossless_albedo(second, c),
        Material::Dielectric { .. }
        | Material::RoughDielectric { .. }
        | Material::ThinDielectric { .. } => 0.0,
    }
}

/// The environment's portals: the scene's `portals` (each checked: a rectangle of positive
/// area), then its open `windows` that are rectangles (a glazed window passes no shadow ray, a
/// parallelogram is no portal); at most [`luxest_render::portal::MAX_PORTALS`].
fn portals(scene: &Scene, path: &Path) -> Result<Vec<Portal>> {
    use luxest_render::portal::MAX_PORTALS;
    for (k, p) in scene.portals.iter().enumerate() {
        if let Some(m) = p.problem() {
            return Err(Error::at(path, format!("portals[{k}]"), m));
        }
    }
    if scene.portals.len() > MAX_PORTALS {
        return Err(Error::at(
            path,
            "portals",
            format!(
                "{} portals: at most {MAX_PORTALS} are supported",
                scene.portals.len()
            ),
        ));
    }
    let mut all = scene.portals.clone();
    for w in &scene.windows {
        let p = Portal {
            name: w.name.clone(),
            corner: w.corner,
            u: w.u,
            v: w.v,
        };
        if w.glazing.is_none() && p.problem().is_none() && all.len() < MAX_PORTALS {
            all.push(p);
        }
    }
    Ok(all)
}

/// Compiles a parsed scene; `path` locates mesh files and names the scene in messages.
pub fn compile(scene: &Scene, path: &Path) -> Result<(CompiledScene, Report)> {
    validate::check_scene(path, scene)?;
    let portals = portals(scene, path)?;
    let cut = windows::cut(scene, path)?;
    let scene = cut.as_ref().unwrap_or(scene);
    let mut report = Report::default();
    let material_index: std::collections::BTreeMap<&str, u32> = scene
        .materials
        .keys()
        .enumerate()
        .map(|(i, k)| (k.as_str(), i as u32))
        .collect();
    let mut b = Builder {
        bounds_min: Vec3::splat(f64::INFINITY),
        bounds_max: Vec3::splat(f64::NEG_INFINITY),
        ..Default::default()
    };
    let loaded = textures::load(path, scene, &mut report.warnings)?;
    let mut any_uvs = false;
    let mut emitters = Vec::new();
    let mut objects = Vec::new();
    for (i, o) in scene.objects.iter().enumerate() {
        let place = format!("objects[{i}]");
        let name = o.name.clone().unwrap_or_else(|| place.clone());
        let mut mesh = object_mesh(path, &place, &o.shape)?;
        if o.face_normals {
            mesh.normals = None;
        } else if o.compute_normals && mesh.normals.is_none() {
            mesh.normals = Some(shapes::angle_weighted_normals(&mesh));
        }
        let surface = scene.surfaces.get(&o.material);
        let textured_surface = surface.is_some_and(|s| {
            s.color.is_some()
                || s.roughness.is_some()
                || s.normal.is_some()
                || s.opacity.as_ref().is_some_and(|o| o.texture.is_some())
        });
        let textured_emission = matches!(o.emission, Some(Emission::Texture { .. }));
        if textured_surface || textured_emission {
            if mesh.uvs.is_none() {
                return Err(Error::at(
                    path,
                    &place,
                    format!(
                        "({name}) has a textured {} but its shape has no texture coordinates",
                        if textured_surface {
                            format!("material \"{}\"", o.material)
                        } else {
                            "emission".to_string()
                        }
                    ),
                ));
            }
            any_uvs = true;
        }
        let material = material_index[o.material.as_str()];
        let emitter = if o.emission.is_some() {
            emitters.len() as u32
        } else {
            NO_EMITTER
        };
        let first = b.indices.len() as u32;
        let placement = Placement {
            place: &place,
            transform: o.transform.to_affine(),
            flip: o.flip_normals,
            material,
            emitter,
        };
        let (count, area, dropped) = b.add(path, mesh, &placement)?;
        if dropped > 0 {
            report.warnings.push(format!(
                "{}: {place} ({name}): dropped {dropped} degenerate triangle{}",
                path.display(),
                if dropped == 1 { "" } else { "s" }
            ));
        }
        if count == 0 {
            // Nothing of it can be hit: an imported scene may carry such a mesh (Mitsuba renders
            // nothing for it); an emitter without area is an error.
            if o.emission.is_some() {
                return Err(Error::at(
                    path,
                    &place,
                    "emitting object has no non-degenerate triangles",
                ));
            }
            report.warnings.push(format!(
                "{}: {place} ({name}): dropped: no non-degenerate triangles",
                path.display()
            ));
            continue;
        }
        if let Some(e) = &o.emission {
            let mut texture = None;
            let radiance_rgb = match e {
                Emission::Radiance(l) => *l,
                Emission::Texture { texture: t, scale } => {
                    texture = Some(loaded.index[t.as_str()]);
                    *scale
                }
                // L = flux / (pi A) for a Lambertian emitter radiating from one side.
                Emission::Flux { lumens, color } => {
                    let l = color
                        .with_luminance(lumens / (PI * area))
                        .expect("validated");
                    // The flux was bounded, but a tiny emitter turns it into a luminance that
                    // overflows f32 images (found with 100 lm on 2e-19 m: inf pixels).
                    if l.max_component() > validate::MAX_EMISSION {
                        return Err(Error::at(
                            path,
                            format!("{place}.emission"),
                            format!(
                                "{} lm from {area:.3e} m² is a luminance of {:.3e}, above the {} an \
                                 emitter may have; give it a larger area or less flux",
                                show(*lumens),
                                l.max_component(),
                                show(validate::MAX_EMISSION)
                            ),
                        ));
                    }
                    l
                }
            };
            // The mean luminance over the surface: the texture's mean over the triangles.
            let mean = match texture {
                None => radiance_rgb,
                Some(t) => {
                    let tris: Vec<([[f64; 2]; 3], f64)> = (first..first + count)
                        .map(|k| {
                            let idx = b.indices[k as usize];
                            let [pa, pb, pc] = idx.map(|v| Vec3::from(b.positions[v as usize]));
                            let uv = idx.map(|v| b.uvs[v as usize].map(|c| c as f64));
                            (uv, 0.5 * (pb - pa).cross(pc - pa).length())
                        })
                        .collect();
                    radiance_rgb * textures::mean_over(&loaded.textures[t as usize], &tris)
                }
            };
            emitters.push(Emitter::Area {
                name: name.clone(),
                first_triangle: first,
                triangle_count: count,
                radiance_rgb,
                texture,
                area_m2: area,
                flux_rgb: mean * (PI * area),
            });
        }
        objects.push(ObjectRange {
            name,
            first_triangle: first,
            triangle_count: count,
            material,
            emitter: (emitter != NO_EMITTER).then_some(emitter),
        });
    }
    for (i, l) in scene.point_lights.iter().enumerate() {
        // Isotropic source: flux = 4π I; a spot: its cone's factor (luxest_render::spot).
        let spot = l.spot.as_ref().map(|s| SpotCone {
            direction: s.direction.try_normalize().expect("validated"),
            cutoff_deg: s.cutoff_deg,
            beam_width_deg: s.beam_width_deg,
        });
        let solid_angle = spot.as_ref().map_or(4.0 * PI, SpotCone::solid_angle_factor);
        let intensity = match l.power {
            PointPower::Intensity(cd) => cd,
            PointPower::Flux(lm) => lm / solid_angle,
        };
        let intensity_rgb = l.color.with_luminance(intensity).expect("validated");
        emitters.push(Emitter::Point {
            name: l
                .name
                .clone()
                .unwrap_or_else(|| format!("point_lights[{i}]")),
            position: l.position,
            intensity_rgb,
            flux_rgb: intensity_rgb * solid_angle,
            spot,
        });
    }
    let lum = luminaires::compile(path, &scene.luminaires)?;
    report.warnings.extend(lum.warnings);
    let glare = observers::compile(
        path,
        &scene.observers,
        &scene.luminaires,
        emitters.len(),
        &lum.openings,
    )?;
    emitters.extend(lum.emitters);

    let used: std::collections::BTreeSet<u32> = b.triangle_material.iter().copied().collect();
    let materials: Vec<NamedMaterial> = scene
        .materials
        .iter()
        .map(|(name, model)| NamedMaterial {
            name: name.clone(),
            model: model.clone(),
        })
        .collect();
    for (i, m) in materials.iter().enumerate() {
        if !used.contains(&(i as u32)) {
            report.warnings.push(format!(
                "{}: materials[\"{}\"]: unused",
                path.display(),
                m.name
            ));
        }
    }
    // Light is trapped (walks end only at --max-depth) where no surface absorbs it: in a
    // channel where every used material reflects or transmits all of it. A white wall in a
    // room with any absorbing surface is not such a case.
    let lossless = |m: &Material, c: usize| {
        matches!(
            m,
            Material::Dielectric { .. }
                | Material::RoughDielectric { .. }
                | Material::ThinDielectric { .. }
        ) || lossless_albedo(m, c) >= 1.0
    };
    if let Some(c) = (0..3).find(|&c| {
        !used.is_empty()
            && used
                .iter()
                .all(|&i| lossless(&materials[i as usize].model, c))
    }) {
        // Choice: allowed (an ideal white furnace is a legitimate test), but its dependence on
        // the path-depth cap is stated.
        report.warnings.push(format!(
            "{}: no material absorbs light in channel {c} (every one reflects or transmits all \
             of it); in a closed scene paths then end only at the depth cap (--max-depth) and \
             the result depends on it",
            path.display(),
        ));
    }
    let used_models: Vec<&Material> = used.iter().map(|&i| &materials[i as usize].model).collect();
    let mut material_kinds = Vec::new();
    for m in &used_models {
        m.for_each(&mut |m| material_kinds.push(m.kind()));
    }
    material_kinds.sort();
    material_kinds.dedup();
    let any = |f: fn(&Material) -> bool| used_models.iter().any(|m| f(m));
    let features = Features {
        material_kinds,
        point_emitters: emitters.iter().any(|e| matches!(e, Emitter::Point { .. })),
        area_emitters: emitters.iter().any(|e| matches!(e, Emitter::Area { .. })),
        specular_paths: any(bsdf::has_delta_lobe),
        transmission: any(bsdf::transmits),
        glossy: any(bsdf::is_glossy),
        smooth_normals: b.normals.iter().any(|n| *n != [0.0; 3]),
        normal_maps: scene.surfaces.values().any(|s| s.normal.is_some()),
        spectral: false,
        camera: scene.camera.is_some(),
        sensors: !scene.sensors.is_empty() || !scene.calculation_surfaces.is_empty(),
        goniometric_luminaires: !scene.luminaires.is_empty(),
        uvs: any_uvs,
        textures: !loaded.textures.is_empty(),
        one_sided: scene.surfaces.values().any(|s| !s.two_sided),
        opacity: scene.surfaces.values().any(|s| s.opacity.is_some()),
        environment: scene.environment.is_some(),
    };
    let name = scene_name(scene, path);
    let stats = Stats {
        vertices: b.positions.len() as u64,
        triangles: b.indices.len() as u64,
        dropped_degenerate: b.dropped,
        bounds_min: b.bounds_min,
        bounds_max: b.bounds_max,
        total_area_m2: b.total_area,
    };
    // Below a micrometre the estimators' offsets and f32 geometry lose the light without a
    // word (a Sobolev scene 1e-14 of its size lost its indirect light, 1e-16 its direct light).
    let span = (b.bounds_max - b.bounds_min).length();
    if span < validate::MIN_SCENE_SPAN {
        return Err(Error::input(
            path,
            format!(
                "the geometry spans {} m, below the {} m luxest traces reliably; give lengths \
                 in metres",
                show(span),
                show(validate::MIN_SCENE_SPAN)
            ),
        ));
    }
    let mut sensors = Vec::new();
    for (i, s) in scene.sensors.iter().enumerate() {
        sensors.push(expand_sensor(path, &format!("sensors[{i}]"), s)?);
    }
    for (i, s) in scene.calculation_surfaces.iter().enumerate() {
        sensors.push(surfaces::expand(
            path,
            &format!("calculation_surfaces[{i}]"),
            s,
        )?);
    }
    // Points made from corners plus edges (sensor grids, calculation surfaces, luminaire
    // openings) are bounded like the authored ones.
    for set in &sensors {
        for (k, p) in set.points.iter().enumerate() {
            if let Some(c) = validate::first_beyond_world(p.position) {
                return Err(Error::at(
                    path,
                    format!("sensors \"{}\", point {k}", set.name),
                    validate::out_of_world(c),
                ));
            }
        }
    }
    for e in &emitters {
        if let Emitter::Luminaire {
            name,
            opening_points,
            ..
        } = e
        {
            if let Some(c) = opening_points
                .iter()
                .find_map(|&p| validate::first_beyond_world(p))
            {
                return Err(Error::at(
                    path,
                    format!("luminaire \"{name}\", its opening"),
                    validate::out_of_world(c),
                ));
            }
        }
    }
    let mut header = SceneHeader {
        name,
        compiler_version: luxest_io::meta::PROGRAM_VERSION.to_string(),
        camera: scene.camera.clone(),
        materials,
        emitters,
        emitter_cdf: Vec::new(),
        objects,
        sensors,
        photometries: lum.tables,
        surfaces: textures::surfaces(scene, &loaded),
        glare,
        portals: if scene.environment.is_some() {
            portals
        } else {
            Vec::new()
        },
        textures: loaded.infos,
        features,
        stats,
    };
    // The environment's flux is its light through the disk of the bounding sphere of
    // everything else, so it comes last.
    let mut environment_texels = Vec::new();
    if let Some(env) = &scene.environment {
        let (emitter, texels) = environment::compile(path, env, &header, &mut report.warnings)?;
        header.emitters.push(emitter);
        environment_texels = texels;
    }
    let fluxes: Vec<f64> = header.emitters.iter().map(Emitter::flux_lm).collect();
    header.emitter_cdf = luxest_render::sampling::Distribution1D::new(&fluxes)
        .ok_or_else(|| Error::input(path, "emitters have no finite positive total flux"))?
        .cdf()
        .to_vec();
    let compiled = CompiledScene {
        header,
        positions: b.positions,
        normals: b.normals,
        indices: b.indices,
        triangle_material: b.triangle_material,
        triangle_emitter: b.triangle_emitter,
        uvs: if any_uvs { b.uvs } else { Vec::new() },
        textures: loaded.textures,
        environment_texels,
        content_hash: String::new(),
    };
    compiled
        .check_consistency()
        .map_err(|m| Error::input(path, m))?;
    observers::check_open_space(path, &compiled)?;
    Ok((compiled, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use luxest_render::scene::MaterialKind;

    /// A floor quad per material of `materials` (RON), lit by a point light.
    fn compiled(materials: &[(&str, &str)]) -> (CompiledScene, Report) {
        let mut text = String::from("Scene(materials: {");
        for (name, m) in materials {
            text += &format!("\"{name}\": {m},");
        }
        text += "}, objects: [";
        for (i, (name, _)) in materials.iter().enumerate() {
            text += &format!(
                "(shape: Quad(corner: ({i}.0, 0.0, 0.0), u: (1.0, 0.0, 0.0), v: (0.0, 0.0, -1.0)), material: \"{name}\"),"
            );
        }
        text += "], point_lights: [(position: (0.5, 1.0, -0.5), power: Intensity(10.0))])";
        let path = Path::new("features.ron");
        let scene: Scene = luxest_io::fsio::parse_ron(path, &text).unwrap();
        compile(&scene, path).unwrap()
    }

    #[test]
    fn features_follow_the_lobes_of_the_mitsuba_materials() {
        let (s, _) = compiled(&[(
            "rough plastic",
            "Plastic(diffuse_reflectance: (0.5, 0.5, 0.5), roughness: Some((distribution: Ggx, alpha: 0.2)))",
        )]);
        let f = &s.header.features;
        assert!(f.glossy && !f.specular_paths && !f.transmission);
        // A smooth coating is a delta lobe; a rough dielectric transmits glossily; a blend
        // lists what it blends.
        let (s, _) = compiled(&[
            ("plastic", "Plastic(diffuse_reflectance: (0.5, 0.5, 0.5))"),
            (
                "frosted",
                "RoughDielectric(ior: 1.5, roughness: (distribution: Beckmann, alpha: 0.2))",
            ),
            (
                "worn",
                "Blend(weight: 0.5, first: Conductor(eta: (0.2, 0.4, 1.4), k: (4.0, 2.4, 1.6)), second: Lambertian(reflectance: (0.5, 0.5, 0.5)))",
            ),
        ]);
        let f = &s.header.features;
        assert!(f.glossy && f.specular_paths && f.transmission);
        assert_eq!(
            f.material_kinds,
            [
                MaterialKind::Lambertian,
                MaterialKind::Conductor,
                MaterialKind::Plastic,
                MaterialKind::RoughDielectric,
                MaterialKind::Blend,
            ]
        );
        let (s, _) = compiled(&[("window", "ThinDielectric(ior: 1.5)")]);
        let f = &s.header.features;
        assert!(!f.glossy && f.specular_paths && f.transmission);
    }

    #[test]
    fn a_lossless_conductor_is_warned_about() {
        // Mitsuba's `none`: Fresnel reflectance 1 at every angle.
        let (_, report) = compiled(&[(
            "chrome",
            "Conductor(eta: (0.0, 0.0, 0.0), k: (1.0, 1.0, 1.0))",
        )]);
        assert!(report
            .warnings
            .iter()
            .any(|w| w.contains("no material absorbs light in channel 0")));
        let (_, report) = compiled(&[(
            "gold",
            "Conductor(eta: (0.14, 0.37, 1.44), k: (3.98, 2.39, 1.60))",
        )]);
        assert!(!report.warnings.iter().any(|w| w.contains("absorbs")));
    }
}
