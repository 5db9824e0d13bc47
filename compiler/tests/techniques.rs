//! The bundled techniques: snapshots of everything they compile to (reviewed as diffs,
//! naga style), parameter and precision grids where every variant compiles (codegen
//! validates with naga) or is refused with a diagnostic naming the limit, and compiles to
//! the textures the packing rules give and the fetches its source counts, both by hand;
//! and the CSM convergence check.

use sshc::Precision;
use sshc::{CompileOptions, Limits};
use std::path::{Path, PathBuf};

/// Every technique file in `techniques/`, by name, sorted: a new file is tested without
/// being listed here.
pub fn techniques() -> Vec<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../techniques");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort();
    assert!(names.len() >= 11, "the bundled techniques: {names:?}");
    names
}

fn path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../techniques")
        .join(format!("{name}.ron"))
}

fn source(name: &str) -> String {
    std::fs::read_to_string(path(name)).unwrap()
}

fn opts(set: &[(&str, String)], precision: &[(&str, Precision)]) -> CompileOptions {
    CompileOptions {
        set: set.iter().map(|(a, b)| (a.to_string(), b.clone())).collect(),
        precision: precision.iter().map(|(a, p)| (a.to_string(), p.name().to_string())).collect(),
        ..Default::default()
    }
}

#[test]
fn snapshots_of_every_technique() {
    for t in &techniques() {
        let c = sshc::compile_str(&source(t), &CompileOptions::default()).unwrap_or_else(|d| panic!("{t}: {}", d.render(t, &source(t))));
        insta::assert_snapshot!(format!("{t}.graph.ron"), c.graph.to_ron());
        for (file, src) in &c.shaders {
            insta::assert_snapshot!(file.clone(), src);
        }
        insta::assert_snapshot!(format!("{t}.explain"), c.explain());
        // What the compiler reports equals what it writes.
        let back = sshc::PassGraph::from_ron(&c.graph.to_ron()).expect("emitted graph reads back");
        assert_eq!(back, c.graph);
    }
}

/// Compile a variant: it must compile (codegen has validated every module with naga), or be
/// refused with an error that names `limit`. Returns what it compiled to, for the grids
/// to check against what the packing rules give by hand.
fn variant(t: &str, o: &CompileOptions, refusal_names: Option<&str>) -> Option<sshc::Compiled> {
    let src = source(t);
    match (sshc::compile_str(&src, o), refusal_names) {
        (Ok(c), None) => Some(c),
        (Ok(_), Some(limit)) => panic!("{t} {:?} {:?}: compiled, but should be refused naming {limit}", o.set, o.precision),
        (Err(d), None) => panic!("{t} {:?} {:?}: refused\n{}", o.set, o.precision, d.render(t, &src)),
        (Err(d), Some(limit)) => {
            let text = d.render(t, &src);
            assert!(text.contains(limit), "{t} {:?}: refusal does not name `{limit}`:\n{text}", o.set);
            None
        }
    }
}

/// [`variant`] that must compile.
fn compiles(t: &str, o: &CompileOptions) -> sshc::Compiled {
    variant(t, o, None).expect("compiled")
}

/// The texture `n` channels of precision `p` pack into, by the packing rules
/// (docs/architecture.md, section 4): 1 component per texel for one channel, 2 for two,
/// else 4; ceil(n / components) layers; the format named by precision and components.
/// Returns (format, layers).
fn packed(p: Precision, n: u32) -> (String, u32) {
    let components = match n {
        1 => 1,
        2 => 2,
        _ => 4,
    };
    let prefix = ["R", "Rg", "", "Rgba"][components as usize - 1];
    let suffix = match p {
        Precision::Unorm8 => "8Unorm",
        Precision::Unorm16 => "16Unorm",
        Precision::F16 => "16Float",
        Precision::F32 => "32Float",
    };
    (format!("{prefix}{suffix}"), n.div_ceil(components))
}

/// (format, layers, mips) of the texture `name` of a compiled variant.
fn texture(c: &sshc::Compiled, name: &str) -> (String, u32, bool) {
    let t = c.graph.textures.iter().find(|t| t.name == name).unwrap_or_else(|| {
        let names: Vec<&str> = c.graph.textures.iter().map(|t| t.name.as_str()).collect();
        panic!("{}: no texture `{name}` among {names:?}", c.graph.technique)
    });
    (format!("{:?}", t.format), t.layers, t.mips)
}

fn has_texture(c: &sshc::Compiled, name: &str) -> bool {
    c.graph.textures.iter().any(|t| t.name == name)
}

/// Fetches per shaded pixel: the cost of the Shade pass's step as the compiler counted it.
fn shade_fetches(c: &sshc::Compiled) -> u32 {
    let shade = c.graph.passes.iter().find(|p| p.name == "shade").expect("a Shade pass");
    shade.steps.iter().map(|s| s.cost.fetches).sum()
}

