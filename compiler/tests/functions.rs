//! Functions declared in a technique: typed parameters, inlined at every call,
//! in the caller's context; recursion, wrong calls and runaway inlining refused with
//! diagnostics at file:line:column.

use sshc::CompileOptions;
use std::time::{Duration, Instant};

fn root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn vsm() -> String {
    std::fs::read_to_string(root().join("techniques/vsm.ron")).unwrap()
}

/// VSM with `functions` declared before its passes and `visibility` as its Shade's body.
fn vsm_with(functions: &str, visibility: &str) -> String {
    let src = vsm();
    let (head, rest) = src.split_once("    passes: [").unwrap();
    let (passes, _) = rest.split_once("        Shade(").unwrap();
    format!(
        "{head}    functions: {{\n{functions}\n    }},\n    passes: [{passes}        Shade(name: \"shade\", reads: [\"filtered\"], visibility: \"{visibility}\"),\n    ],\n)\n"
    )
}

fn compile(src: &str) -> Result<sshc::Compiled, String> {
    sshc::compile_str(src, &CompileOptions::default()).map_err(|d| d.render("t.ron", src))
}

fn refused(src: &str, want: &[&str]) {
    let e = compile(src).expect_err("refused");
    for w in want {
        assert!(e.contains(w), "expected `{w}` in:\n{e}");
    }
}

/// `text` with every `e<digits>` identifier renamed `v<k>`, k its order of first appearance.
fn renumbered(text: &str) -> String {
    let mut seen: Vec<String> = Vec::new();
    let mut out = String::new();
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i] == b'e' && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'));
        let digits = b[i + 1..].iter().take_while(|c| c.is_ascii_digit()).count();
        let ends = b.get(i + 1 + digits).is_none_or(|c| !(c.is_ascii_alphanumeric() || *c == b'_'));
        if starts && digits > 0 && ends {
            let id = &text[i..i + 1 + digits];
            let k = seen.iter().position(|s| s == id).unwrap_or_else(|| {
                seen.push(id.to_string());
                seen.len() - 1
            });
            out += &format!("v{k}");
            i += 1 + digits;
        } else {
            out.push(b[i] as char);
            i += 1;
        }
    }
    out
}

const CHEBYSHEV: &str = r#"        "chebyshev": Function(
            params: { "mean": F32, "second": F32, "t": F32 },
            body: "let variance = max(second - mean * mean, min_variance); let delta = t - mean; select(1.0, variance / (variance + delta * delta), t > mean)",
            doc: "Chebyshev's one-sided bound (Donnelly & Lauritzen 2006, eq. 5)",
        ),"#;

/// The bundled VSM's Shade, its bound written as a function: the same shader and the
/// same operation counts (inlining then the arena's sharing leave nothing of the call).
#[test]
fn a_function_compiles_to_the_code_written_inline() {
    let bundled = compile(&vsm()).unwrap();
    let src = vsm_with(
        CHEBYSHEV,
        "let d_biased = d - bias - slope_bias * depth_slope; linstep(bleed, 1.0, chebyshev(sample(m1), sample(m2), d_biased))",
    );
    let with = compile(&src).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(with.cost.shade, bundled.cost.shade);
    let shade = |c: &sshc::Compiled| c.shaders.iter().find(|(f, _)| f.ends_with("shade.wgsl")).unwrap().1.clone();
    // the same code, but for the numbering of the emitted `let`s (the arena numbers nodes
    // in the order it met them)
    assert_eq!(renumbered(&shade(&with)), renumbered(&shade(&bundled)));
    // called twice with other arguments: two bounds, each argument's own
    let twice = vsm_with(
        CHEBYSHEV,
        "let t = d - bias; 0.5 * (chebyshev(sample(m1), sample(m2), t) + chebyshev(sample(m1), sample(m2), t - 0.01))",
    );
    let c = compile(&twice).unwrap_or_else(|e| panic!("{e}"));
    assert!(c.cost.shade.ops > bundled.cost.shade.ops, "{:?}", c.cost.shade);
}

