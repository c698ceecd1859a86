//! Environment light: radiance arriving from infinitely far away along every ray that leaves
//! the scene — a constant sky (Mitsuba 3 `constant`) or an equirectangular HDR map (Mitsuba 3
//! `envmap`, `src/emitters/envmap.cpp`).
//!
//! Direction ↔ map. For the map-local unit direction d = to_worldᵀ ω (ω pointing from the scene
//! towards the sky), u = atan2(d.x, −d.z) / 2π wrapped to [0, 1) and v = acos(d.y) / π, so that
//! d = (sin φ sin θ, cos θ, −cos φ sin θ) with φ = 2π u, θ = π v. The radiance is the bilinear
//! interpolation of the texels, times `scale`, with Mitsuba's texel placement: column i's
//! centre at u = (i + ½)/W (wrapping around in u), row j at v = j/(H − 1) (the first row is the
//! +y pole, the last the −y pole; clamped).
//!
//! Sampling (for next-event estimation and light paths). Constant: uniform over the sphere.
//! Map: piecewise constant over the cells of the bilinear patches — cell (i, j) spans the
//! columns' centres i and i + 1 in u and the rows j and j + 1 in v — with probability
//! proportional to the mean luminance of its four texels times its solid angle
//! Ω_ij = (2π/W)(cos θ_j − cos θ_{j+1}), and uniform in (φ, cos θ) inside it: the solid-angle
//! density is P(cell) / Ω_cell, positive wherever the radiance is. The cell is drawn by a
//! marginal (row) and a conditional (column) distribution, each from one of the two random
//! numbers, which are then reused inside the cell.
//!
//! The sun ([`SunDisk`], a daylight sky's: [`crate::sky`]) is an analytic disk added to the
//! map: radiance inside its cone of half-angle δ, sampled uniformly in that cone (density
//! 1/Ω_sun, Ω_sun = 2π(1 − cos δ)) with probability p_sun, the map with 1 − p_sun; `pdf` is
//! the mixture's, so every estimator's multiple importance sampling sees one emitter. p_sun is
//! the sun's share of the luminance integral ∫ Y dω, kept within [0.1, 0.9] so that neither
//! part starves. An environment without a sun skips all of it.
//!
//! Light paths enter through the disk of radius R perpendicular to the direction of travel and
//! tangent to the scene's bounding sphere (centre c, radius R: `SceneHeader::bounding_sphere`);
//! a path with direction ω towards the sky and disk point p carries the flux weight
//! L(ω) π R² / p(ω), and the environment's power is Φ = π R² ∫ L dω (the light that crosses the
//! disk, all the scene can receive).

use crate::sampling::{concentric_disk, uniform_sphere, Distribution1D};
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A distant disk source (the sun): unit direction towards it, angular radius, radiance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SunDisk {
    pub direction: Vec3,
    pub half_angle_deg: f64,
    /// cd/m² per channel.
    pub radiance_rgb: Rgb,
}

impl SunDisk {
    /// Ω = 2π (1 − cos δ), sr.
    pub fn solid_angle(&self) -> f64 {
        2.0 * PI * (1.0 - self.half_angle_deg.to_radians().cos())
    }

    /// L Ω (lx): the illuminance on a plane facing the sun.
    pub fn direct_normal_illuminance(&self) -> f64 {
        self.radiance_rgb.luminance() * self.solid_angle()
    }
}

/// The run-time sun: its disk, frame and sampling probability.
#[derive(Clone, Debug)]
struct Sun {
    direction: Vec3,
    tangent: Vec3,
    bitangent: Vec3,
    cos_max: f64,
    solid_angle: f64,
    radiance: Rgb,
    /// Probability of sampling the sun rather than the map.
    p: f64,
}

impl Sun {
    /// The direction of the cone for two uniform numbers (uniform in solid angle).
    #[inline]
    fn cone(&self, r: f64, u2: f64) -> Vec3 {
        let ct = 1.0 - r * (1.0 - self.cos_max);
        let st = (1.0 - ct * ct).max(0.0).sqrt();
        let (sp, cp) = (2.0 * PI * u2).sin_cos();
        self.tangent * (st * cp) + self.bitangent * (st * sp) + self.direction * ct
    }