/// `packed` as (format, layers, mips).
fn with_mips((format, layers): (String, u32), mips: bool) -> (String, u32, bool) {
    (format, layers, mips)
}

#[test]
fn csm_grid_every_order_at_every_precision() {
    for m in [1, 2, 4, 8, 16, 32, 64] {
        for p in Precision::ALL {
            let c = compiles("csm", &opts(&[("M", m.to_string())], &[("f", p)]));
            // the expansion f: a cosine and a sine image per term k = 1..M, 2M channels,
            // the mip chain built in place on the blurred copy
            assert_eq!(texture(&c, "basis"), with_mips(packed(p, 2 * m), false), "csm M = {m} {p:?}");
            assert_eq!(texture(&c, "blurred"), with_mips(packed(p, 2 * m), true), "csm M = {m} {p:?}");
        }
    }
    // M = 1 at Unorm8: sin and cos in one Rg8Unorm layer; M = 64: 32 Rgba8Unorm layers
    assert_eq!(packed(Precision::Unorm8, 2), ("Rg8Unorm".into(), 1));
    assert_eq!(packed(Precision::Unorm8, 128), ("Rgba8Unorm".into(), 32));
    // Under a device with 16 array layers, M = 64 at unorm8 (128 channels, 32 RGBA layers)
    // does not fit and the refusal names the limit.
    let mut o = opts(&[("M", "64".into())], &[]);
    o.limits = Limits {
        max_texture_array_layers: 16,
        ..Limits::default()
    };
    variant("csm", &o, Some("maxTextureArrayLayers = 16"));
    for fix in 0..=2 {
        for alpha in ["0.0", "1.0", "4.0"] {
            let c = compiles("csm", &opts(&[("fix", fix.to_string()), ("alpha", alpha.into())], &[]));
            // the file's M = 4 at Unorm8: 8 channels in 2 Rgba8Unorm layers
            assert_eq!(texture(&c, "basis"), ("Rgba8Unorm".into(), 2, false), "fix {fix} alpha {alpha}");
        }
    }
}

#[test]
fn esm_grid_exponent_precision_and_classification() {
    for c in [5.0, 11.0, 11.2, 40.0, 80.0, 88.0] {
        for p in [Precision::F16, Precision::F32] {
            for classify in 0..=2 {
                let o = opts(&[("c", format!("{c:?}")), ("classify", classify.to_string())], &[("e", p)]);
                // f16 holds exp(c z) for z in [0, 1] only while c <= ln 65504 = 11.09
                let refused = p == Precision::F16 && c > 11.09;
                let Some(compiled) = variant("esm", &o, refused.then_some("must stay at or below 11.0898")) else {
                    continue;
                };
                // one channel e = exp(c z): one component per texel
                assert_eq!(texture(&compiled, "esm"), with_mips(packed(p, 1), false), "esm c = {c} {p:?}");
                // only z-max classification reads the z-max filter; the select folds otherwise
                assert_eq!(has_texture(&compiled, "zmax"), classify == 2, "esm classify = {classify}");
            }
        }
    }
}

#[test]
fn vsm_grid_blur_and_precision() {
    for k in [1, 3, 7, 15] {
        for p in [Precision::Unorm16, Precision::F16, Precision::F32] {
            let c = compiles("vsm", &opts(&[("K", k.to_string())], &[("m1", p), ("m2", p)]));
            // two moments: two components, one layer
            assert_eq!(texture(&c, "moments"), with_mips(packed(p, 2), false), "vsm K = {k} {p:?}");
        }
    }
}

#[test]
fn pcf_and_hard_grids() {
    for n in 1..=8u32 {
        let c = compiles("pcf", &opts(&[("N", n.to_string())], &[]));
        // `sum(i in 0..=N, sum(j in 0..=N, ... fetch(z, i - r, j - r)))`: (N + 1)^2 texels
        assert_eq!(shade_fetches(&c), (n + 1) * (n + 1), "pcf N = {n}");
    }
    variant("pcf", &opts(&[("N", "16".into())], &[]), Some("out of range"));
    for p in Precision::ALL {
        let c = compiles("hard", &opts(&[], &[("z", p)]));
        assert_eq!(texture(&c, "shadow"), with_mips(packed(p, 1), false), "hard {p:?}");
        // one lookup of the receiver's texel
        assert_eq!(shade_fetches(&c), 1, "hard {p:?}");
        let c = compiles("pcf", &opts(&[], &[("z", p)]));
        assert_eq!(texture(&c, "shadow"), with_mips(packed(p, 1), false), "pcf {p:?}");
        assert_eq!(shade_fetches(&c), 16, "pcf N = 3 {p:?}");
    }
}

mod mutations {
    use super::*;
    use proptest::prelude::*;

    const TOKENS: &[&str] = &[
        "(",
        ")",
        ",",
        ":",
        "\"",
        "[",
        "]",
        "{",
        "}",
        "0",
        "-1",
        "1e40",
        "65",
        "M",
        "k",
        "sum(k in 1..=3, ",
        "let x = 1;",
        "..=",
        "/",
        "*",
        "r#\"",
        "\\",
        "é",
        "Unorm8",
        "Shade(",
        "Filter(",
        "expand(",
        "sample(",
        "//",
        "/*",
    ];

