//! The typing rules of built-in functions (`Sig`): the argument types a call takes, the
//! type it returns and how abstract integer arguments are coerced, with WGSL's rules.

use super::Ty;

/// Join two operand types as WGSL does for abstract integers; `None` when they differ.
pub fn unify(a: Ty, b: Ty) -> Option<Ty> {
    match (a, b) {
        _ if a == b => Some(a),
        (Ty::AbstractInt, t @ (Ty::F32 | Ty::I32 | Ty::U32)) | (t @ (Ty::F32 | Ty::I32 | Ty::U32), Ty::AbstractInt) => Some(t),
        // scalar * vector broadcasts
        (Ty::Vec(n), Ty::F32 | Ty::AbstractInt) | (Ty::F32 | Ty::AbstractInt, Ty::Vec(n)) => Some(Ty::Vec(n)),
        _ => None,
    }
}

/// The typing rule of a function: which argument types it takes and what it returns,
/// with WGSL's rules for abstract integer literals and vectors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sig {
    /// f32 or vector arguments of one type (abstract integers become f32); the result
    /// has that type. Component-wise on vectors.
    Float,
    /// One number of any type (`abs`, `sign`); the result has its type and an abstract
    /// integer stays abstract.
    Numeric,
    /// Arguments of one numeric type (`min`, `max`, `clamp`); the result has that type
    /// and abstract integers stay abstract.
    SameNumeric,
    /// `select(f, t, cond)`: `f` and `t` of one type, `cond` a bool.
    Select,
    /// A conversion of a scalar (`f32`, `i32` or `bool`) to this type.
    Convert(Ty),
    /// A vector of this many f32 components.
    Construct(u8),
    /// f32 scalars only; the result is f32.
    Scalars,
    /// `length`: one vector (or f32); the result is f32.
    Length,
    /// `dot`: two vectors of one size; the result is f32.
    Dot,
    /// `div_or(num, den, eps, fallback)`: `num` and `den` f32 or vectors of one size, the
    /// result their type; `eps` and `fallback` that type or f32, which lowering splats.
    Guarded,
}

impl Sig {
    /// The call's shape in words, with `arity` parameters named as docs/language.md
    /// section 8.6 writes them (for diagnostics).
    pub fn describe(self, name: &str, arity: usize) -> String {
        let params = |names: &[&str]| format!("{name}({})", names[..arity.min(names.len())].join(", "));
        match self {
            Sig::Float => format!("{}: f32 or vectors of one size", params(&["x", "y", "z"])),
            Sig::Numeric => format!("{}: one number (f32, i32 or a vector)", params(&["x"])),
            Sig::SameNumeric => format!("{}: numbers of one type (f32, i32, u32 or vectors)", params(&["a", "b", "c"])),
            Sig::Select => "select(f, t, cond): `f` and `t` of one type, `cond` a bool".to_string(),
            Sig::Convert(_) => format!("{}: one scalar (f32, i32, u32 or bool)", params(&["x"])),
            Sig::Construct(n) => format!("{}: {n} f32 components", params(&["x", "y", "z", "w"])),
            Sig::Scalars => format!("{}: f32 scalars", params(&["a", "b", "c", "d"])),
            Sig::Length => format!("{}: one vector", params(&["v"])),
            Sig::Dot => format!("{}: two vectors of one size", params(&["a", "b"])),
            Sig::Guarded => format!(
                "{}: `num` and `den` f32 or vectors of one size; `eps` and `fallback` their type or f32",
                params(&["num", "den", "eps", "fallback"])
            ),
        }
    }

    /// Whether every argument must be a scalar (a vector is refused, not taken component
    /// by component): what the typer's help on a vector argument reads.
    pub fn takes_scalars(self) -> bool {
        match self {
            Sig::Scalars | Sig::Convert(_) | Sig::Construct(_) => true,
            Sig::Numeric | Sig::SameNumeric | Sig::Select | Sig::Length | Sig::Dot | Sig::Float | Sig::Guarded => false,
        }
    }

