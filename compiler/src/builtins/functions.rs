//! The built-in functions (`Func`) and the types of their descriptor (`Builtin`: its
//! `Sig`, `Fold`, range rule, `Wgsl` and `Accuracy`), with what is read from it: names,
//! arity, result and argument types, and the WGSL of a call.

#[cfg(doc)]
use super::fold_call;
use super::{Sig, Ty};
use crate::front::ast::ConstValue;
use crate::interval::Interval;
use std::fmt;

/// Pure functions (WGSL built-ins plus `linstep`, `div_or`, `uv_width`). Everything about
/// one function is its [`Builtin`] descriptor (see [`Func::desc`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Func {
    Abs,
    Exp,
    Exp2,
    Log,
    Log2,
    Sqrt,
    InverseSqrt,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    /// Hyperbolic functions (WGSL `sinh`, `cosh`, `tanh`): exponential soft shadow
    /// mapping's warps written once (issue 51).
    Sinh,
    Cosh,
    Tanh,
    Floor,
    Ceil,
    Fract,
    Round,
    Trunc,
    Sign,
    Saturate,
    Pow,
    Min,
    Max,
    Atan2,
    Step,
    Clamp,
    Mix,
    Smoothstep,
    /// saturate((x - a) / (b - a)); used by VSM light-bleeding reduction.
    Linstep,
    Select,
    ToF32,
    ToI32,
    ToU32,
    Vec2,
    Vec3,
    Vec4,
    Length,
    Dot,
    /// `div_or(num, den, eps, fallback)`: num / den where |den| >= eps, else fallback
    /// (guarded division: no infinity or NaN reaches what follows).
    DivOr,
    /// `uv_width(len, dist)`: the shadow-map uv extent of a world length `len` lying across
    /// the light's view at view distance `dist` (perspective or orthographic light).
    UvWidth,
    /// `noise(x, y, k)`: a stated hash of the integers floor(x), floor(y), floor(k) to a
    /// float uniform in [0, 1) (PCG3D: Jarzynski & Olano 2020, "Hash functions for GPU
    /// rendering"), for per-pixel and per-frame random numbers: `noise(pixel.x, pixel.y,
    /// f32(frame))`.
    Noise,
    /// `if c { t } else { f }` (arguments `f`, `t`, `c`, as `select`): a real branch,
    /// whose arms the code generator emits inside an `if` (`back::expr`); evaluated,
    /// folded and bounded as `select`. Not callable by name: the parser reads `if`.
    Branch,
}

/// Everything the compiler knows about one built-in function. check types a call with
/// [`Builtin::sig`], lower coerces its arguments with it, the arena folds it with
/// [`Builtin::fold`] (through [`fold_call`]), analyse bounds it with [`Builtin::range`], codegen
/// writes it with [`Builtin::wgsl`], `interp` bounds its GPU error with [`Builtin::accuracy`].
pub struct Builtin {
    pub name: &'static str,
    pub arity: usize,
    pub sig: Sig,
    pub fold: Fold,
    /// The range of the result given the ranges of the arguments (interval analysis).
    pub range: fn(&[Interval]) -> Interval,
    pub wgsl: Wgsl,
    /// WGSL's accuracy of the function (what `interp::call_error` bounds a call with).
    pub accuracy: Accuracy,
}

/// WGSL's accuracy of a built-in function: how far the GPU's result may lie from the exact
/// value, beyond the f32 rounding of the result.
#[derive(Clone, Copy, Debug)]
pub enum Accuracy {
    /// Exact: one of its arguments, or an exact function of them.
    Exact,
    /// Rounded once, as any arithmetic result.
    Rounded,
    /// The error beyond the result's rounding, given the result's value and the arguments.
    Bound(fn(f64, &[f64]) -> f64),
}

