//! What the resources of a graph are used as ([`Usages::of`]), from its steps' declared
//! reads and writes and from each step's plan ([`crate::steps::plan`]): the one source of
//! the usages the allocation path ([`crate::resources::Resources::new`]) gives. The type
//! lives with the allocation path: this module reads the steps, which read the resources,
//! and the resources read only the type (no circle of imports).

use crate::graph::{self, PassGraph};
use crate::pipeline::wgpu_format;
use crate::resources::Usages;
use crate::steps::{Dispatch, NodeKind, Targets, plan};

impl Usages {
    pub fn of(graph: &PassGraph) -> Usages {
        use wgpu::TextureUsages as U;
        let mut u = Usages::default();
        for pass in &graph.passes {
            for step in &pass.steps {
                let mut add = |name: &str, usage: U| {
                    if graph.texture(name).is_some_and(|t| wgpu_format(t.format).is_some()) {
                        *u.textures.entry(name.to_string()).or_insert(U::COPY_SRC) |= usage;
                    }
                };
                for b in &step.reads {
                    add(&b.texture, U::TEXTURE_BINDING);
                }
                if pass.kind.is_depth() {
                    for t in &step.writes {
                        add(&t.texture, U::COPY_DST);
                    }
                }
                match plan(step) {
                    NodeKind::Compute(c) => {
                        for t in &c.writes {
                            add(t, U::STORAGE_BINDING);
                        }
                        match c.dispatch {
                            Dispatch::Pixels => u.camera_stored = true,
                            Dispatch::Cells(_) => u.per_cell.extend(c.generated.iter().cloned()),
                            Dispatch::Edges => u.edges = true,
                            Dispatch::Texels | Dispatch::MipTexels | Dispatch::ShadowMapLines | Dispatch::Indirect(_) => {}
                        }
                    }
                    NodeKind::Raster(r) => match &r.targets {
                        Targets::Textures(targets) => {
                            for t in targets {
                                add(&t.texture, U::RENDER_ATTACHMENT);
                            }
                        }
                        Targets::GBuffer => u.gbuffer = true,
                        Targets::Camera(targets) => {
                            for t in targets {
                                add(&t.texture, U::RENDER_ATTACHMENT);
                            }
                        }
                    },
                }
            }
        }
        // a Shade's debug outputs: a host binds them to look at them, as the camera outputs
        for t in graph.textures.iter().filter(|t| t.extent == graph::Extent::Camera) {
            if let Some(usage) = u.textures.get_mut(&t.name) {
                *usage |= U::TEXTURE_BINDING;
            }
        }
        u
    }

    /// The usages of graph texture `name` ([`Usages::textures`]).
    pub fn texture(&self, name: &str) -> wgpu::TextureUsages {
        self.textures.get(name).copied().unwrap_or(wgpu::TextureUsages::COPY_SRC)
    }
}
