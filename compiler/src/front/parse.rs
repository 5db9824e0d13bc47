//! Phase `parse`: the spanned RON tree becomes a [`Technique`] AST. Every unknown field,
//! missing field, wrong kind of value and malformed expression string is a diagnostic
//! at the offending text.
//!
//! Matches on the RON value tree accept the shapes a field may take and refuse every other
//! with a diagnostic, so their last arm is `_`: a value kind added to the reader is refused
//! by default, which is the behaviour wanted, not a case left out.
#![allow(clippy::wildcard_enum_match_arm)]

use crate::diag::{Diagnostic, Phase};
use crate::front::ast::*;
use crate::front::expr::{self, Expr, ExprKind, Literal};
use crate::front::ron::{self, Field, Node, Value};
use crate::span::{Span, Spanned};

/// The most passes a technique may have: each pass takes two timestamp queries of one
/// query set at render time (wgpu allows 4,096 queries in a set), with a wide margin.
pub const MAX_PASSES: usize = 256;

/// Read a technique from RON text.
pub fn parse(source: &str) -> Result<Technique, Diagnostic> {
    let root = ron::parse(source)?;
    technique(&root)
}

fn err(span: Span, msg: impl Into<String>, label: impl Into<String>) -> Diagnostic {
    Diagnostic::error(Phase::Parse, msg).at(span, label)
}

/// The fields of one `Name(field: value, ...)`, taken one by one; leftovers are errors.
struct Fields<'a> {
    what: &'static str,
    span: Span,
    fields: Vec<&'a Field>,
    taken: Vec<bool>,
    known: Vec<&'static str>,
}

impl<'a> Fields<'a> {
    fn of(node: &'a Node, what: &'static str) -> Result<Self, Diagnostic> {
        match &node.value {
            Value::Struct { name, fields } => {
                if let Some((n, span)) = name
                    && n != what
                {
                    return Err(err(
                        *span,
                        format!("expected `{what}(...)`, found `{n}(...)`"),
                        format!("expected `{what}`"),
                    ));
                }
                Ok(Fields {
                    what,
                    span: node.span,
                    fields: fields.iter().collect(),
                    taken: vec![false; fields.len()],
                    known: Vec::new(),
                })
            }
            Value::Tuple { items, .. } if items.is_empty() => Ok(Fields {
                what,
                span: node.span,
                fields: Vec::new(),
                taken: Vec::new(),
                known: Vec::new(),
            }),
            _ => Err(err(
                node.span,
                format!("expected `{what}(...)`, found {}", node.describe()),
                format!("expected `{what}(field: value, ...)`"),
            )),
        }
    }

    fn opt(&mut self, name: &'static str) -> Result<Option<&'a Node>, Diagnostic> {
        self.known.push(name);
        let mut found = None;
        for (i, f) in self.fields.iter().enumerate() {
            if f.name == name {
                if found.is_some() {
                    return Err(err(
                        f.name_span,
                        format!("field `{name}` is given twice in `{}`", self.what),
                        "second time here",
                    ));
                }
                self.taken[i] = true;
                found = Some(&f.value);
            }
        }
        Ok(found)
    }

    fn req(&mut self, name: &'static str) -> Result<&'a Node, Diagnostic> {
        match self.opt(name)? {
            Some(n) => Ok(n),
            None => {
                let mut d = err(
                    self.span,
                    format!("missing field `{name}` in `{}`", self.what),
                    format!("`{name}: ...` is required here"),
                );
                // A misspelling of it among the fields given?
                if let Some(f) = self
                    .fields
                    .iter()
                    .zip(&self.taken)
                    .find(|(f, t)| !**t && closest(&f.name, &[name]).is_some())
                    .map(|(f, _)| f)
                {
                    d = d
                        .also(f.name_span, "unknown field")
                        .help(format!("`{}` is not a field of `{}`: did you mean `{name}`?", f.name, self.what));
                }
                Err(d)
            }
        }
    }

    fn finish(self) -> Result<(), Diagnostic> {
        for (i, f) in self.fields.iter().enumerate() {
            if !self.taken[i] {
                let mut d = err(
                    f.name_span,
                    format!("unknown field `{}` in `{}`", f.name, self.what),
                    "unknown field",
                );
                if let Some(s) = closest(&f.name, &self.known) {
                    d = d.help(format!("did you mean `{s}`?"));
                } else {
                    d = d.note(format!("`{}` has the fields: {}", self.what, self.known.join(", ")));
                }
                return Err(d);
            }
        }
        Ok(())
    }
}

/// The candidate closest to `name` by edit distance, if it is close enough to be a typo.
pub fn closest<'a>(name: &str, candidates: &[&'a str]) -> Option<&'a str> {
    candidates
        .iter()
        .map(|c| (edit_distance(name, c), *c))
        .filter(|(d, c)| *d <= (c.len().max(name.len()) / 3).max(1))
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + (ca != *cb) as usize).min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

