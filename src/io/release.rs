//! Giving a file's blocks back to the file system as they are read, for a file that
//! nothing will read again: the join of `spt convert --out-of-core` reads every part
//! once, and freeing what it has read (Linux `fallocate(PUNCH_HOLE)`) keeps the parts
//! and the file it writes from both being whole on the disk at once.
//!
//! Reads mark byte ranges; a range is freed only in whole blocks of [`ALIGN`] that
//! were read entirely, so a block that still holds unread bytes is never freed, in
//! whatever order the ranges come. Read ranges that touch are merged first, so a file
//! read from end to end in pieces of any size is freed in runs of [`RELEASE_BYTES`].

use std::fs::File;
use std::ops::Range;
use std::path::Path;

use super::direct::ALIGN;

/// Read bytes gathered before they are freed: a call each, and at most this much
/// read but not yet freed per file in a run of reads.
pub const RELEASE_BYTES: u64 = 4 << 20;

/// Frees the blocks of one file that have been read.
pub struct Releaser {
    /// Open for writing: the file system frees blocks only through a writable handle.
    file: File,
    /// Ranges read and not yet freed, sorted, disjoint and not touching.
    read: Vec<Range<u64>>,
    /// Bytes freed so far.
    pub freed: u64,
    /// Whether the file system has refused to free blocks (then nothing more is tried).
    refused: bool,
}

impl Releaser {
    pub fn open(path: &Path) -> std::io::Result<Releaser> {
        let file = std::fs::OpenOptions::new().write(true).open(path)?;
        Ok(Releaser {
            file,
            read: Vec::new(),
            freed: 0,
            refused: false,
        })
    }

    /// Marks `range` as read, never to be read again, and frees the whole blocks of its
    /// run of read bytes once they reach [`RELEASE_BYTES`].
    pub fn mark_read(&mut self, range: Range<u64>) {
        if self.refused || range.is_empty() {
            return;
        }
        let k = merge_in(&mut self.read, range);
        let blocks = whole_blocks(&self.read[k]);
        if blocks.end - blocks.start >= RELEASE_BYTES {
            self.free_run(k);
        }
    }

    /// Frees every whole block read so far.
    pub fn flush(&mut self) {
        let mut k = 0;
        while k < self.read.len() && !self.refused {
            k += self.free_run(k);
        }
    }

    /// Frees the whole blocks of read run `k`, leaving its ends that share a block with
    /// unread bytes; returns how many runs stand where it stood (0 to 2).
    fn free_run(&mut self, k: usize) -> usize {
        let run = self.read[k].clone();
        let blocks = whole_blocks(&run);
        if blocks.is_empty() {
            return 1;
        }
        if !punch_hole(&self.file, blocks.clone()) {
            self.refused = true;
            self.read.clear();
            return 0;
        }
        self.freed += blocks.end - blocks.start;
        let ends = [run.start..blocks.start, blocks.end..run.end];
        let kept: Vec<Range<u64>> = ends.into_iter().filter(|r| !r.is_empty()).collect();
        let n = kept.len();
        self.read.splice(k..=k, kept);
        n
    }
}

/// Inserts `range` into `runs` (sorted, disjoint, not touching), merged with every run
/// it overlaps or touches; returns the index of the run that holds it.
fn merge_in(runs: &mut Vec<Range<u64>>, range: Range<u64>) -> usize {
    // The first run that ends at or after the range's start, and the first that starts
    // after its end: those between are merged with it.
    let first = runs.partition_point(|r| r.end < range.start);
    let last = runs.partition_point(|r| r.start <= range.end);
    let merged = match runs[first..last] {
        [] => range,
        ref joined => {
            let start = joined[0].start.min(range.start);
            let end = joined[joined.len() - 1].end.max(range.end);
            start..end
        }
    };
    runs.splice(first..last, [merged]);
    first
}

/// The blocks of [`ALIGN`] bytes that lie wholly within `range`.
fn whole_blocks(range: &Range<u64>) -> Range<u64> {
    let align = ALIGN as u64;
    let start = range.start.next_multiple_of(align);
    let end = range.end / align * align;
    start..end.max(start)
}

/// Frees `blocks` of `file`, its size unchanged; whether the file system did.
#[cfg(target_os = "linux")]
fn punch_hole(file: &File, blocks: Range<u64>) -> bool {
    use std::os::fd::AsRawFd;
    let (Ok(offset), Ok(len)) = (
        i64::try_from(blocks.start),
        i64::try_from(blocks.end - blocks.start),
    ) else {
        return false;
    };
    let mode = libc::FALLOC_FL_PUNCH_HOLE | libc::FALLOC_FL_KEEP_SIZE;
    // SAFETY: a valid descriptor of a file open for writing; the call touches no memory.
    unsafe { libc::fallocate(file.as_raw_fd(), mode, offset, len) == 0 }
}

/// Frees nothing where the file system's call for it is not known.
#[cfg(not(target_os = "linux"))]
fn punch_hole(_file: &File, _blocks: Range<u64>) -> bool {
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_merge_where_they_overlap_or_touch_and_stay_apart_elsewhere() {
        let mut runs = Vec::new();
        for r in [10..20, 30..40, 20..25, 50..60, 24..31, 0..5] {
            merge_in(&mut runs, r);
        }
        assert_eq!(runs, vec![0..5, 10..40, 50..60]);
        merge_in(&mut runs, 5..50);
        assert_eq!(runs, vec![0..60]);
    }

    #[test]
    fn only_blocks_read_whole_are_freed() {
        let a = ALIGN as u64;
        assert_eq!(whole_blocks(&(1..a)), a..a);
        assert_eq!(whole_blocks(&(0..a)), 0..a);
        assert_eq!(whole_blocks(&(a - 1..3 * a + 1)), a..3 * a);
    }

    #[test]
    fn a_file_read_in_any_order_is_freed_whole_and_reads_back_as_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("part");
        let bytes: Vec<u8> = (0..3 * RELEASE_BYTES as usize)
            .map(|i| (i % 251) as u8)
            .collect();
        std::fs::write(&path, &bytes).unwrap();
        let mut releaser = Releaser::open(&path).unwrap();
        // Pieces of odd sizes, the second half before the first.
        let half = bytes.len() as u64 / 2;
        let cuts: Vec<u64> = (0..)
            .map(|i| i * 1_000_003)
            .take_while(|&c| c < half)
            .collect();
        let pieces = |lo: u64, hi: u64| {
            let mut p: Vec<Range<u64>> = cuts.windows(2).map(|w| lo + w[0]..lo + w[1]).collect();
            p.push(lo + cuts[cuts.len() - 1]..hi);
            p
        };
        for r in pieces(half, bytes.len() as u64)
            .into_iter()
            .chain(pieces(0, half))
        {
            // Unread bytes still read as written.
            let now = std::fs::read(&path).unwrap();
            assert_eq!(
                now[r.start as usize..r.end as usize],
                bytes[r.start as usize..r.end as usize]
            );
            releaser.mark_read(r);
        }
        releaser.flush();
        if releaser.refused {
            eprintln!("this file system frees no blocks: nothing to check");
            return;
        }
        assert_eq!(releaser.freed, bytes.len() as u64);
        assert_eq!(std::fs::metadata(&path).unwrap().len(), bytes.len() as u64);
        let now = std::fs::read(&path).unwrap();
        assert!(now.iter().all(|&b| b == 0), "freed blocks read as zeros");
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            let held = std::fs::metadata(&path).unwrap().blocks() * 512;
            assert!(
                held < 2 * ALIGN as u64,
                "{held} bytes still held on the disk"
            );
        }
    }
}
