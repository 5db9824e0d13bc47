//! The graph steps that full-screen pass emitters build, and the groups of layers one
//! render pass writes together.

use crate::ir::Texture;
use crate::pack::{Limits, layers_per_subpass};
use sshc_graph::{Binding, Draw, OpCount, Step, Target};

/// Groups of layers of one texture that one render pass writes together.
pub(crate) fn layer_chunks(t: &Texture, limits: &Limits) -> Vec<Vec<u32>> {
    let per = layers_per_subpass(t, limits);
    (0..t.layers).collect::<Vec<_>>().chunks(per as usize).map(|c| c.to_vec()).collect()
}

/// A full-screen step writing `layers` of `texture`.
pub(crate) fn fullscreen_step(entry: String, draw: Draw, reads: Vec<Binding>, texture: &str, layers: &[u32]) -> Step {
    Step {
        vertex: Some("vs_fullscreen".into()),
        fragment: Some(entry),
        compute: None,
        draw,
        reads,
        writes: layers
            .iter()
            .map(|&layer| Target {
                texture: texture.to_string(),
                layer,
            })
            .collect(),
        params: false,
        sampler: false,
        light_samples: false,
        cost: OpCount::default(),
    }
}
