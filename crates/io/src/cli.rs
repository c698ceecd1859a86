//! Command-line plumbing shared by the stage binaries, so that every stage behaves the same:
//! `--help` exits 0, usage errors print clap's message and exit 2, any other failure prints one
//! `error: <file>: <place>: <problem>` line and exits 1. Nothing panics on bad input.

use crate::error::Error;
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
    let result = parse::<A>(std::env::args_os()).and_then(|a| match a {
        Some(a) => run(a),
        None => Ok(()),
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Error::Usage(m)) => {
            // clap's own rendering is multi-line on purpose (usage + hint); keep it.
            eprintln!("{}", m.trim_end());
            ExitCode::from(2)
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
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
}

impl CommonArgs {
    /// The number of worker threads to use: `--threads`, or all available cores.
    pub fn thread_count(&self) -> usize {
        thread_count(self.threads)
    }
}

/// The number of worker threads: `requested`, or all available cores.
pub fn thread_count(requested: Option<usize>) -> usize {
    requested.filter(|&t| t > 0).unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    })
}
