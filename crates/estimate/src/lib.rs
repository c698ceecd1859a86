//! estimate: the local estimate of illuminance at sensor points, the double local estimate of
//! luminance images, a backward reference estimator and a direct-simulation baseline.
//!
//! Subcommands: `sensors` (local estimate), `image` (double local estimate), `direct`
//! (photon counting), `gather` (backward reference estimator), `exact` (print exact solutions).
//! Results are compared with exact solutions by `evaluate sensors`.
//!
//! Modules: [`cli`] (arguments and runs), [`local`], [`image`], [`gather`] (the estimators),
//! [`transport`] (the random-walk step and exact point-source light they share),
//! [`singularity`], [`placement`], [`sensors`] (sensor points and the results contract),
//! [`exact_table`].

pub mod cli;
pub mod exact_table;
pub mod gather;
pub mod image;
pub mod light_trace;
pub mod local;
pub mod placement;
pub mod sensors;
pub mod singularity;
pub mod transport;

pub use cli::{run, Args};
pub use sensors::all_sensors;
