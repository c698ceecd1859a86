//! PNG previews of linear images: 8-bit sRGB, exposed by a given factor or so that the 99th
//! percentile of luminance maps to white; and the PNG encoder of any 8-bit sRGB raster (the
//! isolux plots use it).

use crate::color::{srgb_encode, Rgb};
use crate::error::{Error, Result};
use crate::image::RgbImage;
use crate::outputs::OutputPlan;
use std::path::Path;

/// Writes an 8-bit sRGB PNG preview as the planned output `path`: linear values times
/// `exposure`, clipped, sRGB-encoded.
pub fn write_preview_png_to(
    plan: &mut OutputPlan,
    path: &Path,
    image: &RgbImage,
    exposure: f64,
) -> Result<()> {
    let bytes = encode_preview_png(path, image, exposure)?;
    plan.write_bytes(path, &bytes)
}

/// Writes a PNG preview alone, atomically (tools and tests; stages use [`write_preview_png_to`]).
pub fn write_preview_png(path: &Path, image: &RgbImage, exposure: f64) -> Result<()> {
    let bytes = encode_preview_png(path, image, exposure)?;
    crate::fsio::write_bytes_atomically(path, &bytes)
}

/// Writes an auto-exposed PNG preview alone, atomically (tools and tests; stages use
/// [`write_preview_png_auto_to`]).
pub fn write_preview_png_auto(path: &Path, image: &RgbImage) -> Result<()> {
    write_preview_png(path, image, preview_exposure(image))
}

/// The PNG bytes of [`write_preview_png_to`].
pub fn encode_preview_png(path: &Path, image: &RgbImage, exposure: f64) -> Result<Vec<u8>> {
    let data: Vec<u8> = image
        .pixels
        .iter()
        .flat_map(|p| p.map(|v| (srgb_encode(v as f64 * exposure) * 255.0 + 0.5) as u8))
        .collect();
    encode_png_rgb8(image.width as u32, image.height as u32, &data)
        .map_err(|e| Error::input(path, format!("cannot encode PNG: {e}")))
}

/// The PNG bytes of an 8-bit sRGB raster, `data` row by row from the top, 3 bytes a pixel.
pub fn encode_png_rgb8(
    width: u32,
    height: u32,
    data: &[u8],
) -> std::result::Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    let mut encoder = ::png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(::png::ColorType::Rgb);
    encoder.set_depth(::png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(data).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())?;
    Ok(bytes)
}

/// Writes a PNG preview as the planned output `path`, exposed so that the 99th percentile of
/// luminance maps to white.
pub fn write_preview_png_auto_to(
    plan: &mut OutputPlan,
    path: &Path,
    image: &RgbImage,
) -> Result<()> {
    write_preview_png_to(plan, path, image, preview_exposure(image))
}

/// The exposure of [`write_preview_png_auto_to`]: the 99th percentile of luminance maps to white.
pub fn preview_exposure(image: &RgbImage) -> f64 {
    let mut ys: Vec<f64> = image
        .pixels
        .iter()
        .map(|p| Rgb(p.map(|v| v as f64)).luminance())
        .filter(|y| y.is_finite())
        .collect();
    ys.sort_by(f64::total_cmp);
    let p99 = ys
        .get((ys.len() * 99 / 100).min(ys.len().saturating_sub(1)))
        .copied()
        .unwrap_or(1.0);
    if p99 > 0.0 && (1.0 / p99).is_finite() {
        1.0 / p99
    } else {
        1.0
    }
}
