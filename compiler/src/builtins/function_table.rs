//! Every built-in function's descriptor (`Func::desc`): name, arity, signature, constant
//! folding, range rule, WGSL and accuracy, with the helpers those rules share.

use super::fold::finite_f32;
use super::{Accuracy, Builtin, Fold, Func, Sig, Ty, Wgsl};
use crate::front::ast::ConstValue;
use crate::interval::Interval;
use std::f64::consts::PI;

impl Func {
    /// The descriptor: adding a function means adding a variant, its entry in
    /// [`Func::ALL`] and its arm here.
    pub fn desc(self) -> &'static Builtin {
        use Accuracy::{Bound, Exact, Rounded};
        use Fold::{Custom, Float, Hook, IntOrFloat, Never};
        use Sig::{Construct, Convert, Dot, Length, Numeric, SameNumeric, Scalars};
        use Wgsl::{Callee, Expr, Same, Typed};
        match self {
            Func::Abs => &Builtin {
                name: "abs",
                arity: 1,
                sig: Numeric,
                fold: IntOrFloat(|a| a[0].checked_abs(), |x| Some(x[0].abs())),
                range: |v| {
                    let x = v[0];
                    if x.lo >= 0.0 {
                        x
                    } else if x.hi <= 0.0 {
                        Interval { lo: -x.hi, hi: -x.lo }
                    } else {
                        Interval {
                            lo: 0.0,
                            hi: x.magnitude(),
                        }
                    }
                },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Exp => &Builtin {
                name: "exp",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].exp())),
                range: |v| v[0].monotone(f64::exp),
                wgsl: Same,
                accuracy: Bound(|v, x| (3.0 + 2.0 * (arg(x, 0) * std::f64::consts::LOG2_E).abs()) * ulp(v)),
            },
            Func::Exp2 => &Builtin {
                name: "exp2",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].exp2())),
                range: |v| v[0].monotone(f64::exp2),
                wgsl: Same,
                accuracy: Bound(|v, x| (3.0 + 2.0 * arg(x, 0).abs()) * ulp(v)),
            },
            Func::Log => &Builtin {
                name: "log",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| (x[0] > 0.0).then(|| x[0].ln())),
                range: |v| v[0].monotone(|t| if t <= 0.0 { f64::NEG_INFINITY } else { t.ln() }),
                wgsl: Same,
                accuracy: Bound(|v, _| (3.0 * ulp(v)).max(2f64.powi(-21))),
            },
            Func::Log2 => &Builtin {
                name: "log2",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| (x[0] > 0.0).then(|| x[0].log2())),
                range: |v| v[0].monotone(|t| if t <= 0.0 { f64::NEG_INFINITY } else { t.log2() }),
                wgsl: Same,
                accuracy: Bound(|v, _| (3.0 * ulp(v)).max(2f64.powi(-21))),
            },
            Func::Sqrt => &Builtin {
                name: "sqrt",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| (x[0] >= 0.0).then(|| x[0].sqrt())),
                range: |v| v[0].monotone(|t| t.max(0.0).sqrt()),
                wgsl: Same,
                accuracy: Bound(|v, _| 2.5 * ulp(v)),
            },
            Func::InverseSqrt => &Builtin {
                name: "inverseSqrt",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| (x[0] > 0.0).then(|| 1.0 / x[0].sqrt())),
                range: |v| {
                    let x = v[0];
                    if x.lo <= 0.0 {
                        Interval {
                            lo: if x.hi > 0.0 { 1.0 / x.hi.sqrt() } else { 0.0 },
                            hi: f64::INFINITY,
                        }
                    } else {
                        x.monotone(|t| 1.0 / t.sqrt())
                    }
                },
                wgsl: Same,
                accuracy: Bound(|v, _| 2.5 * ulp(v)),
            },
            Func::Sin => &Builtin {
                name: "sin",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].sin())),
                range: |v| trig(v[0], 0.0),
                wgsl: Same,
                accuracy: Bound(|_, x| 2f64.powi(-11) + arg(x, 0).abs() * 2f64.powi(-22)),
            },
            Func::Cos => &Builtin {
                name: "cos",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].cos())),
                range: |v| trig(v[0], PI / 2.0),
                wgsl: Same,
                accuracy: Bound(|_, x| 2f64.powi(-11) + arg(x, 0).abs() * 2f64.powi(-22)),
            },
            Func::Tan => &Builtin {
                name: "tan",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].tan())),
                range: |v| {
                    let x = v[0];
                    if x.is_finite() && (x.hi - x.lo) < PI && (x.lo / PI + 0.5).floor() == (x.hi / PI + 0.5).floor() {
                        x.monotone(f64::tan)
                    } else {
                        Interval::UNBOUNDED
                    }
                },
                wgsl: Same,
                accuracy: Bound(|v, _| 2f64.powi(-11) * (1.0 + v * v)),
            },
            // WGSL: accuracy "inherited from" (exp(x) - exp(-x)) / 2, (exp(x) + exp(-x)) / 2
            // and sinh(x) / cosh(x): two exps of |x| (exp's bound at e^|x|), the sum's and the
            // halving's rounding; tanh divides that by cosh (at least 1)
            Func::Sinh => &Builtin {
                name: "sinh",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].sinh())),
                range: |v| v[0].monotone(f64::sinh),
                wgsl: Same,
                accuracy: Bound(|v, x| hyperbolic_error(arg(x, 0)) + 2.0 * ulp(v)),
            },
            Func::Cosh => &Builtin {
                name: "cosh",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].cosh())),
                // even, least (1) at 0
                range: |v| {
                    let x = v[0];
                    let hi = x.lo.cosh().max(x.hi.cosh());
                    let lo = if x.lo <= 0.0 && x.hi >= 0.0 {
                        1.0
                    } else {
                        x.lo.cosh().min(x.hi.cosh())
                    };
                    Interval { lo, hi }
                },
                wgsl: Same,
                accuracy: Bound(|v, x| hyperbolic_error(arg(x, 0)) + 2.0 * ulp(v)),
            },
            Func::Tanh => &Builtin {
                name: "tanh",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].tanh())),
                range: |v| v[0].monotone(f64::tanh),
                wgsl: Same,
                accuracy: Bound(|v, x| 2.0 * hyperbolic_error(arg(x, 0)) / arg(x, 0).cosh().max(1.0) + 2.5 * ulp(v)),
            },
            Func::Asin => &Builtin {
                name: "asin",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| (x[0].abs() <= 1.0).then(|| x[0].asin())),
                range: |v| {
                    Interval {
                        lo: v[0].lo.max(-1.0),
                        hi: v[0].hi.min(1.0),
                    }
                    .monotone(f64::asin)
                },
                wgsl: Same,
                accuracy: Bound(|v, _| 4096.0 * ulp(v) + 2f64.powi(-22)),
            },
            Func::Acos => &Builtin {
                name: "acos",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| (x[0].abs() <= 1.0).then(|| x[0].acos())),
                range: |v| {
                    Interval {
                        lo: v[0].lo.max(-1.0),
                        hi: v[0].hi.min(1.0),
                    }
                    .monotone(f64::acos)
                },
                wgsl: Same,
                accuracy: Bound(|v, _| 4096.0 * ulp(v) + 2f64.powi(-22)),
            },
            Func::Atan => &Builtin {
                name: "atan",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].atan())),
                range: |v| v[0].monotone(f64::atan),
                wgsl: Same,
                accuracy: Bound(|v, _| 4096.0 * ulp(v) + 2f64.powi(-22)),
            },
            Func::Floor => &Builtin {
                name: "floor",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].floor())),
                range: |v| v[0].monotone(f64::floor),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Ceil => &Builtin {
                name: "ceil",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].ceil())),
                range: |v| v[0].monotone(f64::ceil),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Fract => &Builtin {
                name: "fract",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0] - x[0].floor())),
                range: |_| Interval { lo: 0.0, hi: 1.0 },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Round => &Builtin {
                name: "round",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(round_half_even(x[0]))),
                range: |v| v[0].monotone(round_half_even),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Trunc => &Builtin {
                name: "trunc",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].trunc())),
                range: |v| v[0].monotone(f64::trunc),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Sign => &Builtin {
                name: "sign",
                arity: 1,
                sig: Numeric,
                fold: IntOrFloat(|a| Some(a[0].signum()), |x| Some(x[0].signum() * (x[0] != 0.0) as i32 as f64)),
                range: |v| v[0].monotone(sign),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Saturate => &Builtin {
                name: "saturate",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].clamp(0.0, 1.0))),
                range: |v| Interval {
                    lo: v[0].lo.clamp(0.0, 1.0),
                    hi: v[0].hi.clamp(0.0, 1.0),
                },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Pow => &Builtin {
                name: "pow",
                arity: 2,
                sig: Sig::Float,
                fold: Float(|x| (x[0] >= 0.0).then(|| x[0].powf(x[1]))),
                range: |v| {
                    let (b, e) = (v[0], v[1]);
                    if b.lo >= 0.0 && b.is_finite() && e.is_finite() {
                        let corners = [b.lo.powf(e.lo), b.lo.powf(e.hi), b.hi.powf(e.lo), b.hi.powf(e.hi)];
                        let mut r = Interval::of(&corners);
                        if b.lo <= 1.0 && b.hi >= 1.0 {
                            r = Interval::hull(r, Interval::point(1.0));
                        }
                        r
                    } else {
                        Interval::UNBOUNDED
                    }
                },
                wgsl: Same,
                accuracy: Bound(|v, x| {
                    let y = arg(x, 1);
                    let e = y * arg(x, 0).abs().log2();
                    (3.0 + 2.0 * e.abs()) * ulp(v) + v.abs() * std::f64::consts::LN_2 * y.abs() * 2f64.powi(-21)
                }),
            },
            Func::Min => &Builtin {
                name: "min",
                arity: 2,
                sig: SameNumeric,
                fold: IntOrFloat(|a| Some(a[0].min(a[1])), |x| Some(x[0].min(x[1]))),
                range: |v| Interval {
                    lo: v[0].lo.min(v[1].lo),
                    hi: v[0].hi.min(v[1].hi),
                },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Max => &Builtin {
                name: "max",
                arity: 2,
                sig: SameNumeric,
                fold: IntOrFloat(|a| Some(a[0].max(a[1])), |x| Some(x[0].max(x[1]))),
                range: |v| Interval {
                    lo: v[0].lo.max(v[1].lo),
                    hi: v[0].hi.max(v[1].hi),
                },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Atan2 => &Builtin {
                name: "atan2",
                arity: 2,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].atan2(x[1]))),
                range: |_| Interval { lo: -PI, hi: PI },
                wgsl: Same,
                accuracy: Bound(|v, _| 4096.0 * ulp(v) + 2f64.powi(-22)),
            },
            Func::Step => &Builtin {
                name: "step",
                arity: 2,
                sig: Sig::Float,
                fold: Float(|x| Some(if x[1] >= x[0] { 1.0 } else { 0.0 })),
                range: |_| Interval::UNIT,
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Clamp => &Builtin {
                name: "clamp",
                arity: 3,
                sig: SameNumeric,
                fold: IntOrFloat(
                    |a| Some(a[0].max(a[1]).min(a[2])),
                    |x| (x[1] <= x[2]).then(|| x[0].max(x[1]).min(x[2])),
                ),
                // min(max(x, lo), hi) grows with each argument
                range: |v| Interval {
                    lo: v[0].lo.max(v[1].lo).min(v[2].lo),
                    hi: v[0].hi.max(v[1].hi).min(v[2].hi),
                },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Mix => &Builtin {
                name: "mix",
                arity: 3,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0] * (1.0 - x[2]) + x[1] * x[2])),
                range: |v| {
                    let (a, b, t) = (v[0], v[1], v[2]);
                    let mut vals = Vec::new();
                    for ta in [t.lo, t.hi] {
                        for av in [a.lo, a.hi] {
                            for bv in [b.lo, b.hi] {
                                vals.push(av * (1.0 - ta) + bv * ta);
                            }
                        }
                    }
                    Interval::of(&vals)
                },
                wgsl: Same,
                accuracy: Rounded,
            },
            Func::Smoothstep => &Builtin {
                name: "smoothstep",
                arity: 3,
                sig: Sig::Float,
                fold: Float(|x| {
                    (x[0] != x[1]).then(|| {
                        let t = ((x[2] - x[0]) / (x[1] - x[0])).clamp(0.0, 1.0);
                        t * t * (3.0 - 2.0 * t)
                    })
                }),
                range: |_| Interval::UNIT,
                wgsl: Same,
                accuracy: Bound(|v, _| 4.0 * ulp(v)),
            },
            Func::Linstep => &Builtin {
                name: "linstep",
                arity: 3,
                sig: Sig::Float,
                fold: Float(|x| (x[0] != x[1]).then(|| ((x[2] - x[0]) / (x[1] - x[0])).clamp(0.0, 1.0))),
                range: |_| Interval::UNIT,
                wgsl: Expr(|v| format!("saturate(({} - {}) / ({} - {}))", v[2], v[0], v[1], v[0])),
                accuracy: Bound(|v, _| 4.0 * ulp(v)),
            },
            Func::Select => &Builtin {
                name: "select",
                arity: 3,
                sig: Sig::Select,
                // the arena also folds a select with a constant condition and other operands
                fold: Custom(pick),
                range: |v| Interval::hull(v[0], v[1]),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::ToF32 => &Builtin {
                name: "f32",
                arity: 1,
                sig: Convert(Ty::F32),
                fold: Custom(|v| match v[0] {
                    ConstValue::Int(a) => Some(ConstValue::Float(a as f64)),
                    ConstValue::Uint(a) => finite_f32(a as f64),
                    ConstValue::Float(x) => finite_f32(x),
                    ConstValue::Bool(b) => finite_f32(b as i64 as f64),
                }),
                range: |v| v[0],
                wgsl: Same,
                accuracy: Rounded,
            },
            Func::ToI32 => &Builtin {
                name: "i32",
                arity: 1,
                sig: Convert(Ty::I32),
                fold: Custom(|v| match v[0] {
                    ConstValue::Int(a) => Some(ConstValue::Int(a)),
                    // the same bits (WGSL's i32(u32))
                    ConstValue::Uint(a) => Some(ConstValue::Int(a as i32 as i64)),
                    ConstValue::Float(x) if x.is_finite() => {
                        Some(ConstValue::Int(x.trunc().clamp(i32::MIN as f64, i32::MAX as f64) as i64))
                    }
                    ConstValue::Float(_) => None,
                    ConstValue::Bool(b) => Some(ConstValue::Int(b as i64)),
                }),
                range: |v| v[0].monotone(f64::trunc),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::ToU32 => &Builtin {
                name: "u32",
                arity: 1,
                sig: Convert(Ty::U32),
                fold: Custom(|v| match v[0] {
                    // the same bits (WGSL's u32(i32)): u32(-1) is 4294967295u
                    ConstValue::Int(a) => Some(ConstValue::Uint(a as i32 as u32)),
                    ConstValue::Uint(a) => Some(ConstValue::Uint(a)),
                    // rounded towards zero and clamped to the u32 range, as for i32
                    ConstValue::Float(x) if x.is_finite() => Some(ConstValue::Uint(x.trunc().clamp(0.0, u32::MAX as f64) as u32)),
                    ConstValue::Float(_) => None,
                    ConstValue::Bool(b) => Some(ConstValue::Uint(b as u32)),
                }),
                range: |v| {
                    let t = v[0].monotone(f64::trunc);
                    // a negative i32 becomes a large u32: anything
                    if t.lo < 0.0 { Interval::U32 } else { t.meet(Interval::U32) }
                },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Vec2 => &Builtin {
                name: "vec2",
                arity: 2,
                sig: Construct(2),
                fold: Never,
                range: components,
                wgsl: Callee("vec2<f32>"),
                accuracy: Exact,
            },
            Func::Vec3 => &Builtin {
                name: "vec3",
                arity: 3,
                sig: Construct(3),
                fold: Never,
                range: components,
                wgsl: Callee("vec3<f32>"),
                accuracy: Exact,
            },
            Func::Vec4 => &Builtin {
                name: "vec4",
                arity: 4,
                sig: Construct(4),
                fold: Never,
                range: components,
                wgsl: Callee("vec4<f32>"),
                accuracy: Exact,
            },
            Func::Length => &Builtin {
                name: "length",
                arity: 1,
                sig: Length,
                fold: Never,
                range: |v| Interval {
                    lo: 0.0,
                    hi: (v.len() as f64).sqrt().max(2.0) * v[0].magnitude(),
                },
                wgsl: Same,
                accuracy: Rounded,
            },
            Func::Dot => &Builtin {
                name: "dot",
                arity: 2,
                sig: Dot,
                fold: Never,
                range: |v| {
                    let m = v[0].magnitude() * v[1].magnitude() * 4.0;
                    Interval { lo: -m, hi: m }
                },
                wgsl: Same,
                accuracy: Rounded,
            },
            Func::DivOr => &Builtin {
                name: "div_or",
                arity: 4,
                sig: Sig::Guarded,
                fold: Float(|x| Some(if x[1].abs() >= x[2] && x[1] != 0.0 { x[0] / x[1] } else { x[3] })),
                range: |v| {
                    // the quotient over the denominators at least eps away from 0, and the fallback
                    let (num, den, eps, fb) = (v[0], v[1], v[2], v[3]);
                    if eps.lo <= 0.0 {
                        return Interval::UNBOUNDED;
                    }
                    let mut r = fb;
                    for (lo, hi) in [(den.lo.max(eps.lo), den.hi), (den.lo, den.hi.min(-eps.lo))] {
                        if lo <= hi {
                            r = Interval::hull(r, Interval::of(&[num.lo / lo, num.lo / hi, num.hi / lo, num.hi / hi]));
                        }
                    }
                    r
                },
                // the denominator is replaced by 1 where it is refused, so that no
                // infinity or NaN is computed even in the branch select discards; on
                // vectors, component by component (lowering has splatted eps and fallback)
                wgsl: Typed(|v, ty| match ty {
                    Ty::Vec(k) => {
                        let ok = format!("(abs({d}) >= {e}) & ({d} != vec{k}<f32>(0.0))", d = v[1], e = v[2]);
                        format!(
                            "select({fb}, {n} / select(vec{k}<f32>(1.0), {d}, {ok}), {ok})",
                            n = v[0],
                            d = v[1],
                            fb = v[3]
                        )
                    }
                    Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => format!(
                        "select({fb}, {n} / select(1.0, {d}, abs({d}) >= {e} && {d} != 0.0), abs({d}) >= {e} && {d} != 0.0)",
                        n = v[0],
                        d = v[1],
                        e = v[2],
                        fb = v[3]
                    ),
                }),
                accuracy: Bound(|v, _| 2.5 * ulp(v)),
            },
            Func::Branch => &Builtin {
                name: "if",
                arity: 3,
                sig: Sig::Select,
                fold: Custom(pick),
                range: |v| Interval::hull(v[0], v[1]),
                // never a call: `back::expr` emits the arms inside an `if`
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Noise => &Builtin {
                name: "noise",
                arity: 3,
                sig: Scalars,
                // a hash: the GPU's integer arithmetic, which `interp::noise` repeats
                fold: Hook,
                range: |_| Interval { lo: 0.0, hi: 1.0 },
                // the module defines `sshc_noise` where a body calls it (`NOISE_WGSL`)
                wgsl: Callee("sshc_noise"),
                accuracy: Exact,
            },
            Func::UvWidth => &Builtin {
                name: "uv_width",
                arity: 2,
                sig: Scalars,
                // scaled by the frame: unknown at compile time
                fold: Hook,
                // a length over a texel's world size: scaled by the frame, unknown here
                range: |v| Interval {
                    lo: if v[0].lo >= 0.0 { 0.0 } else { f64::NEG_INFINITY },
                    hi: if v[0].hi <= 0.0 { 0.0 } else { f64::INFINITY },
                },
                // one texel at distance D spans texel_world.x * D + texel_world.y world units
                wgsl: Expr(|v| {
                    format!(
                        "({} / ((frame.texel_world.x * {} + frame.texel_world.y) * frame.shadow_size.x))",
                        v[0], v[1]
                    )
                }),
                accuracy: Rounded,
            },
        }
    }
}

/// The error of the two exponentials WGSL's `sinh` and `cosh` are specified through
/// (accuracy inherited from `(exp(x) -+ exp(-x)) / 2`): `exp`'s bound, (3 + 2 |x| log2 e)
/// ulp, at the larger of the two, e^|x|.
fn hyperbolic_error(x: f64) -> f64 {
    (3.0 + 2.0 * (x * std::f64::consts::LOG2_E).abs()) * ulp(x.abs().exp())
}

/// One f32 ulp of `v` (relative 2^-23).
fn ulp(v: f64) -> f64 {
    v.abs() * 2f64.powi(-23)
}

/// Argument `i` of a call, 0 where it has none.
fn arg(x: &[f64], i: usize) -> f64 {
    x.get(i).copied().unwrap_or(0.0)
}

/// `select(f, t, c)` and `if c { t } else { f }` on constants: the operand the condition
/// picks.
fn pick(v: &[ConstValue]) -> Option<ConstValue> {
    match v[2] {
        ConstValue::Bool(true) => Some(v[1]),
        ConstValue::Bool(false) => Some(v[0]),
        ConstValue::Int(_) | ConstValue::Uint(_) | ConstValue::Float(_) => None,
    }
}

/// WGSL's `round`: half to even.
fn round_half_even(x: f64) -> f64 {
    if (x - x.trunc()).abs() == 0.5 {
        2.0 * (x / 2.0).round()
    } else {
        x.round()
    }
}

/// WGSL's `sign`: -1, 0 or 1.
fn sign(x: f64) -> f64 {
    if x == 0.0 { 0.0 } else { x.signum() }
}

/// Range of a vector constructor: the hull of its components.
fn components(v: &[Interval]) -> Interval {
    v.iter().copied().reduce(Interval::hull).unwrap_or(Interval::UNBOUNDED)
}

/// Range of sin(x + phase) over x.
fn trig(x: Interval, phase: f64) -> Interval {
    if !x.is_finite() || x.hi - x.lo >= 2.0 * PI {
        return Interval { lo: -1.0, hi: 1.0 };
    }
    let (a, b) = (x.lo + phase, x.hi + phase);
    let mut vals = vec![a.sin(), b.sin()];
    // extrema at pi/2 + n pi
    let mut n = ((a - PI / 2.0) / PI).ceil();
    while PI / 2.0 + n * PI <= b {
        vals.push((PI / 2.0 + n * PI).sin());
        n += 1.0;
    }
    Interval::of(&vals)
}
