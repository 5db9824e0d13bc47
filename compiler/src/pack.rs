//! Phase `pack`: dead channel and dead pass elimination (what no shaded pixel can reach
//! is removed, and the reason recorded), then channels are packed into textures: per
//! resource, one 2D-array texture per precision, up to four channels per texel and as
//! many layers as needed, within the limits profile (docs/architecture.md section 7).

use crate::diag::{Diagnostic, Diagnostics, Phase};
use crate::front::ast::{Precision, TableSum};
use crate::handle::Table;
use crate::ir::*;
use sshc_graph as graph;
use std::collections::{HashMap, HashSet};

/// The device limits a technique is compiled against (default: WebGPU's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    pub max_color_attachments: u32,
    pub max_color_attachment_bytes_per_sample: u32,
    pub max_sampled_textures_per_shader_stage: u32,
    pub max_texture_array_layers: u32,
    /// Whether the device renders to 16-bit norm formats (`R16Unorm`, `Rg16Unorm`,
    /// `Rgba16Unorm`): not in WebGPU's core, an adapter-specific feature beyond
    /// `TEXTURE_FORMAT_16BIT_NORM` (lavapipe has it). Where not, a raster pass writing one
    /// is warned about at compile time (`back::formats::render_target_warnings`).
    pub renderable_norm16: bool,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_color_attachments: 8,
            max_color_attachment_bytes_per_sample: 32,
            max_sampled_textures_per_shader_stage: 16,
            max_texture_array_layers: 256,
            renderable_norm16: false,
        }
    }
}

/// Components per texel for a texture holding `n` channels.
pub fn components_for(n: usize) -> u32 {
    match n {
        1 => 1,
        2 => 2,
        _ => 4,
    }
}

/// Bytes of one texel of a texture.
pub fn texel_bytes(p: Precision, components: u32) -> u32 {
    p.bytes() * components
}

/// The precision of a separable filter's intermediate: wide enough that the first axis's
/// result is not rounded to the destination's precision before the second axis.
pub fn scratch_precision(p: Precision) -> Precision {
    match p {
        Precision::Unorm8 => Precision::F16,
        Precision::Unorm16 | Precision::F16 | Precision::F32 => Precision::F32,
    }
}

/// The format a texture is stored in: its precision, with one, two or four components.
pub fn texture_format(t: &Texture) -> graph::Format {
    // a texel of three components is stored in four (WebGPU has no three-component formats)
    let count = match t.components {
        1 | 2 => t.components,
        _ => 4,
    };
    let component = t.precision.component();
    graph::Format::of(component, count).unwrap_or_else(|| unreachable!("every precision has 1-, 2- and 4-component formats"))
}

/// The resources and passes of the IR while `pack` works on them: slots not laid out yet.
struct Working {
    resources: Table<IrResource>,
    passes: Table<IrPass>,
    removed: Vec<String>,
}

/// Remove what the Shade pass cannot reach.
fn eliminate(ir: &Ir, lay: &mut Working) {
    let Some((shade, _)) = lay.passes.with_handles().find(|(_, p)| p.kind.kind().is_shade()) else {
        return;
    };
    let mut live: HashSet<(ResId, ChannelId)> = HashSet::new();
    let mut live_pass = vec![false; lay.passes.len()];
    live_pass[shade.index()] = true;
    if let Some(visibility) = lay.passes[shade].kind.visibility() {
        for h in ir.arena.postorder(&ir.shade_roots(visibility)) {
            if let Node::Sample { channel, resource, .. } = ir.arena.node(h) {
                live.insert((*resource, *channel));
            }
        }
    }
    // Walk writers backwards: passes are in execution order.
    for pi in lay.passes.handles().rev() {
        let Some(w) = lay.passes[pi].writes else { continue };
        let needed: Vec<ChannelId> = lay.resources[w]
            .slots
            .iter()
            .map(|s| s.channel)
            .filter(|c| live.contains(&(w, *c)))
            .collect();
        if needed.is_empty() {
            continue;
        }
        live_pass[pi.index()] = true;
        let reads = lay.passes[pi].reads.clone();
        let carrier = |c: ChannelId| reads.iter().copied().find(|&r| lay.resources[r].slot_of(c).is_some());
        match lay.passes[pi].kind {
            IrPassKind::Map | IrPassKind::Geometry { .. } => {
                let mut roots: Vec<ExprId> = needed.iter().filter_map(|&c| ir.channels[c].value).collect();
                if let IrPassKind::Geometry { keep: Some(k), .. } = lay.passes[pi].kind {
                    roots.push(k);
                }
                for h in ir.arena.postorder(&roots) {
                    if let Node::Channel(c, _) = ir.arena.node(h)
                        && let Some(r) = carrier(*c)
                    {
                        live.insert((r, *c));
                    }
                }
            }
            IrPassKind::Filter { .. } | IrPassKind::Mipmap { .. } | IrPassKind::SummedArea { .. } => {
                for c in needed {
                    if let Some(r) = carrier(c) {
                        live.insert((r, c));
                    }
                }
            }
            IrPassKind::Depth { .. } | IrPassKind::Shade { .. } => {}
        }
    }
    let mut removed = Vec::new();
    for (pi, pass) in lay.passes.with_handles_mut() {
        if !live_pass[pi.index()] {
            pass.live = false;
            removed.push(format!("pass `{}`: no shaded pixel reads what it writes", pass.name));
        }
    }
    for (ri, res) in lay.resources.with_handles_mut() {
        let before = res.slots.len();
        let mut dropped = Vec::new();
        res.slots.retain(|s| {
            let keep = live.contains(&(ri, s.channel));
            if !keep {
                dropped.push(s.channel);
            }
            keep
        });
        if res.slots.is_empty() {
            res.live = false;
            removed.push(format!("resource `{}`: unused", res.name));
        } else if res.slots.len() < before {
            let names: Vec<&str> = dropped.iter().map(|c| ir.channels[*c].name.as_str()).collect();
            removed.push(format!(
                "channels {} of `{}`: no shaded pixel reads them",
                names.join(", "),
                res.name
            ));
        }
    }
    lay.removed.extend(removed);
}

