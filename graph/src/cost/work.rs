//! The work of a frame: each pass's shader invocations, and its fetches and operations
//! (each step's per-invocation counts, [`crate::Step::cost`], times the invocations that
//! run them).

use crate::cost::sizes::{Sizes, below_base, written_layers};
use crate::{Draw, Extent, PassGraph, Step};

/// The work of one pass in a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct PassWork {
    pub pass: String,
    /// Shader invocations per frame, over all the pass's steps.
    pub invocations: f64,
    /// Fetches (texture reads, table loads) and operations per frame: each step's
    /// per-invocation counts (counted on the naga IR by the compiler) times its invocations.
    pub fetches: f64,
    pub ops: f64,
}

/// A step's invocations in one view, and how many times each runs the counted code: texels
/// for map-side steps (the levels below the base for a mip chain), pixels for the Shade,
/// one per row or column for a summed-area step, whose loop body (counted once) runs once
/// per texel of it in each layer of the table it writes; one per edge of the scene's meshes
/// (`edges`) for a classification, one per cell of the mesh of texel centres for skins.
pub fn invocations(graph: &PassGraph, s: &Step, sizes: Sizes, edges: u64) -> (f64, f64) {
    let texels = sizes.texels(Extent::ShadowMap);
    match &s.draw {
        Draw::SceneFromCamera | Draw::CameraGBuffer | Draw::ComputePixels => (sizes.texels(Extent::Camera), 1.0),
        Draw::SceneFromLight | Draw::FullScreen | Draw::ComputeTexels => (texels, 1.0),
        Draw::MipLevels | Draw::ComputeMipLevels => (below_base(texels), 1.0),
        Draw::ComputeRows | Draw::ComputeColumns => {
            let layers = written_layers(graph, s).unwrap_or(1);
            (f64::from(sizes.shadow), f64::from(sizes.shadow) * f64::from(layers))
        }
        Draw::Silhouettes { .. } => (edges as f64, 1.0),
        Draw::Discontinuities { .. } => {
            let cells = f64::from(sizes.shadow.saturating_sub(1));
            (cells * cells, 1.0)
        }
        // the generated primitives' fragments, which no count of the graph and the sizes
        // gives (`sshc render` prints the vertices drawn)
        Draw::Primitives { .. } => (0.0, 0.0),
    }
}

/// Invocations, fetches and operations per frame of every pass, in the graph's order: its
/// steps' ([`invocations`]), once per light sample for a per-sample pass
/// ([`PassGraph::views_of`]). `edges`: the scene's edges (Geometry passes classify each).
pub fn passes(graph: &PassGraph, sizes: Sizes, edges: u64) -> Vec<PassWork> {
    graph
        .passes
        .iter()
        .map(|p| {
            let mut w = PassWork {
                pass: p.name.clone(),
                invocations: 0.0,
                fetches: 0.0,
                ops: 0.0,
            };
            for s in &p.steps {
                let (n, runs) = invocations(graph, s, sizes, edges);
                w.invocations += n;
                w.fetches += f64::from(s.cost.fetches) * n * runs;
                w.ops += f64::from(s.cost.ops) * n * runs;
            }
            let k = f64::from(graph.views_of(p));
            (w.invocations, w.fetches, w.ops) = (w.invocations * k, w.fetches * k, w.ops * k);
            w
        })
        .collect()
}

/// Fetches and operations of a whole frame: [`passes`] summed.
pub fn total(graph: &PassGraph, sizes: Sizes, edges: u64) -> (f64, f64) {
    passes(graph, sizes, edges)
        .iter()
        .fold((0.0, 0.0), |(f, o), w| (f + w.fetches, o + w.ops))
}
