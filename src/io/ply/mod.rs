//! PLY in: ASCII and binary (both byte orders), any scalar type, any property order,
//! unknown properties and elements skipped, polygons fan-triangulated.
//!
//! ```text
//! bytes ─► header (ply-rs-bw) ─► Plan (which fields) ─► binary | ascii decode ─► Geometry
//! ```

pub(crate) mod ascii;
pub(crate) mod binary;
mod error;
pub(crate) mod faces;
pub(crate) mod fields;
mod format;
pub(crate) mod header;
pub mod stream;
pub mod table;
pub(crate) mod write;

use std::path::Path;
use std::time::{Duration, Instant};

pub use error::{Location, PlyError};
pub use format::PlyFormat;
pub use header::{Element, Encoding, Header, Property, PropertyKind};
pub use stream::{PlyStream, VertexBatch};
pub use write::{FaceList, PlyLayout, PolyMesh, write_ply};

use crate::io::geometry::{Geometry, GeometryStats, assemble};
use error::Problem;
use fields::Plan;

/// A PLY file read into geometry, with what the file declared and what was dropped.
#[derive(Debug, Clone)]
pub struct PlyModel {
    pub header: Header,
    pub geometry: Geometry,
    pub stats: GeometryStats,
    pub file_bytes: u64,
    pub load_time: Duration,
}

/// Reads a PLY file. Errors name the file and, where they can, the header line or the
/// element and row at fault.
pub fn read_ply(path: &Path) -> Result<PlyModel, PlyError> {
    read_ply_telling(path, &|_| {})
}

/// [`read_ply`], telling `told` the file's bytes as they are decoded.
pub fn read_ply_telling(path: &Path, told: &dyn Fn(u64)) -> Result<PlyModel, PlyError> {
    let start = Instant::now();
    let io_err = |e: std::io::Error| Problem::file(format!("cannot read: {e}")).in_file(path);
    let file = std::fs::File::open(path).map_err(io_err)?;
    let len = file.metadata().map_err(io_err)?.len();
    if len == 0 {
        return Err(Problem::file("the file is empty").in_file(path));
    }
    // SAFETY: the map is only read, and only for the duration of this call; a file that
    // another process truncates meanwhile is outside what a reader can guard against.
    let map = unsafe { memmap2::MmapOptions::new().populate().map(&file) }.map_err(io_err)?;
    let (header, geometry, stats) = parse(&map, told).map_err(|p| p.in_file(path))?;
    Ok(PlyModel {
        header,
        geometry,
        stats,
        file_bytes: len,
        load_time: start.elapsed(),
    })
}

/// Parses a whole PLY file held in memory, telling `told` the bytes decoded: the
/// header's, then an ASCII payload's row by row, or a binary one's once decoded whole
/// (its decoding takes little beside the read of the file).
fn parse(bytes: &[u8], told: &dyn Fn(u64)) -> Result<(Header, Geometry, GeometryStats), Problem> {
    let header = header::parse_header(bytes)?;
    let plan = Plan::new(&header)?;
    told(header.payload_offset as u64);
    let payload = &bytes[header.payload_offset..];
    let (geometry, stats) = match header.encoding {
        Encoding::Ascii => {
            let first_line = bytes[..header.payload_offset]
                .iter()
                .filter(|&&b| b == b'\n')
                .count()
                + 1;
            let d = ascii::decode(payload, (&header, &plan), first_line, told)?;
            assemble(&d.vertices, &plan.vertex_fields, d.faces)
        }
        Encoding::BinaryLittleEndian | Encoding::BinaryBigEndian => {
            let d = binary::decode(payload, &header, &plan)?;
            told(payload.len() as u64);
            match d.vertices {
                binary::VertexSource::Fixed(rows) => assemble(&rows, &plan.vertex_fields, d.faces),
                binary::VertexSource::Columns(rows) => {
                    assemble(&rows, &plan.vertex_fields, d.faces)
                }
            }
        }
    }
    .map_err(Problem::file)?;
    Ok((header, geometry, stats))
}
