//! Scripted interaction with the viewer: synthetic input events
//! go through the viewer's own handling (`Viewer::handle`, the function the window's
//! events reach), frames are drawn headless, and the statistics the panel shows are
//! checked: orbit, zoom, ε_px, display modes, freezing the level of detail, the up axis.

use crate::common;

use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use spt::apps::view::input::{Button, Command, Input, Move};
use spt::apps::view::loader::Loading;
use spt::apps::view::pacing::Pacer;
use spt::apps::view::viewer::Viewer;
use spt::io::up::UpAxis;
use spt::render::{Camera, Gpu, Mode, OrbitAxes, Renderer, Settings};

const SIZE: (u32, u32) = (320, 240);

fn renderer() -> Arc<Renderer> {
    static R: OnceLock<Arc<Renderer>> = OnceLock::new();
    R.get_or_init(|| {
        if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
            // SAFETY: set once, before any thread of this test binary reads it.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
        }
        Arc::new(Renderer::new(Gpu::new(None).expect("a GPU adapter")))
    })
    .clone()
}

/// A viewer with `model` opened through the background loader, framed as at start.
fn viewer_on(model: &std::path::Path) -> Viewer {
    let renderer = renderer();
    let (scene, gpu_scene) = Loading::start(model, renderer.clone(), || {})
        .wait()
        .expect("model loads");
    let camera = Camera::framed(
        scene.meta(),
        scene.index.chunks(),
        45f64.to_radians(),
        SIZE.0 as f64 / SIZE.1 as f64,
    );
    let mut viewer = Viewer::new(renderer, Settings::default());
    let axes = OrbitAxes::of(scene.meta());
    viewer.install(model.to_path_buf(), scene, gpu_scene, (&camera, axes));
    viewer
}

/// Draws a frame, waits for it, and returns (splats drawn, prefix, pixels).
fn frame(viewer: &mut Viewer) -> (u64, usize, Vec<u8>) {
    viewer.frame_and_wait(SIZE).expect("frame");
    let stats = &viewer.stats;
    let drawn = stats
        .gpu
        .drawn
        .expect("compute culling counts the splats drawn");
    let prefix = stats.frame.as_ref().expect("a frame was recorded").tested;
    assert!(drawn as usize <= prefix, "drawn {drawn} > prefix {prefix}");
    assert_eq!(stats.measured_tested, prefix, "counters of this very frame");
    (drawn, prefix, viewer.read_pixels().expect("pixels").2)
}

/// Mean absolute difference of two RGBA8 images, 0–255.
fn difference(a: &[u8], b: &[u8]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x as f64 - *y as f64).abs())
        .sum::<f64>()
        / a.len() as f64
}

fn send(viewer: &mut Viewer, input: Input) -> Option<Command> {
    viewer.handle(input, SIZE)
}

