//! The viewer's window: winit events turned into [`Input`]s, egui's panel drawn over
//! the frame, the frame presented, models opened in the background (command line, file
//! dialog, drag and drop), screenshots, and the scripted `--screenshot` run.

use std::path::{Path, PathBuf};
use std::sync::{Arc, mpsc};
use std::time::{Duration, Instant};

use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoopProxy};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use super::ViewArgs;
use super::input::{Button, Command, Input, Move};
use super::loader::{Loaded, Loading};
use super::pacing::Pacer;
use super::panel::{self, PanelStatus};
use super::present::{Presented, Presenter};
use super::viewer::{PREVIEW_COARSER, Viewer};
use crate::apps::frame_args::RenderArgs;
use crate::apps::stats::Summary;
use crate::apps::text::count;
use crate::io::png::write_png;
use crate::render::{Gpu, GpuInstances, GpuScene, Renderer};
use crate::tree::instances::InstancedScene;
use crate::tree::scene::Scene;

/// Sent to the event loop from other threads: something finished, redraw.
#[derive(Debug, Clone, Copy)]
pub struct Wake;

/// What exists once the window does.
struct Windowed {
    window: Arc<Window>,
    presenter: Presenter,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    viewer: Viewer,
    adapter: String,
}

impl Windowed {
    /// Shows a model opened from `path` in `seconds`, framed as `args` ask.
    fn install_model(
        &mut self,
        args: &RenderArgs,
        (path, seconds): (PathBuf, f64),
        scene: Arc<Scene>,
        gpu_scene: GpuScene,
    ) -> anyhow::Result<()> {
        let args = self.window_args(args);
        let camera = args.camera(&scene)?;
        eprintln!(
            "model     {} open in {seconds:.2} s ({} nodes)",
            path.display(),
            count(scene.nodes().len() as u64),
        );
        let axes = args.axes(&scene);
        self.set_title(&path);
        self.viewer.install(path, scene, gpu_scene, (&camera, axes));
        Ok(())
    }

    /// Shows a scene of instances opened from `path` in `seconds`, as
    /// [`Windowed::install_model`].
    fn install_scene(
        &mut self,
        args: &RenderArgs,
        (path, seconds): (PathBuf, f64),
        scene: Arc<InstancedScene>,
        gpu: GpuInstances,
    ) -> anyhow::Result<()> {
        let args = self.window_args(args);
        let camera = args.camera_for(&scene.meta, &[scene.frame_chunk()])?;
        eprintln!(
            "scene     {} open in {seconds:.2} s ({} instances of {} models)",
            path.display(),
            count(scene.instances.len() as u64),
            scene.models.len()
        );
        let axes = args.axes_of(&scene.meta);
        self.set_title(&path);
        self.viewer.install_scene(path, scene, gpu, (&camera, axes));
        Ok(())
    }

    /// `args` with the window's size.
    fn window_args(&self, args: &RenderArgs) -> RenderArgs {
        let (width, height) = self.presenter.window_size();
        let mut args = args.clone();
        args.size = (width.max(1), height.max(1));
        args
    }

    fn set_title(&self, path: &Path) {
        let name = path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().to_string());
        self.window.set_title(&format!("spt: {name}"));
    }
}

/// The scripted `--screenshot` run: frames drawn with the model so far, and their times.
#[derive(Default)]
struct Script {
    frames: u32,
    frame_ms: Vec<f64>,
    gpu_ms: Vec<f64>,
    /// The ε_px each frame was drawn with (the pacer's while moving under --target-ms).
    error_px: Vec<f64>,
}

pub struct App {
    args: ViewArgs,
    launched: Instant,
    proxy: EventLoopProxy<Wake>,
    egui_ctx: egui::Context,
    windowed: Option<Windowed>,
    loading: Option<Loading>,
    /// A model to open once the window exists.
    first_model: Option<PathBuf>,
    dialog: Option<mpsc::Receiver<Option<PathBuf>>>,
    message: Option<(String, bool)>,
    pointer: (f64, f64),
    dragging: Option<Button>,
    shift: bool,
    control: bool,
    last_frame: Option<Instant>,
    /// The camera was moving when the last frame was drawn (its time counts for the
    /// frame-time target).
    last_frame_moving: bool,
    first_frame_logged: bool,
    screenshot_requested: bool,
    script: Script,
    /// The error the process exits with.
    pub failure: Option<anyhow::Error>,
}

