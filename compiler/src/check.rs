//! Phase `check`: the pass graph is a DAG whose order follows from reads and writes;
//! every read comes after a write; exactly one Shade pass; expressions are well typed in
//! their context; basis expansions are separable (Annen eq. 5.6: coefficients use
//! receiver-side inputs only, basis functions map-side inputs only); parameter values lie
//! in their ranges; filter sizes are odd and within bounds.

use crate::builtins::{Func, Input, SampleFn, Side, Ty, constant, unify};
use crate::diag::{Diagnostic, Diagnostics, Phase};
use crate::front::ast::*;
use crate::front::expr::{BinOp, Expr, ExprKind, Literal, UnOp};
use crate::front::parse::closest;
use crate::ir::IrKernel;
use crate::lower;
use crate::resolve::{Item, Symbols};
use crate::span::Span;
use indexmap::IndexMap;

/// The largest filter kernel, per axis.
pub const MAX_KERNEL: i64 = 63;

#[derive(Debug)]
pub struct Checked {
    /// Pass indices in execution order (a topological order of the read/write DAG,
    /// stable with respect to the order written).
    pub order: Vec<usize>,
    /// Channels and expansions carried by each resource.
    pub items: IndexMap<String, Vec<Item>>,
    /// The resolved kernel of each Filter pass (by pass index).
    pub kernels: Vec<Option<IrKernel>>,
}

