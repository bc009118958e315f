//! Rendering (DESIGN.md §6–7): the GPU, cameras, scenes, and the three-pass deferred EWA
//! splatting renderer with its mesh reference pass. WGSL lives in `shaders/`.

pub mod camera;
pub mod gpu;
pub mod metrics;
pub mod renderer;
pub mod scene;

pub use camera::Camera;
pub use gpu::Gpu;
pub use renderer::{Culling, FrameStats, Image, Mode, Renderer, Settings};
pub use scene::Scene;
