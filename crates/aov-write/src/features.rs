//! The denoiser's features of a camera ray and their per-pixel f64 sums: albedo as the denoiser
//! sees it and the shading normal facing the ray, both of the first non-delta surface (through
//! mirrors, smooth metals and smooth glass, [`first_hit`]), the hit distance, the emitted radiance seen directly
//! or in a mirror (the part of `trace`'s image a denoiser must leave untouched) — averaged over exactly the pixel samples
//! `trace` uses ([`pixel_jitter`] with the same seed), and extendable like trace's film, so the
//! features at n samples do not depend on the snapshots taken on the way.

use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_io::progress::Progress;
use luxest_render::bsdf::{self, Transport};
use luxest_render::camera::{pixel_jitter, PinholeCamera};
use luxest_render::parallel::run_batches;
use luxest_render::scene::Material;
use luxest_render::world::World;

/// Albedo of a material as the denoiser sees it (Intel Open Image Denoise's definition): a
/// diffuse surface's colour; a metal's reflectivity at normal incidence; 1 for a dielectric
/// (where the ray does not follow it, see [`first_hit`]); for a layered material (`Glossy`, a
/// plastic's coating over its base) the sum of its layers' albedos; for a blend the weighted sum
/// of its materials'.
pub fn albedo(m: &Material) -> Rgb {
    match m {
        Material::Lambertian { reflectance } | Material::Mirror { reflectance } => *reflectance,
        Material::Glossy {
            diffuse, specular, ..
        } => *diffuse + *specular,
        Material::Conductor {
            eta,
            k,
            specular_reflectance,
            ..
        } => bsdf::conductor::reflectance(1.0, eta, k, specular_reflectance),
        Material::Plastic {
            diffuse_reflectance,
            specular_reflectance,
            ior,
            ..
        } => {
            let f0 = bsdf::fresnel_dielectric(1.0, *ior).0;
            *specular_reflectance * f0 + *diffuse_reflectance * (1.0 - f0)
        }
        Material::Blend {
            weight,
            first,
            second,
        } => albedo(first) * (1.0 - weight) + albedo(second) * *weight,
        Material::Dielectric { .. }
        | Material::RoughDielectric { .. }
        | Material::ThinDielectric { .. } => Rgb::WHITE,
    }
}

/// Features of one camera ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirstHit {
    pub albedo: Rgb,
    /// The shading normal, facing the ray (zero where the ray escapes).
    pub normal: Vec3,
    /// Distance in m to the first surface hit (zero where the ray escapes).
    pub depth: f64,
    /// Radiance emitted towards the camera by the surface hit or, through one mirror at the
    /// first hit, by the surface seen in it — or the environment's where the ray leaves the
    /// scene: exactly the terms `trace` adds at those vertices (weight one at the first, the
    /// mirror's reflectance at the second: nothing is sampled before them, and Russian roulette
    /// starts later).
    pub emission: Rgb,
}

impl FirstHit {
    const MISS: FirstHit = FirstHit {
        albedo: Rgb::BLACK,
        normal: Vec3::ZERO,
        depth: 0.0,
        emission: Rgb::BLACK,
    };
}

/// Delta vertices (mirror or smooth-dielectric hits) a feature ray follows at most.
pub const MAX_DELTA_VERTICES: u32 = 8;

/// Features of one camera ray, as Intel Open Image Denoise recommends for perfect specular
/// surfaces: albedo and normal of the first non-delta (diffuse or glossy) surface along the
/// delta path — through a mirror or a smooth metal, its reflectance times the albedo of the
/// surface seen in it; at the first smooth dielectric or thin sheet, the Fresnel blend of the reflected and transmitted paths'
/// features, at a later one its likelier branch alone (no random choice: the features stay
/// noise-free); at most [`MAX_DELTA_VERTICES`] delta vertices, the last one's own features. The
/// emission: see [`FirstHit::emission`]. The geometry is `trace`'s (its shading frames and offsets);
/// the normal is the shading frame's, normal maps applied.
/// Textures are filtered over the ray's footprint, `spread` radians wide (the camera's pixel,
/// [`PinholeCamera::pixel_spread`]) and widening with the distance along the delta path, so that
/// one sample's albedo is already the pixel's average of a minified texture.
pub fn first_hit(world: &World, origin: Vec3, dir: Vec3, spread: f64) -> FirstHit {
    along(world, (origin, dir), (0, false), (spread, 0.0))
}

