//! A global allocator that gives large blocks whole transparent huge pages.
//!
//! The library advises the kernel to back its large buffers with huge pages
//! (`madvise`, in the library's `memory` module), but only the buffer's 2 MiB-aligned interior can have them: the system allocator
//! places a large block 16 bytes past a 4 KiB page boundary, so up to 2 MiB at each end
//! stays in small pages. For a 1080p frame that is about 1,000 page faults (1.5 ms on
//! the virtual machines this crate is measured on), and every large buffer of a
//! one-shot run (the loaded scene, the prepared view, the frame) pays the same.
//!
//! - What it does: blocks of at least [`LARGE`] bytes are mapped directly from the
//!   kernel at a 2 MiB-aligned address, their length rounded up to whole 2 MiB pages,
//!   and advised with `MADV_HUGEPAGE`, so that every page of the block can be huge.
//!   Growing such a block moves its pages (`mremap`) to a new aligned place instead
//!   of copying them. Smaller
//!   blocks, and every block on systems other than Linux, go to [`System`].
//! - Freed large blocks are kept for reuse (at most [`KEPT_BLOCKS`] of them and
//!   [`KEPT_BYTES`] in all; beyond that they go back to the kernel). A new large block
//!   takes the smallest kept block that holds it (the rest of that block stays kept),
//!   or else the largest kept one, grown. Its pages have been written before, so the
//!   block costs no page fault: the buffers of a render (the prepared view, the frame)
//!   reuse those the scene's loading freed, and a program rendering frame after frame
//!   stops faulting after the first.
//! - Cost: one `mmap` (and up to two `munmap`s of the alignment slack) per fresh
//!   block; the kernel zeroes each huge page on its first write (a 2 MiB clear). On
//!   the virtual machines this crate is measured on, a first write runs at 0.3 to
//!   8 GB/s, an ordinary write to a page already faulted in at about 8 GB/s. Fresh
//!   mappings read as zero, so `alloc_zeroed` writes only the reused part of a block.
//! - Limitations: a huge page is reserved whole when any byte of it is written, so a
//!   large block may hold up to 2 MiB more resident memory than it uses; kept blocks
//!   stay resident (up to [`KEPT_BYTES`]) until reused or the allocator is dropped;
//!   the kernel
//!   falls back to small pages silently when it has no free huge page or transparent
//!   huge pages are off (`never`).
//! - Use: the `obscura` command line installs it (`main.rs`); it lives here, not in
//!   the library, because choosing a global allocator is a program's decision. The
//!   library works the same without it.
//! - Source: Linux `mmap(2)`, `mremap(2)`, `madvise(2)` and
//!   Documentation/admin-guide/mm/transhuge.rst.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::{Mutex, PoisonError};

/// The size of a transparent huge page on x86-64 and most 64-bit Linux systems.
const HUGE_PAGE: usize = 2 << 20;

/// Blocks of at least this many bytes are mapped in huge pages: from 1 MiB, one huge
/// page (a 2 MiB clear) costs less than the 256 small-page faults it replaces.
pub const LARGE: usize = 1 << 20;

/// The global allocator of the module doc: large blocks in whole 2 MiB pages, the rest
/// from the system allocator.
///
/// ```
/// use std::alloc::{GlobalAlloc, Layout};
/// use crate::allocator::HugePageAllocator;
///
/// let a = HugePageAllocator::new();
/// let layout = Layout::array::<u32>(4 << 20).unwrap(); // 16 MiB
/// // SAFETY: the layout has a non-zero size; each block is freed with its layout.
/// unsafe {
///     let p = a.alloc_zeroed(layout);
///     assert!(!p.is_null() && *p.add(12345) == 0);
///     *p.add(12345) = 7;
///     a.dealloc(p, layout);
///     // The freed block is kept, and zeroed again when reused.
///     let q = a.alloc_zeroed(layout);
///     assert_eq!((q, *q.add(12345)), (p, 0));
///     a.dealloc(q, layout);
/// }
/// ```
#[derive(Debug, Default)]
pub struct HugePageAllocator {
    kept: Mutex<Kept>,
}

/// The most freed large blocks a [`HugePageAllocator`] keeps for reuse.
pub const KEPT_BLOCKS: usize = 8;

/// The most bytes a [`HugePageAllocator`] keeps in freed blocks.
pub const KEPT_BYTES: usize = 512 << 20;

