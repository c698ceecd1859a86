//! A test utility: the chi-square goodness-of-fit test of a sampling routine against the density
//! it claims, as Mitsuba 3 tests its samplers (`ChiSquareTest(domain=..., sample_func=...,
//! pdf_func=...)`). Every sampling test of the workspace calls it; no stage does, so the linker
//! leaves it out of every binary.
//!
//! A [`Domain`] is a 2-D parameterisation of where the samples live in which the measure is
//! `dx dy`: the sphere and the hemisphere in (cos θ, φ) (`dω = dcos θ dφ`), a rectangle, or a
//! finite set of outcomes. The test draws samples, histograms their parameters into bins,
//! integrates the pdf over each bin numerically (the midpoint rule on `k × k` sub-cells) for the
//! expected counts, pools the bins whose expected count is below 5 (smallest first, as Mitsuba
//! does), and computes Pearson's statistic `X² = Σ (O − E)² / E` with `cells − 1` degrees of
//! freedom. Its p-value is `Q(dof / 2, X² / 2)`, the regularized upper incomplete gamma
//! function (Press et al., *Numerical Recipes*, 3rd ed., §6.2: series and continued fraction).
//!
//! Samples the routine rejects (it returns `None`, as a BSDF does for a direction below the
//! surface) form one more outcome, with expected count `N (1 − ∫ pdf)`: the pdf integrates to
//! the probability that a sample is accepted. (That outcome is left out where the sampler
//! rejects none and the pdf integrates to one within [`INTEGRAL_TOLERANCE`], the midpoint
//! rule's error; a pdf integrating to more than one by more than that fails outright.)
//!
//! The hypothesis "the samples follow the pdf" is rejected at the significance [`SIGNIFICANCE`]
//! corrected for the number `n` of tests run together (Šidák: each test at
//! `α₁ = 1 − (1 − α)^(1/n)`), so that a family of tests falsely fails with probability `α`. A
//! sample outside the domain, a negative or non-finite pdf value, or a sample in a bin where the
//! pdf integrates to zero fails outright.
//!
//! A test is one call (`luxest_render::sampling`'s test of Malley's method):
//!
//! ```ignore
//! let mut r = Rng::new(3, 0);
//! ChiSquareTest::new(Hemisphere)
//!     .run(|| Some(cosine_hemisphere(r.next_f64(), r.next_f64())), |w| w.z / PI)
//!     .unwrap();
//! ```
//!
//! `tests(n)` counts it among the `n` tests a loop runs; `samples`, `resolution`, `edges` and
//! `integration` size it (100 000 samples by default: tens of milliseconds). The account of every
//! test goes to stderr (`cargo test -- --nocapture` shows it), and is the panic message of a
//! failing one.

use crate::math::Vec3;
use std::f64::consts::PI;
use std::fmt;

/// The probability with which a family of chi-square tests fails although every sampler is
/// right: 1 %, Mitsuba's default.
pub const SIGNIFICANCE: f64 = 0.01;

/// How far the pdf's integral over the domain may stray from one (above) or from the fraction of
/// samples accepted (below, where the sampler rejects none) by the error of the midpoint rule: a
/// pdf with a step across bins (the edge of a camera's image) errs by 3e-4 on this workspace's
/// tests, a smooth one by far less.
pub const INTEGRAL_TOLERANCE: f64 = 1e-3;

/// Where samples live: a 2-D parameterisation in which the measure is `dx dy`.
pub trait Domain {
    /// A sample point.
    type Point;
    /// The parameter rectangle `[[x0, x1], [y0, y1]]`.
    fn bounds(&self) -> [[f64; 2]; 2];
    /// The number of bins along x and y when the test names none.
    fn resolution(&self) -> [usize; 2];
    /// The parameters of `p`; `None` when `p` is not a point of the domain.
    fn params(&self, p: &Self::Point) -> Option<[f64; 2]>;
    /// The point with parameters `q` (within the bounds).
    fn point(&self, q: [f64; 2]) -> Self::Point;
}

/// Unit vectors, parameterised by (cos θ, φ) about +z, φ in [0, 2π) from +x towards +y.
#[derive(Clone, Copy, Debug)]
pub struct Sphere;

/// Unit vectors with z ≥ 0, parameterised as on the [`Sphere`].
#[derive(Clone, Copy, Debug)]
pub struct Hemisphere;

