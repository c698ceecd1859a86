//! Bitmap texture images as decoded from their files: PNG (1, 2, 4, 8 and 16 bits, grey,
//! grey + alpha, RGB, RGBA, palette, transparency chunks), JPEG (baseline and progressive,
//! grey or YCbCr) and OpenEXR (f16 or f32 channels R, G, B with optional A, or Y with optional
//! A). The samples are kept as stored: 8- and 16-bit integers are not yet sRGB-decoded (a
//! texture decides the encoding, `luxest_render::texture`), EXR values are linear.
//!
//! Bad input is a one-line error naming the file, never a panic: the size a header claims is
//! checked against [`MAX_TEXTURE_SIDE`] and against the memory available ([`crate::limits`])
//! before the pixels are allocated; a truncated or corrupt file, an image with no pixels, a CMYK
//! JPEG (its inks have no colorimetric meaning without a profile) and a NaN or infinity in an
//! EXR are refused.

use crate::error::{Error, Result};
use std::path::Path;

/// The largest width or height of a texture, in pixels.
pub const MAX_TEXTURE_SIDE: u64 = 1 << 16;

/// Bytes a texel of the texture built from an image can take, mip-maps included (RGBA f32
/// and a pyramid of a third more): what the size check reserves beyond the decoded samples.
pub const TEXTURE_BYTES_PER_TEXEL: u64 = 22;

/// The file format an image was decoded from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Jpeg,
    Exr,
}

impl ImageFormat {
    /// Whether the format stores display-encoded integers (PNG, JPEG) rather than linear
    /// floating-point values (EXR).
    pub fn is_integer(self) -> bool {
        !matches!(self, ImageFormat::Exr)
    }
}

/// The samples of an image, interleaved by pixel, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub enum Samples {
    /// 8-bit integers (0..=255 spans [0, 1]).
    U8(Vec<u8>),
    /// 16-bit integers (0..=65535 spans [0, 1]).
    U16(Vec<u16>),
    /// Linear floating-point values (EXR), all finite.
    F32(Vec<f32>),
}

impl Samples {
    pub fn len(&self) -> usize {
        match self {
            Samples::U8(v) => v.len(),
            Samples::U16(v) => v.len(),
            Samples::F32(v) => v.len(),
        }
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A decoded image: `width` x `height` pixels of `channels` samples each (1 grey, 2 grey and
/// alpha, 3 RGB, 4 RGBA); `samples.len() == width * height * channels`.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureImage {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    pub samples: Samples,
    pub format: ImageFormat,
}

impl TextureImage {
    /// Whether the image has an alpha channel.
    pub fn has_alpha(&self) -> bool {
        self.channels == 2 || self.channels == 4
    }
}

/// Reads and decodes the image file `path` (its format told by its first bytes).
pub fn read_texture_image(path: &Path) -> Result<TextureImage> {
    let bytes = crate::fsio::read_bytes(path)?;
    decode_texture_image(path, bytes)
}

/// Decodes a PNG, JPEG or OpenEXR file's content `bytes`, telling the format by its signature;
/// `path` names it in errors.
pub fn decode_texture_image(path: &Path, bytes: Vec<u8>) -> Result<TextureImage> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        decode_png(path, &bytes)
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        decode_jpeg(path, &bytes)
    } else if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        decode_exr(path, bytes)
    } else {
        Err(Error::input(
            path,
            "not a PNG, JPEG or OpenEXR image (unknown signature in its first bytes)",
        ))
    }
}

/// Checks a `width` x `height` image of `decoded_bytes` per pixel (and the texture built from
/// it) before anything of that size is allocated.
fn check_size(path: &Path, width: u64, height: u64, decoded_bytes: u64) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(Error::input(
            path,
            format!("the image has no pixels ({width}x{height})"),
        ));
    }
    if width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
        return Err(Error::input(
            path,
            format!(
                "the image claims {width}x{height} pixels, more than the {MAX_TEXTURE_SIDE} a \
                 texture's side may have"
            ),
        ));
    }
    crate::limits::check_image(
        "texture",
        width,
        height,
        decoded_bytes + TEXTURE_BYTES_PER_TEXEL,
    )
    .map_err(|m| Error::input(path, m))
}

/// Decodes a PNG: palette and transparency (`tRNS`) expanded to RGB(A), grey below 8 bits
/// scaled to 8 bits, 16-bit samples kept.
pub fn decode_png(path: &Path, bytes: &[u8]) -> Result<TextureImage> {
    let bad = |e: ::png::DecodingError| Error::input(path, format!("not a readable PNG file: {e}"));
    let mut decoder = ::png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(::png::Transformations::EXPAND);
    let header = decoder.read_header_info().map_err(bad)?;
    let (width, height) = (header.width as u64, header.height as u64);
    // The largest output a PNG can have: 16-bit RGBA.
    check_size(path, width, height, 8)?;
    let mut reader = decoder.read_info().map_err(bad)?;
    let (color, depth) = reader.output_color_type();
    let channels = color.samples();
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| Error::input(path, "PNG image too large for this machine's memory"))?;
    let mut buffer = vec![0u8; size];
    let frame = reader.next_frame(&mut buffer).map_err(bad)?;
    buffer.truncate(frame.buffer_size());
    let (width, height) = (width as usize, height as usize);
    let samples = match depth {
        ::png::BitDepth::Sixteen => Samples::U16(
            buffer
                .chunks_exact(2)
                .map(|b| u16::from_be_bytes([b[0], b[1]]))
                .collect(),
        ),
        ::png::BitDepth::Eight => Samples::U8(buffer),
        other => {
            return Err(Error::input(
                path,
                format!("PNG samples of {other:?} bits after expansion, expected 8 or 16"),
            ))
        }
    };
    if samples.len() != width * height * channels {
        return Err(Error::input(
            path,
            format!(
                "PNG decoded to {} samples, expected {width}x{height}x{channels}",
                samples.len()
            ),
        ));
    }
    Ok(TextureImage {
        width,
        height,
        channels,
        samples,
        format: ImageFormat::Png,
    })
}

