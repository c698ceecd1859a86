//! OpenEXR images as the pipeline exchanges them: one 3-channel feature per file (R, G, B as
//! 32-bit float, linear), ZIP scanline compression, string attributes for run metadata; the
//! reader refuses a header whose claims the file or the memory cannot hold.
//!
//! Half floats are never written: photometric values (1e5 cd/m² and more) overflow f16.

use crate::error::{Error, Result};
use crate::image::RgbImage;
use crate::outputs::OutputPlan;
use ::exr::block::chunk::{Chunk, CompressedBlock, CompressedScanLineBlock};
use ::exr::block::writer::ChunksWriter;
use ::exr::image::write::layers::WritableLayers;
use ::exr::prelude::*;
use std::path::Path;

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
    ::exr::block::write(&mut buffer, headers, true, |_, writer| {
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

/// Claims of sample data up to this size are read without the expansion bound below.
const MIN_EXR_CLAIM: u128 = 16 << 20;

/// The largest factor by which `compression` can expand stored bytes into samples, generously:
/// none 1; RLE 64 (two bytes for a run of 128); deflate (ZIP) about 1032, PXR24 4/3 of that;
/// B44 stores a 4x4 block of halves in at least 3 bytes; PIZ's Huffman coding with runs of at
/// most 255 codes stays below 500; the lossy DWA and HTJ2K are bounded at 5000.
fn max_expansion(compression: ::exr::compression::Compression) -> u128 {
    use ::exr::compression::Compression::*;
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

/// Checks an EXR's header before its pixels are read: the image it claims must fit in the memory
/// available (with the RGB copy this reader makes), and the file must be long enough to hold at
/// least the table of chunk offsets the header implies (8 bytes per chunk). A few hundred bytes
/// claiming 100000² pixels are refused here instead of aborting in the allocator.
fn check_exr_size(path: &Path, bytes: &[u8]) -> Result<()> {
    let meta = ::exr::meta::MetaData::read_from_buffered(bytes, false)
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

/// An EXR's first valid layer at its largest resolution, every channel as stored (its size
/// checked against the file's bytes first): what [`read_rgb_bytes`] and the texture decoder
/// read.
pub(crate) fn read_first_layer(
    path: &Path,
    bytes: Vec<u8>,
) -> Result<::exr::image::Image<::exr::image::Layer<::exr::image::AnyChannels<FlatSamples>>>> {
    check_exr_size(path, &bytes)?;
    read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| Error::input(path, format!("not a readable OpenEXR file: {e}")))
}

/// [`read_rgb`] of a file's content `bytes`; `path` names it in errors.
pub fn read_rgb_bytes(path: &Path, bytes: Vec<u8>) -> Result<RgbImage> {
    let image = read_first_layer(path, bytes)?;
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
