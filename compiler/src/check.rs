//! Phase `check`: the pass graph is a DAG whose order follows from reads and writes;
//! every read comes after a write; exactly one Shade pass; expressions are well typed in
//! their context; basis expansions are separable (Annen eq. 5.6: coefficients use
//! receiver-side inputs only, basis functions map-side inputs only); parameter values lie
//! in their ranges; filter sizes are odd and within bounds.

use crate::builtins::{AT_SAMPLE, Func, Input, SampleFn, Side, Ty, constant, unify};
use crate::consteval::{self, IntOp, IntSpans, MAX_SERIES, NotConst};
use crate::diag::{Diagnostic, Diagnostics, Phase};
use crate::front::ast::*;
use crate::front::expr::{BinOp, Expr, ExprKind, Literal, UnOp};
use crate::front::parse::closest;
use crate::ir::IrKernel;
use crate::resolve::{Item, Symbols};
use crate::span::Span;
use crate::types::{Resolved, Types, comp_index};
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
            if let Some(p) = writers.iter().find(|p| !matches!(p.kind, PassKind::Geometry { .. })) {
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
            PassKind::Shade { reads, visibility, .. } => {
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
                let mut ty = Typer::new(sym, Mode::Shade, &mut types);
                ty.available = Some(carried);
                ty.per_sample = per_sample.clone();
                ty.carriers = items
                    .iter()
                    .flat_map(|(r, list)| list.iter().map(move |i| (*i, r.clone())))
                    .collect();
                match ty.infer_as(visibility, Ty::F32) {
                    Ok(t) => expect_f32(t, visibility.span, "the visibility", &mut diags),
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
            if skins && *view != LightView::PerSample {
                diags.push(
                    Diagnostic::error(Phase::Check, format!("Geometry pass `{}` draws Skins from the light's centre", p.name.value))
                        .at(p.kind_span, "skins join two sample views")
                        .note("skins are depth discontinuities of one sample's map warped into its neighbour's view (Heidrich et al. 2000, section 3.2)")
                        .help("write `view: PerSample`"),
                );
            }
            if !skins && *view == LightView::PerSample {
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
        .any(|p| matches!(p.kind, PassKind::Depth { .. }) && p.kind.writes().is_some_and(|w| w.value == name))
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
fn distinct_sites(uses: impl IntoIterator<Item = Use>) -> Vec<Use> {
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
    }
}

struct Local<'a> {
    name: String,
    ty: Ty,
    uses: Vec<Use>,
    /// Known at compile time (a series variable, an expansion index, or a `let` of
    /// compile-time values), so usable where a constant is needed.
    konst: bool,
    /// What the series limit needs to know of its value.
    bind: Bind<'a>,
}

/// How a local gets its value, for counting the terms of series whose bounds use it.
enum Bind<'a> {
    /// A series variable: one value per term of its series.
    Series,
    /// A `let` of compile-time values (evaluated with the series variables in scope).
    Let(&'a Expr),
    /// Anything else: not known to the series limit.
    Other,
}

/// Type inference for one expression in one context; what it infers goes into `types`.
struct Typer<'s, 'a> {
    sym: &'s Symbols<'a>,
    types: &'s mut Types,
    /// Uses of values not known at compile time so far (to tell constant `let`s).
    runtime: usize,
    mode: Mode,
    locals: Vec<Local<'a>>,
    uses: Vec<Use>,
    /// For a Shade pass: channels and expansions its reads carry, and the resource of each.
    /// What a Shade pass's reads carry: (item, resource, whether a summed-area table).
    available: Option<Vec<(Item, String, bool)>>,
    /// For a Shade pass: the resources that hold one view per light sample.
    per_sample: Vec<String>,
    /// For a Shade pass: what every resource carries (to name where a lookup's channel is).
    carriers: Vec<(Item, String)>,
    /// Inside `at_sample(k, ..)`.
    in_sample: bool,
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
    fn new(sym: &'s Symbols<'a>, mode: Mode, types: &'s mut Types) -> Self {
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
            envs: vec![vec![]],
            floor: 0,
            calling: vec![],
            inlined: 0,
        }
    }

    fn err(span: Span, msg: impl Into<String>, label: impl Into<String>) -> Diagnostic {
        Diagnostic::error(Phase::Check, msg).at(span, label)
    }

    /// Infer the type of `e` where the context needs `want` (F32 or I32): an abstract
    /// integer is settled to it.
    fn infer_as(&mut self, e: &'a Expr, want: Ty) -> Result<Ty, Diagnostic> {
        let t = self.infer(e)?;
        self.settle(e, want)?;
        Ok(t)
    }

    /// Where an abstract integer expression meets a concrete type: its value must be an
    /// i32 (it is computed as one), and it converts to f32 if `to` is a float type.
    fn settle(&mut self, e: &Expr, to: Ty) -> Result<(), Diagnostic> {
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
                        return Err(mismatch());
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
                Bind::Other => Slot::Known(None),
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
        if !self.sym.channels.contains_key(ch) {
            return Err(Self::err(args[0].span, format!("unknown channel `{ch}`"), "not a declared channel"));
        }
        self.infer(&args[0])?;
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
                    let carriers: Vec<String> = self
                        .carriers
                        .iter()
                        .filter(|(i, _)| *i == item)
                        .map(|(_, r)| format!("`{r}`"))
                        .collect();
                    return Err(Self::err(
                        args[0].span,
                        format!("`{target}` is not carried by any resource this Shade pass reads"),
                        "not available here",
                    )
                    .help(if carriers.is_empty() {
                        "no pass writes it: list it in the `channels` of a Map, Geometry or Depth pass".to_string()
                    } else {
                        format!("add {} (which carries it) to the Shade pass's `reads`", carriers.join(" or "))
                    }));
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
                self.settle(a, *want)?;
            }
            self.runtime += 1;
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
        let ty = f
            .result(&tys)
            .map_err(|m| Self::err(span, format!("type mismatch: {m}"), "in this call"))?;
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
