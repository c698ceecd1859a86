//! First-hit features and their per-pixel f64 sums: albedo as the denoiser sees it, the
//! shading normal facing the camera, the hit distance, the emitted radiance seen directly (the
//! part of `trace`'s image a denoiser must leave untouched) — averaged over exactly the pixel samples
//! `trace` uses ([`pixel_jitter`] with the same seed), and extendable like trace's film, so the
//! features at n samples do not depend on the snapshots taken on the way.

use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_render::camera::{pixel_jitter, PinholeCamera};
use luxest_render::parallel::run_batches;
use luxest_render::scene::Material;
use luxest_render::world::World;

/// Albedo of a material as the denoiser sees it.
pub fn albedo(m: &Material) -> Rgb {
    match m {
        Material::Lambertian { reflectance } | Material::Mirror { reflectance } => *reflectance,
        Material::Glossy {
            diffuse, specular, ..
        } => *diffuse + *specular,
        Material::Dielectric { .. } => Rgb::WHITE,
    }
}

/// First-hit features of one camera ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirstHit {
    pub albedo: Rgb,
    /// The shading normal, facing the camera (zero where the ray escapes).
    pub normal: Vec3,
    /// Hit distance in m (zero where the ray escapes).
    pub depth: f64,
    /// Radiance emitted towards the camera by the surface hit: exactly the term `trace` adds
    /// at a camera ray's hit (weight one: nothing is sampled before it).
    pub emission: Rgb,
}

/// First-hit features of one camera ray.
pub fn first_hit(world: &World, origin: Vec3, dir: Vec3) -> FirstHit {
    match world.intersect(origin, dir) {
        None => FirstHit {
            albedo: Rgb::BLACK,
            normal: Vec3::ZERO,
            depth: 0.0,
            emission: Rgb::BLACK,
        },
        Some(sp) => FirstHit {
            albedo: albedo(world.material(sp.triangle)),
            normal: if sp.ns.dot(dir) > 0.0 { -sp.ns } else { sp.ns },
            depth: sp.distance,
            emission: world.emitted_radiance(sp.triangle, sp.ng, -dir),
        },
    }
}

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

    /// Adds samples `self.samples .. target` of every pixel (rows in parallel, each pixel's
    /// samples in order).
    pub fn advance(
        &mut self,
        world: &World,
        cam: &PinholeCamera,
        seed: u64,
        threads: usize,
        target: u32,
    ) {
        let (w, h, done) = (self.width, self.height, self.samples);
        let rows = run_batches(h, threads, "aov-write", |y| {
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
                        );
                        a = a + hit.albedo;
                        n += hit.normal;
                        d += hit.depth;
                        e = e + hit.emission;
                    }
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
