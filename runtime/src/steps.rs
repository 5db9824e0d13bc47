//! The step nodes: each step of the graph becomes, once at load, a node that owns its
//! pipeline (immutable, shared by every light, view and target set that runs the
//! technique); binding a scene makes its [`StepBinding`]s (bind groups and attachments,
//! kept with the targets, not in the node), and each frame it records itself with them
//! into the command encoder. [`build`] is the one place that reads
//! [`Draw`]: what a step draws or dispatches is decided there and nowhere else.

use crate::device::{Gpu, Result, RuntimeError};
use crate::graph::{self, Binding, Draw, PassGraph, PassKind, Resolve, Target, View};
use crate::pipeline::{
    BindingLayout, ColorTarget, DEPTH_FORMAT, DepthState, GeometryGroup, Pipeline, PipelineKey, Slot, Stages, StepPipeline,
};
use crate::pipeline::{CAMERA_FORMATS, mip_count, wgpu_format};
use crate::resources::Resources;
use std::collections::HashMap;
use std::sync::Arc;

/// The graph's passes as nodes, in execution order.
pub(crate) struct PassNode {
    pub name: String,
    pub kind: PassKind,
    pub steps: Vec<StepNode>,
}

/// One step: its pipeline, what it binds, and what it records.
pub(crate) struct StepNode {
    /// The pass's name (the label of its render and compute passes).
    label: String,
    pipeline: Arc<StepPipeline>,
    /// What it reads (group 1), and as what.
    reads: Vec<(Binding, Slot)>,
    params: bool,
    sampler: bool,
    kind: NodeKind,
    /// Binds the `LightSamples` uniform (group 0, binding 3).
    light_samples: bool,
    /// Views it renders: 1, or one per light sample (`views: PerLightSample`).
    views: u32,
    /// It belongs to a `PerLightSample` pass: each view binds that sample's `Frame`.
    per_sample: bool,
    /// Layers per view of each texture it writes (a per-sample pass writes view k's
    /// layer l at `k * layers + l`).
    view_layers: Vec<u32>,
}

pub(crate) enum NodeKind {
    Raster(RasterStep),
    Compute(ComputeStep),
}

/// A raster step: one render pass per level it writes.
pub(crate) struct RasterStep {
    pub targets: Targets,
    /// Clear colour of each target.
    clear: Vec<wgpu::Color>,
    depth: Option<DepthTarget>,
    pub draw: DrawCall,
    levels: Levels,
    /// How overlapping fragments combine (generated primitives), or none (they replace).
    pub blend: Option<wgpu::BlendState>,
}

pub(crate) enum Targets {
    /// Layers of the graph's textures.
    Textures(Vec<Target>),
    /// The four camera outputs, then the Shade's debug outputs (camera-sized textures).
    Camera(Vec<Target>),
    /// The G-buffer of a deferred Shade.
    GBuffer,
}

#[derive(Clone, Copy)]
pub(crate) enum DepthTarget {
    Light,
    Camera,
}

/// What a raster step draws.
pub(crate) enum DrawCall {
    /// The scene's triangles.
    Scene,
    /// One full-screen triangle (3 vertices, no vertex buffer).
    FullScreenTriangle,
    /// The primitives of a generated buffer, with the draw arguments at its start that a
    /// `Silhouettes` step wrote (`draw_indirect`).
    Generated(String),
}

#[derive(Clone, Copy, PartialEq)]
pub(crate) enum Levels {
    /// Level 0.
    Base,
    /// Levels 1.. of the targets' mip chain, each reading the level above.
    BelowBase,
}

/// A compute step: one compute pass.
pub(crate) struct ComputeStep {
    /// The summed-area tables or storage textures it writes (group 2).
    pub writes: Vec<String>,
    pub dispatch: Dispatch,
    /// The generated buffer a `Silhouettes` step appends to (group 3); its vertex count is
    /// reset before the dispatch.
    pub generated: Option<String>,
}

/// How many workgroups a compute step runs.
pub(crate) enum Dispatch {
    /// One invocation per row (or column) of the shadow map, [`graph::COMPUTE_WORKGROUP`]
    /// per workgroup.
    ShadowMapLines,
    /// One invocation per edge of the scene's meshes, [`graph::COMPUTE_WORKGROUP`] per
    /// workgroup.
    Edges,
    /// One invocation per texel of the shadow map, [`graph::TEXEL_WORKGROUP`] squared per
    /// workgroup.
    Texels,
    /// One dispatch per mip level k >= 1 of the target, one invocation per texel of it.
    MipTexels,
    /// One invocation per camera pixel, [`graph::TEXEL_WORKGROUP`] squared per workgroup.
    Pixels,
    /// One invocation per cell of the mesh of texel centres ((size - 1)^2), x the column
    /// ([`graph::COMPUTE_WORKGROUP`] per workgroup), y the row, over the map of the view's
    /// neighbour `source`; nothing where the view has no such neighbour (the ends of an
    /// open chain of samples).
    Cells(graph::Neighbour),
    /// Arguments in a buffer, written on the GPU (`dispatch_workgroups_indirect`).
    #[expect(dead_code, reason = "the Geometry passes will size their dispatches on the GPU")]
    Indirect(IndirectArgs),
}

/// An indirect argument buffer (draw or dispatch arguments, written by an earlier step).
#[derive(Clone)]
pub(crate) struct IndirectArgs {
    pub buffer: wgpu::Buffer,
    pub offset: u64,
}

/// What binding a scene gives a node, for one light and view: bind groups, attachment
/// views and draw arguments at the targets' sizes.
pub(crate) enum StepBinding {
    Raster {
        /// One render pass per level, its commands in a bundle.
        passes: Vec<RasterPass>,
    },
    Compute {
        group0: wgpu::BindGroup,
        group1: Option<wgpu::BindGroup>,
        group2: Option<wgpu::BindGroup>,
        /// The edge adjacency and the generated buffer of a `Silhouettes` step, one group
        /// per chunk of edges with its number of edges (invocations), and the buffers to
        /// reset (the generated one's header, the vertex claims); a `Discontinuities` step's
        /// one group with its cells.
        geometry: Option<GeometryGroups>,
        /// A `ComputeMipLevels` step: per level k >= 1, group 1 (level k - 1), group 2
        /// (level k, storage) and the level's size; `group1`, `group2` are then unused.
        levels: Vec<(Option<wgpu::BindGroup>, wgpu::BindGroup, u32)>,
        /// A deferred Shade's G-buffer, read at group 3.
        gbuffer: Option<wgpu::BindGroup>,
    },
}

