//! Progress of a long run on stderr, as renderers show it (Mitsuba 3, pbrt-v4, Cycles,
//! Radiance's `rpict -t`): the fraction done, the rate in the stage's own units (samples/s,
//! paths/s), the time elapsed and the time left.
//!
//! Workers count their work with [`Progress::inc`], one relaxed atomic addition (a [`Tally`]
//! gathers the additions of a fine-grained loop), and never draw: a thread of the progress's
//! own reads the count and draws. So progress touches neither the random numbers nor the order
//! of the work, and a run's outputs are bit-identical with and without it
//! (`tests/progress.rs`).
//!
//! How it is drawn, [`Display`]:
//! - on a terminal, one line redrawn in place (a carriage return) at most 10 times a second,
//!   cut to the terminal's width and erased when the work ends;
//! - otherwise (a log: `make -j`, Slurm's `slurm-<job>.out`), a plain line every
//!   [`DEFAULT_INTERVAL`] seconds, so only a run that lasts that long prints any, and a last
//!   line when such a run ends;
//! - nothing with `--quiet` ([`crate::cli::Console`]).
//!
//! Two environment variables override the choice: `LUXEST_PROGRESS=off|bar|lines` (no
//! progress, the terminal's line, or the log's lines, whatever stderr is; `auto`, the default,
//! chooses by whether stderr is a terminal) and `LUXEST_PROGRESS_INTERVAL=SECONDS` (the log's
//! interval; 0: a line every 10 ms and always the last one, for tests). `--quiet` wins over both.

use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Seconds between two lines of progress in a log, unless `LUXEST_PROGRESS_INTERVAL` says
/// otherwise: a 10-hour Slurm job writes 1200 lines, a 20-second run none.
pub const DEFAULT_INTERVAL: f64 = 30.0;

/// Time between two frames on a terminal (at most 10 frames a second).
const FRAME_PERIOD: Duration = Duration::from_millis(100);

/// The shortest time between two lines in a log (`LUXEST_PROGRESS_INTERVAL=0`).
const SHORTEST_LINE_PERIOD: f64 = 0.01;

/// Units a [`Tally`] gathers before it adds them to its [`Progress`].
const TALLY_UNITS: u64 = 64;

/// Width of the terminal's bar, in characters.
const BAR_WIDTH: usize = 20;

/// How progress is shown.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Display {
    /// Nothing (`--quiet`, `LUXEST_PROGRESS=off`, and every library caller's default).
    Off,
    /// One line redrawn in place on a terminal.
    Bar,
    /// A plain line every `interval` seconds once the run lasts that long, and a last line.
    Lines { interval: f64 },
}

impl Display {
    /// The display of a stage's progress on this process's stderr (see the module
    /// documentation).
    pub fn for_stderr(quiet: bool) -> Display {
        Display::choose(
            quiet,
            std::env::var("LUXEST_PROGRESS").ok().as_deref(),
            std::env::var("LUXEST_PROGRESS_INTERVAL").ok().as_deref(),
            std::io::stderr().is_terminal(),
        )
    }

    /// The display given `--quiet`, the two environment variables' values and whether stderr
    /// is a terminal. An unknown mode is `auto`, an interval that is not a number ≥ 0 the
    /// default.
    pub fn choose(
        quiet: bool,
        mode: Option<&str>,
        interval: Option<&str>,
        terminal: bool,
    ) -> Display {
        let interval = interval
            .and_then(|s| s.trim().parse::<f64>().ok())
            .filter(|s| *s >= 0.0 && s.is_finite())
            .unwrap_or(DEFAULT_INTERVAL);
        match (quiet, mode.map(str::trim)) {
            (true, _) | (false, Some("off")) => Display::Off,
            (false, Some("bar")) => Display::Bar,
            (false, Some("lines")) => Display::Lines { interval },
            _ if terminal => Display::Bar,
            _ => Display::Lines { interval },
        }
    }
}

/// The progress of one stretch of work: `total` units (or an unknown number) counted by
/// [`Progress::inc`] from any thread, shown as [`Display`] says until the value is dropped or
/// [`Progress::finish`]ed.
pub struct Progress {
    shared: Option<Arc<Shared>>,
    drawer: Option<JoinHandle<()>>,
}

