//! Pipelines and the key that determines them.
//!
//! A [`PipelineKey`] holds everything a pipeline is built from: the shader source itself,
//! the entry points, the binding layout, the colour targets with their blend state, the
//! depth state and the vertex input. [`StepPipeline::build`] reads nothing else, so two
//! steps with equal keys can share one pipeline (the device caches them by key).

use crate::graph::Format;
use std::sync::Arc;

/// The depth attachment format of scene draws.
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Number of levels of a full mip chain.
pub fn mip_count(size: u32) -> u32 {
    32 - size.max(1).leading_zeros()
}

/// The wgpu format of a texture; `None` for a summed-area table (a storage buffer).
pub(crate) fn wgpu_format(f: Format) -> Option<wgpu::TextureFormat> {
    use wgpu::TextureFormat as T;
    Some(match f {
        Format::R8Unorm => T::R8Unorm,
        Format::Rg8Unorm => T::Rg8Unorm,
        Format::Rgba8Unorm => T::Rgba8Unorm,
        Format::R16Unorm => T::R16Unorm,
        Format::Rg16Unorm => T::Rg16Unorm,
        Format::Rgba16Unorm => T::Rgba16Unorm,
        Format::R16Float => T::R16Float,
        Format::Rg16Float => T::Rg16Float,
        Format::Rgba16Float => T::Rgba16Float,
        Format::R32Float => T::R32Float,
        Format::Rg32Float => T::Rg32Float,
        Format::Rgba32Float => T::Rgba32Float,
        Format::SummedAreaU32 | Format::SummedAreaF32 => return None,
    })
}

/// The camera outputs of the Shade pass, in [`crate::gpu::CameraOutput`] order.
pub(crate) const CAMERA_FORMATS: [wgpu::TextureFormat; 4] = [
    wgpu::TextureFormat::R32Float,
    wgpu::TextureFormat::Rgba8Unorm,
    wgpu::TextureFormat::Rgba32Float,
    wgpu::TextureFormat::Rgba16Float,
];

/// Everything a pipeline is built from.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) struct PipelineKey {
    /// The WGSL source (its identity is its text).
    pub source: Arc<str>,
    pub stages: Stages,
    pub layout: BindingLayout,
}

/// The entry points and fixed-function state.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Stages {
    Raster {
        vertex: Option<String>,
        fragment: Option<String>,
        /// The scene's vertex buffer (position and normal, 24-byte stride), or none.
        scene_vertices: bool,
        targets: Vec<ColorTarget>,
        depth: Option<DepthState>,
    },
    Compute {
        entry: Option<String>,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct ColorTarget {
    pub format: wgpu::TextureFormat,
    pub blend: Option<wgpu::BlendState>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct DepthState {
    pub format: wgpu::TextureFormat,
    pub compare: wgpu::CompareFunction,
    pub write: bool,
}

/// The bind groups of a step (see the conventions in [`crate::graph`]).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) struct BindingLayout {
    /// Group 0 binding 1: the `Params` uniform.
    pub params: bool,
    /// Group 0 binding 2: the filtering sampler.
    pub sampler: bool,
    /// Group 0 binding 3: the `LightSamples` uniform.
    pub light_samples: bool,
    /// Group 1: what the step reads.
    pub reads: Vec<(u32, Slot)>,
    /// Group 2 (compute steps): what the step writes, bindings 0, 1, ...
    pub writes: Vec<Slot>,
    /// Group 3 (Geometry passes): the edge adjacency and a generated buffer.
    pub geometry: Option<GeometryGroup>,
}

/// What group 3 of a Geometry pass's step, or of a deferred Shade's compute step, binds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum GeometryGroup {
    /// A `Silhouettes` step (compute): 0 edges, 1 face planes, 2 edge faces (read-only
    /// storage), 3 the generated buffer and 5 the vertex claims (read-write storage).
    Classify,
    /// A `Discontinuities` step (compute): 3 the generated buffer (read-write storage).
    Discontinuities,
    /// A `Primitives` step (raster): 4 the generated buffer (read-only storage, vertex and
    /// fragment stages). Binding 4, so that one module can hold both steps' entry points:
    /// the classification's bindings 0 to 3 and the draw's are distinct variables.
    Draw,
    /// A `ComputePixels` step: 0 to 2 the G-buffer (`sshc_graph::GBUFFER`), read with
    /// `textureLoad`.
    GBuffer,
}

