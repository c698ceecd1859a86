//! Checks on the authored scene that serde cannot express: finiteness, ranges, references.
//! Each failure names the scene file and the place (`materials["white"].reflectance`).

use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_io::num::show;
use luxest_io::{Error, Result};
use luxest_render::scene::{
    Camera, Emission, Environment, Material, Microfacet, PointLight, PointPower, Scene, Sensor,
    Shape,
};
use std::path::Path;

/// Largest icosphere subdivision level (20 * 4^8 = 1.3 M triangles).
pub const MAX_SPHERE_SUBDIVISIONS: u32 = 8;
/// Largest image side accepted for the camera.
pub const MAX_RESOLUTION: u32 = 1 << 15;

/// Largest radiance (cd/m² or W/(sr m²) per channel), intensity (cd) and flux (lm) an emitter
/// may have. Images are written as f32 (largest 3.4e38), and the estimators multiply the power by
/// geometric kernels (1/r² for r down to a millimetre: 1e6) and sum it over up to 2^53 samples in
/// f64; 1e25 keeps all of these finite with margins of ten orders of magnitude.
pub const MAX_EMISSION: f64 = 1e25;

/// Largest |coordinate| of any point of a scene, m (6700 astronomical units). Embree's ray
/// queries require |origin| below 1.8e18 (beyond, the library aborts the process or drops the
/// geometry), and f32 vertices are spaced 1e-7 of their magnitude apart: 1e15 leaves three
/// orders of magnitude for offsets and room for a 1 m room to be resolved 1e8 m from the origin.
pub const MAX_COORDINATE: f64 = 1e15;

/// Smallest bounding-box diagonal of a scene's geometry, m: Sobolev scenes (2000 m across)
/// scaled by s matched the exact solution down to s = 1e-11 (2e-8 m), were biased at 1e-12 and
/// lost light below; 1e-6 m keeps a margin of fifty, and no lighting scene is smaller.
pub const MIN_SCENE_SPAN: f64 = 1e-6;

/// Whether the coordinate `c` lies beyond ±[`MAX_COORDINATE`] (or is NaN): the one test of
/// every point of a scene, authored or computed.
pub(crate) fn beyond_world(c: f64) -> bool {
    c.is_nan() || c.abs() > MAX_COORDINATE
}

/// The first coordinate of `p` that is [`beyond_world`], if any.
pub(crate) fn first_beyond_world(p: Vec3) -> Option<f64> {
    [p.x, p.y, p.z].into_iter().find(|&c| beyond_world(c))
}

/// The message for a coordinate [`beyond_world`].
pub(crate) fn out_of_world(v: f64) -> String {
    format!(
        "{} m is outside the world coordinates luxest can trace (±{} m)",
        show(v),
        show(MAX_COORDINATE)
    )
}

pub(crate) struct Check<'a> {
    pub(crate) path: &'a Path,
}

