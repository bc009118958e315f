//! `spt bench`'s results: one row per configuration, written as `results.csv` and
//! `summary.md`, each labelled with the adapter and the machine.

use std::fmt::Write as _;
use std::path::Path;

use super::measure::{Measured, PSNR_CAP_DB};
use crate::io::atomic::write_atomically;
use crate::render::Culling;

/// How a configuration chose its splats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Strategy {
    /// The sequential point tree's selection.
    Spt,
    /// A random subset of the leaves, as many as SPT drew.
    Random,
    /// Every leaf (ε = 0).
    NoLod,
}

impl Strategy {
    /// The name in the CSV, the tables and the plot.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Spt => "spt",
            Strategy::Random => "random",
            Strategy::NoLod => "no-lod",
        }
    }
}

/// The name of a culling strategy in the CSV, the tables and the plot.
pub fn culling_name(c: Culling) -> &'static str {
    match c {
        Culling::Compute => "compute",
        Culling::Vertex => "vertex",
    }
}

/// One measured configuration.
#[derive(Debug, Clone)]
pub struct Row {
    /// "orbit-near", "orbit-mid", "orbit-far" or "fly-through".
    pub path: String,
    pub strategy: Strategy,
    pub culling: Culling,
    pub eps_px: f64,
    pub cameras: usize,
    pub m: Measured,
}

/// Where the numbers come from: the adapter (name, backend, driver) and the machine.
#[derive(Debug, Clone)]
pub struct Environment {
    pub model: String,
    pub reference: &'static str,
    pub adapter: String,
    pub backend: String,
    pub driver: String,
    pub machine: String,
    pub date: String,
    pub size: (u32, u32),
    /// How the splat passes drew (`--raster`).
    pub raster: &'static str,
}

impl Environment {
    /// "adapter (backend, driver), raster path on machine, date".
    pub fn label(&self) -> String {
        format!(
            "{} ({}, {}), {} raster, on {}, {}",
            self.adapter, self.backend, self.driver, self.raster, self.machine, self.date
        )
    }
}

/// "N cores (CPU model), OS kernel", read from /proc where there is one.
pub fn machine() -> String {
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    format!("{cores} cores ({cpu}), {}", std::env::consts::OS)
}

fn opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| format!("{v:.3}"))
}

fn psnr(v: f64) -> String {
    if v >= PSNR_CAP_DB {
        "inf".into()
    } else {
        format!("{v:.2}")
    }
}

/// Quotes a CSV field when it needs it.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

pub fn write_csv(path: &Path, env: &Environment, rows: &[Row]) -> anyhow::Result<()> {
    let mut out = String::from(
        "model,path,strategy,culling,eps_px,cameras,splats,tested,gpu_ms_median,gpu_ms_p95,\
         wall_ms_median,psnr_db,hole_rate,spill_rate,flip,ssim,reference,width,height,adapter,backend,driver,\
         machine,date,raster\n",
    );
    for r in rows {
        let m = &r.m;
        writeln!(
            out,
            "{},{},{},{},{},{},{:.1},{:.1},{},{},{:.3},{},{:.6},{:.6},{:.5},{:.4},{},{},{},{},{},{},{},{},{}",
            field(&env.model),
            r.path,
            r.strategy.name(),
            culling_name(r.culling),
            r.eps_px,
            r.cameras,
            m.splats,
            m.tested,
            opt(m.gpu_ms_median),
            opt(m.gpu_ms_p95),
            m.wall_ms_median,
            psnr(m.psnr_db),
            m.hole_rate,
            m.spill_rate,
            m.flip,
            m.ssim,
            env.reference,
            env.size.0,
            env.size.1,
            field(&env.adapter),
            field(&env.backend),
            field(&env.driver),
            field(&env.machine),
            env.date,
            env.raster
        )?;
    }
    write_text(path, &out)
}

pub fn write_text(path: &Path, text: &str) -> anyhow::Result<()> {
    Ok(write_atomically(path, |w| w.write_all(text.as_bytes()))?)
}

/// The Markdown summary: one table per camera path, then the random-subset comparison
/// and the stability check.
pub fn summary(env: &Environment, rows: &[Row], checks: &[String]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "## `spt bench` on {}\n", env.model);
    let _ = writeln!(
        s,
        "{}×{}, error against the {}: PSNR, holes and spill against it at 1×, FLIP and SSIM \
         (means over the pixels either image covers) against it rendered at 4×4 the size and \
         averaged in linear light. Adapter: {}.\n",
        env.size.0,
        env.size.1,
        env.reference,
        env.label()
    );
    let mut paths: Vec<&str> = rows.iter().map(|r| r.path.as_str()).collect();
    paths.dedup();
    for path in paths {
        let _ = writeln!(s, "### {path}\n");
        let _ = writeln!(
            s,
            "| strategy | culling | ε px | splats | tested | GPU ms median | GPU ms p95 | wall ms | PSNR dB | holes | spill | FLIP | SSIM |"
        );
        let _ = writeln!(
            s,
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
        );
        for r in rows.iter().filter(|r| r.path == path) {
            let m = &r.m;
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.0} | {:.0} | {} | {} | {:.1} | {} | {:.3} % | {:.3} % | {:.4} | {:.3} |",
                r.strategy.name(),
                culling_name(r.culling),
                r.eps_px,
                m.splats,
                m.tested,
                opt(m.gpu_ms_median),
                opt(m.gpu_ms_p95),
                m.wall_ms_median,
                psnr(m.psnr_db),
                m.hole_rate * 100.0,
                m.spill_rate * 100.0,
                m.flip,
                m.ssim
            );
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(
        s,
        "### SPT against a random subset of leaves at equal splat counts\n"
    );
    let _ = writeln!(
        s,
        "| path | ε px | SPT splats | SPT FLIP | SPT PSNR dB | random splats | random FLIP | random PSNR dB | SPT better |"
    );
    let _ = writeln!(s, "| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for (spt, random) in equal_budget_pairs(rows) {
        let _ = writeln!(
            s,
            "| {} | {} | {:.0} | {:.4} | {} | {:.0} | {:.4} | {} | {} |",
            spt.path,
            spt.eps_px,
            spt.m.splats,
            spt.m.flip,
            psnr(spt.m.psnr_db),
            random.m.splats,
            random.m.flip,
            psnr(random.m.psnr_db),
            verdict(spt, random)
        );
    }
    let _ = writeln!(s);
    if !checks.is_empty() {
        let _ = writeln!(s, "### Stability\n");
        for c in checks {
            let _ = writeln!(s, "- {c}");
        }
        let _ = writeln!(s);
    }
    s
}

