//! The arena's evaluation on the CPU, in f64: one expression ([`Arena::eval`]) or a span
//! of a postorder node by node with [`Hooks`] for the leaves (tests, `rounding`, `interp`).

use super::{Arena, ExprId, Node, eval_call};
use crate::builtins::{Fold, Sig, Ty};
use crate::consteval;
use crate::front::ast::ConstValue;
use crate::front::expr::{BinOp, UnOp};

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
