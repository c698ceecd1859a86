//! Command-line plumbing shared by the stage binaries, so that every stage behaves the same:
//! `--help` exits 0, usage errors print clap's message and exit 2, any other failure prints one
//! `error: <file>: <place>: <problem>` line and exits 1. Nothing panics on bad input.

use crate::error::Error;
use crate::limits::WorkPlan;
use crate::progress::{Display, Progress};
use clap::Parser;
use std::ffi::OsString;
use std::process::ExitCode;

/// Parses `argv` (including the program name) into `A`; usage errors become [`Error::Usage`],
/// `--help`/`--version` become `Ok(None)` after printing.
pub fn parse<A: Parser>(
    argv: impl IntoIterator<Item = impl Into<OsString> + Clone>,
) -> Result<Option<A>, Error> {
    match A::try_parse_from(argv) {
        Ok(a) => Ok(Some(a)),
        Err(e) if e.exit_code() == 0 => {
            let _ = e.print();
            Ok(None)
        }
        Err(e) => Err(Error::Usage(e.render().to_string())),
    }
}

/// The whole `main` of a stage binary: parse the process arguments, run, report.
pub fn main<A: Parser>(run: impl FnOnce(A) -> Result<(), Error>) -> ExitCode {
    main_from(std::env::args_os(), run)
}

/// [`main`] over `argv` (the program name first), returning the exit status: what a stage
/// binary does, also for the tests that run a stage as a process of its own (to kill it, limit
/// it, or read its stderr).
pub fn main_from<A: Parser>(
    argv: impl IntoIterator<Item = impl Into<OsString> + Clone>,
    run: impl FnOnce(A) -> Result<(), Error>,
) -> ExitCode {
    ExitCode::from(exit_status(argv, run))
}

/// The exit status of [`main_from`] as a number (0, 1 or 2).
pub fn exit_status<A: Parser>(
    argv: impl IntoIterator<Item = impl Into<OsString> + Clone>,
    run: impl FnOnce(A) -> Result<(), Error>,
) -> u8 {
    prepare_process();
    let result = parse::<A>(argv).and_then(|a| match a {
        Some(a) => run(a),
        None => Ok(()),
    });
    match result {
        Ok(()) => 0,
        Err(Error::Usage(m)) => {
            eprintln!("{}", usage_message(&m));
            2
        }
        Err(e) => {
            eprintln!("error: {e}");
            e.exit_code()
        }
    }
}

/// Makes an exceeded file-size limit (`ulimit -f`) an error of the write that exceeds it: by
/// default SIGXFSZ ends the process on the spot, which left the output's temporary
/// `.NAME.tmp-…` behind; ignored, the write fails with EFBIG ("File too large"), and the run
/// reports it in one line naming the file and removes its temporaries like any failed write.
fn prepare_process() {
    #[cfg(all(
        target_os = "linux",
        any(
            target_arch = "x86_64",
            target_arch = "x86",
            target_arch = "aarch64",
            target_arch = "arm",
            target_arch = "riscv64"
        )
    ))]
    {
        extern "C" {
            fn signal(signum: std::os::raw::c_int, handler: usize) -> usize;
        }
        // Linux's signal.h on these architectures: SIGXFSZ 25; SIG_IGN is the handler 1.
        const SIGXFSZ: std::os::raw::c_int = 25;
        const SIG_IGN: usize = 1;
        // SAFETY: setting a signal's disposition to "ignore" installs no handler code; it is
        // done before the stage starts any thread.
        unsafe {
            signal(SIGXFSZ, SIG_IGN);
        }
    }
}

/// How a usage error is printed: clap's own rendering is multi-line on purpose (usage + hint)
/// and starts with `error:`; a stage's own usage errors get the same prefix.
fn usage_message(m: &str) -> String {
    let m = m.trim_end();
    if m.starts_with("error:") {
        m.to_string()
    } else {
        format!("error: {m}")
    }
}

/// Writes `text` to standard output, the way the stages print tables: a reader that has closed
/// the pipe (`| head`) ends the output quietly, any other failure (a full device) is one
/// `error: <stdout>: …` line; `print!` would panic on both.
pub fn print(text: &str) -> Result<(), Error> {
    print_to(&mut std::io::stdout().lock(), text)
}

/// [`print`] to any writer.
pub fn print_to(out: &mut impl std::io::Write, text: &str) -> Result<(), Error> {
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(Error::io("<stdout>", e)),
        _ => Ok(()),
    }
}

/// Arguments shared by the Monte Carlo stages.
#[derive(clap::Args, Clone, Debug)]
pub struct CommonArgs {
    /// Seed of all random numbers; the same seed gives bit-identical results at any thread count.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads, 1 to 4096; 0 or leaving it out: all cores.
    #[arg(long, value_parser = crate::num::THREADS)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub console: Console,
}

/// What a stage prints on stderr besides its errors: the progress of its work, the plan of a
/// long run, warnings and notes, and its closing `wrote …` line. `-q/--quiet` (every stage's,
/// through [`CommonArgs`] or on its own) silences all of it; errors are printed all the same.
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub struct Console {
    /// Print nothing on stderr but errors: no progress, plan, warnings or summary.
    #[arg(short, long)]
    pub quiet: bool,
}

