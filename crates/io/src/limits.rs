//! Size limits derived from the memory the machine has, checked *before* allocating: a film,
//! an image read from an EXR header or a mesh whose size exceeds what can be held is refused with
//! a message stating the limit, instead of aborting the process in the allocator.
//!
//! The limit is the kernel's estimate of memory available without swapping (`MemAvailable` in
//! `/proc/meminfo`); where that cannot be read, only sizes that overflow the address space are
//! refused.

/// Bytes of memory available to this process now (`MemAvailable`), if it can be read.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_mem_available(&text)
}

/// `MemAvailable: N kB` of a `/proc/meminfo` text, in bytes.
fn parse_mem_available(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line
        .trim_start_matches("MemAvailable:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    kb.checked_mul(1024)
}

/// A byte count for messages: `25.8 GB`.
pub fn show_bytes(bytes: u128) -> String {
    const UNITS: [&str; 6] = ["B", "kB", "MB", "GB", "TB", "PB"];
    let mut v = bytes as f64;
    let mut unit = 0;
    while v >= 1000.0 && unit + 1 < UNITS.len() {
        v /= 1000.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{v:.1} {}", UNITS[unit])
    }
}

/// Checks that `bytes` for `what` fit in `available` bytes (`None`: unknown, only the address
/// space limits). The message states both sizes.
pub fn check_fits(what: &str, bytes: u128, available: Option<u64>) -> Result<(), String> {
    let limit = available.map_or(isize::MAX as u128, |a| (a as u128).min(isize::MAX as u128));
    if bytes <= limit {
        return Ok(());
    }
    Err(match available {
        Some(a) => format!(
            "{what} needs {} of memory, more than the {} available on this machine \
             (MemAvailable in /proc/meminfo)",
            show_bytes(bytes),
            show_bytes(a as u128)
        ),
        None => format!(
            "{what} needs {}, more than this machine can address",
            show_bytes(bytes)
        ),
    })
}

/// Checks that `count` items of `item_bytes` each fit in the memory available now.
pub fn check_allocation(what: &str, count: u128, item_bytes: u128) -> Result<(), String> {
    check_fits(what, count.saturating_mul(item_bytes), available_memory())
}

/// Checks a `width` x `height` image of `bytes_per_pixel` (all buffers the stage keeps per
/// pixel) against the memory available now: `a 100000x100000 film needs 240.0 GB of memory, ...`.
pub fn check_image(
    what: &str,
    width: u64,
    height: u64,
    bytes_per_pixel: u64,
) -> Result<(), String> {
    check_allocation(
        &format!("a {width}x{height} {what}"),
        width as u128 * height as u128,
        bytes_per_pixel as u128,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meminfo_is_parsed_in_bytes() {
        let text = "MemTotal:       32000000 kB\nMemFree:  100 kB\nMemAvailable:   24000000 kB\n";
        assert_eq!(parse_mem_available(text), Some(24_000_000 * 1024));
        assert_eq!(parse_mem_available("MemTotal: 1 kB\n"), None);
        assert!(available_memory().is_some_and(|b| b > 0));
    }

    #[test]
    fn sizes_beyond_available_memory_are_refused_with_both_sizes() {
        // 32768² pixels at 24 bytes (three f64 accumulators) on a 24 GB machine.
        let e = check_fits(
            "a 32768x32768 film",
            32768 * 32768 * 24,
            Some(24_000_000_000),
        )
        .unwrap_err();
        assert_eq!(
            e,
            "a 32768x32768 film needs 25.8 GB of memory, more than the 24.0 GB available on \
             this machine (MemAvailable in /proc/meminfo)"
        );
        assert!(check_fits("x", 1000, Some(1000)).is_ok());
        assert!(check_fits("x", u128::MAX, None).is_err());
        let e = check_image("film", 100_000, 100_000, 24).unwrap_err();
        assert!(e.starts_with("a 100000x100000 film needs 240.0 GB"), "{e}");
        assert!(check_image("film", 256, 256, 24).is_ok());
    }
}