fn along(
    world: &World,
    (origin, dir): (Vec3, Vec3),
    (vertices, split): (u32, bool),
    (spread, travelled): (f64, f64),
) -> FirstHit {
    let Some(sp) = world.intersect(origin, dir) else {
        return FirstHit {
            emission: world.environment_radiance(dir),
            ..FirstHit::MISS
        };
    };
    let wo = -dir;
    let travelled = travelled + sp.distance;
    let footprint = world.uv_footprint(&sp, wo, spread * travelled);
    let m = world.material_filtered(sp.triangle, sp.uv, (wo, sp.ns), footprint);
    let m = &*m;
    // trace's shading frame: the interpolated normal, the normal map's where there is one.
    let shading = world.shading_of(&sp, wo);
    let n = shading.n;
    let own = FirstHit {
        albedo: albedo(m),
        normal: if n.dot(dir) > 0.0 { -n } else { n },
        depth: sp.distance,
        emission: world.emitted_radiance(&sp, wo),
    };
    if vertices >= MAX_DELTA_VERTICES {
        return own;
    }
    // A branch of the delta path: trace's own sample (uc picks reflection below the Fresnel
    // reflectance, refraction above it) and the features where it leads.
    // The sample's weight is the lobe's (a mirror's reflectance, a smooth metal's Fresnel
    // reflectance).
    let branch = |uc: f64, split: bool| {
        let s = shading.sample_with(m, wo, (0.5, 0.5), uc, Transport::Radiance)?;
        Some((
            s.weight,
            along(
                world,
                (world.offset(sp.position, sp.ng, s.wi), s.wi),
                (vertices + 1, split),
                (spread, travelled),
            ),
        ))
    };
    let fresnel = match m {
        // trace's Fresnel reflectance at this vertex (bsdf::sample with flat normals).
        Material::Dielectric { ior } => Some(bsdf::dielectric_side(wo, n, n, *ior).reflectance),
        Material::ThinDielectric { ior } => {
            Some(bsdf::dielectric::thin_reflectance(wo.dot(n), *ior))
        }
        _ => None,
    };
    match (m, fresnel) {
        (
            Material::Mirror { .. }
            | Material::Conductor {
                roughness: None, ..
            },
            _,
        ) => match branch(0.0, split) {
            Some((reflectance, next)) => FirstHit {
                albedo: reflectance * next.albedo,
                normal: next.normal,
                depth: own.depth,
                emission: if vertices == 0 {
                    own.emission + reflectance * next.emission
                } else {
                    own.emission
                },
            },
            None => own,
        },
        (_, Some(f)) => {
            // Weights of the reflected and transmitted branches; at later dielectrics the
            // likelier branch alone, so that one camera ray's features stay one path (no
            // noise, no blow-up).
            let (reflected, transmitted) = match (split, f >= 0.5) {
                (false, _) => (f, 1.0 - f),
                (true, true) => (1.0, 0.0),
                (true, false) => (0.0, 1.0),
            };
            let (mut a, mut nrm) = (Rgb::BLACK, Vec3::ZERO);
            for (uc, w) in [(0.0, reflected), (1.0, transmitted)] {
                if w > 0.0 {
                    if let Some((_, h)) = branch(uc, true) {
                        a = a + h.albedo * w;
                        nrm += h.normal * w;
                    }
                }
            }
            FirstHit {
                albedo: a,
                normal: nrm,
                ..own
            }
        }
        _ => own,
    }
}

