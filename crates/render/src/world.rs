//! A compiled scene ready for Monte Carlo: the Embree tracer plus the queries every estimator
//! needs — surface interactions at hits, emitter choice by flux, emission sampling, points on
//! area emitters and directions towards the environment for next-event estimation, the
//! environment's radiance along rays that leave the scene, and scale-aware ray offsets.

use crate::compiled::{CompiledScene, Emitter, NO_EMITTER};
use crate::environment::{EnvironmentLight, EnvironmentSample};
use crate::light_bvh::{LightBounds, LightBvh, LightSampler};
use crate::luminaire::GoniometricLight;
use crate::portal::{PortalSampler, Views};
use crate::rt::{Hit, RayTracer};
use crate::sampling::{
    cosine_hemisphere, uniform_sphere, Distribution1D, Rng, Sampler, TriangleMeshSampler,
};
use crate::scene::{Material, OpacityChannel};
use crate::shading::Shading;
use crate::texture::Texture;
use luxest_io::color::Rgb;
use luxest_io::error::Result;
use luxest_io::math::Vec3;
use std::borrow::Cow;

/// A surface point hit by a ray.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// Position reconstructed from the triangle's vertices (more accurate than origin + t d).
    pub position: Vec3,
    /// Unit geometric normal, front side `(b - a) x (c - a)`.
    pub ng: Vec3,
    /// Unit shading normal: the interpolated vertex normals, as the mesh gives them (Mitsuba 3
    /// does not turn them to `ng`'s side), or `ng` for flat triangles.
    pub ns: Vec3,
    pub triangle: u32,
    pub distance: f64,
    /// Texture coordinates (zero unless the scene stores them).
    pub uv: [f64; 2],
}

/// A point on a light source with the flux it carries (for light paths).
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample {
    pub position: Vec3,
    /// Unit normal of an area emitter; `None` for a point source and the environment.
    pub normal: Option<Vec3>,
    pub direction: Vec3,
    /// The path enters from the environment: `position` lies on the disk outside the scene's
    /// bounding sphere and is no vertex of the path (no connection starts there).
    pub environment: bool,
    /// Flux weight (lm per RGB channel) of the path: emitter flux / selection probability.
    pub flux: Rgb,
    pub emitter: u32,
}

/// A point on an area emitter or a point source, for next-event estimation.
#[derive(Clone, Copy, Debug)]
pub struct LightPoint {
    pub position: Vec3,
    /// `None` for a point source.
    pub normal: Option<Vec3>,
    /// Radiance (area) or intensity (point, luminaire: towards the receiver) per channel.
    pub emitted: Rgb,
    /// Area density (area emitters, including the emitter choice) or discrete probability
    /// (point sources).
    pub pdf: f64,
}

pub struct World {
    pub scene: CompiledScene,
    pub tracer: RayTracer,
    /// Every emitter by flux: where light paths start.
    emitter_choice: Distribution1D,
    /// The emitters next-event estimation draws points on — all but the environment, which it
    /// samples on its own (see [`World::environment`]) — by flux; `None` when the environment
    /// is the only emitter. Without an environment the same distribution as `emitter_choice`.
    light_choice: Option<Distribution1D>,
    /// The one emitter of `light_choice`, if it has one alone (then no number is drawn).
    single_light: Option<usize>,
    /// Per area emitter, uniform points on its triangles from one 2D sample (None for point
    /// emitters).
    triangle_choice: Vec<Option<TriangleMeshSampler>>,
    /// Per area emitter, its triangles as (corner, edge 1, edge 2, unit normal), for fast
    /// sampling of points on lights.
    emitter_triangles: Vec<Vec<[Vec3; 4]>>,
    /// Per emitter, the run-time luminaire (empty unless the scene has luminaires).
    luminaires: Vec<Option<GoniometricLight>>,
    /// Whether any vertex has a shading normal (else shading normals are not interpolated).
    smooth: bool,
    /// Unit geometric normal of every triangle (saves a cross product and a square root per
    /// hit).
    triangle_normals: Vec<[f32; 3]>,
    /// Absolute offset used to leave surfaces and stop short of targets, from the scene size.
    pub epsilon: f64,
    /// Length of the bounding-box diagonal, m.
    pub diagonal: f64,
    /// The smallest side of the bounding box that is not flat (within [`FLAT_ULPS`] f32
    /// roundings of the geometry's largest coordinate), m (the "room size"); the diagonal for a
    /// flat scene. Scale for defaults such as the kernel regularisation radius.
    pub room_scale: f64,
    /// The area emitters alone, by flux (indexed like the emitters, others weigh 0); `None`
    /// without area emitters.
    area_choice: Option<Distribution1D>,
    /// The environment emitter and its index, if the scene has one.
    environment: Option<(u32, EnvironmentLight)>,
    /// The lights of `light_choice` in a BVH, indexed by emitter; `None` without them.
    light_bvh: Option<LightBvh>,
    /// How [`World::sample_light_point`] chooses its light.
    light_sampler: LightSampler,
    /// The environment's portals (the compiled header's), if it has any and they are in use
    /// ([`World::set_portals`]).
    portals: Option<PortalSampler>,
}

/// A direction towards the environment from [`World::sample_environment`].
pub type EnvSample = EnvironmentSample;

/// The cut-out test of a scene with opacity: a hit on a surface of opacity α (its `value`
/// times its texture's alpha at the hit) is kept where α reaches the cut-off, or, without a
/// cut-off, with probability α — decided by a hash of the hit and the ray, so that every ray
/// draws independently and the result is the same at any thread count.
fn opacity_mask(scene: &CompiledScene) -> Box<crate::rt::Mask> {
    type Cut = (Option<Texture>, OpacityChannel, f64, Option<f64>);
    let per_material: Vec<Option<Cut>> = scene
        .header
        .surfaces
        .iter()
        .map(|s| {
            s.opacity.as_ref().map(|o| {
                let texture = o.texture.map(|t| scene.textures[t as usize].clone());
                (texture, o.channel, o.value, o.cutoff)
            })
        })
        .collect();
    let triangle_material = scene.triangle_material.clone();
    let indices = scene.indices.clone();
    let uvs = scene.uvs.clone();
    Box::new(move |prim, u, v, ray| {
        let m = triangle_material[prim as usize] as usize;
        let Some(Some((texture, channel, value, cutoff))) = per_material.get(m) else {
            return true;
        };
        let mut alpha = *value;
        if let Some(t) = texture {
            let corners = indices[prim as usize].map(|i| uvs[i as usize]);
            alpha *= opacity(t, interpolate_uv(corners, u as f64, v as f64), *channel);
        }
        match cutoff {
            Some(c) => alpha >= *c,
            None if alpha >= 1.0 => true,
            None if alpha <= 0.0 => false,
            None => {
                let mut h = 0x9e37_79b9_7f4a_7c15u64 ^ prim as u64;
                for x in [u, v].into_iter().chain(ray) {
                    h = crate::sampling::splitmix64(h ^ x.to_bits() as u64);
                }
                ((h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)) < alpha
            }
        }
    })
}