impl GeometryGroup {
    fn entries(self) -> Vec<wgpu::BindGroupLayoutEntry> {
        let buffer = |binding, read_only, visibility| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        match self {
            GeometryGroup::Classify => {
                let c = wgpu::ShaderStages::COMPUTE;
                vec![
                    buffer(0, true, c),
                    buffer(1, true, c),
                    buffer(2, true, c),
                    buffer(3, false, c),
                    buffer(5, false, c),
                ]
            }
            GeometryGroup::Discontinuities => vec![buffer(3, false, wgpu::ShaderStages::COMPUTE)],
            GeometryGroup::Draw => vec![buffer(4, true, wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT)],
            GeometryGroup::GBuffer => (0..sshc_graph::GBUFFER.len() as u32)
                .map(|binding| wgpu::BindGroupLayoutEntry {
                    binding,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                })
                .collect(),
        }
    }
}

/// One binding of group 1 or 2.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Slot {
    /// A `texture_2d_array<f32>`, filterable when the step binds the sampler.
    Texture { filterable: bool },
    /// A storage buffer (a summed-area table).
    Buffer { read_only: bool },
    /// A write-only `texture_storage_2d_array` of the format (a `ComputeTexels` step's target).
    StorageTexture { format: wgpu::TextureFormat },
}

/// A built pipeline and its bind group layouts.
pub(crate) struct StepPipeline {
    pub pipeline: Pipeline,
    pub group0: wgpu::BindGroupLayout,
    /// What the step reads; an empty layout when a compute step reads nothing but writes.
    pub group1: Option<wgpu::BindGroupLayout>,
    /// What a compute step writes.
    pub group2: Option<wgpu::BindGroupLayout>,
    /// The Geometry pass's buffers.
    pub group3: Option<wgpu::BindGroupLayout>,
}

pub(crate) enum Pipeline {
    Render(wgpu::RenderPipeline),
    Compute(wgpu::ComputePipeline),
}

impl Slot {
    fn entry(self, binding: u32) -> wgpu::BindGroupLayoutEntry {
        let ty = match self {
            Slot::Texture { filterable } => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable },
                view_dimension: wgpu::TextureViewDimension::D2Array,
                multisampled: false,
            },
            Slot::Buffer { read_only } => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            Slot::StorageTexture { format } => wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format,
                view_dimension: wgpu::TextureViewDimension::D2Array,
            },
        };
        let visibility = match self {
            Slot::Buffer { read_only: false } | Slot::StorageTexture { .. } => wgpu::ShaderStages::COMPUTE,
            Slot::Texture { .. } | Slot::Buffer { read_only: true } => wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
        };
        wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty,
            count: None,
        }
    }
}

fn group0_layout(device: &wgpu::Device, l: &BindingLayout) -> wgpu::BindGroupLayout {
    let vis = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
    let uniform = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: vis,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let mut entries = vec![uniform(0)];
    if l.params {
        entries.push(uniform(1));
    }
    if l.sampler {
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 2,
            visibility: vis,
            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
            count: None,
        });
    }
    if l.light_samples {
        entries.push(uniform(3));
    }
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("frame"),
        entries: &entries,
    })
}

pub(crate) const SCENE_VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 2] = [
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x3,
        offset: 0,
        shader_location: 0,
    },
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x3,
        offset: 12,
        shader_location: 1,
    },
];

