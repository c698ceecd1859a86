//! The authored scene format (`scenes/*.ron`), as documented in `docs/scene-format.md`.
//!
//! These types are what a person or `data-gen` writes. They may reference mesh files and use
//! local transforms; `scene-compile` turns them into a [`crate::compiled::CompiledScene`].
//! Units: metres, degrees, candela, lumen, cd/m² (luminance). Unknown fields are errors.

use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A calculation surface's EN 12464-1 / EN 17037 requirements (one type for the scene, the
/// compiled header and the report).
pub use luxest_io::requirements::{DaylightTarget, Requirements};

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
    /// Materials by name, referenced from objects (a name given twice is an error).
    #[serde(deserialize_with = "luxest_io::fsio::unique_keys")]
    pub materials: BTreeMap<String, Material>,
    /// Surfaces: a shape, a transform, a material and optionally an emission.
    pub objects: Vec<Object>,
    /// Point sources.
    #[serde(default)]
    pub point_lights: Vec<PointLight>,
    /// Illuminance sensors (point lists and grids).
    #[serde(default)]
    pub sensors: Vec<Sensor>,
    /// Luminaires from photometric files (IES LM-63, EULUMDAT); see [`Luminaire`].
    #[serde(default)]
    pub luminaires: Vec<Luminaire>,
    /// Calculation surfaces (work planes, EN 12464-1 grids); compiled into sensor sets.
    #[serde(default)]
    pub calculation_surfaces: Vec<CalculationSurface>,
    /// Bitmap textures by name, referenced from `surfaces` and from emissions.
    #[serde(default, deserialize_with = "luxest_io::fsio::unique_keys")]
    pub textures: BTreeMap<String, TextureDesc>,
    /// Per material name: its textures, cut-outs and sidedness. A material without an entry
    /// is untextured, opaque and two-sided.
    #[serde(default, deserialize_with = "luxest_io::fsio::unique_keys")]
    pub surfaces: BTreeMap<String, Surface>,
    /// Light arriving from infinitely far away (sky, HDR environment map); see [`Environment`].
    #[serde(default)]
    pub environment: Option<Environment>,
    /// Openings cut into the wall quads they lie in (daylight through them); see [`Window`].
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub windows: Vec<Window>,
    /// Rectangles through which the environment lights the interior (window openings of
    /// imported scenes, which have no `windows`): next-event estimation samples the
    /// environment through them; see [`crate::portal`]. Open `windows` are portals too.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub portals: Vec<crate::portal::Portal>,
    /// Glare observers (EN 12464-1 / CIE 117): `estimate sensors` computes the UGR of every
    /// observer and line of sight; see [`Observer`].
    #[serde(default)]
    pub observers: Vec<Observer>,
}

/// A window: the parallelogram `corner + s u + t v` (world space, s, t in [0, 1]) cut out of
/// the `Quad` object it lies in, its edges along the quad's (docs/scene-format.md, *Windows*).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Window {
    #[serde(default)]
    pub name: Option<String>,
    pub corner: Vec3,
    pub u: Vec3,
    pub v: Vec3,
    /// A material (of `materials`) filling the opening, e.g. `ThinDielectric` glass; none: open.
    #[serde(default)]
    pub glazing: Option<String>,
}

/// A glare observer (EN 12464-1 / CIE 117): eye position and horizontal lines of sight.
///
/// `estimate sensors` computes the unified glare rating along each line of sight
/// (`luxest_photometry::ugr`): the background luminance is the indirect illuminance at the eye
/// on the plane facing the line of sight / π, the sources are the luminaires seen from the eye
/// (their luminous openings: `Opening::Area` or the file's dimensions), each with the share of
/// its opening not hidden by the scene. The eye must be in open space: `scene-compile` refuses
/// an eye inside an object or outside the room.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Observer {
    /// Unique among observers; names the results.
    pub name: String,
    /// Eye, m (seated 1.2 m, standing 1.6 m above the floor).
    pub position: Vec3,
    /// Lines of sight (any length, normalised when compiled; usually horizontal); at least one.
    pub views: Vec<Vec3>,
    /// UGR_L of the task area (EN 12464-1), reported beside the value.
    #[serde(default)]
    pub ugr_limit: Option<f64>,
}