    fn mutate(src: &str, ops: &[(usize, usize, usize)]) -> String {
        let mut s = src.to_string();
        for &(pos, len, tok) in ops {
            let mut at = pos % (s.len() + 1);
            while !s.is_char_boundary(at) {
                at -= 1;
            }
            let mut end = (at + len % 8).min(s.len());
            while !s.is_char_boundary(end) {
                end -= 1;
            }
            match tok % 3 {
                0 => s.replace_range(at..end, ""),
                1 => s.insert_str(at, TOKENS[tok % TOKENS.len()]),
                _ => s.replace_range(at..end, TOKENS[tok % TOKENS.len()]),
            }
        }
        s
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]
        /// Random token mutations of the bundled techniques never panic the compiler.
        #[test]
        fn mutated_techniques_never_panic(which in 0usize..64, ops in proptest::collection::vec((0usize..100_000, 0usize..8, 0usize..1000), 1..6)) {
            let names = techniques();
            let src = source(&names[which % names.len()]);
            let mutated = mutate(&src, &ops);
            let r = std::panic::catch_unwind(|| {
                let checked = sshc::check_str(&mutated, &CompileOptions::default());
                if let Err(d) = sshc::compile_str(&mutated, &CompileOptions::default()) {
                    // rendering must not panic either
                    let text = d.render("mutated.ron", &mutated);
                    // check and compile agree: what passes check fails only in a later phase
                    if checked.is_ok() {
                        assert_later_than_check(&d, &text);
                    }
                }
            });
            prop_assert!(r.is_ok(), "panicked on:\n{}", mutated);
        }
    }
}

/// Errors of a technique that `check_str` accepted: none may come from a front-end phase,
/// and none may be an internal error of `lower` (an invariant check should have made).
fn assert_later_than_check(d: &sshc::Diagnostics, text: &str) {
    use sshc::Phase;
    for e in d.errors() {
        assert!(
            !matches!(e.phase, Phase::Syntax | Phase::Parse | Phase::Resolve | Phase::Check),
            "check passed but compile reports a front-end error:\n{text}"
        );
        assert!(
            !e.message.contains("internal compiler error"),
            "check passed but lower failed:\n{text}"
        );
    }
}

#[test]
fn check_and_compile_agree_on_integer_literals() {
    // 2^31 does not fit in an i32: `check` refuses it, at the literal, as `compile` does.
    let src = source("hard").replace(
        "select(0.0, 1.0, d_biased <= nearest(z))",
        "select(0.0, 1.0, d_biased <= nearest(z)) * f32(2147483648)",
    );
    let at = src.find("2147483648").unwrap();
    for d in [
        sshc::check_str(&src, &CompileOptions::default()).unwrap_err(),
        sshc::compile_str(&src, &CompileOptions::default()).unwrap_err(),
    ] {
        let e = d.errors().next().unwrap();
        assert_eq!(e.phase, sshc::Phase::Check, "{}", d.render("hard", &src));
        assert_eq!(
            (e.primary.0.start as usize, e.primary.0.end as usize),
            (at, at + 10),
            "{}",
            d.render("hard", &src)
        );
        assert!(e.message.contains("does not fit in i32"), "{}", e.message);
    }
    // 2^31 - 1 fits, and an abstract integer beside an f32 converts to f32.
    for ok in ["* f32(2147483647)", "* (7 / 2)", "+ 0.0 * f32(sum(k in 1..=3, 2 * k))"] {
        let src = source("hard").replace(
            "select(0.0, 1.0, d_biased <= nearest(z))",
            &format!("select(0.0, 1.0, d_biased <= nearest(z)) {ok}"),
        );
        if ok.contains("7 / 2") {
            // abstract 7 / 2 is the integer 3, then the f32 3.0 (as WGSL)
            let dumped = CompileOptions {
                dump_after: Some(sshc::DumpPhase::Lower),
                ..Default::default()
            };
            let out = sshc::compile_with_dump(&src, &dumped);
            out.result.unwrap_or_else(|d| panic!("{}", d.render("hard", &src)));
            let dump = out.dump.expect("dumped after lower");
            let visibility = dump
                .lines()
                .find(|l| l.trim_start().starts_with("visibility = "))
                .expect("a visibility");
            assert!(visibility.contains("* 3.0)"), "{visibility}");
        }
        sshc::check_str(&src, &CompileOptions::default()).unwrap_or_else(|d| panic!("{ok}: {}", d.render("hard", &src)));
        sshc::compile_str(&src, &CompileOptions::default()).unwrap_or_else(|d| panic!("{ok}: {}", d.render("hard", &src)));
    }
    // An abstract expression without an i32 value is refused by check too.
    let src = source("hard").replace(
        "select(0.0, 1.0, d_biased <= nearest(z))",
        "select(0.0, 1.0, d_biased <= nearest(z)) * (2147483647 + 1)",
    );
    let d = sshc::check_str(&src, &CompileOptions::default()).unwrap_err();
    assert!(
        d.render("hard", &src)
            .contains("integer overflow: 2147483647 + 1 does not fit in i32"),
        "{}",
        d.render("hard", &src)
    );
}

