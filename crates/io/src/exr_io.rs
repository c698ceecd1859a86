//! OpenEXR images as the pipeline exchanges them: one 3-channel feature per file (R, G, B as
//! 32-bit float, linear), ZIP scanline compression, string attributes for run metadata.
//!
//! Half floats are never written: photometric values (1e5 cd/m² and more) overflow f16.

use crate::color::Rgb;
use crate::error::{Error, Result};
use crate::outputs::OutputPlan;
use exr::block::chunk::{Chunk, CompressedBlock, CompressedScanLineBlock};
use exr::block::writer::ChunksWriter;
use exr::image::write::layers::WritableLayers;
use exr::prelude::*;
use std::path::Path;

/// A linear RGB image, row-major from the top-left, interleaved `[r, g, b]` per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
    /// Header attributes (name, value) beyond the standard ones.
    pub attributes: Vec<(String, String)>,
}

impl RgbImage {
    pub fn new(width: usize, height: usize) -> RgbImage {
        RgbImage {
            width,
            height,
            pixels: vec![[0.0; 3]; width * height],
            attributes: Vec::new(),
        }
    }
    /// The header attribute `key` (one of [`crate::header`]'s keys), if present.
    pub fn attribute(&self, key: &str) -> Option<&str> {
        crate::header::get(&self.attributes, key)
    }
    /// Sets the header attribute `key`, replacing an earlier value.
    pub fn set_attribute(&mut self, key: &str, value: impl std::fmt::Display) {
        crate::header::set(&mut self.attributes, key, value)
    }
    /// The autoexposure shared by the denoiser and the evaluation tonemap (training/transfer.py):
    /// `0.18 / exp(mean over pixels of ln(max(Y, 0) + 1e-4))`, Y the Rec. 709 luminance,
    /// accumulated in f64. It maps the image's log-average luminance to middle grey.
    pub fn autoexposure(&self) -> f64 {
        self.autoexposure_scaled(1.0)
    }
    /// The [`RgbImage::autoexposure`] of the image's pixels times `scale` (each Y times `scale`
    /// in f64; the image is not changed): what the denoiser gives a model fed the image scaled
    /// (see [`dim_exponent`]).
    pub fn autoexposure_scaled(&self, scale: f64) -> f64 {
        const KEY: f64 = 0.18;
        const EPS: f64 = 1e-4;
        if self.pixels.is_empty() {
            return 1.0;
        }
        let sum: f64 = self
            .pixels
            .iter()
            .map(|p| (Rgb(p.map(f64::from)).luminance() * scale).max(0.0) + EPS)
            .map(f64::ln)
            .sum();
        KEY / (sum / self.pixels.len() as f64).exp()
    }
    /// Position of the first non-finite pixel value, if any.
    pub fn first_non_finite(&self) -> Option<(usize, usize)> {
        self.pixels
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
            .map(|i| (i % self.width, i / self.width))
    }
}

/// The mean luminance below which the denoiser brightens its input: 1/32, below the darkest
/// training image of the committed models (mean luminance 0.6) by a factor of 19 and where the
/// autoexposure's `1e-4` is still small against the image (docs/architecture.md, *Exposure and
/// tonemap*).
pub const DIM_LUMINANCE: f64 = 1.0 / 32.0;

