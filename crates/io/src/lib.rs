//! luxest-io: the I/O and the contracts every luxest stage shares. It links no Embree, so a
//! stage that never traces a ray (`denoise`, `evaluate`, or a researcher's replacement for one)
//! builds without it.
//!
//! - [`error`], [`cli`]: one-line errors, exit codes and the shared command-line behaviour;
//! - [`fsio`]: atomic output files, RON reading and writing;
//! - [`meta`], [`header`]: run metadata carried by every Monte Carlo artifact, and every
//!   `luxest.*` header key with its typed reading and writing;
//! - [`naming`]: the file names stages exchange (`<name>_<spp>spp.<kind>.exr`, ...);
//! - [`outputs`]: the output plan every stage makes before writing (no output over an input,
//!   another output or a non-regular file; all outputs of a run committed together);
//! - [`limits`]: the resource rule: buffers sized against the memory available before
//!   allocating, and the one-line plan of a long run;
//! - [`progress`]: the progress of a long run on stderr (a line redrawn on a terminal, periodic
//!   lines in a log);
//! - [`num`]: validated numbers for command-line options (finite, in range, unit in messages);
//! - [`image`]: the linear RGB image every stage exchanges, with its header attributes;
//! - [`exposure`]: the exposure contract shared with Python (autoexposure, dim-image exponent);
//! - [`exr`]: OpenEXR reading and writing (f32 RGB, ZIP scanlines, header attributes);
//! - [`png`]: PNG previews of linear images, and the PNG encoder of 8-bit sRGB rasters;
//! - [`texture_image`]: decoding of bitmap texture images (PNG, JPEG, OpenEXR) with their size
//!   checked before allocating;
//! - [`sensors`]: sensor results (RON + CSV), with glare ratings and the sky's figures;
//! - [`requirements`]: a calculation surface's EN 12464-1 / EN 17037 requirements (scene →
//!   compiled scene → report);
//! - [`math`], [`color`]: f64 vectors and transforms, RGB, luminance and the sRGB transfer
//!   function;
//! - [`chi2`]: a test utility, the chi-square test every sampling routine's tests call (no stage
//!   uses it).
//!
//! Invariant: no stage depends on another stage's crate; whatever two stages exchange is read and
//! written through this crate.

pub mod chi2;
pub mod cli;
pub mod color;
pub mod error;
pub mod exposure;
pub mod exr;
pub mod fsio;
pub mod header;
pub mod image;
pub mod limits;
pub mod math;
pub mod meta;
pub mod naming;
pub mod num;
pub mod outputs;
pub mod png;
pub mod progress;
pub mod requirements;
pub mod sensors;
pub mod texture_image;

pub use error::{Error, Result};