impl Check<'_> {
    /// `name` must be a key of the scene's `textures`.
    pub(crate) fn texture_name(&self, scene: &Scene, place: &str, name: &str) -> Result<()> {
        if scene.textures.contains_key(name) {
            Ok(())
        } else {
            Err(self.fail(place, format!("unknown texture \"{name}\"")))
        }
    }

    pub(crate) fn fail(&self, place: &str, msg: impl Into<String>) -> Error {
        Error::at(self.path, place, msg)
    }
    pub(crate) fn finite(&self, place: &str, v: f64) -> Result<()> {
        if v.is_finite() {
            Ok(())
        } else {
            Err(self.fail(place, format!("{v} is not a finite number")))
        }
    }
    pub(crate) fn vec(&self, place: &str, v: Vec3) -> Result<()> {
        for (i, c) in [v.x, v.y, v.z].into_iter().enumerate() {
            self.finite(&format!("{place}[{i}]"), c)?;
        }
        Ok(())
    }
    /// A point of the scene: finite and within ±[`MAX_COORDINATE`].
    pub(crate) fn position(&self, place: &str, v: Vec3) -> Result<()> {
        for (i, c) in [v.x, v.y, v.z].into_iter().enumerate() {
            let place = format!("{place}[{i}]");
            self.finite(&place, c)?;
            if beyond_world(c) {
                return Err(self.fail(&place, out_of_world(c)));
            }
        }
        Ok(())
    }
    pub(crate) fn nonzero_vec(&self, place: &str, v: Vec3) -> Result<Vec3> {
        self.vec(place, v)?;
        v.try_normalize()
            .ok_or_else(|| self.fail(place, "must not be the zero vector"))
    }
    pub(crate) fn rgb_in(&self, place: &str, c: Rgb, lo: f64, hi: f64, what: &str) -> Result<()> {
        for (i, v) in c.0.into_iter().enumerate() {
            self.finite(&format!("{place}[{i}]"), v)?;
            if !(lo..=hi).contains(&v) {
                return Err(self.fail(
                    place,
                    format!("{what} {} is outside [{}, {}]", show(v), show(lo), show(hi)),
                ));
            }
        }
        Ok(())
    }
    pub(crate) fn positive(&self, place: &str, v: f64, what: &str) -> Result<()> {
        self.finite(place, v)?;
        if v > 0.0 {
            Ok(())
        } else {
            Err(self.fail(place, format!("{what} must be positive, got {}", show(v))))
        }
    }
    /// A tint or radiance: finite, non-negative, with positive luminance.
    pub(crate) fn emission_rgb(&self, place: &str, c: Rgb) -> Result<()> {
        self.rgb_in(place, c, 0.0, MAX_EMISSION, "emission component")?;
        if c.luminance() > 0.0 {
            Ok(())
        } else {
            Err(self.fail(place, "emitter has zero power (luminance 0)"))
        }
    }
}

fn check_camera(c: &Check, cam: &Camera) -> Result<()> {
    c.position("camera.position", cam.position)?;
    c.position("camera.look_at", cam.look_at)?;
    let dir = c
        .nonzero_vec("camera.look_at", cam.look_at - cam.position)
        .map_err(|_| c.fail("camera.look_at", "equals camera.position"))?;
    let up = c.nonzero_vec("camera.up", cam.up)?;
    if dir.cross(up).length() < 1e-6 {
        return Err(c.fail("camera.up", "is parallel to the viewing direction"));
    }
    c.finite("camera.vfov_deg", cam.vfov_deg)?;
    if !(cam.vfov_deg > 0.0 && cam.vfov_deg < 180.0) {
        return Err(c.fail(
            "camera.vfov_deg",
            format!("{} is outside (0, 180)", cam.vfov_deg),
        ));
    }
    let (w, h) = cam.resolution;
    if w == 0 || h == 0 || w > MAX_RESOLUTION || h > MAX_RESOLUTION {
        return Err(c.fail(
            "camera.resolution",
            format!("{w}x{h} is outside 1..={MAX_RESOLUTION} per side"),
        ));
    }
    Ok(())
}

