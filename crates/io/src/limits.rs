//! The resource rule (docs/architecture.md, *Command-line conventions*): a stage sizes its
//! memory and its work from its arguments before it starts. Memory: a film, an image read from
//! an EXR header, a mesh, a buffer of view points or light-path records whose size exceeds what
//! can be held is refused with a message stating both sizes and the limit, instead of aborting
//! the process in the allocator. Work: a stage whose run is predicted to take longer than
//! [`PLAN_AFTER_SECONDS`] says so first, in one line ([`WorkPlan`]).
//!
//! The limit is the least of what applies to this process: the kernel's estimate of memory
//! available without swapping (`MemAvailable` in `/proc/meminfo`), the headroom under its
//! control group's memory limit (a container's or a batch job's: cgroup v2 `memory.max`, v1
//! `memory.limit_in_bytes`, minus the group's usage less its reclaimable page cache) and under
//! its own resource limits (`ulimit -v` and `ulimit -d`: the soft limit minus what the process
//! already maps). A run under such a limit was aborted by the allocator although `MemAvailable`
//! had room (`memory allocation of 6174015488 bytes failed`). Where none can be read, only sizes
//! that overflow the address space are refused.

use std::path::{Path, PathBuf};

/// The memory this process may still allocate, and which limit that is (for messages).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryLimit {
    pub bytes: u64,
    /// Where the limit comes from, as a message names it: "MemAvailable in /proc/meminfo".
    pub source: &'static str,
}

/// The least of the limits that apply to this process now (see the module documentation), if
/// any can be read.
pub fn memory_limit() -> Option<MemoryLimit> {
    let meminfo = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| parse_mem_available(&t))
        .map(|bytes| MemoryLimit {
            bytes,
            source: "MemAvailable in /proc/meminfo",
        });
    let rlimits = std::fs::read_to_string("/proc/self/limits")
        .ok()
        .zip(std::fs::read_to_string("/proc/self/status").ok())
        .map(|(limits, status)| rlimit_headroom(&limits, &status))
        .unwrap_or_default();
    [meminfo, cgroup_headroom()]
        .into_iter()
        .chain(rlimits)
        .flatten()
        .min_by_key(|l| l.bytes)
}

/// Bytes of memory available to this process now (the least of its limits, [`memory_limit`]),
/// if any can be read.
pub fn available_memory() -> Option<u64> {
    memory_limit().map(|l| l.bytes)
}

/// `MemAvailable: N kB` of a `/proc/meminfo` text, in bytes.
fn parse_mem_available(text: &str) -> Option<u64> {
    kb_field(text, "MemAvailable:")
}

/// The value of a `KEY: N kB` line (`/proc/meminfo`, `/proc/self/status`), in bytes.
fn kb_field(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kb: u64 = line
        .trim_start_matches(key)
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    kb.checked_mul(1024)
}

/// The headroom under the soft address-space and data-size limits (`/proc/self/limits`), less
/// what the process already has (`VmSize`, `VmData` of `/proc/self/status`).
fn rlimit_headroom(limits: &str, status: &str) -> [Option<MemoryLimit>; 2] {
    let soft = |name: &str| -> Option<u64> {
        let line = limits.lines().find(|l| l.starts_with(name))?;
        line[name.len()..].split_whitespace().next()?.parse().ok()
    };
    let headroom = |name: &str, used: &str, source: &'static str| {
        let limit = soft(name)?;
        let used = kb_field(status, used).unwrap_or(0);
        Some(MemoryLimit {
            bytes: limit.saturating_sub(used),
            source,
        })
    };
    [
        headroom(
            "Max address space",
            "VmSize:",
            "address space under this process's limit (ulimit -v)",
        ),
        headroom(
            "Max data size",
            "VmData:",
            "data size under this process's limit (ulimit -d)",
        ),
    ]
}

/// The headroom under the memory limits of this process's control group and its ancestors
/// (cgroup v2 or v1), if it has any.
fn cgroup_headroom() -> Option<MemoryLimit> {
    let membership = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let root = Path::new("/sys/fs/cgroup");
    let mut best: Option<u64> = None;
    for line in membership.lines() {
        let mut parts = line.splitn(3, ':');
        let (Some(id), Some(controllers), Some(path)) = (parts.next(), parts.next(), parts.next())
        else {
            continue;
        };
        let path = path.trim_start_matches('/');
        // v2: the unified hierarchy ("0::/path"); v1: the memory controller's.
        let (base, limit_file, usage_file) = if id == "0" && controllers.is_empty() {
            let unified = if root.join("unified").is_dir() {
                root.join("unified")
            } else {
                root.to_path_buf()
            };
            (unified, "memory.max", "memory.current")
        } else if controllers.split(',').any(|c| c == "memory") {
            (
                root.join("memory"),
                "memory.limit_in_bytes",
                "memory.usage_in_bytes",
            )
        } else {
            continue;
        };
        let mut dir: PathBuf = base.join(path);
        loop {
            if let Some(h) = group_headroom(&dir, limit_file, usage_file) {
                best = Some(best.map_or(h, |b| b.min(h)));
            }
            if dir == base || !dir.pop() || !dir.starts_with(&base) {
                break;
            }
        }
    }
    best.map(|bytes| MemoryLimit {
        bytes,
        source: "headroom under this process's control group memory limit",
    })
}

