//! What a graph needs of a device: the wgpu features and limits beyond WebGPU's defaults,
//! each with the pass that needs it and why. [`Requirements::of`] reads only the graph, so
//! a host can ask before it opens its device ([`Requirements::features`],
//! [`Requirements::limits`]); loading a graph ([`crate::gpu::Technique::new`]) checks them
//! against the device and refuses it with every missing feature and limit listed.

use crate::device::Gpu;
use crate::error::{Result, RuntimeError};
use crate::graph::{self, PassGraph};
use crate::pipeline::{CAMERA_FORMATS, wgpu_format};
use crate::steps::{self, Dispatch, NodeKind, Targets};

/// A device limit a graph can exceed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Limit {
    MaxTextureArrayLayers,
    MaxUniformBufferBindingSize,
    MaxBindGroups,
    MaxColorAttachments,
    MaxColorAttachmentBytesPerSample,
    MaxSampledTexturesPerShaderStage,
    MaxStorageBuffersPerShaderStage,
    MaxStorageTexturesPerShaderStage,
    MaxUniformBuffersPerShaderStage,
    MaxComputeWorkgroupSizeX,
    MaxComputeWorkgroupSizeY,
    MaxComputeInvocationsPerWorkgroup,
}

impl Limit {
    /// The field's name in `wgpu::Limits`.
    pub fn name(self) -> &'static str {
        match self {
            Limit::MaxTextureArrayLayers => "max_texture_array_layers",
            Limit::MaxUniformBufferBindingSize => "max_uniform_buffer_binding_size",
            Limit::MaxBindGroups => "max_bind_groups",
            Limit::MaxColorAttachments => "max_color_attachments",
            Limit::MaxColorAttachmentBytesPerSample => "max_color_attachment_bytes_per_sample",
            Limit::MaxSampledTexturesPerShaderStage => "max_sampled_textures_per_shader_stage",
            Limit::MaxStorageBuffersPerShaderStage => "max_storage_buffers_per_shader_stage",
            Limit::MaxStorageTexturesPerShaderStage => "max_storage_textures_per_shader_stage",
            Limit::MaxUniformBuffersPerShaderStage => "max_uniform_buffers_per_shader_stage",
            Limit::MaxComputeWorkgroupSizeX => "max_compute_workgroup_size_x",
            Limit::MaxComputeWorkgroupSizeY => "max_compute_workgroup_size_y",
            Limit::MaxComputeInvocationsPerWorkgroup => "max_compute_invocations_per_workgroup",
        }
    }

    /// The device's value of this limit.
    pub fn of(self, l: &wgpu::Limits) -> u64 {
        match self {
            Limit::MaxTextureArrayLayers => l.max_texture_array_layers.into(),
            Limit::MaxUniformBufferBindingSize => l.max_uniform_buffer_binding_size,
            Limit::MaxBindGroups => l.max_bind_groups.into(),
            Limit::MaxColorAttachments => l.max_color_attachments.into(),
            Limit::MaxColorAttachmentBytesPerSample => l.max_color_attachment_bytes_per_sample.into(),
            Limit::MaxSampledTexturesPerShaderStage => l.max_sampled_textures_per_shader_stage.into(),
            Limit::MaxStorageBuffersPerShaderStage => l.max_storage_buffers_per_shader_stage.into(),
            Limit::MaxStorageTexturesPerShaderStage => l.max_storage_textures_per_shader_stage.into(),
            Limit::MaxUniformBuffersPerShaderStage => l.max_uniform_buffers_per_shader_stage.into(),
            Limit::MaxComputeWorkgroupSizeX => l.max_compute_workgroup_size_x.into(),
            Limit::MaxComputeWorkgroupSizeY => l.max_compute_workgroup_size_y.into(),
            Limit::MaxComputeInvocationsPerWorkgroup => l.max_compute_invocations_per_workgroup.into(),
        }
    }

    /// Raise the limit in `l` to at least `v` (saturating at the field's type).
    fn raise(self, l: &mut wgpu::Limits, v: u64) {
        let small = |x: &mut u32| *x = (*x).max(u32::try_from(v).unwrap_or(u32::MAX));
        match self {
            Limit::MaxTextureArrayLayers => small(&mut l.max_texture_array_layers),
            Limit::MaxUniformBufferBindingSize => l.max_uniform_buffer_binding_size = l.max_uniform_buffer_binding_size.max(v),
            Limit::MaxBindGroups => small(&mut l.max_bind_groups),
            Limit::MaxColorAttachments => small(&mut l.max_color_attachments),
            Limit::MaxColorAttachmentBytesPerSample => small(&mut l.max_color_attachment_bytes_per_sample),
            Limit::MaxSampledTexturesPerShaderStage => small(&mut l.max_sampled_textures_per_shader_stage),
            Limit::MaxStorageBuffersPerShaderStage => small(&mut l.max_storage_buffers_per_shader_stage),
            Limit::MaxStorageTexturesPerShaderStage => small(&mut l.max_storage_textures_per_shader_stage),
            Limit::MaxUniformBuffersPerShaderStage => small(&mut l.max_uniform_buffers_per_shader_stage),
            Limit::MaxComputeWorkgroupSizeX => small(&mut l.max_compute_workgroup_size_x),
            Limit::MaxComputeWorkgroupSizeY => small(&mut l.max_compute_workgroup_size_y),
            Limit::MaxComputeInvocationsPerWorkgroup => small(&mut l.max_compute_invocations_per_workgroup),
        }
    }
}