fn check_material(c: &Check, place: &str, m: &Material) -> Result<()> {
    match m {
        Material::Lambertian { reflectance } | Material::Mirror { reflectance } => c.rgb_in(
            &format!("{place}.reflectance"),
            *reflectance,
            0.0,
            1.0,
            "reflectance",
        ),
        Material::Dielectric { ior } | Material::ThinDielectric { ior } => {
            check_ior(c, place, *ior, false)
        }
        Material::Conductor {
            eta,
            k,
            specular_reflectance,
            roughness,
        } => {
            c.rgb_in(
                &format!("{place}.eta"),
                *eta,
                0.0,
                MAX_CONDUCTOR_IOR,
                "index of refraction",
            )?;
            c.rgb_in(
                &format!("{place}.k"),
                *k,
                0.0,
                MAX_CONDUCTOR_IOR,
                "extinction coefficient",
            )?;
            if let Some(i) = (0..3).find(|&i| eta.0[i] == 0.0 && k.0[i] == 0.0) {
                return Err(c.fail(
                    place,
                    format!("eta and k are both 0 in channel {i} (no interface)"),
                ));
            }
            c.rgb_in(
                &format!("{place}.specular_reflectance"),
                *specular_reflectance,
                0.0,
                1.0,
                "reflectance",
            )?;
            check_roughness(c, place, roughness.as_ref())
        }
        Material::Plastic {
            diffuse_reflectance,
            specular_reflectance,
            ior,
            nonlinear: _,
            roughness,
        } => {
            c.rgb_in(
                &format!("{place}.diffuse_reflectance"),
                *diffuse_reflectance,
                0.0,
                1.0,
                "reflectance",
            )?;
            c.rgb_in(
                &format!("{place}.specular_reflectance"),
                *specular_reflectance,
                0.0,
                1.0,
                "reflectance",
            )?;
            // Mitsuba's roughplastic refuses an index-matched coating (its tables divide by it).
            check_ior(c, place, *ior, roughness.is_some())?;
            check_roughness(c, place, roughness.as_ref())
        }
        Material::RoughDielectric { ior, roughness } => {
            check_ior(c, place, *ior, true)?;
            check_roughness(c, place, Some(roughness))
        }
        Material::Blend {
            weight,
            first,
            second,
        } => {
            c.finite(&format!("{place}.weight"), *weight)?;
            if !(0.0..=1.0).contains(weight) {
                return Err(c.fail(
                    &format!("{place}.weight"),
                    format!("{} is outside [0, 1]", show(*weight)),
                ));
            }
            check_material(c, &format!("{place}.first"), first)?;
            check_material(c, &format!("{place}.second"), second)
        }
        Material::Glossy {
            diffuse,
            specular,
            roughness,
        } => {
            c.rgb_in(
                &format!("{place}.diffuse"),
                *diffuse,
                0.0,
                1.0,
                "reflectance",
            )?;
            c.rgb_in(
                &format!("{place}.specular"),
                *specular,
                0.0,
                1.0,
                "reflectance",
            )?;
            if let Some(i) = (0..3).find(|&i| diffuse.0[i] + specular.0[i] > 1.0) {
                return Err(c.fail(
                    place,
                    format!(
                        "diffuse + specular = {} in channel {i} exceeds 1 (not energy conserving)",
                        diffuse.0[i] + specular.0[i]
                    ),
                ));
            }
            c.finite(&format!("{place}.roughness"), *roughness)?;
            if !(*roughness > 0.0 && *roughness <= 1.0) {
                return Err(c.fail(
                    &format!("{place}.roughness"),
                    format!("{roughness} is outside (0, 1]"),
                ));
            }
            Ok(())
        }
    }
}

/// Largest index of refraction (real part or extinction coefficient) a conductor may have:
/// metals in the visible stay below 10 (silver's k ≈ 4, aluminium's ≈ 8).
const MAX_CONDUCTOR_IOR: f64 = 100.0;

/// A dielectric's relative index of refraction: in (0, 10], and not 1 where the model
/// (a rough interface) needs an interface.
fn check_ior(c: &Check, place: &str, ior: f64, interface: bool) -> Result<()> {
    c.positive(&format!("{place}.ior"), ior, "index of refraction")?;
    if ior > 10.0 {
        return Err(c.fail(&format!("{place}.ior"), format!("{ior} is outside (0, 10]")));
    }
    if interface && ior == 1.0 {
        return Err(c.fail(
            &format!("{place}.ior"),
            "1 matches the outside: a rough interface needs an index other than 1",
        ));
    }
    Ok(())
}

/// Largest microfacet α accepted: beyond it a "rough" surface is no longer a microfacet
/// surface (Mitsuba accepts any α; the scenes it ships stay below 1).
const MAX_ALPHA: f64 = 4.0;