/// FLIP differences below this are reported as equal (when SPT draws every leaf, the
/// "subset" is all leaves and the images are the same but for blending order).
pub const EQUAL_FLIP: f64 = 2e-4;

/// "yes", "equal" or "**no**": whether SPT's FLIP is lower than the random subset's.
pub fn verdict(spt: &Row, random: &Row) -> &'static str {
    let d = random.m.flip - spt.m.flip;
    if d.abs() < EQUAL_FLIP {
        "equal"
    } else if d > 0.0 {
        "yes"
    } else {
        "**no**"
    }
}

/// Each random-subset row with the SPT row (compute culling) whose budget it matched.
pub fn equal_budget_pairs(rows: &[Row]) -> Vec<(&Row, &Row)> {
    rows.iter()
        .filter(|r| r.strategy == Strategy::Random)
        .filter_map(|random| {
            rows.iter()
                .find(|r| {
                    r.strategy == Strategy::Spt
                        && r.culling == Culling::Compute
                        && r.path == random.path
                        && r.eps_px == random.eps_px
                })
                .map(|spt| (spt, random))
        })
        .collect()
}

/// A row's frame time: the median GPU time, or the wall time where the adapter has no
/// timestamps.
pub fn frame_ms(row: &Row) -> f64 {
    row.m.gpu_ms_median.unwrap_or(row.m.wall_ms_median)
}

/// The fixed-frame-time path: for each budget (ms) and camera path, the SPT row
/// (compute culling) with the least FLIP among those whose frame time fits the budget
/// (None when no ε of the sweep does).
pub fn within_budgets<'a>(
    rows: &'a [Row],
    budgets: &[f64],
) -> Vec<(f64, &'a str, Option<&'a Row>)> {
    let mut paths: Vec<&str> = rows.iter().map(|r| r.path.as_str()).collect();
    paths.dedup();
    let mut out = Vec::new();
    for &budget in budgets {
        for &path in &paths {
            let best = rows
                .iter()
                .filter(|r| r.strategy == Strategy::Spt && r.culling == Culling::Compute)
                .filter(|r| r.path == path && frame_ms(r) <= budget)
                .min_by(|a, b| a.m.flip.total_cmp(&b.m.flip));
            out.push((budget, path, best));
        }
    }
    out
}

/// The fixed-frame-time table of summary.md.
pub fn budget_table(rows: &[Row], budgets: &[f64]) -> String {
    let mut s = String::from(
        "### FLIP within a frame-time budget\n\nFor each budget, the least FLIP of the sweep \
         (SPT, compute culling) among the ε whose median GPU time fits in it.\n\n\
         | budget ms | path | ε px | frame ms (GPU median) | splats | FLIP |\n| --- | --- | --- | --- | --- | --- |\n",
    );
    for (budget, path, best) in within_budgets(rows, budgets) {
        let _ = match best {
            Some(r) => writeln!(
                s,
                "| {budget} | {path} | {} | {:.1} | {:.0} | {:.4} |",
                r.eps_px,
                frame_ms(r),
                r.m.splats,
                r.m.flip
            ),
            None => writeln!(s, "| {budget} | {path} | none fits | | | |"),
        };
    }
    s.push('\n');
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::apps::bench::measure::Measured;

    fn row(eps_px: f64, gpu_ms: f64, flip: f64) -> Row {
        Row {
            path: "orbit-mid".into(),
            strategy: Strategy::Spt,
            culling: Culling::Compute,
            eps_px,
            cameras: 1,
            m: Measured {
                gpu_ms_median: Some(gpu_ms),
                flip,
                ..Measured::default()
            },
        }
    }

    #[test]
    fn a_budget_takes_the_least_flip_among_the_frames_that_fit() {
        let rows = [
            row(0.0, 300.0, 0.030),
            row(1.0, 150.0, 0.032),
            row(4.0, 60.0, 0.050),
        ];
        let found = within_budgets(&rows, &[50.0, 100.0, 200.0, 400.0]);
        let eps: Vec<Option<f64>> = found.iter().map(|f| f.2.map(|r| r.eps_px)).collect();
        assert_eq!(eps, [None, Some(4.0), Some(1.0), Some(0.0)]);
        assert!(budget_table(&rows, &[50.0]).contains("| 50 | orbit-mid | none fits |"));
    }
}
