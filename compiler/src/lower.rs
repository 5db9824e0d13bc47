//! Phase `lower`: compile-time params are substituted, series unrolled, expansions turned
//! into one concrete channel per basis term, `expand(f)` rewritten as
//! `constant + sum_i a_i(d) * lookup(B_i)` (Annen eq. 5.8), and passes put in execution
//! order. Expressions go into the hash-consed arena, which folds constants as it goes.
//! Last, the precisions left to the compiler (`Auto`) are chosen on the channels' ranges:
//! the IR is final when `lower` returns.

use crate::builtins::{AT_SAMPLE, Func, SampleFn, Ty};
use crate::check::Checked;
use crate::consteval::{self, IntOp, IntSpans, MAX_SERIES};
use crate::diag::{Diagnostic, Diagnostics, Phase};
use crate::front::ast::*;
use crate::front::expr::{BinOp, Expr, ExprKind, Literal, UnOp};
use crate::handle::Table;
use crate::ir::*;
use crate::ranges::{F16_MAX, F16_MIN_NORMAL, fits, scene_slot_ranges, smallest_magnitude};
use crate::resolve::{Item, Symbols};
use crate::span::Span;
use crate::types::{Resolved, Types, comp_index};

/// Lowering stops past this many distinct expression nodes.
pub const MAX_NODES: usize = 1 << 20;

/// Lowers expressions that `check` has typed: types, name resolutions and the conversions
/// of abstract integers come from its [`Types`]; nothing is inferred again here.
struct Lowerer<'s, 'a> {
    sym: &'s Symbols<'a>,
    types: &'s Types,
    arena: &'s mut Arena,
    locals: Vec<(String, ExprId)>,
    /// The series variables being unrolled and their values, innermost last (for messages).
    series: Vec<(String, i64)>,
    /// AST channel index -> IR channel id.
    channel_ids: &'s [ChannelId],
    /// IR expansions (by AST expansion index), for `expand`.
    expansions: &'s Table<IrExpansion>,
    /// For a Shade pass: what its reads carry.
    shade_reads: Option<Vec<(Item, ResId)>>,
    /// Inside `at_sample(k, ..)`: the light sample k.
    view: Option<u8>,
    /// Light samples of the technique (`at_sample`'s index runs over 0..samples).
    samples: u32,
    /// Locals below this index are the callers' of the function bodies being inlined.
    floor: usize,
    /// The `Channel` and `Expansion` parameters of the function bodies being inlined: name,
    /// the item their argument named, and `locals.len()` where they were bound (a `let` of
    /// the body bound after one shadows it, as in `check`).
    aliases: Vec<(String, Item, usize)>,
    /// Aliases below this index are the callers'.
    alias_floor: usize,
}

/// An invariant `check` established does not hold: a compiler bug, reported as a value.
fn internal(span: Span, what: &str) -> Diagnostic {
    Diagnostic::error(Phase::Lower, format!("internal compiler error: {what}")).at(span, "here")
}

impl<'s, 'a> Lowerer<'s, 'a> {
    fn new(
        sym: &'s Symbols<'a>,
        types: &'s Types,
        arena: &'s mut Arena,
        channel_ids: &'s [ChannelId],
        expansions: &'s Table<IrExpansion>,
        shade_reads: Option<Vec<(Item, ResId)>>,
    ) -> Self {
        Lowerer {
            sym,
            types,
            arena,
            locals: vec![],
            series: vec![],
            channel_ids,
            expansions,
            shade_reads,
            view: None,
            samples: 1,
            floor: 0,
            aliases: vec![],
            alias_floor: 0,
        }
    }

    fn err(span: Span, msg: impl Into<String>, label: impl Into<String>) -> Diagnostic {
        Diagnostic::error(Phase::Lower, msg).at(span, label)
    }

    /// The concrete type `check` gave `e` (an abstract integer is computed as i32).
    fn ty(&self, e: &Expr) -> Result<Ty, Diagnostic> {
        self.types
            .ty(e)
            .map(Ty::concrete)
            .ok_or_else(|| internal(e.span, "expression not typed by check"))
    }

    /// The value of `e` (lowered to `h`) where it is used: an abstract integer that
    /// `check` converted to f32 becomes the f32 constant.
    fn coerce(&mut self, e: &Expr, h: ExprId) -> ExprId {
        if self.types.converts_to_f32(e)
            && let Some(ConstValue::Int(v)) = self.arena.as_const(h)
        {
            return self.arena.f32(v as f64);
        }
        // check has made sure the value is a u32
        if self.types.converts_to_u32(e)
            && let Some(ConstValue::Int(v)) = self.arena.as_const(h)
            && let Ok(v) = u32::try_from(v)
        {
            return self.arena.add(Node::U32(v), Ty::U32, e.span);
        }
        h
    }

