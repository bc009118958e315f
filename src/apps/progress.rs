//! Stage progress for long commands: a bar on a terminal (stderr), and one plain line
//! per finished stage on stdout either way, so logs and pipes get the same summary.
//! The line ends with the stage's CPU time and how many of the thread pool's threads
//! it kept busy on average (CPU time over wall time): a stage that leaves cores idle
//! shows.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::apps::stats::{peak_memory_bytes, process_cpu_seconds};

/// One stage of a command.
pub struct Stage {
    name: &'static str,
    bar: ProgressBar,
    done: AtomicU64,
    start: Instant,
    /// The process's CPU seconds when the stage started.
    cpu_start: Option<f64>,
}

impl Stage {
    /// A stage whose amount of work is known (`total` in `unit`), or a spinner when 0.
    pub fn start(name: &'static str, total: u64, unit: &'static str) -> Stage {
        let target = if std::io::stderr().is_terminal() {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        };
        let bar = if total > 0 {
            let bar = ProgressBar::with_draw_target(Some(total), target);
            bar.set_style(bar_style(unit));
            bar
        } else {
            let bar = ProgressBar::with_draw_target(None, target);
            bar.set_style(ProgressStyle::with_template("{prefix:>8} {spinner} {elapsed}").unwrap());
            bar.enable_steady_tick(Duration::from_millis(100));
            bar
        };
        bar.set_prefix(name);
        Stage {
            name,
            bar,
            done: AtomicU64::new(0),
            start: Instant::now(),
            cpu_start: process_cpu_seconds(),
        }
    }

    /// From now on, a bar of `total` units of work (a spinner until then), none done
    /// yet; the stage keeps its start.
    pub fn measure(&self, total: u64, unit: &'static str) {
        self.bar.disable_steady_tick();
        self.done.store(0, Ordering::Relaxed);
        self.bar.set_style(bar_style(unit));
        self.bar.set_length(total);
        self.bar.set_position(0);
    }

    /// Adds `n` units of work done (callable from any thread).
    pub fn advance(&self, n: u64) {
        let done = self.done.fetch_add(n, Ordering::Relaxed) + n;
        self.bar.set_position(done);
    }

    /// Ends the stage without a line: its bar cleared, for a command whose standard
    /// output is a report of its own.
    pub fn clear(&self) {
        self.bar.finish_and_clear();
    }

    /// Seconds since the stage started.
    pub fn seconds(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// Ends the stage and prints `name  seconds  summary; CPU-s, threads busy` (without
    /// the "; " where the summary is empty); returns the time it took.
    pub fn finish(&self, summary: &str) -> Duration {
        let took = self.start.elapsed();
        self.bar.finish_and_clear();
        let busy = self
            .cpu_start
            .zip(process_cpu_seconds())
            .map_or(String::new(), |(start, now)| {
                busy_threads(now - start, took.as_secs_f64())
            });
        let busy = match summary.is_empty() {
            true => busy.trim_start_matches("; "),
            false => &busy,
        };
        say!(
            "{:>8}  {:>7.2} s  {summary}{busy}",
            self.name,
            took.as_secs_f64()
        );
        took
    }
}

/// The unit of a stage whose work is counted in bytes, which its bar shows in kB, MB
/// or GB.
pub const BYTES: &str = "bytes";

/// A bar's look: `name [====>    ] done/total unit elapsed ETA left` (in bytes: `done
/// MB/total MB`).
fn bar_style(unit: &str) -> ProgressStyle {
    let counts = match unit {
        BYTES => "{bytes}/{total_bytes}".to_string(),
        _ => format!("{{human_pos}}/{{human_len}} {unit}"),
    };
    let template = format!("{{prefix:>8}} [{{bar:40}}] {counts} {{elapsed}} ETA {{eta}}");
    ProgressStyle::with_template(&template)
        .unwrap()
        .progress_chars("=> ")
}

/// A build's last line: "total 18.03 s, 0.78 M points/s, peak memory 2.03 GiB; 32.5
/// CPU-s, 1.8 of 2 threads busy" for `points` built in `total` seconds (the memory and
/// CPU where the system tells them).
pub fn total_line(total: f64, points: u64) -> String {
    let peak = peak_memory_bytes().map_or(String::new(), |b| {
        format!(", peak memory {:.2} GiB", b as f64 / (1u64 << 30) as f64)
    });
    let busy = process_cpu_seconds().map_or(String::new(), |cpu| busy_threads(cpu, total));
    format!(
        "total {total:.2} s, {:.2} M points/s{peak}{busy}",
        points as f64 / 1e6 / total.max(1e-9)
    )
}

/// Wall times shorter than this say nothing of the threads busy: the CPU clock counts in
/// ticks of the scheduler, and a stage of a few milliseconds read "2.3 of 2 threads".
const MIN_BUSY_WALL_S: f64 = 0.1;

/// "; 22.1 CPU-s, 1.9 of 2 threads busy": `cpu` seconds of CPU over `wall` seconds, and
/// the threads of the pool that the parallel work runs on; the CPU time alone where
/// `wall` is under [`MIN_BUSY_WALL_S`].
fn busy_threads(cpu: f64, wall: f64) -> String {
    if wall < MIN_BUSY_WALL_S {
        return format!("; {cpu:.1} CPU-s");
    }
    format!(
        "; {cpu:.1} CPU-s, {:.1} of {} threads busy",
        cpu / wall,
        rayon::current_num_threads()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threads_busy_are_told_only_over_a_measurable_wall_time() {
        assert_eq!(busy_threads(0.03, 0.01), "; 0.0 CPU-s");
        let told = busy_threads(3.6, 2.0);
        assert!(told.starts_with("; 3.6 CPU-s, 1.8 of "), "{told}");
        assert!(told.ends_with(" threads busy"), "{told}");
    }
}
