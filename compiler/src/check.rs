//! Phase `check`, the graph checks: the pass graph is a DAG whose order follows from
//! reads and writes; every read comes after a write; exactly one Shade pass; every
//! expression is typed in its context (by the typer, `check/typer/`) and its inputs come
//! from the side it may read: basis expansions are separable (Annen eq. 5.6: coefficients
//! use receiver-side inputs only, basis functions map-side inputs only), geometry inputs
//! only in what Geometry passes write; per-sample resources are read where each view is
//! known; parameter values lie in their ranges; filter sizes are odd and within bounds.

mod typer;

use crate::builtins::{Input, Side, Ty, unify};
use crate::check::typer::{Bind, Local, Typer, distinct_sites};
use crate::consteval::{self, MAX_SERIES};
use crate::diag::{Diagnostic, Diagnostics, Phase};
use crate::front::ast::*;
use crate::front::expr::{Expr, ExprKind};
use crate::front::parse::closest;
use crate::ir::IrKernel;
use crate::resolve::{Item, Symbols};
use crate::span::Span;
use crate::types::Types;
use indexmap::IndexMap;

pub use crate::check::typer::{Mode, Use};

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
    /// The resolve rule of each Geometry pass (by pass index).
    pub resolves: Vec<Option<Resolve>>,
    /// The type of every expression, what every name resolves to, and where abstract
    /// integers become f32: what `lower` builds the IR from.
    pub types: Types,
    /// Light samples the per-sample passes render (`light_samples`, 1 when absent).
    pub samples: u32,
}