impl StepBinding {
    /// Number of render or compute passes it records per frame (0 for a mip chain of one
    /// level).
    pub fn passes(&self) -> usize {
        match self {
            StepBinding::Raster { passes, .. } => passes.len(),
            StepBinding::Compute { .. } => 1,
        }
    }
}

/// A Geometry compute step's group 3 per chunk, with the invocations of each, and the
/// buffers reset before it (the generated buffer's header, the vertex claims).
type GeometryGroups = (Vec<(wgpu::BindGroup, u32)>, [wgpu::Buffer; 2]);

/// One render pass of a raster step: its attachments, and its commands (the pipeline, the
/// bind groups, the draws) recorded once at binding.
pub(crate) struct RasterPass {
    bundle: wgpu::RenderBundle,
    color: Vec<wgpu::TextureView>,
    depth: Option<wgpu::TextureView>,
    /// What the bundle sets, kept to record it again over a scene's new draws
    /// ([`StepNode::record_draws`]): its bind groups by index, and its attachments' formats.
    groups: Vec<(u32, wgpu::BindGroup)>,
    formats: (Vec<Option<wgpu::TextureFormat>>, Option<wgpu::TextureFormat>),
}

/// What every step's group 0 binds.
pub(crate) struct Group0<'a> {
    pub light_samples: &'a wgpu::Buffer,
    pub params: Option<&'a wgpu::Buffer>,
    pub sampler: &'a wgpu::Sampler,
}

/// Timestamp writes for the start and the end of a node's work.
#[derive(Clone, Copy)]
pub(crate) struct Stamps<'a> {
    pub set: &'a wgpu::QuerySet,
    pub begin: Option<u32>,
    pub end: Option<u32>,
}

/// The colour attachments a render pass may have (WebGPU's `maxColorAttachments`; a
/// Shade's camera outputs and debug outputs come to at most this).
const MAX_COLOR_ATTACHMENTS: usize = 8;

const WHITE: wgpu::Color = wgpu::Color {
    r: 1.0,
    g: 1.0,
    b: 1.0,
    a: 1.0,
};
const NAN: wgpu::Color = wgpu::Color {
    r: f64::NAN,
    g: f64::NAN,
    b: f64::NAN,
    a: f64::NAN,
};
/// Where the camera sees no surface: visibility 1, a dark background, position and normal NaN.
const CAMERA_CLEAR: [wgpu::Color; 4] = [
    wgpu::Color {
        r: 1.0,
        g: 0.0,
        b: 0.0,
        a: 1.0,
    },
    wgpu::Color {
        r: 0.02,
        g: 0.02,
        b: 0.03,
        a: 1.0,
    },
    NAN,
    NAN,
];
/// The G-buffer where the camera sees no surface: world w = -1 (see [`graph::GBUFFER`]).
const GBUFFER_CLEAR: [wgpu::Color; 3] = [
    wgpu::Color {
        r: 0.0,
        g: 0.0,
        b: 0.0,
        a: -1.0,
    },
    wgpu::Color::TRANSPARENT,
    wgpu::Color::TRANSPARENT,
];

/// What a step is, decided from its [`Draw`]: the runtime's one match on `Draw`. Plain
/// data, no device: [`build`] turns it into a node with a pipeline, the resources take
/// their usages from it ([`Usages`]) and [`crate::gpu::Requirements`] its attachments,
/// bindings and workgroups.
pub(crate) fn plan(step: &graph::Step) -> NodeKind {
    let n = step.writes.len();
    let raster = |targets, clear, depth, draw, levels| {
        NodeKind::Raster(RasterStep {
            targets,
            clear,
            depth,
            draw,
            levels,
            blend: None,
        })
    };
    match &step.draw {
        Draw::SceneFromLight => raster(
            Targets::Textures(step.writes.clone()),
            // no occluder: the far plane
            vec![WHITE; n],
            Some(DepthTarget::Light),
            DrawCall::Scene,
            Levels::Base,
        ),
        Draw::SceneFromCamera => raster(
            Targets::Camera(step.writes.clone()),
            // debug outputs: NaN where the camera sees no surface, as the position
            CAMERA_CLEAR.iter().copied().chain(std::iter::repeat_n(NAN, n)).collect(),
            Some(DepthTarget::Camera),
            DrawCall::Scene,
            Levels::Base,
        ),
        Draw::CameraGBuffer => raster(
            Targets::GBuffer,
            GBUFFER_CLEAR.to_vec(),
            Some(DepthTarget::Camera),
            DrawCall::Scene,
            Levels::Base,
        ),
        Draw::ComputePixels => NodeKind::Compute(ComputeStep {
            // the debug outputs, stored after the camera outputs
            writes: step.writes.iter().map(|t| t.texture.clone()).collect(),
            dispatch: Dispatch::Pixels,
            generated: None,
        }),
        Draw::FullScreen => raster(
            Targets::Textures(step.writes.clone()),
            vec![wgpu::Color::TRANSPARENT; n],
            None,
            DrawCall::FullScreenTriangle,
            Levels::Base,
        ),
        Draw::MipLevels => raster(
            Targets::Textures(step.writes.clone()),
            vec![wgpu::Color::TRANSPARENT; n],
            None,
            DrawCall::FullScreenTriangle,
            Levels::BelowBase,
        ),
        Draw::ComputeRows | Draw::ComputeColumns => NodeKind::Compute(ComputeStep {
            writes: step.writes.iter().map(|t| t.texture.clone()).collect(),
            dispatch: Dispatch::ShadowMapLines,
            generated: None,
        }),
        Draw::ComputeTexels => NodeKind::Compute(ComputeStep {
            writes: step.writes.iter().map(|t| t.texture.clone()).collect(),
            dispatch: Dispatch::Texels,
            generated: None,
        }),
        Draw::ComputeMipLevels => NodeKind::Compute(ComputeStep {
            writes: step.writes.iter().map(|t| t.texture.clone()).collect(),
            dispatch: Dispatch::MipTexels,
            generated: None,
        }),
        Draw::Silhouettes { buffer } => NodeKind::Compute(ComputeStep {
            writes: step.writes.iter().map(|t| t.texture.clone()).collect(),
            dispatch: Dispatch::Edges,
            generated: Some(buffer.clone()),
        }),
        Draw::Discontinuities { buffer, source } => NodeKind::Compute(ComputeStep {
            writes: step.writes.iter().map(|t| t.texture.clone()).collect(),
            dispatch: Dispatch::Cells(*source),
            generated: Some(buffer.clone()),
        }),
        Draw::Primitives { buffer, resolve } => {
            let (clear, blend) = resolve_state(*resolve);
            // A depth test: the light's depth attachment (cleared to 1), no blending.
            let depth = (*resolve == Resolve::Nearest).then_some(DepthTarget::Light);
            // blending 32-bit floats is a feature: `Requirements` checks it
            NodeKind::Raster(RasterStep {
                targets: Targets::Textures(step.writes.clone()),
                clear: vec![clear; n],
                depth,
                draw: DrawCall::Generated(buffer.clone()),
                levels: Levels::Base,
                blend,
            })
        }
    }
}