/// One control group's limit minus its usage less the page cache it could reclaim; `None`
/// without a limit (`max`, or v1's near-2^63 "unlimited").
fn group_headroom(dir: &Path, limit_file: &str, usage_file: &str) -> Option<u64> {
    let read = |f: &str| std::fs::read_to_string(dir.join(f)).ok();
    let limit: u64 = read(limit_file)?.trim().parse().ok()?;
    if limit >= 1 << 60 {
        return None;
    }
    let usage: u64 = read(usage_file)
        .and_then(|u| u.trim().parse().ok())
        .unwrap_or(0);
    let cache = read("memory.stat")
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("inactive_file "))
                .and_then(|v| v.trim().parse::<u64>().ok())
        })
        .unwrap_or(0);
    Some(limit.saturating_sub(usage.saturating_sub(cache)))
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

/// Checks that `bytes` for `what` fit under `available` (`None`: unknown, only the address
/// space limits). The message states both sizes and which limit it is.
pub fn check_fits(what: &str, bytes: u128, available: Option<MemoryLimit>) -> Result<(), String> {
    let limit = available.map_or(isize::MAX as u128, |a| {
        (a.bytes as u128).min(isize::MAX as u128)
    });
    if bytes <= limit {
        return Ok(());
    }
    Err(match available {
        Some(a) => format!(
            "{what} needs {} of memory, more than the {} available on this machine ({})",
            show_bytes(bytes),
            show_bytes(a.bytes as u128),
            a.source
        ),
        None => format!(
            "{what} needs {}, more than this machine can address",
            show_bytes(bytes)
        ),
    })
}

/// Checks that `count` items of `item_bytes` each fit in the memory available now.
pub fn check_allocation(what: &str, count: u128, item_bytes: u128) -> Result<(), String> {
    check_fits(what, count.saturating_mul(item_bytes), memory_limit())
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

/// Runs predicted to take longer than this (wall-clock seconds) print their plan first.
pub const PLAN_AFTER_SECONDS: f64 = 60.0;

/// What a run will do, predicted before it starts from its arguments and a short calibration
/// on the scene (the cost of a ray, the mean length of a path): printed as one line on stderr
/// when the run is predicted to take longer than [`PLAN_AFTER_SECONDS`], so that a run that
/// will take hours says so before it starts, with the options that set its work.
#[derive(Clone, Debug, PartialEq)]
pub struct WorkPlan {
    /// The stage and subcommand: `estimate sensors`.
    pub stage: String,
    /// The work in the arguments' terms: `64 light paths of ~1.0e5 collisions, ...`.
    pub work: String,
    /// Units of work predicted in all ...
    pub units: f64,
    /// ... and what they count: `ray casts` (the Monte Carlo stages), `pixels` (`denoise`).
    pub unit: &'static str,
    /// Predicted wall-clock seconds.
    pub seconds: f64,
    /// Threads the work is spread over.
    pub threads: usize,
    /// Memory the run will hold at its peak, bytes (as checked before it starts).
    pub memory_bytes: u128,
    /// Seconds the calibration took.
    pub calibration_seconds: f64,
    /// The options that set the work, for the user who wants less of it.
    pub levers: String,
}

impl WorkPlan {
    /// The plan as one line: `estimate sensors: plan: ...; about 3.2 h on 1 thread ...`.
    pub fn line(&self) -> String {
        format!(
            "{}: plan: {}: ~{} {}, about {} on {} thread{} (from a {:.1} s \
             calibration), {} of memory; {} set the work",
            self.stage,
            self.work,
            show_count(self.units),
            self.unit,
            show_duration(self.seconds),
            self.threads,
            if self.threads == 1 { "" } else { "s" },
            self.calibration_seconds,
            show_bytes(self.memory_bytes),
            self.levers
        )
    }

    /// Whether the run is long enough to be announced.
    pub fn is_long(&self) -> bool {
        self.seconds > PLAN_AFTER_SECONDS
    }
}

/// Times `unit(k)` for k = 0, 1, ... until it has run at least 64 times and 20 ms, or 4096
/// times: a stage's calibration of one unit of its work (a pixel sample, a path) on the scene
/// at hand. Returns the seconds per unit and the seconds spent.
pub fn seconds_per_unit(mut unit: impl FnMut(u64)) -> (f64, f64) {
    let start = std::time::Instant::now();
    let mut k = 0;
    while k < 4096 && !(k >= 64 && start.elapsed().as_secs_f64() >= 0.02) {
        unit(k);
        k += 1;
    }
    let spent = start.elapsed().as_secs_f64();
    (spent / k as f64, spent)
}

/// A duration for messages: `45 s`, `12 min`, `3.2 h`, `4.1 days`, `2.3e3 years`.
pub fn show_duration(seconds: f64) -> String {
    let s = seconds.max(0.0);
    if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.0} min", s / 60.0)
    } else if s < 2.0 * 86400.0 {
        format!("{:.1} h", s / 3600.0)
    } else if s < 365.25 * 86400.0 {
        format!("{:.1} days", s / 86400.0)
    } else {
        format!("{:.1e} years", s / (365.25 * 86400.0))
    }
}

