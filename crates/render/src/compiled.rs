//! The compiled scene: one self-contained, versioned file that every rendering stage reads.
//!
//! Layout (all integers little-endian):
//!
//! ```text
//! magic    8 bytes  "LUXSCENE"
//! schema   u32      SCHEMA_VERSION
//! reserved u32      0
//! hash     16 bytes xxh3-128 of everything after the header-length field
//! hlen     u64      length of the RON header
//! header   hlen bytes of RON: SceneHeader (camera, materials, emitters, sensors, features, stats)
//! arrays   positions [f32;3] x V, normals [f32;3] x V, indices [u32;3] x T,
//!          triangle material u32 x T, triangle emitter u32 x T (NO_EMITTER if none),
//!          texture coordinates [f32;2] x V (only if `features.uvs`),
//!          each texture of `header.textures`, in order ([`Texture::encode`])
//!          environment map texels [f32;3] x W·H (row-major, top row first; only with an
//!          `Emitter::Environment` that has a map)
//! ```
//!
//! Geometry is in world space; the small metadata stays human-readable RON while the bulk arrays
//! are raw so that a million triangles load in tens of milliseconds.
//! Conventions: a triangle's front side is along `(b - a) x (c - a)`; a zero vertex normal means
//! "flat: use the geometric normal".

use crate::scene::{Camera, Material, MaterialKind};
pub use crate::spot::SpotCone;
use crate::texture::Texture;
use luxest_io::color::Rgb;
use luxest_io::error::{Error, Result};
use luxest_io::math::Vec3;
use serde::{Deserialize, Serialize};
use std::path::Path;

pub const MAGIC: &[u8; 8] = luxest_io::meta::COMPILED_MAGIC;
/// Bumped whenever the layout or the meaning of a field changes.
/// 4: luminaires' `maintenance_factor` (included in `multiplier`), calculation surfaces'
/// `requirements`.
/// 3: environment light (`Emitter::Environment`, its map's texels after the other arrays), spot
/// lights (`Emitter::Point::spot`); texture coordinates, textures, surfaces (textured,
/// one-sided and cut-out materials), textured area emitters.
/// 2: goniometric luminaires (`Emitter::Luminaire`, `photometries`), sensor kinds and
/// calculation-grid layouts.
pub const SCHEMA_VERSION: u32 = 4;
/// `triangle_emitter` value of a triangle that does not emit.
pub const NO_EMITTER: u32 = u32::MAX;
/// Fixed part before the RON header: magic, schema, reserved, hash, header length.
const PREAMBLE_LEN: usize = 8 + 4 + 4 + 16 + 8;

/// Everything but the bulk geometry arrays.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneHeader {
    pub name: String,
    /// Version of the `scene-compile` that wrote the file.
    pub compiler_version: String,
    pub camera: Option<Camera>,
    pub materials: Vec<NamedMaterial>,
    pub emitters: Vec<Emitter>,
    /// Cumulative distribution for choosing an emitter in proportion to its luminous flux
    /// (Y of `flux_rgb`); `emitter_cdf[i]` = P(index <= i), last entry 1.
    pub emitter_cdf: Vec<f64>,
    pub objects: Vec<ObjectRange>,
    pub sensors: Vec<SensorSet>,
    /// Goniometric intensity tables referenced by `Emitter::Luminaire` (one per distinct file).
    #[serde(default)]
    pub photometries: Vec<PhotometricTable>,
    /// The bitmap textures, in the order their pixels follow the arrays.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub textures: Vec<TextureInfo>,
    /// Per material (indexed like `materials`), its textures and sidedness; empty when no
    /// material has any (every material untextured and two-sided).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub surfaces: Vec<CompiledSurface>,
    /// The glare observers and the luminous openings of the luminaires they rate; `None`
    /// when the scene has no observers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glare: Option<GlareSetup>,
    /// The environment's portals (the scene's `portals` and its open `windows`, world space);
    /// empty without an environment.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub portals: Vec<crate::portal::Portal>,
    pub features: Features,
    pub stats: Stats,
}

