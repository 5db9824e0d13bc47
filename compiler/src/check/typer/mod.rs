//! The expression typer of phase `check`: the type of every expression in its context
//! (a constant, an expansion's `let`, coefficient or basis function, a channel's value,
//! the visibility), what every name resolves to, where abstract integers settle, and
//! which side (map, receiver, geometry) each input read comes from, for the separability
//! and placement rules the graph checks apply. Series and function calls are checked as
//! they unroll and inline, within the limits of `consteval` and `front::expr`.
//!
//! The files, one job each: this one holds the typer's state, the dispatch over expression
//! kinds and where abstract integers settle; `names.rs` resolves names and indexes constant
//! arrays; `calls.rs` checks calls of built-in and technique functions; `lookups.rs` the
//! lookups of stored channels (`sample`, `expand` and the like, `neighbour`, `at_sample`);
//! `series.rs` the series and their term limit.

use crate::builtins::{Func, Side, Ty, unify};
use crate::consteval::{self, IntOp, IntSpans, NotConst};
use crate::diag::{Diagnostic, Phase};
use crate::front::ast::ConstValue;
use crate::front::expr::{BinOp, Expr, ExprKind, Literal, UnOp};
use crate::resolve::{Item, Symbols};
use crate::span::Span;
use crate::types::{Types, comp_index};

mod calls;
mod lookups;
mod names;
mod series;

/// The context an expression is typed in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Known at compile time: literals, fixed params, constants.
    Const,
    /// An expansion's `let`: anything but sampling; sides are recorded.
    Let,
    Coeff,
    Basis,
    ChannelValue,
    Shade,
}

#[derive(Clone, Debug)]
pub struct Use {
    pub name: String,
    pub side: Side,
    pub span: Span,
    pub via: Option<Span>,
}

/// Each input site once (the first binding it was read through): a binding's value may read
/// another binding many times, and copying its uses per reference grows as 2^n along a chain
/// of bindings each read twice by the next.
pub(crate) fn distinct_sites(uses: impl IntoIterator<Item = Use>) -> Vec<Use> {
    let mut seen = std::collections::HashSet::new();
    uses.into_iter().filter(|u| seen.insert(u.span)).collect()
}

pub(crate) struct Local<'a> {
    pub(crate) name: String,
    pub(crate) ty: Ty,
    pub(crate) uses: Vec<Use>,
    /// Known at compile time (a series variable, an expansion index, or a `let` of
    /// compile-time values), so usable where a constant is needed.
    pub(crate) konst: bool,
    /// What the series limit needs to know of its value.
    pub(crate) bind: Bind<'a>,
}

/// How a local gets its value, for counting the terms of series whose bounds use it.
pub(crate) enum Bind<'a> {
    /// A series variable: one value per term of its series.
    Series,
    /// A `let` of compile-time values (evaluated with the series variables in scope).
    Let(&'a Expr),
    /// Anything else: not known to the series limit.
    Other,
    /// A function's `Channel` or `Expansion` parameter: the item its argument named, usable
    /// only as a lookup's first argument.
    Item(Item),
}

/// Type inference for one expression in one context; what it infers goes into `types`.
pub(crate) struct Typer<'s, 'a> {
    sym: &'s Symbols<'a>,
    types: &'s mut Types,
    /// Uses of values not known at compile time so far (to tell constant `let`s).
    pub(crate) runtime: usize,
    pub(crate) mode: Mode,
    pub(crate) locals: Vec<Local<'a>>,
    pub(crate) uses: Vec<Use>,
    /// For a Shade pass: channels and expansions its reads carry, and the resource of each.
    /// What a Shade pass's reads carry: (item, resource, whether a summed-area table).
    pub(crate) available: Option<Vec<(Item, String, bool)>>,
    /// For a Shade pass: the resources that hold one view per light sample.
    pub(crate) per_sample: Vec<String>,
    /// For a Shade pass: what every resource carries (to name where a lookup's channel is).
    pub(crate) carriers: Vec<(Item, String)>,
    /// Inside `at_sample(k, ..)`.
    in_sample: bool,
    /// The `if` expressions whose arms enclose the expression being checked, outermost
    /// first (lookups with implicit derivatives are refused inside them).
    arms: Vec<Span>,
    /// One entry per term the enclosing series unroll to (one empty entry outside any):
    /// the values of their variables, outermost first (`None` where a bound was not known).
    envs: Vec<Vec<Option<i64>>>,
    /// Locals below this index belong to the callers of the function bodies being checked:
    /// a body sees its parameters, not its caller's `let`s (series variables below it still
    /// count in `envs`, so nested series stay limited through calls).
    floor: usize,
    /// The functions whose bodies are being checked, outermost first (recursion is refused).
    calling: Vec<usize>,
    /// Expression nodes of function bodies checked so far in this context (each call
    /// inlines its body), limited to `front::expr::MAX_NODES`.
    inlined: usize,
}

