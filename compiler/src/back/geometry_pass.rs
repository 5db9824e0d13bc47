//! The Geometry pass: primitives drawn into the shadow map, their fragments writing the
//! pass's channels (through the entries Map passes use), overlaps combined by the resolve
//! rule. Primitives built from silhouettes come from their library (`back/geometry.rs`),
//! with the compute step that classifies the edges, or for `Skins` finds the depth
//! discontinuities, ahead of the draws; `BackFaces` draws the scene's own triangles. The
//! resolve rules a channel's storage cannot take are refused here.

use crate::back::depth::SCENE_FROM_LIGHT_VS;
use crate::back::expr::Site;
use crate::back::geometry;
use crate::back::internal;
use crate::back::map::{EntryForm, channel_entries};
use crate::back::parts::Split;
use crate::back::steps::fullscreen_step;
use crate::back::text::{COMP, decode_expr, f32_lit, header};
use crate::diag::{Diagnostic, Phase};
use crate::front::ast::{Precision, Primitive, Resolve};
use crate::ir::{ExprId, IrPass, IrPassKind, Program};
use crate::pack::Limits;
use sshc_graph::{self as graph, Draw, OpCount, Step, View};
use std::fmt::Write as _;

/// The buffer a Geometry pass's classification appends to.
fn geometry_buffer_name(pass: &IrPass) -> String {
    // skins join two views' discontinuities; the others classify one view's silhouettes
    let skins = pass.kind.primitive().is_some_and(Primitive::joins_sample_views);
    format!("{}.{}", pass.name, if skins { "skins" } else { "silhouettes" })
}

/// The generated buffers of a module: one per `Silhouettes` step, laid out as its
/// primitive's library says.
pub(crate) fn geometry_buffers(pass: &IrPass, steps: &[Step]) -> Vec<graph::BufferDecl> {
    let Some(primitive) = pass.kind.primitive() else {
        return vec![];
    };
    let Some(lib) = geometry::library(primitive) else {
        return vec![];
    };
    steps
        .iter()
        .filter(|s| s.draw.generates_records())
        .map(|_| graph::BufferDecl {
            name: geometry_buffer_name(pass),
            record_bytes: lib.record_bytes,
            vertices_per_record: lib.vertices_per_record,
        })
        .collect()
}

