//! The film: per-pixel f64 sums of radiance and of the squared luminance, from which the mean
//! image and its per-pixel standard error follow. A film can keep receiving samples, which is
//! what makes progressive rendering and snapshots exact: an image at n samples is the same
//! whether it was rendered in one pass or several.

use luxest_io::color::Rgb;

/// Per-pixel accumulators.
pub struct Film {
    pub width: usize,
    pub height: usize,
    pub sum: Vec<[f64; 3]>,
    pub sum_y2: Vec<f64>,
    pub samples: u32,
}

impl Film {
    pub fn new(width: usize, height: usize) -> Film {
        Film {
            width,
            height,
            sum: vec![[0.0; 3]; width * height],
            sum_y2: vec![0.0; width * height],
            samples: 0,
        }
    }

    /// Mean radiance per pixel.
    pub fn mean(&self) -> Vec<Rgb> {
        let n = self.samples.max(1) as f64;
        self.sum.iter().map(|s| Rgb(s.map(|v| v / n))).collect()
    }

    /// Standard error of each pixel's mean luminance.
    pub fn standard_error(&self) -> Vec<f64> {
        let n = self.samples as f64;
        self.sum
            .iter()
            .zip(&self.sum_y2)
            .map(|(s, s2)| {
                if self.samples < 2 {
                    return f64::INFINITY;
                }
                let mean = Rgb(*s).luminance() / n;
                ((s2 / n - mean * mean).max(0.0) / (n - 1.0)).sqrt()
            })
            .collect()
    }
}
