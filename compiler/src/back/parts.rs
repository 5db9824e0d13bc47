//! Long straight-line bodies split into functions.
//!
//! naga's WGSL front end types a function's expressions with `Typifier::grow`, which walks
//! the function's expression arena from its start for each new expression: parsing a
//! function of n expressions costs O(n^2). The compiler parses every module it emits (to
//! validate it) and so does wgpu when it creates the shader module. A technique at the
//! series limit (`MAX_SERIES`: 4,096 `fetch` terms, about 60,000 naga expressions in one
//! entry point) took 3.3 s to compile in a release build and over 100 s in the fuzzing
//! build (docs/fuzzing.md, finding 1).
//!
//! A run of more than [`MAX_RUN`] consecutive `let`s is therefore emitted as functions of
//! [`PART`] `let`s each: a part takes the values it reads from before it as arguments
//! (earlier `let`s and the entry's `in_*` locals) and returns, in a struct, the values that
//! are read after it. Each function's arena stays small, so parsing is linear in the
//! number of parts: the series at the limit compiles in 0.22 s (release), PCSS (the only
//! bundled technique split, its Shade has about 1,500 `let`s) in 23 ms instead of 27.
//! Shader compilers inline the calls (Mesa's NIR inlines every function before it
//! optimises), so the code that runs is the same and so is every value (a GPU test
//! compares every bundled technique split at every fifth `let` with its whole form, bit
//! for bit); naga's operation counts count a called function at its call site
//! (`back::count_ops`), so the cost report does not change either. Bodies of up to
//! `MAX_RUN` lets are emitted as before. The arms of a branch (`if c { .. } else { .. }`)
//! are split the same way, their functions taking what they read from the enclosing scope
//! as arguments: sixteen arms of a 4,096-term series took 10 s to parse in one arena
//! (release), 1.8 s split (issue 48, item 4).

use crate::builtins::Input;
use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;

/// Runs of `let`s longer than this are split (the default of [`Split::max_run`]).
pub const MAX_RUN: usize = 512;
/// `let`s per function of a split run (the default of [`Split::part`]).
pub const PART: usize = 128;

/// Where bodies are split: `CompileOptions::split`. Tests lower both to split small
/// bodies and check that the split code computes the same values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Split {
    pub max_run: usize,
    pub part: usize,
}

impl Default for Split {
    fn default() -> Self {
        Split {
            max_run: MAX_RUN,
            part: PART,
        }
    }
}

/// One line of an entry point's body.
#[derive(Clone, Debug)]
pub enum Line {
    /// `let name = rhs;`, whose value has WGSL type `ty`.
    Let { name: String, ty: &'static str, rhs: String },
    /// Anything else (a control-flow statement, a `let` of an entry local), kept in the entry.
    Raw(String),
    /// A branch: `var name: ty;` and the `if` that assigns it (`text`, lines without the
    /// body's indentation), kept in the entry like [`Line::Raw`]; later lines read `name`.
    Branch { name: String, ty: &'static str, text: String },
}

impl Line {
    /// The statement's text, for what it reads.
    fn text(&self) -> &str {
        match self {
            Line::Let { rhs, .. } => rhs,
            Line::Raw(s) | Line::Branch { text: s, .. } => s,
        }
    }

    /// Whether the line is kept in the entry (ends a run of `let`s that may be split).
    fn kept(&self) -> bool {
        !matches!(self, Line::Let { .. })
    }
}

/// The WGSL type of an entry point's local that generated code may read: the `in_*`
/// inputs, the integer texel coordinates `texel` and `in_base`, a deferred Shade's
/// `in_duv_dx` and `in_duv_dy`, and their per-sample copies
/// `NAME_vK` (`at_sample`). `None` for anything else (globals, functions, fields).
fn local_ty(name: &str) -> Option<&'static str> {
    let base = match name.rsplit_once("_v") {
        Some((b, k)) if !k.is_empty() && k.bytes().all(|c| c.is_ascii_digit()) => b,
        _ => name,
    };
    match base {
        "texel" | "in_base" => Some("vec2<i32>"),
        // a deferred Shade's screen-space footprint of `in_uv` (implicit-LOD lookups)
        "in_duv_dx" | "in_duv_dy" => Some("vec2<f32>"),
        _ => Input::ALL.iter().find(|i| i.desc().wgsl == base).map(|i| i.desc().ty.wgsl()),
    }
}

/// The identifiers `text` reads: names not preceded by `.` (fields and swizzles) and not
/// part of a number literal (`1i`, `0.5f`).
fn identifiers(text: &str) -> Vec<&str> {
    let b = text.as_bytes();
    let (mut out, mut i) = (Vec::new(), 0);
    while i < b.len() {
        let c = b[i];
        if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            let after_dot = text[..start].trim_end().ends_with('.');
            if !after_dot {
                out.push(&text[start..i]);
            }
        } else if c.is_ascii_digit() {
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_' || b[i] == b'.') {
                i += 1;
            }
        } else {
            i += 1;
        }
    }
    out
}

