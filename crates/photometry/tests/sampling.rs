//! The emission sampler against its own density (chi-square, as Mitsuba tests its samplers) and
//! the Monte Carlo flux E[I/p] against the table integral and the closed form.

use crate::common::{chi2_z, get, Rng};
use luxest_photometry::{c_gamma_from_direction, IntensitySampler, Photometry};
use std::f64::consts::PI;

/// Chi-square test with bins = every table cell split 2 × 2 in (C, cos γ): the density is
/// constant on each bin, so its expected count is N · pdf(bin centre) · bin solid angle exactly.
fn chi_square(p: &Photometry, n: usize, seed: u64) -> f64 {
    let s = IntensitySampler::new(p).unwrap();
    let (c, g) = (p.c_angles_deg(), p.gamma_angles_deg());
    let (nc, ng) = (c.len() - 1, g.len() - 1);
    let mut counts = vec![0u64; nc * ng * 4];
    let mut rng = Rng(seed);
    for _ in 0..n {
        let smp = s.sample(rng.uniform(), rng.uniform());
        let (cd, gd) = c_gamma_from_direction(smp.dir);
        let i = c
            .partition_point(|&x| x <= cd)
            .saturating_sub(1)
            .min(nc - 1);
        let j = g
            .partition_point(|&x| x <= gd)
            .saturating_sub(1)
            .min(ng - 1);
        let si = usize::from(cd >= 0.5 * (c[i] + c[i + 1]));
        let mu = -smp.dir[2];
        let (m0, m1) = (g[j].to_radians().cos(), g[j + 1].to_radians().cos());
        let sj = usize::from(mu <= 0.5 * (m0 + m1));
        counts[((i * ng + j) * 2 + si) * 2 + sj] += 1;
    }
    let (mut chi2, mut dof, mut pool_e, mut pool_o, mut total_e) = (0.0, 0usize, 0.0, 0.0, 0.0);
    for i in 0..nc {
        for j in 0..ng {
            let (m0, m1) = (g[j].to_radians().cos(), g[j + 1].to_radians().cos());
            for si in 0..2 {
                for sj in 0..2 {
                    let cc = c[i] + (0.25 + 0.5 * si as f64) * (c[i + 1] - c[i]);
                    let mu = m0 - (0.25 + 0.5 * sj as f64) * (m0 - m1);
                    let sg = (1.0 - mu * mu).sqrt();
                    let dir = [sg * cc.to_radians().cos(), sg * cc.to_radians().sin(), -mu];
                    let area = 0.5 * (c[i + 1] - c[i]).to_radians() * 0.5 * (m0 - m1);
                    let e = n as f64 * s.pdf(dir) * area;
                    let o = counts[((i * ng + j) * 2 + si) * 2 + sj] as f64;
                    total_e += e;
                    if e < 5.0 {
                        pool_e += e;
                        pool_o += o;
                    } else {
                        chi2 += (o - e) * (o - e) / e;
                        dof += 1;
                    }
                }
            }
        }
    }
    // The density integrates to one: this checks the cell solid angles independently.
    assert!(
        (total_e / n as f64 - 1.0).abs() < 1e-9,
        "{}",
        total_e / n as f64
    );
    if pool_e > 0.0 {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof += 1;
    }
    let z = chi2_z(chi2, (dof - 1) as f64);
    eprintln!(
        "{}: chi2 {chi2:.1} with {} dof, z = {z:.2}",
        p.name,
        dof - 1
    );
    z
}

#[test]
fn sampler_passes_chi_square_against_its_pdf() {
    for (k, name) in ["quad.ies", "bilat90.ldt", "cos2.ies", "bilat-open.ies"]
        .iter()
        .enumerate()
    {
        let z = chi_square(&get(name), 400_000, 1000 + k as u64);
        // z > 4 has probability 3e-5 under the null hypothesis.
        assert!(z < 4.0, "{name}: z = {z}");
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
