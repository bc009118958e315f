//! The join's reads of the part files, ahead of its writes. A reader thread fills slabs
//! with the next pieces' values while the joining thread fixes, hashes and writes the
//! slab before: both wait on the device (the 200 M-point tile's 19 GB of parts are read
//! once and written once), and one thread doing each in turn waited on each in turn.
//! The bytes written and their order are the same either way.

use std::path::Path;
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};

use bytemuck::Pod;

use super::job::Part;
use crate::io::direct::{DirectFile, ReadBuffer};
use crate::io::release::Releaser;
use crate::tree::spt_write::Hashed;

/// Bytes per slab, at most.
const SLAB_BYTES: usize = 8 << 20;
/// Slabs in flight: the one being written, and the ones read ahead of it.
const SLABS: usize = 3;
/// Bytes per read of a part file, at most. The parts are read past the page cache
/// ([`crate::io::direct`]), whose copies took a core's whole time in the 200 M-point
/// tile's join; a read takes the spans that follow it in the same file along (most
/// pieces of the join's layout are a part's consecutive chunks, of 40 kB in the median).
const READ_BYTES: usize = 4 << 20;

/// The buffer that part files' reads go through.
pub fn read_buffer() -> ReadBuffer {
    ReadBuffer::new(READ_BYTES)
}

/// What becomes of a part file's bytes once the join has read them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AfterRead {
    /// Kept: `spt jobs join` may be run again over the same parts.
    Keep,
    /// Freed as they are read ([`Releaser`]): `spt convert`, whose parts nothing reads
    /// again, then holds its parts and its file on the disk about once, not twice.
    Free,
}

/// An open part file and its path, which its read errors name.
pub struct PartFile<'a> {
    file: DirectFile,
    path: &'a Path,
    /// Where the last read ended.
    position: u64,
    /// Frees what has been read ([`AfterRead::Free`]).
    releaser: Option<Releaser>,
}

