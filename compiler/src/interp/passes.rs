//! Every pass after Depth and Geometry run in execution order: given outputs stored, Map
//! channels per texel, Filter kernels, Mipmap chains and SummedArea tables, each texel with
//! its allowance.

use super::evaluation::{Evaluation, Prepared};
use super::inputs::input_value;
use super::model::stored_at;
use super::table::table;
use super::texels::{Level, Texels};
use super::{Given, Model, Rounding, Scratch, stored};
use crate::front::ast::{Precision, Reduce};
use crate::ir::{ChannelId, ExprId, IrKernel, IrPassKind, Node, PassId, PlacedSlot, ResId};
use std::collections::HashMap;

impl Evaluation<'_> {
    fn slots(&self, r: ResId) -> Vec<PlacedSlot> {
        self.p.resources[r].slots.clone()
    }

    fn source(&self, pass: PassId) -> Result<ResId, String> {
        self.p.passes[pass]
            .reads
            .first()
            .copied()
            .ok_or_else(|| format!("pass `{}` reads nothing", self.p.passes[pass].name))
    }

    /// The maps given for channel `c` of `r`, checked: one per view, each `size` x `size`.
    fn given<'g>(&self, given: &'g Given, pass: PassId, r: ResId, c: ChannelId) -> Result<&'g [Vec<f64>], String> {
        let size = self.frame.shadow_size as usize;
        let views = if self.p.per_sample(r) { self.p.samples as usize } else { 1 };
        let what = || format!("channel `{}` of pass `{}`", self.p.channels[c].name, self.p.passes[pass].name);
        let maps = given.maps.get(&(r, c)).ok_or_else(|| format!("{} is not given", what()))?;
        if maps.len() != views {
            return Err(format!("{} is given {} view(s), not {views}", what(), maps.len()));
        }
        if let Some(m) = maps.iter().find(|m| size == 0 || m.len() != size * size) {
            return Err(format!("{} is given a map of {} values, not {size} x {size}", what(), m.len()));
        }
        Ok(maps)
    }

    pub(super) fn run_pass(&mut self, id: PassId, given: &Given, rounding: Rounding) -> Result<(), String> {
        let pass = &self.p.passes[id];
        let Some(out) = pass.writes else { return Ok(()) };
        let size = self.frame.shadow_size as usize;
        let keep = |slot: &PlacedSlot, v: f64| match rounding {
            Rounding::Exact => v,
            Rounding::Stored => stored(slot, v),
        };
        match &pass.kind {
            // given: a Depth output as the caller gives it (a synthetic field is stored as
            // the slot stores it), a Geometry output read back as the GPU stored it (exact,
            // but for a unorm code's conversion to f32 in the shader: `k * (1 / 255)` on
            // lavapipe, an ulp from `k / 255`)
            IrPassKind::Depth { .. } | IrPassKind::Geometry { .. } => {
                let read_back = pass.kind.kind().is_geometry();
                for slot in self.slots(out) {
                    let unorm = slot.precision.is_unorm();
                    let allow = |x: f64| match (read_back, unorm) {
                        (false, _) => self.model.storage(&slot, x),
                        (true, true) => self.model.ulp(x),
                        (true, false) => 0.0,
                    };
                    let views = self
                        .given(given, id, out, slot.channel)?
                        .iter()
                        .map(|map| {
                            let v: Vec<f64> = map.iter().map(|&x| if read_back { x } else { keep(&slot, x) }).collect();
                            let a = v.iter().map(|&x| allow(x)).collect();
                            Texels::new(vec![Level { size, v, a }], &slot)
                        })
                        .collect();
                    self.texels.insert((out, slot.channel), views);
                }
            }
            IrPassKind::Map => {
                for slot in self.slots(out) {
                    let (level, clamped) = self.map_channel(id, &slot, size, rounding)?;
                    if clamped > 0 {
                        self.clamped.push((slot.channel, clamped));
                    }
                    self.insert(out, &slot, vec![level]);
                }
            }
            IrPassKind::Filter { kernel } => {
                let src = self.source(id)?;
                for slot in self.slots(out) {
                    let base = self.read(src, slot.channel)?.base().clone();
                    let level = filter(&base, kernel, &slot, rounding, self.model);
                    self.insert(out, &slot, vec![level]);
                }
            }
            IrPassKind::Mipmap { reduce } => {
                let src = self.source(id)?;
                for slot in self.slots(out) {
                    let base = self.read(src, slot.channel)?.base().clone();
                    let levels = mip_chain(base, *reduce, &slot, rounding, self.model);
                    self.insert(out, &slot, levels);
                }
            }
            IrPassKind::SummedArea { .. } => {
                let src = self.source(id)?;
                for slot in self.slots(out) {
                    let base = self.read(src, slot.channel)?.base().clone();
                    let code = crate::back::summed_area::table_code(&self.p, out, slot.texture).map_err(|d| d.message.clone())?;
                    let (base, sat) = table(&base, &slot, code, rounding, self.model);
                    let texels = Texels {
                        sat: Some(sat),
                        ..Texels::new(vec![base], &slot)
                    };
                    self.texels.insert((out, slot.channel), vec![texels]);
                }
            }
            IrPassKind::Shade { .. } => {}
        }
        Ok(())
    }

    fn insert(&mut self, r: ResId, slot: &PlacedSlot, levels: Vec<Level>) {
        self.texels.insert((r, slot.channel), vec![Texels::new(levels, slot)]);
    }

    /// The centre's texels of a channel (Map, Filter, Mipmap and SummedArea passes read no
    /// per-sample resource).
    fn read(&self, r: ResId, c: ChannelId) -> Result<&Texels, String> {
        self.texels.get(&(r, c)).and_then(|v| v.first()).ok_or_else(|| {
            format!(
                "channel `{}` of `{}` is read before it is written",
                self.p.channels[c].name, self.p.resources[r].name
            )
        })
    }

    /// One Map channel at every texel: value and allowance (with its storage's rounding).
    /// A Map channel's texels, and how many were clamped to its declared range.
    fn map_channel(&self, pass: PassId, slot: &PlacedSlot, size: usize, rounding: Rounding) -> Result<(Level, usize), String> {
        let mut clamped = 0;
        let c = slot.channel;
        let h = self.p.channels[c]
            .value
            .ok_or_else(|| format!("channel `{}` has no value", self.p.channels[c].name))?;
        let prepared = Prepared::new(&self.p, h);
        // the resources this pass reads, by the channels they carry
        let mut from: HashMap<ChannelId, &Texels> = HashMap::new();
        for &r in &self.p.passes[pass].reads {
            for s in &self.p.resources[r].slots {
                if let Some(t) = self.texels.get(&(r, s.channel)).and_then(|v| v.first()) {
                    from.entry(s.channel).or_insert(t);
                }
            }
        }
        let mut scratch = Scratch::default();
        scratch.fit(self.p.arena.len());
        let (mut v, mut a) = (Vec::with_capacity(size * size), Vec::with_capacity(size * size));
        for y in 0..size as i64 {
            for x in 0..size as i64 {
                let leaf = |h: ExprId, k: usize, _: &[[f64; 4]]| -> Option<(f64, f64)> {
                    match self.p.arena.node(h) {
                        Node::Channel(ch, [dx, dy]) => from.get(ch).map(|t| t.texel(x + *dx as i64, y + *dy as i64)),
                        Node::Input(i, _) => input_value(&self.frame, *i, k, None).map(|v| (v, 0.0)),
                        Node::Param(id) => Some((self.p.params[*id].value.as_f64(), 0.0)),
                        Node::Sample { .. } => None,
                        Node::F32(_)
                        | Node::I32(_)
                        | Node::U32(_)
                        | Node::Bool(_)
                        | Node::Unary(..)
                        | Node::Binary(..)
                        | Node::Call(..)
                        | Node::Swizzle(..) => None,
                    }
                };
                let r = self.allowed(&prepared, &leaf, &mut scratch);
                // a declared range: clamped to it when stored (1-Lipschitz: the allowance holds)
                let value = match self.p.channels[c].range {
                    Some((lo, hi)) => {
                        let kept = r.value.clamp(lo, hi);
                        clamped += usize::from(kept != r.value);
                        kept
                    }
                    None => r.value,
                };
                v.push(match rounding {
                    Rounding::Exact => value,
                    Rounding::Stored => stored(slot, value),
                });
                a.push(r.allowance + self.model.storage(slot, value));
            }
        }
        Ok((Level { size, v, a }, clamped))
    }
}

