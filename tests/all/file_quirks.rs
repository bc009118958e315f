//! Valid files that other readers take and spt must read as they do, each written here
//! in miniature: files without points (described by `spt info`, refused with "nothing
//! to draw" by the commands that draw), colours that are zero everywhere (dropped,
//! shaded grey), vertices without z (in the plane z = 0), LAZ of LASzip 1's point-wise
//! compressor (read, equal to the chunked file it came from).

use std::path::Path;

use crate::common;
use crate::common::las_files::{point_wise, sample, sample_of_format};
use spt::io::formats::read_model;

const HEADER: &str = "ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\n\
                      property float y\nproperty float z\n{more}end_header\n";

/// An ASCII PLY cloud of `rows`, with the properties after z declared by `more`.
fn ascii_cloud(rows: &[&str], more: &str) -> String {
    let header = HEADER
        .replace("{n}", &rows.len().to_string())
        .replace("{more}", more);
    header + &rows.iter().map(|r| format!("{r}\n")).collect::<String>()
}

/// `spt args… path`, with `out` (a file in `dir`) after the path when given.
fn spt(args: &[&str], path: &Path, out: Option<&str>, dir: &Path) -> (Option<i32>, String, String) {
    let mut all: Vec<std::ffi::OsString> = args.iter().map(Into::into).collect();
    all.push(path.into());
    if let Some(out) = out {
        all.push(dir.join(out).into());
    }
    common::run_spt(&all)
}

#[test]
fn a_file_without_points_is_described_and_nothing_is_drawn() {
    let dir = common::temp_dir();
    let d = dir.path();
    let files = [
        ("empty.ply", ascii_cloud(&[], "").into_bytes()),
        ("empty.las", sample(0, false)),
        ("empty.laz", sample(0, true)),
    ];
    for (name, bytes) in files {
        let path = d.join(name);
        std::fs::write(&path, bytes).unwrap();
        let (code, stdout, stderr) = spt(&["info"], &path, None, d);
        assert_eq!(code, Some(0), "{name}: {stderr}");
        assert!(
            stdout.contains("the file holds no points"),
            "{name}: {stdout}"
        );
        let (png, bench) = (d.join("out.png"), d.join("bench"));
        let (png, bench) = (png.to_str().unwrap(), bench.to_str().unwrap());
        let drawing: [(&[&str], Option<&str>); 4] = [
            (&["convert"], Some("out.spt")),
            (&["convert", "--out-of-core"], Some("out.spt")),
            (&["render", "-o", png], None),
            (&["bench", "--frames", "1", "--out", bench], None),
        ];
        for (args, out) in drawing {
            let (code, _, stderr) = spt(args, &path, out, d);
            assert_eq!(code, Some(1), "{name} {args:?}: {stderr}");
            assert!(
                stderr.contains(name) && stderr.contains("nothing to draw"),
                "{name} {args:?}: {stderr}"
            );
        }
        for out in ["out.spt", "out.png", "bench"] {
            assert!(!d.join(out).exists(), "{name}: {out} was written");
        }
    }
}

#[test]
fn colours_zero_everywhere_are_dropped_and_said() {
    let dir = common::temp_dir();
    let ply = dir.path().join("black.ply");
    let colours = "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    let rows = ["0 0 0 0 0 0", "1 0 0 0 0 0", "0 1 0 0 0 0", "0 0 1 0 0 0"];
    std::fs::write(&ply, ascii_cloud(&rows, colours)).unwrap();
    // A LAS file of point format 3 whose RGB (the record's last 6 of 34 bytes) is zero.
    let mut las = sample(500, false);
    let data = u32::from_le_bytes(las[96..100].try_into().unwrap()) as usize;
    for record in las[data..].chunks_exact_mut(34) {
        record[28..].fill(0);
    }
    let las_path = dir.path().join("black.las");
    std::fs::write(&las_path, las).unwrap();
    for path in [&ply, &las_path] {
        let model = read_model(path).unwrap();
        assert!(model.geometry.colors.is_none(), "{}", path.display());
        assert!(model.stats.colors_all_zero, "{}", path.display());
        let (code, stdout, _) = spt(&["info"], path, None, dir.path());
        assert_eq!(code, Some(0));
        assert!(stdout.contains("zero everywhere"), "{stdout}");
    }
    // One channel above zero anywhere keeps them.
    let mut rows = rows;
    rows[2] = "0 1 0 0 0 1";
    std::fs::write(&ply, ascii_cloud(&rows, colours)).unwrap();
    assert!(read_model(&ply).unwrap().geometry.colors.is_some());
}

#[test]
fn vertices_without_z_lie_in_the_plane_z_0() {
    let dir = common::temp_dir();
    let header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty int8 x\nproperty uint16 y\n\
                  property float64 i\nend_header\n";
    let path = dir.path().join("flat.ply");
    std::fs::write(&path, format!("{header}1 2 9\n4 5 9\n7 9 9\n")).unwrap();
    let model = read_model(&path).unwrap();
    assert!(model.stats.z_absent);
    assert_eq!(model.geometry.bounds.min, [1.0, 2.0, 0.0]);
    assert_eq!(model.geometry.bounds.max, [7.0, 9.0, 0.0]);
    let (code, stdout, _) = spt(&["info"], &path, None, dir.path());
    assert_eq!(code, Some(0));
    assert!(
        stdout.contains("no z in the file: read as z = 0"),
        "{stdout}"
    );
}

#[test]
fn a_point_wise_laz_reads_as_its_chunked_twin() {
    // LAS 1.2's point format 3, and LAS 1.4's 6, whose points come in layers.
    let dir = common::temp_dir();
    for format in [3, 6] {
        let laz = sample_of_format(3000, format, true);
        let (chunked, single) = (dir.path().join("chunked.laz"), dir.path().join("pw.laz"));
        std::fs::write(&chunked, &laz).unwrap();
        std::fs::write(&single, point_wise(&laz)).unwrap();
        let (a, b) = (read_model(&chunked).unwrap(), read_model(&single).unwrap());
        assert_eq!(b.geometry.positions.len(), 3000, "format {format}");
        assert_eq!(a.geometry, b.geometry, "format {format}");
    }
}

#[test]
fn a_laz_whose_gps_times_switch_sequence_again_and_again_reads_without_aborting() {
    // A 1.4 kB LAS 1.4 LAZ file that the fuzzer made from one the `las` crate wrote
    // (tests/fixtures/): its damaged GPS-time stream switches time sequence about
    // 36,000 times in a row, and the `laz` decoder goes a call deeper for each, past a
    // thread's default stack. It reads, with its 70 points, on spt's decoder stacks.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/laz_gps_switches.laz");
    let (code, stdout, stderr) = common::run_spt(&["info".as_ref(), path.as_os_str()]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with("points") && l.ends_with(" 70")),
        "{stdout}"
    );
}
