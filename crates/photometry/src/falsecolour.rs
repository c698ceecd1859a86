//! False-colour luminance images, as PNG: what a lighting report shows of a rendered room.
//!
//! A luminance image (cd/m², one value a pixel, row-major from the top) is drawn on a
//! **logarithmic** colour scale — the eye judges luminance ratios, and a lit room spans two to
//! three decades — with the isolux plots' colours ([`crate::isolux::colour`]), enlarged by an
//! integer factor (nearest neighbour, so every image pixel stays a block of one colour), beside
//! a vertical scale bar labelled in cd/m² at the 1, 2, 5 × 10^k values inside its range.
//!
//! **Range.** Unless given, the scale spans [lo, hi] with hi the 99.5th percentile of the
//! luminances rounded up to 1, 2 or 5 × 10^k, and lo the 1st percentile of the non-zero ones
//! rounded down likewise, but at least hi / 10⁴; pixels outside are drawn in the end colours
//! (black pixels, luminance 0, in the lowest).

use crate::grid::GridError;
use crate::isolux::{colour, text_width, SrgbRaster};

const INK: [u8; 3] = [20, 20, 20];
const PAPER: [u8; 3] = [255, 255, 255];

/// What to draw besides the image.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FalseColourOptions {
    /// Title line above the image.
    pub title: String,
    /// The scale's range (cd/m², 0 < lo < hi); `None` for the automatic range.
    pub range_cd_m2: Option<(f64, f64)>,
    /// Smallest width of the drawn image, px: the image is enlarged by the smallest integer
    /// factor that reaches it (1 when it is already as wide).
    pub min_width_px: u32,
}

/// A drawn false-colour image and where its parts lie on the raster.
#[derive(Debug, Clone, PartialEq)]
pub struct FalseColour {
    pub raster: SrgbRaster,
    /// The scale's range, cd/m².
    pub lo: f64,
    pub hi: f64,
    /// The luminance image's rectangle on the raster: left, top, width, height (px).
    pub image_rect: (u32, u32, u32, u32),
    /// The scale bar's rectangle: left, top, width, height (px); luminance hi at its top.
    pub bar_rect: (u32, u32, u32, u32),
}

/// The position of `l` on the logarithmic scale [lo, hi], clamped to [0, 1].
pub fn scale_position(l: f64, lo: f64, hi: f64) -> f64 {
    if l.is_nan() || l <= 0.0 {
        return 0.0;
    }
    ((l / lo).ln() / (hi / lo).ln()).clamp(0.0, 1.0)
}

/// The colour of luminance `l` on the scale [lo, hi].
pub fn luminance_colour(l: f64, lo: f64, hi: f64) -> [u8; 3] {
    colour(scale_position(l, lo, hi))
}

/// The nearest 1, 2 or 5 × 10^k at or above (`up`) or at or below `x` (> 0).
fn nice_125(x: f64, up: bool) -> f64 {
    let p = 10f64.powf(x.log10().floor());
    let steps = [1.0, 2.0, 5.0, 10.0];
    if up {
        steps
            .iter()
            .map(|m| m * p)
            .find(|&v| v >= x * (1.0 - 1e-12))
            .unwrap_or(10.0 * p)
    } else {
        steps
            .iter()
            .rev()
            .map(|m| m * p)
            .find(|&v| v <= x * (1.0 + 1e-12))
            .unwrap_or(p)
    }
}

/// The automatic range of the module docs for `luminance` (finite, ≥ 0).
pub fn auto_range(luminance: &[f64]) -> (f64, f64) {
    let mut all: Vec<f64> = luminance.iter().copied().filter(|l| *l > 0.0).collect();
    if all.is_empty() {
        return (0.1, 1.0);
    }
    all.sort_by(f64::total_cmp);
    let q = |f: f64| all[((f * (all.len() - 1) as f64).round() as usize).min(all.len() - 1)];
    let hi = nice_125(q(0.995), true);
    let lo = nice_125(q(0.01).max(hi * 1e-4), false);
    if lo < hi {
        (lo, hi)
    } else {
        (hi / 10.0, hi)
    }
}

/// The 1, 2, 5 × 10^k values inside [lo, hi] (ends included when they are such values).
pub fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let mut p = 10f64.powf(lo.log10().floor());
    while p <= hi * (1.0 + 1e-12) {
        for m in [1.0, 2.0, 5.0] {
            let v = m * p;
            if v >= lo * (1.0 - 1e-12) && v <= hi * (1.0 + 1e-12) {
                out.push(v);
            }
        }
        p *= 10.0;
    }
    out
}

fn fmt_cd(v: f64) -> String {
    if v >= 1.0 {
        format!("{v:.0}")
    } else {
        let digits = (-v.log10().floor()) as usize;
        format!("{v:.digits$}")
    }
}

