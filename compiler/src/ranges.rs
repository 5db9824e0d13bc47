//! Range analysis of the IR: the interval of every expression under given channel and
//! input ranges ([`RangeEval`]), of every slot of every resource in pass order
//! ([`slot_ranges`]), and what a precision holds ([`fits`]). `lower` chooses the `Auto`
//! precisions on these ranges; `analyse` fits every precision to them and derives the
//! encodings; `tables` and `rounding` read them too.

use crate::builtins::Ty;
use crate::front::ast::{ConstValue, LightView, Precision, Reduce};
use crate::front::expr::{BinOp, UnOp};
use crate::ir::*;
use std::collections::HashMap;

pub const F16_MAX: f64 = 65504.0;
pub const F32_MAX: f64 = f32::MAX as f64;
/// The smallest positive normal f16.
pub const F16_MIN_NORMAL: f64 = 6.103515625e-5;

/// Range of every expression node under given channel ranges.
pub struct RangeEval<'a> {
    ir: &'a Ir,
    /// Map side: the range of each channel as stored in the resources the pass reads.
    channels: HashMap<ChannelId, Interval>,
    /// One runtime param evaluated over another range than its declared one.
    pub param_range: Option<(ParamId, Interval)>,
    /// Inputs taken over another range than their descriptor's (`texel_size` at one map
    /// size, for `tables`).
    pub inputs: HashMap<crate::builtins::Input, Interval>,
    memo: HashMap<ExprId, Interval>,
}

impl<'a> RangeEval<'a> {
    pub fn new(ir: &'a Ir, channels: HashMap<ChannelId, Interval>) -> Self {
        RangeEval {
            ir,
            channels,
            param_range: None,
            inputs: HashMap::new(),
            memo: HashMap::new(),
        }
    }

    pub fn eval(&mut self, root: ExprId) -> Interval {
        for h in self.ir.arena.postorder(&[root]) {
            if !self.memo.contains_key(&h) {
                let r = self.node(h);
                self.memo.insert(h, r);
            }
        }
        self.memo[&root]
    }

    fn get(&self, h: ExprId) -> Interval {
        self.memo.get(&h).copied().unwrap_or(Interval::UNBOUNDED)
    }

    fn node(&self, h: ExprId) -> Interval {
        let r = self.node_exact(h);
        // u32 arithmetic wraps: a range that leaves [0, 2^32 - 1] may hold any u32
        if self.ir.arena.ty(h) == Ty::U32 && !(r.lo >= 0.0 && r.hi <= u32::MAX as f64) {
            Interval::U32
        } else {
            r
        }
    }