/// A warning for every pass elimination removed ([`eliminate`]'s decision, read from the
/// layout's live flags) whose output no pass reads at all: not a specialisation (a fixed
/// param folding a lookup away leaves the read in place) but a read that goes around the
/// pass, as a Shade reading the resource a Mipmap pass reads instead of the chain it builds
/// (issue 51: `check` said ok, and only `explain` said "Removed"). The warning is at the
/// pass, names the read that bypasses it (a later live pass reading a resource that carries
/// the same channels; line and column from `source`) and offers to read the pass's output.
pub fn removed_pass_warnings(ir: &Ir, layout: &Layout, source: &str) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    for (pi, pass) in layout.passes.with_handles() {
        let Some(w) = pass.writes else { continue };
        if pass.live || layout.passes.iter().any(|q| q.reads.contains(&w)) {
            continue;
        }
        let written = &ir.resources[w];
        let channels: Vec<ChannelId> = written.slots.iter().map(|s| s.channel).collect();
        // the first live pass after it reading another resource with one of its channels
        let bypass = layout
            .passes
            .with_handles()
            .filter(|(qi, q)| q.live && qi.index() > pi.index())
            .find_map(|(_, q)| {
                q.reads.iter().zip(&q.read_spans).find_map(|(&r, &span)| {
                    let shared: Vec<&str> = channels
                        .iter()
                        .filter(|&&c| ir.resources[r].slot_of(c).is_some())
                        .map(|&c| ir.channels[c].name.as_str())
                        .collect();
                    (r != w && !shared.is_empty()).then_some((q, r, span, shared))
                })
            });
        let mut d = Diagnostic::warning(
            Phase::Pack,
            format!(
                "pass `{}` is removed: no pass reads `{}`, the resource it writes",
                pass.name, written.name
            ),
        )
        .at(pass.span, format!("removed: nothing reads `{}`", written.name));
        match bypass {
            Some((q, r, span, shared)) => {
                let (line, col) = crate::span::line_col(source, span.start as usize);
                let list: Vec<String> = shared.iter().map(|c| format!("`{c}`")).collect();
                d = d
                    .also(span, format!("`{}` reads `{}` here, around `{}`", q.name, ir.resources[r].name, pass.name))
                    .note(format!(
                        "`{}` reads `{}` at line {line}, column {col}, which carries {} as `{}` does: its lookups go around pass `{}` and see none of what it does{}",
                        q.name,
                        ir.resources[r].name,
                        list.join(", "),
                        written.name,
                        pass.name,
                        if pass.kind.kind().makes_mip_chain() {
                            " (a texture without mip levels)"
                        } else {
                            ""
                        }
                    ))
                    .help(format!(
                        "read `{}` instead of `{}` in the `reads` of `{}`",
                        written.name, ir.resources[r].name, q.name
                    ))
                    .fix(span, format!("\"{}\"", written.name));
            }
            None => {
                d = d.help(format!("read `{}` in a later pass, or remove pass `{}`", written.name, pass.name));
            }
        }
        out.push(d);
    }
    out
}

