fn main() -> std::process::ExitCode {
    luxest_core::cli::main(scene_compile::run)
}