    /// The range of `h`'s value computed without wrapping.
    fn node_exact(&self, h: ExprId) -> Interval {
        let a = &self.ir.arena;
        let integers = || if a.ty(h) == Ty::U32 { Interval::U32 } else { Interval::I32 };
        match a.node(h) {
            Node::F32(b) => Interval::point(f32::from_bits(*b) as f64),
            Node::I32(v) => Interval::point(*v as f64),
            Node::U32(v) => Interval::point(*v as f64),
            Node::Bool(v) => Interval::point(*v as i32 as f64),
            Node::Param(p) if self.param_range.is_some_and(|(o, _)| o == *p) => {
                self.param_range.map(|(_, r)| r).unwrap_or(Interval::UNBOUNDED)
            }
            Node::Param(p) => {
                let p = &self.ir.params[*p];
                match (p.range, p.value) {
                    (Some((lo, hi)), _) => Interval { lo, hi },
                    (None, ConstValue::Bool(_)) => Interval::UNIT,
                    (None, _) => Interval::UNBOUNDED,
                }
            }
            Node::Input(i, _) => self.inputs.get(i).copied().unwrap_or_else(|| {
                let (lo, hi) = i.range();
                Interval { lo, hi }
            }),
            Node::Channel(c, _) => self.channels.get(c).copied().unwrap_or(Interval::UNBOUNDED),
            // Receiver side: a lookup's range is not known before the slot is laid out.
            Node::Sample { .. } => Interval::UNBOUNDED,
            Node::Unary(UnOp::Neg, x) => {
                let x = self.get(*x);
                Interval { lo: -x.hi, hi: -x.lo }
            }
            Node::Unary(UnOp::Not, _) => Interval::UNIT,
            // ~x is -x - 1 on i32, 2^32 - 1 - x on u32
            Node::Unary(UnOp::BitNot, x) => {
                let x = self.get(*x);
                let top = if a.ty(h) == Ty::U32 { u32::MAX as f64 } else { -1.0 };
                Interval {
                    lo: top - x.hi,
                    hi: top - x.lo,
                }
            }
            Node::Binary(op, x, y) => {
                let (x, y) = (self.get(*x), self.get(*y));
                match op {
                    BinOp::Add => Interval {
                        lo: x.lo + y.lo,
                        hi: x.hi + y.hi,
                    },
                    BinOp::Sub => Interval {
                        lo: x.lo - y.hi,
                        hi: x.hi - y.lo,
                    },
                    BinOp::Mul => Interval::of(&[mul(x.lo, y.lo), mul(x.lo, y.hi), mul(x.hi, y.lo), mul(x.hi, y.hi)]),
                    BinOp::Div => {
                        if y.lo <= 0.0 && y.hi >= 0.0 {
                            Interval::UNBOUNDED
                        } else {
                            Interval::of(&[x.lo / y.lo, x.lo / y.hi, x.hi / y.lo, x.hi / y.hi])
                        }
                    }
                    BinOp::Rem => {
                        let m = y.magnitude();
                        Interval {
                            lo: if x.lo < 0.0 { -m } else { 0.0 },
                            hi: if x.hi > 0.0 { m } else { 0.0 },
                        }
                    }
                    BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne | BinOp::And | BinOp::Or => Interval::UNIT,
                    // of non-negative operands, `&` is at most the smaller one
                    BinOp::BitAnd if x.lo >= 0.0 && y.lo >= 0.0 => Interval {
                        lo: 0.0,
                        hi: x.hi.min(y.hi),
                    },
                    BinOp::BitAnd | BinOp::BitOr | BinOp::BitXor | BinOp::Shl => integers(),
                    // a right shift of a non-negative value only shrinks it
                    BinOp::Shr if x.lo >= 0.0 => Interval { lo: 0.0, hi: x.hi },
                    BinOp::Shr => integers(),
                }
            }
            Node::Swizzle(x, _) => self.get(*x),
            Node::Call(f, args) => {
                let v: Vec<Interval> = args.iter().map(|x| self.get(*x)).collect();
                (f.desc().range)(&v)
            }
        }
    }
}

/// 0 * inf is 0 here: a zero factor bounds the product whatever the other range.
fn mul(a: f64, b: f64) -> f64 {
    if a == 0.0 || b == 0.0 { 0.0 } else { a * b }
}

/// Ranges of every slot of every resource (indexed by resource, then slot), in pass order
/// (no diagnostics). `param_range` overrides the range of one runtime param: the probe
/// of the largest safe value evaluates the same IR under another environment.
pub fn slot_ranges(ir: &Ir, param_range: Option<(ParamId, Interval)>) -> Vec<Vec<Interval>> {
    ranges_from(ir, param_range, false)
}

/// [`slot_ranges`] with the Depth pass's output narrowed to the scene's depths where the
/// compilation is specialised for a scene (`SceneFacts::depth_floor`). Only the channels
/// left to the compiler (`Auto`) are judged on these: an explicit precision keeps the
/// generic ranges and so the generic encodes, and a specialised build stores what the
/// generic one stores.
pub fn scene_slot_ranges(ir: &Ir) -> Vec<Vec<Interval>> {
    ranges_from(ir, None, true)
}

/// [`slot_ranges`] with each Map and Geometry channel's value's analysed interval in place
/// of its declared range (`analyse` refuses a declared range the value cannot reach).
pub fn value_slot_ranges(ir: &Ir) -> Vec<Vec<Interval>> {
    ranges_with(ir, None, false, false)
}