/// Freed mapped blocks (address and mapped length; whole huge pages, 2 MiB-aligned).
#[derive(Debug, Default)]
struct Kept {
    blocks: [(usize, usize); KEPT_BLOCKS],
    count: usize,
}

impl Kept {
    fn bytes(&self) -> usize {
        self.blocks[..self.count].iter().map(|b| b.1).sum()
    }

    /// Adds a block if there is room; false if not.
    fn put(&mut self, at: usize, len: usize) -> bool {
        if self.count == KEPT_BLOCKS || self.bytes() + len > KEPT_BYTES {
            return false;
        }
        self.blocks[self.count] = (at, len);
        self.count += 1;
        true
    }

    /// Removes and returns a block for `len` bytes (a multiple of [`HUGE_PAGE`]): the
    /// first `len` bytes of the smallest block that holds them (the rest of it stays
    /// kept, always with room: it replaces a larger block), else the largest block
    /// whole; `None` when none is kept.
    fn take(&mut self, len: usize) -> Option<(usize, usize)> {
        let kept = &self.blocks[..self.count];
        let fits = (0..kept.len())
            .filter(|&i| kept[i].1 >= len)
            .min_by_key(|&i| kept[i].1);
        let i = fits.or_else(|| (0..kept.len()).max_by_key(|&i| kept[i].1))?;
        let (at, kept_len) = self.blocks[i];
        self.count -= 1;
        self.blocks[i] = self.blocks[self.count];
        if kept_len > len {
            // Last, as a freed block: the order decides between equal fits later.
            self.blocks[self.count] = (at + len, kept_len - len);
            self.count += 1;
            return Some((at, len));
        }
        Some((at, kept_len))
    }
}

impl HugePageAllocator {
    /// An allocator keeping no block yet.
    #[must_use]
    pub const fn new() -> Self {
        HugePageAllocator {
            kept: Mutex::new(Kept {
                blocks: [(0, 0); KEPT_BLOCKS],
                count: 0,
            }),
        }
    }

