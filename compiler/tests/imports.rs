//! No two modules of a crate import each other (counted from the code's `crate::` paths,
//! comments left out), in every crate of the workspace: a module that needs another's
//! items and is needed by it is one module, or a third holds what both need.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .flatten()
    {
        let p = e.path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The module path of `file` below `src` (`front::ast`; `crate` for lib.rs and main.rs).
fn module(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    let path = parts.join("::");
    let path = path.strip_suffix("::mod").unwrap_or(&path).to_string();
    if path == "lib" || path == "main" { "crate".into() } else { path }
}

/// The modules `code` names through `crate::` paths: for `crate::a::b`, `a::b` where it is
/// a module, else `a`.
fn named(code: &str, modules: &BTreeSet<String>) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for (i, _) in code.match_indices("crate::") {
        let rest = &code[i + 7..];
        let path: String = rest
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == ':')
            .collect();
        let segs: Vec<&str> = path.split("::").filter(|s| !s.is_empty()).collect();
        // the longest prefix that is a module
        if let Some(m) = (1..=segs.len()).rev().map(|n| segs[..n].join("::")).find(|m| modules.contains(m)) {
            out.insert(m);
        }
    }
    out
}

/// The crates' source folders the tests read.
const CRATES: [&str; 8] = [
    "compiler/src",
    "runtime/src",
    "runtime/light/src",
    "graph/src",
    "lab/src",
    "lab/scene/src",
    "lab/records/src",
    "shaders-gen/impl/src",
];

/// Each module of the crate in `crate_src` and the modules it imports (itself left out).
fn imports_of(crate_src: &str) -> BTreeMap<String, BTreeSet<String>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let src = root.join(crate_src);
    let mut list = Vec::new();
    files(&src, &mut list);
    let modules: BTreeSet<String> = list.iter().map(|f| module(&src, f)).collect();
    let mut imports: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in &list {
        let text = std::fs::read_to_string(f).unwrap();
        let code: String = text
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        let m = module(&src, f);
        let mut n = named(&code, &modules);
        n.remove(&m);
        imports.insert(m, n);
    }
    imports
}

#[test]
fn no_two_modules_import_each_other() {
    let mut checked = 0;
    for crate_src in CRATES {
        let imports = imports_of(crate_src);
        for (a, na) in &imports {
            for b in na {
                assert!(
                    !imports.get(b).is_some_and(|nb| nb.contains(a)),
                    "{crate_src}: `{a}` and `{b}` import each other"
                );
            }
        }
        checked += imports.len();
    }
    assert!(checked > 60, "{checked} modules read");
}

/// No circle of imports of any length either (issue 49 found `resources` -> `usages` ->
/// `steps` -> `resources` in the runtime, which the test of pairs does not see): from no
/// module does a path of imports lead back to it.
#[test]
fn no_modules_import_each_other_around_a_circle() {
    for crate_src in CRATES {
        let imports = imports_of(crate_src);
        for start in imports.keys() {
            // a walk from `start`, remembering how each module was reached
            let mut came_from: BTreeMap<&String, &String> = BTreeMap::new();
            let mut todo: Vec<&String> = vec![start];
            while let Some(m) = todo.pop() {
                for n in imports.get(m).into_iter().flatten() {
                    if n == start {
                        let mut circle = vec![start.clone(), m.clone()];
                        let mut at = m;
                        while let Some(prev) = came_from.get(at) {
                            circle.push((*prev).clone());
                            at = prev;
                        }
                        circle.dedup();
                        panic!("{crate_src}: a circle of imports through `{start}`: {}", circle.join(" <- "));
                    }
                    if !came_from.contains_key(n) && n != start {
                        came_from.insert(n, m);
                        todo.push(n);
                    }
                }
            }
        }
    }
}

/// The compiler's phases in the order `run_phases` runs them (the names of
/// `sshc::DumpPhase::ALL`), each with the modules that make it up: a module belongs to the
/// phase whose entry is the longest prefix of its path.
const PHASES: [(&str, &[&str]); 9] = [
    ("parse", &["front"]),
    ("resolve", &["resolve"]),
    ("check", &["check"]),
    ("lower", &["lower"]),
    ("analyse", &["analyse"]),
    ("pack", &["pack"]),
    ("schedule", &["schedule"]),
    ("codegen", &["back"]),
    ("emit", &["emit"]),
];

