//! aov-write: the denoiser's auxiliary features, albedo and shading normal of the first
//! non-delta surface (through mirrors and smooth glass, as Intel Open Image Denoise
//! recommends; [`first_hit`]), optionally the first hit's depth, and the emitted radiance seen
//! directly or in a mirror, averaged over the pixel samples
//! `trace` uses ([`luxest_render::camera::pixel_jitter`] with the same seed), written in the Intel
//! Open Image Denoise training-toolkit layout: `<prefix>_<spp>spp.alb.exr`, `.emi.exr`,
//! `.nrm.exr` (and `_ref.`). The emission averages exactly the image's samples; albedo, normal
//! and depth at least `--min-samples` (trace's first samples and the next ones of the same
//! sequence), so that a denoiser gets antialiased features of a 1-spp image.
//!
//! Conventions (as OIDN expects): albedo in [0, 1] — the reflectance of diffuse surfaces, the
//! sum diffuse + specular of glossy ones; through a mirror its reflectance times what it shows,
//! through smooth glass the Fresnel blend of both sides (a later dielectric: its likelier side);
//! black where nothing is hit. Normals are world-space unit shading normals facing the camera,
//! components in [−1, 1]; zero where nothing is hit. Depth is the distance along the ray (m),
//! zero where nothing is hit.
//!
//! Modules: [`cli`] (arguments and run), [`features`] (first-hit features and their sums).

pub mod cli;
pub mod features;

pub use cli::{run, Args, ESTIMATOR};
pub use features::{albedo, first_hit, FeatureFilm};