fn render(line: &Line, out: &mut String) {
    match line {
        Line::Let { name, rhs, .. } => {
            let _ = writeln!(out, "    let {name} = {rhs};");
        }
        Line::Raw(s) => {
            let _ = writeln!(out, "    {s}");
        }
        Line::Branch { text, .. } => {
            for l in text.lines() {
                let _ = writeln!(out, "    {l}");
            }
        }
    }
}

/// The body's text and the module-level functions (and their result structs) it calls.
/// `prefix` names the functions (the entry's name: unique in its module); `kept` are the
/// WGSL expressions the code after the body reads (names, or a channel's `texel_3.x`).
/// `outer` gives the type of a name defined before `lines` that they may read (an arm's
/// enclosing scope; nothing for an entry's body, whose only outer names are its locals).
pub fn split(
    lines: &[Line],
    prefix: &str,
    kept: &HashSet<String>,
    at: Split,
    outer: &dyn Fn(&str) -> Option<&'static str>,
) -> (String, String) {
    let Split { max_run, part: part_len } = at;
    let part_len = part_len.max(1);
    let (mut functions, mut body) = (String::new(), String::new());
    let long_run = lines.split(Line::kept).any(|run| run.len() > max_run);
    if !long_run {
        lines.iter().for_each(|l| render(l, &mut body));
        return (functions, body);
    }
    // the last line reading each name (usize::MAX: read after the body)
    let mut last_read: HashMap<&str, usize> = HashMap::new();
    for (i, l) in lines.iter().enumerate() {
        for id in identifiers(l.text()) {
            last_read.insert(id, i);
        }
    }
    for id in kept.iter().flat_map(|k| identifiers(k)) {
        last_read.insert(id, usize::MAX);
    }
    let mut let_ty: HashMap<&str, &'static str> = HashMap::new();
    let (mut i, mut part) = (0, 0);
    while i < lines.len() {
        let run_end = lines[i..].iter().position(Line::kept).map_or(lines.len(), |p| i + p);
        if run_end - i <= max_run {
            for l in &lines[i..run_end.max(i + 1)] {
                render(l, &mut body);
                if let Line::Let { name, ty, .. } | Line::Branch { name, ty, .. } = l {
                    let_ty.insert(name, ty);
                }
            }
            i = run_end.max(i + 1);
            continue;
        }
        for chunk_start in (i..run_end).step_by(part_len) {
            let end = (chunk_start + part_len).min(run_end);
            let lets: Vec<(&str, &'static str, &str)> = lines[chunk_start..end]
                .iter()
                .filter_map(|l| match l {
                    Line::Let { name, ty, rhs } => Some((name.as_str(), *ty, rhs.as_str())),
                    Line::Raw(_) | Line::Branch { .. } => None,
                })
                .collect();
            let defined: HashSet<&str> = lets.iter().map(|l| l.0).collect();
            let mut args: Vec<(&str, &'static str)> = Vec::new();
            for (_, _, rhs) in &lets {
                for id in identifiers(rhs) {
                    if defined.contains(id) || args.iter().any(|a| a.0 == id) {
                        continue;
                    }
                    if let Some(ty) = let_ty.get(id).copied().or_else(|| local_ty(id)).or_else(|| outer(id)) {
                        args.push((id, ty));
                    }
                }
            }
            let results: Vec<(&str, &'static str)> = lets
                .iter()
                .filter(|(n, _, _)| last_read.get(n).is_some_and(|&r| r >= end))
                .map(|(n, t, _)| (*n, *t))
                .collect();
            for (n, t, _) in &lets {
                let_ty.insert(n, t);
            }
            if results.is_empty() {
                // nothing after the part reads its values
                continue;
            }
            part += 1;
            let (st, f, v) = (
                format!("{prefix}_part{part}"),
                format!("{prefix}_part{part}_f"),
                format!("{prefix}_p{part}"),
            );
            let _ = writeln!(functions, "\nstruct {st} {{");
            for (n, t) in &results {
                let _ = writeln!(functions, "    {n}: {t},");
            }
            let params: Vec<String> = args.iter().map(|(n, t)| format!("{n}: {t}")).collect();
            let _ = writeln!(functions, "}}\n\nfn {f}({}) -> {st} {{", params.join(", "));
            for (n, _, rhs) in &lets {
                let _ = writeln!(functions, "    let {n} = {rhs};");
            }
            let names: Vec<&str> = results.iter().map(|r| r.0).collect();
            let _ = writeln!(functions, "    return {st}({});\n}}", names.join(", "));
            let call_args: Vec<&str> = args.iter().map(|a| a.0).collect();
            let _ = writeln!(body, "    let {v} = {f}({});", call_args.join(", "));
            for n in names {
                let _ = writeln!(body, "    let {n} = {v}.{n};");
            }
        }
        i = run_end;
    }
    (functions, body)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers_skip_fields_swizzles_and_literal_suffixes() {
        assert_eq!(
            identifiers("clamp(in_base + vec2<i32>(1i, -2i), frame.shadow_size.xy) * e12.x + 0.5f"),
            ["clamp", "in_base", "vec2", "i32", "frame", "e12"]
        );
    }

    #[test]
    fn locals_have_their_input_types_in_every_view() {
        assert_eq!(local_ty("in_uv"), Some("vec2<f32>"));
        assert_eq!(local_ty("in_uv_v3"), Some("vec2<f32>"));
        assert_eq!(local_ty("in_base_v12"), Some("vec2<i32>"));
        assert_eq!(local_ty("in_d"), Some("f32"));
        assert_eq!(local_ty("frame"), None);
        assert_eq!(local_ty("e5"), None);
    }

    fn chain(n: usize) -> Vec<Line> {
        // e0 = in_d; e_k = e_{k-1} + in_d: every part reads the previous part's last value
        (0..n)
            .map(|k| Line::Let {
                name: format!("e{k}"),
                ty: "f32",
                rhs: if k == 0 { "in_d".into() } else { format!("e{} + in_d", k - 1) },
            })
            .collect()
    }

    #[test]
    fn short_bodies_are_unchanged() {
        let lines = chain(MAX_RUN);
        let (functions, body) = split(
            &lines,
            "fs",
            &HashSet::from([format!("e{}", MAX_RUN - 1)]),
            Split::default(),
            &|_| None,
        );
        assert!(functions.is_empty());
        assert_eq!(body.lines().count(), MAX_RUN);
        assert!(body.starts_with("    let e0 = in_d;\n"));
    }

    #[test]
    fn a_branch_is_kept_in_the_entry_and_its_value_passed_to_the_parts_that_read_it() {
        let mut lines = vec![Line::Branch {
            name: "b0".into(),
            ty: "vec2<f32>",
            text: "var b0: vec2<f32>;\nif in_d > 0.5 {\n    b0 = vec2<f32>(1.0);\n} else {\n    b0 = vec2<f32>(0.0);\n}\n".into(),
        }];
        lines.extend(chain(MAX_RUN + 1));
        if let Line::Let { rhs, .. } = &mut lines[1] {
            *rhs = "b0.x".into();
        }
        let (functions, body) = split(&lines, "fs", &HashSet::from([format!("e{MAX_RUN}")]), Split::default(), &|_| None);
        // the branch stays in the entry, indented as a body's lines, before the parts
        assert!(
            body.starts_with("    var b0: vec2<f32>;\n    if in_d > 0.5 {\n        b0 = vec2<f32>(1.0);\n"),
            "{body}"
        );
        assert!(body.contains("    let fs_p1 = fs_part1_f(b0, in_d);\n"), "{body}");
        assert!(
            functions.contains("fn fs_part1_f(b0: vec2<f32>, in_d: f32) -> fs_part1 {"),
            "{functions}"
        );
    }

    #[test]
    fn long_runs_become_parts_that_pass_on_what_later_lines_read() {
        let n = MAX_RUN + 1;
        let (functions, body) = split(&chain(n), "fs", &HashSet::from([format!("e{}", n - 1)]), Split::default(), &|_| {
            None
        });
        let parts = n.div_ceil(PART);
        assert_eq!(functions.matches("\nfn fs_part").count(), parts);
        // the first part reads in_d only; the others the previous part's last value too
        assert!(functions.contains("fn fs_part1_f(in_d: f32) -> fs_part1 {"));
        assert!(functions.contains(&format!("fn fs_part2_f(e{}: f32, in_d: f32) -> fs_part2 {{", PART - 1)));
        // each part returns only its last value, which the next part (or the end) reads
        assert!(functions.contains(&format!("struct fs_part1 {{\n    e{}: f32,\n}}", PART - 1)));
        assert!(body.contains(&format!("    let e{} = fs_p{parts}.e{};\n", n - 1, n - 1)));
        assert_eq!(body.lines().count(), 2 * parts);
    }
}
