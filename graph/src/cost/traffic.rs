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
//!   texel); the Shade's four camera targets ([`CAMERA_BYTES_PER_PIXEL`]) and its depth
//!   (a deferred Shade: the G-buffer, [`GBUFFER_BYTES_PER_PIXEL`], and the depth, then the
//!   four targets from the compute step, which reads the G-buffer back once); a
//!   summed-area table's 16-byte cells;
//! - reads, for steps over the shadow map: each texture it binds, over the base level, in
//!   as many layers as the step writes where the two textures have the same layer count (a
//!   filter reads the layers it writes), all its layers otherwise; a mip level reads the
//!   level above it (4/3 of the base over the chain);
//! - not counted, because the graph and the sizes do not give them: the scene's vertices,
//!   what a Shade reads (it depends on what the camera sees: at most the textures it
//!   binds), generated primitives and the records of Geometry passes.

use crate::{Draw, Extent, PassGraph, PassKind, Step, View, Views};

/// The Shade pass's targets: visibility (r32float), colour (rgba8unorm), position
/// (rgba32float) and normal (rgba16float).
pub const CAMERA_BYTES_PER_PIXEL: f64 = 32.0;
/// A deferred Shade's G-buffer ([`crate::GBUFFER`]): 16 + 8 + 8 bytes.
pub const GBUFFER_BYTES_PER_PIXEL: f64 = 32.0;
/// `Depth32Float`.
pub const DEPTH_BYTES_PER_TEXEL: f64 = 4.0;

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

/// The sizes a frame runs at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sizes {
    /// Shadow-map resolution (texels on a side).
    pub shadow: u32,
    /// Camera resolution (width, height).
    pub camera: (u32, u32),
}

impl Sizes {
    fn texels(&self, e: Extent) -> f64 {
        match e {
            Extent::ShadowMap => f64::from(self.shadow) * f64::from(self.shadow),
            Extent::Camera => f64::from(self.camera.0) * f64::from(self.camera.1),
        }
    }
}

/// Whether a step's reads are compulsory traffic, every texel of what it reads once: a
/// full-screen or compute step over the map reads its inputs whole; the camera's raster, a
/// classification over the scene's edges and a draw of generated primitives read only
/// where their fragments or edges look.
fn reads_whole_textures(d: &Draw) -> bool {
    match d {
        Draw::SceneFromCamera | Draw::Silhouettes { .. } | Draw::Primitives { .. } => false,
        Draw::SceneFromLight
        | Draw::CameraGBuffer
        | Draw::ComputePixels
        | Draw::FullScreen
        | Draw::MipLevels
        | Draw::ComputeRows
        | Draw::ComputeColumns
        | Draw::ComputeTexels
        | Draw::ComputeMipLevels
        | Draw::Discontinuities { .. } => true,
    }
}

/// Compulsory bytes of one step (one view of it).
pub fn step(graph: &PassGraph, kind: PassKind, s: &Step, sizes: Sizes) -> Traffic {
    let texture = |name: &str| graph.textures.iter().find(|t| t.name == name);
    let base = sizes.texels(Extent::ShadowMap);
    let mut t = Traffic::default();
    // the levels below the base of a chain: 1/4 + 1/16 + ... of it
    let chain = |d: &Draw| {
        if d.writes_levels_below_base() { 1.0 / 3.0 } else { 1.0 }
    };
    for w in &s.writes {
        if let Some(tex) = texture(&w.texture) {
            t.written += f64::from(tex.format.bytes_per_texel()) * sizes.texels(tex.extent) * chain(&s.draw);
        }
    }
    match s.draw {
        Draw::SceneFromLight => t.written += DEPTH_BYTES_PER_TEXEL * base,
        Draw::SceneFromCamera => {
            t.written += (CAMERA_BYTES_PER_PIXEL + DEPTH_BYTES_PER_TEXEL) * sizes.texels(Extent::Camera);
        }
        // a deferred Shade: the G-buffer written, then read back and the outputs stored
        Draw::CameraGBuffer => {
            t.written += (GBUFFER_BYTES_PER_PIXEL + DEPTH_BYTES_PER_TEXEL) * sizes.texels(Extent::Camera);
        }
        Draw::ComputePixels => {
            t.read += GBUFFER_BYTES_PER_PIXEL * sizes.texels(Extent::Camera);
            t.written += CAMERA_BYTES_PER_PIXEL * sizes.texels(Extent::Camera);
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
    if kind == PassKind::Shade || !reads_whole_textures(&s.draw) {
        return t;
    }
    let written_layers = s.writes.len() as u32;
    let written_layer_count = s.writes.first().and_then(|w| texture(&w.texture)).map(|t| t.layers);
    for b in &s.reads {
        let Some(tex) = texture(&b.texture) else { continue };
        let layers = if written_layers > 0 && written_layer_count == Some(tex.layers) {
            written_layers.min(tex.layers)
        } else {
            tex.layers
        };
        let level = match b.view {
            // level k - 1 for each level k >= 1 written: the base and all but the last
            View::PreviousLevel => 4.0 / 3.0,
            View::Base | View::All => 1.0,
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
        t.read += f64::from(tex.format.bytes_per_texel()) * texels * level;
    }
    t
}

/// Compulsory bytes of one frame of each pass, in the graph's order: its steps, once per
/// light sample for a per-sample pass.
pub fn passes(graph: &PassGraph, sizes: Sizes) -> Vec<(String, Traffic)> {
    graph
        .passes
        .iter()
        .map(|p| {
            let views = if p.views == Views::PerLightSample {
                f64::from(graph.samples)
            } else {
                1.0
            };
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
