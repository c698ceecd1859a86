//! Comparison of sensor results with exact solutions: the table `make validate` prints and the
//! z-test it fails on. The cases themselves live in `luxest_core::exact_case`.

pub use luxest_core::exact_case::{Case, Row};
use luxest_core::sensors::SensorResults;
use luxest_core::{Error, Result};
use std::path::Path;

/// Prints the comparison table; returns the number of rows with |z| > max_z.
pub fn print_table(title: &str, rows: &[Row], max_z: f64) -> usize {
    println!("{title}");
    println!(
        "  {:<34} {:>14} {:>14} {:>11} {:>7} {:>10}",
        "point", "exact", "estimate", "std.err", "z", "rel.err"
    );
    let mut bad = 0;
    for r in rows {
        let flag = if r.z().abs() > max_z {
            bad += 1;
            "  <-- |z| too large"
        } else {
            ""
        };
        println!(
            "  {:<34} {:>14.6e} {:>14.6e} {:>11.3e} {:>7.2} {:>10.2e}{flag}",
            r.label,
            r.exact,
            r.estimate,
            r.standard_error,
            r.z(),
            r.relative_error()
        );
    }
    bad
}

/// `estimate compare`: reads results, compares, prints; an error if any |z| > max_z.
pub fn run(path: &Path, case: &Case, max_z: f64, sets: &[String]) -> Result<()> {
    let mut results = SensorResults::read_ron(path)?;
    if !sets.is_empty() {
        for name in sets {
            if !results.sets.iter().any(|s| &s.name == name) {
                return Err(Error::input(
                    path,
                    format!("no sensor set named \"{name}\""),
                ));
            }
        }
        results.sets.retain(|s| sets.contains(&s.name));
    }
    let rows = case.rows(&results);
    let title = format!(
        "{} — {} light paths, {:.2} s, singularity {}",
        path.display(),
        results.run.samples,
        results.run.seconds,
        results.singularity
    );
    let bad = print_table(&title, &rows, max_z);
    if bad > 0 {
        return Err(Error::input(
            path,
            format!(
                "validation failed: {bad} of {} values have |z| > {max_z}",
                rows.len()
            ),
        ));
    }
    Ok(())
}
