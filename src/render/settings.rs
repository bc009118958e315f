//! How a frame is drawn: display mode, culling strategy, level of detail, light.

use glam::{DVec3, Vec3};

/// Display modes (docs/design.md §7b); what each shows: [`Mode::description`]. The
/// discriminant is the mode's number in the frame uniform; WGSL gets each as
/// `MODE_<NAME>` from [`Mode::wgsl_constants`].
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    Shaded = 0,
    Levels = 1,
    Normals = 2,
    Radius = 3,
    Points = 4,
    Mesh = 5,
    Edl = 6,
    Elevation = 7,
    Classification = 8,
    Intensity = 9,
    Returns = 10,
}

impl Mode {
    /// Every mode, in the order of their numbers.
    pub const ALL: [Mode; 11] = [
        Mode::Shaded,
        Mode::Levels,
        Mode::Normals,
        Mode::Radius,
        Mode::Points,
        Mode::Mesh,
        Mode::Edl,
        Mode::Elevation,
        Mode::Classification,
        Mode::Intensity,
        Mode::Returns,
    ];

    /// The mode's name on the command line and in WGSL (`MODE_` + upper case).
    pub fn name(self) -> &'static str {
        match self {
            Mode::Shaded => "shaded",
            Mode::Levels => "levels",
            Mode::Normals => "normals",
            Mode::Radius => "radius",
            Mode::Points => "points",
            Mode::Mesh => "mesh",
            Mode::Edl => "edl",
            Mode::Elevation => "elevation",
            Mode::Classification => "classification",
            Mode::Intensity => "intensity",
            Mode::Returns => "returns",
        }
    }

    /// What the mode shows, in one line.
    pub fn description(self) -> &'static str {
        match self {
            Mode::Shaded => "Real colours (grey when the model has none), lit",
            Mode::Levels => "Colour by tree level",
            Mode::Normals => "View-space normals as colours",
            Mode::Radius => "Colour by splat radius (blue small, red large)",
            Mode::Points => "Plain points: no blending, nearest splat wins",
            Mode::Mesh => "The mesh the model came from (reference; needs a PLY with faces)",
            Mode::Edl => {
                "Eye-dome lighting (Boucheny 2009): the colours, unlit, darkened where the \
                 depth steps away from the eye around a pixel; shape without normals"
            }
            Mode::Elevation => {
                "Colour by height over the model's range (a ramp from low blue to high red), lit"
            }
            Mode::Classification => {
                "LiDAR: colour by ASPRS class (ground brown, vegetation greens, buildings \
                 red, water blue…), lit"
            }
            Mode::Intensity => {
                "LiDAR: intensity as grey between the model's 1st and 99th percentiles, lit"
            }
            Mode::Returns => {
                "LiDAR: colour by return (single yellow, first green, intermediate blue, \
                 last red), lit"
            }
        }
    }

    /// The WGSL constants of every mode: `const MODE_SHADED: u32 = 0u;` …
    pub fn wgsl_constants() -> String {
        Mode::ALL
            .iter()
            .map(|m| {
                let name = m.name().to_uppercase();
                format!("const MODE_{name}: u32 = {}u;\n", *m as u32)
            })
            .collect()
    }
}

/// How the splats of the prefix are culled (docs/design.md §6); each strategy:
/// [`Culling::description`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Culling {
    Vertex,
    Compute,
}

impl Culling {
    pub const ALL: [Culling; 2] = [Culling::Vertex, Culling::Compute];

    /// The strategy's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Culling::Vertex => "vertex",
            Culling::Compute => "compute",
        }
    }

    /// What the strategy does, in one line.
    pub fn description(self) -> &'static str {
        match self {
            Culling::Vertex => {
                "In the vertex stage: every node of the prefix is drawn as a quad; culled \
                 ones collapse to a point outside the clip volume"
            }
            Culling::Compute => {
                "A compute pass tests each node once and compacts the survivors into an \
                 indirect draw"
            }
        }
    }
}

/// How the splat passes draw (docs/gpu.md); each way: [`Raster::description`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Raster {
    /// [`Raster::Compute`] on a GPU that has it, [`Raster::Hardware`] on a CPU
    /// adapter ([`crate::render::Renderer::raster`]).
    Auto,
    Hardware,
    Compute,
}

