//! LDR-FLIP of display-referred images.
//!
//! [`flip`]: LDR-FLIP (Andersson et al. 2020, "FLIP: A Difference Evaluator for Alternating
//! Images"), as NVIDIA's flip_evaluator 1.7 computes it (`flip_evaluator.evaluate(reference,
//! test, "LDR")`, inputs sRGB-encoded in [0, 1]) at its default viewing conditions: 0.7 m from
//! a 0.7 m wide monitor of 3840 pixels, [`FLIP_PIXELS_PER_DEGREE`] = 67.0206451416 (their f32
//! value of `0.7 * 3840 / 0.7 * pi / 180`). Colour pipeline: sRGB to linear, clamp to [0, 1],
//! linear RGB to XYZ (D65) to YCxCz; separable spatial filtering with the contrast sensitivity
//! functions (achromatic and red-green: one Gaussian each; blue-yellow: a sum of two Gaussians,
//! filtered as two separable passes); back to linear RGB, clamped to [0, 1]; CIELab; Hunt
//! adjustment (`a, b *= 0.01 L`); HyAB distance `|dL| + sqrt(da^2 + db^2)`, raised to 0.7 and
//! mapped to [0, 1] with `cmax` (the distance of green and blue) and `pc = 0.4`, `pt = 0.95`.
//! Feature pipeline: the achromatic channel normalised to [0, 1] (`(Y + 16) / 116`), filtered
//! with first and second derivatives of a Gaussian (sigma `0.5 * 0.082 * ppd` pixels, radius
//! `ceil(3 sigma)`, positive and negative weights normalised to +1 and -1); edge and point
//! magnitudes; feature difference `(max(|d edge|, |d point|) / sqrt 2)^0.5`. Error per pixel
//! `e_c^(1 - e_f)`; [`Flip::mean`] is the mean over pixels. All image filters clamp to the
//! nearest edge pixel at the borders (as the C++ code does). flip_evaluator computes in f32;
//! this code in f64.

use super::filter::{filter_1d, Border};
use super::{check_sizes, Display};

/// FLIP's default pixels per degree: flip_evaluator's `calculatePPD(0.7, 3840, 0.7)` evaluated in
/// f32 (0.7 m viewing distance, 3840 pixels across a 0.7 m wide monitor).
pub const FLIP_PIXELS_PER_DEGREE: f64 = 67.020_645_141_601_56;

/// A FLIP evaluation.
#[derive(Clone, Debug, PartialEq)]
pub struct Flip {
    /// Mean of the error map.
    pub mean: f64,
    /// Error per pixel in [0, 1], row-major.
    pub map: Vec<f32>,
}

const FLIP_QC: f64 = 0.7;
const FLIP_PC: f64 = 0.4;
const FLIP_PT: f64 = 0.95;
const FLIP_W: f64 = 0.082;
const FLIP_QF: f64 = 0.5;
/// D65 reference white of FLIP's XYZ <-> YCxCz / CIELab conversions.
const FLIP_WHITE: [f64; 3] = [0.950428545, 1.0, 1.088900371];
const FLIP_INV_WHITE: [f64; 3] = [1.052156925, 1.0, 0.918357670];

fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_rgb_to_xyz(c: [f64; 3]) -> [f64; 3] {
    const M: [[f64; 3]; 3] = [
        [
            10135552.0 / 24577794.0,
            8788810.0 / 24577794.0,
            4435075.0 / 24577794.0,
        ],
        [
            2613072.0 / 12288897.0,
            8788810.0 / 12288897.0,
            887015.0 / 12288897.0,
        ],
        [
            1425312.0 / 73733382.0,
            8788810.0 / 73733382.0,
            70074185.0 / 73733382.0,
        ],
    ];
    mat3(&M, c)
}

fn xyz_to_linear_rgb(c: [f64; 3]) -> [f64; 3] {
    const M: [[f64; 3]; 3] = [
        [3.241003275, -1.537398934, -0.498615861],
        [-0.969224334, 1.875930071, 0.041554224],
        [0.055639423, -0.204011202, 1.057148933],
    ];
    mat3(&M, c)
}

fn mat3(m: &[[f64; 3]; 3], c: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|r| m[r][0] * c[0] + m[r][1] * c[1] + m[r][2] * c[2])
}

