//! `sshc explain`: the compiled technique in plain words: parameters, passes in order
//! (with the schedule each runs in, as the `schedule` phase recorded it), channels and how
//! they are packed, cost, and what was removed.

use crate::Compiled;
use crate::front::ast::{LightView, Primitive, Resolve};
use crate::ir::{IrPassKind, Origin, Program, short};
use crate::schedule::Choice;
use std::fmt::Write as _;

/// How the technique runs under cascaded shadow maps (the runtime's `bind_cascades`): one
/// compiled graph for every cascade, so what is counted in texels is the same count in each
/// cascade, while what the Frame uniform gives per view (the light's size in the map, a
/// texel's world size) is each cascade's own.
/// The Shade's debug outputs: what this build writes (each texture, its format, its
/// expression after folding), or which ones it leaves out.
fn debug_outputs(s: &mut String, ir: &Program, g: &sshc_graph::PassGraph) {
    if !ir.debug_omitted.is_empty() {
        let _ = writeln!(
            s,
            "\nDebug outputs: {} declared, left out of this build (compile with `--debug`, or `render --dump`, to write them)",
            ir.debug_omitted.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
        );
    }
    if ir.debug.is_empty() {
        return;
    }
    let _ = writeln!(s, "\nDebug outputs (camera-sized textures the Shade writes, unclamped):");
    for d in &ir.debug {
        let format = g.texture(&d.texture).map_or_else(String::new, |t| format!(" ({:?})", t.format));
        let _ = writeln!(s, "  {} -> {}{format} = {}", d.name, d.texture, ir.arena.display(d.expr, Some(ir)));
    }
}

fn cascades(s: &mut String, ir: &Program, g: &sshc_graph::PassGraph) {
    let _ = writeln!(s, "\nUnder cascades (`--cascades N`, a light at infinity):");
    if g.passes.iter().any(|p| p.views.is_per_sample()) {
        let _ = writeln!(
            s,
            "  refused: the per-sample passes render views from points on a local light, and cascades split the view of a light at infinity"
        );
        return;
    }
    let _ = writeln!(
        s,
        "  every pass runs once per cascade on that cascade's view, with this one compiled graph (no variant per cascade)"
    );
    let params: Vec<&str> = ir.params.iter().map(|p| p.name.as_str()).collect();
    let kernels: Vec<String> = ir
        .passes
        .iter()
        .filter(|p| p.live)
        .filter_map(|p| match &p.kind {
            IrPassKind::Filter { kernel } => Some(format!("{} ({kernel:?})", p.name)),
            IrPassKind::Depth { .. }
            | IrPassKind::Map
            | IrPassKind::Mipmap { .. }
            | IrPassKind::SummedArea { .. }
            | IrPassKind::Geometry { .. }
            | IrPassKind::Shade { .. } => None,
        })
        .collect();
    if !params.is_empty() || !kernels.is_empty() {
        let mut what = Vec::new();
        if !kernels.is_empty() {
            what.push(format!("the filter kernels of {}", kernels.join(", ")));
        }
        if !params.is_empty() {
            what.push(format!("the parameters ({})", params.join(", ")));
        }
        let _ = writeln!(
            s,
            "  the same in every cascade: {}; a width in texels covers less of the world in a nearer (finer) cascade",
            what.join(" and ")
        );
    }
    let _ = writeln!(
        s,
        "  each cascade's own: its depth range, a texel's world size and the light's size in its map, so what the Shade computes from them (a search region or penumbra width from the light's size) keeps its world size"
    );
}