struct Shared {
    label: String,
    unit: &'static str,
    /// The units to do; [`UNKNOWN`] when not known (a run for a given time).
    total: AtomicU64,
    /// Seconds the run may take at most (`trace --time`), as f64 bits; 0: none.
    budget: AtomicU64,
    done: AtomicU64,
    start: Instant,
    display: Display,
    stop: Mutex<bool>,
    wake: Condvar,
    sink: Mutex<Box<dyn Write + Send>>,
}

/// [`Shared::total`] of work whose size is not known.
const UNKNOWN: u64 = u64::MAX;

impl Progress {
    /// Progress that shows nothing: what library callers and tests pass.
    pub fn off() -> Progress {
        Progress {
            shared: None,
            drawer: None,
        }
    }

    /// The progress of `label`'s work (`trace`, `estimate sensors`) of `total` `unit`s
    /// (`samples`, `paths`; `None`: not known), drawn on stderr as `display` says.
    pub fn new(
        label: impl Into<String>,
        total: Option<u64>,
        unit: &'static str,
        display: Display,
    ) -> Progress {
        Progress::to_sink(label, total, unit, display, Box::new(std::io::stderr()))
    }

    /// [`Progress::new`] drawn into `sink` (the tests' buffer).
    fn to_sink(
        label: impl Into<String>,
        total: Option<u64>,
        unit: &'static str,
        display: Display,
        sink: Box<dyn Write + Send>,
    ) -> Progress {
        if display == Display::Off {
            return Progress::off();
        }
        let shared = Arc::new(Shared {
            label: label.into(),
            unit,
            total: AtomicU64::new(total.unwrap_or(UNKNOWN)),
            budget: AtomicU64::new(0),
            done: AtomicU64::new(0),
            start: Instant::now(),
            display,
            stop: Mutex::new(false),
            wake: Condvar::new(),
            sink: Mutex::new(sink),
        });
        let drawer = {
            let shared = Arc::clone(&shared);
            std::thread::Builder::new()
                .name("progress".into())
                .spawn(move || shared.draw_until_stopped())
                .ok()
        };
        Progress {
            shared: drawer.is_some().then_some(shared),
            drawer,
        }
    }

    /// Counts `n` more units done.
    #[inline]
    pub fn inc(&self, n: u64) {
        if let Some(s) = &self.shared {
            s.done.fetch_add(n, Ordering::Relaxed);
        }
    }

    /// Sets the units to do (when a run learns its size on the way).
    pub fn set_total(&self, total: u64) {
        if let Some(s) = &self.shared {
            s.total.store(total, Ordering::Relaxed);
        }
    }

    /// Prints `line` on stderr while the progress is shown: on a terminal above its line
    /// (erased, then redrawn by the next frame), in a log as a line of its own.
    pub fn println(&self, line: &str) {
        match &self.shared {
            Some(s) if s.display == Display::Bar => s.write(&format!("\r\x1b[K{line}\n")),
            Some(s) => s.write(&format!("{line}\n")),
            None => eprintln!("{line}"),
        }
    }

    /// Bounds the run's time (a render for a time, `trace --time`): the fraction done is at
    /// least the time spent over `seconds`, the time left at most what remains of them.
    pub fn set_time_budget(&self, seconds: f64) {
        if let Some(s) = &self.shared {
            s.budget
                .store(seconds.max(0.0).to_bits(), Ordering::Relaxed);
        }
    }

    /// A counter for one worker's fine-grained loop (see [`Tally`]).
    pub fn tally(&self) -> Tally<'_> {
        Tally {
            progress: self,
            pending: 0,
        }
    }

    /// Ends the display: the terminal's line is erased, a log gets its last line (when the run
    /// lasted at least the interval). Dropping the progress does the same.
    pub fn finish(self) {}
}

impl Drop for Progress {
    fn drop(&mut self) {
        if let Some(s) = &self.shared {
            *s.stop.lock().unwrap_or_else(|e| e.into_inner()) = true;
            s.wake.notify_all();
        }
        if let Some(d) = self.drawer.take() {
            let _ = d.join();
        }
    }
}

/// Counts a worker's units and adds them to its [`Progress`] 64 at a time (and the rest when
/// dropped): a loop over light paths of a few microseconds each then shares no cache line with
/// the other workers' on every path.
pub struct Tally<'a> {
    progress: &'a Progress,
    pending: u64,
}

