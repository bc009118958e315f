//! Chunks on the GPU: on close-ups of the LiDAR tile, the nodes the GPU tests
//! (the visible chunks' prefixes) are at most 1.5 per splat that survives its culling
//! (3.4–4.3 with one list), and a chunked list draws the same picture as the same nodes
//! in one chunk.

use crate::common;

use spt::render::{Camera, Settings};
use spt::tree::chunks::Chunk;
use spt::tree::scene::Scene;

#[test]
fn terrain_close_ups_test_at_most_one_and_a_half_nodes_per_splat() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let scene = Scene::open(&dir.join("terrain_utm.ply")).unwrap();
    let r = common::renderer();
    let gpu = r.upload(&scene);
    let settings = Settings::default();
    for (az, el, dist) in [(30.0, 35.0, 1.0), (120.0, 30.0, 0.7), (250.0, 20.0, 0.8)] {
        let camera = Camera::orbit(scene.meta(), az, el, dist, 45f64.to_radians());
        let (_, stats) = r
            .render(&scene, &gpu, &camera, &settings, 512, 512)
            .unwrap();
        let survivors = stats.gpu_drawn.expect("compute culling counts survivors");
        let ratio = stats.tested as f64 / survivors as f64;
        eprintln!(
            "orbit {az},{el},{dist}: {} tested, {survivors} survivors: {ratio:.2}",
            stats.tested
        );
        assert!(
            ratio <= 1.5,
            "orbit {az},{el},{dist}: {ratio:.2} nodes per survivor"
        );
    }
}

#[test]
fn chunks_draw_what_one_list_draws() {
    let chunked = Scene::open(&common::default_model()).unwrap();
    let mut list = match &chunked.tree {
        spt::tree::scene::TreeSource::Memory(l) => l.clone(),
        spt::tree::scene::TreeSource::File(f) => f.to_list(),
    };
    assert!(list.chunks.len() > 10);
    // The same nodes as one chunk: sorted by parent error as one list.
    let mut order: Vec<usize> = (0..list.nodes.len()).collect();
    order.sort_by_key(|&i| (std::cmp::Reverse(list.nodes[i].parent_error), i));
    let mut position = vec![0u32; order.len()];
    for (k, &i) in order.iter().enumerate() {
        position[i] = k as u32;
    }
    list.parents = order
        .iter()
        .map(|&i| match list.parents[i] {
            u32::MAX => u32::MAX,
            p => position[p as usize],
        })
        .collect();
    list.nodes = order.iter().map(|&i| list.nodes[i]).collect();
    list.shapes = order.iter().map(|&i| list.shapes[i]).collect();
    list.chunks = vec![Chunk::of(0, &list.nodes)];
    let single = Scene::from_list(list, None);
    let r = common::renderer();
    let settings = Settings::default();
    for az in [0.0, 120.0] {
        let camera = Camera::orbit(chunked.meta(), az, 20.0, 1.2, 45f64.to_radians());
        let (a, sa) = r
            .render(&chunked, &r.upload(&chunked), &camera, &settings, 256, 256)
            .unwrap();
        let (b, sb) = r
            .render(&single, &r.upload(&single), &camera, &settings, 256, 256)
            .unwrap();
        assert_eq!(
            sa.gpu_drawn, sb.gpu_drawn,
            "azimuth {az}: the same splats survive"
        );
        assert!(
            sa.tested < sb.tested,
            "azimuth {az}: {} vs {}",
            sa.tested,
            sb.tested
        );
        let differ = common::differences(&a, &b).0;
        eprintln!(
            "azimuth {az}: {} vs {} tested; {differ} channel values differ by > 2",
            sa.tested, sb.tested
        );
        assert!(
            differ * 1000 <= a.rgba.len(),
            "azimuth {az}: {differ} values differ"
        );
    }
}
