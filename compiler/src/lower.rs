//! Phase `lower`: compile-time params are substituted, series unrolled, expansions turned
//! into one concrete channel per basis term, `expand(f)` rewritten as
//! `constant + sum_i a_i(d) * lookup(B_i)` (Annen eq. 5.8), and passes put in execution
//! order. Expressions go into the hash-consed arena, which folds constants as it goes.

use crate::builtins::{Func, Input, SampleFn, Ty, constant};
use crate::check::{Checked, comp_index};
use crate::diag::{Diagnostic, Diagnostics, Phase};
use crate::front::ast::*;
use crate::front::expr::{BinOp, Expr, ExprKind, Literal};
use crate::ir::*;
use crate::resolve::{Item, Symbols};
use crate::span::Span;

/// Unrolling stops past this many terms in one series.
pub const MAX_SERIES: i64 = 4096;
/// Lowering stops past this many distinct expression nodes.
pub const MAX_NODES: usize = 1 << 20;

struct Lowerer<'s, 'a> {
    sym: &'s Symbols<'a>,
    arena: &'s mut Arena,
    locals: Vec<(String, H, bool)>,
    /// AST channel index -> IR channel id.
    channel_ids: &'s [ChannelId],
    /// IR expansions (by AST expansion index), for `expand`.
    expansions: &'s [IrExpansion],
    /// For a Shade pass: what its reads carry.
    shade_reads: Option<Vec<(Item, ResId)>>,
    const_only: bool,
}

type Lowered = (H, bool);

impl<'s, 'a> Lowerer<'s, 'a> {
    fn new(
        sym: &'s Symbols<'a>,
        arena: &'s mut Arena,
        channel_ids: &'s [ChannelId],
        expansions: &'s [IrExpansion],
        shade_reads: Option<Vec<(Item, ResId)>>,
        const_only: bool,
    ) -> Self {
        Lowerer {
            sym,
            arena,
            locals: vec![],
            channel_ids,
            expansions,
            shade_reads,
            const_only,
        }
    }

    fn err(span: Span, msg: impl Into<String>, label: impl Into<String>) -> Diagnostic {
        Diagnostic::error(Phase::Lower, msg).at(span, label)
    }

    /// An abstract integer literal takes the type its context asks for.
    fn coerce(&mut self, (h, abs): Lowered, to: Ty) -> H {
        if abs
            && matches!(to, Ty::F32 | Ty::Vec(_))
            && let Some(ConstValue::Int(v)) = self.arena.as_const(h)
        {
            return self.arena.f32(v as f64);
        }
        h
    }

    fn budget(&self, span: Span) -> Result<(), Diagnostic> {
        if self.arena.len() > MAX_NODES {
            return Err(Self::err(
                span,
                format!("the technique grows past {MAX_NODES} distinct operations after unrolling"),
                "while unrolling this",
            )
            .help("lower the series order or the filter sizes"));
        }
        Ok(())
    }

