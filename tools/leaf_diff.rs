//! How far the leaves of two `.spt` files of the same points differ: for a change that
//! is meant to move the surfels by rounding only, or within a stated tolerance.
//!
//! Leaves (nodes without children) are matched by their position's bits; for each pair
//! it reports whether the record or the shape differs at all, the relative change of
//! the radius |r₁ − r₀| / r₀ and of the ellipse's area r² · ratio, the angle between the
//! normals and between the major axes (of ellipses with ratio < 0.95, where the axis is
//! defined): the share of leaves that changed at all and by more than 1 % (1°), the
//! 99.9th percentile and the largest.
//!
//! ```text
//! cargo run --release --example leaf_diff -- OLD.spt NEW.spt
//! ```

use std::collections::HashMap;
use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Parser;
use glam::DVec3;
use spt::apps::stats::quantile;
use spt::surfel::shape::SplatShape;
use spt::tree::record::NodeRecord;
use spt::tree::spt_file::SptFile;

#[derive(Parser)]
struct Args {
    old: PathBuf,
    new: PathBuf,
}

/// A leaf's record and shape.
type Leaf = (NodeRecord, SplatShape);

fn leaves(file: &SptFile) -> Vec<Leaf> {
    let mut has_children = vec![false; file.nodes().len()];
    for &p in file.parents() {
        if let Some(slot) = has_children.get_mut(p as usize) {
            *slot = true;
        }
    }
    (file.nodes().iter().zip(file.shapes()).zip(&has_children))
        .filter(|(_, parent)| !**parent)
        .map(|((r, s), _)| (*r, *s))
        .collect()
}

/// The changes of one matched pair: radius, area, normal angle, axis angle (degrees;
/// `None` where either ellipse is nearly round).
fn changes((r0, s0): &Leaf, (r1, s1): &Leaf) -> (f64, f64, f64, Option<f64>) {
    let relative = |a: f64, b: f64| if a > 0.0 { (b - a).abs() / a } else { b.abs() };
    let (n0, n1) = (r0.normal().as_dvec3(), r1.normal().as_dvec3());
    let (h0, h1) = (s0.unpack(n0), s1.unpack(n1));
    let area = |r: &NodeRecord, ratio: f64| (r.radius() as f64).powi(2) * ratio;
    // atan2 of the cross and dot products: exact for equal vectors, accurate near 0.
    let angle = |a: DVec3, b: DVec3| a.cross(b).length().atan2(a.dot(b).abs()).to_degrees();
    let axis = (h0.ratio < 0.95 && h1.ratio < 0.95).then(|| angle(h0.axis, h1.axis));
    (
        relative(r0.radius() as f64, r1.radius() as f64),
        relative(area(r0, h0.ratio), area(r1, h1.ratio)),
        angle(n0, n1),
        axis,
    )
}

/// One line of a change's distribution: how many changed at all and by more than
/// `notable`, its 99.9th percentile and its largest.
fn summary(name: &str, mut values: Vec<f64>, notable: f64) {
    let share = |n: usize| 100.0 * n as f64 / values.len().max(1) as f64;
    let changed = share(values.iter().filter(|v| **v > 0.0).count());
    let beyond = values.iter().filter(|v| **v > notable).count();
    let max = values.iter().copied().fold(0.0, f64::max);
    let p999 = quantile(&mut values, 0.999).unwrap_or(0.0);
    println!(
        "{name} of {}: {changed:.3} % changed, {beyond} by more than {notable}, \
         99.9th percentile {p999:.3e}, largest {max:.3e}",
        values.len()
    );
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let open = |p: &PathBuf| SptFile::open(p).with_context(|| format!("{}", p.display()));
    let (old, new) = (open(&args.old)?, open(&args.new)?);
    let (old, new) = (leaves(&old), leaves(&new));
    if old.len() != new.len() {
        bail!("{} leaves against {}", old.len(), new.len());
    }
    let by_position: HashMap<[u32; 3], &Leaf> = old.iter().map(|l| (l.0.position, l)).collect();
    let (mut radius, mut area, mut normal, mut axis) = (vec![], vec![], vec![], vec![]);
    let (mut unmatched, mut differ) = (0, 0);
    for leaf in &new {
        let Some(before) = by_position.get(&leaf.0.position) else {
            unmatched += 1;
            continue;
        };
        differ += (*before != leaf) as usize;
        let (r, a, n, u) = changes(before, leaf);
        radius.push(r);
        area.push(a);
        normal.push(n);
        axis.extend(u);
    }
    println!(
        "{} leaves, {unmatched} without a match by position, {differ} differ in record or shape",
        new.len()
    );
    summary("radius (relative)", radius, 0.01);
    summary("area r² · ratio (relative)", area, 0.01);
    summary("normal (degrees)", normal, 1.0);
    summary("major axis of ellipses (degrees)", axis, 1.0);
    Ok(())
}
