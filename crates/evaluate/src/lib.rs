//! evaluate: error of images against references (PSNR, SSIM, MS-SSIM, FLIP on tonemapped
//! images; relMSE and SMAPE on linear values) and of sensor results against exact values, as
//! CSV and RON reports. The metrics are checked against scikit-image, pytorch_msssim and
//! NVIDIA's flip-evaluator on fixtures (`tests/metrics_parity.rs` of the workspace).
//!
//! Modules: [`cli`] (arguments and runs), [`images`] and [`sensors`] (the two reports),
//! [`metrics`] (one metric per file). Invariant: evaluate links no Embree and reads no scene —
//! it depends on `luxest-io` and `luxest-exact` only (checked by `tests/architecture.rs`).

pub mod cli;
pub mod images;
pub mod metrics;
pub mod sensors;