/// The texture coordinates at barycentric (u, v) of a triangle whose corners have `corners`.
#[inline]
fn interpolate_uv([a, b, c]: [[f32; 2]; 3], u: f64, v: f64) -> [f64; 2] {
    let w = 1.0 - u - v;
    [0, 1].map(|k| a[k] as f64 * w + b[k] as f64 * u + c[k] as f64 * v)
}

/// A texture's opacity at `uv` read from `channel`.
#[inline]
pub fn opacity(t: &Texture, uv: [f64; 2], channel: OpacityChannel) -> f64 {
    opacity_of(t.eval(uv, 0.0), t.has_alpha(), channel)
}

/// The opacity in a texel (linear RGBA) of a texture that has alpha or not.
pub fn opacity_of(c: [f32; 4], has_alpha: bool, channel: OpacityChannel) -> f64 {
    let luminance = || Rgb([c[0] as f64, c[1] as f64, c[2] as f64]).luminance();
    match channel {
        OpacityChannel::Auto if has_alpha => c[3] as f64,
        OpacityChannel::Alpha => c[3] as f64,
        OpacityChannel::Auto | OpacityChannel::Luminance => luminance(),
    }
}

/// What a one-sided surface is seen from the back: it reflects nothing.
static BLACK: Material = Material::Lambertian {
    reflectance: Rgb::BLACK,
};

/// A side of the bounding box at most this many f32 roundings (`f32::EPSILON`) of the
/// geometry's largest |coordinate| is flat: a scene in one plane, up to the noise of its f32
/// vertices (rotated analytic shapes, exported meshes: about 1e-7 of their coordinates). It was
/// 1e-6 of the diagonal, which sensors and lights far off enlarge: two 2e6 m planes 2 m apart
/// (Sobolev's planes made wider) counted as flat, the room scale became 2e6 m and the default
/// kernel radius 2 km, which cut the indirect light without a word (with 4 roundings the
/// threshold there is 0.48 m).
pub const FLAT_ULPS: f64 = 4.0;

/// Largest image side of a camera stage (as scene-compile allows for the scene's camera).
pub const MAX_RESOLUTION: u32 = 1 << 15;

/// Bytes per pixel a camera stage may keep for its film: trace's f64 sums of the radiance and
/// of its square (48 B) bound aov-write's features and the double local estimate's film. Checked
/// against the memory available before any film is allocated.
pub const FILM_BYTES_PER_PIXEL: u64 = 48;

/// Parses a `WIDTHxHEIGHT` resolution override (a usage error otherwise, stating the range).
pub fn parse_resolution(r: &str) -> Result<(u32, u32)> {
    let parsed = r
        .split_once('x')
        .and_then(|(a, b)| Some((a.parse::<u32>().ok()?, b.parse::<u32>().ok()?)));
    match parsed {
        Some((a, b)) if a > 0 && b > 0 && a <= MAX_RESOLUTION && b <= MAX_RESOLUTION => Ok((a, b)),
        _ => Err(luxest_io::Error::Usage(format!(
            "--resolution: expected WIDTHxHEIGHT with each side in 1..={MAX_RESOLUTION}, got '{r}'"
        ))),
    }
}

/// How Embree intersects the scene's triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Traversal {
    /// Embree's robust mode: watertight on shared edges, also for rays that start on an edge
    /// or in a corner, where the local estimate's sensors and connection points sit.
    Robust,
    /// Embree's default mode, about 1.3× the robust mode's ray rate: for estimators whose rays
    /// start at sampled interior points of surfaces (the camera path tracer and its features).
    Fast,
}

/// Loads a compiled scene for a camera stage: the world and its pinhole camera, with an
/// optional `WIDTHxHEIGHT` resolution override. Errors name the scene file.
pub fn load_with_camera(
    path: &std::path::Path,
    resolution: Option<&str>,
    traversal: Traversal,
) -> Result<(World, crate::camera::PinholeCamera)> {
    let compiled = CompiledScene::load(path)?;
    let mut camera = compiled
        .header
        .camera
        .clone()
        .ok_or_else(|| luxest_io::Error::input(path, "scene has no camera"))?;
    if let Some(r) = resolution {
        camera.resolution = parse_resolution(r)?;
    }
    let (w, h) = camera.resolution;
    luxest_io::limits::check_image("film", w as u64, h as u64, FILM_BYTES_PER_PIXEL)
        .map_err(luxest_io::Error::Usage)?;
    let world = World::load_from(path, compiled, traversal)?;
    let cam = crate::camera::PinholeCamera::new(&camera)
        .ok_or_else(|| luxest_io::Error::input(path, "degenerate camera"))?;
    Ok((world, cam))
}

impl World {
    /// [`World::new`] with errors attributed to the compiled scene's file.
    pub fn load_from(
        path: &std::path::Path,
        scene: CompiledScene,
        traversal: Traversal,
    ) -> Result<World> {
        World::with_traversal(scene, traversal).map_err(|e| match e {
            luxest_io::Error::Usage(m) => luxest_io::Error::input(path, m),
            other => other,
        })
    }

    /// The world with [`Traversal::Robust`] ray queries.
    pub fn new(scene: CompiledScene) -> Result<World> {
        World::with_traversal(scene, Traversal::Robust)
    }