/// How a call on constants is evaluated at compile time.
#[derive(Clone, Copy)]
pub enum Fold {
    /// Never folded.
    Never,
    /// Never folded; the evaluators' leaf hook gives its value (`interp`): it reads the
    /// frame (`uv_width`), or is the GPU's integer hash (`noise`).
    Hook,
    /// On the arguments as f64 (integers converted; booleans are not folded), the result
    /// rounded to f32; `None` or a result that is not finite is not folded.
    Float(fn(&[f64]) -> Option<f64>),
    /// Integer arithmetic when every argument is an integer, else as [`Fold::Float`].
    IntOrFloat(fn(&[i64]) -> Option<i64>, fn(&[f64]) -> Option<f64>),
    /// Any other rule, on the constants as they are.
    Custom(fn(&[ConstValue]) -> Option<ConstValue>),
}

/// How a call is written in WGSL, given the WGSL expressions of its arguments.
#[derive(Clone, Copy)]
pub enum Wgsl {
    /// `name(args)`: the WGSL built-in of the same name.
    Same,
    /// `callee(args)` with another callee (a type constructor such as `vec2<f32>`).
    Callee(&'static str),
    /// Any other expression of the arguments.
    Expr(fn(&[String]) -> String),
    /// An expression of the arguments that depends on the result's type.
    Typed(fn(&[String], Ty) -> String),
}

impl fmt::Debug for Builtin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Builtin")
            .field("name", &self.name)
            .field("arity", &self.arity)
            .field("sig", &self.sig)
            .finish_non_exhaustive()
    }
}

impl Func {
    /// The WGSL of a call of this function on `args` (WGSL expressions), as its
    /// descriptor says: the same name, another callee, or an expression of its own.
    /// `ty` is the call's result type.
    pub fn wgsl_call(self, args: &[String], ty: Ty) -> String {
        let d = self.desc();
        match d.wgsl {
            Wgsl::Same => format!("{}({})", d.name, args.join(", ")),
            Wgsl::Callee(callee) => format!("{callee}({})", args.join(", ")),
            Wgsl::Expr(write) => write(args),
            Wgsl::Typed(write) => write(args, ty),
        }
    }

    pub const ALL: [Func; 45] = [
        Func::Abs,
        Func::Exp,
        Func::Exp2,
        Func::Log,
        Func::Log2,
        Func::Sqrt,
        Func::InverseSqrt,
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Asin,
        Func::Acos,
        Func::Atan,
        Func::Sinh,
        Func::Cosh,
        Func::Tanh,
        Func::Floor,
        Func::Ceil,
        Func::Fract,
        Func::Round,
        Func::Trunc,
        Func::Sign,
        Func::Saturate,
        Func::Pow,
        Func::Min,
        Func::Max,
        Func::Atan2,
        Func::Step,
        Func::Clamp,
        Func::Mix,
        Func::Smoothstep,
        Func::Linstep,
        Func::Select,
        Func::ToF32,
        Func::ToI32,
        Func::ToU32,
        Func::Vec2,
        Func::Vec3,
        Func::Vec4,
        Func::Length,
        Func::Dot,
        Func::DivOr,
        Func::UvWidth,
        Func::Noise,
        Func::Branch,
    ];

    pub fn name(self) -> &'static str {
        self.desc().name
    }

    pub fn from_name(n: &str) -> Option<Func> {
        Func::ALL.into_iter().find(|f| f.name() == n)
    }

    pub fn arity(self) -> usize {
        self.desc().arity
    }

    /// Result type for these argument types, or a message saying what was expected.
    pub fn result(self, args: &[Ty]) -> Result<Ty, String> {
        let d = self.desc();
        if args.len() != d.arity {
            return Err(format!("`{}` takes {} argument(s), found {}", d.name, d.arity, args.len()));
        }
        d.sig.result(d.name, args)
    }

    /// The type argument `i` is coerced to (abstract integer literals become it), given
    /// the argument types and the call's result type from [`Func::result`].
    pub fn arg_ty(self, i: usize, args: &[Ty], result: Ty) -> Ty {
        self.desc().sig.arg_ty(i, args, result)
    }

    /// Whether a call on abstract integers stays an abstract integer (`min(1, 2)`).
    pub fn keeps_abstract(self) -> bool {
        self.desc().sig.keeps_abstract()
    }
}