/// The group 3 layout a step's plan binds (Geometry passes and a deferred Shade).
pub(crate) fn geometry_group(kind: &NodeKind) -> Option<GeometryGroup> {
    match kind {
        NodeKind::Compute(c) => match (&c.dispatch, &c.generated) {
            (Dispatch::Edges, Some(_)) => Some(GeometryGroup::Classify),
            (Dispatch::Cells(_), Some(_)) => Some(GeometryGroup::Discontinuities),
            (Dispatch::Pixels, _) => Some(GeometryGroup::GBuffer),
            (
                Dispatch::ShadowMapLines
                | Dispatch::Edges
                | Dispatch::Texels
                | Dispatch::MipTexels
                | Dispatch::Cells(_)
                | Dispatch::Indirect(_),
                _,
            ) => None,
        },
        NodeKind::Raster(r) => match r.draw {
            DrawCall::Generated(_) => Some(GeometryGroup::Draw),
            DrawCall::Scene | DrawCall::FullScreenTriangle => None,
        },
    }
}

/// Build the node of every step: decide from its [`Draw`] what it records, check what it
/// binds against the graph and the device, and build (or find) its pipeline.
pub(crate) fn build(gpu: &Gpu, graph: &PassGraph, sources: &HashMap<String, Arc<str>>) -> Result<Vec<PassNode>> {
    let mut passes = Vec::new();
    for pass in &graph.passes {
        let source = sources
            .get(&pass.shader)
            .ok_or_else(|| RuntimeError::NotFound(format!("no source for shader `{}`", pass.shader)))?;
        let mut steps = Vec::new();
        for step in &pass.steps {
            let texture_format = |name: &str| {
                let t = graph
                    .texture(name)
                    .ok_or_else(|| RuntimeError::NotFound(format!("no texture `{name}`")))?;
                wgpu_format(t.format).ok_or_else(|| RuntimeError::NotFound(format!("texture `{name}` has no texture format")))
            };
            let is_table = |name: &str| graph.texture(name).is_some_and(|t| t.format.is_table());
            let kind = plan(step);
            if let NodeKind::Raster(r) = &kind
                && let Targets::Textures(t) = &r.targets
            {
                for t in t {
                    texture_format(&t.texture)?;
                }
            }
            // What the step reads (group 1).
            let mut reads = Vec::new();
            for b in &step.reads {
                if is_table(&b.texture) {
                    reads.push((b.binding, Slot::Buffer { read_only: true }));
                    continue;
                }
                // the texture exists (filtering 32-bit floats is a feature: `Requirements`)
                texture_format(&b.texture)?;
                let below_base = matches!(&kind, NodeKind::Raster(r) if r.levels == Levels::BelowBase)
                    || matches!(&kind, NodeKind::Compute(c) if matches!(c.dispatch, Dispatch::MipTexels));
                if b.view == View::PreviousLevel && !below_base {
                    return Err(RuntimeError::NotFound(format!(
                        "pass `{}` reads `{}` at the previous mip level outside a MipLevels step",
                        pass.name, b.texture
                    )));
                }
                reads.push((b.binding, Slot::Texture { filterable: step.sampler }));
            }
            let stages = match &kind {
                NodeKind::Raster(r) => Stages::Raster {
                    vertex: step.vertex.clone(),
                    fragment: step.fragment.clone(),
                    scene_vertices: matches!(r.draw, DrawCall::Scene),
                    targets: match &r.targets {
                        Targets::Camera(t) => CAMERA_FORMATS
                            .iter()
                            .copied()
                            .map(Ok)
                            .chain(t.iter().map(|t| texture_format(&t.texture)))
                            .collect::<Result<Vec<_>>>()?,
                        Targets::GBuffer => graph::GBUFFER.iter().filter_map(|f| wgpu_format(*f)).collect(),
                        Targets::Textures(t) => t.iter().map(|t| texture_format(&t.texture)).collect::<Result<_>>()?,
                    }
                    .into_iter()
                    .map(|format| ColorTarget { format, blend: r.blend })
                    .collect(),
                    depth: r.depth.map(|_| DepthState {
                        format: DEPTH_FORMAT,
                        compare: wgpu::CompareFunction::Less,
                        write: true,
                    }),
                },
                NodeKind::Compute(c) => {
                    // a `ComputeTexels` step stores into textures (of storage formats:
                    // `PassGraph::from_ron` checks), and a `ComputePixels` step into its debug
                    // outputs; the others into tables
                    let texels = matches!(c.dispatch, Dispatch::Texels | Dispatch::MipTexels | Dispatch::Pixels);
                    if let Some(w) = c.writes.iter().find(|w| is_table(w) == texels) {
                        let what = if texels { "a summed-area table" } else { "not a summed-area table" };
                        return Err(RuntimeError::NotFound(format!(
                            "a compute step of pass `{}` writes `{w}`, which is {what}",
                            pass.name
                        )));
                    }
                    Stages::Compute {
                        entry: step.compute.clone(),
                    }
                }
            };
            let writes = match &kind {
                NodeKind::Compute(c) if matches!(c.dispatch, Dispatch::Texels | Dispatch::MipTexels) => c
                    .writes
                    .iter()
                    .map(|w| texture_format(w).map(|format| Slot::StorageTexture { format }))
                    .collect::<Result<_>>()?,
                // the camera outputs, then the debug outputs, stored per pixel
                NodeKind::Compute(c) if matches!(c.dispatch, Dispatch::Pixels) => CAMERA_FORMATS
                    .iter()
                    .map(|&format| Ok(Slot::StorageTexture { format }))
                    .chain(
                        c.writes
                            .iter()
                            .map(|w| texture_format(w).map(|format| Slot::StorageTexture { format })),
                    )
                    .collect::<Result<_>>()?,
                NodeKind::Compute(c) => vec![Slot::Buffer { read_only: false }; c.writes.len()],
                NodeKind::Raster(_) => vec![],
            };
            let key = PipelineKey {
                source: source.clone(),
                stages,
                layout: BindingLayout {
                    params: step.params,
                    sampler: step.sampler,
                    light_samples: step.light_samples,
                    reads,
                    writes,
                    geometry: geometry_group(&kind),
                },
            };
            let label = format!("pipeline of pass `{}` ({:?})", pass.name, step.fragment);
            steps.push(StepNode {
                label: pass.name.clone(),
                pipeline: gpu.pipeline(&key, &label)?,
                reads: step.reads.iter().cloned().zip(key.layout.reads.iter().map(|r| r.1)).collect(),
                params: step.params,
                sampler: step.sampler,
                kind,
                light_samples: step.light_samples,
                views: graph.views_of(pass),
                per_sample: pass.views.is_per_sample(),
                view_layers: step
                    .writes
                    .iter()
                    .map(|w| graph.texture(&w.texture).map_or(1, |t| t.layers))
                    .collect(),
            });
        }
        passes.push(PassNode {
            name: pass.name.clone(),
            kind: pass.kind,
            steps,
        });
    }
    Ok(passes)
}

