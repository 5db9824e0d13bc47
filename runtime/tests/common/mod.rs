//! What the runtime's integration tests share: a one-pass depth graph, a Shade pass whose
//! visibility a test writes directly, and a scene of one triangle covering both views.
#![allow(dead_code)]

use sshc_runtime::gpu::{
    CameraOutput, FrameState, FrameTimes, Gpu, RuntimeError, Scene, SceneInputs, Sizes, TargetLimits, Targets, Technique,
};
use sshc_runtime::graph::*;

/// One Depth pass drawing the scene from the light into `z`.
pub fn depth_graph(views: Views) -> (PassGraph, Vec<(String, String)>) {
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
// 0.5 from the light's centre, 0.5 + k from light sample k
@fragment fn fs_depth(i: VOut) -> @location(0) f32 {{ return i.d + frame.sample.x; }}
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
        samples: 1,
        textures: vec![TextureDecl {
            name: "z".into(),
            format: Format::R32Float,
            layers: 1,
            extent: Extent::ShadowMap,
            mips: false,
            transient: false,
            channels: vec![],
            views: 1,
        }],
        buffers: vec![],
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
                light_samples: false,
                cost: OpCount::default(),
            }],
        }],
        removed: vec![],
        specialised: None,
        shadow_map: None,
    };
    (graph, vec![("t.depth.wgsl".into(), shader)])
}

pub fn identity() -> [f32; 16] {
    [1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.]
}

/// One triangle covering the light's and the camera's view (both identity).
pub fn one_triangle() -> SceneInputs {
    SceneInputs {
        vertices: vec![-1., -1., 0.5, 0., 0., 1., 3., -1., 0.5, 0., 0., 1., -1., 3., 0.5, 0., 0., 1.],
        meshes: vec![],
        casting_vertices: None,
        unshadowed: vec![],
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
        samples: Vec::new(),
        samples_closed: false,
        light: None,
    }
}

/// `depth_graph` plus a hand-written Shade pass whose visibility is `value` (WGSL) everywhere.
pub fn shade_graph(value: &str) -> (PassGraph, Vec<(String, String)>) {
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
            light_samples: false,
            cost: OpCount::default(),
        }],
    });
    shaders.push(("t.shade.wgsl".into(), shader));
    (g, shaders)
}

/// Run the depth graph and a Shade pass writing visibility `value` on [`one_triangle`];
/// read back camera output `which`.
pub fn run_shade(gpu: &Gpu, value: &str, which: CameraOutput) -> Result<Vec<f32>, RuntimeError> {
    let (g, shaders) = shade_graph(value);
    let mut run = bind(&load(gpu, g, shaders)?, &one_triangle())?;
    run.run_frame()?;
    Ok(run.targets.inspect().read_camera(which)?.channel(0))
}

/// A graph and its shaders loaded (checked as a graph file is).
pub fn load(gpu: &Gpu, g: PassGraph, shaders: Vec<(String, String)>) -> Result<Technique, RuntimeError> {
    Technique::new(gpu, ValidGraph::try_from(g)?, shaders)
}

/// A technique on one scene: its stages, as a host holds them.
pub struct Run {
    pub scene: Scene,
    pub targets: Targets,
    pub state: FrameState,
}

impl Run {
    pub fn run_frame(&mut self) -> Result<FrameTimes, RuntimeError> {
        self.targets.run_frame(&mut self.scene, &self.state)
    }
}

/// `technique` on the soup, camera and light of `s`.
pub fn bind(technique: &Technique, s: &SceneInputs) -> Result<Run, RuntimeError> {
    bind_within(technique, s, TargetLimits::default())
}

/// [`bind`] within `limits`.
pub fn bind_within(technique: &Technique, s: &SceneInputs, limits: TargetLimits) -> Result<Run, RuntimeError> {
    let scene = Scene::from_soup(
        technique.gpu(),
        &s.vertices,
        &s.meshes,
        s.casting_vertices,
        &s.unshadowed,
        &[technique],
        limits.max_bytes,
    )?;
    let state = FrameState::of_inputs(technique, s);
    let targets = Targets::with_limits(technique, &scene, &state, Sizes::of(s), limits)?;
    Ok(Run { scene, targets, state })
}
