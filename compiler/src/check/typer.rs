//! The expression typer of phase `check`: the type of every expression in its context
//! (a constant, an expansion's `let`, coefficient or basis function, a channel's value,
//! the visibility), what every name resolves to, where abstract integers settle, and
//! which side (map, receiver, geometry) each input read comes from, for the separability
//! and placement rules the graph checks apply. Series and function calls are checked as
//! they unroll and inline, within the limits of `consteval` and `front::expr`.

use crate::builtins::{AT_SAMPLE, Func, Input, SampleFn, Side, Ty, constant, unify};
use crate::consteval::{self, IntOp, IntSpans, MAX_SERIES, NotConst};
use crate::diag::{Diagnostic, Phase};
use crate::front::ast::*;
use crate::front::expr::{BinOp, Expr, ExprKind, Literal, UnOp};
use crate::front::parse::closest;
use crate::resolve::{Item, Symbols};
use crate::span::{Span, Spanned};
use crate::types::{Resolved, Types, comp_index};

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

/// Every name `e` reads (a superset of its free names: names bound inside it count too).
fn free_names<'e>(e: &'e Expr, out: &mut std::collections::HashSet<&'e str>) {
    match &e.kind {
        ExprKind::Lit(_) => {}
        ExprKind::Name(n) => {
            out.insert(n.as_str());
        }
        ExprKind::Unary(_, a) | ExprKind::Member(a, _) | ExprKind::Index { index: a, .. } => free_names(a, out),
        ExprKind::Binary(_, a, b) => {
            free_names(a, out);
            free_names(b, out);
        }
        ExprKind::Call { args, .. } => args.iter().for_each(|a| free_names(a, out)),
        ExprKind::Let { value, body, .. } => {
            free_names(value, out);
            free_names(body, out);
        }
        ExprKind::Sum { from, to, body, .. } => {
            free_names(from, out);
            free_names(to, out);
            free_names(body, out);
        }
        ExprKind::If { cond, then, els } => {
            free_names(cond, out);
            free_names(then, out);
            free_names(els, out);
        }
    }
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
            } => {
                if crate::builtins::is_reserved(var) {
                    return Err(Self::err(*var_span, format!("`{var}` is a built-in name"), "reserved"));
                }
                let mode = self.mode;
                self.mode = Mode::Const;
                for b in [from, to] {
                    let t = self.infer_as(b, Ty::I32);
                    match t {
                        Ok(Ty::I32 | Ty::AbstractInt) => {}
                        Ok(t) => {
                            self.mode = mode;
                            return Err(Self::err(
                                b.span,
                                format!("type mismatch: series bounds are integers, found {t}"),
                                format!("this is {t}"),
                            ));
                        }
                        Err(d) => {
                            self.mode = mode;
                            return Err(d);
                        }
                    }
                }
                self.mode = mode;
                // Nested series unroll, for each term of the enclosing series, the terms of
                // the inner one: counted exactly, term by term where a bound depends on an
                // enclosing series variable (`sum(j in 0..=i, ..)`), so that the limit holds
                // for the product however the bounds are written.
                let outer = self.envs.len() as i64;
                let (bounds, konst_bounds) = self.series_bounds(from, to);
                // an unknown bound counts one term here; lower checks it as it unrolls
                let counts: Vec<i64> = bounds.iter().map(|b| b.map_or(1, |(lo, hi)| (hi - lo + 1).max(0))).collect();
                let max = counts.iter().copied().max().unwrap_or(0);
                if max > MAX_SERIES {
                    return Err(Self::err(
                        e.span,
                        format!("series of {max} terms: at most {MAX_SERIES} unroll"),
                        "too long",
                    ));
                }
                let total: i64 = counts.iter().sum();
                if total > MAX_SERIES {
                    let label = if konst_bounds {
                        format!("{max} terms, inside series of {outer} terms in all")
                    } else {
                        let min = counts.iter().copied().min().unwrap_or(0);
                        format!("{min} to {max} terms (bounds that depend on an enclosing series), for each of {outer} enclosing terms")
                    };
                    return Err(Self::err(
                        e.span,
                        format!("nested series unroll {total} terms: at most {MAX_SERIES} in all"),
                        label,
                    )
                    .help("the terms of nested series multiply; lower the bounds"));
                }
                let mut inner: Vec<Vec<Option<i64>>> = Vec::with_capacity(total as usize);
                for (env, b) in self.envs.iter().zip(&bounds) {
                    match *b {
                        Some((lo, hi)) => inner.extend((lo..=hi).map(|k| {
                            let mut v = env.clone();
                            v.push(Some(k));
                            v
                        })),
                        None => {
                            let mut v = env.clone();
                            v.push(None);
                            inner.push(v);
                        }
                    }
                }
                let outer_envs = std::mem::replace(&mut self.envs, inner);
                self.locals.push(Local {
                    name: var.clone(),
                    ty: Ty::I32,
                    uses: vec![],
                    konst: true,
                    bind: Bind::Series,
                });
                let r = self.infer(body);
                self.envs = outer_envs;
                self.locals.pop();
                let t = r?;
                if !t.is_arithmetic() {
                    return Err(Self::err(
                        body.span,
                        format!("type mismatch: a series sums numbers, found {t}"),
                        format!("this is {t}"),
                    ));
                }
                Ok(t)
            }
        }
    }

    /// The locals in scope, each hiding any param of its name, with no value: for
    /// evaluating what does not depend on them.
    fn scope(&self) -> consteval::Env {
        self.locals[self.floor..].iter().map(|l| (l.name.clone(), None)).collect()
    }

    /// The bounds of a series `from..=to` for each term of the enclosing series (one per
    /// entry of `envs`; `None` where a bound cannot be evaluated here), and whether they are
    /// the same constants for all (bounds that use no local).
    fn series_bounds(&self, from: &Expr, to: &Expr) -> (Vec<Option<(i64, i64)>>, bool) {
        let eval = |env: &mut consteval::Env| match (consteval::eval(self.sym, from, env), consteval::eval(self.sym, to, env)) {
            (Ok(ConstValue::Int(lo)), Ok(ConstValue::Int(hi))) => Some((lo, hi)),
            _ => None,
        };
        if let Some(b) = eval(&mut self.scope()) {
            return (vec![Some(b); self.envs.len()], true);
        }
        // The locals the bounds use, through the `let`s they name.
        let mut needed = std::collections::HashSet::new();
        free_names(from, &mut needed);
        free_names(to, &mut needed);
        for l in self.locals[self.floor..].iter().rev() {
            if let (true, Bind::Let(x)) = (needed.contains(l.name.as_str()), &l.bind) {
                free_names(x, &mut needed);
            }
        }
        // What each needed local holds, in scope order: a `let` that depends on no series
        // variable is evaluated once here, the others once per enclosing term below.
        enum Slot<'x> {
            Known(Option<ConstValue>),
            Series(usize),
            Let(&'x Expr),
        }
        let mut plan: Vec<(&str, Slot)> = Vec::new();
        let mut once: consteval::Env = Vec::new();
        let mut dependent = std::collections::HashSet::new();
        let mut series = 0;
        for (li, l) in self.locals.iter().enumerate() {
            let name = l.name.as_str();
            let slot = match &l.bind {
                Bind::Series => {
                    series += 1;
                    Slot::Series(series - 1)
                }
                Bind::Let(x) => {
                    let mut uses = std::collections::HashSet::new();
                    free_names(x, &mut uses);
                    if uses.iter().any(|n| dependent.contains(n)) {
                        Slot::Let(x)
                    } else {
                        Slot::Known(consteval::eval(self.sym, x, &mut once).ok())
                    }
                }
                Bind::Other | Bind::Item(_) => Slot::Known(None),
            };
            match &slot {
                Slot::Known(v) => {
                    dependent.remove(name);
                    once.push((name.to_string(), *v));
                }
                Slot::Series(_) | Slot::Let(_) => {
                    dependent.insert(name);
                    once.push((name.to_string(), None));
                }
            }
            // a caller's locals (below the floor) are not in a function body's scope
            if needed.contains(name) && li >= self.floor {
                plan.push((name, slot));
            }
        }
        let bounds = self
            .envs
            .iter()
            .map(|env| {
                let mut c: consteval::Env = Vec::with_capacity(plan.len());
                for (name, slot) in &plan {
                    let v = match slot {
                        Slot::Known(v) => *v,
                        Slot::Series(i) => env[*i].map(ConstValue::Int),
                        Slot::Let(x) => consteval::eval(self.sym, x, &mut c).ok(),
                    };
                    c.push((name.to_string(), v));
                }
                eval(&mut c)
            })
            .collect();
        (bounds, false)
    }

    fn name(&mut self, e: &Expr, n: &str, span: Span) -> Result<Ty, Diagnostic> {
        let (ty, r) = self.resolve_name(n, span)?;
        self.types.set_name(e, r);
        Ok(ty)
    }

    fn resolve_name(&mut self, n: &str, span: Span) -> Result<(Ty, Resolved), Diagnostic> {
        if let Some(l) = self.locals[self.floor..].iter().rev().find(|l| l.name == n) {
            if let Bind::Item(item) = l.bind {
                let (what, named, example) = match item {
                    Item::Channel(c) => (
                        "channel",
                        &self.sym.t.channels[c].name.value,
                        format!("`sample({n})`, `nearest({n})`, `fetch({n}, dx, dy)`"),
                    ),
                    Item::Expansion(e) => (
                        "expansion",
                        &self.sym.t.expansions[e].name.value,
                        format!("`expand({n})`, `expand_width({n}, w)`"),
                    ),
                };
                return Err(Self::err(
                    span,
                    format!("`{n}` is a {what} parameter, not a value"),
                    format!("the {what} `{named}` here"),
                )
                .note(format!(
                    "a {what} parameter names the {what} its call passed; it is read only through a lookup"
                ))
                .help(format!(
                    "look it up, as {example}, or declare the parameter `F32` and pass the looked-up value"
                )));
            }
            let ty = l.ty;
            if !l.konst {
                if self.mode == Mode::Const {
                    return Err(Self::err(
                        span,
                        format!("`{n}` is not known at compile time"),
                        "bound to a value computed per pixel or texel",
                    )
                    .help("a value needed at compile time may use literals, params with `fixed: true` and series variables only"));
                }
                self.runtime += 1;
            }
            let uses: Vec<Use> = l
                .uses
                .iter()
                .map(|u| Use {
                    via: Some(u.via.unwrap_or(span)),
                    ..u.clone()
                })
                .collect();
            self.uses.extend(uses);
            return Ok((ty, Resolved::Local));
        }
        if let Some((i, p)) = self.sym.param(n) {
            if self.mode == Mode::Const && !p.fixed {
                return Err(Self::err(
                    span,
                    format!("param `{n}` is a runtime uniform, but this value is needed at compile time"),
                    "not known at compile time",
                )
                .also(p.name.span, "declared here")
                .help(format!("add `fixed: true` to param `{n}`")));
            }
            if !p.fixed {
                self.runtime += 1;
            }
            return Ok((Ty::from_scalar(p.ty.value), Resolved::Param(i)));
        }
        if let Some(c) = constant(n) {
            return Ok((Ty::F32, Resolved::Constant(c)));
        }
        if let Some(input) = Input::from_name(n) {
            if self.mode == Mode::Const {
                return Err(Self::err(span, format!("`{n}` is not known at compile time"), "a per-pixel input").note(input.doc()));
            }
            if input.per_sample() && !self.in_sample {
                return Err(Self::err(span, format!("`{n}` belongs to one light sample"), "outside `at_sample`")
                    .note(input.doc())
                    .help("use it inside `at_sample(k, ...)`"));
            }
            if input.side() != Side::Both {
                self.uses.push(Use {
                    name: n.to_string(),
                    side: input.side(),
                    span,
                    via: None,
                });
            }
            self.runtime += 1;
            return Ok((input.ty(), Resolved::Input(input)));
        }
        if let Some(&c) = self.sym.channels.get(n) {
            match self.mode {
                Mode::Shade => {
                    return Err(Self::err(
                        span,
                        format!("channel `{n}` must be looked up in a Shade pass"),
                        "a stored channel, not a value",
                    )
                    .help(format!(
                        "use `sample({n})`, `sample_lod({n}, lod)`, `sample_width({n}, w)`, `nearest({n})`, `fetch({n}, dx, dy)` or `sample_box({n}, wx, wy)`"
                    )));
                }
                Mode::Const => {
                    return Err(Self::err(
                        span,
                        format!("channel `{n}` is not known at compile time"),
                        "a per-texel value",
                    ));
                }
                Mode::Let | Mode::Coeff | Mode::Basis | Mode::ChannelValue => {
                    self.uses.push(Use {
                        name: n.to_string(),
                        side: Side::Map,
                        span,
                        via: None,
                    });
                    self.runtime += 1;
                    return Ok((Ty::F32, Resolved::Channel(c)));
                }
            }
        }
        if self.sym.expansions.contains_key(n) {
            return Err(Self::err(span, format!("expansion `{n}` is not a value"), "an expansion")
                .help(format!("evaluate it with `expand({n})` in the Shade pass")));
        }
        let names = self.sym.visible_names();
        let local_names: Vec<&str> = self.locals[self.floor..].iter().map(|l| l.name.as_str()).collect();
        let all: Vec<&str> = names.into_iter().chain(local_names).collect();
        let mut d = Self::err(span, format!("unknown name `{n}`"), "not a param, channel, input or binding");
        if let Some(s) = closest(n, &all) {
            d = d.help(format!("did you mean `{s}`?"));
        }
        Err(d)
    }

    /// `at_sample(k, body)`: k an integer known at compile time (a literal, a fixed param
    /// or a series variable), body any value, evaluated with the receiver seen from light
    /// sample k; in the Shade pass only, and not nested.
    /// `neighbour(ch, dx, dy)`: a channel of the map at a texel offset known at compile time,
    /// on the map side only (a Map pass's channel values and basis functions).
    fn neighbour(&mut self, name_span: Span, args: &'a [Expr], span: Span) -> Result<Ty, Diagnostic> {
        use crate::builtins::{MAX_NEIGHBOUR, NEIGHBOUR};
        if !matches!(self.mode, Mode::ChannelValue | Mode::Basis) {
            return Err(Self::err(
                name_span,
                format!("`{NEIGHBOUR}` reads the map around the texel being computed"),
                "not on the map side",
            )
            .note("it is available in channel values and basis functions, which Map passes compute per texel")
            .help("in a Shade pass, `fetch(ch, dx, dy)` reads texels around the receiver's"));
        }
        if args.len() != 3 {
            return Err(Self::err(
                span,
                format!(
                    "`{NEIGHBOUR}` takes 3 arguments (a channel and two texel offsets), found {}",
                    args.len()
                ),
                "wrong number of arguments",
            ));
        }
        let ExprKind::Name(ch) = &args[0].kind else {
            return Err(Self::err(
                args[0].span,
                format!("the first argument of `{NEIGHBOUR}` names a channel"),
                "expected a channel name",
            ));
        };
        // a function's `Channel` parameter names its argument's channel; any other local
        // of that name hides the channel
        match self.locals[self.floor..].iter().rev().find(|l| &l.name == ch).map(|l| &l.bind) {
            Some(Bind::Item(Item::Channel(_))) => {}
            Some(Bind::Item(Item::Expansion(_))) => {
                return Err(Self::err(
                    args[0].span,
                    format!("`{ch}` is an expansion parameter, but `{NEIGHBOUR}` reads one channel"),
                    "an expansion parameter",
                )
                .help("pass the channel itself, or evaluate the expansion term by term with `neighbour` of each channel"));
            }
            Some(_) => {
                return Err(Self::err(
                    args[0].span,
                    format!("`{ch}` here is a value, not a channel: the first argument of `{NEIGHBOUR}` names a channel"),
                    "a value",
                )
                .help("rename the `let` or parameter that hides the channel"));
            }
            None => {
                if !self.sym.channels.contains_key(ch) {
                    return Err(Self::err(args[0].span, format!("unknown channel `{ch}`"), "not a declared channel"));
                }
                self.infer(&args[0])?;
            }
        }
        let mode = self.mode;
        self.mode = Mode::Const;
        for a in &args[1..] {
            let t = self.infer_as(a, Ty::I32);
            if let Err(d) = t {
                self.mode = mode;
                return Err(d);
            }
            match t {
                Ok(Ty::I32 | Ty::AbstractInt) => {}
                Ok(t) => {
                    self.mode = mode;
                    return Err(Self::err(
                        a.span,
                        format!("type mismatch: a texel offset is an integer, found {t}"),
                        format!("this is {t}"),
                    ));
                }
                Err(_) => {}
            }
            let (known, _) = self.series_bounds(a, a);
            if let Some(k) = known.iter().flatten().map(|b| b.0).find(|k| k.abs() > MAX_NEIGHBOUR) {
                self.mode = mode;
                return Err(
                    Self::err(a.span, format!("offset {k} is farther than {MAX_NEIGHBOUR} texels"), "too far")
                        .help("a Map pass reads at most 31 texels away along each axis"),
                );
            }
        }
        self.mode = mode;
        Ok(Ty::F32)
    }

    /// `name[index]`: an element of a constant array, the index an integer known at compile
    /// time, within the array where its value is known here (lower checks the others as it
    /// unrolls).
    fn index(&mut self, name: &str, name_span: Span, index: &'a Expr) -> Result<Ty, Diagnostic> {
        let Some(&ai) = self.sym.arrays.get(name) else {
            let cands: Vec<&str> = self.sym.arrays.keys().map(String::as_str).collect();
            let mut d = Self::err(name_span, format!("`{name}` is not a constant array"), "indexed here")
                .note("only the technique's `arrays` can be indexed");
            if let Some(s) = closest(name, &cands) {
                d = d.help(format!("did you mean `{s}`?"));
            }
            return Err(d);
        };
        let a = &self.sym.t.arrays[ai];
        let mode = self.mode;
        self.mode = Mode::Const;
        let k = self.infer_as(index, Ty::I32);
        self.mode = mode;
        match k? {
            Ty::I32 | Ty::AbstractInt => {}
            t @ (Ty::F32 | Ty::U32 | Ty::Bool | Ty::Vec(_)) => {
                return Err(Self::err(
                    index.span,
                    format!("type mismatch: an array index is an i32, found {t}"),
                    format!("this is {t}"),
                ));
            }
        }
        let len = a.values.len() as i64;
        let (known, _) = self.series_bounds(index, index);
        if let Some(k) = known.iter().flatten().map(|b| b.0).find(|k| !(0..len).contains(k)) {
            return Err(Self::err(
                index.span,
                format!("index {k} is outside `{name}`, which has {len} elements"),
                "out of range",
            )
            .also(a.name.span, "declared here")
            .help(format!("indices run from 0 to {}", len - 1)));
        }
        Ok(a.ty.value)
    }

    fn at_sample(&mut self, name_span: Span, args: &'a [Expr], span: Span) -> Result<Ty, Diagnostic> {
        if self.mode != Mode::Shade {
            return Err(Self::err(
                name_span,
                format!("`{AT_SAMPLE}` is only available in a Shade pass"),
                "it picks a light sample's view of the receiver",
            ));
        }
        if self.in_sample {
            return Err(Self::err(name_span, format!("`{AT_SAMPLE}` inside `{AT_SAMPLE}`"), "nested").help("one sample's view at a time"));
        }
        if args.len() != 2 {
            return Err(Self::err(
                span,
                format!("`{AT_SAMPLE}` takes 2 arguments (a sample index and a value), found {}", args.len()),
                "wrong number of arguments",
            ));
        }
        let mode = self.mode;
        self.mode = Mode::Const;
        let k = self.infer_as(&args[0], Ty::I32);
        self.mode = mode;
        match k? {
            Ty::I32 | Ty::AbstractInt => {}
            t @ (Ty::F32 | Ty::U32 | Ty::Bool | Ty::Vec(_)) => {
                return Err(Self::err(
                    args[0].span,
                    format!("type mismatch: a sample index is an i32, found {t}"),
                    format!("this is {t}"),
                ));
            }
        }
        self.in_sample = true;
        let t = self.infer(&args[1]);
        self.in_sample = false;
        t
    }

    /// A call of the technique's function `fi`: its arguments against the parameters'
    /// types, then its body in the caller's context with only the parameters (bound to the
    /// arguments) as locals.
    fn call_function(&mut self, fi: usize, name_span: Span, args: &'a [Expr], span: Span) -> Result<Ty, Diagnostic> {
        let f = &self.sym.t.functions[fi];
        let name = f.name.value.as_str();
        let signature = || {
            let ps: Vec<String> = f.params.iter().map(|(p, t)| format!("{}: {}", p.value, t.value)).collect();
            format!("{name}({})", ps.join(", "))
        };
        if args.len() != f.params.len() {
            return Err(Self::err(
                span,
                format!("`{name}` takes {} argument(s), found {}", f.params.len(), args.len()),
                "wrong number of arguments",
            )
            .also(f.name.span, format!("declared here: {}", signature())));
        }
        if let Some(pos) = self.calling.iter().position(|&c| c == fi) {
            let chain: Vec<&str> = self.calling[pos..]
                .iter()
                .map(|&c| self.sym.t.functions[c].name.value.as_str())
                .chain(std::iter::once(name))
                .collect();
            return Err(Self::err(name_span, format!("recursive call of `{name}`"), "calls itself")
                .also(f.name.span, "declared here")
                .note(format!("calls: {}", chain.join(" -> ")))
                .help("functions are inlined at every call, so they cannot recurse; unroll it with `sum`"));
        }
        let nodes = {
            let mut n = 0usize;
            f.body.walk(&mut |_| n += 1);
            n
        };
        self.inlined += nodes;
        let limit = crate::front::expr::MAX_NODES as usize;
        if self.inlined > limit {
            return Err(Self::err(
                name_span,
                format!("calls of the technique's functions inline more than {limit} expression nodes here"),
                "inlined here",
            )
            .note("every call inlines its function's body; calls inside function bodies multiply")
            .help("call the functions fewer times, or bind a result with `let` and reuse it"));
        }
        // the arguments, in the caller's scope
        let mut bound = Vec::with_capacity(args.len());
        for (a, (p, want)) in args.iter().zip(&f.params) {
            let want = match want.value {
                ParamTy::Value(t) => Spanned::new(t, want.span),
                kind @ (ParamTy::Channel | ParamTy::Expansion) => {
                    let item = self.item_argument(a, kind == ParamTy::Expansion, name, p, &signature)?;
                    bound.push(Local {
                        name: p.value.clone(),
                        ty: Ty::F32,
                        uses: vec![],
                        konst: false,
                        bind: Bind::Item(item),
                    });
                    continue;
                }
            };
            let want = &want;
            let before = self.uses.len();
            let runtime = self.runtime;
            let t = self.infer(a)?;
            if unify(t, want.value) != Some(want.value) {
                return Err(Self::err(
                    a.span,
                    format!("type mismatch: parameter `{}` of `{name}` is {}, found {t}", p.value, want.value),
                    format!("this is {t}"),
                )
                .also(p.span, format!("declared here: {}", signature())));
            }
            // an abstract integer argument takes the parameter's scalar type
            if matches!(want.value, Ty::I32 | Ty::U32 | Ty::F32) {
                self.settle(a, want.value)?;
            }
            let uses = distinct_sites(self.uses.drain(before..));
            bound.push(Local {
                name: p.value.clone(),
                ty: want.value,
                uses,
                konst: self.runtime == runtime,
                bind: Bind::Other,
            });
        }
        // the body, seeing the parameters only
        let (floor, depth) = (self.floor, self.locals.len());
        self.floor = depth;
        self.locals.extend(bound);
        self.calling.push(fi);
        let r = self.infer(&f.body);
        self.calling.pop();
        self.locals.truncate(depth);
        self.floor = floor;
        r.map_err(|d| d.also(name_span, format!("in this call of `{name}`")))
    }

    /// The item a call passes for a `Channel` (or, with `expand`, `Expansion`) parameter `p`
    /// of function `fname`: a declared channel's name or the caller's own parameter of that
    /// kind, and in a Shade pass one its reads carry.
    fn item_argument(&self, a: &Expr, expand: bool, fname: &str, p: &Name, signature: &dyn Fn() -> String) -> Result<Item, Diagnostic> {
        let (what, a_what) = if expand {
            ("expansion", "an expansion")
        } else {
            ("channel", "a channel")
        };
        let names: Vec<&str> = if expand {
            self.sym.expansions.keys().map(String::as_str).collect()
        } else {
            self.sym.channels.keys().map(String::as_str).collect()
        };
        let refuse = |found: String, hint: Option<&str>| {
            let d = Self::err(
                a.span,
                format!("parameter `{}` of `{fname}` takes {a_what} by name, found {found}", p.value),
                format!("not a {what}"),
            )
            .also(p.span, format!("declared here: {}", signature()))
            .note(format!("calls are inlined: the body's lookups read the {what} named here"));
            match hint {
                Some(h) => d.help(format!("did you mean `{h}`?")),
                None if names.is_empty() => d.help(format!("the technique declares no {what}")),
                None => d.help(format!(
                    "pass the name of a {what}: {}",
                    names.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
                )),
            }
        };
        let ExprKind::Name(n) = &a.kind else {
            return Err(refuse("an expression".to_string(), None));
        };
        let item = if let Some(l) = self.locals[self.floor..].iter().rev().find(|l| &l.name == n) {
            match l.bind {
                Bind::Item(item @ Item::Channel(_)) if !expand => item,
                Bind::Item(item @ Item::Expansion(_)) if expand => item,
                Bind::Item(_) => {
                    let other = if expand { "a channel" } else { "an expansion" };
                    return Err(refuse(format!("`{n}`, {other} parameter"), None));
                }
                Bind::Series | Bind::Let(_) | Bind::Other => {
                    return Err(refuse(
                        format!("`{n}`, a value (a `let`, a series variable or a value parameter)"),
                        None,
                    ));
                }
            }
        } else if !expand && let Some(&c) = self.sym.channels.get(n) {
            Item::Channel(c)
        } else if expand && let Some(&e) = self.sym.expansions.get(n) {
            Item::Expansion(e)
        } else {
            let found = if self.sym.channels.contains_key(n) {
                format!("`{n}`, a channel")
            } else if self.sym.expansions.contains_key(n) {
                format!("`{n}`, an expansion")
            } else if self.sym.param(n).is_some() {
                format!("`{n}`, a param (a value)")
            } else if Input::from_name(n).is_some() || constant(n).is_some() {
                format!("`{n}`, a built-in value")
            } else {
                // an unknown name: perhaps a misspelt channel
                return Err(refuse(format!("`{n}`, which is not declared"), closest(n, &names)));
            };
            return Err(refuse(found, None));
        };
        if self.mode == Mode::Shade
            && let Some(avail) = &self.available
            && !avail.iter().any(|(i, _, _)| *i == item)
        {
            let real = self.item_name(item);
            return Err(Self::err(
                a.span,
                format!("`{real}` is not carried by any resource this Shade pass reads"),
                format!("passed to `{}` of `{fname}`, whose body looks it up", p.value),
            )
            .help(self.carriers_help(item)));
        }
        Ok(item)
    }

    /// `NAME_tI_kK`, the name of an expansion's unrolled channel (term I at index value K):
    /// the expansion's name, I and K, where NAME is a declared expansion.
    fn basis_channel<'n>(&self, name: &'n str) -> Option<(&'n str, usize, i64)> {
        let (rest, k) = name.rsplit_once("_k")?;
        let (e, term) = rest.rsplit_once("_t")?;
        let (term, k) = (term.parse().ok()?, k.parse().ok()?);
        self.sym.expansions.contains_key(e).then_some((e, term, k))
    }

    /// The help for a channel or expansion the Shade pass does not read: the resources
    /// that carry it, to add to its `reads`, or that no pass writes it.
    fn carriers_help(&self, item: Item) -> String {
        let carriers: Vec<String> = self
            .carriers
            .iter()
            .filter(|(i, _)| *i == item)
            .map(|(_, r)| format!("`{r}`"))
            .collect();
        if carriers.is_empty() {
            "no pass writes it: list it in the `channels` of a Map, Geometry or Depth pass".to_string()
        } else {
            format!("add {} (which carries it) to the Shade pass's `reads`", carriers.join(" or "))
        }
    }

    fn item_name(&self, item: Item) -> &'a str {
        match item {
            Item::Channel(c) => &self.sym.t.channels[c].name.value,
            Item::Expansion(e) => &self.sym.t.expansions[e].name.value,
        }
    }

    fn call(&mut self, name: &str, name_span: Span, args: &'a [Expr], span: Span) -> Result<Ty, Diagnostic> {
        if name == AT_SAMPLE {
            return self.at_sample(name_span, args, span);
        }
        if let Some(&fi) = self.sym.functions.get(name) {
            return self.call_function(fi, name_span, args, span);
        }
        if name == crate::builtins::NEIGHBOUR {
            return self.neighbour(name_span, args, span);
        }
        if let Some((how, expand)) = SampleFn::from_name(name) {
            if self.mode != Mode::Shade {
                return Err(Self::err(
                    name_span,
                    format!("`{name}` is only available in a Shade pass"),
                    "lookups need a receiver",
                )
                .note("channel values and basis functions are computed per texel from the channels of the map"));
            }
            // naga's uniformity analysis refuses implicit derivatives (`textureSample`) in
            // non-uniform control flow; a branch's arms are
            if how == SampleFn::Sample
                && let Some(&arm) = self.arms.last()
            {
                return Err(Self::err(
                    span,
                    format!("`{name}` takes the level of detail from screen-space derivatives, which are undefined inside a branch"),
                    "implicit level of detail",
                )
                .also(arm, "inside an arm of this `if`")
                .note("neighbouring pixels may take different arms, so the derivatives between them do not exist (WGSL's uniformity rules refuse it)")
                .help(format!(
                    "give the level explicitly (`{}`, `{}`), or look it up before the `if` with `let`",
                    SampleFn::SampleLod.name(expand),
                    SampleFn::SampleWidth.name(expand)
                )));
            }
            let extra = how.extra_args();
            if args.len() != extra.len() + 1 {
                return Err(Self::err(
                    span,
                    format!("`{name}` takes {} argument(s), found {}", extra.len() + 1, args.len()),
                    "wrong number of arguments",
                ));
            }
            let ExprKind::Name(target) = &args[0].kind else {
                return Err(Self::err(
                    args[0].span,
                    format!(
                        "the first argument of `{name}` names a {}",
                        if expand { "expansion" } else { "channel" }
                    ),
                    "expected a name",
                ));
            };
            // a function's `Channel` or `Expansion` parameter names its argument's item
            let alias = match self.locals[self.floor..].iter().rev().find(|l| &l.name == target).map(|l| &l.bind) {
                Some(Bind::Item(i)) => Some(*i),
                _ => None,
            };
            let item = match alias {
                Some(i @ Item::Channel(_)) if !expand => Some(i),
                Some(i @ Item::Expansion(_)) if expand => Some(i),
                Some(i) => {
                    let (is, other) = if expand {
                        ("a channel", SampleFn::name(how, false))
                    } else {
                        ("an expansion", SampleFn::name(how, true))
                    };
                    return Err(Self::err(
                        args[0].span,
                        format!(
                            "`{target}` is {is} parameter (`{}` here), but `{name}` takes {}",
                            self.item_name(i),
                            if expand { "an expansion" } else { "a channel" }
                        ),
                        format!("{is} parameter"),
                    )
                    .help(format!(
                        "look it up with `{other}`, the same lookup on {}",
                        if expand { "a channel" } else { "an expansion" }
                    )));
                }
                None if expand => self.sym.expansions.get(target).map(|&i| Item::Expansion(i)),
                None => self.sym.channels.get(target).map(|&i| Item::Channel(i)),
            };
            let real: &str = match (alias, item) {
                (Some(_), Some(i)) => self.item_name(i),
                _ => target,
            };
            let target = real;
            let Some(item) = item else {
                let what = if expand { "expansion" } else { "channel" };
                let cands: Vec<&str> = if expand {
                    self.sym.expansions.keys().map(String::as_str).collect()
                } else {
                    self.sym.channels.keys().map(String::as_str).collect()
                };
                let mut d = Self::err(args[0].span, format!("unknown {what} `{target}`"), format!("not a declared {what}"));
                if let (false, Some((e, term, k))) = (expand, self.basis_channel(target)) {
                    // the name `explain` lists for an expansion's unrolled channel
                    d = d
                        .note(format!(
                            "`{target}` is the channel the compiler makes for term {term} at {} = {k} of expansion `{e}`; the language names it only through the expansion",
                            self.sym.t.expansions[self.sym.expansions[e]].index.value
                        ))
                        .help(format!("read the expansion: `{}({e}, ...)`", SampleFn::name(how, true)));
                } else if let Some(s) = closest(target, &cands) {
                    d = d.help(format!("did you mean `{s}`?"));
                }
                return Err(d);
            };
            if let Some(avail) = &self.available {
                let holders: Vec<(&String, bool)> = avail.iter().filter(|(i, _, _)| *i == item).map(|(_, r, t)| (r, *t)).collect();
                if holders.is_empty() {
                    return Err(Self::err(
                        args[0].span,
                        format!("`{target}` is not carried by any resource this Shade pass reads"),
                        "not available here",
                    )
                    .help(self.carriers_help(item)));
                }
                if holders.len() > 1 {
                    return Err(Self::err(
                        args[0].span,
                        format!(
                            "`{target}` is carried by several resources this pass reads: {}",
                            holders.iter().map(|(h, _)| format!("`{h}`")).collect::<Vec<_>>().join(", ")
                        ),
                        "ambiguous",
                    )
                    .help("read only one version of it"));
                }
                let (holder, table) = holders[0];
                let sampled = self.per_sample.iter().any(|r| r == holder);
                if sampled != self.in_sample {
                    return Err(if sampled {
                        Self::err(
                            args[0].span,
                            format!("`{target}` is held once per light sample by `{holder}`: say which sample"),
                            "which sample's view?",
                        )
                        .help(format!(
                            "look it up inside `at_sample(k, ...)`, e.g. `sum(k in 0..=N - 1, at_sample(k, {name}({target}...)))`"
                        ))
                    } else {
                        Self::err(
                            args[0].span,
                            format!("`{target}` is seen from the light's centre, but this lookup is inside `at_sample`"),
                            "a centre-view channel",
                        )
                        .note("inside `at_sample(k, ..)` the receiver's uv and depth are those of sample k's view")
                        .help("look it up outside `at_sample`")
                    });
                }
                // the box lookups on a mip chain combine a Mean chain's texels
                if how.needs_mean_chain() && !table {
                    let writer = &self.sym.t.passes[self.sym.resources[holder.as_str()].writer];
                    match &writer.kind {
                        PassKind::Mipmap { reduce: Reduce::Mean, .. } => {}
                        PassKind::Mipmap { reduce, .. } => {
                            return Err(Self::err(
                                span,
                                format!("`{name}` takes a mean over a box, but `{holder}` is a {reduce:?} mip chain"),
                                "needs a Mean chain",
                            )
                            .also(writer.name.span, format!("`reduce: {reduce:?}` here"))
                            .note("a Max or Min chain keeps each block's extreme, not its mean: no combination of its texels is the box's mean")
                            .help(format!(
                                "read a Mean chain of `{target}` (a Mipmap pass with `reduce: Mean`), or bound the box with `nearest_level_at` on this one"
                            )));
                        }
                        other @ (PassKind::Depth { .. }
                        | PassKind::Map { .. }
                        | PassKind::Filter { .. }
                        | PassKind::SummedArea { .. }
                        | PassKind::Geometry { .. }
                        | PassKind::Shade { .. }) => {
                            return Err(
                                Self::err(span, format!("`{name}` reads a mip chain, but `{holder}` has none"), "no mip chain")
                                    .also(
                                        writer.name.span,
                                        format!("`{holder}` is written by this {} pass", other.kind_name()),
                                    )
                                    .note("the lookup reads the level where the box spans one to two texels")
                                    .help(format!("add a Mipmap pass with `reduce: Mean` over `{holder}` and read its output")),
                            );
                        }
                    }
                }
                if if table { !how.table_may_answer() } else { how.reads_table() } {
                    let d = if table {
                        Self::err(
                            span,
                            format!("`{name}` cannot read `{target}` from `{holder}`, a summed-area table"),
                            "summed-area tables are read by box lookups and `nearest`",
                        )
                        .help(format!(
                            "use `{}({target}, wx, wy)`, the mean over a box wx x wy wide in uv units (`{}` off the receiver), or `{}` for one texel's stored value",
                            if expand { "expand_box" } else { "sample_box" },
                            if expand { "expand_box_at" } else { "sample_box_at" },
                            if expand { "expand_nearest" } else { "nearest" },
                        ))
                    } else {
                        Self::err(
                            span,
                            format!("`{name}` needs a summed-area table, but `{holder}` is a texture"),
                            "box lookups read summed-area tables",
                        )
                        .help("add a SummedArea pass over the resource and read its output, or use `sample_width` on a mip chain")
                    };
                    return Err(d);
                }
            }
            for (a, want) in args[1..].iter().zip(extra) {
                let t = self.infer(a)?;
                if unify(t, *want) != Some(*want) {
                    return Err(Self::err(
                        a.span,
                        format!("type mismatch: `{name}` expects {want} here, found {t}"),
                        format!("this is {t}"),
                    ));
                }
                self.settle(a, *want)?;
            }
            self.runtime += 1;
            return Ok(Ty::F32);
        }
        let Some(f) = Func::from_name(name) else {
            let mut cands: Vec<&str> = Func::ALL.iter().filter(|f| **f != Func::Branch).map(|f| f.name()).collect();
            cands.extend(SampleFn::NAMES);
            cands.push("sum");
            let mut d = Self::err(name_span, format!("unknown function `{name}`"), "not a built-in function");
            if let Some(s) = closest(name, &cands) {
                d = d.help(format!("did you mean `{s}`?"));
            }
            return Err(d);
        };
        let d = f.desc();
        if args.len() != d.arity {
            return Err(Self::err(
                span,
                format!("`{name}` takes {} argument(s), found {}", d.arity, args.len()),
                "wrong number of arguments",
            )
            .note(d.sig.describe(name, d.arity)));
        }
        let tys = args.iter().map(|a| self.infer(a)).collect::<Result<Vec<_>, _>>()?;
        let ty = f.result(&tys).map_err(|m| {
            let mut diag = Self::err(span, format!("type mismatch: {m}"), "in this call");
            // a vector where the function takes scalars: offer a component (issue 51)
            if d.sig.takes_scalars() {
                let vectors: Vec<(&Expr, Ty)> = args
                    .iter()
                    .zip(&tys)
                    .filter(|(_, t)| matches!(t, Ty::Vec(_)))
                    .map(|(a, t)| (a, *t))
                    .collect();
                for (a, t) in &vectors {
                    diag = diag.also(a.span, format!("{t}: take one component, `.x` or `.y`"));
                }
                if let Some((a, _)) = vectors.first() {
                    let example = if let ExprKind::Name(n) = &a.kind {
                        format!("`{n}.x`")
                    } else {
                        "`(...).x`".to_string()
                    };
                    diag = diag.help(format!(
                        "`{name}` takes scalars: pass one component of each vector, such as {example}, and call it once per axis"
                    ));
                }
            }
            diag
        })?;
        // Abstract arguments take the type the builtin's signature gives each argument
        // (`Sig::arg_ty`): i32 or u32 where it computes in integers (conversions; min,
        // max, clamp, abs, sign and select of integers: `clamp(h, 1u, 90)` is u32
        // throughout), f32 otherwise.
        for (i, a) in args.iter().enumerate() {
            let to = match f.arg_ty(i, &tys, ty) {
                Ty::I32 | Ty::AbstractInt => Ty::I32,
                Ty::U32 => Ty::U32,
                Ty::F32 | Ty::Bool | Ty::Vec(_) => Ty::F32,
            };
            self.settle(a, to)?;
        }
        Ok(ty)
    }
}
