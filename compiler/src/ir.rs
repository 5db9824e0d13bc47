//! The IR shared by the phases after `lower`: parameters resolved, series unrolled, one
//! concrete channel per basis term, passes in execution order, and every expression in
//! one hash-consed [`Arena`] (equal sub-expressions share a handle, constants fold as
//! nodes are added).

use crate::builtins::{Fold, Func, Input, SampleFn, Sig, Ty};
use crate::consteval;
use crate::front::ast::{ConstValue, LightModel, LightView, Neighbour, Precision, Primitive, Reduce, Resolve, ScalarTy};
use crate::front::expr::{BinOp, UnOp, fmt_float};
use crate::handle::{Handle, Kind, Table};
pub use crate::interval::{Interval, short};
use crate::span::Span;
use std::collections::HashMap;
use std::fmt::{self, Write as _};

pub mod validate;

/// Handle of an expression node in the expression [`Arena`].
pub type ExprId = Handle<Node>;
/// Handle of a channel in [`Ir::channels`].
pub type ChannelId = Handle<IrChannel>;
/// Handle of a resource in [`Ir::resources`].
pub type ResId = Handle<IrResource>;
/// Handle of a pass in [`Ir::passes`].
pub type PassId = Handle<IrPass>;
/// Handle of a param in [`Ir::params`].
pub type ParamId = Handle<IrParam>;
/// Handle of an expansion in [`Ir::expansions`].
pub type ExpansionId = Handle<IrExpansion>;

impl Kind for Node {
    const KIND: &'static str = "node";
}
impl Kind for IrChannel {
    const KIND: &'static str = "channel";
}
impl<S> Kind for Resource<S> {
    const KIND: &'static str = "resource";
}
impl Kind for IrParam {
    const KIND: &'static str = "param";
}
impl Kind for IrExpansion {
    const KIND: &'static str = "expansion";
}
impl Kind for IrPass {
    const KIND: &'static str = "pass";
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Node {
    /// An f32 constant, by its bits.
    F32(u32),
    I32(i32),
    U32(u32),
    Bool(bool),
    /// A runtime uniform parameter.
    Param(ParamId),
    /// A built-in input; receiver-side inputs inside `at_sample(k, ..)` carry the sample
    /// view k (`Some(k)`): the receiver seen from light sample k.
    Input(Input, Option<u8>),
    /// Map side: the value of a channel at the texel being computed, or at the texel that
    /// many texels away (`neighbour(ch, dx, dy)`), clamped to the map's edge.
    Channel(ChannelId, [i32; 2]),
    /// Receiver side: a lookup of `channel` in `resource`.
    Sample {
        channel: ChannelId,
        resource: ResId,
        how: SampleFn,
        args: Vec<ExprId>,
        /// The light sample's view inside `at_sample(k, ..)` (the channel's resource holds
        /// one layer block per sample); `None` for the centre.
        view: Option<u8>,
    },
    Unary(UnOp, ExprId),
    Binary(BinOp, ExprId, ExprId),
    Call(Func, Vec<ExprId>),
    /// Vector components, e.g. `.x` = [0], `.xy` = [0, 1].
    Swizzle(ExprId, Vec<u8>),
}

#[derive(Clone, Debug, Default)]
pub struct Arena {
    nodes: Vec<(Node, Ty, Span)>,
    index: HashMap<(Node, Ty), ExprId>,
}

impl Arena {
    pub fn node(&self, h: ExprId) -> &Node {
        &self.nodes[h.index()].0
    }

    pub fn ty(&self, h: ExprId) -> Ty {
        self.nodes[h.index()].1
    }

    pub fn span(&self, h: ExprId) -> Span {
        self.nodes[h.index()].2
    }

    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    pub fn f32(&mut self, v: f64) -> ExprId {
        self.add(Node::F32((v as f32).to_bits()), Ty::F32, Span::UNDEFINED)
    }

    pub fn i32(&mut self, v: i32) -> ExprId {
        self.add(Node::I32(v), Ty::I32, Span::UNDEFINED)
    }

    pub fn as_const(&self, h: ExprId) -> Option<ConstValue> {
        match self.node(h) {
            Node::F32(b) => Some(ConstValue::Float(f32::from_bits(*b) as f64)),
            Node::I32(v) => Some(ConstValue::Int(*v as i64)),
            Node::U32(v) => Some(ConstValue::Uint(*v)),
            Node::Bool(v) => Some(ConstValue::Bool(*v)),
            Node::Param(_)
            | Node::Input(..)
            | Node::Channel(..)
            | Node::Sample { .. }
            | Node::Unary(..)
            | Node::Binary(..)
            | Node::Call(..)
            | Node::Swizzle(..) => None,
        }
    }

    fn constant(&mut self, v: ConstValue, ty: Ty, span: Span) -> Option<ExprId> {
        let node = match (v, ty) {
            (ConstValue::Float(f), Ty::F32) => {
                let f = f as f32;
                if !f.is_finite() {
                    return None;
                }
                Node::F32(f.to_bits())
            }
            (ConstValue::Int(i), Ty::I32) => Node::I32(i32::try_from(i).ok()?),
            (ConstValue::Uint(u), Ty::U32) => Node::U32(u),
            (ConstValue::Bool(b), Ty::Bool) => Node::Bool(b),
            _ => return None,
        };
        Some(self.intern(node, ty, span))
    }

    fn intern(&mut self, node: Node, ty: Ty, span: Span) -> ExprId {
        if let Some(h) = self.index.get(&(node.clone(), ty)) {
            return *h;
        }
        let h = ExprId::new(self.nodes.len());
        self.nodes.push((node.clone(), ty, span));
        self.index.insert((node, ty), h);
        h
    }

    /// Add a node, folding it when its operands are constants.
    pub fn add(&mut self, node: Node, ty: Ty, span: Span) -> ExprId {
        if let Some(h) = self.fold(&node, ty, span) {
            return h;
        }
        self.intern(node, ty, span)
    }

    /// The components of a vector constructor (`vec2`..`vec4` of scalars), by handle.
    fn components(&self, h: ExprId) -> Option<Vec<ExprId>> {
        if let Node::Call(Func::Vec2 | Func::Vec3 | Func::Vec4, args) = self.node(h)
            && args.iter().all(|a| self.ty(*a) == Ty::F32)
        {
            return Some(args.clone());
        }
        None
    }

