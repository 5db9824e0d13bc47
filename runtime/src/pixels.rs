//! A host's pixels in place of the deferred Shade's own camera raster.
//!
//! A deferred renderer already has, per pixel, the world position and the normal of what
//! its camera sees. A graph whose Shade runs deferred (the compute schedule) rasterises
//! them into its G-buffer ([`crate::graph::GBUFFER`]) and then shades every pixel from
//! there. With host pixels ([`crate::gpu::Targets::set_host_pixels`]) that raster is
//! replaced by one compute step of the runtime's that writes the same G-buffer from the
//! host's textures:
//!
//! - the world position, as the host gives it;
//! - the normal, normalised and turned towards the camera (the forward Shade turns it
//!   towards the side its screen-space face normal shows: the same side wherever the
//!   surface is not seen edge-on), octahedral ([`crate::graph::OCTAHEDRAL_WGSL`]);
//! - what the raster took from screen-space derivatives: the footprint `dpdx(uv)`,
//!   `dpdy(uv)` of the light-space uv and the receiver-plane depth slope
//!   ([`crate::graph::DEPTH_SLOPE_WGSL`], one definition with the compiler's). Each
//!   derivative is the difference across the pixel's 2 x 2 quad, as a GPU's fine
//!   derivatives are: between the quad's two columns on the pixel's row for x, and its two
//!   rows on the pixel's column for y.
//!
//! Tolerance of that derivation: where the pixel's quad lies on one triangle, the host's
//! world positions are the raster's interpolated ones and the differences are the ones
//! the hardware takes, so the G-buffer, and the visibility computed from it, are the
//! forward Shade's bit for bit (on lavapipe: `tests/tests/embedding.rs`,
//! `host_pixels_give_the_forward_shade_where_a_quad_lies_on_one_triangle`). Where the quad
//! straddles an edge the hardware extrapolates the triangle's attributes into its helper
//! pixels and the host's pixels hold another surface: the depth slope there is another
//! estimate, as a renderer's own derivatives at edges are.

use crate::device::Gpu;
use crate::error::{Result, RuntimeError};
use crate::graph::{DEPTH_SLOPE_WGSL, FRAME_WGSL, OCTAHEDRAL_WGSL, TEXEL_WORKGROUP};
use crate::resources::Resources;
use crate::steps::Stamps;

/// A host's per-pixel inputs of the Shade, at the camera's size.
#[derive(Clone, Copy)]
pub struct HostPixels<'a> {
    /// `Rgba32Float`: the world position in xyz, w = 1 where a surface is and 0 where none.
    pub world: &'a wgpu::Texture,
    /// `Rgba16Float` or `Rgba32Float`: the normal in xyz (any length; normalised here).
    pub normal: &'a wgpu::Texture,
}

fn shader() -> String {
    format!(
        "{FRAME_WGSL}
@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var h_world: texture_2d<f32>;
@group(0) @binding(2) var h_normal: texture_2d<f32>;
@group(0) @binding(3) var g_world: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var g_normal: texture_storage_2d<rg32float, write>;
@group(0) @binding(5) var g_duv: texture_storage_2d<rgba16float, write>;

{OCTAHEDRAL_WGSL}
// (uv, normalised depth) of the host's pixel p in the light's view, as the Shade computes them
fn light_space(p: vec2<i32>) -> vec3<f32> {{
    let world = vec4<f32>(textureLoad(h_world, p, 0).xyz, 1.0);
    let in_d = (-(frame.light_view * world).z - frame.depth_range.x) * frame.depth_range.z;
    let light_clip = frame.light_view_proj * world;
    let in_uv = light_clip.xy / light_clip.w * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5);
    return vec3<f32>(in_uv, in_d);
}}

@compute @workgroup_size({TEXEL_WORKGROUP}, {TEXEL_WORKGROUP})
fn main(@builtin(global_invocation_id) id: vec3<u32>) {{
    let size = vec2<i32>(textureDimensions(h_world));
    let p = vec2<i32>(id.xy);
    if any(p >= size) {{
        return;
    }}
    let host = textureLoad(h_world, p, 0);
    if host.w <= 0.0 {{
        // no surface: the G-buffer's clear value (w = -1)
        textureStore(g_world, p, vec4<f32>(0.0, 0.0, 0.0, -1.0));
        textureStore(g_normal, p, vec4<f32>(0.0));
        textureStore(g_duv, p, vec4<f32>(0.0));
        return;
    }}
    // fine derivatives: across the pixel's 2 x 2 quad, on its own row (x) and column (y)
    let q = p - (p & vec2<i32>(1));
    let last = size - 1;
    let dx = light_space(vec2<i32>(min(q.x + 1, last.x), p.y)) - light_space(vec2<i32>(q.x, p.y));
    let dy = light_space(vec2<i32>(p.x, min(q.y + 1, last.y))) - light_space(vec2<i32>(p.x, q.y));
    let duv_dx = dx.xy;
    let duv_dy = dy.xy;
    let dd_dx = dx.z;
    let dd_dy = dy.z;
{DEPTH_SLOPE_WGSL}    let given = normalize(textureLoad(h_normal, p, 0).xyz);
    let n = select(given, -given, dot(given, frame.camera_position.xyz - host.xyz) < 0.0);
    textureStore(g_world, p, vec4<f32>(host.xyz, in_depth_slope));
    textureStore(g_normal, p, vec4<f32>(octahedral(n), 0.0, 0.0));
    textureStore(g_duv, p, vec4<f32>(duv_dx, duv_dy));
}}
"
    )
}

