//! `spt render SCENE.json -o out.png`: one frame of a scene of instances
//! (docs/scenes.md), headless; prints the instances drawn, the splats, the GPU and CPU
//! times, and the memory the scene holds.

use std::path::Path;

use anyhow::Context;

use crate::apps::frame_args::RenderArgs;
use crate::apps::render::FrameTimes;
use crate::apps::text::count;
use crate::render::{Gpu, Renderer};
use crate::tree::instances::InstancedScene;
use crate::tree::report::Silent;
use crate::tree::select::error_per_distance;

pub fn run(path: &Path, output: &Path, args: &RenderArgs) -> anyhow::Result<()> {
    crate::io::atomic::check_writable(output, &[path])?;
    if args.gpu_budget().is_some() {
        anyhow::bail!("--gpu-memory streams one model; a scene's models are uploaded whole");
    }
    let scene = InstancedScene::open(path, &Silent)?;
    let camera = args.camera_for(&scene.meta, &[scene.frame_chunk()])?;
    let gpu = Gpu::new(args.backend.as_deref())?;
    say!("adapter   {}", gpu.describe());
    let renderer = Renderer::new(gpu);
    let settings = args.settings();
    let uploaded = renderer.upload_instanced(&scene);
    let mut times = FrameTimes::default();
    let mut last = None;
    for _ in 0..args.frames {
        let start = std::time::Instant::now();
        let frame = renderer
            .render_instanced(&scene, &uploaded, &camera, &settings, args.size)
            .with_context(|| format!("rendering {}", path.display()))?;
        times.add(&frame.1, start);
        last = Some(frame);
    }
    let (image, stats, visible) = last.expect("at least one frame");
    crate::io::png::write_png(output, image.width, image.height, &image.rgba)?;
    let models: usize = scene.models.iter().map(|m| m.nodes().len()).sum();
    say!(
        "scene     {} models ({} nodes), {} instances in {} groups",
        scene.models.len(),
        count(models as u64),
        count(scene.instances.len() as u64),
        count(scene.groups.len() as u64)
    );
    say!(
        "instances {} drawn (in view, with nodes to test), {} of them placed by the GPU",
        count(visible as u64),
        count(stats.gpu_placed.unwrap_or(0))
    );
    if stats.coarsened {
        let px = stats.eps / error_per_distance(1.0, camera.fov_y, args.size.1);
        say!("lod       coarser than asked: ε = {px:.3} px (the survivor lists' room)");
    }
    let drawn = stats.gpu_drawn.unwrap_or(0);
    say!(
        "culled    {} splats survived the compute culling of {} nodes in {} ranges; {} of them \
         on an outline",
        count(drawn),
        count(stats.tested as u64),
        count(stats.chunks_tested as u64),
        count(stats.gpu_outline.unwrap_or(0)),
    );
    say!("raster    {}", renderer.raster(settings.raster).name());
    let plan = times.print(drawn as usize);
    say!("cpu plan  {plan:.3} ms per frame (median): instances in view, their prefixes");
    print_memory(&scene, &uploaded);
    say!("wrote     {}", output.display());
    Ok(())
}

/// The scene's memory: what its models hold, and what each instance adds.
fn print_memory(scene: &InstancedScene, gpu: &crate::render::GpuInstances) {
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    let m = gpu.memory();
    say!(
        "memory    GPU: models {:.1} MiB, survivor room {:.1} MiB, instances {} B each \
         ({:.1} MiB)",
        mib(m.models),
        mib(m.survivor_room),
        m.per_instance,
        mib(m.per_instance * scene.instances.len() as u64),
    );
    say!(
        "          CPU: instances {} B each ({:.1} MiB: transform and model {} B, groups {:.1} B)",
        scene.bytes_per_instance(),
        mib(scene.bytes_per_instance() * scene.instances.len() as u64),
        std::mem::size_of::<crate::tree::instances::Instance>(),
        scene.groups.bytes() as f64 / scene.instances.len().max(1) as f64,
    );
}