/// Bytes per pixel the feature film keeps (albedo, normal, emission sums and depth in f64), with
/// an output image (f32 RGB) and its encoding: checked against the memory available before
/// the film is allocated.
pub const BYTES_PER_PIXEL: u64 = 3 * 24 + 8 + 2 * 12;

/// Feature sums per pixel over samples `0..samples`.
pub struct FeatureFilm {
    pub width: usize,
    pub height: usize,
    albedo: Vec<[f64; 3]>,
    normal: Vec<[f64; 3]>,
    depth: Vec<f64>,
    emission: Vec<[f64; 3]>,
    pub samples: u32,
}

impl FeatureFilm {
    pub fn new(width: usize, height: usize) -> FeatureFilm {
        FeatureFilm {
            width,
            height,
            albedo: vec![[0.0; 3]; width * height],
            normal: vec![[0.0; 3]; width * height],
            depth: vec![0.0; width * height],
            emission: vec![[0.0; 3]; width * height],
            samples: 0,
        }
    }

    /// The plan of a run to `samples` samples per pixel (the resource rule): first hits of
    /// camera rays spread over the image, timed.
    pub fn plan(
        &self,
        world: &World,
        cam: &PinholeCamera,
        threads: usize,
        samples: u32,
    ) -> luxest_io::limits::WorkPlan {
        let (w, h) = (self.width as u64, self.height as u64);
        let pixels = w * h;
        let (per_sample, spent) = luxest_io::limits::seconds_per_unit(|k| {
            let pixel = (k * 7919) % pixels;
            let (u, v) = pixel_jitter(0x00ca_11b2_a7e2, pixel, k);
            let dir = cam.direction((pixel % w) as f64 + u, (pixel / w) as f64 + v);
            first_hit(world, cam.position, dir, cam.pixel_spread());
        });
        let total = (pixels * samples as u64) as f64;
        let threads = threads.min(self.height).max(1);
        luxest_io::limits::WorkPlan {
            stage: "aov-write".into(),
            work: format!("{w}x{h} pixels x {samples} first hits"),
            units: total,
            unit: "camera rays",
            seconds: total * per_sample / threads as f64,
            threads,
            memory_bytes: pixels as u128 * BYTES_PER_PIXEL as u128,
            calibration_seconds: spent,
            levers: "--spp, --min-samples, --resolution and --threads".into(),
        }
    }

    /// Adds samples `self.samples .. target` of every pixel (rows in parallel, each pixel's
    /// samples in order), counting them on `progress`.
    pub fn advance(
        &mut self,
        world: &World,
        cam: &PinholeCamera,
        (seed, threads): (u64, usize),
        target: u32,
        progress: &Progress,
    ) {
        let (w, h, done) = (self.width, self.height, self.samples);
        let rows = run_batches(h, threads, |y| {
            let mut tally = progress.tally();
            (0..w)
                .map(|x| {
                    let pixel = y * w + x;
                    let (mut a, mut n, mut d, mut e) = (Rgb::BLACK, Vec3::ZERO, 0.0, Rgb::BLACK);
                    for s in done..target {
                        let (u, v) = pixel_jitter(seed, pixel as u64, s as u64);
                        let hit = first_hit(
                            world,
                            cam.position,
                            cam.direction(x as f64 + u, y as f64 + v),
                            cam.pixel_spread(),
                        );
                        a = a + hit.albedo;
                        n += hit.normal;
                        d += hit.depth;
                        e = e + hit.emission;
                    }
                    tally.add(target.saturating_sub(done) as u64);
                    (a, n, d, e)
                })
                .collect::<Vec<_>>()
        });
        for (y, row) in rows.into_iter().enumerate() {
            for (x, (a, n, d, e)) in row.into_iter().enumerate() {
                let p = y * w + x;
                for k in 0..3 {
                    self.albedo[p][k] += a.0[k];
                    self.emission[p][k] += e.0[k];
                }
                self.normal[p][0] += n.x;
                self.normal[p][1] += n.y;
                self.normal[p][2] += n.z;
                self.depth[p] += d;
            }
        }
        self.samples = target;
    }

