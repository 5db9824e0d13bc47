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
