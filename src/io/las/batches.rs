//! A LAS or LAZ file read a batch at a time, for builders that never hold all of a
//! file's points ([`crate::tree::out_of_core`]): the same checks as [`super::read_las`]
//! before the decoder sees the file, then batches of positions (f64, the file's
//! coordinates), 16-bit colours and attributes.

use std::path::{Path, PathBuf};

use las::{PointData, PointDataBuilder, Reader};

use super::{BATCH, LAZ_BATCH, LasError, fill_contained, open_checked};
use crate::io::PointAttributes;
use crate::io::format::PointBatch;

/// Bytes the reader's buffer reads from a record after a seek: std's `BufReader`
/// capacity, 8 KiB ([`super::open_checked`]).
#[cfg(target_os = "linux")]
const BUFFERED_READ: i64 = 8 << 10;

/// A LAS or LAZ file open for reading in batches.
pub struct LasBatches {
    path: PathBuf,
    reader: Reader,
    data: PointData,
    per_batch: u64,
    read: u64,
    /// The row the batches end before: the header's count, or a range's end
    /// ([`LasBatches::seek_rows`]).
    until: u64,
    expected: u64,
}

impl LasBatches {
    pub fn open(path: &Path) -> Result<LasBatches, LasError> {
        let (reader, _) = open_checked(path)?;
        let header = reader.header();
        let format = header.point_format();
        Ok(LasBatches {
            path: path.to_owned(),
            data: PointDataBuilder::new().for_header(header).build(),
            per_batch: if format.is_compressed {
                LAZ_BATCH
            } else {
                BATCH
            },
            read: 0,
            until: header.number_of_points(),
            expected: header.number_of_points(),
            reader,
        })
    }

    /// Points the header announces.
    pub fn point_count(&self) -> u64 {
        self.expected
    }

    /// Whether the file is LAZ, whose seeks decode from a chunk's start.
    pub fn compressed(&self) -> bool {
        self.reader.header().point_format().is_compressed
    }

    /// Calls `f` on the positions of rows 0, `stride` (at least 1), 2 `stride`, … below
    /// the header's count, each row read alone where its record lies: for a LAS file
    /// (a LAZ file's are read faster in a pass).
    pub fn strided(&mut self, stride: u64, f: &mut dyn FnMut([f64; 3])) -> Result<(), LasError> {
        let stride = stride.max(1);
        let rows = (0..self.expected).step_by(stride as usize);
        self.ask_ahead(rows.clone(), stride);
        for row in rows {
            let failed = |e: String| damaged(&self.path, self.expected, row, e);
            self.reader.seek(row).map_err(|e| failed(e.to_string()))?;
            if fill_contained(&mut self.reader, 1, &mut self.data).map_err(failed)? == 0 {
                return Err(failed("no record".into()));
            }
            let d = &self.data;
            if let (Some(x), Some(y), Some(z)) = (d.x().next(), d.y().next(), d.z().next()) {
                f([x, y, z]);
            }
        }
        Ok(())
    }

    /// Asks the kernel to read the records of `rows`, `stride` apart, into the page
    /// cache, all at once, so that reading them one by one finds them there. From a
    /// cold cache each read otherwise waits out its own trip to the disk: the 200
    /// M-point tile's 16,384 sampled records took 1.3–1.4 s so, 0.5 s asked ahead
    /// (warm: 0.07–0.14 s, 0.11–0.16 s; 2026-11-30). Rows closer than a buffer's read
    /// are read nearly in sequence, which the kernel reads ahead of by itself: not
    /// asked. Only a hint, where the system takes one (Linux): nothing is read here,
    /// and a record it misses is read as before.
    fn ask_ahead(&self, rows: impl Iterator<Item = u64>, stride: u64) {
        #[cfg(target_os = "linux")]
        {
            use std::os::fd::AsRawFd;
            let Ok(raw) = self.reader.header().clone().into_raw() else {
                return;
            };
            let (data, record) = (
                u64::from(raw.offset_to_point_data),
                u64::from(raw.point_data_record_length),
            );
            let len = BUFFERED_READ.max(i64::from(raw.point_data_record_length));
            if stride.saturating_mul(record) < len as u64 {
                return;
            }
            let Ok(file) = std::fs::File::open(&self.path) else {
                return;
            };
            for row in rows {
                let at = row.saturating_mul(record).saturating_add(data);
                let Ok(at) = i64::try_from(at) else {
                    return;
                };
                // SAFETY: a hint on an open descriptor; it reads no memory of ours.
                unsafe {
                    libc::posix_fadvise(file.as_raw_fd(), at, len, libc::POSIX_FADV_WILLNEED)
                };
            }
        }
        #[cfg(not(target_os = "linux"))]
        let _ = (rows, stride);
    }

    /// From now on, reads the rows of `rows` (their part below the header's count),
    /// cut into batches as a pass from row 0 would cut them where `rows.start` is a
    /// whole number of batches.
    pub fn seek_rows(&mut self, rows: std::ops::Range<u64>) -> Result<(), LasError> {
        let start = rows.start.min(self.expected);
        if start < self.expected {
            (self.reader.seek(start))
                .map_err(|e| damaged(&self.path, self.expected, start, e.to_string()))?;
        }
        self.read = start;
        self.until = rows.end.clamp(start, self.expected);
        Ok(())
    }

    /// Reads the next batch into `out` (cleared first); false once every point is read.
    pub fn next_batch(&mut self, out: &mut PointBatch) -> Result<bool, LasError> {
        out.clear();
        if self.read >= self.until {
            return Ok(false);
        }
        let want = self.per_batch.min(self.until - self.read);
        let n = fill_contained(&mut self.reader, want, &mut self.data)
            .map_err(|e| damaged(&self.path, self.expected, self.read, e))?;
        if n == 0 {
            return Ok(false);
        }
        self.read += n;
        let d = &self.data;
        out.xyz
            .extend(d.x().zip(d.y()).zip(d.z()).map(|((x, y), z)| [x, y, z]));
        if let Some(colors) = d.rgb() {
            out.rgb.extend(colors.map(|(r, g, b)| [r, g, b]));
        }
        out.attributes.extend(
            d.intensity()
                .zip(d.classification())
                .zip(d.return_number().zip(d.number_of_returns()))
                .map(|((i, c), (r, n))| PointAttributes::new(i, c, r, n)),
        );
        Ok(true)
    }
}

/// The error of the file at `path`, whose header announces `expected` points, when
/// decoding failed at `row` (`e`).
fn damaged(path: &Path, expected: u64, row: u64, e: String) -> LasError {
    LasError {
        path: path.to_owned(),
        message: format!(
            "the header announces {expected} points; decoding failed after {row} ({e}): the \
             file is damaged or truncated"
        ),
    }
}
