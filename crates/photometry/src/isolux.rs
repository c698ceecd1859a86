//! False-colour isolux plots of a calculation grid, as PNG.
//!
//! The plot shows the whole grid rectangle to scale (u to the right, v up) with its outline, the
//! excluded border (margin) in grey with the calculation area's edge dashed, the illuminance as a
//! continuous false-colour field, black contour lines (isolux lines) at the chosen levels with
//! their values in lx, the luminaires' positions if given, metre ticks on both axes, a legend bar
//! labelled in lx, and a line with Eavg, Emin, Emax, U0, Ud when the figures are given.
//!
//! **Field.** The point values sit at cell centres; the field is their bilinear interpolation,
//! extended to the calculation area's edges by holding the outermost values constant (a ring of
//! clamped values added around the grid). The contours are traced on that same extended grid by
//! marching squares (linear interpolation along cell edges, saddles resolved by the cell-centre
//! mean), so lines and colours agree.
//!
//! **Levels.** Unless given, contour levels are the multiples of a "nice" step (1, 2, 2.5 or 5 ×
//! 10^k) between Emin and Emax, chosen to give 4 to 10 lines; the colour scale spans the nearest
//! multiples of that step below Emin and above Emax.
//!
//! Text uses an embedded, hand-drawn 5 × 8 pixel font (digits, letters, a few signs), drawn at
//! twice its size; no font files are read.

use crate::grid::{CalcGrid, GridError, GridStats};

/// What to draw besides the field.
#[derive(Debug, Clone, PartialEq)]
pub struct IsoluxOptions {
    /// Contour levels (lx); `None` for automatic levels.
    pub levels_lx: Option<Vec<f64>>,
    /// Width of the rectangle on the image (px); the height follows to scale.
    pub plot_width_px: u32,
    /// Title line, e.g. "Work plane 0.75 m: illuminance".
    pub title: String,
    /// Luminaire positions in the rectangle's coordinates (s along u, t along v, m).
    pub luminaires_st: Vec<(f64, f64)>,
}

impl Default for IsoluxOptions {
    fn default() -> Self {
        IsoluxOptions {
            levels_lx: None,
            plot_width_px: 640,
            title: String::new(),
            luminaires_st: Vec::new(),
        }
    }
}

/// An 8-bit sRGB raster (display-referred: what the plot shows, 3 bytes a pixel), row-major from
/// the top; not to be confused with the linear, scene-referred [`luxest_io::image::RgbImage`].
#[derive(Debug, Clone, PartialEq)]
pub struct SrgbRaster {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u8>,
}

impl SrgbRaster {
    pub(crate) fn new(width: u32, height: u32, bg: [u8; 3]) -> Self {
        SrgbRaster {
            width,
            height,
            data: bg.repeat((width * height) as usize),
        }
    }
    fn blend(&mut self, x: i64, y: i64, c: [u8; 3], a: f64) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 || a <= 0.0 {
            return;
        }
        let k = 3 * (y as usize * self.width as usize + x as usize);
        let a = a.min(1.0);
        for (ch, &cv) in c.iter().enumerate() {
            let old = self.data[k + ch] as f64;
            self.data[k + ch] = (old + (cv as f64 - old) * a).round() as u8;
        }
    }
    pub(crate) fn set(&mut self, x: i64, y: i64, c: [u8; 3]) {
        self.blend(x, y, c, 1.0);
    }
    /// The pixel at (x, y).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let k = 3 * (y as usize * self.width as usize + x as usize);
        [self.data[k], self.data[k + 1], self.data[k + 2]]
    }
    /// The raster as PNG bytes.
    pub fn encode_png(&self) -> Result<Vec<u8>, String> {
        luxest_io::png::encode_png_rgb8(self.width, self.height, &self.data)
    }

    /// An anti-aliased line of width `w` px (coverage from the distance to the segment).
    pub(crate) fn line(&mut self, a: (f64, f64), b: (f64, f64), w: f64, c: [u8; 3]) {
        let r = w / 2.0 + 1.0;
        let (x0, x1) = (
            (a.0.min(b.0) - r).floor() as i64,
            (a.0.max(b.0) + r).ceil() as i64,
        );
        let (y0, y1) = (
            (a.1.min(b.1) - r).floor() as i64,
            (a.1.max(b.1) + r).ceil() as i64,
        );
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let l2 = dx * dx + dy * dy;
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let t = if l2 > 0.0 {
                    (((px - a.0) * dx + (py - a.1) * dy) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let (qx, qy) = (a.0 + t * dx - px, a.1 + t * dy - py);
                let d = (qx * qx + qy * qy).sqrt();
                self.blend(x, y, c, (w / 2.0 + 0.5 - d).clamp(0.0, 1.0));
            }
        }
    }
    pub(crate) fn rect(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, c: [u8; 3]) {
        for y in y0..y1 {
            for x in x0..x1 {
                self.set(x, y, c);
            }
        }
    }
    /// Text at (x, y) (top-left), font pixels scaled by `s`; returns the width drawn.
    pub(crate) fn text(&mut self, x: i64, y: i64, s: i64, t: &str, c: [u8; 3]) -> i64 {
        let mut cx = x;
        for ch in t.chars() {
            if let Some(g) = glyph(ch) {
                for (row, bits) in g.iter().enumerate() {
                    for col in 0..5 {
                        if bits & (1 << (4 - col)) != 0 {
                            self.rect(
                                cx + col * s,
                                y + row as i64 * s,
                                cx + (col + 1) * s,
                                y + (row as i64 + 1) * s,
                                c,
                            );
                        }
                    }
                }
            }
            cx += 6 * s;
        }
        cx - x
    }
}

