//! The viewer without its window: the model on the GPU, the camera, the display
//! settings and the statistics; it takes [`Input`]s and records frames into an encoder.
//! The window layer (`app.rs`) adds the surface, the panel and the event loop; tests
//! drive this directly.

use crate::io::up::UpAxis;
use std::collections::{HashSet, VecDeque};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::controls::OrbitCamera;
use super::input::{Button, Command, Input, Move};
pub use super::pacing::ERROR_PX_RANGE;
use super::pacing::Pacer;
use super::streamer::Streamer;
use crate::render::camera::bounding_sphere;
use crate::render::residency::Residency;
use crate::render::{
    Camera, CounterReadback, EncodedFrame, FrameTargets, GpuCounters, GpuScene, MeshUpload, Mode,
    OrbitAxes, Renderer, Settings, SliceUpload,
};
use crate::render::{GpuInstances, SceneMemory};
use crate::tree::TreeMeta;
use crate::tree::chunks::Chunk;
use crate::tree::instances::InstancedScene;
use crate::tree::scene::Scene;

/// What the viewer draws: one model's list, or a scene of instances.
pub enum Content {
    One {
        scene: Arc<Scene>,
        /// The list on the GPU: a prefix of it while the model uploads.
        gpu_scene: GpuScene,
        /// Under a GPU memory budget: what streams the list's slices in and out.
        streamer: Option<Box<Streamer>>,
    },
    Many {
        scene: Arc<InstancedScene>,
        gpu: GpuInstances,
        /// The scene's box as one chunk, to frame it.
        frame: [Chunk; 1],
        /// Instances the last frame planned on the CPU, and the test ranges they
        /// handed over; far instances the GPU placed (read a few frames late).
        visible: usize,
        ranges: usize,
        far_visible: usize,
    },
}

impl Content {
    /// The GPU lists whose counters a frame reads.
    fn gpu_scenes(&self) -> Vec<&GpuScene> {
        match self {
            Content::One { gpu_scene, .. } => vec![gpu_scene],
            Content::Many { gpu, .. } => gpu.models.iter().collect(),
        }
    }
}

/// A model (or a scene) ready to draw.
pub struct Model {
    pub path: PathBuf,
    pub content: Content,
    /// Seconds from the request to open it to all of it on the GPU (None while uploading).
    pub load_seconds: Option<f64>,
    counters: CounterReadback,
    pub camera: OrbitCamera,
    home: OrbitCamera,
}

impl Model {
    /// What the model (or the whole scene) is, as one model's header would say.
    pub fn meta(&self) -> &TreeMeta {
        match &self.content {
            Content::One { scene, .. } => scene.meta(),
            Content::Many { scene, .. } => &scene.meta,
        }
    }

    /// The chunks a camera is framed on.
    pub fn chunks(&self) -> &[Chunk] {
        match &self.content {
            Content::One { scene, .. } => scene.index.chunks(),
            Content::Many { frame, .. } => frame,
        }
    }

    /// Nodes of the model, or of all the scene's models.
    pub fn node_count(&self) -> u64 {
        match &self.content {
            Content::One { scene, .. } => scene.nodes().len() as u64,
            Content::Many { scene, .. } => {
                scene.models.iter().map(|m| m.nodes().len() as u64).sum()
            }
        }
    }

    /// Triangles of the mesh reference (0 without one, and for a scene).
    pub fn mesh_triangles(&self) -> u32 {
        match &self.content {
            Content::One { gpu_scene, .. } => gpu_scene.mesh_triangles(),
            Content::Many { .. } => 0,
        }
    }

    /// What streams the list under a GPU memory budget.
    pub fn streamer(&self) -> Option<&Streamer> {
        match &self.content {
            Content::One { streamer, .. } => streamer.as_deref(),
            Content::Many { .. } => None,
        }
    }

    /// A scene's memory: the GPU's by what it is for, and the CPU bytes an instance
    /// costs.
    pub fn scene_memory(&self) -> Option<(SceneMemory, u64)> {
        match &self.content {
            Content::One { .. } => None,
            Content::Many { scene, gpu, .. } => Some((gpu.memory(), scene.bytes_per_instance())),
        }
    }

