//! Large buffers on transparent huge pages: a global allocator that asks Linux to back the
//! interior of every allocation of 4 MiB or more with 2 MiB pages (`madvise(MADV_HUGEPAGE)`).
//!
//! Why: a time step streams a dozen point arrays and the node and element arrays of a million
//! points, a few hundred megabytes, through the cores. On 4 KiB pages each core walks the page
//! tables every 4 KiB of every stream, and in a virtual machine each of those walks is a
//! two-level one. Most Linux machines leave huge pages to programs that ask for them (the
//! kernel's `transparent_hugepage/enabled` set to `madvise`). The advice changes no value, only
//! how the memory is mapped, so outputs are the same bits either way.
//!
//! Off by default: on the 2-core development machine (AMD EPYC, KVM) huge pages gained 2-3 % on
//! one thread but cost 3-8 % on two (docs/performance-pages.md), all of it in the two scatters
//! (particle to grid 15.2 against 16.8 ns per particle-step, dry 1M-point column; docs/design.md
//! §5.4). The
//! binaries install the allocator (`#[global_allocator] static A: HugePageAlloc =
//! HugePageAlloc;`), and `--huge-pages on` ([`set_enabled`]`(true)` before the buffers are
//! allocated) turns the advice on, to measure it on other machines. Elsewhere than Linux the
//! allocator is the system's.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, Ordering};

/// Allocations from this size on are advised (smaller ones would waste most of a huge page).
pub const THRESHOLD: usize = 4 << 20;

/// The huge page size advised for (x86-64 and most arm64 kernels).
const HUGE: usize = 2 << 20;

static ENABLED: AtomicBool = AtomicBool::new(false);

/// Turns the advice on or off for the allocations that follow (off by default).
pub fn set_enabled(on: bool) {
    ENABLED.store(on, Ordering::Relaxed);
}

/// Whether allocations are advised now.
pub fn enabled() -> bool {
    ENABLED.load(Ordering::Relaxed)
}

/// The bytes of this process's memory on transparent huge pages now (Linux's
/// `/proc/self/smaps_rollup`), `None` where that cannot be read.
pub fn resident_huge_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/smaps_rollup").ok()?;
    let line = text.lines().find(|l| l.starts_with("AnonHugePages:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// The whole 2 MiB pages inside `[start, start + len)`: (first page's address, length).
fn huge_interior(start: usize, len: usize) -> Option<(usize, usize)> {
    let first = start.checked_add(HUGE - 1)? & !(HUGE - 1);
    let end = start.checked_add(len)? & !(HUGE - 1);
    (end > first).then(|| (first, end - first))
}

/// Advises the whole huge pages inside the `len` bytes at `ptr` (an allocation just made).
fn advise(ptr: *mut u8, len: usize) {
    if ptr.is_null() || len < THRESHOLD || !enabled() {
        return;
    }
    #[cfg(target_os = "linux")]
    if let Some((first, bytes)) = huge_interior(ptr as usize, len) {
        debug_assert!(first >= ptr as usize && first + bytes <= ptr as usize + len);
        // SAFETY: [first, first + bytes) lies inside the allocation at `ptr`, which this
        // process owns and has mapped; MADV_HUGEPAGE changes how its pages are backed, never
        // their contents, and a refusal (an old kernel, huge pages disabled) leaves them as
        // they were, so its result is not needed.
        unsafe {
            libc::madvise(first as *mut libc::c_void, bytes, libc::MADV_HUGEPAGE);
        }
    }
}

/// The system allocator, with large allocations advised onto huge pages (module docs).
#[derive(Debug, Clone, Copy, Default)]
pub struct HugePageAlloc;

// SAFETY: every call is the system allocator's with the same arguments; the advice after it
// only touches the page mapping of memory the system allocator just handed out.
unsafe impl GlobalAlloc for HugePageAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract is passed on unchanged.
        let p = unsafe { System.alloc(layout) };
        advise(p, layout.size());
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as in `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        advise(p, layout.size());
        p
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as in `alloc`.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        advise(p, new_size);
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as in `alloc`.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_interior_is_the_whole_huge_pages_inside() {
        // Aligned at both ends: all of it.
        assert_eq!(
            huge_interior(4 * HUGE, 3 * HUGE),
            Some((4 * HUGE, 3 * HUGE))
        );
        // Unaligned: the pages that start after the start and end before the end.
        assert_eq!(
            huge_interior(4 * HUGE + 16, 3 * HUGE),
            Some((5 * HUGE, 2 * HUGE))
        );
        // Less than one whole page inside.
        assert_eq!(huge_interior(HUGE + 1, HUGE), None);
        assert_eq!(huge_interior(usize::MAX - 10, 100), None);
    }

    #[test]
    fn advised_memory_keeps_its_contents() {
        set_enabled(true);
        // A buffer of twice the threshold, written, advised again (as a realloc does) and read.
        let n = 2 * THRESHOLD / 8;
        let mut v: Vec<u64> = (0..n as u64).collect();
        advise(v.as_mut_ptr().cast(), n * 8);
        assert!(v.iter().enumerate().all(|(i, &x)| x == i as u64));
    }
}
