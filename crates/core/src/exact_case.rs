//! Analytic validation cases for sensor results (`sobolev:I=100,h1=1,...`): the exact value
//! each sensor point should have, shared by `estimate compare` and `evaluate sensors`.

use crate::exact::{self, Sobolev};
use crate::math::Vec3;
use crate::sensors::SensorResults;
use std::collections::BTreeMap;

/// An analytic case and its parameters, parsed from `name:key=value,...`.
#[derive(Clone, Debug, PartialEq)]
pub enum Case {
    /// Source at the origin, plane 1 at y = −h1 (sensors with y < 0), plane 2 at y = +h2.
    /// With a bin radius, the exact value is the mean over the counting disk (direct
    /// simulation).
    Sobolev(Sobolev, Option<f64>),
    /// Sphere centred at the origin; every sensor on the wall.
    Sphere {
        intensity_cd: f64,
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
            map.insert(k.trim().to_string(), v);
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
                s.check()?;
                let bin = map.remove("bin");
                Case::Sobolev(s, bin)
            }
            "sphere" => Case::Sphere {
                intensity_cd: get("I", None)?,
                radius: get("R", None)?,
                rho: get("rho", None)?,
                source: Vec3::new(
                    get("x", Some(0.0))?,
                    get("y", Some(0.0))?,
                    get("z", Some(0.0))?,
                ),
            },
            "cie171-5.8" => Case::Cie171Room {
                flux_lm: get("flux", None)?,
                area_m2: get("area", None)?,
                rho: get("rho", None)?,
                source: Vec3::new(get("x", None)?, get("y", None)?, get("z", None)?),
            },
            other => {
                return Err(format!(
                    "unknown case '{other}' (sobolev, sphere, cie171-5.8)"
                ))
            }
        };
        if let Some(k) = map.keys().next() {
            return Err(format!("unknown parameter '{k}' for case {name}"));
        }
        Ok(case)
    }

    /// The rows to compare for `results`.
    pub fn rows(&self, results: &SensorResults) -> Vec<Row> {
        let points = results
            .sets
            .iter()
            .flat_map(|s| s.points.iter().map(move |p| (s.name.as_str(), p)));
        match self {
            Case::Sobolev(s, bin) => points
                .map(|(set, p)| {
                    let r = (p.position.x * p.position.x + p.position.z * p.position.z).sqrt();
                    let plane = if p.position.y < 0.0 { *s } else { s.swapped() };
                    let exact = match bin {
                        None => plane.illuminance1(r).value,
                        Some(b) => exact::disk_average(|x| plane.illuminance1(x).value, r, *b),
                    };
                    Row {
                        label: format!("{set} r={r}"),
                        exact,
                        estimate: p.value,
                        standard_error: p.standard_error,
                    }
                })
                .collect(),
            Case::Sphere {
                intensity_cd,
                radius,
                rho,
                source,
            } => points
                .map(|(set, p)| Row {
                    label: format!(
                        "{set} ({:.3}, {:.3}, {:.3})",
                        p.position.x, p.position.y, p.position.z
                    ),
                    exact: exact::integrating_sphere_illuminance(
                        *intensity_cd,
                        *radius,
                        *rho,
                        *source,
                        p.position,
                    ),
                    estimate: p.value,
                    standard_error: p.standard_error,
                })
                .collect(),
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
                        - exact::point_source_illuminance(intensity, *source, p.position, p.normal);
                    var += p.standard_error * p.standard_error;
                    n += 1.0;
                }
                // Errors of different sensors are positively correlated (shared paths), so the
                // standard error of the mean is bounded by the mean standard error.
                let se = (var / n).sqrt();
                vec![Row {
                    label: format!("mean indirect over {n} sensors"),
                    exact: exact::cie171_mean_indirect_illuminance(*flux_lm, *area_m2, *rho),
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
    }
}
