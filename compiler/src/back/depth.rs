//! The Depth pass: the scene rasterised from the light, each fragment storing its linear
//! light-view depth (encoded as its channel is stored); its vertex stage also draws the
//! `BackFaces` of Geometry passes.

use crate::back::internal;
use crate::back::text::{encode_expr, header};
use crate::diag::Diagnostic;
use crate::ir::{IrPass, Program};
use sshc_graph::{Draw, FRAME_WGSL, OpCount, Step, Target};
use std::fmt::Write as _;

/// A Depth pass: one step drawing the scene from the light into its channel's layer.
pub(crate) fn depth(ir: &Program, pass: &IrPass) -> Result<(String, Vec<Step>), Diagnostic> {
    let w = pass.writes.ok_or_else(|| internal("depth pass without output"))?;
    let res = &ir.resources[w];
    let slot = res.slots.first().ok_or_else(|| internal("depth resource without channel"))?;
    let (t, layer, comp) = slot.place();
    let tex = &res.textures[t];
    let mut s = header(ir, pass);
    s.push_str(FRAME_WGSL);
    s.push_str("@group(0) @binding(0) var<uniform> frame: Frame;\n\n");
    s.push_str(SCENE_FROM_LIGHT_VS);
    s.push_str(
        "
@fragment
fn fs_depth(in: DepthVarying) -> @location(0) vec4<f32> {
    // linear depth in [0, 1] between the fitted near and far planes (Annen 6.2.1 uses linear z)
    let z = (in.view_distance - frame.depth_range.x) * frame.depth_range.z;
",
    );
    let mut comps = ["0.0".to_string(), "0.0".into(), "0.0".into(), "1.0".into()];
    comps[comp as usize] = encode_expr("z", slot.encode);
    let _ = write!(s, "    return vec4<f32>({});\n}}\n", comps.join(", "));
    let step = Step {
        vertex: Some("vs_depth".into()),
        fragment: Some("fs_depth".into()),
        compute: None,
        draw: Draw::SceneFromLight,
        reads: vec![],
        writes: vec![Target {
            texture: tex.name.clone(),
            layer,
        }],
        params: false,
        sampler: false,
        light_samples: false,
        cost: OpCount::default(),
    };
    Ok((s, vec![step]))
}

/// The scene drawn from the light, with each fragment's light-view distance: the vertex
/// stage of Depth passes and of `BackFaces`.
pub(crate) const SCENE_FROM_LIGHT_VS: &str = "struct DepthVarying {
    @builtin(position) clip: vec4<f32>,
    @location(0) view_distance: f32,
}

@vertex
fn vs_depth(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> DepthVarying {
    var out: DepthVarying;
    let world = vec4<f32>(position, 1.0);
    out.clip = frame.light_view_proj * world;
    out.view_distance = -(frame.light_view * world).z;
    return out;
}
";