/// A texture: a PNG, JPEG or EXR file (or a checkerboard) and how it is looked up.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureDesc {
    /// Image file, relative to the scene file (empty for a checkerboard).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub path: String,
    /// Instead of a file: Mitsuba 3's `checkerboard`, the first colour where u and v (after
    /// `uv_transform`) lie in the same half of their unit interval, the second elsewhere
    /// (linear RGB).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checkerboard: Option<[Rgb; 2]>,
    /// How stored values become linear ones; default: sRGB for PNG and JPEG, linear for EXR.
    #[serde(default)]
    pub encoding: Option<crate::texture::Encoding>,
    #[serde(default)]
    pub wrap: crate::texture::Wrap,
    #[serde(default)]
    pub filter: crate::texture::Filter,
    /// Applied to a point's texture coordinates before the lookup.
    #[serde(default)]
    pub uv_transform: Option<crate::texture::UvTransform>,
}

/// What varies over a material's surfaces (see `docs/scene-format.md`, *Textures*).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Surface {
    /// Texture multiplying the material's main colour ([`Material::textured`]).
    #[serde(default)]
    pub color: Option<String>,
    /// Texture whose first channel multiplies the microfacet α (Glossy: its roughness).
    #[serde(default)]
    pub roughness: Option<String>,
    /// Cut-out: where the surface is not there (leaves, grilles).
    #[serde(default)]
    pub opacity: Option<Opacity>,
    /// Tangent-space normal map as Mitsuba 3's `normalmap` reads it: linear RGB = (x, y, z) ·
    /// 0.5 + 0.5 in the shading frame (x along ∂p/∂u made perpendicular to the shading normal,
    /// y = normal × x, z the shading normal); see `docs/scene-format.md`, *Normal maps*.
    #[serde(default)]
    pub normal: Option<String>,
    /// Multiplies the decoded normal's x and y before it is normalised (default (1, 1):
    /// Mitsuba's `normalmap`; a glTF `normalTexture` with its `scale` s is (s, −s): glTF's y
    /// points towards decreasing v).
    #[serde(default = "unit_xy", skip_serializing_if = "is_unit_xy")]
    pub normal_scale: [f64; 2],
    /// False: the surface reflects from its front side only (black from the back), as a
    /// Mitsuba 3 BSDF not wrapped in `twosided`.
    #[serde(default = "yes")]
    pub two_sided: bool,
}

fn yes() -> bool {
    true
}

fn unit_xy() -> [f64; 2] {
    [1.0, 1.0]
}

fn is_unit_xy(v: &[f64; 2]) -> bool {
    *v == [1.0, 1.0]
}

/// Opacity of a cut-out surface: `value` × the texture's `channel` (1 without a texture).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Opacity {
    #[serde(default)]
    pub texture: Option<String>,
    #[serde(default)]
    pub channel: OpacityChannel,
    #[serde(default = "one")]
    pub value: f64,
    /// Opaque where the opacity reaches `cutoff`, transparent below (glTF `alphaMode: MASK`);
    /// absent: opaque with a probability equal to the opacity (Mitsuba 3 `mask`).
    #[serde(default)]
    pub cutoff: Option<f64>,
}

/// An environment emitter: radiance arriving from every direction that leaves the scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Environment {
    /// The same luminance from every direction, cd/m² per RGB channel (Mitsuba 3 `constant`).
    Constant(Rgb),
    /// An equirectangular (latitude-longitude) map, linear RGB in cd/m², as Mitsuba 3 `envmap`
    /// reads it: for the map-local unit direction d, u = atan2(d.x, −d.z) / 2π (wrapped to
    /// [0, 1)) runs along the image's width, v = acos(d.y) / π down its height (the top row
    /// is +y); bilinear between texel centres, wrapping in u.
    Map {
        /// OpenEXR file (R, G, B), relative to the scene file.
        path: String,
        /// Multiplies every texel.
        #[serde(default = "one")]
        scale: f64,
        /// Map-to-world rotation, row-major: world = to_world · local.
        #[serde(default = "identity")]
        to_world: [[f64; 3]; 3],
    },
    /// A daylight sky with Radiance gensky's conventions (CIE overcast, clear, intermediate;
    /// with or without the sun), see [`crate::sky`] and docs/scene-format.md, *Skies*.
    Sky(crate::sky::Sky),
}