    /// The world with the given kind of ray queries (the stage that loads it chooses:
    /// docs/architecture.md, *Crate graph*).
    pub fn with_traversal(scene: CompiledScene, traversal: Traversal) -> Result<World> {
        for m in &scene.header.materials {
            crate::bsdf::prepare(&m.model);
        }
        let mask = scene.header.features.opacity.then(|| opacity_mask(&scene));
        let tracer = RayTracer::with_mask(
            &scene.positions,
            &scene.indices,
            traversal == Traversal::Robust,
            mask,
        )?;
        let weights: Vec<f64> = scene.header.emitters.iter().map(Emitter::flux_lm).collect();
        let emitter_choice = Distribution1D::new(&weights).ok_or_else(|| {
            luxest_io::Error::input(
                &scene.header.name,
                "scene has no emitter with positive flux",
            )
        })?;
        let light_weights: Vec<f64> = scene
            .header
            .emitters
            .iter()
            .map(|e| match e {
                Emitter::Environment { .. } => 0.0,
                _ => e.flux_lm(),
            })
            .collect();
        let light_choice = Distribution1D::new(&light_weights);
        let lights: Vec<usize> = (0..light_weights.len())
            .filter(|&i| !matches!(scene.header.emitters[i], Emitter::Environment { .. }))
            .collect();
        let single_light = (lights.len() == 1).then(|| lights[0]);
        let emitter_triangles: Vec<Vec<[Vec3; 4]>> = scene
            .header
            .emitters
            .iter()
            .map(|e| match e {
                Emitter::Area {
                    first_triangle,
                    triangle_count,
                    ..
                } => (*first_triangle..first_triangle + triangle_count)
                    .map(|t| {
                        let [a, b, c] = scene.triangle(t as usize);
                        let n = (b - a)
                            .cross(c - a)
                            .try_normalize()
                            .unwrap_or(Vec3::new(0.0, 0.0, 1.0));
                        [a, b - a, c - a, n]
                    })
                    .collect(),
                Emitter::Point { .. } | Emitter::Luminaire { .. } | Emitter::Environment { .. } => {
                    Vec::new()
                }
            })
            .collect();
        let triangle_choice = emitter_triangles
            .iter()
            .map(|tris: &Vec<[Vec3; 4]>| {
                let corners: Vec<[Vec3; 3]> =
                    tris.iter().map(|&[a, e1, e2, _]| [a, e1, e2]).collect();
                TriangleMeshSampler::new(&corners)
            })
            .collect();
        let luminaires = if scene.header.features.goniometric_luminaires {
            GoniometricLight::for_emitters(&scene.header.emitters, &scene.header.photometries)
                .map_err(|m| luxest_io::Error::input(&scene.header.name, m))?
        } else {
            Vec::new()
        };
        let environment = environment_light(&scene)
            .map_err(|m| luxest_io::Error::input(&scene.header.name, m))?;
        let portals = portal_sampler(&scene, &environment);
        let smooth = scene.header.features.smooth_normals;
        let triangle_normals = (0..scene.triangle_count())
            .map(|t| {
                let [a, b, c] = scene.triangle(t);
                (b - a)
                    .cross(c - a)
                    .try_normalize()
                    .unwrap_or(Vec3::new(0.0, 0.0, 1.0))
                    .to_f32()
            })
            .collect();
        let s = &scene.header.stats;
        let mut lo = s.bounds_min;
        let mut hi = s.bounds_max;
        for e in &scene.header.emitters {
            if let Emitter::Point { position, .. } | Emitter::Luminaire { position, .. } = e {
                lo = lo.min(*position);
                hi = hi.max(*position);
            }
            if let Emitter::Luminaire { opening_points, .. } = e {
                for p in opening_points {
                    lo = lo.min(*p);
                    hi = hi.max(*p);
                }
            }
        }
        for set in &scene.header.sensors {
            for p in &set.points {
                lo = lo.min(p.position);
                hi = hi.max(p.position);
            }
        }
        let diagonal = (hi - lo).length().max(f64::MIN_POSITIVE);
        let size = hi - lo;
        // Flat: within the rounding of the geometry's f32 coordinates (sensors and lights are
        // f64 and may lie far off without making the room's sides flat).
        let geometry = s
            .bounds_min
            .max_abs_component()
            .max(s.bounds_max.max_abs_component());
        let flat = if geometry.is_finite() {
            FLAT_ULPS * f32::EPSILON as f64 * geometry
        } else {
            0.0
        };
        let room_scale = [size.x, size.y, size.z]
            .into_iter()
            .filter(|&s| s > flat)
            .fold(diagonal, f64::min);
        let area_weights: Vec<f64> = scene
            .header
            .emitters
            .iter()
            .map(|e| match e {
                Emitter::Area { .. } => e.flux_lm(),
                _ => 0.0,
            })
            .collect();
        let area_choice = Distribution1D::new(&area_weights);
        let extent = lo
            .max_abs_component()
            .max(hi.max_abs_component())
            .max(diagonal);
        // f32 geometry: positions are accurate to ~6e-8 of their magnitude, so offsets are
        // taken relative to the local coordinates (see `margin`); this is only the floor for
        // points near the origin.
        let epsilon = 1e-9 * extent;
        let light_bvh = LightBvh::new(&light_bounds(&scene, &emitter_triangles, &luminaires));
        Ok(World {
            scene,
            tracer,
            emitter_choice,
            light_choice,
            single_light,
            triangle_choice,
            emitter_triangles,
            luminaires,
            smooth,
            triangle_normals,
            epsilon,
            diagonal,
            room_scale,
            area_choice,
            environment,
            light_bvh,
            light_sampler: LightSampler::Power,
            portals,
        })
    }

    /// Chooses how [`World::sample_light_point`] picks its light (power by default; `trace`
    /// uses the BVH).
    pub fn set_light_sampler(&mut self, sampler: LightSampler) {
        self.light_sampler = sampler;
    }

    /// How [`World::sample_light_point`] picks its light.
    pub fn light_sampler(&self) -> LightSampler {
        self.light_sampler
    }

    /// The shading frame at a point of `triangle` with texture coordinates `uv`, geometric
    /// normal `ng` and mesh shading normal `ns`, seen from `wo` (see [`crate::shading`]): the
    /// normal map of its surface applied, if it has one.
    #[inline]
    pub fn shading(
        &self,
        triangle: u32,
        uv: [f64; 2],
        (ng, ns): (Vec3, Vec3),
        wo: Vec3,
    ) -> Shading {
        if self.scene.header.features.normal_maps {
            let mi = self.scene.triangle_material[triangle as usize] as usize;
            if let Some(s) = self.scene.header.surfaces.get(mi) {
                if let Some(t) = s.normal {
                    let texel = self.texture(t).eval(uv, 0.0);
                    let dp_du = self.dp_du(triangle, ng);
                    return Shading::mapped((ng, ns), texel, s.normal_scale, dp_du, wo);
                }
            }
        }
        if ns == ng {
            Shading::flat(ng)
        } else {
            Shading::smooth(ng, ns)
        }
    }