/// The step that writes each light's G-buffer from the host's pixels.
pub(crate) struct PixelsStep {
    pipeline: wgpu::ComputePipeline,
    /// Per bound light: its `Frame`, the host's textures, its G-buffer.
    groups: Vec<wgpu::BindGroup>,
    size: (u32, u32),
}

/// Refuse a host texture that is not what the step reads.
fn check(t: &wgpu::Texture, what: &str, formats: &[wgpu::TextureFormat], camera: (u32, u32)) -> Result<()> {
    let bad = |m: String| Err(RuntimeError::Param(format!("host pixels: the {what} texture {m}")));
    if !formats.contains(&t.format()) {
        return bad(format!(
            "is {:?}; it must be {}",
            t.format(),
            formats.iter().map(|f| format!("{f:?}")).collect::<Vec<_>>().join(" or ")
        ));
    }
    if (t.width(), t.height()) != camera {
        return bad(format!(
            "is {} x {}, the camera {} x {}: host pixels are the camera's",
            t.width(),
            t.height(),
            camera.0,
            camera.1
        ));
    }
    if t.dimension() != wgpu::TextureDimension::D2 || t.depth_or_array_layers() != 1 || t.sample_count() != 1 {
        return bad("is not a plain 2D texture (one layer, one sample)".into());
    }
    if !t.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) {
        return bad("has no TEXTURE_BINDING usage: the runtime reads it in a compute step".into());
    }
    Ok(())
}

impl PixelsStep {
    /// The step for `pixels` over every bound light's resources (checked: formats, sizes,
    /// usages).
    pub fn new(gpu: &Gpu, pixels: &HostPixels, bound: &[Resources]) -> Result<PixelsStep> {
        let camera = bound.first().map_or((0, 0), |b| b.camera_size);
        check(pixels.world, "world-position", &[wgpu::TextureFormat::Rgba32Float], camera)?;
        check(
            pixels.normal,
            "normal",
            &[wgpu::TextureFormat::Rgba16Float, wgpu::TextureFormat::Rgba32Float],
            camera,
        )?;
        gpu.scoped("the step of the host's pixels", || {
            let device = &gpu.device;
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("host pixels"),
                source: wgpu::ShaderSource::Wgsl(shader().into()),
            });
            let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("host pixels"),
                layout: None,
                module: &module,
                entry_point: Some("main"),
                compilation_options: Default::default(),
                cache: None,
            });
            let (world, normal) = (
                pixels.world.create_view(&Default::default()),
                pixels.normal.create_view(&Default::default()),
            );
            let groups = bound
                .iter()
                .map(|res| {
                    let g: Vec<wgpu::TextureView> = res.gbuffer.iter().map(|t| t.create_view(&Default::default())).collect();
                    let views = [&world, &normal, &g[0], &g[1], &g[2]];
                    let mut entries = vec![wgpu::BindGroupEntry {
                        binding: 0,
                        resource: res.centre_frame(),
                    }];
                    entries.extend(views.iter().enumerate().map(|(i, v)| wgpu::BindGroupEntry {
                        binding: i as u32 + 1,
                        resource: wgpu::BindingResource::TextureView(v),
                    }));
                    device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("host pixels"),
                        layout: &pipeline.get_bind_group_layout(0),
                        entries: &entries,
                    })
                })
                .collect();
            PixelsStep {
                pipeline,
                groups,
                size: camera,
            }
        })
    }

    /// Record light `light`'s G-buffer from the host's pixels, with the timestamps of the
    /// step it replaces.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, light: usize, stamps: Option<Stamps>) {
        let Some(group) = self.groups.get(light) else { return };
        let timestamp_writes = stamps
            .map(|s| wgpu::ComputePassTimestampWrites {
                query_set: s.set,
                beginning_of_pass_write_index: s.begin,
                end_of_pass_write_index: s.end,
            })
            .filter(|t| t.beginning_of_pass_write_index.is_some() || t.end_of_pass_write_index.is_some());
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("host pixels"),
            timestamp_writes,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(self.size.0.div_ceil(TEXEL_WORKGROUP), self.size.1.div_ceil(TEXEL_WORKGROUP), 1);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_step_validates() {
        crate::validate::validate_wgsl(&super::shader()).unwrap_or_else(|e| panic!("{e}"));
    }
}