/// A Filter pass over one level: separable kernels along x then y through an intermediate
/// at the scratch precision, the Laplacian in one step; allowances carried through.
fn filter(src: &Level, kernel: &IrKernel, slot: &PlacedSlot, rounding: Rounding, model: Model) -> Level {
    let n = src.size as i64;
    let scratch = crate::pack::scratch_precision(slot.precision);
    let keep = |v: f64, p: Precision| match rounding {
        Rounding::Exact => v,
        Rounding::Stored => stored_at(p, slot.encode.bias, slot.encode.scale, v),
    };
    let step_at = |v: f64, p: Precision| model.storage(&PlacedSlot { precision: p, ..*slot }, v);
    let out = |f: &dyn Fn(i64, i64) -> (f64, f64), p: Precision| -> Level {
        let mut l = Level {
            size: src.size,
            v: Vec::with_capacity(src.v.len()),
            a: Vec::with_capacity(src.v.len()),
        };
        for y in 0..n {
            for x in 0..n {
                let (v, a) = f(x, y);
                l.v.push(keep(v, p));
                l.a.push(a + step_at(v, p) + 4.0 * model.ulp(v));
            }
        }
        l
    };
    match kernel {
        IrKernel::LoG => out(
            &|x, y| {
                let (mut v, mut a) = (0.0, 0.0);
                for (k, w) in IrKernel::LOG_3X3.iter().enumerate() {
                    let (tv, ta) = src.at(x + k as i64 % 3 - 1, y + k as i64 / 3 - 1);
                    v += w * tv;
                    a += w.abs() * ta;
                }
                (v, a)
            },
            slot.precision,
        ),
        IrKernel::Box(_) | IrKernel::Gaussian(..) | IrKernel::Max(_) | IrKernel::Min(_) => {
            let r = (kernel.size() as i64 - 1) / 2;
            let weights = kernel.weights_1d();
            let axis = |l: &Level, dx: i64, dy: i64, p: Precision| {
                out(
                    &|x, y| match &weights {
                        Some(w) => {
                            let (mut v, mut a) = (0.0, 0.0);
                            for (k, wk) in w.iter().enumerate() {
                                let o = k as i64 - r;
                                let (tv, ta) = l.at(x + o * dx, y + o * dy);
                                v += wk * tv;
                                a += wk * ta;
                            }
                            (v, a)
                        }
                        None => {
                            let mut best: Option<(f64, f64)> = None;
                            for o in -r..=r {
                                let t = l.at(x + o * dx, y + o * dy);
                                let better = match (best, kernel) {
                                    (None, _) => true,
                                    (Some(b), IrKernel::Min(_)) => t.0 < b.0,
                                    (Some(b), IrKernel::Max(_) | IrKernel::Box(_) | IrKernel::Gaussian(..) | IrKernel::LoG) => t.0 > b.0,
                                };
                                if better {
                                    best = Some(t);
                                }
                            }
                            // the allowance of the window's largest, as any texel near the extreme may win
                            let amax = (-r..=r).map(|o| l.at(x + o * dx, y + o * dy).1).fold(0.0, f64::max);
                            best.map_or((f64::NAN, 0.0), |b| (b.0, amax))
                        }
                    },
                    p,
                )
            };
            let mid = axis(src, 1, 0, scratch);
            axis(&mid, 0, 1, slot.precision)
        }
    }
}

