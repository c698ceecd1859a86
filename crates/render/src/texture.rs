//! Bitmap textures: an image (PNG, JPEG or OpenEXR, decoded by [`luxest_io::texture_image`])
//! turned into linear RGBA, looked up at a surface point's UV with Mitsuba 3's `bitmap`
//! semantics, plus a mip-map pyramid for minification.
//!
//! - UV convention (glTF's, and Mitsuba 3's after its OBJ loader flips v): (0, 0) is the
//!   top-left corner of the image's top-left texel, u runs right, v runs down; (1, 1) is the
//!   bottom-right corner. A [`UvTransform`] is applied to the UV first: uv' = M · (u, v, 1).
//! - [`Encoding`]: integer images (PNG, JPEG) are sRGB-encoded colours by default, decoded with
//!   the exact IEC 61966-2-1 curve (8-bit samples through a 256-entry table); `Linear` is for
//!   data (roughness, opacity, normal maps). EXR is always linear. Alpha is always linear, and 1
//!   where the image has none; a grey image is replicated into R, G and B.
//! - [`Filter`], as Mitsuba 3's `filter_type` (Dr.Jit's texture): texel (i, j) of a w x h image
//!   has its centre at ((i + ½)/w, (j + ½)/h). `Bilinear` interpolates the four texels around
//!   (u w − ½, v h − ½); `Nearest` takes texel (⌊u w⌋, ⌊v h⌋).
//! - [`Wrap`], as Mitsuba 3's `wrap_mode`, applied to the integer texel index i of a side of n
//!   texels: `Repeat` i mod n; `Clamp` the nearest of 0 and n − 1; `Mirror` the image flipped
//!   every other period (i mod n in even periods ⌊i/n⌋, n − 1 − i mod n in odd ones).
//! - Minification: each mip level halves the previous one's sides (rounded down, at least 1)
//!   and is its exact box filter: a texel of the coarser level is the area-weighted mean of the
//!   finer texels it covers, so odd sizes need no resampling to a power of two. A lookup with
//!   a `footprint` (the side, in UV units, of the square region the result should average;
//!   scaled by the UV transform's [`UvTransform::scale`]) covering more than one texel is the
//!   mean of 2 x 2 trilinear lookups at the centres of the footprint's quarters, each at the
//!   continuous level λ = log2(½ footprint · max(w, h)) (bilinear lookups of the two levels
//!   around λ, interpolated). Against a supersampled box filter of the footprint this has a
//!   third to a fifth of a single trilinear lookup's error on binary detail at footprints of 3
//!   to 6 texels (test `minified_lookups_approach_the_box_filtered_reference`).
//!   `footprint = 0`, or one of a texel or less, is the bilinear lookup of level 0, Mitsuba's.
//!   `Nearest` takes the nearest texel of the level nearest log2 of the footprint in texels.
//!   Channels are filtered independently (alpha is not premultiplied), in linear values.
//!
//! Storage: 8-bit images stay 8-bit and are decoded on lookup (their mip levels are 16-bit
//! linear); 16-bit and EXR images are stored as f32. The compiled scene stores the base level
//! and the options ([`Texture::encode`]); the levels are rebuilt on load.

use luxest_io::color::srgb_decode;
use luxest_io::error::{Error, Result};
use luxest_io::texture_image::{ImageFormat, Samples, TextureImage, MAX_TEXTURE_SIDE};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::LazyLock;

/// How texel indices outside the image map back into it (Mitsuba 3 `wrap_mode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Wrap {
    #[default]
    Repeat,
    Mirror,
    Clamp,
}

/// How a lookup combines texels (Mitsuba 3 `filter_type`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Filter {
    #[default]
    Bilinear,
    Nearest,
}

/// What an integer image's samples encode.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Encoding {
    /// sRGB-encoded colour (IEC 61966-2-1), decoded to linear.
    Srgb,
    /// Linear values: sample / maximum code.
    Linear,
}

/// An affine map of texture coordinates, uv' = M · (u, v, 1), rows of M (glTF's
/// `KHR_texture_transform` and Mitsuba 3's `to_uv` as a matrix). Serialised as the matrix
/// alone: in RON `((m00, m01, m02), (m10, m11, m12))`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct UvTransform(pub [[f64; 3]; 2]);

impl UvTransform {
    pub const IDENTITY: UvTransform = UvTransform([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);

    /// M · (u, v, 1).
    pub fn apply(&self, uv: [f64; 2]) -> [f64; 2] {
        let m = &self.0;
        [
            m[0][0] * uv[0] + m[0][1] * uv[1] + m[0][2],
            m[1][0] * uv[0] + m[1][1] * uv[1] + m[1][2],
        ]
    }
    /// The factor by which the map scales lengths on average: √|det| of its linear part.
    pub fn scale(&self) -> f64 {
        let m = &self.0;
        (m[0][0] * m[1][1] - m[0][1] * m[1][0]).abs().sqrt()
    }
    pub fn is_finite(&self) -> bool {
        self.0.iter().flatten().all(|v| v.is_finite())
    }
}

impl Default for UvTransform {
    fn default() -> Self {
        UvTransform::IDENTITY
    }
}

/// How a texture is built from its image and looked up.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TextureOptions {
    /// `None`: sRGB for PNG and JPEG, linear for EXR.
    pub encoding: Option<Encoding>,
    pub wrap: Wrap,
    pub filter: Filter,
    pub uv_transform: UvTransform,
}

/// The linear value of each 8-bit sRGB code (IEC 61966-2-1).
static SRGB8: LazyLock<[f32; 256]> =
    LazyLock::new(|| std::array::from_fn(|k| srgb_decode(k as f64 / 255.0) as f32));
/// The value of each 8-bit linear code, k / 255.
static UNORM8: LazyLock<[f32; 256]> = LazyLock::new(|| std::array::from_fn(|k| k as f32 / 255.0));

/// The linear value of 8-bit sRGB code `k` (the table lookups decode with).
pub fn srgb8_to_linear(k: u8) -> f32 {
    SRGB8[k as usize]
}

#[derive(Clone, Debug, PartialEq)]
enum Texels {
    /// 8-bit codes, R, G, B decoded by the texture's table, A by k / 255 (level 0 of 8-bit
    /// images).
    U8(Vec<[u8; 4]>),
    /// Linear values k / 65535 (the mip levels of 8-bit images: their quantisation, 8e-6, is
    /// far below 8-bit sRGB's, which would bias a grey mean of 0.5 by 0.6 %).
    U16(Vec<[u16; 4]>),
    /// Linear values.
    F32(Vec<[f32; 4]>),
}

