//! Daylight-factor figures of a calculation surface (EN 17037): with a sky in the results
//! (`SensorResults.sky`), the daylight factor at a point is its illuminance over the sky's
//! unobstructed horizontal illuminance, DF = 100 % · E / E_h; the report gives its median,
//! minimum and mean over the surface and checks them against the surface's
//! `DaylightTarget` (median ≥ `median_percent`, minimum ≥ `min_percent`).
//!
//! Uncertainties: the mean and minimum are Ē and Emin of [`crate::surface::Surface::stats`]
//! (jackknife over batches, or propagated) divided by E_h; the median's standard error is that
//! of the point at the median (the mean of the two middle points' for an even count), an
//! approximation that ignores which point is the median.

use crate::checks::{Bound, Check};
use luxest_io::requirements::DaylightTarget;
use luxest_io::sensors::SkyInfo;
use luxest_io::{Error, Result};
use luxest_photometry::{Estimate, GridStats};
use std::path::Path;

/// A surface's daylight-factor figures, %.
#[derive(Clone, Debug, PartialEq)]
pub struct DaylightFigures {
    pub median: Estimate,
    pub min: Estimate,
    pub mean: Estimate,
    /// The sky's unobstructed horizontal illuminance E_h, lx.
    pub horizontal_lux: f64,
}

/// The reports' sentence about the sky (Markdown and HTML alike): its description, the
/// unobstructed horizontal illuminance E_h, the sun's position when there is a sun, and how the
/// daylight factor follows from E_h.
pub fn sky_sentence(sky: &SkyInfo) -> String {
    let sun = match &sky.sun {
        Some(sun) => format!(
            "; sun at altitude {:.1}°, azimuth {:.1}°",
            sun.altitude_deg, sun.azimuth_deg
        ),
        None => String::new(),
    };
    format!(
        "{}: unobstructed horizontal illuminance E_h = {:.0} lx{sun}. Daylight factor DF = 100 % · \
         E / E_h (EN 17037).",
        sky.description, sky.horizontal_illuminance_lux
    )
}

/// The daylight factors of a surface with figures `stats` under `sky`; `file` names the
/// results in errors (a sky without horizontal illuminance gives no daylight factor).
pub fn figures(file: &Path, stats: &GridStats, sky: &SkyInfo) -> Result<DaylightFigures> {
    let eh = sky.horizontal_illuminance_lux;
    if !(eh.is_finite() && eh > 0.0) {
        return Err(Error::at(
            file,
            "sky",
            format!(
                "horizontal illuminance {eh} lx is not a positive number: no daylight factor \
                 (a sky below the horizon?)"
            ),
        ));
    }
    let pct = |e: Estimate| Estimate {
        value: 100.0 * e.value / eh,
        std_error: 100.0 * e.std_error / eh,
    };
    let mut order: Vec<usize> = (0..stats.values.len()).collect();
    order.sort_by(|&a, &b| stats.values[a].total_cmp(&stats.values[b]));
    let n = order.len();
    let middle: &[usize] = if n % 2 == 1 {
        &order[n / 2..n / 2 + 1]
    } else {
        &order[n / 2 - 1..n / 2 + 1]
    };
    let m = middle.len() as f64;
    let median = Estimate {
        value: middle.iter().map(|&k| stats.values[k]).sum::<f64>() / m,
        std_error: middle
            .iter()
            .map(|&k| stats.point_std_errors[k])
            .sum::<f64>()
            / m,
    };
    Ok(DaylightFigures {
        median: pct(median),
        min: pct(stats.e_min),
        mean: pct(stats.e_avg),
        horizontal_lux: eh,
    })
}

/// The checks of the figures against an EN 17037 target.
pub fn checks(target: &DaylightTarget, f: &DaylightFigures) -> Vec<Check> {
    let mut out = vec![Check::new(
        "DF median",
        Some(f.median),
        Bound::AtLeast,
        target.median_percent,
        "%",
    )];
    if let Some(min) = target.min_percent {
        out.push(Check::new("DF min", Some(f.min), Bound::AtLeast, min, "%"));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Five points 100 … 500 lx under a 10 000 lx sky: DF median 3 %, min 1 %, mean 3 %.
    #[test]
    fn daylight_factor_is_illuminance_over_the_sky_s_horizontal_illuminance() {
        let values = [300.0, 100.0, 500.0, 200.0, 400.0];
        let se = [1.0, 2.0, 3.0, 4.0, 5.0];
        let stats = GridStats::from_independent(&values, &se).unwrap();
        let sky = SkyInfo {
            description: "CIE overcast sky".into(),
            horizontal_illuminance_lux: 10_000.0,
            sky_horizontal_illuminance_lux: 10_000.0,
            sun: None,
        };
        let f = figures(Path::new("r"), &stats, &sky).unwrap();
        assert!((f.median.value - 3.0).abs() < 1e-12);
        // The median point is the first (300 lx, SE 1 lx): 0.01 %.
        assert!((f.median.std_error - 0.01).abs() < 1e-12);
        assert!((f.min.value - 1.0).abs() < 1e-12);
        assert!((f.mean.value - 3.0).abs() < 1e-12);
        let target = DaylightTarget {
            median_percent: 2.0,
            min_percent: Some(1.5),
        };
        let c = checks(&target, &f);
        assert!(c[0].pass && !c[1].pass);
        let dark = SkyInfo {
            horizontal_illuminance_lux: 0.0,
            ..sky
        };
        let e = figures(Path::new("r"), &stats, &dark).unwrap_err();
        assert!(e.to_string().contains("not a positive number"), "{e}");
    }
}