    /// [`World::shading`] at a hit.
    #[inline]
    pub fn shading_of(&self, sp: &SurfacePoint, wo: Vec3) -> Shading {
        self.shading(sp.triangle, sp.uv, (sp.ng, sp.ns), wo)
    }

    /// ∂p/∂u of a triangle from its texture coordinates, as Mitsuba 3 computes it (p1 − p0
    /// without texture coordinates; an axis perpendicular to `ng` where they are degenerate).
    pub fn dp_du(&self, triangle: u32, ng: Vec3) -> Vec3 {
        let idx = self.scene.indices[triangle as usize];
        let [a, b, c] = idx.map(|i| Vec3::from(self.scene.positions[i as usize]));
        let (dp0, dp1) = (b - a, c - a);
        if !self.scene.header.features.uvs {
            return dp0;
        }
        let [ta, tb, tc] = idx.map(|i| self.scene.uvs[i as usize].map(|x| x as f64));
        let (d0, d1) = (
            [tb[0] - ta[0], tb[1] - ta[1]],
            [tc[0] - ta[0], tc[1] - ta[1]],
        );
        let det = d0[0] * d1[1] - d0[1] * d1[0];
        if det == 0.0 {
            return ng.orthonormal_basis().0;
        }
        (dp0 * d1[1] - dp1 * d0[1]) * (1.0 / det)
    }

    /// The material of a triangle as authored (untextured, both sides); the estimators ask
    /// [`World::material_at`] instead.
    pub fn material(&self, triangle: u32) -> &Material {
        self.scene.material_of(triangle as usize)
    }

