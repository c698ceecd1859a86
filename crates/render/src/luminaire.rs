//! Goniometric luminaires at run time: a compiled [`Emitter::Luminaire`] with its intensity
//! table, frame and emission sampler, as every estimator uses it.
//!
//! A luminaire is a point source (the far-field model of its photometric file) whose intensity
//! depends on direction: towards the world direction ω it radiates
//!
//! ```text
//! I(ω) = multiplier · I_table(frame⁻¹ ω) · tint    (cd per RGB channel, tint of luminance 1)
//! ```
//!
//! with `I_table` the bilinear C-γ table ([`luxest_photometry::Photometry`]). Like an isotropic
//! point it is a delta light: no ray ever hits it, so its direct light is always computed by a
//! connection, `E = I(ω) g(ω) / d² · V` for a sensor of response g, and `L = f I(ω) cos / d² · V`
//! for reflected radiance.
//!
//! **Emission** (light paths). A direction is drawn from the tabulated density p(ω) of
//! [`IntensitySampler`] (cells chosen by their exact flux, uniform in solid angle within a
//! cell) and the path carries the weight
//!
//! ```text
//! Q = multiplier · tint · I_table(ω) / p(ω) / P(luminaire)
//! ```
//!
//! — the same estimator as an isotropic point's `Φ / P(e)` (where I/p = 4πI = Φ). It is
//! unbiased: the expected flux leaving into dω is P(e) · p(ω) dω · Q = multiplier · tint ·
//! I_table(ω) dω, because p > 0 wherever I_table > 0; integrated over the sphere this is
//! multiplier × the table integral, the flux the luminaire emits (`flux_rgb` in the compiled
//! scene). The weight varies only with the bilinear surface within a cell, so it stays close to
//! the table flux.
//!
//! **Area form** (`scene::Opening::Area`): the luminous opening is divided into N cells whose
//! centres are point sources radiating I(ω)/N each (the midpoint rule for an opening whose
//! every point radiates I(ω)/A per unit area). Connections sum over the N sources; a light path
//! or a next-event sample picks one uniformly (probability 1/N) and weighs it with the full
//! I(ω), which has the same expectation.

use crate::compiled::{Emitter, PhotometricTable};
use luxest_io::color::Rgb;
use luxest_io::math::Vec3;
use luxest_photometry::{Frame, IntensitySampler, Orientation, Photometry};
use std::sync::Arc;

/// Rotation taking luxest_photometry's z-up frame into luxest's y-up world, row-major:
/// (x, y, z) ↦ (x, z, −y), so up (0, 0, 1) ↦ (0, 1, 0), nadir ↦ (0, −1, 0) and the C = 90°
/// axis +y ↦ −z (C stays counter-clockwise seen from above).
const Z_UP_TO_Y_UP: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]];

fn apply(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

/// The luminaire-to-world rotation for an authored aim, tilt and rotation in the y-up world:
/// `luxest_photometry::Orientation` applied in the y-up frame (see `scene::Luminaire`).
pub fn frame_in_world(
    aim: Vec3,
    tilt_deg: f64,
    rotation_deg: f64,
) -> Result<[[f64; 3]; 3], String> {
    // Express the aim in the z-up frame (the inverse is the transpose), orient there, map back.
    let a: [f64; 3] = aim.into();
    let aim_z_up = [a[0], -a[2], a[1]];
    let f = Orientation {
        aim: aim_z_up,
        tilt_deg,
        rotation_deg,
    }
    .frame()?;
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| Z_UP_TO_Y_UP[i][k] * f.m[k][j]).sum();
        }
    }
    Ok(m)
}

/// The compiled table of a photometry: the expanded angles and intensities (exactly what
/// [`photometry_from_table`] rebuilds).
pub fn table_from_photometry(source: &str, p: &Photometry) -> PhotometricTable {
    let (c, g) = (p.c_angles_deg(), p.gamma_angles_deg());
    let mut cd = Vec::with_capacity(c.len() * g.len());
    for i in 0..c.len() {
        for j in 0..g.len() {
            cd.push(p.table_cd(i, j));
        }
    }
    PhotometricTable {
        source: source.to_string(),
        c_deg: c.to_vec(),
        gamma_deg: g.to_vec(),
        cd,
        table_flux_lm: p.flux_from_table_lm(),
        file_flux_lm: p.file_flux_lm(),
        input_watts: p.input_watts,
    }
}

