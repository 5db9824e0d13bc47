//! Screenshots: the window's surface copied out and written as a PNG, the visibility
//! beside it, and the view as an `sshc render` command line.

use crate::image_io::ImageFiles as _;
use crate::run::Bound;
use std::path::{Path, PathBuf};

/// A copy of the surface texture into a buffer (rows padded to 256 bytes), where the
/// surface allows it.
pub(super) fn copy_out(device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, texture: &wgpu::Texture) -> Option<wgpu::Buffer> {
    if !texture.usage().contains(wgpu::TextureUsages::COPY_SRC) {
        return None;
    }
    let row = (texture.width() * 4).div_ceil(256) * 256;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("sshc view: screenshot"),
        size: u64::from(row) * u64::from(texture.height()),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: None,
            },
        },
        texture.size(),
    );
    Some(buffer)
}

pub(super) fn write_png(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    (w, h): (u32, u32),
    format: wgpu::TextureFormat,
    path: &Path,
) -> Result<(), String> {
    let slice = buffer.slice(..);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| format!("error: reading the window back: {e}"))?;
    let data = slice
        .get_mapped_range()
        .map_err(|e| format!("error: reading the window back: {e}"))?;
    let row = (w * 4).div_ceil(256) * 256;
    let bgra = matches!(format, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb);
    let mut img = image::RgbaImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let i = (y * row + x * 4) as usize;
            let p = &data[i..i + 4];
            let px = if bgra { [p[2], p[1], p[0], 255] } else { [p[0], p[1], p[2], 255] };
            img.put_pixel(x, y, image::Rgba(px));
        }
    }
    drop(data);
    buffer.unmap();
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("error: {}: {e}", dir.display()))?;
    }
    crate::session::save_image(&img, path)
}

/// The visibility beside a screenshot: `NAME.visibility.pfm`, as `sshc render --visibility`
/// writes it (light 0's alone, or each light's in a channel).
pub(super) fn write_visibility(ex: &Bound, png: &Path) -> Result<Option<PathBuf>, String> {
    let p = png.with_extension("visibility.pfm");
    let vis = ex.inspect().read_visibilities().map_err(|e| format!("error: {e}"))?;
    // cascades: their combination in channel 0 (`sshc render --visibility` writes it)
    match if ex.targets.cascades() > 1 { 1 } else { ex.targets.lights() } {
        1 => vis.write_pfm_gray(&p, 0),
        2 | 3 => vis.write_pfm_rgb(&p),
        _ => return Ok(None),
    }
    .map_err(|e| format!("error: {e}"))?;
    Ok(Some(p))
}

/// A view's `sshc render` line with its cascade options.
pub(super) fn with_words(mut command: String, cascading: &crate::bind::Cascading) -> String {
    for w in cascading.words() {
        command.push(' ');
        command.push_str(&w);
    }
    command
}
