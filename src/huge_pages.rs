//! The command line's allocator: the system allocator for small blocks;
//! large ones mapped directly, on 2 MiB boundaries, and advised for
//! transparent huge pages.
//!
//! A run from process start to image fills fresh buffers of several
//! megabytes (the OBJ's bytes, the mesh cache's file, the scene's arrays,
//! the visibility buffer, the 8-bit image, the PNG). In 4 KiB pages each
//! megabyte costs the kernel 256 page faults, each zeroing and mapping one
//! page; where transparent huge pages are enabled only for memory that
//! asks (`madvise`, a common default), a block advised with
//! `MADV_HUGEPAGE` is mapped 2 MiB at a time instead. Blocks are aligned
//! and sized to whole huge pages so that all of a block can be mapped so.
//!
//! A large block is its own anonymous mapping, so it starts zeroed
//! (`alloc_zeroed` writes nothing: pages never touched are never faulted
//! in) and goes back to the kernel when freed. The advice only changes how
//! memory is mapped, never its contents; where it is refused (transparent
//! huge pages off) the block is mapped in small pages. On other systems
//! every block goes to the system allocator.

use std::alloc::{GlobalAlloc, Layout, System};

/// The huge page size of x86-64 and of aarch64 with 4 KiB pages.
const HUGE_PAGE: usize = 2 << 20;

/// Blocks from this size on are mapped on huge pages. Smaller ones would
/// waste most of a huge page.
const MIN_BYTES: usize = HUGE_PAGE;

/// The system allocator with large blocks on transparent huge pages (see
/// the module docs). Set it as the binary's `#[global_allocator]`.
pub struct HugePageAlloc;

/// The bytes a block of `layout` is mapped with, a whole number of huge
/// pages; None for blocks the system allocator serves (small ones, or an
/// alignment beyond a huge page). The same layout gives the same answer,
/// which is what `dealloc` relies on.
fn huge_len(layout: Layout) -> Option<usize> {
    if !cfg!(target_os = "linux") || layout.size() < MIN_BYTES || layout.align() > HUGE_PAGE {
        return None;
    }
    layout.size().checked_next_multiple_of(HUGE_PAGE)
}

/// A fresh zeroed mapping of `len` bytes (a multiple of [`HUGE_PAGE`]) at
/// a multiple of [`HUGE_PAGE`], advised for huge pages; null on failure.
#[cfg(target_os = "linux")]
fn map_huge(len: usize) -> *mut u8 {
    let Some(span) = len.checked_add(HUGE_PAGE) else {
        return std::ptr::null_mut();
    };
    // SAFETY: a new private anonymous mapping; nothing else refers to it.
    // The parts cut off before and after the aligned block are whole
    // pages of that mapping, unmapped once.
    unsafe {
        let prot = libc::PROT_READ | libc::PROT_WRITE;
        let flags = libc::MAP_PRIVATE | libc::MAP_ANONYMOUS;
        let map = libc::mmap(std::ptr::null_mut(), span, prot, flags, -1, 0);
        if map == libc::MAP_FAILED {
            return std::ptr::null_mut();
        }
        let map = map.cast::<u8>();
        let lead = map.addr().next_multiple_of(HUGE_PAGE) - map.addr();
        if lead > 0 {
            libc::munmap(map.cast(), lead);
        }
        let block = map.add(lead);
        let tail = HUGE_PAGE - lead;
        if tail > 0 {
            libc::munmap(block.add(len).cast(), tail);
        }
        libc::madvise(block.cast(), len, libc::MADV_HUGEPAGE);
        block
    }
}

/// Unmaps a block [`map_huge`] gave.
#[cfg(target_os = "linux")]
fn unmap_huge(ptr: *mut u8, len: usize) {
    // SAFETY: `ptr` and `len` are a mapping `map_huge` made, freed once.
    unsafe {
        libc::munmap(ptr.cast(), len);
    }
}

#[cfg(not(target_os = "linux"))]
fn map_huge(_len: usize) -> *mut u8 {
    unreachable!("huge_len gives no length on this system")
}

