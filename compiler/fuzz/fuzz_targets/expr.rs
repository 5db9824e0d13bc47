//! Visibility expressions: the input becomes the `visibility` string of the Shade pass of a
//! fixed, valid technique (params of each type, plain, derived and expansion channels, a
//! raw depth resource and a filtered, mipmapped one), so that nearly every input reaches
//! the expression parser and the valid ones go on through resolve, check, lower, analyse,
//! pack and WGSL codegen.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

const HEAD: &str = r####"Technique(
    name: "fuzz",
    title: "expression fuzzing envelope",
    paper: "none",
    light: Any,
    params: {
        "N": Param(ty: I32, default: 3, range: (1, 15), fixed: true, doc: "fixed int"),
        "K": Param(ty: I32, default: 2, range: (0, 8), doc: "uniform int"),
        "c": Param(ty: F32, default: 80.0, range: (1.0, 88.0), fixed: true, doc: "fixed float"),
        "bias": Param(ty: F32, default: 0.002, range: (0.0, 0.1), doc: "uniform float"),
        "slope_bias": Param(ty: F32, default: 0.001, range: (0.0, 0.1), doc: "uniform float"),
        "flag": Param(ty: Bool, default: true, doc: "bool"),
    },
    channels: {
        "z": Channel(precision: F32, doc: "depth"),
        "m1": Channel(precision: F32, value: "z", doc: "first moment"),
        "m2": Channel(precision: F32, value: "z * z", doc: "second moment"),
    },
    expansions: {
        "e": Expansion(
            index: "k", from: 1, to: 1,
            constant: 0.0,
            terms: [ Term(coeff: "exp(-c * d)", basis: "exp(c * z)") ],
            precision: F32,
        ),
    },
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Map(name: "moments", reads: ["shadow"], writes: "moments", channels: ["m1", "m2"]),
        Mipmap(name: "mips", reads: "moments", writes: "filtered", reduce: Mean),
        Map(name: "exponential", reads: ["shadow"], writes: "esm", channels: ["e"]),
        Shade(name: "shade", reads: ["shadow", "filtered", "esm"], visibility: r###""####;

const TAIL: &str = r####""###),
    ],
)
"####;

fuzz_target!(|data: &[u8]| {
    let Ok(expr) = std::str::from_utf8(data) else { return };
    // The raw string cannot hold its own terminator.
    if expr.contains("\"###") {
        return;
    }
    let mut source = String::with_capacity(HEAD.len() + expr.len() + TAIL.len());
    source.push_str(HEAD);
    source.push_str(expr);
    source.push_str(TAIL);
    common::drive(&source);
});
