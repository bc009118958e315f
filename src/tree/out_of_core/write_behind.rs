//! Many files filled by one thread and written by another: the filling thread appends
//! records to each file's buffer, and hands a full buffer over whole (no copy) to a
//! writer thread, which writes it and hands it back empty. The kernel's copy of every
//! byte into its page cache then runs beside the filling instead of inside it: in the
//! spill of the 200 M-point tile that copy was a fifth of the plan's samples.
//!
//! Each file's bytes reach it in the order they were appended (one writer, one queue).
//! The first error of a write is kept and returned once all is done; later buffers are
//! dropped unwritten.

use std::fs::File;
use std::io::Write;
use std::sync::mpsc::{Receiver, SyncSender, channel, sync_channel};

/// Full buffers waiting for the writer, at most.
const QUEUED: usize = 8;

/// The filling side: one buffer per file.
pub struct Writers {
    buffers: Vec<Vec<u8>>,
    capacity: usize,
    full: SyncSender<(usize, Vec<u8>)>,
    empty: Receiver<Vec<u8>>,
}

impl Writers {
    /// Appends `bytes` to file `k`, handing its buffer over first when they would not
    /// fit.
    pub fn write(&mut self, k: usize, bytes: &[u8]) {
        if self.buffers[k].len() + bytes.len() > self.capacity {
            self.hand_over(k);
        }
        self.buffers[k].extend_from_slice(bytes);
    }

    /// Hands file `k`'s buffer to the writer (if it holds anything), taking an empty
    /// one back when one is there.
    fn hand_over(&mut self, k: usize) {
        if self.buffers[k].is_empty() {
            return;
        }
        let fresh = self
            .empty
            .try_recv()
            .unwrap_or_else(|_| Vec::with_capacity(self.capacity));
        let full = std::mem::replace(&mut self.buffers[k], fresh);
        // Refused only when the writer is gone, which it is not before `fill` returns.
        let _ = self.full.send((k, full));
    }
}

/// Runs `fill` with [`Writers`] over `files` (buffers of `capacity` bytes each) while a
/// thread of its own writes them; returns what `fill` returned once every byte is
/// written, or the first write's error.
pub fn write_behind<T>(
    mut files: Vec<File>,
    capacity: usize,
    fill: impl FnOnce(&mut Writers) -> T,
) -> std::io::Result<T> {
    let count = files.len();
    let (full, queued) = sync_channel::<(usize, Vec<u8>)>(QUEUED);
    let (back, empty) = channel::<Vec<u8>>();
    std::thread::scope(|scope| {
        let writer = scope.spawn(move || {
            let mut failed: Option<std::io::Error> = None;
            for (k, mut buffer) in queued {
                if failed.is_none() {
                    failed = files[k].write_all(&buffer).err();
                }
                buffer.clear();
                let _ = back.send(buffer);
            }
            failed.map_or(Ok(()), Err)
        });
        let mut writers = Writers {
            buffers: (0..count).map(|_| Vec::with_capacity(capacity)).collect(),
            capacity,
            full,
            empty,
        };
        let value = fill(&mut writers);
        for k in 0..writers.buffers.len() {
            writers.hand_over(k);
        }
        drop(writers);
        let written = writer
            .join()
            .unwrap_or_else(|p| std::panic::resume_unwind(p));
        written.map(|()| value)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_file_gets_its_bytes_in_order() {
        // Buffers of 10 bytes, records of 3 to 7: many hand-overs, interleaved.
        let dir = tempfile::tempdir().unwrap();
        let paths: Vec<_> = (0..3).map(|k| dir.path().join(format!("f{k}"))).collect();
        let files = paths.iter().map(|p| File::create(p).unwrap()).collect();
        let mut expected = vec![Vec::new(); 3];
        let value = write_behind(files, 10, |w| {
            for n in 0..200u32 {
                let (k, record) = ((n * 7 % 3) as usize, vec![n as u8; 3 + (n % 5) as usize]);
                w.write(k, &record);
                expected[k].extend_from_slice(&record);
            }
            "filled"
        })
        .unwrap();
        assert_eq!(value, "filled");
        for (p, bytes) in paths.iter().zip(&expected) {
            assert_eq!(&std::fs::read(p).unwrap(), bytes, "{}", p.display());
        }
    }

    #[test]
    fn a_failed_write_is_returned() {
        // A file opened for reading refuses writes.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("read_only");
        std::fs::write(&path, b"").unwrap();
        let files = vec![File::open(&path).unwrap()];
        let result = write_behind(files, 4, |w| (0..10).for_each(|_| w.write(0, b"abc")));
        assert!(result.is_err());
    }
}