#[cfg(not(target_os = "linux"))]
fn unmap_huge(_ptr: *mut u8, _len: usize) {
    unreachable!("huge_len gives no length on this system")
}

// SAFETY: a block is either the system allocator's (when `huge_len` gives
// None for its layout), freed and resized by it with the caller's layout,
// or one mapping of `huge_len` bytes, aligned to a huge page (so to any
// alignment `huge_len` accepts), freed by unmapping that length.
unsafe impl GlobalAlloc for HugePageAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        match huge_len(layout) {
            Some(len) => map_huge(len),
            // SAFETY: the caller's layout, of non-zero size.
            None => unsafe { System.alloc(layout) },
        }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        match huge_len(layout) {
            Some(len) => map_huge(len),
            // SAFETY: the caller's layout, of non-zero size.
            None => unsafe { System.alloc_zeroed(layout) },
        }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        match huge_len(layout) {
            Some(len) => unmap_huge(ptr, len),
            // SAFETY: `ptr` is the system allocator's block of `layout`.
            None => unsafe { System.dealloc(ptr, layout) },
        }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: the caller guarantees `new_size` rounded up to
        // `layout.align()` does not overflow `isize`.
        let new = unsafe { Layout::from_size_align_unchecked(new_size, layout.align()) };
        match (huge_len(layout), huge_len(new)) {
            // SAFETY: the system allocator's block of `layout`.
            (None, None) => unsafe { System.realloc(ptr, layout, new_size) },
            (Some(old), Some(len)) if old == len => ptr,
            _ => {
                // SAFETY: `new` has a non-zero size (the caller's).
                let p = unsafe { self.alloc(new) };
                if !p.is_null() {
                    // SAFETY: both blocks hold at least the bytes copied
                    // and are distinct; `ptr` is the caller's live block.
                    unsafe {
                        std::ptr::copy_nonoverlapping(ptr, p, layout.size().min(new_size));
                        self.dealloc(ptr, layout);
                    }
                }
                p
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_blocks_are_whole_huge_pages_and_small_ones_the_systems() {
        let layout = |size, align| Layout::from_size_align(size, align).unwrap();
        assert_eq!(huge_len(layout(MIN_BYTES - 1, 8)), None);
        assert_eq!(huge_len(layout(MIN_BYTES, 4 * HUGE_PAGE)), None);
        if cfg!(target_os = "linux") {
            assert_eq!(huge_len(layout(MIN_BYTES + 1, 16)), Some(2 * HUGE_PAGE));
        }
    }

    #[test]
    fn blocks_keep_their_bytes_across_every_realloc_crossing() {
        let a = HugePageAlloc;
        let sizes = [100, MIN_BYTES + 5, 3 * MIN_BYTES, MIN_BYTES + 7, 1000, 64];
        let mut layout = Layout::from_size_align(sizes[0], 8).unwrap();
        // SAFETY: each block is used within its size and freed once, with
        // its layout.
        unsafe {
            let mut p = a.alloc(layout);
            assert!(!p.is_null());
            for i in 0..layout.size() {
                *p.add(i) = i as u8;
            }
            for &n in &sizes[1..] {
                let kept = layout.size().min(n);
                p = a.realloc(p, layout, n);
                assert!(!p.is_null());
                layout = Layout::from_size_align(n, 8).unwrap();
                if huge_len(layout).is_some() {
                    assert_eq!(p as usize % HUGE_PAGE, 0);
                }
                assert!((0..kept).all(|i| *p.add(i) == i as u8), "to {n} bytes");
                for i in kept..n {
                    *p.add(i) = i as u8;
                }
            }
            a.dealloc(p, layout);
            let z = Layout::from_size_align(3 * MIN_BYTES + 1, 64).unwrap();
            let q = a.alloc_zeroed(z);
            assert!(!q.is_null());
            assert!((0..z.size()).step_by(4093).all(|i| *q.add(i) == 0));
            a.dealloc(q, z);
        }
    }
}
