//! A graph whose features this runtime cannot honour is refused at load, naming the pass
//! and the feature, rather than run another way; and light-sample views, which it honours.

use sshc_runtime::gpu::{CameraOutput, Gpu, RuntimeError, SampleView};
use sshc_runtime::graph::*;

mod common;
use common::{depth_graph, identity, one_triangle};

/// A pass with one view per light sample runs once per sample, each view into its own layer
/// block with its own `Frame` (`sample.x = k`); a scene that gives another number of samples
/// is refused at binding, naming both counts.
#[test]
fn per_light_sample_views_render_one_layer_block_each() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let (mut g, shaders) = depth_graph(Views::PerLightSample);
    g.samples = 3;
    g.textures[0].views = 3;
    let t = common::load(&gpu, g, shaders).unwrap_or_else(|e| panic!("{e}"));
    let e = common::bind(&t, &one_triangle()).err().expect("no samples bound");
    assert!(
        matches!(&e, RuntimeError::Param(m) if m.contains("3 light-sample view(s)") && m.contains("gives 0")),
        "{e}"
    );
    let mut inputs = one_triangle();
    inputs.samples = (0..3)
        .map(|k| SampleView {
            light_view: identity(),
            light_view_proj: identity(),
            position: [k as f32, 0.0, 1.0],
            near: 0.1,
            far: 10.0,
            light_proj_y: 1.0,
            weights: [0.5, 0.5],
        })
        .collect();
    let mut ex = common::bind(&t, &inputs).unwrap_or_else(|e| panic!("{e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    for k in 0..3 {
        let z = ex.targets.inspect().read_texture("z", k, 0).unwrap_or_else(|e| panic!("{e}"));
        let want = 0.5 + k as f32;
        assert!(z.rgba.iter().all(|p| p[0] == want), "layer {k}: {:?}", z.rgba);
    }
    assert!(ex.targets.inspect().read_texture("z", 3, 0).is_err(), "three layers, not four");

    // The same graph from the light's centre writes one layer with sample.x = 0.
    let (g, shaders) = depth_graph(Views::LightCenter);
    let t = common::load(&gpu, g, shaders).unwrap_or_else(|e| panic!("{e}"));
    let mut ex = common::bind(&t, &one_triangle()).unwrap_or_else(|e| panic!("{e}"));
    let times = ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(times.passes.len(), 1);
    let z = ex.targets.inspect().read_texture("z", 0, 0).unwrap_or_else(|e| panic!("{e}"));
    assert!(z.rgba.iter().all(|p| p[0] == 0.5), "{:?}", z.rgba);
}

/// Camera-sized textures are a Shade's debug outputs: one written from the light (a Depth
/// pass's target) is refused at load, naming the pass.
#[test]
fn camera_sized_textures_outside_the_shade_are_refused() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let (mut g, shaders) = depth_graph(Views::LightCenter);
    g.textures[0].extent = Extent::Camera;
    let e = common::load(&gpu, g, shaders).expect_err("a camera-sized texture must be refused");
    assert!(
        matches!(&e, RuntimeError::Graph(GraphError::Step { pass, message }) if pass == "depth" && message.contains("camera-sized")),
        "{e}"
    );
}

#[test]
fn graphs_with_no_passes_are_refused() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let (mut g, shaders) = depth_graph(Views::LightCenter);
    g.passes.clear();
    let e = common::load(&gpu, g, shaders).expect_err("a graph with no passes must be refused");
    assert!(e.to_string().contains("no passes"), "{e}");
}

#[test]
fn graphs_with_more_passes_than_timestamps_are_refused() {
    use sshc_runtime::gpu::MAX_PASSES;
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let (mut g, shaders) = depth_graph(Views::LightCenter);
    let pass = g.passes[0].clone();
    // 2,100 passes, as a 2,100-pass technique compiles to: refused before any module is built
    // (bound: well under a second, no GPU objects).
    g.passes = (0..2100)
        .map(|i| PassDecl {
            name: format!("depth{i}"),
            ..pass.clone()
        })
        .collect();
    let start = std::time::Instant::now();
    let e = common::load(&gpu, g, shaders).expect_err("2,100 passes must be refused");
    assert!(
        matches!(&e, RuntimeError::Limit { needed: 2100, limit, .. } if *limit == MAX_PASSES as u64),
        "{e}"
    );
    assert!(e.to_string().contains("passes"), "{e}");
    assert!(!e.to_string().contains("QuerySet"), "{e}");
    assert!(start.elapsed().as_secs() < 10);
    // At the limit the graph loads.
    let (mut g, shaders) = depth_graph(Views::LightCenter);
    g.passes = (0..MAX_PASSES)
        .map(|i| PassDecl {
            name: format!("depth{i}"),
            ..pass.clone()
        })
        .collect();
    common::load(&gpu, g, shaders).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn a_shade_pass_writing_nan_or_out_of_range_visibility_is_an_error() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let ok = common::run_shade(&gpu, "0.25 + f32(zero)", CameraOutput::Visibility).unwrap_or_else(|e| panic!("{e}"));
    assert!(ok.iter().all(|v| *v == 0.25), "{ok:?}");
    for value in ["bitcast<f32>(0x7fc00000u + zero)", "1e30 + f32(zero)", "-0.5 + f32(zero)"] {
        let e = common::run_shade(&gpu, value, CameraOutput::Visibility)
            .err()
            .unwrap_or_else(|| panic!("visibility `{value}` must be refused"));
        assert!(
            matches!(&e, RuntimeError::Output { pass, .. } if pass == "tampered_shade"),
            "{value}: {e}"
        );
        assert!(e.to_string().contains("pass `tampered_shade` wrote visibility"), "{e}");
    }
    // the helper on its own
    use sshc_runtime::gpu::{VISIBILITY_EPSILON, check_visibility};
    assert!(check_visibility(&[0.0, 1.0 + VISIBILITY_EPSILON / 2.0], 2, "s").is_ok());
    let e = check_visibility(&[0.5, f32::INFINITY, f32::NAN], 2, "s").unwrap_err();
    assert!(
        e.to_string().contains("pixel (1, 0)") && e.to_string().contains("2 pixel(s)"),
        "{e}"
    );
}
