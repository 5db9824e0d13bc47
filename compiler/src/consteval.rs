//! Constant evaluation, shared by `check` (filter sizes, sigmas, expansion bounds, the
//! value of abstract integer expressions) and by the IR arena's folding (`ir::Arena::add`
//! folds unary and binary operations through [`unary`] and [`binary`]). One set of rules:
//! integers are i32 (a result outside i32 is not a constant), u32 arithmetic wraps modulo
//! 2^32 (as on the GPU), floats are rounded to f32 after every operation, division by zero
//! and a shift by 32 or more are not constants.

use crate::builtins::{Func, constant};
use crate::diag::{Diagnostic, Phase};
use crate::front::ast::ConstValue;
use crate::front::expr::{BinOp, Expr, ExprKind, Literal, UnOp};
use crate::resolve::Symbols;
use crate::span::Span;
use ConstValue::{Bool, Float, Int, Uint};

/// Unrolling stops past this many terms in one series (also bounds constant evaluation).
pub const MAX_SERIES: i64 = 4096;

/// A value as the GPU would hold it: floats rounded to f32 (finite only), integers in i32.
pub fn represent(v: ConstValue) -> Option<ConstValue> {
    match v {
        ConstValue::Float(f) => {
            let f = f as f32;
            f.is_finite().then_some(ConstValue::Float(f as f64))
        }
        ConstValue::Int(i) => i32::try_from(i).ok().map(|i| ConstValue::Int(i as i64)),
        ConstValue::Uint(u) => Some(ConstValue::Uint(u)),
        ConstValue::Bool(b) => Some(ConstValue::Bool(b)),
    }
}

/// A unary operation on a constant (not yet rounded: see [`represent`]).
pub fn unary(op: UnOp, v: ConstValue) -> Option<ConstValue> {
    match (op, v) {
        (UnOp::Neg, Float(x)) => Some(Float(-x)),
        (UnOp::Neg, Int(x)) => Some(Int(x.checked_neg()?)),
        (UnOp::Not, Bool(x)) => Some(Bool(!x)),
        (UnOp::BitNot, Int(x)) => Some(Int(!x)),
        (UnOp::BitNot, Uint(x)) => Some(Uint(!x)),
        (UnOp::Neg, Bool(_) | Uint(_)) | (UnOp::Not, Float(_) | Int(_) | Uint(_)) | (UnOp::BitNot, Float(_) | Bool(_)) => None,
    }
}

/// A comparison of two constants of one type (`None` for another operator).
fn compare<T: PartialOrd>(op: BinOp, x: T, y: T) -> Option<ConstValue> {
    Some(Bool(match op {
        BinOp::Lt => x < y,
        BinOp::Le => x <= y,
        BinOp::Gt => x > y,
        BinOp::Ge => x >= y,
        BinOp::Eq => x == y,
        BinOp::Ne => x != y,
        BinOp::Add
        | BinOp::Sub
        | BinOp::Mul
        | BinOp::Div
        | BinOp::Rem
        | BinOp::And
        | BinOp::Or
        | BinOp::BitAnd
        | BinOp::BitOr
        | BinOp::BitXor
        | BinOp::Shl
        | BinOp::Shr => return None,
    }))
}

/// A shift count: below 32 (WGSL refuses a constant count of 32 or more).
fn shift_count(y: ConstValue) -> Option<u32> {
    let c = match y {
        Int(c) => u32::try_from(c).ok()?,
        Uint(c) => c,
        Float(_) | Bool(_) => return None,
    };
    (c < 32).then_some(c)
}

