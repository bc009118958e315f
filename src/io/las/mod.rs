//! LAS 1.0–1.4 and LAZ files in, with the `las` crate (LAZ decoded in parallel across
//! cores by `laz`): positions (scaled integers, to f64, then rebased as PLY vertices are,
//! [`super::geometry`]), RGB, each point's intensity, class and returns
//! ([`PointAttributes`]), and what LiDAR users read a tile by: counts by ASPRS class
//! and by return number, intensity range, scale, offset and CRS ([`LasSummary`]).
//!
//! Bad files get an error that names the file and what is wrong, and nothing is
//! allocated from a header's word alone: before the decoder sees a file, [`checks`]
//! holds its sizes against the file, and points are decoded in batches of [`BATCH`], so
//! memory follows the points a file really holds.
//!
//! Colours: LAS stores 16-bit channels, but many writers put 0–255 values in them;
//! when no channel of any point exceeds 255, the values are taken as 8-bit.

use std::fs::File;
use std::io::{BufReader, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use las::{PointData, PointDataBuilder, Reader};
use serde::Serialize;

mod batches;
mod checks;
mod format;
mod in_order;
mod point_wise;

use super::geometry::{Geometry, GeometryStats, PointAttributes, assemble};
use super::rows::{Field, VertexFields, VertexRows};
use super::scalar::Scalar;
pub use batches::LasBatches;
pub use checks::MAX_CHUNK_BYTES;
use checks::{LazLayout, check_layout, check_laz};
pub use format::LasFormat;

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
    /// "16-bit", "8-bit (in 16-bit fields)" or "zero everywhere (shaded grey)" when
    /// the points have RGB.
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

/// Reads a LAS or LAZ file.
pub fn read_las(path: &Path) -> Result<LasModel, LasError> {
    read_las_telling(path, &|_| {})
}

/// [`read_las`], telling `told` the file's bytes as its points are decoded (in
/// proportion to the points: a LAZ file's bytes per point vary).
pub fn read_las_telling(path: &Path, told: &dyn Fn(u64)) -> Result<LasModel, LasError> {
    let start = Instant::now();
    let fail = |message: String| LasError {
        path: path.to_owned(),
        message,
    };
    let (mut reader, file_bytes) = open_checked(path)?;
    let points = decode(&mut reader, file_bytes, told).map_err(fail)?;
    let eight_bit = points.eight_bit_rgb();
    let summary = summarize(reader.header(), &points, eight_bit);
    let (mut geometry, stats) = assemble(&points, &points.fields(eight_bit), None).map_err(fail)?;
    geometry.attributes = Some(points.attributes(geometry.rows.as_deref()));
    Ok(LasModel {
        summary,
        geometry,
        stats,
        file_bytes,
        load_time: start.elapsed(),
    })
}

/// The decoded points: f64 positions and, when the format has them, 16-bit RGB.
/// A reader of the file at `path`, once [`checks`] have held its sizes against the
/// file, and the file's size.
fn open_checked(path: &Path) -> Result<(Reader, u64), LasError> {
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
    if header.point_format().is_compressed
        && check_laz(&mut file, &header).map_err(fail)? == LazLayout::PointWise
    {
        return Ok((point_wise::reader(path).map_err(fail)?, file_bytes));
    }
    file.seek(SeekFrom::Start(0)).map_err(io)?;
    let reader = Reader::new(BufReader::new(file)).map_err(|e| fail(format!("{e}")))?;
    Ok((reader, file_bytes))
}

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

    /// Whether the points have RGB whose channels all stay within 0–255 (8-bit values
    /// stored in LAS's 16-bit fields).
    fn eight_bit_rgb(&self) -> bool {
        self.rgb
            .as_ref()
            .is_some_and(|c| c.iter().flatten().all(|v| *v <= 255))
    }

    /// The fields for [`assemble`]: x y z, then red green blue, 8-bit when `eight_bit`
    /// ([`LasPoints::eight_bit_rgb`]), else 16-bit.
    fn fields(&self, eight_bit: bool) -> VertexFields {
        let field = |property, scalar| Field { property, scalar };
        let mut fields: Vec<Field> = (0..3).map(|k| field(k, Scalar::F64)).collect();
        if self.rgb.is_some() {
            let scalar = if eight_bit { Scalar::U8 } else { Scalar::U16 };
            fields.extend((3..6).map(|k| field(k, scalar)));
        }
        VertexFields {
            fields,
            has_normals: false,
            color_channels: if self.rgb.is_some() { 3 } else { 0 },
            z_absent: false,
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
fn decode(reader: &mut Reader, file_bytes: u64, told: &dyn Fn(u64)) -> Result<LasPoints, String> {
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
    // The file's bytes up to the points decoded so far: ⌊file_bytes · decoded / expected⌋.
    let bytes_to = |decoded: usize| {
        let decoded = (decoded as u64).min(expected);
        (file_bytes as u128 * decoded as u128 / expected.max(1) as u128) as u64
    };
    while (points.xyz.len() as u64) < expected {
        let before = points.xyz.len();
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
        told(bytes_to(points.xyz.len()) - bytes_to(before));
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

/// Stack of each thread that may decode LAZ points: 256 MiB, reserved, and touched
/// only as deep as a call goes. The `laz` crate's GPS-time decoder calls itself once
/// for each switch of time sequence it decodes: a valid stream switches at most once a
/// point, but a damaged one can switch tens of thousands of times in a row, 64 bytes of
/// stack each (a 1.4 kB LAZ file that the fuzzer made went about 36,000 calls deep,
/// past a thread's default 2 MiB, and aborted the process). The depth is bounded by
/// the stream's length, not by this stack: a file crafted for it can still go deeper.
pub const DECODER_STACK: usize = 256 << 20;

/// Makes rayon's global pool, where the `laz` crate decodes a chunked file's chunks,
/// with threads of [`DECODER_STACK`]; an error when the pool was already made. For a
/// program's start (the `spt` binary, the fuzzer).
pub fn use_decoder_stacks() -> Result<(), rayon::ThreadPoolBuildError> {
    rayon::ThreadPoolBuilder::new()
        .stack_size(DECODER_STACK)
        .build_global()
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

fn summarize(header: &las::Header, points: &LasPoints, eight_bit: bool) -> LasSummary {
    let t = header.transforms();
    let crs = if header.has_wkt_crs() && header.has_crs_vlrs() {
        Some("WKT".to_owned())
    } else if header.has_crs_vlrs() {
        Some("GeoTIFF keys".to_owned())
    } else {
        None
    };
    let colors = points.rgb.as_ref().map(|rgb| {
        if rgb.iter().all(|c| *c == [0; 3]) {
            "zero everywhere (shaded grey)".to_owned()
        } else if eight_bit {
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
