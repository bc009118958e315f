//! LAS and LAZ in: a small file written by the `las` crate reads back with its
//! points, colours and counts; damaged copies (truncated LAS and LAZ, a point count of
//! 10⁹ in a small file, a point-wise LAZ whose layers claim gigabytes, a VLR counted
//! but missing, a zero scale factor, a file that only starts with `LASF`) are
//! refused with an error that names the file and the problem, `spt info` exits 1 on
//! them without panicking, and no allocation exceeds 8 MiB meanwhile (a 10⁹-point
//! header would ask for tens of GB). Alone in its binary: the allocation counter sees
//! every thread of the process.

use crate::common;

use crate::common::las_files::{
    POINT_COUNT_AT, VLR_COUNT_AT, X_SCALE_AT, point_wise, sample, sample_of_format,
};
use spt::io::las::read_las;

#[test]
fn a_written_file_reads_back_with_its_points_colours_and_counts() {
    let _alone = crate::alone();
    let dir = common::temp_dir();
    for (name, compressed) in [("grid.las", false), ("grid.laz", true)] {
        let path = dir.path().join(name);
        std::fs::write(&path, sample(3000, compressed)).unwrap();
        let m = read_las(&path).unwrap();
        let s = &m.summary;
        assert_eq!(
            (s.points, m.geometry.positions.len()),
            (3000, 3000),
            "{name}"
        );
        assert_eq!(s.compressed, compressed);
        assert_eq!(s.by_class, vec![(2, 1024), (9, 1976)], "{name}");
        assert_eq!(s.by_return, vec![(1, 1500), (2, 1500)], "{name}");
        assert_eq!(s.intensity, Some((0, 999)), "{name}");
        assert_eq!(
            m.geometry.bounds.min,
            [500_000.0, 5_000_000.0, 99.0],
            "{name}"
        );
        assert_eq!(m.geometry.bounds.max[0], 500_063.0, "{name}");
        // 8-bit values in 16-bit fields are taken as they are.
        let colors = m.geometry.colors.as_ref().unwrap();
        assert_eq!(colors[5], [200, 5, 40, 255], "{name}");
    }
}

#[test]
fn every_point_format_reads() {
    let _alone = crate::alone();
    let dir = common::temp_dir();
    for format in 0..=10u8 {
        for compressed in [false, true] {
            let name = format!("format{format}.{}", if compressed { "laz" } else { "las" });
            let path = dir.path().join(&name);
            std::fs::write(
                &path,
                common::las_files::sample_of_format(500, format, compressed),
            )
            .unwrap();
            let m = read_las(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(m.geometry.positions.len(), 500, "{name}");
            assert_eq!(m.summary.point_format, format, "{name}");
            let colors = matches!(format, 2 | 3 | 5 | 7 | 8 | 10);
            assert_eq!(m.geometry.colors.is_some(), colors, "{name}");
            assert_eq!(m.summary.by_class, vec![(2, 500)], "{name}");
        }
    }
}

struct Damaged {
    name: &'static str,
    bytes: Vec<u8>,
    /// Words the error must hold.
    expect: &'static [&'static str],
}

fn damaged() -> Vec<Damaged> {
    let las = sample(3000, false);
    let laz = sample(3000, true);
    let patch = |mut b: Vec<u8>, at: usize, with: &[u8]| {
        b[at..at + with.len()].copy_from_slice(with);
        b
    };
    vec![
        Damaged {
            name: "truncated.las",
            bytes: las[..las.len() * 2 / 3].to_vec(),
            expect: &["3000 points", "truncated"],
        },
        Damaged {
            name: "truncated.laz",
            bytes: laz[..laz.len() * 2 / 3].to_vec(),
            expect: &["LAZ"],
        },
        Damaged {
            name: "billion.las",
            bytes: patch(las.clone(), POINT_COUNT_AT, &1_000_000_000u32.to_le_bytes()),
            expect: &["1000000000 points", "holds at most 3000"],
        },
        Damaged {
            name: "billion.laz",
            bytes: patch(laz.clone(), POINT_COUNT_AT, &1_000_000_000u32.to_le_bytes()),
            expect: &["1000000000 points", "damaged or truncated"],
        },
        Damaged {
            name: "zero_scale.las",
            bytes: patch(las.clone(), X_SCALE_AT, &0f64.to_le_bytes()),
            expect: &["x scale factor is 0"],
        },
        Damaged {
            name: "vlr_count.las",
            bytes: patch(las.clone(), VLR_COUNT_AT, &1u32.to_le_bytes()),
            expect: &["1 VLR", "only 0 lie before the point data"],
        },
        Damaged {
            // Point-wise, its LAS 1.4 points still come in layers, whose sizes follow
            // the first point (30 bytes) and the point count: one stated at 3.9 GB.
            name: "point_wise_layers.laz",
            bytes: {
                let b = point_wise(&sample_of_format(3000, 6, true));
                let data = u32::from_le_bytes(b[96..100].try_into().unwrap()) as usize;
                patch(b, data + 34, &0xe800_0000u32.to_le_bytes())
            },
            expect: &["layers hold", "damaged"],
        },
        Damaged {
            name: "only_magic.las",
            bytes: b"LASF and then nothing a LAS reader could use".to_vec(),
            expect: &["not a readable LAS header"],
        },
    ]
}

#[test]
fn damaged_files_are_refused_with_a_clear_error_and_no_large_allocation() {
    let _alone = crate::alone();
    let dir = common::temp_dir();
    for f in damaged() {
        let path = dir.path().join(f.name);
        std::fs::write(&path, &f.bytes).unwrap();
        crate::largest_allocation::reset();
        let err = read_las(&path).map(|_| ()).expect_err(f.name).to_string();
        let largest = crate::largest_allocation::largest();
        common::bad_files::check_refusal(f.name, &err, f.expect, largest, 8 << 20);
        let (code, _, stderr) = common::run_spt(&["info".as_ref(), path.as_os_str()]);
        assert_eq!(code, Some(1), "{}: {stderr}", f.name);
        assert!(
            stderr.contains(f.name) && !stderr.contains("panicked"),
            "{}: {stderr}",
            f.name
        );
    }
}