impl App {
    pub fn new(args: ViewArgs, model: PathBuf, proxy: EventLoopProxy<Wake>) -> App {
        App {
            args,
            launched: Instant::now(),
            proxy,
            egui_ctx: egui::Context::default(),
            windowed: None,
            loading: None,
            first_model: Some(model),
            dialog: None,
            message: None,
            pointer: (0.0, 0.0),
            dragging: None,
            shift: false,
            control: false,
            last_frame: None,
            last_frame_moving: false,
            first_frame_logged: false,
            screenshot_requested: false,
            script: Script::default(),
            failure: None,
        }
    }

    fn create_window(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let (w, h) = self.args.render.size;
        let attributes = Window::default_attributes()
            .with_title("spt")
            .with_inner_size(winit::dpi::PhysicalSize::new(w, h));
        let window = Arc::new(event_loop.create_window(attributes)?);
        let instance = Gpu::instance(
            self.args.render.backend.as_deref(),
            Some(Box::new(event_loop.owned_display_handle())),
        )?;
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| anyhow::anyhow!("cannot draw into the window: {e}"))?;
        let gpu = Gpu::with_instance(instance, Some(&surface))?;
        let adapter = gpu.describe();
        eprintln!("adapter   {adapter}");
        let renderer = Arc::new(Renderer::new(gpu));
        let presenter = Presenter::new(&renderer, window.clone(), surface)?;
        let max_side = renderer.gpu.device.limits().max_texture_dimension_2d as usize;
        let egui_state = egui_winit::State::new(
            self.egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(max_side),
        );
        let egui_renderer = egui_wgpu::Renderer::new(
            &renderer.gpu.device,
            renderer.gpu.overlay_format(),
            egui_wgpu::RendererOptions::default(),
        );
        let mut viewer = Viewer::new(renderer, self.args.render.settings());
        viewer.auto_mode = self.args.render.mode.is_none();
        viewer.pacer = Pacer::new(self.args.target_ms);
        viewer.show_panel = !self.args.hide_panel;
        self.windowed = Some(Windowed {
            window,
            presenter,
            egui_state,
            egui_renderer,
            viewer,
            adapter,
        });
        Ok(())
    }

    /// Starts opening `path` in the background.
    fn open(&mut self, path: &Path) {
        let Some(w) = &self.windowed else { return };
        let proxy = self.proxy.clone();
        let within = (w.viewer.renderer.clone(), self.args.render.gpu_budget());
        self.loading = Some(Loading::start_within(path, within, move || {
            let _ = proxy.send_event(Wake);
        }));
        self.message = None;
    }

    /// Asks for a file on another thread, so that the window keeps drawing.
    fn open_dialog(&mut self) {
        let (send, receive) = mpsc::channel();
        let proxy = self.proxy.clone();
        let spawned = std::thread::Builder::new()
            .name("file dialog".into())
            .spawn(move || {
                let picked = rfd::FileDialog::new()
                    .set_title("Open a model")
                    .add_filter("models (PLY, LAS, LAZ, spt)", &["ply", "las", "laz", "spt"])
                    .pick_file();
                let _ = send.send(picked);
                let _ = proxy.send_event(Wake);
            });
        match spawned {
            Ok(_) => self.dialog = Some(receive),
            Err(e) => self.message = Some((format!("cannot open a file dialog: {e}"), true)),
        }
    }

    /// Takes a finished load or dialog, if any.
    fn poll_background(&mut self) {
        if let Some(dialog) = &self.dialog {
            match dialog.try_recv() {
                Ok(Some(path)) => {
                    self.dialog = None;
                    self.open(&path);
                }
                Ok(None) | Err(mpsc::TryRecvError::Disconnected) => self.dialog = None,
                Err(mpsc::TryRecvError::Empty) => {}
            }
        }
        let Some(loading) = &mut self.loading else {
            return;
        };
        let messages = loading.poll();
        let seconds = loading.started.elapsed().as_secs_f64();
        let path = loading.path.clone();
        let Some(w) = &mut self.windowed else { return };
        for message in messages {
            match message {
                Ok(Loaded::Scene(scene, gpu_scene)) => {
                    let opened = (path.clone(), seconds);
                    if let Err(e) = w.install_model(&self.args.render, opened, scene, gpu_scene) {
                        self.message = Some((format!("{e:#}"), true));
                    }
                }
                Ok(Loaded::Instances(scene, gpu)) => {
                    let opened = (path.clone(), seconds);
                    if let Err(e) = w.install_scene(&self.args.render, opened, scene, gpu) {
                        self.message = Some((format!("{e:#}"), true));
                    }
                }
                Ok(Loaded::Streamed(residency)) => {
                    let proxy = self.proxy.clone();
                    let wake = move || {
                        let _ = proxy.send_event(Wake);
                    };
                    if let Err(e) = w.viewer.stream(residency, wake) {
                        self.message = Some((format!("{e:#}"), true));
                    }
                }
                Ok(Loaded::Slice(slice)) => w.viewer.add_slice(slice),
                Ok(Loaded::Mesh(mesh)) => w.viewer.add_mesh(mesh),
                Ok(Loaded::Done) => {
                    w.viewer.upload_finished(seconds);
                    // Streamed, the loader only checks the file: the slices come by need.
                    let done = match self.args.render.gpu_budget() {
                        Some(_) => "checked",
                        None => "on the GPU",
                    };
                    eprintln!(
                        "model     {} {done} in {seconds:.2} s ({})",
                        path.display(),
                        self.loading
                            .as_ref()
                            .map_or(String::new(), |l| l.progress.timeline(Instant::now()))
                    );
                }
                Err(e) => {
                    let text = format!("{e:#}");
                    if self.args.screenshot.is_some() {
                        // The run ends with it, and says it then.
                        self.failure = Some(e);
                    } else {
                        eprintln!("error: {text}");
                    }
                    self.message = Some((text, true));
                }
            }
        }
        if self.loading.as_ref().is_some_and(Loading::is_finished) {
            self.loading = None;
        }
    }

    /// Applies an input; carries out what the viewer hands back.
    fn input(&mut self, input: Input) {
        let Some(w) = &mut self.windowed else { return };
        let viewport = w.presenter.window_size();
        let handed_back = w.viewer.handle(input, viewport);
        w.window.request_redraw();
        match handed_back {
            Some(Command::Screenshot) => self.screenshot_requested = true,
            Some(Command::Open) => self.open_dialog(),
            _ => {}
        }
    }

    /// One frame: the panel's input and layout, the model's frame with the panel over
    /// it, presentation; then what follows a frame (logs, scripted frames, screenshots).
    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        self.poll_background();
        if self.failure.is_some() {
            // A scripted run whose model failed to open.
            event_loop.exit();
            return;
        }
        let now = Instant::now();
        let seconds = self
            .last_frame
            .map_or(0.0, |t| now.duration_since(t).as_secs_f64());
        let Some(w) = &mut self.windowed else { return };
        let size = w.presenter.window_size();
        if size.0 == 0 || size.1 == 0 {
            return; // minimized
        }
        // The previous frame took `seconds` if the window drew it while the camera moved
        // (after a pause the interval measures the pause).
        if self.last_frame_moving {
            w.viewer.frame_took(seconds * 1e3);
        }
        w.viewer.advance(seconds.min(0.25));
        if self.args.spin != 0.0
            && let Some(m) = &mut w.viewer.model
        {
            m.camera.orbit(-self.args.spin / 0.3, 0.0);
            w.viewer.pacer.moved(now);
        }
        self.last_frame_moving = w.viewer.pacer.moving(now);
        let Some((output, primitives, commands)) = self.run_panel() else {
            return;
        };
        let Some(w) = &mut self.windowed else { return };
        let renderer = w.viewer.renderer.clone();
        let mut encoder = renderer
            .gpu
            .device
            .create_command_encoder(&Default::default());
        if let Err(e) = w.viewer.draw(&mut encoder, size) {
            self.message = Some((format!("{e:#}"), true));
            // Fall back to what always draws.
            w.viewer.settings.mode = crate::render::Mode::Shaded;
            return;
        }
        paint_panel(w, &renderer, &mut encoder, (&output, &primitives), size);
        let targets = w.viewer.current_targets().expect("just drawn");
        let presented = w.presenter.present(&renderer, encoder, targets);
        if matches!(presented, Presented::Skipped) {
            w.window.request_redraw();
            return;
        }
        w.viewer.submitted();
        self.last_frame = Some(now);
        for commands in commands {
            self.input(Input::Command(commands));
        }
        self.after_frame(event_loop, seconds);
    }

    /// The panel: its input taken from the window, laid out and tessellated, with the
    /// commands its buttons gave.
    fn run_panel(
        &mut self,
    ) -> Option<(egui::FullOutput, Vec<egui::ClippedPrimitive>, Vec<Command>)> {
        let w = self.windowed.as_mut()?;
        let raw = w.egui_state.take_egui_input(&w.window);
        let status = PanelStatus {
            adapter: &w.adapter,
            loading: self.loading.as_ref().map(|l| {
                let (stage, fraction) = l.progress.snapshot();
                let name = l.path.file_name().map_or_else(
                    || l.path.display().to_string(),
                    |n| n.to_string_lossy().to_string(),
                );
                (name, stage, fraction, l.started.elapsed().as_secs_f64())
            }),
            message: self.message.as_ref().map(|(m, e)| (m.as_str(), *e)),
        };
        let mut commands = Vec::new();
        let viewer = &mut w.viewer;
        let mut output = self.egui_ctx.run_ui(raw, |ui| {
            if viewer.show_panel {
                commands = panel::show(ui.ctx(), viewer, &status);
            }
        });
        let platform = std::mem::take(&mut output.platform_output);
        w.egui_state.handle_platform_output(&w.window, platform);
        let shapes = std::mem::take(&mut output.shapes);
        let primitives = self.egui_ctx.tessellate(shapes, output.pixels_per_point);
        Some((output, primitives, commands))
    }

    /// After a presented frame: the first frame's time, the scripted frames' times, and
    /// the screenshots asked for.
    fn after_frame(&mut self, event_loop: &ActiveEventLoop, seconds: f64) {
        let Some(w) = &mut self.windowed else { return };
        if w.viewer.model.is_some() && !self.first_frame_logged {
            self.first_frame_logged = true;
            let coarse = w.viewer.stats.frame.as_ref().is_some_and(|f| f.coarsened);
            let note = if w.viewer.stats.preview {
                format!(
                    " (a preview at {PREVIEW_COARSER}× the asked ε_px; the frame at ε_px follows)"
                )
            } else if coarse {
                " (coarser than asked until the model is uploaded)".to_string()
            } else {
                String::new()
            };
            eprintln!(
                "first frame {:.2} s after launch{note}",
                self.launched.elapsed().as_secs_f64(),
            );
        }
        // The scripted frames start once the whole model is on the GPU (under a budget:
        // checked, and what the view wants streamed in).
        let settled = self.loading.is_none() && w.viewer.is_streaming_settled();
        if w.viewer.model.is_some() && settled && !w.viewer.stats.preview {
            self.script.frames += 1;
            if self.script.frames > 1 {
                self.script.frame_ms.push(seconds * 1e3);
            }
            self.script.gpu_ms.extend(w.viewer.stats.gpu.gpu_ms);
            self.script.error_px.push(w.viewer.stats.frame_error_px);
        }
        if self.screenshot_requested {
            self.screenshot_requested = false;
            let name = format!(
                "spt-screenshot-{}.png",
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0, |d| d.as_secs())
            );
            self.message = Some(match save_screenshot(&w.viewer, Path::new(&name)) {
                Ok(()) => (format!("saved {name}"), false),
                Err(e) => (format!("{e:#}"), true),
            });
        }
        if let Some(path) = self.args.screenshot.clone()
            && w.viewer.model.is_some()
            && self.script.frames >= self.args.render.frames
        {
            match save_screenshot(&w.viewer, &path) {
                Ok(()) => self.report_script(&path),
                Err(e) => self.failure = Some(e),
            }
            event_loop.exit();
        }
    }

    /// What `--screenshot` measured, on stdout.
    fn report_script(&mut self, path: &Path) {
        let Some(w) = &self.windowed else { return };
        let stats = &w.viewer.stats;
        if let Some(m) = &w.viewer.model {
            say!(
                "splats    {} drawn of {} nodes, {} tested",
                stats.gpu.drawn.map_or("–".into(), count),
                count(m.node_count()),
                count(stats.frame.as_ref().map_or(0, |f| f.tested) as u64)
            );
        }
        for (name, values) in [
            ("frame", &mut self.script.frame_ms),
            ("gpu", &mut self.script.gpu_ms),
        ] {
            if let Some(s) = Summary::of(values) {
                say!(
                    "{name:<9} {:.2} ms median of {}, p95 {:.2} ms",
                    s.median,
                    s.count,
                    s.p95
                );
            }
        }
        if let Some(s) = Summary::of(&mut self.script.error_px)
            && self.args.target_ms.is_some()
        {
            say!(
                "ε_px      {:.3} median, {:.3} last (target {:.0} ms)",
                s.median,
                w.viewer.stats.frame_error_px,
                self.args.target_ms.unwrap_or_default()
            );
        }
        if let Some(s) = w.viewer.model.as_ref().and_then(|m| m.streamer()) {
            say!("gpu memory {}", s.residency.memory_line());
        }
        say!("wrote     {}", path.display());
    }

    /// Keeps drawing while something moves; while a model loads, redraws only to show
    /// the progress (ten times a second, four once a model is on screen) so that the
    /// loader keeps the processor; otherwise waits for input.
    fn schedule(&self, event_loop: &ActiveEventLoop) {
        let Some(w) = &self.windowed else { return };
        let shown = w.viewer.model.is_some();
        let busy = w.viewer.is_animating()
            || self.screenshot_requested
            || (shown
                && self.loading.is_none()
                && (self.args.spin != 0.0 || self.args.screenshot.is_some()));
        if busy {
            w.window.request_redraw();
            event_loop.set_control_flow(ControlFlow::Poll);
        } else if self.loading.is_some() || self.args.screenshot.is_some() {
            let period = if shown { 250 } else { 100 };
            event_loop.set_control_flow(ControlFlow::WaitUntil(
                Instant::now() + Duration::from_millis(period),
            ));
        } else if let Some(rest) = w.viewer.refine_due() {
            // The last frame was coarsened for the frame-time target: draw the user's
            // ε once the camera rests.
            event_loop.set_control_flow(ControlFlow::WaitUntil(rest));
        } else {
            event_loop.set_control_flow(ControlFlow::Wait);
        }
    }

    /// A timed wake-up (see [`App::schedule`]) redraws.
    fn woke(&self) {
        if let Some(w) = &self.windowed {
            w.window.request_redraw();
        }
    }
}

