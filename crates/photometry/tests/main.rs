//! The photometry crate's integration tests, compiled as one binary (one link instead of five).

mod common;
mod grid_stats;
mod illuminance;
mod isolux;
mod parsers;
mod sampling;
