//! What storage rounding does to the visibility: a first-order estimate of the
//! visibility error that each stored channel's precision causes, per channel and for all
//! of them, reported by `explain` and warned about at compile time above
//! [`WARN_ABOVE`].
//!
//! The estimate is sampled, not a proof. A shadow-map texel seen through a filter is
//! modelled as a mixture of two depth planes, `z1` (weight `a`) and `z2`: every Map
//! channel's value is computed at both depths from its expression (`f(z1)`, `f(z2)`) and
//! the filters and mip levels after it are linear (the mixture `a f(z1) + (1 - a) f(z2)`),
//! a maximum or a minimum (of the two). The Shade's visibility is then evaluated in f64
//! at receivers of depth `d`, with every lookup of a channel returning that channel's
//! mixture, and again with the channel moved by its storage rounding, up and down:
//!
//! - `Unorm8`, `Unorm16`: half a step of the encoded range, `(hi - lo) / (2 (2^n - 1))`
//!   (a unorm store rounds to the nearest step);
//! - `F16`: half an ulp, `|v| 2^-11`, and at least half the subnormal spacing, `2^-25`;
//! - `F32`: half an ulp, `|v| 2^-24`, at least `2^-150`.
//!
//! A channel's error is the largest change of the visibility (clamped to [0, 1], as the
//! runtime stores it) over the configurations; the total is the largest sum of the
//! channels' changes at one configuration (first order: each channel's worst sign).
//! Configurations: `z1 <= z2` on the eighths of [0, 1] (`z1 = z2` is a plane), `a` = 1/2
//! for two planes, and receivers `d` on sixteenths of [0, 1]. Inputs
//! other than `d` take the values of [`typical`]; lookups at offsets and filtered lookups
//! read the same mixture.
//!
//! Not estimated: techniques with Geometry passes, per-sample views, summed-area tables
//! or Laplacian filters, whose stored values are not functions of a texel's depth.

use crate::builtins::Input;
use crate::front::ast::{Precision, Reduce};
use crate::ir::{ChannelId, IrKernel, IrPassKind, Node, PlacedSlot, Program, ResId};
use std::collections::HashMap;

/// Above this estimated visibility error a compilation warns: 5 % of the visibility's
/// range (13 of 255 display steps) shows as banding or speckle at a glance; below it the
/// rounding is a small part of what separates a technique from the ground truth.
pub const WARN_ABOVE: f64 = 0.05;

/// Node evaluations one estimate may spend (the configurations are thinned past it).
const BUDGET: usize = 20_000_000;

/// One stored channel's part of the estimate.
#[derive(Clone, Debug)]
pub struct ChannelError {
    pub channel: ChannelId,
    pub name: String,
    /// The precision it is stored at.
    pub precision: Precision,
    /// The largest visibility change its rounding causes at its precision.
    pub error: f64,
    /// The same at each precision of [`Precision::ALL`] (`None` where that precision
    /// cannot hold the channel's range: a unorm needs a finite one, F16 at most 65504).
    pub at: [Option<f64>; 4],
}

/// The estimate for one precision assignment.
#[derive(Clone, Debug)]
pub struct Estimate {
    pub channels: Vec<ChannelError>,
    /// The largest sum of the channels' changes at one configuration.
    pub total: f64,
    /// Configurations evaluated, and those whose visibility was not a number (skipped).
    pub configurations: usize,
    pub skipped: usize,
}

/// Why a technique's rounding was not estimated.
pub fn unsupported(p: &Program) -> Option<&'static str> {
    for pass in p.passes.iter().filter(|pass| pass.live) {
        match &pass.kind {
            IrPassKind::Geometry { .. } => return Some("its Geometry passes generate what they store"),
            IrPassKind::Depth { view } if *view != crate::front::ast::LightView::Center => {
                return Some("it renders per-sample views");
            }
            IrPassKind::SummedArea => return Some("it reads summed-area tables"),
            IrPassKind::Filter { kernel: IrKernel::LoG } => return Some("it filters with a Laplacian"),
            IrPassKind::Depth { .. }
            | IrPassKind::Map
            | IrPassKind::Filter { .. }
            | IrPassKind::Mipmap { .. }
            | IrPassKind::Shade { .. } => {}
        }
    }
    None
}

/// The value an input takes in the typical configuration its descriptor states
/// ([`InputDesc::typical`](crate::builtins::InputDesc::typical)).
pub fn typical(i: Input) -> f64 {
    i.desc().typical
}

/// How a resource's texels combine the two planes' values.
#[derive(Clone, Copy, PartialEq)]
enum Mix {
    Mean,
    Max,
    Min,
}