/// The power of two `e` by which the denoiser multiplies the radiance it gives a model (the
/// output is divided by `2^e`): the least `e ≥ 0` with `2^e · L ≥ DIM_LUMINANCE`, `L` the mean
/// over pixels of the Rec. 709 luminance of `max(hdr − emission, 0)` (per channel, f64: the
/// radiance a model with the `emi` feature denoises; `max(hdr, 0)` without `emission`); 0 for an
/// image that is black or not dim. The autoexposure's `1e-4` (a black pixel's floor) makes a
/// model's input depend on the radiance's unit: an image 100 times dimmer than the Cornell box
/// lost 10 dB at 256 spp before this, while a brighter one denoises alike (docs/measurements.md,
/// *Dim images*). Powers of two are exact in f32, so images differing by one are denoised alike.
pub fn dim_exponent(hdr: &RgbImage, emission: Option<&RgbImage>) -> i32 {
    if hdr.pixels.is_empty() {
        return 0;
    }
    let dimmed = |h: &[f32; 3], e: &[f32; 3]| {
        Rgb(std::array::from_fn(|c| {
            (h[c] as f64 - e[c] as f64).max(0.0)
        }))
        .luminance()
    };
    let sum: f64 = match emission {
        Some(emi) => hdr
            .pixels
            .iter()
            .zip(&emi.pixels)
            .map(|(h, e)| dimmed(h, e))
            .sum(),
        None => hdr.pixels.iter().map(|h| dimmed(h, &[0.0; 3])).sum(),
    };
    let mean = sum / hdr.pixels.len() as f64;
    if mean.is_nan() || mean <= 0.0 || mean >= DIM_LUMINANCE {
        return 0;
    }
    // The least e with mean · 2^e ≥ DIM_LUMINANCE (below 200: a positive mean of f32 values is at
    // least 2^-149 over the pixel count).
    let mut e = 0;
    while mean * 2f64.powi(e) < DIM_LUMINANCE {
        e += 1;
    }
    e
}

/// Writes `image` as the planned output `path` of a stage's run (see [`crate::outputs`]).
pub fn write_rgb_to(plan: &mut OutputPlan, path: &Path, image: &RgbImage) -> Result<()> {
    let bytes = encode_rgb(path, image)?;
    plan.write_bytes(path, &bytes)
}

/// Writes `image` alone, atomically (tools and tests; a stage plans all its outputs and uses
/// [`write_rgb_to`]).
pub fn write_rgb(path: &Path, image: &RgbImage) -> Result<()> {
    let bytes = encode_rgb(path, image)?;
    crate::fsio::write_bytes_atomically(path, &bytes)
}

/// `image` as a ZIP-compressed scanline EXR with f32 R, G, B channels; `path` is named in errors.
pub fn encode_rgb(path: &Path, image: &RgbImage) -> Result<Vec<u8>> {
    if image.pixels.len() != image.width * image.height || image.width == 0 || image.height == 0 {
        return Err(Error::input(
            path,
            format!(
                "refusing to write a {}x{} image with {} pixels",
                image.width,
                image.height,
                image.pixels.len()
            ),
        ));
    }
    let w = image.width;
    // The header's channel list (R, G, B as f32) only: the pixel blocks are zip_block's.
    let channels = SpecificChannels::rgb(|_: Vec2<usize>| (0f32, 0f32, 0f32));
    let mut attributes = LayerAttributes::default();
    for (k, v) in &image.attributes {
        attributes.other.insert(
            Text::from(k.as_str()),
            AttributeValue::Text(Text::from(v.as_str())),
        );
    }
    attributes.software_name = Some(Text::from(
        format!("luxest {}", crate::meta::PROGRAM_VERSION).as_str(),
    ));
    let encoding = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let layer = Layer::new((image.width, image.height), attributes, encoding, channels);
    let bounds = IntegerBounds::new(layer.attributes.layer_position, layer.size);
    let headers = layer.infer_headers(&ImageAttributes::new(bounds));
    let order: Vec<usize> = headers[0]
        .channels
        .list
        .iter()
        .map(|c| match c.name.to_string().as_str() {
            "R" => 0,
            "G" => 1,
            _ => 2,
        })
        .collect();
    let lines = headers[0].compression.scan_lines_per_block();
    let mut buffer = std::io::Cursor::new(Vec::new());
    exr::block::write(&mut buffer, headers, true, |_, writer| {
        for (index, y0) in (0..image.height).step_by(lines).enumerate() {
            let rows = &image.pixels[y0 * w..(y0 + lines).min(image.height) * w];
            let block = CompressedScanLineBlock {
                y_coordinate: y0 as i32,
                compressed_pixels_le: zip_block(rows, w, &order),
            };
            let chunk = Chunk {
                layer_index: 0,
                compressed_block: CompressedBlock::ScanLine(block),
            };
            writer.write_chunk(index, chunk)?;
        }
        Ok(())
    })
    .map_err(|e| Error::input(path, format!("cannot encode EXR: {e}")))?;
    let mut bytes = buffer.into_inner();
    sort_header_attributes(&mut bytes);
    Ok(bytes)
}

