//! The per-frame uniform (`Frame` in `shaders/common.wgsl`): camera-relative matrices,
//! the level-of-detail budget, lens, light and display flags.

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};

use super::camera::{Camera, bounding_sphere};
use super::settings::{DEPTH_PUSH, Mode, PREFILTER_PX, Settings};
use crate::tree::TreeMeta;

/// Mirrors `struct Frame` in `shaders/common.wgsl`, field for field.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(super) struct FrameUniform {
    pub view: [[f32; 4]; 4],
    pub proj: [[f32; 4]; 4],
    pub model_offset: [f32; 4],
    pub viewport: [f32; 4],
    pub lod: [f32; 4],
    pub lens: [f32; 4],
    pub light: [f32; 4],
    pub background: [f32; 4],
    pub flags: [u32; 4],
    pub blend: [f32; 4],
    pub lod_eye: [f32; 4],
}

/// The sRGB transfer function, inverted: an sRGB-encoded value in 0–1 to linear.
pub(super) fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
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
        let (centre, radius) = bounding_sphere(meta);
        // Near plane: a small fraction of the model, never beyond its nearest point.
        let near = (radius * 1e-4)
            .max((centre - camera.eye).length() * 1e-6)
            .max(f64::MIN_POSITIVE);
        let aspect = width as f64 / height as f64;
        let tan_y = (camera.fov_y * 0.5).tan();
        let mode = match settings.mode {
            Mode::Shaded => 0,
            Mode::Levels => 1,
            Mode::Normals => 2,
            Mode::Radius => 3,
            Mode::Points => 4,
            Mode::Mesh => 5,
        };
        FrameUniform {
            view: camera.view_rotation().to_cols_array_2d(),
            proj: camera.projection(aspect, near).to_cols_array_2d(),
            model_offset: (-eye_rel).as_vec3().extend(0.0).to_array(),
            viewport: [
                width as f32,
                height as f32,
                1.0 / width as f32,
                1.0 / height as f32,
            ],
            lod: [lod_eps as f32, meta.error_scale, near as f32, DEPTH_PUSH],
            lens: [
                (tan_y * aspect) as f32,
                tan_y as f32,
                PREFILTER_PX,
                if settings.ewa { 1.0 } else { 0.0 },
            ],
            light: settings.light.normalize_or(Vec3::Z).extend(0.25).to_array(),
            background: settings
                .background
                .map(srgb_to_linear)
                .into_iter()
                .chain([1.0])
                .collect::<Vec<_>>()
                .try_into()
                .unwrap(),
            flags: [
                mode,
                settings.cull_back_faces as u32,
                (lod_eps > 0.0) as u32,
                settings.lod_eye.is_some() as u32,
            ],
            blend: [
                settings.radius_scale,
                if settings.mode == Mode::Shaded {
                    settings.coverage_weight
                } else {
                    0.0
                },
                0.0,
                0.0,
            ],
            lod_eye: settings
                .lod_eye
                .map_or(DVec3::ZERO, |e| e - camera.eye)
                .as_vec3()
                .extend(0.0)
                .to_array(),
        }
    }
}