fn string(node: &Node) -> Result<Spanned<String>, Diagnostic> {
    match &node.value {
        Value::Str(s) => Ok(Spanned::new(s.text.clone(), node.span)),
        _ => Err(err(
            node.span,
            format!("expected a string, found {}", node.describe()),
            "expected a string",
        )),
    }
}

/// A name: a string holding an identifier.
fn name(node: &Node) -> Result<Name, Diagnostic> {
    let s = string(node)?;
    let ok = s.value.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && s.value.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !ok {
        return Err(
            err(node.span, format!("`{}` is not a valid name", s.value), "names are identifiers")
                .help("use letters, digits and `_`, starting with a letter"),
        );
    }
    Ok(s)
}

fn names(node: &Node) -> Result<Vec<Name>, Diagnostic> {
    match &node.value {
        Value::List(items) => items.iter().map(name).collect(),
        Value::Str(_) => Ok(vec![name(node)?]),
        _ => Err(err(
            node.span,
            format!("expected a list of names, found {}", node.describe()),
            "expected `[\"a\", \"b\"]`",
        )),
    }
}

fn boolean(node: &Node) -> Result<bool, Diagnostic> {
    match &node.value {
        Value::Bool(b) => Ok(*b),
        _ => Err(err(
            node.span,
            format!("expected `true` or `false`, found {}", node.describe()),
            "expected a boolean",
        )),
    }
}

fn number(node: &Node) -> Result<Spanned<f64>, Diagnostic> {
    match &node.value {
        Value::Int(v) => Ok(Spanned::new(*v as f64, node.span)),
        Value::Float(v) => Ok(Spanned::new(*v, node.span)),
        _ => Err(err(
            node.span,
            format!("expected a number, found {}", node.describe()),
            "expected a number",
        )),
    }
}

/// An expression: a string in the expression language, or a plain number.
fn expression(node: &Node) -> Result<Expr, Diagnostic> {
    match &node.value {
        Value::Str(s) => expr::parse(s),
        Value::Int(v) => Ok(Expr::new(ExprKind::Lit(Literal::Int(*v)), node.span)),
        Value::Float(v) => Ok(Expr::new(ExprKind::Lit(Literal::Float(*v)), node.span)),
        Value::Bool(v) => Ok(Expr::new(ExprKind::Lit(Literal::Bool(*v)), node.span)),
        _ => Err(err(
            node.span,
            format!("expected an expression string, found {}", node.describe()),
            "expected an expression such as \"exp(c * z)\"",
        )),
    }
}

fn opt_string(f: &mut Fields, key: &'static str) -> Result<Option<String>, Diagnostic> {
    f.opt(key)?.map(|n| string(n).map(|s| s.value)).transpose()
}

/// An identifier-like enum value: `Unorm8`, or `Segment(samples: 4)` for variants with data.
fn variant(node: &Node) -> Result<(String, Span), Diagnostic> {
    match &node.value {
        Value::Ident(n) => Ok((n.clone(), node.span)),
        Value::Struct { name: Some((n, s)), .. } | Value::Tuple { name: Some((n, s)), .. } => Ok((n.clone(), *s)),
        _ => Err(err(
            node.span,
            format!("expected a name such as `F32`, found {}", node.describe()),
            "expected a variant name",
        )),
    }
}

