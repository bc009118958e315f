//! Getting a frame back from the GPU: textures and small buffers are copied into
//! mappable buffers by the frame's own encoder, and read after the submit.

use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

/// Bytes per row of a texture copy: rows are padded to multiples of 256 bytes.
pub(super) fn padded_row(width: u32, bytes_per_pixel: u32) -> u32 {
    (width * bytes_per_pixel).div_ceil(256) * 256
}

fn mappable(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    })
}

/// Copies a whole 2D texture of `bytes_per_pixel` into a new mappable buffer.
pub(super) fn copy_texture(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    bytes_per_pixel: u32,
) -> wgpu::Buffer {
    let size = texture.size();
    let row = padded_row(size.width, bytes_per_pixel);
    let buffer = mappable(device, "readback", (row * size.height) as u64);
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: Default::default(),
            aspect: Default::default(),
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: None,
            },
        },
        size,
    );
    buffer
}

/// Maps a buffer (after the submit that fills it) and copies its contents out.
pub(super) fn read(device: &wgpu::Device, buffer: &wgpu::Buffer) -> anyhow::Result<Vec<u8>> {
    let mapped = Arc::new(OnceLock::new());
    let result = mapped.clone();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = result.set(r.is_ok());
    });
    wait_until(device, || mapped.get().is_some())?;
    anyhow::ensure!(
        mapped.get() == Some(&true),
        "mapping a readback buffer failed"
    );
    let data = buffer.slice(..).get_mapped_range()?.to_vec();
    buffer.unmap();
    Ok(data)
}

/// How long [`wait_until`] waits for map callbacks once the GPU is idle.
const MAP_WAIT: Duration = Duration::from_secs(30);

/// Waits for the GPU until `arrived()` holds. A map callback runs in whichever thread's
/// poll collected it (wgpu fires callbacks after releasing its locks): when another
/// thread shares the device, this thread's wait may return a moment before the callback
/// ran, so the wait repeats, for at most `MAP_WAIT`.
pub(super) fn wait_until(
    device: &wgpu::Device,
    mut arrived: impl FnMut() -> bool,
) -> anyhow::Result<()> {
    let start = Instant::now();
    loop {
        device.poll(wgpu::PollType::wait_indefinitely())?;
        if arrived() {
            return Ok(());
        }
        anyhow::ensure!(
            start.elapsed() < MAP_WAIT,
            "a GPU buffer was not mapped within {MAP_WAIT:?}"
        );
        std::thread::yield_now();
    }
}

/// The rows of a padded RGBA8 copy, without their padding.
pub(super) fn unpad_rgba8(data: &[u8], width: u32, height: u32) -> Vec<u8> {
    let row = padded_row(width, 4) as usize;
    (0..height as usize)
        .flat_map(|y| &data[y * row..y * row + width as usize * 4])
        .copied()
        .collect()
}

/// Which pixels of a padded R32Uint copy of a mask are set (not 0).
pub(super) fn mask(data: &[u8], width: u32, height: u32) -> Vec<bool> {
    let row = padded_row(width, 4) as usize;
    (0..height as usize)
        .flat_map(|y| data[y * row..y * row + width as usize * 4].chunks_exact(4))
        .map(|v| v != [0; 4])
        .collect()
}

/// View distance per pixel from padded Rgba16Float copies of the colour sum (weight in
/// alpha) and the normal sum (z·w in alpha): z = Σzw / Σw, 0 where nothing was drawn.
pub(super) fn depth(color_sum: &[u8], normal_sum: &[u8], width: u32, height: u32) -> Vec<f32> {
    let row = padded_row(width, 8) as usize;
    let alpha =
        |data: &[u8], at: usize| half::f16::from_le_bytes([data[at], data[at + 1]]).to_f32();
    (0..height as usize)
        .flat_map(|y| (0..width as usize).map(move |x| y * row + x * 8 + 6))
        .map(|at| {
            let w = alpha(color_sum, at);
            if w > 0.0 {
                alpha(normal_sum, at) / w
            } else {
                0.0
            }
        })
        .collect()
}
