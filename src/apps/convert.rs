//! `spt convert IN.ply OUT.spt`: load, leaf surfels, tree, errors, sort, write, each
//! with its progress and timing, then a summary.

use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;

use std::sync::Mutex;

use crate::apps::progress::{BYTES, Stage, total_line};
use crate::apps::text::{count, walls};
use crate::apps::{convert_large, disk};
use crate::io::GeometryStats;
use crate::io::PointAttributes;
use crate::io::atomic::{check_writable, folder_of};
use crate::surfel::shape::SplatShape;
use crate::tree::NodeRecord;
use crate::tree::report::{Finished, Report, Step};
use crate::tree::scene::ordered_from_file;
use crate::tree::spt_file::file_bytes;
use crate::tree::spt_write::write_ordered;

fn rate(n: f64, seconds: f64) -> f64 {
    n / seconds.max(1e-9)
}

/// Prints each step of the build as `spt convert` shows it: a progress bar on a
/// terminal, then one line with its time and throughput.
#[derive(Default)]
struct Steps {
    current: Mutex<Option<Stage>>,
}

impl Steps {
    fn current(&self) -> std::sync::MutexGuard<'_, Option<Stage>> {
        self.current.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Report for Steps {
    fn step(&self, step: Step, total: u64) {
        let (name, unit) = match step {
            Step::Read => ("load", BYTES),
            Step::Surfels => ("surfels", "samples"),
            Step::Hierarchy => ("tree", "leaves"),
            Step::Errors => ("errors", "nodes"),
            Step::Sort => ("sort", ""),
            other => (other.name(), ""),
        };
        *self.current() = Some(Stage::start(name, total, unit));
    }

    fn advance(&self, n: u64) {
        if let Some(stage) = self.current().as_ref() {
            stage.advance(n);
        }
    }

    fn finished(&self, what: Finished) {
        let Some(stage) = self.current().take() else {
            return;
        };
        let per_s = |n: u64| rate(n as f64 / 1e6, stage.seconds());
        let summary = match what {
            Finished::Read(model) => format!(
                "{} vertices, {} triangles, {:.0} MB/s{}",
                count(model.geometry.positions.len() as u64),
                count(model.geometry.triangles.len() as u64),
                rate(model.file_bytes as f64 / 1e6, stage.seconds()),
                dropped(&model.stats)
            ),
            Finished::Surfels(leaves) => {
                let walls = walls(leaves.stats.added_splats());
                format!(
                    "{:.2} M surfels/s{walls}",
                    per_s(leaves.surfels.len() as u64)
                )
            }
            Finished::Hierarchy { leaves, internal } => format!(
                "{} internal nodes, {:.2} M leaves/s",
                count(internal),
                per_s(leaves)
            ),
            Finished::Errors(meta) => {
                format!(
                    "depth {}, {:.2} M nodes/s",
                    meta.depth,
                    per_s(meta.node_count)
                )
            }
            Finished::Sort { nodes } => format!("{} nodes", count(nodes)),
        };
        stage.finish(&summary);
    }
}

/// ", 3 non-finite vertices dropped, …" for what the reader dropped or flagged.
fn dropped(st: &GeometryStats) -> String {
    [
        (st.vertices_dropped_nonfinite, "non-finite vertices dropped"),
        (
            st.vertices_dropped_out_of_range,
            "vertices out of range dropped",
        ),
        (st.outliers, "outliers kept"),
    ]
    .iter()
    .filter(|(n, _)| *n > 0)
    .map(|(n, what)| format!(", {} {what}", count(*n)))
    .collect()
}

/// `spt convert`: once `output` is known to be writable (before any work), builds in
/// memory, or out of core when asked or when the model would not fit in `memory_mib`
/// (default: [`convert_large::default_memory`]).
pub fn run_either(
    input: &Path,
    output: &Path,
    memory_mib: Option<u64>,
    out_of_core: bool,
) -> anyhow::Result<()> {
    check_writable(output, &[input])?;
    let memory = memory_mib.map_or_else(convert_large::default_memory, |m| m << 20);
    let (out_of_core, points) = convert_large::wanted(input, memory, out_of_core)?;
    if out_of_core {
        convert_large::run(input, (output, points), memory)
    } else {
        let needed = points.saturating_mul(disk::FILE_BYTES_PER_POINT);
        disk::say_room(folder_of(output), needed, "the .spt file", false);
        run(input, output)
    }
}

/// Builds `input`'s tree in memory and writes it to `output`.
pub fn run(input: &Path, output: &Path) -> anyhow::Result<()> {
    let start = Instant::now();
    let set = ordered_from_file(input, &Steps::default())?;
    let points = set.meta.leaf_count;
    let scale = set.meta.error_scale;

    let bytes = file_bytes(&set.meta, &set.chunks);
    let stage = Stage::start("write", bytes, "bytes");
    write_ordered(output, &set, &|n| stage.advance(n))?;
    stage.finish(&format!(
        "{} ({:.1} MB, {:.0} MB/s)",
        output.display(),
        bytes as f64 / 1e6,
        rate(bytes as f64 / 1e6, stage.seconds())
    ));

    // Smallest non-zero and largest node error, without a copy of the errors.
    let (emin, emax) = set
        .records
        .par_iter()
        .map(|r| r.error(scale))
        .filter(|e| *e > 0.0)
        .fold(|| (f64::MAX, 0.0f64), |(a, b), e| (a.min(e), b.max(e)))
        .reduce(|| (f64::MAX, 0.0), |x, y| (x.0.min(y.0), x.1.max(y.1)));
    let total = start.elapsed().as_secs_f64();
    let record = std::mem::size_of::<NodeRecord>();
    let shape = std::mem::size_of::<SplatShape>();
    let attributes = if set.meta.has_attributes {
        std::mem::size_of::<PointAttributes>()
    } else {
        0
    };
    say!(
        "{} nodes ({} leaves, {} internal), depth {}, {} bytes per node ({record} record + \
         4 parent index + {shape} shape{})",
        count(set.meta.node_count),
        count(set.meta.leaf_count),
        count(set.meta.node_count - set.meta.leaf_count),
        set.meta.depth,
        record + 4 + shape + attributes,
        if attributes > 0 {
            format!(" + {attributes} LiDAR attributes")
        } else {
            String::new()
        }
    );
    if emax == 0.0 {
        say!("errors: all zero (a single leaf)");
    } else {
        say!("errors: {emin:.3e} to {emax:.3e} model units (error scale {scale:.6e})");
    }
    say!("{}", total_line(total, points));
    Ok(())
}