    /// A scene's instances: in all, drawn by the last frame, and the test ranges they
    /// handed over.
    pub fn instances(&self) -> Option<(usize, usize, usize)> {
        match &self.content {
            Content::One { .. } => None,
            Content::Many {
                scene,
                visible,
                far_visible,
                ranges,
                ..
            } => Some((scene.instances.len(), visible + far_visible, *ranges)),
        }
    }

    /// The axis the model stands on; `None` for a sensor frame seen as its sensor saw it.
    pub fn up(&self) -> Option<UpAxis> {
        UpAxis::ALL
            .into_iter()
            .find(|a| self.camera.axes == OrbitAxes::about(*a))
    }
}

/// What the panel shows of the recent frames.
#[derive(Debug, Clone, Default)]
pub struct Stats {
    /// Frames presented in the last second.
    pub fps: f64,
    /// CPU time to choose the prefix and record the frame's passes, ms.
    pub cpu_ms: f64,
    /// The newest GPU measurement (a few frames late), and its frame's prefix.
    pub gpu: GpuCounters,
    pub measured_tested: usize,
    /// The frame just recorded (prefix, ε, whether it was coarsened while uploading).
    pub frame: Option<EncodedFrame>,
    /// The ε_px that frame was asked for: the user's, or the pacer's while moving.
    pub frame_error_px: f64,
    /// The next frame is a scene's first, drawn as a preview; the frame just recorded
    /// was one ([`PREVIEW_COARSER`]).
    preview_next: bool,
    pub preview: bool,
    recent: VecDeque<Instant>,
}

/// A scene's first frame is a preview at this many times the user's ε_px (about 1/16
/// of the splats: on lavapipe, a forest of 10⁵ trees in well under a second instead of
/// five); the frame at the user's ε follows at once.
pub const PREVIEW_COARSER: f64 = 4.0;

impl Stats {
    /// Takes the counters of a frame that arrived, if one did.
    fn took(&mut self, arrived: Option<(EncodedFrame, GpuCounters)>) {
        if let Some((frame, counters)) = arrived {
            self.gpu = counters;
            self.measured_tested = frame.tested + counters.far.map_or(0, |f| f.tested as usize);
        }
    }

    fn frame_presented(&mut self, now: Instant) {
        self.recent.push_back(now);
        while self
            .recent
            .front()
            .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(1))
        {
            self.recent.pop_front();
        }
        let span = now.duration_since(*self.recent.front().expect("just pushed"));
        self.fps = if self.recent.len() > 1 {
            (self.recent.len() - 1) as f64 / span.as_secs_f64()
        } else {
            0.0
        };
    }
}

pub struct Viewer {
    pub renderer: Arc<Renderer>,
    pub model: Option<Model>,
    pub settings: Settings,
    /// Whether each model opened picks its display mode (no `--mode` was given): eye-dome
    /// lighting for a cloud without colours, shaded for the others.
    pub auto_mode: bool,
    pub show_panel: bool,
    pub stats: Stats,
    /// The frame-time target and the ε_px it adapts (`--target-ms`).
    pub pacer: Pacer,
    targets: Option<FrameTargets>,
    held: HashSet<Move>,
}

impl Viewer {
    pub fn new(renderer: Arc<Renderer>, settings: Settings) -> Viewer {
        Viewer {
            renderer,
            model: None,
            settings,
            auto_mode: false,
            show_panel: true,
            stats: Stats::default(),
            pacer: Pacer::new(None),
            targets: None,
            held: HashSet::new(),
        }
    }

    /// Makes `scene` the model shown, seen by `camera`, orbiting about `axes`. Its list
    /// may be on the GPU only in part: more comes with [`Viewer::add_slice`].
    pub fn install(
        &mut self,
        path: PathBuf,
        scene: Arc<Scene>,
        gpu_scene: GpuScene,
        (camera, axes): (&Camera, OrbitAxes),
    ) {
        let content = Content::One {
            scene,
            gpu_scene,
            streamer: None,
        };
        self.install_content(path, content, (camera, axes));
    }

    /// Makes the scene of instances `scene` the model shown, as [`Viewer::install`].
    pub fn install_scene(
        &mut self,
        path: PathBuf,
        scene: Arc<InstancedScene>,
        gpu: GpuInstances,
        view: (&Camera, OrbitAxes),
    ) {
        let frame = [scene.frame_chunk()];
        let content = Content::Many {
            scene,
            gpu,
            frame,
            visible: 0,
            ranges: 0,
            far_visible: 0,
        };
        self.install_content(path, content, view);
        self.stats.preview_next = true;
    }

