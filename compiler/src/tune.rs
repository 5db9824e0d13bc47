//! What `sshc tune` may vary in a technique, and the technique file it writes back.
//!
//! [`space`] reads a technique's axes: every param with a declared `range:` (fixed or
//! runtime, the biases included), every channel's and expansion's precision, every
//! schedulable pass's schedule, the shadow-map size and the cascade count, each narrowed or
//! frozen by the technique's `tune:` block. `check` (run at parse) refuses a `tune:` entry that names
//! no axis or leaves a param's declared range, at the entry. [`rewrite`] edits the source
//! text at the spans the parser kept: the chosen values become the defaults, precisions
//! and schedules, the map size a `shadow_map:` field, and the rest of the file (comments,
//! layout, the `tune:` block) stays as written.

use crate::diag::{Diagnostic, Diagnostics, Phase};
use crate::front::ast::{Precision, ScalarTy, Schedule, Technique, TuneAxis, TuneChoice, TuneValue};
use crate::front::parse::{MAX_SHADOW_MAP, closest};
use crate::span::Span;

/// The shadow-map sizes the tuner tries when a technique does not narrow them: powers of
/// two from 256 to 4,096 texels a side.
pub const SHADOW_MAPS: [u32; 5] = [256, 512, 1024, 2048, 4096];

/// Cascades of a light at infinity: 1 to 4 (the runtime's `sshc_light::MAX_CASCADES`, which
/// the lab checks again; the compiler does not depend on the light crate).
pub const MAX_CASCADES: u32 = 4;

/// What one axis may take.
#[derive(Clone, Debug, PartialEq)]
pub enum Domain {
    /// A real interval (an F32 param's declared range, or the `tune:` sub-range).
    Real { lo: f64, hi: f64 },
    /// Whole numbers in `lo..=hi` (an I32 param).
    Int { lo: i64, hi: i64 },
    /// These values, as RON literals (`1024`, `F16`, `Compute`, `true`).
    Choice(Vec<String>),
}

/// One axis of the search.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// `bias`, `shadow_map`, `cascades`, `precision:z` or `schedule:shade`: the name a sweep
    /// axis and a `--set`/`--precision`/`--schedule` option use.
    pub name: String,
    pub domain: Domain,
    /// The technique's own value, as a RON literal (`shadow_map` and `cascades`: none, the
    /// scene's own).
    pub default: Option<String>,
    /// Frozen (by `tune:`) or not tunable (a param without a declared range): the axis
    /// keeps its default and is listed for the record.
    pub frozen: Option<String>,
}

impl Axis {
    /// Whether the search varies this axis.
    pub fn varies(&self) -> bool {
        self.frozen.is_none() && !matches!(&self.domain, Domain::Choice(v) if v.len() < 2)
    }
}

/// A technique's search space.
#[derive(Clone, Debug, PartialEq)]
pub struct Space {
    pub technique: String,
    pub axes: Vec<Axis>,
    /// The technique's own `shadow_map:` (a tuned file's), if any.
    pub shadow_map: Option<u32>,
}

fn diag(span: Span, msg: impl Into<String>, label: impl Into<String>) -> Diagnostic {
    Diagnostic::error(Phase::Parse, msg).at(span, label)
}

/// A real written the way a RON F32 literal reads it back: the shortest text that reads
/// back as the same f32 (what `sshc tune` writes into a tuned technique).
pub fn real_literal(x: f64) -> String {
    literal(ScalarTy::F32, x)
}

/// A number written the way a RON literal of `ty` reads it back.
pub(crate) fn literal(ty: ScalarTy, x: f64) -> String {
    match ty {
        ScalarTy::I32 => format!("{}", x.round() as i64),
        ScalarTy::Bool => (x != 0.0).to_string(),
        ScalarTy::F32 => {
            // the shortest text that reads back as the same f32, with a point or exponent
            let s = format!("{:?}", x as f32);
            if s.contains(['.', 'e', 'E']) || !s.chars().all(|c| c.is_ascii_digit() || c == '-') {
                s
            } else {
                format!("{s}.0")
            }
        }
    }
}

