//! The GPU: an adapter of any backend (a real GPU when there is one, software Vulkan
//! (lavapipe) or OpenGL (llvmpipe) otherwise), with the adapter's own limits rather
//! than wgpu's defaults.

use anyhow::{Context, bail};

use super::gbuffer::{COVERAGE, GBUFFER};
use super::targets::{COVERED, OUTPUT, OUTPUT_GAMMA};

/// Where the backend choice comes from when none is given.
pub const BACKEND_ENV: &str = "SPT_BACKEND";

/// A device and queue with what the renderer needs to know of them.
pub struct Gpu {
    /// Kept to make (and remake) window surfaces.
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// Timestamp queries are available (GPU times are measured).
    pub timestamps: bool,
    /// A texture can be viewed in another format of its family (not on GL): the viewer
    /// then draws its panel through the output's gamma view ([`Gpu::overlay_format`]).
    pub view_formats: bool,
    /// A depth attachment that a pass only tests can also be read as a texture in that
    /// pass (not on GL): pass 2 then reads pass 1's depth (`SplatPasses::depth_bind`).
    pub read_only_depth: bool,
    /// Compute shaders can write the G-buffer's formats as storage textures: the splat
    /// passes can be drawn in compute ([`super::Raster::Compute`]).
    pub compute_raster: bool,
    /// And pass 3 after them, writing the output through its [`OUTPUT_GAMMA`] view and
    /// the covered mask as storage textures (where views can be reinterpreted).
    pub compute_shading: bool,
}

/// Parses a backend name: vulkan, gl, metal, dx12, or `all` (any).
pub fn parse_backends(name: &str) -> anyhow::Result<wgpu::Backends> {
    Ok(match name.to_ascii_lowercase().as_str() {
        "vulkan" | "vk" => wgpu::Backends::VULKAN,
        "gl" | "gles" | "opengl" => wgpu::Backends::GL,
        "metal" | "mtl" => wgpu::Backends::METAL,
        "dx12" | "d3d12" => wgpu::Backends::DX12,
        "all" | "any" => wgpu::Backends::all(),
        other => bail!("unknown backend '{other}': use vulkan, gl, metal, dx12 or all"),
    })
}

impl Gpu {
    /// Opens an adapter: from `backend`, else from `SPT_BACKEND`, else any (a hardware
    /// adapter preferred). Fails with a clear message when none exists.
    pub fn new(backend: Option<&str>) -> anyhow::Result<Gpu> {
        let instance = Gpu::instance(backend, None)?;
        Gpu::with_instance(instance, None)
    }

    /// The instance for `backend` (as [`Gpu::new`] chooses it), knowing the display
    /// that windows will be shown on, when there are windows.
    pub fn instance(
        backend: Option<&str>,
        display: Option<Box<dyn wgpu::wgt::WgpuHasDisplayHandle>>,
    ) -> anyhow::Result<wgpu::Instance> {
        let chosen = match backend
            .map(str::to_owned)
            .or_else(|| std::env::var(BACKEND_ENV).ok())
        {
            Some(name) => parse_backends(&name)?,
            None => wgpu::Backends::all(),
        };
        let mut desc = match display {
            Some(d) => wgpu::InstanceDescriptor::new_with_display_handle(d),
            None => wgpu::InstanceDescriptor::new_without_display_handle(),
        };
        desc.backends = chosen;
        Ok(wgpu::Instance::new(desc))
    }

    /// Opens an adapter of `instance` (one that can draw into `surface`, when given).
    pub fn with_instance(
        instance: wgpu::Instance,
        surface: Option<&wgpu::Surface>,
    ) -> anyhow::Result<Gpu> {
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: surface,
            apply_limit_buckets: false,
        }))
        .with_context(|| {
            format!(
                "no GPU adapter{}: install a driver (software Vulkan: apt-get install \
                 mesa-vulkan-drivers) or choose another backend with --backend / {BACKEND_ENV}",
                if surface.is_some() {
                    " that can draw into this window"
                } else {
                    ""
                }
            )
        })?;
        let wanted = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::SHADER_EARLY_DEPTH_TEST;
        let features = adapter.features() & wanted;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("spt"),
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .context("cannot open the GPU device")?;
        let info = adapter.get_info();
        let downlevel = adapter.get_downlevel_capabilities().flags;
        let view_formats = downlevel.contains(wgpu::DownlevelFlags::VIEW_FORMATS);
        let read_only_depth = downlevel.contains(wgpu::DownlevelFlags::READ_ONLY_DEPTH_STENCIL);
        let storage = |formats: &[wgpu::TextureFormat]| {
            formats.iter().all(|f| {
                let usages = adapter.get_texture_format_features(*f).allowed_usages;
                usages.contains(wgpu::TextureUsages::STORAGE_BINDING)
            })
        };
        let compute_raster = downlevel.contains(wgpu::DownlevelFlags::COMPUTE_SHADERS)
            && storage(&[GBUFFER, COVERAGE, wgpu::TextureFormat::R32Float]);
        let compute_shading = compute_raster && view_formats && storage(&[OUTPUT_GAMMA, COVERED]);
        Ok(Gpu {
            instance,
            adapter,
            device,
            queue,
            info,
            timestamps: features.contains(wgpu::Features::TIMESTAMP_QUERY),
            view_formats,
            read_only_depth,
            compute_raster,
            compute_shading,
        })
    }

    /// Whether the adapter is a CPU rasterizer (lavapipe, llvmpipe, WARP): its "GPU"
    /// work runs on the cores that plan the frame, and branches spare work where a GPU's
    /// lanes would wait.
    pub fn on_cpu(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Whether pass 2 reads pass 1's depth to leave out the coverage samples of pixels
    /// inside the picture's outlines (WGSL `SKIP_SURROUNDED_SAMPLES`): where it can
    /// ([`Gpu::read_only_depth`]) and where branches spare work, not on a CPU
    /// rasterizer. Knot at 512×512, pass 2: H100 −10 %, lavapipe +20 to +30 %.
    pub fn skips_surrounded_samples(&self) -> bool {
        self.read_only_depth && !self.on_cpu()
    }

    /// The format the viewer sees the output in, to draw its panel and to present it:
    /// [`OUTPUT_GAMMA`] where views can be reinterpreted (not on GL), else [`OUTPUT`].
    pub fn overlay_format(&self) -> wgpu::TextureFormat {
        if self.view_formats {
            OUTPUT_GAMMA
        } else {
            OUTPUT
        }
    }

    /// "name (backend, driver)".
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {} {})",
            self.info.name, self.info.backend, self.info.driver, self.info.driver_info
        )
    }

    /// Largest storage-buffer binding, a multiple of the record size.
    pub fn max_binding_bytes(&self) -> u64 {
        let limits = self.device.limits();
        limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
            / 256
            * 256
    }
}