impl<'s, 'a> Typer<'s, 'a> {
    pub(crate) fn new(sym: &'s Symbols<'a>, mode: Mode, types: &'s mut Types) -> Self {
        Typer {
            sym,
            types,
            runtime: 0,
            mode,
            locals: vec![],
            uses: vec![],
            available: None,
            per_sample: vec![],
            carriers: vec![],
            in_sample: false,
            arms: vec![],
            envs: vec![vec![]],
            floor: 0,
            calling: vec![],
            inlined: 0,
        }
    }

    pub(crate) fn err(span: Span, msg: impl Into<String>, label: impl Into<String>) -> Diagnostic {
        Diagnostic::error(Phase::Check, msg).at(span, label)
    }

    /// Infer the type of `e` where the context needs `want` (F32 or I32): an abstract
    /// integer is settled to it.
    pub(crate) fn infer_as(&mut self, e: &'a Expr, want: Ty) -> Result<Ty, Diagnostic> {
        let t = self.infer(e)?;
        self.settle(e, want)?;
        Ok(t)
    }

    /// Where an abstract integer expression meets a concrete type: its value must be an
    /// i32 (it is computed as one), and it converts to f32 if `to` is a float type.
    pub(crate) fn settle(&mut self, e: &Expr, to: Ty) -> Result<(), Diagnostic> {
        if self.types.ty(e) != Some(Ty::AbstractInt) {
            return Ok(());
        }
        match consteval::eval(self.sym, e, &mut self.scope()) {
            Ok(ConstValue::Int(v)) if to == Ty::U32 && u32::try_from(v).is_err() => {
                return Err(Self::err(e.span, format!("{v} is not a u32"), "used as a u32 here")
                    .note(format!("a u32 lies from 0 to {}", u32::MAX))
                    .help("write the bit pattern you mean as a u32 literal (`0xffffffffu`), or convert with `u32(...)`"));
            }
            // depends on a series variable: its value is known only when unrolled
            Ok(_) | Err(NotConst::Runtime(_)) => {}
            Err(NotConst::NoValue) => {
                return Err(Self::err(
                    e.span,
                    "this integer expression has no i32 value",
                    "overflows i32 or divides by zero",
                )
                .help("integer expressions are computed in i32; write float literals (`2.0`) for larger values"));
            }
        }
        if matches!(to, Ty::F32 | Ty::Vec(_)) {
            self.types.convert_to_f32(e);
        }
        if to == Ty::U32 {
            self.types.convert_to_u32(e);
        }
        Ok(())
    }

    fn infer(&mut self, e: &'a Expr) -> Result<Ty, Diagnostic> {
        let runtime = self.runtime;
        let t = self.infer_kind(e)?;
        self.types.set(e, t);
        // An integer operation on values known here (all but series variables, whose
        // values `lower` checks as it unrolls) must have an i32 value. Operands that read
        // a runtime value are not evaluated, except a divisor, which alone can be 0.
        if t.is_integer() {
            self.int_fault(e, self.runtime == runtime)?;
        }
        Ok(t)
    }