/// Points `[x, y]` of a rectangle.
#[derive(Clone, Copy, Debug)]
pub struct Rectangle {
    pub x: [f64; 2],
    pub y: [f64; 2],
}

impl Rectangle {
    /// The unit square [0, 1]².
    pub const UNIT: Rectangle = Rectangle {
        x: [0.0, 1.0],
        y: [0.0, 1.0],
    };
}

/// The outcomes `0..n` of a discrete choice; the "pdf" is the probability of each outcome.
#[derive(Clone, Copy, Debug)]
pub struct Discrete(pub usize);

/// A unit vector's (cos θ, φ); `None` if it is not of unit length.
fn spherical_params(p: &Vec3) -> Option<[f64; 2]> {
    // False for NaN too.
    let unit = (p.length() - 1.0).abs() < 1e-6;
    unit.then(|| [p.z.clamp(-1.0, 1.0), p.y.atan2(p.x).rem_euclid(2.0 * PI)])
}

fn spherical_point(q: [f64; 2]) -> Vec3 {
    let r = (1.0 - q[0] * q[0]).max(0.0).sqrt();
    Vec3::new(r * q[1].cos(), r * q[1].sin(), q[0])
}

impl Domain for Sphere {
    type Point = Vec3;
    fn bounds(&self) -> [[f64; 2]; 2] {
        [[-1.0, 1.0], [0.0, 2.0 * PI]]
    }
    fn resolution(&self) -> [usize; 2] {
        [16, 32]
    }
    fn params(&self, p: &Vec3) -> Option<[f64; 2]> {
        spherical_params(p)
    }
    fn point(&self, q: [f64; 2]) -> Vec3 {
        spherical_point(q)
    }
}

impl Domain for Hemisphere {
    type Point = Vec3;
    fn bounds(&self) -> [[f64; 2]; 2] {
        [[0.0, 1.0], [0.0, 2.0 * PI]]
    }
    fn resolution(&self) -> [usize; 2] {
        [8, 32]
    }
    fn params(&self, p: &Vec3) -> Option<[f64; 2]> {
        spherical_params(p).filter(|q| q[0] >= 0.0)
    }
    fn point(&self, q: [f64; 2]) -> Vec3 {
        spherical_point(q)
    }
}

impl Domain for Rectangle {
    type Point = [f64; 2];
    fn bounds(&self) -> [[f64; 2]; 2] {
        [self.x, self.y]
    }
    fn resolution(&self) -> [usize; 2] {
        [16, 16]
    }
    fn params(&self, p: &[f64; 2]) -> Option<[f64; 2]> {
        Some(*p)
    }
    fn point(&self, q: [f64; 2]) -> [f64; 2] {
        q
    }
}

impl Domain for Discrete {
    type Point = usize;
    fn bounds(&self) -> [[f64; 2]; 2] {
        [[0.0, self.0 as f64], [0.0, 1.0]]
    }
    fn resolution(&self) -> [usize; 2] {
        [self.0, 1]
    }
    fn params(&self, p: &usize) -> Option<[f64; 2]> {
        (*p < self.0).then_some([*p as f64 + 0.5, 0.5])
    }
    fn point(&self, q: [f64; 2]) -> usize {
        (q[0].max(0.0) as usize).min(self.0.saturating_sub(1))
    }
}

/// A chi-square test of a sampler on a [`Domain`]: [`ChiSquareTest::run`] takes the sampler and
/// its pdf.
#[derive(Clone, Debug)]
pub struct ChiSquareTest<D: Domain> {
    domain: D,
    samples: usize,
    /// Bin edges along x and y, increasing from the domain's lower to its upper bound.
    edges: [Vec<f64>; 2],
    /// Midpoint-rule sub-cells per bin side.
    integration: usize,
    /// The number of tests of the family this one belongs to (Šidák correction).
    tests: usize,
}