/// What `estimate sensors` needs to rate glare (see `scene::Observer`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GlareSetup {
    pub observers: Vec<CompiledObserver>,
    /// One per `Emitter::Luminaire`, in emitter order.
    pub openings: Vec<LuminousArea>,
}

/// A glare observer with its lines of sight normalised.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CompiledObserver {
    pub name: String,
    pub position: Vec3,
    pub views: Vec<Vec3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ugr_limit: Option<f64>,
}

/// A luminaire's luminous opening as glare sees it: the emitter's index and the opening's
/// IES LM-63 signed dimensions (width, length, height; m; negative: round), the scene's
/// `Opening::Area` rectangle or else the file's; all zero when neither gives one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LuminousArea {
    pub emitter: u32,
    pub ies_dimensions_m: [f64; 3],
}

/// A luminaire's intensity distribution, expanded to the full C-γ sphere (no reference to the
/// source file at run time: `source` is for reports).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhotometricTable {
    /// The file as the scene named it.
    pub source: String,
    /// C angles, degrees: 0 first, 360 (a copy of 0) last.
    pub c_deg: Vec<f64>,
    /// γ angles, degrees, increasing within [0, 180].
    pub gamma_deg: Vec<f64>,
    /// Intensities in cd, row-major: `cd[i * gamma_deg.len() + j]` = I(C_i, γ_j).
    pub cd: Vec<f64>,
    /// ∫ I dΩ over the bilinear table (lm): what one luminaire with multiplier 1 emits.
    pub table_flux_lm: f64,
    /// The flux the file states (lamp lumens, or EULUMDAT's luminaire flux), if any.
    pub file_flux_lm: Option<f64>,
    /// Input power the file states (W), if any.
    pub input_watts: Option<f64>,
}

/// Where a texture of the compiled scene came from (its pixels are in the array section).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureInfo {
    /// The scene's name for it.
    pub name: String,
    /// The image file as the scene named it (for reports; not read at run time).
    pub source: String,
    pub width: u32,
    pub height: u32,
}

/// A material's textures (indices into `SceneHeader::textures`) and sidedness, as
/// [`crate::scene::Surface`] describes them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CompiledSurface {
    /// Multiplies the material's main colour ([`Material::textured`]).
    pub color: Option<u32>,
    /// Its first channel multiplies the microfacet α.
    pub roughness: Option<u32>,
    pub opacity: Option<CompiledOpacity>,
    /// Tangent-space normal map ([`crate::scene::Surface::normal`]).
    pub normal: Option<u32>,
    /// Multiplies the decoded normal's x and y ([`crate::scene::Surface::normal_scale`]).
    #[serde(default = "unit_xy")]
    pub normal_scale: [f64; 2],
    /// False: black seen from the back side.
    pub two_sided: bool,
}

/// Opacity of a cut-out surface: `value` × the texture's `channel` (1 without a texture).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CompiledOpacity {
    pub texture: Option<u32>,
    pub channel: crate::scene::OpacityChannel,
    pub value: f64,
    /// Opaque where the opacity reaches `cutoff`, transparent below; `None`: opaque with
    /// probability equal to the opacity.
    pub cutoff: Option<f64>,
}