    /// [`consteval::int_fault`] for `e`, its operands evaluated without series variables.
    fn int_fault(&self, e: &Expr, all_known: bool) -> Result<(), Diagnostic> {
        let (op, operands, divisor): (IntOp, Vec<&Expr>, Span) = match &e.kind {
            ExprKind::Unary(UnOp::Neg, a) => (IntOp::Neg, vec![a], e.span),
            ExprKind::Binary(op @ (BinOp::Add | BinOp::Sub | BinOp::Mul | BinOp::Div | BinOp::Rem | BinOp::Shl | BinOp::Shr), a, b) => {
                (IntOp::Binary(*op), vec![a, b], b.span)
            }
            ExprKind::Call { name, args, .. } if Func::from_name(name) == Some(Func::Abs) => {
                (IntOp::Call(Func::Abs), args.iter().collect(), e.span)
            }
            ExprKind::Lit(_)
            | ExprKind::Name(_)
            | ExprKind::Unary(..)
            | ExprKind::Binary(..)
            | ExprKind::Call { .. }
            | ExprKind::Member(..)
            | ExprKind::Index { .. }
            | ExprKind::Let { .. }
            | ExprKind::If { .. }
            | ExprKind::Sum { .. } => return Ok(()),
        };
        // a divisor or a shift count may be known where the other operand is not
        let divides = matches!(op, IntOp::Binary(BinOp::Div | BinOp::Rem | BinOp::Shl | BinOp::Shr));
        if !all_known && !divides {
            return Ok(());
        }
        let vals: Vec<Option<ConstValue>> = operands
            .iter()
            .enumerate()
            .map(|(i, x)| {
                // a runtime dividend cannot be known; the divisor may still be
                if !all_known && i == 0 {
                    return None;
                }
                consteval::eval(self.sym, x, &mut self.scope()).ok()
            })
            .collect();
        match consteval::int_fault(Phase::Check, op, &vals, IntSpans { op: e.span, divisor }) {
            Some(d) => Err(d),
            None => Ok(()),
        }
    }

    /// `x << n`, `x >> n`: `x` an integer (its type is the result's), `n` a u32 (an
    /// abstract integer becomes one), as in WGSL.
    fn shift(&mut self, e: &Expr, op: BinOp, (a, ta): (&Expr, Ty), (b, tb): (&Expr, Ty)) -> Result<Ty, Diagnostic> {
        if !ta.is_integer() {
            return Err(Self::err(
                a.span,
                format!("type mismatch: `{}` shifts an integer (i32 or u32), found {ta}", op.symbol()),
                format!("this is {ta}"),
            )
            .also(e.span, "in this shift"));
        }
        if !matches!(tb, Ty::U32 | Ty::AbstractInt) {
            return Err(Self::err(
                b.span,
                format!("type mismatch: the count of `{}` is a u32, found {tb}", op.symbol()),
                format!("this is {tb}"),
            )
            .also(e.span, "in this shift")
            .help("convert it with `u32(...)`"));
        }
        self.settle(b, Ty::U32)?;
        Ok(ta)
    }