impl<D: Domain> ChiSquareTest<D> {
    /// A test with 100 000 samples on the domain's default bins.
    pub fn new(domain: D) -> Self {
        let [nx, ny] = domain.resolution();
        let [bx, by] = domain.bounds();
        ChiSquareTest {
            edges: [uniform_edges(bx, nx), uniform_edges(by, ny)],
            domain,
            samples: 100_000,
            integration: 8,
            tests: 1,
        }
    }
    /// Draws `n` samples.
    pub fn samples(mut self, n: usize) -> Self {
        self.samples = n;
        self
    }
    /// `nx × ny` bins of equal size.
    pub fn resolution(mut self, nx: usize, ny: usize) -> Self {
        let [bx, by] = self.domain.bounds();
        self.edges = [uniform_edges(bx, nx), uniform_edges(by, ny)];
        self
    }
    /// Bins between the given edges, which must increase from the domain's lower bound to its
    /// upper bound: bins aligned with a piecewise-constant pdf's pieces integrate it exactly.
    pub fn edges(mut self, x: Vec<f64>, y: Vec<f64>) -> Self {
        for (edges, [lo, hi]) in [&x, &y].into_iter().zip(self.domain.bounds()) {
            assert!(
                edges.len() >= 2
                    && edges[0] == lo
                    && edges[edges.len() - 1] == hi
                    && edges.windows(2).all(|w| w[0] < w[1]),
                "bin edges {edges:?} must increase from {lo} to {hi}"
            );
        }
        self.edges = [x, y];
        self
    }
    /// Integrates the pdf over each bin on `k × k` sub-cells (default 8).
    pub fn integration(mut self, k: usize) -> Self {
        self.integration = k.max(1);
        self
    }
    /// Counts this test as one of `n` run together: it rejects at the Šidák-corrected
    /// significance `1 − (1 − SIGNIFICANCE)^(1/n)`.
    pub fn tests(mut self, n: usize) -> Self {
        self.tests = n.max(1);
        self
    }

    /// Draws the samples from `sample` (`None`: the sampler rejected this one) and compares them
    /// with `pdf` (the density in the domain's measure). `Err` when the test rejects the
    /// sampler; either way the [`Report`] says why (its `Debug` is the message, so `unwrap`
    /// explains a failure).
    pub fn run(
        &self,
        mut sample: impl FnMut() -> Option<D::Point>,
        mut pdf: impl FnMut(D::Point) -> f64,
    ) -> Result<Report, Report> {
        let [ex, ey] = &self.edges;
        let (nx, ny) = (ex.len() - 1, ey.len() - 1);
        let n = self.samples;
        let mut report = Report {
            statistic: f64::NAN,
            dof: 0,
            p_value: 0.0,
            significance: sidak(SIGNIFICANCE, self.tests),
            tests: self.tests,
            samples: n,
            rejected: 0,
            pdf_integral: f64::NAN,
            failure: None,
            deviations: Vec::new(),
        };
        let mut observed = vec![0.0; nx * ny];
        let [[x0, x1], [y0, y1]] = self.domain.bounds();
        for i in 0..n {
            let Some(p) = sample() else {
                report.rejected += 1;
                continue;
            };
            let q = self
                .domain
                .params(&p)
                .filter(|q| (x0..=x1).contains(&q[0]) && (y0..=y1).contains(&q[1]));
            let Some([x, y]) = q else {
                report.failure = Some(format!("sample {i} lies outside the domain"));
                return Err(report);
            };
            observed[bin(ex, x) * ny + bin(ey, y)] += 1.0;
        }
        // The mean of the pdf over a bin by the midpoint rule on k × k sub-cells.
        let mut mean_pdf = |xs: &[f64], ys: &[f64], k: usize| -> Result<f64, String> {
            let mut sum = 0.0;
            for a in 0..k {
                for b in 0..k {
                    let q = [
                        xs[0] + (a as f64 + 0.5) / k as f64 * (xs[1] - xs[0]),
                        ys[0] + (b as f64 + 0.5) / k as f64 * (ys[1] - ys[0]),
                    ];
                    let v = pdf(self.domain.point(q));
                    if !(v >= 0.0 && v.is_finite()) {
                        return Err(format!(
                            "the pdf is {v} at parameters ({:.6}, {:.6})",
                            q[0], q[1]
                        ));
                    }
                    sum += v;
                }
            }
            Ok(sum / (k * k) as f64)
        };
        let mut expected = vec![0.0; nx * ny];
        for (bx, xs) in ex.windows(2).enumerate() {
            for (by, ys) in ey.windows(2).enumerate() {
                let c = bx * ny + by;
                let mut mean = mean_pdf(xs, ys, self.integration);
                // Samples where no sub-cell midpoint saw any density: a sliver of the pdf's
                // support the midpoints missed (a corner cut by the bin's edge), or none at all.
                if mean == Ok(0.0) && observed[c] > 0.0 {
                    mean = mean_pdf(xs, ys, 16 * self.integration);
                }
                match mean {
                    Ok(m) => expected[c] = m * (xs[1] - xs[0]) * (ys[1] - ys[0]) * n as f64,
                    Err(why) => {
                        report.failure = Some(why);
                        return Err(report);
                    }
                }
            }
        }
        report.pdf_integral = expected.iter().sum::<f64>() / n as f64;
        if report.pdf_integral > 1.0 + INTEGRAL_TOLERANCE {
            report.failure = Some(format!(
                "the pdf integrates to {:.6} over the domain, more than one",
                report.pdf_integral
            ));
            return Err(report);
        }
        let mut cells: Vec<Cell> = (0..nx * ny)
            .map(|c| Cell {
                observed: observed[c],
                expected: expected[c],
                name: format!(
                    "bin [{:.4}, {:.4}) × [{:.4}, {:.4})",
                    ex[c / ny],
                    ex[c / ny + 1],
                    ey[c % ny],
                    ey[c % ny + 1]
                ),
            })
            .collect();
        if report.rejected > 0 || report.pdf_integral < 1.0 - INTEGRAL_TOLERANCE {
            cells.push(Cell {
                observed: report.rejected as f64,
                expected: n as f64 * (1.0 - report.pdf_integral).max(0.0),
                name: "rejected samples".into(),
            });
        }
        let (statistic, dof) = match pearson(&cells) {
            Ok(s) => s,
            Err(e) => {
                report.failure = Some(e);
                return Err(report);
            }
        };
        report.statistic = statistic;
        report.dof = dof;
        report.p_value = chi_square_p_value(statistic, dof);
        // The cells tested alone (not pooled) that deviate most.
        cells.retain(|c| c.expected >= 5.0);
        cells.sort_by(|a, b| b.contribution().total_cmp(&a.contribution()));
        report.deviations = cells
            .into_iter()
            .take(4)
            .map(|c| {
                format!(
                    "{}: {} observed, {:.1} expected",
                    c.name, c.observed, c.expected
                )
            })
            .collect();
        // Shown by `cargo test -- --nocapture`, and for a failing test.
        eprintln!("{report:?}");
        if report.p_value >= report.significance {
            Ok(report)
        } else {
            Err(report)
        }
    }
}