fn check_roughness(c: &Check, place: &str, r: Option<&Microfacet>) -> Result<()> {
    let Some(r) = r else {
        return Ok(());
    };
    let at = format!("{place}.roughness.alpha");
    c.finite(&at, r.alpha)?;
    if !(r.alpha > 0.0 && r.alpha <= MAX_ALPHA) {
        return Err(c.fail(
            &at,
            format!("{} is outside (0, {}]", show(r.alpha), show(MAX_ALPHA)),
        ));
    }
    Ok(())
}

fn check_point_light(c: &Check, place: &str, l: &PointLight) -> Result<()> {
    c.position(&format!("{place}.position"), l.position)?;
    let v = match l.power {
        PointPower::Intensity(v) | PointPower::Flux(v) => v,
    };
    c.finite(&format!("{place}.power"), v)?;
    if v <= 0.0 {
        return Err(c.fail(
            &format!("{place}.power"),
            format!("emitter power must be positive, got {}", show(v)),
        ));
    }
    if v > MAX_EMISSION {
        return Err(c.fail(
            &format!("{place}.power"),
            format!(
                "{} exceeds {}, beyond which the estimators' arithmetic and f32 images overflow",
                show(v),
                show(MAX_EMISSION)
            ),
        ));
    }
    c.emission_rgb(&format!("{place}.color"), l.color)?;
    if let Some(spot) = &l.spot {
        let place = format!("{place}.spot");
        c.nonzero_vec(&format!("{place}.direction"), spot.direction)?;
        let (cut, beam) = (spot.cutoff_deg, spot.beam_width_deg);
        c.finite(&format!("{place}.cutoff_deg"), cut)?;
        c.finite(&format!("{place}.beam_width_deg"), beam)?;
        if !(cut > 0.0 && cut <= 180.0) {
            return Err(c.fail(
                &format!("{place}.cutoff_deg"),
                format!("the cutoff must be in (0, 180] degrees, got {}", show(cut)),
            ));
        }
        if !(0.0..=cut).contains(&beam) {
            return Err(c.fail(
                &format!("{place}.beam_width_deg"),
                format!(
                    "the beam width must be in [0, cutoff_deg = {}] degrees, got {}",
                    show(cut),
                    show(beam)
                ),
            ));
        }
    }
    Ok(())
}

/// An environment: a constant radiance like an emitter's; a map's scale positive and its
/// `to_world` a rotation (the file is read when compiling); a sky's date, place and level in
/// range and its sky not black.
fn check_environment(c: &Check, env: &Environment) -> Result<()> {
    match env {
        Environment::Constant(l) => c.emission_rgb("environment.Constant", *l),
        Environment::Map {
            scale, to_world, ..
        } => {
            c.positive("environment.scale", *scale, "the map's scale")?;
            if *scale > MAX_EMISSION {
                return Err(c.fail(
                    "environment.scale",
                    format!("{} exceeds {}", show(*scale), show(MAX_EMISSION)),
                ));
            }
            for (i, row) in to_world.iter().enumerate() {
                c.vec(&format!("environment.to_world[{i}]"), Vec3::from(*row))?;
            }
            luxest_render::compiled::check_rotation(to_world)
                .map_err(|m| c.fail("environment.to_world", m))
        }
        Environment::Sky(sky) => sky
            .model()
            .map(|_| ())
            .map_err(|m| c.fail("environment.Sky", m)),
    }
}

fn check_sensor(c: &Check, place: &str, s: &Sensor) -> Result<()> {
    match s {
        Sensor::Points { points, .. } => {
            if points.is_empty() {
                return Err(c.fail(place, "sensor list has no points"));
            }
            for (i, p) in points.iter().enumerate() {
                c.position(&format!("{place}.points[{i}].position"), p.position)?;
                c.nonzero_vec(&format!("{place}.points[{i}].normal"), p.normal)?;
                crate::surfaces::normalised_kind(c, &format!("{place}.points[{i}].kind"), &p.kind)?;
            }
        }
        Sensor::Grid {
            corner,
            u,
            v,
            counts,
            normal,
            ..
        } => {
            c.position(&format!("{place}.corner"), *corner)?;
            c.nonzero_vec(&format!("{place}.u"), *u)?;
            c.nonzero_vec(&format!("{place}.v"), *v)?;
            if u.cross(*v).try_normalize().is_none() {
                return Err(c.fail(place, "u and v are parallel"));
            }
            if counts.0 == 0 || counts.1 == 0 || (counts.0 as u64) * (counts.1 as u64) > 1 << 24 {
                return Err(c.fail(
                    &format!("{place}.counts"),
                    format!("{counts:?} must be positive, at most 2^24 points"),
                ));
            }
            if let Some(n) = normal {
                c.nonzero_vec(&format!("{place}.normal"), *n)?;
            }
        }
    }
    Ok(())
}

