//! luxest-core: the types and services every luxest stage shares.
//!
//! - [`scene`]: the authored scene format (RON) that people and `data-gen` write;
//! - [`compiled`]: the compiled, world-space scene every rendering stage reads;
//! - [`math`], [`color`], [`sampling`]: f64 vectors and transforms, RGB/luminance, seeded RNG
//!   and sampling routines;
//! - [`fsio`], [`exr_io`], [`meta`]: atomic output, RON and EXR I/O, run metadata;
//! - [`rt`]: the one wrapper around Embree;
//! - [`error`], [`cli`]: one-line errors and the shared command-line behaviour.
//!
//! Invariant: no stage depends on another stage's crate; whatever two stages share lives here.

pub mod bsdf;
pub mod camera;
pub mod cli;
pub mod color;
pub mod compiled;
pub mod error;
pub mod exact;
pub mod exact_case;
pub mod exr_io;
pub mod fsio;
pub mod math;
pub mod meta;
pub mod parallel;
pub mod quadrature;
pub mod rt;
pub mod sampling;
pub mod scene;
pub mod sensors;
pub mod world;

pub use error::{Error, Result};