fn uniform_edges([lo, hi]: [f64; 2], n: usize) -> Vec<f64> {
    assert!(n >= 1, "at least one bin");
    (0..=n)
        .map(|i| {
            if i == n {
                hi
            } else {
                lo + (hi - lo) * i as f64 / n as f64
            }
        })
        .collect()
}

/// The bin of `x` between `edges` (the upper bound itself in the last bin).
fn bin(edges: &[f64], x: f64) -> usize {
    edges
        .partition_point(|&e| e <= x)
        .saturating_sub(1)
        .min(edges.len() - 2)
}

/// One outcome of the test: a bin, or the sampler's rejections.
struct Cell {
    observed: f64,
    expected: f64,
    name: String,
}

impl Cell {
    fn contribution(&self) -> f64 {
        if self.expected > 0.0 {
            (self.observed - self.expected).powi(2) / self.expected
        } else if self.observed > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    }
}

/// Pearson's statistic and its degrees of freedom over `cells`, those expecting fewer than 5
/// pooled, smallest first, until the pool expects 5 (Mitsuba's rule). An error where a cell
/// that expects nothing was observed, or fewer than two cells remain.
fn pearson(cells: &[Cell]) -> Result<(f64, usize), String> {
    let mut order: Vec<&Cell> = cells.iter().collect();
    order.sort_by(|a, b| a.expected.total_cmp(&b.expected));
    let (mut statistic, mut used) = (0.0, 0usize);
    let (mut pool_observed, mut pool_expected) = (0.0, 0.0);
    for c in order {
        if c.expected == 0.0 && c.observed > 0.0 {
            return Err(format!(
                "{}: {} samples, where the pdf leaves no probability",
                c.name, c.observed
            ));
        }
        if c.expected < 5.0 || (pool_expected > 0.0 && pool_expected < 5.0) {
            pool_observed += c.observed;
            pool_expected += c.expected;
        } else {
            statistic += c.contribution();
            used += 1;
        }
    }
    if pool_expected > 0.0 {
        statistic += (pool_observed - pool_expected).powi(2) / pool_expected;
        used += 1;
    }
    if used < 2 {
        return Err(format!(
            "{used} cell(s) expect 5 samples or more: too few samples or bins for a test"
        ));
    }
    Ok((statistic, used - 1))
}