impl StepNode {
    /// Create the bind groups, attachment views and draw arguments at `res`'s sizes: one
    /// [`StepBinding`] per view.
    pub fn bind(&self, gpu: &Gpu, res: &Resources, shared: &Group0) -> Result<Vec<StepBinding>> {
        (0..self.views).map(|view| self.bind_view(gpu, res, shared, view)).collect()
    }

    /// What view `view` binds: its `Frame` and its layers of the targets (a pass of one
    /// view binds the centre's `Frame` and layer 0's block).
    fn bind_view(&self, gpu: &Gpu, res: &Resources, shared: &Group0, view: u32) -> Result<StepBinding> {
        let frame = if self.per_sample {
            res.sample_frame(view as usize).ok_or_else(|| {
                RuntimeError::Param(format!(
                    "pass `{}` renders light sample {view}, but the scene gives {} sample view(s)",
                    self.label, res.samples
                ))
            })?
        } else {
            res.centre_frame()
        };
        let group0 = self.group0(gpu, shared, frame)?;
        let bound = match &self.kind {
            NodeKind::Raster(r) => {
                let levels = match r.levels {
                    Levels::Base => 0..1,
                    Levels::BelowBase => 1..mip_count(res.shadow_size),
                };
                // per level: group 1, the colour attachments and their formats, the depth
                let mut levels_bound = Vec::new();
                for level in levels {
                    let view_of = |t: &wgpu::Texture, d: &wgpu::TextureViewDescriptor| (t.create_view(d), t.format());
                    let color: Vec<(wgpu::TextureView, wgpu::TextureFormat)> = match &r.targets {
                        Targets::Camera(t) => res
                            .camera
                            .iter()
                            .map(|t| Ok(view_of(t, &Default::default())))
                            .chain(t.iter().map(|w| res.texture(&w.texture).map(|t| view_of(t, &Default::default()))))
                            .collect::<Result<_>>()?,
                        Targets::GBuffer => res.gbuffer.iter().map(|t| view_of(t, &Default::default())).collect(),
                        Targets::Textures(ts) => ts
                            .iter()
                            .zip(&self.view_layers)
                            .map(|(w, per)| {
                                res.texture(&w.texture).map(|t| {
                                    view_of(
                                        t,
                                        &wgpu::TextureViewDescriptor {
                                            dimension: Some(wgpu::TextureViewDimension::D2),
                                            base_array_layer: view * per + w.layer,
                                            array_layer_count: Some(1),
                                            base_mip_level: level,
                                            mip_level_count: Some(1),
                                            ..Default::default()
                                        },
                                    )
                                })
                            })
                            .collect::<Result<_>>()?,
                    };
                    let depth = r.depth.map(|d| match d {
                        DepthTarget::Light => view_of(&res.light_depth, &Default::default()),
                        DepthTarget::Camera => view_of(&res.camera_depth, &Default::default()),
                    });
                    levels_bound.push((self.group1(gpu, res, level)?, color, depth));
                }
                // Seen from the light, only the shadow casters are drawn.
                let from_light = matches!(r.depth, Some(DepthTarget::Light));
                let vertices = matches!(r.draw, DrawCall::Scene).then(|| (res.draw.clone(), from_light));
                let (geometry, indirect) = match &r.draw {
                    DrawCall::Generated(name) => {
                        let buf = res.generated(name)?;
                        let g1 = if self.reads.is_empty() {
                            Some(self.empty_group(gpu, 1)?)
                        } else {
                            None
                        };
                        let g2 = self.empty_group(gpu, 2)?;
                        let g3 = self.group3(gpu, &[(4, buf.as_entire_binding())])?;
                        (Some((g1, g2, g3)), Some(buf.clone()))
                    }
                    DrawCall::Scene | DrawCall::FullScreenTriangle => (None, None),
                };
                let Pipeline::Render(pipeline) = &self.pipeline.pipeline else {
                    return Err(self.mismatch());
                };
                // Each level's commands, recorded once into a render bundle: a frame records
                // a pass and one bundle, not the pipeline, every group and every draw again
                // (docs/embedding.md, "Host CPU").
                let passes = levels_bound
                    .into_iter()
                    .map(|(group1, color, depth)| {
                        let mut groups = vec![(0, group0.clone())];
                        groups.extend(group1.map(|g| (1, g)));
                        if let Some((g1, g2, g3)) = &geometry {
                            groups.extend(g1.clone().map(|g| (1, g)));
                            groups.extend([(2, g2.clone()), (3, g3.clone())]);
                        }
                        let formats = (color.iter().map(|c| Some(c.1)).collect(), depth.as_ref().map(|d| d.1));
                        let bundle = self.bundle(gpu, pipeline, &groups, &formats, |be| match &r.draw {
                            DrawCall::Scene => {
                                if let Some((draw, from_light)) = &vertices {
                                    draw.record(be, *from_light);
                                }
                            }
                            DrawCall::FullScreenTriangle => be.draw(0..3, 0..1),
                            DrawCall::Generated(_) => {
                                if let Some(buffer) = &indirect {
                                    be.draw_indirect(buffer, 0);
                                }
                            }
                        });
                        RasterPass {
                            bundle,
                            color: color.into_iter().map(|c| c.0).collect(),
                            depth: depth.map(|d| d.0),
                            groups,
                            formats,
                        }
                    })
                    .collect();
                StepBinding::Raster { passes }
            }
            NodeKind::Compute(c) => {
                // the storage view of every written texture at one mip level, all layers
                let storage = |level: u32| -> Result<Option<wgpu::BindGroup>> {
                    let Some(layout) = &self.pipeline.group2 else { return Ok(None) };
                    let mut views = Vec::new();
                    for w in &c.writes {
                        views.push(res.texture(w)?.create_view(&wgpu::TextureViewDescriptor {
                            dimension: Some(wgpu::TextureViewDimension::D2Array),
                            base_mip_level: level,
                            mip_level_count: Some(1),
                            ..Default::default()
                        }));
                    }
                    let entries: Vec<wgpu::BindGroupEntry> = views
                        .iter()
                        .enumerate()
                        .map(|(i, v)| wgpu::BindGroupEntry {
                            binding: i as u32,
                            resource: wgpu::BindingResource::TextureView(v),
                        })
                        .collect();
                    Ok(Some(gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: None,
                        layout,
                        entries: &entries,
                    })))
                };
                let mut levels = Vec::new();
                if matches!(c.dispatch, Dispatch::MipTexels) {
                    for level in 1..mip_count(res.shadow_size) {
                        let g2 = storage(level)?.ok_or_else(|| {
                            RuntimeError::NotFound(format!("pass `{}`: a mip chain's compute step without storage", self.label))
                        })?;
                        levels.push((self.group1(gpu, res, level)?, g2, (res.shadow_size >> level).max(1)));
                    }
                }
                let group2 = match &self.pipeline.group2 {
                    // a mip chain binds each level's storage view (`levels`)
                    _ if matches!(c.dispatch, Dispatch::MipTexels) => None,
                    // the camera outputs, then the debug outputs, as one-layer arrays
                    Some(layout) if matches!(c.dispatch, Dispatch::Pixels) => {
                        let array = |t: &wgpu::Texture| {
                            t.create_view(&wgpu::TextureViewDescriptor {
                                dimension: Some(wgpu::TextureViewDimension::D2Array),
                                ..Default::default()
                            })
                        };
                        let views: Vec<wgpu::TextureView> = res
                            .camera
                            .iter()
                            .map(|t| Ok(array(t)))
                            .chain(c.writes.iter().map(|w| res.texture(w).map(array)))
                            .collect::<Result<_>>()?;
                        Some(bind_views(gpu, layout, &views))
                    }
                    None => None,
                    Some(layout) => {
                        let mut entries = Vec::new();
                        // storage textures: the base level, every layer
                        let mut views = Vec::new();
                        if matches!(c.dispatch, Dispatch::Texels) {
                            for w in &c.writes {
                                views.push(res.texture(w)?.create_view(&wgpu::TextureViewDescriptor {
                                    dimension: Some(wgpu::TextureViewDimension::D2Array),
                                    base_mip_level: 0,
                                    mip_level_count: Some(1),
                                    ..Default::default()
                                }));
                            }
                        }
                        for (i, w) in c.writes.iter().enumerate() {
                            entries.push(wgpu::BindGroupEntry {
                                binding: i as u32,
                                resource: match views.get(i) {
                                    Some(v) => wgpu::BindingResource::TextureView(v),
                                    None => res.table(w)?.as_entire_binding(),
                                },
                            });
                        }
                        Some(gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                            label: None,
                            layout,
                            entries: &entries,
                        }))
                    }
                };
                let geometry = match (&c.generated, &c.dispatch) {
                    (Some(name), Dispatch::Cells(_)) => {
                        let buf = res.generated(name)?;
                        let g3 = self.group3(gpu, &[(3, buf.as_entire_binding())])?;
                        let cells = res.shadow_size.saturating_sub(1);
                        Some((vec![(g3, cells)], [buf.clone(), buf.clone()]))
                    }
                    (Some(name), _) => {
                        // the edges in chunks of at most one binding each: the shader's
                        // `arrayLength(&cs_edges)` is its chunk's, and an edge names its
                        // faces and welded vertices by their indices in the whole scene
                        let (e, buf) = (res.edges()?, res.generated(name)?);
                        let (total, chunk) = (u64::from(e.extent), res.edges_per_chunk.max(1));
                        let mut groups = Vec::new();
                        for first in (0..total.max(1)).step_by(chunk as usize) {
                            let n = chunk.min(total - first.min(total));
                            let edges = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                buffer: &e.edges,
                                offset: first * 48,
                                // an empty scene binds one edge-sized slot (the buffer's least)
                                size: wgpu::BufferSize::new(n.max(1) * 48),
                            });
                            let g3 = self.group3(
                                gpu,
                                &[
                                    (0, edges),
                                    (1, e.planes.as_entire_binding()),
                                    (2, e.edge_faces.as_entire_binding()),
                                    (3, buf.as_entire_binding()),
                                    (5, e.claims.as_entire_binding()),
                                ],
                            )?;
                            groups.push((g3, n as u32));
                        }
                        Some((groups, [buf.clone(), e.claims.clone()]))
                    }
                    (None, _) => None,
                };
                // a deferred Shade's G-buffer (group 3)
                let gbuffer = match (&c.dispatch, &self.pipeline.group3) {
                    (Dispatch::Pixels, Some(layout)) => {
                        if res.gbuffer.is_empty() {
                            return Err(RuntimeError::NotFound(format!("pass `{}`: no G-buffer was allocated", self.label)));
                        }
                        let views: Vec<wgpu::TextureView> = res.gbuffer.iter().map(|t| t.create_view(&Default::default())).collect();
                        Some(bind_views(gpu, layout, &views))
                    }
                    _ => None,
                };
                StepBinding::Compute {
                    group0,
                    group1: self.group1(gpu, res, 0)?,
                    group2,
                    geometry,
                    levels,
                    gbuffer,
                }
            }
        };
        Ok(bound)
    }

    fn group0(&self, gpu: &Gpu, shared: &Group0, frame: wgpu::BindingResource) -> Result<wgpu::BindGroup> {
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: frame,
        }];
        if self.light_samples {
            entries.push(wgpu::BindGroupEntry {
                binding: 3,
                resource: shared.light_samples.as_entire_binding(),
            });
        }
        if self.params {
            let buf = shared
                .params
                .ok_or_else(|| RuntimeError::NotFound("step binds params, but the graph has none".into()))?;
            entries.push(wgpu::BindGroupEntry {
                binding: 1,
                resource: buf.as_entire_binding(),
            });
        }
        if self.sampler {
            entries.push(wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::Sampler(shared.sampler),
            });
        }
        Ok(gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &self.pipeline.group0,
            entries: &entries,
        }))
    }

    /// Group 3 of a Geometry pass's step: (binding, buffer) pairs.
    fn group3(&self, gpu: &Gpu, buffers: &[(u32, wgpu::BindingResource<'_>)]) -> Result<wgpu::BindGroup> {
        let layout = self
            .pipeline
            .group3
            .as_ref()
            .ok_or_else(|| RuntimeError::NotFound(format!("pass `{}`: a Geometry step without its group 3", self.label)))?;
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .map(|(binding, b)| wgpu::BindGroupEntry {
                binding: *binding,
                resource: b.clone(),
            })
            .collect();
        Ok(gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("geometry"),
            layout,
            entries: &entries,
        }))
    }

    /// An empty group 1 or 2, keeping a raster step's group 3 at its index.
    fn empty_group(&self, gpu: &Gpu, index: u32) -> Result<wgpu::BindGroup> {
        let layout = if index == 1 { &self.pipeline.group1 } else { &self.pipeline.group2 };
        layout
            .as_ref()
            .map(|layout| {
                gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: None,
                    layout,
                    entries: &[],
                })
            })
            .ok_or_else(|| RuntimeError::NotFound(format!("pass `{}`: a Geometry step without group {index}", self.label)))
    }

    /// What the step reads, for writing mip level `level`.
    fn group1(&self, gpu: &Gpu, res: &Resources, level: u32) -> Result<Option<wgpu::BindGroup>> {
        let Some(layout) = &self.pipeline.group1 else { return Ok(None) };
        let mut views = Vec::new();
        let mut tables = Vec::new();
        for (b, slot) in &self.reads {
            if let Slot::Buffer { .. } = slot {
                tables.push((b.binding, res.table(&b.texture)?));
                continue;
            }
            let t = res.texture(&b.texture)?;
            let (base, count) = match b.view {
                View::All => (0, None),
                View::Base => (0, Some(1)),
                // checked at load: only in steps writing levels 1..
                View::PreviousLevel => (level.saturating_sub(1), Some(1)),
            };
            views.push((
                b.binding,
                t.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2Array),
                    base_mip_level: base,
                    mip_level_count: count,
                    ..Default::default()
                }),
            ));
        }
        let mut entries: Vec<wgpu::BindGroupEntry> = views
            .iter()
            .map(|(binding, v)| wgpu::BindGroupEntry {
                binding: *binding,
                resource: wgpu::BindingResource::TextureView(v),
            })
            .collect();
        entries.extend(tables.into_iter().map(|(binding, b)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        }));
        Ok(Some(gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout,
            entries: &entries,
        })))
    }

    /// Whether the node rasterises the deferred Shade's G-buffer (what a host's pixels
    /// replace).
    pub fn draws_gbuffer(&self) -> bool {
        matches!(&self.kind, NodeKind::Raster(r) if matches!(r.targets, Targets::GBuffer))
    }

    /// Views the node records (one per light sample in a per-sample pass).
    pub fn views(&self) -> u32 {
        self.views
    }

    /// Record the node's passes; `stamps.begin` goes to its first pass, `stamps.end` to its last.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        bound: &StepBinding,
        res: &Resources,
        stamps: Option<Stamps>,
        view: u32,
    ) -> Result<()> {
        match (&self.kind, bound, &self.pipeline.pipeline) {
            (NodeKind::Raster(r), StepBinding::Raster { passes }, Pipeline::Render(_)) => {
                let last = passes.len().saturating_sub(1);
                for (i, p) in passes.iter().enumerate() {
                    let timestamp_writes = stamps
                        .map(|s| wgpu::RenderPassTimestampWrites {
                            query_set: s.set,
                            beginning_of_pass_write_index: s.begin.filter(|_| i == 0),
                            end_of_pass_write_index: s.end.filter(|_| i == last),
                        })
                        .filter(|t| t.beginning_of_pass_write_index.is_some() || t.end_of_pass_write_index.is_some());
                    // on the stack (WebGPU's 8 colour attachments at most): nothing is
                    // allocated per frame
                    let mut attachments: [Option<wgpu::RenderPassColorAttachment>; MAX_COLOR_ATTACHMENTS] = Default::default();
                    for (slot, (view, clear)) in attachments.iter_mut().zip(p.color.iter().zip(&r.clear)) {
                        *slot = Some(wgpu::RenderPassColorAttachment {
                            view,
                            depth_slice: None,
                            resolve_target: None,
                            ops: wgpu::Operations {
                                load: wgpu::LoadOp::Clear(*clear),
                                store: wgpu::StoreOp::Store,
                            },
                        });
                    }
                    let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some(&self.label),
                        color_attachments: &attachments[..p.color.len().min(MAX_COLOR_ATTACHMENTS)],
                        depth_stencil_attachment: p.depth.as_ref().map(|view| wgpu::RenderPassDepthStencilAttachment {
                            view,
                            depth_ops: Some(wgpu::Operations {
                                load: wgpu::LoadOp::Clear(1.0),
                                store: wgpu::StoreOp::Store,
                            }),
                            stencil_ops: None,
                        }),
                        timestamp_writes,
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                    rp.execute_bundles(std::iter::once(&p.bundle));
                }
                Ok(())
            }
            (NodeKind::Compute(_), StepBinding::Compute { .. }, Pipeline::Compute(_)) => {
                self.clear_generated(encoder, bound);
                let mut cpass = begin_compute(encoder, &self.label, stamps);
                self.dispatch(&mut cpass, bound, res, view)
            }
            _ => Err(self.mismatch()),
        }
    }

    /// The buffers a compute step resets before its pass (a Geometry step's generated
    /// buffer header and vertex claims); `false` when it has none, so that it can join the
    /// compute pass of the step before it ([`crate::targets::Targets::record`]).
    pub fn resets_buffers(bound: &StepBinding) -> bool {
        matches!(bound, StepBinding::Compute { geometry: Some(_), .. })
    }

    /// The pass's name (the label of its render and compute passes).
    pub fn label(&self) -> &str {
        &self.label
    }

    /// Whether a compute step has nothing to dispatch for `view`: a `Cells` step whose view
    /// has no source sample (the first sample's previous, the last's next, on an open
    /// chain) or no cells. Its buffers are still reset ([`StepNode::clear_generated`]: the
    /// draw after it then draws nothing), but no compute pass is begun for it.
    pub fn dispatches_nothing(&self, bound: &StepBinding, res: &Resources, view: u32) -> bool {
        match &self.kind {
            NodeKind::Compute(c) => matches!(c.dispatch, Dispatch::Cells(_)) && source_cells(c, bound, res, view).is_none(),
            NodeKind::Raster(_) => false,
        }
    }

    /// Each level's commands, recorded once into a render bundle: a frame records a pass
    /// and one bundle, not the pipeline, every group and every draw again
    /// (docs/embedding.md, "Host CPU").
    fn bundle<'a>(
        &self,
        gpu: &Gpu,
        pipeline: &'a wgpu::RenderPipeline,
        groups: &'a [(u32, wgpu::BindGroup)],
        (color, depth): &(Vec<Option<wgpu::TextureFormat>>, Option<wgpu::TextureFormat>),
        draw: impl FnOnce(&mut wgpu::RenderBundleEncoder<'a>),
    ) -> wgpu::RenderBundle {
        let mut be = gpu.device.create_render_bundle_encoder(&wgpu::RenderBundleEncoderDescriptor {
            label: Some(&self.label),
            color_formats: color,
            depth_stencil: depth.map(|format| wgpu::RenderBundleDepthStencil {
                format,
                depth_read_only: false,
                stencil_read_only: true,
            }),
            sample_count: 1,
            multiview: None,
        });
        be.set_pipeline(pipeline);
        for (index, group) in groups {
            be.set_bind_group(*index, group, &[]);
        }
        draw(&mut be);
        be.finish(&wgpu::RenderBundleDescriptor { label: Some(&self.label) })
    }

    /// Whether the step draws the scene's meshes (a Depth pass, a forward Shade): what
    /// [`StepNode::record_draws`] records again when the scene's draws change.
    pub fn draws_scene(&self) -> bool {
        matches!(&self.kind, NodeKind::Raster(r) if matches!(r.draw, DrawCall::Scene))
    }

    /// Record a scene-drawing step's bundles again over `res`'s draws (a mesh or an
    /// instance added or removed, in buffers that did not move): the bind groups, views
    /// and attachments stay; no bind group or buffer is made.
    pub fn record_draws(&self, gpu: &Gpu, res: &Resources, bound: &mut StepBinding) -> Result<()> {
        let (NodeKind::Raster(r), StepBinding::Raster { passes }, Pipeline::Render(pipeline)) =
            (&self.kind, bound, &self.pipeline.pipeline)
        else {
            return Err(self.mismatch());
        };
        let from_light = matches!(r.depth, Some(DepthTarget::Light));
        for p in passes {
            p.bundle = self.bundle(gpu, pipeline, &p.groups, &p.formats, |be| res.draw.record(be, from_light));
        }
        Ok(())
    }

    /// Whether what the step binds comes from the scene: its draws (a Depth pass, a forward
    /// Shade), its edge adjacency or the buffers generated from it (Geometry passes). Only
    /// these are bound again when the targets take a new scene
    /// ([`crate::gpu::Targets::set_scene`]).
    pub fn binds_scene(&self) -> bool {
        match &self.kind {
            NodeKind::Raster(r) => matches!(r.draw, DrawCall::Scene | DrawCall::Generated(_)),
            NodeKind::Compute(c) => {
                c.generated.is_some() || matches!(c.dispatch, Dispatch::Edges | Dispatch::Cells(_) | Dispatch::Indirect(_))
            }
        }
    }

    /// Whether the step runs as a compute dispatch (recorded into a compute pass).
    pub fn is_compute(&self) -> bool {
        matches!(self.kind, NodeKind::Compute(_))
    }

    /// A fresh count of generated vertices and fresh vertex claims every frame
    /// (instance_count stays 1): encoder commands, outside any pass.
    pub fn clear_generated(&self, encoder: &mut wgpu::CommandEncoder, bound: &StepBinding) {
        if let (
            NodeKind::Compute(c),
            StepBinding::Compute {
                geometry: Some((_, [buffer, claims])),
                ..
            },
        ) = (&self.kind, bound)
        {
            // the vertex count, then the records claimed and dropped
            encoder.clear_buffer(buffer, 0, Some(4));
            encoder.clear_buffer(buffer, 16, Some(8));
            if matches!(c.dispatch, Dispatch::Edges) {
                encoder.clear_buffer(claims, 0, None);
            }
        }
    }

    fn mismatch(&self) -> RuntimeError {
        RuntimeError::NotFound(format!("pass `{}`: a step's node and its pipeline disagree", self.label))
    }

    /// Record a compute step's dispatches into an open compute pass (its own, or the one
    /// the compute steps before it in the same pass and view opened: wgpu orders the
    /// dispatches of one pass that write and read the same resource).
    pub fn dispatch(&self, cpass: &mut wgpu::ComputePass<'_>, bound: &StepBinding, res: &Resources, view: u32) -> Result<()> {
        match (&self.kind, bound, &self.pipeline.pipeline) {
            (
                NodeKind::Compute(c),
                StepBinding::Compute {
                    group0,
                    group1,
                    group2,
                    geometry,
                    levels,
                    gbuffer,
                },
                Pipeline::Compute(pipeline),
            ) => {
                cpass.set_pipeline(pipeline);
                cpass.set_bind_group(0, group0, &[]);
                if let Some(g1) = group1 {
                    cpass.set_bind_group(1, g1, &[]);
                }
                if let Some(g2) = group2 {
                    cpass.set_bind_group(2, g2, &[]);
                }
                // a Discontinuities step's one group (a Silhouettes step sets its chunks')
                if let Some((groups, _)) = geometry
                    && let [(g3, _)] = &groups[..]
                {
                    cpass.set_bind_group(3, g3, &[]);
                }
                if let Some(g3) = gbuffer {
                    cpass.set_bind_group(3, g3, &[]);
                }
                match &c.dispatch {
                    Dispatch::ShadowMapLines => {
                        cpass.dispatch_workgroups(res.shadow_size.div_ceil(graph::COMPUTE_WORKGROUP), 1, 1);
                    }
                    Dispatch::Texels => {
                        let n = res.shadow_size.div_ceil(graph::TEXEL_WORKGROUP);
                        cpass.dispatch_workgroups(n, n, 1);
                    }
                    Dispatch::Pixels => {
                        let (w, h) = res.camera_size;
                        cpass.dispatch_workgroups(w.div_ceil(graph::TEXEL_WORKGROUP), h.div_ceil(graph::TEXEL_WORKGROUP), 1);
                    }
                    // level by level, each reading the one above (wgpu orders the
                    // dispatches of a pass that write and read the same texture)
                    Dispatch::MipTexels => {
                        for (g1, g2, size) in levels {
                            if let Some(g1) = g1 {
                                cpass.set_bind_group(1, g1, &[]);
                            }
                            cpass.set_bind_group(2, g2, &[]);
                            let n = size.div_ceil(graph::TEXEL_WORKGROUP);
                            cpass.dispatch_workgroups(n, n, 1);
                        }
                    }
                    Dispatch::Edges => {
                        for (g3, edges) in geometry.iter().flat_map(|g| &g.0) {
                            cpass.set_bind_group(3, g3, &[]);
                            // Workgroups per dimension are limited (WebGPU guarantees
                            // 65,535): edges beyond 64 x 65,535 spread over y, and the
                            // shader skips indices past its chunk (see `Draw::Silhouettes`).
                            let groups = edges.div_ceil(graph::COMPUTE_WORKGROUP);
                            let max = 65_535;
                            if groups > 0 {
                                cpass.dispatch_workgroups(groups.min(max), groups.div_ceil(max), 1);
                            }
                        }
                    }
                    Dispatch::Cells(_) => {
                        if let Some(cells) = source_cells(c, bound, res, view) {
                            cpass.dispatch_workgroups(cells.div_ceil(graph::COMPUTE_WORKGROUP), cells, 1);
                        }
                    }
                    Dispatch::Indirect(a) => cpass.dispatch_workgroups_indirect(&a.buffer, a.offset),
                }
                Ok(())
            }
            _ => Err(self.mismatch()),
        }
    }
}

