//! estimate: the local estimate of illuminance at sensor points, the double local estimate of
//! luminance images, light tracing, a backward reference estimator and a direct-simulation
//! baseline.
//!
//! Subcommands: `sensors` (local estimate), `image` (double local estimate, or light tracing
//! with `--light-tracing`), `direct` (direct simulation: photon counting), `gather` (backward
//! reference estimator), `exact` (print exact solutions). Results are compared with exact
//! solutions by `evaluate sensors`.
//!
//! Modules, one per method: [`local_estimate`], [`double_local_estimate`], [`light_tracing`],
//! [`direct_simulation`], [`gather`]; what they share: [`transport`] (the light-path walk and
//! the exact point-source light), [`sensor_batches`] (batches of light paths at sensor points
//! and their standard errors), [`image`] (the image estimators' result), [`singularity`] (the
//! kernel's treatment); [`placement`] and [`sensors`] (sensor points and the results
//! contract), [`work`] (each run's work and memory, predicted before it starts), [`glare`] (UGR at the
//! scene's observers, from the local estimate's indirect part at the eye), [`exact_table`]
//! (`estimate exact`), [`cli`] (arguments and runs).
//!
//! Dependencies run one way: `cli` → the methods → `transport`, `sensor_batches`, `image`;
//! `double_local_estimate` uses `light_tracing`'s camera connection for its multiple
//! importance sampling; `local_estimate` uses `gather`'s near-field sample.

pub mod cli;
pub mod direct_simulation;
pub mod double_local_estimate;
pub mod exact_table;
pub mod gather;
pub mod glare;
pub mod image;
pub mod light_tracing;
pub mod local_estimate;
pub mod placement;
pub mod sensor_batches;
pub mod sensors;
pub mod singularity;
pub mod transport;
pub mod work;

pub use cli::{run, Args};
pub use sensors::all_sensors;
