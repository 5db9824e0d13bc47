//! The public entry points: `Evaluation::new` runs the passes, then the visibility and the
//! debug outputs at a receiver with the interval allowed about them (the filtering
//! hardware's positions included), with the per-thread `Scratch`.

use super::model::FILTER_SHIFT;
use super::texels::Texels;
use super::{Allowed, Frame, Given, Model, Receiver, Rounding};
use crate::builtins::{SampleFn, Ty};
use crate::ir::{ChannelId, ExprId, Hooks, Node, Program, ResId};
use std::collections::HashMap;

/// A leaf's value and allowance in component `i`, given the values computed so far.
pub(super) type LeafAllowed<'a> = dyn Fn(ExprId, usize, &[[f64; 4]]) -> Option<(f64, f64)> + 'a;

/// An expression prepared for repeated evaluation: its root and its nodes in postorder.
pub(super) struct Prepared {
    pub(super) root: ExprId,
    pub(super) order: Vec<ExprId>,
}

impl Prepared {
    pub(super) fn new(p: &Program, root: ExprId) -> Prepared {
        Prepared {
            root,
            order: p.arena.postorder(&[root]),
        }
    }
}

/// A technique's passes after Depth evaluated on one depth map.
pub struct Evaluation<'p> {
    pub(super) p: Program<'p>,
    pub(super) frame: Frame,
    /// Every stored channel, one entry per view (the centre's alone, or one per sample).
    pub(super) texels: HashMap<(ResId, ChannelId), Vec<Texels>>,
    pub(super) shade: Prepared,
    /// The views of the Shade's filtered lookups (`None`: the centre's): each is shifted by
    /// the filtering hardware's positions on its own.
    pub(super) filtered: Vec<Option<u8>>,
    pub(super) model: Model,
    /// Per Map channel with a declared range: the texels whose value it clamped.
    pub(super) clamped: Vec<(ChannelId, usize)>,
    /// The Shade's debug outputs (where the build has them), each with the views of its
    /// filtered lookups.
    pub(super) debug: Vec<(Prepared, Vec<Option<u8>>)>,
}

impl<'p> Evaluation<'p> {
    /// The channels whose declared range clamped some stored value: their names and how
    /// many texels (what `sshc verify` reports).
    pub fn clamped(&self) -> Vec<(String, usize)> {
        self.clamped.iter().map(|(c, n)| (self.p.channels[*c].name.clone(), *n)).collect()
    }