    fn expr(&mut self, e: &Expr) -> Result<Lowered, Diagnostic> {
        self.budget(e.span)?;
        Ok(match &e.kind {
            ExprKind::Lit(Literal::Int(v)) => {
                let v = i32::try_from(*v).map_err(|_| Self::err(e.span, "integer literal out of i32 range", "too large"))?;
                (self.arena.i32(v), true)
            }
            ExprKind::Lit(Literal::Float(v)) => (self.arena.f32(*v), false),
            ExprKind::Lit(Literal::Bool(b)) => (self.arena.add(Node::Bool(*b), Ty::Bool, e.span), false),
            ExprKind::Name(n) => self.name(n, e.span)?,
            ExprKind::Unary(op, a) => {
                let (h, abs) = self.expr(a)?;
                let ty = self.arena.ty(h);
                (self.arena.add(Node::Unary(*op, h), ty, e.span), abs)
            }
            ExprKind::Binary(op, a, b) => {
                let la = self.expr(a)?;
                let lb = self.expr(b)?;
                let (ta, tb) = (self.arena.ty(la.0), self.arena.ty(lb.0));
                let abs = la.1 && lb.1;
                let operand = if abs {
                    Ty::I32
                } else if la.1 {
                    tb
                } else if lb.1 {
                    ta
                } else {
                    // vector op scalar keeps the vector type
                    if matches!(ta, Ty::Vec(_)) { ta } else { tb }
                };
                let scalar_of = |t: Ty| if matches!(t, Ty::Vec(_)) { Ty::F32 } else { t };
                let ha = self.coerce(la, scalar_of(operand));
                let hb = self.coerce(lb, scalar_of(operand));
                let ty = if op.is_comparison() || op.is_logic() { Ty::Bool } else { operand };
                (self.arena.add(Node::Binary(*op, ha, hb), ty, e.span), abs && !op.is_comparison())
            }
            ExprKind::Call { name, args, .. } => self.call(name, args, e.span)?,
            ExprKind::Member(base, m) => {
                let (h, _) = self.expr(base)?;
                let comps: Vec<u8> = m.chars().map(|c| comp_index(c) as u8).collect();
                let ty = if comps.len() == 1 { Ty::F32 } else { Ty::Vec(comps.len() as u8) };
                // Swizzles of a constructor fold to its components.
                if let (Node::Call(Func::Vec2 | Func::Vec3 | Func::Vec4, parts), 1) = (self.arena.node(h).clone(), comps.len()) {
                    return Ok((parts[comps[0] as usize], false));
                }
                (self.arena.add(Node::Swizzle(h, comps), ty, e.span), false)
            }
            ExprKind::Let { name, value, body, .. } => {
                let (h, abs) = self.expr(value)?;
                self.locals.push((name.clone(), h, abs));
                let r = self.expr(body);
                self.locals.pop();
                r?
            }
            ExprKind::Sum { var, from, to, body, .. } => {
                let lo = self.const_int(from)?;
                let hi = self.const_int(to)?;
                if hi - lo + 1 > MAX_SERIES {
                    return Err(Self::err(
                        e.span,
                        format!("series of {} terms: at most {MAX_SERIES} unroll", hi - lo + 1),
                        "too long",
                    ));
                }
                let mut acc: Option<Lowered> = None;
                for k in lo..=hi {
                    let kh = self.arena.i32(k as i32);
                    self.locals.push((var.clone(), kh, false));
                    let term = self.expr(body);
                    self.locals.pop();
                    let term = term?;
                    acc = Some(match acc {
                        None => term,
                        Some(a) => {
                            let ty = if a.1 && term.1 {
                                Ty::I32
                            } else if a.1 {
                                self.arena.ty(term.0)
                            } else {
                                self.arena.ty(a.0)
                            };
                            let ha = self.coerce(a, ty);
                            let hb = self.coerce(term, ty);
                            (self.arena.add(Node::Binary(BinOp::Add, ha, hb), ty, e.span), a.1 && term.1)
                        }
                    });
                }
                match acc {
                    Some(a) => a,
                    None => (self.arena.i32(0), true),
                }
            }
        })
    }

    fn const_int(&mut self, e: &Expr) -> Result<i64, Diagnostic> {
        let (h, _) = self.expr(e)?;
        match self.arena.as_const(h) {
            Some(ConstValue::Int(v)) => Ok(v),
            _ => Err(Self::err(
                e.span,
                "series bounds must be integers known at compile time",
                "not a compile-time integer",
            )),
        }
    }

    fn name(&mut self, n: &str, span: Span) -> Result<Lowered, Diagnostic> {
        if let Some((_, h, abs)) = self.locals.iter().rev().find(|l| l.0 == n) {
            return Ok((*h, *abs));
        }
        if let Some((i, p)) = self.sym.param(n) {
            let v = self.sym.values[i].value;
            if self.const_only && !p.fixed {
                return Err(Diagnostic::error(
                    Phase::Check,
                    format!("param `{n}` is a runtime uniform, but this value is needed at compile time"),
                )
                .at(span, "not known at compile time")
                .also(p.name.span, "declared here")
                .help(format!("add `fixed: true` to param `{n}`")));
            }
            if p.fixed {
                return Ok(match v {
                    ConstValue::Int(x) => (self.arena.i32(x as i32), false),
                    ConstValue::Float(x) => (self.arena.f32(x), false),
                    ConstValue::Bool(b) => (self.arena.add(Node::Bool(b), Ty::Bool, span), false),
                });
            }
            return Ok((self.arena.add(Node::Param(i), Ty::from_scalar(p.ty.value), span), false));
        }
        if let Some(c) = constant(n) {
            return Ok((self.arena.f32(c), false));
        }
        if let Some(input) = Input::from_name(n) {
            if self.const_only {
                return Err(Self::err(span, format!("`{n}` is not known at compile time"), "a per-pixel input"));
            }
            return Ok((self.arena.add(Node::Input(input), input.ty(), span), false));
        }
        if let Some(&c) = self.sym.channels.get(n) {
            if self.const_only {
                return Err(Self::err(
                    span,
                    format!("channel `{n}` is not known at compile time"),
                    "a per-texel value",
                ));
            }
            return Ok((self.arena.add(Node::Channel(self.channel_ids[c]), Ty::F32, span), false));
        }
        Err(Self::err(span, format!("unknown name `{n}`"), "unknown"))
    }

