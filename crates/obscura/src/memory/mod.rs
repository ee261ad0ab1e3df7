//! Large buffers backed by transparent huge pages where the system offers them.
//!
//! The first write to a fresh 4 KiB page costs a page fault, about 1.5 µs on the virtual
//! machines this crate is measured on: a 1920x1080 frame (16.6 MB of depths and ids)
//! then costs 6 ms before a single pixel is drawn, and a prepared view of Sponza 3 ms
//! more. A 2 MiB huge page costs one fault for 512 small ones. On Linux the kernel
//! backs a range with huge pages when asked with `madvise(MADV_HUGEPAGE)` before the
//! first write (transparent huge pages in `madvise` or `always` mode).
//!
//! - Input: an element count; output: a `Vec` with that capacity (or that many zeroed
//!   elements) whose whole 2 MiB-aligned pages are advised to be huge.
//! - Cost: one `madvise` system call per buffer of 2 MiB or more; none for smaller ones.
//! - Limitations: only the 2 MiB-aligned interior of the allocation can get huge pages
//!   (the allocator places the buffer, not this module); the kernel may refuse (no
//!   free huge page, THP disabled) and falls back to small pages silently. Other systems
//!   get plain allocations. A huge page is reserved whole when any byte of it is
//!   written, so the resident size may grow by up to 2 MiB per buffer.
//! - Source: Linux `madvise(2)` and Documentation/admin-guide/mm/transhuge.rst.
//!
//! A program can go further and install a global allocator that maps large blocks in
//! whole huge pages, ends included, and keeps freed ones for reuse, so later buffers
//! cost no page fault at all: the `obscura` command line does (its `allocator.rs`).
//! Choosing a global allocator is a program's decision, so the library offers none.

#[cfg(test)]
mod probe;

use std::collections::TryReserveError;

/// The size of a transparent huge page on x86-64 and most 64-bit Linux systems.
pub(crate) const HUGE_PAGE: usize = 2 << 20;

/// An empty vector with room for at least `n` elements, its 2 MiB pages advised to be
/// huge (see the module doc). An error when the allocation fails.
pub(crate) fn vec_with_capacity<T>(n: usize) -> Result<Vec<T>, TryReserveError> {
    vec_with_capacity_advised(n, true)
}

/// [`vec_with_capacity`], the advice given only when `advise` is true (tests compare
/// both).
pub(crate) fn vec_with_capacity_advised<T>(
    n: usize,
    advise: bool,
) -> Result<Vec<T>, TryReserveError> {
    let mut v: Vec<T> = Vec::new();
    v.try_reserve_exact(n)?;
    if advise {
        advise_huge_pages(v.as_mut_ptr().cast(), v.capacity() * size_of::<T>());
    }
    Ok(v)
}

/// Element types whose all-zero bit pattern is a valid value.
pub(crate) trait Zeroable: Copy {}
impl Zeroable for u32 {}
impl Zeroable for f32 {}
impl Zeroable for u64 {}
impl Zeroable for f64 {}

/// `n` elements of all-zero bits, their 2 MiB pages advised to be huge. The memory comes
/// zeroed from the allocator (`calloc`: fresh pages from the kernel are zero, so nothing
/// is written here and the first touch happens where the caller first writes).
pub(crate) fn zeroed_vec<T: Zeroable>(n: usize) -> Option<Vec<T>> {
    zeroed_vec_advised(n, true)
}

/// [`zeroed_vec`], the advice given only when `advise` is true.
pub(crate) fn zeroed_vec_advised<T: Zeroable>(n: usize, advise: bool) -> Option<Vec<T>> {
    let layout = std::alloc::Layout::array::<T>(n).ok()?;
    if layout.size() == 0 {
        return Some(Vec::new());
    }
    // SAFETY: the layout has a non-zero size.
    let ptr = unsafe { std::alloc::alloc_zeroed(layout) };
    if ptr.is_null() {
        return None;
    }
    if advise {
        advise_huge_pages(ptr, layout.size());
    }
    // SAFETY: `ptr` was allocated by the global allocator with the layout of `[T; n]`
    // (what `Vec<T>` uses for capacity `n`), and its `n` elements are initialized: zero
    // bits are a valid `T` (the `Zeroable` bound).
    Some(unsafe { Vec::from_raw_parts(ptr.cast::<T>(), n, n) })
}

