//! The Shade pass: the visibility evaluated per camera pixel, forward (the camera
//! raster's fragments) or deferred (a G-buffer, then one compute invocation per pixel);
//! the receiver's inputs seen from the light's centre and, for `at_sample`, from each
//! light sample's view.

use crate::back::expr::{Emitter, Site};
use crate::back::parts::Split;
use crate::back::text::header;
use crate::builtins::{InView, Input, Ty};
use crate::diag::Diagnostic;
use crate::ir::{ExprId, IrPass, Program};
use sshc_graph::{self as graph, Draw, OpCount, Step};
use std::collections::BTreeSet;
use std::fmt::Write as _;

/// The receiver seen from light sample `k`: the `in_*_v{k}` locals of the inputs in `used`
/// and of those they need, each from its descriptor's [`InView`] lines (its own matrices,
/// depth range and texel size in `light_samples`; the weights of its segments), in the
/// order of `Input::ALL` with what an input needs first. Unused inputs are not emitted, so
/// each sample costs only what its lookups and inputs need.
fn sample_prologue(k: u8, used: &BTreeSet<Input>) -> String {
    fn emit(i: Input, k: u8, done: &mut BTreeSet<Input>, s: &mut String) {
        if !done.insert(i) {
            return;
        }
        let (needs, lines): (&[Input], &[&str]) = match i.desc().view {
            InView::Own { needs, wgsl } => (needs, wgsl),
            InView::OnlyThere(wgsl) => (&[], wgsl),
            InView::Same => (&[], &[]),
        };
        for &n in needs {
            emit(n, k, done, s);
        }
        for line in lines {
            let _ = writeln!(s, "    {}", line.replace("{k}", &k.to_string()));
        }
    }
    let mut s = format!("    // the receiver seen from light sample {k}\n    let sv{k} = light_samples.views[{k}];\n");
    let mut done = BTreeSet::new();
    for i in Input::ALL.into_iter().filter(|i| used.contains(i)) {
        emit(i, k, &mut done, &mut s);
    }
    s
}

/// What the camera raster of both Shade schedules interpolates.
// The clip position is `@invariant`: the runtime redraws the objects that receive no
// shadow with its own vertex stage of the same expression, testing depth Equal against this
// raster's (runtime/src/receivers.rs), which invariance makes exact.
const SHADE_VARYING: &str = "
struct ShadeVarying {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
}
";

/// The camera raster's vertex stage: the scene's world position and normal.
const SHADE_VERTEX: &str = "
@vertex
fn vs_shade(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> ShadeVarying {
    var out: ShadeVarying;
    out.clip = frame.camera_view_proj * vec4<f32>(position, 1.0);
    out.world = position;
    out.normal = normal;
    return out;
}
";

/// The receiver's normal, in a fragment entry taking `in: ShadeVarying`.
const SHADE_NORMAL: &str = graph::SHADE_NORMAL_WGSL;

/// The receiver seen from the light's centre, from `in.world`, `world` and `n`; `distant`,
/// where the graph is specialised for a scene, keeps only the form of the
/// direction to the light and of the texel's size that the light's kind takes.
fn shade_receiver(distant: Option<bool>) -> String {
    let to_light = match distant {
        None => {
            "select(normalize(frame.light_position.xyz - in.world), normalize(frame.light_position.xyz), frame.light_position.w == 0.0)"
        }
        Some(false) => "normalize(frame.light_position.xyz - in.world)",
        Some(true) => "normalize(frame.light_position.xyz)",
    };
    let texel = match distant {
        None => "frame.texel_world.x * in_d_world + frame.texel_world.y",
        // perspective: y is 0; orthographic: x is 0 (sshc_graph's `texel_world`)
        Some(false) => "frame.texel_world.x * in_d_world",
        Some(true) => "frame.texel_world.y",
    };
    format!(
        "    let in_d_world = -(frame.light_view * world).z;
    let in_d = (in_d_world - frame.depth_range.x) * frame.depth_range.z;
    let light_clip = frame.light_view_proj * world;
    let in_uv = light_clip.xy / light_clip.w * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5);
    let to_light = {to_light};
    let in_ndotl = dot(n, to_light);
    // tan(acos(ndotl)), for slope-scaled bias
    let in_slope = min(sqrt(max(1.0 - in_ndotl * in_ndotl, 0.0)) / max(abs(in_ndotl), 0.01), 100.0);
    let texel_pos = in_uv * frame.shadow_size.xy - 0.5;
    let in_tf = fract(texel_pos);
    // one shadow-map texel at the receiver, in normalised depth units
    let in_texel_depth = ({texel}) * frame.depth_range.z;
    let in_base = vec2<i32>(floor(texel_pos));
"
    )
}

