//! An expression evaluated with its running error bound: the Shade's leaves at a receiver
//! (inputs, params, the frame's functions, lookups with their allowance) and the bound node
//! by node in postorder (`Evaluation::allowed`).

use super::evaluation::{Evaluation, LeafAllowed, Prepared, Shift, change, raw_visibility};
use super::inputs::{At, input_value, uv_width};
use super::{Allowed, Model, Receiver, Scratch, Seen, call_error, input_error, noise};
use crate::builtins::{Func, Input, SampleFn, Ty};
use crate::front::expr::BinOp;
use crate::ir::{ExprId, Hooks, Node};

impl Evaluation<'_> {
    /// The leaf values of the Shade at receiver `r`: inputs, params, the frame's functions,
    /// lookups (with their allowance); inside `at_sample(k, ..)`, as light sample k sees it.
    pub(super) fn receiver_leaf<'a>(
        &'a self,
        r: &'a Receiver,
        shift: Shift,
    ) -> impl Fn(ExprId, usize, &[[f64; 4]]) -> Option<(f64, f64)> + 'a {
        let f = &self.frame;
        let n = f.shadow_size as f64;
        let centre = Seen {
            uv: r.uv,
            d_world: r.d_world,
            near: f.near,
            far: f.far,
            ndotl: r.ndotl,
            depth_slope: r.depth_slope,
            lod: r.lod,
            texel_world: f.texel_world[0],
            weights: [0.0; 2],
        };
        move |h: ExprId, k: usize, vals: &[[f64; 4]]| -> Option<(f64, f64)> {
            let arg = |h: &ExprId, c: usize| vals.get(h.index()).map_or(f64::NAN, |v| v[c]);
            let seen = |view: &Option<u8>| match view {
                Some(s) => r.samples.get(*s as usize).copied(),
                None => Some(centre),
            };
            match self.p.arena.node(h) {
                Node::Input(i, view) => {
                    let at = At {
                        seen: seen(view)?,
                        centre: view.is_none(),
                        pixel: r.pixel,
                    };
                    let v = input_value(f, *i, k, Some(&at))?;
                    Some((v, 0.0))
                }
                Node::Param(id) => Some((self.p.params[*id].value.as_f64(), 0.0)),
                Node::Call(Func::UvWidth, a) => Some((uv_width(f, arg(&a[0], 0), arg(&a[1], 0)), 0.0)),
                Node::Call(Func::Noise, a) => Some((noise(arg(&a[0], 0), arg(&a[1], 0), arg(&a[2], 0)), 0.0)),
                Node::Sample {
                    channel,
                    resource,
                    how,
                    args,
                    view,
                } => {
                    let t = self.texels.get(&(*resource, *channel))?.get(view.map_or(0, usize::from))?;
                    let s = seen(view)?;
                    let a = |i: usize| args.get(i).map_or(f64::NAN, |h| arg(h, 0));
                    let margin = match self.model {
                        Model::Gpu => n * 4.0 * input_error(Input::Uv, 0.0),
                        Model::F64 => 0.0,
                    };
                    let texel = |uv: [f64; 2]| t.table_texel([uv[0] * n, uv[1] * n], margin, self.model);
                    let by = if shift.view == *view { shift.by } else { [0.0; 3] };
                    let at = [s.uv[0] + by[0], s.uv[1] + by[1]];
                    Some(match how {
                        SampleFn::Sample => t.filtered(at, s.lod + by[2]),
                        SampleFn::SampleLod => t.filtered(at, a(0) + by[2]),
                        SampleFn::SampleWidth => t.filtered(at, (a(0) * n).max(1.0).log2() + by[2]),
                        SampleFn::SampleAt => t.filtered([at[0] + a(0), at[1] + a(1)], by[2]),
                        SampleFn::Nearest => texel(s.uv),
                        SampleFn::NearestAt => texel([s.uv[0] + a(0), s.uv[1] + a(1)]),
                        SampleFn::Fetch => t.nearest([s.uv[0] * n - 0.5 + a(0), s.uv[1] * n - 0.5 + a(1)], margin),
                        SampleFn::Box => t.boxed(s.uv, [a(0), a(1)], self.model),
                        SampleFn::BoxAt => t.boxed([s.uv[0] + a(0), s.uv[1] + a(1)], [a(2), a(3)], self.model),
                        SampleFn::SampleWidthAt => t.filtered([at[0] + a(0), at[1] + a(1)], (a(2) * n).max(1.0).log2() + by[2]),
                        SampleFn::NearestLevel => t.nearest_level(s.uv, a(0), margin),
                        SampleFn::NearestLevelAt => t.nearest_level([s.uv[0] + a(1), s.uv[1] + a(2)], a(0), margin),
                        SampleFn::MipBox => t.mip_box(s.uv, a(0), margin, self.model),
                        SampleFn::MipBoxAt => t.mip_box([s.uv[0] + a(0), s.uv[1] + a(1)], a(2), margin, self.model),
                    })
                }
                Node::Channel(..)
                | Node::F32(_)
                | Node::I32(_)
                | Node::U32(_)
                | Node::Bool(_)
                | Node::Unary(..)
                | Node::Binary(..)
                | Node::Call(..)
                | Node::Swizzle(..) => None,
            }
        }
    }

    /// Evaluate `e` with `leaf` (value and allowance of leaves), then bound its error
    /// node by node (a running error analysis, in postorder): a node's error is its own
    /// (the lookup's or input's allowance, f32 rounding, the built-in's bound) plus, for each
    /// operand, the largest change of the node when that operand alone moves by its error
    /// either way (a bool operand that may flip: flipped). A clamp, a `select` or a
    /// comparison therefore passes on exactly what its operands' errors can do to it. The
    /// Shade's interval is its raw value (NaN read as 1) widened by the root's error, then
    /// clamped.
    pub(super) fn allowed(&self, e: &Prepared, leaf: &LeafAllowed, scratch: &mut Scratch) -> Allowed {
        let arena = &self.p.arena;
        // the visibility (a debug output may be the same node, and is not clamped)
        let shade = std::ptr::eq(e, &self.shade);
        let plain = |h: ExprId, k: usize, vals: &[[f64; 4]]| leaf(h, k, vals).map(|(v, _)| v);
        let Scratch { vals, errors } = scratch;
        let hooks = Hooks { leaf: &plain, exact: true };
        arena.eval_span(&e.order, &hooks, vals);
        let width = |h: ExprId| match arena.ty(h) {
            Ty::Vec(n) => (n as usize).clamp(1, 4),
            Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => 1,
        };
        let mut operands: Vec<ExprId> = Vec::new();
        for &h in &e.order {
            let v = vals.get(h.index()).copied().unwrap_or([f64::NAN; 4]);
            let w = width(h);
            let model = self.model;
            let ulp = |k: usize| model.ulp(v[k]);
            let float = matches!(arena.ty(h), Ty::F32 | Ty::Vec(_));
            // the node's own error, per component
            let mut err = [0.0f64; 4];
            for (k, x) in err.iter_mut().enumerate().take(w) {
                *x = match arena.node(h) {
                    Node::Input(..) | Node::Sample { .. } | Node::Channel(..) | Node::Param(_) => {
                        let own = leaf(h, k, vals).map_or(0.0, |(_, a)| a);
                        match arena.node(h) {
                            Node::Input(i, _) if model == Model::Gpu => own + input_error(*i, v[k]),
                            Node::Input(..) => own,
                            Node::F32(_)
                            | Node::I32(_)
                            | Node::U32(_)
                            | Node::Bool(_)
                            | Node::Param(_)
                            | Node::Channel(..)
                            | Node::Sample { .. }
                            | Node::Unary(..)
                            | Node::Binary(..)
                            | Node::Call(..)
                            | Node::Swizzle(..) => own,
                        }
                    }
                    // f32's add, subtract and multiply are correctly rounded: exact operands
                    // with a result f32 holds give that result exactly
                    Node::Binary(BinOp::Add | BinOp::Sub | BinOp::Mul, x, y)
                        if float
                            && v[k] as f32 as f64 == v[k]
                            && [x, y]
                                .iter()
                                .all(|o| errors.get(o.index()).is_some_and(|e| e.iter().all(|e| *e == 0.0))) =>
                    {
                        0.0
                    }
                    Node::Binary(BinOp::Add | BinOp::Sub | BinOp::Mul, ..) if float => ulp(k),
                    Node::Binary(BinOp::Div, ..) if float => 3.0 * ulp(k),
                    Node::Call(f, a) if float => {
                        let arg = |i: usize| a.get(i).and_then(|x| vals.get(x.index())).map_or(0.0, |x| x[k]);
                        match (model, call_error(*f, v[k], &[arg(0), arg(1)])) {
                            (_, None) => 0.0,
                            (Model::Gpu, Some(e)) => e + ulp(k),
                            (Model::F64, Some(_)) => 4.0 * ulp(k),
                        }
                    }
                    Node::F32(_)
                    | Node::I32(_)
                    | Node::U32(_)
                    | Node::Bool(_)
                    | Node::Unary(..)
                    | Node::Binary(..)
                    | Node::Call(..)
                    | Node::Swizzle(..) => 0.0,
                };
            }
            // a value that is not a number stays one whatever moves it; a number whose
            // own error is not a number may be anything
            for k in 0..w {
                if err[k].is_nan() {
                    err[k] = if v[k].is_nan() { 0.0 } else { f64::INFINITY };
                }
            }
            // what each operand's error can do to it
            operands.clear();
            match arena.node(h) {
                Node::Unary(_, x) | Node::Swizzle(x, _) => operands.push(*x),
                Node::Binary(_, x, y) => operands.extend([*x, *y]),
                Node::Call(_, a) | Node::Sample { args: a, .. } => operands.extend(a.iter().copied()),
                Node::F32(_) | Node::I32(_) | Node::U32(_) | Node::Bool(_) | Node::Param(_) | Node::Input(..) | Node::Channel(..) => {}
            }
            operands.dedup();
            for &x in &operands {
                let ex = errors.get(x.index()).copied().unwrap_or([0.0; 4]);
                if ex.iter().all(|e| *e == 0.0) {
                    continue;
                }
                // an operand that may be anything makes this node anything
                if ex.iter().take(width(x)).any(|e| e.is_infinite()) {
                    for e in err.iter_mut().take(w) {
                        *e = f64::INFINITY;
                    }
                    continue;
                }
                let keep = vals[x.index()];
                // a bool flips; a number moves one component at a time, both ways (moving
                // every component together would hide what cancels between them)
                let moves: Vec<[f64; 4]> = if arena.ty(x) == Ty::Bool {
                    vec![keep.map(|b| if b != 0.0 { 0.0 } else { 1.0 })]
                } else {
                    let wx = width(x);
                    let mut m = Vec::with_capacity(2 * wx);
                    for k in (0..wx).filter(|&k| ex[k] != 0.0) {
                        for by in [ex[k], -ex[k]] {
                            let mut moved = keep;
                            if wx == 1 {
                                // a scalar is held in every component
                                moved = [keep[0] + by; 4];
                            } else {
                                moved[k] += by;
                            }
                            m.push(moved);
                        }
                    }
                    m
                };
                // per moved component: the largest change of each of this node's components,
                // summed over the operand's components (first order in each)
                let mut total = [0.0f64; 4];
                for pair in moves.chunks(if arena.ty(x) == Ty::Bool { 1 } else { 2 }) {
                    let mut worst = [0.0f64; 4];
                    for m in pair {
                        vals[x.index()] = *m;
                        let moved = arena.eval_node(h, &hooks, vals);
                        for k in 0..w {
                            worst[k] = worst[k].max(change(moved[k], v[k]));
                        }
                    }
                    for k in 0..w {
                        total[k] += worst[k];
                    }
                }
                vals[x.index()] = keep;
                for k in 0..w {
                    err[k] += total[k];
                }
            }
            // a `select` whose condition may flip takes either branch with its own error
            if let Node::Call(Func::Select | Func::Branch, a) = arena.node(h)
                && let [f, t, c] = a.as_slice()
                && errors.get(c.index()).is_some_and(|e| e[0] > 0.0)
            {
                let (ef, et) = (errors[f.index()], errors[t.index()]);
                for k in 0..w {
                    err[k] += ef[k].max(et[k]);
                }
            }
            if w == 1 {
                err = [err[0]; 4];
            }
            if let Some(slot) = errors.get_mut(h.index()) {
                *slot = err;
            }
        }
        let root = vals.get(e.root.index()).map_or(f64::NAN, |v| v[0]);
        let error = errors.get(e.root.index()).map_or(f64::INFINITY, |v| v[0]);
        let mut out = Allowed::new(if shade { raw_visibility(root) } else { root }, shade);
        out.widen(error, shade);
        out
    }
}
