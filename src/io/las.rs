//! LAS 1.0–1.4 and LAZ files in, with the `las` crate (LAZ decoded in parallel across
//! cores by `laz`): positions (scaled integers, to f64, then rebased as PLY vertices are,
//! [`super::geometry`]), RGB, each point's intensity, class and returns
//! ([`PointAttributes`]), and what LiDAR users read a tile by: counts by ASPRS class
//! and by return number, intensity range, scale, offset and CRS ([`LasSummary`]).
//!
//! Bad files get an error that names the file and what is wrong, and nothing is
//! allocated from a header's word alone: the header's point count and record length must
//! fit in the file (uncompressed), a LAZ chunk table may hold no more chunks than its
//! compressed bytes, an extended VLR no more bytes than the file, and points are decoded
//! in batches of [`BATCH`], so memory follows the points a file really holds.
//!
//! Colours: LAS stores 16-bit channels, but many writers put 0–255 values in them;
//! when no channel of any point exceeds 255, the values are taken as 8-bit.

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use las::{PointData, PointDataBuilder, Reader};
use serde::Serialize;

use super::geometry::{Geometry, GeometryStats, PointAttributes, assemble};
use super::ply::fields::{Field, VertexFields, VertexRows};
use super::ply::scalar::Scalar;

/// LAS points decoded at a time: a batch's records (about 2 MB) stay in cache while each
/// field is taken out of them.
pub const BATCH: u64 = 1 << 16;
/// LAZ points decoded at a time (at most; and no more than the file could hold at
/// [`RESERVED_BYTES_PER_POINT`]): enough chunks of the usual 50,000 points for the
/// parallel decoder to keep every core busy.
pub const LAZ_BATCH: u64 = 1 << 20;
/// Bytes of file per point reserved before decoding (a LAS record takes 20 or more, LAZ
/// packs one in about 4–10): a file that holds more points grows its vectors as it
/// decodes, and a header's count alone reserves nothing beyond the file's size.
pub const RESERVED_BYTES_PER_POINT: u64 = 4;

/// A LAS or LAZ file that cannot be read, and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct LasError {
    pub path: PathBuf,
    pub message: String,
}

/// What a LAS file says of itself, and counts over its points.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LasSummary {
    /// "1.2", "1.4"…
    pub version: String,
    pub point_format: u8,
    pub compressed: bool,
    pub points: u64,
    /// (return number, points), ascending, for the numbers present.
    pub by_return: Vec<(u8, u64)>,
    /// (ASPRS class, points), ascending, for the classes present.
    pub by_class: Vec<(u8, u64)>,
    /// (min, max) intensity.
    pub intensity: Option<(u16, u16)>,
    pub scale: [f64; 3],
    pub offset: [f64; 3],
    /// "WKT" or "GeoTIFF keys" when the file carries a CRS.
    pub crs: Option<String>,
    /// "16-bit" or "8-bit (in 16-bit fields)" when the points have RGB.
    pub colors: Option<String>,
    pub system_identifier: String,
    pub generating_software: String,
}

/// A LAS file read: its summary and its geometry.
#[derive(Debug, Clone)]
pub struct LasModel {
    pub summary: LasSummary,
    pub geometry: Geometry,
    pub stats: GeometryStats,
    pub file_bytes: u64,
    pub load_time: Duration,
}

/// Whether `bytes` (a file's first bytes) start as a LAS file does.
pub fn is_las(bytes: &[u8]) -> bool {
    bytes.starts_with(b"LASF")
}

