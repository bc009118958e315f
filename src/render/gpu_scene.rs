//! A scene's list and mesh as they live on the GPU: the list in slices of at most one
//! storage binding, each with the buffers compute culling compacts into, and the mesh's
//! vertex and index buffers. Made by `upload.rs`; drawn by the passes.

use std::ops::Range;

/// One slice of the list on the GPU, with what compute culling needs.
pub(super) struct Slice {
    pub count: u32,
    /// Nodes, for vertex culling (`splats.rs`).
    pub direct: wgpu::BindGroup,
    /// Nodes, survivors (read_write) and the compaction record, for the cull pass.
    pub cull: wgpu::BindGroup,
    /// Nodes and survivors, for the compacted draw.
    pub compacted: wgpu::BindGroup,
    /// The slice's [`super::cull::Compaction`]: indirect draw arguments, then the
    /// slice's share of the nodes to test.
    pub compaction: wgpu::Buffer,
    /// The slice's [`super::cull::TestRange`]s of the frame, for the cull pass.
    pub ranges: wgpu::Buffer,
}

/// What one frame tests of a slice: its part of the frame's ranges, relative to the
/// slice's first node, and the nodes in them.
pub(super) struct Share<'a> {
    pub slice: &'a Slice,
    pub ranges: Vec<Range<u32>>,
    pub count: u32,
}

/// The mesh of the reference pass on the GPU.
pub(super) struct MeshBuffers {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub index_count: u32,
}

/// The list and mesh of a scene on the GPU. It may be uploaded a slice at a time, front
/// (coarse) first: frames drawn meanwhile use what is there (see `plan.rs`).
pub struct GpuScene {
    pub(super) slices: Vec<Slice>,
    pub(super) mesh: Option<MeshBuffers>,
    /// Slices the whole list takes.
    pub(super) planned_slices: usize,
}

/// One slice uploaded, to be added with [`GpuScene::push`].
pub struct SliceUpload(pub(super) Slice);

/// The mesh uploaded, to be added with [`GpuScene::set_mesh`].
pub struct MeshUpload(pub(super) MeshBuffers);

impl GpuScene {
    /// Triangles of the mesh reference (0 without one).
    pub fn mesh_triangles(&self) -> u32 {
        self.mesh.as_ref().map_or(0, |m| m.index_count / 3)
    }

    /// Nodes on the GPU so far: always a prefix of the list.
    pub fn uploaded_nodes(&self) -> usize {
        self.slices.iter().map(|s| s.count as usize).sum()
    }

    /// Slices of the whole list (uploaded or not).
    pub(super) fn planned_slices(&self) -> usize {
        self.planned_slices
    }

    pub fn push(&mut self, slice: SliceUpload) {
        self.slices.push(slice.0);
    }

    pub fn set_mesh(&mut self, mesh: MeshUpload) {
        self.mesh = Some(mesh.0);
    }

    /// Each uploaded slice with its share of `ranges` (list indices, ascending; the
    /// parts past the uploaded slices are left out).
    pub(super) fn shares(&self, ranges: &[Range<usize>]) -> Vec<Share<'_>> {
        let mut first = 0;
        self.slices
            .iter()
            .map(|slice| {
                let end = first + slice.count as usize;
                let local: Vec<Range<u32>> = ranges
                    .iter()
                    .filter(|r| r.start < end && r.end > first)
                    .map(|r| (r.start.max(first) - first) as u32..(r.end.min(end) - first) as u32)
                    .collect();
                first = end;
                Share {
                    slice,
                    count: local.iter().map(|r| r.len() as u32).sum(),
                    ranges: local,
                }
            })
            .collect()
    }
}
