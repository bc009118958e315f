//! A scene's list and mesh as they live on the GPU: the list in slices of at most one
//! storage binding, each with the buffers compute culling compacts into, and the mesh's
//! vertex and index buffers. Made by `upload.rs`; drawn by the passes.

use std::ops::Range;
use std::sync::atomic::AtomicBool;

/// One slice of the list on the GPU, with what compute culling needs.
pub(super) struct Slice {
    /// Its index in the scene's plan, and its first node (list index).
    pub index: usize,
    pub first: usize,
    pub count: u32,
    /// Bytes of its buffers ([`super::upload::slice_bytes`]).
    pub bytes: u64,
    /// Nodes, for vertex culling (`splats.rs`).
    pub direct: wgpu::BindGroup,
    /// Nodes, survivors (read_write) and the compaction record, for the cull pass.
    pub cull: wgpu::BindGroup,
    /// Nodes and survivors, for the compacted draw.
    pub compacted: wgpu::BindGroup,
    /// Nodes, survivors and the compaction record, for the compute rasterizer.
    pub rasterized: wgpu::BindGroup,
    /// The slice's [`super::cull::Compaction`]: indirect draw arguments, then the
    /// slice's share of the nodes to test.
    pub compaction: wgpu::Buffer,
    /// The slice's [`super::cull::TestRange`]s of the frame, for the cull pass.
    pub ranges: wgpu::Buffer,
}

/// What one frame tests of a slice: its part of the frame's ranges, relative to the
/// slice's first node, the placement of each (empty: all at placement 0, a model drawn
/// alone), and the nodes in them; where the GPU also culls far instances into it, the
/// buffer of the compute rasterizer's dispatch over its survivors
/// ([`super::far::FarArgs::RASTER_AT`]).
pub(super) struct Share<'a> {
    pub slice: &'a Slice,
    pub ranges: Vec<Range<u32>>,
    pub placements: Vec<u32>,
    pub count: u32,
    pub far: Option<&'a wgpu::Buffer>,
}

impl Share<'_> {
    /// Whether the frame may draw survivors of this slice.
    pub fn drawn(&self) -> bool {
        self.count > 0 || self.far.is_some()
    }
}

/// The mesh of the reference pass on the GPU.
pub(super) struct MeshBuffers {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub index_count: u32,
}

/// The list and mesh of a scene on the GPU. The list is planned in slices of
/// `slice_nodes` consecutive nodes; any set of them may be resident: a prefix while a
/// model uploads front (coarse) first, or, under a GPU memory budget, the slices the
/// recent views needed ([`super::residency`]). Frames drawn meanwhile use what is there
/// (see `plan.rs`).
pub struct GpuScene {
    /// Slot k holds slice k (nodes k·slice_nodes …) when it is resident.
    pub(super) slices: Vec<Option<Slice>>,
    pub(super) mesh: Option<MeshBuffers>,
    pub(super) slice_nodes: usize,
    pub(super) total: usize,
    resident_bytes: u64,
    /// Whether the last frame planned found its asked ε's ranges all resident: the
    /// next one searches at that ε first (`plan.rs`).
    pub(super) asked_fitted: AtomicBool,
    /// Where the model is drawn this frame ([`super::placement::Placement`]s, written
    /// before each frame): one for a model drawn alone, one per instance otherwise.
    pub(super) placements: wgpu::Buffer,
    /// Room per slice for a model drawn at many placements (None: drawn alone).
    pub(super) room: Option<InstancedRoom>,
    /// The counters of its far instances, where the GPU places them (`far.rs`).
    pub(super) far_counters: Option<wgpu::Buffer>,
}

/// What a model drawn at many placements holds room for in each slice: survivors (each
/// with its placement index) and test ranges a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InstancedRoom {
    pub survivors: usize,
    pub ranges: usize,
}

/// What each slice of a [`GpuScene`] binds besides its own buffers, and the room it
/// makes: given to whoever uploads slices ([`GpuScene::home`]), on any thread.
#[derive(Clone)]
pub struct SliceHome {
    pub(super) placements: wgpu::Buffer,
    pub(super) room: Option<InstancedRoom>,
}

/// One slice uploaded, to be added with [`GpuScene::insert`].
pub struct SliceUpload(pub(super) Slice);

impl SliceUpload {
    /// The slice's index in its scene's plan.
    pub fn index(&self) -> usize {
        self.0.index
    }

    /// Bytes of its buffers on the GPU.
    pub fn bytes(&self) -> u64 {
        self.0.bytes
    }
}

/// The mesh uploaded, to be added with [`GpuScene::set_mesh`].
pub struct MeshUpload(pub(super) MeshBuffers);

impl GpuScene {
    pub(super) fn new(
        total: usize,
        slice_nodes: usize,
        (placements, room): (wgpu::Buffer, Option<InstancedRoom>),
    ) -> GpuScene {
        let slice_nodes = slice_nodes.max(1);
        GpuScene {
            slices: (0..total.div_ceil(slice_nodes)).map(|_| None).collect(),
            mesh: None,
            slice_nodes,
            total,
            resident_bytes: 0,
            asked_fitted: AtomicBool::new(true),
            placements,
            room,
            far_counters: None,
        }
    }