/// The probability that a chi-square variable with `dof` degrees of freedom exceeds
/// `statistic`: `Q(dof / 2, statistic / 2)`.
pub fn chi_square_p_value(statistic: f64, dof: usize) -> f64 {
    regularized_gamma_q(dof as f64 / 2.0, statistic / 2.0)
}

/// The per-test significance of `tests` independent tests that together falsely reject with
/// probability `alpha` (Šidák 1967): `1 − (1 − alpha)^(1/tests)`.
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    -((-alpha).ln_1p() / tests.max(1) as f64).exp_m1()
}

/// ln Γ(x) for x > 0: Stirling's series to x⁻⁹ (Abramowitz and Stegun 6.1.41) after raising
/// x to at least 10 with Γ(x) = Γ(x + 1) / x; absolute error below 1e-13.
pub fn ln_gamma(x: f64) -> f64 {
    assert!(x > 0.0, "ln Γ({x}): the argument must be positive");
    let (mut x, mut shift) = (x, 0.0);
    while x < 10.0 {
        shift -= x.ln();
        x += 1.0;
    }
    let (inv, inv2) = (1.0 / x, 1.0 / (x * x));
    let series = inv
        * (1.0 / 12.0
            - inv2 * (1.0 / 360.0 - inv2 * (1.0 / 1260.0 - inv2 * (1.0 / 1680.0 - inv2 / 1188.0))));
    (x - 0.5) * x.ln() - x + 0.5 * (2.0 * PI).ln() + series + shift
}

/// The regularized lower incomplete gamma function P(a, x) = γ(a, x) / Γ(a), a > 0.
pub fn regularized_gamma_p(a: f64, x: f64) -> f64 {
    1.0 - regularized_gamma_q(a, x)
}

/// The regularized upper incomplete gamma function Q(a, x) = Γ(a, x) / Γ(a), a > 0: its power
/// series below x = a + 1, the continued fraction (modified Lentz) above.
pub fn regularized_gamma_q(a: f64, x: f64) -> f64 {
    assert!(a > 0.0, "Q({a}, {x}): a must be positive");
    if x.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    if x == f64::INFINITY {
        return 0.0;
    }
    // x^a e^-x / Γ(a), the factor both expansions share.
    let front = (a * x.ln() - x - ln_gamma(a)).exp();
    const EPS: f64 = 1e-16;
    if x < a + 1.0 {
        // P(a, x) = front Σ x^n / (a (a + 1) ... (a + n)).
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..100_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term < sum * EPS {
                break;
            }
        }
        1.0 - (front * sum).min(1.0)
    } else {
        // Q(a, x) = front / (x + 1 − a − 1 (1 − a) / (x + 3 − a − 2 (2 − a) / (x + 5 − a − ...))).
        const TINY: f64 = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..100_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < TINY {
                d = TINY;
            }
            c = b + an / c;
            if c.abs() < TINY {
                c = TINY;
            }
            d = 1.0 / d;
            let step = d * c;
            h *= step;
            if (step - 1.0).abs() < EPS {
                break;
            }
        }
        (front * h).min(1.0)
    }
}

/// The outcome of a [`ChiSquareTest`]; its `Debug` is a readable account (what `unwrap`
/// prints).
#[derive(Clone)]
pub struct Report {
    /// Pearson's X² (NaN where the test failed before computing it).
    pub statistic: f64,
    pub dof: usize,
    /// P(X² at least this large | the samples follow the pdf); 0 on an outright failure.
    pub p_value: f64,
    /// The Šidák-corrected significance the p-value was compared with.
    pub significance: f64,
    pub tests: usize,
    pub samples: usize,
    /// Samples the sampler rejected (returned `None` for).
    pub rejected: usize,
    /// The pdf integrated over the domain.
    pub pdf_integral: f64,
    /// Why the test failed before its statistic: a sample outside the domain, a bad pdf value,
    /// samples where the pdf is zero, too few cells.
    pub failure: Option<String>,
    /// The cells tested alone that contribute most to the statistic (shown on a failure).
    pub deviations: Vec<String>,
}

