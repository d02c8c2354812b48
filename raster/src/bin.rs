//! Binning screen triangles into tiles.
//!
//! Source triangles are set up in fixed chunks of `CHUNK` (independent of the
//! thread count); each chunk's screen triangles are sorted into per-tile lists
//! (counting sort into one array, CSR style). A tile later walks the chunks in
//! order, so every tile sees its triangles in scene order whatever the
//! scheduling: the depth test's tie-break (first triangle wins) and thus the
//! output are deterministic.

use crate::setup::RasterTri;
use crate::target::{Target, TILE};

/// Source triangles per setup/bin chunk.
pub(crate) const CHUNK: usize = 4096;

/// One chunk's screen triangles and its per-tile index lists.
#[derive(Default)]
pub struct BinnedChunk {
    pub(crate) tris: Vec<RasterTri>,
    /// Tile t's entries are `items[offsets[t]..offsets[t + 1]]`.
    pub(crate) offsets: Vec<u32>,
    /// Indices into `tris`.
    pub(crate) items: Vec<u32>,
    /// Each tile's next free slot while binning (kept for its allocation).
    fill: Vec<u32>,
}

impl BinnedChunk {
    #[inline]
    pub(crate) fn tile_items(&self, t: usize) -> &[u32] {
        &self.items[self.offsets[t] as usize..self.offsets[t + 1] as usize]
    }
}

/// Tile index range [tx0, tx1) × [ty0, ty1) a triangle's bounding box touches.
#[inline]
fn tile_range(t: &RasterTri) -> (usize, usize, usize, usize) {
    let [x0, y0, x1, y1] = t.bbox;
    (
        x0 as usize / TILE,
        (x1 as usize - 1) / TILE + 1,
        y0 as usize / TILE,
        (y1 as usize - 1) / TILE + 1,
    )
}

/// One chunk's screen triangles binned into a new [`BinnedChunk`].
pub fn bin_chunk(target: &Target, tris: Vec<RasterTri>) -> BinnedChunk {
    let mut chunk = BinnedChunk {
        tris,
        ..BinnedChunk::default()
    };
    chunk.bin(target);
    chunk
}

impl BinnedChunk {
    /// (Re)builds the per-tile lists of `self.tris`, reusing the vectors'
    /// allocations: a frame drawn after frame keeps its chunks, where
    /// fresh ones would cost page faults every frame.
    pub(crate) fn bin(&mut self, target: &Target) {
        let BinnedChunk {
            tris,
            offsets,
            items,
            fill,
        } = self;
        bin_into(target, tris, offsets, items, fill);
    }
}

/// Calls `f` with the index of each tile in [tx0, tx1) × [ty0, ty1)
/// (`tiles_x` a row), row by row. Most screen triangles are a few pixels
/// and touch one tile: that case skips the loops (binning was ~85
/// instructions a drawn triangle with them, both sweeps).
#[inline(always)]
fn for_each_tile(
    (tx0, tx1, ty0, ty1): (usize, usize, usize, usize),
    tiles_x: usize,
    mut f: impl FnMut(usize),
) {
    if tx1 == tx0 + 1 && ty1 == ty0 + 1 {
        f(ty0 * tiles_x + tx0);
        return;
    }
    for ty in ty0..ty1 {
        for tx in tx0..tx1 {
            f(ty * tiles_x + tx);
        }
    }
}

fn bin_into(
    target: &Target,
    tris: &[RasterTri],
    offsets: &mut Vec<u32>,
    items: &mut Vec<u32>,
    fill: &mut Vec<u32>,
) {
    let tiles_x = target.tiles_x as usize;
    let tiles = target.tile_count();
    // Counts first: tile t's in counts[t] (offsets[t + 1]).
    offsets.clear();
    offsets.resize(tiles + 1, 0);
    let counts = &mut offsets[1..];
    for t in tris {
        for_each_tile(tile_range(t), tiles_x, |i| counts[i] += 1);
    }
    for i in 1..offsets.len() {
        offsets[i] += offsets[i - 1];
    }
    fill.clear();
    fill.extend_from_slice(&offsets[..tiles]);
    items.clear();
    items.resize(offsets[tiles] as usize, 0);
    for (i, t) in tris.iter().enumerate() {
        for_each_tile(tile_range(t), tiles_x, |tile| {
            let slot = &mut fill[tile];
            items[*slot as usize] = i as u32;
            *slot += 1;
        });
    }
}