pub fn check(sym: &Symbols) -> Result<Checked, Diagnostics> {
    let t = sym.t;
    let mut diags = Diagnostics::default();

    check_params(sym, &mut diags);

    // Exactly one Shade pass.
    let shades: Vec<&Pass> = t.passes.iter().filter(|p| matches!(p.kind, PassKind::Shade { .. })).collect();
    if shades.is_empty() {
        diags.push(
            Diagnostic::error(Phase::Check, "the technique has no Shade pass")
                .at(t.name.span, "nothing evaluates visibility for this technique")
                .help("add `Shade(name: \"shade\", reads: [...], visibility: \"...\")` to `passes`"),
        );
    }
    for extra in shades.iter().skip(1) {
        diags.push(
            Diagnostic::error(Phase::Check, "a technique has exactly one Shade pass")
                .at(extra.kind_span, "second Shade pass")
                .also(shades[0].kind_span, "first Shade pass"),
        );
    }

    // Reads must name written resources.
    for p in &t.passes {
        for r in p.kind.reads() {
            if !sym.resources.contains_key(&r.value) {
                let cands: Vec<&str> = sym.resources.keys().map(String::as_str).collect();
                let mut d = Diagnostic::error(
                    Phase::Check,
                    format!("pass `{}` reads `{}`, which no pass writes", p.name.value, r.value),
                )
                .at(r.span, "read before any write");
                if let Some(s) = closest(&r.value, &cands) {
                    d = d.help(format!("did you mean `{s}`?"));
                } else {
                    d = d.help(format!("add a pass with `writes: \"{}\"`", r.value));
                }
                diags.push(d);
            }
        }
    }
    diags.check()?;

    let order = topo_order(sym)?;

    // Channel items of every resource, in execution order.
    let mut items: IndexMap<String, Vec<Item>> = IndexMap::new();
    for &pi in &order {
        let p = &t.passes[pi];
        let list = match &p.kind {
            PassKind::Depth { channel, .. } => {
                let Some(&c) = sym.channels.get(&channel.value) else {
                    diags.push(
                        Diagnostic::error(
                            Phase::Check,
                            format!("a Depth pass writes one channel, but `{}` is an expansion", channel.value),
                        )
                        .at(channel.span, "not a channel")
                        .help("declare a channel without `value` in `channels` and name it here"),
                    );
                    continue;
                };
                if let Some(v) = &t.channels[c].value {
                    diags.push(
                        Diagnostic::error(
                            Phase::Check,
                            format!(
                                "channel `{}` is written by the Depth pass `{}` but also has a `value`",
                                channel.value, p.name.value
                            ),
                        )
                        .at(v.span, "a depth channel holds the rasterised depth")
                        .help("remove `value`, or let a Map pass compute this channel"),
                    );
                }
                vec![Item::Channel(c)]
            }
            PassKind::Map { channels, .. } | PassKind::Geometry { channels, .. } => channels
                .iter()
                .map(|n| match sym.expansions.get(&n.value) {
                    Some(&e) => Item::Expansion(e),
                    None => Item::Channel(sym.channels[&n.value]),
                })
                .collect(),
            PassKind::Filter { reads, .. } | PassKind::Mipmap { reads, .. } | PassKind::SummedArea { reads, .. } => {
                items.get(&reads.value).cloned().unwrap_or_default()
            }
            PassKind::Shade { .. } => continue,
        };
        if let Some(w) = p.kind.writes() {
            items.insert(w.value.clone(), list);
        }
    }

    // Expansions.
    for e in &t.expansions {
        check_expansion(sym, e, &mut diags);
    }
    // Channel values are computed per shadow-map texel.
    for c in &t.channels {
        if let Some(v) = &c.value {
            let mut ty = Typer::new(sym, Mode::ChannelValue);
            match ty.infer(v) {
                Ok(t) => expect_f32(t, v.span, "a channel value", &mut diags),
                Err(d) => diags.push(d),
            }
            for u in ty.uses.iter().filter(|u| u.side == Side::Receiver) {
                diags.push(side_error(
                    u,
                    "the value of channel",
                    &c.name.value,
                    "channel values are computed per shadow-map texel, before any receiver is known",
                ));
            }
        }
    }

    let mut kernels = vec![None; t.passes.len()];
    for &pi in &order {
        let p = &t.passes[pi];
        match &p.kind {
            PassKind::Map { reads, channels, .. } => {
                let carried: Vec<Item> = reads
                    .iter()
                    .flat_map(|r| items.get(&r.value).cloned().unwrap_or_default())
                    .collect();
                for n in channels {
                    let needed = map_inputs(sym, &n.value);
                    for (ch, span) in needed {
                        if !carried.contains(&Item::Channel(ch)) {
                            diags.push(
                                Diagnostic::error(
                                    Phase::Check,
                                    format!(
                                        "Map pass `{}` computes `{}` from channel `{}`, which none of its reads carries",
                                        p.name.value, n.value, t.channels[ch].name.value
                                    ),
                                )
                                .at(n.span, "computed here")
                                .also(span, "channel used here")
                                .help("add the resource holding it to `reads`"),
                            );
                        }
                    }
                    if let Some(&c) = sym.channels.get(&n.value)
                        && t.channels[c].value.is_none()
                    {
                        diags.push(
                            Diagnostic::error(
                                Phase::Check,
                                format!("channel `{}` has no `value` for Map pass `{}` to compute", n.value, p.name.value),
                            )
                            .at(n.span, "nothing to compute")
                            .also(t.channels[c].span, "declared here")
                            .help("give the channel a `value`, or write it with a Depth pass"),
                        );
                    }
                }
            }
            PassKind::Filter { kernel, .. } => match resolve_kernel(sym, kernel) {
                Ok(k) => kernels[pi] = Some(k),
                Err(d) => diags.push(d),
            },
            PassKind::Shade { reads, visibility } => {
                let carried: Vec<(Item, String, bool)> = reads
                    .iter()
                    .flat_map(|r| {
                        let table = matches!(t.passes[sym.resources[&r.value].writer].kind, PassKind::SummedArea { .. });
                        items
                            .get(&r.value)
                            .cloned()
                            .unwrap_or_default()
                            .into_iter()
                            .map(move |i| (i, r.value.clone(), table))
                    })
                    .collect();
                let mut ty = Typer::new(sym, Mode::Shade);
                ty.available = Some(carried);
                match ty.infer(visibility) {
                    Ok(t) => expect_f32(t, visibility.span, "the visibility", &mut diags),
                    Err(d) => diags.push(d),
                }
            }
            _ => {}
        }
    }
    diags.check()?;
    Ok(Checked { order, items, kernels })
}

