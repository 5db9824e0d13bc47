//! The graph the runtime's integration tests load: one Depth pass drawing the scene from
//! the light into `z`, with its shader.

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
                cost: OpCount::default(),
            }],
        }],
        removed: vec![],
    };
    (graph, vec![("t.depth.wgsl".into(), shader)])
}
