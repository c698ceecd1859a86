fn main() -> std::process::ExitCode {
    luxest_core::cli::main(evaluate::cli::run)
}
