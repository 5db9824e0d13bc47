//! The texels an evaluation is given rather than computes (`Given`): the Depth pass's and
//! every Geometry pass's outputs, and where the compiled graph keeps them (`given_slots`).

use crate::ir::{ChannelId, IrPassKind, Program, ResId};
use std::collections::HashMap;

/// Texels given to an evaluation instead of computed by it: the Depth pass's output and
/// every Geometry pass's, by resource and channel, one map per view (the centre's alone, or
/// one per light sample), decoded, row 0 first.
#[derive(Clone, Debug, Default)]
pub struct Given {
    pub(super) maps: HashMap<(ResId, ChannelId), Vec<Vec<f64>>>,
}

impl Given {
    /// The Depth pass's output: one linear depth map per view.
    pub fn depth(compiled: &crate::Compiled, views: Vec<Vec<f32>>) -> Given {
        let mut g = Given::default();
        for s in slots(&compiled.program()).into_iter().filter(|s| !s.geometry) {
            g.insert(
                s.resource,
                s.channel,
                views.iter().map(|v| v.iter().map(|&z| z as f64).collect()).collect(),
            );
        }
        g
    }

    /// One channel's maps, one per view.
    pub fn maps(&self, resource: ResId, channel: ChannelId) -> Option<&[Vec<f64>]> {
        self.maps.get(&(resource, channel)).map(Vec::as_slice)
    }

    /// Give one channel's maps, one per view.
    pub fn insert(&mut self, resource: ResId, channel: ChannelId, views: Vec<Vec<f64>>) {
        self.maps.insert((resource, channel), views);
    }
}

/// A channel an evaluation must be given, and where the compiled graph keeps it.
#[derive(Clone, Debug, PartialEq)]
pub struct GivenSlot {
    /// The pass that writes it.
    pub pass: String,
    /// Written by a Geometry pass (else by Depth).
    pub geometry: bool,
    pub resource: ResId,
    pub channel: ChannelId,
    /// The graph's texture, and the channel's layer within one view's block of `layers`.
    pub texture: String,
    pub layer: u32,
    pub layers: u32,
    pub component: u32,
    /// Views: 1, or one per light sample (view k's block starts at layer `k * layers`).
    pub views: u32,
    /// The stored value is `(v - bias) * scale`.
    pub bias: f64,
    pub scale: f64,
}

impl GivenSlot {
    /// A stored texel's value.
    pub fn decode(&self, stored: f32) -> f64 {
        stored as f64 / self.scale + self.bias
    }

    /// The array layer of view `k`.
    pub fn array_layer(&self, k: u32) -> u32 {
        k * self.layers + self.layer
    }
}

/// The channels written by the live Depth and Geometry passes of `compiled`: what an
/// evaluation is given rather than computes.
pub fn given_slots(compiled: &crate::Compiled) -> Vec<GivenSlot> {
    slots(&compiled.program())
}

fn slots(p: &Program) -> Vec<GivenSlot> {
    let mut out = Vec::new();
    for pass in p.passes.iter().filter(|pass| pass.live) {
        let geometry = match pass.kind {
            IrPassKind::Depth { .. } => false,
            IrPassKind::Geometry { .. } => true,
            IrPassKind::Map
            | IrPassKind::Filter { .. }
            | IrPassKind::Mipmap { .. }
            | IrPassKind::SummedArea { .. }
            | IrPassKind::Shade { .. } => {
                continue;
            }
        };
        let Some(r) = pass.writes else { continue };
        let res = &p.resources[r];
        for s in &res.slots {
            let Some(t) = res.textures.get(s.texture) else { continue };
            out.push(GivenSlot {
                pass: pass.name.clone(),
                geometry,
                resource: r,
                channel: s.channel,
                texture: t.name.clone(),
                layer: s.layer,
                layers: t.layers,
                component: s.component,
                views: if p.per_sample(r) { p.samples } else { 1 },
                bias: s.encode.bias,
                scale: s.encode.scale,
            });
        }
    }
    out
}
