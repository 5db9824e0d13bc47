//! Two probes of hostile and extreme inputs at the runtime's own interface (lab/tests/probes.rs runs them
//! through `sshc`): a graph file with a syntax error is named with its line and column, and
//! the shaded colour is refused with the visibility it is computed from (a plain render
//! read only the colour, so a NaN visibility passed on into the PNG and exited 0).

use sshc_runtime::gpu::{CameraOutput, Gpu, RuntimeError, Technique};
use sshc_runtime::graph::*;

mod common;

#[test]
fn a_graph_syntax_error_names_the_file_line_and_column() {
    let dir = std::env::temp_dir().join(format!("sshc-runtime-probes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (g, shaders) = common::depth_graph(Views::LightCenter);
    let text = g.to_ron().replacen("  params_size: 0,\n", "  params_size: 0,\n  colour: 3,\n", 1);
    let line = text.lines().position(|l| l == "  colour: 3,").expect("the field was added") + 1;
    let graph = dir.join("t.graph.ron");
    std::fs::write(&graph, text).unwrap();
    for (name, src) in &shaders {
        std::fs::write(dir.join(name), src).unwrap();
    }
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let e = Technique::load(&gpu, &graph).expect_err("an unknown field is refused");
    let want = format!(
        "{}:{line}:3: not a valid pass graph: Unexpected field named `colour`",
        graph.display()
    );
    assert!(e.to_string().starts_with(&want), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

fn colour(gpu: &Gpu, value: &str) -> Result<Vec<f32>, RuntimeError> {
    common::run_shade(gpu, value, CameraOutput::Color)
}

#[test]
fn the_colour_is_refused_with_the_visibility_it_is_computed_from() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let ok = colour(&gpu, "0.25 + f32(zero)").unwrap_or_else(|e| panic!("{e}"));
    assert!(ok.iter().all(|v| *v == 1.0), "{ok:?}");
    for value in ["bitcast<f32>(0x7fc00000u + zero)", "1e30 + f32(zero)"] {
        let e = colour(&gpu, value)
            .err()
            .unwrap_or_else(|| panic!("a colour beside visibility `{value}` must be refused"));
        assert!(
            matches!(&e, RuntimeError::Output { pass, .. } if pass == "tampered_shade"),
            "{value}: {e}"
        );
        assert!(e.to_string().contains("pass `tampered_shade` wrote visibility"), "{e}");
    }
}