fn expect_f32(t: Ty, span: Span, what: &str, diags: &mut Diagnostics) {
    if !matches!(t, Ty::F32 | Ty::AbstractInt) {
        diags.push(
            Diagnostic::error(Phase::Check, format!("type mismatch: {what} must be f32, found {t}"))
                .at(span, format!("this is {t}"))
                .help(if t == Ty::Bool {
                    "turn a condition into a number with `select(0.0, 1.0, cond)`"
                } else {
                    "reduce it to one f32"
                }),
        );
    }
}

/// Map-side channels that computing `name` (a channel or an expansion) reads, with the span of a use.
fn map_inputs(sym: &Symbols, name: &str) -> Vec<(usize, Span)> {
    let t = sym.t;
    let mut exprs: Vec<&Expr> = Vec::new();
    if let Some(&c) = sym.channels.get(name) {
        exprs.extend(t.channels[c].value.iter());
    } else if let Some(&e) = sym.expansions.get(name) {
        let e = &t.expansions[e];
        exprs.extend(e.terms.iter().map(|t| &t.basis));
        exprs.extend(e.lets.iter().map(|(_, v)| v));
    }
    let mut out: Vec<(usize, Span)> = Vec::new();
    for e in exprs {
        e.walk(&mut |x| {
            if let ExprKind::Name(n) = &x.kind
                && let Some(&c) = sym.channels.get(n)
                && !out.iter().any(|(o, _)| *o == c)
            {
                out.push((c, x.span));
            }
        });
    }
    out
}

fn check_params(sym: &Symbols, diags: &mut Diagnostics) {
    for (i, p) in sym.t.params.iter().enumerate() {
        let v = sym.values[i].value.as_f64();
        if let Some((lo, hi)) = &p.range {
            if lo.value > hi.value {
                diags.push(
                    Diagnostic::error(Phase::Check, format!("param `{}` has an empty range", p.name.value))
                        .at(lo.span.join(hi.span), "the low end exceeds the high end"),
                );
                continue;
            }
            if v < lo.value || v > hi.value {
                let origin = if sym.overridden[i] {
                    "set on the command line to"
                } else {
                    "defaults to"
                };
                diags.push(
                    Diagnostic::error(
                        Phase::Check,
                        format!(
                            "param `{}` is out of range: {origin} {}, but its range is [{}, {}]",
                            p.name.value, sym.values[i].value, lo.value, hi.value
                        ),
                    )
                    .at(
                        if sym.overridden[i] { lo.span.join(hi.span) } else { p.default.span },
                        if sym.overridden[i] {
                            "range declared here"
                        } else {
                            "outside the range"
                        },
                    )
                    .help(format!("choose a value of `{}` in [{}, {}]", p.name.value, lo.value, hi.value)),
                );
            }
        }
        if p.ty.value == ScalarTy::Bool && p.range.is_some() {
            diags.push(
                Diagnostic::error(Phase::Check, format!("bool param `{}` cannot have a range", p.name.value)).at(p.span, "remove `range`"),
            );
        }
    }
}

