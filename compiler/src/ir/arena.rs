//! The expression arena: the IR's expression nodes ([`Node`]) and the one hash-consed
//! [`Arena`] that holds them, folding constants and identities as nodes are added, and
//! walking them operands first.

use super::{ChannelId, ExprId, ParamId, ResId};
use crate::builtins::{Func, Input, SampleFn, Ty};
use crate::consteval;
use crate::front::ast::ConstValue;
use crate::front::expr::{BinOp, UnOp};
use crate::span::Span;
use std::collections::HashMap;

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
    /// Vector components, e.g. `.x` is `[0]`, `.xy` is `[0, 1]`.
    Swizzle(ExprId, Vec<u8>),
}

#[derive(Clone, Debug, Default)]
pub struct Arena {
    pub(super) nodes: Vec<(Node, Ty, Span)>,
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

    /// The identities that hold for every finite value, with a constant operand of zeros
    /// or ones (a scalar, or a vector constructor of them): `0 + x`, `x + 0`, `x - 0`,
    /// `1 * x`, `x * 1`, `x / 1` are `x`, where `x` already has the result's type (a
    /// scalar broadcast into a vector operation does not).
    fn identity(&self, op: BinOp, a: ExprId, b: ExprId, ty: Ty) -> Option<ExprId> {
        let keep = |h: ExprId| (self.ty(h) == ty).then_some(h);
        let (zero, one) = (|h| self.is_splat_of(h, 0.0), |h| self.is_splat_of(h, 1.0));
        match op {
            BinOp::Add if zero(a) => keep(b),
            BinOp::Add | BinOp::Sub if zero(b) => keep(a),
            BinOp::Mul if one(a) => keep(b),
            BinOp::Mul | BinOp::Div if one(b) => keep(a),
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
            | BinOp::Shr => None,
        }
    }

    /// Vector folds that only ever remove work (a fold that split one vector operation
    /// into several scalar ones would add operations: docs/language.md section 8.9):
    /// identities with a constant operand of zeros or ones, operations whose operands
    /// are all constant components, and a single-component swizzle of a constructor.
    fn fold_vector(&mut self, node: &Node, ty: Ty, span: Span) -> Option<ExprId> {
        match node {
            Node::Binary(op, a, b) if matches!(ty, Ty::Vec(_)) => {
                let (a, b) = (*a, *b);
                if let Some(h) = self.identity(*op, a, b, ty) {
                    return Some(h);
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
                if matches!(ty, Ty::F32 | Ty::I32 | Ty::U32)
                    && let Some(h) = self.identity(*op, *a, *b, ty)
                {
                    return Some(h);
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
}

/// Evaluate a pure function on constants with f32 results rounded as the GPU would store
/// them (the function's [`crate::builtins::Fold`] rule).
pub fn eval_call(f: Func, v: &[ConstValue]) -> Option<ConstValue> {
    crate::builtins::fold_call(f, v)
}
