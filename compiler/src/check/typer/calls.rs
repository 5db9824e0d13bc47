//! Calls: the dispatch by name, the built-in functions' signatures, and the technique's
//! functions, inlined with their `Channel` and `Expansion` arguments.

use super::{Bind, Local, Mode, Typer, distinct_sites};
use crate::builtins::{AT_SAMPLE, Func, Input, SampleFn, Ty, constant, unify};
use crate::diag::Diagnostic;
use crate::front::ast::{Name, ParamTy};
use crate::front::expr::{Expr, ExprKind};
use crate::front::parse::closest;
use crate::resolve::Item;
use crate::span::{Span, Spanned};

impl<'s, 'a> Typer<'s, 'a> {
    pub(super) fn call(&mut self, name: &str, name_span: Span, args: &'a [Expr], span: Span) -> Result<Ty, Diagnostic> {
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
            return self.lookup(name, how, expand, name_span, args, span);
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

    pub(super) fn item_name(&self, item: Item) -> &'a str {
        match item {
            Item::Channel(c) => &self.sym.t.channels[c].name.value,
            Item::Expansion(e) => &self.sym.t.expansions[e].name.value,
        }
    }
}
