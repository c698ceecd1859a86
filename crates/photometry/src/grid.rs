//! Calculation surfaces (EN 12464-1:2021 §4.4 and Annex, EN 12464-2, as DIALux lays them out) and
//! the figures a lighting engineer reports for them, with their Monte Carlo uncertainties.
//!
//! **Grid.** A rectangle (corner `origin`, edges `edge_u`, `edge_v`; normal n = û × v̂) moved by
//! `offset_m` along n (a work plane 0.75 m above the floor rectangle), shrunk by `margin_m` on
//! every side (EN 12464-1: a border of 0.5 m from the walls is excluded from work planes unless a
//! task lies there). On the remaining calculation area of sides L_u, L_v the standard's maximum
//! cell size is (EN 12464-1:2011 §4.4, kept in the 2021 edition)
//!
//! ```text
//! p = 0.2 · 5^(log10 d)  m,  capped at 10 m,
//! ```
//!
//! with d the longer side, or the shorter side when the longer is at least twice it (a corridor
//! gets cells sized for its width).
//!
//! the number of points per side n = ⌈L / p⌉ (at least 1), the actual spacing L / n ≤ p, and the
//! points sit at the cell centres: origin + (i + ½) L_u/n_u û + (j + ½) L_v/n_v v̂. A spacing can
//! instead be given in metres or as point counts. Points are numbered k = j · n_u + i.
//!
//! **Figures.** Eavg = mean of the point values, Emin, Emax, U0 = Emin/Eavg, Ud = Emin/Emax
//! (EN 12464-1 §4.4; CIE S 017 17-21-068). Their standard errors, two ways:
//!
//! - [`GridStats::from_batches`] (preferred). The estimators compute every point's value as the
//!   mean of B independent batches; `batches[b][k]` is batch b's estimate at point k. Points that
//!   share light paths within a batch are correlated, but the batches are independent, so the
//!   delete-one-batch jackknife (Efron & Stein 1981; Efron & Tibshirani, *An Introduction to the
//!   Bootstrap*, §11) over the whole statistic captures the correlation:
//!   θ₍b₎ = θ(point means without batch b), SE = √((B−1)/B · Σ_b (θ₍b₎ − θ̄)²). For the linear
//!   Eavg this equals the batch-means SE exactly; for the smooth ratios U0, Ud it is the delta
//!   method with the batch covariance. Emin and Emax are not smooth where two points tie for the
//!   minimum: there the jackknife SE and the value itself (a minimum of noisy means is biased
//!   low) are only approximate, which a report should say when the two smallest points lie within
//!   a few standard errors of each other ([`GridStats::min_is_ambiguous`]).
//! - [`GridStats::from_independent`]: per-point values and standard errors σ_k, assuming the
//!   points independent: SE(Eavg) = √(Σσ_k²)/n; SE(Emin) = σ_kmin (the argmin's), likewise Emax;
//!   U0 by the delta method with Cov(E_kmin, Eavg) = σ_kmin²/n:
//!   Var(U0) ≈ U0² (σ_min²/Emin² + SE(Eavg)²/Eavg² − 2σ_min²/(n Emin Eavg)); Ud likewise with
//!   the two points independent. Underestimates the uncertainty when points are positively
//!   correlated (light paths shared between points, as in the local estimate).

use crate::frame::{cross, dot, norm, scale};
use std::fmt;

/// A grid that cannot be laid out, or statistics that cannot be computed.
#[derive(Debug, Clone, PartialEq)]
pub struct GridError(pub String);

impl fmt::Display for GridError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for GridError {}

/// How the points are spaced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Spacing {
    /// EN 12464-1: p = 0.2 · 5^(log10 d) m, capped at 10 m.
    Standard,
    /// A maximum spacing p in metres (n = ⌈L/p⌉ per side).
    Given(f64),
    /// Explicit point counts along u and v.
    Counts(usize, usize),
}

/// A calculation surface as the scene describes it (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridSpec {
    pub origin: [f64; 3],
    pub edge_u: [f64; 3],
    pub edge_v: [f64; 3],
    /// Offset along the normal û × v̂ (m), e.g. the work-plane height above the floor rectangle.
    pub offset_m: f64,
    /// Border excluded on every side (m).
    pub margin_m: f64,
    pub spacing: Spacing,
}

