//! A global allocator that records the largest single allocation, for the checks that
//! no allocation is sized by a header alone (the bad-input test and the fuzzer).
//! Include with `#[path]` in a binary of its own: it sees every thread of the process.
//!
//! ```ignore
//! #[path = "../tools/largest_allocation.rs"]
//! mod largest_allocation;
//! #[global_allocator]
//! static ALLOC: largest_allocation::Largest = largest_allocation::Largest;
//! ```

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Forwards to the system allocator and records sizes.
pub struct Largest;

static LARGEST: AtomicUsize = AtomicUsize::new(0);

/// Forgets the sizes seen so far.
pub fn reset() {
    LARGEST.store(0, Ordering::Relaxed);
}

/// The largest single allocation (or reallocation) since the last [`reset`], in bytes.
pub fn largest() -> usize {
    LARGEST.load(Ordering::Relaxed)
}

// SAFETY: forwards every call to the system allocator; only records sizes.
unsafe impl GlobalAlloc for Largest {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        LARGEST.fetch_max(l.size(), Ordering::Relaxed);
        unsafe { System.alloc(l) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        LARGEST.fetch_max(l.size(), Ordering::Relaxed);
        unsafe { System.alloc_zeroed(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        LARGEST.fetch_max(n, Ordering::Relaxed);
        unsafe { System.realloc(p, l, n) }
    }
}
