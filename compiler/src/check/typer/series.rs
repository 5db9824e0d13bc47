//! Series (`sum(i in from..=to, body)`): their bounds, known at compile time, and the
//! limit on the terms they unroll to, nested series counted term by term.

use super::{Bind, Local, Mode, Typer};
use crate::builtins::Ty;
use crate::consteval::{self, MAX_SERIES};
use crate::diag::Diagnostic;
use crate::front::ast::ConstValue;
use crate::front::expr::{Expr, ExprKind};
use crate::span::Span;

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

impl<'s, 'a> Typer<'s, 'a> {
    /// `sum(var in from..=to, body)`: integer bounds known at compile time, at most
    /// `MAX_SERIES` terms in all with the enclosing series', the body a number typed with
    /// `var` bound to each term's value.
    pub(super) fn series(
        &mut self,
        e: &Expr,
        var: &str,
        var_span: Span,
        from: &'a Expr,
        to: &'a Expr,
        body: &'a Expr,
    ) -> Result<Ty, Diagnostic> {
        if crate::builtins::is_reserved(var) {
            return Err(Self::err(var_span, format!("`{var}` is a built-in name"), "reserved"));
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
            name: var.to_string(),
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

    /// The locals in scope, each hiding any param of its name, with no value: for
    /// evaluating what does not depend on them.
    pub(super) fn scope(&self) -> consteval::Env {
        self.locals[self.floor..].iter().map(|l| (l.name.clone(), None)).collect()
    }

    /// The bounds of a series `from..=to` for each term of the enclosing series (one per
    /// entry of `envs`; `None` where a bound cannot be evaluated here), and whether they are
    /// the same constants for all (bounds that use no local).
    pub(super) fn series_bounds(&self, from: &Expr, to: &Expr) -> (Vec<Option<(i64, i64)>>, bool) {
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
}
