//! What a mode shows: the texture (the shaded colour, the visibility, the cascades, the
//! truth's, a graph's texture) and how to read it.

use crate::run::Bound;
use crate::view::present::Pick;
use crate::view::state::{ColourMap, Mode};
use sshc_runtime::gpu::CameraOutput;

/// The texture a mode shows from `ex` (the truth's from `truth`: the truth, the error, the
/// standard error), and how to read it.
pub(super) fn shown<'a>(mode: &Mode, ex: &'a Bound, truth: Option<&'a [wgpu::Texture; 3]>) -> (Option<&'a wgpu::Texture>, Pick) {
    match mode {
        Mode::Shaded => (Some(ex.targets.camera_texture(CameraOutput::Color)), shaded()),
        // light 0's visibility, or the cascades' combination
        Mode::Visibility => (
            Some(ex.targets.visibility()),
            Pick {
                layer: 0,
                level: 0,
                channel: 0,
                map: ColourMap::Grey.index(),
                lo: 0.0,
                hi: 1.0,
                square: false,
            },
        ),
        // the combining step's channel 1: the cascade, `k + t` in a band
        Mode::Cascades => {
            let n = ex.targets.cascades();
            let texture = if n > 1 {
                ex.targets.visibility()
            } else {
                ex.targets.camera_texture(CameraOutput::Visibility)
            };
            (
                Some(texture),
                Pick {
                    layer: 0,
                    level: 0,
                    // one R32Float channel without cascades: its g reads 0, cascade 0
                    channel: 1,
                    map: ColourMap::Viridis.index(),
                    lo: 0.0,
                    hi: (n.max(2) - 1) as f32,
                    square: false,
                },
            )
        }
        Mode::Truth | Mode::Error { .. } | Mode::StdError { .. } => {
            let (i, map, lo, hi) = match *mode {
                Mode::Error { range } => (1, ColourMap::Diverging, -range, range),
                Mode::StdError { range } => (2, ColourMap::Viridis, 0.0, range),
                _ => (0, ColourMap::Grey, 0.0, 1.0),
            };
            (
                truth.map(|t| &t[i]),
                Pick {
                    layer: 0,
                    level: 0,
                    channel: 0,
                    map: map.index(),
                    lo,
                    hi,
                    square: false,
                },
            )
        }
        Mode::Texture {
            name,
            layer,
            level,
            channel,
            lo,
            hi,
            map,
        } => (
            ex.targets.texture(name).ok(),
            Pick {
                layer: *layer,
                level: *level,
                channel: *channel,
                map: map.index(),
                lo: *lo,
                hi: *hi,
                // a shadow map's texture in a square; a debug output over the camera's view
                square: ex
                    .graph()
                    .texture(name)
                    .is_none_or(|t| t.extent != sshc_runtime::graph::Extent::Camera),
            },
        ),
    }
}

/// The shaded colour as it is.
fn shaded() -> Pick {
    Pick {
        layer: 0,
        level: 0,
        channel: 4,
        map: 0,
        lo: 0.0,
        hi: 1.0,
        square: false,
    }
}
