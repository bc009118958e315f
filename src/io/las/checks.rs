//! What the LAS and LAZ decoders would trust without checking, checked against the file
//! first: the header's point count and record length must fit in the file
//! (uncompressed); a LAZ chunk table may hold no more chunks than its compressed bytes,
//! no more bytes than the file, and no fewer points than the header announces; a LASzip
//! VLR must describe the header's records in chunks of at most [`MAX_CHUNK_BYTES`]; a
//! layered chunk's layers must fit in it; an extended VLR may hold no more bytes than
//! the file. Each failure is a sentence for the file's error.

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};

/// `n` bytes of `file` from `at`, or `None` past its end.
fn bytes_at(file: &mut File, at: u64, n: usize) -> Option<Vec<u8>> {
    let mut buf = vec![0; n];
    file.seek(SeekFrom::Start(at)).ok()?;
    file.read_exact(&mut buf).ok()?;
    Some(buf)
}

/// Checks that the header's sizes fit in the file (see the module doc).
pub(super) fn check_layout(file: &mut File, len: u64) -> Result<(), String> {
    let raw = las::raw::Header::read_from(BufReader::new(&mut *file))
        .map_err(|e| format!("not a readable LAS header ({len} bytes): {e}"))?;
    for (axis, s) in
        ["x", "y", "z"]
            .iter()
            .zip([raw.x_scale_factor, raw.y_scale_factor, raw.z_scale_factor])
    {
        if s == 0.0 || !s.is_finite() {
            return Err(format!(
                "the {axis} scale factor is {s}: coordinates cannot be decoded"
            ));
        }
    }
    let data = u64::from(raw.offset_to_point_data);
    if data > len {
        return Err(format!(
            "the point data would start at byte {data}, past the end ({len} bytes)"
        ));
    }
    // LAS 1.4 keeps a legacy 32-bit count beside its 64-bit one: both must fit.
    let count = raw
        .large_file
        .map_or(0, |l| l.number_of_point_records)
        .max(u64::from(raw.number_of_point_records));
    check_vlrs(file, &raw, data)?;
    let compressed = raw.point_data_record_format & 0x80 != 0;
    if !compressed {
        let record = u64::from(raw.point_data_record_length);
        let room = (len - data) / record.max(1);
        if count > room {
            return Err(format!(
                "the header says {count} points of {record} bytes, but the file holds at most {room} (truncated?)"
            ));
        }
    }
    if let Some(evlr) = raw.evlr {
        check_evlr(file, len, evlr.start_of_first_evlr)?;
    }
    Ok(())
}

/// The VLRs the header counts must each start before the point data: the decoder
/// reads them one after the other from the end of the header, and one counted but
/// missing would be read from the points (or past the end of the file).
fn check_vlrs(file: &mut File, raw: &las::raw::Header, data: u64) -> Result<(), String> {
    let declared = raw.number_of_variable_length_records;
    let mut at = u64::from(raw.header_size);
    for k in 0..declared {
        // A VLR's 54-byte header gives the u16 length of its data at byte 20.
        let length = (at + 54 <= data)
            .then(|| bytes_at(file, at + 20, 2))
            .flatten()
            .map(|b| u64::from(u16::from_le_bytes([b[0], b[1]])));
        let Some(length) = length else {
            return Err(format!(
                "the header counts {declared} VLR(s), but only {k} lie before the point data \
                 (byte {data})"
            ));
        };
        at += 54 + length;
    }
    Ok(())
}

/// A LAZ chunk table (its offset is the first 8 bytes of the point data) may list no
/// more chunks than there are compressed bytes before it.
fn check_chunk_table(file: &mut File, len: u64, data: u64) -> Result<(), String> {
    let mut word = |at: u64, n: usize| bytes_at(file, at, n);
    let table = word(data, 8)
        .map(|b| i64::from_le_bytes(b.try_into().unwrap_or_default()))
        .ok_or("the LAZ point data is cut short before its chunk table offset")?;
    if table == -1 {
        // Written by a streaming encoder: the table's offset is at the end of the file.
        return Ok(());
    }
    if table <= data as i64 || table as u64 + 8 > len {
        return Err(format!(
            "the LAZ chunk table offset {table} lies outside the file ({len} bytes)"
        ));
    }
    let table = table as u64;
    let chunks = word(table + 4, 4)
        .map(|b| u32::from_le_bytes(b.try_into().unwrap_or_default()))
        .unwrap_or(0);
    if u64::from(chunks) > table - data {
        return Err(format!(
            "the LAZ chunk table lists {chunks} chunks in {} compressed bytes",
            table - data
        ));
    }
    Ok(())
}

