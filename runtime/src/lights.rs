//! Several lights in one frame: the graph's passes run once per scene light,
//! each light on its own resources (its shadow maps, its camera outputs), and then one
//! compute step combines the lights' shaded images into the frame's colour and gathers
//! their visibilities into one texel a pixel, channel `l` for light `l`.
//!
//! The combination: light `l`'s Shade wrote its shaded colour `c_l` (that light alone); the
//! frame's colour is their mean, `(c_0 + ... + c_{n-1}) / n`, each light weighted equally (the
//! lights of a scene share one intensity; the mean keeps the image in [0, 1] as one light's
//! is). The lights' colours and visibilities are first copied into the layers of two array
//! textures, so the step reads `n` layers with one binding of each.

use crate::device::{Gpu, Result, RuntimeError};
use crate::resources::Resources;

/// Most lights one frame combines (defined beside the lights, in `sshc-light`, so that
/// scene loaders refuse what the runtime cannot bind).
pub use sshc_light::MAX_LIGHTS;

const COMBINE_WGSL: &str = "
@group(0) @binding(0) var visibility: texture_2d_array<f32>;
@group(0) @binding(1) var color: texture_2d_array<f32>;
@group(0) @binding(2) var out_color: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(3) var out_visibility: texture_storage_2d_array<rgba32float, write>;

@compute @workgroup_size(8, 8)
fn combine(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(out_color);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let lights = textureNumLayers(visibility);
    var c = vec4<f32>(0.0);
    var v = vec4<f32>(0.0);
    for (var l = 0u; l < lights; l++) {
        c += textureLoad(color, id.xy, l, 0);
        v[l % 4u] = textureLoad(visibility, id.xy, l, 0).r;
        // four lights a layer; the last layer's unused channels 0
        if l % 4u == 3u || l + 1u == lights {
            textureStore(out_visibility, id.xy, l / 4u, v);
            v = vec4<f32>(0.0);
        }
    }
    textureStore(out_color, id.xy, c / f32(lights));
}
";

/// Cascades of one light (docs/runtime.md, section 1): per pixel, the cascade whose
/// slice of view distances holds the pixel's (`dot(p - eye, forward)`, `p` the camera
/// pass's world position), mixed with the next cascade over the last `band` fraction of its
/// slice, so that no seam shows where two cascades meet; beyond the last split, the last
/// cascade. Colour and visibility (channel 0) come from that mixture; channel 1 holds the
/// cascade, fractional in a band (`sshc render --visibility` and the viewer can show it).
/// `Slices` is the schema's (`sshc_graph::SLICES_WGSL`, checked against naga's layout),
/// declared before it ([`cascades_wgsl`]).
const CASCADES_WGSL: &str = "
@group(0) @binding(0) var visibility: texture_2d_array<f32>;
@group(0) @binding(1) var color: texture_2d_array<f32>;
@group(0) @binding(2) var out_color: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(3) var out_visibility: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var position: texture_2d<f32>;
@group(0) @binding(5) var<uniform> slices: Slices;

fn split(i: u32) -> f32 {
    if i < 4u {
        return slices.lo[i];
    }
    return slices.hi.x;
}

@compute @workgroup_size(8, 8)
fn combine(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(out_color);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let n = u32(slices.forward.w);
    let p = textureLoad(position, id.xy, 0).xyz;
    var k = 0u;
    var t = 0.0;
    // no surface (NaN position): cascade 0, whose visibility is 1 there as every one's
    if all(p == p) {
        let d = dot(p - slices.eye.xyz, slices.forward.xyz);
        k = n - 1u;
        for (var i = 0u; i + 1u < n; i++) {
            if d <= split(i + 1u) {
                k = i;
                break;
            }
        }
        if k + 1u < n {
            let far = split(k + 1u);
            let start = far - slices.eye.w * (far - split(k));
            t = clamp((d - start) / max(far - start, 1e-30), 0.0, 1.0);
        }
    }
    let next = min(k + 1u, n - 1u);
    let v = mix(textureLoad(visibility, id.xy, k, 0).r, textureLoad(visibility, id.xy, next, 0).r, t);
    let c = mix(textureLoad(color, id.xy, k, 0), textureLoad(color, id.xy, next, 0), t);
    textureStore(out_color, id.xy, c);
    textureStore(out_visibility, id.xy, vec4<f32>(v, f32(k) + t, 0.0, 0.0));
}
";

/// Layers of the lights' gathered visibilities: four lights to an RGBA layer.
pub(crate) fn visibility_layers(lights: usize) -> u32 {
    lights.div_ceil(4) as u32
}