impl CompiledSurface {
    /// Whether the surface is what a material without a `surfaces` entry is.
    pub fn is_plain(&self) -> bool {
        self.color.is_none()
            && self.roughness.is_none()
            && self.opacity.is_none()
            && self.normal.is_none()
            && self.two_sided
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NamedMaterial {
    pub name: String,
    pub model: Material,
}

fn unit_xy() -> [f64; 2] {
    [1.0, 1.0]
}

/// A light source in world space with its photometric power.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Emitter {
    /// Point source: intensity per RGB channel in cd (Y = luminous intensity), the same in
    /// every direction, or for a spot light the on-axis intensity times the cone's falloff.
    Point {
        name: String,
        position: Vec3,
        intensity_rgb: Rgb,
        flux_rgb: Rgb,
        /// A spot light's cone (see [`crate::spot`]); `None`: isotropic.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        spot: Option<SpotCone>,
    },
    /// Lambertian area emitter over a contiguous triangle range, emitting from front sides.
    Area {
        name: String,
        first_triangle: u32,
        triangle_count: u32,
        /// Luminance per RGB channel, cd/m² (with `texture`: the factor of its texels).
        radiance_rgb: Rgb,
        /// Index into `SceneHeader::textures`: the luminance varies over the emitter as
        /// `radiance_rgb` × texel.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        texture: Option<u32>,
        area_m2: f64,
        /// pi * L * A, lm per channel.
        flux_rgb: Rgb,
    },
    /// A goniometric point source (far field) at `position`: intensity towards the world
    /// direction ω is `multiplier · I_table(frame⁻¹ ω) · color_rgb` (cd per channel).
    Luminaire {
        name: String,
        position: Vec3,
        /// Luminaire-to-world rotation, row-major: world = frame · local (C-γ frame).
        frame: [[f64; 3]; 3],
        /// Index into `SceneHeader::photometries`.
        photometry: u32,
        /// The scene's multiplier × its maintenance factor.
        multiplier: f64,
        /// The scene's maintenance factor (included in `multiplier`; for reports).
        #[serde(default = "one", skip_serializing_if = "is_one")]
        maintenance_factor: f64,
        /// Tint with luminance 1.
        color_rgb: Rgb,
        /// multiplier · table flux · color, lm per channel.
        flux_rgb: Rgb,
        /// Area form: world positions of the point sources that subdivide the luminous
        /// opening, each radiating 1/len of the intensity; empty for the point form.
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        opening_points: Vec<Vec3>,
    },
    /// Light arriving from infinitely far away along every ray that leaves the scene (see
    /// [`crate::environment`]); at most one per scene.
    Environment {
        name: String,
        /// Constant environment: its radiance, cd/m² per channel; map: the scale (the same in
        /// every channel).
        radiance_rgb: Rgb,
        /// The equirectangular map, its texels in the array section; `None`: constant.
        map: Option<EnvironmentMap>,
        /// The flux through the disk of the scene's bounding sphere
        /// ([`SceneHeader::bounding_sphere`]): π R² ∫ L dω, lm per channel (the sun's
        /// included).
        flux_rgb: Rgb,
        /// A daylight sky's sun, added to the map (see [`crate::environment::SunDisk`]).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        sun: Option<crate::environment::SunDisk>,
        /// A daylight sky's description and unobstructed horizontal illuminance (what
        /// `estimate sensors` copies into its results for daylight factors).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        sky: Option<luxest_io::sensors::SkyInfo>,
    },
}

/// An environment map's size and orientation (its texels follow the triangle arrays).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentMap {
    /// The file as the scene named it (for reports).
    pub source: String,
    pub width: u32,
    pub height: u32,
    /// Map-to-world rotation, row-major: world = to_world · local.
    pub to_world: [[f64; 3]; 3],
}

impl Emitter {
    pub fn name(&self) -> &str {
        match self {
            Emitter::Point { name, .. }
            | Emitter::Area { name, .. }
            | Emitter::Luminaire { name, .. }
            | Emitter::Environment { name, .. } => name,
        }
    }
    /// Luminous flux in lm (Y of the RGB flux).
    pub fn flux_lm(&self) -> f64 {
        match self {
            Emitter::Point { flux_rgb, .. }
            | Emitter::Area { flux_rgb, .. }
            | Emitter::Luminaire { flux_rgb, .. }
            | Emitter::Environment { flux_rgb, .. } => flux_rgb.luminance(),
        }
    }
}

impl SceneHeader {
    /// The sphere environment light enters through (centre, radius, m): the one around the
    /// box of the geometry, the delta lights and the sensors, enlarged by 1e-6 of itself (at
    /// least 1e-6 m). Scene-compile and the world both take it from here, so the
    /// environment's flux and its light paths agree.
    pub fn bounding_sphere(&self) -> (Vec3, f64) {
        let mut lo = Vec3::splat(f64::INFINITY);
        let mut hi = Vec3::splat(f64::NEG_INFINITY);
        let s = &self.stats;
        if s.triangles > 0 && s.bounds_min.is_finite() && s.bounds_max.is_finite() {
            lo = s.bounds_min;
            hi = s.bounds_max;
        }
        for e in &self.emitters {
            if let Emitter::Point { position, .. } | Emitter::Luminaire { position, .. } = e {
                lo = lo.min(*position);
                hi = hi.max(*position);
            }
        }
        for p in self.sensors.iter().flat_map(|s| &s.points) {
            lo = lo.min(p.position);
            hi = hi.max(p.position);
        }
        if !(lo.is_finite() && hi.is_finite()) {
            return (Vec3::ZERO, 1e-6);
        }
        let radius = 0.5 * (hi - lo).length();
        ((lo + hi) * 0.5, (radius * (1.0 + 1e-6)).max(1e-6))
    }
}