/// A binary operation on two constants of one type (not yet rounded: see [`represent`]).
pub fn binary(op: BinOp, x: ConstValue, y: ConstValue) -> Option<ConstValue> {
    // shifts: the count is u32 (or an abstract integer) whatever the shifted type
    if op.is_shift() {
        let c = shift_count(y)?;
        return Some(match (op, x) {
            (BinOp::Shl, Int(x)) => Int((x as i32).wrapping_shl(c) as i64),
            (BinOp::Shr, Int(x)) => Int(((x as i32) >> c) as i64),
            (BinOp::Shl, Uint(x)) => Uint(x.wrapping_shl(c)),
            (BinOp::Shr, Uint(x)) => Uint(x >> c),
            _ => return None,
        });
    }
    Some(match (x, y) {
        (Float(x), Float(y)) => match op {
            BinOp::Add => Float(x + y),
            BinOp::Sub => Float(x - y),
            BinOp::Mul => Float(x * y),
            BinOp::Div if y != 0.0 => Float(x / y),
            BinOp::Rem if y != 0.0 => Float(x % y),
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne => compare(op, x, y)?,
            BinOp::Div | BinOp::Rem | BinOp::And | BinOp::Or => return None,
            BinOp::BitAnd | BinOp::BitOr | BinOp::BitXor | BinOp::Shl | BinOp::Shr => return None,
        },
        (Uint(x), Uint(y)) => match op {
            BinOp::Add => Uint(x.wrapping_add(y)),
            BinOp::Sub => Uint(x.wrapping_sub(y)),
            BinOp::Mul => Uint(x.wrapping_mul(y)),
            BinOp::Div if y != 0 => Uint(x / y),
            BinOp::Rem if y != 0 => Uint(x % y),
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne => compare(op, x, y)?,
            BinOp::BitAnd => Uint(x & y),
            BinOp::BitOr => Uint(x | y),
            BinOp::BitXor => Uint(x ^ y),
            BinOp::Div | BinOp::Rem | BinOp::And | BinOp::Or | BinOp::Shl | BinOp::Shr => return None,
        },
        (Int(x), Int(y)) => match op {
            BinOp::Add => Int(x.checked_add(y)?),
            BinOp::Sub => Int(x.checked_sub(y)?),
            BinOp::Mul => Int(x.checked_mul(y)?),
            BinOp::Div if y != 0 => Int(x / y),
            BinOp::Rem if y != 0 => Int(x % y),
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne => compare(op, x, y)?,
            // on the i32 bits
            BinOp::BitAnd => Int(((x as i32) & (y as i32)) as i64),
            BinOp::BitOr => Int(((x as i32) | (y as i32)) as i64),
            BinOp::BitXor => Int(((x as i32) ^ (y as i32)) as i64),
            BinOp::Div | BinOp::Rem | BinOp::And | BinOp::Or | BinOp::Shl | BinOp::Shr => return None,
        },
        (Bool(x), Bool(y)) => match op {
            BinOp::And => Bool(x && y),
            BinOp::Or => Bool(x || y),
            BinOp::Eq => Bool(x == y),
            BinOp::Ne => Bool(x != y),
            BinOp::Add
            | BinOp::Sub
            | BinOp::Mul
            | BinOp::Div
            | BinOp::Rem
            | BinOp::Lt
            | BinOp::Le
            | BinOp::Gt
            | BinOp::Ge
            | BinOp::BitAnd
            | BinOp::BitOr
            | BinOp::BitXor
            | BinOp::Shl
            | BinOp::Shr => return None,
        },
        (Float(_), Int(_) | Uint(_) | Bool(_))
        | (Int(_), Float(_) | Uint(_) | Bool(_))
        | (Uint(_), Float(_) | Int(_) | Bool(_))
        | (Bool(_), Float(_) | Int(_) | Uint(_)) => return None,
    })
}

/// An integer operation whose operands may be known at compile time, for [`int_fault`].
#[derive(Clone, Copy, Debug)]
pub enum IntOp {
    Neg,
    Binary(BinOp),
    Call(Func),
}

/// Where an integer operation stands in the technique file, for [`int_fault`].
#[derive(Clone, Copy, Debug)]
pub struct IntSpans {
    /// The whole operation.
    pub op: Span,
    /// The divisor of a `/` or `%` (the operation's span where there is none to point at).
    pub divisor: Span,
}