/// Reads a LAS or LAZ file.
pub fn read_las(path: &Path) -> Result<LasModel, LasError> {
    let start = Instant::now();
    let fail = |message: String| LasError {
        path: path.to_owned(),
        message,
    };
    let io = |e: std::io::Error| fail(format!("cannot read: {e}"));
    let mut file = File::open(path).map_err(io)?;
    let file_bytes = file.metadata().map_err(io)?.len();
    check_layout(&mut file, file_bytes).map_err(fail)?;
    file.seek(SeekFrom::Start(0)).map_err(io)?;
    let header = las::Header::new(BufReader::new(&mut file)).map_err(|e| fail(format!("{e}")))?;
    if header.point_format().is_compressed {
        check_laz(&mut file, &header).map_err(fail)?;
    }
    file.seek(SeekFrom::Start(0)).map_err(io)?;
    let mut reader = Reader::new(BufReader::new(file)).map_err(|e| fail(format!("{e}")))?;
    let points = decode(&mut reader, file_bytes).map_err(fail)?;
    let summary = summarize(reader.header(), &points);
    let (mut geometry, stats) = assemble(&points, &points.fields(), None).map_err(fail)?;
    geometry.attributes = Some(points.attributes(geometry.rows.as_deref()));
    Ok(LasModel {
        summary,
        geometry,
        stats,
        file_bytes,
        load_time: start.elapsed(),
    })
}

/// `n` bytes of `file` from `at`, or `None` past its end.
fn bytes_at(file: &mut File, at: u64, n: usize) -> Option<Vec<u8>> {
    let mut buf = vec![0; n];
    file.seek(SeekFrom::Start(at)).ok()?;
    file.read_exact(&mut buf).ok()?;
    Some(buf)
}

