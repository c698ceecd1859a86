//! Adaptive Gauss–Kronrod (7/15-point) quadrature, used by the exact solutions.
//!
//! Nodes and weights are QUADPACK's `qk15` (Piessens et al., 1983); the unit tests check that
//! the Kronrod rule integrates polynomials of degree 22 and the Gauss rule degree 13 exactly.

const XGK: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
const WGK: [f64; 8] = [
    0.022_935_322_010_529_22,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_2,
    0.140_653_259_715_525_9,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_8,
];
/// Gauss weights for the nodes XGK[1], XGK[3], XGK[5], XGK[7].
const WG: [f64; 4] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
];

/// One 15-point Kronrod estimate of the integral over [a, b] and its difference from the
/// embedded 7-point Gauss estimate (the error estimate).
pub fn gauss_kronrod_15(f: &mut impl FnMut(f64) -> f64, a: f64, b: f64) -> (f64, f64) {
    let c = 0.5 * (a + b);
    let h = 0.5 * (b - a);
    let fc = f(c);
    let mut kronrod = WGK[7] * fc;
    let mut gauss = WG[3] * fc;
    for i in 0..7 {
        let x = h * XGK[i];
        let s = f(c - x) + f(c + x);
        kronrod += WGK[i] * s;
        if i % 2 == 1 {
            gauss += WG[i / 2] * s;
        }
    }
    (kronrod * h, ((kronrod - gauss) * h).abs())
}

/// Integral of `f` over [a, b] by recursive bisection until each piece's error estimate is
/// below its share of `abs_tol` (or the depth limit is reached). Returns (value, error bound).
pub fn integrate(f: &mut impl FnMut(f64) -> f64, a: f64, b: f64, abs_tol: f64) -> (f64, f64) {
    /// Work bound: at most this many interval evaluations in one call. A non-finite integrand
    /// or an unreachable tolerance would otherwise split down to depth 40 (2^40 intervals, which
    /// never ends); at the bound the estimate so far is returned with its error estimate.
    const MAX_INTERVALS: u32 = 1 << 16;
    fn rec(
        f: &mut impl FnMut(f64) -> f64,
        a: f64,
        b: f64,
        tol: f64,
        depth: u32,
        budget: &mut u32,
    ) -> (f64, f64) {
        let (v, e) = gauss_kronrod_15(f, a, b);
        *budget = budget.saturating_sub(1);
        if e <= tol
            || !e.is_finite()
            || depth == 0
            || *budget == 0
            || (b - a).abs() < 1e-14 * (a.abs() + b.abs())
        {
            return (v, e);
        }
        let m = 0.5 * (a + b);
        let (v1, e1) = rec(f, a, m, tol * 0.5, depth - 1, budget);
        let (v2, e2) = rec(f, m, b, tol * 0.5, depth - 1, budget);
        (v1 + v2, e1 + e2)
    }
    let mut budget = MAX_INTERVALS;
    rec(f, a, b, abs_tol, 40, &mut budget)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_are_exact_for_their_polynomial_degree() {
        for deg in 0..=22 {
            let (k, e) = gauss_kronrod_15(&mut |x: f64| x.powi(deg), -1.0, 1.0);
            let exact = if deg % 2 == 1 {
                0.0
            } else {
                2.0 / (deg as f64 + 1.0)
            };
            assert!(
                (k - exact).abs() < 1e-14,
                "Kronrod degree {deg}: {k} vs {exact}"
            );
            // The Gauss rule is exact to degree 13, so the difference vanishes there.
            if deg <= 13 {
                assert!(e < 1e-14, "Gauss degree {deg}: error estimate {e}");
            }
        }
    }

    #[test]
    fn adaptive_integration_ends_on_non_finite_integrands_and_unreachable_tolerances() {
        // 1/x on [0, 1] is infinite at 0 and its integral diverges: the call must end.
        let (v, e) = integrate(&mut |x: f64| 1.0 / x, 0.0, 1.0, 1e-12);
        assert!(
            !(v.is_finite() && e <= 1e-12),
            "no false convergence: {v} ± {e}"
        );
        let (v, _) = integrate(&mut |_| f64::NAN, 0.0, 1.0, 1e-12);
        assert!(v.is_nan());
        // A tolerance of 0 is unreachable for sin; the budget ends it with the right value.
        let (v, _) = integrate(&mut |x: f64| x.sin(), 0.0, 3.0, 0.0);
        assert!((v - (1.0 - 3f64.cos())).abs() < 1e-13, "{v}");
    }

    #[test]
    fn adaptive_integration_handles_peaks() {
        // A narrow Lorentzian: integral of 1/(x^2 + s^2) over [-1, 1] = 2 atan(1/s)/s.
        let s = 1e-4;
        let (v, _) = integrate(&mut |x: f64| 1.0 / (x * x + s * s), -1.0, 1.0, 1e-9);
        let exact = 2.0 * (1.0 / s).atan() / s;
        assert!((v / exact - 1.0).abs() < 1e-10, "{v} vs {exact}");
    }
}