/// Every error fixture: what compile refuses in a front-end phase, check refuses with the
/// same diagnostic; what compile refuses later, check accepts.
#[test]
fn check_and_compile_agree_on_every_error_fixture() {
    use sshc::Phase;
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/errors");
    for f in std::fs::read_dir(&dir).unwrap().filter_map(|e| e.ok()).map(|e| e.path()) {
        if f.extension().is_none_or(|x| x != "ron") {
            continue;
        }
        let src = std::fs::read_to_string(&f).unwrap();
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        let compiled = sshc::compile_str(&src, &CompileOptions::default()).expect_err(&name);
        let checked = sshc::check_str(&src, &CompileOptions::default());
        let front = compiled
            .errors()
            .any(|e| matches!(e.phase, Phase::Syntax | Phase::Parse | Phase::Resolve | Phase::Check));
        match checked {
            Err(d) => {
                assert!(front, "{name}: check refuses what compile refuses only later");
                assert_eq!(d.render(&name, &src), compiled.render(&name, &src), "{name}");
            }
            Ok(()) => assert_later_than_check(&compiled, &compiled.render(&name, &src)),
        }
    }
}

#[test]
fn check_and_compile_agree_on_empty_series() {
    // An empty series is the zero of its body's type (docs/language.md): here vec2(0.0),
    // so `.x` of it is well typed in check and lowers to a vector in compile.
    for body in ["vec2(d, 1.0)", "d", "k"] {
        let sum = format!("sum(k in 1..=0, {body})");
        let term = if body.starts_with("vec2") {
            format!("{sum}.x")
        } else if body == "k" {
            format!("f32({sum})")
        } else {
            sum.clone()
        };
        let src = source("hard").replace(
            "select(0.0, 1.0, d_biased <= nearest(z))",
            &format!("select(0.0, 1.0, d_biased <= nearest(z)) + {term}"),
        );
        sshc::check_str(&src, &CompileOptions::default()).unwrap_or_else(|d| panic!("{body}: {}", d.render("hard", &src)));
        let c = sshc::compile_str(&src, &CompileOptions::default()).unwrap_or_else(|d| panic!("{body}: {}", d.render("hard", &src)));
        for (file, wgsl) in &c.shaders {
            sshc::validate_wgsl(wgsl).unwrap_or_else(|e| panic!("{file}: {e}"));
        }
    }
}

#[test]
fn lookups_by_filter_width_validate() {
    // `sample_width` and `expand_width` pick the mip level of a footprint given in uv units.
    let src = source("csm").replace("let s = expand(f);", "let s = expand_width(f, 4.0 * texel_size);");
    let c = sshc::compile_str(&src, &CompileOptions::default()).unwrap_or_else(|d| panic!("{}", d.render("csm", &src)));
    let shade = &c.shaders.iter().find(|(f, _)| f.ends_with("shade.wgsl")).unwrap().1;
    assert!(shade.contains("textureSampleLevel(t_blurred, smp, in_uv, 0i, log2(max("), "{shade}");
    let src = source("vsm").replace("let mean = sample(m1);", "let mean = sample_width(m1, 0.01);");
    let c = sshc::compile_str(&src, &CompileOptions::default()).unwrap_or_else(|d| panic!("{}", d.render("vsm", &src)));
    assert!(
        c.shaders
            .iter()
            .any(|(_, s)| s.contains("log2(max(1e-2f * frame.shadow_size.x, 1.0))"))
    );
}

#[test]
fn cssm_with_summed_area_tables_snapshots() {
    // filter = 1: the table path (every channel Unorm8, box lookups); the default snapshot
    // above covers the mipmap path.
    let src = source("cssm");
    let c = sshc::compile_str(&src, &opts(&[("filter", "1".into())], &[])).unwrap_or_else(|d| panic!("{}", d.render("cssm", &src)));
    insta::assert_snapshot!("cssm-filter1.graph.ron", c.graph.to_ron());
    for (file, wgsl) in &c.shaders {
        insta::assert_snapshot!(format!("cssm-filter1.{file}"), wgsl);
    }
    insta::assert_snapshot!("cssm-filter1.explain", c.explain());
}

