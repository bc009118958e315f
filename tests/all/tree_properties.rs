//! Sequential point trees on random point sets and real models: errors monotone toward
//! the root, parent errors bit-identical, the list sorted, and for random views and
//! ε_px from 0 to 100 every leaf has a drawn ancestor-or-self and no drawn node lies
//! outside the CPU's ranges (each chunk's prefix), the prefixes bounded from the index
//! alone hold them, and the nodes the GPU tests are at most 1.5 per node drawn.

use crate::common;

use glam::Vec3;
use proptest::prelude::*;
use spt::io::Geometry;
use spt::io::ply::read_ply;
use spt::surfel::leaf_surfels;
use spt::tree::build_sequential_list;
use spt::tree::select::{BLOCK, TreeView, check_views, random_views, tested};

fn cloud(points: &[[f64; 3]]) -> Geometry {
    let mut g = common::geometry_of(points);
    g.triangles.clear();
    g
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_point_sets(
        pool in prop::collection::vec(prop::array::uniform3(-1.0f64..1.0), 1..300),
        repeats in prop::collection::vec(0usize..400, 0..100),
        exponent in -7i32..=7,
        seed in 1u64..u64::MAX,
    ) {
        let scale = 10f64.powi(exponent);
        let distinct: Vec<[f64; 3]> = pool.iter().map(|p| p.map(|c| c * scale)).collect();
        let mut points = distinct.clone();
        points.extend(repeats.iter().map(|&k| distinct[k % distinct.len()]));
        check_cloud(&points, seed)?;
    }
}

/// A flat set of four (three of them on a line) takes the terrain path, whose long
/// triangles add two splats to its four leaves (proptest found it).
#[test]
fn a_flat_set_s_long_triangles_add_leaves() {
    let points = [
        [0.0, -0.26138929817625256, 0.0],
        [0.0, -0.8567534749055895, 0.0],
        [0.0, 0.8422036962889449, 0.0],
        [0.6975049437658696, 0.0, 0.390660997458884],
    ];
    check_cloud(&points, 1).unwrap();
}

/// The tree of `points` as a cloud: a leaf per point and per added splat, its
/// invariants, and 40 random views (from `seed`) drawn without holes within the
/// prefixes and their bounds.
fn check_cloud(points: &[[f64; 3]], seed: u64) -> Result<(), TestCaseError> {
    // A flat set takes the terrain path, whose long triangles add splats.
    let leaves = leaf_surfels(&cloud(points));
    let added = leaves.stats.added_splats() as usize;
    let list = build_sequential_list(leaves);
    prop_assert_eq!(list.meta.leaf_count as usize, points.len() + added);
    common::assert_tree_invariants(&list, "random cloud");
    let view = TreeView::new(&list.meta, &list.nodes, &list.chunks);
    let views = random_views(&list.meta, 40, 1.0, 100.0, seed);
    let stats = check_views(&view, &list.parents, &views);
    prop_assert_eq!(stats.holes, 0);
    prop_assert_eq!(stats.past_prefix, 0);
    check_bounds(&list, &views);
    Ok(())
}

/// The prefix bounds from the index alone (what a streamed file's frame searches with)
/// hold the exact ranges, and exceed them by less than a block per chunk.
fn check_bounds(list: &spt::tree::SequentialList, views: &[(glam::DVec3, f64)]) {
    let view = TreeView::new(&list.meta, &list.nodes, &list.chunks);
    for &(eye, eps) in views {
        let exact = view.index.ranges(&list.nodes, eye, eps, None);
        let bound = view.index.ranges_bound(eye, eps, None);
        let mut inside = vec![false; list.nodes.len()];
        for r in &bound {
            inside[r.clone()].fill(true);
        }
        assert!(exact.iter().all(|r| inside[r.clone()].iter().all(|&b| b)));
        let (e, b) = (tested(&exact), tested(&bound));
        assert!(b < e + BLOCK * list.chunks.len().max(1), "{b} against {e}");
        // The searches of a frame, run in lockstep, end where each chunk's own does.
        for (c, chunk) in list.chunks.iter().enumerate() {
            let within = overlap(&exact, chunk.range());
            if within > 0 {
                assert_eq!(within, view.index.chunk_prefix(c, &list.nodes, eye, eps));
            }
        }
        check_fit(&view, eye, eps);
    }
}