/// Why an integer (i32) operation on operands known at compile time has no i32 value, as a
/// diagnostic at the operation in the technique file: a `/` or `%` by 0 (the divisor alone
/// decides), -2147483648 / -1 or % -1, or a `+`, `-`, `*`, negation or `abs` whose exact
/// value lies outside i32. `None` where the value exists or an operand is not known. WGSL
/// refuses such a constant expression (a shader-creation error), so without this the
/// failure would surface as an internal error located in the generated shader. `check`
/// calls it for the operations it can evaluate, `lower` for those inside series (the
/// series variable known only when unrolled), one rule and one message for both.
pub fn int_fault(phase: Phase, op: IntOp, args: &[Option<ConstValue>], at: IntSpans) -> Option<Diagnostic> {
    let int = |i: usize| match args.get(i) {
        Some(Some(Int(v))) => Some(*v),
        _ => None,
    };
    // u32 operations wrap: only a division by zero and a shift count have no value
    let uint = |i: usize| match args.get(i) {
        Some(Some(Uint(v))) => Some(*v as i64),
        _ => None,
    };
    let fits = |v: i128| i32::try_from(v).is_ok();
    let overflow = |what: String, exact: Option<i128>| {
        let mut d = Diagnostic::error(phase, format!("integer overflow: {what} does not fit in i32")).at(at.op, "overflows i32");
        if let Some(v) = exact {
            d = d.note(format!(
                "its exact value is {v}; integers are i32, from {} to {}",
                i32::MIN,
                i32::MAX
            ));
        }
        Some(d.help("integer expressions are computed in i32; write float literals (`2.0`) for larger values"))
    };
    match op {
        IntOp::Binary(op @ (BinOp::Shl | BinOp::Shr)) => {
            let c = int(1).or(uint(1))?;
            (!(0..32).contains(&c)).then(|| {
                Diagnostic::error(phase, format!("shift by {c}: the count of `{}` must be from 0 to 31", op.symbol()))
                    .at(at.divisor, format!("this count is {c}"))
                    .also(at.op, "in this shift")
                    .help("WGSL refuses a constant shift of the integer's width or more; shift in two steps or mask the count (`n & 31u`)")
            })
        }
        IntOp::Binary(op @ (BinOp::Div | BinOp::Rem)) => {
            let y = int(1).or(uint(1))?;
            if y == 0 {
                let what = if op == BinOp::Div { "division" } else { "remainder" };
                return Some(
                    Diagnostic::error(phase, format!("integer {what} by zero"))
                        .at(at.divisor, "this divisor is 0")
                        .also(at.op, "in this integer operation")
                        .help("an integer division by zero has no value; for a float, write the operands as floats (`7.0 / 0.0`)"),
                );
            }
            let x = int(0)?;
            (y == -1 && x == i32::MIN as i64 && int(1).is_some()).then(|| {
                Diagnostic::error(phase, format!("integer overflow: {x} {} {y} does not fit in i32", op.symbol()))
                    .at(at.op, "overflows i32")
            })
        }
        IntOp::Binary(op @ (BinOp::Add | BinOp::Sub | BinOp::Mul)) => {
            let (x, y) = (int(0)? as i128, int(1)? as i128);
            let v = if op == BinOp::Add {
                x + y
            } else if op == BinOp::Sub {
                x - y
            } else {
                x * y
            };
            if fits(v) {
                return None;
            }
            overflow(format!("{x} {} {y}", op.symbol()), Some(v))
        }
        IntOp::Binary(_) => None,
        IntOp::Neg => {
            let x = int(0)? as i128;
            if fits(-x) {
                return None;
            }
            overflow(format!("-({x})"), Some(-x))
        }
        IntOp::Call(Func::Abs) => {
            let x = int(0)? as i128;
            if fits(x.abs()) {
                return None;
            }
            overflow(format!("abs({x})"), Some(x.abs()))
        }
        IntOp::Call(_) => None,
    }
}

/// Why an expression has no compile-time value.
pub enum NotConst {
    /// A name that is not known at compile time (the diagnostic says which and why).
    Runtime(Diagnostic),
    /// The operations have no representable value (overflow, division by zero, a vector).
    NoValue,
}

/// Evaluate an expression that must be known at compile time (kernel sizes, sigmas,
/// expansion bounds): literals, fixed params, `PI`/`E`, operators, pure built-ins,
/// `let` and `sum`. An integer mixed with a float is an abstract integer literal (check
/// has refused every other mix) and converts to f32, as WGSL does.
pub fn const_eval(sym: &Symbols, e: &Expr) -> Result<ConstValue, Diagnostic> {
    match eval(sym, e, &mut Vec::new()) {
        Ok(v) => Ok(v),
        Err(NotConst::Runtime(d)) => Err(d),
        Err(NotConst::NoValue) => Err(Diagnostic::error(Phase::Check, "this value must be known at compile time")
            .at(e.span, "depends on runtime values")
            .help("use literals and params with `fixed: true` only")),
    }
}

/// Local bindings in scope, innermost last: a name with its compile-time value, or `None`
/// for a local whose value is not known here (it still hides a param of its name).
pub type Env = Vec<(String, Option<ConstValue>)>;

