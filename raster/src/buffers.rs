//! Frame buffers: what the shading pass leaves for post stages and AOV
//! writers, row-major at the render target's (supersampled) size.
//!
//! The visibility buffer stays tile-major (target.rs): the scan owns one
//! contiguous tile at a time. Everything after shading is row-major, so an
//! image-space stage reads a pixel's neighbours as `i ± 1` and `i ± width`
//! whatever tile they were shaded in. Shading writes these planes per tile
//! in parallel through `TileWriter`, each tile its own rectangle.

use crate::target::{Target, TILE};
use std::marker::PhantomData;

/// Resizes `v` to `n` elements, new ones zero. An empty `v` (a first
/// frame's) becomes one zeroed allocation: a large block comes from the
/// system already zero, its pages faulted in where a pass first writes
/// them, in parallel, where `resize` would first write every element on
/// the calling thread.
pub(crate) fn resize_zeroed<T: bytemuck::Zeroable + Clone>(v: &mut Vec<T>, n: usize) {
    if v.is_empty() {
        *v = bytemuck::try_zeroed_vec(n).unwrap_or_else(|()| {
            let layout = std::alloc::Layout::array::<T>(n).expect("capacity overflow");
            std::alloc::handle_alloc_error(layout)
        });
    } else {
        v.resize(n, T::zeroed());
    }
}

/// One f32 per pixel per channel, row-major, `width × height`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Planes3 {
    pub r: Vec<f32>,
    pub g: Vec<f32>,
    pub b: Vec<f32>,
}

impl Planes3 {
    pub(crate) fn new(len: usize) -> Planes3 {
        Planes3 {
            r: vec![0.0; len],
            g: vec![0.0; len],
            b: vec![0.0; len],
        }
    }

    pub fn len(&self) -> usize {
        self.r.len()
    }

    pub fn is_empty(&self) -> bool {
        self.r.is_empty()
    }

    /// Pixel `i` as [r, g, b].
    #[inline(always)]
    pub fn get(&self, i: usize) -> [f32; 3] {
        [self.r[i], self.g[i], self.b[i]]
    }
}

/// Which optional buffers a frame fills (colour always is).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BufferSet {
    /// View depth w (distance along the camera axis), +inf where nothing is hit.
    pub depth: bool,
    /// World-space unit shading normal, 0 where nothing is hit.
    pub normal: bool,
    /// Visibility-buffer id, [`crate::MISS`] where nothing is hit.
    pub id: bool,
}

impl BufferSet {
    pub fn union(self, o: BufferSet) -> BufferSet {
        BufferSet {
            depth: self.depth | o.depth,
            normal: self.normal | o.normal,
            id: self.id | o.id,
        }
    }
}

/// The shading pass's output; optional planes are empty unless asked for.
#[derive(Clone, Debug)]
pub struct FrameBuffers {
    pub width: u32,
    pub height: u32,
    /// Linear HDR radiance.
    pub color: Planes3,
    pub depth: Vec<f32>,
    pub normal: Planes3,
    pub id: Vec<u32>,
}

impl FrameBuffers {
    pub fn new(target: &Target, set: BufferSet) -> FrameBuffers {
        let n = target.pixel_count();
        let len = |on: bool| if on { n } else { 0 };
        FrameBuffers {
            width: target.width,
            height: target.height,
            color: Planes3::new(n),
            depth: vec![0.0; len(set.depth)],
            normal: Planes3::new(len(set.normal)),
            id: vec![0; len(set.id)],
        }
    }
}

/// Parallel writes into a row-major plane, one tile rectangle per worker.
///
/// Rows of a tile are not contiguous in a row-major plane, so tiles cannot
/// be handed out as `&mut` slices; the writer keeps the plane's pointer and
/// gives a tile its row segments. Soundness rests on one rule, kept by the
/// shading pass (frame.rs): each tile index is handled by exactly one
/// worker, and tile rectangles do not overlap.
pub(crate) struct TileWriter<'a, T> {
    ptr: *mut T,
    width: usize,
    height: usize,
    _plane: PhantomData<&'a mut [T]>,
}