impl<'a> PartFile<'a> {
    pub fn open(part: &'a Part) -> std::io::Result<PartFile<'a>> {
        PartFile::at(&part.path)
    }

    /// Opens `part` for the join's reads, its bytes freed or kept once read.
    pub fn open_for_join(part: &'a Part, after: AfterRead) -> std::io::Result<PartFile<'a>> {
        let mut file = PartFile::at(&part.path)?;
        if after == AfterRead::Free {
            // A part that cannot be opened for writing is read all the same, and kept.
            file.releaser = Releaser::open(&part.path).ok();
        }
        Ok(file)
    }

    fn at(path: &'a Path) -> std::io::Result<PartFile<'a>> {
        let file = DirectFile::open(path).map_err(|e| cannot_read(path, e))?;
        Ok(PartFile {
            file,
            path,
            position: 0,
            releaser: None,
        })
    }

    /// Fills `into` from byte `at` on, or from where the last read ended when `at` is
    /// `None`, through `buffer` ([`read_buffer`]), reading up to `ahead` bytes past it
    /// for the reads that follow.
    pub fn read_at(
        &mut self,
        (at, ahead): (Option<u64>, u64),
        into: &mut [u8],
        buffer: &mut ReadBuffer,
    ) -> std::io::Result<()> {
        let at = at.unwrap_or(self.position);
        let read = self.file.read_exact_at((at, ahead), into, buffer);
        read.map_err(|e| cannot_read(self.path, e))?;
        self.position = at + into.len() as u64;
        if let Some(releaser) = &mut self.releaser {
            releaser.mark_read(at..self.position);
        }
        Ok(())
    }
}

impl Drop for PartFile<'_> {
    /// Frees the last of what was read, when the part's bytes go once read.
    fn drop(&mut self) {
        if let Some(releaser) = &mut self.releaser {
            releaser.flush();
        }
    }
}

/// `e` of reading `path`, naming it.
fn cannot_read(path: &Path, e: std::io::Error) -> std::io::Error {
    std::io::Error::new(e.kind(), format!("cannot read {}: {e}", path.display()))
}

/// `count` values of a part file's section, from byte `at` of part `part`.
#[derive(Debug, Clone, Copy)]
pub struct Span {
    pub part: usize,
    pub at: u64,
    pub count: usize,
}

/// Values read ahead: the first `used` of `values`, runs of consecutive spans, each as
/// (span index, index in the span of its first value, length).
struct Slab<T> {
    values: Vec<T>,
    used: usize,
    runs: Vec<(usize, usize, usize)>,
}

/// Writes the values of `spans` (of `files`), in order, to `out`: each run of a span
/// is first changed by `fix`, given the span's index, the index in the span of the
/// run's first value, and the run. The reads run on a thread of their own,
/// [`SLABS`] − 1 slabs ahead.
pub fn stream<T: Pod + Send>(
    files: &mut [PartFile],
    spans: &[Span],
    out: &mut Hashed,
    fix: impl FnMut(usize, usize, &mut [T]),
) -> std::io::Result<()> {
    // A slab is allocated whole: a small section's slabs together hold it about once.
    let total = spans.iter().map(|s| s.count).sum::<usize>();
    let per_slab = (SLAB_BYTES / size_of::<T>())
        .min(total.div_ceil(SLABS))
        .max(1);
    stream_slabs(files, spans, per_slab, (fix, |bytes| out.put(bytes)))
}

/// [`stream`] in slabs of `per_slab` values, each written by `put`.
fn stream_slabs<T: Pod + Send>(
    files: &mut [PartFile],
    spans: &[Span],
    per_slab: usize,
    (mut fix, mut put): (
        impl FnMut(usize, usize, &mut [T]),
        impl FnMut(&[u8]) -> std::io::Result<()>,
    ),
) -> std::io::Result<()> {
    let (full_tx, full_rx) = sync_channel(SLABS);
    let (free_tx, free_rx) = sync_channel(SLABS);
    for _ in 0..SLABS {
        let slab = Slab {
            values: Vec::new(),
            used: 0,
            runs: Vec::new(),
        };
        free_tx.send(slab).expect("the channel holds every slab");
    }
    std::thread::scope(move |scope| {
        scope.spawn(move || read_slabs(files, spans, per_slab, (free_rx, full_tx)));
        // Returning early drops both channels' other ends, which stops the reader.
        for slab in full_rx {
            let mut slab: Slab<T> = slab?;
            let mut first = 0;
            for &(span, start, len) in &slab.runs {
                fix(span, start, &mut slab.values[first..first + len]);
                first += len;
            }
            put(bytemuck::cast_slice(&slab.values[..slab.used]))?;
            // A reader that has read every span takes no more slabs; those it sent
            // are still to be written.
            let _ = free_tx.send(slab);
        }
        Ok(())
    })
}

/// The reader of [`stream`]: fills each free slab with up to `per_slab` values of the
/// spans in order and sends it on, or the first read error.
fn read_slabs<T: Pod>(
    files: &mut [PartFile],
    spans: &[Span],
    per_slab: usize,
    (free, full): (Receiver<Slab<T>>, SyncSender<std::io::Result<Slab<T>>>),
) {
    let take = || {
        let mut slab = free.recv().ok()?;
        slab.values.resize(per_slab, T::zeroed());
        slab.used = 0;
        slab.runs.clear();
        Some(slab)
    };
    let Some(mut slab) = take() else {
        return;
    };
    let mut buffer = read_buffer();
    let following = following_bytes::<T>(spans);
    for (k, span) in spans.iter().enumerate() {
        let mut done = 0;
        while done < span.count {
            if slab.used == per_slab {
                let sent = full.send(Ok(slab));
                let Some(next) = sent.ok().and_then(|()| take()) else {
                    return;
                };
                slab = next;
            }
            let n = (per_slab - slab.used).min(span.count - done);
            let into = &mut slab.values[slab.used..slab.used + n];
            let from = (done == 0).then_some(span.at);
            let ahead = ((span.count - done - n) * size_of::<T>()) as u64 + following[k];
            let into = bytemuck::cast_slice_mut(into);
            if let Err(e) = files[span.part].read_at((from, ahead), into, &mut buffer) {
                let _ = full.send(Err(e));
                return;
            }
            slab.runs.push((k, done, n));
            slab.used += n;
            done += n;
        }
    }
    if slab.used > 0 {
        let _ = full.send(Ok(slab));
    }
}

/// For each span, the bytes of the spans after it that continue it in its file: the
/// run of spans each of which starts where the one before ends.
fn following_bytes<T>(spans: &[Span]) -> Vec<u64> {
    let bytes = |s: &Span| (s.count * size_of::<T>()) as u64;
    let mut following = vec![0u64; spans.len()];
    for k in (1..spans.len()).rev() {
        let (before, span) = (&spans[k - 1], &spans[k]);
        if span.part == before.part && span.at == before.at + bytes(before) {
            following[k - 1] = bytes(span) + following[k];
        }
    }
    following
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_come_out_in_order_fixed_run_by_run_through_small_slabs() {
        // Three part files of u32 values 1000 f + i; spans across them, some empty,
        // some longer than a slab, some reading on where the last one of their file
        // ended.
        let dir = tempfile::tempdir().unwrap();
        let paths: Vec<_> = (0..3u32)
            .map(|f| {
                let path = dir.path().join(format!("part{f}"));
                let values: Vec<u32> = (0..40).map(|i| 1000 * f + i).collect();
                std::fs::write(&path, bytemuck::cast_slice(&values)).unwrap();
                path
            })
            .collect();
        let span = |part: usize, first: u64, count: usize| Span {
            part,
            at: 4 * first,
            count,
        };
        let spans = [
            span(1, 3, 7),
            span(0, 0, 0),
            span(2, 10, 13),
            span(0, 5, 2),
            span(1, 10, 30),
            span(2, 0, 1),
        ];
        for per_slab in [1, 4, 5, 64] {
            let mut files: Vec<PartFile> = paths.iter().map(|p| PartFile::at(p).unwrap()).collect();
            let mut written: Vec<u8> = Vec::new();
            // Each value gets its span's index and its index in the span added.
            let fix = |k: usize, first: usize, run: &mut [u32]| {
                for (i, v) in run.iter_mut().enumerate() {
                    *v += 100_000 * k as u32 + 10_000 * (first + i) as u32;
                }
            };
            let put = |bytes: &[u8]| {
                written.extend_from_slice(bytes);
                Ok(())
            };
            stream_slabs(&mut files, &spans, per_slab, (fix, put)).unwrap();
            let expected: Vec<u32> = (spans.iter().enumerate())
                .flat_map(|(k, s)| {
                    let start = (s.at / 4) as u32;
                    (0..s.count as u32).map(move |i| {
                        1000 * s.part as u32 + start + i + 100_000 * k as u32 + 10_000 * i
                    })
                })
                .collect();
            assert_eq!(
                bytemuck::cast_slice::<u8, u32>(&written),
                expected,
                "{per_slab}"
            );
        }
    }

    #[test]
    fn a_span_past_its_file_s_end_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("job7.part");
        std::fs::write(&path, [0u8; 40]).unwrap();
        let mut files = vec![PartFile::at(&path).unwrap()];
        let spans = [Span {
            part: 0,
            at: 8,
            count: 9,
        }];
        let put = |_: &[u8]| Ok(());
        let failed = stream_slabs::<u32>(&mut files, &spans, 4, (|_, _, _| {}, put)).unwrap_err();
        assert!(failed.to_string().contains("job7.part"), "{failed}");
    }
}