fn identity() -> [[f64; 3]; 3] {
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
}

/// Which values of an opacity texture are the opacity.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum OpacityChannel {
    /// Its alpha channel if it has one, else the luminance of its colour.
    #[default]
    Auto,
    /// Its alpha channel (1 where it has none): glTF's base colour alpha.
    Alpha,
    /// The luminance of its colour, alpha ignored: Mitsuba 3's `mask` (its `bitmap` drops alpha).
    Luminance,
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

/// Surface scattering models. Reflectances are linear RGB in [0, 1]. The models after `Glossy`
/// are Mitsuba 3's plugins of the same name (named per variant), with Mitsuba's parameters and
/// semantics; `docs/scene-format.md` documents each.
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
    /// A metal with the complex index of refraction `eta + i k` per channel (relative to the
    /// outside): smooth without `roughness` (Mitsuba `conductor`), a microfacet surface with it
    /// (`roughconductor`); the Fresnel reflectance is scaled by `specular_reflectance`.
    Conductor {
        eta: Rgb,
        k: Rgb,
        #[serde(default = "white")]
        specular_reflectance: Rgb,
        #[serde(default)]
        roughness: Option<Microfacet>,
    },
    /// A diffuse base under a dielectric coating (Mitsuba `plastic`, or `roughplastic` with
    /// `roughness`), with the internal scattering between base and coating.
    Plastic {
        diffuse_reflectance: Rgb,
        #[serde(default = "white")]
        specular_reflectance: Rgb,
        /// int_ior / ext_ior (Mitsuba's default: polypropylene in air).
        #[serde(default = "plastic_ior")]
        ior: f64,
        /// Mitsuba's `nonlinear`: the diffuse colour darkens and saturates through internal
        /// scattering, as in wet or varnished materials.
        #[serde(default)]
        nonlinear: bool,
        #[serde(default)]
        roughness: Option<Microfacet>,
    },
    /// A rough dielectric interface with reflection and transmission (Mitsuba
    /// `roughdielectric`); `ior` as for `Dielectric`.
    RoughDielectric { ior: f64, roughness: Microfacet },
    /// A thin dielectric sheet (a window pane): reflection with the internal reflections of
    /// both faces summed, transmission straight through (Mitsuba `thindielectric`).
    ThinDielectric { ior: f64 },
    /// (1 − weight) · first + weight · second (Mitsuba `blendbsdf`).
    Blend {
        weight: f64,
        first: Box<Material>,
        second: Box<Material>,
    },
}

/// Microfacet roughness (isotropic), Mitsuba 3's convention: `alpha` is the distribution's α
/// (the root-mean-square slope for Beckmann).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Microfacet {
    pub distribution: MicrofacetDistribution,
    pub alpha: f64,
}

/// The microfacet normal distributions of Mitsuba 3.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum MicrofacetDistribution {
    /// GGX / Trowbridge-Reitz.
    Ggx,
    /// Beckmann (Gaussian slopes).
    Beckmann,
}

/// Mitsuba 3's default `int_ior / ext_ior` of `plastic` and `roughplastic`: polypropylene (1.49)
/// in air (1.000277), from its table of indices (`include/mitsuba/render/ior.h`).
pub fn plastic_ior() -> f64 {
    1.49 / 1.000277
}

/// The kind of a material, as listed in the features manifest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum MaterialKind {
    Lambertian,
    Mirror,
    Dielectric,
    Glossy,
    Conductor,
    Plastic,
    RoughDielectric,
    ThinDielectric,
    Blend,
}