// SAFETY: the writer hands out disjoint row segments (see the type docs);
// T: Send lets the values cross threads.
unsafe impl<T: Send> Send for TileWriter<'_, T> {}
// SAFETY: a shared writer only gives out row segments through the
// unsafe `tile_row`, whose callers keep to one worker per tile, so no two
// threads reach the same element.
unsafe impl<T: Send> Sync for TileWriter<'_, T> {}

impl<'a, T> TileWriter<'a, T> {
    /// A writer over `plane` (`width × height`, or empty: then `row` gives
    /// empty slices and nothing is written).
    pub(crate) fn new(plane: &'a mut [T], target: &Target) -> TileWriter<'a, T> {
        let (width, height) = if plane.is_empty() {
            (0, 0)
        } else {
            assert_eq!(plane.len(), target.pixel_count(), "plane size");
            (target.width as usize, target.height as usize)
        };
        TileWriter {
            ptr: plane.as_mut_ptr(),
            width,
            height,
            _plane: PhantomData,
        }
    }

    /// Asks the cache for row `y` of the tile at `x0` for writing (its lines
    /// arrive while the rows before it are shaded). Row-major planes give a
    /// tile row only TILE × 4 bytes before the next row's page, too short a
    /// run for the hardware prefetcher, and without this every packet's
    /// store waited on a line from memory, and the shading pass ran
    /// markedly slower than into a tile-local buffer.
    #[inline(always)]
    pub(crate) fn prefetch_row(&self, x0: usize, y: usize) {
        if self.width == 0 || y >= self.height {
            return;
        }
        let n = TILE.min(self.width - x0);
        let bytes = n * std::mem::size_of::<T>();
        #[cfg(target_arch = "x86_64")]
        for off in (0..bytes).step_by(64) {
            // SAFETY: a prefetch is a hint: it never faults, and the
            // address is inside the plane (x0 + n ≤ width, y < height).
            // (`prefetchw` where the target has PRFCHW, else `prefetcht0`:
            // x86-64-v3 does not include it, and t0 measured as good here.)
            unsafe {
                use std::arch::x86_64::{_mm_prefetch, _MM_HINT_ET0};
                let p = (self.ptr.add(y * self.width + x0) as *const i8).add(off);
                _mm_prefetch::<_MM_HINT_ET0>(p);
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = bytes;
    }

    /// Row `y` of the tile whose left column is `x0`: the pixels
    /// x0 .. min(x0 + TILE, width).
    ///
    /// # Safety
    /// The caller must be the only one writing tile (x0 / TILE, y / TILE)
    /// while the returned slice lives (see the type docs).
    #[inline(always)]
    #[allow(clippy::mut_from_ref)] // disjoint rows from a shared writer are its purpose
    pub(crate) unsafe fn tile_row(&self, x0: usize, y: usize) -> &mut [T] {
        if self.width == 0 {
            return &mut [];
        }
        assert!(x0.is_multiple_of(TILE) && x0 < self.width && y < self.height);
        let n = TILE.min(self.width - x0);
        // SAFETY: in bounds (asserted); exclusive by the caller's contract.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(y * self.width + x0), n) }
    }
}

/// A hint to bring every cache line of `v` in (a value or a slice): one
/// prefetch per 64 bytes from its start, and one at its last byte (a value
/// straddling a line boundary). No effect on results; nothing for an
/// empty slice. The one prefetch helper of the raster and the NPR stages.
#[inline(always)]
pub fn prefetch<T: ?Sized>(v: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let p = v as *const T as *const i8;
        let size = std::mem::size_of_val(v);
        if size == 0 {
            return;
        }
        // SAFETY: a prefetch never faults; every address is inside `v`.
        unsafe {
            for off in (0..size).step_by(64) {
                _mm_prefetch::<_MM_HINT_T0>(p.add(off));
            }
            _mm_prefetch::<_MM_HINT_T0>(p.add(size - 1));
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = v;
}
