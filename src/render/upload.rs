//! A scene's list and mesh on the GPU, uploaded once: the list in slices of at most one
//! storage binding, each with the buffers compute culling compacts into.

use wgpu::util::DeviceExt;

use super::renderer::Renderer;
use super::shaders::WORKGROUP_SIZE;
use crate::tree::NodeRecord;
use crate::tree::report::{Report, Silent, Step};
use crate::tree::scene::Scene;

/// Nodes per slice at most: one dispatch of 65,535 workgroups covers a slice.
const MAX_SLICE_NODES: u64 = 65_535 * WORKGROUP_SIZE as u64;

/// One slice of the list on the GPU, with what compute culling needs.
pub(super) struct Slice {
    pub count: u32,
    /// Nodes, for vertex culling.
    pub direct: wgpu::BindGroup,
    /// Nodes, survivors (read_write) and the compaction record, for the cull pass.
    pub cull: wgpu::BindGroup,
    /// Nodes and survivors, for the compacted draw.
    pub compacted: wgpu::BindGroup,
    /// Indirect draw arguments followed by the slice's prefix count.
    pub compaction: wgpu::Buffer,
}

/// The list and mesh of a scene on the GPU. It may be uploaded a slice at a time, front
/// (coarse) first: frames drawn meanwhile use what is there (see `encode.rs`).
pub struct GpuScene {
    pub(super) slices: Vec<Slice>,
    pub(super) mesh: Option<(wgpu::Buffer, wgpu::Buffer, u32)>,
    /// Slices the whole list takes.
    planned_slices: usize,
}

/// One slice uploaded, to be added with [`GpuScene::push`].
pub struct SliceUpload(Slice);

/// The mesh uploaded, to be added with [`GpuScene::set_mesh`].
pub struct MeshUpload((wgpu::Buffer, wgpu::Buffer, u32));

impl GpuScene {
    /// Triangles of the mesh reference (0 without one).
    pub fn mesh_triangles(&self) -> u32 {
        self.mesh.as_ref().map_or(0, |m| m.2 / 3)
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
}

impl Renderer {
    /// Uploads a scene's list (once, in binding-size slices) and mesh.
    pub fn upload(&self, scene: &Scene) -> GpuScene {
        self.upload_reporting(scene, &Silent)
    }

    /// [`Renderer::upload`], telling `report` the nodes uploaded, slice by slice.
    pub fn upload_reporting(&self, scene: &Scene, report: &dyn Report) -> GpuScene {
        let nodes = scene.nodes();
        report.step(Step::Upload, nodes.len() as u64);
        let mut gpu_scene = self.empty_gpu_scene(nodes.len());
        for range in self.slice_plan(nodes.len()) {
            report.advance(range.len() as u64);
            gpu_scene.push(self.upload_slice(&nodes[range]));
        }
        if let Some(mesh) = self.upload_mesh(scene) {
            gpu_scene.set_mesh(mesh);
        }
        gpu_scene
    }

    /// Nodes per slice: one storage binding, one dispatch.
    fn nodes_per_slice(&self) -> usize {
        let record = std::mem::size_of::<NodeRecord>() as u64;
        (self.gpu.max_binding_bytes() / record).clamp(1, MAX_SLICE_NODES) as usize
    }

    /// The node ranges of the slices of a list of `total` nodes, front first.
    pub fn slice_plan(&self, total: usize) -> impl Iterator<Item = std::ops::Range<usize>> {
        let per_slice = self.nodes_per_slice();
        (0..total)
            .step_by(per_slice)
            .map(move |start| start..(start + per_slice).min(total))
    }

    /// A scene of `total` nodes with nothing uploaded yet.
    pub fn empty_gpu_scene(&self, total: usize) -> GpuScene {
        GpuScene {
            slices: Vec::new(),
            mesh: None,
            planned_slices: self.slice_plan(total).count(),
        }
    }

    /// Uploads one slice of the list (a range given by [`Renderer::slice_plan`]), to
    /// be pushed in order.
    pub fn upload_slice(&self, chunk: &[NodeRecord]) -> SliceUpload {
        let device = &self.gpu.device;
        let bind = |layout, buffers: &[&wgpu::Buffer]| {
            let entries: Vec<wgpu::BindGroupEntry> = buffers
                .iter()
                .enumerate()
                .map(|(k, b)| wgpu::BindGroupEntry {
                    binding: k as u32,
                    resource: b.as_entire_binding(),
                })
                .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout,
                entries: &entries,
            })
        };
        let nodes = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("nodes"),
            contents: bytemuck::cast_slice(chunk),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let survivors = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("survivors"),
            size: 4 * chunk.len() as u64,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let compaction = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("compaction"),
            size: 20,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::INDIRECT
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        SliceUpload(Slice {
            count: chunk.len() as u32,
            direct: bind(&self.pipelines.nodes_layout, &[&nodes]),
            cull: bind(
                &self.pipelines.cull_layout,
                &[&nodes, &survivors, &compaction],
            ),
            compacted: bind(&self.pipelines.compacted_layout, &[&nodes, &survivors]),
            compaction,
        })
    }

    /// Uploads the mesh reference of a scene that has one.
    pub fn upload_mesh(&self, scene: &Scene) -> Option<MeshUpload> {
        let device = &self.gpu.device;
        scene.mesh.as_ref().map(|m| {
            let mut vertices = Vec::with_capacity(m.positions.len() * 28);
            for i in 0..m.positions.len() {
                vertices.extend_from_slice(bytemuck::bytes_of(&m.positions[i]));
                vertices.extend_from_slice(bytemuck::bytes_of(&m.normals[i]));
                vertices.extend_from_slice(&m.colors[i]);
            }
            let vb = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("mesh vertices"),
                contents: &vertices,
                usage: wgpu::BufferUsages::VERTEX,
            });
            let ib = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("mesh indices"),
                contents: bytemuck::cast_slice(&m.triangles),
                usage: wgpu::BufferUsages::INDEX,
            });
            MeshUpload((vb, ib, (m.triangles.len() * 3) as u32))
        })
    }
}
