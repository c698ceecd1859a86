fn main() -> std::process::ExitCode {
    luxest_core::cli::main(trace::run)
}