fn save_screenshot(viewer: &Viewer, path: &Path) -> anyhow::Result<()> {
    let (width, height, rgba) = viewer.read_pixels()?;
    write_png(path, width, height, &rgba)
}

/// The viewer's meaning of a key, if any.
fn key_input(key: &Key, pressed: bool, control: bool) -> Option<Input> {
    let hold = |m| Some(Input::Hold(m, pressed));
    let once = |c| pressed.then_some(Input::Command(c));
    match key {
        Key::Named(NamedKey::ArrowLeft) => hold(Move::TurnLeft),
        Key::Named(NamedKey::ArrowRight) => hold(Move::TurnRight),
        Key::Named(NamedKey::ArrowUp) => hold(Move::TurnUp),
        Key::Named(NamedKey::ArrowDown) => hold(Move::TurnDown),
        Key::Named(NamedKey::Tab) => once(Command::TogglePanel),
        Key::Named(NamedKey::F12) => once(Command::Screenshot),
        Key::Character(c) => match c.to_lowercase().as_str() {
            "o" if control => once(Command::Open),
            "w" => hold(Move::Forward),
            "s" => hold(Move::Back),
            "a" => hold(Move::Left),
            "d" => hold(Move::Right),
            "q" => hold(Move::Down),
            "e" => hold(Move::Up),
            "f" => once(Command::Frame),
            "r" => once(Command::Reset),
            "m" => once(Command::NextMode),
            "u" => once(Command::NextUp),
            "x" => once(Command::ToggleEwa),
            "l" => once(Command::ToggleFreeze),
            "p" => once(Command::Screenshot),
            "+" | "=" => once(Command::MoreError),
            "-" | "_" => once(Command::LessError),
            _ => None,
        },
        _ => None,
    }
}

