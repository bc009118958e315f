//! The viewer's panel (egui): level of detail, display, camera, statistics, loading and
//! messages. Buttons that act on the viewer come back as [`Command`]s, handled exactly
//! as their keys are.

use crate::io::up::UpAxis;
use egui::{Color32, RichText};

use super::input::Command;
use super::viewer::{ERROR_PX_RANGE, Viewer};
use crate::apps::text::count;
use crate::render::residency::mib;
use crate::render::{Culling, Mode, PrefixCut, Raster};

/// What the panel shows besides the viewer itself.
pub struct PanelStatus<'a> {
    /// The adapter, as [`crate::render::Gpu::describe`] puts it.
    pub adapter: &'a str,
    /// A model being opened: its name, stage, fraction done and seconds so far.
    pub loading: Option<(String, &'static str, Option<f32>, f64)>,
    /// The last error (red) or notice.
    pub message: Option<(&'a str, bool)>,
}

const MODES: [(Mode, &str); 11] = [
    (Mode::Shaded, "shaded"),
    (Mode::Levels, "tree levels"),
    (Mode::Normals, "normals"),
    (Mode::Radius, "splat radius"),
    (Mode::Edl, "eye-dome lighting"),
    (Mode::Elevation, "elevation"),
    (Mode::Classification, "classification (LiDAR)"),
    (Mode::Intensity, "intensity (LiDAR)"),
    (Mode::Returns, "returns (LiDAR)"),
    (Mode::Points, "points (no blending)"),
    (Mode::Mesh, "mesh (reference)"),
];

/// Draws the panel; returns the commands its buttons gave.
pub fn show(ctx: &egui::Context, viewer: &mut Viewer, status: &PanelStatus) -> Vec<Command> {
    let mut commands = Vec::new();
    egui::Window::new("spt")
        .default_pos([8.0, 8.0])
        .default_width(300.0)
        .max_width(300.0)
        .resizable(false)
        .show(ctx, |ui| {
            ui.set_max_width(300.0);
            model_section(ui, viewer, status, &mut commands);
            ui.separator();
            lod_section(ui, viewer);
            ui.separator();
            display_section(ui, viewer);
            ui.separator();
            ui.horizontal(|ui| {
                if ui.button("Frame (F)").clicked() {
                    commands.push(Command::Frame);
                }
                if ui.button("Reset view (R)").clicked() {
                    commands.push(Command::Reset);
                }
                if ui.button("Screenshot (F12)").clicked() {
                    commands.push(Command::Screenshot);
                }
            });
            up_row(ui, viewer, &mut commands);
            ui.separator();
            stats_section(ui, viewer, status);
            ui.collapsing("Controls", |ui| {
                ui.label(
                    "Left drag: orbit · Shift+left or middle drag: pan · wheel: zoom at the \
                     pointer · right drag: light\nWASD: move · Q/E: down/up · arrows: orbit\n\
                     F: frame · R: reset · M: next mode · U: next up axis · +/−: ε_px ×2/÷2 · \
                     X: EWA · L: freeze LOD\nTab: hide this panel · F12 or P: screenshot · Ctrl+O: open · \
                     drop a file to open it",
                );
            });
        });
    commands
}

fn model_section(
    ui: &mut egui::Ui,
    viewer: &Viewer,
    status: &PanelStatus,
    commands: &mut Vec<Command>,
) {
    ui.horizontal(|ui| {
        if ui.button("Open… (Ctrl+O)").clicked() {
            commands.push(Command::Open);
        }
        if let Some(m) = &viewer.model {
            let name = m.path.file_name().map_or_else(
                || m.path.display().to_string(),
                |n| n.to_string_lossy().to_string(),
            );
            ui.label(RichText::new(name).strong())
                .on_hover_text(m.path.display().to_string());
        }
    });
    if let Some((name, stage, fraction, seconds)) = &status.loading {
        ui.label(format!("opening {name}: {stage}, {seconds:.1} s"));
        let bar = match fraction {
            Some(f) => egui::ProgressBar::new(*f).show_percentage(),
            None => egui::ProgressBar::new(0.0).animate(true),
        };
        ui.add(bar);
    }
    if let Some((text, is_error)) = status.message {
        let color = if is_error {
            Color32::from_rgb(220, 50, 50)
        } else {
            ui.visuals().text_color()
        };
        ui.label(RichText::new(text).color(color));
    }
}

fn lod_section(ui: &mut egui::Ui, viewer: &mut Viewer) {
    let s = &mut viewer.settings;
    ui.add_enabled(
        s.lod,
        egui::Slider::new(&mut s.error_px, ERROR_PX_RANGE.0..=ERROR_PX_RANGE.1)
            .logarithmic(true)
            .text("ε (pixels)"),
    )
    .on_hover_text("Largest screen-space error of the level of detail, in pixels");
    pacing_rows(ui, viewer);
    let s = &mut viewer.settings;
    let mut leaves_only = !s.lod;
    if ui
        .checkbox(&mut leaves_only, "Leaves only (no level of detail)")
        .changed()
    {
        s.lod = !leaves_only;
    }
    let mut frozen = s.lod_eye.is_some();
    if ui
        .checkbox(&mut frozen, "Freeze LOD (L)")
        .on_hover_text("Keep the current selection while the camera moves, to inspect it")
        .changed()
    {
        viewer.set_frozen(frozen);
    }
}

/// The frame-time target (`--target-ms`) and the ε_px the last frame was drawn with.
fn pacing_rows(ui: &mut egui::Ui, viewer: &mut Viewer) {
    let pacer = &mut viewer.pacer;
    let mut on = pacer.target_ms.is_some();
    ui.horizontal(|ui| {
        if ui
            .checkbox(&mut on, "Hold frame time")
            .on_hover_text(
                "While the camera moves, coarsen the level of detail so that frames take \
                 this long; the ε above returns once the camera rests",
            )
            .changed()
        {
            pacer.target_ms = on.then_some(100.0);
        }
        if let Some(ms) = &mut pacer.target_ms {
            ui.add(
                egui::Slider::new(ms, 10.0..=1000.0)
                    .logarithmic(true)
                    .suffix(" ms"),
            );
        }
    });
    ui.label(format!(
        "drawn at ε = {:.3} px",
        viewer.stats.frame_error_px
    ));
}

/// The axis the model stands on, to choose another.
fn up_row(ui: &mut egui::Ui, viewer: &Viewer, commands: &mut Vec<Command>) {
    let Some(m) = &viewer.model else { return };
    let current = m.up();
    egui::ComboBox::from_label("Up (U)")
        .selected_text(current.map_or("as the sensor saw it", UpAxis::name))
        .show_ui(ui, |ui| {
            for axis in UpAxis::ALL {
                if ui
                    .selectable_label(current == Some(axis), axis.name())
                    .clicked()
                {
                    commands.push(Command::SetUp(axis));
                }
            }
        });
}

fn display_section(ui: &mut egui::Ui, viewer: &mut Viewer) {
    let m = viewer.model.as_ref();
    let has_mesh = m.is_some_and(|m| m.mesh_triangles() > 0);
    let has_attributes = m.is_some_and(|m| m.meta().has_attributes);
    let compute_raster = viewer.renderer.gpu.compute_raster;
    let s = &mut viewer.settings;
    let lidar = |mode| matches!(mode, Mode::Classification | Mode::Intensity | Mode::Returns);
    egui::ComboBox::from_label("Display (M)")
        .selected_text(MODES.iter().find(|m| m.0 == s.mode).map_or("", |m| m.1))
        .show_ui(ui, |ui| {
            for (mode, name) in MODES {
                if (mode != Mode::Mesh || has_mesh) && (!lidar(mode) || has_attributes) {
                    ui.selectable_value(&mut s.mode, mode, name);
                }
            }
        });
    if s.mode == Mode::Edl {
        ui.add(egui::Slider::new(&mut s.edl_strength, 0.0..=10.0).text("EDL strength"));
        ui.add(egui::Slider::new(&mut s.edl_radius_px, 0.5..=8.0).text("EDL radius (px)"));
    }
    super::legend::show(ui, s.mode, m.map(|m| (m.meta(), m.camera.axes.up)));
    ui.checkbox(&mut s.ewa, "EWA prefilter (X)");
    ui.checkbox(&mut s.cull_back_faces, "Back-face culling");
    ui.horizontal(|ui| {
        ui.label("Culling");
        ui.radio_value(&mut s.culling, Culling::Compute, "compute");
        ui.radio_value(&mut s.culling, Culling::Vertex, "vertex");
    });
    if compute_raster {
        ui.horizontal(|ui| {
            ui.label("Raster");
            ui.radio_value(&mut s.raster, Raster::Auto, "auto")
                .on_hover_text(Raster::Auto.description());
            ui.radio_value(&mut s.raster, Raster::Hardware, "hardware")
                .on_hover_text(Raster::Hardware.description());
            ui.radio_value(&mut s.raster, Raster::Compute, "compute")
                .on_hover_text(Raster::Compute.description());
        });
    }
    ui.horizontal(|ui| {
        ui.label("Prefix cut");
        for cut in PrefixCut::CHOICES {
            ui.radio_value(&mut s.prefix_cut, cut, cut.name())
                .on_hover_text(cut.description());
        }
    });
    ui.horizontal(|ui| {
        ui.label("Background");
        ui.color_edit_button_rgb(&mut s.background);
    });
}

/// Width of the stats grid's label column, points: "splats drawn", the longest.
const STATS_LABEL_WIDTH: f32 = 90.0;

/// The nodes a frame handed to the GPU to test: in its chunks' prefixes (a model), or
/// in the CPU's ranges (a scene, `ranges` of them) and for the far instances the GPU
/// placed (`far`, read a few frames late).
fn tested_text(
    f: &crate::render::EncodedFrame,
    ranges: Option<usize>,
    far: Option<crate::render::FarCounts>,
) -> String {
    let Some(ranges) = ranges else {
        return format!(
            "{} in {} chunks",
            count(f.tested as u64),
            count(f.ranges.len() as u64)
        );
    };
    let mut tested = format!(
        "{} in {} ranges",
        count(f.tested as u64),
        count(ranges as u64)
    );
    if let Some(far) = far {
        let placed = count(far.visible);
        tested += &format!(" + {} of {placed} far instances", count(far.tested));
    }
    tested
}

fn stats_section(ui: &mut egui::Ui, viewer: &Viewer, status: &PanelStatus) {
    let st = &viewer.stats;
    let ms = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.2} ms"));
    // The labels' column is as wide as its longest label from the first frame on (a
    // grid learns its widths from the frame before, so a first-frame screenshot
    // overlapped them).
    let grid = egui::Grid::new("stats")
        .num_columns(2)
        .min_col_width(STATS_LABEL_WIDTH);
    grid.show(ui, |ui| {
        let mut row = |name: &str, value: String| {
            ui.label(name);
            ui.label(value);
            ui.end_row();
        };
        row(
            "fps",
            if st.fps > 0.0 {
                format!("{:.1}", st.fps)
            } else {
                "idle (draws on change)".into()
            },
        );
        row("CPU", ms(Some(st.cpu_ms)));
        row("GPU", ms(st.gpu.gpu_ms));
        if let Some(m) = &viewer.model {
            let total = m.node_count();
            row(
                "splats drawn",
                match st.gpu.drawn {
                    Some(d) => format!("{} / {}", count(d), count(total)),
                    None if viewer.settings.culling == Culling::Vertex => {
                        format!("– / {} (vertex culling)", count(total))
                    }
                    // The GPU's counts come back a few frames late.
                    None => format!("– / {}", count(total)),
                },
            );
            let instances = m.instances();
            if let Some((all, drawn, _)) = instances {
                row(
                    "instances",
                    format!("{} drawn / {}", count(drawn as u64), count(all as u64)),
                );
            }
            if let Some((gpu, cpu)) = m.scene_memory() {
                let models = format!("{:.0} MiB models", mib(gpu.models));
                let room = format!("{:.0} MiB survivors", mib(gpu.survivor_room));
                let each = format!("{} B an instance", gpu.per_instance);
                row("GPU memory", format!("{models} + {room} + {each}"));
                row(
                    "CPU memory",
                    format!("{cpu} B an instance beyond the models"),
                );
            }
            if let Some(f) = &st.frame {
                let ranges = instances.map(|(_, _, ranges)| ranges);
                row("tested", tested_text(f, ranges, st.gpu.far));
                row("plan", format!("{:.2} ms CPU", f.plan_ms));
                if f.coarsened {
                    row("", "coarser until uploaded".into());
                }
            }
            if let Some(s) = m.streamer() {
                let r = &s.residency;
                row(
                    "GPU memory",
                    format!(
                        "{:.0} / {:.0} MiB resident (peak {:.0})",
                        mib(r.resident_bytes()),
                        mib(r.budget()),
                        mib(r.peak_bytes())
                    ),
                );
            }
            let meta = m.meta();
            row(
                "model",
                format!("{} leaves, depth {}", count(meta.leaf_count), meta.depth),
            );
            let size = glam::DVec3::from(meta.bounds.max) - glam::DVec3::from(meta.bounds.min);
            row(
                "size",
                format!("{:.4} × {:.4} × {:.4}", size.x, size.y, size.z),
            );
            let o = meta.origin;
            row("origin", format!("{} {} {}", o[0], o[1], o[2]));
            if let Some(s) = m.load_seconds {
                row("opened in", format!("{s:.2} s"));
            }
        }
    });
    ui.add(egui::Label::new(RichText::new(status.adapter).small()).wrap());
}
