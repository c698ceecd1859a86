//! The authored scene format (`scenes/*.ron`), as documented in `docs/scene-format.md`.
//!
//! These types are what a person or `data-gen` writes. They may reference mesh files and use
//! local transforms; `scene-compile` turns them into a [`crate::compiled::CompiledScene`].
//! Units: metres, degrees, candela, lumen, cd/m² (luminance). Unknown fields are errors.

use crate::color::Rgb;
use crate::math::Vec3;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A whole authored scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Optional display name; defaults to the file stem.
    #[serde(default)]
    pub name: Option<String>,
    /// The pinhole camera; scenes used only for sensor estimates may omit it.
    #[serde(default)]
    pub camera: Option<Camera>,
    /// Materials by name, referenced from objects.
    pub materials: BTreeMap<String, Material>,
    /// Surfaces: a shape, a transform, a material and optionally an emission.
    pub objects: Vec<Object>,
    /// Point sources.
    #[serde(default)]
    pub point_lights: Vec<PointLight>,
    /// Illuminance sensors (point lists and grids).
    #[serde(default)]
    pub sensors: Vec<Sensor>,
}

/// Pinhole camera.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Eye position, m.
    pub position: Vec3,
    /// A point the camera looks at, m.
    pub look_at: Vec3,
    /// Up direction (need not be orthogonal to the view direction).
    #[serde(default = "default_up")]
    pub up: Vec3,
    /// Vertical field of view, degrees, in (0, 180).
    pub vfov_deg: f64,
    /// Image width and height in pixels.
    pub resolution: (u32, u32),
}

fn default_up() -> Vec3 {
    Vec3::new(0.0, 1.0, 0.0)
}

/// Surface scattering models. Reflectances are linear RGB in [0, 1].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Material {
    /// Ideal diffuse reflector: BRDF = reflectance / pi.
    Lambertian { reflectance: Rgb },
    /// Ideal specular reflector.
    Mirror { reflectance: Rgb },
    /// Smooth dielectric interface (glass, water) with Fresnel reflection and refraction.
    Dielectric {
        /// Index of refraction of the inside relative to the outside (the side the normal points to).
        ior: f64,
    },
    /// A diffuse base plus a GGX microfacet specular lobe:
    /// f = diffuse/pi + specular * D_GGX(alpha = roughness²) G / (4 cos_i cos_o).
    /// Energy-bounded by requiring diffuse + specular <= 1 per channel.
    Glossy {
        diffuse: Rgb,
        specular: Rgb,
        roughness: f64,
    },
}

/// The kind of a material, as listed in the features manifest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum MaterialKind {
    Lambertian,
    Mirror,
    Dielectric,
    Glossy,
}

impl Material {
    pub fn kind(&self) -> MaterialKind {
        match self {
            Material::Lambertian { .. } => MaterialKind::Lambertian,
            Material::Mirror { .. } => MaterialKind::Mirror,
            Material::Dielectric { .. } => MaterialKind::Dielectric,
            Material::Glossy { .. } => MaterialKind::Glossy,
        }
    }
}

/// A surface in the scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Object {
    /// Optional name used in messages and the compiled object table.
    #[serde(default)]
    pub name: Option<String>,
    pub shape: Shape,
    #[serde(default)]
    pub transform: Transform,
    /// Name of an entry of `materials`.
    pub material: String,
    /// Makes the object a diffuse area emitter (emitting from its front side).
    #[serde(default)]
    pub emission: Option<Emission>,
    /// Reverses the front side (e.g. a box seen from the inside, a room).
    #[serde(default)]
    pub flip_normals: bool,
}

/// Geometry of an object, in its local frame (before `transform`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Shape {
    /// The parallelogram `corner + s u + t v`, s, t in [0, 1]; front side along `u x v`.
    Quad { corner: Vec3, u: Vec3, v: Vec3 },
    /// A planar convex polygon, fan-triangulated from the first vertex; front side by the
    /// right-hand rule of the vertex order (counter-clockwise seen from the front).
    Polygon { vertices: Vec<Vec3> },
    /// An axis-aligned box centred on the origin with edge lengths `size`; normals point out.
    Box { size: Vec3 },
    /// A sphere of `radius` centred on the origin, tessellated as an icosphere with
    /// `20 * 4^subdivisions` triangles whose vertices lie on the sphere; normals point out.
    Sphere { radius: f64, subdivisions: u32 },
    /// A Wavefront OBJ mesh (path relative to the scene file). Polygons are triangulated;
    /// OBJ materials are ignored (the object's `material` applies).
    Obj { path: String },
    /// A glTF 2.0 mesh, `.gltf` (with external or embedded buffers) or `.glb`; every mesh of
    /// the default scene with its node transforms. glTF materials are ignored.
    Gltf { path: String },
}

/// Local-to-world transform: scale, then rotate about x, then y, then z (degrees,
/// right-handed), then translate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Transform {
    pub scale: Vec3,
    pub rotate_deg: Vec3,
    pub translate: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            scale: Vec3::splat(1.0),
            rotate_deg: Vec3::ZERO,
            translate: Vec3::ZERO,
        }
    }
}

impl Transform {
    pub fn to_affine(&self) -> crate::math::Affine {
        use crate::math::Affine;
        Affine::translate(self.translate)
            .compose(&Affine::rotate_axis(2, self.rotate_deg.z))
            .compose(&Affine::rotate_axis(1, self.rotate_deg.y))
            .compose(&Affine::rotate_axis(0, self.rotate_deg.x))
            .compose(&Affine::scale(self.scale))
    }
}

/// Emission of a diffuse (Lambertian) area emitter, from the front side only.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Emission {
    /// Luminance in cd/m² per RGB channel (Y is the photometric luminance).
    Radiance(Rgb),
    /// Total flux in lm, spread uniformly over the emitting area: L = flux / (pi A).
    Flux {
        lumens: f64,
        #[serde(default = "white")]
        color: Rgb,
    },
}

/// An isotropic point source.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointLight {
    #[serde(default)]
    pub name: Option<String>,
    pub position: Vec3,
    pub power: PointPower,
    /// Tint; rescaled so that its luminance is 1 (the photometric magnitude is `power`).
    #[serde(default = "white")]
    pub color: Rgb,
}

fn white() -> Rgb {
    Rgb::WHITE
}

/// Photometric magnitude of a point source.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum PointPower {
    /// Luminous intensity in candela (same in every direction).
    Intensity(f64),
    /// Total luminous flux in lumen: I = flux / (4 pi).
    Flux(f64),
}

/// Where illuminance is wanted.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Sensor {
    /// Explicit points, each with its own normal.
    Points {
        name: String,
        points: Vec<SensorPoint>,
    },
    /// A rectangular grid of `counts.0 x counts.1` cells over the parallelogram
    /// `corner + s u + t v`; one sensor at each cell centre, facing `normal`
    /// (default: `u x v`).
    Grid {
        name: String,
        corner: Vec3,
        u: Vec3,
        v: Vec3,
        counts: (u32, u32),
        #[serde(default)]
        normal: Option<Vec3>,
    },
}

/// A sensor point: position (m) and the normal of the receiving surface element.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorPoint {
    pub position: Vec3,
    pub normal: Vec3,
}