/// The axis kinds a `tune:` entry may name besides params.
fn axis_kinds(t: &Technique) -> Vec<String> {
    let mut names: Vec<String> = t.params.iter().map(|p| p.name.value.clone()).collect();
    names.extend(["shadow_map".to_string(), "cascades".to_string()]);
    names.extend(t.channels.iter().map(|c| format!("precision:{}", c.name.value)));
    names.extend(t.expansions.iter().map(|e| format!("precision:{}", e.name.value)));
    names.extend(
        t.passes
            .iter()
            .filter(|p| p.kind.schedulable())
            .map(|p| format!("schedule:{}", p.name.value)),
    );
    names
}

/// Checks the `tune:` block against the technique: each entry names a param, a channel's or
/// expansion's precision, a schedulable pass's schedule, `shadow_map` or `cascades`, and its
/// values lie in the axis's domain (a param's declared range, whole numbers for an I32).
pub(crate) fn check(t: &Technique) -> Result<(), Diagnostic> {
    for axis in &t.tune {
        check_axis(t, axis)?;
    }
    Ok(())
}

fn check_axis(t: &Technique, axis: &TuneAxis) -> Result<(), Diagnostic> {
    let name = axis.name.value.as_str();
    let span = axis.name.span;
    if !axis_kinds(t).iter().any(|k| k == name) {
        let what = if let Some(target) = name.strip_prefix("precision:") {
            format!("no channel or expansion is named `{target}`")
        } else if let Some(target) = name.strip_prefix("schedule:") {
            format!("no Map, Filter, Mipmap or Shade pass is named `{target}`")
        } else {
            format!("the technique has no param `{name}`")
        };
        return Err(unknown(t, axis, what));
    }
    let values: &[crate::span::Spanned<TuneValue>] = match &axis.choice {
        TuneChoice::Values(v) => v,
        TuneChoice::Frozen => &[],
        TuneChoice::Range(lo, hi) => {
            let Some(p) = t.params.iter().find(|p| p.name.value == name) else {
                return Err(diag(
                    lo.span.join(hi.span),
                    format!("`{name}` takes a list of values, not a range"),
                    "a range",
                )
                .help("a range `(lo, hi)` narrows a param's declared range; give the other axes a list such as `[512, 1024]`"));
            };
            if p.ty.value == ScalarTy::Bool {
                return Err(diag(
                    lo.span.join(hi.span),
                    format!("`{name}` is a Bool param: a range means nothing"),
                    "a range",
                )
                .help("write `[true, false]`, or `Frozen`"));
            }
            if !(lo.value.is_finite() && hi.value.is_finite() && lo.value <= hi.value) {
                return Err(diag(
                    lo.span.join(hi.span),
                    format!("`{name}`: the range ({}, {}) is empty or not finite", lo.value, hi.value),
                    "need lo <= hi",
                ));
            }
            let Some((plo, phi)) = &p.range else {
                return Err(diag(
                    span,
                    format!("`{name}` declares no `range:`, so the tuner cannot bound it"),
                    "no declared range",
                )
                .help(format!(
                    "declare the values it may take: `range: ({}, {})` on the param",
                    lo.value, hi.value
                )));
            };
            for v in [lo, hi] {
                if v.value < plo.value || v.value > phi.value {
                    return Err(diag(
                        v.span,
                        format!(
                            "`{name}` = {} is outside the param's declared range ({}, {})",
                            v.value, plo.value, phi.value
                        ),
                        "outside the declared range",
                    ));
                }
            }
            return Ok(());
        }
    };
    if let Some(p) = t.params.iter().find(|p| p.name.value == name) {
        for v in values {
            let ok = match (&v.value, p.ty.value) {
                (TuneValue::Bool(_), ScalarTy::Bool) => true,
                (TuneValue::Number(x), ScalarTy::I32) => x.fract() == 0.0,
                (TuneValue::Number(x), ScalarTy::F32) => x.is_finite(),
                _ => false,
            };
            if !ok {
                return Err(diag(
                    v.span,
                    format!("`{name}` is a {} param: `{}` is not one of its values", p.ty.value.name(), v.value),
                    format!("expected {}", p.ty.value.name()),
                ));
            }
            if let (TuneValue::Number(x), Some((lo, hi))) = (&v.value, &p.range)
                && (*x < lo.value || *x > hi.value)
            {
                return Err(diag(
                    v.span,
                    format!("`{name}` = {x} is outside the param's declared range ({}, {})", lo.value, hi.value),
                    "outside the declared range",
                )
                .help("the tuner searches inside a param's declared range: widen `range:` if the value is meant"));
            }
        }
        return Ok(());
    }
    let whole = |v: &crate::span::Spanned<TuneValue>, lo: u32, hi: u32, what: &str| -> Result<(), Diagnostic> {
        match v.value {
            TuneValue::Number(x) if x.fract() == 0.0 && x >= f64::from(lo) && x <= f64::from(hi) => Ok(()),
            TuneValue::Number(_) | TuneValue::Bool(_) | TuneValue::Name(_) => Err(diag(
                v.span,
                format!("`{name}`: `{}` is not {what} from {lo} to {hi}", v.value),
                "out of range",
            )),
        }
    };
    if name == "shadow_map" {
        return values.iter().try_for_each(|v| whole(v, 1, MAX_SHADOW_MAP, "a texel count"));
    }
    if name == "cascades" {
        return values.iter().try_for_each(|v| whole(v, 1, MAX_CASCADES, "a cascade count"));
    }
    if let Some(target) = name.strip_prefix("precision:") {
        if !t.channels.iter().any(|c| c.name.value == target) && !t.expansions.iter().any(|e| e.name.value == target) {
            return Err(unknown(t, axis, format!("no channel or expansion is named `{target}`")));
        }
        for v in values {
            if !matches!(&v.value, TuneValue::Name(n) if Precision::parse(n).is_some()) {
                return Err(diag(v.span, format!("`{}` is not a precision", v.value), "not a precision")
                    .note("expected one of: Unorm8, Unorm16, F16, F32"));
            }
        }
        return Ok(());
    }
    if let Some(target) = name.strip_prefix("schedule:") {
        if !t.passes.iter().any(|p| p.name.value == target && p.kind.schedulable()) {
            return Err(unknown(
                t,
                axis,
                format!("no Map, Filter, Mipmap or Shade pass is named `{target}`"),
            ));
        }
        for v in values {
            if !matches!(&v.value, TuneValue::Name(n) if Schedule::NAMES.contains(&n.as_str())) {
                return Err(diag(v.span, format!("`{}` is not a schedule", v.value), "not a schedule")
                    .note(format!("expected one of: {}", Schedule::NAMES.join(", "))));
            }
        }
        return Ok(());
    }
    Err(unknown(t, axis, format!("the technique has no param `{name}`")))
}

