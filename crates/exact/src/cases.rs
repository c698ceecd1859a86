//! Analytic validation cases for sensor results (`sobolev:I=100,h1=1,...`): the exact value
//! each sensor point should have, used by `evaluate sensors` (and the validation tests).

use crate::solutions::{self, CosnSobolev, Sobolev};
use luxest_io::math::Vec3;
use luxest_io::num::Real;
use luxest_io::sensors::{SensorResults, SensorValue};
use std::collections::BTreeMap;

/// An analytic case and its parameters, parsed from `name:key=value,...`.
#[derive(Clone, Debug, PartialEq)]
pub enum Case {
    /// Source at the origin, plane 1 at y = −h1 (sensors with y < 0), plane 2 at y = +h2.
    /// With a bin radius, the exact value is the mean over the counting disk (direct
    /// simulation).
    Sobolev(Sobolev, Option<f64>),
    /// A cosⁿ luminaire (I0 cosⁿψ, nadir −y) at the origin between plane 1 at y = −h1
    /// (sensors with y < 0) and plane 2 at y = +h2; `cosn-plane` is the same with both
    /// reflectances 0 (plane 1 alone: the closed-form direct term). With a bin radius, the exact
    /// value is the mean over the counting disk (direct simulation).
    CosnSobolev(CosnSobolev, Option<f64>),
    /// Sphere centred at the origin; every sensor on the wall.
    Sphere {
        intensity_cd: f64,
        radius: f64,
        rho: f64,
        source: Vec3,
    },
    /// Sphere centred at the origin with a cosⁿ luminaire (I0 cosⁿψ, nadir −y) at `source`:
    /// the indirect term depends only on its flux 2π I0/(n + 1). A luminaire from a photometric
    /// table differs from the smooth cosⁿ by the table's interpolation error (for cos² at 2.5°
    /// steps: 0.03 % of the flux, at most 0.05 % of I0 in the direct term).
    CosnSphere {
        i0_cd: f64,
        n: f64,
        radius: f64,
        rho: f64,
        source: Vec3,
    },
    /// Closed room: compares the area-weighted mean indirect illuminance (value minus the
    /// exact direct term) over all sensors, which must tile the room's surfaces in equal cells.
    Cie171Room {
        flux_lm: f64,
        area_m2: f64,
        rho: f64,
        source: Vec3,
    },
}

/// One compared quantity.
#[derive(Clone, Debug)]
pub struct Row {
    pub label: String,
    pub exact: f64,
    pub estimate: f64,
    pub standard_error: f64,
}

impl Row {
    pub fn z(&self) -> f64 {
        (self.estimate - self.exact) / self.standard_error
    }
    pub fn relative_error(&self) -> f64 {
        (self.estimate - self.exact) / self.exact
    }
}

/// The checked parameters of an integrating-sphere case `name`: intensity, radius and
/// reflectance in their domains, and the source position (x, y, z; default the centre) inside.
fn sphere_source(
    name: &str,
    intensity_cd: f64,
    radius: f64,
    rho: f64,
    get: &mut impl FnMut(&str, Option<f64>) -> std::result::Result<f64, String>,
) -> std::result::Result<Vec3, String> {
    solutions::check_integrating_sphere(intensity_cd, radius, rho)
        .map_err(|m| format!("case {name}: {m}"))?;
    let source = Vec3::new(
        get("x", Some(0.0))?,
        get("y", Some(0.0))?,
        get("z", Some(0.0))?,
    );
    inside_sphere(name, source, radius)?;
    Ok(source)
}

/// Rows of the two-plane cases, labelled by the radius r from the axis through the source:
/// `exact(point, r)` at r, or averaged over a counting disk of radius `bin` about it.
fn radial_rows<'a>(
    points: impl Iterator<Item = (&'a str, &'a SensorValue)>,
    bin: Option<f64>,
    exact: impl Fn(&SensorValue, f64) -> f64,
) -> Vec<Row> {
    points
        .map(|(set, p)| {
            let r = (p.position.x * p.position.x + p.position.z * p.position.z).sqrt();
            let exact = match bin {
                None => exact(p, r),
                Some(b) => solutions::disk_average(|x| exact(p, x), r, b),
            };
            Row {
                label: format!("{set} r={r}"),
                exact,
                estimate: p.value,
                standard_error: p.standard_error,
            }
        })
        .collect()
}

