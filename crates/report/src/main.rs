fn main() -> std::process::ExitCode {
    // `report ugr-table FILE` is a subcommand of its own; `report RESULTS ...` the report.
    let argv: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if argv.get(1).is_some_and(|a| a == "ugr-table") {
        let rest = std::iter::once(std::ffi::OsString::from("report ugr-table"))
            .chain(argv.into_iter().skip(2));
        return luxest_io::cli::main_from(rest.collect::<Vec<_>>(), report::ugr_table::run);
    }
    luxest_io::cli::main(report::cli::run)
}
