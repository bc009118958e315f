//! Trees of hard inputs build, terminate and are sane: many identical points, collinear
//! points, a flat grid, tiny and huge scales (same relative errors), one and two points.

use crate::common;

use glam::DVec3;
use spt::io::ply::read_ply;
use spt::surfel::leaf_surfels;
use spt::tree::select::{TreeView, check_views, random_views};
use spt::tree::{SequentialList, build_sequential_list};

fn tree_of(points: &[[f64; 3]], what: &str) -> SequentialList {
    let list = build_sequential_list(leaf_surfels(&common::geometry_of(points)));
    assert_eq!(list.meta.leaf_count as usize, points.len(), "{what}");
    common::assert_tree_invariants(&list, what);
    // Every internal node has at least two children: fewer internal nodes than leaves.
    assert!(
        list.meta.node_count < 2 * list.meta.leaf_count.max(1),
        "{what}: {} nodes",
        list.meta.node_count
    );
    let view = TreeView::new(&list.meta, &list.nodes, &list.chunks);
    let stats = check_views(
        &view,
        &list.parents,
        &random_views(&list.meta, 20, 1.0, 100.0, 3),
    );
    assert_eq!(
        (stats.holes, stats.past_prefix),
        (0, 0),
        "{what}: {stats:?}"
    );
    list
}

/// Depth stays logarithmic: at most 2·log2(n)/log2(16/15)... in practice far less;
/// assert a bound that a linear-depth build would break.
fn assert_shallow(list: &SequentialList, what: &str) {
    let n = list.meta.leaf_count as f64;
    let bound = 4.0 * n.log2().max(1.0) + 4.0;
    assert!(
        (list.meta.depth as f64) <= bound,
        "{what}: depth {} for {n} leaves",
        list.meta.depth
    );
}

#[test]
fn two_hundred_thousand_identical_points() {
    let list = tree_of(&vec![[3.0, -2.0, 1e6]; 200_000], "identical");
    assert_shallow(&list, "identical");
}

#[test]
fn hundred_thousand_collinear_points() {
    let pts: Vec<[f64; 3]> = (0..100_000)
        .map(|i| [i as f64 * 1e-3, 2.0 * i as f64 * 1e-3, -(i as f64) * 1e-3])
        .collect();
    let list = tree_of(&pts, "collinear");
    assert_shallow(&list, "collinear");
}

#[test]
fn exponentially_spaced_points_keep_a_shallow_tree() {
    // Midpoint splits would peel one point per level here.
    let pts: Vec<[f64; 3]> = (0..1000)
        .map(|i| [0.5f64.powi(i % 60) + i as f64 * 1e-12, 0.0, 0.0])
        .collect();
    let list = tree_of(&pts, "exponential");
    assert_shallow(&list, "exponential");
}

#[test]
fn flat_grid() {
    let pts: Vec<[f64; 3]> = (0..250 * 250)
        .map(|i| [(i % 250) as f64, (i / 250) as f64, 0.0])
        .collect();
    let list = tree_of(&pts, "grid");
    assert_shallow(&list, "grid");
    // A flat grid has no perpendicular error: only tangential overhang.
    for r in &list.nodes {
        assert!(r.normal().z.abs() > 0.9999, "normal {:?}", r.normal());
    }
}

#[test]
fn single_point_and_two_points() {
    let one = tree_of(&[[1.0, 2.0, 3.0]], "one point");
    assert_eq!(one.meta.node_count, 1);
    assert_eq!(one.nodes[0].error, 0);
    let two = tree_of(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], "two points");
    assert_eq!(two.meta.node_count, 3);
    assert!(two.nodes[0].error > 0, "the root of two disks has an error");
}

/// The default model scaled by `s`: the same tree, with the same errors relative to
/// the model's size.
fn same_relative_errors(s: f64) {
    let g = read_ply(&common::default_model()).unwrap().geometry;
    let base = build_sequential_list(leaf_surfels(&g));
    let pts: Vec<[f64; 3]> = common::to_mesh(&g)
        .positions
        .iter()
        .map(|p| p.map(|c| c * s))
        .collect();
    let mut scaled_g = common::geometry_of(&pts);
    scaled_g.triangles = g.triangles.clone();
    let scaled = build_sequential_list(leaf_surfels(&scaled_g));
    common::assert_tree_invariants(&scaled, "scaled");
    assert_eq!(scaled.meta.node_count, base.meta.node_count);
    assert_eq!(scaled.meta.depth, base.meta.depth);
    let rel = |l: &SequentialList| -> Vec<f64> {
        let size = (DVec3::from(l.meta.bounds.max) - DVec3::from(l.meta.bounds.min)).max_element();
        let mut e: Vec<f64> = l
            .nodes
            .iter()
            .map(|r| r.error(l.meta.error_scale) / size)
            .collect();
        e.sort_by(f64::total_cmp);
        e
    };
    let (a, b) = (rel(&base), rel(&scaled));
    let mut worst = 0.0f64;
    for (x, y) in a.iter().zip(&b) {
        if *x > 0.0 {
            worst = worst.max((y / x - 1.0).abs());
        }
    }
    // Half floats carry 11 bits: two steps apart at most.
    assert!(
        worst < 2e-3,
        "scale {s:e}: relative errors differ by {worst:e}"
    );
}

#[test]
fn scaled_by_1e_minus_7_has_the_same_relative_errors() {
    same_relative_errors(1e-7);
}

#[test]
fn scaled_by_1e7_has_the_same_relative_errors() {
    same_relative_errors(1e7);
}
