//! Compute culling: each node of a slice's share of the frame's ranges (the visible
//! chunks' prefixes) is tested once against the selection test (and the frustum, and
//! back faces when asked); survivors are appended to the slice's survivor list, whose
//! length becomes the instance count of the indirect draw that follows (`splats.rs`, 4
//! vertices per survivor). One dispatch per slice covers all its ranges: thread i
//! finds its range by binary search over their running ends ([`TestRange`]). WGSL:
//! `shaders/cull.wgsl`.

use bytemuck::{Pod, Zeroable};

use super::bindings::{Slot, cull as slots};
use super::gpu_scene::Share;
use super::placement::Placement;
use super::shaders::{WORKGROUP_SIZE, module};

/// A slice's compaction record (`struct Compaction` in cull.wgsl): the arguments of the
/// two indirect draws, of the survivors on an outline and of the others, whose
/// instance counts the pass counts up; then the nodes of the slice to test, in how
/// many ranges, and the slice's first node (its list index).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(super) struct Compaction {
    pub outline: DrawIndirectArgs,
    pub inner: DrawIndirectArgs,
    pub count: u32,
    pub range_count: u32,
    pub first: u32,
}

/// `wgpu::util::DrawIndirectArgs`, as a Pod field (`struct DrawArgs` in cull.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(super) struct DrawIndirectArgs {
    pub vertex_count: u32,
    pub instance_count: u32,
    pub first_vertex: u32,
    pub first_instance: u32,
}

/// One range of a slice to test (`struct TestRange` in cull.wgsl): its first node
/// (relative to the slice), the running total of the nodes of the slice's ranges up
/// to and including it, and the placement its nodes are drawn at. Thread i tests node
/// `start + i − (end of the range before)` of the first range whose `end` exceeds i.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub(super) struct TestRange {
    pub start: u32,
    pub end: u32,
    pub placement: u32,
}

impl TestRange {
    /// The records of a share's ranges, range k at `placements[k]` (all at placement 0
    /// when `placements` is empty: a model drawn alone).
    pub fn of(ranges: &[std::ops::Range<u32>], placements: &[u32]) -> Vec<TestRange> {
        let mut end = 0;
        ranges
            .iter()
            .enumerate()
            .map(|(k, r)| {
                end += r.len() as u32;
                TestRange {
                    start: r.start,
                    end,
                    placement: placements.get(k).copied().unwrap_or(0),
                }
            })
            .collect()
    }
}

const _: () = assert!(
    std::mem::size_of::<DrawIndirectArgs>() == std::mem::size_of::<wgpu::util::DrawIndirectArgs>()
);

impl Compaction {
    /// Before culling: 4 vertices per splat, no survivor yet, `count` nodes to test in
    /// `range_count` ranges of the slice whose first node is `first`.
    pub fn reset(count: u32, range_count: u32, first: u32) -> Compaction {
        let draw = DrawIndirectArgs {
            vertex_count: 4,
            instance_count: 0,
            first_vertex: 0,
            first_instance: 0,
        };
        Compaction {
            outline: draw,
            inner: draw,
            count,
            range_count,
            first,
        }
    }

    /// Byte offsets of the two draws' arguments, in the order `splats.rs` draws them.
    pub const DRAWS_AT: [u64; 2] = [
        std::mem::offset_of!(Compaction, outline) as u64,
        std::mem::offset_of!(Compaction, inner) as u64,
    ];

    /// Byte offsets of the two instance counts (the survivors), for reading them back.
    pub const SURVIVORS_AT: [u64; 2] = [
        Compaction::DRAWS_AT[0] + std::mem::offset_of!(DrawIndirectArgs, instance_count) as u64,
        Compaction::DRAWS_AT[1] + std::mem::offset_of!(DrawIndirectArgs, instance_count) as u64,
    ];
}

/// A storage-buffer entry of `slot`, visible to the compute stage.
pub(super) fn storage(slot: Slot, read_only: bool, min_size: u64) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding: slot.binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(min_size),
        },
        count: None,
    }
}

/// The cull pass: its bind group layout (nodes, survivors, compaction, test ranges,
/// shapes) and pipeline.
pub(super) struct CullPass {
    pub layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl CullPass {
    pub fn new(device: &wgpu::Device, frame_layout: &wgpu::BindGroupLayout) -> CullPass {
        let node = size_of::<crate::tree::NodeRecord>() as u64;
        let shape = size_of::<crate::surfel::shape::SplatShape>() as u64;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cull"),
            entries: &[
                storage(slots::NODES, true, node),
                storage(slots::SURVIVORS, false, size_of::<u32>() as u64),
                storage(slots::COMPACTION, false, size_of::<Compaction>() as u64),
                storage(slots::RANGES, true, size_of::<TestRange>() as u64),
                storage(slots::SHAPES, true, shape),
                storage(slots::PLACEMENTS, true, size_of::<Placement>() as u64),
                storage(slots::SURVIVOR_PLACEMENTS, false, size_of::<u32>() as u64),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("cull"),
            bind_group_layouts: &[Some(frame_layout), Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("cull"),
            layout: Some(&pipeline_layout),
            module: &module(device, "cull"),
            entry_point: Some("cull"),
            compilation_options: Default::default(),
            cache: None,
        });
        CullPass { layout, pipeline }
    }

    /// Writes every slice's compaction record and ranges for its share (through the
    /// queue: they take effect at the next submit), then records the culling of each
    /// slice with nodes to test: the frame's first pass (`timestamps`: its start).
    pub fn encode(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        frame_bind: &wgpu::BindGroup,
        shares: &[Share],
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        for share in shares {
            let slice = share.slice;
            let first = slice.first as u32;
            let record = Compaction::reset(share.count, share.ranges.len() as u32, first);
            queue.write_buffer(&slice.compaction, 0, bytemuck::bytes_of(&record));
            if !share.ranges.is_empty() {
                let ranges = TestRange::of(&share.ranges, &share.placements);
                queue.write_buffer(&slice.ranges, 0, bytemuck::cast_slice(&ranges));
            }
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("cull"),
            timestamp_writes: timestamps,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, frame_bind, &[]);
        for share in shares.iter().filter(|s| s.count > 0) {
            pass.set_bind_group(1, &share.slice.cull, &[]);
            pass.dispatch_workgroups(share.count.div_ceil(WORKGROUP_SIZE), 1, 1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::TestRange;

    #[test]
    fn the_compaction_record_has_the_size_of_the_wgsl_struct() {
        super::super::shaders::assert_wgsl_size::<super::Compaction>("cull", "Compaction");
        super::super::shaders::assert_wgsl_size::<TestRange>("cull", "TestRange");
        super::super::shaders::assert_wgsl_size::<super::DrawIndirectArgs>("cull", "DrawArgs");
    }

    #[test]
    fn test_ranges_carry_running_ends() {
        let r = TestRange::of(&[3..5, 10..11, 20..24], &[]);
        let ends: Vec<u32> = r.iter().map(|t| t.end).collect();
        assert_eq!(ends, [2, 3, 7]);
        assert_eq!(r[2].start, 20);
        assert!(r.iter().all(|t| t.placement == 0));
        let placed = TestRange::of(&[0..4, 0..4], &[7, 9]);
        let placed: Vec<(u32, u32)> = placed.iter().map(|t| (t.end, t.placement)).collect();
        assert_eq!(placed, [(4, 7), (8, 9)]);
    }
}
