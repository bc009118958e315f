//! LAZ files of LASzip 1's point-wise compressor: one arithmetic-coded stream of every
//! point, without chunks or a chunk table. Their LASzip VLR gives a chunk size of 0,
//! which the `laz` crate takes for variable-size chunks (and then asks for the table
//! such files lack); read with that field set to one chunk as long as any stream, the
//! sequential decoder reads them point after point.

use std::io::Cursor;
use std::path::Path;

use las::{LazParallelism, Reader, ReaderOptions};

/// The LASzip VLR's user id and record id.
const USER_ID: &[u8] = b"laszip encoded";
const RECORD_ID: u16 = 22204;
/// Where the chunk size lies in the VLR's data: after the compressor, coder,
/// version (major, minor, revision) and options.
const CHUNK_SIZE_AT: usize = 12;
/// A fixed chunk longer than any point-wise stream (`u32::MAX` means variable).
const ONE_CHUNK: u32 = u32::MAX - 1;

/// A reader of the point-wise LAZ file at `path` (whose layout the checks accepted),
/// decoding on one core from the file held in memory (compressed: a few bytes a point).
pub(super) fn reader(path: &Path) -> Result<Reader, String> {
    let mut bytes = std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?;
    let at = chunk_size_offset(&bytes).ok_or("the LASzip VLR cannot be found")?;
    bytes[at..at + 4].copy_from_slice(&ONE_CHUNK.to_le_bytes());
    let options = ReaderOptions::default().with_laz_parallelism(LazParallelism::No);
    Reader::with_options(Cursor::new(bytes), options).map_err(|e| e.to_string())
}

/// The byte offset of the chunk size in the LASzip VLR of the LAS file `bytes`: VLRs
/// follow the header (its size at byte 94, their count at 100), each a 54-byte header
/// (user id at 2, record id at 18, data length at 20) and its data.
fn chunk_size_offset(bytes: &[u8]) -> Option<usize> {
    let u16_at = |at: usize| Some(u16::from_le_bytes(bytes.get(at..at + 2)?.try_into().ok()?));
    let u32_at = |at: usize| Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?));
    let mut at = usize::from(u16_at(94)?);
    for _ in 0..u32_at(100)? {
        let user_id = bytes.get(at + 2..at + 18)?;
        let length = usize::from(u16_at(at + 20)?);
        if user_id.starts_with(USER_ID) && u16_at(at + 18)? == RECORD_ID {
            let field = at + 54 + CHUNK_SIZE_AT;
            return (field + 4 <= at + 54 + length && field + 4 <= bytes.len()).then_some(field);
        }
        at += 54 + length;
    }
    None
}
