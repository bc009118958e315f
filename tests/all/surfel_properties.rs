//! Property tests: on random clouds and random meshes (duplicates, degenerate and
//! non-manifold triangles, any scale and offset), every surfel is finite with a unit
//! normal and a radius > 0, and every triangle is covered by its vertices' disks.

use crate::common;

use proptest::prelude::*;
use spt::io::ply::{FaceList, PolyMesh, read_ply};
use spt::surfel::leaf_surfels;

fn model() -> impl Strategy<Value = PolyMesh> {
    (
        prop::collection::vec(prop::array::uniform3(-1.0f64..1.0), 1..60),
        prop::collection::vec(0usize..80, 0..120),
        prop::collection::vec(prop::array::uniform3(0usize..80), 0..80),
        -7i32..=7,
        prop::sample::select(vec![0.0, 1e3, 1e7, -5e5]),
    )
        .prop_map(|(pool, picks, tris, exponent, offset)| {
            let scale = 10f64.powi(exponent);
            // Points drawn from a small pool repeat: duplicates are common.
            let mut positions: Vec<[f64; 3]> = pool.clone();
            positions.extend(picks.iter().map(|&k| pool[k % pool.len()]));
            for p in &mut positions {
                *p = p.map(|c| c * scale + offset);
            }
            let n = positions.len();
            let triangles: Vec<[u32; 3]> = tris.iter().map(|t| t.map(|k| (k % n) as u32)).collect();
            PolyMesh {
                positions,
                faces: FaceList::triangles(&triangles),
                ..PolyMesh::default()
            }
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn surfels_are_sane_and_cover_every_triangle(m in model()) {
        let dir = common::temp_dir();
        let path = dir.path().join("random.ply");
        common::write_double(&path, &m);
        let g = read_ply(&path).unwrap().geometry;
        let leaves = leaf_surfels(&g);
        prop_assert_eq!(leaves.surfels.len(), m.positions.len());
        common::assert_sane(&leaves, "random model");
        common::assert_covers(&g, &leaves, "random model");
    }
}