fn xyz_to_ycxcz(c: [f64; 3]) -> [f64; 3] {
    let x = c[0] * FLIP_INV_WHITE[0];
    let y = c[1] * FLIP_INV_WHITE[1];
    let z = c[2] * FLIP_INV_WHITE[2];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_xyz(c: [f64; 3]) -> [f64; 3] {
    let y = (c[0] + 16.0) / 116.0;
    let x = y + c[1] / 500.0;
    let z = y - c[2] / 200.0;
    [x * FLIP_WHITE[0], y * FLIP_WHITE[1], z * FLIP_WHITE[2]]
}

fn xyz_to_cielab(c: [f64; 3]) -> [f64; 3] {
    let delta = 6.0 / 29.0;
    let delta_cube = delta * delta * delta;
    let factor = 1.0 / (3.0 * delta * delta);
    let term = 4.0 / 29.0;
    let f = |v: f64| {
        if v > delta_cube {
            v.cbrt()
        } else {
            factor * v + term
        }
    };
    let x = f(c[0] * FLIP_INV_WHITE[0]);
    let y = f(c[1] * FLIP_INV_WHITE[1]);
    let z = f(c[2] * FLIP_INV_WHITE[2]);
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// CIELab with the Hunt adjustment: a and b scaled by `0.01 L`.
fn hunt(lab: [f64; 3]) -> [f64; 3] {
    [lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]]
}

fn hyab(a: [f64; 3], b: [f64; 3]) -> f64 {
    (a[0] - b[0]).abs() + ((a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// `HyAB(green, blue)^0.7` in Hunt-adjusted CIELab: the largest colour distance.
fn flip_cmax() -> f64 {
    let lab = |rgb: [f64; 3]| hunt(xyz_to_cielab(linear_rgb_to_xyz(rgb)));
    hyab(lab([0.0, 1.0, 0.0]), lab([0.0, 0.0, 1.0])).powf(FLIP_QC)
}

/// The separated CSF filters: (achromatic, red-green, blue-yellow part 1, blue-yellow part 2).
fn flip_spatial_filters(ppd: f64) -> [Vec<f64>; 4] {
    use std::f64::consts::PI;
    // (a, b) of the Gaussians: achromatic, red-green, blue-yellow (two).
    const A1: [f64; 3] = [1.0, 1.0, 34.1];
    const B1: [f64; 3] = [0.0047, 0.0053, 0.04];
    const A2Z: f64 = 13.5;
    const B2Z: f64 = 0.025;
    let max_b = 0.04f64; // the largest scale parameter (b1 of blue-yellow)
    let radius = (3.0 * (max_b / (2.0 * PI * PI)).sqrt() * ppd).ceil() as i64;
    let gaussian = |x2: f64, a: f64, b: f64| a * (PI / b).sqrt() * (-PI * PI * x2 / b).exp();
    let gaussian_sqrt =
        |x2: f64, a: f64, b: f64| (a * (PI / b).sqrt()).sqrt() * (-PI * PI * x2 / b).exp();
    let mut f: [Vec<f64>; 4] = Default::default();
    for i in -radius..=radius {
        let x = i as f64 / ppd;
        let x2 = x * x;
        f[0].push(gaussian(x2, A1[0], B1[0]));
        f[1].push(gaussian(x2, A1[1], B1[1]));
        f[2].push(gaussian_sqrt(x2, A1[2], B1[2]));
        f[3].push(gaussian_sqrt(x2, A2Z, B2Z));
    }
    let sums: Vec<f64> = f.iter().map(|k| k.iter().sum()).collect();
    let norm_z = 1.0 / (sums[2] * sums[2] + sums[3] * sums[3]).sqrt();
    let norms = [1.0 / sums[0], 1.0 / sums[1], norm_z, norm_z];
    for (k, n) in f.iter_mut().zip(norms) {
        k.iter_mut().for_each(|v| *v *= n);
    }
    f
}

/// The feature filters: (Gaussian, first derivative, second derivative).
fn flip_feature_filters(ppd: f64) -> [Vec<f64>; 3] {
    let sd = 0.5 * FLIP_W * ppd;
    let radius = (3.0 * sd).ceil() as i64;
    let mut g = Vec::new();
    let mut dg = Vec::new();
    let mut ddg = Vec::new();
    for i in -radius..=radius {
        let x = i as f64;
        let gv = (-(x * x) / (2.0 * sd * sd)).exp();
        g.push(gv);
        dg.push(-x * gv);
        ddg.push((x * x / (sd * sd) - 1.0) * gv);
    }
    let g_sum: f64 = g.iter().sum();
    let pos = |k: &[f64]| k.iter().filter(|v| **v > 0.0).sum::<f64>();
    let neg = |k: &[f64]| -k.iter().filter(|v| **v <= 0.0).sum::<f64>();
    let (dp, dn, ddp, ddn) = (pos(&dg), neg(&dg), pos(&ddg), neg(&ddg));
    g.iter_mut().for_each(|v| *v /= g_sum);
    dg.iter_mut()
        .for_each(|v| *v /= if *v > 0.0 { dp } else { dn });
    ddg.iter_mut()
        .for_each(|v| *v /= if *v > 0.0 { ddp } else { ddn });
    [g, dg, ddg]
}

/// Spatially filtered, Hunt-adjusted CIELab of a YCxCz image given as three planes.
fn flip_filtered_lab(
    ycxcz: &[Vec<f64>; 3],
    w: usize,
    h: usize,
    f: &[Vec<f64>; 4],
) -> Vec<[f64; 3]> {
    let sep = |p: &[f64], k: &[f64]| {
        let tmp = filter_1d(p, w, h, k, true, Border::Clamp);
        filter_1d(&tmp, w, h, k, false, Border::Clamp)
    };
    let y = sep(&ycxcz[0], &f[0]);
    let cx = sep(&ycxcz[1], &f[1]);
    let cz1 = sep(&ycxcz[2], &f[2]);
    let cz2 = sep(&ycxcz[2], &f[3]);
    (0..w * h)
        .map(|i| {
            let rgb = xyz_to_linear_rgb(ycxcz_to_xyz([y[i], cx[i], cz1[i] + cz2[i]]))
                .map(|v| v.clamp(0.0, 1.0));
            hunt(xyz_to_cielab(linear_rgb_to_xyz(rgb)))
        })
        .collect()
}

/// Edge and point magnitudes of the normalised achromatic channel.
fn flip_features(y: &[f64], w: usize, h: usize, f: &[Vec<f64>; 3]) -> (Vec<f64>, Vec<f64>) {
    let gray: Vec<f64> = y.iter().map(|v| (v + 16.0) / 116.0).collect();
    let along_x = |p: &[f64], k: &[f64]| filter_1d(p, w, h, k, true, Border::Clamp);
    let along_y = |p: &[f64], k: &[f64]| filter_1d(p, w, h, k, false, Border::Clamp);
    let gx = along_x(&gray, &f[0]);
    let dx = along_y(&along_x(&gray, &f[1]), &f[0]);
    let ddx = along_y(&along_x(&gray, &f[2]), &f[0]);
    let dy = along_y(&gx, &f[1]);
    let ddy = along_y(&gx, &f[2]);
    let edge = dx.iter().zip(&dy).map(|(a, b)| a.hypot(*b)).collect();
    let point = ddx.iter().zip(&ddy).map(|(a, b)| a.hypot(*b)).collect();
    (edge, point)
}

fn flip_ycxcz_planes(image: &Display) -> [Vec<f64>; 3] {
    let mut planes: [Vec<f64>; 3] = Default::default();
    for p in &image.pixels {
        let linear = p.map(|v| srgb_to_linear(v).clamp(0.0, 1.0));
        let c = xyz_to_ycxcz(linear_rgb_to_xyz(linear));
        for k in 0..3 {
            planes[k].push(c[k]);
        }
    }
    planes
}

/// LDR-FLIP of sRGB-encoded display images at [`FLIP_PIXELS_PER_DEGREE`].
pub fn flip(reference: &Display, test: &Display) -> Flip {
    flip_with_ppd(reference, test, FLIP_PIXELS_PER_DEGREE)
}

/// LDR-FLIP at `ppd` pixels per degree of visual angle.
pub fn flip_with_ppd(reference: &Display, test: &Display, ppd: f64) -> Flip {
    check_sizes(reference, test);
    let (w, h) = (reference.width, reference.height);
    if w == 0 || h == 0 {
        return Flip {
            mean: 0.0,
            map: Vec::new(),
        };
    }
    let ref_ycxcz = flip_ycxcz_planes(reference);
    let test_ycxcz = flip_ycxcz_planes(test);

    let spatial = flip_spatial_filters(ppd);
    let ref_lab = flip_filtered_lab(&ref_ycxcz, w, h, &spatial);
    let test_lab = flip_filtered_lab(&test_ycxcz, w, h, &spatial);
    let cmax = flip_cmax();
    let pccmax = FLIP_PC * cmax;

    let feature = flip_feature_filters(ppd);
    let (ref_edge, ref_point) = flip_features(&ref_ycxcz[0], w, h, &feature);
    let (test_edge, test_point) = flip_features(&test_ycxcz[0], w, h, &feature);

    let mut map = Vec::with_capacity(w * h);
    let mut sum = 0.0;
    for i in 0..w * h {
        let d = hyab(ref_lab[i], test_lab[i]).powf(FLIP_QC);
        let color = if d < pccmax {
            d * FLIP_PT / pccmax
        } else {
            FLIP_PT + (d - pccmax) / (cmax - pccmax) * (1.0 - FLIP_PT)
        };
        let edge = (ref_edge[i] - test_edge[i]).abs();
        let point = (ref_point[i] - test_point[i]).abs();
        let feature = (edge.max(point) / std::f64::consts::SQRT_2).powf(FLIP_QF);
        let e = color.powf(1.0 - feature);
        sum += e;
        map.push(e as f32);
    }
    Flip {
        mean: sum / (w * h) as f64,
        map,
    }
}
