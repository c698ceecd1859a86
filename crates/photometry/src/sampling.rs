//! Sampling emission directions from a goniometric distribution.
//!
//! The table's cells (C_i, C_{i+1}) × (γ_j, γ_{j+1}) are chosen with probability proportional to
//! their exact flux W_ij = ∫∫_cell I sin γ dγ dC over the bilinear surface (so Σ W_ij is
//! [`Photometry::flux_from_table_lm`]); within the chosen cell the direction is uniform in
//! solid angle (C uniform, cos γ uniform). The solid-angle density is therefore piecewise
//! constant,
//!
//! ```text
//! p(ω) = W_ij / (W Ω_ij),   Ω_ij = ΔC (cos γ_j − cos γ_{j+1}),   W = Σ W_ij,
//! ```
//!
//! exactly what [`IntensitySampler::pdf`] returns. The estimator weight I(ω)/p(ω) stays unbiased,
//! E[I/p] = ∫_{p>0} I dω = W, because p > 0 wherever I > 0: a cell has W_ij = 0 only if its four
//! corner values are 0, and then the bilinear I vanishes on it. Within a cell I/p varies only as
//! the bilinear surface does around its mean, so the weight stays within a small factor of W.
//!
//! A light path carrying the luminaire's flux starts with power W per sample in expectation; a
//! photon's weight is I(ω)/p(ω) (cd·sr = lm).

use crate::frame::c_gamma_from_direction;
use crate::photometry::{locate_c, locate_gamma, Photometry};

/// One sampled emission direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IntensitySample {
    /// Unit direction in the luminaire frame.
    pub dir: [f64; 3],
    /// Solid-angle density (1/sr).
    pub pdf_sr: f64,
    /// I(dir) in candela (bilinear table value).
    pub intensity_cd: f64,
}

/// A tabulated 2D distribution over the table's cells (see the module docs).
#[derive(Debug, Clone)]
pub struct IntensitySampler {
    photometry: Photometry,
    /// Cumulative, normalised cell weights, cell k = i * (ng − 1) + j.
    cdf: Vec<f64>,
    /// Density in each cell: W_ij / (W Ω_ij).
    density: Vec<f64>,
    total_lm: f64,
}

impl IntensitySampler {
    /// The sampler of a distribution; `None` when the table emits no light at all.
    pub fn new(photometry: &Photometry) -> Option<IntensitySampler> {
        let (c, g) = (photometry.c_angles_deg(), photometry.gamma_angles_deg());
        let (nc, ng) = (c.len() - 1, g.len() - 1);
        let mut cdf = Vec::with_capacity(nc * ng);
        let mut density = Vec::with_capacity(nc * ng);
        let mut acc = 0.0;
        for i in 0..nc {
            let dc = (c[i + 1] - c[i]).to_radians();
            for j in 0..ng {
                let w = photometry.cell_integral(i, j);
                let omega = dc * (g[j].to_radians().cos() - g[j + 1].to_radians().cos());
                acc += w;
                cdf.push(acc);
                density.push(if omega > 0.0 { w / omega } else { 0.0 });
            }
        }
        if !(acc > 0.0 && acc.is_finite()) {
            return None;
        }
        for (x, d) in cdf.iter_mut().zip(density.iter_mut()) {
            *x /= acc;
            *d /= acc;
        }
        Some(IntensitySampler {
            photometry: photometry.clone(),
            cdf,
            density,
            total_lm: acc,
        })
    }

    /// W = ∫ I dω (lm), the normalisation: equal to the photometry's table flux.
    pub fn total_lm(&self) -> f64 {
        self.total_lm
    }

    /// A direction from two uniform numbers in [0, 1).
    pub fn sample(&self, u1: f64, u2: f64) -> IntensitySample {
        let u1 = u1.clamp(0.0, 1.0);
        let u2 = u2.clamp(0.0, 1.0);
        let k = self
            .cdf
            .partition_point(|&x| x <= u1)
            .min(self.cdf.len() - 1);
        let lo = if k == 0 { 0.0 } else { self.cdf[k - 1] };
        let ur = ((u1 - lo) / (self.cdf[k] - lo)).clamp(0.0, 1.0);
        let (c, g) = (
            self.photometry.c_angles_deg(),
            self.photometry.gamma_angles_deg(),
        );
        let ng = g.len() - 1;
        let (i, j) = (k / ng, k % ng);
        let c_deg = c[i] + ur * (c[i + 1] - c[i]);
        let (mu0, mu1) = (g[j].to_radians().cos(), g[j + 1].to_radians().cos());
        let mu = mu0 - u2 * (mu0 - mu1);
        let sin_g = (1.0 - mu * mu).max(0.0).sqrt();
        let cr = c_deg.to_radians();
        let dir = [sin_g * cr.cos(), sin_g * cr.sin(), -mu];
        let gamma_deg = mu
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees()
            .clamp(g[j], g[j + 1]);
        IntensitySample {
            dir,
            pdf_sr: self.density[k],
            intensity_cd: self.photometry.intensity_cd(c_deg, gamma_deg),
        }
    }

    /// The solid-angle density (1/sr) of a direction in the luminaire frame.
    pub fn pdf(&self, dir_local: [f64; 3]) -> f64 {
        let (c_deg, gamma_deg) = c_gamma_from_direction(dir_local);
        let g = self.photometry.gamma_angles_deg();
        let Some((j, _)) = locate_gamma(g, gamma_deg) else {
            return 0.0;
        };
        let (i, _) = locate_c(self.photometry.c_angles_deg(), c_deg);
        self.density[i * (g.len() - 1) + j]
    }
}