impl GridSpec {
    /// A horizontal work plane over the floor rectangle [x0, x1] × [y0, y1] at `height_m`, facing
    /// up, with the standard spacing.
    pub fn work_plane(
        x0: f64,
        y0: f64,
        x1: f64,
        y1: f64,
        height_m: f64,
        margin_m: f64,
    ) -> GridSpec {
        GridSpec {
            origin: [x0, y0, 0.0],
            edge_u: [x1 - x0, 0.0, 0.0],
            edge_v: [0.0, y1 - y0, 0.0],
            offset_m: height_m,
            margin_m,
            spacing: Spacing::Standard,
        }
    }
}

/// The standard's maximum grid spacing (m) for a calculation area whose longer side is `d_m`.
pub fn standard_spacing_m(d_m: f64) -> f64 {
    // EN 12464-1:2021, 4.4 / Annex: p = 0.2 × 5^(log10 d), p ≤ 10 m.
    (0.2 * 5f64.powf(d_m.log10())).min(10.0)
}

/// Points per side for a side of `len_m` at maximum spacing `p_m`: ⌈L/p⌉, at least 1. A ratio
/// within 1e-9 of an integer counts as that integer, so 5 m at 1 m spacing gives 5 points.
pub fn points_per_side(len_m: f64, p_m: f64) -> usize {
    let r = len_m / p_m;
    ((r - 1e-9).ceil().max(1.0)) as usize
}

/// A laid-out calculation grid.
#[derive(Debug, Clone, PartialEq)]
pub struct CalcGrid {
    pub spec: GridSpec,
    /// Unit normal û × v̂.
    pub normal: [f64; 3],
    pub u_dir: [f64; 3],
    pub v_dir: [f64; 3],
    /// Sides of the whole rectangle and of the calculation area (m).
    pub len_u: f64,
    pub len_v: f64,
    pub area_u: f64,
    pub area_v: f64,
    pub nu: usize,
    pub nv: usize,
}

impl CalcGrid {
    pub fn new(spec: GridSpec) -> Result<CalcGrid, GridError> {
        let (lu, lv) = (norm(spec.edge_u), norm(spec.edge_v));
        let finite = spec
            .origin
            .iter()
            .chain(&spec.edge_u)
            .chain(&spec.edge_v)
            .all(|x| x.is_finite())
            && spec.offset_m.is_finite()
            && spec.margin_m.is_finite();
        if !finite || lu <= 0.0 || lv <= 0.0 {
            return Err(GridError(
                "grid: the rectangle's corner and edges must be finite and non-zero".into(),
            ));
        }
        let (u, v) = (scale(spec.edge_u, 1.0 / lu), scale(spec.edge_v, 1.0 / lv));
        if dot(u, v).abs() > 1e-6 {
            return Err(GridError(format!(
                "grid: the edges must be perpendicular (cos = {:.3})",
                dot(u, v)
            )));
        }
        if spec.margin_m < 0.0 || 2.0 * spec.margin_m >= lu.min(lv) {
            return Err(GridError(format!(
                "grid: margin {} m leaves no calculation area in a {lu} m x {lv} m rectangle",
                spec.margin_m
            )));
        }
        let (au, av) = (lu - 2.0 * spec.margin_m, lv - 2.0 * spec.margin_m);
        let (nu, nv) = match spec.spacing {
            Spacing::Standard => {
                let (long, short) = (au.max(av), au.min(av));
                let p = standard_spacing_m(if long >= 2.0 * short { short } else { long });
                (points_per_side(au, p), points_per_side(av, p))
            }
            Spacing::Given(p) if p > 0.0 && p.is_finite() => {
                (points_per_side(au, p), points_per_side(av, p))
            }
            Spacing::Counts(a, b) if a >= 1 && b >= 1 => (a, b),
            _ => {
                return Err(GridError(
                    "grid: spacing must be positive (metres) or at least 1 x 1 points".into(),
                ))
            }
        };
        if nu.saturating_mul(nv) > 10_000_000 {
            return Err(GridError(format!("grid: {nu} x {nv} points is too many")));
        }
        Ok(CalcGrid {
            spec,
            normal: cross(u, v),
            u_dir: u,
            v_dir: v,
            len_u: lu,
            len_v: lv,
            area_u: au,
            area_v: av,
            nu,
            nv,
        })
    }

