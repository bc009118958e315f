//! Rendering (DESIGN.md §6–7): the GPU, cameras, scenes, and the three-pass deferred EWA
//! splatting renderer with its mesh reference pass. WGSL lives in `shaders/`.

pub mod camera;
mod counters;
mod encode;
mod frame;
mod gbuffer;
pub mod gpu;
pub mod metrics;
mod pipelines;
mod readback;
pub mod renderer;
pub mod scene;
pub mod settings;
mod targets;
pub mod upload;

pub use camera::Camera;
pub use counters::{CounterReadback, GpuCounters};
pub use encode::EncodedFrame;
pub use gpu::Gpu;
pub use pipelines::{FULLSCREEN, OUTPUT_GAMMA, fullscreen_pipeline};
pub use renderer::{FrameStats, Image, Renderer};
pub use scene::{LoadReport, Scene, Silent};
pub use settings::{Culling, Mode, Settings};
pub use targets::FrameTargets;
pub use upload::{GpuScene, MeshUpload, SliceUpload};
