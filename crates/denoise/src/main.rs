fn main() -> std::process::ExitCode {
    luxest_core::cli::main(denoise::cli::run)
}
