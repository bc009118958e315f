//! `spt view [MODEL]`: the large-mesh viewer. A window (winit) showing the renderer's
//! frames with a panel (egui) over them; models open in the background.
//!
//! ```text
//! app.rs ── winit events ─► input.rs (Input) ─► viewer.rs (camera: controls.rs, settings)
//!    │                                              │ records the frame (render::encode)
//!    ├── panel.rs (egui, drawn over the frame) ◄────┘
//!    ├── loader.rs (PLY → tree, or .spt mmap, then upload; on its own thread)
//!    └── present.rs (copies the finished frame onto the window's surface)
//! ```

mod app;
pub mod controls;
pub mod input;
mod legend;
pub mod loader;
pub mod pacing;
mod panel;
mod present;
pub mod streamer;
pub mod viewer;

use std::path::PathBuf;

use anyhow::Context;

use crate::apps::frame_args::RenderArgs;

/// The model opened when none is given, relative to the repository.
pub const DEFAULT_MODEL: &str = "data/torus_knot.ply";

/// The options of `spt view`.
#[derive(Debug, Clone, clap::Args)]
pub struct ViewArgs {
    /// The model: a PLY, LAS or LAZ file (converted in the background) or an .spt file
    /// (memory-mapped).
    /// Default: data/torus_knot.ply.
    pub model: Option<PathBuf>,
    #[command(flatten)]
    pub render: RenderArgs,
    /// Draw --frames frames of the model (the window's --size, camera options as for
    /// `spt render`), save the window's picture to this PNG, print the frame times and
    /// exit. For scripts and tests.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Start with the panel hidden (Tab shows it).
    #[arg(long)]
    pub hide_panel: bool,
    /// Turn the camera this many degrees around the model every frame (a turntable,
    /// to measure frame times while orbiting).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub spin: f64,
    /// Hold this frame time while the camera moves, in ms: the level of detail coarsens
    /// (ε_px grows) until frames take about this long, and returns to --error-px once the
    /// camera has rested for 0.3 s.
    #[arg(long, value_parser = parse_target_ms)]
    pub target_ms: Option<f64>,
}

/// A frame-time target: a finite number of milliseconds, at least 1.
fn parse_target_ms(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 1.0 => Ok(v),
        _ => Err(format!("{s}: a frame time in ms, at least 1")),
    }
}

/// The default model: `data/torus_knot.ply` under the current directory, else under the
/// repository the executable was built in.
pub fn default_model() -> anyhow::Result<PathBuf> {
    let here = PathBuf::from(DEFAULT_MODEL);
    if here.exists() {
        return Ok(here);
    }
    let built_in = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(DEFAULT_MODEL);
    if built_in.exists() {
        return Ok(built_in);
    }
    anyhow::bail!(
        "no model given and the default {DEFAULT_MODEL} is not here: give a PLY or .spt file \
         (regenerate the default with `cargo run --release --example gen_model`)"
    )
}

pub fn run(args: ViewArgs) -> anyhow::Result<()> {
    let model = match &args.model {
        Some(m) => m.clone(),
        None => default_model()?,
    };
    if !model.exists() {
        anyhow::bail!("{}: no such file", model.display());
    }
    if let Some(shot) = &args.screenshot {
        crate::io::atomic::check_writable(shot, &[&model])?;
    }
    let event_loop = winit::event_loop::EventLoop::<app::Wake>::with_user_event()
        .build()
        .context(
            "cannot open a window (no display? set DISPLAY, or run under Xvfb: \
             xvfb-run spt view ...)",
        )?;
    let mut app = app::App::new(args, model, event_loop.create_proxy());
    event_loop.run_app(&mut app)?;
    match app.failure {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