    fn install_content(
        &mut self,
        path: PathBuf,
        content: Content,
        (camera, axes): (&Camera, OrbitAxes),
    ) {
        let mut model = Model {
            path,
            content,
            load_seconds: None,
            counters: CounterReadback::empty(),
            camera: OrbitCamera::from_camera(camera, axes, 1.0),
            home: OrbitCamera::from_camera(camera, axes, 1.0),
        };
        let radius = bounding_sphere(model.meta()).1;
        model.camera = OrbitCamera::from_camera(camera, axes, radius);
        model.home = model.camera;
        model.counters = CounterReadback::new(&self.renderer.gpu, &model.content.gpu_scenes());
        if self.settings.mode == Mode::Mesh && model.mesh_triangles() == 0 {
            self.settings.mode = Mode::Shaded;
        }
        if self.auto_mode {
            self.settings.mode = default_mode(model.meta());
        }
        self.settings.lod_eye = None;
        self.stats = Stats::default();
        self.model = Some(model);
    }

    /// Turns the model to stand on `up`: the orbit turns about it, and the model is
    /// framed from the default direction, which becomes the starting view (R).
    pub fn set_up(&mut self, up: UpAxis, viewport: (u32, u32)) {
        let Some(m) = &mut self.model else { return };
        let axes = OrbitAxes::about(up);
        let meta = m.meta();
        let aspect = viewport.0 as f64 / viewport.1.max(1) as f64;
        let framed = Camera::framed_about(axes, meta, m.chunks(), m.camera.fov_y, aspect);
        let radius = bounding_sphere(meta).1;
        m.camera = OrbitCamera::from_camera(&framed, axes, radius);
        m.home = m.camera;
    }

    /// The next slice of the model's list, uploaded.
    pub fn add_slice(&mut self, slice: SliceUpload) {
        if let Some(Model {
            content: Content::One { gpu_scene, .. },
            ..
        }) = &mut self.model
        {
            gpu_scene.insert(slice);
        }
    }

    /// Streams the model's list under the budget of `residency` from now on (its first
    /// slice resident); `wake` after each upload.
    pub fn stream(
        &mut self,
        residency: Residency,
        wake: impl Fn() + Send + 'static,
    ) -> anyhow::Result<()> {
        if let Some(Model {
            content:
                Content::One {
                    scene,
                    gpu_scene,
                    streamer,
                },
            ..
        }) = &mut self.model
        {
            let renderer = self.renderer.clone();
            let target = (scene.clone(), gpu_scene.home());
            *streamer = Some(Box::new(Streamer::start(
                target, renderer, residency, wake,
            )?));
        }
        Ok(())
    }

    /// Whether what the view wants is on the GPU (always, without a budget), or as much
    /// of it as the budget holds.
    pub fn is_streaming_settled(&self) -> bool {
        self.model
            .as_ref()
            .and_then(Model::streamer)
            .is_none_or(Streamer::is_settled)
    }

    pub fn add_mesh(&mut self, mesh: MeshUpload) {
        if let Some(Model {
            content: Content::One { gpu_scene, .. },
            ..
        }) = &mut self.model
        {
            gpu_scene.set_mesh(mesh);
        }
    }

    /// The whole model is on the GPU, `seconds` after it was asked for.
    pub fn upload_finished(&mut self, seconds: f64) {
        if let Some(m) = &mut self.model {
            m.load_seconds = Some(seconds);
        }
    }

    pub fn camera(&self) -> Option<Camera> {
        self.model.as_ref().map(|m| m.camera.camera())
    }

    /// Applies one input; returns the commands the window layer carries out itself
    /// (screenshot, open).
    pub fn handle(&mut self, input: Input, viewport: (u32, u32)) -> Option<Command> {
        if moves_camera(&input) {
            self.pacer.moved(Instant::now());
        }
        match input {
            Input::Hold(m, down) => {
                if down {
                    self.held.insert(m);
                } else {
                    self.held.remove(&m);
                }
                None
            }
            Input::Command(c) => self.command(c, viewport),
            Input::Drag {
                button,
                shift,
                dx,
                dy,
            } => {
                match (button, shift) {
                    (Button::Right, _) => self.turn_light(dx, dy),
                    (Button::Middle, _) | (Button::Left, true) => {
                        if let Some(m) = &mut self.model {
                            m.camera.pan(dx, dy, viewport)
                        }
                    }
                    (Button::Left, false) => {
                        if let Some(m) = &mut self.model {
                            m.camera.orbit(dx, dy)
                        }
                    }
                }
                None
            }
            Input::Wheel { notches, x, y } => {
                if let Some(m) = &mut self.model {
                    m.camera.zoom_at(notches, (x, y), viewport);
                }
                None
            }
        }
    }