fn check_expansion(sym: &Symbols, e: &Expansion, diags: &mut Diagnostics) {
    let mut ty = Typer::new(sym, Mode::Const);
    for (bound, what) in [(&e.from, "start"), (&e.to, "end")] {
        match ty.infer(bound) {
            Ok(Ty::I32 | Ty::AbstractInt) => {}
            Ok(t) => diags.push(
                Diagnostic::error(
                    Phase::Check,
                    format!(
                        "type mismatch: the {what} of expansion `{}` must be an integer, found {t}",
                        e.name.value
                    ),
                )
                .at(bound.span, format!("this is {t}")),
            ),
            Err(d) => diags.push(d),
        }
    }
    ty.mode = Mode::Coeff;
    match ty.infer(&e.constant) {
        Ok(t) => expect_f32(t, e.constant.span, "the constant term", diags),
        Err(d) => diags.push(d),
    }
    for u in ty.uses.drain(..).filter(|u| u.side == Side::Map) {
        diags.push(side_error(
            &u,
            "the constant of expansion",
            &e.name.value,
            "the constant term is added per receiver",
        ));
    }
    ty.mode = Mode::Let;
    ty.locals.push(Local {
        name: e.index.value.clone(),
        ty: Ty::I32,
        uses: vec![],
    });
    for (name, value) in &e.lets {
        ty.uses.clear();
        match ty.infer(value) {
            Ok(t) => {
                let uses = std::mem::take(&mut ty.uses);
                ty.locals.push(Local {
                    name: name.value.clone(),
                    ty: t.concrete(),
                    uses,
                });
            }
            Err(d) => {
                diags.push(d);
                return;
            }
        }
    }
    for term in &e.terms {
        ty.mode = Mode::Coeff;
        match ty.infer(&term.coeff) {
            Ok(t) => expect_f32(t, term.coeff.span, "a coefficient", diags),
            Err(d) => diags.push(d),
        }
        for u in ty.uses.drain(..).filter(|u| u.side == Side::Map) {
            diags.push(
                side_error(
                    &u,
                    "a coefficient of expansion",
                    &e.name.value,
                    "coefficients a_i(d) are evaluated per receiver and may use receiver-side inputs only (Annen eq. 5.6)",
                )
                .help("move the factor that depends on the shadow map into `basis`"),
            );
        }
        ty.mode = Mode::Basis;
        match ty.infer(&term.basis) {
            Ok(t) => expect_f32(t, term.basis.span, "a basis function", diags),
            Err(d) => diags.push(d),
        }
        for u in ty.uses.drain(..).filter(|u| u.side == Side::Receiver) {
            diags.push(side_error(&u, "a basis function of expansion", &e.name.value, "basis functions B_i(z) are stored per shadow-map texel and prefiltered, so they may use map-side inputs only (Annen eq. 5.6)").help("move the factor that depends on the receiver into `coeff`"));
        }
    }
}

fn side_error(u: &Use, what: &str, owner: &str, why: &str) -> Diagnostic {
    let side = match u.side {
        Side::Receiver => "a receiver-side input",
        _ => "a map-side channel",
    };
    let mut d = Diagnostic::error(
        Phase::Check,
        format!("non-separable term: {what} `{owner}` uses `{}`, {side}", u.name),
    )
    .at(u.span, format!("`{}` is {side}", u.name))
    .note(why);
    if let Some(via) = u.via {
        d = d.also(via, "used through this binding");
    }
    d
}

fn resolve_kernel(sym: &Symbols, kernel: &crate::span::Spanned<Kernel>) -> Result<IrKernel, Diagnostic> {
    let size = |e: &Expr| -> Result<u32, Diagnostic> {
        const_typed(sym, e, &[Ty::I32, Ty::AbstractInt], "a filter size", "an integer")?;
        let v = lower::const_eval(sym, e)?;
        match v {
            ConstValue::Int(n) if (1..=MAX_KERNEL).contains(&n) && n % 2 == 1 => Ok(n as u32),
            ConstValue::Int(n) => Err(Diagnostic::error(
                Phase::Check,
                format!("bad filter size {n}: sizes are odd and between 1 and {MAX_KERNEL}"),
            )
            .at(e.span, format!("evaluates to {n}"))
            .note("an odd size keeps the kernel centred on the texel")
            .help(if n % 2 == 0 && n > 0 {
                format!("use {} or {}", n - 1, n + 1)
            } else {
                format!("use a size in 1..={MAX_KERNEL}")
            })),
            other => Err(Diagnostic::error(
                Phase::Check,
                format!("type mismatch: a filter size must be an integer, found {other}"),
            )
            .at(e.span, "not an integer")),
        }
    };
    Ok(match &kernel.value {
        Kernel::Box { size: s } => IrKernel::Box(size(s)?),
        Kernel::Max { size: s } => IrKernel::Max(size(s)?),
        Kernel::Min { size: s } => IrKernel::Min(size(s)?),
        Kernel::LoG => IrKernel::LoG,
        Kernel::Gaussian { size: s, sigma } => {
            let n = size(s)?;
            const_typed(sym, sigma, &[Ty::F32, Ty::AbstractInt], "a Gaussian sigma", "an f32")?;
            let sg = lower::const_eval(sym, sigma)?.as_f64();
            if !(sg > 0.0 && sg.is_finite()) {
                return Err(
                    Diagnostic::error(Phase::Check, format!("bad Gaussian sigma {sg}: it must be positive")).at(sigma.span, "not positive"),
                );
            }
            IrKernel::Gaussian(n, sg)
        }
    })
}

