fn main() -> std::process::ExitCode {
    luxest_core::cli::main(aov_write::run)
}