pub fn explain(c: &Compiled) -> String {
    let ir = &Program::new(&c.ir, &c.layout);
    let g = &c.graph;
    let mut s = String::new();
    let _ = writeln!(s, "Technique `{}`", ir.technique);
    if !ir.lights.is_empty() {
        let l: Vec<String> = ir.lights.iter().map(|l| format!("{l:?}")).collect();
        let _ = writeln!(s, "Assumes a light of kind: {}", l.join(" or "));
    }
    if !ir.params.is_empty() {
        let _ = writeln!(s, "\nParameters:");
        for p in &ir.params {
            let how = if p.uniform { "runtime uniform" } else { "fixed at compile time" };
            let range = p
                .range
                .map(|(a, b)| format!(", range [{}, {}]", short(a), short(b)))
                .unwrap_or_default();
            let doc = p.doc.as_deref().map(|d| format!(" - {d}")).unwrap_or_default();
            let _ = writeln!(s, "  {} = {} ({how}{range}){doc}", p.name, p.value);
        }
    }
    let _ = writeln!(s, "\nPasses, in execution order:");
    for (i, (pi, p)) in ir.passes.with_handles().filter(|(_, p)| p.live).enumerate() {
        let choice = c.schedules.of(pi);
        let reads: Vec<&str> = p
            .reads
            .iter()
            .filter(|r| ir.resources[**r].live)
            .map(|r| ir.resources[*r].name.as_str())
            .collect();
        let samples = ir.samples;
        let what = match &p.kind {
            IrPassKind::Depth {
                view: LightView::PerSample,
            } => format!(
                "rasterises the scene once from each of the {samples} light samples and stores linear depth, one layer block per sample"
            ),
            IrPassKind::Depth { .. } => "rasterises the scene from the light and stores linear depth".to_string(),
            IrPassKind::Map => format!(
                "computes channels per shadow-map texel ({})",
                schedule(
                    choice,
                    "a full-screen triangle",
                    "8 x 8 texels per workgroup, storage-texture writes"
                )
            ),
            IrPassKind::Filter { kernel } => format!(
                "filters with {kernel:?}{} ({})",
                if kernel.separable() {
                    " (separable: horizontal then vertical)"
                } else {
                    ""
                },
                schedule(
                    choice,
                    "a full-screen triangle per step",
                    "8 x 8 texels per workgroup, each workgroup loading its tile and apron into workgroup memory once per layer"
                )
            ),
            IrPassKind::Mipmap { reduce } => format!(
                "builds a {reduce:?} mip chain in place ({})",
                schedule(
                    choice,
                    "a full-screen triangle per level",
                    "one dispatch per level, 8 x 8 texels per workgroup"
                )
            ),
            IrPassKind::SummedArea { .. } => format!("builds a summed-area table{}", table_sums(ir, p.writes)),
            IrPassKind::Geometry {
                primitive: Primitive::BackFaces,
                keep,
                ..
            } => format!(
                "rasterises the scene's triangles that face away from the light, the nearest kept by a depth test (Lawlor 2006, section 3.1, step 3){}",
                if keep.is_some() {
                    ", fragments failing `keep` discarded"
                } else {
                    ""
                }
            ),
            IrPassKind::Geometry {
                primitive: Primitive::Skins,
                from,
                keep,
                ..
            } => format!(
                "for each of the {samples} light samples, warps the skins of the {} sample's depth discontinuities into its view (Heidrich et al. 2000, section 3.2: a compute step finds them in every cell of the map and appends them; a draw pulls them from the buffer, indirectly), the skin nearest the sample kept by a depth test{}",
                match from {
                    Some(sshc_graph::Neighbour::Next) => "next",
                    _ => "previous",
                },
                if keep.is_some() {
                    ", fragments failing `keep` discarded"
                } else {
                    ""
                }
            ),
            IrPassKind::Geometry {
                primitive, resolve, keep, ..
            } => {
                let buffers: Vec<String> = g
                    .buffers
                    .iter()
                    .filter(|b| {
                        // the buffers its silhouette steps append to (one record per edge)
                        let silhouettes = |st: &sshc_graph::Step| !st.draw.joins_sample_views() && st.draw.appends_to() == Some(b.name.as_str());
                        g.passes.iter().any(|gp| gp.name == p.name && gp.steps.iter().any(silhouettes))
                    })
                    .map(|b| {
                        format!(
                            "buffer `{}`: a {}-byte header (draw arguments, records claimed and dropped) and at most one {}-byte record per edge of the scene's meshes, as many as one storage binding holds, {} vertices drawn per record",
                            b.name,
                            sshc_graph::GENERATED_HEADER_BYTES,
                            b.record_bytes,
                            b.vertices_per_record
                        )
                    })
                    .collect();
                let how = if *resolve == Resolve::Nearest {
                    "the fragment nearest the light kept by a depth test".to_string()
                } else {
                    format!("overlaps resolved by {resolve:?}")
                };
                format!(
                    "generates {primitive:?} at the silhouette edges seen from the light's centre (a compute step classifies every edge and appends a record per silhouette; a draw pulls the primitives from the records, indirectly), {how}{}; {}",
                    if keep.is_some() {
                        ", fragments failing `keep` discarded"
                    } else {
                        ""
                    },
                    buffers.join("; ")
                )
            }
            IrPassKind::Shade { .. } => format!(
                "evaluates visibility per camera pixel; {}",
                match choice {
                    Some(Choice::Fragment) | None => "schedule: fragment (forward), the camera raster's fragments evaluate it".to_string(),
                    Some(Choice::Compute) => "schedule: compute (deferred), a camera raster writes a G-buffer of 32 bytes a pixel (world position and depth slope, normal, uv footprint), then one compute invocation per pixel (8 x 8 per workgroup) evaluates it from there".to_string(),
                    Some(Choice::Refused(why)) => format!("schedule: fragment (forward); compute (deferred) was asked for, but {why}"),
                }
            ),
        };
        let steps = g.passes.iter().find(|gp| gp.name == p.name).map(|gp| gp.steps.len()).unwrap_or(0);
        let _ = write!(s, "  {}. {} ({}): {what}", i + 1, p.name, p.kind_name());
        if !reads.is_empty() {
            let _ = write!(s, "; reads {}", reads.join(", "));
        }
        if let Some(w) = p.writes {
            let _ = write!(s, "; writes {}", ir.resources[w].name);
        }
        let _ = writeln!(s, "; {steps} GPU step(s)");
    }
    if let Some(visibility) = ir.shade_pass().and_then(|p| p.kind.visibility()) {
        let text = ir.arena.display(visibility, Some(ir));
        let shown = if text.len() > 400 {
            format!(
                "{}... ({} characters)",
                &text[..text.char_indices().nth(400).map(|x| x.0).unwrap_or(text.len())],
                text.len()
            )
        } else {
            text
        };
        let _ = writeln!(s, "\nVisibility after lowering and constant folding:\n  {shown}");
    }
    debug_outputs(&mut s, ir, g);
    cascades(&mut s, ir, g);
    let _ = writeln!(s, "\nChannels and packing:");
    for r in ir.resources.iter().filter(|r| r.live) {
        let _ = writeln!(s, "  {}:", r.name);
        for sl in &r.slots {
            let ch = &ir.channels[sl.channel];
            let origin = match ch.origin {
                Origin::Depth => "depth".to_string(),
                Origin::Declared => "declared".to_string(),
                Origin::Basis { expansion, term, k } => format!("basis term {term} of `{}` at k = {k}", ir.expansions[expansion].name),
            };
            let range = sl.range;
            let place = format!(
                "{} layer {} .{}",
                r.textures[sl.texture].name,
                sl.layer,
                ['r', 'g', 'b', 'a'][sl.component as usize]
            );
            let enc = if sl.encode.is_identity() {
                String::new()
            } else {
                format!(", stored as (v - {}) * {}", short(sl.encode.bias), short(sl.encode.scale))
            };
            let _ = writeln!(
                s,
                "    {} ({origin}): {} range {range}{enc} -> {place}",
                ch.name,
                sl.precision.name()
            );
        }
    }
    let _ = writeln!(s, "\nTextures (bytes per shadow-map texel, mip chains count 4/3):");
    for (n, f, l, b) in &c.cost.textures {
        let _ = writeln!(s, "  {n}: {f:?} x {l} layer(s) = {b:.2} B");
    }
    let _ = writeln!(s, "  total: {:.2} B per shadow-map texel", c.cost.bytes_per_texel());
    let _ = writeln!(s, "\nWork per invocation (naga IR counts):");
    for (n, k, steps, oc) in &c.cost.passes {
        let _ = writeln!(s, "  {n} ({k:?}, {steps} step(s)): {} fetches, {} operations", oc.fetches, oc.ops);
    }
    let _ = writeln!(
        s,
        "  per shaded pixel: {} fetches, {} operations",
        c.cost.shade.fetches, c.cost.shade.ops
    );
    if !ir.removed.is_empty() {
        let _ = writeln!(s, "\nRemoved:");
        for r in ir.removed.iter() {
            let _ = writeln!(s, "  {r}");
        }
    }
    rounding_report(&mut s, ir);
    if !c.ir.precision_choices.is_empty() {
        let _ = writeln!(s, "\nPrecisions chosen by the compiler (by range):");
        for p in &c.ir.precision_choices {
            let _ = writeln!(s, "  {p}");
        }
    }
    if let Some(sp) = &c.ir.specialised {
        let _ = writeln!(
            s,
            "\nSpecialised for scene {} (a {} light; the runtime refuses a scene whose light is of another kind):",
            sp.facts.scene,
            sp.facts.light.name()
        );
        for f in &sp.folded {
            let _ = writeln!(s, "  {f}");
        }
    }
    s
}

