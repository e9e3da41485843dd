//! Huge pages for large allocations (Linux), as a global allocator for the
//! front-ends' binaries.
//!
//! A 16.7M-particle load writes ~1.5 GB of freshly allocated arrays (the
//! positions, keys, order, packed particles, the BVH, gathers); on 4 KiB
//! pages that is ~370,000 page faults, each taken under the process's
//! memory locks (measured: ~9 % of such a load's samples in the kernel's
//! fault path and its locks, besides zeroing the pages). Where transparent
//! huge pages are enabled only for regions that ask (`madvise`, the usual
//! distribution default), this allocator asks for every allocation of at
//! least [`HUGE`] bytes, so that its 2 MiB-aligned interior faults in 2 MiB
//! at a time. Everything else is the system allocator's: the same blocks,
//! the same alignment, the same contents; where the kernel declines (huge
//! pages off, no contiguous memory) the advice changes nothing. Measured
//! alone on that load: ×0.97 (1.68 → 1.63 s), peak memory unchanged
//! (pages are still touched only where written).
//!
//! Each binary opts in (a library cannot choose the allocator):
//!
//! ```ignore
//! #[global_allocator]
//! static ALLOC: voxless::huge_pages::HugePages = voxless::huge_pages::HugePages;
//! ```

use std::alloc::{GlobalAlloc, Layout, System};

/// Allocations from this size on are advised to use huge pages.
pub const HUGE: usize = 8 << 20;

/// The system allocator, with huge pages advised for large blocks (see the
/// module docs).
pub struct HugePages;

// SAFETY: every block comes from `System` with the caller's layout and goes
// back to it unchanged; the advice only changes how its pages are backed.
unsafe impl GlobalAlloc for HugePages {
    #[inline]
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded with the caller's layout.
        let p = unsafe { System.alloc(layout) };
        advise(p, layout.size());
        p
    }

    #[inline]
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        advise(p, layout.size());
        p
    }

    #[inline]
    unsafe fn dealloc(&self, p: *mut u8, layout: Layout) {
        // SAFETY: `p` came from `System` with this layout.
        unsafe { System.dealloc(p, layout) }
    }

    #[inline]
    unsafe fn realloc(&self, p: *mut u8, layout: Layout, size: usize) -> *mut u8 {
        // SAFETY: as `dealloc`; the new size is the caller's.
        let q = unsafe { System.realloc(p, layout, size) };
        if size > layout.size() {
            advise(q, size);
        }
        q
    }
}

/// Advises huge pages for the whole 2 MiB pages inside `[p, p + size)`.
#[inline]
fn advise(p: *mut u8, size: usize) {
    #[cfg(target_os = "linux")]
    if size >= HUGE && !p.is_null() {
        const PAGE: usize = 2 << 20;
        let start = (p as usize).next_multiple_of(PAGE);
        let end = (p as usize + size) / PAGE * PAGE;
        if end > start {
            // SAFETY: the range lies inside the block just allocated;
            // MADV_HUGEPAGE changes no contents (a refusal is ignored).
            unsafe {
                libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (p, size);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The VMA flags (`/proc/self/smaps`' `VmFlags`) of the mapping holding
    /// address `at`.
    #[cfg(target_os = "linux")]
    fn vm_flags(at: usize) -> Option<String> {
        let smaps = std::fs::read_to_string("/proc/self/smaps").ok()?;
        let mut inside = false;
        for line in smaps.lines() {
            if let Some((range, _)) = line.split_once(' ')
                && let Some((lo, hi)) = range.split_once('-')
                && let (Ok(lo), Ok(hi)) =
                    (usize::from_str_radix(lo, 16), usize::from_str_radix(hi, 16))
            {
                inside = (lo..hi).contains(&at);
            } else if inside && let Some(flags) = line.strip_prefix("VmFlags:") {
                return Some(flags.trim().to_string());
            }
        }
        None
    }

    /// Small and large blocks, grown and shrunk, keep their contents; a
    /// large block's pages are advised (where the kernel has huge pages).
    #[test]
    fn blocks_keep_contents_and_large_ones_are_advised() {
        for size in [24, 4096, HUGE - 8, HUGE, 3 * HUGE + 12345] {
            let layout = Layout::from_size_align(size, 8).unwrap();
            // SAFETY: a non-zero size; the block is written within its size
            // and given back with the layout it has.
            unsafe {
                let p = HugePages.alloc(layout);
                assert!(!p.is_null());
                for k in (0..size).step_by(4093) {
                    *p.add(k) = (k % 251) as u8;
                }
                #[cfg(target_os = "linux")]
                if size >= HUGE
                    && std::path::Path::new("/sys/kernel/mm/transparent_hugepage").exists()
                {
                    let interior = (p as usize).next_multiple_of(2 << 20);
                    let flags = vm_flags(interior).expect("the block's mapping in smaps");
                    assert!(flags.split(' ').any(|f| f == "hg"), "{size}: {flags}");
                }
                let q = HugePages.realloc(p, layout, 2 * size);
                for k in (0..size).step_by(4093) {
                    assert_eq!(*q.add(k), (k % 251) as u8);
                }
                let grown = Layout::from_size_align(2 * size, 8).unwrap();
                let r = HugePages.realloc(q, grown, size / 2);
                for k in (0..size / 2).step_by(4093) {
                    assert_eq!(*r.add(k), (k % 251) as u8);
                }
                HugePages.dealloc(r, Layout::from_size_align(size / 2, 8).unwrap());
                let z = HugePages.alloc_zeroed(layout);
                assert!((0..size).step_by(4093).all(|k| *z.add(k) == 0));
                HugePages.dealloc(z, layout);
            }
        }
    }
}