/// Draws the luminance image (`width` × `height`, cd/m²) with its scale bar.
pub fn render_falsecolour(
    width: usize,
    height: usize,
    luminance: &[f64],
    opts: &FalseColourOptions,
) -> Result<FalseColour, GridError> {
    if width == 0 || height == 0 || luminance.len() != width * height {
        return Err(GridError(format!(
            "false colour: {} values for a {width} x {height} image",
            luminance.len()
        )));
    }
    if let Some(k) = luminance.iter().position(|l| !(l.is_finite() && *l >= 0.0)) {
        return Err(GridError(format!(
            "false colour: pixel ({}, {}) has luminance {}, not a finite number >= 0",
            k % width,
            k / width,
            luminance[k]
        )));
    }
    let (lo, hi) = match opts.range_cd_m2 {
        Some((lo, hi)) if lo > 0.0 && hi > lo && hi.is_finite() => (lo, hi),
        Some((lo, hi)) => {
            return Err(GridError(format!(
                "false colour: range [{lo}, {hi}] cd/m2 is not 0 < lo < hi"
            )))
        }
        None => auto_range(luminance),
    };
    let zoom = (opts.min_width_px as usize).div_ceil(width).clamp(1, 16);
    let (iw, ih) = (width * zoom, height * zoom);
    let (left, top) = (16usize, 44usize);
    let bar_w = 24usize;
    let bar_x = left + iw + 20;
    let labels_w = 10 + text_width("00000", 2) as usize;
    let raster_w = bar_x + bar_w + labels_w + 16;
    let raster_h = top + ih.max(200) + 20;
    let mut img = SrgbRaster::new(raster_w as u32, raster_h as u32, PAPER);
    img.text(left as i64, 14, 2, &opts.title, INK);
    for y in 0..height {
        for x in 0..width {
            let c = luminance_colour(luminance[y * width + x], lo, hi);
            img.rect(
                (left + x * zoom) as i64,
                (top + y * zoom) as i64,
                (left + (x + 1) * zoom) as i64,
                (top + (y + 1) * zoom) as i64,
                c,
            );
        }
    }
    // The scale bar: hi at the top, lo at the bottom, logarithmic.
    let bar_h = ih.max(200);
    let (by0, by1) = (top as i64, (top + bar_h) as i64);
    for y in by0..by1 {
        let f = (by1 - 1 - y) as f64 / (by1 - by0 - 1) as f64;
        img.rect(bar_x as i64, y, (bar_x + bar_w) as i64, y + 1, colour(f));
    }
    let (bx0, bx1) = (bar_x as f64, (bar_x + bar_w) as f64);
    for (a, b) in [
        ((bx0, by0 as f64), (bx1, by0 as f64)),
        ((bx1, by0 as f64), (bx1, by1 as f64)),
        ((bx1, by1 as f64), (bx0, by1 as f64)),
        ((bx0, by1 as f64), (bx0, by0 as f64)),
    ] {
        img.line(a, b, 1.0, INK);
    }
    let mut last_y = f64::NEG_INFINITY;
    for v in ticks(lo, hi).into_iter().rev() {
        let y = by1 as f64 - scale_position(v, lo, hi) * (by1 - by0) as f64;
        img.line((bx1, y), (bx1 + 5.0, y), 1.2, INK);
        if y - last_y >= 18.0 {
            img.text(
                bar_x as i64 + bar_w as i64 + 9,
                (y - 7.0) as i64,
                2,
                &fmt_cd(v),
                INK,
            );
            last_y = y;
        }
    }
    img.text(bar_x as i64, 14, 2, "cd/m2", INK);
    Ok(FalseColour {
        raster: img,
        lo,
        hi,
        image_rect: (left as u32, top as u32, iw as u32, ih as u32),
        bar_rect: (bar_x as u32, top as u32, bar_w as u32, bar_h as u32),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_and_ticks_are_one_two_five_values() {
        // 3 .. 700 cd/m²: the range rounds out to 2 .. 1000.
        let l: Vec<f64> = (0..1000)
            .map(|k| 3.0 * (700.0f64 / 3.0).powf(k as f64 / 999.0))
            .collect();
        assert_eq!(auto_range(&l), (2.0, 1000.0));
        assert_eq!(
            ticks(2.0, 1000.0),
            [2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0]
        );
        assert_eq!(fmt_cd(0.05), "0.05");
    }

    /// Every image pixel is drawn, enlarged, in the colour of its position on the log scale:
    /// √(lo·hi) is the middle colour, lo and below the lowest, hi and above the highest.
    #[test]
    fn pixels_take_their_log_scale_colour() {
        let (lo, hi) = (1.0, 100.0);
        let lum = [0.0, 0.5, 10.0, 100.0, 1e4, 1.0];
        let opts = FalseColourOptions {
            title: "t".into(),
            range_cd_m2: Some((lo, hi)),
            min_width_px: 30,
        };
        let fc = render_falsecolour(3, 2, &lum, &opts).unwrap();
        let (x0, y0, w, h) = fc.image_rect;
        assert_eq!((w, h), (30, 20));
        let expect = [
            colour(0.0),
            colour(0.0),
            colour(0.5),
            colour(1.0),
            colour(1.0),
            colour(0.0),
        ];
        for (k, c) in expect.iter().enumerate() {
            let (px, py) = (x0 + 10 * (k as u32 % 3) + 5, y0 + 10 * (k as u32 / 3) + 5);
            assert_eq!(fc.raster.pixel(px, py), *c, "pixel {k}");
        }
        // The bar: row r from the top has the colour of (h − 1 − r) / (h − 1), the highest
        // at its top, the lowest at its bottom.
        let (bx, by, bw, bh) = fc.bar_rect;
        let row = |r: u32| colour((bh - 1 - r) as f64 / (bh - 1) as f64);
        assert_eq!(fc.raster.pixel(bx + bw / 2, by + 2), row(2));
        assert_eq!(fc.raster.pixel(bx + bw / 2, by + bh - 3), row(bh - 3));
        let bad = render_falsecolour(3, 2, &[0.0, 1.0, f64::NAN, 1.0, 1.0, 1.0], &opts);
        assert!(bad.unwrap_err().0.contains("pixel (2, 0)"));
    }
}