/// Type-check an expression that must be known at compile time.
fn const_typed(sym: &Symbols, e: &Expr, allowed: &[Ty], what: &str, want: &str) -> Result<(), Diagnostic> {
    let t = Typer::new(sym, Mode::Const).infer(e)?;
    if allowed.contains(&t) {
        Ok(())
    } else {
        Err(Typer::err(
            e.span,
            format!("type mismatch: {what} must be {want}, found {t}"),
            format!("this is {t}"),
        ))
    }
}

/// The execution order: Kahn's algorithm over writer -> reader edges, taking passes in the
/// order written when several are ready. A cycle is reported with its passes.
fn topo_order(sym: &Symbols) -> Result<Vec<usize>, Diagnostics> {
    let t = sym.t;
    let n = t.passes.len();
    let deps: Vec<Vec<usize>> = t
        .passes
        .iter()
        .map(|p| {
            p.kind
                .reads()
                .iter()
                .filter_map(|r| sym.resources.get(&r.value).map(|res| res.writer))
                .collect()
        })
        .collect();
    let mut done = vec![false; n];
    let mut order = Vec::with_capacity(n);
    while order.len() < n {
        let Some(next) = (0..n).find(|&i| !done[i] && deps[i].iter().all(|&d| done[d])) else {
            // Find one cycle among the remaining passes to report it.
            let start = (0..n).find(|&i| !done[i]).unwrap_or(0);
            let mut path = vec![start];
            let mut cur = start;
            while let Some(&nxt) = deps[cur].iter().find(|&&d| !done[d]) {
                if let Some(pos) = path.iter().position(|&p| p == nxt) {
                    path.drain(..pos);
                    break;
                }
                path.push(nxt);
                cur = nxt;
            }
            let names: Vec<&str> = path.iter().rev().map(|&i| t.passes[i].name.value.as_str()).collect();
            let first = &t.passes[path[0]];
            let mut d = Diagnostic::error(
                Phase::Check,
                format!("the passes form a cycle: {} -> {}", names.join(" -> "), names[0]),
            )
            .at(first.name.span, "this pass depends on its own output");
            for &i in path.iter().skip(1) {
                d = d.also(t.passes[i].name.span, "part of the cycle");
            }
            return Err(d
                .help("pass order follows reads and writes; one of these reads must come from a resource that does not depend on it")
                .into());
        };
        done[next] = true;
        order.push(next);
    }
    Ok(order)
}

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

struct Local {
    name: String,
    ty: Ty,
    uses: Vec<Use>,
}

/// Type inference for one expression in one context.
struct Typer<'s, 'a> {
    sym: &'s Symbols<'a>,
    mode: Mode,
    locals: Vec<Local>,
    uses: Vec<Use>,
    /// For a Shade pass: channels and expansions its reads carry, and the resource of each.
    /// What a Shade pass's reads carry: (item, resource, whether a summed-area table).
    available: Option<Vec<(Item, String, bool)>>,
}