    /// Whether `h` is the scalar `v` or a vector constructor of `v`s.
    fn is_splat_of(&self, h: ExprId, v: f64) -> bool {
        let is = |h: ExprId| self.as_const(h).is_some_and(|c| c.as_f64() == v);
        is(h) || self.components(h).is_some_and(|c| c.iter().all(|&x| is(x)))
    }

    /// Vector folds that only ever remove work (a fold that split one vector operation
    /// into several scalar ones would add operations: docs/language.md section 8.9):
    /// identities with a constant operand of zeros or ones, operations whose operands
    /// are all constant components, and a single-component swizzle of a constructor.
    fn fold_vector(&mut self, node: &Node, ty: Ty, span: Span) -> Option<ExprId> {
        match node {
            Node::Binary(op, a, b) if matches!(ty, Ty::Vec(_)) => {
                let (a, b) = (*a, *b);
                // identities: the kept operand already has the result's type
                let keep = |h: ExprId| (self.ty(h) == ty).then_some(h);
                match op {
                    BinOp::Add if self.is_splat_of(a, 0.0) => return keep(b),
                    BinOp::Add | BinOp::Sub if self.is_splat_of(b, 0.0) => {
                        if let Some(h) = keep(a) {
                            return Some(h);
                        }
                    }
                    BinOp::Mul if self.is_splat_of(a, 1.0) => return keep(b),
                    BinOp::Mul | BinOp::Div if self.is_splat_of(b, 1.0) => {
                        if let Some(h) = keep(a) {
                            return Some(h);
                        }
                    }
                    BinOp::Add
                    | BinOp::Sub
                    | BinOp::Mul
                    | BinOp::Div
                    | BinOp::Rem
                    | BinOp::Lt
                    | BinOp::Le
                    | BinOp::Gt
                    | BinOp::Ge
                    | BinOp::Eq
                    | BinOp::Ne
                    | BinOp::And
                    | BinOp::Or
                    | BinOp::BitAnd
                    | BinOp::BitOr
                    | BinOp::BitXor
                    | BinOp::Shl
                    | BinOp::Shr => {}
                }
                if !matches!(op, BinOp::Add | BinOp::Sub | BinOp::Mul | BinOp::Div) {
                    return None;
                }
                // all components constant on both sides (a scalar constant broadcasts)
                let n = match ty {
                    Ty::Vec(n) => n as usize,
                    Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => return None,
                };
                let side = |h: ExprId| -> Option<Vec<ConstValue>> {
                    match self.components(h) {
                        Some(c) if c.len() == n => c.iter().map(|&x| self.as_const(x)).collect(),
                        Some(_) => None,
                        None => self.as_const(h).map(|c| vec![c; n]),
                    }
                };
                let (x, y) = (side(a)?, side(b)?);
                let mut comps = Vec::with_capacity(n);
                for (x, y) in x.into_iter().zip(y) {
                    let v = consteval::binary(*op, x, y)?;
                    comps.push(self.constant(v, Ty::F32, span)?);
                }
                let f = match n {
                    2 => Func::Vec2,
                    3 => Func::Vec3,
                    _ => Func::Vec4,
                };
                Some(self.intern(Node::Call(f, comps), ty, span))
            }
            Node::Swizzle(a, comps) if comps.len() == 1 => self.components(*a).and_then(|c| c.get(comps[0] as usize).copied()),
            Node::Binary(..)
            | Node::Swizzle(..)
            | Node::F32(_)
            | Node::I32(_)
            | Node::U32(_)
            | Node::Bool(_)
            | Node::Param(_)
            | Node::Input(..)
            | Node::Channel(..)
            | Node::Sample { .. }
            | Node::Unary(..)
            | Node::Call(..) => None,
        }
    }

    fn fold(&mut self, node: &Node, ty: Ty, span: Span) -> Option<ExprId> {
        use ConstValue::*;
        if let Some(h) = self.fold_vector(node, ty, span) {
            return Some(h);
        }
        match node {
            Node::Unary(op, a) => {
                let v = consteval::unary(*op, self.as_const(*a)?)?;
                self.constant(v, ty, span)
            }
            Node::Binary(op, a, b) => {
                let (x, y) = (self.as_const(*a), self.as_const(*b));
                // Identities that hold for every finite value.
                if matches!(ty, Ty::F32 | Ty::I32 | Ty::U32) {
                    let is = |c: Option<ConstValue>, v: f64| c.is_some_and(|c| c.as_f64() == v);
                    match op {
                        BinOp::Add if is(x, 0.0) => return Some(*b),
                        BinOp::Add | BinOp::Sub if is(y, 0.0) => return Some(*a),
                        BinOp::Mul if is(x, 1.0) => return Some(*b),
                        BinOp::Mul | BinOp::Div if is(y, 1.0) => return Some(*a),
                        BinOp::Add
                        | BinOp::Sub
                        | BinOp::Mul
                        | BinOp::Div
                        | BinOp::Rem
                        | BinOp::Lt
                        | BinOp::Le
                        | BinOp::Gt
                        | BinOp::Ge
                        | BinOp::Eq
                        | BinOp::Ne
                        | BinOp::And
                        | BinOp::Or
                        | BinOp::BitAnd
                        | BinOp::BitOr
                        | BinOp::BitXor
                        | BinOp::Shl
                        | BinOp::Shr => {}
                    }
                }
                // (c1 * x) / c2 -> (c1 / c2) * x
                if let (BinOp::Div, Some(Float(c2)), Node::Binary(BinOp::Mul, m1, m2)) = (op, y, self.node(*a).clone())
                    && c2 != 0.0
                    && let Some(Float(c1)) = self.as_const(m1)
                {
                    let k = self.f32(c1 / c2);
                    return Some(self.add(Node::Binary(BinOp::Mul, k, m2), ty, span));
                }
                // Logic with one constant side.
                match (op, x, y) {
                    (BinOp::And, Some(Bool(true)), _) | (BinOp::Or, Some(Bool(false)), _) => return Some(*b),
                    (BinOp::And, _, Some(Bool(true))) | (BinOp::Or, _, Some(Bool(false))) => return Some(*a),
                    (BinOp::And, Some(Bool(false)), _) | (BinOp::And, _, Some(Bool(false))) => return self.constant(Bool(false), ty, span),
                    (BinOp::Or, Some(Bool(true)), _) | (BinOp::Or, _, Some(Bool(true))) => return self.constant(Bool(true), ty, span),
                    _ => {}
                }
                let v = consteval::binary(*op, x?, y?)?;
                self.constant(v, ty, span)
            }
            Node::Call(Func::Select | Func::Branch, args) => match self.as_const(args[2])? {
                Bool(true) => Some(args[1]),
                Bool(false) => Some(args[0]),
                Int(_) | Uint(_) | Float(_) => None,
            },
            Node::Call(f, args) => {
                if !matches!(ty, Ty::F32 | Ty::I32 | Ty::U32) {
                    return None;
                }
                let vals: Vec<ConstValue> = args.iter().map(|a| self.as_const(*a)).collect::<Option<_>>()?;
                let v = eval_call(*f, &vals)?;
                self.constant(v, ty, span)
            }
            Node::F32(_)
            | Node::I32(_)
            | Node::U32(_)
            | Node::Bool(_)
            | Node::Param(_)
            | Node::Input(..)
            | Node::Channel(..)
            | Node::Sample { .. }
            | Node::Swizzle(..) => None,
        }
    }

