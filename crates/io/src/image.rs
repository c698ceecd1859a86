//! The linear RGB image every stage exchanges: row-major from the top-left, 32-bit float
//! R, G, B per pixel (scene-referred radiance, albedo, normals, ...), with the string header
//! attributes that carry its run metadata ([`crate::header`]).
//!
//! It is read and written as OpenEXR by [`crate::exr`], previewed as PNG by [`crate::png`]; its
//! autoexposure, a contract shared with Python, is [`crate::exposure`]'s.

/// A linear RGB image, row-major from the top-left, interleaved `[r, g, b]` per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
    /// Header attributes (name, value) beyond the standard ones.
    pub attributes: Vec<(String, String)>,
}

impl RgbImage {
    pub fn new(width: usize, height: usize) -> RgbImage {
        RgbImage {
            width,
            height,
            pixels: vec![[0.0; 3]; width * height],
            attributes: Vec::new(),
        }
    }
    /// The header attribute `key` (one of [`crate::header`]'s keys), if present.
    pub fn attribute(&self, key: &str) -> Option<&str> {
        crate::header::get(&self.attributes, key)
    }
    /// Sets the header attribute `key`, replacing an earlier value.
    pub fn set_attribute(&mut self, key: &str, value: impl std::fmt::Display) {
        crate::header::set(&mut self.attributes, key, value)
    }
    /// Position of the first non-finite pixel value, if any.
    pub fn first_non_finite(&self) -> Option<(usize, usize)> {
        self.pixels
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
            .map(|i| (i % self.width, i / self.width))
    }
}