    /// The cone's density at `w` (uniform inside, 0 outside).
    #[inline]
    fn cone_pdf(&self, w: Vec3) -> f64 {
        if w.dot(self.direction) >= self.cos_max {
            1.0 / self.solid_angle
        } else {
            0.0
        }
    }
}

/// An equirectangular map's texels and the sampling distribution over its cells.
#[derive(Clone, Debug)]
struct Map {
    width: usize,
    height: usize,
    /// Row-major RGB, `height` rows of `width` texels, linear, before the scale.
    texels: Vec<[f32; 3]>,
    /// Rows of cells (H − 1 of them) by their weight.
    rows: Distribution1D,
    /// Per row, its W cells by weight (`None` for a row of weight 0, never drawn).
    columns: Vec<Option<Distribution1D>>,
}

/// The run-time environment emitter (world space).
#[derive(Clone, Debug)]
pub struct EnvironmentLight {
    /// Constant: the radiance; map: the scale, per channel.
    radiance: Rgb,
    map: Option<Map>,
    /// Map-to-world rotation, row-major.
    to_world: [[f64; 3]; 3],
    /// The bounding sphere light paths enter through.
    center: Vec3,
    radius: f64,
    sun: Option<Sun>,
}

/// A direction towards the environment with the radiance arriving along it.
#[derive(Clone, Copy, Debug)]
pub struct EnvironmentSample {
    /// Unit direction from the receiver towards the sky.
    pub direction: Vec3,
    pub radiance: Rgb,
    /// Solid-angle density of the direction.
    pub pdf: f64,
}

/// Index drawn from `d` with `u`, its probability, and `u` rescaled to [0, 1) within the entry.
fn sample_remapped(d: &Distribution1D, u: f64) -> (usize, f64, f64) {
    let (i, p) = d.sample(u);
    let below = if i == 0 { 0.0 } else { d.cdf()[i - 1] };
    let r = if p > 0.0 { (u - below) / p } else { 0.5 };
    (i, p, r.clamp(0.0, 1.0 - f64::EPSILON / 2.0))
}

fn mul(m: &[[f64; 3]; 3], v: Vec3) -> Vec3 {
    Vec3::new(
        m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
        m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
        m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z,
    )
}

fn mul_transposed(m: &[[f64; 3]; 3], v: Vec3) -> Vec3 {
    Vec3::new(
        m[0][0] * v.x + m[1][0] * v.y + m[2][0] * v.z,
        m[0][1] * v.x + m[1][1] * v.y + m[2][1] * v.z,
        m[0][2] * v.x + m[1][2] * v.y + m[2][2] * v.z,
    )
}

/// Mitsuba's map coordinates (u, v) of the map-local unit direction `d`.
pub fn direction_to_uv(d: Vec3) -> (f64, f64) {
    let u = (d.x.atan2(-d.z) / (2.0 * PI)).rem_euclid(1.0);
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    (u, v)
}

/// The map-local unit direction of map coordinates (u, v).
pub fn uv_to_direction(u: f64, v: f64) -> Vec3 {
    let (st, ct) = (PI * v).sin_cos();
    let (sp, cp) = (2.0 * PI * u).sin_cos();
    Vec3::new(sp * st, ct, -cp * st)
}

impl Map {
    fn texel(&self, i: usize, j: usize) -> Rgb {
        let t = self.texels[j * self.width + i];
        Rgb([t[0] as f64, t[1] as f64, t[2] as f64])
    }

    /// cos θ of row `j`'s centre.
    fn row_cos(&self, j: usize) -> f64 {
        (PI * j as f64 / (self.height - 1) as f64).cos()
    }

    fn cell_solid_angle(&self, j: usize) -> f64 {
        2.0 * PI / self.width as f64 * (self.row_cos(j) - self.row_cos(j + 1))
    }

