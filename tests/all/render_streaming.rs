//! Drawing under a GPU memory budget: the
//! slices a view wants are streamed in, coarse first, the least recently wanted evicted;
//! the resident bytes never pass the budget, and a view whose slices do not all fit is
//! drawn at a coarser ε with no hole: the same picture as the whole list resident
//! drawn at that ε.

use crate::common;

use spt::render::{Camera, Renderer, Settings};
use spt::tree::scene::Scene;
use spt::tree::select::error_per_distance;

const SIZE: (u32, u32) = (256, 256);

/// Views of the knot: far, then two close-ups on opposite sides.
fn views(scene: &Scene) -> Vec<Camera> {
    [(30.0, 20.0, 2.2), (0.0, 10.0, 0.6), (180.0, -10.0, 0.6)]
        .into_iter()
        .map(|(azimuth, elevation, distance)| {
            Camera::orbit(
                scene.meta(),
                azimuth,
                elevation,
                distance,
                45f64.to_radians(),
            )
        })
        .collect()
}

fn stream_and_compare(renderer: &Renderer, scene: &Scene, budget: u64) -> usize {
    let (mut gpu, mut residency) = renderer.begin_streaming(scene, budget).unwrap();
    let whole = renderer.upload(scene);
    let settings = Settings::default();
    let mut coarsened = 0;
    for (k, camera) in views(scene).iter().enumerate() {
        renderer.stream_for_view(scene, (&mut gpu, &mut residency), camera, &settings, SIZE);
        assert!(gpu.resident_bytes() <= budget && residency.peak_bytes() <= budget);
        assert_eq!(gpu.resident_bytes(), residency.resident_bytes());
        let (image, stats) = renderer
            .render(scene, &gpu, camera, &settings, SIZE.0, SIZE.1)
            .unwrap();
        // The same view with the whole list resident, at the ε the streamed frame drew.
        let px = stats.eps / error_per_distance(1.0, camera.fov_y, SIZE.1);
        let same_eps = Settings {
            error_px: px,
            ..settings
        };
        let (reference, ref_stats) = renderer
            .render(scene, &whole, camera, &same_eps, SIZE.0, SIZE.1)
            .unwrap();
        let (values, coverage) = common::differences(&image, &reference);
        eprintln!(
            "budget {budget} B, view {k}: {}/{} slices, ε {px:.3} px{}, drawn {} (whole list at that ε: {}); \
             differing channel values {values}, coverage {coverage}",
            gpu.resident_slices(),
            gpu.planned_slices(),
            if stats.coarsened { " (coarser)" } else { "" },
            stats.selected,
            ref_stats.selected
        );
        assert!(stats.selected > 0);
        assert_eq!(stats.selected, ref_stats.selected, "view {k}: the same cut");
        assert!(
            values == 0 && coverage == 0,
            "view {k}: a streamed frame differs"
        );
        coarsened += stats.coarsened as usize;
    }
    coarsened
}

#[test]
fn a_streamed_view_is_the_whole_lists_view_at_its_epsilon_within_the_budget() {
    let renderer = common::renderer();
    let scene = Scene::open(&common::default_model()).unwrap();
    let whole = renderer.upload(&scene).resident_bytes();
    // A budget that holds everything: nothing coarsened.
    assert_eq!(stream_and_compare(renderer, &scene, 2 * whole), 0);
    // Budgets of two thirds and a quarter of the list: the close-ups evict, and views
    // whose slices do not fit are drawn coarser.
    assert!(
        stream_and_compare(renderer, &scene, whole * 2 / 3)
            + stream_and_compare(renderer, &scene, whole / 4)
            > 0
    );
}

#[test]
fn a_budget_below_the_coarsest_slice_is_refused() {
    let renderer = common::renderer();
    let scene = Scene::open(&common::default_model()).unwrap();
    let err = renderer
        .begin_streaming(&scene, 1000)
        .err()
        .expect("refused");
    assert!(
        err.to_string().contains("below the coarsest slice"),
        "{err}"
    );
}
