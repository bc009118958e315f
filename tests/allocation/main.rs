//! The tests that bound the largest single allocation while bad files are read: a
//! binary of their own, since the counting allocator sees every thread of the process,
//! and each such test runs [`alone`].

#[path = "../all/common/mod.rs"]
mod common;
#[path = "../../tools/largest_allocation.rs"]
mod largest_allocation;

mod bad_input_allocation;
mod las_input;

#[global_allocator]
static ALLOC: largest_allocation::Largest = largest_allocation::Largest;

/// Holds every other test of this binary off while the caller measures allocations.
pub fn alone() -> std::sync::MutexGuard<'static, ()> {
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}