    fn call(&mut self, name: &str, args: &[Expr], span: Span) -> Result<Lowered, Diagnostic> {
        if let Some((how, expand)) = SampleFn::from_name(name) {
            let Some(reads) = self.shade_reads.clone() else {
                return Err(Self::err(span, format!("`{name}` is only available in a Shade pass"), "here"));
            };
            let ExprKind::Name(target) = &args[0].kind else {
                return Err(Self::err(args[0].span, "expected a name", "here"));
            };
            let mut extra = Vec::new();
            for (a, want) in args[1..].iter().zip(how.extra_args()) {
                let l = self.expr(a)?;
                extra.push(self.coerce(l, *want));
            }
            let find = |item: Item| reads.iter().find(|(i, _)| *i == item).map(|(_, r)| *r);
            if expand {
                let e = self.sym.expansions[target.as_str()];
                let res = find(Item::Expansion(e))
                    .ok_or_else(|| Self::err(args[0].span, format!("`{target}` is not read by this pass"), "here"))?;
                let exp = self.expansions[e].clone();
                let mut acc = exp.constant;
                for (coeff, ch) in exp.terms {
                    let s = self.arena.add(
                        Node::Sample {
                            channel: ch,
                            resource: res,
                            how,
                            args: extra.clone(),
                        },
                        Ty::F32,
                        span,
                    );
                    let prod = self.arena.add(Node::Binary(BinOp::Mul, coeff, s), Ty::F32, span);
                    acc = self.arena.add(Node::Binary(BinOp::Add, acc, prod), Ty::F32, span);
                    self.budget(span)?;
                }
                return Ok((acc, false));
            }
            let c = self.sym.channels[target.as_str()];
            let res =
                find(Item::Channel(c)).ok_or_else(|| Self::err(args[0].span, format!("`{target}` is not read by this pass"), "here"))?;
            let ch = self.channel_ids[c];
            return Ok((
                self.arena.add(
                    Node::Sample {
                        channel: ch,
                        resource: res,
                        how,
                        args: extra,
                    },
                    Ty::F32,
                    span,
                ),
                false,
            ));
        }
        let f = Func::from_name(name).ok_or_else(|| Self::err(span, format!("unknown function `{name}`"), "here"))?;
        let lowered = args.iter().map(|a| self.expr(a)).collect::<Result<Vec<_>, _>>()?;
        let tys: Vec<Ty> = lowered
            .iter()
            .map(|(h, abs)| if *abs { Ty::AbstractInt } else { self.arena.ty(*h) })
            .collect();
        let ty = f.result(&tys).map_err(|m| Self::err(span, m, "here"))?;
        let all_abs = lowered.iter().all(|l| l.1);
        let arg_ty = |i: usize| f.arg_ty(i, &tys, ty);
        let hs: Vec<H> = lowered
            .into_iter()
            .enumerate()
            .map(|(i, l)| {
                let t = arg_ty(i);
                let scalar = if matches!(t, Ty::Vec(_)) && !matches!(self.arena.ty(l.0), Ty::Vec(_)) {
                    Ty::F32
                } else {
                    t
                };
                self.coerce(l, scalar)
            })
            .collect();
        // min/max/clamp/abs/sign of abstract integers stay abstract
        let abs = all_abs && f.keeps_abstract();
        let ty = if ty == Ty::AbstractInt { Ty::I32 } else { ty };
        Ok((self.arena.add(Node::Call(f, hs), ty, span), abs))
    }
}