    fn command(&mut self, c: Command, viewport: (u32, u32)) -> Option<Command> {
        let s = &mut self.settings;
        match c {
            Command::MoreError => s.error_px = (s.error_px * 2.0).min(ERROR_PX_RANGE.1),
            Command::LessError => s.error_px = (s.error_px * 0.5).max(ERROR_PX_RANGE.0),
            Command::ToggleEwa => s.ewa = !s.ewa,
            Command::TogglePanel => self.show_panel = !self.show_panel,
            Command::NextMode => {
                let m = self.model.as_ref();
                let has_mesh = m.is_some_and(|m| m.mesh_triangles() > 0);
                let has_attributes = m.is_some_and(|m| m.meta().has_attributes);
                s.mode = next_mode(s.mode, has_mesh, has_attributes);
            }
            Command::ToggleFreeze => self.set_frozen(self.settings.lod_eye.is_none()),
            Command::NextUp => {
                if let Some(m) = &self.model {
                    let next = m.up().map_or(UpAxis::Z, UpAxis::next);
                    self.set_up(next, viewport);
                }
            }
            Command::SetUp(up) => self.set_up(up, viewport),
            Command::Frame => {
                if let Some(m) = &mut self.model {
                    let aspect = viewport.0 as f64 / viewport.1.max(1) as f64;
                    let framed = Camera::framed_from(
                        m.camera.axes,
                        m.meta(),
                        m.chunks(),
                        [m.camera.azimuth_deg, m.camera.elevation_deg],
                        m.camera.fov_y,
                        aspect,
                    );
                    let min = m.camera.min_distance;
                    m.camera = OrbitCamera::from_camera(&framed, m.camera.axes, 0.0);
                    m.camera.min_distance = min;
                }
            }
            Command::Reset => {
                if let Some(m) = &mut self.model {
                    m.camera = m.home;
                }
            }
            Command::Screenshot | Command::Open => return Some(c),
        }
        None
    }

    /// Freezes the level of detail at the current eye (the selection stays as it is
    /// while the camera moves), or lets it follow the camera again.
    pub fn set_frozen(&mut self, frozen: bool) {
        self.settings.lod_eye = if frozen {
            self.camera().map(|c| c.eye)
        } else {
            None
        };
    }

    /// Right drag: the light direction (view space) turns with the pointer.
    fn turn_light(&mut self, dx: f64, dy: f64) {
        let rotation = glam::Quat::from_rotation_y(dx as f32 * 0.01)
            * glam::Quat::from_rotation_x(dy as f32 * 0.01);
        self.settings.light = (rotation * self.settings.light).normalize_or(glam::Vec3::Z);
    }

    /// Something moves on its own (held keys): the window keeps redrawing.
    pub fn is_animating(&self) -> bool {
        !self.held.is_empty()
    }

    /// Moves the camera for the keys held over `seconds`.
    pub fn advance(&mut self, seconds: f64) {
        if self.is_animating() {
            self.pacer.moved(Instant::now());
        }
        let Some(m) = &mut self.model else { return };
        let axis = |plus: Move, minus: Move| {
            (self.held.contains(&plus) as i32 - self.held.contains(&minus) as i32) as f64
        };
        let (f, r, u) = (
            axis(Move::Forward, Move::Back),
            axis(Move::Right, Move::Left),
            axis(Move::Up, Move::Down),
        );
        // One distance to the target per second.
        m.camera.walk(f * seconds, r * seconds, u * seconds);
        m.camera.turn(
            axis(Move::TurnRight, Move::TurnLeft),
            axis(Move::TurnDown, Move::TurnUp),
            seconds,
        );
    }