/// The triangles that came from one authored object.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectRange {
    pub name: String,
    pub first_triangle: u32,
    pub triangle_count: u32,
    pub material: u32,
    pub emitter: Option<u32>,
}

/// A named set of sensor points, in world space with unit normals.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSet {
    pub name: String,
    /// `Some((nu, nv))` for a grid (points in row-major order, u fastest), `None` for a list.
    pub grid: Option<(u32, u32)>,
    pub points: Vec<crate::scene::SensorPoint>,
    /// For a calculation surface: how its grid was laid out (a report reassembles it from
    /// this; point k = j · nu + i is cell (i, j)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calculation_grid: Option<GridLayout>,
    /// For a calculation surface: its requirements, which the report checks.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub requirements: Option<crate::scene::Requirements>,
}

fn one() -> f64 {
    1.0
}

fn is_one(x: &f64) -> bool {
    *x == 1.0
}

/// The layout of a calculation surface's grid, in world space.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridLayout {
    /// Corner of the whole rectangle (offset included, margin not), m.
    pub origin: Vec3,
    /// The rectangle's full edges, m.
    pub u: Vec3,
    pub v: Vec3,
    /// Border excluded on every side, m.
    pub margin_m: f64,
    /// Points along u and v; the point spacing is (|u| − 2 margin)/nu by (|v| − 2 margin)/nv.
    pub nu: u32,
    pub nv: u32,
}

/// What the scene uses: stages dispatch on this and pay nothing for what is absent.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Features {
    /// Material models used by at least one triangle, sorted.
    pub material_kinds: Vec<MaterialKind>,
    pub point_emitters: bool,
    pub area_emitters: bool,
    /// Any ideal mirror or dielectric: delta (specular) paths exist.
    pub specular_paths: bool,
    /// Any dielectric: light is transmitted through surfaces.
    pub transmission: bool,
    /// Any glossy (microfacet) lobe.
    pub glossy: bool,
    /// Any interpolated vertex normals (otherwise all shading is flat).
    pub smooth_normals: bool,
    /// Any normal-mapped surface.
    #[serde(default)]
    pub normal_maps: bool,
    /// Always false: luxest is RGB; kept so the manifest states it.
    pub spectral: bool,
    pub camera: bool,
    pub sensors: bool,
    /// Any luminaire from a photometric file (`Emitter::Luminaire`).
    #[serde(default)]
    pub goniometric_luminaires: bool,
    /// Texture coordinates are stored (some material or emitter is textured).
    #[serde(default)]
    pub uvs: bool,
    /// Any textured colour, roughness, normal or emission.
    #[serde(default)]
    pub textures: bool,
    /// Any one-sided material (black from the back).
    #[serde(default)]
    pub one_sided: bool,
    /// Any cut-out (opacity) surface: every ray query skips its transparent points.
    #[serde(default)]
    pub opacity: bool,
    /// An environment emitter (`Emitter::Environment`): rays that leave the scene carry light.
    #[serde(default)]
    pub environment: bool,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stats {
    pub vertices: u64,
    pub triangles: u64,
    /// Degenerate triangles dropped while compiling (zero area or non-finite).
    pub dropped_degenerate: u64,
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
    pub total_area_m2: f64,
}