    /// Handles reachable from `root`, operands before users (the order codegen emits them).
    pub fn postorder(&self, roots: &[ExprId]) -> Vec<ExprId> {
        let mut seen = vec![false; self.nodes.len()];
        let mut out = Vec::new();
        for &r in roots {
            self.visit(r, &mut seen, &mut out);
        }
        out
    }

    /// [`Arena::postorder`] without the nodes `stop` holds and what only they reach: the
    /// part of the graph not yet done. Codegen asks for it at every emitted value, so it
    /// must not walk what it emitted before (a series of 4,096 terms in both arms of an
    /// `if` walked its shared chain once per term: 4 s to check, issue 48, item 4).
    pub fn postorder_until(&self, roots: &[ExprId], stop: impl Fn(ExprId) -> bool) -> Vec<ExprId> {
        let mut seen = vec![false; self.nodes.len()];
        let mut out = Vec::new();
        for &r in roots {
            self.visit_until(r, &mut seen, &mut out, &stop);
        }
        out
    }

    fn visit(&self, h: ExprId, seen: &mut [bool], out: &mut Vec<ExprId>) {
        self.visit_until(h, seen, out, &|_| false)
    }

    fn visit_until(&self, h: ExprId, seen: &mut [bool], out: &mut Vec<ExprId>, stop: &dyn Fn(ExprId) -> bool) {
        // Iterative to keep deep series off the call stack.
        let mut stack = vec![(h, false)];
        while let Some((h, done)) = stack.pop() {
            if seen[h.index()] || (!done && stop(h)) {
                continue;
            }
            if done {
                seen[h.index()] = true;
                out.push(h);
                continue;
            }
            stack.push((h, true));
            for c in self.operands(h).into_iter().rev() {
                if !seen[c.index()] {
                    stack.push((c, false));
                }
            }
        }
    }

    pub fn operands(&self, h: ExprId) -> Vec<ExprId> {
        match self.node(h) {
            Node::Unary(_, a) | Node::Swizzle(a, _) => vec![*a],
            Node::Binary(_, a, b) => vec![*a, *b],
            Node::Call(_, args) | Node::Sample { args, .. } => args.clone(),
            Node::F32(_) | Node::I32(_) | Node::U32(_) | Node::Bool(_) | Node::Param(_) | Node::Input(..) | Node::Channel(..) => {
                vec![]
            }
        }
    }

    /// Write `h` as an expression (for dumps and explain).
    pub fn display(&self, h: ExprId, ir: Option<&Ir>) -> String {
        let mut s = String::new();
        self.write(&mut s, h, ir, 0);
        s
    }

    fn write(&self, s: &mut String, h: ExprId, ir: Option<&Ir>, depth: usize) {
        if depth > 24 {
            let _ = write!(s, "%{}", h.index());
            return;
        }
        let chan = |c: ChannelId| ir.map(|ir| ir.channels[c].name.clone()).unwrap_or_else(|| format!("ch{c}"));
        match self.node(h) {
            Node::F32(b) => s.push_str(&fmt_float(f32::from_bits(*b) as f64)),
            Node::I32(v) => {
                let _ = write!(s, "{v}");
            }
            Node::U32(v) => {
                let _ = write!(s, "{v}u");
            }
            Node::Bool(v) => {
                let _ = write!(s, "{v}");
            }
            Node::Param(p) => match ir {
                Some(ir) => {
                    let _ = write!(s, "params.{}", ir.params[*p].name);
                }
                None => {
                    let _ = write!(s, "param{}", p.index());
                }
            },
            Node::Input(i, view) => {
                s.push_str(i.name());
                if let Some(k) = view {
                    let _ = write!(s, "@{k}");
                }
            }
            Node::Channel(c, [0, 0]) => s.push_str(&chan(*c)),
            Node::Channel(c, [dx, dy]) => {
                let _ = write!(s, "neighbour({}, {dx}, {dy})", chan(*c));
            }
            Node::Sample {
                channel, how, args, view, ..
            } => {
                let _ = write!(s, "{}({}", how.name(false), chan(*channel));
                for a in args {
                    s.push_str(", ");
                    self.write(s, *a, ir, depth + 1);
                }
                s.push(')');
                // inside `at_sample(k, ..)`: the lookup reads sample k's view
                if let Some(k) = view {
                    let _ = write!(s, "@{k}");
                }
            }
            Node::Unary(op, a) => {
                s.push_str(op.symbol());
                s.push('(');
                self.write(s, *a, ir, depth + 1);
                s.push(')');
            }
            Node::Binary(op, a, b) => {
                s.push('(');
                self.write(s, *a, ir, depth + 1);
                let _ = write!(s, " {} ", op.symbol());
                self.write(s, *b, ir, depth + 1);
                s.push(')');
            }
            Node::Call(Func::Branch, args) if args.len() == 3 => {
                s.push_str("if ");
                self.write(s, args[2], ir, depth + 1);
                s.push_str(" { ");
                self.write(s, args[1], ir, depth + 1);
                s.push_str(" } else { ");
                self.write(s, args[0], ir, depth + 1);
                s.push_str(" }");
            }
            Node::Call(f, args) => {
                let _ = write!(s, "{}(", f.name());
                for (i, a) in args.iter().enumerate() {
                    if i > 0 {
                        s.push_str(", ");
                    }
                    self.write(s, *a, ir, depth + 1);
                }
                s.push(')');
            }
            Node::Swizzle(a, c) => {
                self.write(s, *a, ir, depth + 1);
                s.push('.');
                for i in c {
                    s.push(['x', 'y', 'z', 'w'][*i as usize]);
                }
            }
        }
    }
}

impl Arena {
    /// Evaluate an expression on the CPU (f64): its first component (a scalar's value).
    /// `leaf` gives the value of params, inputs, channels and samples, a scalar that a
    /// vector input takes in each component.
    pub fn eval(&self, h: ExprId, leaf: &dyn Fn(&Node) -> Option<f64>) -> f64 {
        let order = self.postorder(&[h]);
        let mut vals = vec![[f64::NAN; 4]; self.nodes.len()];
        self.eval_ordered(&order, h, leaf, &mut vals)
    }

