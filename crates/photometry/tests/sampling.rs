//! The emission sampler and the luminous opening's point sampler against their own densities
//! (the chi-square harness of `luxest_io::chi2`, as Mitsuba tests its samplers), and the Monte
//! Carlo flux E[I/p] against the table integral and the closed form.

use crate::common::{get, Rng};
use luxest_io::chi2::{ChiSquareTest, Rectangle, Sphere};
use luxest_photometry::{c_gamma_from_direction, IntensitySampler, LuminousOpening, Photometry};
use std::f64::consts::{PI, TAU};

/// `edges` with each interval split in two.
fn halved(edges: &[f64]) -> Vec<f64> {
    let mut out = vec![edges[0]];
    for w in edges.windows(2) {
        out.extend([0.5 * (w[0] + w[1]), w[1]]);
    }
    out
}

/// Bins on the table's cells split 2 × 2 in (cos θ = −cos γ, φ = C): the density is constant on
/// each, so one pdf value per bin integrates it exactly. Beyond the table's γ range (one that
/// starts after 0° or ends short of 180°) one more bin each side, where the density is zero.
fn table_bins(p: &Photometry) -> (Vec<f64>, Vec<f64>) {
    let z: Vec<f64> = p
        .gamma_angles_deg()
        .iter()
        .map(|g| -g.to_radians().cos())
        .collect();
    let mut z = halved(&z);
    if z[0] > -1.0 + 1e-12 {
        z.insert(0, -1.0);
    }
    if z[z.len() - 1] < 1.0 - 1e-12 {
        z.push(1.0);
    }
    let n = z.len();
    (z[0], z[n - 1]) = (-1.0, 1.0);
    let c: Vec<f64> = p.c_angles_deg().iter().map(|c| c.to_radians()).collect();
    let mut phi = halved(&c);
    let n = phi.len();
    (phi[0], phi[n - 1]) = (0.0, TAU);
    (z, phi)
}

#[test]
fn sampler_passes_chi_square_against_its_pdf() {
    let names = ["quad.ies", "bilat90.ldt", "cos2.ies", "bilat-open.ies"];
    for (k, name) in names.iter().enumerate() {
        let p = get(name);
        let s = IntensitySampler::new(&p).unwrap();
        let (z, phi) = table_bins(&p);
        let mut rng = Rng(1000 + k as u64);
        let report = ChiSquareTest::new(Sphere)
            .edges(z, phi)
            .integration(1)
            .samples(200_000)
            .tests(names.len())
            .run(
                || Some(s.sample(rng.uniform(), rng.uniform()).dir.into()),
                |w| s.pdf(w.into()),
            )
            .unwrap_or_else(|r| panic!("{name}: {r:?}"));
        // The density integrates to one: this checks the cells' solid angles independently.
        assert!((report.pdf_integral - 1.0).abs() < 1e-9, "{report:?}");
    }
}

#[test]
fn opening_points_are_uniform_over_the_opening() {
    // Rectangle, disc and ellipse, binned on the rectangle around them; the round shapes'
    // edges cut bins, so the density is integrated finely there.
    let shapes = [(0.6, 1.2), (-0.4, -0.4), (-0.3, -0.8)];
    for (k, (width, length)) in shapes.into_iter().enumerate() {
        let opening = LuminousOpening::from_ies(width, length, 0.0);
        let (a, b) = (0.5 * opening.length_m, 0.5 * opening.width_m);
        let area = opening.flat_area_m2().unwrap();
        let round = width < 0.0;
        let inside = |p: [f64; 2]| !round || (p[0] / a).powi(2) + (p[1] / b).powi(2) <= 1.0;
        let mut rng = Rng(2000 + k as u64);
        ChiSquareTest::new(Rectangle {
            x: [-a, a],
            y: [-b, b],
        })
        .integration(32)
        .tests(shapes.len())
        .run(
            || {
                let p = opening.sample_flat_point(rng.uniform(), rng.uniform())?;
                assert_eq!(p[2], 0.0);
                Some([p[0], p[1]])
            },
            |p| if inside(p) { 1.0 / area } else { 0.0 },
        )
        .unwrap_or_else(|r| panic!("{width} x {length}: {r:?}"));
    }
}