    /// Bytes held in freed blocks kept for reuse.
    #[cfg(test)]
    #[must_use]
    pub fn kept_bytes(&self) -> usize {
        self.lock().bytes()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Kept> {
        // Nothing panics while the lock is held; a poisoned lock still holds valid blocks.
        self.kept.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// A mapped block for `size` bytes, zeroed if asked: a kept block when there is
    /// one (see the module doc), else a fresh mapping; null on failure.
    fn obtain(&self, size: usize, zeroed: bool) -> *mut u8 {
        let Some(len) = mapped_len(size) else {
            return std::ptr::null_mut();
        };
        let taken = self.lock().take(len);
        let Some((at, kept_len)) = taken else {
            return map(size);
        };
        let (p, reused) = if kept_len == len {
            (at as *mut u8, size)
        } else {
            // SAFETY: a kept block is a whole mapping of `kept_len` bytes, used by
            // nobody; `remap` moves its pages and maps the rest fresh (zero).
            let p = unsafe { remap(at as *mut u8, kept_len, size) };
            if p.is_null() {
                // SAFETY: still the kept block (remap leaves it unchanged on failure).
                unsafe { unmap(at as *mut u8, kept_len) };
                return map(size);
            }
            (p, kept_len)
        };
        if zeroed {
            // SAFETY: the first `reused` bytes of the block are mapped and ours.
            unsafe { std::ptr::write_bytes(p, 0, reused) };
        }
        p
    }

    /// Frees a mapped block of `size` bytes: kept if there is room, else unmapped.
    ///
    /// # Safety
    /// `ptr` is such a block, not used after this.
    unsafe fn release(&self, ptr: *mut u8, size: usize) {
        let Some(len) = mapped_len(size) else {
            return;
        };
        if !self.lock().put(ptr as usize, len) {
            // SAFETY: the caller's contract.
            unsafe { unmap(ptr, size) };
        }
    }
}

impl Drop for HugePageAllocator {
    fn drop(&mut self) {
        let kept = self.kept.get_mut().unwrap_or_else(PoisonError::into_inner);
        for &(at, len) in &kept.blocks[..kept.count] {
            // SAFETY: kept blocks are whole mappings used by nobody.
            unsafe { unmap(at as *mut u8, len) };
        }
        kept.count = 0;
    }
}

/// The largest alignment of a mapped block (more goes to [`System`]).
const MAPPED_ALIGN: usize = 4096;

/// Whether a block of this layout is mapped (rather than given to [`System`]).
#[inline]
fn is_mapped(size: usize, align: usize) -> bool {
    cfg!(target_os = "linux") && size >= LARGE && align <= MAPPED_ALIGN
}

/// The length mapped for a block of `size` bytes: whole huge pages.
#[inline]
fn mapped_len(size: usize) -> Option<usize> {
    size.checked_next_multiple_of(HUGE_PAGE)
}

// SAFETY: every block is either from `System` (small ones: all calls forwarded with
// their layouts) or a private anonymous mapping of `mapped_len(size)` bytes at a
// 2 MiB-aligned address (large ones), which `is_mapped` tells apart from the layout
// alone, as `GlobalAlloc` guarantees the same layout at `dealloc` and `realloc`.
// Mappings are readable, writable, and aligned to 2 MiB, more than the largest
// alignment `is_mapped` accepts; kept blocks (freed mappings) are handed out whole or
// split at huge page boundaries, and zeroed by `obtain` where `alloc_zeroed` needs it.
unsafe impl GlobalAlloc for HugePageAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if is_mapped(layout.size(), layout.align()) {
            self.obtain(layout.size(), false)
        } else {
            // SAFETY: the caller's contract (non-zero size).
            unsafe { System.alloc(layout) }
        }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if is_mapped(layout.size(), layout.align()) {
            self.obtain(layout.size(), true)
        } else {
            // SAFETY: the caller's contract.
            unsafe { System.alloc_zeroed(layout) }
        }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if is_mapped(layout.size(), layout.align()) {
            // SAFETY: `ptr` is a mapping of this size (the impl's invariant).
            unsafe { self.release(ptr, layout.size()) }
        } else {
            // SAFETY: the caller's contract.
            unsafe { System.dealloc(ptr, layout) }
        }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let old = is_mapped(layout.size(), layout.align());
        let new = is_mapped(new_size, layout.align());
        if !old && !new {
            // SAFETY: the caller's contract.
            return unsafe { System.realloc(ptr, layout, new_size) };
        }
        if old && new {
            // SAFETY: `ptr` is a mapping of `layout.size()` bytes.
            return unsafe { remap(ptr, layout.size(), new_size) };
        }
        // Between the two kinds: a new block, the contents copied, the old freed.
        // SAFETY: `new_size` is non-zero and `layout.align()` a power of two (the
        // caller's contract), so the layout is valid; the blocks do not overlap.
        unsafe {
            let new_layout = Layout::from_size_align_unchecked(new_size, layout.align());
            let p = self.alloc(new_layout);
            if !p.is_null() {
                std::ptr::copy_nonoverlapping(ptr, p, layout.size().min(new_size));
                self.dealloc(ptr, layout);
            }
            p
        }
    }
}

/// A fresh mapping of `mapped_len(size)` bytes at a 2 MiB-aligned address, advised to
/// be huge; null on failure.
#[cfg(target_os = "linux")]
fn map(size: usize) -> *mut u8 {
    let Some(len) = mapped_len(size) else {
        return std::ptr::null_mut();
    };
    let Some(span) = len.checked_add(HUGE_PAGE) else {
        return std::ptr::null_mut();
    };
    // SAFETY: an anonymous private mapping has no preconditions; the slack around the
    // aligned part is unmapped (whole pages of the fresh mapping, touched by nobody).
    unsafe {
        let p = libc::mmap(
            std::ptr::null_mut(),
            span,
            libc::PROT_READ | libc::PROT_WRITE,
            libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
            -1,
            0,
        );
        if p == libc::MAP_FAILED {
            return std::ptr::null_mut();
        }
        let start = p as usize;
        let aligned = start.next_multiple_of(HUGE_PAGE);
        if aligned > start {
            libc::munmap(p, aligned - start);
        }
        let end = aligned + len;
        if start + span > end {
            libc::munmap(end as *mut libc::c_void, start + span - end);
        }
        // Advice refused (THP off) leaves small pages: still correct.
        libc::madvise(aligned as *mut libc::c_void, len, libc::MADV_HUGEPAGE);
        aligned as *mut u8
    }
}

/// Unmaps a block made by [`map`] for `size` bytes.
///
/// # Safety
/// `ptr` is such a block, not used after this.
#[cfg(target_os = "linux")]
unsafe fn unmap(ptr: *mut u8, size: usize) {
    if let Some(len) = mapped_len(size) {
        // SAFETY: the block's whole mapping (the caller's contract).
        unsafe { libc::munmap(ptr.cast(), len) };
    }
}

