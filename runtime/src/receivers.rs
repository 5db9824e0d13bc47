//! Objects that receive no shadow (`Instance::receives`, `SceneInputs::unshadowed`): they
//! are drawn unshadowed and read visibility 1.
//!
//! After each light's passes, one raster step of the runtime's draws those objects again
//! over the camera's depth with the test `Equal` and no depth write, into the Shade's
//! visibility and colour: where such an object is the surface the camera sees, the
//! visibility becomes 1 and the colour the lit one ([`crate::graph::SHADE_COLOR_WGSL`] with
//! `vis = 1`, the normal as the Shade takes it, [`crate::graph::SHADE_NORMAL_WGSL`]). Its
//! vertex stage computes the clip position with the same expression as the generated
//! Shade's, and both are `@invariant`, so the depths are equal bit for bit and the test
//! picks exactly the pixels the object won. A receiving object at the very same depth (a
//! coplanar overlap) is overdrawn too.
//!
//! With a host's pixels ([`crate::gpu::HostPixels`]) the runtime rasterises no camera
//! depth: the step is skipped, and the host's own lighting pass applies its rule.

use crate::device::{Gpu, Result};
use crate::graph::{FRAME_WGSL, SHADE_COLOR_WGSL, SHADE_NORMAL_WGSL};
use crate::pipeline::{DEPTH_FORMAT, SCENE_VERTEX_ATTRIBUTES};
use crate::resources::Resources;

fn wgsl() -> String {
    format!(
        "{FRAME_WGSL}
@group(0) @binding(0) var<uniform> frame: Frame;

struct Varying {{
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
}}

@vertex
fn vs_unshadowed(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> Varying {{
    var out: Varying;
    out.clip = frame.camera_view_proj * vec4<f32>(position, 1.0);
    out.world = position;
    out.normal = normal;
    return out;
}}

struct Out {{
    @location(0) visibility: vec4<f32>,
    @location(1) color: vec4<f32>,
}}

@fragment
fn fs_unshadowed(in: Varying) -> Out {{
{SHADE_NORMAL_WGSL}    let to_light = select(normalize(frame.light_position.xyz - in.world), normalize(frame.light_position.xyz), frame.light_position.w == 0.0);
    let lambert = max(dot(n, to_light), 0.0);
    let vis = 1.0;
    var out: Out;
    out.visibility = vec4<f32>(vis, 0.0, 0.0, 1.0);
    out.color = {SHADE_COLOR_WGSL};
    return out;
}}
"
    )
}

/// The step, with one bind group and set of views per bound light.
pub(crate) struct Unshadowed {
    pipeline: wgpu::RenderPipeline,
    /// Per light: its `Frame`, and views of its visibility, colour and camera depth.
    lights: Vec<(wgpu::BindGroup, [wgpu::TextureView; 3])>,
}

impl Unshadowed {
    /// The step for these lights' resources; `None` when their draws have no object that
    /// receives no shadow (nothing is created then).
    pub fn new(gpu: &Gpu, bound: &[Resources]) -> Result<Option<Unshadowed>> {
        if bound.iter().all(|r| r.draw.unshadowed.is_empty()) {
            return Ok(None);
        }
        gpu.scoped("creating the draw of objects that receive no shadow", || {
            let device = &gpu.device;
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("unshadowed"),
                source: wgpu::ShaderSource::Wgsl(wgsl().into()),
            });
            let target = |format| {
                Some(wgpu::ColorTargetState {
                    format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })
            };
            let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("unshadowed"),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_unshadowed"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: 24,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &SCENE_VERTEX_ATTRIBUTES,
                    })],
                },
                primitive: wgpu::PrimitiveState {
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(wgpu::CompareFunction::Equal),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_unshadowed"),
                    compilation_options: Default::default(),
                    // the camera outputs' visibility and colour (`CAMERA_FORMATS` 0 and 1)
                    targets: &[target(bound[0].camera[0].format()), target(bound[0].camera[1].format())],
                }),
                multiview_mask: None,
                cache: None,
            });
            let lights = bound
                .iter()
                .map(|res| {
                    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("unshadowed"),
                        layout: &pipeline.get_bind_group_layout(0),
                        entries: &[wgpu::BindGroupEntry {
                            binding: 0,
                            resource: res.centre_frame(),
                        }],
                    });
                    let view = |t: &wgpu::Texture| t.create_view(&Default::default());
                    (group, [view(&res.camera[0]), view(&res.camera[1]), view(&res.camera_depth)])
                })
                .collect();
            Some(Unshadowed { pipeline, lights })
        })
    }

    /// The lights' camera targets were created again at a new size: their attachment views
    /// are made again; the pipeline and the bind groups (each light's `Frame`) stay.
    pub fn resize(&mut self, bound: &[Resources]) {
        for ((_, views), res) in self.lights.iter_mut().zip(bound) {
            let view = |t: &wgpu::Texture| t.create_view(&Default::default());
            *views = [view(&res.camera[0]), view(&res.camera[1]), view(&res.camera_depth)];
        }
    }

    /// Record the draw for light `l` (after its passes, before the lights are combined).
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, l: usize, res: &Resources) {
        let Some((group, [visibility, color, depth])) = self.lights.get(l) else {
            return;
        };
        if res.draw.unshadowed.is_empty() {
            return;
        }
        let load = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("unshadowed"),
            color_attachments: &[load(visibility), load(color)],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rp.set_pipeline(&self.pipeline);
        rp.set_bind_group(0, group, &[]);
        res.draw.record_unshadowed(&mut rp);
    }
}
