//! The memory traffic a pass cannot avoid, and the time it implies at a bandwidth: the
//! cost model beside the operation counts.
//!
//! A pass's *compulsory* bytes are what any schedule of it must move between memory and
//! the GPU, with a perfect cache: every texel it writes once, at its format, and every
//! texel it reads once. Their sum over a bandwidth is a lower bound on the pass's time
//! (the roofline's memory side); a pass near its bound is limited by memory, one far above
//! it by something else (arithmetic, scheduling, the raster path). The model, per step:
//!
//! - writes: every target layer at its format over its extent (a mip chain's levels below
//!   the base: a third of the base); a depth pass's `Depth32Float` attachment (4 bytes a
//!   texel); the Shade's four camera targets (`CAMERA_BYTES_PER_PIXEL`) and its depth
//!   (a deferred Shade: the G-buffer, `GBUFFER_BYTES_PER_PIXEL`, and the depth, then the
//!   four targets from the compute step, which reads the G-buffer back once); a
//!   summed-area table's 16-byte cells;
//! - reads, for steps over the shadow map: each texture it binds, over the base level, in
//!   as many layers as the step writes where the two textures have the same layer count (a
//!   filter reads the layers it writes), all its layers otherwise; a mip level reads the
//!   level above it (4/3 of the base over the chain);
//! - not counted, because the graph and the sizes do not give them: the scene's vertices,
//!   what a Shade reads (it depends on what the camera sees: at most the textures it
//!   binds), generated primitives and the records of Geometry passes.

use crate::cost::sizes::{
    CAMERA_BYTES_PER_PIXEL, DEPTH_BYTES_PER_TEXEL, GBUFFER_BYTES_PER_PIXEL, Sizes, below_base, with_levels, written_layers,
};
use crate::{Draw, Extent, PassGraph, PassKind, Step, View};

/// Compulsory bytes of one frame of a pass.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Traffic {
    pub read: f64,
    pub written: f64,
}

impl Traffic {
    pub fn total(&self) -> f64 {
        self.read + self.written
    }

    /// The lower bound on time, in milliseconds, at `gbps` (10^9 bytes a second).
    pub fn bound_ms(&self, gbps: f64) -> f64 {
        self.total() / (gbps * 1e9) * 1e3
    }
}

/// Compulsory bytes of one step (one view of it).
pub fn step(graph: &PassGraph, kind: PassKind, s: &Step, sizes: Sizes) -> Traffic {
    let base = sizes.texels(Extent::ShadowMap);
    let camera = sizes.texels(Extent::Camera);
    let mut t = Traffic::default();
    for w in &s.writes {
        if let Some(tex) = graph.texture(&w.texture) {
            let bytes = f64::from(tex.format.bytes_per_texel()) * sizes.texels(tex.extent);
            t.written += if s.draw.writes_levels_below_base() {
                below_base(bytes)
            } else {
                bytes
            };
        }
    }
    match s.draw {
        Draw::SceneFromLight => t.written += f64::from(DEPTH_BYTES_PER_TEXEL) * base,
        Draw::SceneFromCamera => {
            t.written += f64::from(CAMERA_BYTES_PER_PIXEL + DEPTH_BYTES_PER_TEXEL) * camera;
        }
        // a deferred Shade: the G-buffer written, then read back and the outputs stored
        Draw::CameraGBuffer => {
            t.written += f64::from(GBUFFER_BYTES_PER_PIXEL + DEPTH_BYTES_PER_TEXEL) * camera;
        }
        Draw::ComputePixels => {
            t.read += f64::from(GBUFFER_BYTES_PER_PIXEL) * camera;
            t.written += f64::from(CAMERA_BYTES_PER_PIXEL) * camera;
        }
        // their targets' bytes (above) and reads (below) are all they move
        Draw::FullScreen
        | Draw::MipLevels
        | Draw::ComputeRows
        | Draw::ComputeColumns
        | Draw::ComputeTexels
        | Draw::ComputeMipLevels
        | Draw::Silhouettes { .. }
        | Draw::Primitives { .. }
        | Draw::Discontinuities { .. } => {}
    }
    if kind.is_shade() || !s.draw.reads_whole_textures() {
        return t;
    }
    let written_layers_now = s.writes.len() as u32;
    let written_layer_count = written_layers(graph, s);
    for b in &s.reads {
        let Some(tex) = graph.texture(&b.texture) else { continue };
        let layers = if written_layers_now > 0 && written_layer_count == Some(tex.layers) {
            written_layers_now.min(tex.layers)
        } else {
            tex.layers
        };
        let texels = match s.draw {
            // the neighbour's depth map: one layer of the per-sample block
            Draw::Discontinuities { .. } => sizes.texels(tex.extent),
            Draw::SceneFromLight
            | Draw::SceneFromCamera
            | Draw::CameraGBuffer
            | Draw::ComputePixels
            | Draw::FullScreen
            | Draw::MipLevels
            | Draw::ComputeRows
            | Draw::ComputeColumns
            | Draw::ComputeTexels
            | Draw::ComputeMipLevels
            | Draw::Silhouettes { .. }
            | Draw::Primitives { .. } => sizes.texels(tex.extent) * f64::from(layers),
        };
        let bytes = f64::from(tex.format.bytes_per_texel()) * texels;
        t.read += match b.view {
            // level k - 1 for each level k >= 1 written: the base and all but the last
            View::PreviousLevel => with_levels(bytes),
            View::Base | View::All => bytes,
        };
    }
    t
}

/// Compulsory bytes of one frame of each pass, in the graph's order: its steps, once per
/// light sample for a per-sample pass ([`PassGraph::views_of`]).
pub fn passes(graph: &PassGraph, sizes: Sizes) -> Vec<(String, Traffic)> {
    graph
        .passes
        .iter()
        .map(|p| {
            let views = f64::from(graph.views_of(p));
            let mut t = Traffic::default();
            for s in &p.steps {
                let st = step(graph, p.kind, s, sizes);
                t.read += st.read * views;
                t.written += st.written * views;
            }
            (p.name.clone(), t)
        })
        .collect()
}