    pub fn len(&self) -> usize {
        self.nu * self.nv
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Position of point (i, j) in the rectangle's own coordinates (s along u, t along v, m,
    /// from the rectangle's corner, margin included).
    pub fn local(&self, i: usize, j: usize) -> (f64, f64) {
        let m = self.spec.margin_m;
        (
            m + (i as f64 + 0.5) * self.area_u / self.nu as f64,
            m + (j as f64 + 0.5) * self.area_v / self.nv as f64,
        )
    }
    /// World position of point (i, j).
    pub fn point(&self, i: usize, j: usize) -> [f64; 3] {
        let (s, t) = self.local(i, j);
        let o = self.spec.origin;
        let h = self.spec.offset_m;
        [0, 1, 2].map(|k| o[k] + s * self.u_dir[k] + t * self.v_dir[k] + h * self.normal[k])
    }
    /// All points, k = j · n_u + i.
    pub fn points(&self) -> Vec<[f64; 3]> {
        (0..self.nv)
            .flat_map(|j| (0..self.nu).map(move |i| (i, j)))
            .map(|(i, j)| self.point(i, j))
            .collect()
    }
}

/// A value with its standard error (same unit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    pub value: f64,
    pub std_error: f64,
}

impl fmt::Display for Estimate {
    /// `value ± standard error`, with the precision the caller asks for (`{:.1}`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match f.precision() {
            Some(p) => write!(f, "{:.*} ± {:.*}", p, self.value, p, self.std_error),
            None => write!(f, "{} ± {}", self.value, self.std_error),
        }
    }
}

impl Estimate {
    /// Relative standard error (0 when the value is 0).
    pub fn rel_error(&self) -> f64 {
        if self.value == 0.0 {
            0.0
        } else {
            (self.std_error / self.value).abs()
        }
    }
}

/// Grid figures with their standard errors (see the module docs for the methods).
#[derive(Debug, Clone, PartialEq)]
pub struct GridStats {
    pub n_points: usize,
    pub e_avg: Estimate,
    pub e_min: Estimate,
    pub e_max: Estimate,
    pub u0: Estimate,
    pub ud: Estimate,
    /// Index of the minimum and maximum point.
    pub argmin: usize,
    pub argmax: usize,
    /// The point values the figures were computed from (batch means for `from_batches`).
    pub values: Vec<f64>,
    /// Per-point standard errors.
    pub point_std_errors: Vec<f64>,
}

struct Figures {
    avg: f64,
    min: f64,
    max: f64,
    kmin: usize,
    kmax: usize,
}

fn figures(v: &[f64]) -> Figures {
    let mut f = Figures {
        avg: 0.0,
        min: f64::INFINITY,
        max: f64::NEG_INFINITY,
        kmin: 0,
        kmax: 0,
    };
    for (k, &x) in v.iter().enumerate() {
        f.avg += x;
        if x < f.min {
            f.min = x;
            f.kmin = k;
        }
        if x > f.max {
            f.max = x;
            f.kmax = k;
        }
    }
    f.avg /= v.len() as f64;
    f
}

fn ratio(a: f64, b: f64) -> f64 {
    if b == 0.0 {
        0.0
    } else {
        a / b
    }
}