/// Deflate level of the ZIP blocks: 1, the fastest. The `exr` crate compresses at level 4, which
/// took 3.5 times as long for 2 % smaller files of radiance (a 1024² denoised image: 0.12 s
/// against 0.034 s, 4.6 against 4.7 MB), a cost every stage paid for each image it wrote.
const ZIP_LEVEL: u8 = 1;

/// One ZIP scanline block of `rows` (whole rows of `width` pixels), as OpenEXR's ZIP compressor
/// stores it: per scanline the channels in the header's order (`order`: the RGB index of each),
/// each row of little-endian f32; the bytes split into even- and odd-indexed halves, each byte
/// replaced by its difference to the previous one plus 128, then zlib-compressed. Where that is
/// not smaller than the raw bytes, the raw bytes (readers tell them apart by size).
fn zip_block(rows: &[[f32; 3]], width: usize, order: &[usize]) -> Vec<u8> {
    let mut raw = Vec::with_capacity(rows.len() * 12);
    for row in rows.chunks(width) {
        for &c in order {
            for p in row {
                raw.extend_from_slice(&p[c].to_le_bytes());
            }
        }
    }
    let half = raw.len().div_ceil(2);
    let mut packed = vec![0u8; raw.len()];
    for (i, &b) in raw.iter().enumerate() {
        packed[if i % 2 == 0 { i / 2 } else { half + i / 2 }] = b;
    }
    for i in (1..packed.len()).rev() {
        packed[i] = packed[i].wrapping_sub(packed[i - 1]).wrapping_add(128);
    }
    let compressed = miniz_oxide::deflate::compress_to_vec_zlib(&packed, ZIP_LEVEL);
    if compressed.len() < raw.len() {
        compressed
    } else {
        raw
    }
}

/// Puts the header attributes of a single-part EXR in name order, in place.
///
/// The `exr` crate writes custom attributes in `HashMap` order, which changes from run to run;
/// sorted, the same image and attributes always give the same bytes (the contract fixtures of
/// `tests/fixtures/contract` rely on it). The header keeps its length, so the chunk offsets after
/// it stay valid. Anything unexpected (multi-part files, a malformed header) is left as it is.
fn sort_header_attributes(bytes: &mut [u8]) {
    const MULTIPART: u32 = 1 << 12;
    if bytes.len() < 8 || bytes[..4] != [0x76, 0x2f, 0x31, 0x01] {
        return;
    }
    if u32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]) & MULTIPART != 0 {
        return;
    }
    let cstr_end = |from: usize| bytes[from..].iter().position(|&b| b == 0).map(|i| from + i);
    // (name, whole attribute) spans from byte 8 to the header's terminating empty name.
    let mut attributes: Vec<(std::ops::Range<usize>, std::ops::Range<usize>)> = Vec::new();
    let mut at = 8;
    let end = loop {
        let Some(name_end) = cstr_end(at) else { return };
        if name_end == at {
            break at;
        }
        let Some(type_end) = cstr_end(name_end + 1) else {
            return;
        };
        let Some(size) = bytes.get(type_end + 1..type_end + 5) else {
            return;
        };
        let size = u32::from_le_bytes([size[0], size[1], size[2], size[3]]) as usize;
        let next = type_end + 5 + size;
        if next > bytes.len() {
            return;
        }
        attributes.push((at..name_end, at..next));
        at = next;
    };
    let mut sorted = attributes.clone();
    sorted.sort_by(|a, b| bytes[a.0.clone()].cmp(&bytes[b.0.clone()]));
    let header: Vec<u8> = sorted
        .iter()
        .flat_map(|(_, whole)| bytes[whole.clone()].iter().copied())
        .collect();
    bytes[8..end].copy_from_slice(&header);
}