#[test]
fn sampled_mean_cosine_matches_closed_form() {
    // The samplers of cos² and cos³ tables reproduce their different first moments.
    let a = get("cos2.ies");
    let g = a.gamma_angles_deg().to_vec();
    let rows = vec![g
        .iter()
        .map(|x| 1000.0 * x.to_radians().cos().max(0.0).powi(3))
        .collect::<Vec<_>>()];
    let b = Photometry::from_table("cos3", &[0.0], &g, &rows).unwrap();
    let (sa, sb) = (
        IntensitySampler::new(&a).unwrap(),
        IntensitySampler::new(&b).unwrap(),
    );
    // Mean cos γ under each: cos² gives 3/4, cos³ gives 4/5; the sampler of `a` must not match b.
    let mut rng = Rng(3);
    let n = 200_000;
    let (mut ma, mut mb) = (0.0, 0.0);
    for _ in 0..n {
        ma += -sa.sample(rng.uniform(), rng.uniform()).dir[2];
        mb += -sb.sample(rng.uniform(), rng.uniform()).dir[2];
    }
    let (ma, mb) = (ma / n as f64, mb / n as f64);
    // E[cos γ] for I ∝ cos^n over the hemisphere: (n + 1)/(n + 2); table error ~1e-3.
    assert!((ma - 0.75).abs() < 3e-3, "{ma}");
    assert!((mb - 0.8).abs() < 3e-3, "{mb}");
}

#[test]
fn sample_pdf_and_intensity_are_consistent() {
    let p = get("bilat90.ies");
    let s = IntensitySampler::new(&p).unwrap();
    let mut rng = Rng(5);
    for _ in 0..20_000 {
        let smp = s.sample(rng.uniform(), rng.uniform());
        let len = (smp.dir.iter().map(|x| x * x).sum::<f64>()).sqrt();
        assert!((len - 1.0).abs() < 1e-12);
        let pdf = s.pdf(smp.dir);
        // Equal except for a direction that rounds onto a cell boundary.
        let on_boundary = {
            let (c, g) = c_gamma_from_direction(smp.dir);
            p.c_angles_deg().iter().any(|&x| (x - c).abs() < 1e-7)
                || p.gamma_angles_deg().iter().any(|&x| (x - g).abs() < 1e-7)
        };
        assert!((pdf - smp.pdf_sr).abs() <= 1e-9 * pdf.max(smp.pdf_sr) || on_boundary);
        let i = p.intensity_dir_cd(smp.dir);
        assert!(
            (i - smp.intensity_cd).abs() <= 1e-9 * i.max(1.0),
            "{i} vs {}",
            smp.intensity_cd
        );
    }
}

/// E[I/p] = ∫ I dω: the Monte Carlo flux against the table integral (within 4 standard errors
/// of the estimate itself) and, for cos² γ, against 2π I0 / 3 within that plus the table's
/// interpolation bound 2π (Δγ²/8) n² I0.
#[test]
fn monte_carlo_flux_equals_table_flux() {
    for (name, closed) in [
        (
            "cos2.ies",
            Some((
                2.0 * PI * 1000.0 / 3.0,
                2.0 * PI * 2.5f64.to_radians().powi(2) / 8.0 * 4.0 * 1000.0,
            )),
        ),
        ("quad.ies", None),
        ("bilat90.ldt", None),
    ] {
        let p = get(name);
        let s = IntensitySampler::new(&p).unwrap();
        let table = p.flux_from_table_lm();
        assert!((s.total_lm() - table).abs() < 1e-9 * table);
        let mut rng = Rng(17);
        let n = 1_000_000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..n {
            let smp = s.sample(rng.uniform(), rng.uniform());
            let w = smp.intensity_cd / smp.pdf_sr;
            sum += w;
            sum2 += w * w;
        }
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean).max(0.0) / (n - 1) as f64).sqrt();
        eprintln!("{name}: MC flux {mean:.4} ± {se:.4} lm, table {table:.4} lm");
        assert!(
            (mean - table).abs() <= 4.0 * se + 1e-12 * table,
            "{name}: {mean} ± {se} vs {table}"
        );
        // The weight is nearly constant: the sampler is close to proportional to I.
        assert!(se / mean < 1e-3, "{se} {mean}");
        if let Some((want, bound)) = closed {
            assert!((mean - want).abs() <= bound + 4.0 * se, "{mean} vs {want}");
        }
    }
}