/// Rebuilds the photometry of a compiled table. The stored C list ends with the 360° copy of
/// the 0° plane, which `Photometry::from_table` adds back itself, so the rebuilt table is
/// identical value for value.
pub fn photometry_from_table(t: &PhotometricTable) -> Result<Photometry, String> {
    let (nc, ng) = (t.c_deg.len(), t.gamma_deg.len());
    if nc < 2 || ng < 2 || t.cd.len() != nc * ng {
        return Err(format!("photometric table {}: malformed", t.source));
    }
    let rows: Vec<Vec<f64>> = (0..nc - 1)
        .map(|i| t.cd[i * ng..(i + 1) * ng].to_vec())
        .collect();
    Photometry::from_table(&t.source, &t.c_deg[..nc - 1], &t.gamma_deg, &rows)
        .map_err(|e| format!("photometric table {}: {e}", t.source))
}

/// A luminaire ready for sampling and evaluation.
#[derive(Clone, Debug)]
pub struct GoniometricLight {
    pub position: Vec3,
    /// The point sources: the photometric centre (point form) or the opening's cell centres.
    sources: Vec<Vec3>,
    /// 1 / sources.len(): each source's share of the intensity.
    share: f64,
    frame: Frame,
    photometry: Arc<Photometry>,
    sampler: Arc<IntensitySampler>,
    /// multiplier × tint: candela per channel per table candela.
    scale_rgb: Rgb,
}

impl GoniometricLight {
    /// The run-time luminaires of a scene, one entry per emitter (`None` for other emitters);
    /// luminaires sharing a table share its photometry and sampler.
    pub fn for_emitters(
        emitters: &[Emitter],
        tables: &[PhotometricTable],
    ) -> Result<Vec<Option<GoniometricLight>>, String> {
        let mut shared: Vec<Option<(Arc<Photometry>, Arc<IntensitySampler>)>> =
            vec![None; tables.len()];
        emitters
            .iter()
            .map(|e| {
                let Emitter::Luminaire {
                    name,
                    position,
                    frame,
                    photometry,
                    multiplier,
                    color_rgb,
                    opening_points,
                    ..
                } = e
                else {
                    return Ok(None);
                };
                let k = *photometry as usize;
                let table = tables
                    .get(k)
                    .ok_or_else(|| format!("luminaire {name}: no photometric table {k}"))?;
                if shared[k].is_none() {
                    let p = photometry_from_table(table)?;
                    let s = IntensitySampler::new(&p).ok_or_else(|| {
                        format!("photometric table {}: emits no light", table.source)
                    })?;
                    shared[k] = Some((Arc::new(p), Arc::new(s)));
                }
                let (p, s) = shared[k].clone().expect("set above");
                let sources = if opening_points.is_empty() {
                    vec![*position]
                } else {
                    opening_points.clone()
                };
                Ok(Some(GoniometricLight {
                    position: *position,
                    share: 1.0 / sources.len() as f64,
                    sources,
                    frame: Frame { m: *frame },
                    photometry: p,
                    sampler: s,
                    scale_rgb: *color_rgb * *multiplier,
                }))
            })
            .collect()
    }

    /// Intensity (cd per channel) radiated towards the world direction `dir` (any length > 0).
    #[inline]
    pub fn intensity_toward(&self, dir: Vec3) -> Rgb {
        let local = self.frame.to_local(dir.into());
        self.scale_rgb * self.photometry.intensity_dir_cd(local)
    }

    /// The point sources (one for the point form).
    pub fn sources(&self) -> &[Vec3] {
        &self.sources
    }

