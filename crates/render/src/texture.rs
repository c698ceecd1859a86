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
//!   to 6 texels (tests: `trilinear_lookups_approach_the_box_filtered_reference`).
//!   `footprint = 0`, or one of a texel or less, is the bilinear lookup of level 0, Mitsuba's.
//!   `Nearest` takes the nearest texel of the level nearest log2 of the footprint in texels.
//!   Channels are filtered independently (alpha is not premultiplied), in linear values.
//!
//! Storage: 8-bit images stay 8-bit and are decoded on lookup (their mip levels are 16-bit
//! linear); 16-bit and EXR images are stored as f32. The compiled
//! scene stores the base level and the options ([`Texture::encode`]); levels are rebuilt on load.

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
/// `KHR_texture_transform` and Mitsuba 3's `to_uv` as a matrix).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
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
                    UNORM8[p[3] as usize],
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
        let rgba = |s: &[f32], one: f32| -> [f32; 4] {
            match s.len() {
                1 => [s[0], s[0], s[0], one],
                2 => [s[0], s[0], s[0], s[1]],
                3 => [s[0], s[1], s[2], one],
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
                            rgba(&p[..c], 1.0)
                        })
                        .collect(),
                )
            }
            Samples::F32(v) => {
                if let Some(x) = v.iter().find(|x| !x.is_finite()) {
                    return Err(format!("non-finite texel value {x}"));
                }
                Texels::F32(v.chunks_exact(c).map(|s| rgba(s, 1.0)).collect())
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
    /// documentation). A non-finite UV is read as (0, 0), a non-finite or negative footprint as
    /// 0.
    pub fn eval(&self, uv: [f64; 2], footprint: f64) -> [f32; 4] {
        let uv = uv.map(|x| if x.is_finite() { x } else { 0.0 });
        let uv = self.uv_transform.apply(uv);
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
        if !(texels > 1.0) {
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
        let xs = [
            wrap(self.wrap, x0, l.width),
            wrap(self.wrap, x0 + 1, l.width),
        ];
        let ys = [
            wrap(self.wrap, y0, l.height),
            wrap(self.wrap, y0 + 1, l.height),
        ];
        let mut out = [0f64; 4];
        for (j, &ty) in ys.iter().enumerate() {
            let wy = if j == 0 { 1.0 - fy } else { fy };
            for (i, &tx) in xs.iter().enumerate() {
                let w = wy * if i == 0 { 1.0 - fx } else { fx };
                let t = self.decode_texel(l, ty * l.width + tx);
                for c in 0..4 {
                    out[c] += w * t[c] as f64;
                }
            }
        }
        out.map(|v| v as f32)
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
    /// transform; an affine map, so the mean over the triangle's surface): the triangle is cut
    /// into [`TRIANGLE_MEAN_CELLS`]² congruent triangles and the lookup at each one's centroid,
    /// filtered over a footprint of its size, averaged.
    pub fn mean_over_triangle(&self, uv: [[f64; 2]; 3]) -> [f64; 4] {
        let n = TRIANGLE_MEAN_CELLS;
        let (a, b, c) = (uv[0], uv[1], uv[2]);
        let e1 = [b[0] - a[0], b[1] - a[1]];
        let e2 = [c[0] - a[0], c[1] - a[1]];
        let area = 0.5 * (e1[0] * e2[1] - e1[1] * e2[0]).abs();
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

/// Cells along a side in [`Texture::mean_over_triangle`].
pub const TRIANGLE_MEAN_CELLS: usize = 16;

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
        // Non-finite UVs read as (0, 0).
        assert_eq!(red(&row(Clamp, Nearest), f64::NAN), 0.0);
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
}
