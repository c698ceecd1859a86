//! Checks on the authored scene that serde cannot express: finiteness, ranges, references.
//! Each failure names the scene file and the place (`materials["white"].reflectance`).

use luxest_core::color::Rgb;
use luxest_core::math::Vec3;
use luxest_core::scene::{
    Camera, Emission, Material, PointLight, PointPower, Scene, Sensor, Shape,
};
use luxest_core::{Error, Result};
use std::path::Path;

/// Largest icosphere subdivision level (20 * 4^8 = 1.3 M triangles).
pub const MAX_SPHERE_SUBDIVISIONS: u32 = 8;
/// Largest image side accepted for the camera.
pub const MAX_RESOLUTION: u32 = 1 << 15;

struct Check<'a> {
    path: &'a Path,
}

impl Check<'_> {
    fn fail(&self, place: &str, msg: impl Into<String>) -> Error {
        Error::at(self.path, place, msg)
    }
    fn finite(&self, place: &str, v: f64) -> Result<()> {
        if v.is_finite() {
            Ok(())
        } else {
            Err(self.fail(place, format!("{v} is not a finite number")))
        }
    }
    fn vec(&self, place: &str, v: Vec3) -> Result<()> {
        for (i, c) in [v.x, v.y, v.z].into_iter().enumerate() {
            self.finite(&format!("{place}[{i}]"), c)?;
        }
        Ok(())
    }
    fn nonzero_vec(&self, place: &str, v: Vec3) -> Result<Vec3> {
        self.vec(place, v)?;
        v.try_normalize()
            .ok_or_else(|| self.fail(place, "must not be the zero vector"))
    }
    fn rgb_in(&self, place: &str, c: Rgb, lo: f64, hi: f64, what: &str) -> Result<()> {
        for (i, v) in c.0.into_iter().enumerate() {
            self.finite(&format!("{place}[{i}]"), v)?;
            if !(lo..=hi).contains(&v) {
                return Err(self.fail(place, format!("{what} {v} is outside [{lo}, {hi}]")));
            }
        }
        Ok(())
    }
    fn positive(&self, place: &str, v: f64, what: &str) -> Result<()> {
        self.finite(place, v)?;
        if v > 0.0 {
            Ok(())
        } else {
            Err(self.fail(place, format!("{what} must be positive, got {v}")))
        }
    }
    /// A tint or radiance: finite, non-negative, with positive luminance.
    fn emission_rgb(&self, place: &str, c: Rgb) -> Result<()> {
        self.rgb_in(place, c, 0.0, f64::MAX, "emission component")?;
        if c.luminance() > 0.0 {
            Ok(())
        } else {
            Err(self.fail(place, "emitter has zero power (luminance 0)"))
        }
    }
}

fn check_camera(c: &Check, cam: &Camera) -> Result<()> {
    c.vec("camera.position", cam.position)?;
    c.vec("camera.look_at", cam.look_at)?;
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
        Material::Dielectric { ior } => {
            c.positive(&format!("{place}.ior"), *ior, "index of refraction")?;
            if *ior > 10.0 {
                return Err(c.fail(&format!("{place}.ior"), format!("{ior} is outside (0, 10]")));
            }
            Ok(())
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

fn check_point_light(c: &Check, place: &str, l: &PointLight) -> Result<()> {
    c.vec(&format!("{place}.position"), l.position)?;
    let v = match l.power {
        PointPower::Intensity(v) | PointPower::Flux(v) => v,
    };
    c.finite(&format!("{place}.power"), v)?;
    if v <= 0.0 {
        return Err(c.fail(
            &format!("{place}.power"),
            format!("emitter power must be positive, got {v}"),
        ));
    }
    c.emission_rgb(&format!("{place}.color"), l.color)
}

fn check_sensor(c: &Check, place: &str, s: &Sensor) -> Result<()> {
    match s {
        Sensor::Points { points, .. } => {
            if points.is_empty() {
                return Err(c.fail(place, "sensor list has no points"));
            }
            for (i, p) in points.iter().enumerate() {
                c.vec(&format!("{place}.points[{i}].position"), p.position)?;
                c.nonzero_vec(&format!("{place}.points[{i}].normal"), p.normal)?;
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
            c.vec(&format!("{place}.corner"), *corner)?;
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
            Shape::Obj { .. } | Shape::Gltf { .. } => {}
        }
        match &o.emission {
            None => {}
            Some(Emission::Radiance(l)) => c.emission_rgb(&format!("{place}.emission"), *l)?,
            Some(Emission::Flux { lumens, color }) => {
                c.finite(&format!("{place}.emission.lumens"), *lumens)?;
                if *lumens <= 0.0 {
                    return Err(c.fail(
                        &format!("{place}.emission.lumens"),
                        format!("emitter power must be positive, got {lumens}"),
                    ));
                }
                c.emission_rgb(&format!("{place}.emission.color"), *color)?;
            }
        }
    }
    for (i, l) in scene.point_lights.iter().enumerate() {
        check_point_light(&c, &format!("point_lights[{i}]"), l)?;
    }
    if scene.point_lights.is_empty() && scene.objects.iter().all(|o| o.emission.is_none()) {
        return Err(Error::input(
            path,
            "scene has no emitter (no point light and no object with emission)",
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
    Ok(())
}