/// Rows labelled by the point's position, with the exact value `exact(position)`.
fn point_rows<'a>(
    points: impl Iterator<Item = (&'a str, &'a SensorValue)>,
    exact: impl Fn(Vec3) -> f64,
) -> Vec<Row> {
    points
        .map(|(set, p)| Row {
            label: format!(
                "{set} ({:.3}, {:.3}, {:.3})",
                p.position.x, p.position.y, p.position.z
            ),
            exact: exact(p.position),
            estimate: p.value,
            standard_error: p.standard_error,
        })
        .collect()
}

/// Refuses a source outside the sphere of `radius` centred at the origin (case `name`).
fn inside_sphere(name: &str, source: Vec3, radius: f64) -> std::result::Result<(), String> {
    let what = if name.starts_with("cosn") {
        "luminaire"
    } else {
        "source"
    };
    if source.length() >= radius {
        return Err(format!(
            "case {name}: the {what} ({}, {}, {}) must be inside the sphere of radius {radius}",
            source.x, source.y, source.z
        ));
    }
    Ok(())
}

impl Case {
    pub fn parse(spec: &str) -> std::result::Result<Case, String> {
        let (name, params) = spec.split_once(':').unwrap_or((spec, ""));
        let mut map = BTreeMap::new();
        for kv in params.split(',').filter(|s| !s.is_empty()) {
            let (k, v) = kv
                .split_once('=')
                .ok_or_else(|| format!("expected key=value, got '{kv}'"))?;
            let v: f64 = v
                .trim()
                .parse()
                .map_err(|_| format!("'{v}' is not a number"))?;
            let k = k.trim();
            Real::finite("")
                .check_named(k, v)
                .map_err(|m| format!("case {name}: {m}"))?;
            if map.insert(k.to_string(), v).is_some() {
                return Err(format!(
                    "case {name}: parameter {k} is given twice (each parameter may appear once)"
                ));
            }
        }
        let mut get = |k: &str, default: Option<f64>| {
            map.remove(k)
                .or(default)
                .ok_or_else(|| format!("case {name} needs parameter {k}"))
        };
        let case = match name {
            "sobolev" => {
                let s = Sobolev {
                    intensity_cd: get("I", None)?,
                    h1: get("h1", None)?,
                    h2: get("h2", None)?,
                    rho1: get("rho1", None)?,
                    rho2: get("rho2", None)?,
                };
                s.check().map_err(|m| format!("case sobolev: {m}"))?;
                let bin = map.remove("bin");
                if let Some(b) = bin {
                    solutions::POSITIVE_M
                        .check_named("bin", b)
                        .map_err(|m| format!("case sobolev: {m}"))?;
                }
                Case::Sobolev(s, bin)
            }
            "cosn-sobolev" | "cosn-plane" => {
                let plane = name == "cosn-plane";
                let c = CosnSobolev {
                    i0_cd: get("I0", None)?,
                    n: get("n", None)?,
                    h1: get(if plane { "h" } else { "h1" }, None)?,
                    h2: if plane { 1.0 } else { get("h2", None)? },
                    rho1: if plane { 0.0 } else { get("rho1", None)? },
                    rho2: if plane { 0.0 } else { get("rho2", None)? },
                };
                c.check().map_err(|m| format!("case {name}: {m}"))?;
                let bin = map.remove("bin");
                if let Some(b) = bin {
                    solutions::POSITIVE_M
                        .check_named("bin", b)
                        .map_err(|m| format!("case {name}: {m}"))?;
                }
                Case::CosnSobolev(c, bin)
            }
            "sphere" => {
                let (intensity_cd, radius, rho) =
                    (get("I", None)?, get("R", None)?, get("rho", None)?);
                let source = sphere_source(name, intensity_cd, radius, rho, &mut get)?;
                Case::Sphere {
                    intensity_cd,
                    radius,
                    rho,
                    source,
                }
            }
            "cosn-sphere" => {
                let (i0_cd, n, radius, rho) = (
                    get("I0", None)?,
                    get("n", None)?,
                    get("R", None)?,
                    get("rho", None)?,
                );
                solutions::COSN_EXPONENT
                    .check_named("n", n)
                    .map_err(|m| format!("case cosn-sphere: {m}"))?;
                let source = sphere_source(name, i0_cd, radius, rho, &mut get)?;
                Case::CosnSphere {
                    i0_cd,
                    n,
                    radius,
                    rho,
                    source,
                }
            }
            "cie171-5.8" => {
                let (flux_lm, area_m2, rho) =
                    (get("flux", None)?, get("area", None)?, get("rho", None)?);
                solutions::check_cie171(flux_lm, area_m2, rho)
                    .map_err(|m| format!("case cie171-5.8: {m}"))?;
                Case::Cie171Room {
                    flux_lm,
                    area_m2,
                    rho,
                    source: Vec3::new(get("x", None)?, get("y", None)?, get("z", None)?),
                }
            }
            other => {
                return Err(format!(
                    "unknown case '{other}' (sobolev, cosn-plane, cosn-sobolev, sphere, cosn-sphere, cie171-5.8)"
                ))
            }
        };
        if let Some(k) = map.keys().next() {
            return Err(format!("unknown parameter '{k}' for case {name}"));
        }
        Ok(case)
    }