pub fn check(sym: &Symbols) -> Result<Checked, Diagnostics> {
    let t = sym.t;
    let mut diags = Diagnostics::default();
    let mut types = Types::default();

    check_params(sym, &mut diags);

    // Exactly one Shade pass.
    let shades: Vec<&Pass> = t.passes.iter().filter(|p| p.kind.kind().is_shade()).collect();
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
        check_expansion(sym, e, &mut types, &mut diags);
    }
    // The elements of constant arrays: known at compile time, of the array's type.
    for a in &t.arrays {
        for v in &a.values {
            let mut ty = Typer::new(sym, Mode::Const, &mut types);
            match ty.infer_as(v, a.ty.value) {
                Ok(got) if unify(got, a.ty.value) == Some(a.ty.value) => {
                    if matches!(a.ty.value, Ty::F32 | Ty::I32)
                        && let Err(d) = ty.settle(v, a.ty.value)
                    {
                        diags.push(d);
                    }
                }
                Ok(got) => diags.push(
                    Diagnostic::error(
                        Phase::Check,
                        format!("type mismatch: `{}` holds {}, found {got}", a.name.value, a.ty.value),
                    )
                    .at(v.span, format!("this is {got}")),
                ),
                Err(d) => diags.push(d),
            }
        }
    }
    // Channel values are computed per shadow-map texel.
    for c in &t.channels {
        if let Some(v) = &c.value {
            let mut ty = Typer::new(sym, Mode::ChannelValue, &mut types);
            match ty.infer_as(v, Ty::F32) {
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
            // Geometry inputs exist per fragment of generated primitives: only in channels
            // that Geometry passes, and nothing else, write.
            let writers: Vec<&Pass> = t
                .passes
                .iter()
                .filter(|p| match &p.kind {
                    PassKind::Map { channels, .. } | PassKind::Geometry { channels, .. } => {
                        channels.iter().any(|n| n.value == c.name.value)
                    }
                    PassKind::Depth { .. }
                    | PassKind::Filter { .. }
                    | PassKind::Mipmap { .. }
                    | PassKind::SummedArea { .. }
                    | PassKind::Shade { .. } => false,
                })
                .collect();
            if let Some(p) = writers.iter().find(|p| !p.kind.kind().is_geometry()) {
                for u in ty.uses.iter().filter(|u| u.side == Side::Geometry) {
                    diags.push(geometry_only(
                        u,
                        &format!(
                            "channel `{}` is computed by the {} pass `{}`, per shadow-map texel",
                            c.name.value,
                            p.kind.kind_name(),
                            p.name.value
                        ),
                    ));
                }
            }
            // Each primitive's fragments have their own geometry inputs.
            for p in &writers {
                if let PassKind::Geometry { primitive, .. } = &p.kind {
                    for u in ty.uses.iter().filter(|u| u.side == Side::Geometry) {
                        if let Some(i) = Input::from_name(&u.name).filter(|i| !i.primitives().contains(primitive)) {
                            diags.push(primitive_input(u, i, *primitive, &p.name.value));
                        }
                    }
                }
            }
        }
    }

    let samples = match &t.light_samples {
        None => 1,
        Some(e) => light_samples(sym, e, &mut types).unwrap_or_else(|d| {
            diags.push(d);
            1
        }),
    };
    let per_sample = per_sample_resources(sym);
    check_sample_views(sym, &per_sample, &mut diags);

    let mut kernels = vec![None; t.passes.len()];
    let mut resolves = vec![None; t.passes.len()];
    for &pi in &order {
        let p = &t.passes[pi];
        match &p.kind {
            PassKind::Map { reads, channels, .. } | PassKind::Geometry { reads, channels, .. } => {
                let carried: Vec<Item> = reads
                    .iter()
                    .flat_map(|r| items.get(&r.value).cloned().unwrap_or_default())
                    .collect();
                if let PassKind::Geometry {
                    resolve, primitive, keep, ..
                } = &p.kind
                {
                    match resolve_rule(sym, resolve, &mut types) {
                        Ok(r) => {
                            if let Err(d) = primitive_resolve(p, *primitive, r, resolve) {
                                diags.push(d);
                            }
                            resolves[pi] = Some(r);
                        }
                        Err(d) => diags.push(d),
                    }
                    if let Some(k) = keep {
                        check_keep(sym, p, *primitive, k, &carried, &mut types, &mut diags);
                    }
                }
                for n in channels {
                    let needed = map_inputs(sym, &n.value);
                    for (ch, span) in needed {
                        if !carried.contains(&Item::Channel(ch)) {
                            diags.push(
                                Diagnostic::error(
                                    Phase::Check,
                                    format!(
                                        "{} pass `{}` computes `{}` from channel `{}`, which none of its reads carries",
                                        p.kind.kind_name(),
                                        p.name.value,
                                        n.value,
                                        t.channels[ch].name.value
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
            PassKind::Filter { kernel, .. } => match resolve_kernel(sym, kernel, &mut types) {
                Ok(k) => kernels[pi] = Some(k),
                Err(d) => diags.push(d),
            },
            PassKind::Shade {
                reads, visibility, debug, ..
            } => {
                let carried: Vec<(Item, String, bool)> = reads
                    .iter()
                    .flat_map(|r| {
                        let table = t.passes[sym.resources[&r.value].writer].kind.kind().makes_table();
                        items
                            .get(&r.value)
                            .cloned()
                            .unwrap_or_default()
                            .into_iter()
                            .map(move |i| (i, r.value.clone(), table))
                    })
                    .collect();
                let mut ty = Typer::new(sym, Mode::Shade, &mut types);
                ty.available = Some(carried);
                ty.per_sample = per_sample.clone();
                ty.carriers = items
                    .iter()
                    .flat_map(|(r, list)| list.iter().map(move |i| (*i, r.clone())))
                    .collect();
                match ty.infer_as(visibility, Ty::F32) {
                    Ok(t) => {
                        expect_f32(t, visibility.span, "the visibility", &mut diags);
                        // the debug outputs, in the visibility's `let`s: checked where the
                        // visibility is, so that an error in a `let` is reported once
                        for o in debug {
                            match ty.infer_as(&o.value, Ty::F32) {
                                Ok(t) => expect_debug(t, &o.name, o.value.span, &mut diags),
                                Err(d) => diags.push(d),
                            }
                        }
                    }
                    Err(d) => diags.push(d),
                }
                for u in ty.uses.iter().filter(|u| u.side == Side::Geometry) {
                    diags.push(geometry_only(u, "the visibility is computed per camera pixel"));
                }
            }
            PassKind::Depth { .. } | PassKind::Mipmap { .. } | PassKind::SummedArea { .. } => {}
        }
    }
    diags.check()?;
    Ok(Checked {
        order,
        items,
        kernels,
        resolves,
        types,
        samples,
    })
}

/// The most light samples a technique renders views of (`light_samples`).
pub const MAX_LIGHT_SAMPLES: u32 = sshc_graph::MAX_LIGHT_SAMPLES;

/// `light_samples`: an integer known at compile time in 1..=MAX_LIGHT_SAMPLES.
fn light_samples(sym: &Symbols, e: &Expr, types: &mut Types) -> Result<u32, Diagnostic> {
    const_typed(sym, e, types, Ty::I32, "`light_samples`", "an integer")?;
    match consteval::const_eval(sym, e)? {
        ConstValue::Int(n) if (1..=i64::from(MAX_LIGHT_SAMPLES)).contains(&n) => Ok(n as u32),
        ConstValue::Int(n) => Err(Diagnostic::error(
            Phase::Check,
            format!("{n} light samples: a technique renders 1 to {MAX_LIGHT_SAMPLES} sample views"),
        )
        .at(e.span, format!("evaluates to {n}"))
        .note("each sample is a view of its own: a depth map, and a layer block of every per-sample resource")),
        other @ (ConstValue::Float(_) | ConstValue::Bool(_) | ConstValue::Uint(_)) => Err(Diagnostic::error(
            Phase::Check,
            format!("type mismatch: `light_samples` must be an integer, found {other}"),
        )
        .at(e.span, "not an integer")),
    }
}

/// Resources written by `view: PerSample` passes: one layer block per light sample.
fn per_sample_resources(sym: &Symbols) -> Vec<String> {
    sym.t
        .passes
        .iter()
        .filter(|p| {
            matches!(
                p.kind,
                PassKind::Depth {
                    view: LightView::PerSample,
                    ..
                } | PassKind::Geometry {
                    view: LightView::PerSample,
                    ..
                }
            )
        })
        .filter_map(|p| p.kind.writes().map(|w| w.value.clone()))
        .collect()
}

/// Which passes may read per-sample resources, and what a `Skins` pass needs: a per-sample
/// Geometry pass reads only per-sample resources (each view its own layer block), a
/// centre-view pass none; Shade reads them through `at_sample` (checked by the typer).
/// `Skins` run per sample, resolve by the depth test and name the neighbour they warp;
/// the other primitives grow from the silhouettes seen from the light's centre.
fn check_sample_views(sym: &Symbols, per_sample: &[String], diags: &mut Diagnostics) {
    for p in &sym.t.passes {
        let sampled = match &p.kind {
            PassKind::Geometry { view, .. } => *view == LightView::PerSample,
            PassKind::Shade { .. } | PassKind::Depth { .. } => continue,
            PassKind::Map { .. } | PassKind::Filter { .. } | PassKind::Mipmap { .. } | PassKind::SummedArea { .. } => false,
        };
        for r in p.kind.reads() {
            let is = per_sample.contains(&r.value);
            if is != sampled {
                let d = Diagnostic::error(
                    Phase::Check,
                    if is {
                        format!(
                            "{} pass `{}` reads `{}`, which holds one view per light sample",
                            p.kind.kind_name(),
                            p.name.value,
                            r.value
                        )
                    } else {
                        format!(
                            "Geometry pass `{}` renders one view per light sample but reads `{}`, seen from the light's centre",
                            p.name.value, r.value
                        )
                    },
                )
                .at(r.span, "read here");
                diags.push(if is {
                    d.note("per-sample resources are read by per-sample Geometry passes and, through `at_sample(k, ..)`, by the Shade pass")
                } else {
                    d.help("read resources written with `view: PerSample`")
                });
            }
        }
        if let PassKind::Geometry { primitive, view, from, .. } = &p.kind {
            let skins = primitive.joins_sample_views();
            if skins && !view.is_per_sample() {
                diags.push(
                    Diagnostic::error(Phase::Check, format!("Geometry pass `{}` draws Skins from the light's centre", p.name.value))
                        .at(p.kind_span, "skins join two sample views")
                        .note("skins are depth discontinuities of one sample's map warped into its neighbour's view (Heidrich et al. 2000, section 3.2)")
                        .help("write `view: PerSample`"),
                );
            }
            if !skins && view.is_per_sample() {
                diags.push(
                    Diagnostic::error(
                        Phase::Check,
                        format!("Geometry pass `{}` draws {primitive:?} once per light sample", p.name.value),
                    )
                    .at(p.kind_span, "only Skins are drawn per sample")
                    .note("cones, sheets, ribbons and back faces grow from the silhouettes seen from the light's centre"),
                );
            }
            match (skins, from) {
                (true, None) => diags.push(
                    Diagnostic::error(
                        Phase::Check,
                        format!("Skins pass `{}` does not say which neighbour it warps", p.name.value),
                    )
                    .at(p.kind_span, "missing `from`")
                    .help("add `from: Previous` (skins of sample k - 1 into view k) or `from: Next` (of sample k + 1)"),
                ),
                (false, Some(f)) => diags.push(
                    Diagnostic::error(Phase::Check, format!("`from` is a field of Skins passes, not of {primitive:?}"))
                        .at(f.span, "remove this"),
                ),
                _ => {}
            }
            if skins && !p.kind.reads().iter().any(|r| is_depth_resource(sym, &r.value)) {
                diags.push(
                    Diagnostic::error(
                        Phase::Check,
                        format!("Skins pass `{}` reads no per-sample Depth resource", p.name.value),
                    )
                    .at(p.kind_span, "skins are found in the samples' depth maps")
                    .help("add the resource of a `Depth(view: PerSample)` pass to `reads`"),
                );
            }
        }
    }
}

/// Whether `name` is written by a Depth pass.
fn is_depth_resource(sym: &Symbols, name: &str) -> bool {
    sym.t
        .passes
        .iter()
        .any(|p| p.kind.kind().is_depth() && p.kind.writes().is_some_and(|w| w.value == name))
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

/// A debug output is an f32 or a vector of f32 (what a float texture stores).
fn expect_debug(t: Ty, name: &Name, span: Span, diags: &mut Diagnostics) {
    if !matches!(t, Ty::F32 | Ty::AbstractInt | Ty::Vec(_)) {
        diags.push(
            Diagnostic::error(
                Phase::Check,
                format!(
                    "type mismatch: debug output `{}` must be f32 or a vector of f32, found {t}",
                    name.value
                ),
            )
            .at(span, format!("this is {t}"))
            .help(if t == Ty::Bool {
                "show a condition as a number with `select(0.0, 1.0, cond)`"
            } else {
                "convert it with `f32(...)`"
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

fn check_expansion(sym: &Symbols, e: &Expansion, types: &mut Types, diags: &mut Diagnostics) {
    let mut ty = Typer::new(sym, Mode::Const, types);
    let mut bounds_typed = true;
    for (bound, what) in [(&e.from, "start"), (&e.to, "end")] {
        match ty.infer_as(bound, Ty::I32) {
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
            Err(d) => {
                diags.push(d);
                bounds_typed = false;
            }
        }
    }
    // The number of terms is known here: an empty or too long expansion is refused now,
    // not when lowering unrolls it.
    if bounds_typed
        && let (Ok(ConstValue::Int(lo)), Ok(ConstValue::Int(hi))) = (consteval::const_eval(sym, &e.from), consteval::const_eval(sym, &e.to))
    {
        if hi < lo {
            diags.push(
                Diagnostic::error(
                    Phase::Check,
                    format!("expansion `{}` has no terms: its index runs from {lo} to {hi}", e.name.value),
                )
                .at(e.from.span.join(e.to.span), "empty range"),
            );
        } else if hi - lo + 1 > MAX_SERIES {
            diags.push(
                Diagnostic::error(
                    Phase::Check,
                    format!("expansion `{}` has {} orders: at most {MAX_SERIES}", e.name.value, hi - lo + 1),
                )
                .at(e.to.span, "too many"),
            );
        }
    }
    ty.mode = Mode::Coeff;
    match ty.infer_as(&e.constant, Ty::F32) {
        Ok(t) => expect_f32(t, e.constant.span, "the constant term", diags),
        Err(d) => diags.push(d),
    }
    for u in ty.uses.iter().filter(|u| u.side == Side::Geometry) {
        diags.push(geometry_only(u, "an expansion's constant is computed per receiver"));
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
        konst: true,
        bind: Bind::Other,
    });
    for (name, value) in &e.lets {
        ty.uses.clear();
        let before = ty.runtime;
        match ty.infer_as(value, Ty::I32) {
            Ok(t) => {
                let uses = distinct_sites(std::mem::take(&mut ty.uses));
                let konst = ty.runtime == before;
                ty.locals.push(Local {
                    name: name.value.clone(),
                    ty: t.concrete(),
                    uses,
                    konst,
                    bind: Bind::Other,
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
        match ty.infer_as(&term.coeff, Ty::F32) {
            Ok(t) => expect_f32(t, term.coeff.span, "a coefficient", diags),
            Err(d) => diags.push(d),
        }
        for u in ty.uses.iter().filter(|u| u.side == Side::Geometry) {
            diags.push(geometry_only(u, "an expansion's coefficients are computed per receiver"));
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
        match ty.infer_as(&term.basis, Ty::F32) {
            Ok(t) => expect_f32(t, term.basis.span, "a basis function", diags),
            Err(d) => diags.push(d),
        }
        for u in ty.uses.iter().filter(|u| u.side == Side::Geometry) {
            diags.push(geometry_only(u, "an expansion's basis functions are computed per shadow-map texel"));
        }
        for u in ty.uses.drain(..).filter(|u| u.side == Side::Receiver) {
            diags.push(side_error(&u, "a basis function of expansion", &e.name.value, "basis functions B_i(z) are stored per shadow-map texel and prefiltered, so they may use map-side inputs only (Annen eq. 5.6)").help("move the factor that depends on the receiver into `coeff`"));
        }
    }
}

/// A geometry input used in a channel a pass of another primitive writes.
fn primitive_input(u: &Use, input: Input, primitive: Primitive, pass: &str) -> Diagnostic {
    let has: Vec<String> = input.primitives().iter().map(|p| format!("{p:?}")).collect();
    let mut d = Diagnostic::error(
        Phase::Check,
        format!("`{}` exists only per fragment of {} primitives", u.name, has.join(" and ")),
    )
    .at(u.span, format!("pass `{pass}` draws {primitive:?}"))
    .note("docs/language.md section 8.5 lists each geometry input's primitives");
    if let Some(via) = u.via {
        d = d.also(via, "used through this binding");
    }
    d
}

/// A resolve rule a primitive cannot use: Ribbons and BackFaces keep the nearest fragment
/// (a depth test on their depth); the cones and sheets of penumbra maps write no depth.
fn primitive_resolve(p: &Pass, primitive: Primitive, r: Resolve, spec: &ResolveSpec) -> Result<(), Diagnostic> {
    let (span, label) = match spec {
        ResolveSpec::Expr(e) => (e.span, "this resolve rule"),
        ResolveSpec::Rule(_) => (p.kind_span, "this pass's `resolve`"),
    };
    let Some(nearest) = primitive.keeps_nearest() else { return Ok(()) };
    if nearest == (r == Resolve::Nearest) {
        return Ok(());
    }
    let d = Diagnostic::error(
        Phase::Check,
        format!("Geometry pass `{}` draws {primitive:?} with resolve {r:?}", p.name.value),
    )
    .at(span, label);
    Err(if nearest {
        d.note("ribbons and back faces write a depth, and the fragment nearest the light wins (Lawlor 2006, section 3.1)")
            .help("write `resolve: Nearest`")
    } else {
        d.note("cones and sheets write no depth: overlaps combine by blending (Wyman & Hansen 2003, figure 6)")
            .help("use KeepMin, KeepMax, Add or Multiply")
    })
}

/// A Geometry pass's `keep`: a bool per fragment over map-side values, the pass's reads
/// at the fragment's texel and its primitive's geometry inputs.
fn check_keep(sym: &Symbols, p: &Pass, primitive: Primitive, keep: &Expr, carried: &[Item], types: &mut Types, diags: &mut Diagnostics) {
    let mut ty = Typer::new(sym, Mode::ChannelValue, types);
    match ty.infer_as(keep, Ty::Bool) {
        Ok(Ty::Bool) => {}
        Ok(other) => diags.push(
            Diagnostic::error(Phase::Check, format!("type mismatch: `keep` must be bool, found {other}"))
                .at(keep.span, format!("this is {other}"))
                .help("compare, e.g. `z_frag > near + c * (far - near)`"),
        ),
        Err(d) => diags.push(d),
    }
    for u in &ty.uses {
        match u.side {
            Side::Receiver => diags.push(side_error(
                u,
                "the `keep` of pass",
                &p.name.value,
                "`keep` runs per fragment drawn from the light, before any receiver is known",
            )),
            Side::Geometry => {
                if let Some(i) = Input::from_name(&u.name).filter(|i| !i.primitives().contains(&primitive)) {
                    diags.push(primitive_input(u, i, primitive, &p.name.value));
                }
            }
            Side::Map | Side::Both => {}
        }
    }
    let mut seen = Vec::new();
    keep.walk(&mut |x| {
        if let ExprKind::Name(n) = &x.kind
            && let Some(&c) = sym.channels.get(n)
            && !seen.contains(&c)
        {
            seen.push(c);
            if !carried.contains(&Item::Channel(c)) {
                diags.push(
                    Diagnostic::error(
                        Phase::Check,
                        format!(
                            "the `keep` of pass `{}` reads channel `{n}`, which none of its reads carries",
                            p.name.value
                        ),
                    )
                    .at(x.span, "channel used here")
                    .help("add the resource holding it to `reads`"),
                );
            }
        }
    });
}

/// A Geometry-side input used where no generated primitive's fragment exists.
fn geometry_only(u: &Use, where_: &str) -> Diagnostic {
    let mut d = Diagnostic::error(
        Phase::Check,
        format!("`{}` exists only per fragment of a Geometry pass's primitives", u.name),
    )
    .at(u.span, "not available here")
    .note(format!(
        "{where_}; geometry inputs may be used in the values of channels that only Geometry passes write"
    ));
    if let Some(via) = u.via {
        d = d.also(via, "used through this binding");
    }
    d
}

fn side_error(u: &Use, what: &str, owner: &str, why: &str) -> Diagnostic {
    let side = match u.side {
        Side::Receiver => "a receiver-side input",
        Side::Map | Side::Both => "a map-side channel",
        Side::Geometry => "an input of Geometry passes' fragments",
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

/// A Geometry pass's resolve rule: named, or the index a compile-time integer gives.
fn resolve_rule(sym: &Symbols, spec: &ResolveSpec, types: &mut Types) -> Result<Resolve, Diagnostic> {
    let e = match spec {
        ResolveSpec::Rule(r) => return Ok(*r),
        ResolveSpec::Expr(e) => e,
    };
    const_typed(sym, e, types, Ty::I32, "a resolve rule", "an integer")?;
    let names = "0 KeepMin, 1 KeepMax, 2 Add, 3 Multiply";
    match consteval::const_eval(sym, e)? {
        ConstValue::Int(n) if (0..Resolve::ALL.len() as i64).contains(&n) => Ok(Resolve::ALL[n as usize]),
        ConstValue::Int(n) => {
            Err(Diagnostic::error(Phase::Check, format!("resolve rule {n} does not exist: {names}"))
                .at(e.span, format!("evaluates to {n}")))
        }
        other @ (ConstValue::Float(_) | ConstValue::Bool(_) | ConstValue::Uint(_)) => Err(Diagnostic::error(
            Phase::Check,
            format!("type mismatch: a resolve rule must be an integer ({names}), found {other}"),
        )
        .at(e.span, "not an integer")),
    }
}

fn kernel_size(sym: &Symbols, e: &Expr, types: &mut Types) -> Result<u32, Diagnostic> {
    const_typed(sym, e, types, Ty::I32, "a filter size", "an integer")?;
    let v = consteval::const_eval(sym, e)?;
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
        other @ (ConstValue::Float(_) | ConstValue::Bool(_) | ConstValue::Uint(_)) => Err(Diagnostic::error(
            Phase::Check,
            format!("type mismatch: a filter size must be an integer, found {other}"),
        )
        .at(e.span, "not an integer")),
    }
}

fn resolve_kernel(sym: &Symbols, kernel: &crate::span::Spanned<Kernel>, types: &mut Types) -> Result<IrKernel, Diagnostic> {
    let size = |e: &Expr, types: &mut Types| kernel_size(sym, e, types);
    Ok(match &kernel.value {
        Kernel::Box { size: s } => IrKernel::Box(size(s, types)?),
        Kernel::Max { size: s } => IrKernel::Max(size(s, types)?),
        Kernel::Min { size: s } => IrKernel::Min(size(s, types)?),
        Kernel::LoG => IrKernel::LoG,
        Kernel::Gaussian { size: s, sigma } => {
            let n = size(s, types)?;
            const_typed(sym, sigma, types, Ty::F32, "a Gaussian sigma", "an f32")?;
            let sg = consteval::const_eval(sym, sigma)?.as_f64();
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
/// `want` is I32 or F32; an abstract integer is accepted for either.
fn const_typed(sym: &Symbols, e: &Expr, types: &mut Types, want_ty: Ty, what: &str, want: &str) -> Result<(), Diagnostic> {
    let t = Typer::new(sym, Mode::Const, types).infer_as(e, want_ty)?;
    if t == want_ty || t == Ty::AbstractInt {
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
