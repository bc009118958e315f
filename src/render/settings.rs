//! How a frame is drawn: display mode, culling strategy, level of detail, light.

use glam::{DVec3, Vec3};

/// Display modes (DESIGN.md §7b).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Mode {
    /// Real colours (grey when the model has none), lit.
    Shaded,
    /// Colour by tree level.
    Levels,
    /// View-space normals as colours.
    Normals,
    /// Colour by splat radius (blue small, red large).
    Radius,
    /// Plain points: no blending, nearest splat wins.
    Points,
    /// The mesh the model came from (reference; needs a PLY with faces).
    Mesh,
    /// Eye-dome lighting (Boucheny 2009): the colours, unlit, darkened where the depth
    /// steps away from the eye around a pixel; shape without normals.
    Edl,
    /// Colour by height over the model's range (a ramp from low blue to high red), lit.
    Elevation,
    /// LiDAR: colour by ASPRS class (ground brown, vegetation greens, buildings red,
    /// water blue…), lit.
    Classification,
    /// LiDAR: intensity as grey between the model's 1st and 99th percentiles, lit.
    Intensity,
    /// LiDAR: colour by return (single yellow, first green, intermediate blue, last
    /// red), lit.
    Returns,
}

/// How the splats of the prefix are culled (DESIGN.md §6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum Culling {
    /// In the vertex stage: every node of the prefix is drawn as a quad; culled ones
    /// collapse to a point outside the clip volume.
    Vertex,
    /// A compute pass tests each node once and compacts the survivors into an indirect draw.
    Compute,
}

/// How a frame is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// The largest screen-space error, pixels (0: leaves only).
    pub error_px: f64,
    pub mode: Mode,
    pub ewa: bool,
    pub lod: bool,
    pub cull_back_faces: bool,
    /// Direction toward the light in view space (x right, y up, z toward the viewer).
    pub light: Vec3,
    /// Background colour, sRGB 0–1.
    pub background: [f32; 3],
    pub culling: Culling,
    /// The eye the level of detail is chosen for (file coordinates) when it is frozen
    /// while the camera moves; None: the camera's own eye.
    pub lod_eye: Option<DVec3>,
    /// Eye-dome lighting: strength (darkening per unit of log₂ depth step) and the
    /// distance in pixels of the neighbours it compares with.
    pub edl_strength: f32,
    pub edl_radius_px: f32,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            error_px: 1.0,
            mode: Mode::Shaded,
            ewa: true,
            lod: true,
            cull_back_faces: false,
            light: Vec3::new(0.4, 0.6, 1.0),
            background: [1.0, 1.0, 1.0],
            culling: Culling::Compute,
            lod_eye: None,
            edl_strength: 1.0,
            edl_radius_px: 1.5,
        }
    }
}

impl Settings {
    /// The mesh the model came from: the reference that image error is measured against.
    pub fn mesh() -> Self {
        Settings {
            mode: Mode::Mesh,
            ..Settings::default()
        }
    }

    /// Every leaf splat, without level of detail.
    pub fn leaves() -> Self {
        Settings {
            lod: false,
            ..Settings::default()
        }
    }
}

/// Prefilter radius in pixels.
pub const PREFILTER_PX: f32 = 1.0;
/// Pass 1 pushes each splat back by this many radii. The patches follow the surface to
/// second order, so those of one surface meet within a fraction of a radius; a larger
/// push blends a fold's hidden side into its front (1 radius: FLIP 0.083 on the default
/// model's leaves, against 0.079 at 0.25; tools/quality.rs).
pub const DEPTH_PUSH: f32 = 0.25;