/// Validates everything that does not need the mesh files.
pub fn check_scene(path: &Path, scene: &Scene) -> Result<()> {
    let c = Check { path };
    if let Some(name) = &scene.name {
        // The name becomes the default output directory build/<name>/.
        luxest_io::outputs::path_component(name, path, "name")?;
    }
    check_unique_names(&c, scene)?;
    if let Some(cam) = &scene.camera {
        check_camera(&c, cam)?;
    }
    for (name, m) in &scene.materials {
        check_material(&c, &format!("materials[\"{name}\"]"), m)?;
    }
    for (i, o) in scene.objects.iter().enumerate() {
        let place = format!("objects[{i}]");
        if !scene.materials.contains_key(&o.material) {
            return Err(c.fail(
                &format!("{place}.material"),
                format!("unknown material \"{}\"", o.material),
            ));
        }
        let t = &o.transform;
        c.vec(&format!("{place}.transform.scale"), t.scale)?;
        c.vec(&format!("{place}.transform.rotate_deg"), t.rotate_deg)?;
        c.vec(&format!("{place}.transform.translate"), t.translate)?;
        if let Some(m) = &t.matrix {
            for (r, row) in m.iter().enumerate() {
                for (k, v) in row.iter().enumerate() {
                    c.finite(&format!("{place}.transform.matrix[{r}][{k}]"), *v)?;
                }
            }
            let det = t.to_affine().determinant();
            if !(det.is_finite() && det != 0.0) {
                return Err(c.fail(
                    &format!("{place}.transform.matrix"),
                    "is singular (flattens the object)",
                ));
            }
        }
        for (i, v) in [t.translate.x, t.translate.y, t.translate.z]
            .into_iter()
            .enumerate()
        {
            if beyond_world(v) {
                return Err(c.fail(
                    &format!("{place}.transform.translate[{i}]"),
                    out_of_world(v),
                ));
            }
        }
        if t.scale.x == 0.0 || t.scale.y == 0.0 || t.scale.z == 0.0 {
            return Err(c.fail(
                &format!("{place}.transform.scale"),
                "has a zero component (flattens the object)",
            ));
        }
        match &o.shape {
            Shape::Quad { corner, u, v } => {
                c.vec(&format!("{place}.shape.corner"), *corner)?;
                c.vec(&format!("{place}.shape.u"), *u)?;
                c.vec(&format!("{place}.shape.v"), *v)?;
            }
            Shape::Polygon { vertices } => {
                if vertices.len() < 3 {
                    return Err(c.fail(
                        &format!("{place}.shape.vertices"),
                        "a polygon needs at least 3 vertices",
                    ));
                }
                for (k, v) in vertices.iter().enumerate() {
                    c.vec(&format!("{place}.shape.vertices[{k}]"), *v)?;
                }
                check_planar_convex(&c, &format!("{place}.shape.vertices"), vertices)?;
            }
            Shape::Box { size } => {
                c.vec(&format!("{place}.shape.size"), *size)?;
                if size.x <= 0.0 || size.y <= 0.0 || size.z <= 0.0 {
                    return Err(c.fail(
                        &format!("{place}.shape.size"),
                        "box edge lengths must be positive",
                    ));
                }
            }
            Shape::Sphere {
                radius,
                subdivisions,
            } => {
                c.positive(&format!("{place}.shape.radius"), *radius, "radius")?;
                if *subdivisions > MAX_SPHERE_SUBDIVISIONS {
                    return Err(c.fail(
                        &format!("{place}.shape.subdivisions"),
                        format!("{subdivisions} exceeds {MAX_SPHERE_SUBDIVISIONS}"),
                    ));
                }
            }
            Shape::Obj { .. }
            | Shape::Gltf { .. }
            | Shape::Ply { .. }
            | Shape::Serialized { .. } => {}
        }
        match &o.emission {
            None => {}
            Some(Emission::Radiance(l)) => c.emission_rgb(&format!("{place}.emission"), *l)?,
            Some(Emission::Flux { lumens, color }) => {
                c.finite(&format!("{place}.emission.lumens"), *lumens)?;
                if *lumens <= 0.0 {
                    return Err(c.fail(
                        &format!("{place}.emission.lumens"),
                        format!("emitter power must be positive, got {}", show(*lumens)),
                    ));
                }
                if *lumens > MAX_EMISSION {
                    return Err(c.fail(
                        &format!("{place}.emission.lumens"),
                        format!(
                            "{} lm exceeds {} lm, beyond which the estimators' arithmetic and \
                             f32 images overflow",
                            show(*lumens),
                            show(MAX_EMISSION)
                        ),
                    ));
                }
                c.emission_rgb(&format!("{place}.emission.color"), *color)?;
            }
            Some(Emission::Texture { texture, scale }) => {
                c.texture_name(scene, &format!("{place}.emission.texture"), texture)?;
                c.emission_rgb(&format!("{place}.emission.scale"), *scale)?;
            }
        }
    }
    crate::textures::check(&c, scene)?;
    for (i, l) in scene.point_lights.iter().enumerate() {
        check_point_light(&c, &format!("point_lights[{i}]"), l)?;
    }
    for (i, l) in scene.luminaires.iter().enumerate() {
        crate::luminaires::check(&c, &format!("luminaires[{i}]"), l)?;
    }
    if let Some(env) = &scene.environment {
        check_environment(&c, env)?;
    }
    if scene.point_lights.is_empty()
        && scene.luminaires.is_empty()
        && scene.environment.is_none()
        && scene.objects.iter().all(|o| o.emission.is_none())
    {
        return Err(Error::input(
            path,
            "scene has no emitter (no point light, luminaire, environment or object with \
             emission)",
        ));
    }
    let mut names = std::collections::BTreeSet::new();
    for (i, s) in scene.sensors.iter().enumerate() {
        let place = format!("sensors[{i}]");
        let name = match s {
            Sensor::Points { name, .. } | Sensor::Grid { name, .. } => name,
        };
        if !names.insert(name.clone()) {
            return Err(c.fail(
                &format!("{place}.name"),
                format!("duplicate sensor name \"{name}\""),
            ));
        }
        check_sensor(&c, &place, s)?;
    }
    for (i, s) in scene.calculation_surfaces.iter().enumerate() {
        let place = format!("calculation_surfaces[{i}]");
        if !names.insert(s.name.clone()) {
            return Err(c.fail(
                &format!("{place}.name"),
                format!("duplicate sensor name \"{}\"", s.name),
            ));
        }
        crate::surfaces::check(&c, &place, s)?;
    }
    Ok(())
}