/// Half the rounding step of `precision` at value `v` over the stored range `range`.
fn half_step(precision: Precision, v: f64, range: (f64, f64)) -> f64 {
    let width = range.1 - range.0;
    match precision {
        Precision::Unorm8 => width / (2.0 * 255.0),
        Precision::Unorm16 => width / (2.0 * 65535.0),
        Precision::F16 => (v.abs() * 2f64.powi(-11)).max(2f64.powi(-25)),
        Precision::F32 => (v.abs() * 2f64.powi(-24)).max(2f64.powi(-150)),
    }
}

/// How much an estimate computes.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Detail {
    /// Each channel at its laid-out precision: what a compilation's warning needs.
    Warn,
    /// Each channel at every precision besides (`sshc explain`). The configurations are
    /// the same, so the two give the same figures for the laid-out precisions.
    Explain,
}

/// The estimate with each stored channel at its laid-out precision (and, for
/// [`Detail::Explain`], each channel's error at every precision). `None` where
/// [`unsupported`] or nothing is looked up.
pub fn estimate(p: &Program, detail: Detail) -> Option<Estimate> {
    if unsupported(p).is_some() {
        return None;
    }
    let shade = p.shade()?;
    let order = p.arena.postorder(&[shade]);
    // the (resource, channel) pairs the Shade looks up, with their slot
    let mut looked: Vec<(ResId, ChannelId, PlacedSlot, Mix)> = Vec::new();
    for &h in &order {
        if let Node::Sample { channel, resource, .. } = p.arena.node(h)
            && !looked.iter().any(|l| l.0 == *resource && l.1 == *channel)
        {
            let slot = *p.resources[*resource].slots.iter().find(|s| s.channel == *channel)?;
            looked.push((*resource, *channel, slot, mix_of(p, *resource)));
        }
    }
    if looked.is_empty() {
        return None;
    }
    let (plane_steps, receiver_steps) = (8, 16);
    let planes: Vec<f64> = (0..=plane_steps).map(|i| i as f64 / plane_steps as f64).collect();
    let mut textures: Vec<(f64, f64, f64)> = Vec::new();
    for (i, &z1) in planes.iter().enumerate() {
        for &z2 in &planes[i..] {
            textures.push((z1, z2, if z1 == z2 { 1.0 } else { 0.5 }));
        }
    }
    let mut receivers: Vec<f64> = (0..=receiver_steps).map(|i| i as f64 / receiver_steps as f64).collect();
    // thin the receivers where the expression is large
    let evals_per_channel = match detail {
        Detail::Warn => 2,
        Detail::Explain => 8,
    };
    let per = order.len().max(1) * (1 + evals_per_channel * looked.len());
    while receivers.len() > 3 && per * textures.len() * receivers.len() > BUDGET {
        receivers = receivers.iter().step_by(2).copied().collect();
    }
    let mut channels: Vec<ChannelError> = looked
        .iter()
        .map(|(_, c, slot, _)| ChannelError {
            channel: *c,
            name: p.channels[*c].name.clone(),
            precision: slot.precision,
            error: 0.0,
            at: Precision::ALL.map(|q| (detail == Detail::Explain && crate::analyse::fits(q, slot.range)).then_some(0.0)),
        })
        .collect();
    let (mut total, mut configurations, mut skipped) = (0.0f64, 0, 0);
    let mut scratch = vec![[f64::NAN; 4]; p.arena.len()];
    let mut memo = HashMap::new();
    for &(z1, z2, a) in &textures {
        let mut stored = Vec::with_capacity(looked.len());
        for (_, c, _, mix) in &looked {
            let f1 = channel_value(p, *c, z1, &mut memo, 0);
            let f2 = channel_value(p, *c, z2, &mut memo, 0);
            stored.push(match mix {
                Mix::Mean => a * f1 + (1.0 - a) * f2,
                Mix::Max => f1.max(f2),
                Mix::Min => f1.min(f2),
            });
        }
        for &d in &receivers {
            let mut visibility = |moved: Option<(usize, f64)>| {
                let v = p.arena.eval_ordered(
                    &order,
                    shade,
                    &|n: &Node| match n {
                        Node::Sample { channel, resource, .. } => {
                            let k = looked.iter().position(|l| l.0 == *resource && l.1 == *channel)?;
                            let dv = moved.filter(|m| m.0 == k).map_or(0.0, |m| m.1);
                            Some(stored[k] + dv)
                        }
                        Node::Input(Input::D, _) => Some(d),
                        Node::Input(i, _) => Some(typical(*i)),
                        Node::Param(id) => Some(p.params[*id].value.as_f64()),
                        Node::Channel(..) => Some(0.5),
                        Node::Swizzle(..) => None,
                        Node::F32(_)
                        | Node::I32(_)
                        | Node::U32(_)
                        | Node::Bool(_)
                        | Node::Unary(..)
                        | Node::Binary(..)
                        | Node::Call(..) => None,
                    },
                    &mut scratch,
                );
                // the runtime stores the visibility clamped to [0, 1]
                if v.is_nan() { f64::NAN } else { v.clamp(0.0, 1.0) }
            };
            let v0 = visibility(None);
            if v0.is_nan() {
                skipped += 1;
                continue;
            }
            configurations += 1;
            let mut sum = 0.0;
            for (k, (_, _, slot, _)) in looked.iter().enumerate() {
                let mut worst_at = |q: Precision| {
                    let step = half_step(q, stored[k], (slot.range.lo, slot.range.hi));
                    let (up, down) = (visibility(Some((k, step))), visibility(Some((k, -step))));
                    [up, down]
                        .iter()
                        .map(|v| (v - v0).abs())
                        .filter(|e| !e.is_nan())
                        .fold(0.0, f64::max)
                };
                // the laid-out precision once, the others only for `Detail::Explain`
                let laid_out = channels[k].precision;
                let worst = worst_at(laid_out);
                for (i, q) in Precision::ALL.iter().enumerate() {
                    if let Some(e) = channels[k].at[i].as_mut() {
                        *e = e.max(if *q == laid_out { worst } else { worst_at(*q) });
                    }
                }
                channels[k].error = channels[k].error.max(worst);
                sum += worst;
            }
            total = total.max(sum);
        }
    }
    Some(Estimate {
        channels,
        total,
        configurations,
        skipped,
    })
}

