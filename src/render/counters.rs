//! A frame's GPU counters: its timestamps (GPU time, in all and per pass) and, with
//! compute culling, the survivors of each slice (splats drawn). Read either at once
//! (offline frames) or a few frames late without stalling (the viewer), through one
//! small copy per frame.

use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use super::cull::Compaction;
use super::far::{FarCounters, FarCounts};
use super::gpu::Gpu;
use super::gpu_scene::GpuScene;
use super::plan::EncodedFrame;
use super::readback;
use super::targets::{FrameTargets, STAMP_BYTES, stamp};

/// What the GPU measured of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GpuCounters {
    /// From the first pass's start to the end of shading, when the adapter has
    /// timestamp queries.
    pub gpu_ms: Option<f64>,
    /// The same time per pass: visibility (with the G-buffer's clear), attributes (or
    /// the points or mesh pass), shading.
    pub passes_ms: Option<[f64; 3]>,
    /// Splats the compute culling kept (None with vertex culling).
    pub drawn: Option<u64>,
    /// Of those, the splats on an outline (`on_outline`), which pass 2 draws with the
    /// coverage samples and the prefilter's band.
    pub outline: Option<u64>,
    /// A scene's far instances placed by the GPU, all models together.
    pub far: Option<FarCounts>,
}

/// Bytes of one frame's counters: the timestamps, then two u32 per slice (of the
/// whole list, uploaded or not): its survivors on an outline and the others; then the
/// far instances' counters of each model the GPU places them for.
fn counters_bytes(gpu_scenes: &[&GpuScene]) -> u64 {
    let slices: usize = gpu_scenes.iter().map(|g| g.planned_slices()).sum();
    let far = gpu_scenes
        .iter()
        .filter(|g| g.far_counters.is_some())
        .count() as u64;
    STAMP_BYTES + 8 * slices.max(1) as u64 + far * FarCounters::READ_BYTES
}

/// Records copies of the frame's counters into `into` (at least `counters_bytes`).
pub(super) fn copy_counters(
    encoder: &mut wgpu::CommandEncoder,
    targets: &FrameTargets,
    gpu_scenes: &[&GpuScene],
    into: &wgpu::Buffer,
) {
    if let Some((_, resolve)) = &targets.queries {
        encoder.copy_buffer_to_buffer(resolve, 0, into, 0, STAMP_BYTES);
    }
    // The resident slices in order, model after model, as the frame's `slices` counts them.
    for (k, slice) in gpu_scenes.iter().flat_map(|g| g.resident()).enumerate() {
        // The indirect draws' instance counts: the survivors.
        for (j, at) in Compaction::SURVIVORS_AT.into_iter().enumerate() {
            let to = STAMP_BYTES + 4 * (2 * k + j) as u64;
            encoder.copy_buffer_to_buffer(&slice.compaction, at, into, to, 4);
        }
    }
    let slices: usize = gpu_scenes.iter().map(|g| g.planned_slices()).sum();
    let far = gpu_scenes.iter().filter_map(|g| g.far_counters.as_ref());
    for (j, counters) in far.enumerate() {
        let to = STAMP_BYTES + 8 * slices.max(1) as u64 + j as u64 * FarCounters::READ_BYTES;
        encoder.copy_buffer_to_buffer(counters, 0, into, to, FarCounters::READ_BYTES);
    }
}

/// Decodes counters copied by [`copy_counters`].
pub(super) fn parse_counters(gpu: &Gpu, bytes: &[u8], frame: &EncodedFrame) -> GpuCounters {
    let stamps = STAMP_BYTES as usize;
    let passes_ms = gpu.timestamps.then(|| {
        let t: [u64; stamp::COUNT as usize] = bytemuck::pod_read_unaligned(&bytes[..stamps]);
        let period_ns = gpu.queue.get_timestamp_period() as f64;
        let ms = |from: u32, to: u32| {
            t[to as usize].saturating_sub(t[from as usize]) as f64 * period_ns / 1e6
        };
        [
            ms(stamp::START, stamp::VISIBILITY_END),
            ms(stamp::VISIBILITY_END, stamp::ATTRIBUTES_END),
            ms(stamp::ATTRIBUTES_END, stamp::END),
        ]
    });
    let gpu_ms = passes_ms.map(|p| p.iter().sum());
    // Per slice: (outline, inner) survivors.
    let survivors = || {
        bytes[stamps..stamps + 8 * frame.slices]
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()) as u64)
    };
    let drawn = frame.compute.then(|| survivors().sum());
    let outline = frame.compute.then(|| survivors().step_by(2).sum());
    let far = (frame.far_models > 0).then(|| {
        let from = bytes.len() - frame.far_models * FarCounters::READ_BYTES as usize;
        let mut counts = FarCounts::default();
        for c in bytes[from..].chunks_exact(FarCounters::READ_BYTES as usize) {
            counts.add(bytemuck::pod_read_unaligned(c));
        }
        counts
    });
    GpuCounters {
        gpu_ms,
        passes_ms,
        drawn,
        outline,
        far,
    }
}

