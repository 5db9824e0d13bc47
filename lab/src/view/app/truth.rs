//! The truth in the viewer: refined on its own thread while a mode shows it, started over
//! once the view stands, each estimate made textures and an RMS against the visibility.

use super::App;
use crate::view::state::Mode;
use serde_json::json;

/// Frames the view must stand still before the truth starts over.
const TRUTH_SETTLE: u64 = 3;

impl App {
    /// Keep the truth going while a mode shows it: start it over where the view changed,
    /// and take a new estimate (its textures and the RMS against the visibility).
    pub(super) fn refine(&mut self) -> Result<(), String> {
        let shows = matches!(self.state.mode, Mode::Truth | Mode::Error { .. } | Mode::StdError { .. });
        self.refiner.pause(!shows);
        if self.ex.is_none() {
            return Ok(());
        }
        // started over once the view has stood for a few frames, not at every frame of a
        // drag (each start reads the camera's positions back from the GPU)
        if shows && self.truth_stale && self.frame >= self.last_move + TRUTH_SETTLE {
            let Some(ex) = &self.ex else { return Ok(()) };
            let (p, n) = crate::session::positions_normals(ex)?;
            let mut scene = self.current_scene();
            scene.lights.truncate(1);
            self.refiner.restart(scene, p, n);
            self.truth_stale = false;
            self.truth = None;
            self.truth_textures = None;
            self.rms = None;
        }
        let Some(ex) = &self.ex else { return Ok(()) };
        let Some(e) = self.refiner.poll() else { return Ok(()) };
        let vis = ex.inspect().read_visibilities().map_err(|e| format!("error: {e}"))?.channel(0);
        let error: Vec<f32> = vis
            .iter()
            .zip(&e.visibility)
            .map(|(v, t)| if t.is_finite() { v - t } else { 0.0 })
            .collect();
        let truth: Vec<f32> = e.visibility.iter().map(|t| if t.is_finite() { *t } else { 1.0 }).collect();
        self.rms = Some(crate::view::refine::rms(&vis, &e.visibility, &e.facing));
        let (mean_se, max_se) = e.std_errors();
        self.log.write(
            self.frame,
            json!({"event": "truth", "rounds": e.rounds, "seconds": e.seconds, "mean_std_error": mean_se, "max_std_error": max_se,
                   "rms": self.rms.map(|r| r.0), "rms_penumbra": self.rms.map(|r| r.1)}),
        );
        if let Some(gfx) = &self.gfx {
            let make = |data: &[f32]| {
                let t = gfx.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("sshc view: truth"),
                    size: wgpu::Extent3d {
                        width: e.width,
                        height: e.height,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wgpu::TextureFormat::R32Float,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                });
                let bytes: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
                gfx.queue.write_texture(
                    t.as_image_copy(),
                    &bytes,
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(e.width * 4),
                        rows_per_image: None,
                    },
                    t.size(),
                );
                t
            };
            self.truth_textures = Some([make(&truth), make(&error), make(&e.std_error)]);
        }
        self.truth = Some(e);
        Ok(())
    }
}