/// A Geometry pass: one fragment entry per group of layers, writing the pass's channels
/// per fragment of its primitives; overlaps combine by the resolve rule (graph
/// `Resolve`): blending, or a depth test (`Nearest`). `Add` keeps `1 - sum(1 - v)`: its
/// fragments write the shadow amount `1 - v`. Primitives built from silhouettes come
/// from their library (classification on the GPU, primitives pulled from its records;
/// `back/geometry.rs`); `BackFaces` draws the scene's triangles that face away from the
/// light (Lawlor 2006, section 3.1, step 3). Fragments failing `keep` are discarded.
pub(crate) fn geometry(
    ir: &Program,
    pass: &IrPass,
    primitive: Primitive,
    resolve: Resolve,
    keep: Option<ExprId>,
    limits: &Limits,
    split: Split,
) -> Result<(String, Vec<Step>), Diagnostic> {
    let w = pass.writes.ok_or_else(|| internal("geometry pass without output"))?;
    let res = &ir.resources[w];
    for tex in &res.textures {
        if tex.precision == Precision::F32 && resolve != Resolve::Nearest {
            let ch = res
                .slots
                .iter()
                .find(|s| res.textures[s.texture].name == tex.name)
                .map(|s| ir.channels[s.channel].name.clone())
                .unwrap_or_default();
            return Err(Diagnostic::error(
                Phase::Codegen,
                format!(
                    "pass `{}` blends channel `{ch}` at F32: WebGPU blends 32-bit float targets only with an optional feature",
                    pass.name
                ),
            )
            .at(pass.span, "overlapping primitives are resolved by blending")
            .help("declare the channel F16, Unorm8 or Unorm16"));
        }
    }
    let lib = geometry::library(primitive);
    // The foremost surface the light sees: the channel of the Depth resource the pass
    // reads. The penumbra map holds the penumbrae of those surfaces only (Wyman & Hansen
    // 2003, section 3), so fragments behind it are discarded (the paper's fragment
    // program, line 4).
    let surface = if primitive.behind_the_lit_surface_discarded() {
        Some(
            pass.reads
                .iter()
                .find(|&&r| ir.passes[ir.resources[r].writer].kind.kind().is_depth())
                .and_then(|&r| ir.resources[r].slots.first().map(|s| s.channel))
                .ok_or_else(|| {
                    Diagnostic::error(Phase::Codegen, format!("Geometry pass `{}` reads no Depth resource", pass.name))
                        .at(pass.span, "cones and sheets need the surface the light sees at each texel")
                        .help("add the Depth pass's resource to `reads`")
                })?,
        )
    } else {
        None
    };
    // Skins: the per-sample Depth resource whose discontinuities they span, and the
    // detector's threshold.
    let skins = if primitive.joins_sample_views() {
        let depth = pass
            .reads
            .iter()
            .copied()
            .find(|&r| ir.passes[ir.resources[r].writer].kind.kind().is_depth())
            .ok_or_else(|| internal("Skins pass without a Depth resource (check refuses it)"))?;
        let threshold = ir
            .params
            .iter()
            .find(|p| p.name == geometry::SKIN_THRESHOLD_PARAM)
            .ok_or_else(|| {
                Diagnostic::error(
                    Phase::Codegen,
                    format!("Skins pass `{}` needs the param `{}`", pass.name, geometry::SKIN_THRESHOLD_PARAM),
                )
                .at(pass.span, "its discontinuity detector has no threshold")
                .note("a skin spans a depth step larger than the threshold (normalised depth) where the map's 3x3 Laplacian of Gaussian exceeds it too")
                .help(format!(
                    "declare `{}: (type: F32, default: 0.02)` in `params`",
                    geometry::SKIN_THRESHOLD_PARAM
                ))
            })?;
        let IrPassKind::Geometry { from: Some(from), .. } = pass.kind else {
            return Err(internal("Skins pass without `from` (check refuses it)"));
        };
        Some((depth, threshold, from))
    } else {
        None
    };
    let buffer = geometry_buffer_name(pass);
    let (signature, head) = match &lib {
        Some(lib) => (
            format!("in: {}", lib.varying),
            format!("    let texel = vec2<i32>(in.clip.xy);\n{}", lib.inputs),
        ),
        None => (
            "in: DepthVarying, @builtin(front_facing) front: bool".to_string(),
            "    let texel = vec2<i32>(in.clip.xy);\n    let in_z_frag = in.view_distance;\n".to_string(),
        ),
    };
    let entries = channel_entries(
        ir,
        pass,
        Site::Geometry,
        limits,
        EntryForm {
            signature: &signature,
            head: &head,
            prelude: &|em| {
                if let Some(surface) = surface {
                    let z = em.load_map_channel(surface, [0, 0])?;
                    em.line(&format!(
                        "let in_z_surface = frame.depth_range.x + {z} * (frame.depth_range.y - frame.depth_range.x);"
                    ));
                    em.line("if in_z_frag > in_z_surface {\n        discard;\n    }");
                }
                if lib.is_none() {
                    // winding seen from the light: counter-clockwise faces it
                    em.line("if front {\n        discard;\n    }");
                }
                if let Some(k) = keep {
                    let k = em.emit(k)?;
                    em.line(&format!("if !({k}) {{\n        discard;\n    }}"));
                }
                Ok(())
            },
            store: &|slot, stored| {
                if !slot.encode.is_identity() && matches!(resolve, Resolve::Add | Resolve::Multiply) {
                    return Err(Diagnostic::error(
                        Phase::Codegen,
                        format!(
                            "pass `{}` adds or multiplies channel `{}`, whose storage is scaled to its range",
                            pass.name, ir.channels[slot.channel].name
                        ),
                    )
                    .at(pass.span, "sums and products of scaled values are not the scaled sum or product")
                    .help("give the channel a range inside [0, 1], or resolve with KeepMin or KeepMax"));
                }
                Ok(match resolve {
                    Resolve::Add => format!("1.0 - {stored}"),
                    Resolve::KeepMin | Resolve::KeepMax | Resolve::Multiply | Resolve::Nearest => stored,
                })
            },
            step: &|entry, texture, chunk| match &lib {
                Some(lib) => {
                    let mut step = fullscreen_step(
                        entry,
                        Draw::Primitives {
                            buffer: buffer.clone(),
                            resolve,
                        },
                        vec![],
                        texture,
                        chunk,
                    );
                    step.vertex = Some(lib.vertex.into());
                    step
                }
                None => {
                    let mut step = fullscreen_step(entry, Draw::SceneFromLight, vec![], texture, chunk);
                    step.vertex = Some("vs_depth".into());
                    step
                }
            },
            depth: lib.as_ref().and_then(|l| l.depth),
            split,
            compute: false,
        },
    )?;
    let mut entries = entries;
    let mut steps = Vec::new();
    let mut prefix = String::new();
    if let Some((depth, threshold, from)) = skins {
        // the source map's depth, decoded, and the threshold, ahead of the library
        let r = &ir.resources[depth];
        let slot = r.slots.first().ok_or_else(|| internal("depth resource without channel"))?;
        let (t, layer, comp) = slot.place();
        let per = r.textures[t].layers;
        let tex = entries.decl.binding(&r.textures[t].name, View::Base);
        let stored = format!(
            "textureLoad({tex}, clamp(t, vec2<i32>(0i), vec2<i32>(frame.shadow_size.xy) - 1i), view * {per}i + {layer}i, 0i).{}",
            COMP[comp as usize]
        );
        let tau = if threshold.uniform {
            entries.decl.uses_params = true;
            format!("params.{}", threshold.name)
        } else {
            f32_lit(threshold.value.as_f64() as f32)
        };
        let _ = write!(
            prefix,
            "{}@group(0) @binding(3) var<uniform> light_samples: LightSamples;

const SKIN_FROM: i32 = {};

// linear depth of sample view `view` at texel t (clamped to the map)
fn sk_depth(t: vec2<i32>, view: i32) -> f32 {{
    return {};
}}

// the discontinuity threshold, normalised depth (param `{}`)
fn sk_threshold() -> f32 {{
    return {tau};
}}
",
            graph::LIGHT_SAMPLES_WGSL,
            match from {
                graph::Neighbour::Previous => "-1i",
                graph::Neighbour::Next => "1i",
            },
            decode_expr(&stored, slot.encode),
            threshold.name
        );
        let bindings = entries.decl.graph_bindings();
        for s in &mut entries.steps {
            s.reads = bindings.clone();
            s.params = entries.decl.uses_params;
        }
        steps.push(Step {
            vertex: None,
            fragment: None,
            compute: Some("cs_skins".into()),
            draw: Draw::Discontinuities {
                buffer: buffer.clone(),
                source: from,
            },
            reads: bindings,
            writes: vec![],
            params: entries.decl.uses_params,
            sampler: false,
            light_samples: true,
            cost: OpCount::default(),
        });
    } else if let Some(lib) = &lib {
        steps.push(Step {
            vertex: None,
            fragment: None,
            compute: Some(lib.compute.into()),
            draw: Draw::Silhouettes { buffer: buffer.clone() },
            reads: vec![],
            writes: vec![],
            params: false,
            sampler: false,
            light_samples: false,
            cost: OpCount::default(),
        });
    }
    steps.extend(entries.steps);
    let library = match &lib {
        Some(lib) => format!("{prefix}{}", lib.source),
        None => SCENE_FROM_LIGHT_VS.to_string(),
    };
    let src = format!(
        "{}{}\n{}\n{}{}",
        header(ir, pass),
        entries.decl.declarations(ir),
        library,
        entries.structs,
        entries.bodies
    );
    Ok((src, steps))
}
