//! The docs name files that exist (issue 52: "every claim in docs/ that names a function,
//! file or count checked by a test or removed"; this checks the files): every repository
//! path in `docs/*.md` and `README.md` (a word starting with a top-level folder and ending
//! in a file extension) is a file or folder of the repository. Placeholders (`scenes/S.ron`,
//! `techniques/T.ron`: a one-capital-letter stem), globs and `<...>` parts are not paths.
//! The extension walks (docs/extending.md) name functions where they are: each name a step
//! gives is in a file the step names. (Its table of counts is checked by
//! `scripts/extension-costs.py --check`.)

use std::path::Path;

const TOP: &[&str] = &[
    "compiler/",
    "runtime/",
    "lab/",
    "graph/",
    "tests/",
    "shaders-gen/",
    "scripts/",
    "scenes/",
    "techniques/",
    "sweeps/",
    "docs/",
];
const EXTENSIONS: &[&str] = &[
    ".rs", ".ron", ".sh", ".py", ".wgsl", ".md", ".toml", ".csv", ".png", ".svg", ".glb", ".jsonl",
];

/// The repository paths `line` names.
fn paths(line: &str) -> Vec<&str> {
    line.split(|c: char| c.is_whitespace() || "`()[],;:'\"|".contains(c))
        .map(|w| w.trim_end_matches(['.', '!', '?']))
        .filter(|w| TOP.iter().any(|t| w.starts_with(t)) && EXTENSIONS.iter().any(|e| w.ends_with(e)))
        .filter(|w| !w.contains(['*', '<', '{', '$']))
        .filter(|w| {
            let stem = Path::new(w).file_stem().and_then(|s| s.to_str()).unwrap_or("");
            !(stem.len() == 1 && stem.chars().all(|c| c.is_ascii_uppercase()))
        })
        .collect()
}

#[test]
fn every_file_the_docs_name_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut docs: Vec<_> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.push(root.join("README.md"));
    let (mut named, mut missing) = (0, Vec::new());
    for doc in &docs {
        let text = std::fs::read_to_string(doc).unwrap();
        for (i, line) in text.lines().enumerate() {
            for p in paths(line) {
                named += 1;
                if !root.join(p).exists() {
                    missing.push(format!("{}:{}: {p}", doc.strip_prefix(&root).unwrap_or(doc).display(), i + 1));
                }
            }
        }
    }
    assert!(named > 300, "only {named} paths found: the scan is broken");
    assert!(missing.is_empty(), "the docs name files that do not exist:\n{}", missing.join("\n"));
}

#[test]
fn paths_are_words_that_start_at_a_top_folder() {
    assert_eq!(
        paths("see `compiler/src/lib.rs`, lab/tests/view.rs: and scenes/S.ron or docs/*.md (tests/x.rs)."),
        ["compiler/src/lib.rs", "lab/tests/view.rs", "tests/x.rs"]
    );
}

/// The numbered steps of a Markdown file, each with its continuation lines: (line, text).
fn steps(text: &str) -> Vec<(usize, String)> {
    let mut out: Vec<(usize, String)> = Vec::new();
    let mut open = false;
    for (i, line) in text.lines().enumerate() {
        let digits = line.len() - line.trim_start_matches(|c: char| c.is_ascii_digit()).len();
        if digits > 0 && line[digits..].starts_with(". ") {
            out.push((i + 1, line.to_string()));
            open = true;
        } else if open && line.starts_with("   ") && !line.trim().is_empty() {
            let last = out.last_mut().unwrap();
            last.1.push('\n');
            last.1.push_str(line);
        } else {
            open = false;
        }
    }
    out
}

/// The code names in backticks in `text`: identifiers and paths of them (`Func::desc`).
fn code_names(text: &str) -> Vec<&str> {
    text.split('`')
        .skip(1)
        .step_by(2)
        .filter(|w| {
            w.split("::").all(|s| {
                s.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
                    && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            })
        })
        .collect()
}

fn has_word(text: &str, word: &str) -> bool {
    text.match_indices(word).any(|(i, _)| {
        let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
        !text[..i].ends_with(ident) && !text[i + word.len()..].starts_with(ident)
    })
}

/// The extension walks name places where they are: every code name a step of
/// docs/extending.md gives (a function, table, type or test, in backticks) is a word of a
/// `.rs` file the same step names (each segment of a path such as `Func::desc`).
#[test]
fn every_name_an_extension_walk_gives_is_in_a_file_of_its_step() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join("docs/extending.md")).unwrap();
    let (mut checked, mut missing) = (0, Vec::new());
    for (line, step) in steps(&text) {
        let sources: Vec<String> = paths(&step)
            .into_iter()
            .filter(|p| p.ends_with(".rs"))
            .map(|p| std::fs::read_to_string(root.join(p)).unwrap_or_else(|e| panic!("docs/extending.md:{line}: {p}: {e}")))
            .collect();
        if sources.is_empty() {
            continue;
        }
        for name in code_names(&step) {
            checked += 1;
            if !sources.iter().any(|s| name.split("::").all(|w| has_word(s, w))) {
                missing.push(format!("docs/extending.md:{line}: `{name}`"));
            }
        }
    }
    assert!(checked > 150, "only {checked} names found: the scan is broken");
    assert!(missing.is_empty(), "names in no file their step names:\n{}", missing.join("\n"));
}

#[test]
fn steps_and_names_are_read_from_numbered_items() {
    let s = steps("text\n1. `a.rs`: `f`, `T::g`\n   and `h`.\n\n2. `x y`, `in_*`\nnot a step `z`\n");
    assert_eq!(
        s,
        [
            (2, "1. `a.rs`: `f`, `T::g`\n   and `h`.".to_string()),
            (5, "2. `x y`, `in_*`".to_string())
        ]
    );
    assert_eq!(code_names(&s[0].1), ["f", "T::g", "h"]);
    assert!(code_names(&s[1].1).is_empty());
    assert!(has_word("fn f_g() { f(1) }", "f") && !has_word("fn f_g()", "f"));
}