impl Texels {
    /// Linear RGBA of texel `index`; `rgb_table` decodes 8-bit R, G, B.
    fn get(&self, index: usize, rgb_table: &[f32; 256]) -> [f32; 4] {
        match self {
            Texels::U8(v) => {
                let p = v[index];
                [
                    rgb_table[p[0] as usize],
                    rgb_table[p[1] as usize],
                    rgb_table[p[2] as usize],
                    p[3] as f32 / 255.0,
                ]
            }
            Texels::U16(v) => v[index].map(|k| k as f32 * (1.0 / 65535.0)),
            Texels::F32(v) => v[index],
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
struct Level {
    width: usize,
    height: usize,
    texels: Texels,
}

/// A decoded, mip-mapped bitmap texture (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Level 0 is the image; each further level halves the sides, down to 1 x 1.
    levels: Vec<Level>,
    encoding: Encoding,
    wrap: Wrap,
    filter: Filter,
    uv_transform: UvTransform,
    has_alpha: bool,
    /// R, G, B decoding table of 8-bit levels.
    rgb_table: &'static [f32; 256],
}

impl Texture {
    /// Reads the image `path` and builds its texture.
    pub fn load(path: &Path, options: &TextureOptions) -> Result<Texture> {
        let image = luxest_io::texture_image::read_texture_image(path)?;
        Texture::from_image(&image, options).map_err(|m| Error::input(path, m))
    }

    /// Builds the texture of a decoded image. Fails on an sRGB encoding asked of an EXR, a
    /// non-finite UV transform or an inconsistent image.
    pub fn from_image(
        image: &TextureImage,
        options: &TextureOptions,
    ) -> std::result::Result<Texture, String> {
        let (w, h, c) = (image.width, image.height, image.channels);
        if w == 0 || h == 0 || !(1..=4).contains(&c) || image.samples.len() != w * h * c {
            return Err(format!(
                "inconsistent image: {w}x{h} pixels of {c} channels with {} samples",
                image.samples.len()
            ));
        }
        let encoding = match (options.encoding, image.format) {
            (Some(Encoding::Srgb), ImageFormat::Exr) => {
                return Err("an OpenEXR texture is linear; encoding Srgb does not apply".into())
            }
            (Some(e), _) => e,
            (None, f) if f.is_integer() => Encoding::Srgb,
            (None, _) => Encoding::Linear,
        };
        // Grey, grey + alpha, RGB, RGBA → RGBA.
        let rgba = |s: &[f32]| -> [f32; 4] {
            match s.len() {
                1 => [s[0], s[0], s[0], 1.0],
                2 => [s[0], s[0], s[0], s[1]],
                3 => [s[0], s[1], s[2], 1.0],
                _ => [s[0], s[1], s[2], s[3]],
            }
        };
        let texels = match &image.samples {
            Samples::U8(v) => Texels::U8(
                v.chunks_exact(c)
                    .map(|s| match s.len() {
                        1 => [s[0], s[0], s[0], 255],
                        2 => [s[0], s[0], s[0], s[1]],
                        3 => [s[0], s[1], s[2], 255],
                        _ => [s[0], s[1], s[2], s[3]],
                    })
                    .collect(),
            ),
            Samples::U16(v) => {
                // Grey (and alpha): one colour sample; RGB (and alpha): three.
                let colour_samples = if c <= 2 { 1 } else { 3 };
                Texels::F32(
                    v.chunks_exact(c)
                        .map(|s| {
                            let mut p = [0f32; 4];
                            for (i, &k) in s.iter().enumerate() {
                                let x = k as f64 / 65535.0;
                                let srgb = i < colour_samples && encoding == Encoding::Srgb;
                                p[i] = if srgb { srgb_decode(x) } else { x } as f32;
                            }
                            rgba(&p[..c])
                        })
                        .collect(),
                )
            }
            Samples::F32(v) => {
                if let Some(x) = v.iter().find(|x| !x.is_finite()) {
                    return Err(format!("non-finite texel value {x}"));
                }
                Texels::F32(v.chunks_exact(c).map(rgba).collect())
            }
        };
        Texture::build(
            Level {
                width: w,
                height: h,
                texels,
            },
            encoding,
            options,
            image.has_alpha(),
        )
    }

    fn build(
        base: Level,
        encoding: Encoding,
        options: &TextureOptions,
        has_alpha: bool,
    ) -> std::result::Result<Texture, String> {
        if !options.uv_transform.is_finite() {
            return Err(format!(
                "UV transform {:?} is not finite",
                options.uv_transform.0
            ));
        }
        let rgb_table: &'static [f32; 256] = match encoding {
            Encoding::Srgb => &SRGB8,
            Encoding::Linear => &UNORM8,
        };
        let mut levels = vec![base];
        loop {
            let last = levels.last().expect("level 0");
            if last.width == 1 && last.height == 1 {
                break;
            }
            let next = downsample(last, rgb_table);
            levels.push(next);
        }
        Ok(Texture {
            levels,
            encoding,
            wrap: options.wrap,
            filter: options.filter,
            uv_transform: options.uv_transform,
            has_alpha,
            rgb_table,
        })
    }

    pub fn width(&self) -> usize {
        self.levels[0].width
    }
    pub fn height(&self) -> usize {
        self.levels[0].height
    }
    /// The number of mip levels, the image included.
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }
    /// Width and height of mip level `level`.
    pub fn level_size(&self, level: usize) -> (usize, usize) {
        (self.levels[level].width, self.levels[level].height)
    }
    pub fn encoding(&self) -> Encoding {
        self.encoding
    }
    pub fn wrap(&self) -> Wrap {
        self.wrap
    }
    pub fn filter(&self) -> Filter {
        self.filter
    }
    pub fn uv_transform(&self) -> UvTransform {
        self.uv_transform
    }
    /// Whether the image had an alpha channel (without one, alpha is 1 everywhere).
    pub fn has_alpha(&self) -> bool {
        self.has_alpha
    }
    /// Bytes the texels of all levels take.
    pub fn memory_bytes(&self) -> usize {
        self.levels
            .iter()
            .map(|l| match &l.texels {
                Texels::U8(v) => v.len() * 4,
                Texels::U16(v) => v.len() * 8,
                Texels::F32(v) => v.len() * 16,
            })
            .sum()
    }

    /// Texel (x, y) of mip level `level`, linear RGBA.
    pub fn texel(&self, level: usize, x: usize, y: usize) -> [f32; 4] {
        let l = &self.levels[level];
        self.decode_texel(l, y * l.width + x)
    }

    fn decode_texel(&self, level: &Level, index: usize) -> [f32; 4] {
        level.texels.get(index, self.rgb_table)
    }

    /// The texture's linear RGBA at `uv` (before the UV transform), averaged over a square
    /// of side `footprint` in UV units (0: no minification filtering; see the module
    /// documentation). A non-finite UV (given, or after the transform) is read as 0, a
    /// non-finite or negative footprint as 0.
    pub fn eval(&self, uv: [f64; 2], footprint: f64) -> [f32; 4] {
        let finite = |x: f64| if x.is_finite() { x } else { 0.0 };
        let uv = self.uv_transform.apply(uv.map(finite)).map(finite);
        let width = footprint * self.uv_transform.scale();
        // The footprint in level-0 texels along the longer side.
        let texels = if width.is_finite() {
            width * self.width().max(self.height()) as f64
        } else {
            0.0
        };
        if self.filter == Filter::Nearest {
            let level = texels.max(1.0).log2().round() as usize;
            return self.nearest(level.min(self.levels.len() - 1), uv);
        }
        if texels <= 1.0 {
            return self.bilinear(0, uv);
        }
        // 2 x 2 trilinear lookups, each over a quarter of the footprint.
        let q = 0.25 * width;
        let lambda = (0.5 * texels).log2();
        let mut sum = [0f64; 4];
        for d in [[-q, -q], [q, -q], [-q, q], [q, q]] {
            let v = self.trilinear([uv[0] + d[0], uv[1] + d[1]], lambda);
            for c in 0..4 {
                sum[c] += v[c] as f64;
            }
        }
        sum.map(|s| (0.25 * s) as f32)
    }