/// The combining step's textures at a camera size, for `n` lights, and its bind group.
fn targets(
    device: &wgpu::Device,
    pipeline: &wgpu::ComputePipeline,
    slices: Option<&wgpu::Buffer>,
    camera: (u32, u32),
    n: u32,
    position: &wgpu::Texture,
) -> ([wgpu::Texture; 2], wgpu::Texture, wgpu::Texture, wgpu::BindGroup) {
    let texture = |label: &str, format: wgpu::TextureFormat, layers: u32, usage: wgpu::TextureUsages| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: camera.0,
                height: camera.1,
                depth_or_array_layers: layers,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let input = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
    // the host samples the visibilities (`Targets::visibility`)
    let output = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING;
    let layers = [
        texture("lights' visibility", wgpu::TextureFormat::R32Float, n, input),
        texture("lights' colour", wgpu::TextureFormat::Rgba8Unorm, n, input),
    ];
    let color = texture("combined colour", wgpu::TextureFormat::Rgba8Unorm, 1, output);
    // lights: four to a layer; cascades: one layer (their mixture and the cascade)
    let visibility_layers = if slices.is_some() { 1 } else { visibility_layers(n as usize) };
    let visibility = texture("visibility per light", wgpu::TextureFormat::Rgba32Float, visibility_layers, output);
    let array = |t: &wgpu::Texture| {
        t.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        })
    };
    let (v_in, c_in) = (array(&layers[0]), array(&layers[1]));
    let c_out = color.create_view(&Default::default());
    // the lights' shader writes an array (of one layer up to four lights), the cascades' one
    // layer
    let v_out = if slices.is_some() {
        visibility.create_view(&Default::default())
    } else {
        array(&visibility)
    };
    let p_in = position.create_view(&Default::default());
    fn view(binding: u32, view: &wgpu::TextureView) -> wgpu::BindGroupEntry<'_> {
        wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::TextureView(view),
        }
    }
    let mut entries = vec![view(0, &v_in), view(1, &c_in), view(2, &c_out), view(3, &v_out)];
    if let Some(b) = slices {
        entries.push(view(4, &p_in));
        entries.push(wgpu::BindGroupEntry {
            binding: 5,
            resource: b.as_entire_binding(),
        });
    }
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("combine lights"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    (layers, color, visibility, group)
}

/// The cascades' combining shader: the schema's `Slices`, then [`CASCADES_WGSL`].
fn cascades_wgsl() -> String {
    format!("{}{CASCADES_WGSL}", sshc_graph::SLICES_WGSL)
}

/// The cascades' uniform (the schema's `Slices`): eye and band, forward and count, the
/// splits (unused ones past the last).
fn slices_uniform(s: &Slices) -> sshc_graph::SlicesUniform {
    let Slices {
        eye,
        forward,
        splits,
        band,
    } = s;
    let at = |i: usize| splits.get(i).copied().unwrap_or(f32::MAX);
    sshc_graph::SlicesUniform {
        eye: [eye[0], eye[1], eye[2], *band],
        forward: [forward[0], forward[1], forward[2], splits.len().saturating_sub(1) as f32],
        lo: [at(0), at(1), at(2), at(3)],
        hi: [at(4), 0.0, 0.0, 0.0],
    }
}

/// How the combining step makes one frame of the bound light views.
#[derive(Clone, Debug, PartialEq)]
pub enum Combining {
    /// Several lights: the mean of their colours; visibility channel `l` light `l`'s.
    Lights,
    /// Cascades of one light: by the pixel's view distance (`CASCADES_WGSL`).
    Cascades(Slices),
}

/// Where cascades split the camera's view, for the combining step: each pixel takes the
/// cascade whose slice holds its view distance, mixed with the next over a band.
#[derive(Clone, Debug, PartialEq)]
pub struct Slices {
    /// The camera's position and unit view direction.
    pub eye: [f32; 3],
    pub forward: [f32; 3],
    /// The `n + 1` split distances along `forward`, increasing.
    pub splits: Vec<f32>,
    /// The fraction of each slice, at its far end, over which it mixes into the next, in
    /// [0, 1).
    pub band: f32,
}

impl Slices {
    /// Refuse slices that `n` cascades cannot take: not `n + 1` finite increasing splits, a
    /// band outside [0, 1), an eye or axis not finite.
    pub fn check(&self, n: usize) -> Result<()> {
        let bad = |m: String| Err(RuntimeError::Param(m));
        let s = &self.splits;
        if s.len() != n + 1 || !s.iter().all(|x| x.is_finite()) || s.windows(2).any(|w| w[0] >= w[1]) {
            return bad(format!(
                "{} split distances for {n} cascades: give {} increasing finite distances",
                s.len(),
                n + 1
            ));
        }
        if !(0.0..1.0).contains(&self.band) {
            return bad(format!("cascade band {}: a fraction of a slice, in [0, 1)", self.band));
        }
        if !(self.eye.iter().chain(&self.forward).all(|x| x.is_finite())) {
            return bad("the camera's eye and forward axis must be finite".into());
        }
        Ok(())
    }
}