impl GridStats {
    /// Figures from per-point values and standard errors, the points assumed independent.
    pub fn from_independent(values: &[f64], std_errors: &[f64]) -> Result<GridStats, GridError> {
        let n = values.len();
        if n == 0 || std_errors.len() != n {
            return Err(GridError(format!(
                "grid statistics: {} values and {} standard errors",
                n,
                std_errors.len()
            )));
        }
        if values.iter().chain(std_errors).any(|x| !x.is_finite()) {
            return Err(GridError(
                "grid statistics: non-finite point value or standard error".into(),
            ));
        }
        let f = figures(values);
        let nf = n as f64;
        let var_avg = std_errors.iter().map(|s| s * s).sum::<f64>() / (nf * nf);
        let (smin, smax) = (std_errors[f.kmin], std_errors[f.kmax]);
        let u0 = ratio(f.min, f.avg);
        let ud = ratio(f.min, f.max);
        let var_u0 = if f.min > 0.0 && f.avg > 0.0 {
            u0 * u0
                * (smin * smin / (f.min * f.min) + var_avg / (f.avg * f.avg)
                    - 2.0 * smin * smin / (nf * f.min * f.avg))
        } else {
            0.0
        };
        let var_ud = if f.kmin == f.kmax || f.min <= 0.0 {
            0.0
        } else {
            ud * ud * (smin * smin / (f.min * f.min) + smax * smax / (f.max * f.max))
        };
        Ok(GridStats {
            n_points: n,
            e_avg: Estimate {
                value: f.avg,
                std_error: var_avg.sqrt(),
            },
            e_min: Estimate {
                value: f.min,
                std_error: smin,
            },
            e_max: Estimate {
                value: f.max,
                std_error: smax,
            },
            u0: Estimate {
                value: u0,
                std_error: var_u0.max(0.0).sqrt(),
            },
            ud: Estimate {
                value: ud,
                std_error: var_ud.max(0.0).sqrt(),
            },
            argmin: f.kmin,
            argmax: f.kmax,
            values: values.to_vec(),
            point_std_errors: std_errors.to_vec(),
        })
    }

    /// Figures from B ≥ 2 independent batch estimates per point (`batches[b][k]`), standard
    /// errors by the delete-one-batch jackknife over each figure (see the module docs).
    pub fn from_batches(batches: &[Vec<f64>]) -> Result<GridStats, GridError> {
        let nb = batches.len();
        if nb < 2 {
            return Err(GridError(format!(
                "grid statistics: need at least 2 batches, got {nb}"
            )));
        }
        let n = batches[0].len();
        if n == 0 || batches.iter().any(|b| b.len() != n) {
            return Err(GridError(
                "grid statistics: every batch must hold the same, non-zero number of points".into(),
            ));
        }
        if batches.iter().flatten().any(|x| !x.is_finite()) {
            return Err(GridError("grid statistics: non-finite batch value".into()));
        }
        let bf = nb as f64;
        let mut mean = vec![0.0; n];
        for b in batches {
            for (m, x) in mean.iter_mut().zip(b) {
                *m += x;
            }
        }
        mean.iter_mut().for_each(|m| *m /= bf);
        let mut point_se = vec![0.0; n];
        for b in batches {
            for ((s, x), m) in point_se.iter_mut().zip(b).zip(&mean) {
                *s += (x - m) * (x - m);
            }
        }
        point_se
            .iter_mut()
            .for_each(|s| *s = (*s / ((bf - 1.0) * bf)).sqrt());

        let f = figures(&mean);
        // Jackknife replicates of each figure.
        let mut reps: Vec<[f64; 5]> = Vec::with_capacity(nb);
        let mut loo = vec![0.0; n];
        for b in batches {
            for ((l, m), x) in loo.iter_mut().zip(&mean).zip(b) {
                *l = (bf * m - x) / (bf - 1.0);
            }
            let g = figures(&loo);
            reps.push([
                g.avg,
                g.min,
                g.max,
                ratio(g.min, g.avg),
                ratio(g.min, g.max),
            ]);
        }
        let se = |k: usize| {
            let m = reps.iter().map(|r| r[k]).sum::<f64>() / bf;
            ((bf - 1.0) / bf * reps.iter().map(|r| (r[k] - m) * (r[k] - m)).sum::<f64>()).sqrt()
        };
        Ok(GridStats {
            n_points: n,
            e_avg: Estimate {
                value: f.avg,
                std_error: se(0),
            },
            e_min: Estimate {
                value: f.min,
                std_error: se(1),
            },
            e_max: Estimate {
                value: f.max,
                std_error: se(2),
            },
            u0: Estimate {
                value: ratio(f.min, f.avg),
                std_error: se(3),
            },
            ud: Estimate {
                value: ratio(f.min, f.max),
                std_error: se(4),
            },
            argmin: f.kmin,
            argmax: f.kmax,
            values: mean,
            point_std_errors: point_se,
        })
    }

