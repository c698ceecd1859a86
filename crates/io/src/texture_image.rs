//! Bitmap texture images as decoded from their files: PNG (1, 2, 4, 8 and 16 bits, grey,
//! grey + alpha, RGB, RGBA, palette, transparency chunks), JPEG (baseline and progressive,
//! grey or YCbCr) and OpenEXR (f16 or f32 channels R, G, B with optional A, or Y with optional
//! A). The samples are kept as stored: 8- and 16-bit integers are not yet sRGB-decoded (a
//! texture decides the encoding, `luxest_render::texture`), EXR values are linear.
//!
//! Bad input is a one-line error naming the file, never a panic: the size a header claims is
//! checked against [`MAX_TEXTURE_SIDE`], against the memory available ([`crate::limits`]) and
//! against what the file's bytes can code (PNG: deflate's largest expansion; JPEG: a bit per
//! 8x8 block; EXR: [`crate::exr`]'s bound) before the pixels are allocated; a truncated or corrupt file, an image with no pixels, a CMYK
//! JPEG (its inks have no colorimetric meaning without a profile) and a NaN or infinity in an
//! EXR are refused.

use crate::error::{Error, Result};
use std::path::Path;

/// The largest width or height of a texture, in pixels.
pub const MAX_TEXTURE_SIDE: u64 = 1 << 16;

/// Bytes a texel of the texture built from an image takes, mip-maps included (rounded up):
/// 8-bit images keep 4 bytes of RGBA and a pyramid of a third as many 8-byte texels; others
/// 16 bytes (RGBA f32) and a third more. What the size check reserves beyond the decoded
/// samples.
pub fn texture_bytes_per_texel(eight_bit: bool) -> u64 {
    if eight_bit {
        7
    } else {
        22
    }
}

/// Claims of decoded data up to this size are decoded without the expansion bound below.
const MIN_CLAIM: u64 = 16 << 20;

