//! `.spt` files written section by section, their checksum computed on the way
//! ([`spt_file`](super::spt_file) lays the file out): for lists too large to hold
//! twice. [`write_ordered`] writes a tree in id order as its list, gathering each
//! section in slabs, so that the list is never held sorted; the out-of-core assembly
//! streams its parts through [`write_hashed`] too.
//!
//! On the Lucy-size mesh (14 M vertices, 21 M nodes) the sorted copy of the records
//! and shapes was the build's peak: 672 MB of records beside their copy, 504 MB of
//! shapes.

use std::io::{Seek, SeekFrom, Write};
use std::path::Path;

use bytemuck::Pod;
use xxhash_rust::xxh3::Xxh3;

use super::select::BlockIndexBuilder;
use super::spt_file::{CHECKSUM_OFFSET, header_for};
use super::{OrderedSet, gather_into};
use crate::io::atomic::{AtomicWriter, write_atomically_seekable};

/// A writer that hashes what it writes (XXH3-64, as the header's checksum) and tells
/// `progress` how many bytes went by.
pub struct Hashed<'a> {
    w: &'a mut AtomicWriter,
    hash: Xxh3,
    progress: &'a (dyn Fn(u64) + Sync),
}

impl Hashed<'_> {
    pub fn put(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.hash.update(bytes);
        self.w.write_all(bytes)?;
        (self.progress)(bytes.len() as u64);
        Ok(())
    }
}

/// Writes the file at `path` atomically: `header` (its checksum zeroed), then what
/// `body` puts, then the checksum of both in the header's place.
pub fn write_hashed(
    path: &Path,
    header: &[u8],
    progress: &(dyn Fn(u64) + Sync),
    body: impl FnOnce(&mut Hashed) -> std::io::Result<()>,
) -> std::io::Result<()> {
    write_atomically_seekable(path, |w| {
        let mut out = Hashed {
            w,
            hash: Xxh3::new(),
            progress,
        };
        out.put(header)?;
        body(&mut out)?;
        let checksum = out.hash.digest();
        w.seek(SeekFrom::Start(CHECKSUM_OFFSET))?;
        w.write_all(&checksum.to_le_bytes())
    })
}

/// Nodes gathered per slab: 32 MB of records.
const SLAB: usize = 1 << 20;

/// Puts `values` in the order of `ids`, a slab at a time, each slab gathered while the
/// one before it is written; `seen` is shown each slab as it is written. Two slab
/// buffers take turns: a fresh one per slab made the kernel zero 1.2 GB of new pages on
/// the Lucy-size mesh.
fn put_gathered<T: Pod + Send + Sync>(
    out: &mut Hashed,
    values: &[T],
    (ids, slab): (&[u32], usize),
    mut seen: impl FnMut(&[T]) + Send,
) -> std::io::Result<()> {
    let mut slabs = ids.chunks(slab);
    let (mut current, mut spare) = (Vec::new(), Vec::new());
    let Some(first) = slabs.next() else {
        return Ok(());
    };
    gather_into(values, first, &mut current);
    loop {
        let following = slabs.next();
        let (written, ()) = rayon::join(
            || {
                seen(&current);
                out.put(bytemuck::cast_slice(&current))
            },
            || {
                if let Some(ids) = following {
                    gather_into(values, ids, &mut spare);
                }
            },
        );
        written?;
        if following.is_none() {
            return Ok(());
        }
        std::mem::swap(&mut current, &mut spare);
    }
}

/// Writes `set`'s list as an `.spt` file at `path`, atomically: the same bytes as
/// [`write_to`](super::spt_file::write_to) writes for `set.gather()`, without the
/// sorted copy. `progress` hears the bytes written. The prefix search's blocks are
/// made from the records as they go by ([`BlockIndexBuilder`]).
pub fn write_ordered(
    path: &Path,
    set: &OrderedSet,
    progress: &(dyn Fn(u64) + Sync),
) -> std::io::Result<()> {
    let header = header_for(&set.meta, &set.chunks, 0);
    let mut blocks = BlockIndexBuilder::new(&set.chunks);
    write_hashed(path, &header, progress, |out| {
        put_gathered(out, &set.records, (&set.order, SLAB), |slab| {
            blocks.feed(slab)
        })?;
        out.put(bytemuck::cast_slice(&set.parents))?;
        put_gathered(out, &set.shapes, (&set.order, SLAB), |_| {})?;
        if !set.attributes.is_empty() {
            put_gathered(out, &set.attributes, (&set.order, SLAB), |_| {})?;
        }
        out.put(bytemuck::cast_slice(&set.chunks))?;
        let (suffix, heads) = blocks.finish();
        out.put(bytemuck::cast_slice(&suffix))?;
        out.put(bytemuck::cast_slice(&heads))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slabs_put_the_values_in_the_order_of_their_ids() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("gathered");
        let values: Vec<u32> = (100..110).collect();
        let ids = [3u32, 1, 4, 1, 5, 9, 2, 6];
        let header = [0u8; 256];
        write_hashed(&path, &header, &|_| {}, |out| {
            put_gathered(out, &values, (&ids, 3), |_| {})
        })
        .unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let body: &[u32] = bytemuck::cast_slice(&bytes[header.len()..]);
        let expected: Vec<u32> = ids.iter().map(|&i| values[i as usize]).collect();
        assert_eq!(body, expected.as_slice());
        // The checksum is the hash of the header (checksum zeroed) and the body.
        let mut hash = Xxh3::new();
        hash.update(&header);
        hash.update(&bytes[header.len()..]);
        let at = CHECKSUM_OFFSET as usize;
        assert_eq!(bytes[at..at + 8], hash.digest().to_le_bytes());
    }

    #[test]
    fn a_file_past_the_writeback_step_reads_back_whole() {
        // 1.5 steps of values, put in slabs that straddle the step: the file going
        // direct past it, and the checksum's seek back, must not change a byte.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("large");
        let n = (crate::io::syncing_file::WRITEBACK_STEP as usize / 4) * 3 / 2;
        let values: Vec<u32> = (0..n as u32)
            .map(|i| i.wrapping_mul(2_654_435_761))
            .collect();
        let ids: Vec<u32> = (0..n as u32).rev().collect();
        let header = [7u8; 256];
        write_hashed(&path, &header, &|_| {}, |out| {
            put_gathered(out, &values, (&ids, 3 << 20), |_| {})
        })
        .unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let body: &[u32] = bytemuck::cast_slice(&bytes[header.len()..]);
        assert_eq!(body.len(), n);
        assert!(
            body.iter()
                .zip(ids.iter())
                .all(|(&v, &i)| v == values[i as usize])
        );
    }
}
