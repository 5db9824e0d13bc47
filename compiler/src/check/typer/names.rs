//! What a name is in its context (a local, a param, a constant, an input, a channel) and
//! the elements of constant arrays.

use super::{Bind, Mode, Typer, Use};
use crate::builtins::{Input, Side, Ty, constant};
use crate::diag::Diagnostic;
use crate::front::expr::Expr;
use crate::front::parse::closest;
use crate::resolve::Item;
use crate::span::Span;
use crate::types::Resolved;

impl<'s, 'a> Typer<'s, 'a> {
    pub(super) fn name(&mut self, e: &Expr, n: &str, span: Span) -> Result<Ty, Diagnostic> {
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

    /// `name[index]`: an element of a constant array, the index an integer known at compile
    /// time, within the array where its value is known here (lower checks the others as it
    /// unrolls).
    pub(super) fn index(&mut self, name: &str, name_span: Span, index: &'a Expr) -> Result<Ty, Diagnostic> {
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

    /// `NAME_tI_kK`, the name of an expansion's unrolled channel (term I at index value K):
    /// the expansion's name, I and K, where NAME is a declared expansion.
    pub(super) fn basis_channel<'n>(&self, name: &'n str) -> Option<(&'n str, usize, i64)> {
        let (rest, k) = name.rsplit_once("_k")?;
        let (e, term) = rest.rsplit_once("_t")?;
        let (term, k) = (term.parse().ok()?, k.parse().ok()?);
        self.sym.expansions.contains_key(e).then_some((e, term, k))
    }
}