    /// [`Arena::eval`] for callers that evaluate one expression many times: `order` is
    /// `postorder(&[h])`, `vals` a scratch of one value per node of the arena. Vectors are
    /// evaluated component by component (a scalar is held in every component, so mixing
    /// it with a vector broadcasts it); `length` and `dot` reduce over the operand's width.
    pub fn eval_ordered(&self, order: &[ExprId], h: ExprId, leaf: &dyn Fn(&Node) -> Option<f64>, vals: &mut [[f64; 4]]) -> f64 {
        let hooks = Hooks {
            leaf: &|n: ExprId, _: usize, _: &[[f64; 4]]| leaf(self.node(n)),
            exact: false,
        };
        self.eval_span(order, &hooks, vals);
        vals.get(h.index()).map_or(f64::NAN, |v| v[0])
    }

    /// Evaluate the nodes of `order` (a suffix of a postorder is allowed: the nodes before
    /// it keep their values in `vals`) into `vals`, with [`Hooks`]: `leaf` gives params,
    /// inputs, channels, samples and the calls the arena cannot fold alone (`uv_width`,
    /// `noise`) per component, reading the values of their arguments from `vals`.
    pub fn eval_span(&self, order: &[ExprId], hooks: &Hooks, vals: &mut [[f64; 4]]) {
        for &n in order {
            let v = self.eval_node(n, hooks, vals);
            if let Some(slot) = vals.get_mut(n.index()) {
                *slot = v;
            }
        }
    }

    /// One node's value from its operands' in `vals`.
    pub fn eval_node(&self, n: ExprId, hooks: &Hooks, vals: &[[f64; 4]]) -> [f64; 4] {
        use ConstValue::*;
        let leaf = hooks.leaf;
        let width = |x: ExprId| match self.ty(x) {
            Ty::Vec(n) => (n as usize).clamp(1, 4),
            Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => 1,
        };
        {
            let get = |x: &ExprId, i: usize| vals.get(x.index()).map_or(f64::NAN, |v| v[i]);
            let w = width(n);
            let mut v = [f64::NAN; 4];
            for (i, slot) in v.iter_mut().enumerate().take(w) {
                *slot = match self.node(n) {
                    Node::F32(b) => f32::from_bits(*b) as f64,
                    Node::I32(x) => *x as f64,
                    Node::U32(x) => *x as f64,
                    Node::Bool(b) => *b as i32 as f64,
                    Node::Unary(UnOp::Neg, x) => -get(x, i),
                    Node::Unary(UnOp::Not, x) => (get(x, i) == 0.0) as i32 as f64,
                    Node::Unary(UnOp::BitNot, x) => {
                        if self.ty(n) == Ty::U32 {
                            !(get(x, i) as u32) as f64
                        } else {
                            !(get(x, i) as i32) as f64
                        }
                    }
                    // integer operations of u32 (and bit operations of i32) with their wrapping
                    Node::Binary(op, x, y) if self.ty(n) == Ty::U32 || op.is_bitwise() => {
                        let (x, y) = (get(x, i), get(y, i));
                        let r = consteval::binary(*op, int_const(x, self.ty(n)), int_const(y, self.ty(n)));
                        r.map_or(f64::NAN, ConstValue::as_f64)
                    }
                    Node::Binary(op, x, y) => {
                        let (x, y) = (get(x, i), get(y, i));
                        let int = self.ty(n) == Ty::I32;
                        match op {
                            BinOp::Add => x + y,
                            BinOp::Sub => x - y,
                            BinOp::Mul => x * y,
                            BinOp::Div => {
                                if int {
                                    (x / y).trunc()
                                } else {
                                    x / y
                                }
                            }
                            BinOp::Rem => x % y,
                            BinOp::Lt => (x < y) as i32 as f64,
                            BinOp::Le => (x <= y) as i32 as f64,
                            BinOp::Gt => (x > y) as i32 as f64,
                            BinOp::Ge => (x >= y) as i32 as f64,
                            BinOp::Eq => (x == y) as i32 as f64,
                            BinOp::Ne => (x != y) as i32 as f64,
                            BinOp::And => (x != 0.0 && y != 0.0) as i32 as f64,
                            BinOp::Or => (x != 0.0 || y != 0.0) as i32 as f64,
                            // the guard above takes these
                            BinOp::BitAnd | BinOp::BitOr | BinOp::BitXor | BinOp::Shl | BinOp::Shr => f64::NAN,
                        }
                    }
                    Node::Call(f, a) => {
                        let componentwise = || {
                            let args: Vec<ConstValue> = a
                                .iter()
                                .map(|x| match self.ty(*x) {
                                    t @ (Ty::I32 | Ty::U32) => int_const(get(x, i), t),
                                    Ty::F32 | Ty::Bool | Ty::Vec(_) | Ty::AbstractInt => Float(get(x, i)),
                                })
                                .collect();
                            let folded = if hooks.exact {
                                crate::builtins::fold_call_exact(*f, &args)
                            } else {
                                eval_call(*f, &args)
                            };
                            folded.map_or(f64::NAN, ConstValue::as_f64)
                        };
                        match (f.desc().fold, f.desc().sig) {
                            // the frame's functions and the GPU's hash: the hook's
                            (Fold::Hook, _) => leaf(n, i, vals).unwrap_or(f64::NAN),
                            (_, Sig::Select) => {
                                if get(&a[2], i) != 0.0 {
                                    get(&a[1], i)
                                } else {
                                    get(&a[0], i)
                                }
                            }
                            // constructors: the arguments' components in order
                            (_, Sig::Construct(_)) => {
                                let mut parts = a.iter().flat_map(|x| (0..width(*x)).map(move |k| (x, k)));
                                match (a.len(), parts.nth(i)) {
                                    // one scalar fills every component
                                    (1, _) if width(a[0]) == 1 => get(&a[0], 0),
                                    (_, Some((x, k))) => get(x, k),
                                    (_, None) => f64::NAN,
                                }
                            }
                            (_, Sig::Length) => (0..width(a[0])).map(|k| get(&a[0], k).powi(2)).sum::<f64>().sqrt(),
                            (_, Sig::Dot) => (0..width(a[0])).map(|k| get(&a[0], k) * get(&a[1], k)).sum(),
                            (
                                Fold::Never | Fold::Float(_) | Fold::IntOrFloat(..) | Fold::Custom(_),
                                Sig::Float | Sig::Numeric | Sig::SameNumeric | Sig::Convert(_) | Sig::Scalars | Sig::Guarded,
                            ) => componentwise(),
                        }
                    }
                    Node::Swizzle(x, c) => c.get(i).map_or(f64::NAN, |&k| get(x, k as usize)),
                    Node::Param(_) | Node::Input(..) | Node::Channel(..) | Node::Sample { .. } => leaf(n, i, vals).unwrap_or(f64::NAN),
                };
            }
            // a scalar is held in every component
            if w == 1 {
                v = [v[0]; 4];
            }
            v
        }
    }
}

/// A leaf's value in component `i` given the values computed so far (by node).
pub type Leaf<'a> = dyn Fn(ExprId, usize, &[[f64; 4]]) -> Option<f64> + 'a;

/// How [`Arena::eval_span`] evaluates.
pub struct Hooks<'a> {
    /// The value of a leaf (param, input, channel, sample) or of a call the arena cannot
    /// evaluate alone, in component `i`, given the values computed so far.
    pub leaf: &'a Leaf<'a>,
    /// Fold built-in calls in f64 without rounding to f32 (`builtins::fold_call_exact`).
    pub exact: bool,
}

