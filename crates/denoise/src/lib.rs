//! denoise: noisy radiance (hdr) plus albedo and normal features → a denoised radiance image,
//! with a U-Net exported by `training/export.py`, run through ONNX Runtime (`ort`, library
//! loaded at run time).
//!
//! The model contract (ARCHITECTURE.md, Models; training/transfer.py): input `input` float32
//! NCHW with the channels named in the metadata key `luxest.channels` (hdr[,alb[,nrm]]), raw
//! linear values, any H and W; input `exposure` float32 (N,), the autoexposure of the *whole*
//! image ([`RgbImage::autoexposure`]); output `output` float32 N×3×H×W linear radiance. The
//! transfer function and the padding to multiples of 16 are inside the graph.
//!
//! Large images are denoised in tiles: each tile's core is extended by `overlap` pixels of
//! context on every side (clipped at the image border) and only the core is kept. Tile origins
//! and the overlap are multiples of 16, so every tile sees the same pooling grid as the whole
//! image; with an overlap at least the network's receptive-field radius the tiled result equals
//! the whole-image result to rounding (tested). Because the exposure is computed once for the
//! whole image, tiles never disagree on brightness.
//!
//! Modules: [`cli`] (arguments and run), [`model`] (ONNX Runtime, the model contract,
//! inference), [`tiling`], [`feature`] (features and their files).

pub mod cli;
pub mod feature;
pub mod model;
pub mod tiling;

pub use feature::{feature_path, output_path, Feature};
pub use model::{runtime_library_path, Denoiser};
pub use tiling::Tiling;