/// Nodes of `ranges` within `r`.
fn overlap(ranges: &[std::ops::Range<usize>], r: std::ops::Range<usize>) -> usize {
    let overlap =
        |q: &std::ops::Range<usize>| q.end.min(r.end).saturating_sub(q.start.max(r.start));
    ranges.iter().map(overlap).sum()
}

/// With a third of each chunk loaded (and its first block, which holds a root's
/// infinite parent error), the least fitting ε's prefix bounds lie in it, and just
/// below that ε they do not (unless it is the asked one). Chunks the eye is within reach
/// of need more at any ε; they are left out. The wanted ranges lie in the same units of
/// loading as the asked prefixes.
fn check_fit(view: &TreeView, eye: glam::DVec3, eps: f64) {
    let chunks = view.index.chunks();
    let loaded = |_start: usize, count: usize| (count / 3).max(BLOCK);
    let fitting = |e: f64| {
        let bounds = view.index.ranges_bound(eye, e, None);
        let fit = |c: &spt::tree::chunks::Chunk| {
            overlap(&bounds, c.range()) <= loaded(0, c.count as usize)
        };
        chunks.iter().map(fit).collect::<Vec<bool>>()
    };
    let ever = fitting(1e300);
    let fits = |e: f64| {
        fitting(e)
            .iter()
            .zip(&ever)
            .all(|(&now, &ever)| now || !ever)
    };
    // A unit of loading that is not a multiple of the block, so that slice boundaries
    // fall inside blocks.
    let unit = 3 * BLOCK / 2 + 7;
    let fit = view.index.fit(eye, eps, None, unit, loaded);
    assert!(fit.eps >= eps);
    assert!(
        fits(fit.eps),
        "ε {eps} raised to {}: the bounds do not fit",
        fit.eps
    );
    if fit.eps > eps * (1.0 + 1e-6) {
        assert!(
            !fits(fit.eps * (1.0 - 1e-6)),
            "ε {} is not the least that fits",
            fit.eps
        );
    }
    let units = |ranges: &[std::ops::Range<usize>]| {
        let mut k: Vec<usize> = ranges
            .iter()
            .flat_map(|r| r.start / unit..(r.end - 1) / unit + 1)
            .collect();
        k.dedup();
        k
    };
    let asked = view.index.ranges_bound(eye, eps, None);
    assert_eq!(units(&fit.wanted), units(&asked), "ε {eps}: wanted units");
}

fn check_model(g: &Geometry, what: &str, views: usize) {
    let list = build_sequential_list(leaf_surfels(g));
    common::assert_tree_invariants(&list, what);
    let view = TreeView::new(&list.meta, &list.nodes, &list.chunks);
    let stats = check_views(
        &view,
        &list.parents,
        &random_views(&list.meta, views, 1.0, 100.0, 7),
    );
    check_bounds(&list, &random_views(&list.meta, views, 1.0, 100.0, 7));
    assert_eq!(stats.holes, 0, "{what}: {stats:?}");
    assert_eq!(stats.past_prefix, 0, "{what}: {stats:?}");
    assert!(stats.drawn_per_leaf_path >= 1.0, "{what}: {stats:?}");
    eprintln!(
        "{what}: {} chunks, {:.2} nodes tested per node drawn; {stats:?}",
        list.chunks.len(),
        stats.tested_per_drawn()
    );
    // With chunks, the GPU tests at most 1.5 nodes per node drawn (4 with
    // one list on the bunny's views).
    assert!(stats.tested_per_drawn() <= 1.5, "{what}: {stats:?}");
}

#[test]
fn default_model_selection_is_hole_free() {
    let g = read_ply(&common::default_model()).unwrap().geometry;
    check_model(&g, "torus knot", 200);
}

#[test]
fn bunny_selection_over_1000_views() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let g = read_ply(&dir.join("bunny.ply")).unwrap().geometry;
    check_model(&g, "bunny", 1000);
}

#[test]
fn leaves_only_and_root_only() {
    let g = read_ply(&common::default_model()).unwrap().geometry;
    let list = build_sequential_list(leaf_surfels(&g));
    let view = TreeView::new(&list.meta, &list.nodes, &list.chunks);
    let eye = Vec3::new(0.0, 0.0, 40.0).as_dvec3();
    // ε = 0: exactly the leaves are drawn.
    let sel = view.select(eye, 0.0);
    assert_eq!(sel.drawn.len() as u64, list.meta.leaf_count);
    // A huge ε: only the root.
    let sel = view.select(eye, 1e9);
    assert_eq!(sel.drawn, vec![0]);
    assert_eq!(sel.tested(), 1);
}