#[test]
fn orbit_zoom_error_and_modes_change_what_is_drawn() {
    let mut v = viewer_on(&common::default_model());
    let (drawn0, prefix0, image0) = frame(&mut v);
    assert!(drawn0 > 0);
    eprintln!("start: {drawn0} drawn, prefix {prefix0}");

    // Orbit: a 100 px drag to the right turns the camera 30° around the target.
    let before = v.model.as_ref().unwrap().camera;
    send(
        &mut v,
        Input::Drag {
            button: Button::Left,
            shift: false,
            dx: 100.0,
            dy: 0.0,
        },
    );
    let after = v.model.as_ref().unwrap().camera;
    let turned = (before.azimuth_deg - after.azimuth_deg).rem_euclid(360.0);
    assert!((turned - 30.0).abs() < 1e-9, "turned {turned}°");
    assert_eq!(after.distance, before.distance);
    let (_, _, image1) = frame(&mut v);
    let moved = difference(&image0, &image1);
    eprintln!("orbit: mean pixel change {moved:.2}");
    assert!(
        moved > 2.0,
        "the picture must change when orbiting ({moved})"
    );

    // ε_px larger: fewer splats; back: the same count again.
    let (drawn_1px, prefix_1px, _) = frame(&mut v);
    for _ in 0..4 {
        send(&mut v, Input::Command(Command::MoreError));
    }
    assert_eq!(v.settings.error_px, 16.0);
    let (drawn_16px, prefix_16px, _) = frame(&mut v);
    eprintln!(
        "ε 1 px: {drawn_1px} drawn (prefix {prefix_1px}); ε 16 px: {drawn_16px} (prefix {prefix_16px})"
    );
    assert!(drawn_16px * 2 < drawn_1px, "{drawn_16px} vs {drawn_1px}");
    assert!(prefix_16px < prefix_1px);

    // Zoom at ε 16 px: out draws fewer splats, back in draws more again.
    send(
        &mut v,
        Input::Wheel {
            notches: -8.0,
            x: 160.0,
            y: 120.0,
        },
    );
    let (drawn_far, _, _) = frame(&mut v);
    send(
        &mut v,
        Input::Wheel {
            notches: 16.0,
            x: 160.0,
            y: 120.0,
        },
    );
    let (drawn_near, _, _) = frame(&mut v);
    eprintln!("ε 16 px: zoomed out {drawn_far} drawn, zoomed in {drawn_near}");
    assert!(drawn_far < drawn_16px && drawn_16px < drawn_near);

    // Display modes: M cycles shaded → levels → normals → radius → edl → elevation →
    // points → mesh →
    // shaded (the knot has faces); each changes the picture.
    send(&mut v, Input::Command(Command::Reset));
    let (_, _, shaded) = frame(&mut v);
    for expected in [
        Mode::Levels,
        Mode::Normals,
        Mode::Radius,
        Mode::Edl,
        Mode::Elevation,
        Mode::Points,
        Mode::Mesh,
    ] {
        send(&mut v, Input::Command(Command::NextMode));
        assert_eq!(v.settings.mode, expected);
        v.frame_and_wait(SIZE).expect("frame");
        let pixels = v.read_pixels().unwrap().2;
        let d = difference(&shaded, &pixels);
        eprintln!("{expected:?}: mean pixel change {d:.2} from shaded");
        assert!(d > 1.0, "{expected:?} looks like shaded ({d})");
    }
    send(&mut v, Input::Command(Command::NextMode));
    assert_eq!(v.settings.mode, Mode::Shaded);

    // The window layer's own commands come back to it.
    assert_eq!(
        send(&mut v, Input::Command(Command::Screenshot)),
        Some(Command::Screenshot)
    );
    assert_eq!(
        send(&mut v, Input::Command(Command::Open)),
        Some(Command::Open)
    );
}

#[test]
fn freezing_the_level_of_detail_keeps_the_selection_while_moving() {
    let mut v = viewer_on(&common::default_model());
    v.settings.error_px = 8.0;
    let (_, prefix_at_start, _) = frame(&mut v);
    send(&mut v, Input::Command(Command::ToggleFreeze));
    assert!(v.settings.lod_eye.is_some());
    let (drawn_frozen, _, _) = frame(&mut v);
    // Zoom far out: a live level of detail would coarsen; a frozen one keeps its cut
    // (splats outside the view are culled, so compare the prefix).
    send(
        &mut v,
        Input::Wheel {
            notches: -10.0,
            x: 160.0,
            y: 120.0,
        },
    );
    let (_, prefix_frozen_far, _) = frame(&mut v);
    assert_eq!(prefix_frozen_far, prefix_at_start);
    send(&mut v, Input::Command(Command::ToggleFreeze));
    let (drawn_live_far, prefix_live_far, _) = frame(&mut v);
    eprintln!(
        "frozen: {drawn_frozen} drawn, prefix {prefix_at_start}; live, far: {drawn_live_far} drawn, prefix {prefix_live_far}"
    );
    assert!(prefix_live_far < prefix_at_start);
}

#[test]
fn held_keys_move_the_camera_and_frame_brings_the_model_back() {
    let mut v = viewer_on(&common::default_model());
    let start = v.camera().unwrap();
    send(&mut v, Input::Hold(Move::Forward, true));
    assert!(v.is_animating());
    v.advance(0.5);
    send(&mut v, Input::Hold(Move::Forward, false));
    assert!(!v.is_animating());
    let walked = v.camera().unwrap();
    let step = (walked.eye - start.eye).length();
    let distance = (start.eye - start.target).length();
    assert!(
        (step - 0.5 * distance).abs() < 1e-9 * distance,
        "{step} vs {distance}"
    );
    // Pan far away, then F frames the model again: everything drawn as at start.
    send(
        &mut v,
        Input::Drag {
            button: Button::Middle,
            shift: false,
            dx: 5000.0,
            dy: 0.0,
        },
    );
    let (drawn_away, _, _) = frame(&mut v);
    send(&mut v, Input::Command(Command::Frame));
    let (drawn_framed, _, _) = frame(&mut v);
    eprintln!("panned away: {drawn_away} drawn; framed: {drawn_framed}");
    assert_eq!(drawn_away, 0);
    assert!(drawn_framed > 0);
}

