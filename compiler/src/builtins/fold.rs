//! Calls of built-in functions on constants, evaluated at compile time by their
//! descriptor's `Fold`: rounded to f32 as the GPU stores results, or exact for `interp`.

use super::{Fold, Func};
use crate::front::ast::ConstValue;

/// Evaluate a pure function on constants with f32 results rounded as the GPU would store
/// them; `None` where it is not folded (no finite value, or not evaluated at compile time).
pub fn fold_call(f: Func, v: &[ConstValue]) -> Option<ConstValue> {
    fold_with(f, v, finite_f32)
}

/// [`fold_call`] without rounding float results to f32 and keeping infinities and NaNs:
/// the CPU evaluation of `sshc verify` (`interp`), which is exact where the GPU is not.
pub fn fold_call_exact(f: Func, v: &[ConstValue]) -> Option<ConstValue> {
    fold_with(f, v, |x| Some(ConstValue::Float(x)))
}

fn fold_with(f: Func, v: &[ConstValue], finish: fn(f64) -> Option<ConstValue>) -> Option<ConstValue> {
    let floats = || -> Option<Vec<f64>> {
        v.iter()
            .map(|c| match c {
                ConstValue::Float(x) => Some(*x),
                ConstValue::Int(x) => Some(*x as f64),
                ConstValue::Uint(x) => Some(*x as f64),
                ConstValue::Bool(_) => None,
            })
            .collect()
    };
    match f.desc().fold {
        Fold::Never | Fold::Hook => None,
        Fold::Float(g) => finish(g(&floats()?)?),
        Fold::IntOrFloat(int, g) => {
            // u32 arguments (`min`, `max`, `clamp` of u32): their result is one of them
            if let Some(a) = v
                .iter()
                .map(|c| match c {
                    ConstValue::Uint(a) => Some(*a as i64),
                    ConstValue::Int(_) | ConstValue::Float(_) | ConstValue::Bool(_) => None,
                })
                .collect::<Option<Vec<i64>>>()
            {
                return int(&a).and_then(|r| u32::try_from(r).ok()).map(ConstValue::Uint);
            }
            let ints: Option<Vec<i64>> = v
                .iter()
                .map(|c| match c {
                    ConstValue::Int(a) => Some(*a),
                    ConstValue::Uint(_) | ConstValue::Float(_) | ConstValue::Bool(_) => None,
                })
                .collect();
            match ints {
                Some(a) => int(&a).map(ConstValue::Int),
                None => finish(g(&floats()?)?),
            }
        }
        Fold::Custom(g) => g(v),
    }
}

/// `x` rounded to f32, if finite.
pub(super) fn finite_f32(x: f64) -> Option<ConstValue> {
    x.is_finite().then_some(ConstValue::Float(x as f32 as f64))
}
