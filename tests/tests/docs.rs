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

/// The Markdown files the docs are: `docs/*.md` and `README.md`.
fn markdown(root: &Path) -> Vec<std::path::PathBuf> {
    let mut docs: Vec<_> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.push(root.join("README.md"));
    docs
}

#[test]
fn every_file_the_docs_name_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let docs = markdown(&root);
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

/// Crates and modules outside the repository whose paths the docs may name.
const EXTERNAL: &[&str] = &[
    "std",
    "core",
    "wgpu",
    "naga",
    "glam",
    "bevy",
    "egui",
    "egui_wgpu",
    "egui_winit",
    "winit",
    "serde",
    "ron",
    "clap",
    "image",
    "gltf",
    "plotters",
    "rayon",
    "csv",
    "half",
    "insta",
    "proptest",
    "stacker",
    "xxhash_rust",
    "nvtx",
    "libfuzzer_sys",
    "arbitrary",
    "bvh",
    "obj",
    "tobj",
    "nu_ansi_term",
    "bytemuck",
    "pollster",
    "anyhow",
    "thiserror",
    "tempfile",
    "cargo",
    "slurm",
    "flip",
    "nv_flip",
    "rand",
    "rand_pcg",
    "fastrand",
    "sha2",
    "ctrlc",
    "crossbeam",
    "parking_lot",
    "log",
    // Rust's primitive types, clippy's lints, naga's, glam's, wgpu's and Bevy's types
    "f32",
    "f64",
    "u32",
    "usize",
    "clippy",
    "Typifier",
    "Mat4",
    "Queue",
    "Tonemapping",
    "AssetEvent",
    "Assets",
    "RenderSystems",
    "WgpuSettingsPriority",
    "ShadowFilteringMethod",
    "PbrInput",
];

/// Every item defined in `src` (a Rust file): functions, types, constants, modules,
/// macros, enum variants and struct fields (a word at the start of a line followed by
/// `,`, `(`, ` {` or `:`).
fn definitions(src: &str, out: &mut std::collections::HashSet<String>) {
    const KEYWORDS: &[&str] = &[
        "fn ",
        "struct ",
        "enum ",
        "const ",
        "static ",
        "type ",
        "trait ",
        "mod ",
        "macro_rules! ",
        "union ",
    ];
    for line in src.lines() {
        let t = line.trim_start();
        let t = t
            .strip_prefix("pub(crate) ")
            .or_else(|| t.strip_prefix("pub(super) "))
            .or_else(|| t.strip_prefix("pub "))
            .unwrap_or(t);
        let t = t.strip_prefix("const ").filter(|r| r.starts_with("fn ")).unwrap_or(t);
        let t = t.strip_prefix("async ").unwrap_or(t);
        let ident: String = KEYWORDS
            .iter()
            .find_map(|k| t.strip_prefix(k))
            .unwrap_or(t)
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect();
        if !ident.is_empty() {
            out.insert(ident);
        }
    }
}

/// The docs' code paths are the code's: every backticked path of identifiers in
/// `docs/*.md` and `README.md` (`verify::verify`, `Light::kind`, `sshc::eval::estimate`,
/// `run()`) names an item the repository's Rust sources define (its last segment: a
/// function, type, constant, module, variant or field), and each of its other segments is
/// a word of those sources; paths into other crates (`wgpu::...`) are not checked.
#[test]
fn every_code_path_the_docs_name_is_defined() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let (mut defined, mut words) = (std::collections::HashSet::new(), std::collections::HashSet::new());
    let mut stack: Vec<std::path::PathBuf> = ["compiler", "graph", "runtime", "lab", "tests", "shaders-gen"]
        .iter()
        .map(|d| root.join(d))
        .collect();
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap().filter_map(Result::ok) {
            let p = e.path();
            let name = e.file_name();
            if name == "target" || name.to_string_lossy().starts_with('.') {
                continue;
            }
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                // a file is a module (or a test binary) of its name
                let stem = p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
                defined.insert(stem.clone());
                words.insert(stem);
                let src = std::fs::read_to_string(&p).unwrap();
                definitions(&src, &mut defined);
                words.extend(
                    src.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                        .filter(|w| !w.is_empty())
                        .map(str::to_string),
                );
            }
        }
    }
    let docs = markdown(&root);
    let (mut checked, mut missing) = (0, Vec::new());
    for doc in &docs {
        let text = std::fs::read_to_string(doc).unwrap();
        for (i, line) in text.lines().enumerate() {
            for span in line.split('`').skip(1).step_by(2) {
                let called = span.strip_suffix("()");
                let path = called.unwrap_or(span);
                if !(path.contains("::") || called.is_some()) || code_names(&format!("`{path}`")).is_empty() {
                    continue;
                }
                let segments: Vec<&str> = path.split("::").collect();
                if EXTERNAL.contains(&segments[0]) {
                    continue;
                }
                checked += 1;
                let last = segments[segments.len() - 1];
                let known = defined.contains(last) && segments.iter().all(|s| words.contains(*s));
                if !known {
                    missing.push(format!("{}:{}: `{span}`", doc.strip_prefix(&root).unwrap_or(doc).display(), i + 1));
                }
            }
        }
    }
    assert!(checked > 200, "only {checked} code paths found: the scan is broken");
    assert!(
        missing.is_empty(),
        "the docs name code that is not defined:\n{}",
        missing.join("\n")
    );
}

