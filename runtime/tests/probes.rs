//! Two of issue 11's probes at the runtime's own interface (lab/tests/probes.rs runs them
//! through `sshc`): a graph file with a syntax error is named with its line and column, and
//! the shaded colour is refused with the visibility it is computed from (a plain render
//! read only the colour, so a NaN visibility passed on into the PNG and exited 0).

use sshc_runtime::gpu::{CameraOutput, Executor, Gpu, RuntimeError, SceneInputs};
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
    let e = Executor::load(&gpu, &graph).err().expect("an unknown field is refused");
    let want = format!(
        "{}:{line}:3: not a valid pass graph: Unexpected field named `colour`",
        graph.display()
    );
    assert!(e.to_string().starts_with(&want), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The depth graph plus a Shade pass writing `value` as the visibility and white as the colour.
fn shade_graph(value: &str) -> (PassGraph, Vec<(String, String)>) {
    let (mut g, mut shaders) = common::depth_graph(Views::LightCenter);
    let shader = format!(
        "{FRAME_WGSL}
@group(0) @binding(0) var<uniform> frame: Frame;
struct VOut {{ @builtin(position) pos: vec4<f32> }}
struct ShadeOut {{
    @location(0) visibility: vec4<f32>,
    @location(1) color: vec4<f32>,
    @location(2) position: vec4<f32>,
    @location(3) normal: vec4<f32>,
}}
@vertex fn vs_shade(@location(0) p: vec3<f32>, @location(1) n: vec3<f32>) -> VOut {{
    var o: VOut;
    o.pos = frame.camera_view_proj * vec4<f32>(p, 1.0);
    return o;
}}
@fragment fn fs_shade(i: VOut) -> ShadeOut {{
    // a runtime zero, so that naga's constant evaluation does not see the value
    let zero = u32(frame.target_size.x) * 0u;
    var o: ShadeOut;
    o.visibility = vec4<f32>({value}, 0.0, 0.0, 1.0);
    o.color = vec4<f32>(1.0);
    o.position = vec4<f32>(0.0);
    o.normal = vec4<f32>(0.0, 0.0, 1.0, 0.0);
    return o;
}}
"
    );
    g.passes.push(PassDecl {
        name: "tampered_shade".into(),
        kind: PassKind::Shade,
        views: Views::LightCenter,
        shader: "t.shade.wgsl".into(),
        steps: vec![Step {
            vertex: Some("vs_shade".into()),
            fragment: Some("fs_shade".into()),
            compute: None,
            draw: Draw::SceneFromCamera,
            reads: vec![],
            writes: vec![],
            params: false,
            sampler: false,
            cost: OpCount::default(),
        }],
    });
    shaders.push(("t.shade.wgsl".into(), shader));
    (g, shaders)
}

fn colour(gpu: &Gpu, value: &str) -> Result<Vec<f32>, RuntimeError> {
    let identity = [1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.];
    let (g, shaders) = shade_graph(value);
    let mut ex = Executor::new(gpu, g, shaders)?;
    ex.bind_scene(&SceneInputs {
        // one triangle covering the camera's view
        vertices: vec![-1., -1., 0.5, 0., 0., 1., 3., -1., 0.5, 0., 0., 1., -1., 3., 0.5, 0., 0., 1.],
        meshes: vec![],
        camera_view_proj: identity,
        camera_position: [0.0; 3],
        camera_size: (4, 4),
        shadow_size: 4,
        light_view: identity,
        light_view_proj: identity,
        light_position: [0., 0., 1., 1.],
        near: 0.1,
        far: 10.0,
        light_size: 0.0,
        light_half_extents: [0.0; 2],
        light_angle: 0.0,
        light_proj_y: 1.0,
        light_orthographic: false,
    })?;
    ex.run_frame()?;
    Ok(ex.read_camera(CameraOutput::Color)?.channel(0))
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