/// Decodes a JPEG (8-bit grey or YCbCr converted to RGB; 16-bit lossless grey kept as 16 bits).
pub fn decode_jpeg(path: &Path, bytes: &[u8]) -> Result<TextureImage> {
    let bad = |e: jpeg_decoder::Error| Error::input(path, format!("not a readable JPEG file: {e}"));
    let mut decoder = jpeg_decoder::Decoder::new(std::io::Cursor::new(bytes));
    decoder.read_info().map_err(bad)?;
    let info = decoder
        .info()
        .ok_or_else(|| Error::input(path, "not a readable JPEG file: no frame header"))?;
    let (width, height) = (info.width as u64, info.height as u64);
    // Decoded samples (at most 4 bytes a pixel) and the decoder's coefficients of a progressive
    // image (2 bytes a sample, up to 4 components).
    check_size(path, width, height, 4 + 8)?;
    decoder.set_max_decoding_buffer_size((width * height * 4) as usize);
    let pixels = decoder.decode().map_err(bad)?;
    let (width, height) = (width as usize, height as usize);
    let (channels, samples) = match info.pixel_format {
        jpeg_decoder::PixelFormat::L8 => (1, Samples::U8(pixels)),
        jpeg_decoder::PixelFormat::RGB24 => (3, Samples::U8(pixels)),
        jpeg_decoder::PixelFormat::L16 => (
            1,
            Samples::U16(
                pixels
                    .chunks_exact(2)
                    .map(|b| u16::from_be_bytes([b[0], b[1]]))
                    .collect(),
            ),
        ),
        jpeg_decoder::PixelFormat::CMYK32 => {
            return Err(Error::input(
                path,
                "CMYK JPEG images are not supported as textures (convert to RGB)",
            ))
        }
    };
    if samples.len() != width * height * channels {
        return Err(Error::input(
            path,
            format!(
                "JPEG decoded to {} samples, expected {width}x{height}x{channels}",
                samples.len()
            ),
        ));
    }
    Ok(TextureImage {
        width,
        height,
        channels,
        samples,
        format: ImageFormat::Jpeg,
    })
}

/// Decodes an OpenEXR image's first layer at its largest resolution: channels R, G, B (and A if
/// present), or Y (and A). Every value must be finite.
pub fn decode_exr(path: &Path, bytes: Vec<u8>) -> Result<TextureImage> {
    use ::exr::prelude::{FlatSamples, ReadChannels, ReadLayers};
    crate::exr::check_exr_size(path, &bytes)?;
    let image = ::exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| Error::input(path, format!("not a readable OpenEXR file: {e}")))?;
    let layer = &image.layer_data;
    let (width, height) = (layer.size.width(), layer.size.height());
    check_size(path, width as u64, height as u64, 16)?;
    let list = &layer.channel_data.list;
    let names: Vec<String> = list.iter().map(|c| c.name.to_string()).collect();
    let find = |want: &str| names.iter().position(|n| n == want);
    if find("RY").is_some() || find("BY").is_some() {
        return Err(Error::input(
            path,
            "luminance-chroma (Y, RY, BY) OpenEXR images are not supported: store R, G, B",
        ));
    }
    let wanted: Vec<(&str, usize)> = match (find("R"), find("G"), find("B"), find("Y")) {
        (Some(r), Some(g), Some(b), _) => vec![("R", r), ("G", g), ("B", b)],
        (None, None, None, Some(y)) => vec![("Y", y)],
        _ => {
            return Err(Error::input(
                path,
                format!(
                    "expected channels R, G, B (and A) or Y (and A); found {}",
                    names.join(", ")
                ),
            ))
        }
    };
    let wanted: Vec<(&str, usize)> = wanted
        .into_iter()
        .chain(find("A").map(|a| ("A", a)))
        .collect();
    let channels = wanted.len();
    let mut samples = vec![0f32; width * height * channels];
    for (k, &(name, index)) in wanted.iter().enumerate() {
        let values: Vec<f32> = match &list[index].sample_data {
            FlatSamples::F32(v) => v.clone(),
            FlatSamples::F16(v) => v.iter().map(|h| h.to_f32()).collect(),
            FlatSamples::U32(_) => {
                return Err(Error::input(
                    path,
                    format!("channel {name} holds integers, expected float"),
                ))
            }
        };
        if values.len() != width * height {
            return Err(Error::input(
                path,
                format!(
                    "channel {name} has {} samples for {width}x{height} pixels (subsampled \
                     channels are not supported)",
                    values.len()
                ),
            ));
        }
        for (i, v) in values.into_iter().enumerate() {
            if !v.is_finite() {
                return Err(Error::input(
                    path,
                    format!(
                        "non-finite value (NaN or infinity) in channel {name} at pixel ({}, {})",
                        i % width,
                        i / width
                    ),
                ));
            }
            samples[i * channels + k] = v;
        }
    }
    Ok(TextureImage {
        width,
        height,
        channels,
        samples: Samples::F32(samples),
        format: ImageFormat::Exr,
    })
}