/// The constant of integer type `ty` holding `x` (a shift count is u32 whatever `ty`).
fn int_const(x: f64, ty: Ty) -> ConstValue {
    if ty == Ty::U32 {
        ConstValue::Uint(x as u32)
    } else {
        ConstValue::Int(x as i64)
    }
}

/// Evaluate a pure function on constants with f32 results rounded as the GPU would store
/// them (the function's [`crate::builtins::Fold`] rule).
pub fn eval_call(f: Func, v: &[ConstValue]) -> Option<ConstValue> {
    crate::builtins::fold_call(f, v)
}

#[derive(Clone, Debug)]
pub struct IrParam {
    pub name: String,
    pub name_span: Span,
    pub ty: ScalarTy,
    pub value: ConstValue,
    pub range: Option<(f64, f64)>,
    /// A runtime uniform (true) or substituted at compile time (false).
    pub uniform: bool,
    pub doc: Option<String>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Origin {
    /// Written by a Depth pass.
    Depth,
    /// Declared in `channels` with a value.
    Declared,
    /// Basis term `term` of expansion `expansion` at index `k`.
    Basis { expansion: ExpansionId, term: usize, k: i64 },
}

#[derive(Clone, Debug)]
pub struct IrChannel {
    pub name: String,
    pub precision: Precision,
    /// Where the precision was chosen (for diagnostics).
    pub precision_span: Span,
    /// The precision came from `--precision` rather than the file.
    pub precision_overridden: bool,
    /// The precision is left to the compiler (`Auto`): `lower` chooses it, last (`choose_precisions`).
    pub precision_auto: bool,
    pub value: Option<ExprId>,
    /// The declared range (`range: (lo, hi)`): values are clamped to it when stored.
    pub range: Option<(f64, f64)>,
    pub origin: Origin,
    pub span: Span,
}

#[derive(Clone, Debug)]
pub struct IrExpansion {
    pub name: String,
    pub constant: ExprId,
    /// Unrolled terms: receiver-side coefficient and the basis channel it multiplies.
    pub terms: Vec<(ExprId, ChannelId)>,
    pub span: Span,
}

/// How a channel value is stored: `stored = (value - bias) * scale`, decoded as `stored / scale + bias`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Encode {
    pub bias: f64,
    pub scale: f64,
}

impl Encode {
    pub const IDENTITY: Encode = Encode { bias: 0.0, scale: 1.0 };

    pub fn is_identity(&self) -> bool {
        *self == Encode::IDENTITY
    }
}

/// What `analyse` found about one channel as stored in one resource.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlotInfo {
    pub range: Interval,
    pub encode: Encode,
}

/// The product of `analyse`, a side table beside the IR (which `analyse` only reads):
/// range and storage encoding of every (resource, channel) slot as lowered, before
/// elimination drops any.
#[derive(Clone, Debug, Default)]
pub struct Analysis {
    pub slots: HashMap<(ResId, ChannelId), SlotInfo>,
}

impl Analysis {
    pub fn get(&self, r: ResId, c: ChannelId) -> Option<SlotInfo> {
        self.slots.get(&(r, c)).copied()
    }
}

/// One channel as stored in one resource, as `lower` knows it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slot {
    pub channel: ChannelId,
    pub precision: Precision,
}