impl StepPipeline {
    /// Build the pipeline of `key` (and nothing else) from `module`, the key's source. The
    /// caller holds the error scope ([`crate::gpu::Gpu::pipeline`]).
    pub fn build(device: &wgpu::Device, key: &PipelineKey, module: &wgpu::ShaderModule, label: &str) -> StepPipeline {
        let l = &key.layout;
        let compute = matches!(key.stages, Stages::Compute { .. });
        let group0 = group0_layout(device, l);
        let layout_of = |label: &str, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            })
        };
        let reads: Vec<_> = l.reads.iter().map(|(b, s)| s.entry(*b)).collect();
        let writes: Vec<_> = l.writes.iter().enumerate().map(|(i, s)| s.entry(i as u32)).collect();
        // Empty groups 1 and 2 keep the later groups at their indices.
        let geometry = l.geometry.is_some();
        let group1 = (!reads.is_empty() || compute || geometry).then(|| layout_of("reads", &reads));
        let group2 = (compute || geometry).then(|| layout_of("writes", &writes));
        let group3 = l.geometry.map(|g| layout_of("geometry", &g.entries()));
        let mut layouts: Vec<Option<&wgpu::BindGroupLayout>> = vec![Some(&group0)];
        layouts.extend(group1.iter().map(Some));
        layouts.extend(group2.iter().map(Some));
        layouts.extend(group3.iter().map(Some));
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &layouts,
            immediate_size: 0,
        });
        let pipeline = match &key.stages {
            Stages::Compute { entry } => Pipeline::Compute(device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                module,
                entry_point: entry.as_deref(),
                compilation_options: Default::default(),
                cache: None,
            })),
            Stages::Raster {
                vertex,
                fragment,
                scene_vertices,
                targets,
                depth,
            } => {
                let targets: Vec<Option<wgpu::ColorTargetState>> = targets
                    .iter()
                    .map(|t| {
                        Some(wgpu::ColorTargetState {
                            format: t.format,
                            blend: t.blend,
                            write_mask: wgpu::ColorWrites::ALL,
                        })
                    })
                    .collect();
                let buffers: Vec<Option<wgpu::VertexBufferLayout>> = if *scene_vertices {
                    vec![Some(wgpu::VertexBufferLayout {
                        array_stride: 24,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &SCENE_VERTEX_ATTRIBUTES,
                    })]
                } else {
                    vec![]
                };
                Pipeline::Render(device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(&layout),
                    vertex: wgpu::VertexState {
                        module,
                        entry_point: vertex.as_deref(),
                        compilation_options: Default::default(),
                        buffers: &buffers,
                    },
                    primitive: wgpu::PrimitiveState {
                        cull_mode: None,
                        ..Default::default()
                    },
                    depth_stencil: depth.map(|d| wgpu::DepthStencilState {
                        format: d.format,
                        depth_write_enabled: Some(d.write),
                        depth_compare: Some(d.compare),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module,
                        entry_point: fragment.as_deref(),
                        compilation_options: Default::default(),
                        targets: &targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                }))
            }
        };
        StepPipeline {
            pipeline,
            group0,
            group1,
            group2,
            group3,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{CAMERA_OUTPUTS, GBUFFER, cost};

    /// The cost model's bytes of the fixed attachments (`sshc_graph::cost`, which the
    /// allocation check also counts with) are the formats the runtime makes them in.
    #[test]
    fn the_cost_model_counts_the_attachments_at_their_formats() {
        let bytes = |f: wgpu::TextureFormat| f.block_copy_size(None).unwrap_or(0);
        assert_eq!(CAMERA_OUTPUTS.map(wgpu_format), CAMERA_FORMATS.map(Some));
        assert_eq!(CAMERA_FORMATS.iter().map(|f| bytes(*f)).sum::<u32>(), cost::CAMERA_BYTES_PER_PIXEL);
        let gbuffer: Vec<_> = GBUFFER.iter().filter_map(|f| wgpu_format(*f)).collect();
        assert_eq!(gbuffer.len(), GBUFFER.len());
        assert_eq!(gbuffer.iter().map(|f| bytes(*f)).sum::<u32>(), cost::GBUFFER_BYTES_PER_PIXEL);
        assert_eq!(
            DEPTH_FORMAT.block_copy_size(Some(wgpu::TextureAspect::DepthOnly)),
            Some(cost::DEPTH_BYTES_PER_TEXEL)
        );
    }
}