    /// Intensity (cd per channel) that the point source at `source` radiates towards
    /// `receiver`: its share of the distribution.
    #[inline]
    pub fn source_intensity_toward(&self, source: Vec3, receiver: Vec3) -> Rgb {
        self.intensity_toward(receiver - source) * self.share
    }

    /// A source chosen uniformly by `u` in [0, 1) (all sources are equally likely).
    #[inline]
    pub fn pick_source(&self, u: f64) -> Vec3 {
        let n = self.sources.len();
        self.sources[((u * n as f64) as usize).min(n - 1)]
    }

    /// The source a light sample starts from: the only one for the point form (drawing no
    /// random number), else one chosen uniformly with `rng`.
    #[inline]
    pub fn choose_source(&self, rng: &mut impl crate::sampling::Sampler) -> Vec3 {
        if self.sources.len() > 1 {
            self.pick_source(rng.next_f64())
        } else {
            self.position
        }
    }

    /// An emission direction (world, unit) from two uniform numbers, and the flux weight
    /// I(ω)/p(ω) per channel (lm) before the emitter-choice probability (see the module docs).
    pub fn sample_emission(&self, u1: f64, u2: f64) -> (Vec3, Rgb) {
        let s = self.sampler.sample(u1, u2);
        let dir = Vec3::from(self.frame.to_world(s.dir));
        // A zero density has probability zero (its cell has no flux); NaN cannot arise from a
        // finite table, but would end the path rather than poison the estimate.
        if s.pdf_sr.is_nan() || s.pdf_sr <= 0.0 {
            return (dir, Rgb::BLACK);
        }
        (dir, self.scale_rgb * (s.intensity_cd / s.pdf_sr))
    }

    /// The luminaire's emitted flux (lm per channel): multiplier × tint × the table integral.
    pub fn flux_rgb(&self) -> Rgb {
        self.scale_rgb * self.photometry.flux_from_table_lm()
    }

    /// Bounds for the light BVH: the largest intensity (cd, luminance, all sources together)
    /// towards any direction, and the cosine of the angle γ about the nadir beyond which the
    /// table (bilinear, zero outside its γ range) radiates nothing.
    pub fn intensity_bound(&self) -> (f64, f64) {
        let p = &self.photometry;
        let (cs, gs) = (p.c_angles_deg().len(), p.gamma_angles_deg().len());
        let mut max_cd: f64 = 0.0;
        let mut last_lit = None;
        for j in 0..gs {
            for i in 0..cs {
                let cd = p.table_cd(i, j);
                if cd > 0.0 {
                    max_cd = max_cd.max(cd);
                    last_lit = Some(j);
                }
            }
        }
        let cos_gamma = match last_lit {
            None => 1.0,
            Some(j) => p.gamma_angles_deg()[(j + 1).min(gs - 1)].to_radians().cos(),
        };
        (max_cd * self.scale_rgb.luminance(), cos_gamma)
    }