impl Tally<'_> {
    /// Counts `n` more units done.
    #[inline]
    pub fn add(&mut self, n: u64) {
        self.pending += n;
        if self.pending >= TALLY_UNITS {
            self.progress.inc(std::mem::take(&mut self.pending));
        }
    }
}

impl Drop for Tally<'_> {
    fn drop(&mut self) {
        self.progress.inc(self.pending);
    }
}

impl Shared {
    /// The drawing thread: a frame or a line per period until the progress is dropped, then
    /// the end of the display.
    fn draw_until_stopped(&self) {
        let period = match self.display {
            Display::Lines { interval } => {
                Duration::from_secs_f64(interval.max(SHORTEST_LINE_PERIOD))
            }
            _ => FRAME_PERIOD,
        };
        let mut drawn = false;
        loop {
            let stop = self.stop.lock().unwrap_or_else(|e| e.into_inner());
            let (stop, _) = self
                .wake
                .wait_timeout_while(stop, period, |stop| !*stop)
                .unwrap_or_else(|e| e.into_inner());
            if *stop {
                break;
            }
            drop(stop);
            self.draw(false);
            drawn = true;
        }
        let elapsed = self.start.elapsed().as_secs_f64();
        match self.display {
            Display::Bar if drawn => self.write("\r\x1b[K"),
            Display::Lines { interval } if elapsed >= interval => self.draw(true),
            _ => {}
        }
    }

    /// Draws the current state: a frame on a terminal, a line in a log (`last`: the run's end).
    fn draw(&self, last: bool) {
        let total = self.total.load(Ordering::Relaxed);
        let state = State {
            label: &self.label,
            unit: self.unit,
            done: self.done.load(Ordering::Relaxed),
            total: (total != UNKNOWN).then_some(total),
            budget: Some(f64::from_bits(self.budget.load(Ordering::Relaxed))).filter(|b| *b > 0.0),
            elapsed: self.start.elapsed().as_secs_f64(),
        };
        let text = match self.display {
            Display::Bar => format!("\r{}\x1b[K", fit(&state.frame(), terminal_width() - 1)),
            _ => state.line(last) + "\n",
        };
        self.write(&text);
    }

    /// Writes `text` in one piece; a failed write (stderr closed) is ignored: progress is no
    /// output of the run.
    fn write(&self, text: &str) {
        let mut sink = self.sink.lock().unwrap_or_else(|e| e.into_inner());
        let _ = sink.write_all(text.as_bytes()).and_then(|()| sink.flush());
    }
}

/// What one frame or line shows.
#[derive(Clone, Copy, Debug)]
struct State<'a> {
    label: &'a str,
    unit: &'a str,
    done: u64,
    total: Option<u64>,
    /// Seconds the run may take at most ([`Progress::set_time_budget`]).
    budget: Option<f64>,
    /// Seconds since the work started.
    elapsed: f64,
}