    fn new(width: usize, height: usize, texels: Vec<[f32; 3]>) -> Result<Map, String> {
        if width < 2 || height < 2 {
            return Err(format!(
                "environment map of {width}x{height} texels: at least 2x2 are needed"
            ));
        }
        if texels.len() != width * height {
            return Err(format!(
                "environment map has {} texels for {width}x{height}",
                texels.len()
            ));
        }
        if let Some(k) = texels
            .iter()
            .position(|t| t.iter().any(|c| !(c.is_finite() && *c >= 0.0)))
        {
            return Err(format!(
                "environment map texel ({}, {}) is negative or not finite",
                k % width,
                k / width
            ));
        }
        let mut map = Map {
            width,
            height,
            texels,
            rows: Distribution1D::new(&[1.0]).expect("one positive weight"),
            columns: Vec::new(),
        };
        let mut row_weights = Vec::with_capacity(height - 1);
        for j in 0..height - 1 {
            let omega = map.cell_solid_angle(j);
            let weights: Vec<f64> = (0..width)
                .map(|i| {
                    let i1 = (i + 1) % width;
                    let mean = (map.texel(i, j).luminance()
                        + map.texel(i1, j).luminance()
                        + map.texel(i, j + 1).luminance()
                        + map.texel(i1, j + 1).luminance())
                        / 4.0;
                    mean * omega
                })
                .collect();
            let d = Distribution1D::new(&weights);
            row_weights.push(d.as_ref().map_or(0.0, Distribution1D::total));
            map.columns.push(d);
        }
        map.rows = Distribution1D::new(&row_weights)
            .ok_or_else(|| "environment map is black (no texel with luminance > 0)".to_string())?;
        Ok(map)
    }