impl<'s, 'a> Typer<'s, 'a> {
    fn new(sym: &'s Symbols<'a>, mode: Mode) -> Self {
        Typer {
            sym,
            mode,
            locals: vec![],
            uses: vec![],
            available: None,
        }
    }

    fn err(span: Span, msg: impl Into<String>, label: impl Into<String>) -> Diagnostic {
        Diagnostic::error(Phase::Check, msg).at(span, label)
    }

    fn infer(&mut self, e: &Expr) -> Result<Ty, Diagnostic> {
        match &e.kind {
            ExprKind::Lit(Literal::Int(_)) => Ok(Ty::AbstractInt),
            ExprKind::Lit(Literal::Float(_)) => Ok(Ty::F32),
            ExprKind::Lit(Literal::Bool(_)) => Ok(Ty::Bool),
            ExprKind::Name(n) => self.name(n, e.span),
            ExprKind::Unary(op, a) => {
                let t = self.infer(a)?;
                match (op, t) {
                    (UnOp::Neg, t) if t.is_numeric() => Ok(t),
                    (UnOp::Not, Ty::Bool) => Ok(Ty::Bool),
                    (UnOp::Neg, t) => Err(Self::err(
                        e.span,
                        format!("type mismatch: cannot negate {t}"),
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
                let t = unify(ta, tb)
                    .filter(|t| t.is_numeric() || (t == &Ty::Bool && matches!(op, BinOp::Eq | BinOp::Ne)))
                    .ok_or_else(mismatch)?;
                if op.is_comparison() {
                    if matches!(t, Ty::Vec(_)) {
                        return Err(mismatch());
                    }
                    Ok(Ty::Bool)
                } else {
                    Ok(t)
                }
            }
            ExprKind::Call { name, name_span, args } => self.call(name, *name_span, args, e.span),
            ExprKind::Member(base, m) => {
                let t = self.infer(base)?;
                let Ty::Vec(n) = t else {
                    return Err(Self::err(
                        e.span,
                        format!("type mismatch: `.{m}` needs a vector, found {t}"),
                        format!("this is {t}"),
                    ));
                };
                let ok = !m.is_empty()
                    && m.len() <= 4
                    && m.chars()
                        .all(|c| matches!(c, 'x' | 'y' | 'z' | 'w' | 'r' | 'g' | 'b' | 'a') && comp_index(c) < n as usize);
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
                let t = self.infer(value)?;
                let uses: Vec<Use> = self.uses.drain(before..).collect();
                self.locals.push(Local {
                    name: name.clone(),
                    ty: t.concrete(),
                    uses,
                });
                let r = self.infer(body);
                self.locals.pop();
                r
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
                    let t = self.infer(b)?;
                    if !matches!(t, Ty::I32 | Ty::AbstractInt) {
                        self.mode = mode;
                        return Err(Self::err(
                            b.span,
                            format!("type mismatch: series bounds are integers, found {t}"),
                            format!("this is {t}"),
                        ));
                    }
                }
                self.mode = mode;
                self.locals.push(Local {
                    name: var.clone(),
                    ty: Ty::I32,
                    uses: vec![],
                });
                let r = self.infer(body);
                self.locals.pop();
                let t = r?;
                if !t.is_numeric() {
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

    fn name(&mut self, n: &str, span: Span) -> Result<Ty, Diagnostic> {
        if let Some(l) = self.locals.iter().rev().find(|l| l.name == n) {
            let ty = l.ty;
            let uses: Vec<Use> = l
                .uses
                .iter()
                .map(|u| Use {
                    via: Some(u.via.unwrap_or(span)),
                    ..u.clone()
                })
                .collect();
            self.uses.extend(uses);
            return Ok(ty);
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
            let _ = i;
            return Ok(Ty::from_scalar(p.ty.value));
        }
        if constant(n).is_some() {
            return Ok(Ty::F32);
        }
        if let Some(input) = Input::from_name(n) {
            if self.mode == Mode::Const {
                return Err(Self::err(span, format!("`{n}` is not known at compile time"), "a per-pixel input").note(input.doc()));
            }
            if input.side() != Side::Both {
                self.uses.push(Use {
                    name: n.to_string(),
                    side: input.side(),
                    span,
                    via: None,
                });
            }
            return Ok(input.ty());
        }
        if self.sym.channels.contains_key(n) {
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
                _ => {
                    self.uses.push(Use {
                        name: n.to_string(),
                        side: Side::Map,
                        span,
                        via: None,
                    });
                    return Ok(Ty::F32);
                }
            }
        }
        if self.sym.expansions.contains_key(n) {
            return Err(Self::err(span, format!("expansion `{n}` is not a value"), "an expansion")
                .help(format!("evaluate it with `expand({n})` in the Shade pass")));
        }
        let names = self.sym.visible_names();
        let local_names: Vec<&str> = self.locals.iter().map(|l| l.name.as_str()).collect();
        let all: Vec<&str> = names.into_iter().chain(local_names).collect();
        let mut d = Self::err(span, format!("unknown name `{n}`"), "not a param, channel, input or binding");
        if let Some(s) = closest(n, &all) {
            d = d.help(format!("did you mean `{s}`?"));
        }
        Err(d)
    }

    fn call(&mut self, name: &str, name_span: Span, args: &[Expr], span: Span) -> Result<Ty, Diagnostic> {
        if let Some((how, expand)) = SampleFn::from_name(name) {
            if self.mode != Mode::Shade {
                return Err(Self::err(
                    name_span,
                    format!("`{name}` is only available in a Shade pass"),
                    "lookups need a receiver",
                )
                .note("channel values and basis functions are computed per texel from the channels of the map"));
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
            let item = if expand {
                self.sym.expansions.get(target).map(|&i| Item::Expansion(i))
            } else {
                self.sym.channels.get(target).map(|&i| Item::Channel(i))
            };
            let Some(item) = item else {
                let what = if expand { "expansion" } else { "channel" };
                let cands: Vec<&str> = if expand {
                    self.sym.expansions.keys().map(String::as_str).collect()
                } else {
                    self.sym.channels.keys().map(String::as_str).collect()
                };
                let mut d = Self::err(args[0].span, format!("unknown {what} `{target}`"), format!("not a declared {what}"));
                if let Some(s) = closest(target, &cands) {
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
                    .help("add the resource that holds it to the Shade pass's `reads`"));
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
                if table != (how == SampleFn::Box) {
                    let d = if table {
                        Self::err(
                            span,
                            format!("`{name}` cannot read `{target}` from `{holder}`, a summed-area table"),
                            "summed-area tables are read by box lookups",
                        )
                        .help(format!(
                            "use `{}({target}, wx, wy)`, the mean over a box wx x wy wide in uv units",
                            if expand { "expand_box" } else { "sample_box" }
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
            }
            return Ok(Ty::F32);
        }
        let Some(f) = Func::from_name(name) else {
            let mut cands: Vec<&str> = Func::ALL.iter().map(|f| f.name()).collect();
            cands.extend(SampleFn::NAMES);
            cands.push("sum");
            let mut d = Self::err(name_span, format!("unknown function `{name}`"), "not a built-in function");
            if let Some(s) = closest(name, &cands) {
                d = d.help(format!("did you mean `{s}`?"));
            }
            return Err(d);
        };
        let tys = args.iter().map(|a| self.infer(a)).collect::<Result<Vec<_>, _>>()?;
        f.result(&tys)
            .map_err(|m| Self::err(span, format!("type mismatch: {m}"), "in this call"))
    }
}

pub fn comp_index(c: char) -> usize {
    match c {
        'x' | 'r' => 0,
        'y' | 'g' => 1,
        'z' | 'b' => 2,
        _ => 3,
    }
}