    /// True when another point lies within `z` combined standard errors of the minimum, so that
    /// Emin, U0 and Ud (and their standard errors) are only approximate (see the module docs).
    pub fn min_is_ambiguous(&self, z: f64) -> bool {
        let (m, s) = (self.values[self.argmin], self.point_std_errors[self.argmin]);
        self.values
            .iter()
            .zip(&self.point_std_errors)
            .enumerate()
            .any(|(k, (&v, &sk))| k != self.argmin && v - m <= z * (s * s + sk * sk).sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_rule_numbers() {
        // d = 1 m: p = 0.2; 10 m: 0.2·5 = 1; 100 m: 0.2·25 = 5; 1000 m: 25 → capped at 10.
        assert!((standard_spacing_m(1.0) - 0.2).abs() < 1e-15);
        assert!((standard_spacing_m(10.0) - 1.0).abs() < 1e-15);
        assert!((standard_spacing_m(100.0) - 5.0).abs() < 1e-12);
        assert_eq!(standard_spacing_m(1000.0), 10.0);
        assert_eq!(points_per_side(5.0, 1.0), 5);
        assert_eq!(points_per_side(5.01, 1.0), 6);
        assert_eq!(points_per_side(0.1, 1.0), 1);
    }

    #[test]
    fn office_work_plane_layout() {
        // 6 m x 4 m room, 0.5 m margin: area 5 x 3 m, d = 5, p = 0.2·5^0.69897 = 0.61598 m,
        // n_u = ⌈8.117⌉ = 9, n_v = ⌈4.870⌉ = 5.
        let g = CalcGrid::new(GridSpec::work_plane(0.0, 0.0, 6.0, 4.0, 0.75, 0.5)).unwrap();
        assert_eq!((g.nu, g.nv), (9, 5));
        assert_eq!(g.normal, [0.0, 0.0, 1.0]);
        let p0 = g.point(0, 0);
        assert!((p0[0] - (0.5 + 5.0 / 18.0)).abs() < 1e-12);
        assert!((p0[1] - (0.5 + 0.3)).abs() < 1e-12);
        assert!((p0[2] - 0.75).abs() < 1e-12);
        let pl = g.points();
        assert_eq!(pl.len(), 45);
        assert_eq!(pl[9], g.point(0, 1));
        let last = pl[44];
        assert!((last[0] - (5.5 - 5.0 / 18.0)).abs() < 1e-12 && (last[1] - 3.2).abs() < 1e-12);
        assert!(CalcGrid::new(GridSpec::work_plane(0.0, 0.0, 1.0, 1.0, 0.75, 0.5)).is_err());
        // A 10 m x 2 m corridor (ratio 5 ≥ 2): d = 2, p = 0.2·5^0.30103 = 0.32472 m,
        // n = ⌈30.80⌉ = 31 by ⌈6.16⌉ = 7.
        let g = CalcGrid::new(GridSpec::work_plane(0.0, 0.0, 10.0, 2.0, 0.0, 0.0)).unwrap();
        assert_eq!((g.nu, g.nv), (31, 7));
    }

    #[test]
    fn independent_figures_by_hand() {
        let v = [2.0, 4.0, 6.0, 8.0];
        let s = [0.1, 0.2, 0.3, 0.4];
        let st = GridStats::from_independent(&v, &s).unwrap();
        assert_eq!(st.e_avg.value, 5.0);
        assert_eq!(format!("{:.2}", st.e_min), "2.00 ± 0.10");
        assert!((st.e_avg.std_error - (0.01f64 + 0.04 + 0.09 + 0.16).sqrt() / 4.0).abs() < 1e-15);
        assert_eq!((st.e_min.value, st.e_min.std_error), (2.0, 0.1));
        assert_eq!((st.e_max.value, st.e_max.std_error), (8.0, 0.4));
        assert_eq!(st.u0.value, 0.4);
        let var_u0: f64 = 0.16 * (0.01 / 4.0 + 0.01875 / 25.0 - 2.0 * 0.01 / (4.0 * 2.0 * 5.0));
        assert!((st.u0.std_error - var_u0.sqrt()).abs() < 1e-14);
        assert_eq!(st.ud.value, 0.25);
        assert!((st.ud.std_error - (0.0625f64 * (0.01 / 4.0 + 0.16 / 64.0)).sqrt()).abs() < 1e-15);
    }
}