/// Evaluate an expression that must be known at compile time (kernel sizes, series bounds).
pub fn const_eval(sym: &Symbols, e: &Expr) -> Result<ConstValue, Diagnostic> {
    let mut arena = Arena::default();
    let mut l = Lowerer::new(sym, &mut arena, &[], &[], None, true);
    let (h, _) = l.expr(e)?;
    arena.as_const(h).ok_or_else(|| {
        Diagnostic::error(Phase::Check, "this value must be known at compile time")
            .at(e.span, "depends on runtime values")
            .help("use literals and params with `fixed: true` only")
    })
}

pub fn lower(sym: &Symbols, checked: &Checked) -> Result<Ir, Diagnostics> {
    let t = sym.t;
    let mut arena = Arena::default();
    let params: Vec<IrParam> = t
        .params
        .iter()
        .enumerate()
        .map(|(i, p)| IrParam {
            name: p.name.value.clone(),
            name_span: p.name.span,
            ty: p.ty.value,
            value: sym.values[i].value,
            range: p.range.as_ref().map(|(lo, hi)| (lo.value, hi.value)),
            uniform: !p.fixed,
            doc: p.doc.clone(),
            span: p.span,
        })
        .collect();

    let mut channels: Vec<IrChannel> = t
        .channels
        .iter()
        .enumerate()
        .map(|(i, c)| IrChannel {
            name: c.name.value.clone(),
            precision: sym.channel_precision[i],
            precision_span: c.precision.span,
            precision_overridden: sym.channel_precision[i] != c.precision.value,
            value: None,
            origin: if c.value.is_some() { Origin::Declared } else { Origin::Depth },
            span: c.span,
        })
        .collect();
    let channel_ids: Vec<ChannelId> = (0..channels.len()).collect();

    // Channel values (map side).
    for (i, c) in t.channels.iter().enumerate() {
        if let Some(v) = &c.value {
            let mut l = Lowerer::new(sym, &mut arena, &channel_ids, &[], None, false);
            let lv = l.expr(v).map_err(Diagnostics::from)?;
            channels[i].value = Some(l.coerce(lv, Ty::F32));
        }
    }

    // Expansions: one channel per (term, k).
    let mut expansions = Vec::new();
    for (ei, e) in t.expansions.iter().enumerate() {
        let mut l = Lowerer::new(sym, &mut arena, &channel_ids, &[], None, false);
        let lo = l.const_int(&e.from).map_err(Diagnostics::from)?;
        let hi = l.const_int(&e.to).map_err(Diagnostics::from)?;
        if hi < lo {
            return Err(Diagnostic::error(
                Phase::Lower,
                format!("expansion `{}` has no terms: its index runs from {lo} to {hi}", e.name.value),
            )
            .at(e.from.span.join(e.to.span), "empty range")
            .into());
        }
        if hi - lo + 1 > MAX_SERIES {
            return Err(Diagnostic::error(
                Phase::Lower,
                format!("expansion `{}` has {} orders: at most {MAX_SERIES}", e.name.value, hi - lo + 1),
            )
            .at(e.to.span, "too many")
            .into());
        }
        let cl = l.expr(&e.constant).map_err(Diagnostics::from)?;
        let constant = l.coerce(cl, Ty::F32);
        let mut terms = Vec::new();
        let mut new_channels = Vec::new();
        for k in lo..=hi {
            let kh = l.arena.i32(k as i32);
            l.locals.push((e.index.value.clone(), kh, false));
            for (name, value) in &e.lets {
                let v = l.expr(value).map_err(Diagnostics::from)?;
                l.locals.push((name.value.clone(), v.0, v.1));
            }
            for (ti, term) in e.terms.iter().enumerate() {
                let c = l.expr(&term.coeff).map_err(Diagnostics::from)?;
                let coeff = l.coerce(c, Ty::F32);
                let b = l.expr(&term.basis).map_err(Diagnostics::from)?;
                let basis = l.coerce(b, Ty::F32);
                let id = channels.len() + new_channels.len();
                new_channels.push(IrChannel {
                    name: format!("{}_t{ti}_k{k}", e.name.value),
                    precision: sym.expansion_precision[ei],
                    precision_span: e.precision.span,
                    precision_overridden: sym.expansion_precision[ei] != e.precision.value,
                    value: Some(basis),
                    origin: Origin::Basis {
                        expansion: ei,
                        term: ti,
                        k,
                    },
                    span: term.span,
                });
                terms.push((coeff, id));
            }
            l.locals.clear();
        }
        channels.extend(new_channels);
        expansions.push(IrExpansion {
            name: e.name.value.clone(),
            constant,
            terms,
            span: e.span,
        });
    }

    // Resources and passes in execution order.
    let mut resources: Vec<IrResource> = Vec::new();
    let mut res_index = std::collections::HashMap::new();
    let mut passes = Vec::new();
    for &pi in &checked.order {
        let p = &t.passes[pi];
        let reads: Vec<ResId> = p.kind.reads().iter().map(|r| res_index[&r.value]).collect();
        let kind = match &p.kind {
            PassKind::Depth { view, .. } => IrPassKind::Depth { view: *view },
            PassKind::Map { .. } => IrPassKind::Map,
            PassKind::Filter { .. } => IrPassKind::Filter {
                kernel: checked.kernels[pi]
                    .clone()
                    .ok_or_else(|| Diagnostic::error(Phase::Lower, "filter kernel was not resolved").at(p.span, "here"))?,
            },
            PassKind::Mipmap { reduce, .. } => IrPassKind::Mipmap { reduce: *reduce },
            PassKind::SummedArea { .. } => IrPassKind::SummedArea,
            PassKind::Geometry {
                primitive, resolve, view, ..
            } => IrPassKind::Geometry {
                primitive: *primitive,
                resolve: *resolve,
                view: *view,
            },
            PassKind::Shade { reads: rnames, visibility } => {
                let mut shade_reads = Vec::new();
                for r in rnames {
                    let rid = res_index[&r.value];
                    for item in &checked.items[&r.value] {
                        shade_reads.push((*item, rid));
                    }
                }
                let mut l = Lowerer::new(sym, &mut arena, &channel_ids, &expansions, Some(shade_reads), false);
                let v = l.expr(visibility).map_err(Diagnostics::from)?;
                let v = l.coerce(v, Ty::F32);
                IrPassKind::Shade { visibility: v }
            }
        };
        let writes = p.kind.writes().map(|w| {
            let (mips, sat, slots) = match &p.kind {
                PassKind::Filter { .. } | PassKind::Mipmap { .. } | PassKind::SummedArea { .. } => {
                    let src = &resources[reads[0]];
                    let mips = matches!(p.kind, PassKind::Mipmap { .. });
                    let sat = matches!(p.kind, PassKind::SummedArea { .. });
                    (
                        mips,
                        sat,
                        src.slots
                            .iter()
                            .map(|s| Slot {
                                range: None,
                                place: None,
                                encode: Encode::IDENTITY,
                                ..s.clone()
                            })
                            .collect(),
                    )
                }
                _ => {
                    let mut slots = Vec::new();
                    for item in &checked.items[&w.value] {
                        let ids: Vec<ChannelId> = match item {
                            Item::Channel(c) => vec![channel_ids[*c]],
                            Item::Expansion(e) => expansions[*e].terms.iter().map(|(_, c)| *c).collect(),
                        };
                        for c in ids {
                            slots.push(Slot {
                                channel: c,
                                precision: channels[c].precision,
                                range: None,
                                encode: Encode::IDENTITY,
                                place: None,
                            });
                        }
                    }
                    (false, false, slots)
                }
            };
            let id = resources.len();
            resources.push(IrResource {
                name: w.value.clone(),
                slots,
                writer: passes.len(),
                mips,
                sat,
                span: w.span,
                live: true,
                textures: vec![],
            });
            res_index.insert(w.value.clone(), id);
            id
        });
        passes.push(IrPass {
            name: p.name.value.clone(),
            kind,
            reads,
            writes,
            span: p.span,
            live: true,
        });
    }

    Ok(Ir {
        technique: t.name.value.clone(),
        title: t.title.clone(),
        paper: t.paper.clone(),
        lights: t.lights.iter().map(|l| l.value).collect(),
        params,
        channels,
        expansions,
        resources,
        passes,
        arena,
        removed: vec![],
    })
}