/// Object and point-light names name the emitters in compiled scenes and reports: each may be
/// given once (unnamed ones are named by their place).
fn check_unique_names(c: &Check, scene: &Scene) -> Result<()> {
    let mut seen: std::collections::BTreeMap<&str, String> = std::collections::BTreeMap::new();
    let objects = scene
        .objects
        .iter()
        .enumerate()
        .filter_map(|(i, o)| Some((o.name.as_deref()?, format!("objects[{i}].name"))));
    let lights = scene
        .point_lights
        .iter()
        .enumerate()
        .filter_map(|(i, l)| Some((l.name.as_deref()?, format!("point_lights[{i}].name"))));
    for (name, place) in objects.chain(lights) {
        if let Some(first) = seen.get(name) {
            return Err(c.fail(
                &place,
                format!("duplicate name \"{name}\" (already used by {first})"),
            ));
        }
        seen.insert(name, place);
    }
    Ok(())
}

/// How far a polygon's vertex may be from its plane, as a fraction of the polygon's size. Measured
/// geometry is not exactly planar (the Cornell box's walls are off by up to 1.5e-3 of their size);
/// its fan triangulation is still a faithful surface. Beyond 1 % the triangulation would depend on
/// the order of the vertices.
const PLANARITY_TOLERANCE: f64 = 1e-2;
/// Relative tolerance of the convexity test (collinear vertices are allowed).
const POLYGON_TOLERANCE: f64 = 1e-9;

