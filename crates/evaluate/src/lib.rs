//! evaluate: error of images against references (PSNR, SSIM, MS-SSIM, FLIP on tonemapped
//! images; relMSE and SMAPE on linear values) and of sensor results against exact values, as
//! CSV and RON reports. The metrics are checked against scikit-image, pytorch_msssim and
//! NVIDIA's flip-evaluator on fixtures (crates/evaluate/tests/metrics_parity.rs).

pub mod cli;
pub mod metrics;
pub mod report;
