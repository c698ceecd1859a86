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

/// Bytes of activations per pixel of a tile (its core and context): 1.6 GB for the default
/// model's largest tile of 1216² (above).
pub const ACTIVATION_BYTES_PER_PIXEL: u128 = 1100;

impl Tiling {
    /// Checks the largest tile an image of `width` x `height` is cut into against the memory
    /// available (the resource rule): `--tile 16384` would need hundreds of GB of activations.
    pub fn check_memory(&self, width: usize, height: usize) -> Result<()> {
        let (w, h) = self.largest_tile(width, height);
        luxest_io::limits::check_allocation(
            &format!(
                "a {w}x{h} tile of the model's activations (--tile {} with --overlap {})",
                self.tile, self.overlap
            ),
            w * h,
            ACTIVATION_BYTES_PER_PIXEL,
        )
        .map_err(Error::Usage)
    }

    /// The largest tile (core and context) of an image of `width` x `height`.
    pub fn largest_tile(&self, width: usize, height: usize) -> (u128, u128) {
        let side = |n: usize| (n.min(self.tile) + 2 * self.overlap).min(n) as u128;
        (side(width), side(height))
    }

    /// The activations of the largest tile of an image of `width` x `height`, bytes.
    pub fn memory(&self, width: usize, height: usize) -> u128 {
        let (w, h) = self.largest_tile(width, height);
        w * h * ACTIVATION_BYTES_PER_PIXEL
    }

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
    fn a_tile_is_sized_before_the_model_runs() {
        let default = Tiling::default();
        // The default model's largest tile: 1216² pixels, about 1.6 GB.
        assert_eq!(default.largest_tile(4000, 3000), (1216, 1216));
        assert_eq!(default.largest_tile(300, 200), (300, 200));
        if luxest_io::limits::available_memory().is_some_and(|a| a > 2_000_000_000) {
            assert!(default.check_memory(4000, 3000).is_ok());
        }
        let huge = Tiling {
            tile: 1 << 16,
            overlap: 96,
        };
        let e = huge.check_memory(100_000, 100_000).unwrap_err().to_string();
        assert!(
            e.contains("a 65728x65728 tile of the model's activations (--tile 65536 with --overlap 96) needs 4.8 TB of memory"),
            "{e}"
        );
    }

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
