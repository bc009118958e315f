//! The read step's progress: each format tells the file's bytes as it reads them, in
//! several steps where the file is long (a LAS file batch by batch, an ASCII PLY row by
//! row), never more than the file holds, and near all of it by the end.

use std::path::Path;
use std::sync::Mutex;

use spt::io::formats::read_model_telling;
use spt::io::ply::Encoding;
use spt::tree::report::{Report, Step};

use crate::common;

/// The byte counts told while `path` is read, in order.
fn told(path: &Path) -> Vec<u64> {
    let counts = Mutex::new(Vec::new());
    read_model_telling(path, &|n| counts.lock().unwrap().push(n)).unwrap();
    counts.into_inner().unwrap()
}

/// Checks that `counts` add up to between 90 % and all of `path`'s bytes, in at least
/// `steps` non-empty tellings.
fn assert_told(path: &Path, counts: &[u64], steps: usize) {
    let bytes = std::fs::metadata(path).unwrap().len();
    let sum: u64 = counts.iter().sum();
    let what = path.file_name().unwrap().to_string_lossy();
    assert!(sum <= bytes, "{what}: told {sum} of {bytes} bytes");
    assert!(
        sum * 10 >= bytes * 9,
        "{what}: told only {sum} of {bytes} bytes"
    );
    let nonzero = counts.iter().filter(|&&n| n > 0).count();
    assert!(nonzero >= steps, "{what}: {nonzero} tellings, {counts:?}");
}

#[test]
fn every_format_tells_its_bytes_as_it_reads_them() {
    let dir = common::temp_dir();
    // A LAS file of 5 batches of 65,536 points, and the same compressed (one batch).
    for (name, compressed, steps) in [("s.las", false, 5), ("s.laz", true, 1)] {
        let path = dir.path().join(name);
        std::fs::write(&path, common::las_files::sample(4 * 65536 + 7, compressed)).unwrap();
        assert_told(&path, &told(&path), steps);
    }
    // A cloud of 60,000 vertices as ASCII PLY (told every 16,384 rows) and binary (told
    // once decoded, after its header).
    let points: Vec<[f64; 3]> = (0..60_000)
        .map(|i| [(i % 250) as f64, (i / 250) as f64, (i % 7) as f64 * 0.1])
        .collect();
    let mesh = common::to_mesh(&common::geometry_of(&points));
    for (name, encoding, steps) in [
        ("a.ply", Encoding::Ascii, 4),
        ("b.ply", Encoding::BinaryLittleEndian, 2),
    ] {
        let path = dir.path().join(name);
        common::write_standard(&path, &mesh, encoding);
        assert_told(&path, &told(&path), steps);
    }
}

/// The steps begun and the units told, as a convert's bars hear them.
#[derive(Default)]
struct Heard(Mutex<Vec<(Step, u64, u64)>>);

impl Report for Heard {
    fn step(&self, step: Step, total: u64) {
        self.0.lock().unwrap().push((step, total, 0));
    }
    fn advance(&self, n: u64) {
        if let Some(last) = self.0.lock().unwrap().last_mut() {
            last.2 += n;
        }
    }
}

#[test]
fn the_read_step_is_measured_in_the_file_s_bytes() {
    let dir = common::temp_dir();
    let path = dir.path().join("s.las");
    std::fs::write(&path, common::las_files::sample(2 * 65536, false)).unwrap();
    let heard = Heard::default();
    spt::tree::scene::build_from_file(&path, false, &heard).unwrap();
    let steps = heard.0.into_inner().unwrap();
    let (step, total, done) = steps[0];
    assert_eq!(step, Step::Read);
    assert_eq!(total, std::fs::metadata(&path).unwrap().len());
    assert!(done <= total && done * 10 >= total * 9, "{done} of {total}");
}
