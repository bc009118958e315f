//! The options of one frame, shared by `spt render`, the viewer and `spt bench`: image
//! size, camera, budget, display mode, light and culling, and their parsers.

use anyhow::bail;
use glam::{DVec3, Vec3};

use crate::io::up::UpAxis;
use crate::render::{Camera, Culling, Mode, OrbitAxes, PrefixCut, Raster, Settings};
use crate::tree::TreeMeta;
use crate::tree::chunks::Chunk;
use crate::tree::scene::Scene;

/// The options `spt render` (and the viewer's screenshots) take.
#[derive(Debug, Clone, clap::Args)]
pub struct RenderArgs {
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1024x768", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Orbit camera: azimuth and elevation in degrees, distance in bounding-sphere radii,
    /// about the model's up (--up), or for a sensor frame (a cloud seen from its file's
    /// origin) about its image's up, azimuth 0 and elevation 0 looking from the sensor
    /// (default: the whole model framed from azimuth 30, elevation 20; 45 for a
    /// terrain; a sensor frame from its sensor).
    #[arg(long, value_parser = parse_triple, allow_hyphen_values = true, conflicts_with_all = ["eye", "target"])]
    pub orbit: Option<[f64; 3]>,
    /// Eye position in the model file's coordinates (with --target).
    #[arg(long, value_parser = parse_triple, allow_hyphen_values = true, requires = "target")]
    pub eye: Option<[f64; 3]>,
    /// Point looked at, in the model file's coordinates (with --eye).
    #[arg(long, value_parser = parse_triple, allow_hyphen_values = true, requires = "eye")]
    pub target: Option<[f64; 3]>,
    /// Which axis is up (default: the one the file gives, z for LAS and LAZ; else z for
    /// a terrain, y for other models; a sensor frame is seen as its sensor saw it).
    #[arg(long, value_enum, allow_hyphen_values = true)]
    pub up: Option<UpAxis>,
    /// Vertical field of view, degrees.
    #[arg(long, default_value_t = 45.0)]
    pub fov: f64,
    /// Largest screen-space error in pixels (0: leaves only).
    #[arg(long, default_value_t = 1.0)]
    pub error_px: f64,
    /// Display mode (default: shaded; in the viewer, edl for a cloud without colours).
    #[arg(long, value_enum)]
    pub mode: Option<Mode>,
    /// Eye-dome lighting (--mode edl): darkening per log2 depth step.
    #[arg(long, default_value_t = 1.0, value_parser = parse_finite)]
    pub edl_strength: f32,
    /// Eye-dome lighting (--mode edl): distance of the neighbours it compares, pixels.
    #[arg(long, default_value_t = 1.5, value_parser = parse_finite)]
    pub edl_radius: f32,
    /// Direction toward the light in view space: x right, y up, z toward the viewer.
    #[arg(long, value_parser = parse_triple, allow_hyphen_values = true, default_value = "0.4,0.6,1")]
    pub light: [f64; 3],
    /// Background colour, r,g,b in 0–1 (sRGB).
    #[arg(long, value_parser = parse_triple, default_value = "1,1,1")]
    pub background: [f64; 3],
    /// Without the EWA screen-space prefilter.
    #[arg(long)]
    pub no_ewa: bool,
    /// Without level of detail: every leaf.
    #[arg(long)]
    pub no_lod: bool,
    /// A scene: plan every instance on the CPU, including the far ones the GPU
    /// otherwise places itself (docs/scenes.md).
    #[arg(long)]
    pub cpu_instances: bool,
    /// Skip splats whose normal faces away (oriented models).
    #[arg(long)]
    pub cull_back_faces: bool,
    /// Culling of the splats: by a compute pass that compacts the survivors into an
    /// indirect draw (faster on every model measured), or in the vertex stage.
    #[arg(long, value_enum, default_value = "compute")]
    pub culling: Culling,
    /// How the splat passes draw: through the GPU's raster pipeline, or as compute
    /// rasterization (docs/gpu.md); auto: compute on a GPU, hardware on a CPU adapter.
    #[arg(long, value_enum, default_value = "auto")]
    pub raster: Raster,
    /// Where the CPU ends each chunk's prefix: at the node (it reads the nodes of the
    /// last block) or at the block of 64 (the GPU tests the rest); auto: node on a CPU
    /// adapter, block on a GPU. Both draw the same picture.
    #[arg(long, value_enum, default_value = "auto")]
    pub prefix_cut: PrefixCut,
    /// Render this many frames of the same view and report median and p95 times (the
    /// image of the last one is written).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub frames: u32,
    /// GPU backend: vulkan, gl, metal, dx12 or all (default: $SPT_BACKEND, else any).
    #[arg(long)]
    pub backend: Option<String>,
    /// Keep at most this many MiB of the list on the GPU: slices are uploaded as the view
    /// needs them (coarse first) and the least recently needed evicted; a view whose
    /// slices do not all fit is drawn coarser. Default: the whole list.
    #[arg(long, value_name = "MIB", value_parser = clap::value_parser!(u64).range(1..=1 << 30))]
    pub gpu_memory: Option<u64>,
}