/// Checks that the header's sizes fit in the file (see the module doc).
fn check_layout(file: &mut File, len: u64) -> Result<(), String> {
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
    let compressed = raw.point_data_record_format & 0x80 != 0;
    if !compressed {
        let record = u64::from(raw.point_data_record_length);
        let room = (len - data) / record.max(1);
        if count > room {
            return Err(format!(
                "the header says {count} points of {record} bytes, but the file holds at most {room} (truncated?)"
            ));
        }
    } else {
        check_chunk_table(file, len, data)?;
    }
    if let Some(evlr) = raw.evlr {
        check_evlr(file, len, evlr.start_of_first_evlr)?;
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

/// What the LAZ decoder would trust without checking: its VLR's record size must be the
/// header's, its chunks no larger than [`MAX_CHUNK_BYTES`], its chunk table's byte
/// counts must add up to no more than the compressed data, and its chunks must hold at
/// least the points the header announces.
fn check_laz(file: &mut File, header: &las::Header) -> Result<(), String> {
    let vlr = header
        .all_vlrs()
        .find(|v| v.user_id == laz::LazVlr::USER_ID && v.record_id == laz::LazVlr::RECORD_ID)
        .ok_or("compressed, but without the LASzip VLR that says how")?;
    let laz_vlr =
        laz::LazVlr::from_buffer(&vlr.data).map_err(|e| format!("the LASzip VLR: {e}"))?;
    let record = u64::from(header.point_format().len());
    if laz_vlr.items_size() != record || record == 0 {
        return Err(format!(
            "the LASzip VLR describes {}-byte points, the header {record}-byte ones",
            laz_vlr.items_size()
        ));
    }
    let chunk = u64::from(laz_vlr.chunk_size());
    if !laz_vlr.uses_variable_size_chunks() && chunk * record > MAX_CHUNK_BYTES {
        return Err(format!(
            "LAZ chunks of {chunk} points are larger than any writer makes"
        ));
    }
    let data = header_offset_to_points(file)?;
    file.seek(SeekFrom::Start(data))
        .map_err(|e| e.to_string())?;
    let table = laz::laszip::ChunkTable::read_from(BufReader::new(&mut *file), &laz_vlr)
        .map_err(|e| format!("the LAZ chunk table cannot be read: {e}"))?;
    let room = file
        .metadata()
        .map_err(|e| e.to_string())?
        .len()
        .saturating_sub(data);
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
    check_layers(file, data, &laz_vlr, &table, record)?;
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
fn check_layers(
    file: &mut File,
    data: u64,
    vlr: &laz::LazVlr,
    table: &laz::laszip::ChunkTable,
    record: u64,
) -> Result<(), String> {
    let Some(layers) = layer_count(vlr) else {
        return Ok(());
    };
    // The chunks follow the 8-byte chunk table offset, one after the other.
    let mut at = data + 8;
    for (k, entry) in table.as_ref().iter().enumerate() {
        let sizes_at = at + record + 4;
        let sizes = bytes_at(file, sizes_at, 4 * layers as usize);
        let stated: u64 = sizes.map_or(u64::MAX, |b| {
            b.chunks_exact(4)
                .map(|w| u64::from(u32::from_le_bytes(w.try_into().unwrap_or_default())))
                .sum()
        });
        let room = entry.byte_count.saturating_sub(record + 4 + 4 * layers);
        if stated > room {
            return Err(format!(
                "LAZ chunk {k} says its layers hold {stated} bytes; it has {room}: it is damaged"
            ));
        }
        at = at.saturating_add(entry.byte_count);
    }
    Ok(())
}

/// The offset to the point data, from the header's fixed part.
fn header_offset_to_points(file: &mut File) -> Result<u64, String> {
    bytes_at(file, 96, 4)
        .map(|b| u64::from(u32::from_le_bytes(b.try_into().unwrap_or_default())))
        .ok_or_else(|| "the header is cut short".to_owned())
}

/// The decoded points: f64 positions and, when the format has them, 16-bit RGB.
struct LasPoints {
    xyz: Vec<[f64; 3]>,
    rgb: Option<Vec<[u16; 3]>>,
    intensity: Vec<u16>,
    classification: Vec<u8>,
    return_number: Vec<u8>,
    number_of_returns: Vec<u8>,
}

impl LasPoints {
    /// The attributes of the points kept (file rows `kept`; all when `None`).
    fn attributes(&self, kept: Option<&[u32]>) -> Vec<PointAttributes> {
        let of = |i: usize| {
            PointAttributes::new(
                self.intensity[i],
                self.classification[i],
                self.return_number[i],
                self.number_of_returns[i],
            )
        };
        match kept {
            Some(rows) => rows.iter().map(|&r| of(r as usize)).collect(),
            None => (0..self.xyz.len()).map(of).collect(),
        }
    }

    /// The fields for [`assemble`]: x y z, then red green blue, 8- or 16-bit.
    fn fields(&self) -> VertexFields {
        let field = |property, scalar| Field { property, scalar };
        let mut fields: Vec<Field> = (0..3).map(|k| field(k, Scalar::F64)).collect();
        let eight_bit = self
            .rgb
            .as_ref()
            .is_some_and(|c| c.iter().flatten().all(|v| *v <= 255));
        if self.rgb.is_some() {
            let scalar = if eight_bit { Scalar::U8 } else { Scalar::U16 };
            fields.extend((3..6).map(|k| field(k, scalar)));
        }
        VertexFields {
            fields,
            has_normals: false,
            color_channels: if self.rgb.is_some() { 3 } else { 0 },
        }
    }
}

impl VertexRows for LasPoints {
    fn len(&self) -> usize {
        self.xyz.len()
    }

    #[inline(always)]
    fn get(&self, i: usize, f: usize) -> f64 {
        match f {
            0..3 => self.xyz[i][f],
            _ => self.rgb.as_ref().map_or(0.0, |c| f64::from(c[i][f - 3])),
        }
    }
}

/// Decodes every point of a file of `file_bytes`, [`BATCH`] (LAZ: up to [`LAZ_BATCH`])
/// at a time.
fn decode(reader: &mut Reader, file_bytes: u64) -> Result<LasPoints, String> {
    let header = reader.header();
    let expected = header.number_of_points();
    let has_rgb = header.point_format().has_color;
    let mut batch: PointData = PointDataBuilder::new().for_header(header).build();
    // Bounded by the file's size, whatever the header says.
    let n = expected.min(file_bytes / RESERVED_BYTES_PER_POINT) as usize;
    let batch_points = if header.point_format().is_compressed {
        LAZ_BATCH.min(n as u64).max(BATCH)
    } else {
        BATCH.min(n as u64).max(1)
    };
    let mut points = LasPoints {
        xyz: Vec::with_capacity(n),
        rgb: has_rgb.then(|| Vec::with_capacity(n)),
        intensity: Vec::with_capacity(n),
        classification: Vec::with_capacity(n),
        return_number: Vec::with_capacity(n),
        number_of_returns: Vec::with_capacity(n),
    };
    while (points.xyz.len() as u64) < expected {
        let n = fill_contained(reader, batch_points, &mut batch).map_err(|e| {
            format!(
                "the header announces {expected} points; decoding failed after {} ({e}): \
                 the file is damaged or truncated",
                points.xyz.len()
            )
        })?;
        if n == 0 {
            break;
        }
        points.xyz.extend(
            batch
                .x()
                .zip(batch.y())
                .zip(batch.z())
                .map(|((x, y), z)| [x, y, z]),
        );
        if let (Some(rgb), Some(colors)) = (&mut points.rgb, batch.rgb()) {
            rgb.extend(colors.map(|(r, g, b)| [r, g, b]));
        }
        points.intensity.extend(batch.intensity());
        points.classification.extend(batch.classification());
        points.return_number.extend(batch.return_number());
        points.number_of_returns.extend(batch.number_of_returns());
    }
    if points.xyz.is_empty() {
        return Err("the file holds no points".to_owned());
    }
    Ok(points)
}

/// [`Reader::fill_points`], with a panic of the decoder turned into an error. The `laz`
/// crate's arithmetic decoder indexes its tables with what it decodes, and corrupt
/// layered (LAS 1.4) chunks make it index past them (found by the fuzzer, not
/// checkable before decoding); the reader's state is dropped with the error.
fn fill_contained(reader: &mut Reader, n: u64, batch: &mut PointData) -> Result<u64, String> {
    let run = std::panic::AssertUnwindSafe(|| reader.fill_points(n, batch));
    match std::panic::catch_unwind(run) {
        Ok(result) => result.map_err(|e| e.to_string()),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            Err(format!("the LAZ decoder failed: {what}"))
        }
    }
}

/// Whether a panic at `file` (a source path) comes from the LAZ decoder, whose panics
/// [`read_las`] turns into errors: the binary's panic hook stays quiet about those.
pub fn is_decoder_panic(file: &str) -> bool {
    file.contains("/laz-")
}

/// (value, count) of each value present, ascending.
fn histogram(values: &[u8]) -> Vec<(u8, u64)> {
    let mut counts = [0u64; 256];
    for v in values {
        counts[*v as usize] += 1;
    }
    (0..=255u8).zip(counts).filter(|(_, n)| *n > 0).collect()
}

fn summarize(header: &las::Header, points: &LasPoints) -> LasSummary {
    let t = header.transforms();
    let crs = if header.has_wkt_crs() && header.has_crs_vlrs() {
        Some("WKT".to_owned())
    } else if header.has_crs_vlrs() {
        Some("GeoTIFF keys".to_owned())
    } else {
        None
    };
    let colors = points.rgb.as_ref().map(|c| {
        if c.iter().flatten().all(|v| *v <= 255) {
            "8-bit (in 16-bit fields)".to_owned()
        } else {
            "16-bit".to_owned()
        }
    });
    let intensity = points
        .intensity
        .iter()
        .fold(None, |range: Option<(u16, u16)>, &v| {
            Some(range.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))))
        });
    let format = header.point_format();
    LasSummary {
        version: header.version().to_string(),
        point_format: format.to_u8().unwrap_or(0),
        compressed: format.is_compressed,
        points: points.xyz.len() as u64,
        by_return: histogram(&points.return_number),
        by_class: histogram(&points.classification),
        intensity,
        scale: [t.x.scale, t.y.scale, t.z.scale],
        // + 0.0: a −0 offset reads as 0.
        offset: [t.x.offset + 0.0, t.y.offset + 0.0, t.z.offset + 0.0],
        crs,
        colors,
        system_identifier: header.system_identifier().to_owned(),
        generating_software: header.generating_software().to_owned(),
    }
}