/// Width in px of `t` at scale `s`.
pub(crate) fn text_width(t: &str, s: i64) -> i64 {
    6 * s * t.chars().count() as i64 - s
}

fn glyph(c: char) -> Option<&'static [u8; 8]> {
    font().iter().find(|g| g.0 == c).map(|g| &g.1)
}

/// A lighting-report false-colour scale: dark blue, blue, cyan, green, yellow, orange, red, for
/// t in [0, 1] (clamped; non-finite is 0). The isolux and the luminance images share it.
pub fn colour(t: f64) -> [u8; 3] {
    const STOPS: [(f64, [f64; 3]); 7] = [
        (0.0, [38.0, 52.0, 140.0]),
        (0.17, [45.0, 110.0, 205.0]),
        (0.34, [70.0, 185.0, 215.0]),
        (0.5, [95.0, 195.0, 110.0]),
        (0.67, [235.0, 220.0, 80.0]),
        (0.84, [245.0, 150.0, 60.0]),
        (1.0, [215.0, 60.0, 50.0]),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let k = STOPS
        .iter()
        .position(|s| s.0 >= t)
        .unwrap_or(STOPS.len() - 1)
        .max(1);
    let (a, b) = (STOPS[k - 1], STOPS[k]);
    let f = ((t - a.0) / (b.0 - a.0)).clamp(0.0, 1.0);
    [0, 1, 2].map(|i| (a.1[i] + f * (b.1[i] - a.1[i])).round() as u8)
}

/// A nice step (1, 2, 2.5, 5 × 10^k) giving about `target` intervals over `span`.
fn nice_step(span: f64, target: f64) -> f64 {
    let raw = span / target;
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .find(|&s| s >= raw)
        .unwrap_or(10.0 * p)
}

/// Contour levels and colour range [lo, hi] for values in [vmin, vmax] (see the module docs).
pub fn auto_levels(vmin: f64, vmax: f64) -> (Vec<f64>, f64, f64) {
    if vmax.partial_cmp(&vmin) != Some(std::cmp::Ordering::Greater) {
        let v = if vmin.is_finite() { vmin } else { 0.0 };
        return (
            Vec::new(),
            v - 0.5 * v.abs().max(1.0),
            v + 0.5 * v.abs().max(1.0),
        );
    }
    let step = nice_step(vmax - vmin, 6.0);
    let lo = (vmin / step).floor() * step;
    let hi = (vmax / step).ceil() * step;
    let mut levels = Vec::new();
    let mut k = (vmin / step).floor() as i64 + 1;
    while (k as f64) * step < vmax && levels.len() < 50 {
        // Rounded to 10 significant digits so 6 × 0.2 prints as 1.2.
        let l: f64 = format!("{:.9e}", k as f64 * step)
            .parse()
            .unwrap_or(k as f64 * step);
        if l > vmin {
            levels.push(l);
        }
        k += 1;
    }
    (levels, lo, hi)
}

fn fmt_lx(v: f64) -> String {
    if v.abs() >= 100.0 || v == v.round() {
        format!("{v:.0}")
    } else if v.abs() >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

/// The grid values extended by a clamped ring: coordinates (m, from the rectangle's corner) and
/// values on an (nu + 2) × (nv + 2) lattice.
struct Field {
    s: Vec<f64>,
    t: Vec<f64>,
    v: Vec<f64>,
}

impl Field {
    fn new(g: &CalcGrid, values: &[f64]) -> Field {
        let m = g.spec.margin_m;
        let mut s = vec![m];
        s.extend((0..g.nu).map(|i| g.local(i, 0).0));
        s.push(m + g.area_u);
        let mut t = vec![m];
        t.extend((0..g.nv).map(|j| g.local(0, j).1));
        t.push(m + g.area_v);
        let (nu, nv) = (g.nu + 2, g.nv + 2);
        let mut v = vec![0.0; nu * nv];
        for j in 0..nv {
            for i in 0..nu {
                let (ii, jj) = (i.clamp(1, g.nu) - 1, j.clamp(1, g.nv) - 1);
                v[j * nu + i] = values[jj * g.nu + ii];
            }
        }
        Field { s, t, v }
    }
    fn at(&self, i: usize, j: usize) -> f64 {
        self.v[j * self.s.len() + i]
    }
    fn sample(&self, s: f64, t: f64) -> f64 {
        let cell = |a: &[f64], x: f64| {
            let i = a.partition_point(|&q| q <= x).clamp(1, a.len() - 1) - 1;
            let f = if a[i + 1] > a[i] {
                ((x - a[i]) / (a[i + 1] - a[i])).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (i, f)
        };
        let (i, u) = cell(&self.s, s);
        let (j, w) = cell(&self.t, t);
        let a = self.at(i, j) * (1.0 - u) + self.at(i + 1, j) * u;
        let b = self.at(i, j + 1) * (1.0 - u) + self.at(i + 1, j + 1) * u;
        a * (1.0 - w) + b * w
    }
    /// The same bilinear field sampled on a lattice `k` times finer, so contours traced on it
    /// follow the curved level lines of the bilinear surface instead of cutting across cells.
    fn refined(&self, k: usize) -> Field {
        let fine = |a: &[f64]| {
            let mut out = Vec::with_capacity((a.len() - 1) * k + 1);
            for w in a.windows(2) {
                out.extend((0..k).map(|q| w[0] + (w[1] - w[0]) * q as f64 / k as f64));
            }
            out.push(a[a.len() - 1]);
            out
        };
        let (s, t) = (fine(&self.s), fine(&self.t));
        let mut v = Vec::with_capacity(s.len() * t.len());
        for &tt in &t {
            v.extend(s.iter().map(|&ss| self.sample(ss, tt)));
        }
        Field { s, t, v }
    }
    /// Marching squares: contour segments at `level`, in (s, t) metres.
    fn contour(&self, level: f64) -> Vec<((f64, f64), (f64, f64))> {
        let mut segs = Vec::new();
        let (nu, nv) = (self.s.len(), self.t.len());
        for j in 0..nv - 1 {
            for i in 0..nu - 1 {
                let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
                let val = corners.map(|(a, b)| self.at(a, b));
                let pos = corners.map(|(a, b)| (self.s[a], self.t[b]));
                let inside = val.map(|x| x >= level);
                // Crossing points on the four edges (0: bottom, 1: right, 2: top, 3: left).
                let mut cross: [Option<(f64, f64)>; 4] = [None; 4];
                for (e, slot) in cross.iter_mut().enumerate() {
                    let (p, q) = (e, (e + 1) % 4);
                    if inside[p] != inside[q] {
                        let f = (level - val[p]) / (val[q] - val[p]);
                        *slot = Some((
                            pos[p].0 + f * (pos[q].0 - pos[p].0),
                            pos[p].1 + f * (pos[q].1 - pos[p].1),
                        ));
                    }
                }
                let pts: Vec<(usize, (f64, f64))> = cross
                    .iter()
                    .enumerate()
                    .filter_map(|(e, c)| c.map(|c| (e, c)))
                    .collect();
                match pts.len() {
                    2 => segs.push((pts[0].1, pts[1].1)),
                    4 => {
                        // Saddle: the centre value decides which corners connect.
                        let centre = val.iter().sum::<f64>() / 4.0;
                        let c = |e: usize| cross[e].unwrap_or_default();
                        if (centre >= level) == inside[0] {
                            segs.push((c(0), c(1)));
                            segs.push((c(2), c(3)));
                        } else {
                            segs.push((c(3), c(0)));
                            segs.push((c(1), c(2)));
                        }
                    }
                    _ => {}
                }
            }
        }
        segs
    }
}

const INK: [u8; 3] = [20, 20, 20];
const WHITE: [u8; 3] = [255, 255, 255];
const GREY: [u8; 3] = [205, 205, 205];

/// Renders the isolux plot of `values_lx` (one per grid point, k = j · n_u + i).
pub fn render_isolux(
    grid: &CalcGrid,
    values_lx: &[f64],
    stats: Option<&GridStats>,
    opts: &IsoluxOptions,
) -> Result<SrgbRaster, GridError> {
    if values_lx.len() != grid.len() {
        return Err(GridError(format!(
            "isolux: {} values for a grid of {} points",
            values_lx.len(),
            grid.len()
        )));
    }
    if values_lx.iter().any(|v| !v.is_finite()) {
        return Err(GridError("isolux: non-finite grid value".into()));
    }
    let (vmin, vmax) = values_lx
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let (levels, lo, hi) = match &opts.levels_lx {
        Some(l) => {
            let mut l: Vec<f64> = l.iter().copied().filter(|x| x.is_finite()).collect();
            l.sort_by(f64::total_cmp);
            let lo = l.first().copied().unwrap_or(vmin).min(vmin);
            let hi = l.last().copied().unwrap_or(vmax).max(vmax);
            (l, lo, if hi > lo { hi } else { lo + 1.0 })
        }
        None => auto_levels(vmin, vmax),
    };
    let scale = opts.plot_width_px.clamp(100, 4000) as f64 / grid.len_u;
    let (pw, ph) = (
        (grid.len_u * scale).round() as i64,
        (grid.len_v * scale).round() as i64,
    );
    if ph > 8000 {
        return Err(GridError("isolux: rectangle too elongated to draw".into()));
    }
    let (left, top, right, bottom) = (56i64, 48i64, 150i64, 78i64);
    let (w, h) = (left + pw + right, top + ph.max(220) + bottom);
    let mut img = SrgbRaster::new(w as u32, h as u32, WHITE);
    let x_of = |s: f64| left as f64 + s * scale;
    let y_of = |t: f64| (top + ph) as f64 - t * scale;

    // Field, margin and outlines.
    let field = Field::new(grid, values_lx);
    // At most 8x finer, and at most ~4 million lattice points for very large grids.
    let k = ((4.0e6 / ((grid.nu + 2) * (grid.nv + 2)) as f64).sqrt() as usize).clamp(1, 8);
    let fine = field.refined(k);
    let m = grid.spec.margin_m;
    for py in 0..ph {
        for px in 0..pw {
            let (s, t) = (
                (px as f64 + 0.5) / scale,
                (ph as f64 - py as f64 - 0.5) / scale,
            );
            let in_area = s >= m && s <= m + grid.area_u && t >= m && t <= m + grid.area_v;
            let c = if in_area {
                colour((field.sample(s, t) - lo) / (hi - lo))
            } else {
                GREY
            };
            img.set(left + px, top + py, c);
        }
    }
    for level in &levels {
        for (a, b) in fine.contour(*level) {
            img.line((x_of(a.0), y_of(a.1)), (x_of(b.0), y_of(b.1)), 1.6, INK);
        }
    }
    if m > 0.0 {
        let corners = [
            (m, m),
            (m + grid.area_u, m),
            (m + grid.area_u, m + grid.area_v),
            (m, m + grid.area_v),
        ];
        for k in 0..4 {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            let n = (((b.0 - a.0).abs() + (b.1 - a.1).abs()) * scale / 8.0)
                .ceil()
                .max(1.0) as usize;
            for d in (0..n).step_by(2) {
                let f0 = d as f64 / n as f64;
                let f1 = ((d + 1) as f64 / n as f64).min(1.0);
                let p = |f: f64| (x_of(a.0 + f * (b.0 - a.0)), y_of(a.1 + f * (b.1 - a.1)));
                img.line(p(f0), p(f1), 1.0, [90, 90, 90]);
            }
        }
    }
    // Contour labels: up to two per level, away from each other and from the edges.
    let mut placed: Vec<(f64, f64)> = Vec::new();
    for level in &levels {
        let label = fmt_lx(*level);
        let (tw, th) = (text_width(&label, 2) as f64, 16.0);
        let mut count = 0;
        for (a, b) in fine.contour(*level) {
            let (cx, cy) = (x_of(0.5 * (a.0 + b.0)), y_of(0.5 * (a.1 + b.1)));
            // Inside the calculation area, clear of its edges.
            let (ax0, ax1) = (x_of(m) + 6.0, x_of(m + grid.area_u) - 6.0);
            let (ay0, ay1) = (y_of(m + grid.area_v) + 6.0, y_of(m) - 6.0);
            let fits = cx - tw / 2.0 > ax0
                && cx + tw / 2.0 < ax1
                && cy - th / 2.0 > ay0
                && cy + th / 2.0 < ay1;
            if !fits
                || placed
                    .iter()
                    .any(|p| (p.0 - cx).abs() < tw + 40.0 && (p.1 - cy).abs() < 60.0)
            {
                continue;
            }
            let (x0, y0) = (
                (cx - tw / 2.0).round() as i64,
                (cy - th / 2.0).round() as i64,
            );
            img.rect(x0 - 3, y0 - 3, x0 + tw as i64 + 3, y0 + 16 + 1, WHITE);
            img.text(x0, y0, 2, &label, INK);
            placed.push((cx, cy));
            count += 1;
            if count == 2 {
                break;
            }
        }
    }
    // Luminaires: a circle with a cross.
    for &(s, t) in &opts.luminaires_st {
        let (cx, cy) = (x_of(s), y_of(t));
        let r = 7.0;
        for k in 0..24 {
            let (a0, a1) = (
                k as f64 / 24.0 * std::f64::consts::TAU,
                (k + 1) as f64 / 24.0 * std::f64::consts::TAU,
            );
            img.line(
                (cx + r * a0.cos(), cy + r * a0.sin()),
                (cx + r * a1.cos(), cy + r * a1.sin()),
                1.5,
                INK,
            );
        }
        img.line((cx - r, cy), (cx + r, cy), 1.2, INK);
        img.line((cx, cy - r), (cx, cy + r), 1.2, INK);
    }
    // Outline of the rectangle.
    let (x0, y0, x1, y1) = (
        left as f64,
        top as f64,
        (left + pw) as f64,
        (top + ph) as f64,
    );
    for (a, b) in [
        ((x0, y0), (x1, y0)),
        ((x1, y0), (x1, y1)),
        ((x1, y1), (x0, y1)),
        ((x0, y1), (x0, y0)),
    ] {
        img.line(a, b, 2.0, INK);
    }
    // Metre ticks.
    let step = nice_step(grid.len_u.max(grid.len_v), 6.0).max(0.1);
    let mut k = 0;
    while k as f64 * step <= grid.len_u + 1e-9 {
        let s = k as f64 * step;
        img.line((x_of(s), y1), (x_of(s), y1 + 6.0), 1.0, INK);
        let l = fmt_m(s);
        img.text(
            (x_of(s) - text_width(&l, 2) as f64 / 2.0) as i64,
            top + ph + 10,
            2,
            &l,
            INK,
        );
        k += 1;
    }
    let mut k = 0;
    while k as f64 * step <= grid.len_v + 1e-9 {
        let t = k as f64 * step;
        img.line((x0 - 6.0, y_of(t)), (x0, y_of(t)), 1.0, INK);
        let l = fmt_m(t);
        img.text(
            left - 10 - text_width(&l, 2),
            (y_of(t) - 7.0) as i64,
            2,
            &l,
            INK,
        );
        k += 1;
    }
    let last = fmt_m((grid.len_u / step + 1e-9).floor() * step);
    let end = x_of((grid.len_u / step + 1e-9).floor() * step) + text_width(&last, 2) as f64 / 2.0;
    img.text(end as i64 + 8, top + ph + 10, 2, "m", INK);
    // Title and figures.
    img.text(left, 14, 2, &opts.title, INK);
    if let Some(st) = stats {
        let line = format!(
            "Eavg {} lx  Emin {} lx  Emax {} lx  U0 {:.2}  Ud {:.2}",
            fmt_lx(st.e_avg.value),
            fmt_lx(st.e_min.value),
            fmt_lx(st.e_max.value),
            st.u0.value,
            st.ud.value
        );
        img.text(left, top + ph + 52, 2, &line, INK);
    }
    // Legend: a vertical bar from lo (bottom) to hi (top) with the levels marked.
    let (lx0, lx1) = (left + pw + 24, left + pw + 44);
    let (ly0, ly1) = (top, top + ph.max(220));
    for y in ly0..ly1 {
        let f = (ly1 - 1 - y) as f64 / (ly1 - ly0 - 1) as f64;
        img.rect(lx0, y, lx1, y + 1, colour(f));
    }
    for (a, b) in [
        ((lx0, ly0), (lx1, ly0)),
        ((lx1, ly0), (lx1, ly1)),
        ((lx1, ly1), (lx0, ly1)),
        ((lx0, ly1), (lx0, ly0)),
    ] {
        img.line((a.0 as f64, a.1 as f64), (b.0 as f64, b.1 as f64), 1.0, INK);
    }
    let mut ticks = vec![lo];
    ticks.extend(levels.iter().copied().filter(|l| *l > lo && *l < hi));
    ticks.push(hi);
    let mut last_y = f64::INFINITY;
    for (k, v) in ticks.iter().enumerate() {
        let y = ly1 as f64 - (v - lo) / (hi - lo) * (ly1 - ly0) as f64;
        let is_level = k > 0 && k + 1 < ticks.len();
        img.line(
            (lx0 as f64 - if is_level { 4.0 } else { 0.0 }, y),
            (lx1 as f64 + 5.0, y),
            1.2,
            INK,
        );
        // Labels at least 18 px apart; the top one always.
        if last_y - y >= 18.0 || k + 1 == ticks.len() {
            img.text(lx1 + 9, (y - 7.0) as i64, 2, &fmt_lx(*v), INK);
            last_y = y;
        }
    }
    img.text(lx0, ly0 - 22, 2, "lx", INK);
    Ok(img)
}

fn fmt_m(v: f64) -> String {
    if (v - v.round()).abs() < 1e-9 {
        format!("{:.0}", v)
    } else {
        format!("{v:.1}")
    }
}

/// A hand-drawn 5 × 8 pixel font, one glyph per line: the character, then 8 rows (top to
/// bottom) of 5 pixels, `#` ink; rows 0–6 are the cap height, row 7 the descender.
const FONT_ART: &str = r"0 .###. #...# #..## #.#.# ##..# #...# .###. .....
1 ..#.. .##.. ..#.. ..#.. ..#.. ..#.. .###. .....
2 .###. #...# ....# ...#. ..#.. .#... ##### .....
3 ####. ....# ....# .###. ....# ....# ####. .....
4 ...#. ..##. .#.#. #..#. ##### ...#. ...#. .....
5 ##### #.... ####. ....# ....# #...# .###. .....
6 ..##. .#... #.... ####. #...# #...# .###. .....
7 ##### ....# ...#. ..#.. .#... .#... .#... .....
8 .###. #...# #...# .###. #...# #...# .###. .....
9 .###. #...# #...# .#### ....# ...#. .##.. .....
. ..... ..... ..... ..... ..... .##.. .##.. .....
, ..... ..... ..... ..... ..... .##.. ..#.. .#...
- ..... ..... ..... .###. ..... ..... ..... .....
+ ..... ..#.. ..#.. ##### ..#.. ..#.. ..... .....
: ..... .##.. .##.. ..... .##.. .##.. ..... .....
( ...#. ..#.. .#... .#... .#... ..#.. ...#. .....
) .#... ..#.. ...#. ...#. ...#. ..#.. .#... .....
/ ....# ....# ...#. ..#.. .#... #.... #.... .....
= ..... ..... ##### ..... ##### ..... ..... .....
% ##..# ##..# ...#. ..#.. .#... #..## #..## .....
x ..... ..... #...# .#.#. ..#.. .#.#. #...# .....
A .###. #...# #...# ##### #...# #...# #...# .....
B ####. #...# #...# ####. #...# #...# ####. .....
C .###. #...# #.... #.... #.... #...# .###. .....
D ###.. #..#. #...# #...# #...# #..#. ###.. .....
E ##### #.... #.... ####. #.... #.... ##### .....
F ##### #.... #.... ####. #.... #.... #.... .....
G .###. #...# #.... #.### #...# #...# .#### .....
H #...# #...# #...# ##### #...# #...# #...# .....
I .###. ..#.. ..#.. ..#.. ..#.. ..#.. .###. .....
J ..### ...#. ...#. ...#. ...#. #..#. .##.. .....
K #...# #..#. #.#.. ##... #.#.. #..#. #...# .....
L #.... #.... #.... #.... #.... #.... ##### .....
M #...# ##.## #.#.# #.#.# #...# #...# #...# .....
N #...# #...# ##..# #.#.# #..## #...# #...# .....
O .###. #...# #...# #...# #...# #...# .###. .....
P ####. #...# #...# ####. #.... #.... #.... .....
Q .###. #...# #...# #...# #.#.# #..#. .##.# .....
R ####. #...# #...# ####. #.#.. #..#. #...# .....
S .#### #.... #.... .###. ....# ....# ####. .....
T ##### ..#.. ..#.. ..#.. ..#.. ..#.. ..#.. .....
U #...# #...# #...# #...# #...# #...# .###. .....
V #...# #...# #...# #...# #...# .#.#. ..#.. .....
W #...# #...# #...# #.#.# #.#.# #.#.# .#.#. .....
X #...# #...# .#.#. ..#.. .#.#. #...# #...# .....
Y #...# #...# .#.#. ..#.. ..#.. ..#.. ..#.. .....
Z ##### ....# ...#. ..#.. .#... #.... ##### .....
a ..... ..... .###. ....# .#### #...# .#### .....
b #.... #.... #.##. ##..# #...# #...# ####. .....
c ..... ..... .###. #.... #.... #...# .###. .....
d ....# ....# .##.# #..## #...# #...# .#### .....
e ..... ..... .###. #...# ##### #.... .###. .....
f ..##. .#..# .#... ###.. .#... .#... .#... .....
g ..... ..... .#### #...# #...# .#### ....# .###.
h #.... #.... #.##. ##..# #...# #...# #...# .....
i ..#.. ..... .##.. ..#.. ..#.. ..#.. .###. .....
j ...#. ..... ..##. ...#. ...#. ...#. #..#. .##..
k #.... #.... #..#. #.#.. ##... #.#.. #..#. .....
l .#... .#... .#... .#... .#... .#... ..##. .....
m ..... ..... ##.#. #.#.# #.#.# #...# #...# .....
n ..... ..... #.##. ##..# #...# #...# #...# .....
o ..... ..... .###. #...# #...# #...# .###. .....
p ..... ..... ####. #...# #...# ####. #.... #....
q ..... ..... .#### #...# #...# .#### ....# ....#
r ..... ..... #.##. ##..# #.... #.... #.... .....
s ..... ..... .###. #.... .###. ....# ####. .....
t .#... .#... ###.. .#... .#... .#..# ..##. .....
u ..... ..... #...# #...# #...# #..## .##.# .....
v ..... ..... #...# #...# #...# .#.#. ..#.. .....
w ..... ..... #...# #...# #.#.# #.#.# .#.#. .....
y ..... ..... #...# #...# #...# .#### ....# .###.
z ..... ..... ##### ...#. ..#.. .#... ##### .....";

fn font() -> &'static [(char, [u8; 8])] {
    static FONT: std::sync::OnceLock<Vec<(char, [u8; 8])>> = std::sync::OnceLock::new();
    FONT.get_or_init(|| {
        FONT_ART
            .lines()
            .filter_map(|line| {
                let mut parts = line.split_whitespace();
                let c = parts.next()?.chars().next()?;
                let mut rows = [0u8; 8];
                for r in rows.iter_mut() {
                    *r = parts
                        .next()?
                        .bytes()
                        .fold(0u8, |acc, b| (acc << 1) | u8::from(b == b'#'));
                }
                Some((c, rows))
            })
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn font_has_every_glyph_the_plots_use() {
        assert_eq!(font().len(), 72);
        for c in "0123456789.,-+:()/=%x lx Eavg Emin Emax U0 Ud m Work plane".chars() {
            assert!(c == ' ' || glyph(c).is_some(), "{c}");
        }
        // '1': a vertical stroke with a base.
        assert_eq!(glyph('1').unwrap()[6], 0b01110);
    }

    #[test]
    fn auto_levels_are_nice_and_inside() {
        let (l, lo, hi) = auto_levels(212.0, 688.0);
        // span 476 / 6 = 79 → step 100: levels 300..600, range 200..700.
        assert_eq!(l, vec![300.0, 400.0, 500.0, 600.0]);
        assert_eq!((lo, hi), (200.0, 700.0));
        let (l, ..) = auto_levels(0.8, 1.9);
        assert_eq!(l, vec![1.0, 1.2, 1.4, 1.6, 1.8]);
    }
}
