//! The per-frame uniform (`Frame` in `shaders/common.wgsl`): camera-relative matrices,
//! the level-of-detail budget, lens, light and display flags.

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};

use super::camera::{Camera, heights};
use super::settings::{DEPTH_PUSH, PREFILTER_PX, Settings};
use crate::tree::TreeMeta;

/// Mirrors `struct Frame` in `shaders/common.wgsl`, field for field (the WGSL file
/// documents each); 304 bytes, with the padding WGSL's vec3 alignment asks for.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(super) struct FrameUniform {
    pub view: [[f32; 4]; 4],
    pub proj: [[f32; 4]; 4],
    pub model_offset: [f32; 3],
    pub edl_strength: f32,
    pub viewport: [f32; 2],
    pub inv_viewport: [f32; 2],
    pub eps: f32,
    pub error_scale: f32,
    pub near: f32,
    pub depth_push: f32,
    pub tan_half_fov: [f32; 2],
    pub prefilter_px: f32,
    pub ewa: f32,
    pub light_dir: [f32; 3],
    pub specular: f32,
    pub background: [f32; 4],
    pub mode: u32,
    pub cull_back_faces: u32,
    pub lod_on: u32,
    pub lod_frozen: u32,
    pub normals_up: u32,
    pub normals_unknown: u32,
    pub elevation_range: [f32; 2],
    pub lod_eye: [f32; 3],
    pub edl_radius_px: f32,
    pub intensity_range: [f32; 2],
    pub has_attributes: u32,
    pub oriented_normals: u32,
    pub elevation_up: [f32; 3],
    pub elevation_pad: f32,
}

/// The layout of bind group 0 of every pass: the frame uniform.
pub(super) fn frame_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("frame"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: super::bindings::FRAME.binding,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<FrameUniform>() as u64),
            },
            count: None,
        }],
    })
}

/// The sRGB transfer function, inverted: an sRGB-encoded value in 0–1 to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The sRGB transfer function: a linear value in 0–1 to its sRGB encoding in 0–1.
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

impl FrameUniform {
    /// The uniform for `camera` over a `width`×`height` target, selecting with
    /// `lod_eps` (world error per unit of distance; 0: leaves only). The model offset
    /// (origin − eye) is computed in f64 and only then rounded to f32.
    pub fn new(
        meta: &TreeMeta,
        camera: &Camera,
        settings: &Settings,
        (width, height): (u32, u32),
        lod_eps: f64,
    ) -> FrameUniform {
        let eye_rel = camera.eye - DVec3::from(meta.origin);
        let aspect = width as f64 / height as f64;
        let near = camera.near_plane(meta, aspect);
        let tan_y = (camera.fov_y * 0.5).tan();
        let mode = settings.mode as u32;
        let light = settings.light.normalize_or(Vec3::Z);
        let [r, g, b] = settings.background.map(srgb_to_linear);
        let elevation_up = camera.up;
        let elevation_range = heights(meta, elevation_up);
        FrameUniform {
            view: camera.view_rotation().to_cols_array_2d(),
            proj: camera.projection(aspect, near).to_cols_array_2d(),
            model_offset: (-eye_rel).as_vec3().to_array(),
            edl_strength: settings.edl_strength,
            viewport: [width as f32, height as f32],
            inv_viewport: [1.0 / width as f32, 1.0 / height as f32],
            eps: lod_eps as f32,
            error_scale: meta.error_scale,
            near: near as f32,
            depth_push: DEPTH_PUSH,
            tan_half_fov: [(tan_y * aspect) as f32, tan_y as f32],
            prefilter_px: PREFILTER_PX,
            ewa: if settings.ewa { 1.0 } else { 0.0 },
            light_dir: light.to_array(),
            specular: 0.25,
            background: [r, g, b, 1.0],
            mode,
            cull_back_faces: settings.cull_back_faces as u32,
            lod_on: (lod_eps > 0.0) as u32,
            lod_frozen: settings.lod_eye.is_some() as u32,
            normals_up: meta.normals_up() as u32,
            normals_unknown: meta.normals_unknown() as u32,
            elevation_range,
            lod_eye: settings
                .lod_eye
                .map_or(DVec3::ZERO, |e| e - camera.eye)
                .as_vec3()
                .to_array(),
            edl_radius_px: settings.edl_radius_px,
            intensity_range: meta.intensity_range.map(f32::from),
            has_attributes: meta.has_attributes as u32,
            oriented_normals: (meta.oriented_normals && !meta.two_sided) as u32,
            elevation_up: elevation_up.as_vec3().to_array(),
            elevation_pad: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_uniform_has_the_size_of_the_wgsl_struct() {
        super::super::shaders::assert_wgsl_size::<super::FrameUniform>("common", "Frame");
    }
}