#[test]
fn cssm_filter_param_removes_the_unused_prefilter() {
    // The Shade pass selects between the mipmap and the table lookups with the fixed param
    // `filter`: the select folds, and dead-code elimination removes the other path's passes
    // and resources; `sshc explain` says so.
    let src = source("cssm");
    for (filter, kept, gone) in [
        ("0", ["basis", "blur", "mips"], ["basis_sat", "blur_sat", "sat"]),
        ("1", ["basis_sat", "blur_sat", "sat"], ["basis", "blur", "mips"]),
    ] {
        let c = sshc::compile_str(&src, &opts(&[("filter", filter.into())], &[])).unwrap_or_else(|d| panic!("{}", d.render("cssm", &src)));
        let passes: Vec<&str> = c.graph.passes.iter().map(|p| p.name.as_str()).collect();
        let text = c.explain();
        let removed = text
            .split("\nRemoved:")
            .nth(1)
            .unwrap_or_else(|| panic!("filter = {filter}: nothing removed:\n{text}"));
        for p in kept {
            assert!(passes.contains(&p), "filter = {filter}: pass `{p}` missing from {passes:?}");
        }
        for p in gone {
            assert!(!passes.contains(&p), "filter = {filter}: pass `{p}` kept in {passes:?}");
            assert!(
                removed.contains(&format!("pass `{p}`: no shaded pixel reads what it writes")),
                "filter = {filter}: explain does not report removing `{p}`:\n{removed}"
            );
        }
        // the table path stores only unorm codes; the mipmap path keeps the z-weighted basis at F16
        let shade = &c.shaders.iter().find(|(f, _)| f.ends_with("shade.wgsl")).unwrap().1;
        assert_eq!(filter == "1", !shade.contains("textureSampleLevel"), "filter = {filter}:\n{shade}");
    }
}

#[test]
fn cssm_grid_order_filter_and_precision() {
    for m in [1, 2, 4, 8, 16, 32, 64] {
        // mipmaps: the CSM basis at every precision, the z-weighted basis and z/2 at every
        // precision (unorm ones with an affine encoding)
        for p in Precision::ALL {
            let c = compiles("cssm", &opts(&[("M", m.to_string())], &[("f", p), ("g", p), ("zh", p)]));
            // one precision: one texture of 2M (f) + 2M (g) + 1 (zh) = 4M + 1 channels, named
            // after the resource; M + 1 layers of 4 components
            assert_eq!(texture(&c, "basis"), with_mips(packed(p, 4 * m + 1), false), "cssm M = {m} {p:?}");
            assert_eq!(packed(p, 4 * m + 1).1, m + 1);
        }
        // summed-area tables of unorm channels: their codes in u32
        for p in [Precision::Unorm8, Precision::Unorm16] {
            let o = opts(&[("M", m.to_string()), ("filter", "1".into())], &[("fs", p), ("gs", p), ("zhs", p)]);
            let c = compiles("cssm", &o);
            assert_eq!(
                texture(&c, "basis_sat"),
                with_mips(packed(p, 4 * m + 1), false),
                "cssm tables M = {m} {p:?}"
            );
            // the table holds the prefix sums of every layer of the blurred basis
            assert_eq!(
                texture(&c, "table"),
                ("SummedAreaU32".into(), m + 1, false),
                "cssm tables M = {m} {p:?}"
            );
        }
    }
    // a float channel's table sums in f32 (`sum: F32`, the default), one buffer of
    // f32 sums beside the unorm textures' codes where precisions mix
    for p in [Precision::F16, Precision::F32] {
        let c = compiles("cssm", &opts(&[("filter", "1".into())], &[("fs", p), ("gs", p), ("zhs", p)]));
        // M = 4 by default: 4M + 1 = 17 channels in 5 layers of 4
        assert_eq!(texture(&c, "table"), ("SummedAreaF32".into(), 5, false), "cssm f32 table {p:?}");
        let mixed = compiles("cssm", &opts(&[("filter", "1".into())], &[("gs", p)]));
        let formats: Vec<String> = mixed
            .graph
            .textures
            .iter()
            .filter(|t| t.format.is_table())
            .map(|t| format!("{:?}", t.format))
            .collect();
        assert_eq!(formats.len(), 2, "cssm mixed tables {p:?}: {formats:?}");
        assert!(formats.contains(&"SummedAreaF32".to_string()) && formats.contains(&"SummedAreaU32".to_string()));
    }
    for fix in 0..=2 {
        for alpha in ["0.0", "1.0", "4.0"] {
            for filter in ["0", "1"] {
                let o = opts(&[("fix", fix.to_string()), ("alpha", alpha.into()), ("filter", filter.into())], &[]);
                compiles("cssm", &o);
            }
        }
    }
    for k in [1, 3, 7] {
        compiles("cssm", &opts(&[("K", k.to_string())], &[]));
    }
    variant("cssm", &opts(&[("filter", "2".into())], &[]), Some("out of range"));
}

