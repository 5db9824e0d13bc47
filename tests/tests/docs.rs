//! The docs name files that exist (issue 52: "every claim in docs/ that names a function,
//! file or count checked by a test or removed"; this checks the files): every repository
//! path in `docs/*.md` and `README.md` (a word starting with a top-level folder and ending
//! in a file extension) is a file or folder of the repository. Placeholders (`scenes/S.ron`,
//! `techniques/T.ron`: a one-capital-letter stem), globs and `<...>` parts are not paths.

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