/// The receiver-plane depth slope's derivatives, in a fragment entry (screen-space
/// derivatives); `DEPTH_SLOPE` (the schema's, shared with the runtime's host pixels)
/// follows it.
const SHADE_SLOPE: &str = "    // receiver-plane depth gradient over uv from screen-space derivatives (Isidoro 2006):
    // solve [duv/dx; duv/dy] g = [dd/dx; dd/dy]; 0 where the Jacobian is singular
    let duv_dx = dpdx(in_uv);
    let duv_dy = dpdy(in_uv);
    let dd_dx = dpdx(in_d);
    let dd_dy = dpdy(in_d);
";
const DEPTH_SLOPE: &str = graph::DEPTH_SLOPE_WGSL;
const OCTAHEDRAL: &str = graph::OCTAHEDRAL_WGSL;

/// A Shade pass: forward, one camera raster whose fragments evaluate the visibility; or
/// deferred (the compute schedule, where the schedule phase chose it), a camera raster writing the G-buffer
/// ([`graph::GBUFFER`]) and then one compute invocation per pixel evaluating it from there.
/// Both compute the receiver's inputs the same way from the same values, except that the
/// deferred form reads the normal through an octahedral f32 encoding and the footprint of
/// implicit-LOD lookups at F16.
pub(crate) fn shade(
    ir: &Program,
    pass: &IrPass,
    visibility: ExprId,
    deferred: bool,
    split: Split,
) -> Result<(String, Vec<Step>), Diagnostic> {
    let mut em = Emitter::new(ir, Site::Receiver, pass.reads.clone());
    em.split = split;
    em.deferred = deferred;
    let v = em.emit(visibility)?;
    // the debug outputs, where the build has them: (WGSL name, value as a vec4, format)
    let mut debug = Vec::new();
    for d in &ir.ir.debug {
        let value = em.emit(d.expr)?;
        let ty = ir.arena.ty(d.expr);
        debug.push((d.texture.clone(), widened(&value, ty), debug_format(ty)));
    }
    let mut s = header(ir, pass);
    s.push_str(&em.declarations(ir));
    let entry = if deferred { "cs_shade" } else { "fs_shade" };
    let (functions, body) = em.finish(entry);
    s.push_str(&functions);
    s.push_str(SHADE_VARYING);
    let prologues: String = em.views.iter().map(|(&k, used)| sample_prologue(k, used)).collect();
    let receiver = shade_receiver(ir.ir.specialised.as_ref().map(|s| s.facts.light.is_distant()));
    // the `pixel` input, where the code reads it
    let uses_pixel = body.contains("in_pixel") || functions.contains("in_pixel") || debug.iter().any(|(_, v, _)| v.contains("in_pixel"));
    let pixel = |from: &str| {
        if uses_pixel {
            format!("    let in_pixel = {from};\n")
        } else {
            String::new()
        }
    };
    let outputs = |store: &dyn Fn(&str, &str) -> String| {
        format!(
            "    // outputs stay finite and in [0, 1]: NaN is drawn lit, an infinity clamped; a
    // receiver facing away from the light's centre is shadowed by its own surface. NaN and
    // the infinities are told from the bits (all exponent bits set): `raw != raw` is
    // folded to false by drivers that assume no NaN (lavapipe drew NaN as 0). The normal's
    // w is 1 where a receiver facing the light got a value that is not finite, for the
    // host to report (`sshc_graph::CAMERA_OUTPUTS`)
    let raw = {v};
    let raw_bits = bitcast<u32>(raw);
    let raw_special = (raw_bits & 0x7f800000u) == 0x7f800000u;
    let raw_nan = raw_special && (raw_bits & 0x007fffffu) != 0u;
    let vis = select(select(clamp(raw, 0.0, 1.0), 1.0, raw_nan), 0.0, in_ndotl <= 0.0);
    let not_finite = select(0.0, 1.0, raw_special && in_ndotl > 0.0);
    let lambert = max(in_ndotl, 0.0);
{}{}{}{}{}",
            store("visibility", "vec4<f32>(vis, 0.0, 0.0, 1.0)"),
            store("color", graph::SHADE_COLOR_WGSL),
            store("position", "vec4<f32>(in.world, 1.0)"),
            store("normal", "vec4<f32>(n, not_finite)"),
            debug.iter().map(|(name, value, _)| store(name, value)).collect::<String>(),
        )
    };
    // the debug textures each step writes after the camera outputs
    let targets: Vec<graph::Target> = debug
        .iter()
        .map(|(name, ..)| graph::Target {
            texture: name.clone(),
            layer: 0,
        })
        .collect();
    let step = |vertex: Option<&str>, fragment: Option<&str>, compute: Option<&str>, draw: Draw, reads: bool| Step {
        vertex: vertex.map(str::to_string),
        fragment: fragment.map(str::to_string),
        compute: compute.map(str::to_string),
        draw,
        reads: if reads { em.graph_bindings() } else { vec![] },
        writes: if reads { targets.clone() } else { vec![] },
        params: reads && em.uses_params,
        sampler: reads && em.uses_sampler,
        light_samples: reads && !em.views.is_empty(),
        cost: OpCount::default(),
    };
    if !deferred {
        let _ = write!(
            s,
            "
// visibility (r32float), shaded colour (rgba8unorm), world position (rgba32float) and
// world normal (rgba16float): 36 bytes per sample as WebGPU counts them (rgba8unorm 8),
// above its default limit of 32: a host's device raises max_color_attachment_bytes_per_sample.
struct ShadeOut {{
    @location(0) visibility: vec4<f32>,
    @location(1) color: vec4<f32>,
    @location(2) position: vec4<f32>,
    @location(3) normal: vec4<f32>,
{}}}
{SHADE_VERTEX}
@fragment
fn fs_shade(in: ShadeVarying) -> ShadeOut {{
{SHADE_NORMAL}    let world = vec4<f32>(in.world, 1.0);
{receiver}{SHADE_SLOPE}{DEPTH_SLOPE}{}{prologues}{body}{}    return out;
}}
",
            debug
                .iter()
                .enumerate()
                .map(|(i, (name, ..))| format!(
                    "    // debug output `{}`, unclamped (its step's target {i} after the camera outputs)\n    @location({}) {name}: vec4<f32>,\n",
                    &name[graph::DEBUG_PREFIX.len()..],
                    graph::CAMERA_OUTPUTS.len() + i
                ))
                .collect::<String>(),
            pixel("floor(in.clip.xy)"),
            outputs(&|field, value| {
                let decl = if field == "visibility" { "    var out: ShadeOut;\n" } else { "" };
                format!("{decl}    out.{field} = {value};\n")
            })
        );
        let forward = step(Some("vs_shade"), Some("fs_shade"), None, Draw::SceneFromCamera, true);
        return Ok((s, vec![forward]));
    }
    s.push_str(SHADE_VERTEX);
    let _ = write!(
        s,
        "
// The G-buffer (sshc_graph::GBUFFER): world position and the centre view's depth slope,
// the normal (octahedral, f32), the footprint of the centre view's uv (f16).
struct GBufferOut {{
    @location(0) world: vec4<f32>,
    @location(1) normal: vec2<f32>,
    @location(2) duv: vec4<f32>,
}}

{OCTAHEDRAL}
@fragment
fn fs_gbuffer(in: ShadeVarying) -> GBufferOut {{
{SHADE_NORMAL}    let world = vec4<f32>(in.world, 1.0);
    let in_d = (-(frame.light_view * world).z - frame.depth_range.x) * frame.depth_range.z;
    let light_clip = frame.light_view_proj * world;
    let in_uv = light_clip.xy / light_clip.w * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5);
{SHADE_SLOPE}{DEPTH_SLOPE}    var out: GBufferOut;
    out.world = vec4<f32>(in.world, in_depth_slope);
    out.normal = octahedral(n);
    out.duv = vec4<f32>(duv_dx, duv_dy);
    return out;
}}

// The camera outputs (sshc_graph::CAMERA_OUTPUTS) and the G-buffer.
@group(2) @binding(0) var o_visibility: texture_storage_2d_array<r32float, write>;
@group(2) @binding(1) var o_color: texture_storage_2d_array<rgba8unorm, write>;
@group(2) @binding(2) var o_position: texture_storage_2d_array<rgba32float, write>;
@group(2) @binding(3) var o_normal: texture_storage_2d_array<rgba16float, write>;
{}@group(3) @binding(0) var g_world: texture_2d<f32>;
@group(3) @binding(1) var g_normal: texture_2d<f32>;
@group(3) @binding(2) var g_duv: texture_2d<f32>;

@compute @workgroup_size({wg}, {wg})
fn cs_shade(@builtin(global_invocation_id) id: vec3<u32>) {{
    // invocations past the target's edge store nothing
    if any(id.xy >= textureDimensions(o_visibility)) {{
        return;
    }}
    let pixel = vec2<i32>(id.xy);
    let gbuffer = textureLoad(g_world, pixel, 0i);
    // where the camera sees no surface (the G-buffer's clear value has w = -1): the forward
    // form's clear values, visibility 1, a dark background, position and normal NaN
    if gbuffer.w < 0.0 {{
        let nan = bitcast<f32>(0x7fc00000u);
        textureStore(o_visibility, pixel, 0i, vec4<f32>(1.0, 0.0, 0.0, 1.0));
        textureStore(o_color, pixel, 0i, vec4<f32>(0.02, 0.02, 0.03, 1.0));
        textureStore(o_position, pixel, 0i, vec4<f32>(nan));
        textureStore(o_normal, pixel, 0i, vec4<f32>(nan));
{}        return;
    }}
    let in = ShadeVarying(vec4<f32>(0.0), gbuffer.xyz, vec3<f32>(0.0));
    let n = from_octahedral(textureLoad(g_normal, pixel, 0i).xy);
    let world = vec4<f32>(in.world, 1.0);
{receiver}    let in_depth_slope = gbuffer.w;
    let footprint = textureLoad(g_duv, pixel, 0i);
    let in_duv_dx = footprint.xy;
    let in_duv_dy = footprint.zw;
{}{prologues}{body}{}}}
",
        debug
            .iter()
            .enumerate()
            .map(|(i, (name, _, format))| format!(
                "@group(2) @binding({}) var o_{name}: texture_storage_2d_array<{}, write>;\n",
                graph::CAMERA_OUTPUTS.len() + i,
                format.wgsl()
            ))
            .collect::<String>(),
        debug
            .iter()
            .map(|(name, ..)| format!("        textureStore(o_{name}, pixel, 0i, vec4<f32>(nan));\n"))
            .collect::<String>(),
        pixel("vec2<f32>(pixel)"),
        outputs(&|field, value| format!("    textureStore(o_{field}, pixel, 0i, {value});\n")),
        wg = graph::TEXEL_WORKGROUP,
    );
    let gbuffer = step(Some("vs_shade"), Some("fs_gbuffer"), None, Draw::CameraGBuffer, false);
    let pixels = step(None, None, Some("cs_shade"), Draw::ComputePixels, true);
    Ok((s, vec![gbuffer, pixels]))
}