    pub(super) fn result(self, name: &str, args: &[Ty]) -> Result<Ty, String> {
        let same = |tys: &[Ty]| -> Option<Ty> { tys.iter().try_fold(tys[0], |acc, t| unify(acc, *t)) };
        match self {
            Sig::Numeric => match args[0] {
                t if t.is_numeric() => Ok(t.concrete()),
                t => Err(format!("`{name}` expects a number, found {t}")),
            },
            Sig::SameNumeric => match same(args) {
                Some(t) if t.is_arithmetic() => Ok(t.concrete()),
                _ => Err(format!("`{name}` expects arguments of one numeric type, found {}", list(args))),
            },
            Sig::Select => match (unify(args[0], args[1]), args[2]) {
                (Some(t), Ty::Bool) => Ok(t.concrete()),
                (None, _) => Err(format!("`select(f, t, cond)` needs `f` and `t` of one type, found {}", list(args))),
                (_, c) => Err(format!("`select(f, t, cond)` needs a bool condition, found {c}")),
            },
            Sig::Convert(to) => match args[0] {
                Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => Ok(to),
                t @ Ty::Vec(_) => Err(format!("`{name}` converts a scalar, found {t}")),
            },
            Sig::Construct(n) => {
                if args.iter().all(|t| matches!(t, Ty::F32 | Ty::AbstractInt)) {
                    Ok(Ty::Vec(n))
                } else {
                    Err(format!("`{name}` takes f32 components, found {}", list(args)))
                }
            }
            Sig::Length => match args[0] {
                Ty::Vec(_) | Ty::F32 | Ty::AbstractInt => Ok(Ty::F32),
                t @ (Ty::I32 | Ty::U32 | Ty::Bool) => Err(format!("`{name}` expects a vector, found {t}")),
            },
            Sig::Dot => match same(args) {
                Some(Ty::Vec(_)) => Ok(Ty::F32),
                Some(Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt) | None => {
                    Err(format!("`{name}` expects two vectors of one size, found {}", list(args)))
                }
            },
            Sig::Scalars => {
                if args.iter().all(|t| matches!(t, Ty::F32 | Ty::AbstractInt)) {
                    Ok(Ty::F32)
                } else {
                    Err(format!("`{name}` takes f32 arguments, found {}", list(args)))
                }
            }
            Sig::Float => match same(args) {
                Some(t) if t.is_float_like() => Ok(if t == Ty::AbstractInt { Ty::F32 } else { t }),
                _ => Err(format!("`{name}` expects f32 or vector arguments, found {}", list(args))),
            },
            Sig::Guarded => {
                let t = match same(&args[..2]) {
                    Some(t) if t.is_float_like() => {
                        if t == Ty::AbstractInt {
                            Ty::F32
                        } else {
                            t
                        }
                    }
                    _ => {
                        return Err(format!(
                            "`{name}` expects `num` and `den` of one type, f32 or a vector, found {}",
                            list(&args[..2])
                        ));
                    }
                };
                match args[2..].iter().find(|a| !matches!(a, Ty::F32 | Ty::AbstractInt) && **a != t) {
                    None => Ok(t),
                    Some(a) => Err(format!(
                        "`{name}` takes `eps` and `fallback` as f32 or the type of `num` ({t}), found {a}"
                    )),
                }
            }
        }
    }

    pub(super) fn arg_ty(self, i: usize, args: &[Ty], result: Ty) -> Ty {
        match self {
            Sig::Convert(_) => Ty::I32,
            Sig::Select if i == 2 => Ty::Bool,
            Sig::Select | Sig::SameNumeric | Sig::Numeric => result,
            Sig::Length | Sig::Dot => args.iter().copied().find(|t| matches!(t, Ty::Vec(_))).unwrap_or(Ty::F32),
            Sig::Construct(_) => Ty::F32,
            Sig::Float | Sig::Scalars => {
                if matches!(result, Ty::Vec(_)) {
                    result
                } else {
                    Ty::F32
                }
            }
            // num and den the result's type; eps and fallback as given (f32 splatted later)
            Sig::Guarded => {
                if i < 2 || matches!(args.get(i), Some(Ty::Vec(_))) {
                    result
                } else {
                    Ty::F32
                }
            }
        }
    }

    pub(super) fn keeps_abstract(self) -> bool {
        match self {
            Sig::Numeric | Sig::SameNumeric => true,
            Sig::Float | Sig::Select | Sig::Convert(_) | Sig::Construct(_) | Sig::Scalars | Sig::Length | Sig::Dot | Sig::Guarded => false,
        }
    }
}

fn list(args: &[Ty]) -> String {
    args.iter().map(|t| format!("`{t}`")).collect::<Vec<_>>().join(", ")
}
