//! The cost report of a compiled technique, from its graph alone: memory per shadow-map
//! texel and work per invocation (`<name>.cost.md`, `sshc explain`).

use crate::{Extent, Format, OpCount, PassGraph, PassKind};
use std::fmt::Write as _;

/// Cost of a compiled technique.
#[derive(Clone, Debug, PartialEq)]
pub struct Cost {
    /// (texture, format, layers, bytes per shadow-map texel including a mip chain's 4/3).
    pub textures: Vec<(String, Format, u32, f64)>,
    /// (pass, kind, steps, fetches and ops summed over one invocation of each step).
    pub passes: Vec<(String, PassKind, usize, OpCount)>,
    /// Per shaded pixel.
    pub shade: OpCount,
}

impl Cost {
    pub fn of(g: &PassGraph) -> Cost {
        // per shadow-map texel: the camera-sized debug outputs are not among them; a
        // per-sample texture holds `layers` per light sample
        let textures = g
            .textures
            .iter()
            .filter(|t| t.extent == Extent::ShadowMap)
            .map(|t| (t.name.clone(), t.format, t.array_layers(), t.texel_bytes()))
            .collect();
        let mut shade = OpCount::default();
        let passes = g
            .passes
            .iter()
            .map(|p| {
                let mut c = OpCount::default();
                for s in &p.steps {
                    c.fetches += s.cost.fetches;
                    c.ops += s.cost.ops;
                }
                if p.kind.is_shade() {
                    shade = c;
                }
                (p.name.clone(), p.kind, p.steps.len(), c)
            })
            .collect();
        Cost { textures, passes, shade }
    }

    /// Bytes per shadow-map texel of all persistent and transient textures.
    pub fn bytes_per_texel(&self) -> f64 {
        self.textures.iter().map(|t| t.3).sum()
    }

    /// Bytes of the shadow-map textures at a map of `shadow` texels a side (a mip chain's
    /// 4/3 not rounded: the allocation is [`crate::TextureDecl::bytes`]).
    pub fn shadow_map_bytes(&self, shadow: u32) -> f64 {
        self.textures.iter().map(|t| t.3 * f64::from(shadow) * f64::from(shadow)).sum()
    }

    pub fn markdown(&self, technique: &str) -> String {
        let mut s = format!(
            "# Cost of `{technique}`\n\nCounted on the naga IR of the generated WGSL (straight-line code: each counted operation runs once per invocation).\n\n## Memory\n\n| texture | format | layers | bytes per shadow-map texel |\n|---|---|---|---|\n"
        );
        for (n, f, l, b) in &self.textures {
            let _ = writeln!(s, "| {n} | {f:?} | {l} | {b:.2} |");
        }
        let _ = writeln!(s, "| **total** | | | **{:.2}** |\n", self.bytes_per_texel());
        s.push_str(
            "## Work\n\n| pass | kind | steps | texture fetches per invocation | operations per invocation |\n|---|---|---|---|---|\n",
        );
        for (n, k, steps, c) in &self.passes {
            let _ = writeln!(s, "| {n} | {k:?} | {steps} | {} | {} |", c.fetches, c.ops);
        }
        let _ = writeln!(
            s,
            "\nPer shaded pixel: {} texture fetches, {} arithmetic operations.",
            self.shade.fetches, self.shade.ops
        );
        s.push_str("Map, Filter and Mipmap passes run once per shadow-map texel and step (Mipmap steps once per level, on a quarter of the texels of the level above).\n");
        s
    }
}
