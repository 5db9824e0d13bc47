//! The warnings for raster targets in a format the limits profile cannot render to (the
//! formats themselves are pack's: `pack::texture_format`).

use crate::diag::{Diagnostic, Phase};
use crate::ir::{IrChannel, Program};
use crate::pack::Limits;
use sshc_graph as graph;

/// Warnings for textures a raster step writes in a format the limits profile cannot render
/// to (16-bit norm formats: an adapter-specific feature), naming the channels stored there
/// and the fix; the runtime refuses such a graph on a device without the feature.
pub fn render_target_warnings(ir: &Program, g: &graph::PassGraph, limits: &Limits) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    if limits.renderable_norm16 {
        return out;
    }
    let mut warned: Vec<&str> = Vec::new();
    for p in &g.passes {
        for st in p.steps.iter().filter(|s| !s.draw.is_dispatch()) {
            for w in &st.writes {
                if warned.contains(&w.texture.as_str()) {
                    continue;
                }
                let Some(d) = g.texture(&w.texture) else { continue };
                if !d.format.is_norm16() {
                    continue;
                }
                warned.push(&w.texture);
                // the channels stored there (a filter's intermediate holds its source's)
                let stored: Vec<&IrChannel> = ir
                    .resources
                    .iter()
                    .flat_map(|r| {
                        r.textures
                            .iter()
                            .enumerate()
                            .filter(|(_, t)| t.name == d.name || format!("{}_tmp", t.name) == d.name)
                            .flat_map(move |(ti, _)| r.slots.iter().filter(move |s| s.texture == ti))
                    })
                    .map(|s| &ir.channels[s.channel])
                    .collect();
                let mut names: Vec<String> = Vec::new();
                for c in &stored {
                    let n = format!("`{}`", c.name);
                    if !names.contains(&n) {
                        names.push(n);
                    }
                }
                let mut diag = Diagnostic::warning(
                    Phase::Codegen,
                    format!(
                        "pass `{}` renders {} into {:?}, a 16-bit norm format that WebGPU renders to only with an adapter-specific feature",
                        p.name,
                        names.join(", "),
                        d.format
                    ),
                )
                .help("store them at F16 (or Unorm8, or F32); devices without the feature refuse the graph at load");
                match stored.first() {
                    Some(c) if c.precision_overridden => diag = diag.note("`--precision` set their precision"),
                    Some(c) => diag = diag.at(c.precision_span, "Unorm16 here"),
                    None => {}
                }
                out.push(diag);
            }
        }
    }
    out
}
