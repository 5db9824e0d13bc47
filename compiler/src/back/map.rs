//! Channels computed from their values: the Map pass (per shadow-map texel), and the
//! entries that write a resource's channels, one per group of layers of each texture,
//! which Map passes and the fragments of Geometry passes share ([`channel_entries`]).

use crate::back::expr::{Emitter, Site};
use crate::back::internal;
use crate::back::parts::Split;
use crate::back::steps::{fullscreen_step, layer_chunks};
use crate::back::text::{FULLSCREEN_VS, encode_expr, f32_lit, header, out_struct};
use crate::diag::Diagnostic;
use crate::front::ast::LightView;
use crate::ir::{IrPass, PlacedSlot, Program};
use crate::pack::{Limits, texture_format};
use sshc_graph::{self as graph, Draw, Step};
use std::fmt::Write as _;

/// A Map pass: its channels computed per shadow-map texel, by a full-screen fragment entry
/// per group of layers or, where the schedule phase chose `compute`, by a compute entry
/// per layer group storing into storage textures.
pub(crate) fn map(ir: &Program, pass: &IrPass, compute: bool, limits: &Limits, split: Split) -> Result<(String, Vec<Step>), Diagnostic> {
    let (signature, head) = if compute {
        (
            "@builtin(global_invocation_id) id: vec3<u32>",
            "    // invocations past the map's edge (the last workgroups) store nothing
    if any(vec2<f32>(id.xy) >= frame.shadow_size.xy) {
        return;
    }
    let texel = vec2<i32>(id.xy);\n",
        )
    } else {
        ("@builtin(position) pos: vec4<f32>", "    let texel = vec2<i32>(pos.xy);\n")
    };
    let entries = channel_entries(
        ir,
        pass,
        Site::Map,
        limits,
        EntryForm {
            signature,
            head,
            prelude: &|_| Ok(()),
            store: &|_, stored| Ok(stored),
            step: &|entry, texture, chunk| {
                let mut s = fullscreen_step(entry, Draw::FullScreen, vec![], texture, chunk);
                if compute {
                    (s.vertex, s.compute, s.draw) = (None, s.fragment.take(), Draw::ComputeTexels);
                }
                s
            },
            depth: None,
            split,
            compute,
        },
    )?;
    let src = format!(
        "{}{}\n{}\n{FULLSCREEN_VS}{}",
        header(ir, pass),
        entries.decl.declarations(ir),
        entries.structs,
        entries.bodies
    );
    Ok((src, entries.steps))
}

/// How [`channel_entries`] writes one fragment entry.
pub(crate) struct EntryForm<'f, 'a> {
    /// The entry's parameters.
    pub(crate) signature: &'f str,
    /// Its first lines: `texel`, and the inputs as `in_*` locals.
    pub(crate) head: &'f str,
    /// Lines emitted through the entry's emitter before the values.
    pub(crate) prelude: &'f dyn Fn(&mut Emitter<'a>) -> Result<(), Diagnostic>,
    /// The stored expression of a component (given the slot and the encoded value).
    pub(crate) store: &'f dyn Fn(&PlacedSlot, String) -> Result<String, Diagnostic>,
    /// The step that runs an entry over some layers of a texture.
    pub(crate) step: &'f dyn Fn(String, &str, &[u32]) -> Step,
    /// The depth the entry writes (`@builtin(frag_depth)`), a WGSL expression.
    pub(crate) depth: Option<&'f str>,
    /// Where long bodies are split into functions.
    pub(crate) split: Split,
    /// Compute entries storing into storage textures (`Draw::ComputeTexels`) instead of
    /// fragment entries writing colour targets; `signature`, `head` and `step` fit them.
    pub(crate) compute: bool,
}

/// The fragment entries of a Map or Geometry pass: one per group of layers of each texture
/// of the resource it writes, computing its channels from their `value`s.
pub(crate) struct ChannelEntries<'a> {
    pub(crate) structs: String,
    pub(crate) bodies: String,
    /// In texture and layer order, with their reads and params.
    pub(crate) steps: Vec<Step>,
    /// Holds every binding and whether params are used, for the module's declarations.
    pub(crate) decl: Emitter<'a>,
}