/// An extended VLR's header (60 bytes) and its data must lie within the file.
fn check_evlr(file: &mut File, len: u64, start: u64) -> Result<(), String> {
    let header_end = start.checked_add(60).filter(|e| *e <= len).ok_or_else(|| {
        format!("the extended VLRs would start at byte {start}, past the end ({len} bytes)")
    })?;
    let length = bytes_at(file, start + 20, 8)
        .map(|b| u64::from_le_bytes(b.try_into().unwrap_or_default()))
        .unwrap_or(u64::MAX);
    if length > len - header_end {
        return Err(format!(
            "an extended VLR says it holds {length} bytes; the file has {len}"
        ));
    }
    Ok(())
}

/// The largest decompressed LAZ chunk accepted: LASzip writes chunks of 50,000 points
/// (1.7 MB at 34 bytes, 3.4 MB at the largest standard record), and the decoder
/// allocates a whole chunk at once, however few points the file holds.
pub const MAX_CHUNK_BYTES: u64 = 8 << 20;

/// How a LAZ file's points are compressed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum LazLayout {
    /// In chunks listed by a chunk table (LASzip 2 and later): decoded in parallel.
    Chunked,
    /// One stream of points without chunks or table (LASzip 1's point-wise
    /// compressor): decoded in order, on one core.
    PointWise,
}

/// The LASzip VLR's code of the point-wise compressor.
const POINT_WISE: u8 = 1;

/// What the LAZ decoder would trust without checking: its VLR's record size must be the
/// header's, its chunks no larger than [`MAX_CHUNK_BYTES`], its chunk table's byte
/// counts must add up to no more than the compressed data, and its chunks must hold at
/// least the points the header announces. A point-wise file has no chunks: its points
/// are decoded one batch at a time, each bounded by the file's size.
pub(super) fn check_laz(file: &mut File, header: &las::Header) -> Result<LazLayout, String> {
    let vlr = header
        .all_vlrs()
        .find(|v| v.user_id == laz::LazVlr::USER_ID && v.record_id == laz::LazVlr::RECORD_ID)
        .ok_or("compressed, but without the LASzip VLR that says how")?;
    let laz_vlr =
        laz::LazVlr::from_buffer(&vlr.data).map_err(|e| format!("the LASzip VLR: {e}"))?;
    item_sizes(&laz_vlr)?;
    let record = u64::from(header.point_format().len());
    if laz_vlr.items_size() != record || record == 0 {
        return Err(format!(
            "the LASzip VLR describes {}-byte points, the header {record}-byte ones",
            laz_vlr.items_size()
        ));
    }
    let data = header_offset_to_points(file)?;
    let len = file.metadata().map_err(|e| e.to_string())?.len();
    // The VLR's first field is its compressor (`from_buffer` refused unknown ones).
    if vlr.data[..2] == [POINT_WISE, 0] {
        // No chunk table: the decoder reads the points from the point data on as one
        // chunk, whose layers (LAS 1.4 items) must fit in the file.
        if header.number_of_points() > 0 {
            check_layers(file, &laz_vlr, [(data, len.saturating_sub(data))], record)?;
        }
        return Ok(LazLayout::PointWise);
    }
    let chunk = u64::from(laz_vlr.chunk_size());
    if !laz_vlr.uses_variable_size_chunks() && chunk * record > MAX_CHUNK_BYTES {
        return Err(format!(
            "LAZ chunks of {chunk} points are larger than any writer makes"
        ));
    }
    check_chunk_table(file, len, data)?;
    file.seek(SeekFrom::Start(data))
        .map_err(|e| e.to_string())?;
    let table = laz::laszip::ChunkTable::read_from(BufReader::new(&mut *file), &laz_vlr)
        .map_err(|e| format!("the LAZ chunk table cannot be read: {e}"))?;
    let room = len.saturating_sub(data);
    let (mut bytes, mut largest, mut points) = (0u64, 0u64, 0u64);
    for entry in &table {
        bytes = bytes.saturating_add(entry.byte_count);
        largest = largest.max(entry.point_count);
        points = points.saturating_add(entry.point_count);
    }
    // Fixed-size chunks: every chunk holds chunk_size points but the last, which holds
    // at most that.
    if !laz_vlr.uses_variable_size_chunks() {
        points = (table.as_ref().len() as u64).saturating_mul(chunk);
    }
    // The chunks follow the 8-byte chunk table offset, one after the other.
    let chunks = table.as_ref().iter().scan(data + 8, |at, entry| {
        let start = *at;
        *at = at.saturating_add(entry.byte_count);
        Some((start, entry.byte_count))
    });
    check_layers(file, &laz_vlr, chunks, record)?;
    let announced = header.number_of_points();
    if announced > points {
        return Err(format!(
            "the header says {announced} points, but the LAZ chunks hold at most {points}: \
             the file is damaged or truncated"
        ));
    }
    if bytes > room || largest.saturating_mul(record) > MAX_CHUNK_BYTES {
        return Err(format!(
            "the LAZ chunk table lists {bytes} compressed bytes (the file has {room} after the \
             header) or a chunk of {largest} points: it is damaged"
        ));
    }
    Ok(LazLayout::Chunked)
}

