fn main() -> std::process::ExitCode {
    luxest_io::cli::main(scene_compile::run)
}