/// The combining step and its textures, at one camera size and number of lights.
pub(crate) struct Combine {
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    /// Layer `l`: light `l`'s visibility (R32Float) and colour (Rgba8Unorm).
    layers: [wgpu::Texture; 2],
    /// The frame's colour (Rgba8Unorm) and the lights' visibilities (Rgba32Float, light `l`
    /// in layer `l / 4`, channel `l % 4`; cascades: one layer).
    pub color: wgpu::Texture,
    pub visibility: wgpu::Texture,
    size: (u32, u32),
    lights: u32,
    /// Cascades of one light: channel 1 of the visibility is the cascade, not a light's.
    pub cascades: bool,
    /// Cascades: the uniform of the camera and the splits, rewritten per frame.
    slices: Option<wgpu::Buffer>,
}

impl Combine {
    /// Bytes of the combining textures at a camera size, for `lights` lights.
    pub fn bytes(camera: (u32, u32), lights: usize) -> u64 {
        let pixels = camera.0 as u64 * camera.1 as u64;
        pixels * (lights as u64 * (4 + 4) + 4 + 16 * u64::from(visibility_layers(lights)))
    }

    /// `position`: light 0's camera positions, which `Combining::Cascades` reads.
    pub fn new(gpu: &Gpu, camera: (u32, u32), lights: usize, mode: &Combining, position: &wgpu::Texture) -> Result<Combine> {
        if !(2..=MAX_LIGHTS).contains(&lights) {
            return Err(RuntimeError::Limit {
                what: "lights combined in one frame".into(),
                needed: lights as u64,
                limit: MAX_LIGHTS as u64,
            });
        }
        gpu.scoped("creating the lights' combining step", || {
            let device = &gpu.device;
            let source = match mode {
                Combining::Lights => COMBINE_WGSL.into(),
                Combining::Cascades(_) => cascades_wgsl().into(),
            };
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("combine lights"),
                source: wgpu::ShaderSource::Wgsl(source),
            });
            let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("combine lights"),
                layout: None,
                module: &module,
                entry_point: Some("combine"),
                compilation_options: Default::default(),
                cache: None,
            });
            let slices = match mode {
                Combining::Cascades(s) => {
                    let b = device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("cascade slices"),
                        size: u64::from(sshc_graph::SLICES_SIZE),
                        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    });
                    gpu.queue.write_buffer(&b, 0, &slices_uniform(s).to_array());
                    Some(b)
                }
                Combining::Lights => None,
            };
            let n = lights as u32;
            let (layers, color, visibility, group) = targets(device, &pipeline, slices.as_ref(), camera, n, position);
            Combine {
                pipeline,
                group,
                layers,
                color,
                visibility,
                size: camera,
                lights: n,
                cascades: slices.is_some(),
                slices,
            }
        })
    }

    /// A new camera size: the combining textures and their bind group are created again
    /// (`position`: light 0's camera positions at that size); the pipeline and the
    /// cascades' uniform stay.
    pub fn resize(&mut self, gpu: &Gpu, camera: (u32, u32), position: &wgpu::Texture) -> Result<()> {
        let (layers, color, visibility, group) = gpu.scoped("resizing the lights' combining step", || {
            targets(&gpu.device, &self.pipeline, self.slices.as_ref(), camera, self.lights, position)
        })?;
        (self.layers, self.color, self.visibility, self.group, self.size) = (layers, color, visibility, group, camera);
        Ok(())
    }

    /// Cascades: the camera and splits of this frame, written to the uniform the combining
    /// step reads; nothing is created. Ignored for lights.
    pub fn set_slices(&self, queue: &wgpu::Queue, slices: &Slices) {
        if let Some(b) = &self.slices {
            // on the stack: a host refits every frame the camera moves
            queue.write_buffer(b, 0, &slices_uniform(slices).to_array());
        }
    }

    /// Record the copies of every light's visibility and colour into the layers, then the
    /// combining dispatch.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, lights: &[Resources]) {
        let extent = wgpu::Extent3d {
            width: self.size.0,
            height: self.size.1,
            depth_or_array_layers: 1,
        };
        for (l, res) in lights.iter().enumerate().take(self.lights as usize) {
            // camera outputs 0 and 1: visibility and colour (`CameraOutput` order)
            for (k, layers) in self.layers.iter().enumerate() {
                encoder.copy_texture_to_texture(
                    res.camera[k].as_image_copy(),
                    wgpu::TexelCopyTextureInfo {
                        texture: layers,
                        mip_level: 0,
                        origin: wgpu::Origin3d { x: 0, y: 0, z: l as u32 },
                        aspect: wgpu::TextureAspect::All,
                    },
                    extent,
                );
            }
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("combine lights"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.dispatch_workgroups(self.size.0.div_ceil(8), self.size.1.div_ceil(8), 1);
    }
}