/// sRGB transfer function (IEC 61966-2-1) of a linear value in [0, 1].
pub fn srgb_encode(v: f64) -> f64 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

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
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
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
        .map(|p| crate::color::Rgb(p.map(|v| v as f64)).luminance())
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

/// [`read_rgb`] for stage inputs that must be finite: a NaN or infinity is an error naming the
/// file and the pixel.
pub fn read_rgb_finite(path: &Path) -> Result<RgbImage> {
    let image = read_rgb(path)?;
    if let Some((x, y)) = image.first_non_finite() {
        return Err(Error::input(
            path,
            format!("non-finite value (NaN or infinity) at pixel ({x}, {y})"),
        ));
    }
    Ok(image)
}

/// Checks an EXR's header before its pixels are read: the image it claims must fit in the memory
/// available (with the RGB copy this reader makes), and the file must be long enough to hold at
/// least the table of chunk offsets the header implies (8 bytes per chunk). A few hundred bytes
/// claiming 100000² pixels are refused here instead of aborting in the allocator.
/// Claims of sample data up to this size are read without the expansion bound below.
const MIN_EXR_CLAIM: u128 = 16 << 20;

/// The largest factor by which `compression` can expand stored bytes into samples, generously:
/// none 1; RLE 64 (two bytes for a run of 128); deflate (ZIP) about 1032, PXR24 4/3 of that;
/// B44 stores a 4x4 block of halves in at least 3 bytes; PIZ's Huffman coding with runs of at
/// most 255 codes stays below 500; the lossy DWA and HTJ2K are bounded at 5000.
fn max_expansion(compression: exr::compression::Compression) -> u128 {
    use exr::compression::Compression::*;
    match compression {
        Uncompressed => 1,
        RLE => 64,
        ZIP1 | ZIP16 => 1100,
        PXR24 => 1500,
        B44 | B44A => 16,
        PIZ => 1000,
        _ => 5000,
    }
}

fn check_exr_size(path: &Path, bytes: &[u8]) -> Result<()> {
    let meta = exr::meta::MetaData::read_from_buffered(bytes, false)
        .map_err(|e| Error::input(path, format!("not a readable OpenEXR file: {e}")))?;
    let mut chunks: u128 = 0;
    let mut samples_bytes: u128 = 0;
    let mut holds: u128 = 0;
    for header in &meta.headers {
        let (w, h) = (
            header.layer_size.width() as u128,
            header.layer_size.height() as u128,
        );
        let sample_bytes: u128 = header
            .channels
            .list
            .iter()
            .map(|c| c.sample_type.bytes_per_sample() as u128)
            .sum();
        // All channels as stored, plus the f32 RGB image built from them.
        crate::limits::check_allocation(
            &format!("the {w}x{h} image of its header"),
            w * h,
            sample_bytes + 12,
        )
        .map_err(|m| Error::input(path, m))?;
        chunks += header.chunk_count as u128;
        samples_bytes += w * h * sample_bytes;
        holds = holds.max(bytes.len() as u128 * max_expansion(header.compression));
    }
    // A few kilobytes claiming gigabytes: no compression the format has expands that much, so the
    // file is corrupt, and reading it would allocate the claimed size first (found by fuzzing).
    let holds = holds.max(MIN_EXR_CLAIM);
    let (w, h) = meta
        .headers
        .first()
        .map_or((0, 0), |h| (h.layer_size.width(), h.layer_size.height()));
    if samples_bytes > holds {
        return Err(Error::input(
            path,
            format!(
                "truncated or corrupt OpenEXR file: its header claims {w}x{h} pixels, {} of \
                 samples, more than its {} bytes can hold with its compression",
                crate::limits::show_bytes(samples_bytes),
                bytes.len()
            ),
        ));
    }
    if chunks.saturating_mul(8) > bytes.len() as u128 {
        return Err(Error::input(
            path,
            format!(
                "truncated or corrupt OpenEXR file: its header claims {w}x{h} pixels in {chunks} \
                 chunks, but the file has only {} bytes",
                bytes.len()
            ),
        ));
    }
    Ok(())
}