/// Grows or shrinks a block made by [`map`] for `old` bytes to `new` bytes (both
/// mapped sizes), keeping it on a 2 MiB boundary; null on failure (the block is then
/// unchanged). A shrinking block keeps its place; a growing one has its pages moved
/// (not copied) to a fresh aligned mapping: a move the kernel placed itself would
/// lose the alignment, and with it the huge pages at the block's ends.
///
/// # Safety
/// `ptr` is such a block.
#[cfg(target_os = "linux")]
unsafe fn remap(ptr: *mut u8, old: usize, new: usize) -> *mut u8 {
    let (Some(old_len), Some(new_len)) = (mapped_len(old), mapped_len(new)) else {
        return std::ptr::null_mut();
    };
    if old_len == new_len {
        return ptr;
    }
    // SAFETY: `ptr` is a whole mapping of `old_len` bytes (the caller's contract).
    // Shrinking in place keeps its first `new_len` bytes. Moving with MREMAP_FIXED
    // replaces the fresh mapping `target` (ours, used by nobody) with the block's
    // pages, their contents kept, the rest of the new length reading as zero.
    unsafe {
        if new_len < old_len {
            let p = libc::mremap(ptr.cast(), old_len, new_len, 0);
            return if p == libc::MAP_FAILED {
                std::ptr::null_mut()
            } else {
                p.cast()
            };
        }
        let target = map(new);
        if target.is_null() {
            return target;
        }
        let p = libc::mremap(
            ptr.cast(),
            old_len,
            new_len,
            libc::MREMAP_MAYMOVE | libc::MREMAP_FIXED,
            target.cast::<libc::c_void>(),
        );
        if p == libc::MAP_FAILED {
            libc::munmap(target.cast(), new_len);
            return std::ptr::null_mut();
        }
        libc::madvise(p, new_len, libc::MADV_HUGEPAGE);
        p.cast()
    }
}

#[cfg(not(target_os = "linux"))]
fn map(_size: usize) -> *mut u8 {
    unreachable!("is_mapped is false off Linux")
}

#[cfg(not(target_os = "linux"))]
unsafe fn unmap(_ptr: *mut u8, _size: usize) {
    unreachable!("is_mapped is false off Linux")
}

#[cfg(not(target_os = "linux"))]
unsafe fn remap(_ptr: *mut u8, _old: usize, _new: usize) -> *mut u8 {
    unreachable!("is_mapped is false off Linux")
}

/// The library's huge-page probes, shared with its `memory` tests.
#[cfg(test)]
#[path = "../../obscura/src/memory/probe.rs"]
mod probe;

#[cfg(test)]
mod tests {
    use super::*;

    use super::probe::{anon_huge_kib, huge_pages_enabled};

    /// A pattern value for byte `i`.
    fn pattern(i: usize) -> u8 {
        (i.wrapping_mul(2_654_435_761) >> 7) as u8
    }

    /// Allocates `size` bytes with `align`, checks alignment and zeroing, writes a
    /// pattern, grows or shrinks the block through each size of `steps`, checking the
    /// kept prefix each time, and frees it.
    fn round_trip(zeroed: bool, size: usize, align: usize, steps: &[usize]) {
        let a = HugePageAllocator::new();
        let mut layout = Layout::from_size_align(size, align).unwrap();
        // SAFETY: non-zero sizes; every block is used within its size and freed once
        // with its current layout.
        unsafe {
            let mut p = if zeroed {
                a.alloc_zeroed(layout)
            } else {
                a.alloc(layout)
            };
            assert!(!p.is_null());
            assert_eq!(p as usize % align, 0);
            let bytes = std::slice::from_raw_parts_mut(p, size);
            if zeroed {
                assert!(bytes.iter().all(|&b| b == 0));
            }
            bytes
                .iter_mut()
                .enumerate()
                .for_each(|(i, b)| *b = pattern(i));
            for &new in steps {
                p = a.realloc(p, layout, new);
                assert!(!p.is_null());
                assert_eq!(p as usize % align, 0);
                if is_mapped(new, align) {
                    // Moved or not, a mapped block stays on a huge page boundary.
                    assert_eq!(p as usize % HUGE_PAGE, 0);
                }
                let keep = layout.size().min(new);
                let bytes = std::slice::from_raw_parts_mut(p, new);
                assert!(
                    bytes[..keep]
                        .iter()
                        .enumerate()
                        .all(|(i, &b)| b == pattern(i))
                );
                bytes
                    .iter_mut()
                    .enumerate()
                    .for_each(|(i, b)| *b = pattern(i));
                layout = Layout::from_size_align(new, align).unwrap();
            }
            a.dealloc(p, layout);
        }
    }