/// A compiled scene in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct CompiledScene {
    pub header: SceneHeader,
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub indices: Vec<[u32; 3]>,
    pub triangle_material: Vec<u32>,
    pub triangle_emitter: Vec<u32>,
    /// Per vertex (empty unless `features.uvs`), glTF's convention ((0, 0) the image's
    /// top-left corner).
    pub uvs: Vec<[f32; 2]>,
    /// Decoded textures, indexed like `header.textures`.
    pub textures: Vec<Texture>,
    /// The environment map's texels (linear RGB, row-major, top row first); empty without one.
    pub environment_texels: Vec<[f32; 3]>,
    /// xxh3-128 content hash as 32 hex digits (set by `encode` / `decode`).
    pub content_hash: String,
}

fn push_f32x3(out: &mut Vec<u8>, a: &[[f32; 3]]) {
    out.reserve(a.len() * 12);
    for v in a {
        for c in v {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
}
fn push_u32x3(out: &mut Vec<u8>, a: &[[u32; 3]]) {
    out.reserve(a.len() * 12);
    for v in a {
        for c in v {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
}
fn push_f32x2(out: &mut Vec<u8>, a: &[[f32; 2]]) {
    out.reserve(a.len() * 8);
    for v in a {
        for c in v {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
}
fn push_u32(out: &mut Vec<u8>, a: &[u32]) {
    out.reserve(a.len() * 4);
    for c in a {
        out.extend_from_slice(&c.to_le_bytes());
    }
}

/// A cursor over the array section that reports truncation with the file name.
struct Reader<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8]> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| {
            Error::input(self.path, format!("truncated compiled scene (in {what})"))
        })?;
        let s = &self.bytes[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    fn u32s(&mut self, n: usize, what: &str) -> Result<Vec<u32>> {
        let s = self.take(n * 4, what)?;
        Ok(s.chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect())
    }
    fn f32x3(&mut self, n: usize, what: &str) -> Result<Vec<[f32; 3]>> {
        let s = self.take(n * 12, what)?;
        Ok(s.chunks_exact(12)
            .map(|c| {
                let f = |i: usize| f32::from_le_bytes(c[i..i + 4].try_into().unwrap());
                [f(0), f(4), f(8)]
            })
            .collect())
    }
    fn f32x2(&mut self, n: usize, what: &str) -> Result<Vec<[f32; 2]>> {
        let s = self.take(n * 8, what)?;
        Ok(s.chunks_exact(8)
            .map(|c| {
                let f = |i: usize| f32::from_le_bytes(c[i..i + 4].try_into().unwrap());
                [f(0), f(4)]
            })
            .collect())
    }
    fn u32x3(&mut self, n: usize, what: &str) -> Result<Vec<[u32; 3]>> {
        let s = self.take(n * 12, what)?;
        Ok(s.chunks_exact(12)
            .map(|c| {
                let f = |i: usize| u32::from_le_bytes(c[i..i + 4].try_into().unwrap());
                [f(0), f(4), f(8)]
            })
            .collect())
    }
}

impl CompiledScene {
    /// Serialises the scene and sets `content_hash`.
    pub fn encode(&mut self) -> Vec<u8> {
        let header = luxest_io::fsio::to_ron_string(&self.header);
        let nv = self.positions.len();
        let nt = self.indices.len();
        let mut body = Vec::with_capacity(8 + header.len() + nv * 24 + nt * 20);
        body.extend_from_slice(&(header.len() as u64).to_le_bytes());
        body.extend_from_slice(header.as_bytes());
        push_f32x3(&mut body, &self.positions);
        push_f32x3(&mut body, &self.normals);
        push_u32x3(&mut body, &self.indices);
        push_u32(&mut body, &self.triangle_material);
        push_u32(&mut body, &self.triangle_emitter);
        push_f32x2(&mut body, &self.uvs);
        for t in &self.textures {
            t.encode(&mut body);
        }
        push_f32x3(&mut body, &self.environment_texels);
        let hash = xxhash_rust::xxh3::xxh3_128(&body);
        self.content_hash = format!("{hash:032x}");
        let mut out = Vec::with_capacity(PREAMBLE_LEN + body.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&SCHEMA_VERSION.to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        out.extend_from_slice(&hash.to_le_bytes());
        out.extend_from_slice(&body);
        out
    }

    /// Writes the scene atomically to `path`; returns the content hash.
    pub fn save(&mut self, path: &Path) -> Result<String> {
        let bytes = self.encode();
        luxest_io::fsio::write_bytes_atomically(path, &bytes)?;
        Ok(self.content_hash.clone())
    }

    /// Parses a compiled scene; `path` is used only in error messages.
    pub fn decode(path: &Path, bytes: &[u8]) -> Result<CompiledScene> {
        if bytes.len() < PREAMBLE_LEN || &bytes[..8] != MAGIC {
            return Err(Error::input(
                path,
                "not a luxest compiled scene (bad magic); run scene-compile on the .ron scene",
            ));
        }
        let schema = u32::from_le_bytes(bytes[8..12].try_into().unwrap());
        if schema != SCHEMA_VERSION {
            return Err(Error::input(
                path,
                format!("compiled scene has schema version {schema}, this program reads {SCHEMA_VERSION}: recompile it"),
            ));
        }
        let stored_hash = u128::from_le_bytes(bytes[16..32].try_into().unwrap());
        let body = &bytes[32..];
        let hash = xxhash_rust::xxh3::xxh3_128(body);
        if hash != stored_hash {
            return Err(Error::input(
                path,
                "content hash mismatch: the compiled scene is corrupted or truncated",
            ));
        }
        let hlen = u64::from_le_bytes(body[..8].try_into().unwrap()) as usize;
        let mut r = Reader {
            path,
            bytes: body,
            pos: 8,
        };
        let header_bytes = r.take(hlen, "header")?;
        let text = std::str::from_utf8(header_bytes)
            .map_err(|_| Error::input(path, "compiled scene header is not UTF-8"))?;
        let header: SceneHeader = ron::from_str(text).map_err(|e| {
            Error::at(
                path,
                "header",
                format!("cannot parse compiled scene header: {e}"),
            )
        })?;
        // The name becomes a component of default output paths (trace, estimate, aov-write).
        luxest_io::outputs::path_component(&header.name, path, "header.name")?;
        let nv = header.stats.vertices as usize;
        let nt = header.stats.triangles as usize;
        let positions = r.f32x3(nv, "positions")?;
        let normals = r.f32x3(nv, "normals")?;
        let indices = r.u32x3(nt, "indices")?;
        let triangle_material = r.u32s(nt, "triangle materials")?;
        let triangle_emitter = r.u32s(nt, "triangle emitters")?;
        let nuv = if header.features.uvs { nv } else { 0 };
        let uvs = r.f32x2(nuv, "texture coordinates")?;
        let mut textures = Vec::with_capacity(header.textures.len());
        for _ in &header.textures {
            let (t, used) = Texture::decode(path, &body[r.pos..])?;
            r.pos += used;
            textures.push(t);
        }
        let texels = header
            .environment_map()
            .map_or(0, |m| (m.width as usize).saturating_mul(m.height as usize));
        let environment_texels = r.f32x3(texels, "environment map texels")?;
        if r.pos != body.len() {
            return Err(Error::input(
                path,
                "trailing bytes after the compiled scene arrays",
            ));
        }
        let scene = CompiledScene {
            header,
            positions,
            normals,
            indices,
            triangle_material,
            triangle_emitter,
            uvs,
            textures,
            environment_texels,
            content_hash: format!("{hash:032x}"),
        };
        scene
            .check_consistency()
            .map_err(|m| Error::input(path, m))?;
        Ok(scene)
    }

    /// Reads and checks a compiled scene file.
    pub fn load(path: &Path) -> Result<CompiledScene> {
        let bytes = luxest_io::fsio::read_bytes(path)?;
        Self::decode(path, &bytes)
    }

    /// Index bounds and table sizes, so that no stage can index out of range.
    pub fn check_consistency(&self) -> std::result::Result<(), String> {
        let nv = self.positions.len() as u32;
        if let Some((t, _)) = self
            .indices
            .iter()
            .enumerate()
            .find(|(_, tri)| tri.iter().any(|&i| i >= nv))
        {
            return Err(format!("triangle {t} references a vertex beyond {nv}"));
        }
        let nm = self.header.materials.len() as u32;
        if let Some(t) = self.triangle_material.iter().position(|&m| m >= nm) {
            return Err(format!("triangle {t} references material beyond {nm}"));
        }
        let ne = self.header.emitters.len() as u32;
        if let Some(t) = self
            .triangle_emitter
            .iter()
            .position(|&e| e != NO_EMITTER && e >= ne)
        {
            return Err(format!("triangle {t} references emitter beyond {ne}"));
        }
        if self.header.emitter_cdf.len() != self.header.emitters.len() {
            return Err("emitter table and its distribution differ in length".into());
        }
        let ntex = self.header.textures.len() as u32;
        if self.textures.len() != ntex as usize {
            return Err("texture table and texture data differ in length".into());
        }
        if !self.header.surfaces.is_empty() && self.header.surfaces.len() != nm as usize {
            return Err("surface table and material table differ in length".into());
        }
        let texture_refs = self.header.surfaces.iter().flat_map(|s| {
            [
                s.color,
                s.roughness,
                s.normal,
                s.opacity.as_ref().and_then(|o| o.texture),
            ]
        });
        let emitter_refs = self.header.emitters.iter().map(|e| match e {
            Emitter::Area { texture, .. } => *texture,
            _ => None,
        });
        if texture_refs
            .chain(emitter_refs)
            .flatten()
            .any(|t| t >= ntex)
        {
            return Err(format!(
                "a surface or emitter references texture beyond {ntex}"
            ));
        }
        if self.header.features.uvs && self.uvs.len() != self.positions.len() {
            return Err("texture coordinates and vertices differ in number".into());
        }
        let environments = self
            .header
            .emitters
            .iter()
            .filter(|e| matches!(e, Emitter::Environment { .. }))
            .count();
        if environments > 1 {
            return Err(format!("{environments} environment emitters (at most one)"));
        }
        for e in &self.header.emitters {
            match e {
                Emitter::Point {
                    spot: Some(cone), ..
                } => cone.check()?,
                Emitter::Environment {
                    radiance_rgb, map, ..
                } => {
                    if !(radiance_rgb.is_finite() && radiance_rgb.min_component() >= 0.0) {
                        return Err("environment radiance is negative or not finite".into());
                    }
                    if let Some(m) = map {
                        check_rotation(&m.to_world)?;
                    }
                }
                _ => {}
            }
        }
        let texels = self
            .header
            .environment_map()
            .map_or(0, |m| (m.width as usize).saturating_mul(m.height as usize));
        if self.environment_texels.len() != texels {
            return Err(format!(
                "{} environment map texels for a map of {texels}",
                self.environment_texels.len()
            ));
        }
        if let Some(k) = self
            .environment_texels
            .iter()
            .position(|t| t.iter().any(|c| !(c.is_finite() && *c >= 0.0)))
        {
            return Err(format!(
                "environment map texel {k} is negative or not finite"
            ));
        }
        let np = self.header.photometries.len() as u32;
        for e in &self.header.emitters {
            if let Emitter::Luminaire { photometry, .. } = e {
                if *photometry >= np {
                    return Err(format!("luminaire references photometry beyond {np}"));
                }
            }
        }
        for t in &self.header.photometries {
            let (nc, ng) = (t.c_deg.len(), t.gamma_deg.len());
            if nc < 2 || ng < 2 || t.cd.len() != nc * ng {
                return Err(format!(
                    "photometric table {} has {} values for {nc} x {ng} angles",
                    t.source,
                    t.cd.len()
                ));
            }
        }
        Ok(())
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// World-space corners of triangle `t` in double precision.
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        self.indices[t].map(|i| Vec3::from(self.positions[i as usize]))
    }

    pub fn material_of(&self, t: usize) -> &Material {
        &self.header.materials[self.triangle_material[t] as usize].model
    }
}

impl SceneHeader {
    /// The environment emitter's map, if the scene has one.
    pub fn environment_map(&self) -> Option<&EnvironmentMap> {
        self.emitters.iter().find_map(|e| match e {
            Emitter::Environment { map: Some(m), .. } => Some(m),
            _ => None,
        })
    }
}

/// Whether `m` is a rotation (orthonormal rows, determinant +1, within 1e-6).
pub fn check_rotation(m: &[[f64; 3]; 3]) -> std::result::Result<(), String> {
    let row = |i: usize| Vec3::from(m[i]);
    let det = row(0).dot(row(1).cross(row(2)));
    let orthonormal = (0..3).all(|i| {
        (0..3).all(|j| {
            let want = if i == j { 1.0 } else { 0.0 };
            (row(i).dot(row(j)) - want).abs() < 1e-6
        })
    });
    if orthonormal && (det - 1.0).abs() < 1e-6 {
        Ok(())
    } else {
        Err(format!("environment to_world {m:?} is not a rotation"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny() -> CompiledScene {
        CompiledScene {
            header: SceneHeader {
                name: "tiny".into(),
                compiler_version: "test".into(),
                camera: None,
                materials: vec![NamedMaterial {
                    name: "w".into(),
                    model: Material::Lambertian {
                        reflectance: Rgb::splat(0.5),
                    },
                }],
                emitters: vec![],
                emitter_cdf: vec![],
                objects: vec![],
                sensors: vec![],
                photometries: vec![],
                textures: vec![],
                surfaces: vec![],
                glare: None,
                portals: vec![],
                features: Features::default(),
                stats: Stats {
                    vertices: 3,
                    triangles: 1,
                    ..Stats::default()
                },
            },
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            normals: vec![[0.0; 3]; 3],
            indices: vec![[0, 1, 2]],
            triangle_material: vec![0],
            triangle_emitter: vec![NO_EMITTER],
            uvs: vec![],
            textures: vec![],
            environment_texels: vec![],
            content_hash: String::new(),
        }
    }

    #[test]
    fn round_trip_is_exact() {
        let mut s = tiny();
        let bytes = s.encode();
        let back = CompiledScene::decode(Path::new("t.lxs"), &bytes).unwrap();
        assert_eq!(back, s);
    }

    #[test]
    fn environment_map_round_trips_and_is_validated() {
        let mut s = tiny();
        s.header.emitters.push(Emitter::Environment {
            name: "sky".into(),
            radiance_rgb: Rgb::splat(2.0),
            map: Some(EnvironmentMap {
                source: "sky.exr".into(),
                width: 2,
                height: 2,
                to_world: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            }),
            sun: None,
            sky: None,
            flux_rgb: Rgb::splat(1.0),
        });
        s.header.emitter_cdf.push(1.0);
        s.environment_texels = vec![[1.0, 2.0, 3.0]; 4];
        let bytes = s.encode();
        let back = CompiledScene::decode(Path::new("t.lxs"), &bytes).unwrap();
        assert_eq!(back, s);
        let mut bad = s.clone();
        bad.environment_texels[3][1] = -1.0;
        let e = CompiledScene::decode(Path::new("t.lxs"), &bad.encode())
            .unwrap_err()
            .to_string();
        assert!(e.contains("texel 3 is negative"), "{e}");
        let mut bad = s.clone();
        if let Emitter::Environment { map: Some(m), .. } = &mut bad.header.emitters[0] {
            m.to_world[0][0] = 2.0;
        }
        let e = CompiledScene::decode(Path::new("t.lxs"), &bad.encode())
            .unwrap_err()
            .to_string();
        assert!(e.contains("is not a rotation"), "{e}");
    }

    #[test]
    fn corruption_and_truncation_are_detected() {
        let mut s = tiny();
        let mut bytes = s.encode();
        let n = bytes.len();
        bytes[n - 5] ^= 1;
        let e = CompiledScene::decode(Path::new("t.lxs"), &bytes)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.lxs: content hash mismatch"), "{e}");
        let e = CompiledScene::decode(Path::new("t.lxs"), b"hello")
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a luxest compiled scene"), "{e}");
    }

    #[test]
    fn hash_changes_with_content() {
        let mut a = tiny();
        let mut b = tiny();
        b.positions[2][1] = 2.0;
        a.encode();
        b.encode();
        assert_ne!(a.content_hash, b.content_hash);
    }
}
