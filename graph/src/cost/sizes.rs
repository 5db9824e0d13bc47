//! What the cost model's parts share: the sizes a frame runs at, texels per extent, a mip
//! chain's share of its base, the bytes of a texture and of the fixed attachments.

use crate::{CAMERA_OUTPUTS, Extent, Format, GBUFFER, PassGraph, Step, TextureDecl};

/// The sizes a frame runs at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sizes {
    /// Shadow-map resolution (texels on a side).
    pub shadow: u32,
    /// Camera resolution (width, height).
    pub camera: (u32, u32),
}

impl Sizes {
    /// Texels of `e` at these sizes (the camera's: pixels).
    pub fn texels(&self, e: Extent) -> f64 {
        match e {
            Extent::ShadowMap => f64::from(self.shadow) * f64::from(self.shadow),
            Extent::Camera => f64::from(self.camera.0) * f64::from(self.camera.1),
        }
    }

    /// [`Sizes::texels`], exactly.
    pub fn texel_count(&self, e: Extent) -> u64 {
        match e {
            Extent::ShadowMap => u64::from(self.shadow) * u64::from(self.shadow),
            Extent::Camera => u64::from(self.camera.0) * u64::from(self.camera.1),
        }
    }
}

/// Of a mip chain over a base level of `n` texels (or bytes), the levels below the base:
/// `n / 4 + n / 16 + ...`, a third of it.
pub fn below_base(n: f64) -> f64 {
    n / 3.0
}

/// A whole mip chain over a base level of `n` texels (or bytes): 4/3 of it.
pub fn with_levels(n: f64) -> f64 {
    n * 4.0 / 3.0
}

/// [`with_levels`] in whole bytes, rounded down.
pub fn with_levels_bytes(n: u64) -> u64 {
    n * 4 / 3
}

const fn bytes_of(formats: &[Format]) -> u32 {
    let mut sum = 0;
    let mut i = 0;
    while i < formats.len() {
        sum += formats[i].bytes_per_texel();
        i += 1;
    }
    sum
}

/// The Shade pass's targets ([`CAMERA_OUTPUTS`]): visibility (r32float), colour
/// (rgba8unorm), position (rgba32float) and normal (rgba16float), 32 bytes a pixel.
pub const CAMERA_BYTES_PER_PIXEL: u32 = bytes_of(&CAMERA_OUTPUTS);
/// A deferred Shade's G-buffer ([`GBUFFER`]): 16 + 8 + 8 bytes.
pub const GBUFFER_BYTES_PER_PIXEL: u32 = bytes_of(&GBUFFER);
/// `Depth32Float`: the light's and the camera's depth attachments.
pub const DEPTH_BYTES_PER_TEXEL: u32 = 4;

impl TextureDecl {
    /// Bytes of one texel of its extent in all its array layers (every view's), its mip
    /// levels below the base left out.
    pub fn layer_bytes(&self) -> u64 {
        u64::from(self.format.bytes_per_texel()) * u64::from(self.array_layers())
    }

    /// Bytes per texel of its extent: every array layer, a mip chain's 4/3 included (the
    /// cost report's memory, per shadow-map texel for the shadow-map textures).
    pub fn texel_bytes(&self) -> f64 {
        let base = self.layer_bytes() as f64;
        if self.mips { with_levels(base) } else { base }
    }

    /// Bytes allocated for it at `sizes`: every array layer, a mip chain's 4/3 included
    /// (rounded down).
    pub fn bytes(&self, sizes: Sizes) -> u64 {
        let base = self.layer_bytes() * sizes.texel_count(self.extent);
        if self.mips { with_levels_bytes(base) } else { base }
    }
}

/// Layers (of one view) of the first texture `s` writes: the layers a filter writes at
/// once, the tables a summed-area step walks.
pub fn written_layers(graph: &PassGraph, s: &Step) -> Option<u32> {
    s.writes.first().and_then(|w| graph.texture(&w.texture)).map(|t| t.layers)
}