/// Functions call functions; integer and vector parameters; an abstract integer argument
/// takes its parameter's type.
#[test]
fn functions_call_functions_with_every_parameter_type() {
    let src = vsm_with(
        r#"        "square": Function(params: { "x": F32 }, body: "x * x"),
        "norm2": Function(params: { "v": Vec2 }, body: "square(v.x) + square(v.y)"),
        "pick": Function(params: { "k": I32, "on": Bool }, body: "select(0.0, f32(k), on)"),"#,
        "clamp(norm2(vec2(d, sample(m1))) + pick(2, d > 0.5) * 0.0, 0.0, 1.0)",
    );
    compile(&src).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn recursion_is_refused_with_the_chain_of_calls() {
    refused(
        &vsm_with(r#"        "f": Function(params: { "x": F32 }, body: "f(x) + 1.0"),"#, "f(d)"),
        &["error[check]: recursive call of `f`", "calls: f -> f", "t.ron:"],
    );
    refused(
        &vsm_with(
            r#"        "f": Function(params: { "x": F32 }, body: "g(x)"),
        "g": Function(params: { "x": F32 }, body: "f(x * 0.5)"),"#,
            "f(d)",
        ),
        &["recursive call of `f`", "calls: f -> g -> f"],
    );
}

#[test]
fn wrong_calls_name_the_signature() {
    refused(
        &vsm_with(CHEBYSHEV, "chebyshev(d, d)"),
        &[
            "`chebyshev` takes 3 argument(s), found 2",
            "declared here: chebyshev(mean: f32, second: f32, t: f32)",
        ],
    );
    refused(
        &vsm_with(CHEBYSHEV, "chebyshev(d, d, vec2(d, d))"),
        &["type mismatch: parameter `t` of `chebyshev` is f32, found vec2<f32>"],
    );
}

/// A body sees its parameters, the technique's params and the inputs, not its caller's
/// `let`s; it runs in its caller's context (a lookup in a Map pass's channel is refused
/// there, at the lookup, with the call named).
#[test]
fn a_body_sees_its_parameters_in_its_callers_context() {
    refused(
        &vsm_with(
            r#"        "f": Function(params: { "x": F32 }, body: "x + hidden"),"#,
            "let hidden = 1.0; f(d)",
        ),
        &["unknown name `hidden`"],
    );
    let src = vsm().replace(
        "\"m2\": Channel(precision: F32, value: \"z * z\"",
        "\"m2\": Channel(precision: F32, value: \"f(z)\"",
    );
    let src = src.replace(
        "    passes: [",
        "    functions: { \"f\": Function(params: { \"x\": F32 }, body: \"x * sample(m1)\") },\n    passes: [",
    );
    refused(&src, &["`sample` is only available in a Shade pass", "in this call of `f`"]);
}

#[test]
fn names_are_checked_like_the_other_declarations() {
    refused(
        &vsm_with(r#"        "min": Function(params: { "x": F32 }, body: "x"),"#, "d"),
        &["`min` is a built-in name and cannot name a function"],
    );
    refused(
        &vsm_with(r#"        "bias": Function(params: { "x": F32 }, body: "x"),"#, "d"),
        &["duplicate name `bias`"],
    );
    refused(
        &vsm_with(r#"        "f": Function(params: { "x": F32, "x": I32 }, body: "x"),"#, "f(d, 1)"),
        &["two parameters named `x`"],
    );
    refused(
        &vsm_with(r#"        "f": Function(params: { "x": F64 }, body: "x"),"#, "f(d)"),
        &["unknown parameter type `F64`"],
    );
}

/// Inlining is bounded: 40 functions each calling the previous twice would inline 2^40
/// bodies; the inlined nodes are counted as they are checked and refused past the
/// expression limit, within a second.
#[test]
fn runaway_inlining_is_refused_at_once() {
    let mut fns = String::from("        \"g0\": Function(params: { \"x\": F32 }, body: \"x * 0.5\"),\n");
    for i in 1..40 {
        fns += &format!(
            "        \"g{i}\": Function(params: {{ \"x\": F32 }}, body: \"g{}(x) + g{}(x * 0.5)\"),\n",
            i - 1,
            i - 1
        );
    }
    let t = Instant::now();
    refused(&vsm_with(&fns, "g39(d)"), &["inline more than 65536 expression nodes"]);
    assert!(t.elapsed() < Duration::from_secs(2), "{:?}", t.elapsed());
}

/// `neighbour(ch, dx, dy)`: map side only, offsets known at compile time and at
/// most 31 texels away; each offset a texel load of its own.
#[test]
fn neighbourhood_reads_are_map_side_and_bounded() {
    let with_value = |value: &str| {
        vsm().replace(
            "\"m2\": Channel(precision: F32, value: \"z * z\"",
            &format!("\"m2\": Channel(precision: F32, value: \"{value}\""),
        )
    };
    let c = compile(&with_value("sum(dx in -2..=2, neighbour(z, dx, 0) * neighbour(z, dx, 0)) / 5.0")).unwrap_or_else(|e| panic!("{e}"));
    let moments = c.cost.passes.iter().find(|p| p.0 == "moments").unwrap();
    assert_eq!(moments.3.fetches, 5, "{moments:?}");
    refused(&with_value("neighbour(z, 32, 0)"), &["offset 32 is farther than 31 texels"]);
    refused(&with_value("neighbour(z, i32(z), 0)"), &["is not known at compile time"]);
    refused(&with_value("neighbour(nope, 0, 0)"), &["unknown channel `nope`"]);
    // through a function's `Channel` parameter (issue 51): the same code as written inline
    let with_fn = |functions: &str, value: &str| {
        with_value(value).replace("    passes: [", &format!("    functions: {{\n{functions}\n    }},\n    passes: ["))
    };
    let row = r#"        "row": Function(params: { "c": Channel, "r": I32 }, body: "sum(dx in -2..=2, neighbour(c, dx, r) * neighbour(c, dx, r)) / 5.0"),"#;
    let called = compile(&with_fn(row, "row(z, 1)")).unwrap_or_else(|e| panic!("{e}"));
    let inline = compile(&with_value("sum(dx in -2..=2, neighbour(z, dx, 1) * neighbour(z, dx, 1)) / 5.0")).unwrap();
    let map = |c: &sshc::Compiled| {
        c.shaders
            .iter()
            .find(|(f, _)| f.ends_with("moments.wgsl"))
            .map(|s| renumbered(&s.1))
    };
    assert!(
        map(&inline).is_some(),
        "{:?}",
        inline.shaders.iter().map(|s| &s.0).collect::<Vec<_>>()
    );
    assert_eq!(map(&called), map(&inline));
    let esm = std::fs::read_to_string(root().join("techniques/esm.ron")).unwrap();
    let esm_with = esm.replace("value: \"z\", doc: \"copy", "value: \"f(e)\", doc: \"copy").replace(
        "    expansions: {",
        "    functions: { \"f\": Function(params: { \"x\": Expansion }, body: \"neighbour(x, 0, 0)\") },\n    expansions: {",
    );
    assert_ne!(esm_with, esm);
    refused(&esm_with, &["`x` is an expansion parameter, but `neighbour` reads one channel"]);
    refused(
        &with_fn(
            r#"        "v": Function(params: { "z": F32 }, body: "neighbour(z, 0, 0)"),"#,
            "v(z)",
        ),
        &["`z` here is a value, not a channel"],
    );
    refused(
        &vsm_with("", "neighbour(m1, 1, 0)"),
        &["`neighbour` reads the map around the texel being computed", "fetch(ch, dx, dy)"],
    );
}

/// `techniques/examples/vsm-bleeding.ron`, the bundled VSM with its bound and its
/// light-bleeding reduction written as functions, compiles to the same Shade code and the
/// same operation counts as `techniques/vsm.ron`.
#[test]
fn the_vsm_example_written_with_functions_is_the_bundled_vsm() {
    let example = std::fs::read_to_string(root().join("techniques/examples/vsm-bleeding.ron")).unwrap();
    let (a, b) = (compile(&vsm()).unwrap(), compile(&example).unwrap_or_else(|e| panic!("{e}")));
    assert_eq!(a.cost.shade, b.cost.shade);
    assert_eq!(a.cost.passes, b.cost.passes);
    let shade = |c: &sshc::Compiled| c.shaders.iter().find(|(f, _)| f.ends_with("shade.wgsl")).unwrap().1.clone();
    assert_eq!(renumbered(&shade(&a)), renumbered(&shade(&b)).replace("vsm_bleeding", "vsm"));
}

/// Every example technique (techniques/examples/) and the bundled techniques that began as
/// examples of functions (techniques/evsm.ron, msm.ron) compile without warnings; each uses
/// what it is an example of.
#[test]
fn the_example_techniques_compile_and_use_what_they_show() {
    let dir = root().join("techniques/examples");
    let mut seen = 0;
    for (name, folder, uses) in [
        ("evsm", "techniques", &["functions:", "chebyshev("][..]),
        ("msm", "techniques", &["functions:", "solve_c(", "intensity("][..]),
        (
            "poisson-pcf",
            "techniques/examples",
            &["arrays:", "taps[i]", "pixel.x", "frame", "noise("][..],
        ),
        ("vsm-bleeding", "techniques/examples", &["functions:", "reduce_bleeding("][..]),
        // the independent reading `sshc verify --reference` checks msm.ron against
        ("msm-reference", "techniques/examples", &["functions:", "det3(", "shadow("][..]),
        // the region and level lookups (language.md 8.7)
        (
            "vssm-subdivided",
            "techniques/examples",
            &["functions:", "sample_box_at(", "debug:"][..],
        ),
        (
            "pcf-min-early-out",
            "techniques/examples",
            &["reduce: Min", "nearest_level_at("][..],
        ),
    ] {
        let src = std::fs::read_to_string(root().join(folder).join(format!("{name}.ron"))).unwrap();
        for u in uses {
            assert!(src.contains(u), "{name} does not use `{u}`");
        }
        let c = compile(&src).unwrap_or_else(|e| panic!("{name}: {e}"));
        // a table of Unorm16 moments is rendered into Rg16Unorm, which WebGPU renders to only
        // with an adapter feature (lavapipe has it): that warning, and no other
        let expected = |w: &sshc::Diagnostic| name == "vssm-subdivided" && w.message.contains("16-bit norm format");
        assert!(c.warnings.iter().all(expected), "{name}: {:?}", c.warnings);
        seen += usize::from(folder == "techniques/examples");
    }
    assert_eq!(seen, std::fs::read_dir(&dir).unwrap().count(), "an example is not listed here");
}

/// `sinh`, `cosh` and `tanh` (issue 51): typed as the other elementwise builtins (f32 or a
/// vector), their ranges analysed (`tanh` monotone, `cosh` even with its least value 1 at
/// 0), folded at compile time, emitted as WGSL's own, and evaluated by the CPU reference.
#[test]
fn hyperbolic_functions_are_typed_ranged_folded_and_emitted() {
    let src = r#"Technique(
    name: "hyperbolic",
    channels: {
        "z": Channel(precision: F32),
        "t": Channel(precision: F32, value: "tanh(4.0 * z)"),
        "c": Channel(precision: F32, value: "cosh(z - 0.5)"),
        "s": Channel(precision: F32, value: "sinh(2.0 * z - 1.0)"),
    },
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Map(name: "warp", reads: ["shadow"], writes: "warped", channels: ["t", "c", "s"]),
        Shade(name: "shade", reads: ["warped"], visibility: "
            let v = tanh(vec2(sample(t), sample(s)));
            clamp(v.x + v.y * sinh(0.0) + cosh(0.0) - sample(c), 0.0, 1.0)
        "),
    ],
)"#;
    let c = compile(src).unwrap_or_else(|e| panic!("{e}"));
    let range = |name: &str| {
        c.graph
            .textures
            .iter()
            .flat_map(|t| &t.channels)
            .find(|ch| ch.name == name)
            .unwrap_or_else(|| panic!("`{name}` is stored"))
            .range
    };
    let close = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() < 1e-6 && (a.1 - b.1).abs() < 1e-6;
    // z in [0, 1]: tanh(4z) in [0, tanh 4]; cosh(z - 0.5) in [1, cosh 0.5]; sinh(2z - 1) in [-sinh 1, sinh 1]
    assert!(close(range("t"), (0.0, 4f64.tanh())), "{:?}", range("t"));
    assert!(close(range("c"), (1.0, 0.5f64.cosh())), "{:?}", range("c"));
    assert!(close(range("s"), (-1f64.sinh(), 1f64.sinh())), "{:?}", range("s"));
    let wgsl: String = c.shaders.iter().map(|(_, s)| s.as_str()).collect();
    for f in ["tanh(", "cosh(", "sinh("] {
        assert!(wgsl.contains(f), "no `{f}` in the WGSL");
    }
    // `sinh(0.0)` and `cosh(0.0)` fold to constants: no call of them in the Shade's WGSL
    let shade = &c.shaders.iter().find(|(f, _)| f.contains("shade")).unwrap().1;
    assert!(!shade.contains("sinh(") && !shade.contains("cosh("), "{shade}");
    // the CPU reference evaluates them: a receiver in front of a flat map at depth 0.5 reads
    // tanh(tanh 2) + 0 + 1 - cosh(0) = tanh(tanh 2)
    use sshc::eval::{Evaluation, Frame, Given, Model, Receiver, Rounding, Scratch};
    let n = 8u32;
    let frame = Frame {
        shadow_size: n,
        near: 8.0,
        far: 12.0,
        light_size: 0.0,
        light_width: [0.0; 2],
        light_spread: 0.0,
        light_distant: true,
        texel_world: [0.0, 2.0 / n as f64],
        frame: 0,
    };
    let given = Given::depth(&c, vec![vec![0.5; (n * n) as usize]]);
    let ev = Evaluation::new(&c, &given, frame, Rounding::Exact, Model::Gpu).unwrap();
    let r = Receiver {
        uv: [0.5 + 1.0 / 64.0, 0.5 + 1.0 / 64.0],
        d_world: 10.0,
        ndotl: 1.0,
        depth_slope: 0.0,
        lod: 0.0,
        pixel: [0.0, 0.0],
        samples: Vec::new(),
    };
    let v = ev.visibility(&r, &mut Scratch::default());
    assert!((v.value - 2f64.tanh().tanh()).abs() <= v.allowance + 1e-12, "{v:?}");
    assert!(v.allowance < 1e-5, "{v:?}");
}

/// `Channel` parameters (issue 51): a helper that looks up a channel is written once and
/// called per channel; the argument names the channel (or the caller's own channel
/// parameter), and the compiled Shade is the one written inline, lookup for lookup.
#[test]
fn channel_parameters_compile_to_the_lookups_written_inline() {
    let bundled = compile(&vsm()).unwrap();
    let shade = |c: &sshc::Compiled| c.shaders.iter().find(|(f, _)| f.ends_with("shade.wgsl")).unwrap().1.clone();
    let fns = format!(
        r#"{CHEBYSHEV}
        "moment": Function(params: {{ "m": Channel }}, body: "sample(m)"),
        "through": Function(params: {{ "c": Channel }}, body: "moment(c)"),
        "bound": Function(params: {{ "a": Channel, "b": Channel, "t": F32 }}, body: "chebyshev(through(a), moment(b), t)"),"#
    );
    for visibility in [
        // each channel through a one-lookup helper
        "let d_biased = d - bias - slope_bias * depth_slope; linstep(bleed, 1.0, chebyshev(moment(m1), moment(m2), d_biased))",
        // both channels through one helper, one of them passed on by a channel parameter
        "let d_biased = d - bias - slope_bias * depth_slope; linstep(bleed, 1.0, bound(m1, m2, d_biased))",
    ] {
        let with = compile(&vsm_with(&fns, visibility)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(with.cost.shade, bundled.cost.shade, "{visibility}");
        assert_eq!(renumbered(&shade(&with)), renumbered(&shade(&bundled)), "{visibility}");
    }
    // the argument decides which channel is read, even where the parameter is named like
    // another channel: `first(m2)` reads m2, `first(m1)` m1
    let first = r#"        "first": Function(params: { "m1": Channel }, body: "sample(m1)"),"#;
    for ch in ["m1", "m2"] {
        let called = compile(&vsm_with(first, &format!("first({ch})"))).unwrap_or_else(|e| panic!("{e}"));
        let inline = compile(&vsm_with("", &format!("sample({ch})"))).unwrap();
        assert_eq!(renumbered(&shade(&called)), renumbered(&shade(&inline)), "first({ch})");
    }
    // the lookups with extra arguments: a box of taps at offsets, the same as written inline
    let taps = r#"        "cross": Function(params: { "m": Channel, "r": F32 }, body: "0.25 * (nearest_at(m, r, 0.0) + nearest_at(m, -r, 0.0) + nearest_at(m, 0.0, r) + nearest_at(m, 0.0, -r))"),"#;
    let called = compile(&vsm_with(
        taps,
        "clamp(cross(m1, 2.0 * texel_size) - cross(m2, texel_size), 0.0, 1.0)",
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    let inline = compile(&vsm_with(
        "",
        "clamp(0.25 * (nearest_at(m1, 2.0 * texel_size, 0.0) + nearest_at(m1, -(2.0 * texel_size), 0.0) + nearest_at(m1, 0.0, 2.0 * texel_size) + nearest_at(m1, 0.0, -(2.0 * texel_size))) - 0.25 * (nearest_at(m2, texel_size, 0.0) + nearest_at(m2, -texel_size, 0.0) + nearest_at(m2, 0.0, texel_size) + nearest_at(m2, 0.0, -texel_size)), 0.0, 1.0)",
    ))
    .unwrap();
    assert_eq!(called.cost.shade, inline.cost.shade);
    assert_eq!(called.cost.shade.fetches, 8, "{:?}", called.cost.shade);
    assert_eq!(renumbered(&shade(&called)), renumbered(&shade(&inline)));
}

/// `Expansion` parameters: `expand` and its forms through a helper, the same code as inline.
#[test]
fn expansion_parameters_compile_to_the_expansion_written_inline() {
    let csm = std::fs::read_to_string(root().join("techniques/csm.ron")).unwrap();
    let with = csm.replace("let s = expand(f);", "let s = series(f);").replace(
        "    passes: [",
        "    functions: { \"series\": Function(params: { \"e\": Expansion }, body: \"expand(e)\") },\n    passes: [",
    );
    assert_ne!(with, csm);
    let (a, b) = (compile(&csm).unwrap(), compile(&with).unwrap_or_else(|e| panic!("{e}")));
    let shade = |c: &sshc::Compiled| c.shaders.iter().find(|(f, _)| f.ends_with("shade.wgsl")).unwrap().1.clone();
    assert_eq!(a.cost.shade, b.cost.shade);
    assert_eq!(renumbered(&shade(&a)), renumbered(&shade(&b)));
    // a channel where the expansion is taken, and the other way round
    refused(
        &with.replace("series(f)", "series(z)"),
        &["parameter `e` of `series` takes an expansion by name, found `z`, a channel"],
    );
}

/// What a `Channel` parameter refuses, each at the call (or at the use, with the call
/// named), with file:line:column: a value for the channel, the parameter used as a value,
/// a channel the caller's Shade does not read, a lookup of the wrong kind.
#[test]
fn channel_parameters_refuse_values_and_unread_channels() {
    let lit = r#"        "lit": Function(params: { "m": Channel, "t": F32 }, body: "select(0.0, 1.0, t <= sample(m))"),"#;
    refused(
        &vsm_with(lit, "lit(d, d)"),
        &[
            "parameter `m` of `lit` takes a channel by name, found `d`, a built-in value",
            "declared here: lit(m: channel, t: f32)",
            "t.ron:",
            "help: pass the name of a channel: `z`, `m1`, `m2`",
        ],
    );
    refused(
        &vsm_with(lit, "lit(m1 + 1.0, d)"),
        &["takes a channel by name, found an expression"],
    );
    refused(&vsm_with(lit, "lit(bias, d)"), &["found `bias`, a param (a value)"]);
    refused(
        &vsm_with(lit, "lit(m3, d)"),
        &["found `m3`, which is not declared", "did you mean `m1`?"],
    );
    refused(&vsm_with(lit, "let x = d; lit(x, d)"), &["found `x`, a value"]);
    refused(
        &vsm_with(r#"        "lit": Function(params: { "m": Channel }, body: "m * 2.0"),"#, "lit(m1)"),
        &[
            "`m` is a channel parameter, not a value",
            "the channel `m1` here",
            "in this call of `lit`",
            "help: look it up, as `sample(m)`",
        ],
    );
    // `z` is carried by `shadow`, which the Shade does not read: refused at the argument
    refused(
        &vsm_with(lit, "lit(z, d)"),
        &[
            "`z` is not carried by any resource this Shade pass reads",
            "passed to `m` of `lit`, whose body looks it up",
            "add `shadow` (which carries it) to the Shade pass's `reads`",
        ],
    );
    refused(
        &vsm_with(r#"        "e": Function(params: { "m": Channel }, body: "expand(m)"),"#, "e(m1)"),
        &[
            "`m` is a channel parameter (`m1` here), but `expand` takes an expansion",
            "look it up with `sample`, the same lookup on a channel",
        ],
    );
    refused(
        &vsm_with(r#"        "f": Function(params: { "m": Chanel }, body: "sample(m)"),"#, "f(m1)"),
        &["unknown parameter type `Chanel`", "Channel, Expansion"],
    );
}
