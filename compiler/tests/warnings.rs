//! Precision warnings: every `warnings/*.ron` compiles, and its rendered
//! warnings must match `warnings/*.stderr` (empty: none). The storage-rounding estimate
//! (`sshc::rounding`) warns for VSM and MSM moments at Unorm8 (VSM's in a summed-area table
//! too), the render-target check
//! for Unorm16 channels; EVSM at F32 and at F16 within its exponent limits gives none;
//! tables over float channels warn of their stated bound (`sshc::tables`).
//! Set `UPDATE_EXPECT=1` to rewrite the expected files after reviewing a change.

mod expect;

use std::path::Path;

#[test]
fn every_precision_fixture_has_its_warnings() {
    let fixtures = expect::fixtures("tests/warnings");
    assert_eq!(fixtures.len(), 8, "{fixtures:?}");
    expect::check(&fixtures, "warnings", |f, name| {
        let source = std::fs::read_to_string(f).unwrap();
        let opts = sshc::CompileOptions {
            rounding: true,
            ..Default::default()
        };
        let c = sshc::compile_str(&source, &opts).unwrap_or_else(|d| panic!("{name}: refused\n{}", d.render(name, &source)));
        let got = sshc::diag::Diagnostics(c.warnings.clone()).render(name, &source);
        // the cases the issue names
        let rounding = got.contains("storage rounding can move the visibility");
        match name {
            "vsm_unorm8_moments.ron" | "msm_unorm8_moments.ron" | "vsm_unorm8_table_moments.ron" => assert!(rounding, "{name}: {got}"),
            "vsm_unorm16_render_target.ron" => assert!(got.contains("Rg16Unorm") && !rounding, "{name}: {got}"),
            "evsm_f32.ron" | "evsm_f16_within_limits.ron" => assert!(got.is_empty(), "{name}: {got}"),
            // a table over float channels: its stated bound (f32 sums) or its exact area
            // (fixed-point codes), not the channels' own precision
            "vsm_f32_table_small_boxes.ron" => assert!(got.contains("in f32: at 2048 x 2048") && !rounding, "{name}: {got}"),
            "vsm_fixed_table_overflow.ron" => assert!(got.contains("wraps around 2^32") && !rounding, "{name}: {got}"),
            other => panic!("{other}: a fixture without its expectation here"),
        }
        got
    });
}

/// The estimate itself: at F32 every bundled moment technique's rounding error is far
/// below the threshold, and a narrower precision never estimates less than a wider one
/// of the same kind for the same channel (Unorm8 >= Unorm16, F16 >= F32), unless both
/// have reached the visibility's whole range (an error of about 1: MSM's moments at 16
/// bits and at 8).
#[test]
fn the_rounding_estimate_orders_the_precisions() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    for file in [
        "techniques/vsm.ron",
        "techniques/evsm.ron",
        "techniques/msm.ron",
        "techniques/csm.ron",
    ] {
        let source = std::fs::read_to_string(root.join(file)).unwrap();
        let c = sshc::compile_str(&source, &sshc::CompileOptions::default()).unwrap();
        let program = sshc::ir::Program::new(&c.ir, &c.layout);
        let e = sshc::rounding::estimate(&program, sshc::rounding::Detail::Explain).expect("estimated");
        assert!(e.configurations > 500, "{file}: {} configurations", e.configurations);
        for ch in &e.channels {
            let [u8, u16, f16, f32] = ch.at;
            if let (Some(a), Some(b)) = (u8, u16) {
                assert!(a >= b || a > 0.99, "{file} `{}`: Unorm8 {a} < Unorm16 {b}", ch.name);
            }
            if let (Some(a), Some(b)) = (f16, f32) {
                assert!(a >= b || a > 0.99, "{file} `{}`: F16 {a} < F32 {b}", ch.name);
            }
            assert!(f32.is_some_and(|v| v < 0.01), "{file} `{}` at F32: {f32:?}", ch.name);
        }
    }
}
