//! Small LAS and LAZ files written by the `las` crate, and damaged copies of them.

use las::{Builder, Color, Point, Writer, point::Classification, point::Format};

/// A LAS 1.2 file of point format 3 (RGB, intensity, classes, returns, GPS time):
/// `n` points on a 1 m grid of rows of 64 at UTM-sized coordinates, scale 0.01; the
/// first 16 rows ground (class 2), the others water (class 9); LAZ when `compressed`.
pub fn sample(n: usize, compressed: bool) -> Vec<u8> {
    sample_of_format(n, 3, compressed)
}

/// [`sample`] in point `format` (0–10; LAS 1.3 for 4 and 5, 1.4 for 6–10), with the
/// fields it holds.
pub fn sample_of_format(n: usize, format: u8, compressed: bool) -> Vec<u8> {
    let minor = match format {
        0..=3 => 2,
        4 | 5 => 3,
        _ => 4,
    };
    let mut builder = Builder::from((1, minor));
    builder.point_format = Format::new(format).unwrap();
    let format = builder.point_format;
    builder.point_format.is_compressed = compressed;
    builder.transforms.x.scale = 0.01;
    builder.transforms.y.scale = 0.01;
    builder.transforms.z.scale = 0.01;
    builder.transforms.x.offset = 500_000.0;
    builder.transforms.y.offset = 5_000_000.0;
    let header = builder.into_header().unwrap();
    let mut writer = Writer::new(std::io::Cursor::new(Vec::new()), header).unwrap();
    for i in 0..n {
        let (col, row) = ((i % 64) as f64, (i / 64) as f64);
        writer
            .write_point(Point {
                x: 500_000.0 + col,
                y: 5_000_000.0 + row,
                z: 100.0 + (col * 0.3).sin(),
                intensity: (i % 1000) as u16,
                classification: if row < 16.0 {
                    Classification::Ground
                } else {
                    Classification::Water
                },
                return_number: 1 + (i % 2) as u8,
                number_of_returns: 2,
                color: format
                    .has_color
                    .then(|| Color::new(200, (i % 256) as u16, 40)),
                gps_time: format.has_gps_time.then_some(i as f64),
                nir: format.has_nir.then_some(7),
                waveform: format.has_waveform.then(Default::default),
                ..Default::default()
            })
            .unwrap();
    }
    writer.into_inner().unwrap().into_inner()
}

/// A point-wise LAZ file (LASzip 1) made from the chunked one `laz` (one chunk):
/// without the chunk table's offset before the points and the table after them, its
/// VLR naming compressor 1 (point-wise) with chunk size 0, as LASzip 1 wrote it.
pub fn point_wise(laz: &[u8]) -> Vec<u8> {
    let data = u32::from_le_bytes(laz[96..100].try_into().unwrap()) as usize;
    let table = i64::from_le_bytes(laz[data..data + 8].try_into().unwrap()) as usize;
    let mut out = [&laz[..data], &laz[data + 8..table]].concat();
    let user_id = out
        .windows(14)
        .position(|w| w == b"laszip encoded")
        .unwrap();
    let vlr_data = user_id - 2 + 54;
    out[vlr_data..vlr_data + 2].copy_from_slice(&1u16.to_le_bytes());
    out[vlr_data + 12..vlr_data + 16].copy_from_slice(&0u32.to_le_bytes());
    out
}

/// Offsets in a LAS 1.2 header (ASPRS LAS 1.2, table 4).
pub const POINT_COUNT_AT: usize = 107;
pub const VLR_COUNT_AT: usize = 100;
pub const X_SCALE_AT: usize = 131;
