//! What an evaluation reads besides texels: the frame-wide inputs (`Frame`), the receiver
//! and each light sample's view of it (`Receiver`, `Seen`), and the value of a built-in
//! input or of a function the evaluators' leaf hook answers (`noise`, `uv_width`).

use crate::builtins::Input;

/// The frame-wide inputs (docs/language.md section 8.5), as the runtime's `Frame` uniform
/// holds them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub shadow_size: u32,
    /// World distances of the fitted depth range.
    pub near: f64,
    pub far: f64,
    pub light_size: f64,
    pub light_width: [f64; 2],
    pub light_spread: f64,
    pub light_distant: bool,
    /// One texel at view distance D spans `texel_world[0] D + texel_world[1]` world units
    /// across the map (perspective: `[2 / (proj_y N), 0]`; orthographic: `[0, extent / N]`).
    pub texel_world: [f64; 2],
    /// Frames run since the scene was bound.
    pub frame: u32,
}

/// One receiver (a shaded point) as the Shade pass sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct Receiver {
    /// Light-space uv.
    pub uv: [f64; 2],
    /// View distance from the light's centre (world units).
    pub d_world: f64,
    pub ndotl: f64,
    /// The receiver plane's depth slope per texel (`depth_slope`).
    pub depth_slope: f64,
    /// The level of detail of implicit `sample` lookups.
    pub lod: f64,
    /// The camera pixel.
    pub pixel: [f64; 2],
    /// The receiver as each light sample's view sees it, in sample order (empty without
    /// per-sample views).
    pub samples: Vec<Seen>,
}

/// A receiver seen from light sample k (the `in_*_v{k}` of the generated Shade): its
/// coordinates in the sample's view and the view's own depth range, texel size and weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seen {
    pub uv: [f64; 2],
    pub d_world: f64,
    /// The view's fitted depth range (world distances).
    pub near: f64,
    pub far: f64,
    /// `dot(n, normalize(sample position - receiver))`.
    pub ndotl: f64,
    pub depth_slope: f64,
    pub lod: f64,
    /// World size of one texel per unit of view distance (`2 / (proj_y N)`).
    pub texel_world: f64,
    /// Weights of the segments before and after the sample (`segment_before`, `segment_after`).
    pub weights: [f64; 2],
}

impl Seen {
    fn d(&self) -> f64 {
        (self.d_world - self.near) / (self.far - self.near)
    }
}

/// The value of input `i` in component `k`: a frame-wide one from the frame, a receiver's
/// as the view `at` sees it (`None`: no receiver, outside the Shade), a Geometry
/// fragment's never (`None`: the Geometry passes' outputs are given).
pub(super) fn input_value(f: &Frame, i: Input, k: usize, at: Option<&At>) -> Option<f64> {
    let n = f.shadow_size as f64;
    let slope = |ndotl: f64| ((1.0 - ndotl * ndotl).max(0.0).sqrt() / ndotl.abs().max(0.01)).min(100.0);
    Some(match i {
        Input::TexelSize => 1.0 / n,
        Input::ShadowSize => n,
        Input::Near => f.near,
        Input::Far => f.far,
        Input::LightSize => f.light_size,
        Input::LightWidth => f.light_width[k.min(1)],
        Input::LightSpread => f.light_spread,
        Input::LightDistant => f.light_distant as i32 as f64,
        Input::Frame => f.frame as f64,
        Input::D => at?.seen.d(),
        Input::DWorld => at?.seen.d_world,
        Input::Uv => at?.seen.uv[k.min(1)],
        Input::Tf => {
            let t = at?.seen.uv[k.min(1)] * n - 0.5;
            t - t.floor()
        }
        Input::NdotL => at?.seen.ndotl,
        Input::Slope => slope(at?.seen.ndotl),
        // the centre's: (texel_world.x D + texel_world.y) / (far - near); a sample's view
        // is perspective: its texel_world.x D / (far - near)
        Input::TexelDepth => {
            let at = at?;
            let s = &at.seen;
            if at.centre {
                (f.texel_world[0] * s.d_world + f.texel_world[1]) / (f.far - f.near)
            } else {
                s.texel_world * s.d_world / (s.far - s.near)
            }
        }
        Input::DepthSlope => at?.seen.depth_slope,
        Input::SegmentBefore => at?.seen.weights[0],
        Input::SegmentAfter => at?.seen.weights[1],
        Input::Pixel => at?.pixel[k.min(1)],
        Input::ZFrag
        | Input::ZVertex
        | Input::ConeRadius
        | Input::ZSurface
        | Input::OccluderDepth
        | Input::PenumbraLimit
        | Input::LimitDepth
        | Input::Skin => return None,
    })
}

/// A receiver as one view sees it, for [`input_value`].
pub(super) struct At {
    pub(super) seen: Seen,
    /// The light's centre view (not a light sample's).
    pub(super) centre: bool,
    pub(super) pixel: [f64; 2],
}

/// `noise(x, y, k)`: PCG3D of the three integers (`builtins::NOISE_WGSL`), top 24 bits.
pub fn noise(x: f64, y: f64, k: f64) -> f64 {
    let u = |v: f64| v.floor() as i32 as u32;
    let mut v = [u(x), u(y), u(k)];
    for c in &mut v {
        *c = c.wrapping_mul(1664525).wrapping_add(1013904223);
    }
    let mix = |v: &mut [u32; 3]| {
        v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[2]));
        v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
        v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    };
    mix(&mut v);
    for c in &mut v {
        *c ^= *c >> 16;
    }
    mix(&mut v);
    (v[0] >> 8) as f64 / 16_777_216.0
}

/// The light-side function `uv_width(len, dist)`.
pub(super) fn uv_width(f: &Frame, len: f64, dist: f64) -> f64 {
    len / ((f.texel_world[0] * dist + f.texel_world[1]) * f.shadow_size as f64)
}