pub(crate) fn channel_entries<'a>(
    ir: &'a Program,
    pass: &IrPass,
    site: Site,
    limits: &Limits,
    form: EntryForm<'_, 'a>,
) -> Result<ChannelEntries<'a>, Diagnostic> {
    let w = pass.writes.ok_or_else(|| internal("a pass computing channels without output"))?;
    let res = &ir.resources[w];
    let (mut bodies, mut structs, mut steps) = (String::new(), String::new(), Vec::new());
    // a per-sample pass reads per-sample resources in the view it renders
    let per_sample = pass.kind.kind().is_geometry() && pass.kind.view().is_some_and(LightView::is_per_sample);
    let mut decl = Emitter::new(ir, site, pass.reads.clone());
    decl.per_sample_pass = per_sample;
    for (ti, tex) in res.textures.iter().enumerate() {
        if form.compute {
            // group 2 binds the step's one written texture at binding 0
            let _ = writeln!(
                structs,
                "@group(2) @binding(0) var w_{}: texture_storage_2d_array<{}, write>;",
                tex.name,
                texture_format(tex).wgsl()
            );
        }
        for (ci, chunk) in layer_chunks(tex, limits).into_iter().enumerate() {
            let entry = format!("{}_{}_{ci}", if form.compute { "cs" } else { "fs" }, tex.name);
            let out_name = format!("Out_{}_{ci}", tex.name);
            if !form.compute {
                structs.push_str(&out_struct(&out_name, chunk.len(), form.depth.is_some()));
            }
            let mut em = Emitter::new(ir, site, pass.reads.clone());
            em.per_sample_pass = per_sample;
            em.split = form.split;
            em.bindings = decl.bindings.clone();
            (form.prelude)(&mut em)?;
            let mut outs = Vec::new();
            for (oi, &layer) in chunk.iter().enumerate() {
                let mut comps = vec!["0.0f".to_string(); 4];
                for slot in res.slots.iter().filter(|s| s.texture == ti && s.layer == layer) {
                    let v = ir.channels[slot.channel]
                        .value
                        .ok_or_else(|| internal(format!("channel `{}` without value", ir.channels[slot.channel].name)))?;
                    let name = em.emit(v)?;
                    // a declared range: the value clamped to it before it is encoded
                    let name = match ir.channels[slot.channel].range {
                        Some((lo, hi)) => format!("clamp({name}, {}, {})", f32_lit(lo as f32), f32_lit(hi as f32)),
                        None => name,
                    };
                    comps[slot.component as usize] = (form.store)(slot, encode_expr(&name, slot.encode))?;
                }
                outs.push(if form.compute {
                    format!(
                        "    textureStore(w_{}, texel, {layer}i, vec4<f32>({}));",
                        tex.name,
                        comps.join(", ")
                    )
                } else {
                    format!("    out.o{oi} = vec4<f32>({});", comps.join(", "))
                });
            }
            if let Some(d) = form.depth {
                outs.push(format!("    out.depth = {d};"));
            }
            let (functions, body) = em.finish(&entry);
            bodies.push_str(&functions);
            if form.compute {
                let g = graph::TEXEL_WORKGROUP;
                let _ = write!(
                    bodies,
                    "\n@compute @workgroup_size({g}, {g})\nfn {entry}({}) {{\n{}{}{}\n}}\n",
                    form.signature,
                    form.head,
                    body,
                    outs.join("\n")
                );
            } else {
                let _ = write!(
                    bodies,
                    "\n@fragment\nfn {entry}({}) -> {out_name} {{\n{}{}    var out: {out_name};\n{}\n    return out;\n}}\n",
                    form.signature,
                    form.head,
                    body,
                    outs.join("\n")
                );
            }
            decl.bindings = em.bindings.clone();
            decl.uses_params |= em.uses_params;
            steps.push((form.step)(entry, &tex.name, &chunk));
        }
    }
    let bindings = decl.graph_bindings();
    for s in &mut steps {
        s.reads = bindings.clone();
        s.params = decl.uses_params;
    }
    Ok(ChannelEntries {
        structs,
        bodies,
        steps,
        decl,
    })
}