    /// The frame targets, (re)made for `size`.
    pub fn targets(&mut self, size: (u32, u32)) -> anyhow::Result<&FrameTargets> {
        if self.targets.as_ref().is_none_or(|t| t.size != size) {
            self.targets = None;
            self.targets = Some(self.renderer.targets(size)?);
        }
        Ok(self.targets.as_ref().expect("just made"))
    }

    /// Records the frame (the model, or the background alone) into the targets of
    /// `size`, with the copy of its GPU counters.
    pub fn draw(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        size: (u32, u32),
    ) -> anyhow::Result<()> {
        let start = Instant::now();
        self.targets(size)?;
        let targets = self.targets.as_ref().expect("made above");
        let preview = std::mem::take(&mut self.stats.preview_next) && self.model.is_some();
        let error_px = match preview {
            true => (self.settings.error_px.max(0.25) * PREVIEW_COARSER).min(ERROR_PX_RANGE.1),
            false => self.pacer.error_px(start, self.settings.error_px),
        };
        let settings = Settings {
            error_px,
            ..self.settings
        };
        self.stats.preview = preview;
        self.stats.frame_error_px = settings.error_px;
        match &mut self.model {
            Some(m) => {
                let camera = m.camera.camera();
                let frame = encode_content(
                    &self.renderer,
                    encoder,
                    targets,
                    &mut m.content,
                    (&camera, &settings),
                )?;
                m.counters
                    .record(encoder, targets, &m.content.gpu_scenes(), &frame);
                self.stats.frame = Some(frame);
            }
            None => self
                .renderer
                .encode_empty(encoder, targets, self.settings.background),
        }
        self.stats.cpu_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }

    /// The frame recorded last, drawn while the camera moved, took `frame_ms` (from its
    /// start to the next one's, as the window sees it): the pacer adapts its ε_px to it.
    pub fn frame_took(&mut self, frame_ms: f64) {
        let used = self.stats.frame_error_px;
        self.pacer
            .frame_done(used, frame_ms, self.settings.error_px);
    }

    /// When a frame at the user's ε_px is due: at once after a scene's preview, or, where
    /// the last frame was drawn coarser for the frame-time target, once the camera rests.
    pub fn refine_due(&self) -> Option<Instant> {
        if self.stats.preview && self.model.is_some() {
            return Some(Instant::now());
        }
        let coarser = self.stats.frame_error_px != self.settings.error_px;
        self.pacer
            .rest_at()
            .filter(|_| coarser && self.model.is_some())
    }

    /// After the submit of a drawn frame: starts reading its counters and takes those of
    /// earlier frames that have arrived.
    pub fn submitted(&mut self) {
        self.stats.frame_presented(Instant::now());
        if let Some(m) = &mut self.model {
            m.counters.submitted();
        }
        self.collect_counters();
    }

    fn collect_counters(&mut self) {
        if let Some(m) = &mut self.model {
            let arrived = m.counters.poll(&self.renderer.gpu);
            if let (
                Some((frame, counters)),
                Content::Many {
                    gpu, far_visible, ..
                },
            ) = (&arrived, &mut m.content)
            {
                let far = counters.far.unwrap_or_default();
                gpu.observe(far, frame.eps);
                *far_visible = far.visible as usize;
            }
            self.stats.took(arrived);
        }
    }

    /// Draws one frame without a window, waits for the GPU and takes its counters (the
    /// statistics a window would show a few frames later).
    pub fn frame_and_wait(&mut self, size: (u32, u32)) -> anyhow::Result<()> {
        let start = Instant::now();
        let moving = self.pacer.moving(start);
        let device = &self.renderer.gpu.device;
        let mut encoder = device.create_command_encoder(&Default::default());
        self.draw(&mut encoder, size)?;
        self.renderer.gpu.queue.submit([encoder.finish()]);
        self.submitted();
        if let Some(m) = &mut self.model {
            let arrived = m.counters.wait(&self.renderer.gpu)?;
            self.stats.took(arrived);
        }
        if moving {
            self.frame_took(start.elapsed().as_secs_f64() * 1e3);
        }
        Ok(())
    }

    /// The pixels of the last frame drawn (with anything drawn over them), RGBA8 sRGB.
    pub fn read_pixels(&self) -> anyhow::Result<(u32, u32, Vec<u8>)> {
        let targets = self
            .targets
            .as_ref()
            .ok_or_else(|| anyhow::anyhow!("nothing drawn yet"))?;
        let rgba = self.renderer.read_output(targets)?;
        Ok((targets.size.0, targets.size.1, rgba))
    }