fn ranges_from(ir: &Ir, param_range: Option<(ParamId, Interval)>, scene: bool) -> Vec<Vec<Interval>> {
    ranges_with(ir, param_range, scene, true)
}

/// [`ranges_from`], taking each channel's declared range (`declared`) or its value's
/// analysed interval.
fn ranges_with(ir: &Ir, param_range: Option<(ParamId, Interval)>, scene: bool, declared: bool) -> Vec<Vec<Interval>> {
    let mut out: Vec<Vec<Interval>> = ir.resources.iter().map(|r| vec![Interval::UNBOUNDED; r.slots.len()]).collect();
    for pass in &ir.passes {
        let Some(w) = pass.writes else { continue };
        let res = &ir.resources[w];
        let src = |ch: ChannelId| -> Option<Interval> {
            pass.reads.iter().find_map(|&r| {
                let i = ir.resources[r].slots.iter().position(|s| s.channel == ch)?;
                Some(out[r.index()][i])
            })
        };
        let mut ranges = Vec::with_capacity(res.slots.len());
        match &pass.kind {
            IrPassKind::Depth { view } => {
                // specialised for a scene: the centre view's casters lie at or beyond the
                // facts' least depth (what no caster covers stays at 1)
                let floor = match view {
                    LightView::Center if scene => ir
                        .specialised
                        .as_ref()
                        .and_then(|s| s.facts.depth_floor)
                        .map_or(0.0, |f| (f as f64).clamp(0.0, 1.0)),
                    LightView::Center | LightView::PerSample => 0.0,
                };
                ranges.extend(res.slots.iter().map(|_| Interval { lo: floor, hi: 1.0 }))
            }
            IrPassKind::Map | IrPassKind::Geometry { .. } => {
                let mut env = HashMap::new();
                for &r in &pass.reads {
                    for (i, s) in ir.resources[r].slots.iter().enumerate() {
                        env.insert(s.channel, out[r.index()][i]);
                    }
                }
                let mut ev = RangeEval::new(ir, env);
                ev.param_range = param_range;
                for s in &res.slots {
                    let ch = &ir.channels[s.channel];
                    ranges.push(match (ch.range, ch.value) {
                        // clamped to it when stored
                        (Some((lo, hi)), Some(_)) if declared => Interval { lo, hi },
                        (_, Some(v)) => ev.eval(v),
                        (_, None) => Interval::UNIT,
                    });
                }
            }
            IrPassKind::Filter { kernel: IrKernel::LoG } => {
                for s in &res.slots {
                    let r = src(s.channel).unwrap_or(Interval::UNBOUNDED);
                    // centre weight 4, four neighbours -1 (IrKernel::LOG_3X3)
                    let w = r.hi - r.lo;
                    ranges.push(Interval { lo: -4.0 * w, hi: 4.0 * w });
                }
            }
            IrPassKind::Filter { .. }
            | IrPassKind::Mipmap {
                reduce: Reduce::Mean | Reduce::Max | Reduce::Min,
            }
            | IrPassKind::SummedArea { .. } => {
                // convex combinations, maxima and minima stay within the source range
                for s in &res.slots {
                    ranges.push(src(s.channel).unwrap_or(Interval::UNBOUNDED));
                }
            }
            IrPassKind::Shade { .. } => {}
        }
        out[w.index()] = ranges;
    }
    out
}

/// The smallest magnitude other than 0 a range may hold (infinite when it straddles 0: its
/// values may come as near 0 as they like, which the underflow warning leaves alone).
pub fn smallest_magnitude(r: Interval) -> f64 {
    if r.lo > 0.0 {
        r.lo
    } else if r.hi < 0.0 {
        -r.hi
    } else {
        f64::INFINITY
    }
}

/// Whether a precision can hold a range.
pub fn fits(p: Precision, r: Interval) -> bool {
    if r.lo.is_nan() || r.hi.is_nan() {
        return false;
    }
    match p {
        Precision::F32 => r.magnitude() <= F32_MAX,
        Precision::F16 => r.magnitude() <= F16_MAX,
        Precision::Unorm8 | Precision::Unorm16 => r.is_finite(),
    }
}