/// The visibility error the channels' storage rounding causes (`rounding::estimate`).
fn rounding_report(s: &mut String, ir: &Program) {
    use crate::front::ast::Precision;
    if let Some(why) = crate::rounding::unsupported(ir) {
        let _ = writeln!(s, "\nVisibility error from storage rounding: not estimated ({why})");
        return;
    }
    let Some(e) = crate::rounding::estimate(ir, crate::rounding::Detail::Explain) else {
        return;
    };
    let _ = writeln!(
        s,
        "\nVisibility error from storage rounding (a sampled first-order estimate over {} texel and receiver configurations; compiler/src/rounding.rs; warned above {}):",
        e.configurations,
        crate::rounding::WARN_ABOVE
    );
    let heads: Vec<String> = Precision::ALL.iter().map(|p| format!("at {}", p.name())).collect();
    let _ = writeln!(s, "  | channel | stored at | error | {} |", heads.join(" | "));
    let _ = writeln!(s, "  |---|---|---|{}", "---|".repeat(heads.len()));
    for c in &e.channels {
        let at: Vec<String> = c.at.iter().map(|v| v.map_or("-".to_string(), |v| format!("{v:.3e}"))).collect();
        let _ = writeln!(
            s,
            "  | {} | {} | {:.3e} | {} |",
            c.name,
            c.precision.name(),
            c.error,
            at.join(" | ")
        );
    }
    let _ = writeln!(s, "  every channel at its precision: {:.3e}", e.total);
    if e.skipped > 0 {
        let _ = writeln!(s, "  ({} configurations gave no number and were skipped)", e.skipped);
    }
}

