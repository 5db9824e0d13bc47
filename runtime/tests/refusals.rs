//! A graph whose features this runtime cannot honour is refused at load, naming the pass
//! and the feature, rather than run another way.

use sshc_runtime::gpu::{Executor, Gpu, RuntimeError, SceneInputs};
use sshc_runtime::graph::*;

/// One Depth pass drawing the scene from the light into `z`.
fn depth_graph(views: Views) -> (PassGraph, Vec<(String, String)>) {
    let shader = format!(
        "{FRAME_WGSL}
@group(0) @binding(0) var<uniform> frame: Frame;
struct VOut {{ @builtin(position) pos: vec4<f32>, @location(0) d: f32 }}
@vertex fn vs_depth(@location(0) p: vec3<f32>, @location(1) n: vec3<f32>) -> VOut {{
    var o: VOut;
    o.pos = frame.light_view_proj * vec4<f32>(p, 1.0);
    o.d = 0.5;
    return o;
}}
@fragment fn fs_depth(i: VOut) -> @location(0) f32 {{ return i.d; }}
"
    );
    let graph = PassGraph {
        version: SCHEMA_VERSION,
        technique: "t".into(),
        title: None,
        paper: None,
        lights: vec![LightModel::Any],
        params: vec![],
        params_size: 0,
        textures: vec![TextureDecl {
            name: "z".into(),
            format: Format::R32Float,
            layers: 1,
            extent: Extent::ShadowMap,
            mips: false,
            transient: false,
            channels: vec![],
        }],
        passes: vec![PassDecl {
            name: "depth".into(),
            kind: PassKind::Depth,
            views,
            shader: "t.depth.wgsl".into(),
            steps: vec![Step {
                vertex: Some("vs_depth".into()),
                fragment: Some("fs_depth".into()),
                compute: None,
                draw: Draw::SceneFromLight,
                reads: vec![],
                writes: vec![Target {
                    texture: "z".into(),
                    layer: 0,
                }],
                params: false,
                sampler: false,
                cost: OpCount::default(),
            }],
        }],
        removed: vec![],
    };
    (graph, vec![("t.depth.wgsl".into(), shader)])
}

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
fn geometry_passes_are_refused() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let (mut g, shaders) = depth_graph(Views::LightCenter);
    g.passes[0].kind = PassKind::Geometry;
    let e = Executor::new(&gpu, g, shaders).err().expect("a Geometry pass must be refused");
    assert!(
        matches!(&e, RuntimeError::Unsupported { pass, feature } if pass == "depth" && feature.contains("Geometry")),
        "{e}"
    );
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
