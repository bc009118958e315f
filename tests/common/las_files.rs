//! Small LAS and LAZ files written by the `las` crate, and damaged copies of them.

use las::{Builder, Color, Point, Writer, point::Classification, point::Format};

/// A LAS 1.2 file of point format 3 (RGB, intensity, classes, returns, GPS time):
/// `n` points on a 1 m grid of rows of 64 at UTM-sized coordinates, scale 0.01; the
/// first 16 rows ground (class 2), the others water (class 9); LAZ when `compressed`.
pub fn sample(n: usize, compressed: bool) -> Vec<u8> {
    let mut builder = Builder::from((1, 2));
    builder.point_format = Format::new(3).unwrap();
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
                color: Some(Color::new(200, (i % 256) as u16, 40)),
                gps_time: Some(i as f64),
                ..Default::default()
            })
            .unwrap();
    }
    writer.into_inner().unwrap().into_inner()
}

/// Offsets in a LAS 1.2 header (ASPRS LAS 1.2, table 4).
pub const POINT_COUNT_AT: usize = 107;
pub const X_SCALE_AT: usize = 131;
