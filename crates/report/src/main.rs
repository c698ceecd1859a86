fn main() -> std::process::ExitCode {
    luxest_io::cli::main(report::cli::run)
}