/// Lay the live slots out in textures. The IR is only read: the result is a [`Layout`]
/// (resources and passes as laid out, with each slot's range and encoding from
/// `analysis`; what is dead removed, the rest placed).
pub fn pack(ir: &Ir, analysis: &Analysis, limits: &Limits) -> Result<Layout, Diagnostics> {
    let mut lay = Working {
        resources: ir.resources.clone(),
        passes: ir.passes.clone(),
        removed: Vec::new(),
    };
    let mut infos: HashMap<(ResId, ChannelId), SlotInfo> = analysis.slots.clone();
    // Placement of each slot: texture index in its resource, layer, component.
    let mut places: HashMap<(ResId, ChannelId), (usize, u32, u32)> = HashMap::new();
    eliminate(ir, &mut lay);
    let mut diags = Diagnostics::default();
    // A Mipmap pass builds the chain in place: its output shares the textures of its input,
    // which must therefore keep every channel the output needs.
    for pi in lay.passes.handles() {
        if let (true, Some(w), true) = (
            lay.passes[pi].kind.kind().makes_mip_chain(),
            lay.passes[pi].writes,
            lay.passes[pi].live,
        ) {
            let src = lay.passes[pi].reads[0];
            let keep: Vec<ChannelId> = lay.resources[src].slots.iter().map(|s| s.channel).collect();
            let out_slots = lay.resources[src].slots.clone();
            let needed_missing = lay.resources[w].slots.iter().any(|s| !keep.contains(&s.channel));
            debug_assert!(!needed_missing, "mip output needs a channel its input lost");
            // A channel the output does not need keeps the range and encoding of the input.
            for s in &out_slots {
                if lay.resources[w].slot_of(s.channel).is_none()
                    && let Some(info) = infos.get(&(src, s.channel)).copied()
                {
                    infos.insert((w, s.channel), info);
                }
            }
            lay.resources[w].slots = out_slots;
        }
    }
    for ri in lay.resources.handles() {
        if !lay.resources[ri].live {
            continue;
        }
        if let Some(src) = table_source(ir, ri) {
            // A summed-area table sums the unorm codes of its source, texel for texel: same
            // layers and components, its own (u32) storage.
            let textures = lay.resources[src].textures.clone();
            let res = &mut lay.resources[ri];
            let name = res.name.clone();
            let single = textures.len() == 1;
            res.textures = textures
                .into_iter()
                .map(|t| Texture {
                    name: if single {
                        name.clone()
                    } else {
                        format!("{name}_{}", t.precision.name().to_ascii_lowercase())
                    },
                    ..t
                })
                .collect();
            for s in &res.slots {
                if let Some(p) = places.get(&(src, s.channel)).copied() {
                    places.insert((ri, s.channel), p);
                }
                let sum = ir.passes[res.writer].kind.table_sum();
                let channel = &ir.channels[s.channel].name;
                match (s.precision, sum) {
                    // a unorm channel's table sums its codes
                    (Precision::Unorm8 | Precision::Unorm16, Some((how, span))) => diags.push(
                        Diagnostic::error(
                            Phase::Pack,
                            format!(
                                "`sum: {}` sets what a table over a float channel sums, but channel `{channel}` is stored at {}, whose codes table `{}` sums",
                                how.describe(),
                                s.precision.name(),
                                res.name
                            ),
                        )
                        .at(span, "for a float channel")
                        .help("remove `sum:`, or store the channel at F16 or F32"),
                    ),
                    // fixed-point codes span the channel's range
                    (Precision::F16 | Precision::F32, Some((TableSum::Fixed(bits), span))) => {
                        let range = infos.get(&(src, s.channel)).map(|i| i.range);
                        if range.is_none_or(|r| !r.lo.is_finite() || !r.hi.is_finite()) {
                            diags.push(
                                Diagnostic::error(
                                    Phase::Pack,
                                    format!(
                                        "a fixed-point table maps channel `{channel}`'s range onto {bits}-bit codes, and its range is not finite{}",
                                        range.map(|r| format!(" ({r})")).unwrap_or_default()
                                    ),
                                )
                                .at(span, "fixed-point codes")
                                .also(ir.channels[s.channel].span, "declared here")
                                .help("declare the channel's range, `range: (lo, hi)`, or sum it in f32 (`sum: F32`)"),
                            );
                        }
                    }
                    (Precision::F16 | Precision::F32, None | Some((TableSum::F32, _))) | (Precision::Unorm8 | Precision::Unorm16, None) => {}
                }
            }
            continue;
        }
        if let Some(src) = mip_source(ir, ri) {
            // packed identically to its source (processed earlier: passes run in order)
            let textures = lay.resources[src].textures.clone();
            let res = &mut lay.resources[ri];
            res.textures = textures;
            for s in &res.slots {
                if let Some(p) = places.get(&(src, s.channel)).copied() {
                    places.insert((ri, s.channel), p);
                }
            }
            continue;
        }
        let res = &mut lay.resources[ri];
        let mut precisions: Vec<Precision> = res.slots.iter().map(|s| s.precision).collect();
        precisions.sort();
        precisions.dedup();
        let single = precisions.len() == 1;
        res.textures.clear();
        for p in precisions {
            let idx: Vec<usize> = (0..res.slots.len()).filter(|&i| res.slots[i].precision == p).collect();
            let comps = components_for(idx.len());
            let layers = (idx.len() as u32).div_ceil(comps);
            let ti = res.textures.len();
            let name = if single {
                res.name.clone()
            } else {
                format!("{}_{}", res.name, p.name().to_ascii_lowercase())
            };
            if layers > limits.max_texture_array_layers {
                diags.push(
                    Diagnostic::error(
                        Phase::Pack,
                        format!(
                            "resource `{}` needs {layers} texture array layers at {}, above maxTextureArrayLayers = {}",
                            res.name,
                            p.name(),
                            limits.max_texture_array_layers
                        ),
                    )
                    .at(res.span, format!("{} channels of {}", idx.len(), p.name()))
                    .help("lower the series order, or split the channels over several resources"),
                );
            }
            for (j, &i) in idx.iter().enumerate() {
                places.insert((ri, res.slots[i].channel), (ti, j as u32 / comps, j as u32 % comps));
            }
            res.textures.push(Texture {
                name,
                precision: p,
                components: comps,
                layers,
            });
        }
    }
    let Working {
        resources,
        passes,
        removed,
    } = lay;
    let mut placed: Table<PlacedResource, IrResource> = Table::default();
    for (ri, res) in resources.with_handles() {
        let mut slots = Vec::with_capacity(res.slots.len());
        for s in &res.slots {
            let (Some(info), Some(&(texture, layer, component))) = (infos.get(&(ri, s.channel)), places.get(&(ri, s.channel))) else {
                diags.push(
                    Diagnostic::error(
                        Phase::Pack,
                        format!(
                            "internal compiler error: channel `{}` of `{}` was not laid out",
                            ir.channels[s.channel].name, res.name
                        ),
                    )
                    .at(res.span, "here"),
                );
                continue;
            };
            slots.push(PlacedSlot {
                channel: s.channel,
                precision: s.precision,
                range: info.range,
                encode: info.encode,
                texture,
                layer,
                component,
            });
        }
        placed.append(Resource {
            name: res.name.clone(),
            slots,
            writer: res.writer,
            mips: res.mips,
            sat: res.sat,
            span: res.span,
            live: res.live,
            textures: res.textures.clone(),
        });
    }
    let lay = Layout {
        resources: placed,
        passes,
        removed,
    };
    // Sampled textures per shader stage.
    for pass in lay.passes.iter().filter(|p| p.live) {
        let n: usize = pass.reads.iter().map(|&r| lay.resources[r].textures.len()).sum();
        if n as u32 > limits.max_sampled_textures_per_shader_stage {
            diags.push(
                Diagnostic::error(
                    Phase::Pack,
                    format!(
                        "pass `{}` reads {n} textures, above maxSampledTexturesPerShaderStage = {}",
                        pass.name, limits.max_sampled_textures_per_shader_stage
                    ),
                )
                .at(pass.span, "reads too many textures")
                .help("store the channels it reads at fewer precisions, so that they share texture arrays"),
            );
        }
    }
    diags.check()?;
    Ok(lay)
}

/// The resource whose textures a Mipmap output shares.
pub fn mip_source(ir: &Ir, r: ResId) -> Option<ResId> {
    let w = &ir.passes[ir.resources[r].writer];
    w.kind
        .kind()
        .makes_mip_chain()
        .then(|| mip_source(ir, w.reads[0]).unwrap_or(w.reads[0]))
}

/// The resource a SummedArea output sums.
pub fn table_source(ir: &Ir, r: ResId) -> Option<ResId> {
    let w = &ir.passes[ir.resources[r].writer];
    w.kind.kind().makes_table().then(|| w.reads[0])
}

/// How many layers of a texture one render pass can write at once under the limits.
pub fn layers_per_subpass(t: &Texture, limits: &Limits) -> u32 {
    let by_bytes = limits.max_color_attachment_bytes_per_sample / texel_bytes(t.precision, t.components).max(1);
    by_bytes.min(limits.max_color_attachments).max(1)
}
