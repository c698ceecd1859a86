//! trace: camera path tracing of a compiled scene, progressive, with snapshots.
//!
//! - [`cli`]: the arguments and the run;
//! - [`integrator`]: the path-tracing kernels (next-event estimation with MIS);
//! - [`renderer`]: samples added to a film tile by tile, independent of threads and passes;
//! - [`film`]: per-pixel f64 sums and the standard error of each pixel's luminance;
//! - [`progressive`]: the sample counts a run renders to, for a sample or a time budget;
//! - [`output`]: the images written (`<prefix>_<spp>spp.hdr.exr`, `.se.exr`, preview).

pub mod cli;
pub mod film;
pub mod integrator;
pub mod output;
pub mod progressive;
pub mod renderer;

pub use cli::{run, Args, ESTIMATOR};
pub use film::Film;
/// Loads a compiled scene for path tracing: its world, with Embree's fast traversal (the path
/// tracer's rays start at sampled interior points of surfaces, never on the edges and corners
/// that need the robust mode), and its camera, with an optional `WIDTHxHEIGHT` resolution
/// override, next-event estimation choosing its light through the light BVH. Errors name the
/// scene file.
pub fn load(
    path: &std::path::Path,
    resolution: Option<&str>,
) -> luxest_io::Result<(
    luxest_render::world::World,
    luxest_render::camera::PinholeCamera,
)> {
    use luxest_render::world::{load_with_camera, Traversal};
    let (mut world, camera) = load_with_camera(path, resolution, Traversal::Fast)?;
    world.set_light_sampler(luxest_render::light_bvh::LightSampler::Bvh);
    Ok((world, camera))
}
pub use renderer::{pixel_sampler, Renderer, TILE};