impl Console {
    /// The console of `--quiet`: what library callers and tests pass.
    pub const QUIET: Console = Console { quiet: true };

    /// The progress of `label`'s work of `total` `unit`s (`None`: not known), shown on stderr
    /// unless quiet ([`crate::progress`]).
    pub fn progress(&self, label: &str, total: Option<u64>, unit: &'static str) -> Progress {
        Progress::new(label, total, unit, Display::for_stderr(self.quiet))
    }

    /// Prints `message` as a line on stderr unless quiet.
    pub fn note(&self, message: impl std::fmt::Display) {
        if !self.quiet {
            eprintln!("{message}");
        }
    }

    /// Prints the plan of a long run ([`WorkPlan::is_long`]) unless quiet.
    pub fn announce(&self, plan: &WorkPlan) {
        if plan.is_long() {
            self.note(plan.line());
        }
    }

    /// [`Console::announce`] while `progress` is shown (a plan made from the run's first
    /// unit of work), above its line.
    pub fn announce_during(&self, plan: &WorkPlan, progress: &Progress) {
        if plan.is_long() && !self.quiet {
            progress.println(&plan.line());
        }
    }
}

impl CommonArgs {
    /// The number of worker threads to use: `--threads`, or all available cores.
    pub fn thread_count(&self) -> usize {
        thread_count(self.threads)
    }
}

/// The number of worker threads: `requested`, or the CPUs this process may run on (its
/// affinity mask and cgroup quota, as `std::thread::available_parallelism` reads them), so that
/// a Slurm step of `--cpus-per-task=8`, bound to eight CPUs, runs eight threads.
pub fn thread_count(requested: Option<usize>) -> usize {
    requested.filter(|&t| t > 0).unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{self, ErrorKind, Write};

    /// A writer that takes `room` bytes, then fails with `kind`.
    struct Failing {
        room: usize,
        kind: ErrorKind,
        got: Vec<u8>,
    }

    fn failing(room: usize, kind: ErrorKind) -> Failing {
        Failing {
            room,
            kind,
            got: vec![],
        }
    }

    impl Write for Failing {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            if self.room == 0 {
                return Err(io::Error::from(self.kind));
            }
            let n = buf.len().min(self.room);
            self.room -= n;
            self.got.extend_from_slice(&buf[..n]);
            Ok(n)
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    #[derive(Parser, Debug)]
    struct Demo {
        #[arg(long)]
        n: u32,
    }

    #[test]
    fn usage_errors_all_start_with_error() {
        // A stage's own usage error and clap's both read `error: …`, clap's once.
        assert_eq!(
            usage_message("give --spp N or --time SECONDS\n"),
            "error: give --spp N or --time SECONDS"
        );
        let clap = match parse::<Demo>(["demo", "--n", "x"]) {
            Err(Error::Usage(m)) => m,
            other => panic!("{other:?}"),
        };
        let shown = usage_message(&clap);
        assert!(
            shown.starts_with("error: ") && !shown.starts_with("error: error:"),
            "{shown}"
        );
    }

    #[test]
    fn printing_ends_quietly_on_a_closed_pipe_and_fails_in_one_line_on_a_full_device() {
        let mut ok = failing(100, ErrorKind::BrokenPipe);
        print_to(&mut ok, "a table\n").unwrap();
        assert_eq!(ok.got, b"a table\n");
        let mut closed = failing(3, ErrorKind::BrokenPipe);
        print_to(&mut closed, "a table\n").unwrap();
        assert_eq!(closed.got, b"a t");
        let mut full = failing(3, ErrorKind::StorageFull);
        let e = print_to(&mut full, "a table\n").unwrap_err();
        let line = e.to_string();
        assert!(
            line.starts_with("<stdout>: ") && !line.contains('\n'),
            "{line}"
        );
        assert_eq!(e.exit_code(), 1);
    }

    /// The child half of `default_threads_follow_the_cpu_affinity`: run alone, it checks
    /// nothing; run by the parent under `taskset`, it checks the count the parent expects.
    #[test]
    fn thread_count_child() {
        if let Ok(expected) = std::env::var("LUXEST_EXPECT_THREADS") {
            assert_eq!(thread_count(None).to_string(), expected);
            assert_eq!(thread_count(Some(3)), 3);
        }
    }

    #[test]
    fn default_threads_follow_the_cpu_affinity() {
        // This test binary again, bound to one CPU (as Slurm binds a step of -c1): the default
        // thread count must be 1 there.
        let exe = std::env::current_exe().unwrap();
        let out = std::process::Command::new("taskset")
            .args(["-c", "0"])
            .arg(&exe)
            .args([
                "--exact",
                "cli::tests::thread_count_child",
                "--test-threads",
                "1",
            ])
            .env("LUXEST_EXPECT_THREADS", "1")
            .output()
            .expect("taskset (util-linux) runs");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{text}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(text.contains("1 passed"), "the child test ran: {text}");
    }
}