impl RenderArgs {
    /// The GPU memory budget in bytes, if one was given.
    pub fn gpu_budget(&self) -> Option<u64> {
        self.gpu_memory.map(|mib| mib << 20)
    }
}

/// Parses WIDTHxHEIGHT (1–16384 each).
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or("expected WIDTHxHEIGHT, e.g. 1024x768")?;
    let (w, h): (u32, u32) = (
        w.parse().map_err(|_| "bad width")?,
        h.parse().map_err(|_| "bad height")?,
    );
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err("width and height must be 1–16384".into());
    }
    Ok((w, h))
}

fn parse_triple(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| e.to_string())?;
    let t: [f64; 3] = v
        .try_into()
        .map_err(|_| "expected three comma-separated numbers".to_string())?;
    if t.iter().any(|x| !x.is_finite()) {
        return Err("numbers must be finite".into());
    }
    Ok(t)
}

/// A finite number.
fn parse_finite(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(_) => Err("must be finite".into()),
        Err(e) => Err(e.to_string()),
    }
}

impl RenderArgs {
    pub fn settings(&self) -> Settings {
        Settings {
            error_px: self.error_px.max(0.0),
            mode: self.mode.unwrap_or(Mode::Shaded),
            ewa: !self.no_ewa,
            lod: !self.no_lod,
            cull_back_faces: self.cull_back_faces,
            light: DVec3::from(self.light).as_vec3().normalize_or(Vec3::Z),
            background: self.background.map(|c| c.clamp(0.0, 1.0) as f32),
            culling: self.culling,
            raster: self.raster,
            prefix_cut: self.prefix_cut,
            edl_strength: self.edl_strength.clamp(0.0, 100.0),
            edl_radius_px: self.edl_radius.clamp(0.5, 16.0),
            far_on_gpu: !self.cpu_instances,
            ..Settings::default()
        }
    }

    /// The orbit axes of `scene`'s model, about `--up` when given.
    pub fn axes(&self, scene: &Scene) -> OrbitAxes {
        self.axes_of(scene.meta())
    }

    /// [`RenderArgs::axes`] of a model (or scene) described by `meta`.
    pub fn axes_of(&self, meta: &TreeMeta) -> OrbitAxes {
        OrbitAxes::of(&with_up(meta, self.up))
    }

    pub fn camera(&self, scene: &Scene) -> anyhow::Result<Camera> {
        self.camera_for(scene.meta(), scene.index.chunks())
    }

    /// [`RenderArgs::camera`] of a model described by `meta`, framed on `chunks`.
    pub fn camera_for(&self, meta: &TreeMeta, chunks: &[Chunk]) -> anyhow::Result<Camera> {
        let fov = self.fov.to_radians();
        if !(0.01..3.1).contains(&fov) {
            bail!("--fov must be between 1 and 177 degrees");
        }
        let aspect = self.size.0 as f64 / self.size.1 as f64;
        let meta = &with_up(meta, self.up);
        Ok(match (self.orbit, self.eye, self.target) {
            (Some([az, el, dist]), _, _) => Camera::orbit(meta, az, el, dist, fov),
            (None, Some(eye), Some(target)) => {
                let (eye, target) = (DVec3::from(eye), DVec3::from(target));
                if eye == target {
                    bail!("--eye and --target must differ");
                }
                Camera {
                    eye,
                    target,
                    up: OrbitAxes::of(meta).up,
                    fov_y: fov,
                }
            }
            _ => Camera::framed(meta, chunks, fov, aspect),
        })
    }
}

/// `meta` with `up` as its up axis when given.
pub fn with_up(meta: &TreeMeta, up: Option<UpAxis>) -> TreeMeta {
    TreeMeta {
        up: up.or(meta.up),
        ..meta.clone()
    }
}

/// `--up`'s values: the axes by their names.
impl clap::ValueEnum for UpAxis {
    fn value_variants<'a>() -> &'a [Self] {
        &UpAxis::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}

/// `--mode`'s values: the engine's display modes by their names.
impl clap::ValueEnum for Mode {
    fn value_variants<'a>() -> &'a [Self] {
        &Mode::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()).help(self.description()))
    }
}

/// `--raster`'s values: the ways of drawing the splat passes, by their names.
impl clap::ValueEnum for Raster {
    fn value_variants<'a>() -> &'a [Self] {
        &Raster::CHOICES
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()).help(self.description()))
    }
}

/// `--prefix-cut`'s values, by their names.
impl clap::ValueEnum for PrefixCut {
    fn value_variants<'a>() -> &'a [Self] {
        &PrefixCut::CHOICES
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()).help(self.description()))
    }
}

/// `--culling`'s values: the engine's culling strategies by their names.
impl clap::ValueEnum for Culling {
    fn value_variants<'a>() -> &'a [Self] {
        &Culling::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()).help(self.description()))
    }
}