    /// The material at a surface point seen from direction `wo`: its textures evaluated at the
    /// point's texture coordinates `uv`, and black where a one-sided surface is seen from the
    /// back — the side of its shading normal `ns`, as Mitsuba 3's BSDFs tell it. Borrowed (no
    /// copy) for untextured two-sided materials.
    #[inline]
    pub fn material_at(
        &self,
        triangle: u32,
        uv: [f64; 2],
        wo: Vec3,
        ns: Vec3,
    ) -> Cow<'_, Material> {
        self.material_filtered(triangle, uv, (wo, ns), 0.0)
    }

    /// [`World::material_at`] with textures filtered over a footprint `footprint` wide in uv
    /// space (mip-mapped; 0: the finest level, as the estimators look textures up — their
    /// pixel samples do the filtering).
    pub fn material_filtered(
        &self,
        triangle: u32,
        uv: [f64; 2],
        (wo, ns): (Vec3, Vec3),
        footprint: f64,
    ) -> Cow<'_, Material> {
        let mi = self.scene.triangle_material[triangle as usize] as usize;
        let m = &self.scene.header.materials[mi].model;
        let Some(s) = self.scene.header.surfaces.get(mi) else {
            return Cow::Borrowed(m);
        };
        if !s.two_sided && wo.dot(ns) < 0.0 {
            return Cow::Borrowed(&BLACK);
        }
        if s.color.is_none() && s.roughness.is_none() {
            return Cow::Borrowed(m);
        }
        let color = s.color.map(|t| {
            let [r, g, b, _] = self.texture(t).eval(uv, footprint);
            Rgb([r as f64, g as f64, b as f64])
        });
        let roughness = s
            .roughness
            .map(|t| self.texture(t).eval(uv, footprint)[0] as f64);
        Cow::Owned(m.textured(color, roughness))
    }

    /// [`World::material_at`] of a hit.
    #[inline]
    pub fn material_seen(&self, sp: &SurfacePoint, wo: Vec3) -> Cow<'_, Material> {
        self.material_at(sp.triangle, sp.uv, wo, sp.ns)
    }

    fn texture(&self, t: u32) -> &Texture {
        &self.scene.textures[t as usize]
    }

    /// The uv-space width of a footprint `width` metres wide on the surface at `sp` seen from
    /// direction `wo`: the footprint stretches by 1/√|cos θ| on average over its two axes, and
    /// the triangle maps metres to uv units by √(uv area / area). Zero without texture
    /// coordinates.
    pub fn uv_footprint(&self, sp: &SurfacePoint, wo: Vec3, width: f64) -> f64 {
        if !self.scene.header.features.uvs {
            return 0.0;
        }
        let idx = self.scene.indices[sp.triangle as usize];
        let [a, b, c] = idx.map(|i| Vec3::from(self.scene.positions[i as usize]));
        let [ta, tb, tc] = idx.map(|i| self.scene.uvs[i as usize].map(|x| x as f64));
        let area = (b - a).cross(c - a).length();
        let uv_area = ((tb[0] - ta[0]) * (tc[1] - ta[1]) - (tb[1] - ta[1]) * (tc[0] - ta[0])).abs();
        let cos = wo.dot(sp.ng).abs().max(1e-3);
        if area > 0.0 {
            width * (uv_area / area).sqrt() / cos.sqrt()
        } else {
            0.0
        }
    }

    /// Texture coordinates at barycentric (u, v) of a triangle (zero without stored ones).
    #[inline]
    pub fn uv_at(&self, triangle: u32, u: f64, v: f64) -> [f64; 2] {
        if !self.scene.header.features.uvs {
            return [0.0, 0.0];
        }
        let idx = self.scene.indices[triangle as usize];
        interpolate_uv(idx.map(|i| self.scene.uvs[i as usize]), u, v)
    }

    pub fn emitter_of(&self, triangle: u32) -> Option<u32> {
        let e = self.scene.triangle_emitter[triangle as usize];
        (e != NO_EMITTER).then_some(e)
    }

    /// Unit geometric normal of a triangle.
    pub fn geometric_normal(&self, triangle: u32) -> Vec3 {
        Vec3::from(self.triangle_normals[triangle as usize])
    }

    /// The surface point of a hit.
    pub fn surface(&self, hit: &Hit) -> SurfacePoint {
        let t = hit.triangle as usize;
        let idx = self.scene.indices[t];
        let [a, b, c] = idx.map(|i| Vec3::from(self.scene.positions[i as usize]));
        let (u, v) = (hit.u, hit.v);
        let position = a * (1.0 - u - v) + b * u + c * v;
        let ng = Vec3::from(self.triangle_normals[t]);
        let ns = if self.smooth {
            let [na, nb, nc] = idx.map(|i| Vec3::from(self.scene.normals[i as usize]));
            (na * (1.0 - u - v) + nb * u + nc * v)
                .try_normalize()
                .unwrap_or(ng)
        } else {
            ng
        };
        SurfacePoint {
            position,
            ng,
            ns,
            triangle: hit.triangle,
            distance: hit.t,
            uv: self.uv_at(hit.triangle, u, v),
        }
    }

    /// Closest surface along a ray leaving a point light or a luminaire's source, beyond the
    /// margin around it: a luminaire mounted exactly on a ceiling or wall (its position on that
    /// surface, as recessed troffers are placed) emits into the room. The first hit was the
    /// surface itself at t = 0, and every light path's reflected light was lost without a word.
    pub fn intersect_from_source(&self, origin: Vec3, direction: Vec3) -> Option<SurfacePoint> {
        self.tracer
            .intersect(
                origin,
                direction,
                self.margin(origin, origin),
                f64::INFINITY,
            )
            .map(|h| self.surface(&h))
    }

    /// Closest surface along a ray.
    pub fn intersect(&self, origin: Vec3, direction: Vec3) -> Option<SurfacePoint> {
        self.tracer
            .intersect(origin, direction, 0.0, f64::INFINITY)
            .map(|h| self.surface(&h))
    }

    /// Origin for a ray leaving `p` (on a surface with unit normal `ng`) in direction `d`:
    /// offset to the side `d` points to, proportionally to the coordinates' magnitude.
    pub fn offset(&self, p: Vec3, ng: Vec3, d: Vec3) -> Vec3 {
        let eps = self.epsilon.max(2e-6 * p.max_abs_component());
        if d.dot(ng) >= 0.0 {
            p + ng * eps
        } else {
            p - ng * eps
        }
    }

    /// The margin kept at both ends of a segment between two points given in world space.
    pub fn margin(&self, a: Vec3, b: Vec3) -> f64 {
        self.epsilon
            .max(2e-6 * a.max_abs_component().max(b.max_abs_component()))
    }

    /// Whether the segment from `from` to `to` is blocked, ignoring the margin at both ends:
    /// both usually lie on surfaces, and a sensor on an edge or in a corner lies on several
    /// (whose planes pass through the segment's start).
    pub fn occluded(&self, from: Vec3, to: Vec3) -> bool {
        let d = to - from;
        let len = d.length();
        let eps = self.margin(from, to);
        if len <= 2.0 * eps {
            return false;
        }
        self.tracer.occluded(from, d / len, eps, len - eps)
    }

    /// Closest surface within `tfar` along a ray that starts on a sensor point: hits closer
    /// than the margin (the surfaces the sensor itself lies on) are ignored.
    pub fn intersect_from_sensor(
        &self,
        origin: Vec3,
        direction: Vec3,
        tfar: f64,
    ) -> Option<SurfacePoint> {
        let eps = self.margin(origin, origin);
        self.tracer
            .intersect(origin, direction, eps, tfar)
            .map(|h| self.surface(&h))
    }

    /// The run-time luminaire of emitter `ei`, if it is one.
    #[inline]
    pub fn luminaire(&self, ei: usize) -> Option<&GoniometricLight> {
        self.luminaires.get(ei).and_then(Option::as_ref)
    }

    /// For a delta light (isotropic point, spot or luminaire) `ei`: calls
    /// `f(position, intensity)` for each of its point sources with the intensity per channel
    /// (cd) it radiates towards `receiver` (one source, except for a luminaire's area opening);
    /// nothing for area emitters and the environment.
    #[inline]
    pub fn for_each_delta_source(&self, ei: usize, receiver: Vec3, mut f: impl FnMut(Vec3, Rgb)) {
        match &self.scene.header.emitters[ei] {
            Emitter::Point {
                position,
                intensity_rgb,
                spot,
                ..
            } => f(
                *position,
                point_intensity(*intensity_rgb, spot, receiver - *position),
            ),
            Emitter::Luminaire { .. } => {
                let l = self
                    .luminaire(ei)
                    .expect("luminaires are built for luminaire scenes");
                for &s in l.sources() {
                    f(s, l.source_intensity_toward(s, receiver));
                }
            }
            Emitter::Area { .. } | Emitter::Environment { .. } => {}
        }
    }

    /// The environment emitter, if the scene has one.
    #[inline]
    pub fn environment(&self) -> Option<&EnvironmentLight> {
        self.environment.as_ref().map(|(_, e)| e)
    }

    /// Radiance per channel arriving along the unit direction `w` from outside the scene (what
    /// a ray travelling along `w` that escapes sees); black without an environment.
    #[inline]
    pub fn environment_radiance(&self, w: Vec3) -> Rgb {
        self.environment().map_or(Rgb::BLACK, |e| e.radiance(w))
    }

    /// Solid-angle density with which next-event estimation at the point `from` draws the
    /// direction `w` towards the environment ([`World::sample_environment`], besides the light
    /// point of [`World::sample_light_point`]), for multiple importance sampling; 0 without one,
    /// and where the portals are in use and `from` sees none.
    pub fn environment_pdf(&self, from: Vec3, w: Vec3) -> f64 {
        let Some(env) = self.environment() else {
            return 0.0;
        };
        let Some(portals) = &self.portals else {
            return env.pdf(w);
        };
        match portals.rectangles(from) {
            None => 0.0,
            Some(views) => {
                let p_sun = sun_share_through(env, portals, &views);
                through_portals_pdf(env, portals, &views, p_sun, w)
            }
        }
    }

    /// A direction from the point `from` towards the environment for two uniform numbers, its
    /// radiance and its density [`World::environment_pdf`]; `None` without an environment.
    /// Without portals: [`EnvironmentLight::sample`]. With portals: the sun's cone (with its
    /// share of [`EnvironmentLight::sample`], where the sky has a sun whose cone may pass
    /// through a portal from `from`) or the map through the portals ([`crate::portal`]); `None`
    /// where `from` sees no portal (a point in the portals' plane: the wall holding the
    /// windows), whose sky is then left to BSDF sampling (the density there is 0).
    pub fn sample_environment(&self, from: Vec3, u1: f64, u2: f64) -> Option<EnvSample> {
        let env = self.environment()?;
        let Some(portals) = &self.portals else {
            return Some(env.sample(u1, u2));
        };
        let views = portals.rectangles(from)?;
        let p_sun = sun_share_through(env, portals, &views);
        let direction = if u1 < p_sun {
            env.sample_sun(u1 / p_sun, u2)?
        } else {
            let r = ((u1 - p_sun) / (1.0 - p_sun)).clamp(0.0, 1.0 - f64::EPSILON / 2.0);
            portals.sample(&views, r, u2)
        };
        Some(EnvSample {
            direction,
            radiance: env.radiance(direction),
            pdf: through_portals_pdf(env, portals, &views, p_sun, direction),
        })
    }

    /// Uses the compiled scene's portals for [`World::sample_environment`] (`true`, the
    /// default where it has any) or not; `false` samples the environment as if it had none.
    pub fn set_portals(&mut self, on: bool) {
        if !on {
            self.portals = None;
        } else if self.portals.is_none() {
            self.portals = portal_sampler(&self.scene, &self.environment);
        }
    }

    /// The number of portals [`World::sample_environment`] uses.
    pub fn portal_count(&self) -> usize {
        self.portals.as_ref().map_or(0, PortalSampler::len)
    }

    /// Whether the scene has an emitter besides the environment (what
    /// [`World::sample_light_point`] draws from).
    pub fn has_light_points(&self) -> bool {
        self.light_choice.is_some()
    }

    /// Whether a ray from `from` (already offset from its surface) along the unit direction
    /// `w` leaves the scene without hitting anything.
    pub fn escapes(&self, from: Vec3, w: Vec3) -> bool {
        !self
            .tracer
            .occluded(from, w, self.margin(from, from), f64::INFINITY)
    }

    /// Starts a light path: an emitter chosen by flux, a point on it and a direction
    /// (isotropic for point sources, uniform over the cone for spots, from the intensity table
    /// for luminaires (see [`crate::luminaire`]), cosine-distributed from the front of area
    /// emitters, from the map through the bounding disk for the environment (see
    /// [`crate::environment`])).
    pub fn sample_emission(&self, rng: &mut Rng) -> EmissionSample {
        let (ei, p_e) = self.emitter_choice.sample(rng.next_f64());
        match &self.scene.header.emitters[ei] {
            Emitter::Point {
                position,
                flux_rgb,
                spot: None,
                ..
            } => EmissionSample {
                position: *position,
                normal: None,
                direction: uniform_sphere(rng.next_f64(), rng.next_f64()),
                flux: *flux_rgb * (1.0 / p_e),
                emitter: ei as u32,
                environment: false,
            },
            Emitter::Point {
                position,
                intensity_rgb,
                spot: Some(cone),
                ..
            } => {
                let direction = cone.sample(rng.next_f64(), rng.next_f64());
                let weight = cone.falloff(direction) * cone.cone_solid_angle() / p_e;
                EmissionSample {
                    position: *position,
                    normal: None,
                    direction,
                    flux: *intensity_rgb * weight,
                    emitter: ei as u32,
                    environment: false,
                }
            }
            Emitter::Environment { .. } => {
                let env = self.environment().expect("the environment is built");
                let u = [
                    rng.next_f64(),
                    rng.next_f64(),
                    rng.next_f64(),
                    rng.next_f64(),
                ];
                let (position, direction, weight) = env.sample_emission(u);
                EmissionSample {
                    position,
                    normal: None,
                    direction,
                    flux: weight * (1.0 / p_e),
                    emitter: ei as u32,
                    environment: true,
                }
            }
            Emitter::Luminaire { .. } => {
                let l = self
                    .luminaire(ei)
                    .expect("luminaires are built for luminaire scenes");
                let position = l.choose_source(rng);
                let (direction, weight) = l.sample_emission(rng.next_f64(), rng.next_f64());
                EmissionSample {
                    position,
                    normal: None,
                    direction,
                    flux: weight * (1.0 / p_e),
                    emitter: ei as u32,
                    environment: false,
                }
            }
            Emitter::Area {
                flux_rgb,
                texture,
                area_m2,
                ..
            } => {
                let (position, normal, radiance) = self.sample_area_point(ei, rng);
                // Uniform in area and cosine-weighted in direction: the weight is
                // π L(x) A / p_e, the emitter's flux where L is constant.
                let flux = match texture {
                    None => *flux_rgb,
                    Some(_) => radiance * (std::f64::consts::PI * area_m2),
                };
                let local = cosine_hemisphere(rng.next_f64(), rng.next_f64());
                let (t, b) = normal.orthonormal_basis();
                EmissionSample {
                    position,
                    normal: Some(normal),
                    direction: t * local.x + b * local.y + normal * local.z,
                    flux: flux * (1.0 / p_e),
                    emitter: ei as u32,
                    environment: false,
                }
            }
        }
    }

    /// A uniformly distributed point on area emitter `ei`: (position, unit front normal,
    /// its luminance there).
    fn sample_area_point(&self, ei: usize, rng: &mut impl Sampler) -> (Vec3, Vec3, Rgb) {
        let Emitter::Area {
            first_triangle,
            radiance_rgb,
            texture,
            ..
        } = &self.scene.header.emitters[ei]
        else {
            unreachable!("sample_area_point on a point emitter")
        };
        let mesh = self.triangle_choice[ei]
            .as_ref()
            .expect("area emitter has triangles");
        let (u1, u2) = rng.next_2d();
        let (ti, b1, b2) = mesh.sample(u1, u2);
        let [a, e1, e2, n] = self.emitter_triangles[ei][ti];
        let radiance = match texture {
            None => *radiance_rgb,
            Some(_) => {
                let uv = self.uv_at(first_triangle + ti as u32, b1, b2);
                self.textured_radiance(*radiance_rgb, *texture, uv)
            }
        };
        (a + e1 * b1 + e2 * b2, n, radiance)
    }

    /// A point on a light chosen among all emitters but the environment — by flux, or by
    /// importance at `receiver` through the light BVH ([`World::set_light_sampler`]) — for
    /// next-event estimation at `receiver` (a luminaire's or spot's intensity depends on the
    /// direction towards it). Only for scenes with such a light ([`World::has_light_points`]).
    /// Where the BVH finds no light that can reach `receiver`, the point is `receiver` itself
    /// with no emission (a zero-length connection, which the estimators skip).
    pub fn sample_light_point(&self, rng: &mut impl Sampler, receiver: Vec3) -> LightPoint {
        self.sample_light_point_facing(rng, receiver, None)
    }

    /// [`World::sample_light_point`] for a receiver whose unit normal (either side) is known:
    /// the light BVH weighs each light by the receiver's cosine bound too.
    pub fn sample_light_point_facing(
        &self,
        rng: &mut impl Sampler,
        receiver: Vec3,
        normal: Option<Vec3>,
    ) -> LightPoint {
        // One emitter needs no choice (no random number drawn).
        let (ei, p_e) = match (self.single_light, self.light_sampler, &self.light_bvh) {
            (Some(i), _, _) => (i, 1.0),
            (None, LightSampler::Bvh, Some(bvh)) => {
                match bvh.sample(receiver, normal, rng.next_f64()) {
                    Some(chosen) => chosen,
                    None => {
                        return LightPoint {
                            position: receiver,
                            normal: None,
                            emitted: Rgb::BLACK,
                            pdf: 1.0,
                        }
                    }
                }
            }
            _ => match &self.light_choice {
                Some(choice) => choice.sample(rng.next_f64()),
                None => unreachable!("next-event estimation of a scene without light points"),
            },
        };
        match &self.scene.header.emitters[ei] {
            Emitter::Luminaire { .. } => {
                // One source of an area opening, chosen uniformly, with the whole intensity:
                // the expectation is the sum of the sources' shares.
                let l = self
                    .luminaire(ei)
                    .expect("luminaires are built for luminaire scenes");
                let position = l.choose_source(rng);
                LightPoint {
                    position,
                    normal: None,
                    emitted: l.intensity_toward(receiver - position),
                    pdf: p_e,
                }
            }
            Emitter::Point {
                position,
                intensity_rgb,
                spot,
                ..
            } => LightPoint {
                position: *position,
                normal: None,
                emitted: point_intensity(*intensity_rgb, spot, receiver - *position),
                pdf: p_e,
            },
            Emitter::Area { .. } => self.area_light_point(ei, p_e, rng),
            Emitter::Environment { .. } => {
                unreachable!("the light choice gives the environment weight 0")
            }
        }
    }

    /// A uniformly sampled point of the area emitter `ei`, chosen with probability `p_e`.
    fn area_light_point(&self, ei: usize, p_e: f64, rng: &mut impl Sampler) -> LightPoint {
        let Emitter::Area { area_m2, .. } = &self.scene.header.emitters[ei] else {
            unreachable!("area_light_point on an emitter without area")
        };
        let (position, normal, radiance) = self.sample_area_point(ei, rng);
        LightPoint {
            position,
            normal: Some(normal),
            emitted: radiance,
            pdf: p_e / area_m2,
        }
    }

    /// A point on an area emitter, the emitter chosen among the area emitters alone by flux
    /// (point sources and luminaires are exact elsewhere, so an estimator that needs area
    /// emitters only does not spend samples on them); `None` without area emitters. Its `pdf`
    /// is [`World::area_light_point_pdf`].
    pub fn sample_area_light_point(&self, rng: &mut impl Sampler) -> Option<LightPoint> {
        let (ei, p_e) = self.area_choice.as_ref()?.sample(rng.next_f64());
        Some(self.area_light_point(ei, p_e, rng))
    }

    /// Area density with which [`World::sample_area_light_point`] picks a point on the area
    /// emitter `emitter`.
    pub fn area_light_point_pdf(&self, emitter: u32) -> f64 {
        match (
            &self.area_choice,
            &self.scene.header.emitters[emitter as usize],
        ) {
            (Some(choice), Emitter::Area { area_m2, .. }) => choice.pmf(emitter as usize) / area_m2,
            _ => 0.0,
        }
    }

    /// The probability with which [`World::sample_light_point_facing`] chooses the emitter
    /// `emitter` for the receiver `receiver` of normal `normal`.
    pub fn light_choice_pmf(&self, emitter: u32, receiver: Vec3, normal: Option<Vec3>) -> f64 {
        match (self.single_light, self.light_sampler, &self.light_bvh) {
            (Some(i), _, _) => f64::from(u8::from(i == emitter as usize)),
            (None, LightSampler::Bvh, Some(bvh)) => bvh.pmf(emitter as usize, receiver, normal),
            _ => self
                .light_choice
                .as_ref()
                .map_or(0.0, |c| c.pmf(emitter as usize)),
        }
    }

    /// Area density with which [`World::sample_light_point`] picks a point on the area emitter
    /// `emitter` for the receiver `receiver` (for multiple importance sampling).
    pub fn light_point_pdf(&self, emitter: u32, receiver: Vec3) -> f64 {
        self.light_point_pdf_facing(emitter, receiver, None)
    }

    /// Area density with which [`World::sample_light_point_facing`] picks a point on the area
    /// emitter `emitter` for the receiver `receiver` of normal `normal`.
    pub fn light_point_pdf_facing(
        &self,
        emitter: u32,
        receiver: Vec3,
        normal: Option<Vec3>,
    ) -> f64 {
        if !matches!(
            self.scene.header.emitters[emitter as usize],
            Emitter::Area { .. }
        ) {
            return 0.0;
        }
        let p_e = self.light_choice_pmf(emitter, receiver, normal);
        match &self.scene.header.emitters[emitter as usize] {
            Emitter::Area { area_m2, .. } => p_e / area_m2,
            Emitter::Point { .. } | Emitter::Luminaire { .. } | Emitter::Environment { .. } => 0.0,
        }
    }

    /// The emitter index and luminance of the surface at `sp` towards `w`, if it emits that
    /// way.
    #[inline]
    pub fn emission(&self, sp: &SurfacePoint, w: Vec3) -> Option<(u32, Rgb)> {
        let e = self.emitter_of(sp.triangle)?;
        match &self.scene.header.emitters[e as usize] {
            Emitter::Area {
                radiance_rgb,
                texture,
                ..
            } if sp.ng.dot(w) > 0.0 => {
                Some((e, self.textured_radiance(*radiance_rgb, *texture, sp.uv)))
            }
            _ => None,
        }
    }

    /// [`World::emission`] for scenes without textured emitters: the emitter's constant
    /// luminance.
    #[inline]
    pub fn emission_plain(&self, triangle: u32, ng: Vec3, w: Vec3) -> Option<(u32, Rgb)> {
        let e = self.emitter_of(triangle)?;
        match &self.scene.header.emitters[e as usize] {
            Emitter::Area { radiance_rgb, .. } if ng.dot(w) > 0.0 => Some((e, *radiance_rgb)),
            _ => None,
        }
    }

    /// Luminance per channel emitted by the surface at `sp` towards `w` (zero behind the
    /// emitter or off emitters).
    pub fn emitted_radiance(&self, sp: &SurfacePoint, w: Vec3) -> Rgb {
        self.emission(sp, w).map_or(Rgb::BLACK, |(_, l)| l)
    }

    /// An area emitter's luminance at texture coordinates `uv`: `radiance` times the texel.
    #[inline]
    fn textured_radiance(&self, radiance: Rgb, texture: Option<u32>, uv: [f64; 2]) -> Rgb {
        match texture {
            None => radiance,
            Some(t) => {
                let [r, g, b, _] = self.texture(t).eval(uv, 0.0);
                radiance * Rgb([r as f64, g as f64, b as f64])
            }
        }
    }
}