/// README's layout table is complete: its `scenes/` row names every bundled scene (each
/// `.ron` under scenes/, its stem in backticks) and its `sweeps/` row every sweep file.
#[test]
fn the_readme_names_every_bundled_scene_and_sweep() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let row = |folder: &str| {
        readme
            .lines()
            .find(|l| l.starts_with(&format!("| `{folder}/` |")))
            .unwrap_or_else(|| panic!("README.md has no layout row for {folder}/"))
            .to_string()
    };
    let mut missing = Vec::new();
    for folder in ["scenes", "sweeps"] {
        let row = row(folder);
        let mut stack = vec![root.join(folder)];
        let mut found = 0;
        while let Some(dir) = stack.pop() {
            for e in std::fs::read_dir(&dir).unwrap().filter_map(Result::ok) {
                let p = e.path();
                if p.is_dir() {
                    stack.push(p);
                } else if p.extension().is_some_and(|x| x == "ron") {
                    found += 1;
                    let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
                    if !row.contains(&format!("`{stem}`")) {
                        missing.push(format!("{folder}/: `{stem}`"));
                    }
                }
            }
        }
        assert!(found >= 10, "only {found} files in {folder}/: the scan is broken");
    }
    assert!(missing.is_empty(), "README.md's layout table leaves out:\n{}", missing.join("\n"));
}

/// README's tour names every command of the `sshc` binary (`sshc verify`, `sshc view`,
/// ...): each variant of `enum Command` in lab/src/main.rs, in kebab case.
#[test]
fn the_readme_names_every_command() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let main = std::fs::read_to_string(root.join("lab/src/main.rs")).unwrap();
    let body = main
        .split("enum Command {")
        .nth(1)
        .expect("lab/src/main.rs declares `enum Command`");
    let body = &body[..body.find("\n}").expect("the enum ends")];
    let mut commands: Vec<String> = body
        .lines()
        .filter(|l| l.starts_with("    ") && !l.starts_with("     ") && l.trim_start().starts_with(|c: char| c.is_ascii_uppercase()))
        .map(|l| {
            let name: String = l.trim().chars().take_while(char::is_ascii_alphanumeric).collect();
            let mut kebab = String::new();
            for (i, c) in name.chars().enumerate() {
                if c.is_ascii_uppercase() && i > 0 {
                    kebab.push('-');
                }
                kebab.push(c.to_ascii_lowercase());
            }
            kebab
        })
        .collect();
    commands.dedup();
    assert!(commands.len() >= 10, "only {commands:?} found: the scan is broken");
    let missing: Vec<&String> = commands.iter().filter(|c| !readme.contains(&format!("sshc {c}"))).collect();
    assert!(missing.is_empty(), "README.md never shows `sshc {missing:?}`");
}

/// docs/compile-time.md's section "Every bundled technique" has a row for each file in
/// techniques/ (README's "every bundled technique under 5 ms but PCSS" rests on it).
#[test]
fn the_compile_time_table_has_every_technique() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join("docs/compile-time.md")).unwrap();
    let section = text
        .split("\n## ")
        .find(|s| s.starts_with("Every bundled technique"))
        .expect("docs/compile-time.md has a section \"Every bundled technique\"");
    let mut missing = Vec::new();
    let mut found = 0;
    for e in std::fs::read_dir(root.join("techniques")).unwrap().filter_map(Result::ok) {
        let p = e.path();
        if p.extension().is_some_and(|x| x == "ron") {
            found += 1;
            let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
            if !section.lines().any(|l| l.starts_with(&format!("| {stem} |"))) {
                missing.push(stem);
            }
        }
    }
    assert!(found >= 10, "only {found} techniques found: the scan is broken");
    assert!(missing.is_empty(), "docs/compile-time.md has no row for {missing:?}");
}
