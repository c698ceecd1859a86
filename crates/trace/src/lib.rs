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
pub use luxest_render::world::load_with_camera as load;
pub use renderer::{pixel_sampler, Renderer, TILE};