/// A polygon must be planar and convex (it is triangulated as a fan): every vertex within
/// `POLYGON_TOLERANCE` of the polygon's size from the plane of its Newell normal, and every turn
/// between consecutive edges the same way round, turning once in all.
fn check_planar_convex(c: &Check, place: &str, vertices: &[Vec3]) -> Result<()> {
    let n = vertices.len();
    // Newell's method: a robust normal for any simple polygon (Sutherland et al. 1974).
    let mut normal = Vec3::splat(0.0);
    for i in 0..n {
        let (a, b) = (vertices[i], vertices[(i + 1) % n]);
        normal += Vec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let size = vertices
        .iter()
        .map(|v| (*v - vertices[0]).length())
        .fold(0.0, f64::max);
    let Some(normal) = normal.try_normalize().filter(|_| size > 0.0) else {
        return Err(c.fail(place, "polygon has zero area (all vertices on a line)"));
    };
    let centroid = vertices.iter().fold(Vec3::splat(0.0), |s, v| s + *v) * (1.0 / n as f64);
    for (k, v) in vertices.iter().enumerate() {
        let off = (*v - centroid).dot(normal);
        if off.abs() > PLANARITY_TOLERANCE * size {
            return Err(c.fail(
                &format!("{place}[{k}]"),
                format!(
                    "polygon is not planar: this vertex is {} m off the polygon's plane, more \
                     than 1 % of its size {} m (polygons must be planar and convex)",
                    show(off.abs()),
                    show(size)
                ),
            ));
        }
    }
    // Convexity in the polygon's plane: project onto an orthonormal basis (t1, t2) of it.
    let t1 = (vertices[1] - vertices[0] - normal * (vertices[1] - vertices[0]).dot(normal))
        .try_normalize()
        .unwrap_or_else(|| normal.cross(Vec3::new(1.0, 0.0, 0.0)));
    let t2 = normal.cross(t1);
    let flat: Vec<(f64, f64)> = vertices
        .iter()
        .map(|v| ((*v - centroid).dot(t1), (*v - centroid).dot(t2)))
        .collect();
    let mut turning = 0.0;
    for k in 0..n {
        let (a, b, d) = (flat[(k + n - 1) % n], flat[k], flat[(k + 1) % n]);
        let (e0, e1) = ((b.0 - a.0, b.1 - a.1), (d.0 - b.0, d.1 - b.1));
        let cross = e0.0 * e1.1 - e0.1 * e1.0;
        let dot = e0.0 * e1.0 + e0.1 * e1.1;
        if cross < -POLYGON_TOLERANCE * size * size {
            return Err(c.fail(
                &format!("{place}[{k}]"),
                "polygon is not convex: it turns the other way at this vertex \
                 (polygons must be planar and convex)",
            ));
        }
        turning += cross.atan2(dot);
    }
    // A convex polygon turns by 2π in all; a star (self-intersecting) one by a multiple of it.
    if (turning - 2.0 * std::f64::consts::PI).abs() > 1e-6 {
        return Err(c.fail(
            place,
            "polygon is not convex: its edges cross or it winds more than once \
             (polygons must be planar and convex)",
        ));
    }
    Ok(())
}
