//! Render targets: the image size, its tiling, and the buffers the passes
//! write. Buffers are tile-major: tile t owns `TILE_PIXELS` consecutive
//! entries (row-major inside the tile, padded past the image's right and
//! bottom edges), so tiles are disjoint slices that threads can own.

use std::fmt;

/// Tile edge in pixels.
pub const TILE: usize = 64;
pub const TILE_PIXELS: usize = TILE * TILE;
/// Largest image side (after supersampling) accepted; see `fixed.rs` for why
/// this is far inside the fixed-point range.
pub const MAX_DIM: u32 = 16384;
/// Visibility-buffer id of a pixel no triangle covers.
pub const MISS: u32 = u32::MAX;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Target {
    /// Size in samples (the output size times `ssaa`).
    pub width: u32,
    pub height: u32,
    pub(crate) tiles_x: u32,
    pub(crate) tiles_y: u32,
    /// Samples per output pixel along each axis: what the post's resolve
    /// will average, and what stages sized in output pixels scale by.
    pub(crate) ssaa: u32,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TargetError(pub(crate) String);

impl fmt::Display for TargetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for TargetError {}

impl Target {
    /// Checks the size before anything is allocated.
    pub fn new(width: u32, height: u32) -> Result<Target, TargetError> {
        for (name, v) in [("width", width), ("height", height)] {
            if v == 0 || v > MAX_DIM {
                return Err(TargetError(format!(
                    "image {name} {v} is out of range: it must be 1..={MAX_DIM} pixels (after supersampling)"
                )));
            }
        }
        let t = TILE as u32;
        Ok(Target {
            width,
            height,
            tiles_x: width.div_ceil(t),
            tiles_y: height.div_ceil(t),
            ssaa: 1,
        })
    }

    /// The target of an image supersampled `ssaa` × `ssaa` (its size is
    /// already the sample count; 0 is taken as 1).
    pub fn with_ssaa(self, ssaa: u32) -> Target {
        Target {
            ssaa: ssaa.max(1),
            ..self
        }
    }

    pub fn tile_count(&self) -> usize {
        (self.tiles_x * self.tiles_y) as usize
    }

    /// Pixel coordinates of tile `t`'s top-left corner.
    pub fn tile_origin(&self, t: usize) -> (u32, u32) {
        let t = t as u32;
        (
            (t % self.tiles_x) * TILE as u32,
            (t / self.tiles_x) * TILE as u32,
        )
    }

    /// Index of pixel (x, y) in a tile-major buffer.
    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        let (tx, ty) = (x as usize / TILE, y as usize / TILE);
        let t = ty * self.tiles_x as usize + tx;
        t * TILE_PIXELS + (y as usize % TILE) * TILE + x as usize % TILE
    }

    /// Length of a tile-major buffer.
    pub fn buffer_len(&self) -> usize {
        self.tile_count() * TILE_PIXELS
    }

    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Copies a tile-major buffer into a row-major one of `width × height`.
    pub fn to_row_major<T: Copy + Send + Sync>(&self, tiled: &[T]) -> Vec<T> {
        let mut out = Vec::with_capacity(self.pixel_count());
        for y in 0..self.height {
            for x0 in (0..self.width).step_by(TILE) {
                let start = self.index(x0, y);
                let n = (self.width - x0).min(TILE as u32) as usize;
                out.extend_from_slice(&tiled[start..start + n]);
            }
        }
        out
    }
}

/// Depth (NDC z in [0, 1]) and triangle id per pixel: the output of the
/// visibility pass.
#[derive(Default)]
pub struct VisBuffer {
    pub depth: Vec<f32>,
    pub id: Vec<u32>,
}

impl VisBuffer {
    pub fn new(t: &Target) -> VisBuffer {
        VisBuffer {
            depth: vec![0.0; t.buffer_len()],
            id: vec![MISS; t.buffer_len()],
        }
    }

    /// Buffers for `t` left zero, not cleared to [`MISS`]: for a frame
    /// whose first geometry pass clears each tile before it draws (as the
    /// frame's passes do). Zero costs no writes: a large block comes from
    /// the system already zero.
    pub(crate) fn uncleared(t: &Target) -> VisBuffer {
        VisBuffer {
            depth: vec![0.0; t.buffer_len()],
            id: vec![0; t.buffer_len()],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_sizes_before_allocating() {
        assert!(Target::new(0, 10).is_err());
        assert!(Target::new(10, MAX_DIM + 1).is_err());
        let e = Target::new(u32::MAX, 10).unwrap_err();
        assert!(e.0.contains("width"), "{e}");
    }

    #[test]
    fn tile_major_round_trips_to_row_major() {
        let t = Target::new(130, 70).unwrap();
        let mut buf = vec![0u32; t.buffer_len()];
        for y in 0..t.height {
            for x in 0..t.width {
                buf[t.index(x, y)] = y * 1000 + x;
            }
        }
        let rm = t.to_row_major(&buf);
        for (i, v) in rm.iter().enumerate() {
            let (x, y) = (i as u32 % t.width, i as u32 / t.width);
            assert_eq!(*v, y * 1000 + x);
        }
    }
}