impl Material {
    /// The material at a textured point: `color` multiplies its main colour (Lambertian and
    /// Mirror reflectance, Glossy diffuse, Conductor specular reflectance, Plastic diffuse
    /// reflectance, both members of a Blend), `roughness` its microfacet α (Glossy: its
    /// roughness; Conductor, RoughDielectric). Other parameters stay as they are.
    pub fn textured(&self, color: Option<Rgb>, roughness: Option<f64>) -> Material {
        let tint = |c: &Rgb| match color {
            Some(t) => *c * t,
            None => *c,
        };
        // α scaled by the texture, kept within the range validation allows.
        let rough = |r: &Option<Microfacet>| match (r, roughness) {
            (Some(m), Some(s)) => Some(Microfacet {
                distribution: m.distribution,
                alpha: (m.alpha * s).clamp(1e-4, 4.0),
            }),
            _ => *r,
        };
        match self {
            Material::Lambertian { reflectance } => Material::Lambertian {
                reflectance: tint(reflectance),
            },
            Material::Mirror { reflectance } => Material::Mirror {
                reflectance: tint(reflectance),
            },
            Material::Glossy {
                diffuse,
                specular,
                roughness: r,
            } => Material::Glossy {
                diffuse: tint(diffuse),
                specular: *specular,
                roughness: roughness.map_or(*r, |s| (r * s).clamp(1e-4, 1.0)),
            },
            Material::Conductor {
                eta,
                k,
                specular_reflectance,
                roughness: r,
            } => Material::Conductor {
                eta: *eta,
                k: *k,
                specular_reflectance: tint(specular_reflectance),
                roughness: rough(r),
            },
            Material::Plastic {
                diffuse_reflectance,
                specular_reflectance,
                ior,
                nonlinear,
                roughness: r,
            } => Material::Plastic {
                diffuse_reflectance: tint(diffuse_reflectance),
                specular_reflectance: *specular_reflectance,
                ior: *ior,
                nonlinear: *nonlinear,
                // Its coating's tables are per α (validation refuses a roughness texture).
                roughness: *r,
            },
            Material::RoughDielectric { ior, roughness: r } => Material::RoughDielectric {
                ior: *ior,
                roughness: rough(&Some(*r)).unwrap_or(*r),
            },
            Material::Blend {
                weight,
                first,
                second,
            } => Material::Blend {
                weight: *weight,
                first: Box::new(first.textured(color, roughness)),
                second: Box::new(second.textured(color, roughness)),
            },
            Material::Dielectric { .. } | Material::ThinDielectric { .. } => self.clone(),
        }
    }

    pub fn kind(&self) -> MaterialKind {
        match self {
            Material::Lambertian { .. } => MaterialKind::Lambertian,
            Material::Mirror { .. } => MaterialKind::Mirror,
            Material::Dielectric { .. } => MaterialKind::Dielectric,
            Material::Glossy { .. } => MaterialKind::Glossy,
            Material::Conductor { .. } => MaterialKind::Conductor,
            Material::Plastic { .. } => MaterialKind::Plastic,
            Material::RoughDielectric { .. } => MaterialKind::RoughDielectric,
            Material::ThinDielectric { .. } => MaterialKind::ThinDielectric,
            Material::Blend { .. } => MaterialKind::Blend,
        }
    }

    /// This material and, for a blend, the materials it blends (depth first).
    pub fn for_each(&self, f: &mut impl FnMut(&Material)) {
        f(self);
        if let Material::Blend { first, second, .. } = self {
            first.for_each(f);
            second.for_each(f);
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
    /// Ignores the mesh's vertex normals: flat shading with the geometric normal (Mitsuba 3's
    /// `face_normals`).
    #[serde(default, skip_serializing_if = "is_false")]
    pub face_normals: bool,
    /// Where the mesh has no vertex normals, computes them as Mitsuba 3 does for its OBJ, PLY
    /// and serialized meshes: each vertex the normalised sum of its faces' unit normals
    /// weighted by the face's angle at it (Thürmer and Wüthrich 1998). Ignored with
    /// `face_normals`; the Mitsuba importer sets it for those shapes.
    #[serde(default, skip_serializing_if = "is_false")]
    pub compute_normals: bool,
}

fn is_false(b: &bool) -> bool {
    !*b
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
    /// OBJ materials are ignored (the object's `material` applies). With `usemtl`, only the
    /// faces the file assigns (`usemtl NAME`) to that MTL material.
    Obj {
        path: String,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        usemtl: Option<String>,
    },
    /// A glTF 2.0 mesh, `.gltf` (with external or embedded buffers) or `.glb`; every mesh of
    /// the default scene with its node transforms. glTF materials are ignored. With
    /// `primitive: (m, p)`, only primitive `p` of mesh `m`, in the mesh's own frame (no node
    /// transform).
    Gltf {
        path: String,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        primitive: Option<(u32, u32)>,
    },
    /// A Stanford PLY triangle mesh (ASCII or binary little-endian; vertex positions, optional
    /// normals and texture coordinates, faces as index lists, fan-triangulated).
    Ply { path: String },
    /// Mesh `shape_index` of a Mitsuba `.serialized` file (versions 3 and 4).
    Serialized {
        path: String,
        #[serde(default)]
        shape_index: u32,
    },
}

/// Local-to-world transform: scale, then rotate about x, then y, then z (degrees,
/// right-handed), then translate, then `matrix` when given.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Transform {
    pub scale: Vec3,
    pub rotate_deg: Vec3,
    pub translate: Vec3,
    /// A general affine transform applied last: the first three rows of its 4 × 4 matrix,
    /// row-major (`p' = M p + t` with `M` the 3 × 3 block and `t` the last column). Importers
    /// write it (Mitsuba 3's `to_world`, glTF node matrices).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub matrix: Option<[[f64; 4]; 3]>,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            scale: Vec3::splat(1.0),
            rotate_deg: Vec3::ZERO,
            translate: Vec3::ZERO,
            matrix: None,
        }
    }
}

