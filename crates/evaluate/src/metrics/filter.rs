//! One-dimensional and separable image filters with the border rules of scipy.ndimage
//! (half-sample symmetric reflection) and of the FLIP C++ code (clamp to edge), and
//! pytorch_msssim's unpadded filtering.

/// How a 1-D filter reads outside the image.
#[derive(Clone, Copy)]
pub(super) enum Border {
    /// Half-sample symmetric: `d c b a | a b c d | d c b a` (scipy.ndimage `reflect`).
    Reflect,
    /// The nearest edge sample (FLIP).
    Clamp,
}

pub(super) fn border_index(i: isize, n: usize, border: Border) -> usize {
    let n = n as isize;
    match border {
        Border::Clamp => i.clamp(0, n - 1) as usize,
        Border::Reflect => {
            let period = 2 * n;
            let m = i.rem_euclid(period);
            (if m < n { m } else { period - 1 - m }) as usize
        }
    }
}

/// Correlates a `w` x `h` plane with `kernel` (odd length, centred) along x (`along_x`) or y;
/// output of the same size.
pub(super) fn filter_1d(
    src: &[f64],
    w: usize,
    h: usize,
    kernel: &[f64],
    along_x: bool,
    border: Border,
) -> Vec<f64> {
    let r = (kernel.len() / 2) as isize;
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut acc = 0.0;
            for (k, weight) in kernel.iter().enumerate() {
                let d = k as isize - r;
                let i = if along_x {
                    y * w + border_index(x as isize + d, w, border)
                } else {
                    border_index(y as isize + d, h, border) * w + x
                };
                acc += weight * src[i];
            }
            out[y * w + x] = acc;
        }
    }
    out
}

/// Separable filter, first along y then along x (scipy's axis order).
pub(super) fn filter_2d(
    src: &[f64],
    w: usize,
    h: usize,
    kernel: &[f64],
    border: Border,
) -> Vec<f64> {
    let tmp = filter_1d(src, w, h, kernel, false, border);
    filter_1d(&tmp, w, h, kernel, true, border)
}

/// Correlation without padding: only positions the kernel covers fully, first along y then x
/// (pytorch_msssim). A dimension shorter than the kernel is left unfiltered, as there.
pub(super) fn filter_valid(
    src: &[f64],
    w: usize,
    h: usize,
    kernel: &[f64],
) -> (Vec<f64>, usize, usize) {
    let k = kernel.len();
    let (mut cur, mut cw, mut ch) = (src.to_vec(), w, h);
    if ch >= k {
        let nh = ch - k + 1;
        let mut out = vec![0.0; cw * nh];
        for y in 0..nh {
            for x in 0..cw {
                out[y * cw + x] = (0..k).map(|j| kernel[j] * cur[(y + j) * cw + x]).sum();
            }
        }
        cur = out;
        ch = nh;
    }
    if cw >= k {
        let nw = cw - k + 1;
        let mut out = vec![0.0; nw * ch];
        for y in 0..ch {
            for x in 0..nw {
                out[y * nw + x] = (0..k).map(|j| kernel[j] * cur[y * cw + x + j]).sum();
            }
        }
        cur = out;
        cw = nw;
    }
    (cur, cw, ch)
}

pub(super) fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflect_border() {
        assert_eq!(border_index(-1, 4, Border::Reflect), 0);
        assert_eq!(border_index(-2, 4, Border::Reflect), 1);
        assert_eq!(border_index(4, 4, Border::Reflect), 3);
        assert_eq!(border_index(5, 4, Border::Reflect), 2);
        assert_eq!(border_index(-5, 2, Border::Reflect), 0); // b a a b | a b
        assert_eq!(border_index(-3, 2, Border::Reflect), 1);
        assert_eq!(border_index(-3, 4, Border::Clamp), 0);
        assert_eq!(border_index(9, 4, Border::Clamp), 3);
    }
}