    /// Bilinear radiance at (u, v), before the scale.
    fn lookup(&self, u: f64, v: f64) -> Rgb {
        let (w, h) = (self.width, self.height);
        let x = u * w as f64 - 0.5;
        let x0 = x.floor();
        let fx = x - x0;
        let i0 = (x0 as i64).rem_euclid(w as i64) as usize;
        let i1 = (i0 + 1) % w;
        let y = (v.clamp(0.0, 1.0) * (h - 1) as f64).min((h - 1) as f64);
        let j0 = (y.floor() as usize).min(h - 2);
        let fy = y - j0 as f64;
        let top = self.texel(i0, j0) * (1.0 - fx) + self.texel(i1, j0) * fx;
        let bottom = self.texel(i0, j0 + 1) * (1.0 - fx) + self.texel(i1, j0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The cell (i, j) holding (u, v).
    fn cell(&self, u: f64, v: f64) -> (usize, usize) {
        let x = (u * self.width as f64 - 0.5).floor() as i64;
        let i = x.rem_euclid(self.width as i64) as usize;
        let j = ((v.clamp(0.0, 1.0) * (self.height - 1) as f64) as usize).min(self.height - 2);
        (i, j)
    }

    /// Solid-angle density of the map-local direction with coordinates (u, v).
    fn pdf(&self, u: f64, v: f64) -> f64 {
        let (i, j) = self.cell(u, v);
        match &self.columns[j] {
            Some(c) => self.rows.pmf(j) * c.pmf(i) / self.cell_solid_angle(j),
            None => 0.0,
        }
    }

    /// A map-local direction and its solid-angle density.
    fn sample(&self, u1: f64, u2: f64) -> (Vec3, f64) {
        let (j, p_row, r2) = sample_remapped(&self.rows, u2);
        let columns = self.columns[j]
            .as_ref()
            .expect("a row of weight 0 is never drawn");
        let (i, p_col, r1) = sample_remapped(columns, u1);
        let u = ((i as f64 + 0.5 + r1) / self.width as f64).rem_euclid(1.0);
        let (c0, c1) = (self.row_cos(j), self.row_cos(j + 1));
        let cos_t = (c0 - r2 * (c0 - c1)).clamp(-1.0, 1.0);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let (sp, cp) = (2.0 * PI * u).sin_cos();
        let d = Vec3::new(sp * sin_t, cos_t, -cp * sin_t);
        (d, p_row * p_col / self.cell_solid_angle(j))
    }

    /// ∫ luminance dω of the bilinear map (before the scale), by the midpoint rule on 4 × 4
    /// sub-cells of every cell.
    fn luminance_integral(&self) -> f64 {
        let (w, h) = (self.width, self.height);
        let k = 4;
        let mut total = 0.0;
        for j in 0..h - 1 {
            for sj in 0..k {
                let v0 = (j as f64 + sj as f64 / k as f64) / (h - 1) as f64;
                let v1 = (j as f64 + (sj + 1) as f64 / k as f64) / (h - 1) as f64;
                let omega_row = (PI * v0).cos() - (PI * v1).cos();
                let v = 0.5 * (v0 + v1);
                for i in 0..w {
                    for si in 0..k {
                        let u = (i as f64 + 0.5 + (si as f64 + 0.5) / k as f64) / w as f64;
                        total += self.lookup(u, v).luminance() * omega_row;
                    }
                }
            }
        }
        total * 2.0 * PI / (w * k) as f64
    }
}

impl EnvironmentLight {
    /// A constant environment of radiance `radiance` (cd/m² per channel).
    pub fn constant(radiance: Rgb, (center, radius): (Vec3, f64)) -> EnvironmentLight {
        EnvironmentLight {
            radiance,
            map: None,
            to_world: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            center,
            radius,
            sun: None,
        }
    }

    /// A map of `width × height` texels (row-major RGB, top row first) times `scale`, rotated
    /// by `to_world`; an error for a map too small, with a negative or non-finite texel, or
    /// black.
    pub fn map(
        (width, height, texels): (usize, usize, Vec<[f32; 3]>),
        scale: f64,
        to_world: [[f64; 3]; 3],
        (center, radius): (Vec3, f64),
    ) -> Result<EnvironmentLight, String> {
        Ok(EnvironmentLight {
            radiance: Rgb::splat(scale),
            map: Some(Map::new(width, height, texels)?),
            to_world,
            center,
            radius,
            sun: None,
        })
    }

    /// The same environment with the sun disk `sun` added; an error for a disk that is not a
    /// direction, a half-angle outside (0°, 5°], or a radiance not finite and positive.
    pub fn with_sun(mut self, sun: &SunDisk) -> Result<EnvironmentLight, String> {
        let direction = sun
            .direction
            .try_normalize()
            .ok_or("the sun's direction is not a direction")?;
        if !(sun.half_angle_deg > 0.0 && sun.half_angle_deg <= 5.0) {
            return Err(format!(
                "the sun's half-angle {}° is outside (0°, 5°]",
                sun.half_angle_deg
            ));
        }
        let y = sun.radiance_rgb.luminance();
        if !(sun.radiance_rgb.is_finite() && sun.radiance_rgb.min_component() >= 0.0 && y > 0.0) {
            return Err("the sun's radiance is not finite and positive".into());
        }
        let solid_angle = sun.solid_angle();
        let sky = self.luminance_integral();
        let share = y * solid_angle / (y * solid_angle + sky);
        let (tangent, bitangent) = direction.orthonormal_basis();
        self.sun = Some(Sun {
            direction,
            tangent,
            bitangent,
            cos_max: sun.half_angle_deg.to_radians().cos(),
            solid_angle,
            radiance: sun.radiance_rgb,
            p: share.clamp(0.1, 0.9),
        });
        Ok(self)
    }

    /// Radiance of the map (or constant) alone along `w`, without the sun disk.
    #[inline]
    pub(crate) fn sky_radiance(&self, w: Vec3) -> Rgb {
        match &self.map {
            None => self.radiance,
            Some(m) => {
                let (u, v) = direction_to_uv(mul_transposed(&self.to_world, w));
                m.lookup(u, v) * self.radiance
            }
        }
    }

    /// Density of the map (or constant) sampler alone.
    fn sky_pdf(&self, w: Vec3) -> f64 {
        match &self.map {
            None => 1.0 / (4.0 * PI),
            Some(m) => {
                let (u, v) = direction_to_uv(mul_transposed(&self.to_world, w));
                m.pdf(u, v)
            }
        }
    }

    /// The map (or constant) sampler alone.
    fn sky_sample(&self, u1: f64, u2: f64) -> Vec3 {
        match &self.map {
            None => uniform_sphere(u1, u2),
            Some(m) => mul(&self.to_world, m.sample(u1, u2).0),
        }
    }

    /// Radiance per channel (cd/m²) arriving from the unit world direction `w` (pointing from
    /// the scene towards the sky): what a ray travelling along `w` that escapes sees.
    #[inline]
    pub fn radiance(&self, w: Vec3) -> Rgb {
        let l = self.sky_radiance(w);
        match &self.sun {
            Some(s) if w.dot(s.direction) >= s.cos_max => l + s.radiance,
            _ => l,
        }
    }

    /// Solid-angle density with which [`Self::sample`] returns the unit direction `w`.
    pub fn pdf(&self, w: Vec3) -> f64 {
        match &self.sun {
            None => self.sky_pdf(w),
            Some(s) => (1.0 - s.p) * self.sky_pdf(w) + s.p * s.cone_pdf(w),
        }
    }

    /// The probability with which [`Self::sample`] draws the sun's cone (0 without a sun).
    pub fn sun_share(&self) -> f64 {
        self.sun.as_ref().map_or(0.0, |s| s.p)
    }

    /// A direction uniform in the sun's cone for two uniform numbers; `None` without a sun.
    pub fn sample_sun(&self, u1: f64, u2: f64) -> Option<Vec3> {
        self.sun
            .as_ref()
            .map(|s| s.cone(u1.min(1.0 - f64::EPSILON / 2.0), u2))
    }

    /// The sun's unit direction and the cosine of its half-angle; `None` without a sun.
    pub fn sun_cone(&self) -> Option<(Vec3, f64)> {
        self.sun.as_ref().map(|s| (s.direction, s.cos_max))
    }

    /// The density of [`Self::sample_sun`] at `w` (0 without a sun).
    pub fn sun_pdf(&self, w: Vec3) -> f64 {
        self.sun.as_ref().map_or(0.0, |s| s.cone_pdf(w))
    }

    /// A direction towards the sky for two uniform numbers, its radiance and density.
    pub fn sample(&self, u1: f64, u2: f64) -> EnvironmentSample {
        let (direction, pdf) = match &self.sun {
            None => match &self.map {
                None => (uniform_sphere(u1, u2), 1.0 / (4.0 * PI)),
                Some(m) => {
                    let (d, pdf) = m.sample(u1, u2);
                    (mul(&self.to_world, d), pdf)
                }
            },
            Some(s) => {
                let d = if u1 < s.p {
                    // Uniform in the cone, u1 rescaled to [0, 1).
                    s.cone((u1 / s.p).min(1.0 - f64::EPSILON / 2.0), u2)
                } else {
                    let r = ((u1 - s.p) / (1.0 - s.p)).clamp(0.0, 1.0 - f64::EPSILON / 2.0);
                    self.sky_sample(r, u2)
                };
                (d, self.pdf(d))
            }
        };
        EnvironmentSample {
            direction,
            radiance: self.radiance(direction),
            pdf,
        }
    }

    /// ∫ Y(L(ω)) dω, cd/m² · sr (Y the luminance of the RGB radiance).
    pub fn luminance_integral(&self) -> f64 {
        let sky = match &self.map {
            None => 4.0 * PI * self.radiance.luminance(),
            Some(m) => m.luminance_integral() * self.radiance.luminance(),
        };
        sky + self
            .sun
            .as_ref()
            .map_or(0.0, |s| s.radiance.luminance() * s.solid_angle)
    }

    /// The environment's flux through the bounding disk, lm per channel, with the RGB split
    /// of the map's mean (π R² ∫ L dω).
    pub fn flux_rgb(&self) -> Rgb {
        let disk = PI * self.radius * self.radius;
        let sun = self
            .sun
            .as_ref()
            .map_or(Rgb::BLACK, |s| s.radiance * (s.solid_angle * disk));
        sun + match &self.map {
            None => self.radiance * (4.0 * PI * disk),
            Some(m) => {
                // Per channel: the same midpoint rule as the luminance integral, on the
                // channel instead of Y (linear in the texels).
                let mut c = [0.0; 3];
                for (k, ck) in c.iter_mut().enumerate() {
                    let mut one = m.clone();
                    for t in &mut one.texels {
                        *t = [t[k]; 3];
                    }
                    *ck = one.luminance_integral();
                }
                Rgb(c) * self.radiance * disk
            }
        }
    }

    /// Starts a light path from the environment: (origin on the disk outside the bounding
    /// sphere, unit direction of travel, flux weight L π R² / p) for four uniform numbers.
    pub fn sample_emission(&self, u: [f64; 4]) -> (Vec3, Vec3, Rgb) {
        let s = self.sample(u[0], u[1]);
        let (dx, dy) = concentric_disk(u[2], u[3]);
        let (t, b) = s.direction.orthonormal_basis();
        // A little beyond the tangent plane, so that no surface lies behind the origin.
        let r = self.radius * (1.0 + 1e-6);
        let origin = self.center + (s.direction + t * dx + b * dy) * r;
        let weight = if s.pdf > 0.0 {
            s.radiance * (PI * r * r / s.pdf)
        } else {
            Rgb::BLACK
        };
        (origin, -s.direction, weight)
    }

    /// The bounding sphere's centre and radius.
    pub fn bounding_sphere(&self) -> (Vec3, f64) {
        (self.center, self.radius)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use luxest_io::chi2::{ChiSquareTest, Sphere};
    use std::path::Path;

    /// A 16 × 9 map: a bright sun-like texel on a smooth gradient, two black rows (the cells
    /// between them are never sampled).
    fn test_map() -> (usize, usize, Vec<[f32; 3]>) {
        let (w, h) = (16, 9);
        let mut t = Vec::new();
        for j in 0..h {
            for i in 0..w {
                let base = 0.2 + 0.1 * i as f32 + 0.3 * j as f32;
                let sun = if (i, j) == (5, 2) { 40.0 } else { 0.0 };
                let black = j == 6 || j == 7;
                let v = if black { 0.0 } else { base + sun };
                t.push([v, 0.5 * v, 0.25 * v + 0.1 * (!black) as u8 as f32]);
            }
        }
        (w, h, t)
    }

    fn rot_x(deg: f64) -> [[f64; 3]; 3] {
        let (s, c) = deg.to_radians().sin_cos();
        [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
    }

    #[test]
    fn uv_mapping_round_trips_and_matches_mitsubas_axes() {
        // u = 0 is −z, u = 1/4 is +x; v = 0 is +y.
        let d = uv_to_direction(0.0, 0.5);
        assert!((d - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-12);
        let d = uv_to_direction(0.25, 0.5);
        assert!((d - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-12);
        for (u, v) in [(0.1, 0.2), (0.7, 0.9), (0.49, 0.5)] {
            let (u2, v2) = direction_to_uv(uv_to_direction(u, v));
            assert!((u - u2).abs() < 1e-12 && (v - v2).abs() < 1e-12);
        }
    }

    #[test]
    fn lookup_hits_texel_centres_and_wraps() {
        let (w, h, t) = test_map();
        let env =
            EnvironmentLight::map((w, h, t.clone()), 2.0, rot_x(0.0), (Vec3::ZERO, 1.0)).unwrap();
        let m = env.map.as_ref().unwrap();
        for (i, j) in [(0, 0), (5, 2), (15, 8), (3, 6)] {
            let u = (i as f64 + 0.5) / w as f64;
            let v = j as f64 / (h - 1) as f64;
            let l = m.lookup(u, v);
            let e = t[j * w + i];
            assert!((l.0[0] - e[0] as f64).abs() < 1e-5, "{i} {j}: {l:?} {e:?}");
        }
        // Halfway between the last and the first column: their mean.
        let l = m.lookup(0.0, 0.0);
        let e = (t[w - 1][0] + t[0][0]) as f64 / 2.0;
        assert!((l.0[0] - e).abs() < 1e-5);
    }

    #[test]
    fn lookup_agrees_with_mitsuba() {
        // tests/data/envmap_mitsuba.py: Mitsuba 3's `envmap` radiance along 64 escaping rays,
        // with a rotated to_world and a scale, from the committed 8 × 5 map.
        let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
        let image = luxest_io::exr::read_rgb(&data.join("envmap_test.exr")).unwrap();
        let table = std::fs::read_to_string(data.join("envmap_mitsuba.csv")).unwrap();
        let lines: Vec<&str> = table.lines().collect();
        let scale: f64 = lines[1].rsplit("scale ").next().unwrap().parse().unwrap();
        let m: Vec<f64> = lines[2]
            .rsplit(": ")
            .next()
            .unwrap()
            .split(' ')
            .map(|x| x.parse().unwrap())
            .collect();
        let to_world = [[m[0], m[1], m[2]], [m[3], m[4], m[5]], [m[6], m[7], m[8]]];
        let env = EnvironmentLight::map(
            (image.width, image.height, image.pixels),
            scale,
            to_world,
            (Vec3::ZERO, 1.0),
        )
        .unwrap();
        let mut rows = 0;
        for line in &lines[4..] {
            let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
            let l = env.radiance(Vec3::new(v[0], v[1], v[2]));
            for c in 0..3 {
                let want = v[3 + c];
                assert!(
                    (l.0[c] - want).abs() <= 2e-5 * want,
                    "direction {:?}: channel {c} {} vs Mitsuba {want}",
                    &v[..3],
                    l.0[c]
                );
            }
            rows += 1;
        }
        assert_eq!(rows, 64);
    }

    #[test]
    fn map_sampling_follows_its_pdf() {
        // A rotated map: the sampler's world directions are brought back to the map frame, in
        // which the test's sphere about +z is the map's sphere about +y with φ = 2π u; bins
        // aligned with the cells integrate the piecewise-constant pdf exactly.
        let (w, h, t) = test_map();
        let rot = rot_x(30.0);
        let env = EnvironmentLight::map((w, h, t), 1.0, rot, (Vec3::ZERO, 1.0)).unwrap();
        let to_test = |d: Vec3| Vec3::new(-d.z, d.x, d.y);
        let from_test = |p: Vec3| Vec3::new(p.y, p.z, -p.x);
        let mut cos_edges: Vec<f64> = (0..h)
            .map(|j| (PI * j as f64 / (h - 1) as f64).cos())
            .collect();
        cos_edges.reverse();
        cos_edges[0] = -1.0;
        cos_edges[h - 1] = 1.0;
        let mut phi_edges = vec![0.0];
        phi_edges.extend((0..w).map(|i| 2.0 * PI * (i as f64 + 0.5) / w as f64));
        phi_edges.push(2.0 * PI);
        let mut r = Rng::new(7, 3);
        ChiSquareTest::new(Sphere)
            .edges(cos_edges, phi_edges)
            .samples(200_000)
            .run(
                || {
                    let s = env.sample(r.next_f64(), r.next_f64());
                    assert!((env.pdf(s.direction) - s.pdf).abs() <= 1e-9 * s.pdf);
                    Some(to_test(mul_transposed(&rot, s.direction)))
                },
                |p| env.pdf(mul(&rot, from_test(p))),
            )
            .unwrap();
    }

    #[test]
    fn constant_sampling_is_uniform() {
        let env = EnvironmentLight::constant(Rgb::splat(3.0), (Vec3::ZERO, 1.0));
        let mut r = Rng::new(2, 2);
        ChiSquareTest::new(Sphere)
            .run(
                || Some(env.sample(r.next_f64(), r.next_f64()).direction),
                |w| env.pdf(w),
            )
            .unwrap();
    }

    #[test]
    fn sampling_weights_integrate_the_radiance() {
        // E[Y(L(ω)) / p(ω)] = ∫ Y(L) dω, within 4 standard errors.
        let (w, h, t) = test_map();
        let env = EnvironmentLight::map((w, h, t), 1.5, rot_x(-20.0), (Vec3::ZERO, 1.0)).unwrap();
        let mut r = Rng::new(9, 9);
        let n = 200_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let s = env.sample(r.next_f64(), r.next_f64());
            let x = s.radiance.luminance() / s.pdf;
            s1 += x;
            s2 += x * x;
        }
        let mean = s1 / n as f64;
        let se = ((s2 / n as f64 - mean * mean) / n as f64).sqrt();
        let exact = env.luminance_integral();
        assert!(
            (mean - exact).abs() < 4.0 * se + 1e-3 * exact,
            "{mean} ± {se} vs {exact}"
        );
        assert!(
            (env.flux_rgb().luminance() - PI * exact).abs() < 1e-9 * exact,
            "flux {:?}",
            env.flux_rgb()
        );
    }

    #[test]
    fn sun_sampling_is_consistent_and_integrates_the_radiance() {
        // A map with a sun of 2° radius (wide enough to be hit by the map's samples too):
        // the returned density is the mixture's, and E[Y(L)/p] = ∫ Y(L) dω, sun included.
        let (w, h, t) = test_map();
        let sun = SunDisk {
            direction: Vec3::new(0.3, 0.8, -0.2),
            half_angle_deg: 2.0,
            radiance_rgb: Rgb([2000.0, 1800.0, 1500.0]),
        };
        let env = EnvironmentLight::map((w, h, t), 1.0, rot_x(10.0), (Vec3::ZERO, 1.0))
            .unwrap()
            .with_sun(&sun)
            .unwrap();
        let mut r = Rng::new(4, 4);
        let n = 200_000;
        let (mut s1, mut s2, mut in_sun) = (0.0, 0.0, 0);
        for _ in 0..n {
            let s = env.sample(r.next_f64(), r.next_f64());
            assert!((env.pdf(s.direction) - s.pdf).abs() <= 1e-9 * s.pdf);
            let x = s.radiance.luminance() / s.pdf;
            s1 += x;
            s2 += x * x;
            if s.direction.dot(sun.direction.try_normalize().unwrap()) >= 2f64.to_radians().cos() {
                in_sun += 1;
            }
        }
        let mean = s1 / n as f64;
        let se = ((s2 / n as f64 - mean * mean) / n as f64).sqrt();
        let exact = env.luminance_integral();
        let sun_part = sun.radiance_rgb.luminance() * sun.solid_angle();
        assert!(sun_part > 0.2 * exact, "the sun matters in this test");
        assert!(
            (mean - exact).abs() < 4.0 * se + 1e-3 * exact,
            "{mean} ± {se} vs {exact}"
        );
        assert!(in_sun > n / 10, "{in_sun}");
        // Without the sun, the same environment's integral is the map's.
        let plain = EnvironmentLight::map(test_map(), 1.0, rot_x(10.0), (Vec3::ZERO, 1.0)).unwrap();
        assert!((exact - plain.luminance_integral() - sun_part).abs() < 1e-9 * exact);
        // Bad suns.
        let mut bad = sun.clone();
        bad.half_angle_deg = 0.0;
        assert!(plain.clone().with_sun(&bad).is_err());
        bad = sun.clone();
        bad.radiance_rgb = Rgb([f64::NAN, 1.0, 1.0]);
        assert!(plain.with_sun(&bad).is_err());
    }
}
