//! `spt convert` of a model file out of core ([`crate::tree::out_of_core`]): when
//! the in-memory build would not fit the memory budget (`--memory`, by default half of
//! the machine's memory), or when asked (`--out-of-core`). A progress bar per stage over
//! the points, then each stage's time and points/s, and the summary.

use std::path::Path;
use std::sync::Mutex;
use std::time::Instant;

use crate::apps::disk;
use crate::apps::progress::{Stage, total_line};
use crate::apps::text::{count, walls};
use crate::io::atomic::folder_of;
use crate::io::formats::ModelStream;
use crate::io::heap;
use crate::tree::out_of_core::{BYTES_PER_JOB_POINT, Built, Options, Progress, build_file};

/// Bytes per point the in-memory build takes at its peak on a cloud (measured: 14 M
/// points, 3.5 GiB).
const IN_MEMORY_BYTES_PER_POINT: u64 = 270;
/// Bytes per vertex the in-memory build takes at its peak on a mesh (measured: the
/// Lucy-size mesh, 14 M vertices, 1.80 GiB).
const IN_MEMORY_BYTES_PER_VERTEX: u64 = 140;

/// Half of the machine's memory (from /proc/meminfo), or 4 GiB where unknown.
pub fn default_memory() -> u64 {
    let total = std::fs::read_to_string("/proc/meminfo").ok().and_then(|s| {
        let line = s.lines().find(|l| l.starts_with("MemTotal:"))?;
        let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kib * 1024)
    });
    total.map_or(4 << 30, |t| t / 2)
}

/// Whether `input` should be built out of core within `memory` bytes: when asked, or
/// when the in-memory build would not fit (from the header's count alone: the file
/// may be larger than memory); and the points the header declares.
pub fn wanted(input: &Path, memory: u64, forced: bool) -> anyhow::Result<(bool, u64)> {
    let stream = ModelStream::open(input)?;
    let per_point = if stream.has_faces() {
        IN_MEMORY_BYTES_PER_VERTEX
    } else {
        IN_MEMORY_BYTES_PER_POINT
    };
    let points = stream.point_count();
    Ok((forced || points.saturating_mul(per_point) > memory, points))
}

/// Shows each stage of the build as a progress bar over its points, then its time and
/// points/s.
#[derive(Default)]
pub struct Bars {
    current: Mutex<Option<(Stage, u64)>>,
}

impl Bars {
    /// Ends the current stage's bar with its time and points/s.
    pub fn finish(&self) {
        self.finish_saying(&|total, seconds| match total {
            0 => String::new(),
            _ => format!("{:.2} M points/s", total as f64 / 1e6 / seconds.max(1e-9)),
        });
    }

    /// Ends the last stage, the write of `output`, with the file's size and rate.
    pub fn finish_written(&self, output: &Path) {
        let bytes = std::fs::metadata(output).map_or(0, |m| m.len()) as f64;
        self.finish_saying(&|_, seconds| {
            let rate = bytes / 1e6 / seconds.max(1e-9);
            format!(
                "{} ({:.1} MB, {rate:.0} MB/s)",
                output.display(),
                bytes / 1e6
            )
        });
    }

    /// Ends the current stage's bar with `summary` of its total points and seconds.
    fn finish_saying(&self, summary: &dyn Fn(u64, f64) -> String) {
        let current = self
            .current
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take();
        if let Some((stage, total)) = current {
            stage.finish(&summary(total, stage.seconds()));
        }
    }
}

impl Progress for Bars {
    fn stage(&self, name: &'static str, total: u64) {
        self.finish();
        let stage = Stage::start(name, total, "points");
        *self.current.lock().unwrap_or_else(|e| e.into_inner()) = Some((stage, total));
    }

    fn writing(&self, bytes: u64) {
        let current = self.current.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((stage, _)) = current.as_ref() {
            stage.measure(bytes, "bytes");
        }
    }

    fn rebuild(&self, reason: &str) {
        self.finish_saying(&|_, _| format!("not written: {reason}; the jobs are built again"));
    }

    fn advance(&self, points: u64) {
        if let Some((s, _)) = self
            .current
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .as_ref()
        {
            s.advance(points);
        }
    }
}

/// The options for a budget of `memory` bytes, the job files beside `output`; says the
/// budget and the jobs' size.
pub fn options(output: &Path, memory: u64) -> Options {
    let temp_dir = folder_of(output).to_owned();
    let options = Options::for_memory(memory, temp_dir);
    say!(
        "out of core: budget {:.2} GiB, jobs of at most {} points ({} bytes per point)",
        memory as f64 / (1u64 << 30) as f64,
        count(options.job_points),
        BYTES_PER_JOB_POINT
    );
    options
}

/// Freed memory is kept for the next job up to this share of the budget, in quarters
/// ([`heap::keep_freed_memory`]): the jobs are planned to peak at half of it.
const KEEP_FREED_QUARTERS: u64 = 3;

/// Keeps the memory that a job frees for the next, within a budget of `memory` bytes
/// ([`KEEP_FREED_QUARTERS`]). Call it before the jobs' threads first allocate.
pub fn keep_freed_memory_within(memory: u64) {
    heap::keep_freed_memory(memory / 4 * KEEP_FREED_QUARTERS);
}

/// Builds `input` (of `points`, as its header declares) out of core within `memory`
/// bytes and writes it to `output`.
pub fn run(input: &Path, (output, points): (&Path, u64), memory: u64) -> anyhow::Result<()> {
    let start = Instant::now();
    keep_freed_memory_within(memory);
    let options = options(output, memory);
    let needed = points.saturating_mul(disk::OUT_OF_CORE_BYTES_PER_POINT);
    disk::say_room(
        &options.temp_dir,
        needed,
        "the job files and the .spt file",
        true,
    );
    let bars = Bars::default();
    let built = build_file(input, output, &options, &bars)?;
    bars.finish_written(output);
    summary(&built, output, start);
    Ok(())
}

/// Prints what the build made, dropped, and its total time, rate, peak memory and CPU.
pub fn summary(built: &Built, output: &Path, start: Instant) {
    let m = &built.meta;
    let total = start.elapsed().as_secs_f64();
    let walls = walls(built.walls);
    say!(
        "{} nodes ({} leaves{walls}), depth {}, {} jobs, written to {}",
        count(m.node_count),
        count(m.leaf_count),
        m.depth,
        built.jobs,
        output.display()
    );
    if built.dropped + built.outliers > 0 {
        say!(
            "{} points dropped (not finite, or too far from the rest to store), {} outliers \
             kept outside the model's core",
            count(built.dropped),
            count(built.outliers)
        );
    }
    say!("{}", total_line(total, m.leaf_count));
}