/// What specialising for a scene changed (`sshc explain --scene`): per pass, the fetches
/// and operations per invocation of the generic build and of the specialised one, and what
/// elimination removed in the one and not in the other.
pub fn specialisation(generic: &Compiled, specialised: &Compiled) -> String {
    let mut s = String::from("\nSpecialisation against the generic build (per invocation of each pass):\n");
    let _ = writeln!(
        s,
        "  | pass | fetches generic | fetches specialised | operations generic | operations specialised |"
    );
    let _ = writeln!(s, "  |---|---|---|---|---|");
    for (name, _, _, g) in &generic.cost.passes {
        match specialised.cost.passes.iter().find(|p| &p.0 == name) {
            Some((_, _, _, c)) => {
                let _ = writeln!(s, "  | {name} | {} | {} | {} | {} |", g.fetches, c.fetches, g.ops, c.ops);
            }
            None => {
                let _ = writeln!(s, "  | {name} | {} | removed | {} | removed |", g.fetches, g.ops);
            }
        }
    }
    for r in specialised.graph.removed.iter().filter(|r| !generic.graph.removed.contains(r)) {
        let _ = writeln!(s, "  removed besides: {r}");
    }
    s
}

/// How a Map, Filter or Mipmap pass runs, as the `schedule` phase chose: `fragment` and
/// `compute` describe each form; a compute schedule refused says why.
fn schedule(choice: Option<&Choice>, fragment: &str, compute: &str) -> String {
    match choice {
        Some(Choice::Fragment) | None => format!("schedule: fragment, {fragment}"),
        Some(Choice::Compute) => format!("schedule: compute, {compute}"),
        Some(Choice::Refused(why)) => format!("schedule: fragment; compute was asked for, but {why}"),
    }
}

/// What a table over float textures sums, with its stated error (`tables`); empty for
/// unorm codes.
fn table_sums(ir: &crate::ir::Program, table: Option<crate::ir::ResId>) -> String {
    use crate::back::summed_area::{TableCode, table_code};
    let Some(t) = table else {
        return String::new();
    };
    let r = &ir.resources[t];
    let mut parts = Vec::new();
    for (ti, tex) in r.textures.iter().enumerate() {
        let slots: Vec<_> = r.slots.iter().filter(|s| s.texture == ti).collect();
        let width = slots.iter().map(|s| s.range.hi - s.range.lo).fold(0.0, f64::max);
        let n = crate::tables::REFERENCE_SIZE;
        match table_code(ir, t, ti) {
            Ok(TableCode::Codes { fixed: true, scale }) => {
                let bits = (f64::from(scale) + 1.0).log2().round() as u8;
                parts.push(format!(
                    "`{}`: {bits}-bit fixed-point codes over each channel's range, summed exactly in u32 for boxes of up to {} texels (a box is then within half a step, {:.3e} of the widest range, {width:.4})",
                    tex.name,
                    crate::tables::fixed_max_area(bits),
                    0.5 / f64::from(scale)
                ));
            }
            Ok(TableCode::Float) => parts.push(format!(
                "`{}`: f32 sums of the values less each channel's midpoint; at {n} x {n} an entry is within {:.3e} of the f64 sum and a box of A texels within {:.3e} / A (stated bounds, the widest range {width:.4})",
                tex.name,
                crate::tables::f32_entry_bound(n, 0.5 * width),
                crate::tables::f32_box_bound(n, 0.5 * width, 1.0)
            )),
            Ok(TableCode::Codes { fixed: false, .. }) | Err(_) => {}
        }
    }
    if parts.is_empty() {
        String::new()
    } else {
        format!(" ({})", parts.join("; "))
    }
}