/// Levels down to 1 x 1, each texel reducing the 2 x 2 below it (clamped at an odd edge).
fn mip_chain(base: Level, reduce: Reduce, slot: &PlacedSlot, rounding: Rounding, model: Model) -> Vec<Level> {
    let mut levels = vec![base];
    while let Some(prev) = levels.last().filter(|l| l.size > 1) {
        let size = (prev.size / 2).max(1);
        let mut l = Level {
            size,
            v: Vec::with_capacity(size * size),
            a: Vec::with_capacity(size * size),
        };
        for y in 0..size as i64 {
            for x in 0..size as i64 {
                let t = [
                    prev.at(2 * x, 2 * y),
                    prev.at(2 * x + 1, 2 * y),
                    prev.at(2 * x, 2 * y + 1),
                    prev.at(2 * x + 1, 2 * y + 1),
                ];
                let amax = t.iter().map(|t| t.1).fold(0.0, f64::max);
                let (v, a) = match reduce {
                    Reduce::Mean => (t.iter().map(|t| t.0).sum::<f64>() * 0.25, t.iter().map(|t| t.1).sum::<f64>() * 0.25),
                    Reduce::Max => (t.iter().map(|t| t.0).fold(f64::NEG_INFINITY, f64::max), amax),
                    Reduce::Min => (t.iter().map(|t| t.0).fold(f64::INFINITY, f64::min), amax),
                };
                l.v.push(match rounding {
                    Rounding::Exact => v,
                    Rounding::Stored => stored(slot, v),
                });
                l.a.push(a + model.storage(slot, v) + 2.0 * model.ulp(v));
            }
        }
        levels.push(l);
    }
    levels
}
