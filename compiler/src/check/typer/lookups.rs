//! The lookups of stored values: a channel or expansion read in a Shade pass (`sample`,
//! `expand` and the like) from the resource that carries it, `neighbour` on the map side,
//! and `at_sample`, a light sample's view of the receiver.

use super::{Bind, Mode, Typer};
use crate::builtins::{AT_SAMPLE, SampleFn, Ty, unify};
use crate::diag::Diagnostic;
use crate::front::ast::{PassKind, Reduce};
use crate::front::expr::{Expr, ExprKind};
use crate::front::parse::closest;
use crate::resolve::Item;
use crate::span::Span;

impl<'s, 'a> Typer<'s, 'a> {
    /// A lookup `name(target, ..)` of a channel (or, with `expand`, an expansion) the way
    /// `how` says: in a Shade pass only, `target` a declared item or a function's item
    /// parameter, carried by exactly one resource the pass reads (one held per light
    /// sample inside `at_sample`, any other outside), from a mip chain or summed-area
    /// table where `how` needs one.
    pub(super) fn lookup(
        &mut self,
        name: &str,
        how: SampleFn,
        expand: bool,
        name_span: Span,
        args: &'a [Expr],
        span: Span,
    ) -> Result<Ty, Diagnostic> {
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
        Ok(Ty::F32)
    }

    /// The help for a channel or expansion the Shade pass does not read: the resources
    /// that carry it, to add to its `reads`, or that no pass writes it.
    pub(super) fn carriers_help(&self, item: Item) -> String {
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

    /// `neighbour(ch, dx, dy)`: a channel of the map at a texel offset known at compile time,
    /// on the map side only (a Map pass's channel values and basis functions).
    pub(super) fn neighbour(&mut self, name_span: Span, args: &'a [Expr], span: Span) -> Result<Ty, Diagnostic> {
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

    /// `at_sample(k, body)`: k an integer known at compile time (a literal, a fixed param
    /// or a series variable), body any value, evaluated with the receiver seen from light
    /// sample k; in the Shade pass only, and not nested.
    pub(super) fn at_sample(&mut self, name_span: Span, args: &'a [Expr], span: Span) -> Result<Ty, Diagnostic> {
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
}