    /// Trilinear lookup at (transformed) `uv`: bilinear lookups of the levels around the
    /// continuous level `lambda` (clamped to the pyramid), interpolated.
    fn trilinear(&self, uv: [f64; 2], lambda: f64) -> [f32; 4] {
        let lambda = lambda.clamp(0.0, (self.levels.len() - 1) as f64);
        let l0 = lambda.floor() as usize;
        let t = lambda - l0 as f64;
        let a = self.bilinear(l0, uv);
        if t == 0.0 || l0 + 1 >= self.levels.len() {
            return a;
        }
        let b = self.bilinear(l0 + 1, uv);
        std::array::from_fn(|c| ((1.0 - t) * a[c] as f64 + t * b[c] as f64) as f32)
    }

    /// Bilinear lookup of level `level` at (transformed) `uv`.
    fn bilinear(&self, level: usize, uv: [f64; 2]) -> [f32; 4] {
        let l = &self.levels[level];
        let x = texel_coordinate(uv[0] * l.width as f64 - 0.5);
        let y = texel_coordinate(uv[1] * l.height as f64 - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let (xa, xb) = (
            wrap(self.wrap, x0, l.width),
            wrap(self.wrap, x0 + 1, l.width),
        );
        let (ya, yb) = (
            wrap(self.wrap, y0, l.height) * l.width,
            wrap(self.wrap, y0 + 1, l.height) * l.width,
        );
        let texels = [ya + xa, ya + xb, yb + xa, yb + xb].map(|i| self.decode_texel(l, i));
        let weights = [
            (1.0 - fx) * (1.0 - fy),
            fx * (1.0 - fy),
            (1.0 - fx) * fy,
            fx * fy,
        ];
        std::array::from_fn(|c| {
            (0..4)
                .map(|k| weights[k] * texels[k][c] as f64)
                .sum::<f64>() as f32
        })
    }

    /// Nearest-texel lookup of level `level` at (transformed) `uv`.
    fn nearest(&self, level: usize, uv: [f64; 2]) -> [f32; 4] {
        let l = &self.levels[level];
        let x = texel_coordinate(uv[0] * l.width as f64).floor() as i64;
        let y = texel_coordinate(uv[1] * l.height as f64).floor() as i64;
        let (tx, ty) = (wrap(self.wrap, x, l.width), wrap(self.wrap, y, l.height));
        self.decode_texel(l, ty * l.width + tx)
    }

    /// The mean linear RGBA of the image's texels (f64). It equals the integral of either
    /// filter's lookup over the unit UV square, for every wrap mode.
    pub fn average(&self) -> [f64; 4] {
        let l = &self.levels[0];
        let mut sum = [0f64; 4];
        for i in 0..l.width * l.height {
            let t = self.decode_texel(l, i);
            for c in 0..4 {
                sum[c] += t[c] as f64;
            }
        }
        sum.map(|s| s / (l.width * l.height) as f64)
    }

    /// The mean linear RGBA of the texture over a triangle with UVs `uv` (before the UV
    /// transform; the map from a triangle's surface to its UVs is affine, so this is also the
    /// mean over its surface): the triangle is cut into n² congruent triangles and the lookups
    /// at their centroids averaged, each filtered over a footprint of a cell's size. n is
    /// enough for cells of at most ¼ texel (then the lookups are level 0's, and the mean is
    /// the midpoint rule of the bilinear image), from 4 up to [`TRIANGLE_MEAN_MAX_CELLS`].
    pub fn mean_over_triangle(&self, uv: [[f64; 2]; 3]) -> [f64; 4] {
        let (a, b, c) = (uv[0], uv[1], uv[2]);
        let e1 = [b[0] - a[0], b[1] - a[1]];
        let e2 = [c[0] - a[0], c[1] - a[1]];
        let area = 0.5 * (e1[0] * e2[1] - e1[1] * e2[0]).abs();
        let texels =
            area * self.uv_transform.scale().powi(2) * (self.width() * self.height()) as f64;
        let n = if texels.is_finite() {
            ((2.0 * texels.sqrt()).ceil() as usize).clamp(4, TRIANGLE_MEAN_MAX_CELLS)
        } else {
            TRIANGLE_MEAN_MAX_CELLS
        };
        let footprint = (area / (n * n) as f64).sqrt();
        let mut sum = [0f64; 4];
        let mut add = |s: f64, t: f64| {
            let p = [a[0] + s * e1[0] + t * e2[0], a[1] + s * e1[1] + t * e2[1]];
            let v = self.eval(p, footprint);
            for k in 0..4 {
                sum[k] += v[k] as f64;
            }
        };
        let nf = n as f64;
        for i in 0..n {
            for j in 0..n - i {
                // The cell (i, j) pointing like the triangle, and the inverted one beside it.
                add((i as f64 + 1.0 / 3.0) / nf, (j as f64 + 1.0 / 3.0) / nf);
                if i + j + 1 < n {
                    add((i as f64 + 2.0 / 3.0) / nf, (j as f64 + 2.0 / 3.0) / nf);
                }
            }
        }
        sum.map(|s| s / (n * n) as f64)
    }
}

/// The first bytes of an encoded texture.
const ENCODED_MAGIC: &[u8; 4] = b"LXTX";
/// Bumped whenever the encoded layout changes.
const ENCODED_VERSION: u32 = 1;
/// Magic, version, width, height, storage, encoding, wrap, filter, alpha, 3 reserved bytes and
/// the six f64 of the UV transform.
const ENCODED_HEADER_LEN: usize = 4 + 4 + 4 + 4 + 8 + 48;

impl Texture {
    /// Appends the texture as the compiled scene stores it (little-endian):
    ///
    /// ```text
    /// magic "LXTX", version u32, width u32, height u32,
    /// storage u8 (0: 8-bit, 1: f32, 2: 16-bit linear), encoding u8 (0: sRGB, 1: linear; of
    /// 8-bit R, G, B),
    /// wrap u8 (0: repeat, 1: mirror, 2: clamp), filter u8 (0: bilinear, 1: nearest),
    /// has_alpha u8, 3 reserved bytes 0, UV transform 6 f64 (row-major),
    /// level 0 texels, RGBA row-major from the top: 4 u8, 4 f32 or 4 u16 each.
    /// ```
    ///
    /// Mip levels are not stored: [`Texture::decode`] rebuilds them.
    pub fn encode(&self, out: &mut Vec<u8>) {
        let base = &self.levels[0];
        out.extend_from_slice(ENCODED_MAGIC);
        out.extend_from_slice(&ENCODED_VERSION.to_le_bytes());
        out.extend_from_slice(&(base.width as u32).to_le_bytes());
        out.extend_from_slice(&(base.height as u32).to_le_bytes());
        out.push(match base.texels {
            Texels::U8(_) => 0,
            Texels::F32(_) => 1,
            Texels::U16(_) => 2,
        });
        out.push(match self.encoding {
            Encoding::Srgb => 0,
            Encoding::Linear => 1,
        });
        out.push(match self.wrap {
            Wrap::Repeat => 0,
            Wrap::Mirror => 1,
            Wrap::Clamp => 2,
        });
        out.push(match self.filter {
            Filter::Bilinear => 0,
            Filter::Nearest => 1,
        });
        out.push(self.has_alpha as u8);
        out.extend_from_slice(&[0; 3]);
        for v in self.uv_transform.0.iter().flatten() {
            out.extend_from_slice(&v.to_le_bytes());
        }
        match &base.texels {
            Texels::U8(v) => {
                out.reserve(v.len() * 4);
                for p in v {
                    out.extend_from_slice(p);
                }
            }
            Texels::U16(v) => {
                out.reserve(v.len() * 8);
                for k in v.iter().flatten() {
                    out.extend_from_slice(&k.to_le_bytes());
                }
            }
            Texels::F32(v) => {
                out.reserve(v.len() * 16);
                for x in v.iter().flatten() {
                    out.extend_from_slice(&x.to_le_bytes());
                }
            }
        }
    }