fn unknown(t: &Technique, axis: &TuneAxis, msg: String) -> Diagnostic {
    let names = axis_kinds(t);
    let refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut d = diag(axis.name.span, format!("unknown axis `{}`: {msg}", axis.name.value), "unknown axis");
    if let Some(c) = closest(&axis.name.value, &refs) {
        d = d.help(format!("did you mean `{c}`?"));
    }
    d.note(format!("the axes are: {}", names.join(", ")))
}

/// The technique parsed and its `tune:` block checked.
fn parsed(source: &str) -> Result<Technique, Diagnostic> {
    let t = crate::front::parse::parse(source)?;
    check(&t)?;
    Ok(t)
}

/// A technique's search space, its `tune:` block applied. Parses the source (its errors
/// as diagnostics).
pub fn space(source: &str) -> Result<Space, Diagnostics> {
    let t = parsed(source).map_err(|d| Diagnostics(vec![d]))?;
    Ok(space_of(&t))
}

/// Why [`space_with`] failed: the technique's source, or one override, whose text (as
/// `{ "NAME": VALUE }`) the diagnostics' spans point into.
#[derive(Debug)]
pub enum SpaceError {
    Source(Diagnostics),
    Override { text: String, diagnostics: Diagnostics },
}

/// [`space`], with `overrides` (axis name, choice as a `tune:` entry writes it: `[v, ...]`,
/// `(lo, hi)` or `Frozen`) added to the technique's `tune:` block or replacing its entry
/// for that axis, each checked as the block is: `sshc tune --axis NAME=CHOICE`.
pub fn space_with(source: &str, overrides: &[(String, String)]) -> Result<Space, SpaceError> {
    let mut t = parsed(source).map_err(|d| SpaceError::Source(Diagnostics(vec![d])))?;
    for (name, choice) in overrides {
        let quoted = format!("\"{}\"", name.replace('\\', "\\\\").replace('"', "\\\""));
        let text = format!("{{ {quoted}: {choice} }}");
        let fail = |d: Diagnostic| SpaceError::Override {
            text: text.clone(),
            diagnostics: Diagnostics(vec![d]),
        };
        let node = crate::front::ron::parse(&text).map_err(fail)?;
        for axis in crate::front::parse::tune_block(&node).map_err(fail)? {
            check_axis(&t, &axis).map_err(fail)?;
            t.tune.retain(|a| a.name.value != axis.name.value);
            t.tune.push(axis);
        }
    }
    Ok(space_of(&t))
}

