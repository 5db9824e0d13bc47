//! The Filter pass: separable kernels (Box, Gaussian, Max, Min) in two axes through a
//! scratch texture of a wider precision, the 3x3 LoG in one; in the fragment or the
//! compute schedule (a workgroup tile with the kernel's apron: the schedule's
//! [`filter_tile`]). The last axis re-encodes each component from its source's storage to
//! its destination's.

use crate::back::internal;
use crate::back::steps::{fullscreen_step, layer_chunks};
use crate::back::text::{FULLSCREEN_VS, f32_lit, header, out_struct};
use crate::diag::Diagnostic;
use crate::ir::{IrKernel, IrPass, Program, Texture};
use crate::pack::{Limits, scratch_precision, texture_format};
use crate::schedule::filter_tile;
use sshc_graph::{self as graph, Binding, Draw, FRAME_WGSL, Step, View};
use std::fmt::Write as _;

/// Intermediate textures a module needs besides the IR's (the separable filters' scratch).
#[derive(Clone, Debug)]
pub struct Scratch {
    pub name: String,
    pub like: String,
    pub format: graph::Format,
}

/// A Filter pass: per texture of its output, one step per axis of a separable kernel (the
/// first into a scratch texture) or one for the 3x3 stencil, each a sum of weighted taps
/// or their max or min; fragment entries, or compute entries loading a tile and its apron
/// into workgroup memory where the schedule phase chose `compute`. A separable kernel over
/// several textures in the fragment schedule packs the layers of every texture into as
/// few steps per axis as the colour attachments allow ([`pack_axis`]): each texture's
/// source at its own binding, every layer's taps as they would be in a step of its own.
pub(crate) fn filter(
    ir: &Program,
    pass: &IrPass,
    kernel: &IrKernel,
    compute: bool,
    limits: &Limits,
    scratch: &mut Vec<Scratch>,
) -> Result<(String, Vec<Step>), Diagnostic> {
    let src = &ir.resources[pass.reads[0]];
    let dst = &ir.resources[pass.writes.ok_or_else(|| internal("filter without output"))?];
    let packed = !compute && kernel.separable() && dst.textures.len() > 1;
    let mut s = header(ir, pass);
    s.push_str(FRAME_WGSL);
    s.push_str("@group(0) @binding(0) var<uniform> frame: Frame;\n");
    if packed {
        for ti in 0..dst.textures.len() {
            let _ = writeln!(s, "@group(1) @binding({ti}) var t_src_{ti}: texture_2d_array<f32>;");
        }
        s.push('\n');
    } else {
        s.push_str("@group(1) @binding(0) var t_src: texture_2d_array<f32>;\n\n");
    }
    s.push_str(FULLSCREEN_VS);
    let mut steps = Vec::new();
    let mut layers = Layers {
        kernel,
        src,
        dst,
        compute,
        source: "t_src".into(),
    };
    let scratch_of = |tex: &Texture| Texture {
        name: format!("{}_tmp", tex.name),
        precision: scratch_precision(tex.precision),
        ..tex.clone()
    };
    if kernel.separable() {
        for tex in &dst.textures {
            let tmp = scratch_of(tex);
            scratch.push(Scratch {
                name: tmp.name.clone(),
                like: tex.name.clone(),
                format: texture_format(&tmp),
            });
        }
    }
    if packed {
        for (axis, horizontal) in [("h", true), ("v", false)] {
            // (texture, the texture it writes, the one it reads, a chunk of its layers)
            let mut units = Vec::new();
            for (ti, tex) in dst.textures.iter().enumerate() {
                let tmp = scratch_of(tex);
                let (written, read) = if horizontal {
                    (tmp, src.textures[ti].name.clone())
                } else {
                    (tex.clone(), tmp.name)
                };
                for chunk in layer_chunks(&written, limits) {
                    units.push((ti, written.clone(), read.clone(), chunk));
                }
            }
            for (k, bin) in pack_axis(&units, limits).into_iter().enumerate() {
                let entry = format!("fs_{}_{axis}_{k}", dst.name);
                let out_name = format!("Out_{}_{axis}_{k}", dst.name);
                let n: usize = bin.iter().map(|&u| units[u].3.len()).sum();
                s.push_str(&out_struct(&out_name, n, false));
                // every texture of the pass is the shadow map's size: the first read's is theirs
                let first = bin.first().map_or(0, |&u| units[u].0);
                let _ = write!(
                    s,
                    "\n@fragment\nfn {entry}(@builtin(position) pos: vec4<f32>) -> {out_name} {{\n    let texel = vec2<i32>(pos.xy);\n    let last = vec2<i32>(textureDimensions(t_src_{first})) - 1i;\n    var out: {out_name};\n"
                );
                let (mut reads, mut writes, mut oi) = (Vec::new(), Vec::new(), 0);
                for &u in &bin {
                    let (ti, written, read, chunk) = &units[u];
                    layers.source = format!("t_src_{ti}");
                    for &layer in chunk {
                        layers.write(&mut s, *ti, layer, oi, horizontal, &written.name, (0, 0, 0, 0), "");
                        oi += 1;
                        writes.push(graph::Target {
                            texture: written.name.clone(),
                            layer,
                        });
                    }
                    if !reads.iter().any(|b: &Binding| b.binding == *ti as u32) {
                        reads.push(Binding {
                            binding: *ti as u32,
                            texture: read.clone(),
                            view: View::Base,
                        });
                    }
                }
                s.push_str("    return out;\n}\n");
                let mut step = fullscreen_step(entry, Draw::FullScreen, reads, "", &[]);
                step.writes = writes;
                steps.push(step);
            }
        }
        return Ok((s, steps));
    }
    for (ti, tex) in dst.textures.iter().enumerate() {
        let src_tex = &src.textures[ti];
        let tmp_tex = scratch_of(tex);
        let passes: Vec<(&str, bool)> = if kernel.separable() {
            vec![("h", true), ("v", false)]
        } else {
            vec![("2d", false)]
        };
        let tmp = tmp_tex.name.clone();
        for (axis, horizontal) in passes {
            // each axis writes as many layers at once as its target's format allows
            let written = if kernel.separable() && horizontal { &tmp_tex } else { tex };
            let tile_size = filter_tile(kernel, horizontal);
            let (ax, ay, tw, th) = tile_size;
            if compute {
                let _ = writeln!(
                    s,
                    "@group(2) @binding(0) var w_{}: texture_storage_2d_array<{}, write>;",
                    written.name,
                    texture_format(written).wgsl()
                );
            }
            for (ci, chunk) in layer_chunks(written, limits).iter().enumerate() {
                let entry = format!("{}_{}_{axis}_{ci}", if compute { "cs" } else { "fs" }, tex.name);
                let out_name = format!("Out_{}_{axis}_{ci}", tex.name);
                let tile = format!("tile_{}_{axis}_{ci}", tex.name);
                if compute {
                    let g = graph::TEXEL_WORKGROUP;
                    let _ = write!(
                        s,
                        "\n// the workgroup's {g} x {g} texels and the kernel's apron, one layer at a time
var<workgroup> {tile}: array<vec4<f32>, {}>;

@compute @workgroup_size({g}, {g})
fn {entry}(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {{
    let texel = vec2<i32>(id.xy);
    let last = vec2<i32>(textureDimensions(t_src)) - 1i;
    // no early return: every invocation takes part in the loads and barriers
    let inside = all(vec2<f32>(id.xy) < frame.shadow_size.xy);
    let origin = vec2<i32>(wg.xy) * {g}i - vec2<i32>({ax}i, {ay}i);
    let local = vec2<i32>(i32(li % {g}u), i32(li / {g}u));
",
                        tw * th
                    );
                } else {
                    s.push_str(&out_struct(&out_name, chunk.len(), false));
                    let _ = write!(
                        s,
                        "\n@fragment\nfn {entry}(@builtin(position) pos: vec4<f32>) -> {out_name} {{\n    let texel = vec2<i32>(pos.xy);\n    let last = vec2<i32>(textureDimensions(t_src)) - 1i;\n    var out: {out_name};\n"
                    );
                }
                for (oi, &layer) in chunk.iter().enumerate() {
                    layers.write(&mut s, ti, layer, oi, horizontal, &written.name, tile_size, &tile);
                }
                s.push_str(if compute { "}\n" } else { "    return out;\n}\n" });
                let (read, write) = match (kernel.separable(), horizontal) {
                    (true, true) => (src_tex.name.clone(), tmp.clone()),
                    (true, false) => (tmp.clone(), tex.name.clone()),
                    _ => (src_tex.name.clone(), tex.name.clone()),
                };
                let mut step = fullscreen_step(
                    entry,
                    Draw::FullScreen,
                    vec![Binding {
                        binding: 0,
                        texture: read,
                        view: View::Base,
                    }],
                    &write,
                    chunk,
                );
                if compute {
                    (step.vertex, step.compute, step.draw) = (None, step.fragment.take(), Draw::ComputeTexels);
                }
                steps.push(step);
            }
        }
    }
    Ok((s, steps))
}

/// WebGPU's render-target byte cost of a format and its component alignment, as it counts
/// them toward `maxColorAttachmentBytesPerSample` (the running total aligned to each
/// format's alignment, then its cost added).
fn target_cost(f: graph::Format) -> (u32, u32) {
    use graph::Format as F;
    match f {
        F::R8Unorm => (1, 1),
        F::Rg8Unorm => (2, 1),
        F::Rgba8Unorm => (8, 1),
        F::R16Unorm | F::R16Float => (2, 2),
        F::Rg16Unorm | F::Rg16Float => (4, 2),
        F::Rgba16Unorm | F::Rgba16Float => (8, 2),
        F::R32Float => (4, 4),
        F::Rg32Float => (8, 4),
        F::Rgba32Float => (16, 4),
        // buffers, never attachments: as much as the widest format
        F::SummedAreaU32 | F::SummedAreaF32 => (16, 4),
    }
}

/// One axis of a separable filter over several textures: its units (texture, the texture
/// written, the one read, a chunk of layers) packed first-fit, in order, into as few
/// fragment steps as the colour attachments allow (at most `max_color_attachments`, and
/// their bytes per sample as WebGPU counts them within the limit). Each bin lists its
/// units' indices.
fn pack_axis(units: &[(usize, Texture, String, Vec<u32>)], limits: &Limits) -> Vec<Vec<usize>> {
    let bytes = |formats: &[graph::Format]| {
        formats.iter().fold(0u32, |total, f| {
            let (cost, align) = target_cost(*f);
            total.next_multiple_of(align) + cost
        })
    };
    let mut bins: Vec<(Vec<usize>, Vec<graph::Format>)> = Vec::new();
    for (u, (_, written, _, chunk)) in units.iter().enumerate() {
        let added = vec![texture_format(written); chunk.len()];
        let fits = |formats: &Vec<graph::Format>| {
            let all: Vec<graph::Format> = formats.iter().chain(&added).copied().collect();
            all.len() as u32 <= limits.max_color_attachments && bytes(&all) <= limits.max_color_attachment_bytes_per_sample
        };
        match bins.iter_mut().find(|(_, formats)| fits(formats)) {
            Some((members, formats)) => {
                members.push(u);
                formats.extend(&added);
            }
            None => bins.push((vec![u], added)),
        }
    }
    bins.into_iter().map(|(members, _)| members).collect()
}

/// What writes one layer of a Filter step: its taps, their weighted sum (or max or min),
/// and, on the last axis, the re-encoding from the source's storage to the destination's.
struct Layers<'a> {
    kernel: &'a IrKernel,
    src: &'a crate::ir::PlacedResource,
    dst: &'a crate::ir::PlacedResource,
    compute: bool,
    /// The source texture's variable (`t_src`, or `t_src_<texture>` in a packed step).
    source: String,
}

impl Layers<'_> {
    /// Write layer `layer` of texture `ti` as output `oi` (fragment) or a store into
    /// `w_<written>` (compute, through workgroup tile `tile` of `(ax, ay, tw, th)`).
    #[allow(clippy::too_many_arguments)]
    fn write(
        &self,
        s: &mut String,
        ti: usize,
        layer: u32,
        oi: usize,
        horizontal: bool,
        written: &str,
        (ax, ay, tw, th): (i32, i32, i32, i32),
        tile: &str,
    ) {
        let (kernel, src, dst, compute) = (self.kernel, self.src, self.dst, self.compute);
        let t_src = &self.source;
        let size = kernel.size() as i32;
        let r = (size - 1) / 2;
        // out = ((f / scale_in + bias_in * W) - bias_out) * scale_out, W = sum of weights
        let sum_w = if matches!(kernel, IrKernel::LoG) { 0.0 } else { 1.0 };
        let taps: Vec<(i32, i32, f64)> = match kernel {
            IrKernel::LoG => (0..9)
                .filter(|i| IrKernel::LOG_3X3[*i] != 0.0)
                .map(|i| (i as i32 % 3 - 1, i as i32 / 3 - 1, IrKernel::LOG_3X3[i]))
                .collect(),
            IrKernel::Box(_) | IrKernel::Gaussian(..) | IrKernel::Max(_) | IrKernel::Min(_) => {
                let w = kernel.weights_1d().unwrap_or_else(|| vec![1.0; size as usize]);
                (-r..=r)
                    .map(|i| {
                        if horizontal {
                            (i, 0, w[(i + r) as usize])
                        } else {
                            (0, i, w[(i + r) as usize])
                        }
                    })
                    .collect()
            }
        };
        let _ = writeln!(s, "    // layer {layer}");
        if compute {
            // each invocation loads every 64th texel of the tile: one global
            // load per texel and layer instead of one per tap
            let n = tw * th;
            let g2 = (graph::TEXEL_WORKGROUP * graph::TEXEL_WORKGROUP) as i32;
            for j in 0..(n + g2 - 1) / g2 {
                let _ = writeln!(s, "    let k{oi}_{j} = i32(li) + {}i;", j * g2);
                let load = format!(
                    "{tile}[k{oi}_{j}] = textureLoad({t_src}, clamp(origin + vec2<i32>(k{oi}_{j} % {tw}i, k{oi}_{j} / {tw}i), vec2<i32>(0i), last), {layer}i, 0i);"
                );
                if (j + 1) * g2 > n {
                    let _ = writeln!(s, "    if k{oi}_{j} < {n}i {{\n        {load}\n    }}");
                } else {
                    let _ = writeln!(s, "    {load}");
                }
            }
            s.push_str("    workgroupBarrier();\n");
            for (k, (dx, dy, _)) in taps.iter().enumerate() {
                let _ = writeln!(
                    s,
                    "    let a{oi}_{k} = {tile}[(local.y + {}i) * {tw}i + local.x + {}i];",
                    ay + dy,
                    ax + dx
                );
            }
            // the next layer's loads overwrite the tile
            s.push_str("    workgroupBarrier();\n");
        } else {
            for (k, (dx, dy, _)) in taps.iter().enumerate() {
                let _ = writeln!(
                    s,
                    "    let a{oi}_{k} = textureLoad({t_src}, clamp(texel + vec2<i32>({dx}i, {dy}i), vec2<i32>(0i), last), {layer}i, 0i);"
                );
            }
        }
        // the taps folded left to right with `op`: op(op(a0, a1), a2) ...
        let fold = |op: &str| {
            (0..taps.len())
                .map(|k| format!("a{oi}_{k}"))
                .reduce(|a, b| format!("{op}({a}, {b})"))
                .unwrap_or_default()
        };
        let combined = match kernel {
            IrKernel::Max(_) => fold("max"),
            IrKernel::Min(_) => fold("min"),
            IrKernel::Box(_) | IrKernel::Gaussian(..) | IrKernel::LoG => taps
                .iter()
                .enumerate()
                .map(|(k, (_, _, w))| format!("a{oi}_{k} * {}", f32_lit(*w as f32)))
                .collect::<Vec<_>>()
                .join(" + "),
        };
        // Encodes differ only across a LoG (its output range is wider).
        let last_axis = !kernel.separable() || !horizontal;
        let mut value = combined;
        if last_axis {
            let mut fix = Vec::new();
            let mut any = false;
            for c in 0..4u32 {
                let enc_in = src.slots.iter().find(|sl| sl.place() == (ti, layer, c)).map(|sl| sl.encode);
                let enc_out = dst.slots.iter().find(|sl| sl.place() == (ti, layer, c)).map(|sl| sl.encode);
                match (enc_in, enc_out) {
                    (Some(i), Some(o)) if i != o || sum_w != 1.0 => {
                        any = true;
                        fix.push((1.0 / i.scale * o.scale, (i.bias * sum_w - o.bias) * o.scale));
                    }
                    _ => fix.push((1.0, 0.0)),
                }
            }
            if any {
                let m: Vec<String> = fix.iter().map(|f| f32_lit(f.0 as f32)).collect();
                let b: Vec<String> = fix.iter().map(|f| f32_lit(f.1 as f32)).collect();
                value = format!("({value}) * vec4<f32>({}) + vec4<f32>({})", m.join(", "), b.join(", "));
            }
        }
        if compute {
            let _ = writeln!(
                s,
                "    if inside {{\n        textureStore(w_{}, texel, {layer}i, {value});\n    }}",
                written
            );
        } else {
            let _ = writeln!(s, "    out.o{oi} = {value};");
        }
    }
}
