//! Bad files are refused with an error naming the file and the problem, and no
//! allocation grows with a header count that the file cannot hold. This test is alone
//! in its binary: the allocation counter sees every thread of the process.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use common::bad_files::fixtures;
use spt::io::ply::read_ply;

/// Counts the largest single allocation made while a check runs.
struct Largest;
static LARGEST: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator; only records sizes.
unsafe impl GlobalAlloc for Largest {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        LARGEST.fetch_max(l.size(), Ordering::Relaxed);
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        LARGEST.fetch_max(n, Ordering::Relaxed);
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static ALLOC: Largest = Largest;

#[test]
fn bad_files_are_refused_with_a_clear_error_and_no_large_allocation() {
    let dir = common::temp_dir();
    for f in fixtures(dir.path()) {
        let path = dir.path().join(f.name);
        std::fs::write(&path, &f.bytes).unwrap();
        LARGEST.store(0, Ordering::Relaxed);
        let err = read_ply(&path).expect_err(f.name).to_string();
        let largest = LARGEST.load(Ordering::Relaxed);
        assert!(
            err.contains(f.name),
            "{}: error does not name the file: {err}",
            f.name
        );
        for word in f.expect {
            assert!(
                err.contains(word),
                "{}: expected '{word}' in: {err}",
                f.name
            );
        }
        // The test harness itself allocates a few KiB; a header count would take GBs.
        assert!(
            largest < 1 << 20,
            "{}: an allocation of {largest} bytes",
            f.name
        );
    }
}