/// The most a deflate stream expands (about 1032 times: a 258-byte match in under two bits),
/// rounded up: a PNG's pixel data is at most this many times its file's size.
const MAX_DEFLATE_EXPANSION: u64 = 1100;

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
/// it, of 8-bit samples or not) before anything of that size is allocated.
fn check_size(
    path: &Path,
    (width, height): (u64, u64),
    decoded_bytes: u64,
    eight_bit: bool,
) -> Result<()> {
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
        decoded_bytes + texture_bytes_per_texel(eight_bit),
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
    // At most 4 samples a pixel after expansion.
    let eight_bit = header.bit_depth != ::png::BitDepth::Sixteen;
    let sample_bytes = if eight_bit { 1 } else { 2 };
    check_size(path, (width, height), 4 * sample_bytes, eight_bit)?;
    // The filtered rows (a filter byte and the packed samples each) are deflate's output: a
    // file claiming more than its bytes can expand to is corrupt, and decoding it would
    // allocate the claim first (found by fuzzing: 125 bytes claiming 4.4 GB).
    let bits = header.color_type.samples() as u64 * header.bit_depth as u64;
    let raw = height * (1 + (width * bits).div_ceil(8));
    if raw > MIN_CLAIM && raw > bytes.len() as u64 * MAX_DEFLATE_EXPANSION {
        return Err(Error::input(
            path,
            format!(
                "truncated or corrupt PNG file: its header claims {width}x{height} pixels, {} \
                 of pixel data, more than its {} bytes can hold",
                crate::limits::show_bytes(raw as u128),
                bytes.len()
            ),
        ));
    }
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
    let eight_bit = info.pixel_format != jpeg_decoder::PixelFormat::L16;
    check_size(path, (width, height), 4 + 8, eight_bit)?;
    // Huffman coding spends at least one bit on every 8x8 block's DC coefficient: a file
    // claiming more blocks than it has bits is corrupt, and decoding it would allocate the
    // claim first.
    if width * height * 4 > MIN_CLAIM && width * height > bytes.len() as u64 * 8 * 64 {
        return Err(Error::input(
            path,
            format!(
                "truncated or corrupt JPEG file: its header claims {width}x{height} pixels, \
                 more 8x8 blocks than its {} bytes have bits",
                bytes.len()
            ),
        ));
    }
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
    use ::exr::prelude::FlatSamples;
    let image = crate::exr::read_first_layer(path, bytes)?;
    let layer = &image.layer_data;
    let (width, height) = (layer.size.width(), layer.size.height());
    check_size(path, (width as u64, height as u64), 16, false)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn here() -> PathBuf {
        PathBuf::from("textures/t.png")
    }

    /// A PNG of `data` as the `png` crate's encoder writes it (`palette`: entries and their
    /// `tRNS` alphas for an indexed image).
    fn png_bytes(
        (w, h): (u32, u32),
        color: ::png::ColorType,
        depth: ::png::BitDepth,
        data: &[u8],
        palette: Option<(&[u8], &[u8])>,
    ) -> Vec<u8> {
        let mut bytes = Vec::new();
        let mut encoder = ::png::Encoder::new(&mut bytes, w, h);
        encoder.set_color(color);
        encoder.set_depth(depth);
        if let Some((entries, alphas)) = palette {
            encoder.set_palette(entries.to_vec());
            if !alphas.is_empty() {
                encoder.set_trns(alphas.to_vec());
            }
        }
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(data).unwrap();
        writer.finish().unwrap();
        bytes
    }

    #[test]
    fn png_of_every_colour_type_and_depth_decodes_to_its_samples() {
        use ::png::{BitDepth::*, ColorType::*};
        let u8s = |v: &[u8]| Samples::U8(v.to_vec());
        // 2x2 images; 16-bit data big-endian as PNG stores it.
        let grey8 = [0u8, 128, 200, 255];
        let case = |color, depth, data: &[u8]| {
            decode_png(&here(), &png_bytes((2, 2), color, depth, data, None)).unwrap()
        };
        let g = case(Grayscale, Eight, &grey8);
        assert_eq!((g.width, g.height, g.channels), (2, 2, 1));
        assert_eq!(g.samples, u8s(&grey8));
        assert!(!g.has_alpha());
        let ga: Vec<u8> = (0..8).map(|i| i * 30).collect();
        let t = case(GrayscaleAlpha, Eight, &ga);
        assert_eq!((t.channels, t.samples.clone()), (2, u8s(&ga)));
        assert!(t.has_alpha());
        let rgb: Vec<u8> = (0..12).map(|i| i * 20).collect();
        assert_eq!(case(Rgb, Eight, &rgb).samples, u8s(&rgb));
        let rgba: Vec<u8> = (0..16).map(|i| 255 - i * 15).collect();
        let t = case(Rgba, Eight, &rgba);
        assert_eq!((t.channels, t.samples.clone()), (4, u8s(&rgba)));
        let words: Vec<u16> = (0..16).map(|i| i * 4099 + 7).collect();
        let be: Vec<u8> = words.iter().flat_map(|w| w.to_be_bytes()).collect();
        assert_eq!(
            case(Grayscale, Sixteen, &be[..8]).samples,
            Samples::U16(words[..4].to_vec())
        );
        assert_eq!(
            case(GrayscaleAlpha, Sixteen, &be[..16]).samples,
            Samples::U16(words[..8].to_vec())
        );
        assert_eq!(
            case(Rgb, Sixteen, &be[..24]).samples,
            Samples::U16(words[..12].to_vec())
        );
        let t = case(Rgba, Sixteen, &be);
        assert_eq!(
            (t.channels, t.samples.clone()),
            (4, Samples::U16(words.clone()))
        );
        // 1-bit grey scaled to 8 bits: rows of 2 pixels packed in the high bits of a byte.
        let t = case(Grayscale, One, &[0b1000_0000, 0b0100_0000]);
        assert_eq!(t.samples, u8s(&[255, 0, 0, 255]));
        // Palette: indices expanded to RGB, to RGBA where tRNS gives alphas.
        let entries = [10u8, 20, 30, 200, 210, 220];
        let indices = [0u8, 1, 1, 0];
        let bytes = png_bytes((2, 2), Indexed, Eight, &indices, Some((&entries, &[])));
        let t = decode_png(&here(), &bytes).unwrap();
        assert_eq!(t.channels, 3);
        assert_eq!(
            t.samples,
            u8s(&[10, 20, 30, 200, 210, 220, 200, 210, 220, 10, 20, 30])
        );
        let bytes = png_bytes((2, 2), Indexed, Eight, &indices, Some((&entries, &[77])));
        let t = decode_png(&here(), &bytes).unwrap();
        assert_eq!(t.channels, 4);
        assert_eq!(
            t.samples,
            u8s(&[10, 20, 30, 77, 200, 210, 220, 255, 200, 210, 220, 255, 10, 20, 30, 77])
        );
        // The signature decides the decoder.
        let t = decode_texture_image(&here(), png_bytes((2, 2), Rgb, Eight, &rgb, None)).unwrap();
        assert_eq!(t.format, ImageFormat::Png);
    }

    /// CRC-32 (ISO 3309, as PNG chunks use it).
    fn crc32(bytes: &[u8]) -> u32 {
        let mut crc = !0u32;
        for &b in bytes {
            crc ^= b as u32;
            for _ in 0..8 {
                crc = if crc & 1 == 1 {
                    (crc >> 1) ^ 0xedb8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }

    /// `png` with its IHDR claiming `w` x `h` pixels (CRC made right).
    fn with_png_size(png: &[u8], w: u32, h: u32) -> Vec<u8> {
        let mut b = png.to_vec();
        // Signature 8, IHDR length 4 and type 4, then width and height.
        b[16..20].copy_from_slice(&w.to_be_bytes());
        b[20..24].copy_from_slice(&h.to_be_bytes());
        let crc = crc32(&b[12..29]);
        b[29..33].copy_from_slice(&crc.to_be_bytes());
        b
    }

    #[test]
    fn bad_pngs_are_one_line_errors_naming_the_file() {
        use ::png::{BitDepth::*, ColorType::*};
        let data: Vec<u8> = (0..8 * 8 * 4).map(|i| (i * 7 % 251) as u8).collect();
        let png = png_bytes((8, 8), Rgba, Eight, &data, None);
        assert_eq!(
            crc32(&png[12..29]).to_be_bytes(),
            png[29..33],
            "the test's CRC"
        );
        let error = |bytes: Vec<u8>| {
            let e = decode_texture_image(&here(), bytes)
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("textures/t.png: ") && !e.contains('\n'),
                "{e}"
            );
            e
        };
        // Every prefix that cuts into the pixel data. (One cut later, in the last IDAT's CRC or
        // in IEND, still holds the whole image and decodes.)
        let iend = png.len() - 12;
        for len in 0..iend - 4 {
            error(png[..len].to_vec());
        }
        let e = error(with_png_size(&png, 100_000, 100_000));
        assert!(
            e.contains("claims 100000x100000 pixels, more than the 65536"),
            "{e}"
        );
        let e = error(with_png_size(&png, 65_536, 65_536));
        assert!(e.contains("a 65536x65536 texture needs 47.2 GB"), "{e}");
        let e = error(with_png_size(&png, 0, 8));
        assert!(e.contains("not a readable PNG file"), "{e}");
        // A small file claiming gigabytes of pixel data (crates/fuzz/regressions/texture_png/).
        let e = error(with_png_size(&png, 30_000, 30_000));
        assert!(
            e.contains("claims 30000x30000 pixels, 3.6 GB of pixel data, more than its"),
            "{e}"
        );
        let e = error(b"GIF89a".to_vec());
        assert!(e.contains("not a PNG, JPEG or OpenEXR image"), "{e}");
        // A corrupt pixel stream (the zlib data of IDAT overwritten).
        let mut corrupt = png.clone();
        let idat = corrupt.windows(4).position(|w| w == b"IDAT").unwrap();
        for b in &mut corrupt[idat + 4..idat + 12] {
            *b = 0xff;
        }
        error(corrupt);
    }

    #[test]
    fn exr_channels_decode_as_stored_and_non_finite_values_are_refused() {
        let dir = std::env::temp_dir().join(format!("luxest-teximg-{}", std::process::id()));
        let path = dir.join("lin.exr");
        let mut img = crate::image::RgbImage::new(3, 2);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = [i as f32, -0.5 * i as f32, 1e5];
        }
        crate::exr::write_rgb(&path, &img).unwrap();
        let t = read_texture_image(&path).unwrap();
        assert_eq!(
            (t.width, t.height, t.channels, t.format),
            (3, 2, 3, ImageFormat::Exr)
        );
        let expected: Vec<f32> = img.pixels.iter().flatten().copied().collect();
        assert_eq!(t.samples, Samples::F32(expected));
        img.pixels[4][1] = f32::NAN;
        crate::exr::write_rgb(&path, &img).unwrap();
        let e = read_texture_image(&path).unwrap_err().to_string();
        assert!(
            e.ends_with("lin.exr: non-finite value (NaN or infinity) in channel G at pixel (1, 1)"),
            "{e}"
        );
        let bytes = std::fs::read(&path).unwrap();
        for len in (0..bytes.len()).step_by(7) {
            let e = decode_texture_image(&path, bytes[..len].to_vec()).unwrap_err();
            assert!(e.to_string().contains("lin.exr: "), "{e}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