/// A feature a pass needs.
#[derive(Clone, Debug, PartialEq)]
pub struct FeatureNeed {
    pub feature: wgpu::Features,
    /// Who needs it: "pass `name`", or the graph itself ("the graph's texture `t`").
    pub who: String,
    pub why: String,
}

/// A limit a pass needs raised to at least `needed`.
#[derive(Clone, Debug, PartialEq)]
pub struct LimitNeed {
    pub limit: Limit,
    pub needed: u64,
    /// Who needs it: "pass `name`", or the graph itself ("the graph's Params uniform").
    pub who: String,
}

/// Everything a graph needs of a device beyond what every WebGPU device has.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Requirements {
    pub features: Vec<FeatureNeed>,
    pub limits: Vec<LimitNeed>,
    /// Textures a raster pass renders into that are 16-bit norm formats: the device must
    /// also allow them as render attachments (an adapter-specific format feature), which
    /// only the adapter answers ([`Gpu::renderable_norm16`]).
    pub rendered_norm16: Vec<(String, wgpu::TextureFormat)>,
}

/// What one step binds, counted per shader stage (every binding is visible to the stages
/// that can use it, so the counts are the step's totals).
#[derive(Default)]
struct StepCounts {
    sampled: u64,
    storage_buffers: u64,
    storage_textures: u64,
    uniforms: u64,
    /// Colour attachments (raster steps).
    attachments: Vec<wgpu::TextureFormat>,
    groups: u64,
    /// Workgroup size (x, y) of a compute step.
    workgroup: Option<(u32, u32)>,
    /// It blends into its attachments.
    blends: bool,
}

/// The counts of a step, from its plan ([`steps::plan`], the runtime's one reading of `Draw`).
fn step_counts(graph: &PassGraph, step: &graph::Step) -> StepCounts {
    let table = |name: &str| graph.texture(name).is_some_and(|t| t.format.is_table());
    let format = |name: &str| graph.texture(name).and_then(|t| wgpu_format(t.format));
    let mut c = StepCounts {
        uniforms: 1 + u64::from(step.params) + u64::from(step.light_samples),
        ..Default::default()
    };
    for r in &step.reads {
        if table(&r.texture) {
            c.storage_buffers += 1;
        } else {
            c.sampled += 1;
        }
    }
    let writes = step.writes.len() as u64;
    let kind = steps::plan(step);
    let group3 = steps::geometry_group(&kind).is_some();
    match kind {
        NodeKind::Raster(r) => {
            c.attachments = match &r.targets {
                Targets::Textures(t) => t.iter().filter_map(|w| format(&w.texture)).collect(),
                Targets::Camera(t) => CAMERA_FORMATS
                    .iter()
                    .copied()
                    .chain(t.iter().filter_map(|w| format(&w.texture)))
                    .collect(),
                Targets::GBuffer => graph::GBUFFER.iter().filter_map(|f| wgpu_format(*f)).collect(),
            };
            c.blends = r.blend.is_some();
            // a generated buffer's draw reads it at group 3 (groups 1 and 2 empty)
            c.storage_buffers += u64::from(group3);
            c.groups = if group3 { 4 } else { 1 + u64::from(!step.reads.is_empty()) };
        }
        NodeKind::Compute(k) => {
            let line = (graph::COMPUTE_WORKGROUP, 1);
            let texel = (graph::TEXEL_WORKGROUP, graph::TEXEL_WORKGROUP);
            c.groups = if group3 { 4 } else { 3 };
            c.workgroup = Some(match k.dispatch {
                Dispatch::Pixels => {
                    // the four camera outputs and the debug outputs stored, the G-buffer
                    // read at group 3
                    c.storage_textures = CAMERA_FORMATS.len() as u64 + writes;
                    c.sampled += graph::GBUFFER.len() as u64;
                    texel
                }
                Dispatch::Texels | Dispatch::MipTexels => {
                    c.storage_textures = writes;
                    texel
                }
                Dispatch::ShadowMapLines | Dispatch::Indirect(_) => {
                    c.storage_buffers += writes;
                    line
                }
                Dispatch::Edges => {
                    // edges, face planes, edge faces, the generated buffer, the vertex claims
                    c.storage_buffers += writes + 5;
                    line
                }
                Dispatch::Cells(_) => {
                    c.storage_buffers += writes + 1;
                    line
                }
            });
        }
    }
    c
}