impl Transform {
    pub fn to_affine(&self) -> luxest_io::math::Affine {
        use luxest_io::math::Affine;
        let after = match &self.matrix {
            Some([r0, r1, r2]) => Affine::from_rows4([*r0, *r1, *r2, [0.0, 0.0, 0.0, 1.0]]),
            None => Affine::IDENTITY,
        };
        after
            .compose(&Affine::translate(self.translate))
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
    /// Luminance varying over the surface: `scale` × the texture's texels, cd/m² per channel
    /// (the object needs texture coordinates).
    Texture {
        texture: String,
        #[serde(default = "white")]
        scale: Rgb,
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
    /// Makes the source a spot light (Mitsuba 3 `spot`); `None`: isotropic.
    #[serde(default)]
    pub spot: Option<Spot>,
}

/// A spot light's cone: intensity I(θ) = I₀ · falloff(θ), θ the angle to `direction`, with
/// Mitsuba 3's linear falloff: 1 for θ ≤ beam width, (cutoff − θ)/(cutoff − beam width)
/// between, 0 beyond the cutoff. `PointPower::Intensity` is I₀ (on the axis); `Flux` the
/// whole cone's flux, 2π I₀ (1 − (sin c − sin b)/(c − b)) (c, b the angles in radians).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spot {
    /// The cone's axis (need not be unit length).
    pub direction: Vec3,
    /// Half-angle beyond which nothing is emitted, degrees in (0, 180] (Mitsuba's default 20).
    pub cutoff_deg: f64,
    /// Half-angle of the full-intensity core, degrees in [0, cutoff] (Mitsuba's default: 3/4
    /// of the cutoff).
    pub beam_width_deg: f64,
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

/// A sensor point: position (m), the normal of the receiving surface element, and the kind of
/// illuminance it measures (planar on `normal` unless stated).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorPoint {
    pub position: Vec3,
    pub normal: Vec3,
    #[serde(default, skip_serializing_if = "IlluminanceKind::is_planar")]
    pub kind: IlluminanceKind,
}

impl SensorPoint {
    /// A planar sensor (the kind every scene had before the other kinds existed).
    pub fn planar(position: Vec3, normal: Vec3) -> SensorPoint {
        SensorPoint {
            position,
            normal,
            kind: IlluminanceKind::Planar,
        }
    }