fn unknown_variant(span: Span, got: &str, what: &str, options: &[&'static str]) -> Diagnostic {
    let mut d = err(span, format!("unknown {what} `{got}`"), format!("not a {what}"));
    if let Some(s) = closest(got, options) {
        d = d.help(format!("did you mean `{s}`?"));
    }
    d.note(format!("expected one of: {}", options.join(", ")))
}

/// Entries of a map `{ "name": value }`, in order.
fn map_entries(node: &Node) -> Result<Vec<(Name, &Node)>, Diagnostic> {
    match &node.value {
        Value::Map(entries) => entries.iter().map(|(k, v)| Ok((name(k)?, v))).collect(),
        _ => Err(err(
            node.span,
            format!("expected a map `{{ \"name\": ... }}`, found {}", node.describe()),
            "expected a map",
        )),
    }
}

fn technique(root: &Node) -> Result<Technique, Diagnostic> {
    let mut f = Fields::of(root, "Technique")?;
    let name = name(f.req("name")?)?;
    let title = opt_string(&mut f, "title")?;
    let paper = opt_string(&mut f, "paper")?;
    let lights = match f.opt("light")? {
        None => vec![],
        Some(n) => match &n.value {
            Value::List(items) => items.iter().map(light).collect::<Result<_, _>>()?,
            _ => vec![light(n)?],
        },
    };
    let params = match f.opt("params")? {
        None => vec![],
        Some(n) => map_entries(n)?.into_iter().map(|(k, v)| param(k, v)).collect::<Result<_, _>>()?,
    };
    let channels = match f.opt("channels")? {
        None => vec![],
        Some(n) => map_entries(n)?.into_iter().map(|(k, v)| channel(k, v)).collect::<Result<_, _>>()?,
    };
    let expansions = match f.opt("expansions")? {
        None => vec![],
        Some(n) => map_entries(n)?
            .into_iter()
            .map(|(k, v)| expansion(k, v))
            .collect::<Result<_, _>>()?,
    };
    let functions = match f.opt("functions")? {
        None => vec![],
        Some(n) => map_entries(n)?.into_iter().map(|(k, v)| function(k, v)).collect::<Result<_, _>>()?,
    };
    let arrays = match f.opt("arrays")? {
        None => vec![],
        Some(n) => map_entries(n)?.into_iter().map(|(k, v)| array(k, v)).collect::<Result<_, _>>()?,
    };
    let passes_node = f.req("passes")?;
    let passes = match &passes_node.value {
        Value::List(items) if items.len() > MAX_PASSES => {
            return Err(err(
                items[MAX_PASSES].span,
                format!("technique has {} passes: at most {MAX_PASSES}", items.len()),
                "one pass too many",
            )
            .help("each pass takes two GPU timestamp queries and a dispatch or draw; merge passes"));
        }
        Value::List(items) => items.iter().map(pass).collect::<Result<_, _>>()?,
        _ => {
            return Err(err(
                passes_node.span,
                format!("expected a list of passes, found {}", passes_node.describe()),
                "expected `[Depth(...), ...]`",
            ));
        }
    };
    let light_samples = f.opt("light_samples")?.map(expression).transpose()?;
    let shadow_map = f.opt("shadow_map")?.map(shadow_map_size).transpose()?;
    let tune = match f.opt("tune")? {
        None => vec![],
        Some(n) => tune_block(n)?,
    };
    f.finish()?;
    let t = Technique {
        name,
        title,
        paper,
        lights,
        params,
        channels,
        expansions,
        functions,
        arrays,
        passes,
        light_samples,
        shadow_map,
        tune,
        span: root.span,
    };
    Ok(t)
}

pub use sshc_graph::MAX_SHADOW_MAP;

/// `shadow_map: N`, a whole number of texels in 1..=[`MAX_SHADOW_MAP`].
fn shadow_map_size(node: &Node) -> Result<Spanned<u32>, Diagnostic> {
    match node.value {
        Value::Int(n) if (1..=i64::from(MAX_SHADOW_MAP)).contains(&n) => Ok(Spanned::new(n as u32, node.span)),
        _ => Err(err(
            node.span,
            format!(
                "`shadow_map` needs a whole number of texels from 1 to {MAX_SHADOW_MAP}, found {}",
                node.describe()
            ),
            "expected a texel count such as 1024",
        )),
    }
}

/// One `tune:` entry's choice: `[v, ...]`, `(lo, hi)` or `Frozen` (also `sshc tune --axis`).
pub fn tune_choice(name: &str, v: &Node) -> Result<TuneChoice, Diagnostic> {
    Ok(match &v.value {
        Value::Ident(w) if w == "Frozen" => TuneChoice::Frozen,
        Value::List(items) if items.is_empty() => {
            return Err(err(v.span, format!("the axis `{}` has no values", name), "empty list")
                .help("give at least one value, or write `Frozen` to keep the technique's own"));
        }
        Value::List(items) => TuneChoice::Values(
            items
                .iter()
                .map(|i| {
                    let value = match &i.value {
                        Value::Int(x) => TuneValue::Number(*x as f64),
                        Value::Float(x) => TuneValue::Number(*x),
                        Value::Bool(b) => TuneValue::Bool(*b),
                        Value::Ident(n) => TuneValue::Name(n.clone()),
                        _ => {
                            return Err(err(
                                i.span,
                                format!("expected a number, `true`, `false` or a name such as `F16`, found {}", i.describe()),
                                "not a value of an axis",
                            ));
                        }
                    };
                    Ok(Spanned::new(value, i.span))
                })
                .collect::<Result<_, _>>()?,
        ),
        Value::Tuple { name: None, items } if items.len() == 2 => TuneChoice::Range(number(&items[0])?, number(&items[1])?),
        _ => {
            return Err(err(
                v.span,
                format!("expected a list of values, a range `(lo, hi)` or `Frozen`, found {}", v.describe()),
                "not an axis choice",
            ));
        }
    })
}

/// `tune: { "AXIS": [values] | (lo, hi) | Frozen, ... }`: the axes are checked against the
/// technique's params, channels and passes by `tune::check`, which the driver runs after
/// the parse.
pub(crate) fn tune_block(node: &Node) -> Result<Vec<TuneAxis>, Diagnostic> {
    let Value::Map(entries) = &node.value else {
        return Err(err(
            node.span,
            format!("expected a map `{{ \"AXIS\": [values] }}`, found {}", node.describe()),
            "expected a map",
        ));
    };
    let mut out: Vec<TuneAxis> = Vec::new();
    for (k, v) in entries {
        let name = string(k)?;
        if let Some(first) = out.iter().find(|a| a.name.value == name.value) {
            return Err(err(name.span, format!("the axis `{}` is named twice", name.value), "again here")
                .help(format!("its first entry is at byte {}: keep one", first.name.span.start)));
        }
        let choice = tune_choice(&name.value, v)?;
        out.push(TuneAxis {
            name,
            choice,
            span: k.span.join(v.span),
        });
    }
    Ok(out)
}

/// A value type of the expression language: `F32`, `I32`, `U32`, `Bool`, `Vec2` to `Vec4`.
fn value_ty(v: &Node, what: &str) -> Result<Spanned<crate::builtins::Ty>, Diagnostic> {
    use crate::builtins::Ty;
    let (t, span) = variant(v)?;
    let ty = match t.as_str() {
        "F32" => Ty::F32,
        "I32" => Ty::I32,
        "U32" => Ty::U32,
        "Bool" => Ty::Bool,
        "Vec2" => Ty::Vec(2),
        "Vec3" => Ty::Vec(3),
        "Vec4" => Ty::Vec(4),
        _ => {
            return Err(unknown_variant(
                span,
                &t,
                what,
                &["F32", "I32", "U32", "Bool", "Vec2", "Vec3", "Vec4"],
            ));
        }
    };
    Ok(Spanned::new(ty, v.span))
}

/// `"name": Array(ty: Vec2, values: ["vec2(0.5, 0.25)", ...], doc: "...")`; a number may
/// stand for an expression.
fn array(name: Name, node: &Node) -> Result<ArrayDecl, Diagnostic> {
    let mut f = Fields::of(node, "Array")?;
    let ty = value_ty(f.req("ty")?, "element type")?;
    let vn = f.req("values")?;
    let values = match &vn.value {
        Value::List(items) if items.is_empty() => {
            return Err(err(vn.span, "an array needs at least one value", "empty"));
        }
        Value::List(items) => items
            .iter()
            .map(|v| match &v.value {
                Value::Int(i) => Ok(crate::front::expr::Expr::new(
                    crate::front::expr::ExprKind::Lit(crate::front::expr::Literal::Int(*i)),
                    v.span,
                )),
                Value::Float(x) => Ok(crate::front::expr::Expr::new(
                    crate::front::expr::ExprKind::Lit(crate::front::expr::Literal::Float(*x)),
                    v.span,
                )),
                _ => expression(v),
            })
            .collect::<Result<_, _>>()?,
        _ => {
            return Err(err(
                vn.span,
                format!("expected a list of values, found {}", vn.describe()),
                "expected `[...]`",
            ));
        }
    };
    let doc = opt_string(&mut f, "doc")?;
    f.finish()?;
    Ok(ArrayDecl {
        name,
        ty,
        values,
        doc,
        span: node.span,
    })
}

/// A function parameter's type: a value type, or `Channel` / `Expansion` (passed by name).
fn param_ty(v: &Node) -> Result<Spanned<ParamTy>, Diagnostic> {
    let (t, span) = variant(v)?;
    match t.as_str() {
        "Channel" => Ok(Spanned::new(ParamTy::Channel, v.span)),
        "Expansion" => Ok(Spanned::new(ParamTy::Expansion, v.span)),
        "F32" | "I32" | "U32" | "Bool" | "Vec2" | "Vec3" | "Vec4" => {
            let ty = value_ty(v, "parameter type")?;
            Ok(Spanned::new(ParamTy::Value(ty.value), ty.span))
        }
        _ => Err(unknown_variant(
            span,
            &t,
            "parameter type",
            &["F32", "I32", "U32", "Bool", "Vec2", "Vec3", "Vec4", "Channel", "Expansion"],
        )),
    }
}

/// `"name": Function(params: { "x": F32, ... }, body: "...", doc: "...")`.
fn function(name: Name, node: &Node) -> Result<Function, Diagnostic> {
    let mut f = Fields::of(node, "Function")?;
    let params = match f.opt("params")? {
        None => vec![],
        Some(n) => map_entries(n)?
            .into_iter()
            .map(|(k, v)| Ok((k, param_ty(v)?)))
            .collect::<Result<_, _>>()?,
    };
    let body = expression(f.req("body")?)?;
    let doc = opt_string(&mut f, "doc")?;
    f.finish()?;
    Ok(Function {
        name,
        params,
        body,
        doc,
        span: node.span,
    })
}

fn light(node: &Node) -> Result<Spanned<LightModel>, Diagnostic> {
    let (v, span) = variant(node)?;
    if v == "Any" {
        return Ok(Spanned::new(LightModel::Any, node.span));
    }
    let Some(kind) = LightKind::from_name(&v) else {
        let names: Vec<&'static str> = std::iter::once("Any").chain(LightKind::ALL.map(LightKind::name)).collect();
        return Err(unknown_variant(span, &v, "light model", &names));
    };
    let mut samples = 0;
    if kind.takes_samples() {
        let mut f = Fields::of(node, "Segment")?;
        let n = f.req("samples")?;
        samples = match n.value {
            Value::Int(s) if (2..=64).contains(&s) => s as u32,
            _ => {
                return Err(err(
                    n.span,
                    "a segment light needs between 2 and 64 samples",
                    "expected an integer in 2..=64",
                ));
            }
        };
        f.finish()?;
    }
    Ok(Spanned::new(LightModel::of(kind, samples), node.span))
}

fn param(name: Name, node: &Node) -> Result<Param, Diagnostic> {
    let mut f = Fields::of(node, "Param")?;
    let ty_node = f.req("ty")?;
    let (t, tspan) = variant(ty_node)?;
    let ty = match t.as_str() {
        "F32" => ScalarTy::F32,
        "I32" => ScalarTy::I32,
        "Bool" => ScalarTy::Bool,
        _ => return Err(unknown_variant(tspan, &t, "parameter type", &["F32", "I32", "Bool"])),
    };
    let dn = f.req("default")?;
    let default = const_value(dn, ty)?;
    let range = match f.opt("range")? {
        None => None,
        Some(r) => match &r.value {
            Value::Tuple { name: None, items } if items.len() == 2 => {
                let (lo, hi) = (number(&items[0])?, number(&items[1])?);
                f32_range(r.span, lo.value, hi.value)?;
                Some((lo, hi))
            }
            _ => {
                return Err(err(
                    r.span,
                    format!("expected a range `(lo, hi)`, found {}", r.describe()),
                    "expected `(lo, hi)`",
                ));
            }
        },
    };
    let fixed = f.opt("fixed")?.map(boolean).transpose()?.unwrap_or(false);
    let doc = opt_string(&mut f, "doc")?;
    f.finish()?;
    Ok(Param {
        name,
        ty: Spanned::new(ty, ty_node.span),
        default,
        range,
        fixed,
        doc,
        span: node.span,
    })
}

/// A declared range the shaders can hold: both ends and their width finite in f32 (the
/// generated WGSL clamps and encodes with them in f32; `1e39` would be written `inff`,
/// which naga refuses, and `(-3e38, 3e38)` has a width f32 cannot hold).
fn f32_range(span: Span, lo: f64, hi: f64) -> Result<(), Diagnostic> {
    let max = f64::from(f32::MAX);
    let width = (hi as f32) - (lo as f32);
    if lo.is_finite() && hi.is_finite() && lo.abs() <= max && hi.abs() <= max && width.is_finite() {
        return Ok(());
    }
    Err(err(
        span,
        format!("the range ({lo:?}, {hi:?}) is beyond f32: its ends and its width must stay within ±3.4e38"),
        "beyond f32",
    )
    .help("the shaders evaluate in f32; declare the range the values really take"))
}

/// A value of type `ty` as written in RON (used for defaults and `--set`).
pub fn const_value(node: &Node, ty: ScalarTy) -> Result<Spanned<ConstValue>, Diagnostic> {
    let v = match (&node.value, ty) {
        (Value::Int(v), ScalarTy::I32) => ConstValue::Int(*v),
        (Value::Int(v), ScalarTy::F32) => ConstValue::Float(*v as f64),
        (Value::Float(v), ScalarTy::F32) => ConstValue::Float(*v),
        (Value::Bool(v), ScalarTy::Bool) => ConstValue::Bool(*v),
        _ => {
            return Err(Diagnostic::error(
                Phase::Parse,
                format!("expected a value of type {}, found {}", ty.name(), node.describe()),
            )
            .at(node.span, format!("expected {}", ty.name())));
        }
    };
    if let ConstValue::Int(i) = v
        && i32::try_from(i).is_err()
    {
        return Err(err(node.span, format!("{i} does not fit in i32"), "out of i32 range"));
    }
    Ok(Spanned::new(v, node.span))
}

const PRECISIONS: &[&str] = &["Unorm8", "Unorm16", "F16", "F32", "Auto"];

/// A precision, and whether it is `Auto` (left to the compiler: F32 until it chooses).
fn precision(node: &Node) -> Result<(Spanned<Precision>, bool), Diagnostic> {
    let (v, span) = variant(node)?;
    if v == "Auto" {
        return Ok((Spanned::new(Precision::F32, node.span), true));
    }
    match Precision::parse(&v).filter(|_| PRECISIONS.contains(&v.as_str())) {
        Some(p) => Ok((Spanned::new(p, node.span), false)),
        None => Err(unknown_variant(span, &v, "precision", PRECISIONS)),
    }
}

fn channel(name: Name, node: &Node) -> Result<Channel, Diagnostic> {
    let mut f = Fields::of(node, "Channel")?;
    let (precision, precision_auto) = precision(f.req("precision")?)?;
    let value = f.opt("value")?.map(expression).transpose()?;
    let range = match f.opt("range")? {
        None => None,
        Some(r) => {
            let (lo, hi) = match &r.value {
                Value::Tuple { name: None, items } if items.len() == 2 => (number(&items[0])?, number(&items[1])?),
                _ => {
                    return Err(err(
                        r.span,
                        format!("expected a range `(lo, hi)`, found {}", r.describe()),
                        "expected `(lo, hi)`",
                    ));
                }
            };
            if !(lo.value.is_finite() && hi.value.is_finite() && lo.value < hi.value) {
                return Err(err(
                    r.span,
                    format!(
                        "the range ({}, {}) is not two finite numbers, the first below the second",
                        lo.value, hi.value
                    ),
                    "not a range",
                ));
            }
            f32_range(r.span, lo.value, hi.value)?;
            if value.is_none() {
                return Err(err(
                    r.span,
                    "a declared range belongs to a channel with a `value`: a Depth pass's channel stores depths in [0, 1]".to_string(),
                    "no value to clamp",
                ));
            }
            Some((lo, hi))
        }
    };
    let doc = opt_string(&mut f, "doc")?;
    f.finish()?;
    Ok(Channel {
        name,
        precision,
        precision_auto,
        value,
        range,
        doc,
        span: node.span,
    })
}

fn expansion(name: Name, node: &Node) -> Result<Expansion, Diagnostic> {
    let mut f = Fields::of(node, "Expansion")?;
    let index = name_of(f.req("index")?)?;
    let from = expression(f.req("from")?)?;
    let to = expression(f.req("to")?)?;
    let lets = match f.opt("lets")? {
        None => vec![],
        Some(n) => map_entries(n)?
            .into_iter()
            .map(|(k, v)| Ok((k, expression(v)?)))
            .collect::<Result<_, Diagnostic>>()?,
    };
    let constant = match f.opt("constant")? {
        Some(n) => expression(n)?,
        None => Expr::new(ExprKind::Lit(Literal::Float(0.0)), node.span),
    };
    let tn = f.req("terms")?;
    let terms = match &tn.value {
        Value::List(items) if !items.is_empty() => items.iter().map(term).collect::<Result<_, _>>()?,
        Value::List(_) => return Err(err(tn.span, "an expansion needs at least one term", "no terms")),
        _ => {
            return Err(err(
                tn.span,
                format!("expected a list of terms, found {}", tn.describe()),
                "expected `[Term(coeff: ..., basis: ...)]`",
            ));
        }
    };
    let (precision, precision_auto) = precision(f.req("precision")?)?;
    let doc = opt_string(&mut f, "doc")?;
    f.finish()?;
    Ok(Expansion {
        name,
        index,
        from,
        to,
        lets,
        constant,
        terms,
        precision,
        precision_auto,
        doc,
        span: node.span,
    })
}

fn name_of(node: &Node) -> Result<Name, Diagnostic> {
    name(node)
}

fn term(node: &Node) -> Result<Term, Diagnostic> {
    let mut f = Fields::of(node, "Term")?;
    let coeff = expression(f.req("coeff")?)?;
    let basis = expression(f.req("basis")?)?;
    f.finish()?;
    Ok(Term {
        coeff,
        basis,
        span: node.span,
    })
}

const PASSES: &[&str] = &["Depth", "Map", "Filter", "Mipmap", "SummedArea", "Geometry", "Shade"];

fn light_view(f: &mut Fields) -> Result<LightView, Diagnostic> {
    match f.opt("view")? {
        None => Ok(LightView::Center),
        Some(n) => {
            let (v, span) = variant(n)?;
            match v.as_str() {
                "Center" => Ok(LightView::Center),
                "PerSample" => Ok(LightView::PerSample),
                _ => Err(unknown_variant(span, &v, "light view", &["Center", "PerSample"])),
            }
        }
    }
}

/// A pass's optional `schedule: Fragment | Compute`.
fn schedule(f: &mut Fields) -> Result<Option<Spanned<Schedule>>, Diagnostic> {
    match f.opt("schedule")? {
        None => Ok(None),
        Some(n) => {
            let (v, span) = variant(n)?;
            let value = Schedule::parse(&v)
                .filter(|_| v.starts_with(char::is_uppercase))
                .ok_or_else(|| unknown_variant(span, &v, "schedule", &Schedule::NAMES))?;
            Ok(Some(Spanned { value, span }))
        }
    }
}

fn pass(node: &Node) -> Result<Pass, Diagnostic> {
    let (kind_name, kind_span) = match &node.value {
        Value::Struct { name: Some((n, s)), .. } | Value::Tuple { name: Some((n, s)), .. } => (n.clone(), *s),
        Value::Ident(n) => (n.clone(), node.span),
        _ => {
            return Err(err(
                node.span,
                format!("expected a pass such as `Map(...)`, found {}", node.describe()),
                "expected a pass",
            ));
        }
    };
    if !PASSES.contains(&kind_name.as_str()) {
        return Err(unknown_variant(kind_span, &kind_name, "pass kind", PASSES));
    }
    let what: &'static str = PASSES.iter().find(|p| **p == kind_name).copied().unwrap_or("pass");
    let mut f = Fields::of(node, what)?;
    let name = name(f.req("name")?)?;
    let kind = match what {
        "Depth" => PassKind::Depth {
            writes: self::name(f.req("writes")?)?,
            channel: self::name(f.req("channel")?)?,
            view: light_view(&mut f)?,
        },
        "Map" => PassKind::Map {
            reads: names(f.req("reads")?)?,
            writes: self::name(f.req("writes")?)?,
            channels: names(f.req("channels")?)?,
            schedule: schedule(&mut f)?,
        },
        "Filter" => PassKind::Filter {
            reads: self::name(f.req("reads")?)?,
            writes: self::name(f.req("writes")?)?,
            kernel: kernel(f.req("kernel")?)?,
            schedule: schedule(&mut f)?,
        },
        "Mipmap" => {
            let reads = self::name(f.req("reads")?)?;
            let writes = self::name(f.req("writes")?)?;
            let reduce = match f.opt("reduce")? {
                None => Reduce::Mean,
                Some(n) => {
                    let (v, span) = variant(n)?;
                    match v.as_str() {
                        "Mean" => Reduce::Mean,
                        "Max" => Reduce::Max,
                        "Min" => Reduce::Min,
                        _ => return Err(unknown_variant(span, &v, "reduction", &["Mean", "Max", "Min"])),
                    }
                }
            };
            PassKind::Mipmap {
                reads,
                writes,
                reduce,
                schedule: schedule(&mut f)?,
            }
        }
        "SummedArea" => PassKind::SummedArea {
            reads: self::name(f.req("reads")?)?,
            writes: self::name(f.req("writes")?)?,
            sum: f.opt("sum")?.map(table_sum).transpose()?,
        },
        "Geometry" => {
            let reads = names(f.req("reads")?)?;
            let writes = self::name(f.req("writes")?)?;
            let pn = f.req("primitive")?;
            let (p, ps) = variant(pn)?;
            let primitive = match p.as_str() {
                "ConesAndSheets" => Primitive::ConesAndSheets,
                "Ribbons" => Primitive::Ribbons,
                "Skins" => Primitive::Skins,
                "BackFaces" => Primitive::BackFaces,
                _ => return Err(unknown_variant(ps, &p, "primitive", &Primitive::NAMES)),
            };
            let channels = names(f.req("channels")?)?;
            let rn = f.req("resolve")?;
            // A rule's name, or an expression string giving its index (a fixed param).
            let resolve = if let Value::Str(_) = &rn.value {
                ResolveSpec::Expr(expression(rn)?)
            } else {
                let (r, rs) = variant(rn)?;
                ResolveSpec::Rule(match r.as_str() {
                    "KeepMin" => Resolve::KeepMin,
                    "KeepMax" => Resolve::KeepMax,
                    "Add" => Resolve::Add,
                    "Multiply" => Resolve::Multiply,
                    "Nearest" => Resolve::Nearest,
                    _ => {
                        return Err(unknown_variant(
                            rs,
                            &r,
                            "resolve rule",
                            &["KeepMin", "KeepMax", "Add", "Multiply", "Nearest"],
                        ));
                    }
                })
            };
            let view = light_view(&mut f)?;
            let keep = f.opt("keep")?.map(expression).transpose()?;
            let from = match f.opt("from")? {
                None => None,
                Some(n) => {
                    let (v, span) = variant(n)?;
                    let value = match v.as_str() {
                        "Previous" => Neighbour::Previous,
                        "Next" => Neighbour::Next,
                        _ => return Err(unknown_variant(span, &v, "neighbouring sample", &["Previous", "Next"])),
                    };
                    Some(Spanned { value, span })
                }
            };
            PassKind::Geometry {
                reads,
                writes,
                primitive,
                channels,
                resolve,
                view,
                keep,
                from,
            }
        }
        _ => {
            let reads = names(f.req("reads")?)?;
            let visibility = expression(f.req("visibility")?)?;
            let schedule = schedule(&mut f)?;
            let debug = match f.opt("debug")? {
                None => vec![],
                Some(n) => debug_outputs(n, &visibility)?,
            };
            PassKind::Shade {
                reads,
                visibility,
                schedule,
                debug,
            }
        }
    };
    if what != "Shade"
        && let Some(n) = f.opt("debug")?
    {
        return Err(err(
            n.span,
            format!("`debug` outputs belong to the Shade pass, not to a {what} pass"),
            "not a field of this pass",
        )
        .help("move the debug outputs to the Shade pass: they are evaluated per camera pixel, with the visibility"));
    }
    f.finish()?;
    Ok(Pass {
        name,
        kind,
        kind_span,
        span: node.span,
    })
}

/// A Shade's `debug: {"name": "expr", ...}`: each expression wrapped in the visibility's
/// leading `let`s (`let a = ..; let b = ..; body`), so that it sees them as the visibility's
/// body does. The wrappers take the expression's span, so what check says of a debug
/// output points at its string.
fn debug_outputs(node: &Node, visibility: &Expr) -> Result<Vec<DebugOutput>, Diagnostic> {
    let mut lets = Vec::new();
    let mut at = visibility;
    while let ExprKind::Let {
        name,
        name_span,
        value,
        body,
    } = &at.kind
    {
        lets.push((name, *name_span, value));
        at = body;
    }
    let mut out = Vec::new();
    for (name, v) in map_entries(node)? {
        let written = expression(v)?;
        let span = written.span;
        let mut value = written;
        for (n, name_span, let_value) in lets.iter().rev() {
            let kind = ExprKind::Let {
                name: (*n).clone(),
                name_span: *name_span,
                value: (*let_value).clone(),
                body: Box::new(value),
            };
            value = Expr::new(kind, span);
        }
        if value.height() > expr::MAX_TREE_DEPTH {
            return Err(err(
                span,
                format!(
                    "debug output `{}` inside the visibility's {} `let`(s) is deeper than {} levels",
                    name.value,
                    lets.len(),
                    expr::MAX_TREE_DEPTH
                ),
                "too deep",
            )
            .help("split it with `let` bindings of its own, or a function"));
        }
        out.push(DebugOutput { name, value });
    }
    Ok(out)
}

const KERNELS: &[&str] = &["Box", "Gaussian", "Max", "Min", "LoG"];

/// `F32` or `Fixed(bits: B)`, B in 1..=24.
fn table_sum(node: &Node) -> Result<Spanned<TableSum>, Diagnostic> {
    let (v, span) = variant(node)?;
    let sum = match v.as_str() {
        "F32" => {
            if !matches!(node.value, Value::Ident(_)) {
                Fields::of(node, "F32")?.finish()?;
            }
            TableSum::F32
        }
        "Fixed" => {
            let mut f = Fields::of(node, "Fixed")?;
            let b = f.req("bits")?;
            let bits = match b.value {
                Value::Int(v) if (1..=i64::from(TableSum::MAX_BITS)).contains(&v) => v as u8,
                _ => {
                    return Err(err(
                        b.span,
                        format!("a fixed-point table's codes have 1 to {} bits", TableSum::MAX_BITS),
                        format!("expected an integer in 1..={}", TableSum::MAX_BITS),
                    )
                    .note("codes are converted to f32 exactly, which holds integers up to 2^24"));
                }
            };
            f.finish()?;
            TableSum::Fixed(bits)
        }
        _ => return Err(unknown_variant(span, &v, "table sum", &["F32", "Fixed"])),
    };
    Ok(Spanned::new(sum, node.span))
}

fn kernel(node: &Node) -> Result<Spanned<Kernel>, Diagnostic> {
    let (v, span) = variant(node)?;
    let k = match v.as_str() {
        "LoG" => {
            if !matches!(node.value, Value::Ident(_)) {
                Fields::of(node, "LoG")?.finish()?;
            }
            Kernel::LoG
        }
        "Box" | "Max" | "Min" => {
            let what: &'static str = KERNELS.iter().find(|k| **k == v).copied().unwrap_or("Box");
            let mut f = Fields::of(node, what)?;
            let size = expression(f.req("size")?)?;
            f.finish()?;
            match what {
                "Box" => Kernel::Box { size },
                "Max" => Kernel::Max { size },
                _ => Kernel::Min { size },
            }
        }
        "Gaussian" => {
            let mut f = Fields::of(node, "Gaussian")?;
            let size = expression(f.req("size")?)?;
            let sigma = expression(f.req("sigma")?)?;
            f.finish()?;
            Kernel::Gaussian { size, sigma }
        }
        _ => return Err(unknown_variant(span, &v, "filter kernel", KERNELS)),
    };
    Ok(Spanned::new(k, node.span))
}
