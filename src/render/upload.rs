//! Putting a scene on the GPU: the list in slices of at most one storage binding (and
//! one dispatch of the cull pass), each with its survivor list and compaction record,
//! front (coarse) first, so that a model can be drawn while the rest arrives; and the
//! mesh of the reference pass.

use wgpu::util::DeviceExt;

use super::cull::{Compaction, CullPass, TestRange};
use super::gpu::Gpu;
use super::gpu_scene::{GpuScene, Slice, SliceUpload};
use super::shaders::WORKGROUP_SIZE;
use super::splats::SplatPasses;
use crate::tree::NodeRecord;
use crate::tree::record::{PointAttributes, SplatShape};

/// Nodes per slice at most: one dispatch of 65,535 workgroups covers a slice.
const MAX_SLICE_NODES: u64 = 65_535 * WORKGROUP_SIZE as u64;

/// Nodes per slice: one storage binding, one dispatch.
fn nodes_per_slice(gpu: &Gpu) -> usize {
    let record = std::mem::size_of::<NodeRecord>() as u64;
    (gpu.max_binding_bytes() / record).clamp(1, MAX_SLICE_NODES) as usize
}

/// The node ranges of the slices of a list of `total` nodes, front first.
pub(super) fn slice_plan(gpu: &Gpu, total: usize) -> impl Iterator<Item = std::ops::Range<usize>> {
    let per_slice = nodes_per_slice(gpu);
    (0..total)
        .step_by(per_slice)
        .map(move |start| start..(start + per_slice).min(total))
}

/// A scene of `total` nodes with nothing uploaded yet.
pub(super) fn empty_gpu_scene(gpu: &Gpu, total: usize) -> GpuScene {
    GpuScene {
        slices: Vec::new(),
        mesh: None,
        planned_slices: slice_plan(gpu, total).count(),
    }
}

/// A bind group of `layout` with each (binding, buffer) of `buffers`.
fn bind(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout,
        entries: &entries,
    })
}

/// Uploads one slice of the list (a range of [`slice_plan`]): its node records, their
/// shapes and LiDAR attributes (empty for a model without: one zero is bound in their
/// place), bound for both culling strategies, with room for `max_ranges` test ranges,
/// to be pushed in order.
pub(super) fn upload_slice(
    device: &wgpu::Device,
    (splats, cull): (&SplatPasses, &CullPass),
    (chunk, chunk_shapes, chunk_attributes): (&[NodeRecord], &[SplatShape], &[PointAttributes]),
    max_ranges: usize,
) -> SliceUpload {
    assert_eq!(chunk.len(), chunk_shapes.len());
    assert!(chunk_attributes.is_empty() || chunk_attributes.len() == chunk.len());
    let storage = |label, contents| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let nodes = storage("nodes", bytemuck::cast_slice(chunk));
    let shapes = storage("shapes", bytemuck::cast_slice(chunk_shapes));
    let none = [PointAttributes::default()];
    let attributes = storage(
        "attributes",
        bytemuck::cast_slice(if chunk_attributes.is_empty() {
            &none
        } else {
            chunk_attributes
        }),
    );
    let survivors = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("survivors"),
        size: (std::mem::size_of::<u32>() * chunk.len()) as u64,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let compaction = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("compaction"),
        size: std::mem::size_of::<Compaction>() as u64,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::INDIRECT
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let ranges = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("test ranges"),
        size: (std::mem::size_of::<TestRange>() * max_ranges.max(1)) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    SliceUpload(Slice {
        count: chunk.len() as u32,
        direct: bind(
            device,
            &splats.nodes_layout,
            &[(0, &nodes), (2, &shapes), (3, &attributes)],
        ),
        cull: bind(
            device,
            &cull.layout,
            &[(0, &nodes), (1, &survivors), (2, &compaction), (3, &ranges)],
        ),
        compacted: bind(
            device,
            &splats.compacted_layout,
            &[(0, &nodes), (1, &survivors), (2, &shapes), (3, &attributes)],
        ),
        compaction,
        ranges,
    })
}