/// What every phase may import besides the phases before it, each with why. These are
/// the data the phases hand on and the rules several of them apply; that they import no
/// circle among themselves is the two tests above.
const SHARED: [(&str, &str); 11] = [
    ("span", "source positions: every node and diagnostic carries them"),
    ("diag", "the diagnostics every phase returns"),
    ("handle", "typed indices and tables: the IR's and its side tables'"),
    (
        "front::ast",
        "the technique's declarations (`Precision`, `Schedule`, kinds) the IR keeps",
    ),
    (
        "builtins",
        "the builtins' descriptors, which parse, check, lower, analyse and codegen read",
    ),
    ("types", "check's typing (`Types`), which lower reads, inferring nothing again"),
    (
        "consteval",
        "constant evaluation by the rules the IR's arena folds with (check and lower)",
    ),
    ("interval", "the interval type of the builtins' range rules and of the analysis"),
    (
        "ranges",
        "the IR's range analysis: lower chooses `Auto` precisions on it, analyse fits them",
    ),
    ("ir", "the IR: lower's product, which every later phase reads"),
    ("CompileOptions", "the driver's options (lib.rs), which resolve applies"),
];

/// Beside the phases: tools over compiled techniques and the driver, which no phase imports.
const TOOLS: [(&str, &str); 7] = [
    ("crate", "lib.rs, the driver: runs the phases"),
    ("eval", "the public facade of verify's evaluation (interp, rounding, tables)"),
    ("explain", "`sshc explain`, from a compiled technique"),
    ("interp", "`sshc verify`'s CPU evaluation of a compiled technique"),
    ("rounding", "the storage-rounding estimate, after pack"),
    ("tables", "the summed-area tables' error, after pack"),
    ("tune", "`sshc tune`'s search space, and writing a tuned file"),
];

/// The paths a `crate::` path or use tree names, from the text after `crate::`: `a::b::C`
/// gives `a::b::C`; `{a, b::{c, d}}` gives `a`, `b::c`, `b::d`.
fn use_tree(text: &str) -> Vec<String> {
    fn tree(s: &[u8], i: &mut usize, prefix: &str, out: &mut Vec<String>) {
        let ws = |i: &mut usize| {
            while s.get(*i).is_some_and(|c| c.is_ascii_whitespace()) {
                *i += 1;
            }
        };
        let mut path = prefix.to_string();
        loop {
            ws(i);
            if s.get(*i) == Some(&b'{') {
                *i += 1;
                loop {
                    ws(i);
                    if s.get(*i) == Some(&b'}') {
                        *i += 1;
                        return;
                    }
                    let before = *i;
                    tree(s, i, &path, out);
                    ws(i);
                    match s.get(*i) {
                        Some(b',') => *i += 1,
                        Some(b'}') => {
                            *i += 1;
                            return;
                        }
                        _ => return,
                    }
                    if *i == before {
                        return;
                    }
                }
            }
            let start = *i;
            while s.get(*i).is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_' || *c == b'*') {
                *i += 1;
            }
            let ident = String::from_utf8_lossy(&s[start..*i]).into_owned();
            if ident.is_empty() {
                if !path.is_empty() {
                    out.push(path);
                }
                return;
            }
            path = if path.is_empty() { ident } else { format!("{path}::{ident}") };
            if s.get(*i..*i + 2) == Some(b"::".as_slice()) {
                *i += 2;
            } else {
                out.push(path);
                return;
            }
        }
    }
    let mut out = Vec::new();
    tree(text.as_bytes(), &mut 0, "", &mut out);
    out
}

/// Whether `path` is `prefix` or lies below it (`ir::validate` below `ir`).
fn below(path: &str, prefix: &str) -> bool {
    path == prefix || path.strip_prefix(prefix).is_some_and(|r| r.starts_with("::"))
}

