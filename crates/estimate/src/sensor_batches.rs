//! What the two forward estimators at sensor points — the local estimate
//! ([`crate::local_estimate`]) and direct simulation ([`crate::direct_simulation`]) — share:
//! per-batch flux sums at every sensor, and their combination into means with standard errors.
//!
//! Light paths are split into independent batches (at least 2, see
//! [`luxest_render::parallel`]); a batch's sums divided by its paths are one estimate of the
//! illuminance, and the standard error is the batches' standard deviation over √B. All sums
//! are f64.

use crate::sensors::Estimate;
use luxest_io::color::Rgb;
use luxest_io::sensors::Part;
use luxest_render::parallel::{mean_and_standard_error, run_batches};

/// Bytes the sensor estimators keep per batch and sensor point until the batches are combined
/// (RGB sums and their direct part in f64, the batch's Y; measured 56).
pub const BYTES_PER_BATCH_POINT: u128 = 64;

/// How a forward estimator's light paths are split and seeded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Batches {
    /// Light paths in all.
    pub paths: u64,
    /// Independent batches for the standard error (at least 2 are used).
    pub batches: usize,
    pub seed: u64,
    pub threads: usize,
}

impl Batches {
    /// The batches actually run: at least 2, for a standard error.
    pub fn count(&self) -> usize {
        self.batches.max(2)
    }

    /// Light paths of batch `b` (the batches differ by at most one path).
    pub fn paths_of(&self, b: usize) -> u64 {
        let n = self.count() as u64;
        self.paths / n + u64::from((b as u64) < self.paths % n)
    }
}

/// One batch's sums over its light paths.
pub struct BatchSums {
    /// Per sensor: every contribution (flux sums; a backward near-field part scaled to the
    /// batch's paths).
    pub sums: Vec<[f64; 3]>,
    /// Per sensor: the direct ones among them (from emitter vertices and, in the near field,
    /// emitted radiance met first).
    pub direct: Vec<[f64; 3]>,
    pub collisions: u64,
    pub shadow_rays: u64,
    /// Light paths still going when they reached the path-length bound.
    pub truncated: u64,
}

impl BatchSums {
    pub fn new(sensors: usize) -> Self {
        BatchSums {
            sums: vec![[0.0; 3]; sensors],
            direct: vec![[0.0; 3]; sensors],
            collisions: 0,
            shadow_rays: 0,
            truncated: 0,
        }
    }

    /// Adds contribution `c` to sensor `i` (and to its direct part when `direct`).
    pub fn add(&mut self, i: usize, c: Rgb, direct: bool) {
        add(&mut self.sums[i], c);
        if direct {
            add(&mut self.direct[i], c);
        }
    }
}

/// Adds an RGB contribution to an f64 accumulator.
fn add(acc: &mut [f64; 3], c: Rgb) {
    for (a, v) in acc.iter_mut().zip(c.0) {
        *a += v;
    }
}

/// Results of a forward estimator per sensor point.
#[derive(Clone, Debug)]
pub struct SensorEstimates {
    /// Mean RGB illuminance, lx per channel.
    pub rgb: Vec<Rgb>,
    /// Mean photometric illuminance Y and its standard error, lx.
    pub value: Vec<f64>,
    pub standard_error: Vec<f64>,
    /// The exact part from delta lights (point sources, luminaires), included in `value`; zero
    /// for direct simulation, which has no exact term.
    pub delta_light: Vec<f64>,
    /// Per sensor, the direct part (light straight from the emitters, the exact delta-light
    /// term included) and the indirect part of `value`, each as (Y, standard error), lx; the
    /// local estimate only (empty for direct simulation).
    pub direct: Vec<(f64, f64)>,
    pub indirect: Vec<(f64, f64)>,
    /// `batch_values[b][i]`: batch b's estimate of Y at sensor i (the exact delta-light part
    /// included), lx; `value` is their mean, `standard_error` their standard deviation / √B.
    pub batch_values: Vec<Vec<f64>>,
    pub seconds: f64,
    pub collisions: u64,
    pub shadow_rays: u64,
    /// Light paths that reached the path-length bound still carrying light: what they would
    /// have added is missing (the estimate is biased low), e.g. in a closed scene of
    /// reflectance 1.
    pub truncated: u64,
}

impl SensorEstimates {
    /// Per sensor: RGB, Y, the standard error of Y and (local estimate) the direct and
    /// indirect parts, the results contract's values.
    pub fn estimates(&self) -> Vec<Estimate> {
        let part = |p: Option<&(f64, f64)>| {
            p.map(|&(value, standard_error)| Part {
                value,
                standard_error,
            })
        };
        (0..self.value.len())
            .map(|i| Estimate {
                direct: part(self.direct.get(i)),
                indirect: part(self.indirect.get(i)),
                ..Estimate::from((self.rgb[i], self.value[i], self.standard_error[i]))
            })
            .collect()
    }
}

/// Runs `run_batch(b, paths)` for every batch of `batches` (on its threads) and combines the
/// sums at `sensors` sensor points with the exact delta-light part `delta_light` (one per
/// sensor). `split`: report the direct and indirect parts.
pub fn run(
    batches: &Batches,
    sensors: usize,
    delta_light: &[Rgb],
    split: bool,
    run_batch: impl Fn(usize, u64) -> BatchSums + Sync,
) -> SensorEstimates {
    let start = std::time::Instant::now();
    let count = batches.count();
    let results = run_batches(count, batches.threads, |b| {
        run_batch(b, batches.paths_of(b))
    });
    let n = sensors;
    let mut rgb = vec![Rgb::BLACK; n];
    let mut value = vec![0.0; n];
    let mut standard_error = vec![0.0; n];
    let mut batch_values = vec![vec![0.0; n]; count];
    let (mut direct_part, mut indirect_part) = (Vec::new(), Vec::new());
    for i in 0..n {
        let mut ys = Vec::with_capacity(count);
        let (mut ys_direct, mut ys_indirect) = (Vec::new(), Vec::new());
        let mut acc = [0.0; 3];
        for (b, r) in results.iter().enumerate() {
            let paths = batches.paths_of(b).max(1) as f64;
            let e = r.sums[i].map(|s| s / paths);
            add(&mut acc, Rgb(e) * (1.0 / count as f64));
            ys.push(Rgb(e).luminance());
            if split {
                let d = Rgb(r.direct[i].map(|s| s / paths)).luminance();
                ys_direct.push(d);
                ys_indirect.push(Rgb(e).luminance() - d);
            }
        }
        if split {
            let (md, sed) = mean_and_standard_error(&ys_direct);
            direct_part.push((md + delta_light[i].luminance(), sed));
            indirect_part.push(mean_and_standard_error(&ys_indirect));
        }
        let (m, se) = mean_and_standard_error(&ys);
        for (b, y) in ys.iter().enumerate() {
            batch_values[b][i] = y + delta_light[i].luminance();
        }
        rgb[i] = Rgb(acc) + delta_light[i];
        value[i] = m + delta_light[i].luminance();
        standard_error[i] = se;
    }
    SensorEstimates {
        rgb,
        value,
        standard_error,
        delta_light: delta_light.iter().map(Rgb::luminance).collect(),
        direct: direct_part,
        indirect: indirect_part,
        batch_values,
        seconds: start.elapsed().as_secs_f64(),
        collisions: results.iter().map(|r| r.collisions).sum(),
        shadow_rays: results.iter().map(|r| r.shadow_rays).sum(),
        truncated: results.iter().map(|r| r.truncated).sum(),
    }
}