/// A held frame time with a scripted camera: under a frame-time target below what
/// the user's ε_px costs, moving frames are drawn coarser (fewer splats), and once the
/// camera rests the next frame is at the user's ε_px again, within a second.
#[test]
fn a_frame_time_target_coarsens_moving_frames_and_rest_brings_the_users_error_back() {
    let mut v = viewer_on(&common::default_model());
    let user_px = v.settings.error_px;
    // The first frame also builds pipelines: untimed. The target is a third of the
    // fastest of three resting frames, so that no frame at the user's ε can meet it.
    let (resting_drawn, _, _) = frame(&mut v);
    let resting_ms = (0..3)
        .map(|_| {
            let start = Instant::now();
            frame(&mut v);
            start.elapsed().as_secs_f64() * 1e3
        })
        .fold(f64::INFINITY, f64::min);
    v.pacer = Pacer::new(Some(resting_ms / 3.0));
    let mut moving_drawn = Vec::new();
    for _ in 0..12 {
        let drag = Input::Drag {
            button: Button::Left,
            shift: false,
            dx: 4.0,
            dy: 0.0,
        };
        send(&mut v, drag);
        moving_drawn.push(frame(&mut v).0);
        assert!(v.stats.frame_error_px >= user_px);
    }
    let moving_px = v.stats.frame_error_px;
    eprintln!(
        "resting: {resting_drawn} splats in {resting_ms:.1} ms; moving under a {:.1} ms \
         target: ε_px {moving_px:.2}, splats {moving_drawn:?}",
        resting_ms / 3.0
    );
    assert!(
        moving_px > user_px,
        "moving frames coarsened: ε_px {moving_px}"
    );
    assert!(*moving_drawn.last().unwrap() < resting_drawn);
    let rest = v
        .refine_due()
        .expect("a frame at the user's ε is due at rest");
    let last_move = Instant::now();
    assert!(rest.saturating_duration_since(last_move) <= Duration::from_secs(1));
    std::thread::sleep(rest.saturating_duration_since(Instant::now()));
    let (drawn, _, _) = frame(&mut v);
    assert_eq!(v.stats.frame_error_px, user_px, "at rest: the user's ε_px");
    assert!(!v.stats.frame.as_ref().unwrap().coarsened);
    let fewest = *moving_drawn.iter().min().unwrap();
    assert!(
        drawn > 2 * fewest,
        "{drawn} splats at rest, {fewest} moving"
    );
    assert!(v.refine_due().is_none());
}

#[test]
fn the_up_key_stands_the_model_on_the_next_axis_and_frames_it() {
    let mut v = viewer_on(&common::default_model());
    // The knot's file says z (a comment of its header).
    assert_eq!(v.model.as_ref().unwrap().up(), Some(UpAxis::Z));
    let (drawn0, _, image0) = frame(&mut v);
    send(&mut v, Input::Command(Command::NextUp));
    let m = v.model.as_ref().unwrap();
    assert_eq!(m.up(), Some(UpAxis::Y));
    assert_eq!(m.camera.camera().up, glam::DVec3::Y);
    let (drawn1, _, image1) = frame(&mut v);
    let changed = difference(&image0, &image1);
    eprintln!("up z → y: mean pixel change {changed:.2}, {drawn0} → {drawn1} drawn");
    assert!(
        drawn1 > 0 && changed > 2.0,
        "the model must turn ({changed})"
    );
    // Reset returns to the view framed on the new axis; the panel's choice sets one.
    send(&mut v, Input::Command(Command::Reset));
    assert_eq!(v.model.as_ref().unwrap().up(), Some(UpAxis::Y));
    send(&mut v, Input::Command(Command::SetUp(UpAxis::NegZ)));
    assert_eq!(v.model.as_ref().unwrap().up(), Some(UpAxis::NegZ));
}
