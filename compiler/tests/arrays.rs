//! Constant arrays: elements known at compile time, indexed by integers known
//! at compile time (literals and series variables); what they compile to, and what is
//! refused, at file:line:column.

use sshc::CompileOptions;

/// A 16-tap Poisson disk (Fernando 2005, "Percentage-closer soft shadows", its sample table).
const POISSON: [(f64, f64); 16] = [
    (-0.94201624, -0.39906216),
    (0.94558609, -0.76890725),
    (-0.094184101, -0.92938870),
    (0.34495938, 0.29387760),
    (-0.91588581, 0.45771432),
    (-0.81544232, -0.87912464),
    (-0.38277543, 0.27676845),
    (0.97484398, 0.75648379),
    (0.44323325, -0.97511554),
    (0.53742981, -0.47373420),
    (-0.26496911, -0.41893023),
    (0.79197514, 0.19090188),
    (-0.24188840, 0.99706507),
    (-0.81409955, 0.91437590),
    (0.19984126, 0.78641367),
    (0.14383161, -0.14100790),
];

fn technique(arrays: &str, visibility: &str) -> String {
    format!(
        r#"Technique(
    name: "poisson",
    params: {{
        "radius": Param(ty: F32, default: 0.002),
        "bias": Param(ty: F32, default: 0.002),
        "N": Param(ty: I32, default: 16, fixed: true),
    }},
    arrays: {{
{arrays}
    }},
    channels: {{ "z": Channel(precision: F32) }},
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Shade(name: "shade", reads: ["shadow"], visibility: "{visibility}"),
    ],
)
"#
    )
}

fn taps() -> String {
    let values: Vec<String> = POISSON.iter().map(|(x, y)| format!("\"vec2({x:?}, {y:?})\"")).collect();
    format!("        \"taps\": Array(ty: Vec2, values: [{}]),", values.join(", "))
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

/// Poisson-disk PCF over the table: the same operations and fetches as the 16 taps
/// written out one by one.
#[test]
fn a_table_of_taps_compiles_to_the_taps_written_out() {
    let tap = |x: String, y: String| format!("select(0.0, 1.0, d - bias <= nearest_at(z, {x} * radius, {y} * radius))");
    let with = compile(&technique(
        &taps(),
        &format!("sum(i in 0..=N - 1, {}) / 16.0", tap("taps[i].x".into(), "taps[i].y".into())),
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    let terms: Vec<String> = POISSON.iter().map(|(x, y)| tap(format!("{x:?}"), format!("{y:?}"))).collect();
    let written = compile(&technique(&taps(), &format!("({}) / 16.0", terms.join(" + ")))).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(with.cost.shade, written.cost.shade);
    assert_eq!(with.cost.shade.fetches, 16);
}

/// Arrays of scalars index in compile-time contexts too (a series bound), and an element
/// may use fixed params.
#[test]
fn scalar_arrays_serve_compile_time_values() {
    let src = technique(
        r#"        "counts": Array(ty: I32, values: [1, 3, "N - 12"]),
        "weights": Array(ty: F32, values: [0.25, "0.5", 1]),"#,
        "sum(j in 0..=counts[2] - 1, weights[1] * d) / f32(counts[1]) + 0.0 * nearest(z)",
    );
    let c = compile(&src).unwrap_or_else(|e| panic!("{e}"));
    assert!(c.explain().contains("visibility"), "explained");
}

#[test]
fn bad_arrays_and_indices_are_refused_where_they_are_written() {
    refused(
        &technique(&taps(), "taps[16].x + nearest(z)"),
        &[
            "error[check]: index 16 is outside `taps`, which has 16 elements",
            "t.ron:14:",
            "indices run from 0 to 15",
        ],
    );
    refused(
        &technique(&taps(), "sum(i in 0..=16, taps[i].x) + nearest(z)"),
        &["index 16 is outside `taps`, which has 16 elements"],
    );
    refused(
        &technique(&taps(), "taps[i32(d)].x + nearest(z)"),
        &["is not known at compile time"],
    );
    refused(&technique(&taps(), "bias[0] + nearest(z)"), &["`bias` is not a constant array"]);
    refused(
        &technique(r#"        "w": Array(ty: F32, values: ["vec2(1.0, 2.0)"]),"#, "w[0] + nearest(z)"),
        &["type mismatch: `w` holds f32, found vec2<f32>"],
    );
    refused(
        &technique(r#"        "w": Array(ty: F32, values: ["d"]),"#, "w[0] + nearest(z)"),
        &["`d` is not known at compile time"],
    );
    refused(
        &technique(r#"        "w": Array(ty: F32, values: []),"#, "nearest(z)"),
        &["an array needs at least one value"],
    );
}
