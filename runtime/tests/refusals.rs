//! A graph whose features this runtime cannot honour is refused at load, naming the pass
//! and the feature, rather than run another way.

use sshc_runtime::gpu::{CameraOutput, Executor, Gpu, RuntimeError, SceneInputs};
use sshc_runtime::graph::*;

mod common;
use common::depth_graph;

fn identity() -> [f32; 16] {
    [1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.]
}

#[test]
fn per_light_sample_views_are_refused_and_light_centre_runs() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let (g, shaders) = depth_graph(Views::PerLightSample);
    let e = Executor::new(&gpu, g, shaders)
        .err()
        .expect("a PerLightSample graph must be refused");
    assert!(
        matches!(&e, RuntimeError::Unsupported { pass, feature } if pass == "depth" && feature.contains("PerLightSample")),
        "{e}"
    );
    assert!(e.to_string().contains("pass `depth`"), "{e}");

    // The same graph from the light's centre loads and runs.
    let (g, shaders) = depth_graph(Views::LightCenter);
    let mut ex = Executor::new(&gpu, g, shaders).unwrap_or_else(|e| panic!("{e}"));
    ex.bind_scene(&SceneInputs {
        // one triangle covering the light's view
        vertices: vec![-1., -1., 0.5, 0., 0., 1., 3., -1., 0.5, 0., 0., 1., -1., 3., 0.5, 0., 0., 1.],
        meshes: vec![],
        camera_view_proj: identity(),
        camera_position: [0.0; 3],
        camera_size: (4, 4),
        shadow_size: 4,
        light_view: identity(),
        light_view_proj: identity(),
        light_position: [0., 0., 1., 1.],
        near: 0.1,
        far: 10.0,
        light_size: 0.0,
        light_half_extents: [0.0; 2],
        light_angle: 0.0,
        light_proj_y: 1.0,
        light_orthographic: false,
    })
    .unwrap_or_else(|e| panic!("{e}"));
    let times = ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(times.passes.len(), 1);
    let z = ex.read_texture("z", 0, 0).unwrap_or_else(|e| panic!("{e}"));
    assert!(z.rgba.iter().all(|p| p[0] == 0.5), "{:?}", z.rgba);
}

#[test]
fn camera_sized_textures_are_refused() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let (mut g, shaders) = depth_graph(Views::LightCenter);
    g.textures[0].extent = Extent::Camera;
    let e = Executor::new(&gpu, g, shaders)
        .err()
        .expect("a camera-sized texture must be refused");
    assert!(
        matches!(&e, RuntimeError::Unsupported { pass, feature } if pass == "depth" && feature.contains("extent: Camera")),
        "{e}"
    );
}

#[test]
fn graphs_with_no_passes_are_refused() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let (mut g, shaders) = depth_graph(Views::LightCenter);
    g.passes.clear();
    let e = Executor::new(&gpu, g, shaders)
        .err()
        .expect("a graph with no passes must be refused");
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
    let e = Executor::new(&gpu, g, shaders).err().expect("2,100 passes must be refused");
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
    Executor::new(&gpu, g, shaders).unwrap_or_else(|e| panic!("{e}"));
}

/// `depth_graph` plus a hand-written Shade pass whose visibility is `value` (WGSL) everywhere.
fn shade_graph(value: &str) -> (PassGraph, Vec<(String, String)>) {
    let (mut g, mut shaders) = depth_graph(Views::LightCenter);
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
    let v = {value};
    var o: ShadeOut;
    o.visibility = vec4<f32>(v, 0.0, 0.0, 1.0);
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

fn run_shade(gpu: &Gpu, value: &str) -> Result<Vec<f32>, RuntimeError> {
    let (g, shaders) = shade_graph(value);
    let mut ex = Executor::new(gpu, g, shaders)?;
    ex.bind_scene(&SceneInputs {
        // one triangle covering the camera's view
        vertices: vec![-1., -1., 0.5, 0., 0., 1., 3., -1., 0.5, 0., 0., 1., -1., 3., 0.5, 0., 0., 1.],
        meshes: vec![],
        camera_view_proj: identity(),
        camera_position: [0.0; 3],
        camera_size: (4, 4),
        shadow_size: 4,
        light_view: identity(),
        light_view_proj: identity(),
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
    Ok(ex.read_camera(CameraOutput::Visibility)?.channel(0))
}

#[test]
fn a_shade_pass_writing_nan_or_out_of_range_visibility_is_an_error() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let ok = run_shade(&gpu, "0.25 + f32(zero)").unwrap_or_else(|e| panic!("{e}"));
    assert!(ok.iter().all(|v| *v == 0.25), "{ok:?}");
    for value in ["bitcast<f32>(0x7fc00000u + zero)", "1e30 + f32(zero)", "-0.5 + f32(zero)"] {
        let e = run_shade(&gpu, value)
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