impl State<'_> {
    /// The units done per second so far.
    fn rate(&self) -> f64 {
        if self.elapsed > 0.0 {
            self.done as f64 / self.elapsed
        } else {
            0.0
        }
    }

    /// The fraction done: of the total, or of the time budget when that is further along.
    fn fraction(&self) -> Option<f64> {
        let of_total = self.total.map(|t| self.done as f64 / t.max(1) as f64);
        let of_time = self.budget.map(|b| self.elapsed / b);
        match (of_total, of_time) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        }
        .map(|f| f.clamp(0.0, 1.0))
    }

    /// Seconds left at the rate so far, once some work is done, and at most what remains of
    /// the time budget.
    fn left(&self) -> Option<f64> {
        let by_rate = self
            .total
            .filter(|_| self.done > 0)
            .map(|total| self.elapsed * total.saturating_sub(self.done) as f64 / self.done as f64);
        let by_time = self.budget.map(|b| (b - self.elapsed).max(0.0));
        match (by_rate, by_time) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// What is counted: `27.5M/65.5M samples` (`of` = `/`) or `27.5M samples` without a total.
    fn counted(&self, of: &str) -> String {
        match self.total {
            Some(total) => format!(
                "{}{of}{} {}",
                show_si_count(self.done),
                show_si_count(total),
                self.unit
            ),
            None => format!("{} {}", show_si_count(self.done), self.unit),
        }
    }

    /// The terminal's frame, most important first (a narrow terminal cuts the end):
    /// `trace [=========>          ] 42% ~0:31 left, 1.23M samples/s, 0:22 elapsed, 27.5M/65.5M samples`.
    fn frame(&self) -> String {
        let rate = format!("{} {}/s", show_si(self.rate()), self.unit);
        let elapsed = format!("{} elapsed", clock(self.elapsed));
        match self.fraction() {
            Some(f) => {
                let full = ((f * BAR_WIDTH as f64).floor() as usize).min(BAR_WIDTH);
                let head = if full < BAR_WIDTH { ">" } else { "" };
                let bar = format!(
                    "{}{head}{}",
                    "=".repeat(full),
                    " ".repeat(BAR_WIDTH - full - head.len())
                );
                let left = self.left().map_or("--:--".into(), clock);
                format!(
                    "{} [{bar}] {:>3.0}% ~{left} left, {rate}, {elapsed}, {}",
                    self.label,
                    (f * 100.0).floor(),
                    self.counted("/")
                )
            }
            None => format!("{}: {}, {rate}, {elapsed}", self.label, self.counted("/")),
        }
    }

    /// The log's line: `trace: 42% (27.5M of 65.5M samples), 1.23M samples/s, 0:22 elapsed,
    /// ~0:31 left`; `last`: the run's end (`..., 0:53 elapsed, done`).
    fn line(&self, last: bool) -> String {
        let rate = format!("{} {}/s", show_si(self.rate()), self.unit);
        let end = if last {
            "done".to_string()
        } else {
            match self.left() {
                Some(left) => format!("~{} left", clock(left)),
                None => String::new(),
            }
        };
        let counted = match self.fraction() {
            Some(f) => format!("{:.0}% ({})", (f * 100.0).floor(), self.counted(" of ")),
            None => self.counted(" of "),
        };
        let mut line = format!(
            "{}: {counted}, {rate}, {} elapsed",
            self.label,
            clock(self.elapsed)
        );
        if !end.is_empty() {
            line += ", ";
            line += &end;
        }
        line
    }
}

/// A count: whole below 1000, else three significant digits with an SI prefix (`45.1k`).
fn show_si_count(n: u64) -> String {
    if n < 1000 {
        n.to_string()
    } else {
        show_si(n as f64)
    }
}

/// A rate or count with three significant digits and an SI prefix: `0.31`, `812`, `45.1k`,
/// `1.23M`.
fn show_si(v: f64) -> String {
    const PREFIXES: [&str; 6] = ["", "k", "M", "G", "T", "P"];
    let mut v = v.max(0.0);
    let mut p = 0;
    while v >= 999.5 && p + 1 < PREFIXES.len() {
        v /= 1000.0;
        p += 1;
    }
    if v < 9.995 {
        format!("{v:.2}{}", PREFIXES[p])
    } else if v < 99.95 {
        format!("{v:.1}{}", PREFIXES[p])
    } else {
        format!("{v:.0}{}", PREFIXES[p])
    }
}

/// Seconds as a clock: `0:07`, `12:34`, `3:02:01` (hours past 24 keep counting: `51:00:00`).
fn clock(seconds: f64) -> String {
    let s = seconds.clamp(0.0, 1e9).round() as u64;
    let (h, m, s) = (s / 3600, s / 60 % 60, s % 60);
    if h > 0 {
        format!("{h}:{m:02}:{s:02}")
    } else {
        format!("{m}:{s:02}")
    }
}

/// `text` in `width` characters: whole, or cut before the last `, ` that leaves it within
/// them (a frame's parts are separated so), or else cut at `width`.
fn fit(text: &str, width: usize) -> &str {
    match text.char_indices().nth(width) {
        Some((i, _)) => {
            let cut = &text[..i];
            cut.rfind(", ").map_or(cut, |j| &cut[..j])
        }
        None => text,
    }
}