/// One channel as laid out by `pack`: its range and storage encoding (from the
/// [`Analysis`]) and its place, component `component` of layer `layer` of texture
/// `texture` of the resource.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedSlot {
    pub channel: ChannelId,
    pub precision: Precision,
    pub range: Interval,
    pub encode: Encode,
    pub texture: usize,
    pub layer: u32,
    pub component: u32,
}

impl PlacedSlot {
    /// Texture index, layer and component.
    pub fn place(&self) -> (usize, u32, u32) {
        (self.texture, self.layer, self.component)
    }
}

/// A slot as lowered or as laid out: what the IR's printer and validator read of both.
pub trait SlotView {
    fn channel(&self) -> ChannelId;
    fn precision(&self) -> Precision;
    /// The slot as laid out, after `pack`.
    fn placed(&self) -> Option<&PlacedSlot>;
}

impl SlotView for Slot {
    fn channel(&self) -> ChannelId {
        self.channel
    }
    fn precision(&self) -> Precision {
        self.precision
    }
    fn placed(&self) -> Option<&PlacedSlot> {
        None
    }
}

impl SlotView for PlacedSlot {
    fn channel(&self) -> ChannelId {
        self.channel
    }
    fn precision(&self) -> Precision {
        self.precision
    }
    fn placed(&self) -> Option<&PlacedSlot> {
        Some(self)
    }
}

/// One texture of a packed resource: all its channels of one precision.
#[derive(Clone, Debug)]
pub struct Texture {
    pub name: String,
    pub precision: Precision,
    /// Components per texel (1, 2 or 4).
    pub components: u32,
    pub layers: u32,
}

/// A resource whose slots are `S`: [`IrResource`] as lowered, [`PlacedResource`] as laid
/// out by `pack`.
#[derive(Clone, Debug)]
pub struct Resource<S> {
    pub name: String,
    pub slots: Vec<S>,
    pub writer: PassId,
    pub mips: bool,
    pub sat: bool,
    pub span: Span,
    /// False once dead-code elimination found no shaded pixel can reach it.
    pub live: bool,
    /// Set by `pack`.
    pub textures: Vec<Texture>,
}

/// A resource as `lower` left it.
pub type IrResource = Resource<Slot>;
/// A resource as `pack` laid it out (in [`Layout::resources`], indexed by [`ResId`]).
pub type PlacedResource = Resource<PlacedSlot>;

impl<S: SlotView> Resource<S> {
    pub fn slot_of(&self, c: ChannelId) -> Option<&S> {
        self.slots.iter().find(|s| s.channel() == c)
    }
}

/// A filter kernel with its size resolved.
#[derive(Clone, Debug, PartialEq)]
pub enum IrKernel {
    Box(u32),
    Gaussian(u32, f64),
    Max(u32),
    Min(u32),
    LoG,
}

impl IrKernel {
    pub fn size(&self) -> u32 {
        match self {
            IrKernel::Box(n) | IrKernel::Gaussian(n, _) | IrKernel::Max(n) | IrKernel::Min(n) => *n,
            IrKernel::LoG => 3,
        }
    }

    pub fn separable(&self) -> bool {
        !matches!(self, IrKernel::LoG)
    }

    /// 1-D weights of a separable linear kernel (Box, Gaussian), normalised to sum 1.
    pub fn weights_1d(&self) -> Option<Vec<f64>> {
        let w: Vec<f64> = match self {
            IrKernel::Box(n) => vec![1.0; *n as usize],
            IrKernel::Gaussian(n, sigma) => {
                let r = (*n as i64 - 1) / 2;
                (-r..=r).map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp()).collect()
            }
            IrKernel::Max(_) | IrKernel::Min(_) | IrKernel::LoG => return None,
        };
        let s: f64 = w.iter().sum();
        Some(w.into_iter().map(|x| x / s).collect())
    }

    /// The 3x3 Laplacian-of-Gaussian weights (row major), summing to zero.
    pub const LOG_3X3: [f64; 9] = [0.0, -1.0, 0.0, -1.0, 4.0, -1.0, 0.0, -1.0, 0.0];
}

#[derive(Clone, Debug)]
pub enum IrPassKind {
    Depth {
        view: LightView,
    },
    Map,
    Filter {
        kernel: IrKernel,
    },
    Mipmap {
        reduce: Reduce,
    },
    /// A summed-area table of the source; `sum` is what a float texture's table sums
    /// (`None`: not written, `F32`), with the span it was written at.
    SummedArea {
        sum: Option<(crate::front::ast::TableSum, Span)>,
    },
    Geometry {
        primitive: Primitive,
        resolve: Resolve,
        view: LightView,
        /// Fragments for which this bool is false are discarded.
        keep: Option<ExprId>,
        /// `Skins`: the neighbouring sample whose discontinuities are warped in.
        from: Option<Neighbour>,
    },
    Shade {
        visibility: ExprId,
    },
}

impl IrPassKind {
    /// A SummedArea pass's `sum:` as written, with its span (`None` where it is absent, and
    /// for every other kind).
    pub fn table_sum(&self) -> Option<(crate::front::ast::TableSum, Span)> {
        match self {
            IrPassKind::SummedArea { sum } => *sum,
            IrPassKind::Depth { .. }
            | IrPassKind::Map
            | IrPassKind::Filter { .. }
            | IrPassKind::Mipmap { .. }
            | IrPassKind::Geometry { .. }
            | IrPassKind::Shade { .. } => None,
        }
    }

    /// Whether the pass's output carries its source's slots (a filtered copy, a mip chain
    /// or a summed-area table of them) rather than channels the pass makes: the channel's
    /// facts (its precision, its quantisation) are its source's.
    pub fn copies_source(&self) -> bool {
        match self {
            IrPassKind::Filter { .. } | IrPassKind::Mipmap { .. } | IrPassKind::SummedArea { .. } => true,
            IrPassKind::Depth { .. } | IrPassKind::Map | IrPassKind::Geometry { .. } | IrPassKind::Shade { .. } => false,
        }
    }