/// The light BVH's bounds of every emitter that next-event estimation draws from (all but the
/// environment), with its index.
fn light_bounds(
    scene: &CompiledScene,
    emitter_triangles: &[Vec<[Vec3; 4]>],
    luminaires: &[Option<GoniometricLight>],
) -> Vec<(LightBounds, u32)> {
    let mut out = Vec::new();
    for (ei, e) in scene.header.emitters.iter().enumerate() {
        let bounds = match e {
            Emitter::Area { .. } => {
                let tris = &emitter_triangles[ei];
                let Some(first) = tris.first() else { continue };
                let (mut lo, mut hi) = (first[0], first[0]);
                let mut cone = LightBounds::lambertian(first[0], first[0], 0.0, first[3], 1.0);
                for &[a, e1, e2, n] in tris {
                    for p in [a, a + e1, a + e2] {
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                    cone = cone.union(&LightBounds::lambertian(a, a, 0.0, n, 1.0));
                }
                LightBounds::lambertian(
                    lo,
                    hi,
                    e.flux_lm() / std::f64::consts::PI,
                    cone.w,
                    cone.cos_o,
                )
            }
            Emitter::Point {
                position,
                intensity_rgb,
                spot,
                ..
            } => match spot {
                None => LightBounds::point(*position, intensity_rgb.luminance()),
                Some(c) => LightBounds::cone(
                    *position,
                    *position,
                    intensity_rgb.luminance(),
                    c.direction,
                    c.cutoff_deg.to_radians().cos(),
                ),
            },
            Emitter::Luminaire { .. } => {
                let Some(Some(l)) = luminaires.get(ei) else {
                    continue;
                };
                let (phi, cos_gamma) = l.intensity_bound();
                let s = l.sources();
                let (lo, hi) = s[1..]
                    .iter()
                    .fold((s[0], s[0]), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
                LightBounds::cone(lo, hi, phi, l.nadir(), cos_gamma)
            }
            Emitter::Environment { .. } => continue,
        };
        out.push((bounds, ei as u32));
    }
    out
}

/// A point source's intensity towards `toward`: the same in every direction, or a spot's
/// on-axis intensity times its falloff.
#[inline]
fn point_intensity(intensity: Rgb, spot: &Option<crate::spot::SpotCone>, toward: Vec3) -> Rgb {
    match spot {
        None => intensity,
        Some(cone) => intensity * cone.falloff(toward),
    }
}

/// The probability of sampling the sun's cone from a point with portal views `views`: the
/// environment's own share where the cone may pass through a portal, else 0 (the shadow ray of
/// every sun direction would be blocked).
/// The portal sampler of the scene's environment, if it has one and the compiled header lists
/// portals.
fn portal_sampler(
    scene: &CompiledScene,
    environment: &Option<(u32, EnvironmentLight)>,
) -> Option<PortalSampler> {
    match environment {
        Some((_, env)) if !scene.header.portals.is_empty() => Some(PortalSampler::new(
            env,
            &scene.header.portals,
            crate::portal::RESOLUTION,
        )),
        _ => None,
    }
}

/// Solid-angle density of `w` drawn from the sun with probability `p_sun`, else through the
/// portals seen as `views`.
fn through_portals_pdf(
    env: &EnvironmentLight,
    portals: &PortalSampler,
    views: &Views,
    p_sun: f64,
    w: Vec3,
) -> f64 {
    p_sun * env.sun_pdf(w) + (1.0 - p_sun) * portals.pdf(views, w)
}

fn sun_share_through(env: &EnvironmentLight, portals: &PortalSampler, views: &Views) -> f64 {
    match env.sun_cone() {
        Some((d, cos_max)) if portals.cone_may_pass(views, d, cos_max) => env.sun_share(),
        _ => 0.0,
    }
}

/// The run-time environment emitter of a compiled scene, with its index.
fn environment_light(
    scene: &CompiledScene,
) -> std::result::Result<Option<(u32, EnvironmentLight)>, String> {
    let sphere = scene.header.bounding_sphere();
    for (ei, e) in scene.header.emitters.iter().enumerate() {
        if let Emitter::Environment {
            radiance_rgb,
            map,
            sun,
            ..
        } = e
        {
            let light = match map {
                None => EnvironmentLight::constant(*radiance_rgb, sphere),
                Some(m) => EnvironmentLight::map(
                    (
                        m.width as usize,
                        m.height as usize,
                        scene.environment_texels.clone(),
                    ),
                    radiance_rgb.0[0],
                    m.to_world,
                    sphere,
                )?,
            };
            let light = match sun {
                Some(s) => light.with_sun(s)?,
                None => light,
            };
            return Ok(Some((ei as u32, light)));
        }
    }
    Ok(None)
}