    /// Lower `e` and convert it for its context.
    fn expr_coerced(&mut self, e: &Expr) -> Result<ExprId, Diagnostic> {
        let h = self.expr(e)?;
        Ok(self.coerce(e, h))
    }

    /// An integer operation whose operands unrolling made constants (a series variable
    /// among them: `check` has refused the others) must have an i32 value; WGSL would
    /// refuse the constant expression, so it is refused here, at the operation.
    fn int_fault(&self, op: IntOp, operands: &[ExprId], ty: Ty, span: Span, divisor: Span) -> Result<(), Diagnostic> {
        if !matches!(ty, Ty::I32 | Ty::U32) {
            return Ok(());
        }
        let vals: Vec<Option<ConstValue>> = operands.iter().map(|h| self.arena.as_const(*h)).collect();
        match consteval::int_fault(Phase::Lower, op, &vals, IntSpans { op: span, divisor }) {
            Some(d) => Err(self.in_series(d)),
            None => Ok(()),
        }
    }

    /// Name the values of the series variables in scope (the term being unrolled).
    fn in_series(&self, d: Diagnostic) -> Diagnostic {
        let vars: Vec<String> = self.series.iter().map(|(n, k)| format!("`{n}` = {k}")).collect();
        if vars.is_empty() {
            d
        } else {
            d.note(format!("in the term with {}", vars.join(", ")))
        }
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

    fn expr(&mut self, e: &Expr) -> Result<ExprId, Diagnostic> {
        self.budget(e.span)?;
        Ok(match &e.kind {
            ExprKind::Lit(Literal::Int(v)) => {
                let v = i32::try_from(*v).map_err(|_| internal(e.span, "integer literal out of i32 range"))?;
                self.arena.i32(v)
            }
            ExprKind::Lit(Literal::Uint(v)) => self.arena.add(Node::U32(*v), Ty::U32, e.span),
            ExprKind::Lit(Literal::Float(v)) => self.arena.f32(*v),
            ExprKind::Lit(Literal::Bool(b)) => self.arena.add(Node::Bool(*b), Ty::Bool, e.span),
            ExprKind::Name(n) => self.name(e, n)?,
            ExprKind::Unary(op, a) => {
                let h = self.expr(a)?;
                let ty = self.ty(e)?;
                if *op == UnOp::Neg {
                    self.int_fault(IntOp::Neg, &[h], ty, e.span, e.span)?;
                }
                self.arena.add(Node::Unary(*op, h), ty, e.span)
            }
            ExprKind::Binary(op, a, b) => {
                let ha = self.expr(a)?;
                let hb = self.expr(b)?;
                let ha = self.coerce(a, ha);
                let hb = self.coerce(b, hb);
                let ty = self.ty(e)?;
                self.int_fault(IntOp::Binary(*op), &[ha, hb], ty, e.span, b.span)?;
                self.arena.add(Node::Binary(*op, ha, hb), ty, e.span)
            }
            ExprKind::Call { name, args, .. } => self.call(name, args, e)?,
            ExprKind::Index { name, index, .. } => {
                let k = self.expr(index)?;
                let k = match self.arena.as_const(k) {
                    Some(ConstValue::Int(v)) => v,
                    _ => return Err(internal(index.span, "array index not known at compile time")),
                };
                let a = self
                    .sym
                    .arrays
                    .get(name)
                    .map(|&a| &self.sym.t.arrays[a])
                    .ok_or_else(|| internal(e.span, "unknown array"))?;
                let Some(v) = usize::try_from(k).ok().and_then(|k| a.values.get(k)) else {
                    return Err(self.in_series(
                        Self::err(
                            index.span,
                            format!("index {k} is outside `{name}`, which has {} elements", a.values.len()),
                            "out of range",
                        )
                        .also(a.name.span, "declared here"),
                    ));
                };
                // the element sees no local
                let (floor, depth) = (self.floor, self.locals.len());
                self.floor = depth;
                let r = self.expr_coerced(v);
                self.floor = floor;
                r?
            }
            ExprKind::Member(base, m) => {
                let h = self.expr(base)?;
                let comps: Vec<u8> = m
                    .chars()
                    .map(|c| comp_index(c).map(|i| i as u8))
                    .collect::<Option<_>>()
                    .ok_or_else(|| internal(e.span, "unknown vector component"))?;
                let ty = self.ty(e)?;
                // Swizzles of a constructor fold to its components.
                if let (Node::Call(Func::Vec2 | Func::Vec3 | Func::Vec4, parts), 1) = (self.arena.node(h).clone(), comps.len()) {
                    return Ok(parts[comps[0] as usize]);
                }
                self.arena.add(Node::Swizzle(h, comps), ty, e.span)
            }
            ExprKind::If { cond, then, els } => {
                let c = self.expr(cond)?;
                let ty = self.ty(e)?;
                // a condition known here (a series variable's test) takes one arm: the
                // other is not lowered (it may divide by zero where it is not taken)
                match self.arena.as_const(c) {
                    Some(ConstValue::Bool(true)) => self.expr_coerced(then)?,
                    Some(ConstValue::Bool(false)) => self.expr_coerced(els)?,
                    _ => {
                        let t = self.expr_coerced(then)?;
                        let f = self.expr_coerced(els)?;
                        self.arena.add(Node::Call(Func::Branch, vec![f, t, c]), ty, e.span)
                    }
                }
            }
            ExprKind::Let { name, value, body, .. } => {
                let h = self.expr_coerced(value)?;
                self.locals.push((name.clone(), h));
                let r = self.expr(body);
                self.locals.pop();
                r?
            }
            ExprKind::Sum { var, from, to, body, .. } => {
                let lo = self.const_int(from)?;
                let hi = self.const_int(to)?;
                if hi - lo + 1 > MAX_SERIES {
                    // bounds depending on an enclosing series are known only now
                    return Err(Self::err(
                        e.span,
                        format!("series of {} terms: at most {MAX_SERIES} unroll", hi - lo + 1),
                        "too long",
                    ));
                }
                let ty = self.ty(e)?;
                let mut acc: Option<ExprId> = None;
                for k in lo..=hi {
                    let kh = self.arena.i32(k as i32);
                    self.locals.push((var.clone(), kh));
                    self.series.push((var.clone(), k));
                    let term = self.expr(body);
                    self.series.pop();
                    self.locals.pop();
                    let term = term?;
                    acc = Some(match acc {
                        None => term,
                        Some(a) => {
                            // the running sum of an integer series must stay in i32 too
                            self.int_fault(IntOp::Binary(BinOp::Add), &[a, term], ty, e.span, e.span)?;
                            self.arena.add(Node::Binary(BinOp::Add, a, term), ty, e.span)
                        }
                    });
                }
                match acc {
                    Some(a) => a,
                    // An empty series is the zero of its type.
                    None => self.zero(ty, e.span),
                }
            }
        })
    }

    /// The zero of a type: `0`, `0.0`, `vecN(0.0)` (`false` for bool, which a sum never is).
    fn zero(&mut self, ty: Ty, span: Span) -> ExprId {
        match ty {
            Ty::F32 => self.arena.f32(0.0),
            Ty::I32 | Ty::AbstractInt => self.arena.i32(0),
            Ty::U32 => self.arena.add(Node::U32(0), Ty::U32, span),
            Ty::Bool => self.arena.add(Node::Bool(false), Ty::Bool, span),
            Ty::Vec(n) => {
                let z = self.arena.f32(0.0);
                let f = match n {
                    2 => Func::Vec2,
                    3 => Func::Vec3,
                    _ => Func::Vec4,
                };
                self.arena.add(Node::Call(f, vec![z; n as usize]), ty, span)
            }
        }
    }

    fn const_int(&mut self, e: &Expr) -> Result<i64, Diagnostic> {
        let h = self.expr(e)?;
        match self.arena.as_const(h) {
            Some(ConstValue::Int(v)) => Ok(v),
            _ => Err(internal(e.span, "series bounds must be integers known at compile time")),
        }
    }

    fn name(&mut self, e: &Expr, n: &str) -> Result<ExprId, Diagnostic> {
        let span = e.span;
        let r = self.types.name(e).ok_or_else(|| internal(span, "name not resolved by check"))?;
        Ok(match r {
            Resolved::Local => {
                let (_, h) = self.locals[self.floor..]
                    .iter()
                    .rev()
                    .find(|l| l.0 == n)
                    .ok_or_else(|| internal(span, "local binding not in scope"))?;
                *h
            }
            Resolved::Param(i) => {
                let p = &self.sym.t.params[i];
                if p.fixed {
                    match self.sym.values[i].value {
                        ConstValue::Int(x) => self.arena.i32(x as i32),
                        ConstValue::Uint(x) => self.arena.add(Node::U32(x), Ty::U32, span),
                        ConstValue::Float(x) => self.arena.f32(x),
                        ConstValue::Bool(b) => self.arena.add(Node::Bool(b), Ty::Bool, span),
                    }
                } else {
                    // IR params are the technique's, in order.
                    self.arena.add(Node::Param(ParamId::new(i)), Ty::from_scalar(p.ty.value), span)
                }
            }
            Resolved::Constant(c) => self.arena.f32(c),
            // specialised for a scene whose light makes it 0 (`SceneFacts::zero_inputs`)
            Resolved::Input(input)
                if self
                    .sym
                    .scene
                    .as_ref()
                    .is_some_and(|f| f.zero_inputs().contains(&input.desc().name)) =>
            {
                match input.ty() {
                    Ty::Vec(n) => {
                        let zero = self.arena.f32(0.0);
                        let f = match n {
                            2 => Func::Vec2,
                            3 => Func::Vec3,
                            _ => Func::Vec4,
                        };
                        self.arena.add(Node::Call(f, vec![zero; n as usize]), input.ty(), span)
                    }
                    Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => self.arena.f32(0.0),
                }
            }
            Resolved::Input(input) => {
                // inside `at_sample(k, ..)`, the inputs each view computes again are view k's
                let view = match input.desc().view {
                    crate::builtins::InView::Own { .. } | crate::builtins::InView::OnlyThere(_) => self.view,
                    crate::builtins::InView::Same => None,
                };
                self.arena.add(Node::Input(input, view), input.ty(), span)
            }
            Resolved::Channel(c) => self.arena.add(Node::Channel(self.channel_ids[c], [0, 0]), Ty::F32, span),
        })
    }

    /// The item a function body's `Channel` or `Expansion` parameter `n` names, unless a
    /// `let` of the body bound after it shadows it.
    fn alias(&self, n: &str) -> Option<Item> {
        let (_, item, at) = self.aliases[self.alias_floor..].iter().rev().find(|a| a.0 == n)?;
        if self.locals[(*at).max(self.floor)..].iter().any(|l| l.0 == n) {
            return None;
        }
        Some(*item)
    }

    fn call(&mut self, name: &str, args: &[Expr], e: &Expr) -> Result<ExprId, Diagnostic> {
        let span = e.span;
        if name == crate::builtins::NEIGHBOUR {
            // a declared channel, or a function's `Channel` parameter standing for one
            let param = if let ExprKind::Name(n) = &args[0].kind {
                self.alias(n)
            } else {
                None
            };
            let c = match (param, self.types.name(&args[0])) {
                (Some(Item::Channel(c)), _) | (None, Some(Resolved::Channel(c))) => c,
                _ => return Err(internal(args[0].span, "`neighbour` of something other than a channel")),
            };
            let mut offset = [0i32; 2];
            for (o, a) in offset.iter_mut().zip(&args[1..]) {
                let k = self.const_int(a)?;
                if k.abs() > crate::builtins::MAX_NEIGHBOUR {
                    return Err(self.in_series(Self::err(
                        a.span,
                        format!("offset {k} is farther than {} texels", crate::builtins::MAX_NEIGHBOUR),
                        "too far",
                    )));
                }
                *o = k as i32;
            }
            return Ok(self.arena.add(Node::Channel(self.channel_ids[c], offset), Ty::F32, span));
        }
        if let Some(&fi) = self.sym.functions.get(name) {
            // inlined: the arguments in the caller's scope, the body with only the
            // parameters bound to them (check refused recursion and bounded the size)
            let f = &self.sym.t.functions[fi];
            let mut bound = Vec::with_capacity(args.len());
            let mut items = Vec::new();
            let depth = self.locals.len();
            for (a, (p, ty)) in args.iter().zip(&f.params) {
                match ty.value {
                    ParamTy::Value(_) => bound.push((p.value.clone(), self.expr_coerced(a)?)),
                    // passed by name: the caller's parameter's item, or the declared one
                    ParamTy::Channel | ParamTy::Expansion => {
                        let ExprKind::Name(n) = &a.kind else {
                            return Err(internal(a.span, "a channel argument that is not a name"));
                        };
                        let item = match (self.alias(n), ty.value) {
                            (Some(i), _) => Some(i),
                            (None, ParamTy::Channel) => self.sym.channels.get(n.as_str()).map(|&c| Item::Channel(c)),
                            (None, _) => self.sym.expansions.get(n.as_str()).map(|&e| Item::Expansion(e)),
                        };
                        let item = item.ok_or_else(|| internal(a.span, "a channel argument not resolved by check"))?;
                        items.push((p.value.clone(), item, depth));
                    }
                }
            }
            let (floor, alias_floor, aliases) = (self.floor, self.alias_floor, self.aliases.len());
            self.floor = depth;
            self.alias_floor = aliases;
            self.aliases.extend(items);
            self.locals.extend(bound);
            let r = self.expr_coerced(&f.body);
            self.locals.truncate(depth);
            self.aliases.truncate(aliases);
            self.floor = floor;
            self.alias_floor = alias_floor;
            return r;
        }
        if name == AT_SAMPLE {
            // `at_sample(k, body)`: body with the receiver seen from light sample k
            let k = self.expr(&args[0])?;
            let k = match self.arena.as_const(k) {
                Some(ConstValue::Int(v)) => v,
                _ => return Err(internal(args[0].span, "`at_sample` index not known at compile time")),
            };
            if !(0..i64::from(self.samples)).contains(&k) {
                return Err(self.in_series(
                    Self::err(
                        args[0].span,
                        format!(
                            "light sample {k} does not exist: the technique has {} (`light_samples`)",
                            self.samples
                        ),
                        "sample index out of range",
                    )
                    .help(format!("sample indices run from 0 to {}", self.samples.saturating_sub(1))),
                ));
            }
            let outer = self.view.replace(k as u8);
            let r = self.expr_coerced(&args[1]);
            self.view = outer;
            return r;
        }
        if let Some((how, expand)) = SampleFn::from_name(name) {
            let Some(reads) = self.shade_reads.clone() else {
                return Err(internal(span, "lookup outside a Shade pass"));
            };
            let ExprKind::Name(target) = &args[0].kind else {
                return Err(internal(args[0].span, "lookup of something other than a name"));
            };
            let mut extra = Vec::new();
            for a in &args[1..] {
                extra.push(self.expr_coerced(a)?);
            }
            let find = |item: Item| reads.iter().find(|(i, _)| *i == item).map(|(_, r)| *r);
            let alias = self.alias(target);
            if expand {
                let e = match alias {
                    Some(Item::Expansion(e)) => e,
                    _ => self.sym.expansions[target.as_str()],
                };
                let res = find(Item::Expansion(e)).ok_or_else(|| internal(args[0].span, "expansion not read by this pass"))?;
                let exp = self.expansions[ExpansionId::new(e)].clone();
                let mut acc = exp.constant;
                for (coeff, ch) in exp.terms {
                    let s = self.arena.add(
                        Node::Sample {
                            channel: ch,
                            resource: res,
                            how,
                            args: extra.clone(),
                            view: self.view,
                        },
                        Ty::F32,
                        span,
                    );
                    let prod = self.arena.add(Node::Binary(BinOp::Mul, coeff, s), Ty::F32, span);
                    acc = self.arena.add(Node::Binary(BinOp::Add, acc, prod), Ty::F32, span);
                    self.budget(span)?;
                }
                return Ok(acc);
            }
            let c = match alias {
                Some(Item::Channel(c)) => c,
                _ => self.sym.channels[target.as_str()],
            };
            let res = find(Item::Channel(c)).ok_or_else(|| internal(args[0].span, "channel not read by this pass"))?;
            let ch = self.channel_ids[c];
            return Ok(self.arena.add(
                Node::Sample {
                    channel: ch,
                    resource: res,
                    how,
                    args: extra,
                    view: self.view,
                },
                Ty::F32,
                span,
            ));
        }
        let f = Func::from_name(name).ok_or_else(|| internal(span, "unknown function"))?;
        let lowered = args.iter().map(|a| self.expr(a)).collect::<Result<Vec<_>, _>>()?;
        let mut hs: Vec<ExprId> = lowered.into_iter().zip(args).map(|(h, a)| self.coerce(a, h)).collect();
        let ty = self.ty(e)?;
        // a guarded division of vectors takes a scalar eps or fallback in every component
        if let (crate::builtins::Sig::Guarded, Ty::Vec(k)) = (f.desc().sig, ty) {
            for h in &mut hs {
                if self.arena.ty(*h) != ty {
                    let splat = [Func::Vec2, Func::Vec3, Func::Vec4][usize::from(k).saturating_sub(2).min(2)];
                    *h = self.arena.add(Node::Call(splat, vec![*h; usize::from(k)]), ty, span);
                }
            }
        }
        self.int_fault(IntOp::Call(f), &hs, ty, span, span)?;
        Ok(self.arena.add(Node::Call(f, hs), ty, span))
    }
}

pub fn lower(sym: &Symbols, checked: &Checked) -> Result<Ir, Diagnostics> {
    let t = sym.t;
    let types = &checked.types;
    let mut arena = Arena::default();
    let params: Table<IrParam> = t
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

    let mut channels: Table<IrChannel> = t
        .channels
        .iter()
        .enumerate()
        .map(|(i, c)| IrChannel {
            name: c.name.value.clone(),
            precision: sym.channel_precision[i],
            precision_span: c.precision.span,
            precision_overridden: sym.channel_precision[i] != c.precision.value,
            precision_auto: sym.channel_auto[i],
            value: None,
            range: c.range.as_ref().map(|(lo, hi)| (lo.value, hi.value)),
            origin: if c.value.is_some() { Origin::Declared } else { Origin::Depth },
            span: c.span,
        })
        .collect();
    let channel_ids: Vec<ChannelId> = channels.handles().collect();

    let no_expansions = Table::default();
    // Channel values (map side).
    for (i, c) in t.channels.iter().enumerate() {
        if let Some(v) = &c.value {
            let mut l = Lowerer::new(sym, types, &mut arena, &channel_ids, &no_expansions, None);
            channels[channel_ids[i]].value = Some(l.expr_coerced(v).map_err(Diagnostics::from)?);
        }
    }

    // Expansions: one channel per (term, k).
    let mut expansions: Table<IrExpansion> = Table::default();
    for (ei, e) in t.expansions.iter().enumerate() {
        let mut l = Lowerer::new(sym, types, &mut arena, &channel_ids, &no_expansions, None);
        let lo = l.const_int(&e.from).map_err(Diagnostics::from)?;
        let hi = l.const_int(&e.to).map_err(Diagnostics::from)?;
        if hi < lo {
            // refused by check; reachable when a probe re-lowers with other param values
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
        let constant = l.expr_coerced(&e.constant).map_err(Diagnostics::from)?;
        let mut terms = Vec::new();
        let mut new_channels = Vec::new();
        for k in lo..=hi {
            let kh = l.arena.i32(k as i32);
            l.locals.push((e.index.value.clone(), kh));
            for (name, value) in &e.lets {
                let v = l.expr_coerced(value).map_err(Diagnostics::from)?;
                l.locals.push((name.value.clone(), v));
            }
            for (ti, term) in e.terms.iter().enumerate() {
                let coeff = l.expr_coerced(&term.coeff).map_err(Diagnostics::from)?;
                let basis = l.expr_coerced(&term.basis).map_err(Diagnostics::from)?;
                let id = ChannelId::new(channels.len() + new_channels.len());
                new_channels.push(IrChannel {
                    name: format!("{}_t{ti}_k{k}", e.name.value),
                    precision: sym.expansion_precision[ei],
                    precision_span: e.precision.span,
                    precision_overridden: sym.expansion_precision[ei] != e.precision.value,
                    precision_auto: sym.expansion_auto[ei],
                    value: Some(basis),
                    range: None,
                    origin: Origin::Basis {
                        expansion: ExpansionId::new(ei),
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
        expansions.append(IrExpansion {
            name: e.name.value.clone(),
            constant,
            terms,
            span: e.span,
        });
    }

    // Resources and passes in execution order.
    let mut resources: Table<IrResource> = Table::default();
    let mut res_index = std::collections::HashMap::new();
    let mut passes: Table<IrPass> = Table::default();
    let mut debug: Vec<IrDebug> = Vec::new();
    let mut debug_omitted: Vec<String> = Vec::new();
    for &pi in &checked.order {
        let p = &t.passes[pi];
        let reads: Vec<ResId> = p.kind.reads().iter().map(|r| res_index[&r.value]).collect();
        let read_spans: Vec<Span> = p.kind.reads().iter().map(|r| r.span).collect();
        let kind = match &p.kind {
            PassKind::Depth { view, .. } => IrPassKind::Depth { view: *view },
            PassKind::Map { .. } => IrPassKind::Map,
            PassKind::Filter { .. } => IrPassKind::Filter {
                kernel: checked.kernels[pi]
                    .clone()
                    .ok_or_else(|| Diagnostic::error(Phase::Lower, "filter kernel was not resolved").at(p.span, "here"))?,
            },
            PassKind::Mipmap { reduce, .. } => IrPassKind::Mipmap { reduce: *reduce },
            PassKind::SummedArea { sum, .. } => IrPassKind::SummedArea {
                sum: sum.as_ref().map(|s| (s.value, s.span)),
            },
            PassKind::Geometry {
                primitive,
                view,
                keep,
                from,
                ..
            } => IrPassKind::Geometry {
                primitive: *primitive,
                from: from.as_ref().map(|f| f.value),
                resolve: checked.resolves[pi].ok_or_else(|| internal(p.span, "Geometry pass without its checked resolve rule"))?,
                view: *view,
                keep: match keep {
                    Some(k) => {
                        let mut l = Lowerer::new(sym, types, &mut arena, &channel_ids, &no_expansions, None);
                        Some(l.expr(k).map_err(Diagnostics::from)?)
                    }
                    None => None,
                },
            },
            PassKind::Shade {
                reads: rnames,
                visibility,
                debug: outputs,
                ..
            } => {
                let mut shade_reads = Vec::new();
                for r in rnames {
                    let rid = res_index[&r.value];
                    for item in &checked.items[&r.value] {
                        shade_reads.push((*item, rid));
                    }
                }
                let mut l = Lowerer::new(sym, types, &mut arena, &channel_ids, &expansions, Some(shade_reads));
                l.samples = checked.samples;
                let v = l.expr_coerced(visibility).map_err(Diagnostics::from)?;
                // only a build that asks for them has debug outputs
                if !sym.debug {
                    debug_omitted.extend(outputs.iter().map(|o| o.name.value.clone()));
                }
                for o in outputs.iter().filter(|_| sym.debug) {
                    let expr = l.expr_coerced(&o.value).map_err(Diagnostics::from)?;
                    debug.push(IrDebug {
                        name: o.name.value.clone(),
                        texture: crate::resolve::debug_texture(&o.name.value),
                        expr,
                    });
                }
                IrPassKind::Shade { visibility: v }
            }
        };
        let writes = p.kind.writes().map(|w| {
            let (mips, sat, slots) = match &p.kind {
                PassKind::Filter { .. } | PassKind::Mipmap { .. } | PassKind::SummedArea { .. } => {
                    let src = &resources[reads[0]];
                    let mips = p.kind.kind().makes_mip_chain();
                    let sat = p.kind.kind().makes_table();
                    (mips, sat, src.slots.clone())
                }
                PassKind::Depth { .. } | PassKind::Map { .. } | PassKind::Geometry { .. } | PassKind::Shade { .. } => {
                    let mut slots = Vec::new();
                    for item in &checked.items[&w.value] {
                        let ids: Vec<ChannelId> = match item {
                            Item::Channel(c) => vec![channel_ids[*c]],
                            Item::Expansion(e) => expansions[ExpansionId::new(*e)].terms.iter().map(|(_, c)| *c).collect(),
                        };
                        for c in ids {
                            slots.push(Slot {
                                channel: c,
                                precision: channels[c].precision,
                            });
                        }
                    }
                    (false, false, slots)
                }
            };
            let id = resources.append(IrResource {
                name: w.value.clone(),
                slots,
                writer: PassId::new(passes.len()),
                mips,
                sat,
                span: w.span,
                live: true,
                textures: vec![],
            });
            res_index.insert(w.value.clone(), id);
            id
        });
        passes.append(IrPass {
            name: p.name.value.clone(),
            kind,
            reads,
            read_spans,
            writes,
            span: p.span,
            live: true,
            // measured on lavapipe: fragment (docs/gpu.md); the default until a device
            // class measures otherwise
            schedule: sym.schedules[pi].unwrap_or_default(),
        });
    }

    let mut ir = Ir {
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
        samples: checked.samples,
        shadow_map: t.shadow_map.as_ref().map(|s| s.value),
        debug,
        debug_omitted,
        specialised: sym.scene.as_ref().map(|facts| Specialised {
            // the casters' least depth matters only to precisions left to the compiler: a
            // graph without one does not assume it (nor does the runtime check it)
            facts: sshc_graph::SceneFacts {
                depth_floor: facts.depth_floor.filter(|_| sym.channel_auto.iter().chain(&sym.expansion_auto).any(|&a| a)),
                ..facts.clone()
            },
            folded: facts
                .zero_inputs()
                .iter()
                .filter(|name| {
                    crate::builtins::Input::ALL
                        .iter()
                        .any(|i| i.desc().name == **name && types.reads_input(*i))
                })
                .map(|name| format!("`{name}` is 0 for a {} light: folded", facts.light.name()))
                .chain(std::iter::once(format!(
                    "the light is {}: the Shade's direction to the light and texel size take that form only",
                    if facts.light.is_distant() {
                        "at infinity"
                    } else {
                        "at a finite position"
                    }
                )))
                .chain(facts.depth_floor.filter(|_| sym.channel_auto.iter().chain(&sym.expansion_auto).any(|&a| a)).map(|f| {
                    format!(
                        "the casters lie at normalised depth {f} or more in the light's view: the Depth pass writes [{f}, 1] (the runtime refuses a scene whose casters come nearer)"
                    )
                }))
                .collect(),
        }),
        precision_choices: Vec::new(),
    };
    choose_precisions(&mut ir);
    Ok(ir)
}

/// The technique lowered again with fixed param `param` at `value` (an integer param at
/// its floor), for `analyse`'s probe of the largest safe value: a fixed param is
/// substituted here, so another value is another IR. `None` where it does not lower.
pub fn lower_with_value(sym: &Symbols, checked: &Checked, param: ParamId, value: f64) -> Option<Ir> {
    let mut values = sym.values.clone();
    // IR params are the technique's, in order
    let v = &mut values.get_mut(param.index())?.value;
    *v = match *v {
        ConstValue::Int(_) => ConstValue::Int(value.floor() as i64),
        ConstValue::Float(_) | ConstValue::Bool(_) | ConstValue::Uint(_) => ConstValue::Float(value),
    };
    let sym = Symbols {
        values,
        ..sym.clone_shallow()
    };
    lower(&sym, checked).ok()
}

/// Choose the precision of every channel left to the compiler (`precision: Auto`, or
/// `--precision NAME=auto`): F16 where the channel's range, where it is made, fits F16
/// (at most 65504) and stays clear of F16's subnormals (at least 6.1e-5 in magnitude
/// when it does not straddle 0), else F32. The range is the one the range analysis
/// computes (`ranges.rs`, which `analyse` fits the precisions to), so a technique specialised for a scene (`--scene`) is judged on the scene's depths
/// (`SceneFacts::depth_floor`). The choice weighs range only: how finely a value must be
/// kept (a depth compared with a small bias) is the author's to state with an explicit
/// precision. Records one line per channel in `Ir::precision_choices`. The last step of
/// [`lower`]: no later phase changes the IR.
fn choose_precisions(ir: &mut Ir) {
    if !ir.channels.iter().any(|c| c.precision_auto) {
        return;
    }
    let ranges = scene_slot_ranges(ir);
    let mut chosen: Vec<(ChannelId, Precision, Interval)> = Vec::new();
    for (ri, res) in ir.resources.with_handles() {
        // where the channel is made: the Depth, Map or Geometry pass writing it
        if ir.passes[res.writer].kind.copies_source() {
            continue;
        }
        for (si, slot) in res.slots.iter().enumerate() {
            if !ir.channels[slot.channel].precision_auto || chosen.iter().any(|c| c.0 == slot.channel) {
                continue;
            }
            let r = ranges[ri.index()][si];
            let p = if fits(Precision::F16, r) && smallest_magnitude(r) >= F16_MIN_NORMAL {
                Precision::F16
            } else {
                Precision::F32
            };
            chosen.push((slot.channel, p, r));
        }
    }
    for &(c, p, r) in &chosen {
        ir.channels[c].precision = p;
        let why = match p {
            Precision::F16 => "within F16's 65504 and above its smallest normal 6.1e-5".to_string(),
            Precision::F32 | Precision::Unorm8 | Precision::Unorm16 if r.magnitude() > F16_MAX => "beyond F16's 65504".to_string(),
            Precision::F32 | Precision::Unorm8 | Precision::Unorm16 => {
                format!("down to {}, below F16's smallest normal 6.1e-5", short(smallest_magnitude(r)))
            }
        };
        let line = format!("channel `{}` (Auto): {}, spanning {r}, {why}", ir.channels[c].name, p.name());
        ir.precision_choices.push(line);
    }
    for res in ir.resources.iter_mut() {
        for slot in res.slots.iter_mut() {
            if let Some(&(_, p, _)) = chosen.iter().find(|c| c.0 == slot.channel) {
                slot.precision = p;
            }
        }
    }
}