    /// The sensor's geometric response g(ω) to light arriving from the unit direction
    /// `to_source` (pointing from the sensor towards the light): E = ∫ L(ω) g(ω) dω.
    /// Planar: n·ω (negative behind: callers drop non-positive responses); cylindrical
    /// (axis a): |ω − (a·ω) a| / π; semi-cylindrical facing f: (|ω_h| + f·ω_h) / π (CIE S 017,
    /// EN 12464-1 §4.3.5; derivations in `luxest_photometry::illuminance`).
    #[inline]
    pub fn response(&self, to_source: Vec3) -> f64 {
        match self.kind {
            IlluminanceKind::Planar => self.normal.dot(to_source),
            IlluminanceKind::Cylindrical { axis } => {
                (to_source - axis * axis.dot(to_source)).length() / std::f64::consts::PI
            }
            IlluminanceKind::SemiCylindrical { axis, facing } => {
                let h = to_source - axis * axis.dot(to_source);
                (h.length() + facing.dot(h)) / std::f64::consts::PI
            }
        }
    }
}

/// What a sensor measures. Cylindrical kinds are defined about a unit `axis` (vertical in a
/// y-up scene: (0, 1, 0)); a semi-cylinder faces the unit `facing` direction, perpendicular to
/// the axis (normalised and made perpendicular on compile).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum IlluminanceKind {
    /// Illuminance on the plane with the sensor's normal (one-sided, cosine law).
    #[default]
    Planar,
    /// Mean illuminance on the curved surface of a vanishingly small cylinder.
    Cylindrical {
        #[serde(default = "default_axis")]
        axis: Vec3,
    },
    /// Mean illuminance on the curved surface of a small half cylinder facing `facing`.
    SemiCylindrical {
        #[serde(default = "default_axis")]
        axis: Vec3,
        facing: Vec3,
    },
}

fn default_axis() -> Vec3 {
    Vec3::new(0.0, 1.0, 0.0)
}

impl IlluminanceKind {
    pub fn is_planar(&self) -> bool {
        matches!(self, IlluminanceKind::Planar)
    }
}

/// A luminaire described by a photometric file, placed in the scene.
///
/// The file's C-γ frame is placed in luxest's y-up world: with the defaults the luminaire hangs
/// straight down (γ = 0 along −y), the C = 0° plane contains +x and C = 90° contains −z
/// (C counter-clockwise seen from above). `aim` turns the nadir by the smallest rotation to the
/// given direction, after a `tilt_deg` about the luminaire's own x axis (positive tilt swings
/// the nadir towards the C = 90° side) and a `rotation_deg` about its vertical axis (turns the
/// C planes); the order is `luxest_photometry::Orientation`'s.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Luminaire {
    #[serde(default)]
    pub name: Option<String>,
    /// The photometric file (`.ies` or `.ldt`), relative to the scene file.
    pub file: String,
    /// Photometric centre, m.
    pub position: Vec3,
    /// World direction of the nadir (γ = 0); default straight down (0, −1, 0).
    #[serde(default = "default_aim")]
    pub aim: Vec3,
    #[serde(default)]
    pub tilt_deg: f64,
    #[serde(default)]
    pub rotation_deg: f64,
    /// Multiplies every intensity: dimming × count of lamps, > 0; default 1.
    #[serde(default = "one")]
    pub multiplier: f64,
    /// Maintenance factor MF (EN 12464-1, CIE 97), in (0, 1]; default 1. Multiplies every
    /// intensity like `multiplier` (the compiled luminaire's multiplier is their product); the
    /// report's luminaire schedule shows it separately.
    #[serde(default = "one")]
    pub maintenance_factor: f64,
    /// Tint, rescaled to luminance 1 (the photometric magnitude is the file's).
    #[serde(default = "white")]
    pub color: Rgb,
    /// The luminous opening: a point (far field, default) or a rectangle.
    #[serde(default)]
    pub opening: Opening,
}

/// The luminous opening of a luminaire.
///
/// `Area` models the opening as a rectangle every point of which radiates the file's
/// distribution scaled to its share of the area: intensity per unit area I(ω)/A, so that from
/// far away the luminaire is the point form again. The rectangle (centred on `position`, in the
/// plane through it perpendicular to the nadir; `length` along the C0–C180 axis, `width` along
/// C90–C270, m) is integrated by the midpoint rule: `cells` point sources at the cell centres,
/// each radiating I(ω)/(nu·nv). Default size: the file's luminous opening (rectangular or
/// circular: its bounding square); default cells: ⌈side / 0.05 m⌉ per side.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Opening {
    /// Far field: a point at the photometric centre.
    #[default]
    Point,
    Area {
        #[serde(default)]
        length: Option<f64>,
        #[serde(default)]
        width: Option<f64>,
        #[serde(default)]
        cells: Option<(u32, u32)>,
    },
}

fn default_aim() -> Vec3 {
    Vec3::new(0.0, -1.0, 0.0)
}

fn one() -> f64 {
    1.0
}