/// Asks the kernel to back the whole pages of `[ptr, ptr + bytes)` with huge pages.
/// Returns whether the advice was taken (false for ranges under 2 MiB, on other systems,
/// or when the kernel has no transparent huge pages); the memory is unchanged either way.
pub(crate) fn advise_huge_pages(ptr: *mut u8, bytes: usize) -> bool {
    if bytes < HUGE_PAGE {
        return false;
    }
    advise_impl(ptr, bytes)
}

#[cfg(target_os = "linux")]
fn advise_impl(ptr: *mut u8, bytes: usize) -> bool {
    // SAFETY: sysconf has no preconditions.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    let page = usize::try_from(page).unwrap_or(4096).max(1);
    let start = (ptr as usize).next_multiple_of(page);
    let end = (ptr as usize).saturating_add(bytes) / page * page;
    if end <= start {
        return false;
    }
    // SAFETY: the range is whole pages inside the caller's allocation; MADV_HUGEPAGE
    // only changes how the kernel backs them (their contents are preserved), so no
    // Rust-visible memory changes.
    unsafe { libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE) == 0 }
}

#[cfg(not(target_os = "linux"))]
fn advise_impl(_ptr: *mut u8, _bytes: usize) -> bool {
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    use super::probe::{anon_huge_kib, huge_pages_enabled};

    #[test]
    fn buffers_hold_what_is_written_with_and_without_advice() {
        for advise in [true, false] {
            for n in [0, 1, 1000, HUGE_PAGE / 4 - 1, 3 * HUGE_PAGE / 4 + 17] {
                let mut v: Vec<u32> = vec_with_capacity_advised(n, advise).unwrap();
                assert!(v.capacity() >= n && v.is_empty());
                v.extend((0..n as u32).map(|i| i.wrapping_mul(2_654_435_761)));
                assert!(
                    v.iter()
                        .enumerate()
                        .all(|(i, &x)| x == (i as u32).wrapping_mul(2_654_435_761))
                );
                let z: Vec<f32> = zeroed_vec_advised(n, advise).unwrap();
                assert_eq!(z.len(), n);
                assert!(z.iter().all(|&x| x.to_bits() == 0));
                let mut z: Vec<u64> = zeroed_vec_advised(n, advise).unwrap();
                z.iter_mut().enumerate().for_each(|(i, x)| *x = i as u64);
                z.push(7); // the vector owns a normal allocation: it can grow
                assert_eq!(z[n], 7);
                assert!(z[..n].iter().enumerate().all(|(i, &x)| x == i as u64));
            }
        }
        // A size that overflows the address space is an error, not a panic.
        assert!(vec_with_capacity::<u64>(usize::MAX / 4).is_err());
        assert!(zeroed_vec::<u64>(usize::MAX / 4).is_none());
    }

    #[test]
    fn small_ranges_are_not_advised() {
        let mut v = vec![0u8; HUGE_PAGE - 1];
        assert!(!advise_huge_pages(v.as_mut_ptr(), v.len()));
        assert!(!advise_huge_pages(v.as_mut_ptr(), 0));
    }

    #[test]
    fn advised_buffers_get_huge_pages_where_the_system_has_them() {
        let n = 4 * HUGE_PAGE / 4; // 8 MiB of u32: at least one whole aligned 2 MiB page
        let mut v: Vec<u32> = vec_with_capacity(n).unwrap();
        let advised = advise_huge_pages(v.as_mut_ptr().cast(), n * 4);
        if !cfg!(target_os = "linux") {
            assert!(!advised);
            return;
        }
        v.resize(n, 1);
        if !huge_pages_enabled() {
            // Advice taken or not, the kernel uses small pages.
            eprintln!(
                "SKIPPED advised_buffers_get_huge_pages_where_the_system_has_them: \
                 transparent huge pages are off on this system"
            );
            return;
        }
        assert!(advised);
        let kib = anon_huge_kib(v.as_ptr() as usize + n * 2).unwrap_or(0);
        // The kernel may lack a free huge page; it usually has one.
        if kib == 0 {
            eprintln!(
                "SKIPPED the huge-page check of advised_buffers_get_huge_pages_where_the_system_has_them: \
                 no huge page backs the advised buffer (memory fragmented?)"
            );
        } else {
            assert!(kib >= 2048 && kib.is_multiple_of(2048), "{kib}");
        }
    }
}
