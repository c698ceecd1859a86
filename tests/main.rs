//! Cross-stage integration tests, compiled as one binary (as in ripgrep).
//! Helpers live in `util`; each stage has its own module.

mod architecture;
mod contract;
mod daylight;
mod denoise_cli;
mod emitters;
mod estimate_cli;
mod estimate_validation;
mod evaluate_cli;
mod glare;
mod light_sampling;
mod lighting;
mod luminaires;
mod metrics_parity;
mod normals;
mod portals;
mod progress;
mod reliability;
mod reliability_processes;
mod scene_compile_errors;
mod scene_compile_scenes;
mod textures;
mod trace_exact;
mod util;
