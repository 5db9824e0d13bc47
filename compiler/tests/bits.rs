//! `u32` and the bit operators: literals, conversions, wrapping arithmetic and
//! shifts, folded at compile time with the GPU's semantics and emitted as WGSL otherwise;
//! the mistakes are fixtures in `errors/` (shift counts, negative u32s, negation, bits of
//! a float, literals out of range). The GPU's own results are checked in
//! tests/tests/gpu.rs (`a_hash_written_with_u32_operations_matches_the_builtin_noise`).

use sshc::CompileOptions;

fn technique(visibility: &str) -> String {
    format!(
        r#"Technique(
    name: "bits",
    channels: {{ "z": Channel(precision: F32) }},
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Shade(name: "shade", reads: ["shadow"], visibility: "{visibility}"),
    ],
)"#
    )
}

fn compile(visibility: &str) -> sshc::Compiled {
    let src = technique(visibility);
    sshc::compile_str(&src, &CompileOptions::default()).unwrap_or_else(|d| panic!("{}", d.render("bits.ron", &src)))
}

fn shade(c: &sshc::Compiled) -> String {
    c.shaders.iter().find(|(f, _)| f.ends_with("shade.wgsl")).unwrap().1.clone()
}

/// `wgsl` with the digits of every value name `e<digits>` dropped: the names number the
/// IR's nodes, which differ with what was folded away.
fn unnumbered(wgsl: &str) -> String {
    let mut out = String::with_capacity(wgsl.len());
    let mut prev = ' ';
    let mut in_name = false;
    for c in wgsl.chars() {
        if in_name && c.is_ascii_digit() {
            continue;
        }
        in_name = c == 'e' && !(prev.is_ascii_alphanumeric() || prev == '_');
        out.push(c);
        prev = c;
    }
    out
}

/// Each fact below holds in Rust's wrapping u32 and two's-complement i32 arithmetic (the
/// GPU's); the compiler must fold every one to `true`, leaving the same shader as the
/// visibility `1.0 * nearest(z)`: a fact folded wrongly would leave a `select` of
/// `false`, a fact not folded would leave its operations.
#[test]
fn u32_constants_wrap_and_fold_as_on_the_gpu() {
    let facts: [(&str, bool); 16] = [
        ("(0xffffffffu + 2u) * 3u == 3u", (u32::MAX.wrapping_add(2)).wrapping_mul(3) == 3),
        ("0u - 1u == 4294967295u", 0u32.wrapping_sub(1) == u32::MAX),
        (
            "2654435769u * 2654435769u == 3814614961u",
            2_654_435_769u32.wrapping_mul(2_654_435_769) == 3_814_614_961,
        ),
        ("(1u << 31u) >> 31u == 1u", (1u32 << 31) >> 31 == 1),
        ("~0u == 0xffffffffu", !0u32 == u32::MAX),
        ("-8 >> 1u == -4", -8i32 >> 1 == -4),
        ("(0x0f0f & 0xff) == 15", 0x0f0f & 0xff == 15),
        ("(0x0f0f | 0xf0) == 0x0fff", 0x0f0f | 0xf0 == 0x0fff),
        ("(0x0f0f ^ 0xff) == 0x0ff0", 0x0f0f ^ 0xff == 0x0ff0),
        ("~5 == -6", !5i32 == -6),
        ("u32(-1) == 0xffffffffu", -1i32 as u32 == u32::MAX),
        ("i32(0xffffffffu) == -1", u32::MAX as i32 == -1),
        ("u32(3.75) == 3u && u32(-2.5) == 0u && u32(1e20) == 0xffffffffu", true),
        ("f32(0x80000000u) == 2147483648.0", 0x8000_0000u32 as f32 == 2_147_483_648.0),
        (
            "min(7u, 0xffffffffu) == 7u && clamp(9u, 1u, 5u) == 5u && 7u / 2u == 3u && 7u % 4u == 3u",
            true,
        ),
        (
            "sum(k in 0..=3, u32(k) << 1u) == 12u",
            (0..=3u32).map(|k| k << 1).sum::<u32>() == 12,
        ),
    ];
    let reference = unnumbered(&shade(&compile("1.0 * nearest(z)")));
    for (fact, holds) in facts {
        assert!(holds, "the reference value of `{fact}` is wrong");
        let c = compile(&format!("select(0.0, 1.0, {fact}) * nearest(z)"));
        assert_eq!(unnumbered(&shade(&c)), reference, "`{fact}` did not fold to true");
    }
}

/// A hash of the pixel and frame (the language's version of PCG3D's mixing) on runtime
/// values: compiled, validated by naga, and written with WGSL's u32 operators.
#[test]
fn runtime_u32_operations_are_written_as_wgsl() {
    let c = compile(
        "let h = u32(pixel.x) * 1664525u + u32(pixel.y) * 1013904223u + u32(frame); \
         let g = (h ^ (h >> 16u)) * 2246822519u; let s = i32(g) >> 3u; \
         f32((g & 0xffffu) | ~(g << 5u)) / 4294967296.0 + f32(s & 1) * nearest(z)",
    );
    let wgsl = shade(&c);
    for op in [" ^ ", " >> ", " & ", " | ", " << ", "~", "1664525u", "u32(", "i32("] {
        assert!(wgsl.contains(op), "`{op}` missing from\n{wgsl}");
    }
    // the operations are counted like any other
    assert!(c.cost.shade.ops >= 12, "{:?}", c.cost.shade);
}

/// The IR dump prints u32 constants with their suffix, so they read back as u32s.
#[test]
fn u32_constants_print_with_their_suffix() {
    let src = technique("f32(u32(frame) ^ 0x9e3779b9u) * nearest(z)");
    let opts = CompileOptions {
        dump_after: Some(sshc::DumpPhase::Lower),
        ..Default::default()
    };
    let out = sshc::compile_with_dump(&src, &opts);
    if let Err(d) = &out.result {
        panic!("{}", d.render("bits.ron", &src));
    }
    let dump = out.dump.expect("a dump after lower");
    assert!(dump.contains("2654435769u"), "{dump}");
}

/// Abstract integers given to a builtin computing in u32 become u32s (fuzzing found
/// `clamp(h, 1u, 90)` with `90` lowered as an f32: an internal error): every argument
/// of `min`, `max`, `clamp` and `select` over u32 may be a plain literal, on runtime
/// values and on constants (where the call folds).
#[test]
fn abstract_integers_settle_to_u32_in_builtins() {
    for vis in [
        "let h = u32(frame); f32(clamp(h, 1u, 90)) * nearest(z)",
        "let h = u32(frame); f32(min(h, 7) + max(3, h) + select(2, h, h > 5u)) * nearest(z)",
        "f32(clamp(100u, 1, 90) == 90u) * nearest(z)",
    ] {
        let c = compile(vis);
        assert!(!shade(&c).is_empty(), "{vis}");
    }
}
