//! Far instances placed by the GPU: a frame of a scene hands each model's far groups
//! (those whose every member lies at least `FAR_RADII` of its sphere's radii from the
//! eye, `instance_plan.rs`) to the GPU whole, instead of planning their members one by
//! one on the CPU.
//!
//! ```text
//! CPU, per frame: far groups (member ranges) + the model's table at ε for the slots
//!                 they may reach (filled once per ε and slot, lod.rs)
//! GPU: place       a thread per member: cone test, slot = ⌊16 log₂(d / r)⌋, placement
//!                  appended after the CPU's, with its slot        (place.wgsl)
//!      settle_far  cull_far's dispatch, the survivors left to it  (cull.wgsl)
//!      cull_far    a workgroup per placed instance tests its slot's ranges
//!      settle_raster  the compute rasterizer's dispatch
//! ```
//!
//! The slot is the one `ModelLod::far` takes on the CPU: the eye's distance to the
//! instance's sphere in model units, rounded down to 1/16 octave, so the ranges hold
//! every node the exact test draws (lod.rs). Positions reach the GPU as an f32 and the
//! f16 rest of the f64 value (about 2⁻³⁵ of it), relative to the scene's origin, so an
//! instance 10⁶ units away is placed to about 3·10⁻⁵ units. A frame cannot know before
//! it ends how many survivors its far instances ask for: those beyond the list's room
//! are counted, not stored, and the next frame coarsens ([`FarCounts::asked`]).

mod model;
mod pass;
mod plan;
mod records;

pub(super) use model::{BYTES_PER_INSTANCE, FarModel};
pub(super) use pass::{FarDraw, FarPass};
pub(super) use plan::FarPlan;
pub use records::FarCounts;
pub(super) use records::{FarArgs, FarCounters};
