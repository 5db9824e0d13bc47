//! Draws one texture of the graph into the window: one layer, level and channel mapped from
//! a value range through a colour map, or a colour texture as it is. Texels are read with
//! `textureLoad` (nearest), so 32-bit float textures need no filtering feature and a pixel
//! of the window shows one texel's value unchanged.

use wgpu::util::DeviceExt as _;

const WGSL: &str = r#"
struct Show {
    // layer, level, channel (4: rgb as it is), colour map
    pick: vec4<u32>,
    // value range lo, hi; the target's size in pixels
    range: vec4<f32>,
    // x: 1 to keep the texture square, centred (a shadow map), 0 to fill the target
    fit: vec4<u32>,
}
@group(0) @binding(0) var src: texture_2d_array<f32>;
@group(0) @binding(1) var<uniform> show: Show;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(xy * 2.0 - 1.0, 0.0, 1.0);
}

fn viridis(t: f32) -> vec3<f32> {
    // a degree-6 polynomial fit of matplotlib's viridis
    let c0 = vec3<f32>(0.2777, 0.0054, 0.3341);
    let c1 = vec3<f32>(0.1051, 1.4046, 1.3846);
    let c2 = vec3<f32>(-0.3309, 0.2148, 0.0951);
    let c3 = vec3<f32>(-4.6342, -5.7991, -19.3324);
    let c4 = vec3<f32>(6.2283, 14.1799, 56.6906);
    let c5 = vec3<f32>(4.7764, -13.7451, -65.3530);
    let c6 = vec3<f32>(-5.4355, 4.6459, 26.3124);
    return c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * (c5 + t * c6)))));
}

@fragment
fn fs(@builtin(position) at: vec4<f32>) -> @location(0) vec4<f32> {
    let dims = textureDimensions(src, show.pick.y);
    var uv = at.xy / show.range.zw;
    if show.fit.x == 1u {
        let side = min(show.range.z, show.range.w);
        uv = (at.xy - 0.5 * (show.range.zw - side)) / side;
        if any(uv < vec2<f32>(0.0)) || any(uv >= vec2<f32>(1.0)) {
            return vec4<f32>(0.02, 0.02, 0.03, 1.0);
        }
    }
    let texel = min(vec2<u32>(uv * vec2<f32>(dims)), dims - 1u);
    let v = textureLoad(src, texel, show.pick.x, show.pick.y);
    if show.pick.z == 4u {
        return vec4<f32>(v.rgb, 1.0);
    }
    let x = v[min(show.pick.z, 3u)];
    // NaN shows magenta, infinities the colour of the end they lie past. NaN is told by
    // its bits: WGSL lets an implementation assume no NaN, and `x != x` compiled as an
    // ordered comparison is false for NaN (the debug outputs' background, NaN where the
    // camera sees no surface, showed viridis(0), dark purple, on lavapipe)
    let bits = bitcast<u32>(x);
    if (bits & 0x7f800000u) == 0x7f800000u && (bits & 0x007fffffu) != 0u {
        return vec4<f32>(1.0, 0.0, 1.0, 1.0);
    }
    var t = clamp((x - show.range.x) / max(show.range.y - show.range.x, 1e-30), 0.0, 1.0);
    if show.pick.w == 3u {
        // viridis over log(x): lo (above 0, the script checks) to hi by their ratio
        let lo = max(show.range.x, 1e-30);
        t = clamp(log(max(x, lo) / lo) / max(log(max(show.range.y, lo) / lo), 1e-30), 0.0, 1.0);
    }
    var c = vec3<f32>(t);
    if show.pick.w == 1u || show.pick.w == 3u {
        c = clamp(viridis(t), vec3<f32>(0.0), vec3<f32>(1.0));
    } else if show.pick.w == 2u {
        let s = t * 2.0 - 1.0;
        c = select(vec3<f32>(1.0 + s, 1.0 + s, 1.0), vec3<f32>(1.0, 1.0 - s, 1.0 - s), s > 0.0);
    }
    return vec4<f32>(c, 1.0);
}
"#;

/// What to draw: a texture and how to read it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pick {
    pub layer: u32,
    pub level: u32,
    /// 0 to 3, or 4 for the colour as it is.
    pub channel: u32,
    pub map: u32,
    pub lo: f32,
    pub hi: f32,
    /// Keep the texture square and centred (a shadow map) instead of filling the target.
    pub square: bool,
}

/// Where a texture is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    Whole,
    Left,
    Right,
}

pub struct Present {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniform: wgpu::Buffer,
    /// The bind group of the texture drawn last, and that texture.
    bound: Option<(wgpu::Texture, wgpu::BindGroup)>,
}

impl Present {
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, target: wgpu::TextureFormat) -> Present {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("sshc view: present"),
            source: wgpu::ShaderSource::Wgsl(WGSL.into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("sshc view: present"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("sshc view: present"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("sshc view: present"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(target.into())],
            }),
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("sshc view: present"),
            contents: &[0u8; 48],
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        Present {
            device: device.clone(),
            queue: queue.clone(),
            pipeline,
            layout,
            uniform,
            bound: None,
        }
    }

    /// Draw `texture` as `pick` says over `part` of `target` (`size` pixels): the whole,
    /// or its left or right half (a split view: each half shows its own texture at the
    /// same pixels).
    pub fn draw(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        size: (u32, u32),
        texture: &wgpu::Texture,
        pick: Pick,
        part: Part,
    ) {
        let mut bytes = Vec::with_capacity(48);
        for v in [pick.layer, pick.level, pick.channel, pick.map] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        for v in [pick.lo, pick.hi, size.0 as f32, size.1 as f32] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        for v in [u32::from(pick.square), 0, 0, 0] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        self.queue.write_buffer(&self.uniform, 0, &bytes);
        if self.bound.as_ref().is_none_or(|(t, _)| t != texture) {
            let view = texture.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            });
            let group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("sshc view: present"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: self.uniform.as_entire_binding(),
                    },
                ],
            });
            self.bound = Some((texture.clone(), group));
        }
        let Some((_, group)) = &self.bound else { return };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("sshc view: present"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: match part {
                        Part::Whole | Part::Left => wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        Part::Right => wgpu::LoadOp::Load,
                    },
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        let half = size.0 / 2;
        let (x, w) = match part {
            Part::Whole => (0, size.0),
            Part::Left => (0, half),
            Part::Right => (half, size.0 - half),
        };
        if w == 0 || size.1 == 0 {
            return;
        }
        pass.set_scissor_rect(x, 0, w, size.1);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// Clear `target` (nothing to show yet).
    pub fn clear(encoder: &mut wgpu::CommandEncoder, target: &wgpu::TextureView) {
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("sshc view: clear"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: 0.02,
                        g: 0.02,
                        b: 0.03,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
    }
}
