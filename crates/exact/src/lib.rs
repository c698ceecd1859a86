//! luxest-exact: closed-form and quadrature solutions of lighting problems, the yardstick every
//! estimator is validated against.
//!
//! - [`quadrature`]: adaptive Gauss–Kronrod integration;
//! - [`solutions`]: Bessel functions, the Sobolev two-plane problem, the integrating sphere,
//!   CIE 171:2006 test cases 5.2 and 5.8;
//! - [`cases`]: named validation cases (`sobolev:I=100,...`) giving each sensor its exact value.
//!
//! Invariant: no Embree, no scene model — this crate depends on `luxest-io` only, so `evaluate`
//! can compare sensor results against exact values without linking the renderer.

pub mod cases;
pub mod quadrature;
pub mod solutions;
