//! What a conversion will write, against the space free where it writes: said before
//! the build, so that a build too large for its disk is known at its start and not when
//! the disk fills (which stops it with "No space left on device", the file untouched).

use std::path::Path;

use crate::io::disk_space::available_bytes;

/// The `.spt` file's bytes per input point: about 1.5 nodes a point, 60 bytes a node
/// and 4 more with LiDAR attributes (measured 2026-12-04: 89.9 for the Lucy-size
/// cloud, 90.2 for a 3 M-vertex mesh, 96.4 for a 20 M-point LiDAR tile).
pub const FILE_BYTES_PER_POINT: u64 = 97;

/// The disk an out-of-core build takes beside its output at its peak, per input point:
/// the parts and the job inputs not yet built, then the file as the join writes it and
/// frees each part's bytes. Measured 2026-12-04 (blocks held, `tools/peak_disk.sh`):
/// 112.8 bytes a point for a 20 M-point LiDAR tile, 98.1 for the Lucy-size cloud,
/// 86–124 for a 3 M-vertex mesh (1.17, 1.09 and 0.95–1.38 times the file; with the
/// job inputs kept until the join 117.5, 106.4 and 113–127; with the parts and the
/// file both whole, 2.17, 2.24 and 2.61 times the file).
pub const OUT_OF_CORE_BYTES_PER_POINT: u64 = 140;

/// Says on standard output (when `loud`) how much `what` takes in `dir` at its peak,
/// `needed` bytes, and how much is free there; and on standard error, loud or not, that
/// the build will likely stop when less is free than that.
pub fn say_room(dir: &Path, needed: u64, what: &str, loud: bool) {
    // A folder the command makes (a job directory) is on its nearest existing parent's.
    let existing = dir
        .ancestors()
        .find(|a| a.exists())
        .unwrap_or(Path::new("."));
    // Named whole: "in ." says little in a log.
    let named = std::path::absolute(dir).unwrap_or_else(|_| dir.to_owned());
    let (line, warning) = room_lines(&named, needed, available_bytes(existing), what);
    if loud {
        say!("{line}");
    }
    if let Some(warning) = warning {
        eprintln!("{warning}");
    }
}

/// [`say_room`]'s line, and its warning when `free` (None: unknown) is less than
/// `needed`.
fn room_lines(dir: &Path, needed: u64, free: Option<u64>, what: &str) -> (String, Option<String>) {
    let gb = |b: u64| b as f64 / 1e9;
    let place = format!(
        "about {:.1} GB in {} at the peak",
        gb(needed),
        dir.display()
    );
    let free_line = free.map_or(String::new(), |f| format!(", {:.1} GB free", gb(f)));
    let warning = free.filter(|&f| f < needed).map(|f| {
        format!(
            "warning: {what} will take {place}, and {:.1} GB is free there: the build will \
             likely stop when the disk is full",
            gb(f)
        )
    });
    (format!("disk      {place} ({what}){free_line}"), warning)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_warning_comes_only_when_less_is_free_than_needed() {
        let dir = Path::new("out");
        let (line, warning) = room_lines(dir, 4_200_000_000, Some(600_000_000), "the files");
        assert_eq!(
            line,
            "disk      about 4.2 GB in out at the peak (the files), 0.6 GB free"
        );
        let warning = warning.expect("a warning");
        assert!(warning.starts_with("warning: the files will take about 4.2 GB in out"));
        assert!(warning.contains("0.6 GB is free there"));
        assert!(room_lines(dir, 100, Some(100), "x").1.is_none());
        let (line, warning) = room_lines(dir, 100, None, "x");
        assert!(warning.is_none() && !line.contains("free"));
    }
}