/// Reads an EXR that must contain R, G and B channels (f32 or f16; other channels ignored).
pub fn read_rgb(path: &Path) -> Result<RgbImage> {
    let bytes = crate::fsio::read_bytes(path)?;
    read_rgb_bytes(path, bytes)
}

/// [`read_rgb`] of a file's content `bytes`; `path` names it in errors.
pub fn read_rgb_bytes(path: &Path, bytes: Vec<u8>) -> Result<RgbImage> {
    check_exr_size(path, &bytes)?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| Error::input(path, format!("not a readable OpenEXR file: {e}")))?;
    let layer = &image.layer_data;
    let (width, height) = (layer.size.width(), layer.size.height());
    let names: Vec<String> = layer
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    let find = |want: &str| {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == want)
            .ok_or_else(|| {
                Error::input(
                    path,
                    format!("expected channels R, G, B; found {}", names.join(", ")),
                )
            })
    };
    let mut pixels = vec![[0f32; 3]; width * height];
    for (k, name) in ["R", "G", "B"].iter().enumerate() {
        let channel = find(name)?;
        match &channel.sample_data {
            FlatSamples::F32(v) => {
                for (p, &v) in pixels.iter_mut().zip(v) {
                    p[k] = v;
                }
            }
            FlatSamples::F16(v) => {
                for (p, h) in pixels.iter_mut().zip(v) {
                    p[k] = h.to_f32();
                }
            }
            FlatSamples::U32(_) => {
                return Err(Error::input(
                    path,
                    format!("channel {name} holds integers, expected float"),
                ))
            }
        }
    }
    let mut attributes: Vec<(String, String)> = layer
        .attributes
        .other
        .iter()
        .chain(image.attributes.other.iter())
        .filter_map(|(k, v)| match v {
            AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
            _ => None,
        })
        .collect();
    attributes.sort();
    Ok(RgbImage {
        width,
        height,
        pixels,
        attributes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn uniform(w: usize, h: usize, v: f32) -> RgbImage {
        let mut img = RgbImage::new(w, h);
        img.pixels.fill([v; 3]);
        img
    }

    #[test]
    fn dim_exponent_is_the_least_power_of_two_reaching_the_threshold() {
        // A uniform grey of luminance Y (the Rec. 709 weights sum to 1).
        assert_eq!(dim_exponent(&uniform(4, 5, 1e-3), None), 5); // 0.016 < 1/32 <= 0.032
        assert_eq!(dim_exponent(&uniform(2, 2, 1.0 / 32.0), None), 0);
        assert_eq!(dim_exponent(&uniform(2, 2, 1.0 / 64.0), None), 1);
        assert_eq!(dim_exponent(&uniform(2, 2, 1e-30), None), 95); // 2^95 1e-30 = 0.0396
        assert_eq!(dim_exponent(&uniform(3, 3, 0.0), None), 0); // black: nothing to brighten
        assert_eq!(dim_exponent(&uniform(3, 3, -1e-3), None), 0); // negative counts as 0
        assert_eq!(dim_exponent(&RgbImage::new(0, 0), None), 0);
        // An emitter beside a dim wall: without the emission the mean is bright; the model
        // denoises hdr − emission, whose mean 0.75e-6 needs 2^16.
        let mut hdr = uniform(2, 2, 1e-6);
        hdr.pixels[0] = [100.0; 3];
        let mut emi = RgbImage::new(2, 2);
        emi.pixels[0] = [100.0; 3];
        assert_eq!(dim_exponent(&hdr, None), 0);
        assert_eq!(dim_exponent(&hdr, Some(&emi)), 16);
    }

    #[test]
    fn autoexposure_scaled_is_that_of_the_scaled_image() {
        let mut img = RgbImage::new(3, 2);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = [i as f32 * 1e-4, 0.0, 2e-3 * i as f32];
        }
        let mut scaled = img.clone();
        for p in &mut scaled.pixels {
            *p = p.map(|c| c * 1024.0);
        }
        assert_eq!(img.autoexposure_scaled(1024.0), scaled.autoexposure());
        assert_eq!(img.autoexposure_scaled(1.0), img.autoexposure());
    }

    #[test]
    fn round_trip_keeps_values_and_metadata() {
        let dir = std::env::temp_dir().join(format!("luxest-exr-{}", std::process::id()));
        let path = dir.join("a_000004spp.hdr.exr");
        let mut img = RgbImage::new(5, 3);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            // Values far outside the f16 range must survive.
            *p = [i as f32 * 1.0e5, -(i as f32) * 1e-7, 3.0e9];
        }
        img.set_attribute(crate::header::SEED, 42);
        write_rgb(&path, &img).unwrap();
        let back = read_rgb(&path).unwrap();
        assert_eq!(back.pixels, img.pixels);
        assert_eq!(back.attribute(crate::header::SEED), Some("42"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_same_image_gives_the_same_bytes() {
        let dir = std::env::temp_dir().join(format!("luxest-exr-det-{}", std::process::id()));
        let mut img = RgbImage::new(3, 2);
        for (i, key) in crate::header::ALL.iter().enumerate() {
            img.set_attribute(key, i);
        }
        let bytes: Vec<Vec<u8>> = (0..4)
            .map(|i| {
                let path = dir.join(format!("{i}.exr"));
                write_rgb(&path, &img).unwrap();
                std::fs::read(&path).unwrap()
            })
            .collect();
        assert!(bytes.iter().all(|b| *b == bytes[0]));
        let back = read_rgb(&dir.join("0.exr")).unwrap();
        for (i, key) in crate::header::ALL.iter().enumerate() {
            assert_eq!(back.attribute(key), Some(i.to_string().as_str()));
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn zip_blocks_read_back_whatever_their_size_and_content() {
        // Sizes with a partial last block of 16 scanlines, one column and one pixel; content
        // smooth (compressed) and pseudo-random bit patterns (stored raw: deflate cannot shrink
        // them), each read back bit for bit by the `exr` crate's own ZIP decoder.
        let dir = std::env::temp_dir().join(format!("luxest-exr-zip-{}", std::process::id()));
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut random = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            f32::from_bits((state as u32 & 0x7f7f_ffff) | ((state >> 32) as u32 & 0x8000_0000))
        };
        for (w, h) in [(37, 17), (1, 40), (1, 1), (64, 16)] {
            for smooth in [true, false] {
                let mut img = RgbImage::new(w, h);
                for (i, p) in img.pixels.iter_mut().enumerate() {
                    *p = if smooth {
                        [i as f32 * 0.5, 1.0, (i % w) as f32 * 1e-3]
                    } else {
                        [random(), random(), random()]
                    };
                }
                let path = dir.join(format!("{w}x{h}-{smooth}.exr"));
                write_rgb(&path, &img).unwrap();
                let back = read_rgb(&path).unwrap();
                let bits = |im: &RgbImage| -> Vec<u32> {
                    im.pixels.iter().flatten().map(|v| v.to_bits()).collect()
                };
                assert_eq!(bits(&back), bits(&img), "{w}x{h}, smooth {smooth}");
            }
        }
        // The raw fallback is taken where deflate does not shrink a block, and not elsewhere.
        let noisy: Vec<[f32; 3]> = (0..64 * 16)
            .map(|_| [random(), random(), random()])
            .collect();
        assert_eq!(zip_block(&noisy, 64, &[2, 1, 0]).len(), 64 * 16 * 12);
        let flat = vec![[1.0f32; 3]; 64 * 16];
        assert!(zip_block(&flat, 64, &[2, 1, 0]).len() < 200);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn garbage_is_a_clear_error() {
        let dir = std::env::temp_dir().join(format!("luxest-exr-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bad.exr");
        std::fs::write(&path, b"not an exr").unwrap();
        let e = read_rgb(&path).unwrap_err().to_string();
        assert!(e.contains("bad.exr: not a readable OpenEXR file"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
