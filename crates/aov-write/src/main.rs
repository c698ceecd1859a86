fn main() -> std::process::ExitCode {
    luxest_io::cli::main(aov_write::run)
}