/// Each item of a LASzip VLR must state its type's own size (LAS 1.4 and LASzip: the
/// 1.0–1.3 point 20 bytes, GPS time 8, RGB 6, wave packet 29; the 1.4 point 30, RGB 6,
/// RGB and NIR 8, wave packet 29; extra bytes their count): the decoder reads each
/// chunk's first point by the type's size, whatever the VLR says, so a wrong size
/// shifts everything it reads next.
fn item_sizes(vlr: &laz::LazVlr) -> Result<(), String> {
    use laz::LazItemType::*;
    for item in vlr.items() {
        let own = match item.item_type() {
            Point10 => 20,
            GpsTime | RGBNIR14 => 8,
            RGB12 | RGB14 => 6,
            WavePacket13 | WavePacket14 => 29,
            Point14 => 30,
            Byte(n) | Byte14(n) => n,
        };
        if item.size() != own {
            return Err(format!(
                "the LASzip VLR says its {:?} item takes {} bytes; it takes {own}",
                item.item_type(),
                item.size()
            ));
        }
    }
    Ok(())
}

/// The layer sizes (u32 each) that a layered (LAS 1.4, point formats 6–10) LAZ chunk
/// lists after its first point and its point count, by item: 9 for the point, one for
/// RGB, two for RGB and NIR, one for the wave packet, one per extra byte.
fn layer_count(vlr: &laz::LazVlr) -> Option<u64> {
    use laz::LazItemType::*;
    let mut layers = 0u64;
    for item in vlr.items() {
        layers += match item.item_type() {
            Point14 => 9,
            RGB14 | WavePacket14 => 1,
            RGBNIR14 => 2,
            Byte14(n) => u64::from(n),
            // Pointwise chunks (formats 0–5) have no layers.
            _ => return None,
        };
    }
    Some(layers)
}

/// In a layered LAZ, each chunk's layers must fit in the chunk: the decoder allocates
/// each layer at the size the chunk states (a u32, up to 4 GiB), before reading it.
/// `chunks`: each chunk's first byte and byte count.
fn check_layers(
    file: &mut File,
    vlr: &laz::LazVlr,
    chunks: impl IntoIterator<Item = (u64, u64)>,
    record: u64,
) -> Result<(), String> {
    let Some(layers) = layer_count(vlr) else {
        return Ok(());
    };
    for (k, (at, byte_count)) in chunks.into_iter().enumerate() {
        let sizes_at = at + record + 4;
        let sizes = bytes_at(file, sizes_at, 4 * layers as usize);
        let stated: u64 = sizes.map_or(u64::MAX, |b| {
            b.chunks_exact(4)
                .map(|w| u64::from(u32::from_le_bytes(w.try_into().unwrap_or_default())))
                .sum()
        });
        let room = byte_count.saturating_sub(record + 4 + 4 * layers);
        if stated > room {
            return Err(format!(
                "LAZ chunk {k} says its layers hold {stated} bytes; it has {room}: it is damaged"
            ));
        }
    }
    Ok(())
}

/// The offset to the point data, from the header's fixed part.
fn header_offset_to_points(file: &mut File) -> Result<u64, String> {
    bytes_at(file, 96, 4)
        .map(|b| u64::from(u32::from_le_bytes(b.try_into().unwrap_or_default())))
        .ok_or_else(|| "the header is cut short".to_owned())
}