/// The whole numbers of a declared I32 range, within i32 (a range may be written wider).
fn int_domain(lo: f64, hi: f64) -> Domain {
    let (min, max) = (f64::from(i32::MIN), f64::from(i32::MAX));
    Domain::Int {
        lo: lo.ceil().clamp(min, max) as i64,
        hi: hi.floor().clamp(min, max) as i64,
    }
}

fn space_of(t: &Technique) -> Space {
    let narrowed = |name: &str| t.tune.iter().find(|a| a.name.value == name).map(|a| &a.choice);
    let texts = |v: &[crate::span::Spanned<TuneValue>]| v.iter().map(|v| v.value.to_string()).collect::<Vec<_>>();
    let mut axes = Vec::new();
    for p in &t.params {
        let name = p.name.value.clone();
        let default = Some(literal(p.ty.value, p.default.value.as_f64()));
        let declared = match (p.ty.value, &p.range) {
            (ScalarTy::Bool, _) => Some(Domain::Choice(vec!["false".into(), "true".into()])),
            (ScalarTy::I32, Some((lo, hi))) => Some(int_domain(lo.value, hi.value)),
            (ScalarTy::F32, Some((lo, hi))) => Some(Domain::Real {
                lo: lo.value,
                hi: hi.value,
            }),
            (_, None) => None,
        };
        let (domain, frozen) = match (narrowed(&name), declared) {
            (Some(TuneChoice::Frozen), d) => (d.unwrap_or(Domain::Choice(vec![])), Some("frozen by `tune:`".to_string())),
            (Some(TuneChoice::Values(v)), _) => (
                Domain::Choice(
                    v.iter()
                        .map(|v| match &v.value {
                            TuneValue::Number(x) => literal(p.ty.value, *x),
                            other @ (TuneValue::Bool(_) | TuneValue::Name(_)) => other.to_string(),
                        })
                        .collect(),
                ),
                None,
            ),
            (Some(TuneChoice::Range(lo, hi)), _) if p.ty.value == ScalarTy::I32 => (int_domain(lo.value, hi.value), None),
            (Some(TuneChoice::Range(lo, hi)), _) => (
                Domain::Real {
                    lo: lo.value,
                    hi: hi.value,
                },
                None,
            ),
            (None, Some(d)) => (d, None),
            (None, None) => (Domain::Choice(vec![]), Some("no declared `range:`".to_string())),
        };
        axes.push(Axis {
            name,
            domain,
            default,
            frozen,
        });
    }
    let choice = |name: String, all: Vec<String>, default: Option<String>| -> Axis {
        let (domain, frozen) = match narrowed(&name) {
            Some(TuneChoice::Frozen) => (Domain::Choice(all), Some("frozen by `tune:`".to_string())),
            Some(TuneChoice::Values(v)) => (Domain::Choice(texts(v)), None),
            // a range on a non-param is refused by `check`
            Some(TuneChoice::Range(..)) | None => (Domain::Choice(all), None),
        };
        Axis {
            name,
            domain,
            default,
            frozen,
        }
    };
    let precisions = || Precision::ALL.iter().map(|p| p.name().to_string()).collect::<Vec<_>>();
    for c in &t.channels {
        let default = (!c.precision_auto).then(|| c.precision.value.name().to_string());
        axes.push(choice(format!("precision:{}", c.name.value), precisions(), default));
    }
    for e in &t.expansions {
        let default = (!e.precision_auto).then(|| e.precision.value.name().to_string());
        axes.push(choice(format!("precision:{}", e.name.value), precisions(), default));
    }
    for p in t.passes.iter().filter(|p| p.kind.schedulable()) {
        let default = Some(p.kind.schedule().unwrap_or_default().variant().to_string());
        let names = Schedule::NAMES.iter().map(|s| s.to_string()).collect();
        axes.push(choice(format!("schedule:{}", p.name.value), names, default));
    }
    let sizes = SHADOW_MAPS.iter().map(u32::to_string).collect();
    axes.push(choice(
        "shadow_map".into(),
        sizes,
        t.shadow_map.as_ref().map(|s| s.value.to_string()),
    ));
    let cascades = (1..=MAX_CASCADES).map(|n| n.to_string()).collect();
    axes.push(choice("cascades".into(), cascades, None));
    Space {
        technique: t.name.value.clone(),
        axes,
        shadow_map: t.shadow_map.as_ref().map(|s| s.value),
    }
}