    /// The targets of the last frame, for the window layer to draw over and present.
    pub fn current_targets(&self) -> Option<&FrameTargets> {
        self.targets.as_ref()
    }
}

/// Whether `input` moves the camera (and so starts the pacer's moving frames).
/// Records a frame of `content` seen by `camera` with `settings`: one model (its
/// streamed slices received first, and after the frame those it wants asked for), or a
/// scene of instances.
fn encode_content(
    renderer: &Renderer,
    encoder: &mut wgpu::CommandEncoder,
    targets: &FrameTargets,
    content: &mut Content,
    (camera, settings): (&Camera, &Settings),
) -> anyhow::Result<EncodedFrame> {
    match content {
        Content::One {
            scene,
            gpu_scene,
            streamer,
        } => {
            if let Some(s) = streamer.as_mut() {
                s.receive(gpu_scene);
            }
            let frame = renderer.encode(encoder, targets, scene, gpu_scene, camera, settings)?;
            if let Some(s) = streamer.as_mut() {
                // Slices evicted here stay alive until the recorded frame is done.
                s.after_frame((renderer, scene), gpu_scene, &frame.wanted_slices);
            }
            Ok(frame)
        }
        Content::Many {
            scene,
            gpu,
            visible,
            ranges,
            ..
        } => {
            let drawn =
                renderer.encode_instanced(encoder, targets, (scene, gpu), camera, settings)?;
            (*visible, *ranges) = (drawn.visible, drawn.ranges);
            Ok(drawn.frame)
        }
    }
}

fn moves_camera(input: &Input) -> bool {
    match input {
        Input::Drag { button, .. } => *button != Button::Right,
        Input::Wheel { .. } => true,
        Input::Hold(_, down) => *down,
        Input::Command(c) => matches!(c, Command::Frame | Command::Reset),
    }
}

/// The display mode a model opens in when none was asked for: eye-dome lighting for a
/// cloud without colours (its estimated normals, unoriented, shade it poorly; EDL needs
/// none), shaded otherwise.
pub fn default_mode(meta: &crate::tree::TreeMeta) -> Mode {
    if !meta.has_colors && !meta.oriented_normals {
        Mode::Edl
    } else {
        Mode::Shaded
    }
}

/// The display mode after `mode`; mesh only for models that have one, the LiDAR modes
/// only for models with attributes.
pub fn next_mode(mode: Mode, has_mesh: bool, has_attributes: bool) -> Mode {
    match mode {
        Mode::Shaded => Mode::Levels,
        Mode::Levels => Mode::Normals,
        Mode::Normals => Mode::Radius,
        Mode::Radius => Mode::Edl,
        Mode::Edl => Mode::Elevation,
        Mode::Elevation if has_attributes => Mode::Classification,
        Mode::Classification => Mode::Intensity,
        Mode::Intensity => Mode::Returns,
        Mode::Elevation | Mode::Returns => Mode::Points,
        Mode::Points if has_mesh => Mode::Mesh,
        Mode::Points | Mode::Mesh => Mode::Shaded,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cloud_without_colours_opens_in_eye_dome_lighting() {
        let points: Vec<[f64; 3]> = (0..64)
            .map(|i| [(i % 8) as f64, (i / 8) as f64, 0.1 * (i % 3) as f64])
            .collect();
        let (geometry, _) = crate::io::Geometry::from_points(&points).unwrap();
        let list = crate::tree::build_sequential_list(crate::surfel::leaf_surfels(&geometry));
        assert_eq!(default_mode(&list.meta), Mode::Edl);
        let mut coloured = list.meta.clone();
        coloured.has_colors = true;
        assert_eq!(default_mode(&coloured), Mode::Shaded);
    }

    #[test]
    fn the_lidar_modes_come_after_elevation_for_models_with_attributes() {
        let cycle = |has_attributes| {
            let mut mode = Mode::Elevation;
            let mut seen = Vec::new();
            while mode != Mode::Points {
                mode = next_mode(mode, false, has_attributes);
                seen.push(mode);
            }
            seen
        };
        assert_eq!(
            cycle(true),
            [
                Mode::Classification,
                Mode::Intensity,
                Mode::Returns,
                Mode::Points
            ]
        );
        assert_eq!(cycle(false), [Mode::Points]);
    }
}
