//! Rendering (docs/design.md §6–7): the GPU, cameras, and the three-pass deferred EWA
//! splatting renderer with its mesh reference pass, drawing a
//! [`crate::tree::scene::Scene`] (it imports tree and surfel, and of io only the data
//! model; files are opened through the tree). One module per pass, each with its
//! layouts, pipeline, encoding and WGSL (`shaders/`, composed by [`shaders`]; the bind
//! slots they share in [`bindings`]; the splat passes through the raster pipeline
//! ([`splats`]) or in compute ([`raster`]), both writing the G-buffer that shading reads):
//!
//! ```text
//! plan ─► cull ─► splats (visibility, attributes; or points) | mesh ─► shading
//!             └─► raster (the same in compute) ─► resolve ─┘
//!          frame (uniform) · gbuffer · accumulation · targets · gpu_scene (upload)
//!          counters · residency (which slices stay under a GPU budget) · streamed
//!          placement (where a model is drawn) · instanced, instance_plan (scenes of
//!          instances: many placements a frame)
//! ```
//!
//! [`Renderer`] composes them.

mod accumulation;
pub mod bindings;
pub mod camera;
mod counters;
mod cull;
mod far;
mod frame;
mod fullscreen;
mod gbuffer;
pub(crate) mod gpu;
mod gpu_scene;
mod instance_plan;
mod instanced;
mod mesh;
mod placement;
mod plan;
mod raster;
mod readback;
pub(crate) mod renderer;
pub mod residency;
pub(crate) mod settings;
mod shaders;
mod shading;
mod splats;
mod streamed;
mod targets;
mod upload;

pub use camera::{Camera, OrbitAxes};
pub use counters::{CounterReadback, GpuCounters};
pub use far::FarCounts;
pub use frame::{linear_to_srgb, srgb_to_linear};
pub use fullscreen::{fragment_texture, fullscreen_pipeline};
pub use gpu::Gpu;
pub use gpu_scene::{GpuScene, MeshUpload, SliceHome, SliceUpload};
pub use instanced::{GpuInstances, InstancedFrame, SceneMemory};
pub use plan::EncodedFrame;
pub use renderer::{FrameStats, Image, Renderer};
pub use settings::{Culling, Mode, PrefixCut, Raster, Settings};
pub use shaders::module as shader_module;
pub use targets::{FrameTargets, OUTPUT, OUTPUT_GAMMA};