/// A calculation surface: a grid of sensor points laid out as EN 12464-1 prescribes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalculationSurface {
    /// The name of the compiled sensor set (unique among sensors and surfaces).
    pub name: String,
    pub area: SurfaceArea,
    /// Distance along the rectangle's normal, m (the work-plane height above a floor); default 0.
    #[serde(default)]
    pub offset: f64,
    /// Border excluded on every side, m; default 0.5 (EN 12464-1 for work planes).
    #[serde(default = "default_margin")]
    pub margin: f64,
    /// Grid spacing; default the standard's rule.
    #[serde(default)]
    pub spacing: GridSpacing,
    /// What the points measure; default planar illuminance on the rectangle's normal.
    #[serde(default)]
    pub kind: IlluminanceKind,
    /// The task area's requirements (EN 12464-1 Ē_m and U0, EN 17037 daylight factor), which
    /// the report checks; default none.
    #[serde(default)]
    pub requirements: Option<Requirements>,
}

fn default_margin() -> f64 {
    0.5
}

/// The rectangle a calculation surface covers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum SurfaceArea {
    /// `origin + s u + t v`, s, t in [0, 1], u ⟂ v; normal along u × v.
    Rectangle { origin: Vec3, u: Vec3, v: Vec3 },
    /// A horizontal floor rectangle [min.0, max.0] × [min.1, max.1] in (x, z) at `y`, facing
    /// up: origin (x0, y, z1), u = (x1 − x0, 0, 0), v = (0, 0, −(z1 − z0)).
    Floor {
        min: (f64, f64),
        max: (f64, f64),
        y: f64,
    },
}

