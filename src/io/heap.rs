//! What the allocator does with freed memory (glibc on Linux; elsewhere nothing here
//! changes it).
//!
//! By default glibc maps each large list on its own and unmaps it when it is freed, and
//! keeps what a thread frees in that thread's arena, where other threads cannot reuse
//! it. An in-memory build's peak stays low so, but an out-of-core build, whose jobs
//! allocate the same lists again one after another, had the kernel fault in and zero
//! fresh pages for every job. [`share_one_heap`], before any thread starts, puts every
//! allocation in one heap shared by all threads; [`keep_freed_memory`] keeps what is
//! freed there for the next job, until the resident memory passes a limit;
//! [`give_back_freed_memory`] then returns it.
//!
//! Measured on a 20 M-point slice of the generated city (`gen_cloud --points 20000000
//! --size 1265`) built out of core at `--memory 2048` (16 jobs, 2 cores, 2026-11-30):
//! 3.4–3.7 M minor faults and 12.1–12.6 s of system time by default, 0.22–0.28 M and
//! 4.5–4.7 s kept; the whole convert 46.7–48.5 s by default, 41.0–41.3 s kept
//! (alternated, the same file); peak 0.76–0.78 GiB by default, 0.86–1.08 GiB kept.

use std::sync::atomic::{AtomicU64, Ordering};

/// The resident bytes up to which freed memory is kept; 0 when it is not.
static KEEP_UP_TO: AtomicU64 = AtomicU64::new(0);

/// Every thread started from now on allocates from the one heap the process started
/// with, where what any thread frees can serve any other. glibc fixes a thread's
/// arena at its first allocation, so call it before any other thread starts: before
/// rayon's pool is built (the pool's threads allocate as they start). On its own it
/// changes nothing measurable in an in-memory build, whose large lists glibc maps one
/// by one anyway (the Lucy-size cloud: 18.90–19.48 s with one arena against
/// 18.86–18.91 s with glibc's arenas, the same 2.02 GiB peak and 1.36 M faults,
/// alternated; 2 Intel Xeon cores, 2026-12-04).
pub fn share_one_heap() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets the allocator's parameters; the value is in range.
    unsafe {
        libc::mallopt(libc::M_ARENA_MAX, 1);
    }
}

/// From now on, freed memory stays in the heap, for later allocations, until the
/// resident memory passes `limit` bytes (checked at each [`give_back_freed_memory`]).
/// Shared by every thread only where [`share_one_heap`] came before the threads
/// started: a thread that already has an arena of its own keeps it.
pub fn keep_freed_memory(limit: u64) {
    KEEP_UP_TO.store(limit.max(1), Ordering::Relaxed);
    share_one_heap();
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets the allocator's parameters; every value is in range.
    unsafe {
        libc::mallopt(libc::M_MMAP_MAX, 0);
        libc::mallopt(libc::M_TRIM_THRESHOLD, i32::MAX);
    }
}

/// Returns the memory freed so far to the system: always, unless
/// [`keep_freed_memory`] keeps it and the resident memory is within its limit.
pub fn give_back_freed_memory() {
    let limit = KEEP_UP_TO.load(Ordering::Relaxed);
    if limit > 0 && resident_bytes().is_some_and(|r| r <= limit) {
        return;
    }
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only returns free pages of the allocator's arenas.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// The process's resident memory in bytes (Linux: `/proc/self/statm`), if known.
fn resident_bytes() -> Option<u64> {
    #[cfg(target_os = "linux")]
    {
        let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
        let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
        // SAFETY: sysconf reads a constant of the system.
        let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
        Some(pages * u64::try_from(page).ok()?)
    }
    #[cfg(not(target_os = "linux"))]
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_resident_memory_is_read_and_holds_what_was_touched() {
        let Some(before) = resident_bytes() else {
            return; // Not known off Linux.
        };
        let touched = std::hint::black_box(vec![1u8; 64 << 20]);
        let after = resident_bytes().unwrap();
        assert!(after >= 64 << 20, "{before} -> {after} bytes");
        drop(touched);
    }
}