/// [`const_eval`] with local bindings in scope.
pub fn eval(sym: &Symbols, e: &Expr, env: &mut Env) -> Result<ConstValue, NotConst> {
    // an abstract integer beside a float is a float, beside a u32 a u32 (if it is one)
    let lift = |x: ConstValue, y: ConstValue| match (x, y) {
        (Int(i), Float(_)) => Some((Float(i as f64), y)),
        (Float(_), Int(i)) => Some((x, Float(i as f64))),
        (Int(i), Uint(_)) => Some((Uint(u32::try_from(i).ok()?), y)),
        (Uint(_), Int(i)) => Some((x, Uint(u32::try_from(i).ok()?))),
        _ => Some((x, y)),
    };
    let v = match &e.kind {
        ExprKind::Lit(Literal::Int(v)) => Int(*v),
        ExprKind::Lit(Literal::Uint(v)) => Uint(*v),
        ExprKind::Lit(Literal::Float(v)) => Float(*v),
        ExprKind::Lit(Literal::Bool(b)) => Bool(*b),
        ExprKind::Name(n) => name(sym, n, e.span, env)?,
        ExprKind::Unary(op, a) => unary(*op, eval(sym, a, env)?).ok_or(NotConst::NoValue)?,
        ExprKind::Binary(op, a, b) => {
            let x = eval(sym, a, env)?;
            // `&&` and `||` with a decided left side do not need the right one.
            match (op, x) {
                (BinOp::And, Bool(false)) => return Ok(Bool(false)),
                (BinOp::Or, Bool(true)) => return Ok(Bool(true)),
                _ => {}
            }
            let y = eval(sym, b, env)?;
            // a shift count stays as it is: it need not have the shifted value's type
            let (x, y) = if op.is_shift() {
                (x, y)
            } else {
                lift(x, y).ok_or(NotConst::NoValue)?
            };
            binary(*op, x, y).ok_or(NotConst::NoValue)?
        }
        ExprKind::Call { name, args, .. } => {
            let f = Func::from_name(name).ok_or(NotConst::NoValue)?;
            let vals = args.iter().map(|a| eval(sym, a, env)).collect::<Result<Vec<_>, _>>()?;
            if f == Func::Select {
                return match vals[..] {
                    [f, t, Bool(c)] => Ok(if c { t } else { f }),
                    _ => Err(NotConst::NoValue),
                };
            }
            crate::builtins::fold_call(f, &vals).ok_or(NotConst::NoValue)?
        }
        ExprKind::Member(..) => return Err(NotConst::NoValue),
        // an element of a constant array: its expression, which sees no local
        ExprKind::Index { name, index, .. } => {
            let a = sym.arrays.get(name).map(|&a| &sym.t.arrays[a]).ok_or(NotConst::NoValue)?;
            let Int(k) = eval(sym, index, env)? else {
                return Err(NotConst::NoValue);
            };
            let v = usize::try_from(k).ok().and_then(|k| a.values.get(k)).ok_or(NotConst::NoValue)?;
            eval(sym, v, &mut Vec::new())?
        }
        // only the arm taken is evaluated (the other may divide by zero where it is not)
        ExprKind::If { cond, then, els } => match eval(sym, cond, env)? {
            Bool(true) => eval(sym, then, env)?,
            Bool(false) => eval(sym, els, env)?,
            Int(_) | Uint(_) | Float(_) => return Err(NotConst::NoValue),
        },
        ExprKind::Let { name, value, body, .. } => {
            let v = eval(sym, value, env)?;
            env.push((name.clone(), Some(v)));
            let r = eval(sym, body, env);
            env.pop();
            r?
        }
        ExprKind::Sum { var, from, to, body, .. } => {
            let (Int(lo), Int(hi)) = (eval(sym, from, env)?, eval(sym, to, env)?) else {
                return Err(NotConst::NoValue);
            };
            if hi - lo + 1 > MAX_SERIES {
                return Err(NotConst::NoValue);
            }
            let mut acc = Int(0);
            for k in lo..=hi {
                env.push((var.clone(), Some(Int(k))));
                let t = eval(sym, body, env);
                env.pop();
                let (a, t) = lift(acc, t?).ok_or(NotConst::NoValue)?;
                acc = if k == lo {
                    t
                } else {
                    binary(BinOp::Add, a, t).ok_or(NotConst::NoValue)?
                };
                acc = represent(acc).ok_or(NotConst::NoValue)?;
            }
            acc
        }
    };
    represent(v).ok_or(NotConst::NoValue)
}

