//! Writing the runtime's read-back [`Image`]s to files: PFM (float) and 8-bit PNG. The
//! codecs live here, in the lab, so that the runtime carries none.

use crate::files::write_new;
use sshc_runtime::gpu::{Image, Result, RuntimeError};
use std::path::Path;

/// File writers of a read-back image (`use sshc_lab::image_io::ImageFiles`).
pub trait ImageFiles {
    /// Write component `c` as a one-channel PFM (float) file.
    fn write_pfm_gray(&self, path: &Path, c: usize) -> Result<()>;
    /// Write components xyz as a three-channel PFM file.
    fn write_pfm_rgb(&self, path: &Path) -> Result<()>;
    /// Write component `c` (or RGB when `None`) as an 8-bit PNG, values clamped to [0, 1].
    /// `range` maps [lo, hi] to [0, 1] first (for depth and basis images).
    fn write_png(&self, path: &Path, c: Option<usize>, range: (f32, f32)) -> Result<()>;
    /// Write component `c` as an 8-bit RGB PNG through the viridis map, normalised to its
    /// finite values' [min, max] (a constant image at the map's middle), NaN and infinities
    /// black; returns that range (`None`: no finite value).
    fn write_png_viridis(&self, path: &Path, c: usize) -> Result<Option<(f32, f32)>>;
}

/// The finite values' [min, max] of `values` (`None` if there is none).
pub fn finite_range(values: impl IntoIterator<Item = f32>) -> Option<(f32, f32)> {
    values
        .into_iter()
        .filter(|v| v.is_finite())
        .fold(None, |r, v| Some(r.map_or((v, v), |(lo, hi): (f32, f32)| (lo.min(v), hi.max(v)))))
}

/// `v` in [lo, hi] as a position on a colour map, in [0, 1] (the middle where lo = hi).
pub fn normalised(v: f32, (lo, hi): (f32, f32)) -> f64 {
    if hi > lo {
        (((v - lo) / (hi - lo)) as f64).clamp(0.0, 1.0)
    } else {
        0.5
    }
}

impl ImageFiles for Image {
    fn write_pfm_gray(&self, path: &Path, c: usize) -> Result<()> {
        write_pfm(path, self.width, self.height, false, self.channel(c))
    }

    fn write_pfm_rgb(&self, path: &Path) -> Result<()> {
        let data = self.rgba.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
        write_pfm(path, self.width, self.height, true, data)
    }

    fn write_png_viridis(&self, path: &Path, c: usize) -> Result<Option<(f32, f32)>> {
        let range = finite_range(self.rgba.iter().map(|p| p[c]));
        let buf: Vec<u8> = self
            .rgba
            .iter()
            .flat_map(|p| match range.filter(|_| p[c].is_finite()) {
                Some(r) => {
                    let col = colorous::VIRIDIS.eval_continuous(normalised(p[c], r));
                    [col.r, col.g, col.b]
                }
                None => [0, 0, 0],
            })
            .collect();
        let img = ::image::RgbImage::from_raw(self.width, self.height, buf)
            .ok_or_else(|| RuntimeError::NotFound("image size mismatch".into()))?;
        crate::files::save_image(&img, path).map_err(file_error(path))?;
        Ok(range)
    }

    fn write_png(&self, path: &Path, c: Option<usize>, range: (f32, f32)) -> Result<()> {
        let scale = |v: f32| {
            let t = if range.1 > range.0 {
                (v - range.0) / (range.1 - range.0)
            } else {
                v
            };
            (t.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
        };
        let mismatch = || RuntimeError::NotFound("image size mismatch".into());
        match c {
            Some(c) => {
                let buf: Vec<u8> = self.rgba.iter().map(|p| scale(p[c])).collect();
                let img = ::image::GrayImage::from_raw(self.width, self.height, buf).ok_or_else(mismatch)?;
                crate::files::save_image(&img, path).map_err(file_error(path))
            }
            None => {
                let buf: Vec<u8> = self.rgba.iter().flat_map(|p| [scale(p[0]), scale(p[1]), scale(p[2])]).collect();
                let img = ::image::RgbImage::from_raw(self.width, self.height, buf).ok_or_else(mismatch)?;
                crate::files::save_image(&img, path).map_err(file_error(path))
            }
        }
    }
}

/// A writer's message as the runtime's file error on `path`.
fn file_error(path: &Path) -> impl Fn(String) -> RuntimeError + '_ {
    move |message| RuntimeError::File {
        path: path.to_path_buf(),
        message: message.trim_start_matches("error: ").to_string(),
    }
}

fn write_pfm(path: &Path, w: u32, h: u32, color: bool, data: Vec<f32>) -> Result<()> {
    write_new(path, &pfm_bytes(w, h, color, data).map_err(file_error(path))?).map_err(file_error(path))
}

/// A PFM file's bytes (rows top first in `data`).
pub fn pfm_bytes(w: u32, h: u32, color: bool, data: Vec<f32>) -> std::result::Result<Vec<u8>, String> {
    let pfm = pxm::PFMBuilder::new()
        .size(w as usize, h as usize)
        .color(color)
        .scale(-1.0)
        .data(data)
        .build()
        .map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    pfm.write_into(&mut bytes).map_err(|e| e.to_string())?;
    Ok(bytes)
}
