//! A view drawn under a GPU memory budget without a window (`spt render --gpu-memory`,
//! tests): the slices the view wants are uploaded, coarse first, evicting what it does
//! not want, until all of them are resident or the budget is full ([`Residency`]); a
//! view whose slices do not all fit is drawn coarser ([`super::plan`]), never holed.
//! The viewer streams the same way, a few slices per frame, on a background thread.

use super::camera::Camera;
use super::gpu_scene::GpuScene;
use super::plan::plan;
use super::renderer::Renderer;
use super::residency::{Residency, mib};
use super::settings::Settings;
use super::upload;
use crate::tree::scene::Scene;

impl Renderer {
    /// Bytes slice `k` of `gpu`'s plan takes on the GPU once uploaded.
    pub fn slice_bytes(&self, scene: &Scene, gpu: &GpuScene, k: usize) -> u64 {
        let range = gpu.slice_range(k);
        let has_attributes = scene.meta().has_attributes;
        upload::slice_bytes(
            range.len(),
            has_attributes,
            upload::max_ranges(scene, &range),
            gpu.room,
        )
    }

    /// A scene's list planned for a GPU memory `budget` (bytes), with its first slice (the
    /// root and the coarse front of the list) uploaded, and the residency that mirrors it.
    /// An error when even that slice exceeds the budget.
    pub fn begin_streaming(
        &self,
        scene: &Scene,
        budget: u64,
    ) -> anyhow::Result<(GpuScene, Residency)> {
        let mut gpu = self.empty_gpu_scene(scene, Some(budget));
        let mut residency = Residency::new(budget, gpu.planned_slices());
        let first = self.slice_bytes(scene, &gpu, 0);
        anyhow::ensure!(
            first <= budget,
            "a GPU memory budget of {:.1} MiB is below the coarsest slice of the list ({:.1} MiB)",
            mib(budget),
            mib(first)
        );
        gpu.insert(self.upload_slice(scene, &gpu.home(), 0, gpu.slice_range(0)));
        residency.arrived(0, first);
        Ok((gpu, residency))
    }

    /// Uploads what the view of `camera` over `size` pixels wants within the residency's
    /// budget, evicting the slices it does not want.
    pub fn stream_for_view(
        &self,
        scene: &Scene,
        (gpu, residency): (&mut GpuScene, &mut Residency),
        camera: &Camera,
        settings: &Settings,
        size: (u32, u32),
    ) {
        loop {
            // Only the slices it wants: no prefix need be trimmed.
            let frame = plan(scene, camera, settings, size, gpu, (false, false));
            let bytes_of = |k| self.slice_bytes(scene, gpu, k);
            let decision = residency.after_frame(&frame.wanted_slices, bytes_of, usize::MAX);
            for &k in &decision.evict {
                gpu.evict(k);
            }
            if decision.fetch.is_empty() {
                return;
            }
            for k in decision.fetch {
                let slice = self.upload_slice(scene, &gpu.home(), k, gpu.slice_range(k));
                residency.arrived(k, slice.bytes());
                gpu.insert(slice);
            }
        }
    }
}