    /// Whether a range its output cannot hold is this pass's to report: every pass that
    /// makes its channels, and a Laplacian-of-Gaussian filter, whose output (a difference
    /// of neighbours) has a range of its own; the other copies repeat their source's.
    pub fn reports_own_range(&self) -> bool {
        match self {
            IrPassKind::Filter { kernel } => match kernel {
                IrKernel::LoG => true,
                IrKernel::Box(_) | IrKernel::Gaussian(..) | IrKernel::Max(_) | IrKernel::Min(_) => false,
            },
            IrPassKind::Mipmap { .. } | IrPassKind::SummedArea { .. } => false,
            IrPassKind::Depth { .. } | IrPassKind::Map | IrPassKind::Geometry { .. } | IrPassKind::Shade { .. } => true,
        }
    }
}

#[derive(Clone, Debug)]
pub struct IrPass {
    pub name: String,
    pub kind: IrPassKind,
    pub reads: Vec<ResId>,
    /// Where each of `reads` is named, in the same order.
    pub read_spans: Vec<Span>,
    pub writes: Option<ResId>,
    pub span: Span,
    /// False once dead-code elimination removed it.
    pub live: bool,
    /// The schedule the technique or `--schedule` asks for (Map, Filter, Mipmap and Shade
    /// passes; `Fragment` for the others); the `schedule` phase decides the one it runs in.
    pub schedule: crate::front::ast::Schedule,
}

impl IrPass {
    pub fn kind_name(&self) -> &'static str {
        match self.kind {
            IrPassKind::Depth { .. } => "Depth",
            IrPassKind::Map => "Map",
            IrPassKind::Filter { .. } => "Filter",
            IrPassKind::Mipmap { .. } => "Mipmap",
            IrPassKind::SummedArea { .. } => "SummedArea",
            IrPassKind::Geometry { .. } => "Geometry",
            IrPassKind::Shade { .. } => "Shade",
        }
    }
}

#[derive(Clone, Debug)]
pub struct Ir {
    pub technique: String,
    pub title: Option<String>,
    pub paper: Option<String>,
    pub lights: Vec<LightModel>,
    pub params: Table<IrParam>,
    pub channels: Table<IrChannel>,
    pub expansions: Table<IrExpansion>,
    pub resources: Table<IrResource>,
    /// In execution order.
    pub passes: Table<IrPass>,
    pub arena: Arena,
    /// Light samples the per-sample passes render one view each of (1 without any).
    pub samples: u32,
    /// The technique's `shadow_map:` (a tuned file's map size), carried to the graph.
    pub shadow_map: Option<u32>,
    /// The scene it was specialised for (`--scene`), and what that folded.
    pub specialised: Option<Specialised>,
    /// The precisions left to the compiler (`Auto`) and why each was chosen, one line
    /// each (`lower`'s `choose_precisions`; shown by `explain`).
    pub precision_choices: Vec<String>,
    /// The Shade's debug outputs, where the build asks for them (`CompileOptions::debug`;
    /// else empty): roots of the Shade besides its visibility.
    pub debug: Vec<IrDebug>,
    /// The debug outputs the technique declares and this build leaves out (it did not ask
    /// for them): their names, for `explain`.
    pub debug_omitted: Vec<String>,
}

/// A debug output of the Shade: an f32 or vector expression of the Shade's, written
/// unclamped to the camera-sized texture `texture` (`debug_<name>`).
#[derive(Clone, Debug)]
pub struct IrDebug {
    pub name: String,
    pub texture: String,
    pub expr: ExprId,
    pub span: Span,
}

/// A compilation specialised for a scene's facts.
#[derive(Clone, Debug)]
pub struct Specialised {
    pub facts: sshc_graph::SceneFacts,
    /// What the facts folded, one line each (shown by `explain`).
    pub folded: Vec<String>,
}

impl Ir {
    /// The Shade's roots: its visibility, then its debug outputs (where the build has them).
    pub fn shade_roots(&self, visibility: ExprId) -> Vec<ExprId> {
        std::iter::once(visibility).chain(self.debug.iter().map(|d| d.expr)).collect()
    }

    /// Whether resource `r` holds one layer block per light sample (a per-sample pass
    /// writes it).
    pub fn per_sample(&self, r: ResId) -> bool {
        self.passes.iter().any(|p| {
            p.writes == Some(r)
                && matches!(
                    p.kind,
                    IrPassKind::Depth {
                        view: LightView::PerSample
                    } | IrPassKind::Geometry {
                        view: LightView::PerSample,
                        ..
                    }
                )
        })
    }
}

/// The product of `pack`, beside the IR (which `pack` only reads): the resources with
/// their live slots placed in textures (ranges and encodings from the [`Analysis`]), the
/// passes with their live flags, and what elimination removed.
#[derive(Clone, Debug, Default)]
pub struct Layout {
    /// One per resource of the IR, indexed by its [`ResId`].
    pub resources: Table<PlacedResource, IrResource>,
    pub passes: Table<IrPass>,
    /// What optimisation removed, and why (reported by `explain` and the cost report).
    pub removed: Vec<String>,
}

/// What codegen, emit and explain read: the IR of `lower` seen through the [`Layout`] of
/// `pack`. The fields `resources`, `passes` and `removed` are the layout's; everything
/// else (params, channels, expansions, the arena...) derefs to the IR. `S` is
/// [`PlacedSlot`] but for the IR as lowered ([`Program::lowered`], slots [`Slot`]).
pub struct Program<'a, S = PlacedSlot> {
    pub ir: &'a Ir,
    pub resources: &'a Table<Resource<S>, IrResource>,
    pub passes: &'a Table<IrPass>,
    pub removed: &'a [String],
}

impl<S> Clone for Program<'_, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S> Copy for Program<'_, S> {}

impl<S> Program<'_, S> {
    /// The visibility expression of the live Shade pass.
    pub fn shade(&self) -> Option<ExprId> {
        self.passes.iter().filter(|pass| pass.live).find_map(|pass| match pass.kind {
            IrPassKind::Shade { visibility } => Some(visibility),
            IrPassKind::Depth { .. }
            | IrPassKind::Map
            | IrPassKind::Filter { .. }
            | IrPassKind::Mipmap { .. }
            | IrPassKind::SummedArea { .. }
            | IrPassKind::Geometry { .. } => None,
        })
    }
}