/// The technique source with `values` (axis name, RON literal) as its defaults,
/// precisions, schedules and `shadow_map:`, and `header` (lines, without `//`) as a comment
/// above it. `cascades` is not a property of a technique and is left to the header. The
/// result parses (checked) and keeps everything else of the source as written.
pub fn rewrite(source: &str, values: &[(String, String)], header: &[String]) -> Result<String, Diagnostics> {
    let t = parsed(source).map_err(|d| Diagnostics(vec![d]))?;
    let fail = |msg: String| Diagnostics(vec![Diagnostic::error(Phase::Parse, msg)]);
    // (start, end, replacement) edits; an insertion has start == end
    let mut edits: Vec<(usize, usize, String)> = Vec::new();
    // after the first `,` at or after `at` (the end of a field's value): a new field there
    let after_comma = |at: usize| -> usize { source[at..].find(',').map_or(at, |i| at + i + 1) };
    for (name, value) in values {
        if let Some(p) = t.params.iter().find(|p| p.name.value == *name) {
            let text = match p.ty.value {
                ScalarTy::Bool => value.clone(),
                ty @ (ScalarTy::F32 | ScalarTy::I32) => literal(
                    ty,
                    value
                        .parse::<f64>()
                        .map_err(|_| fail(format!("`{name}` = `{value}` is not a number")))?,
                ),
            };
            edits.push((p.default.span.start as usize, p.default.span.end as usize, text));
        } else if let Some(target) = name.strip_prefix("precision:") {
            let span = t
                .channels
                .iter()
                .find(|c| c.name.value == target)
                .map(|c| c.precision.span)
                .or_else(|| t.expansions.iter().find(|e| e.name.value == target).map(|e| e.precision.span))
                .ok_or_else(|| fail(format!("no channel or expansion `{target}`")))?;
            edits.push((span.start as usize, span.end as usize, value.clone()));
        } else if let Some(target) = name.strip_prefix("schedule:") {
            let pass = t
                .passes
                .iter()
                .find(|p| p.name.value == target)
                .ok_or_else(|| fail(format!("no pass `{target}`")))?;
            match pass.kind.schedule_span() {
                Some(s) => edits.push((s.start as usize, s.end as usize, value.clone())),
                None => {
                    let at = after_comma(pass.name.span.end as usize);
                    edits.push((at, at, format!(" schedule: {value},")));
                }
            }
        } else if name == "shadow_map" {
            match &t.shadow_map {
                Some(s) => edits.push((s.span.start as usize, s.span.end as usize, value.clone())),
                None => {
                    let at = after_comma(t.name.span.end as usize);
                    edits.push((at, at, format!("\n    shadow_map: {value},")));
                }
            }
        } else if name != "cascades" {
            return Err(fail(format!("the technique has no axis `{name}`")));
        }
    }
    edits.sort_by_key(|e| std::cmp::Reverse(e.0));
    let mut out = source.to_string();
    for (start, end, text) in edits {
        out.replace_range(start..end, &text);
    }
    let mut head: String = header
        .iter()
        .map(|l| if l.is_empty() { "//\n".to_string() } else { format!("// {l}\n") })
        .collect();
    head.push_str(&out);
    parsed(&head).map_err(|d| Diagnostics(vec![d]))?;
    Ok(head)
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: &str = r#"// a comment kept
Technique(
    name: "t",
    params: {
        "bias": Param(ty: F32, default: 0.001, range: (0.0, 0.1)),
        "N": Param(ty: I32, default: 4, range: (1, 16), fixed: true),
        "free": Param(ty: F32, default: 2.0),
    },
    channels: { "z": Channel(precision: F32) },
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Shade(name: "shade", reads: ["shadow"], visibility: "select(0.0, 1.0, d - bias <= sample(z))"),
    ],
    TUNE
)"#;

    fn with(tune: &str) -> String {
        T.replace("TUNE", tune)
    }

    fn error(tune: &str) -> String {
        let e = space(&with(tune)).unwrap_err();
        let d = &e.0[0];
        format!("{} | {} | {:?}", d.message, d.primary.1, d.help)
    }

    #[test]
    fn the_space_has_every_declared_range_precision_schedule_and_map_size() {
        let s = space(&with("")).unwrap();
        let names: Vec<&str> = s.axes.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(
            names,
            ["bias", "N", "free", "precision:z", "schedule:shade", "shadow_map", "cascades"]
        );
        assert_eq!(s.axes[0].domain, Domain::Real { lo: 0.0, hi: 0.1 });
        assert_eq!(s.axes[1].domain, Domain::Int { lo: 1, hi: 16 });
        // no declared range: not searched, and said why
        assert_eq!(s.axes[2].frozen.as_deref(), Some("no declared `range:`"));
        assert!(!s.axes[2].varies());
        assert_eq!(s.axes[5].domain, Domain::Choice(SHADOW_MAPS.iter().map(u32::to_string).collect()));
        assert_eq!(s.axes[0].default.as_deref(), Some("0.001"));
    }

    #[test]
    fn a_tune_block_narrows_and_freezes_axes() {
        let s = space(&with(
            r#"tune: { "N": [3, 5, 7], "bias": (0.0, 0.01), "shadow_map": [512, 1024], "precision:z": Frozen },"#,
        ))
        .unwrap();
        let axis = |n: &str| s.axes.iter().find(|a| a.name == n).unwrap().clone();
        assert_eq!(axis("N").domain, Domain::Choice(vec!["3".into(), "5".into(), "7".into()]));
        assert_eq!(axis("bias").domain, Domain::Real { lo: 0.0, hi: 0.01 });
        assert_eq!(axis("shadow_map").domain, Domain::Choice(vec!["512".into(), "1024".into()]));
        assert!(!axis("precision:z").varies());
    }

    #[test]
    fn bad_tune_entries_are_refused_at_the_entry() {
        let e = error(r#"tune: { "N": [3, 17] },"#);
        assert!(e.contains("`N` = 17 is outside the param's declared range (1, 16)"), "{e}");
        let e = error(r#"tune: { "bias": (0.0, 0.5) },"#);
        assert!(e.contains("`bias` = 0.5 is outside the param's declared range (0, 0.1)"), "{e}");
        let e = error(r#"tune: { "biass": [0.1] },"#);
        assert!(
            e.contains("unknown axis `biass`: the technique has no param `biass`") && e.contains("did you mean `bias`?"),
            "{e}"
        );
        let e = error(r#"tune: { "N": [2.5] },"#);
        assert!(e.contains("`N` is a i32 param: `2.5` is not one of its values"), "{e}");
        let e = error(r#"tune: { "precision:z": [F64] },"#);
        assert!(e.contains("`F64` is not a precision"), "{e}");
        let e = error(r#"tune: { "schedule:depth": [Compute] },"#);
        assert!(e.contains("no Map, Filter, Mipmap or Shade pass is named `depth`"), "{e}");
        let e = error(r#"tune: { "shadow_map": [0] },"#);
        assert!(e.contains("`shadow_map`: `0` is not a texel count from 1 to 16384"), "{e}");
        let e = error(r#"tune: { "free": (0.0, 1.0) },"#);
        assert!(e.contains("`free` declares no `range:`"), "{e}");
        let e = error(r#"tune: { "N": [], },"#);
        assert!(e.contains("the axis `N` has no values"), "{e}");
    }

    #[test]
    fn rewrite_sets_defaults_precisions_schedules_and_the_map_size_and_keeps_the_rest() {
        let src = with(r#"tune: { "N": [3, 5] },"#);
        let values = [
            ("bias".to_string(), "0.0025".to_string()),
            ("N".to_string(), "5".to_string()),
            ("precision:z".to_string(), "F16".to_string()),
            ("schedule:shade".to_string(), "Compute".to_string()),
            ("shadow_map".to_string(), "1024".to_string()),
            ("cascades".to_string(), "2".to_string()),
        ];
        let out = rewrite(&src, &values, &["tuned by a test".to_string()]).unwrap();
        assert!(out.starts_with("// tuned by a test\n// a comment kept\n"), "{out}");
        let s = space(&out).unwrap();
        let default = |n: &str| s.axes.iter().find(|a| a.name == n).unwrap().default.clone().unwrap();
        assert_eq!(default("bias"), "0.0025");
        assert_eq!(default("N"), "5");
        assert_eq!(default("precision:z"), "F16");
        assert_eq!(default("schedule:shade"), "Compute");
        assert_eq!(s.shadow_map, Some(1024));
        assert!(out.contains(r#"tune: { "N": [3, 5] },"#));
        // it compiles, and the graph carries the map size to every host
        let c = crate::compile_str(&out, &Default::default()).unwrap();
        assert_eq!(c.graph.shadow_map, Some(1024));
        let back = sshc_graph::PassGraph::from_ron(&c.graph.to_ron()).unwrap();
        assert_eq!(back.shadow_map, Some(1024));
        assert_eq!(crate::compile_str(&src, &Default::default()).unwrap().graph.shadow_map, None);
        // rewriting a tuned file again replaces in place rather than inserting twice
        let again = rewrite(
            &out,
            &[("shadow_map".into(), "512".into()), ("schedule:shade".into(), "Fragment".into())],
            &[],
        )
        .unwrap();
        assert_eq!(space(&again).unwrap().shadow_map, Some(512));
        assert_eq!(again.matches("shadow_map:").count(), 1);
        assert_eq!(again.matches("schedule:").count(), 1);
        assert!(rewrite(&src, &[("nope".into(), "1".into())], &[]).is_err());
    }

    #[test]
    fn command_line_axes_narrow_like_the_block_and_are_checked_in_their_own_text() {
        let s = space_with(
            &with(r#"tune: { "N": [3, 5] },"#),
            &[("N".into(), "[2, 6]".into()), ("bias".into(), "Frozen".into())],
        )
        .unwrap();
        let axis = |n: &str| s.axes.iter().find(|a| a.name == n).unwrap().clone();
        assert_eq!(axis("N").domain, Domain::Choice(vec!["2".into(), "6".into()]));
        assert!(!axis("bias").varies());
        match space_with(&with(""), &[("N".into(), "[3, 40]".into())]) {
            Err(SpaceError::Override { text, diagnostics }) => {
                let d = &diagnostics.0[0];
                assert!(d.message.contains("`N` = 40 is outside"), "{}", d.message);
                assert_eq!(&text[d.primary.0.start as usize..d.primary.0.end as usize], "40");
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            space_with(&with(""), &[("N".into(), "[3".into())]),
            Err(SpaceError::Override { .. })
        ));
        assert!(matches!(space_with("Technique(", &[]), Err(SpaceError::Source(_))));
    }

    #[test]
    fn f32_literals_read_back() {
        assert_eq!(literal(ScalarTy::F32, 1.0), "1.0");
        assert_eq!(literal(ScalarTy::F32, 0.0005), "0.0005");
        assert_eq!(literal(ScalarTy::F32, 1e-7), "1e-7");
        assert_eq!(literal(ScalarTy::I32, 7.0), "7");
    }
}
