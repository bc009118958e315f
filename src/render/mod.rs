//! Rendering (DESIGN.md §6–7): the GPU, cameras, scenes, and the three-pass deferred EWA
//! splatting renderer with its mesh reference pass. WGSL lives in `shaders/`.

pub mod camera;
mod frame;
mod gbuffer;
pub mod gpu;
pub mod metrics;
mod pipelines;
mod readback;
pub mod renderer;
pub mod scene;
pub mod settings;
pub mod upload;

pub use camera::Camera;
pub use gpu::Gpu;
pub use renderer::{FrameStats, Image, Renderer};
pub use scene::Scene;
pub use settings::{Culling, Mode, Settings};
pub use upload::GpuScene;