/// Columns of the terminal on stderr (`TIOCGWINSZ`), else `COLUMNS`, else 80; at least 20.
fn terminal_width() -> usize {
    #[cfg(all(
        target_os = "linux",
        any(target_arch = "x86_64", target_arch = "x86", target_arch = "aarch64")
    ))]
    {
        #[repr(C)]
        struct Winsize {
            rows: u16,
            columns: u16,
            x_pixels: u16,
            y_pixels: u16,
        }
        extern "C" {
            fn ioctl(
                fd: std::os::raw::c_int,
                request: std::os::raw::c_ulong,
                ...
            ) -> std::os::raw::c_int;
        }
        // Linux's asm-generic/ioctls.h (x86 and arm64 alike): TIOCGWINSZ 0x5413.
        const TIOCGWINSZ: std::os::raw::c_ulong = 0x5413;
        let mut size = Winsize {
            rows: 0,
            columns: 0,
            x_pixels: 0,
            y_pixels: 0,
        };
        // SAFETY: TIOCGWINSZ writes one `struct winsize` (four unsigned shorts) through the
        // pointer, which points at one; on a descriptor that is not a terminal it fails and
        // writes nothing.
        let ok = unsafe { ioctl(2, TIOCGWINSZ, &mut size as *mut Winsize) } == 0;
        if ok && size.columns > 0 {
            return (size.columns as usize).max(20);
        }
    }
    std::env::var("COLUMNS")
        .ok()
        .and_then(|c| c.trim().parse::<usize>().ok())
        .unwrap_or(80)
        .max(20)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sink the tests read back.
    #[derive(Clone, Default)]
    struct Buffer(Arc<Mutex<Vec<u8>>>);

    impl Write for Buffer {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            self.0.lock().unwrap().extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    impl Buffer {
        fn text(&self) -> String {
            String::from_utf8(self.0.lock().unwrap().clone()).unwrap()
        }
    }

    #[test]
    fn quiet_wins_and_stderr_chooses_between_bar_and_lines() {
        let lines = Display::Lines {
            interval: DEFAULT_INTERVAL,
        };
        assert_eq!(Display::choose(true, Some("bar"), None, true), Display::Off);
        assert_eq!(Display::choose(false, None, None, true), Display::Bar);
        assert_eq!(Display::choose(false, None, None, false), lines);
        assert_eq!(Display::choose(false, Some("auto"), None, false), lines);
        assert_eq!(
            Display::choose(false, Some("bar"), None, false),
            Display::Bar
        );
        assert_eq!(Display::choose(false, Some("lines"), None, true), lines);
        assert_eq!(
            Display::choose(false, Some("off"), None, true),
            Display::Off
        );
        assert_eq!(
            Display::choose(false, None, Some("0.5"), false),
            Display::Lines { interval: 0.5 }
        );
        for bad in ["-1", "soon", "inf", "NaN"] {
            assert_eq!(
                Display::choose(false, None, Some(bad), false),
                lines,
                "{bad}"
            );
        }
    }

    #[test]
    fn frames_and_lines_say_fraction_rate_elapsed_and_time_left() {
        let state = State {
            label: "trace",
            unit: "samples",
            done: 27_500_000,
            total: Some(65_500_000),
            budget: None,
            elapsed: 22.0,
        };
        assert_eq!(
            state.line(false),
            "trace: 41% (27.5M of 65.5M samples), 1.25M samples/s, 0:22 elapsed, ~0:30 left"
        );
        assert_eq!(
            state.frame(),
            "trace [========>           ]  41% ~0:30 left, 1.25M samples/s, 0:22 elapsed, \
             27.5M/65.5M samples"
        );
        let end = State {
            done: 65_500_000,
            elapsed: 52.4,
            ..state
        };
        assert_eq!(
            end.line(true),
            "trace: 100% (65.5M of 65.5M samples), 1.25M samples/s, 0:52 elapsed, done"
        );
        assert!(end
            .frame()
            .starts_with("trace [====================] 100% ~0:00 left"));
        let open = State {
            total: None,
            ..state
        };
        assert_eq!(
            open.line(false),
            "trace: 27.5M samples, 1.25M samples/s, 0:22 elapsed"
        );
        // A render for a time (trace --time 60): the budget is the fraction and the time left.
        let timed = State {
            budget: Some(60.0),
            ..open
        };
        assert_eq!(
            timed.line(false),
            "trace: 36% (27.5M samples), 1.25M samples/s, 0:22 elapsed, ~0:38 left"
        );
        assert!(timed
            .frame()
            .starts_with("trace [=======>            ]  36% ~0:38 left, "));
        // With a total too, whichever is further along.
        assert!(State {
            budget: Some(30.0),
            ..state
        }
        .line(false)
        .starts_with(
            "trace: 73% (27.5M of 65.5M samples), 1.25M samples/s, 0:22 elapsed, ~0:08 left"
        ));
        assert_eq!(
            State {
                done: 0,
                elapsed: 0.0,
                ..state
            }
            .line(false),
            "trace: 0% (0 of 65.5M samples), 0.00 samples/s, 0:00 elapsed"
        );
        assert_eq!(show_si(812.0), "812");
        assert_eq!(show_si(0.314), "0.31");
        assert_eq!(show_si(31.44), "31.4");
        assert_eq!(show_si_count(12), "12");
        assert_eq!(show_si_count(45_123), "45.1k");
        assert_eq!(show_si(999.6), "1.00k");
        assert_eq!(show_si(45_123.0), "45.1k");
        assert_eq!(show_si(123_456.0), "123k");
        assert_eq!(clock(7.4), "0:07");
        assert_eq!(clock(3.0 * 3600.0 + 121.0), "3:02:01");
        assert_eq!(
            fit("trace [===] 5%, ~0:01 left", 26),
            "trace [===] 5%, ~0:01 left"
        );
        assert_eq!(fit("trace [===] 5%, ~0:01 left", 20), "trace [===] 5%");
        assert_eq!(fit("trace [===] 5%", 5), "trace");
    }

    #[test]
    fn logs_get_plain_periodic_lines_and_a_last_one() {
        let sink = Buffer::default();
        let p = Progress::to_sink(
            "estimate sensors",
            Some(1000),
            "paths",
            Display::Lines { interval: 0.02 },
            Box::new(sink.clone()),
        );
        for _ in 0..10 {
            std::thread::sleep(Duration::from_millis(10));
            p.inc(100);
        }
        p.finish();
        let text = sink.text();
        assert!(!text.contains('\r') && !text.contains('\x1b'), "{text:?}");
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines.len() >= 2, "{text:?}");
        assert!(lines.iter().all(|l| l.starts_with("estimate sensors: ")));
        assert!(
            lines
                .last()
                .unwrap()
                .starts_with("estimate sensors: 100% (1.00k of 1.00k paths)")
                && lines.last().unwrap().ends_with(", done"),
            "{text:?}"
        );
    }

    #[test]
    fn a_log_of_a_short_run_gets_nothing() {
        let sink = Buffer::default();
        let p = Progress::to_sink(
            "trace",
            Some(10),
            "samples",
            Display::Lines { interval: 30.0 },
            Box::new(sink.clone()),
        );
        p.inc(10);
        p.finish();
        assert_eq!(sink.text(), "");
    }

    #[test]
    fn terminals_get_frames_redrawn_in_place_at_most_ten_a_second_then_erased() {
        let sink = Buffer::default();
        let p = Progress::to_sink(
            "trace",
            Some(100),
            "samples",
            Display::Bar,
            Box::new(sink.clone()),
        );
        let start = Instant::now();
        for _ in 0..50 {
            std::thread::sleep(Duration::from_millis(7));
            p.inc(2);
        }
        p.finish();
        let seconds = start.elapsed().as_secs_f64();
        let text = sink.text();
        assert!(!text.contains('\n'), "{text:?}");
        let frames = text.matches('\r').count() - 1;
        assert!(
            frames >= 1 && frames as f64 <= 10.0 * seconds + 1.0,
            "{frames} in {seconds} s"
        );
        assert!(text.starts_with("\rtrace ["), "{text:?}");
        assert!(text.ends_with("\r\x1b[K"), "{text:?}");
    }

    #[test]
    fn tallies_add_everything_counted() {
        let sink = Buffer::default();
        let p = Progress::to_sink(
            "x",
            None,
            "paths",
            Display::Lines { interval: 0.0 },
            Box::new(sink.clone()),
        );
        std::thread::scope(|s| {
            for _ in 0..4 {
                s.spawn(|| {
                    let mut t = p.tally();
                    for _ in 0..1001 {
                        t.add(1);
                    }
                });
            }
        });
        p.finish();
        assert!(
            sink.text()
                .lines()
                .last()
                .unwrap()
                .starts_with("x: 4.00k paths"),
            "{}",
            sink.text()
        );
        // Off: counting is a no-op.
        let off = Progress::off();
        off.tally().add(5);
        off.inc(3);
    }
}
