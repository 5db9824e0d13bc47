//! The Mipmap pass: a mip chain built in place, each level the Mean, Max or Min of 2x2
//! texels of the level above.

use crate::back::internal;
use crate::back::steps::{fullscreen_step, layer_chunks};
use crate::back::text::{FULLSCREEN_VS, header, out_struct};
use crate::diag::Diagnostic;
use crate::front::ast::Reduce;
use crate::ir::{IrPass, Program};
use crate::pack::{Limits, texture_format};
use sshc_graph::{self as graph, Binding, Draw, FRAME_WGSL, Step, View};
use std::fmt::Write as _;

/// A Mipmap pass: one step per group of layers of each texture, run for every level below
/// the base by the runtime, each texel reducing the four of the level above; fragment
/// entries, or compute entries storing into the level where the schedule phase chose
/// `compute`.
pub(crate) fn mipmap(
    ir: &Program,
    pass: &IrPass,
    reduce: Reduce,
    compute: bool,
    limits: &Limits,
) -> Result<(String, Vec<Step>), Diagnostic> {
    let dst = &ir.resources[pass.writes.ok_or_else(|| internal("mipmap without output"))?];
    let mut s = header(ir, pass);
    s.push_str(FRAME_WGSL);
    s.push_str("@group(0) @binding(0) var<uniform> frame: Frame;\n");
    s.push_str("// the level above the one being written\n@group(1) @binding(0) var t_src: texture_2d_array<f32>;\n\n");
    s.push_str(FULLSCREEN_VS);
    let mut steps = Vec::new();
    for tex in &dst.textures {
        if compute {
            let _ = writeln!(
                s,
                "// the level being written\n@group(2) @binding(0) var w_{}: texture_storage_2d_array<{}, write>;",
                tex.name,
                texture_format(tex).wgsl()
            );
        }
        for (ci, chunk) in layer_chunks(tex, limits).into_iter().enumerate() {
            let entry = format!("{}_{}_{ci}", if compute { "cs" } else { "fs" }, tex.name);
            let out_name = format!("Out_{}_{ci}", tex.name);
            if compute {
                let g = graph::TEXEL_WORKGROUP;
                let _ = write!(
                    s,
                    "\n@compute @workgroup_size({g}, {g})\nfn {entry}(@builtin(global_invocation_id) id: vec3<u32>) {{\n    // invocations past the level's edge store nothing\n    if any(id.xy >= textureDimensions(w_{})) {{\n        return;\n    }}\n    let texel = vec2<i32>(id.xy);\n    let src = texel * 2i;\n    let last = vec2<i32>(textureDimensions(t_src)) - 1i;\n",
                    tex.name
                );
            } else {
                s.push_str(&out_struct(&out_name, chunk.len(), false));
                let _ = write!(
                    s,
                    "\n@fragment\nfn {entry}(@builtin(position) pos: vec4<f32>) -> {out_name} {{\n    let src = vec2<i32>(pos.xy) * 2i;\n    let last = vec2<i32>(textureDimensions(t_src)) - 1i;\n    var out: {out_name};\n"
                );
            }
            for (oi, &layer) in chunk.iter().enumerate() {
                for (k, (dx, dy)) in [(0, 0), (1, 0), (0, 1), (1, 1)].iter().enumerate() {
                    let _ = writeln!(
                        s,
                        "    let a{oi}_{k} = textureLoad(t_src, min(src + vec2<i32>({dx}i, {dy}i), last), {layer}i, 0i);"
                    );
                }
                let v = match reduce {
                    Reduce::Mean => format!("(a{oi}_0 + a{oi}_1 + a{oi}_2 + a{oi}_3) * 0.25"),
                    Reduce::Max => format!("max(max(a{oi}_0, a{oi}_1), max(a{oi}_2, a{oi}_3))"),
                    Reduce::Min => format!("min(min(a{oi}_0, a{oi}_1), min(a{oi}_2, a{oi}_3))"),
                };
                if compute {
                    let _ = writeln!(s, "    textureStore(w_{}, texel, {layer}i, {v});", tex.name);
                } else {
                    let _ = writeln!(s, "    out.o{oi} = {v};");
                }
            }
            s.push_str(if compute { "}\n" } else { "    return out;\n}\n" });
            let mut step = fullscreen_step(
                entry,
                Draw::MipLevels,
                vec![Binding {
                    binding: 0,
                    texture: tex.name.clone(),
                    view: View::PreviousLevel,
                }],
                &tex.name,
                &chunk,
            );
            if compute {
                (step.vertex, step.compute, step.draw) = (None, step.fragment.take(), Draw::ComputeMipLevels);
            }
            steps.push(step);
        }
    }
    Ok((s, steps))
}
