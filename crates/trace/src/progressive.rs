//! The progressive schedule: which sample counts a run renders to, and when it stops.
//!
//! With a sample budget the run renders each snapshot count below it, then the budget. With a
//! time budget it doubles the sample count per pass (snapshot counts included as pass ends)
//! while the next pass, predicted from the time per sample so far, still fits. Because a film
//! can keep receiving samples, splitting a run into passes never changes its images.

use luxest_io::Result;

/// How much a run renders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Exactly this many samples per pixel.
    Samples(u32),
    /// About this many wall-clock seconds from the run's start.
    Seconds(f64),
}

/// Calls `pass(target)` for each sample count the run renders to, in increasing order; every
/// positive `snapshots` count below the final one is among them (`snapshots` sorted, no
/// duplicates). `elapsed()` gives the seconds since the run started. Returns the final count.
pub fn run_passes(
    budget: Budget,
    snapshots: &[u32],
    elapsed: impl Fn() -> f64,
    mut pass: impl FnMut(u32) -> Result<()>,
) -> Result<u32> {
    match budget {
        Budget::Samples(spp) => {
            for &s in snapshots.iter().filter(|&&s| s > 0 && s < spp) {
                pass(s)?;
            }
            pass(spp)?;
            Ok(spp)
        }
        Budget::Seconds(limit) => {
            let (mut done, mut target) = (0u32, 1u32);
            loop {
                let elapsed = elapsed();
                if done > 0 {
                    let predicted = elapsed * (target - done) as f64 / done as f64;
                    if elapsed + predicted > limit {
                        return Ok(done);
                    }
                }
                let stop = snapshots
                    .iter()
                    .copied()
                    .find(|&s| s > done && s < target)
                    .unwrap_or(target);
                pass(stop)?;
                done = stop;
                if stop == target {
                    target *= 2;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    #[test]
    fn sample_budgets_pass_through_the_snapshots_below_them() {
        let mut targets = Vec::new();
        let last = run_passes(
            Budget::Samples(16),
            &[1, 4, 16, 64],
            || 0.0,
            |t| {
                targets.push(t);
                Ok(())
            },
        )
        .unwrap();
        assert_eq!((targets, last), (vec![1, 4, 16], 16));
    }

    #[test]
    fn time_budgets_double_and_stop_before_the_limit() {
        // A simulated clock: 1 ms per sample.
        let done = Cell::new(0u32);
        let mut targets = Vec::new();
        let last = run_passes(
            Budget::Seconds(0.2),
            &[3],
            || done.get() as f64 * 1e-3,
            |t| {
                done.set(t);
                targets.push(t);
                Ok(())
            },
        )
        .unwrap();
        // After 64 samples (64 ms) the next pass is predicted to end at 128 ms: it runs; after
        // 128 the next would end at 256 ms > 200 ms: the run stops.
        assert_eq!(targets, vec![1, 2, 3, 4, 8, 16, 32, 64, 128]);
        assert_eq!(last, 128);
    }
}