#[test]
fn pcss_grid_samples_and_precision() {
    for n in [1, 2, 3, 6, 8, 16u32] {
        for m in [1, 2, 5, 8, 16u32] {
            let c = compiles("pcss", &opts(&[("N", n.to_string()), ("M", m.to_string())], &[]));
            // N x N blocker-search lookups, then M x M PCF lookups, each `nearest_at(z, ...)`
            assert_eq!(shade_fetches(&c), n * n + m * m, "pcss N = {n} M = {m}");
        }
    }
    variant("pcss", &opts(&[("N", "17".into())], &[]), Some("out of range"));
    variant("pcss", &opts(&[("M", "0".into())], &[]), Some("out of range"));
    for p in Precision::ALL {
        let c = compiles("pcss", &opts(&[], &[("z", p)]));
        assert_eq!(texture(&c, "shadow"), with_mips(packed(p, 1), false), "pcss {p:?}");
    }
}

/// The compulsory bytes of each pass (`sshc_graph::cost::traffic`), derived by hand from the
/// formats: at 2048^2 texels and 1920 x 1080 pixels.
#[test]
fn compulsory_bytes_follow_from_the_formats_and_sizes() {
    use sshc_graph::cost::{Sizes, traffic::passes};
    let sizes = Sizes {
        shadow: 2048,
        camera: (1920, 1080),
    };
    let (texels, pixels) = (2048.0 * 2048.0, 1920.0 * 1080.0);
    let of = |c: &sshc::Compiled, pass: &str| {
        passes(&c.graph, sizes)
            .into_iter()
            .find(|p| p.0 == pass)
            .unwrap_or_else(|| panic!("no pass {pass}"))
            .1
    };
    let esm = compiles("esm", &CompileOptions::default());
    // the depth pass writes its R32Float channel and the Depth32Float attachment
    let t = of(&esm, "depth");
    assert_eq!((t.read, t.written), (0.0, 8.0 * texels));
    // `exponential` reads one R32Float texel and writes one: 33.5 MB, 0.60 ms on an H100
    // in the issue's measurement, 56 GB/s
    let t = of(&esm, "exponential");
    assert_eq!((t.read, t.written), (4.0 * texels, 4.0 * texels));
    assert!((t.bound_ms(3350.0) - 0.010).abs() < 0.0005, "{}", t.bound_ms(3350.0));
    // the separable blur: two steps, each reading and writing every texel once
    let t = of(&esm, "blur");
    assert_eq!((t.read, t.written), (8.0 * texels, 8.0 * texels));
    // the Shade writes its four targets and depth; what it reads depends on the view
    let t = of(&esm, "shade");
    assert_eq!((t.read, t.written), (0.0, 36.0 * pixels));
    // a mip chain: the levels below the base written (1/3 of it), each reading the level
    // above (4/3 of the base in all)
    let vsm = compiles("vsm", &CompileOptions::default());
    let mip = vsm
        .graph
        .passes
        .iter()
        .find(|p| p.kind == sshc_graph::PassKind::Mipmap)
        .expect("vsm mipmaps");
    // techniques/vsm.ron stores `m1` and `m2` at F32 in one texture: 8 bytes a texel
    let bpt = 8.0;
    let t = of(&vsm, &mip.name);
    let layers = mip.steps.iter().map(|s| s.writes.len()).sum::<usize>() as f64;
    assert!((t.written - bpt * texels * layers / 3.0).abs() < 1.0, "{t:?}");
    assert!((t.read - bpt * texels * layers * 4.0 / 3.0).abs() < 1.0, "{t:?}");
    // a per-sample depth pass runs once per light sample
    let linear = compiles("linear-light", &CompileOptions::default());
    let depth = linear.graph.passes.iter().find(|p| p.kind == sshc_graph::PassKind::Depth).unwrap();
    let t = of(&linear, &depth.name);
    // techniques/linear-light.ron's Depth writes `z` at F32 (4 bytes), plus the 4-byte depth
    // buffer, per view
    let per_view = 4.0 + 4.0;
    assert_eq!(t.written, f64::from(linear.graph.samples) * per_view * texels, "{t:?}");
}