impl fmt::Debug for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.failure {
            Some(why) => write!(f, "chi-square test failed: {why}")?,
            None => write!(
                f,
                "chi-square {:.1} with {} degrees of freedom: p = {:.3e} {} α = {:.2e} \
                 ({} over {} test(s), Šidák)",
                self.statistic,
                self.dof,
                self.p_value,
                if self.p_value >= self.significance {
                    "≥"
                } else {
                    "<"
                },
                self.significance,
                SIGNIFICANCE,
                self.tests
            )?,
        }
        write!(
            f,
            "; {} samples, {} rejected by the sampler, pdf integral {:.6}",
            self.samples, self.rejected, self.pdf_integral
        )?;
        if self.p_value < self.significance {
            for d in &self.deviations {
                write!(f, "\n  {d}")?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 64-bit linear congruential generator (Knuth's MMIX constants): enough for tests of the
    /// harness, and independent of the samplers it tests elsewhere.
    struct Lcg(u64);
    impl Lcg {
        fn uniform(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn sphere(&mut self) -> Vec3 {
            let (z, phi) = (1.0 - 2.0 * self.uniform(), 2.0 * PI * self.uniform());
            spherical_point([z, phi])
        }
    }

    #[test]
    fn p_values_match_tabulated_chi_square_quantiles() {
        // Upper quantiles of the chi-square distribution (NIST/SEMATECH e-Handbook of
        // Statistical Methods, 1.3.6.7.4): P(X² > x) for dof degrees of freedom.
        for (x, dof, p) in [
            (3.841, 1, 0.05),
            (6.635, 1, 0.01),
            (18.307, 10, 0.05),
            (23.209, 10, 0.01),
            (3.940, 10, 0.95),
            (124.342, 100, 0.05),
            (135.807, 100, 0.01),
            (77.929, 100, 0.95),
        ] {
            let q = chi_square_p_value(x, dof);
            assert!((q - p).abs() < 1e-4, "{x}, {dof}: {q} vs {p}");
        }
        // Two degrees of freedom: exactly e^(−x/2); one: erfc(√(x/2)), erfc(2) = 0.004677734981.
        for x in [0.1, 1.0, 7.0, 30.0, 200.0] {
            let q = chi_square_p_value(x, 2);
            assert!((q / (-x / 2.0).exp() - 1.0).abs() < 1e-12, "{x}: {q}");
        }
        assert!((chi_square_p_value(8.0, 1) / 0.004677734981047266 - 1.0).abs() < 1e-10);
        assert_eq!(chi_square_p_value(0.0, 5), 1.0);
        assert!((regularized_gamma_p(1.0, 2.0) - (1.0 - (-2.0f64).exp())).abs() < 1e-13);
    }

    #[test]
    fn ln_gamma_matches_factorials_and_the_half_integers() {
        let mut factorial = 1.0f64;
        for n in 1..30 {
            // Γ(n) = (n − 1)!
            assert!((ln_gamma(n as f64) - factorial.ln()).abs() < 1e-12, "{n}");
            factorial *= n as f64;
        }
        assert!((ln_gamma(0.5) - PI.sqrt().ln()).abs() < 1e-13);
        // Γ(n + 1/2) = (2n)! √π / (4^n n!).
        assert!((ln_gamma(5.5) - (52.34277778455352f64).ln()).abs() < 1e-12);
    }

    #[test]
    fn sidak_splits_the_significance_among_the_tests() {
        assert!((sidak(0.01, 1) - 0.01).abs() < 1e-16);
        assert!((sidak(0.05, 10) - 0.005116196891823743).abs() < 1e-15);
        // n tests at α₁ falsely reject together with probability α.
        assert!((1.0 - (1.0 - sidak(0.01, 37)).powi(37) - 0.01).abs() < 1e-14);
    }

    #[test]
    fn a_correct_sampler_passes_and_wrong_densities_are_rejected() {
        let mut rng = Lcg(1);
        // x = √u has density 2x on [0, 1]; y is uniform.
        let mut linear = || Some([rng.uniform().sqrt(), rng.uniform()]);
        let test = ChiSquareTest::new(Rectangle::UNIT).tests(3);
        test.run(&mut linear, |p| 2.0 * p[0]).unwrap();
        // The same samples against a uniform density, and against one 10 % off at most.
        assert!(test.run(&mut linear, |_| 1.0).is_err());
        let close = |p: [f64; 2]| 2.0 * p[0] * (1.0 + 0.15 * (p[0] - 2.0 / 3.0));
        let r = test.run(&mut linear, close).unwrap_err();
        assert!(r.failure.is_none() && r.p_value < 1e-4, "{r:?}");
        // Uniform directions: right on the sphere; on the hemisphere half are outside it.
        let mut rng = Lcg(2);
        ChiSquareTest::new(Sphere)
            .run(|| Some(rng.sphere()), |_| 0.25 / PI)
            .unwrap();
        let r = ChiSquareTest::new(Hemisphere)
            .run(|| Some(rng.sphere()), |_| 0.5 / PI)
            .unwrap_err();
        assert!(r.failure.unwrap().contains("outside the domain"));
    }

    #[test]
    fn rejections_must_match_the_missing_probability() {
        // Uniform directions above the horizon, those below rejected: the pdf 1/(4π) on the
        // upper half integrates to the acceptance probability 1/2.
        let mut rng = Lcg(3);
        let mut upper = || Some(rng.sphere()).filter(|w| w.z >= 0.0);
        let test = ChiSquareTest::new(Sphere).tests(2);
        let ok = test
            .run(&mut upper, |w| if w.z >= 0.0 { 0.25 / PI } else { 0.0 })
            .unwrap();
        assert!(ok.rejected > 40_000 && (ok.pdf_integral - 0.5).abs() < 1e-12);
        // A pdf normalised over the upper half claims that nothing is rejected.
        let r = test
            .run(&mut upper, |w| if w.z >= 0.0 { 0.5 / PI } else { 0.0 })
            .unwrap_err();
        assert!(r.p_value < 1e-12, "{r:?}");
        // Samples where the pdf is zero fail outright.
        let r = test.run(&mut upper, |w| if w.z >= 0.5 { 0.25 / PI } else { 0.0 });
        let why = r.unwrap_err().failure.unwrap();
        assert!(
            why.starts_with("bin") && why.ends_with("leaves no probability"),
            "{why}"
        );
        // A sampler that rejects nothing against a pdf short of 2 % of the probability, and
        // against one claiming 2 % too much.
        let mut rng = Lcg(6);
        let test = ChiSquareTest::new(Sphere).tests(2);
        let short = test.run(|| Some(rng.sphere()), |_| 0.98 / (4.0 * PI));
        assert!(short.unwrap_err().p_value < 1e-12);
        let over = test.run(|| Some(rng.sphere()), |_| 1.02 / (4.0 * PI));
        assert!(over.unwrap_err().failure.unwrap().contains("more than one"));
    }

    #[test]
    fn discrete_choices_and_explicit_edges() {
        let pmf = [0.1, 0.0, 0.3, 0.6];
        let mut rng = Lcg(4);
        let mut choose = || {
            let u = rng.uniform();
            Some(if u < 0.1 {
                0
            } else if u < 0.4 {
                2
            } else {
                3
            })
        };
        let test = ChiSquareTest::new(Discrete(4)).samples(20_000).tests(2);
        test.run(&mut choose, |i| pmf[i]).unwrap();
        assert!(test
            .run(&mut choose, |i| [0.12, 0.0, 0.28, 0.6][i])
            .is_err());
        // A step density on edges that follow its steps: exact expected counts.
        let mut rng = Lcg(5);
        let step = |p: [f64; 2]| if p[0] < 0.3 { 0.5 / 0.3 } else { 0.5 / 0.7 };
        ChiSquareTest::new(Rectangle::UNIT)
            .edges(vec![0.0, 0.1, 0.2, 0.3, 0.65, 1.0], vec![0.0, 0.5, 1.0])
            .integration(1)
            .run(
                || {
                    let (u, v) = (rng.uniform(), rng.uniform());
                    Some([
                        if u < 0.5 {
                            0.6 * u
                        } else {
                            0.3 + 1.4 * (u - 0.5)
                        },
                        v,
                    ])
                },
                step,
            )
            .unwrap();
    }
}