/// Draws the panel (`output` of egui, tessellated into `primitives`) over the frame
/// just drawn into the viewer's targets, in gamma space.
fn paint_panel(
    w: &mut Windowed,
    renderer: &Renderer,
    encoder: &mut wgpu::CommandEncoder,
    (output, primitives): (&egui::FullOutput, &[egui::ClippedPrimitive]),
    size: (u32, u32),
) {
    let (device, queue) = (&renderer.gpu.device, &renderer.gpu.queue);
    let screen = egui_wgpu::ScreenDescriptor {
        size_in_pixels: [size.0, size.1],
        pixels_per_point: output.pixels_per_point,
    };
    for (id, deltas) in &output.textures_delta.set {
        for delta in deltas {
            w.egui_renderer.update_texture(device, queue, *id, delta);
        }
    }
    let extra = w
        .egui_renderer
        .update_buffers(device, queue, encoder, primitives, &screen);
    let Some(targets) = w.viewer.current_targets() else {
        return;
    };
    {
        let view = targets.overlay_view(renderer.gpu.overlay_format());
        let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("panel"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        w.egui_renderer
            .render(&mut pass.forget_lifetime(), primitives, &screen);
    }
    for id in &output.textures_delta.free {
        w.egui_renderer.free_texture(id);
    }
    if !extra.is_empty() {
        queue.submit(extra);
    }
}

impl ApplicationHandler<Wake> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.windowed.is_some() {
            return;
        }
        if let Err(e) = self.create_window(event_loop) {
            self.failure = Some(e);
            event_loop.exit();
            return;
        }
        eprintln!(
            "window    ready {:.2} s after launch",
            self.launched.elapsed().as_secs_f64()
        );
        if let Some(path) = self.first_model.take() {
            self.open(&path);
        }
        self.schedule(event_loop);
    }

    fn user_event(&mut self, _: &ActiveEventLoop, _: Wake) {
        if let Some(w) = &self.windowed {
            w.window.request_redraw();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(w) = &mut self.windowed else { return };
        let response = w.egui_state.on_window_event(&w.window, &event);
        // egui asks for a repaint after every redraw too; that would never idle.
        if response.repaint && !matches!(event, WindowEvent::RedrawRequested) {
            w.window.request_redraw();
        }
        let over_panel = self.egui_ctx.egui_wants_pointer_input();
        let typing = self.egui_ctx.egui_wants_keyboard_input();
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(_) => {
                let renderer = w.viewer.renderer.clone();
                w.presenter.resize(&renderer);
                w.window.request_redraw();
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            WindowEvent::DroppedFile(path) => self.open(&path),
            WindowEvent::ModifiersChanged(m) => {
                self.shift = m.state().shift_key();
                self.control = m.state().control_key();
            }
            WindowEvent::KeyboardInput { event, .. } if !typing => {
                let pressed = event.state == ElementState::Pressed;
                if let Some(input) = key_input(&event.logical_key, pressed, self.control) {
                    // Key repeats of one-shot commands are ignored; held keys repeat harmlessly.
                    if !(event.repeat && matches!(input, Input::Command(_))) {
                        self.input(input);
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let button = match button {
                    MouseButton::Left => Some(Button::Left),
                    MouseButton::Middle => Some(Button::Middle),
                    MouseButton::Right => Some(Button::Right),
                    _ => None,
                };
                self.dragging = match state {
                    ElementState::Pressed if !over_panel => button.or(self.dragging),
                    ElementState::Released if button == self.dragging => None,
                    _ => self.dragging,
                };
            }
            WindowEvent::CursorMoved { position, .. } => {
                let (dx, dy) = (position.x - self.pointer.0, position.y - self.pointer.1);
                self.pointer = (position.x, position.y);
                if let Some(button) = self.dragging {
                    self.input(Input::Drag {
                        button,
                        shift: self.shift,
                        dx,
                        dy,
                    });
                }
            }
            WindowEvent::MouseWheel { delta, .. } if !over_panel => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / 50.0,
                };
                self.input(Input::Wheel {
                    notches,
                    x: self.pointer.0,
                    y: self.pointer.1,
                });
            }
            _ => {}
        }
    }

    fn new_events(&mut self, _: &ActiveEventLoop, cause: winit::event::StartCause) {
        if matches!(cause, winit::event::StartCause::ResumeTimeReached { .. }) {
            self.woke();
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        self.schedule(event_loop);
    }
}