    /// Mean albedo per pixel.
    pub fn albedo(&self) -> Vec<[f32; 3]> {
        let n = self.samples.max(1) as f64;
        self.albedo
            .iter()
            .map(|a| a.map(|v| (v / n) as f32))
            .collect()
    }

    /// Mean emitted radiance seen directly per pixel.
    pub fn emission(&self) -> Vec<[f32; 3]> {
        let n = self.samples.max(1) as f64;
        self.emission
            .iter()
            .map(|e| e.map(|v| (v / n) as f32))
            .collect()
    }

    /// The mean of the unit normals, renormalised (OIDN expects unit or zero normals).
    pub fn normal(&self) -> Vec<[f32; 3]> {
        self.normal
            .iter()
            .map(|s| {
                let v = Vec3::new(s[0], s[1], s[2]);
                v.try_normalize().map(|u| u.to_f32()).unwrap_or([0.0; 3])
            })
            .collect()
    }

    /// Mean hit distance per pixel (m), as R = G = B.
    pub fn depth(&self) -> Vec<[f32; 3]> {
        let n = self.samples.max(1) as f64;
        self.depth.iter().map(|&d| [(d / n) as f32; 3]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use luxest_render::scene::{Microfacet, MicrofacetDistribution};

    fn close(a: Rgb, b: Rgb) -> bool {
        (0..3).all(|c| (a.0[c] - b.0[c]).abs() < 1e-12)
    }

    /// OIDN's albedo of the Mitsuba materials: a metal's reflectivity at normal incidence
    /// ((η − 1)² + k²) / ((η + 1)² + k²) times its specular reflectance; a plastic's coating and
    /// base weighted by the coating's normal-incidence reflectance ((η − 1) / (η + 1))²; a
    /// dielectric's 1; a blend's weighted sum.
    #[test]
    fn albedo_of_the_mitsuba_materials() {
        let rough = Microfacet {
            distribution: MicrofacetDistribution::Ggx,
            alpha: 0.2,
        };
        let metal = Material::Conductor {
            eta: Rgb([0.2, 1.0, 1.5]),
            k: Rgb([3.0, 2.0, 0.0]),
            specular_reflectance: Rgb([1.0, 0.5, 1.0]),
            roughness: Some(rough),
        };
        let f0 = |n: f64, k: f64| ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
        let expected = Rgb([f0(0.2, 3.0), 0.5 * f0(1.0, 2.0), f0(1.5, 0.0)]);
        assert!(close(albedo(&metal), expected), "{:?}", albedo(&metal));
        let plastic = Material::Plastic {
            diffuse_reflectance: Rgb([0.8, 0.4, 0.0]),
            specular_reflectance: Rgb::WHITE,
            ior: 1.5,
            nonlinear: false,
            roughness: None,
        };
        let expected = Rgb([0.04 + 0.96 * 0.8, 0.04 + 0.96 * 0.4, 0.04]);
        assert!(close(albedo(&plastic), expected), "{:?}", albedo(&plastic));
        let glass = Material::RoughDielectric {
            ior: 1.5,
            roughness: rough,
        };
        assert_eq!(albedo(&glass), Rgb::WHITE);
        assert_eq!(albedo(&Material::ThinDielectric { ior: 1.5 }), Rgb::WHITE);
        let blend = Material::Blend {
            weight: 0.25,
            first: Box::new(plastic.clone()),
            second: Box::new(glass),
        };
        let expected = albedo(&plastic) * 0.75 + Rgb::splat(0.25);
        assert!(close(albedo(&blend), expected));
    }
}