fn name(sym: &Symbols, n: &str, span: Span, env: &[(String, Option<ConstValue>)]) -> Result<ConstValue, NotConst> {
    if let Some((_, v)) = env.iter().rev().find(|(l, _)| l == n) {
        return v.ok_or_else(|| {
            NotConst::Runtime(
                Diagnostic::error(Phase::Check, format!("`{n}` is not known at compile time")).at(span, "not a compile-time value"),
            )
        });
    }
    if let Some((i, p)) = sym.param(n) {
        if !p.fixed {
            return Err(NotConst::Runtime(
                Diagnostic::error(
                    Phase::Check,
                    format!("param `{n}` is a runtime uniform, but this value is needed at compile time"),
                )
                .at(span, "not known at compile time")
                .also(p.name.span, "declared here")
                .help(format!("add `fixed: true` to param `{n}`")),
            ));
        }
        return Ok(sym.values[i].value);
    }
    if let Some(c) = constant(n) {
        return Ok(ConstValue::Float(c));
    }
    Err(NotConst::Runtime(
        Diagnostic::error(Phase::Check, format!("`{n}` is not known at compile time")).at(span, "not a compile-time value"),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integers_stay_in_i32_and_floats_round_to_f32() {
        assert_eq!(represent(Int(i32::MAX as i64)), Some(Int(i32::MAX as i64)));
        assert_eq!(represent(Int(i32::MAX as i64 + 1)), None);
        assert_eq!(represent(Float(0.1)), Some(Float(0.1f32 as f64)));
        assert_eq!(represent(Float(1e39)), None);
        assert_eq!(binary(BinOp::Div, Int(7), Int(2)), Some(Int(3)));
        assert_eq!(binary(BinOp::Div, Int(1), Int(0)), None);
        assert_eq!(binary(BinOp::Rem, Float(1.0), Float(0.0)), None);
        assert_eq!(
            binary(BinOp::Add, Int(1), Float(1.0)),
            None,
            "mixed types are converted by the caller"
        );
        assert_eq!(unary(UnOp::Neg, Int(i64::MIN)), None);
        assert_eq!(unary(UnOp::Not, Bool(true)), Some(Bool(false)));
    }

    fn eval_str(expr: &str, params: &str) -> Result<ConstValue, String> {
        let src = format!(
            "Technique(name: \"t\", params: {{ {params} }}, channels: {{ \"z\": Channel(precision: F32) }}, passes: [Depth(name: \"depth\", writes: \"shadow\", channel: \"z\"), Shade(name: \"shade\", reads: [\"shadow\"], visibility: \"{expr}\")])"
        );
        let t = crate::front::parse::parse(&src).map_err(|d| format!("{d:?}"))?;
        let sym = crate::resolve::resolve(&t, &crate::CompileOptions::default()).map_err(|d| format!("{d:?}"))?;
        let crate::front::ast::PassKind::Shade { visibility, .. } = &t.passes[1].kind else {
            unreachable!()
        };
        const_eval(&sym, visibility).map_err(|d| d.message)
    }

    #[test]
    fn expressions_of_literals_fixed_params_lets_and_series() {
        assert_eq!(eval_str("2 * 3 + 1", ""), Ok(Int(7)));
        assert_eq!(eval_str("7 / 2 * 1.0", ""), Ok(Float(3.0)), "the integer quotient, then f32");
        assert_eq!(
            eval_str(
                "let a = N + 1; sum(k in 1..=a, k)",
                "\"N\": Param(ty: I32, default: 3, fixed: true)"
            ),
            Ok(Int(10))
        );
        assert_eq!(
            eval_str("max(f32(N), 0.5)", "\"N\": Param(ty: I32, default: 3, fixed: true)"),
            Ok(Float(3.0))
        );
        assert_eq!(eval_str("sum(k in 1..=0, 2.0)", ""), Ok(Int(0)));
        assert_eq!(eval_str("select(1, 2, 1 < 2)", ""), Ok(Int(2)));
        assert!(
            eval_str("2147483647 + 1", "")
                .unwrap_err()
                .contains("must be known at compile time")
        );
        assert!(
            eval_str("N * 2", "\"N\": Param(ty: I32, default: 3)")
                .unwrap_err()
                .contains("runtime uniform")
        );
        assert!(eval_str("d * 2.0", "").unwrap_err().contains("`d` is not known at compile time"));
    }
}
