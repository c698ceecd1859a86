//! Pass / fail of the computed figures against the requirements the scene states: a surface's
//! maintained illuminance Ē_m and uniformity U0 (EN 12464-1), its daylight factor's median and
//! minimum (EN 17037), an observer's UGR against its limit UGR_L. One verdict per figure, which
//! the Markdown and HTML reports print alike.
//!
//! A figure passes when its value reaches the requirement (Ē ≥ Ē_m, U0 ≥ U0 required, DF ≥
//! target; UGR ≤ UGR_L). The verdict is on the estimate; when the margin is smaller than two of
//! its standard errors the check says so (`close`), since another run might decide otherwise.

use luxest_io::requirements::Requirements;
use luxest_io::sensors::GlareResult;
use luxest_photometry::{Estimate, GridStats};

/// Which way a requirement bounds its figure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bound {
    /// The figure must be at least the requirement.
    AtLeast,
    /// The figure must be at most the requirement.
    AtMost,
}

/// One figure checked against its requirement.
#[derive(Clone, Debug, PartialEq)]
pub struct Check {
    /// The figure, e.g. `Ē` or `U0`.
    pub figure: String,
    /// The figure's value and standard error; `None` when it is undefined (U0 without light).
    pub value: Option<Estimate>,
    pub bound: Bound,
    pub required: f64,
    /// Unit of value and requirement (may be empty).
    pub unit: &'static str,
    pub pass: bool,
    /// The margin is within two standard errors.
    pub close: bool,
}

impl Check {
    /// `value` against `required`.
    pub fn new(
        figure: &str,
        value: Option<Estimate>,
        bound: Bound,
        required: f64,
        unit: &'static str,
    ) -> Check {
        let (pass, close) = match value {
            Some(v) => {
                let margin = match bound {
                    Bound::AtLeast => v.value - required,
                    Bound::AtMost => required - v.value,
                };
                (margin >= 0.0, margin.abs() < 2.0 * v.std_error)
            }
            None => (false, false),
        };
        Check {
            figure: figure.to_string(),
            value,
            bound,
            required,
            unit,
            pass,
            close,
        }
    }

    /// `≥ 500 lx`, `≤ 19`.
    pub fn requirement_text(&self) -> String {
        let op = match self.bound {
            Bound::AtLeast => "≥",
            Bound::AtMost => "≤",
        };
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        format!("{op} {}{unit}", self.required)
    }

    /// `PASS`, `FAIL`, with `(within 2 SE)` when close.
    pub fn verdict_text(&self) -> String {
        format!(
            "{}{}",
            if self.pass { "PASS" } else { "FAIL" },
            if self.close { " (within 2 SE)" } else { "" }
        )
    }
}

/// The checks of a surface's illuminance figures against its requirements (none without).
pub fn surface(req: Option<&Requirements>, stats: &GridStats) -> Vec<Check> {
    let Some(req) = req else { return Vec::new() };
    let mut out = Vec::new();
    if let Some(em) = req.em_lux {
        out.push(Check::new("Ē", Some(stats.e_avg), Bound::AtLeast, em, "lx"));
    }
    if let Some(u0) = req.u0 {
        // Without light anywhere U0 is 0/0: undefined, and it fails.
        let value = (stats.e_max.value > 0.0).then_some(stats.u0);
        out.push(Check::new("U0", value, Bound::AtLeast, u0, ""));
    }
    out
}

/// The check of one UGR against its observer's limit, when it has one.
pub fn glare(g: &GlareResult) -> Option<Check> {
    let limit = g.limit?;
    Some(Check::new(
        "UGR",
        Some(Estimate {
            value: g.ugr,
            std_error: g.standard_error,
        }),
        Bound::AtMost,
        limit,
        "",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(value: f64, std_error: f64) -> Estimate {
        Estimate { value, std_error }
    }

    #[test]
    fn verdicts_follow_the_bound_and_flag_close_margins() {
        let c = Check::new("Ē", Some(e(510.0, 2.0)), Bound::AtLeast, 500.0, "lx");
        assert!(c.pass && !c.close);
        assert_eq!(c.requirement_text(), "≥ 500 lx");
        let c = Check::new("Ē", Some(e(499.0, 1.0)), Bound::AtLeast, 500.0, "lx");
        assert!(!c.pass && c.close);
        assert_eq!(c.verdict_text(), "FAIL (within 2 SE)");
        let c = Check::new("UGR", Some(e(19.4, 0.1)), Bound::AtMost, 19.0, "");
        assert!(!c.pass && !c.close);
        let c = Check::new("U0", None, Bound::AtLeast, 0.6, "");
        assert!(!c.pass);
    }
}