impl Raster {
    /// The two ways of drawing.
    pub const ALL: [Raster; 2] = [Raster::Hardware, Raster::Compute];
    /// What `--raster` takes: either way, or the adapter's choice.
    pub const CHOICES: [Raster; 3] = [Raster::Auto, Raster::Hardware, Raster::Compute];

    /// The way's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Raster::Auto => "auto",
            Raster::Hardware => "hardware",
            Raster::Compute => "compute",
        }
    }

    /// What the way does, in one line.
    pub fn description(self) -> &'static str {
        match self {
            Raster::Auto => {
                "Compute on a GPU, hardware on a CPU adapter (lavapipe, llvmpipe), where \
                 the raster pipeline is faster on small models"
            }
            Raster::Hardware => {
                "The GPU's raster pipeline: one instanced quad per splat, depth test and \
                 blending"
            }
            Raster::Compute => {
                "Compute shaders: each splat's pixels written with atomics into per-pixel \
                 buffers (fixed-point sums: the same image every run); culls in compute"
            }
        }
    }
}

/// Where the CPU ends each chunk's prefix (docs/viewer.md); each choice:
/// [`PrefixCut::description`]. Either draws the same picture: the GPU's test rejects
/// the nodes past the exact end.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum PrefixCut {
    /// [`PrefixCut::Node`] on a CPU adapter, [`PrefixCut::Block`] on a GPU
    /// ([`crate::render::Renderer::prefix_cut`]).
    Auto,
    Node,
    Block,
}

impl PrefixCut {
    /// What `--prefix-cut` takes.
    pub const CHOICES: [PrefixCut; 3] = [PrefixCut::Auto, PrefixCut::Node, PrefixCut::Block];

    /// The choice's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            PrefixCut::Auto => "auto",
            PrefixCut::Node => "node",
            PrefixCut::Block => "block",
        }
    }

    /// What the choice does, in one line.
    pub fn description(self) -> &'static str {
        match self {
            PrefixCut::Auto => "Node on a CPU adapter (lavapipe, llvmpipe), block on a GPU",
            PrefixCut::Node => {
                "At the node: the CPU searches the nodes of each prefix's last block (reads \
                 nodes; the GPU tests no node past the exact end)"
            }
            PrefixCut::Block => {
                "At the block of 64 nodes: the CPU reads only its index; the GPU tests up \
                 to 63 nodes more per chunk"
            }
        }
    }
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
    /// How the splat passes draw; [`Raster::Compute`] culls in compute whatever
    /// `culling` says (it draws the survivor lists).
    pub raster: Raster,
    /// Where the CPU ends each chunk's prefix.
    pub prefix_cut: PrefixCut,
    /// The eye the level of detail is chosen for (file coordinates) when it is frozen
    /// while the camera moves; None: the camera's own eye.
    pub lod_eye: Option<DVec3>,
    /// Eye-dome lighting: strength (darkening per unit of log₂ depth step) and the
    /// distance in pixels of the neighbours it compares with.
    pub edl_strength: f32,
    pub edl_radius_px: f32,
    /// A scene's far instances are placed by the GPU (`render/far.rs`); false plans
    /// every instance on the CPU.
    pub far_on_gpu: bool,
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
            raster: Raster::Auto,
            prefix_cut: PrefixCut::Auto,
            lod_eye: None,
            edl_strength: 1.0,
            edl_radius_px: 1.5,
            far_on_gpu: true,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every mode is listed once, at the index of its number, under a name of its own,
    /// and reaches WGSL as `MODE_<NAME>` with that number.
    #[test]
    fn every_mode_has_one_number_name_and_wgsl_constant() {
        let wgsl = Mode::wgsl_constants();
        for (i, mode) in Mode::ALL.iter().enumerate() {
            assert_eq!(*mode as usize, i, "{mode:?}");
            let name = mode.name();
            assert_eq!(Mode::ALL.iter().filter(|m| m.name() == name).count(), 1);
            let line = format!("const MODE_{}: u32 = {i}u;", name.to_uppercase());
            assert!(wgsl.contains(&line), "{line}");
        }
        assert_eq!(wgsl.lines().count(), Mode::ALL.len());
    }
}
