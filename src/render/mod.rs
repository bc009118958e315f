//! Rendering (DESIGN.md §6–7): the GPU, cameras, and the three-pass deferred EWA
//! splatting renderer with its mesh reference pass, drawing a [`Scene`] of the tree
//! layer (the only layer it imports). WGSL lives in `shaders/`.

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
pub mod settings;
mod shaders;
mod targets;
pub mod upload;

pub use crate::tree::scene::{MeshData, Scene};
pub use camera::Camera;
pub use counters::{CounterReadback, GpuCounters};
pub use encode::EncodedFrame;
pub use gpu::Gpu;
pub use pipelines::{OUTPUT_GAMMA, fullscreen_pipeline};
pub use renderer::{FrameStats, Image, Renderer};
pub use settings::{Culling, Mode, Settings};
pub use shaders::module as shader_module;
pub use targets::FrameTargets;
pub use upload::{GpuScene, MeshUpload, SliceUpload};
