//! `estimate exact`: tables of the exact solutions ([`luxest_exact::solutions`]) for chosen
//! parameters, to check a scene or a result by hand.

use crate::cli::ExactCase;
use luxest_exact::solutions;
use luxest_io::num::{show, Real};
use luxest_io::{Error, Result};

/// A refused parameter is a usage error naming the case: `exact sobolev: rho1 rho2 must be ...`.
fn usage(case: &str) -> impl Fn(String) -> Error + '_ {
    move |m| Error::Usage(format!("estimate exact {case}: {m}"))
}

/// Largest distance from the source's foot in `exact sobolev`, in units of h1 + h2: at 3e4
/// (h = 1 m) the value is already below the quadrature's error bound, and the quadrature's
/// work grows with r (1e5: 25 s; 1e6 and beyond: minutes).
pub const MAX_SOBOLEV_R: f64 = 1e4;

/// Refuses parameters whose solution overflows f64 (`--h1 1e-200`: I/h² is infinite): a usage
/// error rather than a table of inf or NaN.
fn finite(case: &str, values: &[f64]) -> Result<()> {
    match values.iter().find(|v| !v.is_finite()) {
        None => Ok(()),
        Some(v) => Err(usage(case)(format!(
            "the solution for these parameters is {v} in f64 arithmetic; scale the lengths or \
             the power towards 1"
        ))),
    }
}

/// Prints the exact solution of `case` to stdout, after checking its parameters' domain (no
/// NaN, negative or infinite result is printed as if it were one).
pub fn print(case: ExactCase) -> Result<()> {
    let mut lines = Vec::new();
    match case {
        ExactCase::Sobolev {
            intensity,
            h1,
            h2,
            rho1,
            rho2,
            r,
        } => {
            let s = luxest_exact::solutions::Sobolev {
                intensity_cd: intensity,
                h1,
                h2,
                rho1,
                rho2,
            };
            s.check().map_err(usage("sobolev"))?;
            let far = MAX_SOBOLEV_R * (h1 + h2);
            for &r in &r {
                Real::non_negative("m")
                    .check_named("r", r)
                    .map_err(usage("sobolev"))?;
                if r > far {
                    return Err(usage("sobolev")(format!(
                        "r {} m is beyond {} (h1 + h2) = {} m, where the illuminance falls below \
                         the quadrature's error bound (and its work grows with r)",
                        show(r),
                        show(MAX_SOBOLEV_R),
                        show(far)
                    )));
                }
            }
            lines.push(format!("Sobolev problem: I = {intensity} cd, h1 = {h1} m, h2 = {h2} m, rho1 = {rho1}, rho2 = {rho2}"));
            lines.push(format!(
                "flux onto plane 1: {:.9e} lm, onto plane 2: {:.9e} lm",
                s.flux1(),
                s.swapped().flux1()
            ));
            lines.push(format!(
                "{:>10} {:>18} {:>18} {:>18} {:>10}",
                "r (m)", "E1 (lx)", "E1 direct", "E2 (lx)", "err.bound"
            ));
            for r in r {
                let (e1, e2) = (s.illuminance1(r), s.illuminance2(r));
                finite(
                    "sobolev",
                    &[
                        e1.value,
                        e2.value,
                        s.direct1(r),
                        s.flux1(),
                        s.swapped().flux1(),
                        e1.error_bound,
                        e2.error_bound,
                    ],
                )?;
                lines.push(format!(
                    "{:>10} {:>18.10e} {:>18.10e} {:>18.10e} {:>10.1e}",
                    r,
                    e1.value,
                    s.direct1(r),
                    e2.value,
                    e1.error_bound.max(e2.error_bound)
                ));
            }
        }
        ExactCase::Sphere {
            intensity,
            radius,
            rho,
        } => {
            solutions::check_integrating_sphere(intensity, radius, rho).map_err(usage("sphere"))?;
            let ind = luxest_exact::solutions::integrating_sphere_indirect(intensity, radius, rho);
            let direct = intensity / (radius * radius);
            finite("sphere", &[ind, direct, direct + ind])?;
            lines.push(format!("Integrating sphere, central source: I = {intensity} cd, R = {radius} m, rho = {rho}"));
            lines.push(format!("direct {direct:.10e} lx + indirect {ind:.10e} lx = {:.10e} lx everywhere on the wall", direct + ind));
        }
        ExactCase::Cie171 { flux, area, rho } => {
            solutions::check_cie171(flux, area, rho).map_err(usage("cie171"))?;
            let e = luxest_exact::solutions::cie171_mean_indirect_illuminance(flux, area, rho);
            finite("cie171", &[e])?;
            lines.push(format!("CIE 171:2006 5.8: flux {flux} lm, S_T = {area} m², rho = {rho}: mean indirect illuminance {e:.10e} lx"));
        }
    }
    luxest_io::cli::print(&(lines.join("\n") + "\n"))
}
