//! PNG images out: RGBA8 pixels written atomically (the frames of `spt render`, the
//! viewer's screenshots, the benchmark's plots).

use std::path::Path;

/// Writes `rgba` (row-major, top row first, 4 bytes a pixel, `width × height` pixels)
/// as a PNG at `path`, atomically: a failed write leaves no file under that name.
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> anyhow::Result<()> {
    let img = image::RgbaImage::from_raw(width, height, rgba.to_vec()).ok_or_else(|| {
        anyhow::anyhow!(
            "{}: {} bytes are not a {width}×{height} RGBA image",
            path.display(),
            rgba.len()
        )
    })?;
    super::atomic::write_atomically(path, |w| {
        let mut bytes = Vec::new();
        img.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .map_err(std::io::Error::other)?;
        w.write_all(&bytes)
    })
    .map_err(anyhow::Error::from)
}