/// Spacing of a calculation grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum GridSpacing {
    /// EN 12464-1: p = 0.2 · 5^(log10 d) m (d the longer side), ⌈L/p⌉ points per side.
    #[default]
    Standard,
    /// A maximum spacing in metres (⌈L/p⌉ points per side).
    Metres(f64),
    /// Explicit point counts along u and v.
    Counts(u32, u32),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Deserialize)]
    struct Materials {
        materials: BTreeMap<String, Material>,
    }

    /// The normal-map example of `docs/scene-format.md` parses: Mitsuba's convention by default,
    /// glTF's y reversed where stated.
    #[test]
    fn the_documented_normal_maps_parse() {
        #[derive(Deserialize)]
        struct Maps {
            #[allow(dead_code)]
            textures: BTreeMap<String, TextureDesc>,
            surfaces: BTreeMap<String, Surface>,
        }
        let doc = include_str!("../../../docs/scene-format.md");
        let block = doc
            .split("```ron\n")
            .map(|b| &b[..b.find("```").unwrap_or(b.len())])
            .find(|b| b.starts_with("textures: { \"bumps\""))
            .expect("the normal-map example");
        let path = std::path::Path::new("docs/scene-format.md");
        let m: Maps = luxest_io::fsio::parse_ron(path, &format!("({block})"))
            .unwrap_or_else(|e| panic!("{e}\n{block}"));
        assert_eq!(m.surfaces["wall"].normal.as_deref(), Some("bumps"));
        assert_eq!(m.surfaces["wall"].normal_scale, [1.0, 1.0]);
        assert_eq!(m.surfaces["tiles"].normal_scale, [1.0, -1.0]);
        assert!(m.surfaces["tiles"].two_sided);
    }

    /// Every `materials: { … }` example of `docs/scene-format.md` parses, with the defaults the
    /// docs state.
    #[test]
    fn the_documented_materials_parse() {
        let doc = include_str!("../../../docs/scene-format.md");
        let mut names = Vec::new();
        for block in doc.split("```ron\n").skip(1) {
            let block = &block[..block.find("```").unwrap()];
            if block.starts_with("materials: {") {
                let path = std::path::Path::new("docs/scene-format.md");
                let m: Materials = luxest_io::fsio::parse_ron(path, &format!("({block})"))
                    .unwrap_or_else(|e| panic!("{e}\n{block}"));
                names.extend(m.materials);
            }
        }
        let get = |n: &str| names.iter().find(|(k, _)| k == n).unwrap().1.clone();
        assert_eq!(
            get("red plastic"),
            Material::Plastic {
                diffuse_reflectance: Rgb([0.6, 0.05, 0.05]),
                specular_reflectance: Rgb::WHITE,
                ior: 1.49 / 1.000277,
                nonlinear: false,
                roughness: Some(Microfacet {
                    distribution: MicrofacetDistribution::Beckmann,
                    alpha: 0.1
                }),
            }
        );
        assert_eq!(get("worn metal").kind(), MaterialKind::Blend);
        assert!(names.len() >= 9, "{names:?}");
    }

    /// The `luminaires: [ … ]` and `calculation_surfaces: [ … ]` examples of
    /// `docs/scene-format.md` parse, with the maintenance factor and requirements they state
    /// and the defaults of what they leave out.
    #[test]
    fn the_documented_luminaires_and_requirements_parse() {
        #[derive(Deserialize)]
        struct Lighting {
            #[serde(default)]
            luminaires: Vec<Luminaire>,
            #[serde(default)]
            calculation_surfaces: Vec<CalculationSurface>,
            #[serde(default)]
            requirements: Option<Requirements>,
        }
        let doc = include_str!("../../../docs/scene-format.md");
        let path = std::path::Path::new("docs/scene-format.md");
        let (mut lums, mut surfaces, mut reqs) = (Vec::new(), Vec::new(), Vec::new());
        for block in doc.split("```ron\n").skip(1) {
            let block = block[..block.find("```").unwrap()].trim();
            if [
                "luminaires: [",
                "calculation_surfaces: [",
                "requirements: (",
            ]
            .iter()
            .any(|k| block.starts_with(k))
            {
                let l: Lighting = luxest_io::fsio::parse_ron(path, &format!("({block})"))
                    .unwrap_or_else(|e| panic!("{e}\n{block}"));
                lums.extend(l.luminaires);
                surfaces.extend(l.calculation_surfaces);
                reqs.extend(l.requirements);
            }
        }
        assert_eq!(lums[0].maintenance_factor, 0.8);
        assert_eq!(lums[0].multiplier, 1.0);
        assert_eq!(
            surfaces[0].requirements,
            Some(Requirements {
                em_lux: Some(500.0),
                u0: Some(0.6),
                daylight_factor: None
            })
        );
        // The wall sets no requirements: none by default.
        assert_eq!(surfaces[1].requirements, None);
        assert_eq!(
            reqs,
            [Requirements {
                em_lux: Some(300.0),
                u0: Some(0.4),
                daylight_factor: Some(DaylightTarget {
                    median_percent: 2.0,
                    min_percent: Some(0.7)
                }),
            }]
        );
    }

    /// The `portals: [ … ]` example of `docs/scene-format.md` parses into one valid portal.
    #[test]
    fn the_documented_portals_parse() {
        #[derive(Deserialize)]
        struct Portals {
            portals: Vec<crate::portal::Portal>,
        }
        let doc = include_str!("../../../docs/scene-format.md");
        let block = doc
            .split("```ron\n")
            .find(|b| b.starts_with("portals: ["))
            .unwrap();
        let block = &block[..block.find("```").unwrap()];
        let path = std::path::Path::new("docs/scene-format.md");
        let p: Portals = luxest_io::fsio::parse_ron(path, &format!("({block})")).unwrap();
        assert_eq!(p.portals.len(), 1);
        assert_eq!(p.portals[0].name.as_deref(), Some("skylight"));
        assert_eq!(p.portals[0].problem(), None);
    }

    /// The `observers: [ … ]` example of `docs/scene-format.md` parses with the defaults the
    /// docs state.
    #[test]
    fn the_documented_observers_parse() {
        #[derive(Deserialize)]
        struct Observers {
            observers: Vec<Observer>,
        }
        let doc = include_str!("../../../docs/scene-format.md");
        let block = doc
            .split("```ron\n")
            .find(|b| b.starts_with("observers: ["))
            .unwrap();
        let block = &block[..block.find("```").unwrap()];
        let path = std::path::Path::new("docs/scene-format.md");
        let o: Observers = luxest_io::fsio::parse_ron(path, &format!("({block})")).unwrap();
        assert_eq!(o.observers.len(), 2);
        assert_eq!(o.observers[0].views.len(), 2);
        assert_eq!(o.observers[0].ugr_limit, Some(19.0));
        assert_eq!(o.observers[1].ugr_limit, None);
    }
}