    /// Reads a texture written by [`Texture::encode`] from the start of `bytes`; returns it and
    /// the number of bytes it took. Every field is checked (tags, sizes against
    /// [`MAX_TEXTURE_SIDE`] and the memory available, the length, finite values), so corrupt
    /// bytes are an error naming `path`, never a panic.
    pub fn decode(path: &Path, bytes: &[u8]) -> Result<(Texture, usize)> {
        let bad = |m: String| Error::input(path, format!("corrupt texture in compiled scene: {m}"));
        let header = bytes
            .get(..ENCODED_HEADER_LEN)
            .ok_or_else(|| bad("truncated header".into()))?;
        if &header[..4] != ENCODED_MAGIC {
            return Err(bad("bad magic".into()));
        }
        let u32_at = |i: usize| u32::from_le_bytes(header[i..i + 4].try_into().expect("4 bytes"));
        let version = u32_at(4);
        if version != ENCODED_VERSION {
            return Err(bad(format!(
                "version {version}, this program reads {ENCODED_VERSION}"
            )));
        }
        let (width, height) = (u32_at(8) as u64, u32_at(12) as u64);
        if width == 0 || height == 0 || width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
            return Err(bad(format!(
                "size {width}x{height} (sides from 1 to {MAX_TEXTURE_SIDE})"
            )));
        }
        let tag = |i: usize, what: &str, n: u8| {
            if header[i] < n {
                Ok(header[i])
            } else {
                Err(bad(format!("{what} tag {}", header[i])))
            }
        };
        let storage = tag(16, "storage", 3)?;
        let encoding = [Encoding::Srgb, Encoding::Linear][tag(17, "encoding", 2)? as usize];
        let wrap = [Wrap::Repeat, Wrap::Mirror, Wrap::Clamp][tag(18, "wrap", 3)? as usize];
        let filter = [Filter::Bilinear, Filter::Nearest][tag(19, "filter", 2)? as usize];
        let has_alpha = tag(20, "alpha", 2)? == 1;
        if header[21..24] != [0; 3] {
            return Err(bad("reserved bytes not zero".into()));
        }
        let f64_at = |k: usize| {
            let i = 24 + 8 * k;
            f64::from_le_bytes(header[i..i + 8].try_into().expect("8 bytes"))
        };
        let uv_transform = UvTransform([
            [f64_at(0), f64_at(1), f64_at(2)],
            [f64_at(3), f64_at(4), f64_at(5)],
        ]);
        let texel_bytes: u64 = [4, 16, 8][storage as usize];
        // Level 0, the pyramid (a third more) and the encoded copy.
        luxest_io::limits::check_image("texture", width, height, texel_bytes * 2 + texel_bytes / 2)
            .map_err(|m| Error::input(path, m))?;
        let count = (width * height) as usize;
        let len = ENCODED_HEADER_LEN + count * texel_bytes as usize;
        let data = bytes.get(ENCODED_HEADER_LEN..len).ok_or_else(|| {
            bad(format!(
                "truncated texels ({width}x{height} need {} bytes, {} left)",
                len - ENCODED_HEADER_LEN,
                bytes.len() - ENCODED_HEADER_LEN
            ))
        })?;
        let texels = match storage {
            0 => Texels::U8(
                data.chunks_exact(4)
                    .map(|c| [c[0], c[1], c[2], c[3]])
                    .collect(),
            ),
            2 => Texels::U16(
                data.chunks_exact(8)
                    .map(|c| std::array::from_fn(|k| u16::from_le_bytes([c[2 * k], c[2 * k + 1]])))
                    .collect(),
            ),
            _ => {
                let values: Vec<[f32; 4]> = data
                    .chunks_exact(16)
                    .map(|c| {
                        std::array::from_fn(|k| {
                            f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().expect("4 bytes"))
                        })
                    })
                    .collect();
                if let Some(i) = values.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
                    return Err(bad(format!("non-finite value in texel {i}")));
                }
                Texels::F32(values)
            }
        };
        let options = TextureOptions {
            encoding: Some(encoding),
            wrap,
            filter,
            uv_transform,
        };
        let base = Level {
            width: width as usize,
            height: height as usize,
            texels,
        };
        let texture = Texture::build(base, encoding, &options, has_alpha).map_err(bad)?;
        Ok((texture, len))
    }
}

/// The most cells along a side in [`Texture::mean_over_triangle`] (65536 lookups).
pub const TRIANGLE_MEAN_MAX_CELLS: usize = 256;

/// A texel coordinate kept where i64 indices (and index + 1) cannot overflow: far beyond any
/// texture's side, where single texels are no longer resolved by f64 anyway.
fn texel_coordinate(x: f64) -> f64 {
    x.clamp(-1e15, 1e15)
}

/// The texel index of a side of `n` texels that index `i` wraps to.
fn wrap(mode: Wrap, i: i64, n: usize) -> usize {
    let n = n as i64;
    (match mode {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Mirror => {
            let m = i.rem_euclid(n);
            if i.div_euclid(n) % 2 == 0 {
                m
            } else {
                n - 1 - m
            }
        }
    }) as usize
}

/// The box-filter weights of resampling a side of `n` texels to `m` (m ≤ n): output texel j
/// covers input texels [j n/m, (j + 1) n/m); the first input texel it overlaps and the
/// overlapped fraction of each, normalised.
fn box_weights(n: usize, m: usize) -> Vec<(usize, Vec<f64>)> {
    let ratio = n as f64 / m as f64;
    (0..m)
        .map(|j| {
            let (lo, hi) = (j as f64 * ratio, (j + 1) as f64 * ratio);
            let first = lo.floor() as usize;
            let last = (hi.ceil() as usize).min(n);
            let weights = (first..last)
                .map(|i| (hi.min(i as f64 + 1.0) - lo.max(i as f64)).max(0.0) / ratio)
                .collect();
            (first, weights)
        })
        .collect()
}