    /// What its slices bind and make room for, to upload them.
    pub fn home(&self) -> SliceHome {
        SliceHome {
            placements: self.placements.clone(),
            room: self.room,
        }
    }

    /// Triangles of the mesh reference (0 without one).
    pub fn mesh_triangles(&self) -> u32 {
        self.mesh.as_ref().map_or(0, |m| m.index_count / 3)
    }

    /// Bytes of the resident slices' buffers (nodes, shapes, attributes, survivors,
    /// compaction record and test ranges; the mesh is not counted).
    pub fn resident_bytes(&self) -> u64 {
        self.resident_bytes
    }

    /// Slices on the GPU.
    pub fn resident_slices(&self) -> usize {
        self.slices.iter().flatten().count()
    }

    /// Slices of the whole list (resident or not).
    pub fn planned_slices(&self) -> usize {
        self.slices.len()
    }

    /// The node range of slice `k` of the plan.
    pub fn slice_range(&self, k: usize) -> Range<usize> {
        k * self.slice_nodes..((k + 1) * self.slice_nodes).min(self.total)
    }

    /// The slices a node range lies in.
    pub fn slices_of(&self, r: &Range<usize>) -> Range<usize> {
        if r.is_empty() {
            return 0..0;
        }
        r.start / self.slice_nodes..(r.end - 1) / self.slice_nodes + 1
    }

    pub fn is_resident(&self, k: usize) -> bool {
        self.slices.get(k).is_some_and(Option::is_some)
    }

    /// Whether every node of `r` is on the GPU.
    pub fn covers(&self, r: &Range<usize>) -> bool {
        self.slices_of(r).all(|k| self.is_resident(k))
    }

    /// Nodes on the GPU from list index `start` on, up to `count`: the run of resident
    /// slices that starts with `start`'s.
    pub fn resident_run(&self, start: usize, count: usize) -> usize {
        let mut end = start;
        while end < start + count && self.is_resident(end / self.slice_nodes) {
            end = self.slice_range(end / self.slice_nodes).end;
        }
        end.min(start + count) - start
    }

    /// The parts of `ranges` that are on the GPU.
    pub fn clip(&self, ranges: &[Range<usize>]) -> Vec<Range<usize>> {
        let mut out: Vec<Range<usize>> = Vec::new();
        for r in ranges {
            for k in self.slices_of(r).filter(|&k| self.is_resident(k)) {
                let s = self.slice_range(k);
                let part = r.start.max(s.start)..r.end.min(s.end);
                match out.last_mut() {
                    Some(last) if last.end == part.start => last.end = part.end,
                    _ => out.push(part),
                }
            }
        }
        out
    }

    /// The resident slices, in list order.
    pub(super) fn resident(&self) -> impl Iterator<Item = &Slice> {
        self.slices.iter().flatten()
    }

    /// Adds an uploaded slice (replacing the one resident in its place, if any).
    pub fn insert(&mut self, upload: SliceUpload) {
        let slice = upload.0;
        let k = slice.index;
        assert!(
            k < self.slices.len(),
            "slice {k} of a plan of {}",
            self.slices.len()
        );
        self.resident_bytes += slice.bytes;
        if let Some(old) = self.slices[k].replace(slice) {
            self.resident_bytes -= old.bytes;
        }
    }

    /// Drops slice `k` from the GPU; returns the bytes freed.
    pub fn evict(&mut self, k: usize) -> u64 {
        let freed = self
            .slices
            .get_mut(k)
            .and_then(Option::take)
            .map_or(0, |s| s.bytes);
        self.resident_bytes -= freed;
        freed
    }

    pub fn set_mesh(&mut self, mesh: MeshUpload) {
        self.mesh = Some(mesh.0);
    }

    /// Each resident slice with its share of `ranges` (list indices, ascending and
    /// disjoint; the parts in slices not resident are left out). Each slice's ranges are
    /// found by binary search: a frame of tens of thousands of ranges over hundreds of
    /// slices reads each range about once.
    pub(super) fn shares(&self, ranges: &[Range<usize>]) -> Vec<Share<'_>> {
        self.resident()
            .map(|slice| {
                let (first, end) = (slice.first, slice.first + slice.count as usize);
                let from = ranges.partition_point(|r| r.end <= first);
                let local: Vec<Range<u32>> = ranges[from..]
                    .iter()
                    .take_while(|r| r.start < end)
                    .map(|r| (r.start.max(first) - first) as u32..(r.end.min(end) - first) as u32)
                    .collect();
                Share {
                    slice,
                    count: local.iter().map(|r| r.len() as u32).sum(),
                    ranges: local,
                    placements: Vec::new(),
                    far: None,
                }
            })
            .collect()
    }
}