/// Schedules of Map, Filter and Mipmap passes: fragment by default, compute where asked (in
/// the technique or by `--schedule`) and every written format is a storage format, else
/// fragment with the reason in `explain`; `--schedule` names those passes only.
#[test]
fn map_pass_schedules() {
    use sshc_graph::Draw;
    let sched = |pairs: &[(&str, &str)], precision: &[(&str, Precision)]| {
        let mut o = opts(&[], precision);
        o.schedule = pairs.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
        o
    };
    let draws = |c: &sshc::Compiled, pass: &str| -> Vec<Draw> {
        c.graph
            .passes
            .iter()
            .find(|p| p.name == pass)
            .unwrap()
            .steps
            .iter()
            .map(|s| s.draw.clone())
            .collect()
    };
    // every pass as fragment (vsm.ron schedules its mip chain as compute)
    let vsm = compiles("vsm", &sched(&[("mips", "fragment")], &[]));
    assert_eq!(draws(&vsm, "moments"), [Draw::FullScreen]);
    assert_eq!(draws(&vsm, "mips"), [Draw::MipLevels]);
    assert_eq!(
        draws(&compiles("vsm", &CompileOptions::default()), "mips"),
        [Draw::ComputeMipLevels]
    );
    assert!(vsm.explain().contains("(schedule: fragment, a full-screen triangle)"));
    for name in ["moments", "*"] {
        let c = compiles("vsm", &sched(&[(name, "compute")], &[]));
        assert_eq!(draws(&c, "moments"), [Draw::ComputeTexels], "{name}");
        let step = &c.graph.passes.iter().find(|p| p.name == "moments").unwrap().steps[0];
        assert_eq!((step.vertex.as_deref(), step.compute.as_deref()), (None, Some("cs_moments_0")));
        // the same expression per texel, and the edge check (a conversion, a comparison
        // and `any`: 3 operations) the workgroups' overhang needs
        for (a, b) in c.cost.passes.iter().zip(&vsm.cost.passes) {
            match (a.0.as_str(), name) {
                ("moments", _) => assert_eq!((a.3.fetches, a.3.ops), (b.3.fetches, b.3.ops + 3), "{a:?} {b:?}"),
                // `*` runs the blur (Box 3 on one Rg32Float layer) as compute too: each
                // step's workgroup loads its 8 x 8 texels and the apron, 10 x 8 texels, by
                // 64 invocations: 2 loads each instead of 3 taps, 4 for both steps
                ("blur", "*") => assert_eq!((a.3.fetches, b.3.fetches), (4, 6), "{a:?} {b:?}"),
                // the mip chain as compute (by the file, or by `*`): the same loads, and its
                // edge check (a comparison and `any` against the level's size)
                ("mips", _) => assert_eq!((a.3.fetches, a.3.ops), (b.3.fetches, b.3.ops + 2), "{a:?} {b:?}"),
                // `*` makes the Shade deferred: two steps, the G-buffer's three loads more,
                // and more operations (the octahedral normal's encoding and decoding, the
                // edge and background checks; VSM: 114 against 77)
                ("shade", "*") => {
                    assert_eq!(a.2, 2);
                    assert_eq!(a.3.fetches, b.3.fetches + 3, "{a:?} {b:?}");
                    assert!(a.3.ops > b.3.ops, "{a:?} {b:?}");
                }
                _ => assert_eq!(a.3, b.3, "{a:?} {b:?}"),
            }
        }
        assert!(c.explain().contains("(schedule: compute, 8 x 8 texels per workgroup"));
    }
    // Rg16Unorm is not a storage format: fragment, and why
    let c = compiles(
        "vsm",
        &sched(&[("*", "compute")], &[("m1", Precision::Unorm16), ("m2", Precision::Unorm16)]),
    );
    assert_eq!(draws(&c, "moments"), [Draw::FullScreen]);
    assert!(
        c.explain().contains("compute was asked for, but Rg16Unorm is not a storage format"),
        "{}",
        c.explain()
    );
    // refused: a pass that is not a Map pass, no such pass, no such schedule
    for (pairs, want) in [
        (("depth", "compute"), "`--schedule depth=compute`: pass `depth` is a Depth pass"),
        (("nope", "compute"), "`--schedule nope=compute`: no pass named `nope`"),
        (("moments", "tiled"), "`--schedule moments=tiled`: unknown schedule"),
    ] {
        let e = sshc::compile_str(&source("vsm"), &sched(&[pairs], &[])).expect_err("refused");
        let text = e.render("vsm.ron", &source("vsm"));
        assert!(text.contains(want), "{text}");
    }
}

/// `--dump-ir-after` has a dump after every phase, `schedule` included, each phase by its
/// name, and `DumpPhase::ALL` is the order the driver runs the phases in.
#[test]
fn every_phase_dumps_and_all_is_the_order_they_run() {
    use sshc::DumpPhase;
    let src = source("vsm");
    let whole = sshc::compile_with_dump(&src, &CompileOptions::default());
    assert!(whole.result.is_ok());
    assert!(whole.dump.is_none());
    assert_eq!(whole.phases, DumpPhase::ALL, "the phases as the driver ran them");
    for p in DumpPhase::ALL {
        assert_eq!(p.name().parse::<DumpPhase>(), Ok(p));
        let o = sshc::compile_with_dump(
            &src,
            &CompileOptions {
                dump_after: Some(p),
                ..Default::default()
            },
        );
        assert!(o.result.is_ok(), "{}", p.name());
        let dump = o.dump.unwrap_or_else(|| panic!("no dump after {}", p.name()));
        assert!(!dump.trim().is_empty(), "an empty dump after {}", p.name());
    }
    // the front end alone stops after check
    let front = sshc::check_with_dump(
        &src,
        &CompileOptions {
            dump_after: Some(DumpPhase::Schedule),
            ..Default::default()
        },
    );
    assert!(front.0.is_ok());
    assert!(front.1.is_none());
    // the schedule's dump: every pass's schedule, and why a compute one asked for was refused
    let o = sshc::compile_with_dump(
        &src,
        &CompileOptions {
            dump_after: Some(DumpPhase::Schedule),
            schedule: vec![("*".into(), "compute".into())],
            precision: vec![("m1".into(), "Unorm16".into()), ("m2".into(), "Unorm16".into())],
            ..Default::default()
        },
    );
    assert!(o.result.is_ok());
    let dump = o.dump.unwrap_or_default();
    for line in [
        "technique vsm: schedules",
        "  pass depth (Depth): the one schedule of its kind",
        "  pass moments (Map): fragment; compute was asked for, but Rg16Unorm is not a storage format",
        "  pass shade (Shade): compute (deferred), as asked",
    ] {
        assert!(dump.lines().any(|l| l == line), "{line:?} in\n{dump}");
    }
}