    fn infer_kind(&mut self, e: &'a Expr) -> Result<Ty, Diagnostic> {
        match &e.kind {
            ExprKind::Lit(Literal::Int(v)) => {
                if i32::try_from(*v).is_err() {
                    return Err(
                        Self::err(e.span, format!("integer literal {v} does not fit in i32"), "out of i32 range")
                            .note(format!("integers are i32: from {} to {}", i32::MIN, i32::MAX))
                            .help(if u32::try_from(*v).is_ok() {
                                format!("write it as a float literal (`{v}.0`), or as a u32 (`{v}u`)")
                            } else {
                                format!("write it as a float literal: `{v}.0`")
                            }),
                    );
                }
                Ok(Ty::AbstractInt)
            }
            ExprKind::Lit(Literal::Uint(_)) => Ok(Ty::U32),
            ExprKind::Lit(Literal::Float(_)) => Ok(Ty::F32),
            ExprKind::Lit(Literal::Bool(_)) => Ok(Ty::Bool),
            ExprKind::Name(n) => self.name(e, n, e.span),
            ExprKind::Unary(op, a) => {
                let t = self.infer(a)?;
                match (op, t) {
                    (UnOp::Neg, t) if t.is_numeric() => Ok(t),
                    (UnOp::Not, Ty::Bool) => Ok(Ty::Bool),
                    (UnOp::BitNot, t) if t.is_integer() => Ok(t),
                    (UnOp::Neg, Ty::U32) => Err(Self::err(e.span, "type mismatch: cannot negate u32", "this is u32")
                        .help("a u32 has no sign: write `0u - x` for its negation modulo 2^32, or convert with `i32(...)`")),
                    (UnOp::Neg, t) => Err(Self::err(
                        e.span,
                        format!("type mismatch: cannot negate {t}"),
                        format!("this is {t}"),
                    )),
                    (UnOp::BitNot, t) => Err(Self::err(
                        e.span,
                        format!("type mismatch: `~` needs an integer (i32 or u32), found {t}"),
                        format!("this is {t}"),
                    )),
                    (UnOp::Not, t) => Err(Self::err(
                        e.span,
                        format!("type mismatch: `!` needs a bool, found {t}"),
                        format!("this is {t}"),
                    )),
                }
            }
            ExprKind::Binary(op, a, b) => {
                let (ta, tb) = (self.infer(a)?, self.infer(b)?);
                let mismatch = || {
                    Self::err(
                        e.span,
                        format!("type mismatch: `{}` between {ta} and {tb}", op.symbol()),
                        format!("{ta} {} {tb}", op.symbol()),
                    )
                    .also(a.span, format!("{ta}"))
                    .also(b.span, format!("{tb}"))
                    .help(if matches!((ta, tb), (Ty::I32, Ty::F32) | (Ty::F32, Ty::I32)) {
                        "convert explicitly with `f32(...)` or `i32(...)`"
                    } else {
                        "both sides need one type"
                    })
                };
                if op.is_logic() {
                    return if ta == Ty::Bool && tb == Ty::Bool {
                        Ok(Ty::Bool)
                    } else {
                        Err(mismatch())
                    };
                }
                if op.is_shift() {
                    return self.shift(e, *op, (a, ta), (b, tb));
                }
                if op.is_bitwise() {
                    let t = unify(ta, tb).filter(|t| t.is_integer()).ok_or_else(|| {
                        mismatch()
                            .help("`&`, `|` and `^` take two integers of one type (i32 or u32); convert with `u32(...)` or `i32(...)`")
                    })?;
                    if t != Ty::AbstractInt {
                        self.settle(a, t)?;
                        self.settle(b, t)?;
                    }
                    return Ok(t);
                }
                let t = unify(ta, tb)
                    .filter(|t| t.is_arithmetic() || (t == &Ty::Bool && matches!(op, BinOp::Eq | BinOp::Ne)))
                    .ok_or_else(mismatch)?;
                // An abstract operand takes the other's type (a scalar beside a vector
                // broadcasts as f32); two abstract operands stay abstract, unless compared.
                if t != Ty::AbstractInt || op.is_comparison() {
                    let to = if matches!(t, Ty::Vec(_)) { Ty::F32 } else { t.concrete() };
                    self.settle(a, to)?;
                    self.settle(b, to)?;
                }
                if op.is_comparison() {
                    if matches!(t, Ty::Vec(_)) {
                        // one type, but vectors do not compare (issue 51: the help said
                        // "both sides need one type" of two vec2s)
                        let vector = if matches!(ta, Ty::Vec(_)) { a } else { b };
                        let (component, reduced) = if let ExprKind::Name(n) = &vector.kind {
                            (format!("`{n}.x`"), format!("`length({n})`, `max({n}.x, {n}.y)`"))
                        } else {
                            ("`(...).x`".to_string(), "`length(...)`, `max(v.x, v.y)`".to_string())
                        };
                        return Err(Self::err(
                            e.span,
                            format!("vectors do not compare: `{}` between {ta} and {tb}", op.symbol()),
                            format!("{ta} {} {tb}", op.symbol()),
                        )
                        .also(a.span, format!("{ta}"))
                        .also(b.span, format!("{tb}"))
                        .help(format!(
                            "compare one component at a time ({component}), or a scalar made of them ({reduced})"
                        )));
                    }
                    Ok(Ty::Bool)
                } else {
                    Ok(t)
                }
            }
            ExprKind::Call { name, name_span, args } => self.call(name, *name_span, args, e.span),
            ExprKind::Index { name, name_span, index } => self.index(name, *name_span, index),
            ExprKind::Member(base, m) => {
                let t = self.infer(base)?;
                let Ty::Vec(n) = t else {
                    let mut d = Self::err(
                        e.span,
                        format!("type mismatch: `.{m}` needs a vector, found {t}"),
                        format!("this is {t}"),
                    );
                    // `1.e-5`: a number, a point, then an exponent read as a member
                    if let ExprKind::Lit(Literal::Int(v)) = &base.kind
                        && m.starts_with(['e', 'E'])
                    {
                        d = d.help(format!(
                            "a float literal needs a digit after its point: write `{v}.0{m}...` (as in `1.0e-5`)"
                        ));
                    }
                    return Err(d);
                };
                let ok = !m.is_empty() && m.len() <= 4 && m.chars().all(|c| comp_index(c).is_some_and(|i| i < n as usize));
                if !ok {
                    return Err(Self::err(e.span, format!("`{t}` has no component `{m}`"), "unknown component")
                        .help("use x, y, z, w (or r, g, b, a) within the vector's size"));
                }
                Ok(if m.len() == 1 { Ty::F32 } else { Ty::Vec(m.len() as u8) })
            }
            ExprKind::Let {
                name,
                name_span,
                value,
                body,
            } => {
                if crate::builtins::is_reserved(name) {
                    return Err(Self::err(*name_span, format!("`{name}` is a built-in name"), "reserved").help("choose another name"));
                }
                let before = self.uses.len();
                let runtime = self.runtime;
                let t = self.infer_as(value, Ty::I32)?;
                let uses = distinct_sites(self.uses.drain(before..));
                let konst = self.runtime == runtime;
                self.locals.push(Local {
                    name: name.clone(),
                    ty: t.concrete(),
                    uses,
                    konst,
                    bind: if konst { Bind::Let(value) } else { Bind::Other },
                });
                let r = self.infer(body);
                self.locals.pop();
                r
            }
            ExprKind::If { cond, then, els } => {
                let c = self.infer(cond)?;
                if c != Ty::Bool {
                    return Err(Self::err(
                        cond.span,
                        format!("type mismatch: the condition of `if` is a bool, found {c}"),
                        format!("this is {c}"),
                    )
                    .help("compare it (`x > 0.0`), or use `select` to pick between values"));
                }
                self.arms.push(e.span);
                let arms = self.infer(then).and_then(|t| Ok((t, self.infer(els)?)));
                self.arms.pop();
                let (t, f) = arms?;
                // as `select`: one type (abstract integers take the other arm's), and two
                // abstract arms are i32
                let ty = match crate::builtins::unify(t, f) {
                    Some(u)
                        if !matches!(
                            (t, f),
                            (Ty::Vec(_), Ty::F32 | Ty::AbstractInt) | (Ty::F32 | Ty::AbstractInt, Ty::Vec(_))
                        ) =>
                    {
                        u.concrete()
                    }
                    _ => {
                        return Err(Self::err(
                            els.span,
                            format!("type mismatch: the arms of `if` have one type, found {t} and {f}"),
                            format!("this is {f}"),
                        )
                        .also(then.span, format!("this is {t}")));
                    }
                };
                let to = match ty {
                    Ty::U32 => Ty::U32,
                    Ty::F32 | Ty::Vec(_) => Ty::F32,
                    Ty::I32 | Ty::AbstractInt | Ty::Bool => Ty::I32,
                };
                self.settle(then, to)?;
                self.settle(els, to)?;
                Ok(ty)
            }
            ExprKind::Sum {
                var,
                var_span,
                from,
                to,
                body,
            } => self.series(e, var, *var_span, from, to, body),
        }
    }
}