    #[test]
    fn blocks_of_every_size_class_hold_their_contents_through_reallocation() {
        let small = 1000;
        let large = LARGE + 12345;
        let larger = 3 * LARGE + 7;
        for zeroed in [false, true] {
            for align in [1, 8, 64, 4096] {
                // small -> large -> larger -> large (same pages) -> small -> small
                round_trip(
                    zeroed,
                    small,
                    align,
                    &[large, larger, larger - 5, large, 77, 5000],
                );
                round_trip(zeroed, larger, align, &[small]);
                round_trip(zeroed, LARGE, align, &[LARGE - 1, LARGE]);
            }
        }
        // Larger alignments go to the system allocator.
        round_trip(false, LARGE, 2 * MAPPED_ALIGN, &[2 * LARGE]);
    }

    #[test]
    fn large_blocks_are_mapped_on_huge_page_boundaries() {
        if !cfg!(target_os = "linux") {
            assert!(!is_mapped(LARGE, 8));
            return;
        }
        assert!(is_mapped(LARGE, 8) && !is_mapped(LARGE - 1, 8));
        assert!(!is_mapped(LARGE, 2 * MAPPED_ALIGN));
        let layout = Layout::from_size_align(LARGE + 1, 4).unwrap();
        let a = HugePageAllocator::new();
        // SAFETY: a non-zero size; freed with its layout.
        unsafe {
            let p = a.alloc(layout);
            assert_eq!(p as usize % HUGE_PAGE, 0);
            a.dealloc(p, layout);
        }
        // Sizes that cannot be mapped are refused with null, not a panic.
        assert!(mapped_len(usize::MAX - 5).is_none());
        assert!(map(usize::MAX - 5).is_null());
    }

    #[test]
    fn large_blocks_lie_in_huge_pages_from_end_to_end() {
        if !huge_pages_enabled() {
            eprintln!(
                "SKIPPED large_blocks_lie_in_huge_pages_from_end_to_end: transparent huge \
                 pages are off on this system"
            );
            return;
        }
        let size = 3 * HUGE_PAGE + 100;
        let layout = Layout::from_size_align(size, 4).unwrap();
        let a = HugePageAllocator::new();
        // SAFETY: a non-zero size, written within it, freed with its layout.
        unsafe {
            let p = a.alloc_zeroed(layout);
            std::slice::from_raw_parts_mut(p, size).fill(1);
            let kib = anon_huge_kib(p as usize).unwrap_or(0);
            a.dealloc(p, layout);
            // The kernel may lack free huge pages; it usually has them.
            if kib == 0 {
                eprintln!(
                    "SKIPPED the huge-page check of large_blocks_lie_in_huge_pages_from_end_to_end: \
                     no huge page backs the block (memory fragmented?)"
                );
            } else {
                // Every page, the first and the last included: 4 of them (more if the
                // kernel merged a neighbouring mapping of another test into this one).
                assert!(kib >= 4 * 2048, "{kib} KiB in huge pages");
            }
        }
    }

    #[test]
    fn vectors_on_the_allocator_behave_like_vectors() {
        // The allocator as a program would use it, through a Vec's growth by doubling
        // across the size classes.
        let layout_of = |n: usize| Layout::array::<u64>(n).unwrap();
        let a = HugePageAllocator::new();
        // SAFETY: a buffer of `cap` u64s grown by realloc, used within its capacity.
        unsafe {
            let mut cap = 16usize;
            let mut p = a.alloc(layout_of(cap)).cast::<u64>();
            let mut len = 0usize;
            while len < 2_000_000 {
                if len == cap {
                    p = a.realloc(p.cast(), layout_of(cap), cap * 2 * 8).cast();
                    assert!(!p.is_null());
                    cap *= 2;
                }
                p.add(len).write(len as u64 * 3);
                len += 1;
            }
            assert!((0..len).all(|i| *p.add(i) == i as u64 * 3));
            a.dealloc(p.cast(), layout_of(cap));
        }
    }