    /// Run every pass of `compiled` after Depth and Geometry, whose outputs are `given`
    /// (`size` x `size` texels per view, row 0 first).
    pub fn new(
        compiled: &'p crate::Compiled,
        given: &Given,
        frame: Frame,
        rounding: Rounding,
        model: Model,
    ) -> Result<Evaluation<'p>, String> {
        let p = compiled.program();
        let shade = Prepared::new(&p, p.shade().ok_or("the technique has no live Shade pass")?);
        let filtered = filtered_views(&p, &shade.order);
        let debug = p
            .debug
            .iter()
            .map(|d| {
                let e = Prepared::new(&p, d.expr);
                let views = filtered_views(&p, &e.order);
                (e, views)
            })
            .collect();
        let mut ev = Evaluation {
            p,
            frame,
            texels: HashMap::new(),
            shade,
            filtered,
            model,
            clamped: Vec::new(),
            debug,
        };
        for (id, pass) in p.passes.with_handles() {
            if !pass.live {
                continue;
            }
            ev.run_pass(id, given, rounding)?;
        }
        Ok(ev)
    }

    /// The clamped visibility at one receiver and the interval allowed about it.
    pub fn visibility(&self, r: &Receiver, scratch: &mut Scratch) -> Allowed {
        scratch.fit(self.p.arena.len());
        let mut out = self.allowed(&self.shade, &self.receiver_leaf(r, Shift::NONE), scratch);
        if self.model == Model::F64 {
            return out;
        }
        // the filtering hardware's 8-bit positions and level fractions, one axis at a time,
        // the lookups of each view together (each view reads its own positions)
        let texel = FILTER_SHIFT / self.frame.shadow_size as f64;
        let mut extra = 0.0;
        for &view in &self.filtered {
            for axis in 0..3 {
                let mut worst: f64 = 0.0;
                for sign in [1.0, -1.0] {
                    let mut by = [0.0; 3];
                    by[axis] = sign * if axis == 2 { FILTER_SHIFT } else { texel };
                    worst = worst.max(change(self.raw(r, Shift { view, by }, scratch), out.raw));
                }
                extra += worst;
            }
        }
        out.widen(extra, true);
        out
    }

    /// The raw visibility (NaN read as 1) at `r` with filtered lookups shifted by `shift`.
    fn raw(&self, r: &Receiver, shift: Shift, scratch: &mut Scratch) -> f64 {
        raw_visibility(self.shifted(&self.shade, r, shift, scratch)[0])
    }

    /// The value of `e` at `r` with filtered lookups shifted by `shift`.
    fn shifted(&self, e: &Prepared, r: &Receiver, shift: Shift, scratch: &mut Scratch) -> [f64; 4] {
        let leaf = self.receiver_leaf(r, shift);
        let plain = |h: ExprId, k: usize, vals: &[[f64; 4]]| leaf(h, k, vals).map(|(v, _)| v);
        self.p
            .arena
            .eval_span(&e.order, &Hooks { leaf: &plain, exact: true }, &mut scratch.vals);
        scratch.vals.get(e.root.index()).copied().unwrap_or([f64::NAN; 4])
    }

    /// Debug outputs this evaluation has (the build's, `CompileOptions::debug`): their names.
    pub fn debug_names(&self) -> Vec<&str> {
        self.p.debug.iter().map(|d| d.name.as_str()).collect()
    }

    /// Debug output `i` at one receiver: each component's value (unclamped, NaN kept) and
    /// the interval allowed about it, by the visibility's error model (a running bound
    /// node by node, widened by the filtering hardware's positions).
    pub fn debug(&self, i: usize, r: &Receiver, scratch: &mut Scratch) -> Vec<Allowed> {
        let Some((e, views)) = self.debug.get(i) else { return Vec::new() };
        scratch.fit(self.p.arena.len());
        self.allowed(e, &self.receiver_leaf(r, Shift::NONE), scratch);
        let width = match self.p.arena.ty(e.root) {
            Ty::Vec(n) => usize::from(n).clamp(1, 4),
            Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => 1,
        };
        let v = scratch.vals.get(e.root.index()).copied().unwrap_or([f64::NAN; 4]);
        let err = scratch.errors.get(e.root.index()).copied().unwrap_or([f64::INFINITY; 4]);
        let mut out: Vec<Allowed> = (0..width)
            .map(|k| {
                let mut a = Allowed::new(v[k], false);
                a.widen(err[k], false);
                a
            })
            .collect();
        if self.model == Model::F64 {
            return out;
        }
        let texel = FILTER_SHIFT / self.frame.shadow_size as f64;
        for &view in views {
            for axis in 0..3 {
                let mut worst = [0.0f64; 4];
                for sign in [1.0, -1.0] {
                    let mut by = [0.0; 3];
                    by[axis] = sign * if axis == 2 { FILTER_SHIFT } else { texel };
                    let moved = self.shifted(e, r, Shift { view, by }, scratch);
                    for k in 0..width {
                        worst[k] = worst[k].max(change(moved[k], v[k]));
                    }
                }
                for (a, w) in out.iter_mut().zip(worst) {
                    a.widen(w, false);
                }
            }
        }
        out
    }

    /// The clamped visibility at one receiver, without its allowance.
    pub fn value(&self, r: &Receiver, scratch: &mut Scratch) -> f64 {
        scratch.fit(self.p.arena.len());
        self.raw(r, Shift::NONE, scratch).clamp(0.0, 1.0)
    }
}

/// The views (`None`: the centre's) of the filtered lookups among `order`'s nodes: each is
/// shifted by the filtering hardware's positions on its own.
fn filtered_views(p: &Program, order: &[ExprId]) -> Vec<Option<u8>> {
    let mut filtered: Vec<Option<u8>> = Vec::new();
    for &h in order {
        if let Node::Sample { how, view, .. } = p.arena.node(h)
            && matches!(
                how,
                SampleFn::Sample | SampleFn::SampleLod | SampleFn::SampleWidth | SampleFn::SampleAt | SampleFn::SampleWidthAt
            )
            && !filtered.contains(view)
        {
            filtered.push(*view);
        }
    }
    filtered
}

/// The filtering hardware's error as one shift of the filtered lookups of one view: uv by
/// `by[..2]`, the level of detail by `by[2]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Shift {
    pub(super) view: Option<u8>,
    pub(super) by: [f64; 3],
}

impl Shift {
    const NONE: Shift = Shift { view: None, by: [0.0; 3] };
}

/// How far a value moved: 0 between two NaNs, infinite from a number to a NaN.
pub(super) fn change(moved: f64, v: f64) -> f64 {
    if moved == v || (moved.is_nan() && v.is_nan()) {
        0.0
    } else {
        let c = (moved - v).abs();
        if c.is_nan() { f64::INFINITY } else { c }
    }
}

/// The Shade's raw visibility as the runtime reads it before clamping: NaN as 1.
pub(super) fn raw_visibility(v: f64) -> f64 {
    if v.is_nan() { 1.0 } else { v }
}

/// Scratch space of [`Evaluation::visibility`], one per thread: values and errors by node.
#[derive(Default)]
pub struct Scratch {
    pub(super) vals: Vec<[f64; 4]>,
    pub(super) errors: Vec<[f64; 4]>,
}

impl Scratch {
    pub(super) fn fit(&mut self, nodes: usize) {
        self.vals.resize(nodes, [f64::NAN; 4]);
        self.errors.resize(nodes, [0.0; 4]);
    }
}
