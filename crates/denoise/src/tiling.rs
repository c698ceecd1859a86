//! Tiling of large images: cores of `tile`² pixels, each extended by `overlap` pixels of
//! context, origins and overlap multiples of 16 so that every tile sees the whole image's
//! pooling grid.

use luxest_io::{Error, Result};

/// Tiling of large images: cores of `tile`² pixels with `overlap` pixels of context.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tiling {
    pub tile: usize,
    pub overlap: usize,
}

impl Default for Tiling {
    /// 1024² cores with 96 pixels of context: the default U-Net's receptive-field radius is
    /// below 96 (tested); an image of up to 1024² is one tile (the context of smaller cores costs
    /// more than it saves: 768² cores did 41 % more pixels at 1024², 25 % more CPU time), and
    /// the largest tile (1216² inside a large image) needs about 1.6 GB of activations.
    fn default() -> Tiling {
        Tiling {
            tile: 1024,
            overlap: 96,
        }
    }
}

impl Tiling {
    pub fn validate(&self) -> Result<()> {
        if self.tile == 0 || !self.tile.is_multiple_of(16) || !self.overlap.is_multiple_of(16) {
            return Err(Error::Usage(format!(
                "--tile ({}) must be a positive multiple of 16 and --overlap ({}) a multiple of 16",
                self.tile, self.overlap
            )));
        }
        Ok(())
    }
}

/// Splits 0..n into consecutive spans of at most `size` (the last may be shorter).
pub(crate) fn spans(n: usize, size: usize) -> Vec<(usize, usize)> {
    (0..n.div_ceil(size))
        .map(|i| (i * size, ((i + 1) * size).min(n)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_cover_without_overlap() {
        assert_eq!(spans(10, 4), vec![(0, 4), (4, 8), (8, 10)]);
        assert_eq!(spans(8, 8), vec![(0, 8)]);
        assert!(spans(0, 8).is_empty());
    }

    #[test]
    fn tiling_must_align_to_the_pooling_grid() {
        assert!(Tiling {
            tile: 100,
            overlap: 16
        }
        .validate()
        .is_err());
        assert!(Tiling {
            tile: 64,
            overlap: 8
        }
        .validate()
        .is_err());
        assert!(Tiling::default().validate().is_ok());
    }
}
