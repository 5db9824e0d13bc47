//! Textures and summed-area tables read back from the device as f32 RGBA images.

use crate::device::{Gpu, Result};
use crate::graph::{Component, Format};

/// A texture read back, as f32 RGBA per texel (missing components 0, alpha 1), rows top first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<[f32; 4]>,
}

impl Image {
    pub fn channel(&self, c: usize) -> Vec<f32> {
        self.rgba.iter().map(|p| p[c]).collect()
    }

    pub fn at(&self, x: u32, y: u32) -> [f32; 4] {
        self.rgba[(y * self.width + x) as usize]
    }
}

/// One layer of a summed-area table: the u32 sums (wrapping) as f32, rows top first.
pub(crate) fn read_table(gpu: &Gpu, table: &wgpu::Buffer, format: Format, layer: u32, size: u32) -> Result<Image> {
    let bytes = format.bytes_per_texel() as u64 * size as u64 * size as u64;
    let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read back table"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    gpu.scoped("copying a summed-area table for read-back", || {
        enc.copy_buffer_to_buffer(table, layer as u64 * bytes, &buf, 0, bytes);
        gpu.queue.submit([enc.finish()]);
    })?;
    let raw = gpu.map_read(&buf)?;
    let rgba = raw.chunks_exact(16).map(|t| decode_texel(t, format)).collect();
    Ok(Image {
        width: size,
        height: size,
        rgba,
    })
}

/// One layer and mip level of a texture, decoded from `format`.
pub(crate) fn read_back(gpu: &Gpu, tex: &wgpu::Texture, layer: u32, level: u32, w: u32, h: u32, format: Format) -> Result<Image> {
    let bpp = format.bytes_per_texel();
    let row = (w * bpp).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read back"),
        size: row as u64 * h as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    gpu.scoped("copying a texture for read-back", || {
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: tex,
                mip_level: level,
                origin: wgpu::Origin3d { x: 0, y: 0, z: layer },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buf,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        gpu.queue.submit([enc.finish()]);
    })?;
    let raw = gpu.map_read(&buf)?;
    let mut rgba = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        let line = &raw[(y * row) as usize..];
        for x in 0..w {
            rgba.push(decode_texel(&line[(x * bpp) as usize..((x + 1) * bpp) as usize], format));
        }
    }
    Ok(Image { width: w, height: h, rgba })
}

/// One texel of `f` as f32 RGBA (missing components 0, alpha 1).
fn decode_texel(b: &[u8], f: Format) -> [f32; 4] {
    let mut out = [0.0, 0.0, 0.0, 1.0];
    let (component, n) = f.layout();
    let size = component.bytes() as usize;
    for (i, o) in out.iter_mut().enumerate().take(n as usize) {
        let c = &b[i * size..(i + 1) * size];
        *o = match component {
            Component::Unorm8 => c[0] as f32 / 255.0,
            Component::Unorm16 => u16::from_le_bytes([c[0], c[1]]) as f32 / 65535.0,
            Component::Float16 => half::f16::from_bits(u16::from_le_bytes([c[0], c[1]])).to_f32(),
            Component::Float32 => f32::from_le_bytes([c[0], c[1], c[2], c[3]]),
            Component::Uint32 => u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f32,
        };
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texels_decode_per_format() {
        assert_eq!(decode_texel(&[255], Format::R8Unorm), [1.0, 0.0, 0.0, 1.0]);
        assert_eq!(decode_texel(&[0, 0, 0xff, 0xff], Format::Rg16Unorm), [0.0, 1.0, 0.0, 1.0]);
        let h = half::f16::from_f32(0.5).to_bits().to_le_bytes();
        assert_eq!(
            decode_texel(&[h[0], h[1], 0, 0, 0, 0, h[0], h[1]], Format::Rgba16Float),
            [0.5, 0.0, 0.0, 0.5]
        );
        assert_eq!(decode_texel(&2.5f32.to_le_bytes(), Format::R32Float), [2.5, 0.0, 0.0, 1.0]);
    }
}
