//! Linear RGB triples (Rec. 709 primaries), the photometric luminance Y, and the sRGB transfer
//! function that encodes linear values for display and decodes sRGB-encoded textures.
//!
//! In photometric scenes the Y of an RGB value *is* the photometric quantity (cd, lm, lx,
//! cd/m²); the RGB split only tints it.

use serde::{Deserialize, Serialize};
use std::ops::{Add, Mul};

/// Rec. 709 / sRGB luminance weights (ITU-R BT.709-6, item 3.2).
pub const LUMINANCE_WEIGHTS: [f64; 3] = [0.2126, 0.7152, 0.0722];

#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(from = "[f64; 3]", into = "[f64; 3]")]
pub struct Rgb(pub [f64; 3]);

impl From<[f64; 3]> for Rgb {
    fn from(a: [f64; 3]) -> Self {
        Rgb(a)
    }
}
impl From<Rgb> for [f64; 3] {
    fn from(c: Rgb) -> Self {
        c.0
    }
}

impl Rgb {
    pub const BLACK: Rgb = Rgb([0.0; 3]);
    pub const WHITE: Rgb = Rgb([1.0; 3]);

    pub fn splat(v: f64) -> Rgb {
        Rgb([v; 3])
    }
    /// Photometric luminance Y (Rec. 709 weights).
    pub fn luminance(&self) -> f64 {
        self.0
            .iter()
            .zip(LUMINANCE_WEIGHTS)
            .map(|(c, w)| c * w)
            .sum()
    }
    pub fn max_component(&self) -> f64 {
        self.0.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
    }
    pub fn min_component(&self) -> f64 {
        self.0.iter().cloned().fold(f64::INFINITY, f64::min)
    }
    pub fn is_finite(&self) -> bool {
        self.0.iter().all(|c| c.is_finite())
    }
    /// This colour rescaled so that its luminance equals `y`: a tint carrying a photometric
    /// magnitude. `None` if the colour has no luminance.
    pub fn with_luminance(&self, y: f64) -> Option<Rgb> {
        let l = self.luminance();
        (l > 0.0 && l.is_finite()).then(|| *self * (y / l))
    }
}

impl Mul<f64> for Rgb {
    type Output = Rgb;
    fn mul(self, s: f64) -> Rgb {
        Rgb(self.0.map(|c| c * s))
    }
}
impl Mul for Rgb {
    type Output = Rgb;
    fn mul(self, o: Rgb) -> Rgb {
        Rgb([self.0[0] * o.0[0], self.0[1] * o.0[1], self.0[2] * o.0[2]])
    }
}
impl Add for Rgb {
    type Output = Rgb;
    fn add(self, o: Rgb) -> Rgb {
        Rgb([self.0[0] + o.0[0], self.0[1] + o.0[1], self.0[2] + o.0[2]])
    }
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

/// Inverse sRGB transfer function (IEC 61966-2-1): the linear value of an encoded one in [0, 1].
pub fn srgb_decode(v: f64) -> f64 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_has_unit_luminance() {
        assert!((Rgb::WHITE.luminance() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn rescaling_sets_luminance() {
        let c = Rgb([0.9, 0.2, 0.1]).with_luminance(1000.0).unwrap();
        assert!((c.luminance() - 1000.0).abs() < 1e-9);
        assert!(Rgb::BLACK.with_luminance(1.0).is_none());
    }

    #[test]
    fn srgb_decoding_inverts_encoding() {
        // IEC 61966-2-1: code 128 of 255 is 0.2158605 linear, the linear segment ends at 0.04045.
        assert!((srgb_decode(128.0 / 255.0) - 0.215_860_500_113_899_2).abs() < 1e-15);
        assert_eq!(srgb_decode(0.04045), 0.04045 / 12.92);
        assert_eq!(srgb_decode(0.0), 0.0);
        assert!((srgb_decode(1.0) - 1.0).abs() < 1e-15);
        for k in 0..=255 {
            let v = k as f64 / 255.0;
            assert!((srgb_encode(srgb_decode(v)) - v).abs() < 1e-12, "{k}");
        }
    }
}
