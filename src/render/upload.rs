//! Putting a scene on the GPU: the list in slices of at most one storage binding (and
//! one dispatch of the cull pass), each with its survivor list and compaction record,
//! front (coarse) first, so that a model can be drawn while the rest arrives, or under
//! a GPU memory budget in smaller slices, uploaded as views need them; and the mesh of
//! the reference pass.

use wgpu::util::DeviceExt;

use super::bindings::{self as slots, Slot, splat};
use super::cull::{Compaction, CullPass, TestRange};
use super::gpu::Gpu;
use super::gpu_scene::{GpuScene, InstancedRoom, Slice, SliceUpload};
use super::placement::Placement;
use super::raster::ComputeRaster;
use super::shaders::WORKGROUP_SIZE;
use super::splats::SplatPasses;
use crate::io::geometry::PointAttributes;
use crate::surfel::shape::SplatShape;
use crate::tree::NodeRecord;
use crate::tree::scene::Scene;

/// Nodes per slice at most: one dispatch of 65,535 workgroups covers a slice.
const MAX_SLICE_NODES: u64 = 65_535 * WORKGROUP_SIZE as u64;

/// Nodes per slice at most: one storage binding, one dispatch.
fn max_slice_nodes(gpu: &Gpu) -> usize {
    let record = std::mem::size_of::<NodeRecord>() as u64;
    (gpu.max_binding_bytes() / record).clamp(1, MAX_SLICE_NODES) as usize
}

/// Slices of a list of `nodes` nodes without a memory budget.
pub(super) fn planned_slices(gpu: &Gpu, nodes: usize) -> usize {
    nodes.div_ceil(max_slice_nodes(gpu))
}

/// Slices of at least this many nodes under a budget (smaller ones cost more draw calls
/// than they save memory).
const MIN_BUDGET_SLICE_NODES: usize = 1 << 14;

/// A budget holds at least this many slices, so that it can keep the coarse front of the
/// list and still follow the view.
const SLICES_PER_BUDGET: u64 = 64;

/// GPU bytes per node of a slice: its record, shape, survivor index and, for a model
/// with LiDAR attributes, those.
fn node_bytes(has_attributes: bool) -> u64 {
    (std::mem::size_of::<NodeRecord>()
        + std::mem::size_of::<SplatShape>()
        + std::mem::size_of::<u32>()
        + if has_attributes {
            std::mem::size_of::<PointAttributes>()
        } else {
            0
        }) as u64
}

/// Bytes of the buffers [`upload_slice`] makes for `count` nodes with room for
/// `max_ranges` test ranges, drawn alone (`room`: None) or at many placements.
pub(super) fn slice_bytes(
    count: usize,
    has_attributes: bool,
    max_ranges: usize,
    room: Option<InstancedRoom>,
) -> u64 {
    let none = if has_attributes {
        0
    } else {
        std::mem::size_of::<PointAttributes>()
    };
    // Alone: one survivor index a node (in node_bytes) and one shared placement index.
    let survivors = match room {
        None => std::mem::size_of::<u32>() as u64,
        Some(r) => {
            (r.survivors * 2 * std::mem::size_of::<u32>()) as u64
                - (count * std::mem::size_of::<u32>()) as u64
        }
    };
    count as u64 * node_bytes(has_attributes)
        + survivors
        + (none + std::mem::size_of::<Compaction>()) as u64
        + (std::mem::size_of::<TestRange>() * max_ranges.max(1)) as u64
}

/// A scene of `total` nodes with nothing uploaded yet, planned in slices of the most
/// nodes a binding holds, or under a GPU memory budget of `budget` bytes in slices of
/// about 1/64 of what it holds; drawn alone (`room` None) or at up to `room.0`
/// placements a frame, each slice with `room.1`.
pub(super) fn empty_gpu_scene(
    gpu: &Gpu,
    total: usize,
    budget: Option<u64>,
    has_attributes: bool,
    room: Option<(usize, InstancedRoom)>,
) -> GpuScene {
    let most = max_slice_nodes(gpu);
    let slice_nodes = match budget {
        None => most,
        Some(bytes) => {
            let fit = (bytes / node_bytes(has_attributes) / SLICES_PER_BUDGET) as usize;
            fit.clamp(MIN_BUDGET_SLICE_NODES.min(most), most)
        }
    };
    let placements = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("placements"),
        size: (std::mem::size_of::<Placement>() * room.map_or(1, |r| r.0.max(1))) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    GpuScene::new(total, slice_nodes, (placements, room.map(|r| r.1)))
}