/// A mappable buffer of `size` bytes for one frame's counters.
fn mappable_counters(gpu: &Gpu, size: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("counters"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    })
}

/// Reads a frame's counters now: records the copy, submits, waits.
pub(super) fn read_counters_now(
    gpu: &Gpu,
    mut encoder: wgpu::CommandEncoder,
    targets: &FrameTargets,
    gpu_scenes: &[&GpuScene],
    frame: &EncodedFrame,
) -> anyhow::Result<GpuCounters> {
    let buffer = mappable_counters(gpu, counters_bytes(gpu_scenes));
    copy_counters(&mut encoder, targets, gpu_scenes, &buffer);
    gpu.queue.submit([encoder.finish()]);
    let bytes = readback::read(&gpu.device, &buffer)?;
    Ok(parse_counters(gpu, &bytes, frame))
}

/// Counters read a few frames late, never waiting for the GPU: a small ring of mappable
/// buffers; a frame whose counters find no free buffer simply goes unmeasured.
pub struct CounterReadback {
    free: Vec<wgpu::Buffer>,
    /// Copies recorded but not yet submitted.
    recorded: Option<(wgpu::Buffer, EncodedFrame)>,
    /// Submitted and being mapped: the flag turns true once mapping ended, and the
    /// result says whether it succeeded.
    in_flight: VecDeque<(wgpu::Buffer, EncodedFrame, Arc<Mapping>)>,
}

/// (mapping ended, mapping succeeded), set by the map callback.
type Mapping = (AtomicBool, AtomicBool);

/// Frames of counters in flight at most.
const RING: usize = 4;

impl CounterReadback {
    /// The ring for frames of `gpu_scenes` (one model's list, or a scene's models).
    pub fn new(gpu: &Gpu, gpu_scenes: &[&GpuScene]) -> CounterReadback {
        CounterReadback {
            free: (0..RING)
                .map(|_| mappable_counters(gpu, counters_bytes(gpu_scenes)))
                .collect(),
            ..CounterReadback::empty()
        }
    }

    /// A ring without buffers: no frame is measured.
    pub fn empty() -> CounterReadback {
        CounterReadback {
            free: Vec::new(),
            recorded: None,
            in_flight: VecDeque::new(),
        }
    }

    /// Records the copy of this frame's counters, if a buffer is free.
    pub fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &FrameTargets,
        gpu_scenes: &[&GpuScene],
        frame: &EncodedFrame,
    ) {
        if let Some(buffer) = self.free.pop() {
            copy_counters(encoder, targets, gpu_scenes, &buffer);
            self.recorded = Some((buffer, frame.clone()));
        }
    }

    /// Starts mapping what [`CounterReadback::record`] copied; call after the submit.
    pub fn submitted(&mut self) {
        if let Some((buffer, frame)) = self.recorded.take() {
            let ready = Arc::new((AtomicBool::new(false), AtomicBool::new(false)));
            let flag = ready.clone();
            buffer.map_async(wgpu::MapMode::Read, .., move |result| {
                flag.1.store(result.is_ok(), Ordering::Relaxed);
                flag.0.store(true, Ordering::Release);
            });
            self.in_flight.push_back((buffer, frame, ready));
        }
    }

    /// The newest frame's counters, once every frame in flight has arrived (waits for
    /// the GPU).
    pub fn wait(&mut self, gpu: &Gpu) -> anyhow::Result<Option<(EncodedFrame, GpuCounters)>> {
        let in_flight = &self.in_flight;
        readback::wait_until(&gpu.device, || {
            in_flight
                .iter()
                .all(|(_, _, ready)| ready.0.load(Ordering::Acquire))
        })?;
        Ok(self.poll(gpu))
    }

    /// The newest frame whose counters have arrived, if any (polls without waiting).
    pub fn poll(&mut self, gpu: &Gpu) -> Option<(EncodedFrame, GpuCounters)> {
        // An error here only means nothing new arrived.
        let _ = gpu.device.poll(wgpu::PollType::Poll);
        let mut newest = None;
        while let Some((_, _, ready)) = self.in_flight.front() {
            if !ready.0.load(Ordering::Acquire) {
                break;
            }
            let (buffer, frame, ready) = self.in_flight.pop_front().expect("front exists");
            let bytes = ready
                .1
                .load(Ordering::Relaxed)
                .then(|| buffer.slice(..).get_mapped_range().ok())
                .flatten();
            match bytes {
                Some(bytes) => {
                    let counters = parse_counters(gpu, &bytes, &frame);
                    newest = Some((frame, counters));
                    drop(bytes);
                    buffer.unmap();
                    self.free.push(buffer);
                }
                // A failed mapping: replace the buffer.
                None => self.free.push(mappable_counters(gpu, buffer.size())),
            }
        }
        newest
    }
}