    /// The world direction of the nadir (γ = 0).
    pub fn nadir(&self) -> Vec3 {
        Vec3::from(apply(&self.frame.m, [0.0, 0.0, -1.0]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use luxest_io::chi2::{ChiSquareTest, Discrete, Sphere};

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-12
    }

    #[test]
    fn default_orientation_hangs_down_with_c90_towards_minus_z() {
        let m = frame_in_world(Vec3::new(0.0, -1.0, 0.0), 0.0, 0.0).unwrap();
        let f = Frame { m };
        let w = |v: [f64; 3]| Vec3::from(f.to_world(v));
        assert!(close(w([0.0, 0.0, -1.0]), Vec3::new(0.0, -1.0, 0.0)));
        assert!(close(w([1.0, 0.0, 0.0]), Vec3::new(1.0, 0.0, 0.0)));
        assert!(close(w([0.0, 1.0, 0.0]), Vec3::new(0.0, 0.0, -1.0)));
        // Aimed sideways along +x: the nadir follows, the luminaire's up stays in the x-y plane.
        let m = frame_in_world(Vec3::new(2.0, 0.0, 0.0), 0.0, 0.0).unwrap();
        let f = Frame { m };
        assert!(close(
            Vec3::from(f.to_world([0.0, 0.0, -1.0])),
            Vec3::new(1.0, 0.0, 0.0)
        ));
        assert!(Vec3::from(f.to_world([0.0, 0.0, 1.0])).z.abs() < 1e-12);
        // Rotation about the vertical turns C = 0 from +x towards C = 90 (−z).
        let m = frame_in_world(Vec3::new(0.0, -1.0, 0.0), 0.0, 90.0).unwrap();
        assert!(close(
            Vec3::from(Frame { m }.to_world([1.0, 0.0, 0.0])),
            Vec3::new(0.0, 0.0, -1.0)
        ));
        assert!(frame_in_world(Vec3::ZERO, 0.0, 0.0).is_err());
    }

    #[test]
    fn compiled_table_rebuilds_the_same_photometry() {
        let g: Vec<f64> = (0..=36).map(|k| k as f64 * 5.0).collect();
        let c = [0.0, 30.0, 90.0, 200.0];
        let rows: Vec<Vec<f64>> = c
            .iter()
            .map(|&cc| g.iter().map(|&gg| 100.0 + cc * 0.1 + gg).collect())
            .collect();
        let p = Photometry::from_table("t.ies", &c, &g, &rows).unwrap();
        let t = table_from_photometry("t.ies", &p);
        let q = photometry_from_table(&t).unwrap();
        assert_eq!(q.c_angles_deg(), p.c_angles_deg());
        assert_eq!(q.gamma_angles_deg(), p.gamma_angles_deg());
        assert_eq!(table_from_photometry("t.ies", &q), t);
    }

    /// A luminaire of a smooth table (no cell without light), aimed off the vertical, tilted and
    /// rotated, with `sources` point sources.
    fn tilted_luminaire(sources: usize) -> GoniometricLight {
        let c: Vec<f64> = (0..12).map(|k| k as f64 * 30.0).collect();
        let g: Vec<f64> = (0..=18).map(|k| k as f64 * 10.0).collect();
        let rows: Vec<Vec<f64>> = c
            .iter()
            .map(|cc| {
                g.iter()
                    .map(|gg| {
                        100.0 + 60.0 * gg.to_radians().cos() * (1.0 + 0.3 * cc.to_radians().cos())
                    })
                    .collect()
            })
            .collect();
        let p = Photometry::from_table("smooth.ies", &c, &g, &rows).unwrap();
        let s = IntensitySampler::new(&p).unwrap();
        let m = frame_in_world(Vec3::new(0.3, -1.0, 0.4), 20.0, 35.0).unwrap();
        GoniometricLight {
            position: Vec3::ZERO,
            sources: (0..sources)
                .map(|k| Vec3::new(k as f64, 0.0, 0.0))
                .collect(),
            share: 1.0 / sources as f64,
            frame: Frame { m },
            photometry: Arc::new(p),
            sampler: Arc::new(s),
            scale_rgb: Rgb::splat(2.0),
        }
    }

    #[test]
    fn intensity_bound_holds_the_peak_and_the_lit_cone() {
        // A downlight lit to γ = 60° (I = 500 cos γ + 10 C/360), dark from 70°: the bound is
        // the table's peak times the scale, the cone about the nadir reaches 70°, and in
        // random directions the intensity stays below the peak and is 0 outside the cone.
        let c: Vec<f64> = (0..12).map(|k| k as f64 * 30.0).collect();
        let g: Vec<f64> = (0..=18).map(|k| k as f64 * 10.0).collect();
        let rows: Vec<Vec<f64>> = c
            .iter()
            .map(|cc| {
                g.iter()
                    .map(|gg| {
                        if *gg <= 60.0 {
                            500.0 * gg.to_radians().cos() + 10.0 * cc / 360.0
                        } else {
                            0.0
                        }
                    })
                    .collect()
            })
            .collect();
        let p = Photometry::from_table("down.ies", &c, &g, &rows).unwrap();
        let s = IntensitySampler::new(&p).unwrap();
        let m = frame_in_world(Vec3::new(0.3, -1.0, 0.4), 20.0, 35.0).unwrap();
        let light = GoniometricLight {
            position: Vec3::ZERO,
            sources: vec![Vec3::ZERO],
            share: 1.0,
            frame: Frame { m },
            photometry: Arc::new(p),
            sampler: Arc::new(s),
            scale_rgb: Rgb::splat(2.0),
        };
        let (phi, cos_gamma) = light.intensity_bound();
        assert!(
            (phi - 2.0 * (500.0 + 10.0 * 330.0 / 360.0)).abs() < 1e-9,
            "{phi}"
        );
        assert!((cos_gamma - 70f64.to_radians().cos()).abs() < 1e-12);
        let nadir = light.nadir();
        let mut r = Rng::new(5, 5);
        let (mut lit, mut dark) = (0, 0);
        for _ in 0..20_000 {
            let w = crate::sampling::uniform_sphere(r.next_f64(), r.next_f64());
            let i = light.intensity_toward(w).luminance();
            assert!(i <= phi * (1.0 + 1e-12), "{i} > {phi}");
            if nadir.dot(w) < cos_gamma {
                assert_eq!(i, 0.0, "lit outside the cone towards {w:?}");
                dark += 1;
            } else if i > 0.0 {
                lit += 1;
            }
        }
        assert!(lit > 1000 && dark > 1000, "{lit} {dark}");
    }

    #[test]
    fn emission_directions_follow_the_sampler_density_in_the_world() {
        // The table's density, carried into the world by the luminaire's frame: a rotation
        // keeps solid angles, so the world density is the local one at to_local(ω).
        let light = tilted_luminaire(1);
        let mut r = Rng::new(21, 0);
        ChiSquareTest::new(Sphere)
            .run(
                || Some(light.sample_emission(r.next_f64(), r.next_f64()).0),
                |w| light.sampler.pdf(light.frame.to_local(w.into())),
            )
            .unwrap();
    }

    #[test]
    fn sources_of_an_opening_are_picked_uniformly() {
        let light = tilted_luminaire(5);
        let mut r = Rng::new(22, 0);
        ChiSquareTest::new(Discrete(5))
            .samples(20_000)
            .run(|| Some(light.pick_source(r.next_f64()).x as usize), |_| 0.2)
            .unwrap();
    }

    #[test]
    fn sensor_responses_match_the_photometry_kernels() {
        // SensorPoint::response against luxest_photometry's independent implementation, for
        // every kind, over directions on the whole sphere.
        use crate::scene::{IlluminanceKind, SensorPoint};
        use luxest_photometry::SensorKind;
        let a = Vec3::new(0.0, 1.0, 0.0);
        let f = Vec3::new(0.6, 0.0, -0.8);
        let n = Vec3::new(0.3, 0.9, -0.1).try_normalize().unwrap();
        let cases = [
            (
                IlluminanceKind::Planar,
                SensorKind::Planar { normal: n.into() },
            ),
            (
                IlluminanceKind::Cylindrical { axis: a },
                SensorKind::Cylindrical { axis: a.into() },
            ),
            (
                IlluminanceKind::SemiCylindrical { axis: a, facing: f },
                SensorKind::SemiCylindrical {
                    axis: a.into(),
                    facing: f.into(),
                },
            ),
        ];
        for (kind, reference) in cases {
            let s = SensorPoint {
                position: Vec3::ZERO,
                normal: n,
                kind,
            };
            for k in 0..200 {
                // A spiral over the sphere.
                let z = 1.0 - (k as f64 + 0.5) / 100.0;
                let phi = k as f64 * 2.399963;
                let r = (1.0 - z * z).sqrt();
                let w = Vec3::new(r * phi.cos(), z, r * phi.sin());
                let ours = s.response(w).max(0.0);
                let theirs = reference.response(w.into());
                assert!(
                    (ours - theirs).abs() < 1e-14,
                    "{kind:?} {w:?}: {ours} vs {theirs}"
                );
            }
        }
    }
}