/// The next mip level of `level`: sides halved (rounded down, at least 1), each texel the
/// box-filtered mean of the linear values it covers; stored as f32 if `level` is, else as
/// 16-bit linear values.
fn downsample(level: &Level, rgb_table: &[f32; 256]) -> Level {
    let (w, h) = (level.width, level.height);
    let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
    let wx = box_weights(w, nw);
    let wy = box_weights(h, nh);
    let linear = |index: usize| level.texels.get(index, rgb_table).map(|x| x as f64);
    let mut out = Vec::with_capacity(nw * nh);
    let mut row = vec![[0f64; 4]; w];
    for (y0, weights_y) in &wy {
        row.fill([0.0; 4]);
        for (dy, &wgt) in weights_y.iter().enumerate() {
            for (x, r) in row.iter_mut().enumerate() {
                let t = linear((y0 + dy) * w + x);
                for c in 0..4 {
                    r[c] += wgt * t[c];
                }
            }
        }
        for (x0, weights_x) in &wx {
            let mut p = [0f64; 4];
            for (dx, &wgt) in weights_x.iter().enumerate() {
                for c in 0..4 {
                    p[c] += wgt * row[x0 + dx][c];
                }
            }
            out.push(p);
        }
    }
    let texels = match level.texels {
        Texels::U8(_) | Texels::U16(_) => Texels::U16(
            out.iter()
                .map(|p| p.map(|v| (v.clamp(0.0, 1.0) * 65535.0).round() as u16))
                .collect(),
        ),
        Texels::F32(_) => Texels::F32(out.iter().map(|p| p.map(|v| v as f32)).collect()),
    };
    Level {
        width: nw,
        height: nh,
        texels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn data(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/texture")
            .join(name)
    }

    /// A linear f32 texture of `w` x `h` texels `f(x, y)` (RGBA).
    fn linear(
        w: usize,
        h: usize,
        options: TextureOptions,
        f: impl Fn(usize, usize) -> [f32; 4],
    ) -> Texture {
        let samples = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .flat_map(|(x, y)| f(x, y))
            .collect();
        let image = TextureImage {
            width: w,
            height: h,
            channels: 4,
            samples: Samples::F32(samples),
            format: ImageFormat::Exr,
        };
        Texture::from_image(&image, &options).unwrap()
    }

    fn options(wrap: Wrap, filter: Filter) -> TextureOptions {
        TextureOptions {
            wrap,
            filter,
            ..TextureOptions::default()
        }
    }

    #[test]
    fn textures_are_shared_between_render_threads() {
        fn shared<T: Send + Sync>() {}
        shared::<Texture>();
    }

    #[test]
    fn srgb_table_holds_the_iec_61966_2_1_curve() {
        assert_eq!(srgb8_to_linear(0), 0.0);
        assert_eq!(srgb8_to_linear(255), 1.0);
        // Linear segment below 0.04045 (code 10), power segment from code 11.
        assert_eq!(srgb8_to_linear(10), (10.0 / 255.0 / 12.92) as f32);
        assert_eq!(srgb8_to_linear(11), 0.003_346_535_8);
        assert_eq!(srgb8_to_linear(128), 0.215_860_5);
        assert_eq!(srgb8_to_linear(188), 0.502_886_5);
        assert!((1..=255).all(|k| srgb8_to_linear(k) > srgb8_to_linear(k - 1)));
    }

    #[test]
    fn wrap_modes_and_filters_match_hand_computed_lookups() {
        // One row of three texels, red 0, 1, 10; centres at u = 1/6, 1/2, 5/6.
        let row = |wrap, filter| {
            linear(3, 1, options(wrap, filter), |x, _| {
                [[0.0, 1.0, 10.0][x], 0.0, 0.0, 1.0]
            })
        };
        let red = |t: &Texture, u: f64| t.eval([u, 0.5], 0.0)[0];
        use {Filter::*, Wrap::*};
        // Nearest: texel ⌊3u⌋, wrapped.
        for (u, repeat, mirror, clamp) in [
            (0.5, 1.0, 1.0, 1.0),
            (-0.2, 10.0, 0.0, 0.0),   // index −1
            (-0.4, 1.0, 1.0, 0.0),    // index −2
            (1.1, 0.0, 10.0, 10.0),   // index 3
            (1.5, 1.0, 1.0, 10.0),    // index 4
            (2.2, 0.0, 0.0, 10.0),    // index 6: period 2, not mirrored
            (-1.05, 10.0, 10.0, 0.0), // index −4: period −2, not mirrored: texel 2
        ] {
            assert_eq!(red(&row(Repeat, Nearest), u), repeat, "repeat u={u}");
            assert_eq!(red(&row(Mirror, Nearest), u), mirror, "mirror u={u}");
            assert_eq!(red(&row(Clamp, Nearest), u), clamp, "clamp u={u}");
        }
        // Bilinear: x = 3u − ½ between texels ⌊x⌋ and ⌊x⌋ + 1.
        for (u, repeat, mirror, clamp) in [
            (0.5, 1.0, 1.0, 1.0),
            (0.25, 0.25, 0.25, 0.25), // x = 0.25
            (0.0, 5.0, 0.0, 0.0),     // x = −0.5: texels −1 and 0
            (1.0, 5.0, 10.0, 10.0),   // x = 2.5: texels 2 and 3
            (0.75, 7.75, 7.75, 7.75), // x = 1.75
            (-0.25, 7.75, 0.25, 0.0), // x = −1.25: ¼ texel −2 (1 / 1 / 0), ¾ −1 (10 / 0 / 0)
        ] {
            let close = |a: f32, b: f64| (a as f64 - b).abs() < 1e-6;
            assert!(
                close(red(&row(Repeat, Bilinear), u), repeat),
                "repeat u={u}"
            );
            assert!(
                close(red(&row(Mirror, Bilinear), u), mirror),
                "mirror u={u}"
            );
            assert!(close(red(&row(Clamp, Bilinear), u), clamp), "clamp u={u}");
        }
        // Two dimensions: the four texels around (u w − ½, v h − ½), weights (1 − fx)(1 − fy)...
        let t = linear(2, 2, options(Clamp, Bilinear), |x, y| {
            [(x + 2 * y) as f32, 0.0, 0.0, 1.0]
        });
        let v = t.eval([0.5, 0.5], 0.0)[0] as f64;
        assert!((v - 1.5).abs() < 1e-6, "{v}");
        let v = t.eval([0.4, 0.6], 0.0)[0] as f64;
        // x = 0.3, y = 0.7: 0·0.7·0.3 + 1·0.3·0.3 + 2·0.7·0.7 + 3·0.3·0.7.
        assert!((v - (0.09 + 0.98 + 0.63)).abs() < 1e-6, "{v}");
        // The UV transform applies first: u' = 2u + 0.1, v' = v.
        let scaled = linear(
            3,
            1,
            TextureOptions {
                uv_transform: UvTransform([[2.0, 0.0, 0.1], [0.0, 1.0, 0.0]]),
                ..options(Clamp, Bilinear)
            },
            |x, _| [[0.0, 1.0, 10.0][x], 0.0, 0.0, 1.0],
        );
        // u = 0.075 → u' = 0.25 → 0.25 as above.
        assert!((red(&scaled, 0.075) - 0.25).abs() < 1e-6);
        // Non-finite UVs read as (0, 0), also where the transform overflows.
        assert_eq!(red(&row(Clamp, Nearest), f64::NAN), 0.0);
        assert_eq!(red(&scaled, 1e308), 0.0);
    }

    /// The rows of a committed CSV table (header skipped), split at commas.
    fn table(name: &str) -> Vec<Vec<String>> {
        let text = std::fs::read_to_string(data(name)).unwrap();
        text.lines()
            .skip(1)
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect()
    }

    #[test]
    fn lookups_match_mitsuba_3_bitmap() {
        // crates/render/tests/data/texture/mitsuba_bitmap.py: Mitsuba 3.9 `bitmap` of a 5x3
        // 8-bit sRGB PNG, every wrap mode x filter x raw/sRGB x two `to_uv`, at 36 UVs each.
        let rows = table("mitsuba_bitmap.csv");
        assert_eq!(rows.len(), 3 * 2 * 2 * 2 * 36);
        let affine = UvTransform([[2.0, 0.5, 0.1], [-0.3, 1.5, 0.25]]);
        let mut worst = 0f64;
        for row in &rows {
            let wrap = match row[0].as_str() {
                "repeat" => Wrap::Repeat,
                "mirror" => Wrap::Mirror,
                _ => Wrap::Clamp,
            };
            let filter = match row[1].as_str() {
                "bilinear" => Filter::Bilinear,
                _ => Filter::Nearest,
            };
            let options = TextureOptions {
                encoding: Some(if row[2] == "1" {
                    Encoding::Linear
                } else {
                    Encoding::Srgb
                }),
                wrap,
                filter,
                uv_transform: if row[3] == "1" {
                    affine
                } else {
                    UvTransform::IDENTITY
                },
            };
            let texture = Texture::load(&data("bitmap.png"), &options).unwrap();
            let num = |i: usize| row[i].parse::<f64>().unwrap();
            let got = texture.eval([num(4), num(5)], 0.0);
            for c in 0..3 {
                let error = (got[c] as f64 - num(6 + c)).abs();
                worst = worst.max(error);
                assert!(error < 2e-6, "{row:?}: ours {got:?}");
            }
            assert_eq!(got[3], 1.0);
        }
        assert!(worst < 2e-6, "{worst}");
    }

    #[test]
    fn mip_levels_are_exact_box_filters_of_odd_sizes() {
        // 5x3, red = x, green = y: level 1 is 2x1, texel 0 covers x ∈ [0, 2.5) (weights 0.4,
        // 0.4, 0.2), texel 1 covers [2.5, 5); one row covering y ∈ [0, 3).
        let t = linear(5, 3, TextureOptions::default(), |x, y| {
            [x as f32, y as f32, 0.0, 1.0]
        });
        assert_eq!(t.level_count(), 3);
        assert_eq!((t.level_size(1), t.level_size(2)), ((2, 1), (1, 1)));
        let close = |a: [f32; 4], b: [f32; 4]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6);
        assert!(
            close(t.texel(1, 0, 0), [0.8, 1.0, 0.0, 1.0]),
            "{:?}",
            t.texel(1, 0, 0)
        );
        assert!(
            close(t.texel(1, 1, 0), [3.2, 1.0, 0.0, 1.0]),
            "{:?}",
            t.texel(1, 1, 0)
        );
        assert!(close(t.texel(2, 0, 0), [2.0, 1.0, 0.0, 1.0]));
        // Every level keeps the image's mean, whatever the sizes.
        let t = linear(37, 23, TextureOptions::default(), |x, y| {
            let h = ((x * 7919 + y * 104_729) as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
            [(h >> 40) as f32 / (1u64 << 24) as f32, 0.5, 0.0, 1.0]
        });
        let sizes: Vec<_> = (0..t.level_count()).map(|l| t.level_size(l)).collect();
        assert_eq!(sizes, [(37, 23), (18, 11), (9, 5), (4, 2), (2, 1), (1, 1)]);
        let mean = t.average()[0];
        for l in 0..t.level_count() {
            let (w, h) = t.level_size(l);
            let sum: f64 = (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| t.texel(l, x, y)[0] as f64)
                .sum();
            assert!((sum / (w * h) as f64 - mean).abs() < 1e-6, "level {l}");
        }
    }

    /// An 8-bit sRGB grey texture of `n` x `n` texels, black where `black(x, y)`.
    fn binary(n: usize, wrap: Wrap, black: impl Fn(usize, usize) -> bool) -> Texture {
        let samples = (0..n)
            .flat_map(|y| (0..n).map(move |x| (x, y)))
            .map(|(x, y)| if black(x, y) { 0 } else { 255 })
            .collect();
        let image = TextureImage {
            width: n,
            height: n,
            channels: 1,
            samples: Samples::U8(samples),
            format: ImageFormat::Png,
        };
        Texture::from_image(&image, &options(wrap, Filter::Bilinear)).unwrap()
    }

    /// A checkerboard of 3-texel squares (a period the pyramid's halving never divides).
    fn checkerboard(n: usize) -> Texture {
        binary(n, Wrap::Repeat, |x, y| (x / 3 + y / 3) % 2 == 0)
    }

    /// Text-like detail: lines of 8 texel rows with 4 between, strokes of pseudo-random texels.
    fn text_like(n: usize) -> Texture {
        binary(n, Wrap::Repeat, |x, y| {
            let h = ((x / 2 * 7919 + y * 104_729) as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
            y % 12 < 8 && (h >> 61) < 3
        })
    }

    /// The mean of level-0 bilinear lookups over the square of side `footprint` around `uv`,
    /// on a k x k grid of cell centres (k up to 4 samples a texel): the supersampled reference
    /// of a filtered lookup.
    fn supersampled(t: &Texture, uv: [f64; 2], footprint: f64) -> f64 {
        let k = ((4.0 * footprint * t.width() as f64).ceil() as usize).clamp(8, 96);
        let mut sum = 0.0;
        for i in 0..k {
            for j in 0..k {
                let u = uv[0] + footprint * ((i as f64 + 0.5) / k as f64 - 0.5);
                let v = uv[1] + footprint * ((j as f64 + 0.5) / k as f64 - 0.5);
                sum += t.eval([u, v], 0.0)[0] as f64;
            }
        }
        sum / (k * k) as f64
    }

    /// RMS errors against the supersampled reference, over 64 fixed UVs and a footprint of
    /// `texels`: of `eval` (2 x 2 trilinear), of one trilinear lookup at λ = log2(texels), and
    /// of the point (level-0 bilinear) lookup.
    fn minification_errors(t: &Texture, texels: f64) -> [f64; 3] {
        let footprint = texels / t.width() as f64;
        let mut squares = [0f64; 3];
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..64 {
            let uv = [next(), next()];
            let reference = supersampled(t, uv, footprint);
            let lookups = [
                t.eval(uv, footprint),
                t.trilinear(uv, texels.log2()),
                t.eval(uv, 0.0),
            ];
            for (s, v) in squares.iter_mut().zip(lookups) {
                *s += (v[0] as f64 - reference).powi(2);
            }
        }
        squares.map(|s| (s / 64.0).sqrt())
    }

    #[test]
    fn minified_lookups_approach_the_box_filtered_reference() {
        // Footprints of 3 to 48 texels on binary detail: the point lookup aliases (RMS error
        // 0.16 to 0.39); `eval` stays within an eighth of that, and below one trilinear lookup.
        for (name, t) in [
            ("checkerboard", checkerboard(256)),
            ("text", text_like(256)),
        ] {
            for texels in [3.0, 6.0, 12.0, 24.0, 48.0] {
                let [filtered, trilinear, point] = minification_errors(&t, texels);
                eprintln!(
                    "{name}, footprint {texels} texels: RMS error 2x2 trilinear {filtered:.4}, \
                     trilinear {trilinear:.4}, point {point:.4}"
                );
                assert!(
                    filtered < 0.12 * point,
                    "{name} {texels}: {filtered} vs {point}"
                );
                assert!(filtered < 0.035, "{name} {texels}: {filtered}");
                assert!(
                    filtered <= trilinear,
                    "{name} {texels}: {filtered} vs {trilinear}"
                );
            }
        }
    }

    #[test]
    fn jpeg_fixtures_decode_to_their_blocks_as_mitsuba_does() {
        // crates/render/tests/data/texture/mitsuba_bitmap.py: flat 16x16 blocks at quality 100,
        // and Mitsuba 3's (libjpeg's) decoding of each block's centre.
        let blocks = [
            [[200, 30, 40], [20, 180, 60], [30, 50, 220]],
            [[250, 250, 250], [128, 128, 128], [240, 200, 10]],
        ];
        let decode = |name: &str| {
            let bytes = std::fs::read(data(name)).unwrap();
            luxest_io::texture_image::decode_texture_image(&data(name), bytes).unwrap()
        };
        let rgb = decode("pattern.jpg");
        assert_eq!((rgb.width, rgb.height, rgb.channels), (48, 32, 3));
        let grey = decode("pattern_grey.jpg");
        assert_eq!((grey.width, grey.height, grey.channels), (32, 16, 1));
        let (Samples::U8(rgb_samples), Samples::U8(grey_samples)) = (&rgb.samples, &grey.samples)
        else {
            panic!("8-bit samples expected");
        };
        // Every pixel within 3 codes of its block's colour.
        for y in 0..32 {
            for x in 0..48 {
                for c in 0..3 {
                    let got = rgb_samples[(y * 48 + x) * 3 + c] as i32;
                    let want = blocks[y / 16][x / 16][c];
                    assert!(
                        (got - want).abs() <= 3,
                        "({x}, {y}) channel {c}: {got} vs {want}"
                    );
                }
            }
        }
        for y in 0..16 {
            for x in 0..32 {
                let got = grey_samples[y * 32 + x] as i32;
                assert!(
                    (got - [40, 210][x / 16]).abs() <= 3,
                    "grey ({x}, {y}): {got}"
                );
            }
        }
        // Block centres as Mitsuba decodes them, within one code (IDCTs differ in rounding).
        for row in table("jpeg_mitsuba.csv") {
            let n = |i: usize| row[i].parse::<usize>().unwrap();
            let (x, y) = (n(1), n(2));
            for c in 0..3 {
                let ours = if row[0] == "pattern.jpg" {
                    rgb_samples[(y * 48 + x) * 3 + c]
                } else {
                    grey_samples[y * 32 + x]
                };
                assert!(
                    (ours as i64 - n(3 + c) as i64).abs() <= 1,
                    "{row:?}: {ours}"
                );
            }
        }
        // Through a texture: sRGB-decoded, grey replicated, alpha 1.
        let t = Texture::load(&data("pattern_grey.jpg"), &TextureOptions::default()).unwrap();
        let texel = t.texel(0, 8, 8);
        let expected = srgb8_to_linear(grey_samples[8 * 32 + 8]);
        assert_eq!(texel, [expected, expected, expected, 1.0]);
        assert!(!t.has_alpha());
    }

    #[test]
    fn bad_jpegs_are_one_line_errors_naming_the_file() {
        let path = data("pattern.jpg");
        let jpeg = std::fs::read(&path).unwrap();
        let error = |bytes: Vec<u8>| {
            luxest_io::texture_image::decode_texture_image(&path, bytes)
                .unwrap_err()
                .to_string()
        };
        // Every prefix that cuts into the scan (the last two bytes are the end-of-image marker).
        for len in 0..jpeg.len() - 2 {
            let e = error(jpeg[..len].to_vec());
            assert!(
                e.contains("pattern.jpg: ") && !e.contains('\n'),
                "{len}: {e}"
            );
        }
        // A frame header (SOF0: FF C0, length, precision, height, width) claiming 65535².
        let sof = jpeg.windows(2).position(|w| w == [0xff, 0xc0]).unwrap();
        let mut huge = jpeg.clone();
        huge[sof + 5..sof + 9].copy_from_slice(&[0xff, 0xff, 0xff, 0xff]);
        let e = error(huge);
        assert!(e.contains("a 65535x65535 texture needs 81.6 GB"), "{e}");
        let mut zero = jpeg.clone();
        zero[sof + 7..sof + 9].copy_from_slice(&[0, 0]);
        let e = error(zero);
        assert!(e.contains("pattern.jpg: "), "{e}");
    }

    #[test]
    fn exr_fixtures_decode_linear_with_alpha_and_luminance() {
        // Half-float RGBA with PIZ compression, texel (i, j) = (i/4, j/8, −(i + j), 1 − i/8).
        let t = Texture::load(&data("rgba_half.exr"), &TextureOptions::default()).unwrap();
        assert_eq!(
            (t.width(), t.height(), t.encoding()),
            (4, 3, Encoding::Linear)
        );
        assert!(t.has_alpha());
        for j in 0..3 {
            for i in 0..4 {
                let (x, y) = (i as f32, j as f32);
                assert_eq!(
                    t.texel(0, i, j),
                    [x / 4.0, y / 8.0, -(x + y), 1.0 - x / 8.0]
                );
            }
        }
        // One Y channel, texel (i, j) = i + 10 j, replicated into R, G, B.
        let t = Texture::load(&data("luminance.exr"), &TextureOptions::default()).unwrap();
        assert_eq!(t.texel(0, 2, 1), [12.0, 12.0, 12.0, 1.0]);
        assert!(!t.has_alpha());
        let srgb = TextureOptions {
            encoding: Some(Encoding::Srgb),
            ..TextureOptions::default()
        };
        let e = Texture::load(&data("luminance.exr"), &srgb)
            .unwrap_err()
            .to_string();
        assert!(
            e.ends_with(
                "luminance.exr: an OpenEXR texture is linear; encoding Srgb does not apply"
            ),
            "{e}"
        );
        let bytes = std::fs::read(data("rgba_half.exr")).unwrap();
        for len in 0..bytes.len() {
            let path = data("rgba_half.exr");
            let e = luxest_io::texture_image::decode_texture_image(&path, bytes[..len].to_vec());
            assert!(e.unwrap_err().to_string().contains("rgba_half.exr: "));
        }
    }

    #[test]
    fn sixteen_bit_samples_decode_with_their_encoding_and_alpha_stays_linear() {
        let image = TextureImage {
            width: 2,
            height: 1,
            channels: 2,
            samples: Samples::U16(vec![65535, 32768, 0, 13107]),
            format: ImageFormat::Png,
        };
        let t = Texture::from_image(&image, &TextureOptions::default()).unwrap();
        // Grey 1 and 0; alpha 32768/65535 and 0.2 linear, not sRGB-decoded.
        assert_eq!(
            t.texel(0, 0, 0),
            [1.0, 1.0, 1.0, (32768.0f64 / 65535.0) as f32]
        );
        assert_eq!(t.texel(0, 1, 0), [0.0, 0.0, 0.0, 0.2]);
        let mid = TextureImage {
            samples: Samples::U16(vec![32768, 0, 13107, 0]),
            ..image.clone()
        };
        let t = Texture::from_image(&mid, &TextureOptions::default()).unwrap();
        let srgb = luxest_io::color::srgb_decode(32768.0 / 65535.0) as f32;
        assert_eq!(t.texel(0, 0, 0), [srgb, srgb, srgb, 0.0]);
        let linear = TextureOptions {
            encoding: Some(Encoding::Linear),
            ..TextureOptions::default()
        };
        let t = Texture::from_image(&image, &linear).unwrap();
        assert_eq!(t.texel(0, 0, 0)[0], 1.0);
        assert!(t.has_alpha());
    }

    #[test]
    fn averages_over_the_image_and_over_triangles() {
        // A checkerboard of 0 and 1 (sRGB codes 0 and 255): mean ½ exactly.
        let t = checkerboard(96);
        assert_eq!(t.average(), [0.5, 0.5, 0.5, 1.0]);
        // A linear ramp red = u (texel centres (i + ½)/64), clamped: over the triangle (0, 0),
        // (1, 0), (0, 1) the mean of u is 1/3; green = v the same, blue = u v has 1/12.
        let ramp = linear(64, 64, options(Wrap::Clamp, Filter::Bilinear), |x, y| {
            let (u, v) = ((x as f32 + 0.5) / 64.0, (y as f32 + 0.5) / 64.0);
            [u, v, u * v, 1.0]
        });
        let m = ramp.mean_over_triangle([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
        eprintln!("ramp triangle mean {m:?}");
        // The clamped half texel along the edges u = 0 and v = 0 adds ~5e-5.
        assert!((m[0] - 1.0 / 3.0).abs() < 2e-4, "{m:?}");
        assert!((m[1] - 1.0 / 3.0).abs() < 2e-4, "{m:?}");
        assert!((m[2] - 1.0 / 12.0).abs() < 2e-4, "{m:?}");
        // Binary detail against a brute-force mean of 2^16 point lookups on the triangle.
        let text = text_like(128);
        let tri = [[0.1, 0.2], [0.45, 0.3], [0.2, 0.6]];
        let mut brute = 0.0;
        let n = 256;
        for i in 0..n {
            for j in 0..n {
                // Cell centres of an n x n grid of the unit square, folded onto the triangle.
                let (mut s, mut t) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                if s + t > 1.0 {
                    (s, t) = (1.0 - s, 1.0 - t);
                }
                let p = [0, 1]
                    .map(|k| tri[0][k] + s * (tri[1][k] - tri[0][k]) + t * (tri[2][k] - tri[0][k]));
                brute += text.eval(p, 0.0)[0] as f64;
            }
        }
        brute /= (n * n) as f64;
        let m = text.mean_over_triangle(tri)[0];
        eprintln!("text-like triangle mean {m:.5}, brute force {brute:.5}");
        assert!((m - brute).abs() < 1e-3, "{m} vs {brute}");
        // A triangle over many periods of a repeating texture: its average.
        let m = text.mean_over_triangle([[0.0, 0.0], [40.0, 0.0], [0.0, 40.0]])[0];
        assert!(
            (m - text.average()[0]).abs() < 1e-3,
            "{m} vs {:?}",
            text.average()
        );
    }

    #[test]
    fn encoded_textures_decode_to_the_same_texture_and_corruption_is_an_error() {
        let path = Path::new("scenes/room.lxs");
        let png = TextureOptions {
            wrap: Wrap::Mirror,
            filter: Filter::Nearest,
            uv_transform: UvTransform([[2.0, 0.5, 0.1], [-0.3, 1.5, 0.25]]),
            ..TextureOptions::default()
        };
        let textures = [
            Texture::load(&data("bitmap.png"), &png).unwrap(),
            Texture::load(&data("rgba_half.exr"), &TextureOptions::default()).unwrap(),
            checkerboard(20),
        ];
        let mut bytes = Vec::new();
        for t in &textures {
            t.encode(&mut bytes);
        }
        bytes.extend_from_slice(b"rest");
        let mut at = 0;
        for t in &textures {
            let (back, len) = Texture::decode(path, &bytes[at..]).unwrap();
            assert_eq!(&back, t);
            at += len;
        }
        assert_eq!(&bytes[at..], b"rest");
        let mut one = Vec::new();
        textures[1].encode(&mut one);
        let error = |b: &[u8]| {
            let e = Texture::decode(path, b).unwrap_err().to_string();
            assert!(
                e.starts_with("scenes/room.lxs: ") && !e.contains('\n'),
                "{e}"
            );
            e
        };
        for len in 0..one.len() {
            error(&one[..len]);
        }
        let patched = |offset: usize, value: &[u8]| {
            let mut b = one.clone();
            b[offset..offset + value.len()].copy_from_slice(value);
            error(&b)
        };
        assert!(patched(0, b"LXTY").contains("bad magic"));
        assert!(patched(8, &0u32.to_le_bytes()).contains("size 0x3"));
        assert!(patched(8, &70000u32.to_le_bytes()).contains("size 70000x3"));
        let e = patched(8, &65536u32.to_le_bytes());
        assert!(e.contains("truncated texels"), "{e}");
        let e = patched(12, &65536u32.to_le_bytes());
        assert!(
            e.contains("texture needs") || e.contains("truncated texels"),
            "{e}"
        );
        assert!(patched(16, &[3]).contains("storage tag 3"));
        assert!(patched(18, &[3]).contains("wrap tag 3"));
        assert!(patched(24, &f64::NAN.to_le_bytes()).contains("is not finite"));
        assert!(patched(72, &f32::INFINITY.to_le_bytes()).contains("non-finite value in texel 0"));
    }

    #[test]
    fn texture_options_read_from_ron() {
        #[derive(Debug, Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Desc {
            encoding: Option<Encoding>,
            wrap: Wrap,
            filter: Filter,
            uv_transform: Option<UvTransform>,
        }
        let text = "(encoding: Linear, wrap: Mirror, filter: Nearest, \
                    uv_transform: ((2.0, 0.0, 0.5), (0.0, 2.0, 0.0)))";
        let d: Desc = luxest_io::fsio::parse_ron(Path::new("t.ron"), text).unwrap();
        assert_eq!(d.encoding, Some(Encoding::Linear));
        assert_eq!((d.wrap, d.filter), (Wrap::Mirror, Filter::Nearest));
        let m = d.uv_transform.unwrap();
        assert_eq!(m, UvTransform([[2.0, 0.0, 0.5], [0.0, 2.0, 0.0]]));
        assert_eq!(m.apply([0.25, 0.5]), [1.0, 1.0]);
        assert_eq!(m.scale(), 2.0);
    }
}
