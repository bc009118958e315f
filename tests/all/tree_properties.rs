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
        let list = build_sequential_list(leaf_surfels(&cloud(&points)));
        prop_assert_eq!(list.meta.leaf_count as usize, points.len());
        common::assert_tree_invariants(&list, "random cloud");
        let view = TreeView::new(&list.meta, &list.nodes, &list.chunks);
        let stats = check_views(&view, &list.parents, &random_views(&list.meta, 40, 1.0, 100.0, seed));
        prop_assert_eq!(stats.holes, 0);
        prop_assert_eq!(stats.past_prefix, 0);
        check_bounds(&list, &random_views(&list.meta, 40, 1.0, 100.0, seed));
    }
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
    }
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