/// How the texels of `r` combine two planes: through its writers back to the Map or
/// Depth pass that computed the channel (a maximum or minimum filter or mip level on the
/// way makes it a maximum or minimum; linear filters keep the mean).
fn mix_of(p: &Program, r: ResId) -> Mix {
    let mut r = r;
    for _ in 0..p.passes.len() {
        let pass = &p.passes[p.resources[r].writer];
        let mix = match &pass.kind {
            IrPassKind::Filter { kernel: IrKernel::Max(_) } | IrPassKind::Mipmap { reduce: Reduce::Max } => Some(Mix::Max),
            IrPassKind::Filter { kernel: IrKernel::Min(_) } | IrPassKind::Mipmap { reduce: Reduce::Min } => Some(Mix::Min),
            IrPassKind::Filter { .. } | IrPassKind::Mipmap { reduce: Reduce::Mean } | IrPassKind::SummedArea => None,
            IrPassKind::Depth { .. } | IrPassKind::Map | IrPassKind::Geometry { .. } | IrPassKind::Shade { .. } => {
                return Mix::Mean;
            }
        };
        if let Some(m) = mix {
            return m;
        }
        match pass.reads.first() {
            Some(&src) => r = src,
            None => return Mix::Mean,
        }
    }
    Mix::Mean
}

/// The value of channel `c` at a texel of depth `z`: the depth itself for a Depth
/// channel, else its expression with the channels it reads at `z`.
fn channel_value(p: &Program, c: ChannelId, z: f64, memo: &mut HashMap<(ChannelId, u64), f64>, depth: usize) -> f64 {
    let Some(h) = p.channels[c].value else {
        return z;
    };
    // each channel once per depth, however many channels read it
    if let Some(v) = memo.get(&(c, z.to_bits())) {
        return *v;
    }
    // the channels this value reads, computed first (a Map's value reads earlier
    // resources); a bound on the chain keeps a malformed one finite
    let mut known: HashMap<ChannelId, f64> = HashMap::new();
    for n in p.arena.postorder(&[h]) {
        if let Node::Channel(r, _) | Node::Sample { channel: r, .. } = p.arena.node(n)
            && !known.contains_key(r)
        {
            let v = if depth < 16 {
                channel_value(p, *r, z, memo, depth + 1)
            } else {
                f64::NAN
            };
            known.insert(*r, v);
        }
    }
    let v = p.arena.eval(h, &|n: &Node| match n {
        Node::Channel(r, _) | Node::Sample { channel: r, .. } => known.get(r).copied(),
        Node::Input(i, _) => Some(typical(*i)),
        Node::Param(id) => Some(p.params[*id].value.as_f64()),
        Node::Swizzle(..) => None,
        Node::F32(_) | Node::I32(_) | Node::U32(_) | Node::Bool(_) | Node::Unary(..) | Node::Binary(..) | Node::Call(..) => None,
    });
    memo.insert((c, z.to_bits()), v);
    v
}