/// A `Cells` step's cells for `view`, `None` where it has nothing to do: no source view
/// (the shader would find none and return at once, and on lavapipe a dispatch of empty
/// invocations costs as much as half a full one) or no cells.
fn source_cells(c: &ComputeStep, bound: &StepBinding, res: &Resources, view: u32) -> Option<u32> {
    let (Dispatch::Cells(source), StepBinding::Compute { geometry, .. }) = (&c.dispatch, bound) else {
        return None;
    };
    let cells = geometry.as_ref().and_then(|g| g.0.first()).map_or(0, |g| g.1);
    let has_source = res.samples_closed
        || match source {
            graph::Neighbour::Previous => view > 0,
            graph::Neighbour::Next => view + 1 < res.samples,
        };
    (cells > 0 && has_source).then_some(cells)
}

/// Begin a compute pass labelled `label`, with `stamps`' timestamp writes when it has any.
pub(crate) fn begin_compute<'e>(encoder: &'e mut wgpu::CommandEncoder, label: &str, stamps: Option<Stamps>) -> wgpu::ComputePass<'e> {
    encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: stamps
            .filter(|s| s.begin.is_some() || s.end.is_some())
            .map(|s| wgpu::ComputePassTimestampWrites {
                query_set: s.set,
                beginning_of_pass_write_index: s.begin,
                end_of_pass_write_index: s.end,
            }),
    })
}

