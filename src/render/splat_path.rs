//! The seam between a frame's passes and the way its splats are drawn. The renderer
//! plans the frame, culls (compute culling fills each slice's survivor lists), clears
//! the G-buffer and, after the splats, shades it (pass 3); in between, a [`SplatPath`]
//! records the splat passes into the G-buffer of the frame's targets:
//!
//! ```text
//! pass 1 visibility: the nearest pushed-back depth per pixel
//! pass 2 attributes: (colour·w, w), (normal·w, z·w) and coverage of the fragments
//!                    within pass 1's depth          (or: plain points instead of both)
//! ```
//!
//! [`super::splats::SplatPasses`] draws them through the raster pipeline (instanced
//! quads, blending). Another way (a compute rasterizer) implements this trait over the
//! same slices and G-buffer, and the cull, mesh and shading passes stay as they are.

use super::gpu_scene::Share;
use super::settings::Mode;
use super::targets::FrameTargets;

pub(super) trait SplatPath {
    /// Records the splat passes of display mode `mode` (points, or visibility then
    /// attributes) for the nodes of `shares`: after compute culling (`compacted`) each
    /// slice's survivor lists, else every node of its ranges, tested as it is drawn.
    /// Writes the passes' timestamps into `targets`' queries.
    fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &FrameTargets,
        shares: &[Share],
        mode: Mode,
        compacted: bool,
    );
}