/// Bytes per sample of these colour attachments, as wgpu counts them toward
/// `max_color_attachment_bytes_per_sample`: each format's render-target byte cost, after
/// aligning the running total to its component alignment (WebGPU's rule).
fn attachment_bytes(formats: &[wgpu::TextureFormat]) -> u64 {
    let mut total = 0u32;
    for f in formats {
        total = total.next_multiple_of(f.target_component_alignment().unwrap_or(1));
        total += f.target_pixel_byte_cost().unwrap_or(0);
    }
    total.into()
}

impl Requirements {
    /// What `graph` needs, read from its declarations alone.
    pub fn of(graph: &PassGraph) -> Requirements {
        let mut r = Requirements::default();
        let mut limit = |limit: Limit, needed: u64, who: &str| {
            if needed > Limit::of(limit, &wgpu::Limits::default()) {
                r.limits.push(LimitNeed {
                    limit,
                    needed,
                    who: who.to_string(),
                });
            }
        };
        limit(
            Limit::MaxUniformBufferBindingSize,
            graph.params_size.into(),
            "the graph's Params uniform",
        );
        limit(Limit::MaxUniformBufferBindingSize, graph::FRAME_SIZE.into(), "the Frame uniform");
        for t in &graph.textures {
            limit(
                Limit::MaxTextureArrayLayers,
                t.array_layers().into(),
                &format!("the graph's texture `{}`", t.name),
            );
        }
        // each step's counts, once (the features below read whether it blends)
        let counts: Vec<Vec<StepCounts>> = graph
            .passes
            .iter()
            .map(|p| p.steps.iter().map(|st| step_counts(graph, st)).collect())
            .collect();
        for (pass, steps) in graph.passes.iter().zip(&counts) {
            for c in steps {
                let who = format!("pass `{}`", pass.name);
                let name = who.as_str();
                limit(Limit::MaxBindGroups, c.groups, name);
                limit(Limit::MaxColorAttachments, c.attachments.len() as u64, name);
                limit(Limit::MaxColorAttachmentBytesPerSample, attachment_bytes(&c.attachments), name);
                limit(Limit::MaxSampledTexturesPerShaderStage, c.sampled, name);
                limit(Limit::MaxStorageBuffersPerShaderStage, c.storage_buffers, name);
                limit(Limit::MaxStorageTexturesPerShaderStage, c.storage_textures, name);
                limit(Limit::MaxUniformBuffersPerShaderStage, c.uniforms, name);
                if let Some((x, y)) = c.workgroup {
                    limit(Limit::MaxComputeWorkgroupSizeX, x.into(), name);
                    limit(Limit::MaxComputeWorkgroupSizeY, y.into(), name);
                    limit(Limit::MaxComputeInvocationsPerWorkgroup, u64::from(x) * u64::from(y), name);
                }
            }
        }
        let mut feature = |feature: wgpu::Features, who: String, why: String| {
            r.features.push(FeatureNeed { feature, who, why });
        };
        for t in graph.textures.iter().filter(|t| t.format.is_norm16()) {
            let owner = graph
                .passes
                .iter()
                .find(|p| p.steps.iter().any(|s| s.writes.iter().any(|w| w.texture == t.name)))
                .map_or("the graph".to_string(), |p| format!("pass `{}`", p.name));
            feature(
                wgpu::Features::TEXTURE_FORMAT_16BIT_NORM,
                owner,
                format!("texture `{}` is {:?}", t.name, t.format),
            );
        }
        for (pass, steps) in graph.passes.iter().zip(&counts) {
            for (step, c) in pass.steps.iter().zip(steps) {
                if step.sampler {
                    for read in &step.reads {
                        if let Some(t) = graph.texture(&read.texture).filter(|t| t.format.is_float32()) {
                            feature(
                                wgpu::Features::FLOAT32_FILTERABLE,
                                format!("pass `{}`", pass.name),
                                format!("it filters `{}`, a {:?} texture", t.name, t.format),
                            );
                        }
                    }
                }
                let blends = c.blends;
                let raster = step.compute.is_none();
                for w in &step.writes {
                    let Some(t) = graph.texture(&w.texture) else { continue };
                    if blends && t.format.is_float32() {
                        feature(
                            wgpu::Features::FLOAT32_BLENDABLE,
                            format!("pass `{}`", pass.name),
                            format!("it blends generated primitives into `{}`, a {:?} texture", t.name, t.format),
                        );
                    }
                    if raster
                        && t.format.is_norm16()
                        && let Some(f) = wgpu_format(t.format)
                        && !r.rendered_norm16.iter().any(|(n, _)| n == &t.name)
                    {
                        r.rendered_norm16.push((t.name.clone(), f));
                    }
                }
            }
        }
        r
    }

