//! Deterministic parallel batches: batch `b` always uses random stream `b + 1` and batches are
//! combined in index order, so results depend on the seed only, never on the thread count.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Runs `work(b)` for b in 0..batches on `threads` threads; returns the results in batch order.
/// Shows a progress line on stderr when it is a terminal.
pub fn run_batches<T: Send>(
    batches: usize,
    threads: usize,
    label: &str,
    work: impl Fn(usize) -> T + Sync,
) -> Vec<T> {
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<T>>> = Mutex::new((0..batches).map(|_| None).collect());
    let progress = std::io::stderr().is_terminal();
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
                    let d = done.fetch_add(1, Ordering::SeqCst) + 1;
                    if progress {
                        eprint!("\r{label}: {d}/{batches} batches");
                    }
                }
            });
        }
    });
    if progress {
        eprintln!();
    }
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