/// A raster pass rendering into a 16-bit norm format is warned about at compile time, the
/// channels and the fix named, unless the limits profile renders to them (the
/// runtime refuses such a graph on a device without the feature).
#[test]
fn unorm16_render_targets_are_warned_about_against_the_profile() {
    let warned = |o: &CompileOptions| -> Vec<String> {
        let c = compiles("vsm", o);
        c.warnings
            .iter()
            .map(|w| w.render("vsm.ron", &source("vsm")))
            .filter(|w| w.contains("16-bit norm"))
            .collect()
    };
    let unorm16 = opts(&[], &[("m1", Precision::Unorm16), ("m2", Precision::Unorm16)]);
    let w = warned(&unorm16);
    // the moments pass and the blur render into Rg16Unorm (the mip chain too, one warning
    // per texture: moments and blurred)
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(w[0].contains("pass `moments` renders `m1`, `m2` into Rg16Unorm"), "{}", w[0]);
    assert!(w[0].contains("store them at F16"), "{}", w[0]);
    let mut capable = unorm16.clone();
    capable.limits.renderable_norm16 = true;
    assert!(warned(&capable).is_empty());
    assert!(warned(&opts(&[], &[("m1", Precision::F16), ("m2", Precision::F16)])).is_empty());
    assert!(warned(&CompileOptions::default()).is_empty());
}

/// Vector constant folding: identities with constant zeros and ones, operations
/// on constant components and swizzles of constructors fold, so that an expression written
/// with them costs what its hand-simplified form costs; no bundled technique's counts move
/// (the folds never split a vector operation into scalar ones).
#[test]
fn vector_constants_fold_to_the_hand_simplified_cost() {
    let tech = |vis: &str| {
        format!(
            r#"Technique(
    name: "vf",
    params: {{ "c": Param(ty: F32, default: 0.5, range: (0.0, 1.0), doc: "a uniform") }},
    channels: {{ "z": Channel(precision: F32) }},
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Shade(name: "shade", reads: ["shadow"], visibility: "{vis}"),
    ],
)
"#
        )
    };
    let ops = |vis: &str| {
        let src = tech(vis);
        let c = sshc::compile_str(&src, &CompileOptions::default()).unwrap_or_else(|d| panic!("{}", d.render("vf.ron", &src)));
        let shade = c.shaders.iter().find(|(f, _)| f.ends_with("shade.wgsl")).unwrap().1.clone();
        (c.cost.shade, shade)
    };
    let lookup = "step(d, nearest_at(z, o.x * 0.001, o.y * 0.001))";
    let (folded, src) = ops(&format!(
        "let o = vec2(c, c) + vec2(0.0, 0.0) + vec2(0.25, 0.5) * vec2(2.0, 2.0) * 1.0 + vec2(0.0, 0.0) - 0.0; {lookup}"
    ));
    let (by_hand, _) = ops(&format!("let o = vec2(c, c) + vec2(0.5, 1.0); {lookup}"));
    assert_eq!(folded, by_hand, "{src}");
    assert!(!src.contains("vec2<f32>(0.0f, 0.0f)"), "{src}");
    // a component of a constructor is that argument
    let (picked, _) = ops("step(d, nearest_at(z, vec2(c * 0.001, 7.0).x, vec2(3.0, c * 0.002).y))");
    let (plain, _) = ops("step(d, nearest_at(z, c * 0.001, c * 0.002))");
    assert_eq!(picked, plain);
}

/// `sample_mip_box` and `sample_mip_box_at` (issue 51): the Shade calls the module's
/// `mip_box` function on the Mean chain, declared once; snapshot of the module.
#[test]
fn the_mip_box_lookup_compiles_to_one_function_on_the_chain() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mip-box.ron");
    let src = std::fs::read_to_string(&p).unwrap();
    let c = sshc::compile_str(&src, &CompileOptions::default()).unwrap_or_else(|d| panic!("{}", d.render("mip-box.ron", &src)));
    let (_, shade) = c.shaders.iter().find(|(f, _)| f.ends_with("shade.wgsl")).unwrap();
    assert_eq!(shade.matches("fn mip_box(").count(), 1, "{shade}");
    assert_eq!(shade.matches("mip_box(t_").count(), 2, "{shade}");
    insta::assert_snapshot!("fixture.mip-box.shade.wgsl", shade);
}