/// A bind group of `layout` with each (binding, buffer) of `buffers`.
fn bind(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(Slot, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .map(|(slot, b)| wgpu::BindGroupEntry {
            binding: slot.binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout,
        entries: &entries,
    })
}

/// The buffers of one slice: its nodes, shapes and attributes, its survivor list (and
/// their placements), compaction record and test ranges.
struct SliceBuffers {
    nodes: wgpu::Buffer,
    shapes: wgpu::Buffer,
    attributes: wgpu::Buffer,
    survivors: wgpu::Buffer,
    survivor_placements: wgpu::Buffer,
    compaction: wgpu::Buffer,
    ranges: wgpu::Buffer,
}

impl SliceBuffers {
    /// Made for the nodes, shapes and attributes of a slice, with room for `max_ranges`
    /// test ranges and [`upload_slice`]'s survivor list.
    fn new(
        device: &wgpu::Device,
        (chunk, chunk_shapes, chunk_attributes): (&[NodeRecord], &[SplatShape], &[PointAttributes]),
        room: Option<InstancedRoom>,
        max_ranges: usize,
    ) -> SliceBuffers {
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
        let indices = |label, count: usize| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (std::mem::size_of::<u32>() * count.max(1)) as u64,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let survivors = indices("survivors", room.map_or(chunk.len(), |r| r.survivors));
        let survivor_placements = indices("survivor placements", room.map_or(1, |r| r.survivors));
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
        SliceBuffers {
            nodes,
            shapes,
            attributes,
            survivors,
            survivor_placements,
            compaction,
            ranges,
        }
    }
}

/// Uploads slice `index` of the list, whose first node is `first`: its node records,
/// their shapes and LiDAR attributes (empty for a model without: one zero is bound in
/// their place), bound for both culling strategies with the model's `placements`, with
/// room for `max_ranges` test ranges and a survivor list: one survivor a node for a
/// model drawn alone (`room` None; its survivors all share placement 0), or `room`'s.
pub(super) fn upload_slice(
    device: &wgpu::Device,
    (splats, cull, raster): (&SplatPasses, &CullPass, &ComputeRaster),
    (index, first): (usize, usize),
    (chunk, chunk_shapes, chunk_attributes): (&[NodeRecord], &[SplatShape], &[PointAttributes]),
    (placements, room): (&wgpu::Buffer, Option<InstancedRoom>),
    max_ranges: usize,
) -> SliceUpload {
    let max_ranges = room.map_or(max_ranges, |r| r.ranges);
    let b = SliceBuffers::new(
        device,
        (chunk, chunk_shapes, chunk_attributes),
        room,
        max_ranges,
    );
    SliceUpload(Slice {
        index,
        first,
        count: chunk.len() as u32,
        bytes: slice_bytes(chunk.len(), !chunk_attributes.is_empty(), max_ranges, room),
        direct: bind(
            device,
            &splats.nodes_layout,
            &[
                (splat::NODES, &b.nodes),
                (splat::SHAPES, &b.shapes),
                (splat::ATTRIBUTES, &b.attributes),
                (splat::PLACEMENTS, placements),
            ],
        ),
        cull: bind(
            device,
            &cull.layout,
            &[
                (slots::cull::NODES, &b.nodes),
                (slots::cull::SURVIVORS, &b.survivors),
                (slots::cull::COMPACTION, &b.compaction),
                (slots::cull::RANGES, &b.ranges),
                (slots::cull::SHAPES, &b.shapes),
                (slots::cull::PLACEMENTS, placements),
                (slots::cull::SURVIVOR_PLACEMENTS, &b.survivor_placements),
            ],
        ),
        compacted: bind(
            device,
            &splats.compacted_layout,
            &[
                (splat::NODES, &b.nodes),
                (splat::SURVIVORS, &b.survivors),
                (splat::SHAPES, &b.shapes),
                (splat::ATTRIBUTES, &b.attributes),
                (splat::PLACEMENTS, placements),
                (splat::SURVIVOR_PLACEMENTS, &b.survivor_placements),
            ],
        ),
        rasterized: raster.bind_slice([
            (slots::raster::NODES, &b.nodes),
            (slots::raster::SURVIVORS, &b.survivors),
            (slots::raster::SHAPES, &b.shapes),
            (slots::raster::ATTRIBUTES, &b.attributes),
            (slots::raster::COMPACTION, &b.compaction),
            (slots::raster::PLACEMENTS, placements),
            (slots::raster::SURVIVOR_PLACEMENTS, &b.survivor_placements),
        ]),
        compaction: b.compaction,
        ranges: b.ranges,
    })
}

/// The chunks that overlap a node range: the most test ranges a frame hands its slice.
pub(super) fn max_ranges(scene: &Scene, range: &std::ops::Range<usize>) -> usize {
    let chunks = scene.index.chunks();
    // The chunks are in list order: those overlapping start at the one holding range.start.
    let first = chunks.partition_point(|c| c.range().end <= range.start);
    chunks[first..]
        .iter()
        .take_while(|c| c.range().start < range.end)
        .count()
}
