//! The lighting requirements of a task area, as a scene states them for a calculation surface
//! (`CalculationSurface.requirements`, docs/scene-format.md): the maintained illuminance Ē_m and
//! uniformity U0 of EN 12464-1 and the daylight-factor target of EN 17037. `scene-compile` copies
//! them into the compiled scene's sensor set; the `report` stage checks the computed figures
//! against them (pass / fail). One type for the scene, the compiled header and the report.

use serde::{Deserialize, Serialize};

/// What a calculation surface must reach; every requirement is optional.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Requirements {
    /// Maintained illuminance Ē_m required (EN 12464-1), lx: the average must reach it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub em_lux: Option<f64>,
    /// Uniformity U0 = Emin / Ē required (EN 12464-1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u0: Option<f64>,
    /// Daylight factor target (EN 17037).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub daylight_factor: Option<DaylightTarget>,
}

/// An EN 17037 daylight-factor target: the median daylight factor over the surface must reach
/// `median_percent` and, when given, its minimum `min_percent` (%).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DaylightTarget {
    pub median_percent: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_percent: Option<f64>,
}

impl Requirements {
    /// The first requirement that is not a finite positive number (U0 and daylight factors at
    /// most 1 and 100 %), as `(field, message)`; `None` when all are valid.
    pub fn invalid(&self) -> Option<(&'static str, String)> {
        let bad = |v: f64, max: f64| !(v.is_finite() && v > 0.0 && v <= max);
        if let Some(e) = self.em_lux.filter(|&e| bad(e, f64::MAX)) {
            return Some(("em_lux", format!("{e} is not a positive number of lux")));
        }
        if let Some(u) = self.u0.filter(|&u| bad(u, 1.0)) {
            return Some(("u0", format!("{u} is not a uniformity in (0, 1]")));
        }
        if let Some(d) = &self.daylight_factor {
            if bad(d.median_percent, 100.0) {
                return Some((
                    "daylight_factor.median_percent",
                    format!(
                        "{} is not a daylight factor in (0, 100] %",
                        d.median_percent
                    ),
                ));
            }
            if let Some(m) = d.min_percent.filter(|&m| bad(m, 100.0)) {
                return Some((
                    "daylight_factor.min_percent",
                    format!("{m} is not a daylight factor in (0, 100] %"),
                ));
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requirements_are_checked_field_by_field() {
        let ok = Requirements {
            em_lux: Some(500.0),
            u0: Some(0.6),
            daylight_factor: Some(DaylightTarget {
                median_percent: 2.0,
                min_percent: Some(0.7),
            }),
        };
        assert_eq!(ok.invalid(), None);
        let r = Requirements {
            u0: Some(1.5),
            ..ok.clone()
        };
        assert_eq!(r.invalid().unwrap().0, "u0");
        let r = Requirements {
            em_lux: Some(f64::NAN),
            ..ok.clone()
        };
        assert_eq!(r.invalid().unwrap().0, "em_lux");
        let r = Requirements {
            daylight_factor: Some(DaylightTarget {
                median_percent: 2.0,
                min_percent: Some(0.0),
            }),
            ..ok
        };
        assert_eq!(r.invalid().unwrap().0, "daylight_factor.min_percent");
    }
}