/// A count for messages: whole below 100 000, else `6.4e10`.
pub fn show_count(n: f64) -> String {
    if n < 1e5 {
        format!("{n:.0}")
    } else {
        format!("{n:.1e}")
    }
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
        let meminfo = |bytes| {
            Some(MemoryLimit {
                bytes,
                source: "MemAvailable in /proc/meminfo",
            })
        };
        let e = check_fits(
            "a 32768x32768 film",
            32768 * 32768 * 24,
            meminfo(24_000_000_000),
        )
        .unwrap_err();
        assert_eq!(
            e,
            "a 32768x32768 film needs 25.8 GB of memory, more than the 24.0 GB available on \
             this machine (MemAvailable in /proc/meminfo)"
        );
        assert!(check_fits("x", 1000, meminfo(1000)).is_ok());
        assert!(check_fits("x", u128::MAX, None).is_err());
        let e = check_image("film", 100_000, 100_000, 24).unwrap_err();
        assert!(e.starts_with("a 100000x100000 film needs 240.0 GB"), "{e}");
        assert!(check_image("film", 256, 256, 24).is_ok());
    }

    #[test]
    fn plans_read_as_one_line_with_their_duration() {
        let plan = WorkPlan {
            stage: "estimate sensors".into(),
            work: "64 light paths of ~1.0e5 collisions".into(),
            units: 6.4e10,
            unit: "ray casts",
            seconds: 11520.0,
            threads: 1,
            memory_bytes: 2_000_000,
            calibration_seconds: 0.21,
            levers: "--paths and --max-depth".into(),
        };
        assert!(plan.is_long());
        assert_eq!(
            plan.line(),
            "estimate sensors: plan: 64 light paths of ~1.0e5 collisions: ~6.4e10 ray casts, \
             about 3.2 h on 1 thread (from a 0.2 s calibration), 2.0 MB of memory; --paths and \
             --max-depth set the work"
        );
        assert!(!WorkPlan {
            seconds: 59.0,
            ..plan
        }
        .is_long());
        assert_eq!(show_duration(45.2), "45 s");
        assert_eq!(show_duration(720.0), "12 min");
        assert_eq!(show_duration(3.0 * 86400.0), "3.0 days");
        assert_eq!(show_count(64.0), "64");
    }

    #[test]
    fn resource_limits_count_what_the_process_already_maps() {
        let limits = "Limit                     Soft Limit           Hard Limit           Units\n\
                      Max data size             unlimited            unlimited            bytes\n\
                      Max address space         8589934592           unlimited            bytes\n";
        let status = "VmPeak:\t 3000000 kB\nVmSize:\t 2000000 kB\nVmData:\t 100 kB\n";
        let [address, data] = rlimit_headroom(limits, status);
        assert_eq!(data, None, "unlimited");
        let address = address.unwrap();
        assert_eq!(address.bytes, 8_589_934_592 - 2_000_000 * 1024);
        assert!(address.source.contains("ulimit -v"), "{}", address.source);
        // Whatever limits this machine has, a check finds one of them (two live readings of
        // free memory differ by what other processes did in between, so none is compared).
        let least = memory_limit().unwrap();
        assert!(least.bytes > 0, "{}", least.source);
        assert!(
            ["/proc/meminfo", "ulimit -v", "ulimit -d", "control group"]
                .iter()
                .any(|s| least.source.contains(s)),
            "{}",
            least.source
        );
    }
}
