//! Deterministic parallel batches: batch `b` always uses random stream `b + 1` and batches are
//! combined in index order, so results depend on the seed only, never on the thread count.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Runs `work(b)` for b in 0..batches on `threads` threads; returns the results in batch order.
/// It draws nothing: the work counts itself on a [`luxest_io::progress::Progress`], whose own
/// thread draws, so that progress never changes the order of the work.
pub fn run_batches<T: Send>(
    batches: usize,
    threads: usize,
    work: impl Fn(usize) -> T + Sync,
) -> Vec<T> {
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<T>>> = Mutex::new((0..batches).map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..threads.min(batches).max(1) {
            s.spawn(|| {
                crate::rt::enable_flush_to_zero();
                loop {
                    let b = next.fetch_add(1, Ordering::SeqCst);
                    if b >= batches {
                        break;
                    }
                    let r = work(b);
                    results.lock().unwrap()[b] = Some(r);
                }
            });
        }
    });
    results
        .into_inner()
        .unwrap()
        .into_iter()
        .map(|r| r.expect("every batch ran"))
        .collect()
}

/// Mean and standard error of the mean of independent batch values.
pub fn mean_and_standard_error(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    if values.len() < 2 {
        return (mean, f64::INFINITY);
    }
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}
