//! The propagated uncertainties of the grid figures against their actual scatter over many
//! simulated, independently repeated calculations, with and without correlation between points.
//!
//! Model: point k's batch estimate is T_k (1 + c z_b) + s T_k ε_bk with z_b, ε_bk standard normal:
//! c is a common-mode error all points of a batch share (light paths reaching many points), s the
//! point's own noise. The minimum point is well separated (T_min = 250 lx, the others ≥ 380 lx),
//! so Emin is smooth in the data and the jackknife applies.
//!
//! Tolerance: the empirical SD over R = 400 repetitions has a relative standard error of
//! 1/√(2(R−1)) = 3.5 %; the RMS of the B = 16-batch standard errors adds ~1 %; 4 combined σ ≈ 15 %.

use crate::common::Rng;
use luxest_photometry::GridStats;

struct Scatter {
    sd: [f64; 3],
    rms_jack: [f64; 3],
    rms_indep: [f64; 3],
}

fn simulate(c: f64, s: f64, seed: u64) -> Scatter {
    let n = 40;
    let truth: Vec<f64> = (0..n)
        .map(|k| {
            if k == 7 {
                250.0
            } else {
                500.0 + 120.0 * (k as f64 * 1.3).sin()
            }
        })
        .collect();
    let (reps, nb) = (400, 16);
    let mut rng = Rng(seed);
    let mut vals: Vec<[f64; 3]> = Vec::new();
    let (mut j2, mut i2) = ([0.0; 3], [0.0; 3]);
    for _ in 0..reps {
        let batches: Vec<Vec<f64>> = (0..nb)
            .map(|_| {
                let z = rng.normal();
                truth
                    .iter()
                    .map(|t| t * (1.0 + c * z) + s * t * rng.normal())
                    .collect()
            })
            .collect();
        let j = GridStats::from_batches(&batches).unwrap();
        let i = GridStats::from_independent(&j.values, &j.point_std_errors).unwrap();
        vals.push([j.e_avg.value, j.e_min.value, j.u0.value]);
        for (k, (a, b)) in [(j.e_avg, i.e_avg), (j.e_min, i.e_min), (j.u0, i.u0)]
            .iter()
            .enumerate()
        {
            j2[k] += a.std_error * a.std_error / reps as f64;
            i2[k] += b.std_error * b.std_error / reps as f64;
        }
    }
    let mut sd = [0.0; 3];
    for (k, s) in sd.iter_mut().enumerate() {
        let m = vals.iter().map(|v| v[k]).sum::<f64>() / reps as f64;
        *s = (vals.iter().map(|v| (v[k] - m).powi(2)).sum::<f64>() / (reps - 1) as f64).sqrt();
    }
    Scatter {
        sd,
        rms_jack: j2.map(f64::sqrt),
        rms_indep: i2.map(f64::sqrt),
    }
}

const NAMES: [&str; 3] = ["Eavg", "Emin", "U0"];

#[test]
fn jackknife_errors_match_the_scatter_with_correlated_points() {
    let r = simulate(0.05, 0.03, 21);
    for (k, name) in NAMES.iter().enumerate() {
        let ratio = r.rms_jack[k] / r.sd[k];
        eprintln!(
            "{}: scatter {:.4}, jackknife SE {:.4}, independent-points SE {:.4}",
            name, r.sd[k], r.rms_jack[k], r.rms_indep[k]
        );
        assert!(
            (0.85..1.15).contains(&ratio),
            "{}: jackknife/scatter = {ratio}",
            name
        );
    }
    // Assuming independent points badly underestimates the Eavg error here (shared paths), and
    // overestimates the U0 error (the common mode cancels in the ratio).
    assert!(r.rms_indep[0] / r.sd[0] < 0.5);
    assert!(r.rms_indep[2] / r.sd[2] > 1.5);
}

#[test]
fn both_methods_match_the_scatter_with_independent_points() {
    let r = simulate(0.0, 0.04, 22);
    for (k, name) in NAMES.iter().enumerate() {
        for (what, se) in [
            ("jackknife", r.rms_jack[k]),
            ("independent", r.rms_indep[k]),
        ] {
            let ratio = se / r.sd[k];
            assert!(
                (0.85..1.15).contains(&ratio),
                "{} {what}: SE/scatter = {ratio}",
                name
            );
        }
    }
}

#[test]
fn ambiguous_minimum_is_flagged() {
    let batches = vec![
        vec![100.0, 101.0, 300.0],
        vec![102.0, 99.0, 310.0],
        vec![98.0, 100.0, 290.0],
    ];
    let s = GridStats::from_batches(&batches).unwrap();
    assert!(s.min_is_ambiguous(3.0));
    let batches = vec![
        vec![100.0, 201.0, 300.0],
        vec![102.0, 199.0, 310.0],
        vec![98.0, 200.0, 290.0],
    ];
    assert!(!GridStats::from_batches(&batches)
        .unwrap()
        .min_is_ambiguous(3.0));
    assert!(GridStats::from_batches(&batches[..1]).is_err());
    assert!(GridStats::from_independent(&[1.0, f64::NAN], &[0.1, 0.1]).is_err());
}