    /// Allocates `pages` huge pages (less 100 bytes), zeroed or not, and fills them
    /// with `byte`.
    ///
    /// # Safety
    /// The block must be freed with [`layout_of`]`(pages)`.
    unsafe fn filled(a: &HugePageAllocator, pages: usize, zeroed: bool, byte: u8) -> *mut u8 {
        let layout = layout_of(pages);
        // SAFETY: a non-zero size, written within it.
        unsafe {
            let p = if zeroed {
                a.alloc_zeroed(layout)
            } else {
                a.alloc(layout)
            };
            assert!(!p.is_null() && (p as usize).is_multiple_of(HUGE_PAGE));
            let bytes = std::slice::from_raw_parts_mut(p, layout.size());
            if zeroed {
                assert!(
                    bytes.iter().all(|&b| b == 0),
                    "a zeroed block holds old bytes"
                );
            }
            bytes.fill(byte);
            p
        }
    }

    fn layout_of(pages: usize) -> Layout {
        Layout::from_size_align(pages * HUGE_PAGE - 100, 8).unwrap()
    }

    #[test]
    fn freed_blocks_are_reused_whole_split_or_grown_and_zeroed_when_asked() {
        if !cfg!(target_os = "linux") {
            eprintln!(
                "SKIPPED freed_blocks_are_reused_whole_split_or_grown_and_zeroed_when_asked: the allocator maps memory only on Linux"
            );
            return;
        }
        let a = HugePageAllocator::new();
        // SAFETY: every block is used within its size and freed once with its layout.
        unsafe {
            // Whole: the same block again, zeroed.
            let p = filled(&a, 3, false, 7);
            a.dealloc(p, layout_of(3));
            assert_eq!(a.kept_bytes(), 3 * HUGE_PAGE);
            let q = filled(&a, 3, true, 8);
            assert_eq!(q, p);
            assert_eq!(a.kept_bytes(), 0);
            a.dealloc(q, layout_of(3));
            // Split: the smaller block at the start, the rest still kept and taken
            // next, both zeroed although the pages held 8.
            let r = filled(&a, 1, true, 9);
            assert_eq!(r, p);
            assert_eq!(a.kept_bytes(), 2 * HUGE_PAGE);
            let s = filled(&a, 2, true, 9);
            assert_eq!(s as usize, p as usize + HUGE_PAGE);
            assert_eq!(a.kept_bytes(), 0);
            // Grown: a block larger than any kept one takes the largest kept one,
            // its old bytes zeroed and the fresh rest zero.
            a.dealloc(r, layout_of(1));
            a.dealloc(s, layout_of(2));
            let t = filled(&a, 4, true, 1);
            assert_eq!(a.kept_bytes(), HUGE_PAGE);
            // Not zeroed when not asked: the kept page still holds its bytes.
            let u = filled(&a, 1, false, 2);
            assert_eq!(a.kept_bytes(), 0);
            a.dealloc(u, layout_of(1));
            let v = a.alloc(layout_of(1));
            assert_eq!((v, *v.add(HUGE_PAGE / 2)), (u, 2));
            a.dealloc(v, layout_of(1));
            a.dealloc(t, layout_of(4));
        }
        assert_eq!(a.kept_bytes(), 5 * HUGE_PAGE);
    }

    #[test]
    fn at_most_the_limits_are_kept() {
        if !cfg!(target_os = "linux") {
            eprintln!(
                "SKIPPED at_most_the_limits_are_kept: the allocator maps memory only on Linux"
            );
            return;
        }
        // SAFETY: blocks freed once with their layouts, never touched.
        unsafe {
            // The count: the blocks past KEPT_BLOCKS go back to the kernel.
            let a = HugePageAllocator::new();
            let blocks: Vec<*mut u8> = (0..KEPT_BLOCKS + 2)
                .map(|_| a.alloc(layout_of(1)))
                .collect();
            for &p in &blocks {
                assert!(!p.is_null());
                a.dealloc(p, layout_of(1));
            }
            assert_eq!(a.kept_bytes(), KEPT_BLOCKS * HUGE_PAGE);
            // The bytes: with room for more blocks, one larger than KEPT_BYTES is not
            // kept (mapping it costs address space only: it is never written).
            let b = HugePageAllocator::new();
            let pages = KEPT_BYTES / HUGE_PAGE + 1;
            let big = b.alloc(layout_of(pages));
            assert!(!big.is_null());
            b.dealloc(big, layout_of(pages));
            assert_eq!(b.kept_bytes(), 0);
            // One that fits is kept.
            let p = b.alloc(layout_of(1));
            b.dealloc(p, layout_of(1));
            assert_eq!(b.kept_bytes(), HUGE_PAGE);
        }
    }
}