    /// What a set of techniques needs together: a host that switches among them at run
    /// time asks its device for [`Requirements::features`] and [`Requirements::limits`] of
    /// this once. Every need of each is kept, named with its technique (`technique `t`,
    /// pass `p``); the features are their union and each limit the largest asked.
    pub fn of_all<'a>(graphs: impl IntoIterator<Item = &'a PassGraph>) -> Requirements {
        let mut all = Requirements::default();
        for g in graphs {
            let r = Requirements::of(g);
            let named = |who: String| format!("technique `{}`, {who}", g.technique);
            all.features
                .extend(r.features.into_iter().map(|n| FeatureNeed { who: named(n.who), ..n }));
            all.limits
                .extend(r.limits.into_iter().map(|n| LimitNeed { who: named(n.who), ..n }));
            all.rendered_norm16.extend(
                r.rendered_norm16
                    .into_iter()
                    .map(|(t, f)| (format!("{t}` of technique `{}", g.technique), f)),
            );
        }
        all
    }

    /// Every feature the graph needs, as one set (for a host's `DeviceDescriptor`).
    /// `TIMESTAMP_QUERY` is not among them: without it frames run untimed.
    pub fn features(&self) -> wgpu::Features {
        let mut f = self.features.iter().fold(wgpu::Features::empty(), |a, n| a | n.feature);
        if !self.rendered_norm16.is_empty() {
            f |= wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
        }
        f
    }

    /// `base` with every limit the graph needs raised to it (for a host's `DeviceDescriptor`).
    pub fn limits(&self, mut base: wgpu::Limits) -> wgpu::Limits {
        for n in &self.limits {
            n.limit.raise(&mut base, n.needed);
        }
        base
    }

    /// What `gpu` lacks of these, one line each naming the pass that needs it.
    pub fn missing(&self, gpu: &Gpu) -> Vec<String> {
        let mut out = Vec::new();
        for n in &self.features {
            if !gpu.features.contains(n.feature) {
                let names: Vec<&str> = n.feature.iter_names().map(|(name, _)| name).collect();
                out.push(format!("feature {}, needed by {}: {}", names.join(" | "), n.who, n.why));
            }
        }
        for (name, f) in &self.rendered_norm16 {
            if !gpu.renderable_norm16.contains(f) {
                out.push(format!(
                    "{f:?} as a render attachment (an adapter-specific format feature): a raster pass renders texture `{name}`; use F16 or Unorm8"
                ));
            }
        }
        for n in &self.limits {
            let has = n.limit.of(&gpu.limits);
            if n.needed > has {
                out.push(format!(
                    "limit {} of {}, needed by {} (the device allows {has})",
                    n.limit.name(),
                    n.needed,
                    n.who
                ));
            }
        }
        out
    }

    /// Refuse `gpu` when it lacks any of these, listing all of them.
    pub fn check(&self, gpu: &Gpu, technique: &str) -> Result<()> {
        let missing = self.missing(gpu);
        if missing.is_empty() {
            Ok(())
        } else {
            Err(RuntimeError::Unsatisfied {
                technique: technique.to_string(),
                missing,
            })
        }
    }
}