impl<'a> Program<'a> {
    pub fn new(ir: &'a Ir, layout: &'a Layout) -> Program<'a> {
        Program {
            ir,
            resources: &layout.resources,
            passes: &layout.passes,
            removed: &layout.removed,
        }
    }
}

impl<'a> Program<'a, Slot> {
    /// The IR as `lower` left it (nothing laid out yet, nothing removed).
    pub fn lowered(ir: &'a Ir) -> Program<'a, Slot> {
        Program {
            ir,
            resources: &ir.resources,
            passes: &ir.passes,
            removed: &[],
        }
    }
}

impl<'a, S> Program<'a, S> {
    pub fn shade_pass(&self) -> Option<&'a IrPass> {
        self.passes.iter().find(|p| matches!(p.kind, IrPassKind::Shade { .. }))
    }
}

impl<S> std::ops::Deref for Program<'_, S> {
    type Target = Ir;
    fn deref(&self) -> &Ir {
        self.ir
    }
}

impl<S: SlotView> fmt::Display for Program<'_, S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write_dump(f, None)
    }
}

impl Ir {
    pub fn shade_pass(&self) -> Option<&IrPass> {
        self.passes.iter().find(|p| matches!(p.kind, IrPassKind::Shade { .. }))
    }

    pub fn uniform_params(&self) -> impl Iterator<Item = (ParamId, &IrParam)> {
        self.params.with_handles().filter(|(_, p)| p.uniform)
    }
}

/// The IR printed with the side table of `analyse` (`--dump-ir-after analyse`).
pub struct WithAnalysis<'a>(pub &'a Ir, pub &'a Analysis);

impl fmt::Display for WithAnalysis<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        Program::lowered(self.0).write_dump(f, Some(self.1))
    }
}

impl fmt::Display for Ir {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        Program::lowered(self).write_dump(f, None)
    }
}

impl<S: SlotView> Program<'_, S> {
    /// The text form of `--dump-ir-after`: slots show the ranges and encodings of
    /// `analysis` when given, else those of the layout (after `pack`).
    fn write_dump(&self, f: &mut fmt::Formatter<'_>, analysis: Option<&Analysis>) -> fmt::Result {
        writeln!(f, "technique {}", self.technique)?;
        for p in &self.params {
            let kind = if p.uniform { "uniform" } else { "const" };
            write!(f, "  param {} : {} = {} ({kind}", p.name, p.ty.name(), p.value)?;
            if let Some((lo, hi)) = p.range {
                write!(f, ", range [{}, {}]", short(lo), short(hi))?;
            }
            writeln!(f, ")")?;
        }
        for (i, c) in self.channels.iter().enumerate() {
            write!(f, "  channel #{i} {} : {}", c.name, c.precision.name())?;
            if let Some(v) = c.value {
                write!(f, " = {}", self.arena.display(v, Some(self.ir)))?;
            }
            writeln!(f)?;
        }
        for e in &self.expansions {
            writeln!(f, "  expansion {} = {}", e.name, self.arena.display(e.constant, Some(self.ir)))?;
            for (coeff, ch) in &e.terms {
                writeln!(
                    f,
                    "      + {} * {}",
                    self.arena.display(*coeff, Some(self.ir)),
                    self.channels[*ch].name
                )?;
            }
        }
        for (rh, r) in self.resources.with_handles() {
            let writer = self.passes.get(r.writer).map(|p| p.name.as_str()).unwrap_or("?");
            write!(f, "  resource {} (written by pass `{writer}`", r.name)?;
            if r.mips {
                write!(f, "; mip chain")?;
            }
            if r.sat {
                write!(f, "; summed-area table")?;
            }
            if !r.live {
                write!(f, "; removed")?;
            }
            writeln!(f, ")")?;
            for s in &r.slots {
                write!(f, "      {} : {}", self.channels[s.channel()].name, s.precision().name())?;
                let info = match (analysis.and_then(|a| a.get(rh, s.channel())), s.placed()) {
                    (Some(info), _) => Some(info),
                    (None, Some(p)) => Some(SlotInfo {
                        range: p.range,
                        encode: p.encode,
                    }),
                    (None, None) => None,
                };
                if let Some(SlotInfo { range, encode }) = info {
                    write!(f, " range {range}")?;
                    if !encode.is_identity() {
                        write!(f, " stored as (v - ({})) * {}", short(encode.bias), short(encode.scale))?;
                    }
                }
                if let Some(p) = s.placed() {
                    write!(
                        f,
                        " at {}[{}].{}",
                        r.textures[p.texture].name,
                        p.layer,
                        ['r', 'g', 'b', 'a'][p.component as usize]
                    )?;
                }
                writeln!(f)?;
            }
            for t in &r.textures {
                writeln!(
                    f,
                    "      texture {} : {} x{} components x{} layers",
                    t.name,
                    t.precision.name(),
                    t.components,
                    t.layers
                )?;
            }
        }
        for p in self.passes.iter() {
            let reads: Vec<&str> = p.reads.iter().map(|r| self.resources[*r].name.as_str()).collect();
            write!(f, "  pass {} : {} reads [{}]", p.name, p.kind_name(), reads.join(", "))?;
            if let Some(w) = p.writes {
                write!(f, " writes {}", self.resources[w].name)?;
            }
            match &p.kind {
                IrPassKind::Filter { kernel } => write!(f, " kernel {kernel:?}")?,
                IrPassKind::Mipmap { reduce } => write!(f, " reduce {reduce:?}")?,
                IrPassKind::Shade { visibility } => {
                    write!(f, "\n      visibility = {}", self.arena.display(*visibility, Some(self.ir)))?;
                    for d in &self.ir.debug {
                        write!(f, "\n      debug {} = {}", d.name, self.arena.display(d.expr, Some(self.ir)))?;
                    }
                }
                IrPassKind::Geometry { keep: Some(k), .. } => write!(f, "\n      keep = {}", self.arena.display(*k, Some(self.ir)))?,
                IrPassKind::Depth { .. } | IrPassKind::Map | IrPassKind::SummedArea { .. } | IrPassKind::Geometry { .. } => {}
            }
            writeln!(f)?;
        }
        for r in self.removed.iter() {
            writeln!(f, "  removed: {r}")?;
        }
        Ok(())
    }
}