/// The index in [`PHASES`] of the phase `module` belongs to, if any.
fn phase_of(module: &str) -> Option<usize> {
    PHASES
        .iter()
        .enumerate()
        .flat_map(|(i, (_, ms))| ms.iter().map(move |m| (i, *m)))
        .filter(|(_, m)| below(module, m))
        .max_by_key(|(_, m)| m.len())
        .map(|(i, _)| i)
}

/// Whether `module` is shared (a longer match than its phase's: `front::ast` in `front`).
fn shared(module: &str) -> bool {
    let phase_len = phase_of(module).map_or(0, |i| {
        PHASES[i].1.iter().filter(|m| below(module, m)).map(|m| m.len()).max().unwrap_or(0)
    });
    SHARED.iter().any(|(m, _)| below(module, m) && m.len() > phase_len)
}

/// The phase order is the import order: each phase's modules import (by `crate::` paths,
/// comments and the unit tests after `#[cfg(test)]` left out) only modules of the phases
/// before it or of its own, and the shared ones. Every module of the compiler is a phase's,
/// shared or a tool, so a new one is placed here.
#[test]
fn phases_import_only_the_phases_before_them() {
    let names: Vec<&str> = sshc::DumpPhase::ALL.iter().map(|p| p.name()).collect();
    let phases: Vec<&str> = PHASES.iter().map(|(n, _)| *n).collect();
    assert_eq!(phases, names, "the phases here and `DumpPhase::ALL`");

    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let src = root.join("compiler/src");
    let mut list = Vec::new();
    files(&src, &mut list);
    let modules: BTreeSet<String> = list.iter().map(|f| module(&src, f)).collect();
    let mut unplaced = Vec::new();
    let mut wrong = Vec::new();
    let mut checked = 0;
    for f in &list {
        let m = module(&src, f);
        let tool = TOOLS.iter().any(|(t, _)| if *t == "crate" { m == "crate" } else { below(&m, t) });
        if shared(&m) || tool {
            continue;
        }
        let Some(at) = phase_of(&m) else {
            unplaced.push(m);
            continue;
        };
        let text = std::fs::read_to_string(f).unwrap();
        let code: String = text
            .lines()
            .take_while(|l| l.trim() != "#[cfg(test)]")
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        checked += 1;
        for (i, _) in code.match_indices("crate::") {
            for path in use_tree(&code[i + 7..]) {
                let segs: Vec<&str> = path.split("::").collect();
                // the longest prefix that is a module; else an item of lib.rs
                let named = (1..=segs.len())
                    .rev()
                    .map(|n| segs[..n].join("::"))
                    .find(|p| modules.contains(p))
                    .unwrap_or_else(|| segs[0].to_string());
                if shared(&named) {
                    continue;
                }
                match phase_of(&named) {
                    Some(p) if p <= at => {}
                    Some(p) => wrong.push(format!(
                        "`{m}` ({}) imports `{path}` of `{named}` ({}), a later phase",
                        PHASES[at].0, PHASES[p].0
                    )),
                    None => wrong.push(format!(
                        "`{m}` ({}) imports `{path}` of `{named}`, neither a phase nor shared",
                        PHASES[at].0
                    )),
                }
            }
        }
    }
    for m in &modules {
        let tool = TOOLS.iter().any(|(t, _)| if *t == "crate" { m == "crate" } else { below(m, t) });
        if !tool && !shared(m) && phase_of(m).is_none() && !unplaced.contains(m) {
            unplaced.push(m.clone());
        }
    }
    assert!(unplaced.is_empty(), "modules in no phase, not shared and no tool: {unplaced:?}");
    assert!(checked >= 20, "{checked} phase modules read");
    assert!(wrong.is_empty(), "imports against the phase order:\n{}", wrong.join("\n"));
}

#[test]
fn use_trees_name_each_path() {
    assert_eq!(use_tree("a::b::C;"), ["a::b::C"]);
    assert_eq!(use_tree("{CompileOptions, builtins};"), ["CompileOptions", "builtins"]);
    assert_eq!(
        use_tree("front::{ast::*, expr::{Expr, UnOp}};"),
        ["front::ast::*", "front::expr::Expr", "front::expr::UnOp"]
    );
    assert_eq!(use_tree("back::formats::texture_format(t)"), ["back::formats::texture_format"]);
}