/// A bind group of `views` at bindings 0, 1, ...
fn bind_views(gpu: &Gpu, layout: &wgpu::BindGroupLayout, views: &[wgpu::TextureView]) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = views
        .iter()
        .enumerate()
        .map(|(i, v)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: wgpu::BindingResource::TextureView(v),
        })
        .collect();
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout,
        entries: &entries,
    })
}

/// The clear value and blend state of a resolve rule (see [`Resolve`]); `Nearest` does not
/// blend (a depth test picks the fragment).
fn resolve_state(resolve: Resolve) -> (wgpu::Color, Option<wgpu::BlendState>) {
    use wgpu::{BlendComponent as C, BlendFactor as F, BlendOperation as O};
    let one = |operation| C {
        src_factor: F::One,
        dst_factor: F::One,
        operation,
    };
    let (clear, c) = match resolve {
        Resolve::KeepMin => (WHITE, one(O::Min)),
        Resolve::KeepMax => (wgpu::Color::TRANSPARENT, one(O::Max)),
        // target - shadow amount
        Resolve::Add => (WHITE, one(O::ReverseSubtract)),
        // target * value
        Resolve::Multiply => (
            WHITE,
            C {
                src_factor: F::Zero,
                dst_factor: F::Src,
                operation: O::Add,
            },
        ),
        Resolve::Nearest => return (WHITE, None),
    };
    (clear, Some(wgpu::BlendState { color: c, alpha: c }))
}