/// The texture format of a debug output of type `ty`: R32Float for an f32, Rg32Float for
/// a `vec2`, Rgba32Float for a `vec3` (its w 0) and a `vec4`.
pub(crate) fn debug_format(ty: Ty) -> graph::Format {
    match ty {
        Ty::Vec(2) => graph::Format::Rg32Float,
        Ty::Vec(_) => graph::Format::Rgba32Float,
        Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => graph::Format::R32Float,
    }
}

/// The components a debug output of type `ty` has (1 for an f32).
pub(crate) fn debug_components(ty: Ty) -> u32 {
    match ty {
        Ty::Vec(n) => u32::from(n),
        Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => 1,
    }
}

/// A debug output's value as the `vec4<f32>` its target takes (unused components 0).
fn widened(value: &str, ty: Ty) -> String {
    match ty {
        Ty::Vec(2) => format!("vec4<f32>({value}, 0.0, 0.0)"),
        Ty::Vec(3) => format!("vec4<f32>({value}, 0.0)"),
        Ty::Vec(_) => value.to_string(),
        Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => format!("vec4<f32>({value}, 0.0, 0.0, 0.0)"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every input a view computes again, alone and all together, in two views: the
    /// prologue defines it (and what it needs, once) in WGSL that naga accepts, and the
    /// same-in-every-view inputs add nothing.
    #[test]
    fn every_input_seen_from_a_view_is_defined_by_valid_wgsl() {
        let module = |prologue: &str, reads: &str| {
            format!(
                "{}@group(0) @binding(0) var<uniform> frame: Frame;
{}@group(0) @binding(3) var<uniform> light_samples: LightSamples;
struct In {{ world: vec3<f32> }}
@fragment
fn main(@location(0) w: vec3<f32>) -> @location(0) vec4<f32> {{
    let in = In(w);
    let world = vec4<f32>(w, 1.0);
    let n = vec3<f32>(0.0, 0.0, 1.0);
{prologue}    return vec4<f32>({reads});
}}
",
                sshc_graph::FRAME_WGSL,
                graph::LIGHT_SAMPLES_WGSL
            )
        };
        let read = |i: Input, k: u8| match i.ty() {
            Ty::Vec(_) => format!("{}_v{k}.x", i.desc().wgsl),
            Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => format!("f32({}_v{k})", i.desc().wgsl),
        };
        let own: Vec<Input> = Input::ALL
            .into_iter()
            .filter(|i| match i.desc().view {
                InView::Own { .. } | InView::OnlyThere(_) => true,
                InView::Same => false,
            })
            .collect();
        assert!(own.contains(&Input::Uv) && own.contains(&Input::SegmentBefore) && !own.contains(&Input::Pixel));
        for &i in &own {
            let prologue = sample_prologue(0, &BTreeSet::from([i]));
            let wgsl = module(&prologue, &format!("{}, 0.0, 0.0, 1.0", read(i, 0)));
            if let Err(e) = crate::back::validate(&wgsl) {
                panic!("{}: {e}\n{wgsl}", i.name());
            }
        }
        let all: BTreeSet<Input> = own.iter().copied().collect();
        let both: String = [0u8, 1].iter().map(|&k| sample_prologue(k, &all)).collect();
        let sum = own.iter().flat_map(|&i| [read(i, 0), read(i, 1)]).collect::<Vec<_>>().join(" + ");
        let wgsl = module(&both, &format!("{sum}, 0.0, 0.0, 1.0"));
        if let Err(e) = crate::back::validate(&wgsl) {
            panic!("{e}\n{wgsl}");
        }
        // each local once per view, what an input needs before it
        for k in [0u8, 1] {
            let p = sample_prologue(k, &all);
            assert_eq!(p.matches(&format!("let in_d_world_v{k} =")).count(), 1, "{p}");
            assert!(
                p.find(&format!("let in_d_world_v{k} =")) < p.find(&format!("let in_d_v{k} =")),
                "{p}"
            );
        }
        assert!(!sample_prologue(0, &BTreeSet::from([Input::Pixel, Input::TexelSize])).contains("let in_"));
    }
}