    /// Refuses results with a point that does not lie on the case's geometry, facing the way
    /// its surface does: results of another scene, compared with the case, gave a max |z| of
    /// 18 373 and, without --max-z, exit 0. Points may lie within 1 % of the case's size off
    /// its surfaces (a scene's sensors sit on its own planes or just inside its sphere).
    /// Returns the first such point's place (`sets["wall"].points[1]`) and the problem.
    pub fn check_geometry(
        &self,
        results: &SensorResults,
    ) -> std::result::Result<(), (String, String)> {
        let show = |v: Vec3| {
            format!(
                "({}, {}, {})",
                luxest_io::num::show(v.x),
                luxest_io::num::show(v.y),
                luxest_io::num::show(v.z)
            )
        };
        for set in &results.sets {
            for (i, p) in set.points.iter().enumerate() {
                let (x, n) = (p.position, p.normal);
                let problem = match self {
                    Case::Sobolev(Sobolev { h1, h2, .. }, _)
                    | Case::CosnSobolev(CosnSobolev { h1, h2, .. }, _) => {
                        let tol = 1e-2 * (h1 + h2);
                        let (plane, y, up) = if x.y < 0.0 {
                            (1, -h1, 1.0)
                        } else {
                            (2, *h2, -1.0)
                        };
                        ((x.y - y).abs() > tol || n.y * up < 0.99).then(|| {
                            format!(
                                "is not on plane {plan} of the case (y = {}, facing {}y)",
                                luxest_io::num::show(y),
                                if up > 0.0 { "+" } else { "-" },
                                plan = plane
                            )
                        })
                    }
                    Case::Sphere { radius, .. } | Case::CosnSphere { radius, .. } => {
                        let r = x.length();
                        let inward = if r > 0.0 { -n.dot(x) / r } else { 0.0 };
                        ((r - radius).abs() > 1e-2 * radius || inward < 0.99).then(|| {
                            format!(
                                "is not on the case's sphere wall (radius {} about the origin, \
                                 facing in)",
                                luxest_io::num::show(*radius)
                            )
                        })
                    }
                    Case::Cie171Room {
                        area_m2, source, ..
                    } => {
                        // The room is a cube of this total area; no point of it is farther
                        // from a source inside than its diagonal.
                        let diagonal = (3.0 * area_m2 / 6.0).sqrt();
                        ((x - *source).length() > diagonal * 1.01).then(|| {
                            format!(
                                "is {} m from the source, farther than the diagonal ({} m) of \
                                 the case's room of {} m²",
                                luxest_io::num::show((x - *source).length()),
                                luxest_io::num::show(diagonal),
                                luxest_io::num::show(*area_m2)
                            )
                        })
                    }
                };
                if let Some(problem) = problem {
                    return Err((
                        format!("sets[\"{}\"].points[{i}]", set.name),
                        format!(
                            "the point {} {problem}: results of another scene? (--scene \
                             S.lxs checks the results' scene hash)",
                            show(x)
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The rows to compare for `results`.
    pub fn rows(&self, results: &SensorResults) -> Vec<Row> {
        let points = results
            .sets
            .iter()
            .flat_map(|s| s.points.iter().map(move |p| (s.name.as_str(), p)));
        match self {
            Case::Sobolev(s, bin) => radial_rows(points, *bin, |p, r| {
                let plane = if p.position.y < 0.0 { *s } else { s.swapped() };
                plane.illuminance1(r).value
            }),
            Case::CosnSobolev(c, bin) => radial_rows(points, *bin, |p, r| {
                if p.position.y < 0.0 {
                    c.illuminance1(r).value
                } else {
                    c.illuminance2(r).value
                }
            }),
            Case::Sphere {
                intensity_cd,
                radius,
                rho,
                source,
            } => point_rows(points, |x| {
                solutions::integrating_sphere_illuminance(*intensity_cd, *radius, *rho, *source, x)
            }),
            Case::CosnSphere {
                i0_cd,
                n,
                radius,
                rho,
                source,
            } => point_rows(points, |x| {
                solutions::integrating_sphere_cosn_illuminance(
                    *i0_cd, *n, *radius, *rho, *source, x,
                )
            }),
            Case::Cie171Room {
                flux_lm,
                area_m2,
                rho,
                source,
            } => {
                let intensity = flux_lm / (4.0 * std::f64::consts::PI);
                let (mut sum, mut var, mut n) = (0.0, 0.0, 0.0);
                for (_, p) in points {
                    sum += p.value
                        - solutions::point_source_illuminance(
                            intensity, *source, p.position, p.normal,
                        );
                    var += p.standard_error * p.standard_error;
                    n += 1.0;
                }
                // Errors of different sensors are positively correlated (shared paths), so the
                // standard error of the mean is bounded by the mean standard error.
                let se = (var / n).sqrt();
                vec![Row {
                    label: format!("mean indirect over {n} sensors"),
                    exact: solutions::cie171_mean_indirect_illuminance(*flux_lm, *area_m2, *rho),
                    estimate: sum / n,
                    standard_error: se,
                }]
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn case_specs_parse_and_reject_mistakes() {
        let c = Case::parse("sobolev:I=100,h1=1,h2=2,rho1=0.5,rho2=0.9").unwrap();
        assert!(matches!(c, Case::Sobolev(s, None) if s.h2 == 2.0 && s.rho2 == 0.9));
        let c = Case::parse("sobolev:I=100,h1=1,h2=2,rho1=0.5,rho2=0.9,bin=0.1").unwrap();
        assert!(matches!(c, Case::Sobolev(_, Some(b)) if b == 0.1));
        assert!(Case::parse("sobolev:I=100,h1=1")
            .unwrap_err()
            .contains("h2"));
        assert!(Case::parse("sphere:I=1,R=1,rho=0.5,w=3")
            .unwrap_err()
            .contains("'w'"));
        assert!(Case::parse("cube").is_err());
        let c = Case::parse("cosn-sobolev:I0=1000,n=2,h1=1,h2=2,rho1=0.5,rho2=0.9").unwrap();
        assert!(matches!(c, Case::CosnSobolev(s, None) if s.n == 2.0 && s.h2 == 2.0));
        let c = Case::parse("cosn-plane:I0=1000,n=3,h=2,bin=0.1").unwrap();
        assert!(
            matches!(c, Case::CosnSobolev(s, Some(b)) if s.h1 == 2.0 && s.rho1 == 0.0 && b == 0.1)
        );
        assert!(Case::parse("cosn-plane:I0=1000,n=3,h=2,rho1=0.5")
            .unwrap_err()
            .contains("'rho1'"));
        assert!(
            Case::parse("cosn-sobolev:I0=1000,n=25,h1=1,h2=2,rho1=0.5,rho2=0.9")
                .unwrap_err()
                .contains("n: must be")
        );
    }

    #[test]
    fn case_parameters_outside_their_domain_are_refused_with_the_range() {
        for (spec, want) in [
            (
                "sphere:I=1,R=0,rho=0.5",
                "radius: must be a finite number > 0 m, got 0",
            ),
            (
                "sphere:I=1,R=1,rho=1",
                "rho: must be a number in [0, 1), got 1",
            ),
            ("sphere:I=1,R=1,rho=0.5,x=2", "must be inside the sphere"),
            (
                "cosn-sphere:I0=1,n=-1,R=1,rho=0.5",
                "n: must be a number in [0, 100]",
            ),
            (
                "cosn-sphere:I0=1,n=2,R=1,rho=0.5,y=-1.5",
                "luminaire (0, -1.5, 0) must be inside",
            ),
            (
                "cie171-5.8:flux=1,area=96,rho=-0.5,x=0,y=0,z=0",
                "rho: must be a number in [0, 1), got -0.5",
            ),
            (
                "cie171-5.8:flux=1,area=96,rho=1,x=0,y=0,z=0",
                "rho: must be a number in [0, 1)",
            ),
            (
                "sobolev:I=100,h1=0,h2=1,rho1=0.5,rho2=0.5",
                "h1: must be a finite number > 0 m",
            ),
            (
                "sobolev:I=100,h1=1,h2=1,rho1=1,rho2=1",
                "rho1 rho2 must be below 1",
            ),
            (
                "sobolev:I=100,h1=1,h2=1,rho1=1.5,rho2=0.5",
                "rho1: must be a number in [0, 1]",
            ),
            (
                "sobolev:I=-5,h1=1,h2=1,rho1=0.5,rho2=0.5",
                "intensity: must be a finite number > 0 cd",
            ),
            (
                "sobolev:I=100,h1=1,h2=1,rho1=0.5,rho2=0.5,bin=0",
                "bin: must be",
            ),
            (
                "sobolev:I=NaN,h1=1,h2=1,rho1=0.5,rho2=0.5",
                "I: must be a finite number, got NaN",
            ),
            (
                "sphere:I=1,R=1,rho=0.5,rho=0.9",
                "parameter rho is given twice",
            ),
        ] {
            let e = Case::parse(spec).unwrap_err();
            assert!(e.contains(want), "{spec}: {e}");
        }
    }

    #[test]
    fn cosn_luminaire_flux_and_illuminance_are_the_integrals_they_claim() {
        // Φ = ∫ I dΩ = 2π ∫₀^{π/2} I0 cosⁿψ sin ψ dψ, by adaptive quadrature.
        for n in [0.0, 1.0, 2.0, 7.5] {
            let (q, _) = crate::quadrature::integrate(
                &mut |psi: f64| 2.0 * std::f64::consts::PI * 1000.0 * psi.cos().powf(n) * psi.sin(),
                0.0,
                std::f64::consts::FRAC_PI_2,
                1e-9,
            );
            let want = solutions::cosn_luminaire_flux(1000.0, n);
            assert!((q - want).abs() < 1e-8 * want, "n = {n}: {q} vs {want}");
        }
        // Straight below at distance 2: I0 / 4; at 45° on the floor 2 m below: I0 cos³45° / 8.
        let s = Vec3::new(0.0, 2.0, 0.0);
        let up = Vec3::new(0.0, 1.0, 0.0);
        let e = solutions::cosn_luminaire_illuminance(1000.0, 2.0, s, Vec3::ZERO, up);
        assert!((e - 250.0).abs() < 1e-12);
        let e = solutions::cosn_luminaire_illuminance(1000.0, 2.0, s, Vec3::new(2.0, 0.0, 0.0), up);
        assert!((e - 1000.0 * 0.5f64.sqrt().powi(3) / 8.0).abs() < 1e-12);
        // Nothing above the luminaire's horizontal plane.
        let down = Vec3::new(0.0, -1.0, 0.0);
        let e =
            solutions::cosn_luminaire_illuminance(1000.0, 2.0, s, Vec3::new(0.0, 3.0, 0.0), down);
        assert_eq!(e, 0.0);
        assert!(matches!(
            Case::parse("cosn-sphere:I0=1000,n=2,R=1,rho=0.5,x=0.1").unwrap(),
            Case::CosnSphere { n, .. } if n == 2.0
        ));
    }
}
