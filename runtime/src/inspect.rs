//! The inspection view over a frame's targets ([`Inspect`]): read-backs of any texture,
//! camera output, debug output or generated buffer, with the checks a read-back can run
//! (visibility within [0, 1], finite), and memory figures; and `verify`'s depth override
//! ([`crate::gpu::Targets::run_frame_with_depth`]). Out of the frame path: everything here
//! waits for the GPU or writes from the CPU.

use crate::device::{Result, RuntimeError};
use crate::graph::{self, Format, TextureDecl};
use crate::image::{Image, read_back, read_table};
use crate::lights::Combine;
use crate::pipeline::mip_count;
use crate::resources::{Resources, texture_bytes};
use crate::targets::{CameraOutput, Targets, shade_name};

/// How far outside [0, 1] a visibility may lie (rounding of the technique's arithmetic).
pub const VISIBILITY_EPSILON: f32 = 1e-3;

/// Refuses an image of pass `pass` (row-major, `width` per row) where `bad` holds at some
/// pixel: `say` words the first such pixel's value, its `(x, y)` and the count of them.
fn refuse_pixels(
    values: &[f32],
    width: u32,
    pass: &str,
    bad: impl Fn(f32) -> bool,
    say: impl Fn(f32, (usize, usize), usize) -> String,
) -> Result<()> {
    let Some(i) = values.iter().position(|v| bad(*v)) else {
        return Ok(());
    };
    let count = values.iter().filter(|v| bad(**v)).count();
    let w = width.max(1) as usize;
    Err(RuntimeError::Output {
        pass: pass.to_string(),
        message: say(values[i], (i % w, i / w), count),
    })
}

/// Check a visibility image (row-major, `width` per row) that pass `pass` wrote: every value
/// finite and within [0, 1] up to [`VISIBILITY_EPSILON`]; the first bad pixel is named.
pub fn check_visibility(values: &[f32], width: u32, pass: &str) -> Result<()> {
    refuse_pixels(
        values,
        width,
        pass,
        |v| !v.is_finite() || !(-VISIBILITY_EPSILON..=1.0 + VISIBILITY_EPSILON).contains(&v),
        |v, (x, y), count| {
            format!(
                "visibility {v} at pixel ({x}, {y}) ({count} pixel(s) non-finite or outside [0, 1] by more than {VISIBILITY_EPSILON}); the image is refused"
            )
        },
    )
}

/// Refuses a frame where the technique's visibility expression was not a finite number at
/// a receiver facing the light: `flags` is the Shade's normal output's w, 1 there (the
/// visibility written there is finite, so [`check_visibility`] cannot see it).
pub fn check_finite_visibility(flags: &[f32], width: u32, pass: &str) -> Result<()> {
    refuse_pixels(
        flags,
        width,
        pass,
        |f| f > 0.5,
        |_, (x, y), count| {
            format!(
                "the visibility expression is not a finite number (NaN or infinite) at pixel ({x}, {y}) and {} more pixel(s) facing the light (drawn lit where NaN, clamped where infinite); look for a division by zero, or the log or square root of a negative number; the image is refused",
                count - 1
            )
        },
    )
}

/// A debug output of the Shade pass ([`Inspect::debug_outputs`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DebugOutput {
    /// Its name in the technique (`debug: {"name": "..."}`).
    pub name: String,
    /// The camera-sized texture holding it (`debug_<name>`).
    pub texture: String,
    /// Its components: 1 for an f32, 2 to 4 for a vector.
    pub components: usize,
}

/// What a frame generated into one buffer ([`Inspect::generated`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Generated {
    /// Records appended (silhouette edges, for the Geometry passes of this runtime).
    pub records: u32,
    /// Vertices the indirect draw drew: `records` times the buffer's `vertices_per_record`.
    pub vertices: u32,
    /// Instances of the indirect draw (1).
    pub instances: u32,
    /// Records the step asked for: `records + dropped`.
    pub claimed: u32,
    /// Records past the buffer's capacity, written nowhere and not drawn: the frame's
    /// silhouettes passed its bound ([`crate::resources::GeneratedLimits`]).
    pub dropped: u32,
}

/// A view over [`Targets`] for reading back what the last frame wrote, and for memory
/// figures ([`Targets::inspect`]). Every read waits for the GPU.
pub struct Inspect<'a> {
    t: &'a Targets,
}

impl Targets {
    /// The inspection view over these targets.
    pub fn inspect(&self) -> Inspect<'_> {
        Inspect { t: self }
    }
}

impl Inspect<'_> {
    /// Read one layer and mip level of a texture of the graph (light 0's, with several).
    pub fn read_texture(&self, name: &str, layer: u32, level: u32) -> Result<Image> {
        self.read_light_texture(0, name, layer, level)
    }

    /// [`Inspect::read_texture`] of light (or cascade) `light`'s resources. A texture the
    /// lights share ([`crate::gpu::TargetLimits::share_light_textures`]) holds the last
    /// light's values after a frame: asked of another light, it is refused.
    pub fn read_light_texture(&self, light: usize, name: &str, layer: u32, level: u32) -> Result<Image> {
        let b = self.t.light(light)?;
        let graph = self.t.technique.graph();
        let decl = graph
            .texture(name)
            .ok_or_else(|| RuntimeError::NotFound(format!("no texture `{name}`")))?;
        let last = self.t.bound.len() - 1;
        if light != last && self.t.shared.iter().any(|s| s == name) {
            return Err(RuntimeError::NotFound(format!(
                "texture `{name}` is shared by the lights and holds light {last}'s values after a frame, not light {light}'s: make the targets with `TargetLimits::share_light_textures` false to read each light's"
            )));
        }
        if layer >= decl.array_layers() {
            return Err(RuntimeError::NotFound(format!(
                "texture `{name}` has {} layer(s), not {}",
                decl.array_layers(),
                layer + 1
            )));
        }
        let levels = if decl.mips { mip_count(b.shadow_size) } else { 1 };
        if level >= levels {
            return Err(RuntimeError::NotFound(format!(
                "texture `{name}` has {levels} level(s), not {}",
                level + 1
            )));
        }
        let size = (b.shadow_size >> level).max(1);
        if decl.format.is_table() {
            return read_table(&self.t.gpu, b.table(name)?, decl.format, layer, size);
        }
        let (w, h) = match decl.extent {
            graph::Extent::ShadowMap => (size, size),
            graph::Extent::Camera => b.camera_size,
        };
        read_back(&self.t.gpu, b.texture(name)?, layer, level, w, h, decl.format)
    }

    /// The Shade's debug outputs this graph writes (compiled with `CompileOptions::debug`):
    /// each one's name (`debug: {"name": ...}` in the technique), its texture
    /// (`debug_<name>`) and its components (1 to 4). Empty for a graph without them.
    pub fn debug_outputs(&self) -> Vec<DebugOutput> {
        debug_outputs(self.t.technique.graph())
    }

    /// Debug output `name` of light (or cascade) `light`'s Shade, at the camera's size, as
    /// computed (unclamped; NaN where the camera sees no surface): components 0.. of each
    /// pixel hold the output's, the others 0. Light `l`'s Shade writes its own; with
    /// cascades, each cascade's is evaluated at every pixel, not only in its slice.
    pub fn read_debug(&self, light: usize, name: &str) -> Result<Image> {
        let graph = self.t.technique.graph();
        let texture = format!("{}{name}", graph::DEBUG_PREFIX);
        if graph.texture(&texture).is_none_or(|t| t.extent != graph::Extent::Camera) {
            let known: Vec<String> = self.debug_outputs().into_iter().map(|d| d.name).collect();
            return Err(RuntimeError::NotFound(if known.is_empty() {
                format!(
                    "no debug output `{name}`: the graph has none (compile it with debug outputs: `CompileOptions::debug`, `sshc compile --debug`)"
                )
            } else {
                format!("no debug output `{name}`; the graph has {}", known.join(", "))
            }));
        }
        self.read_light_texture(light, &texture, 0, 0)
    }

    /// Read a camera output of the Shade pass. The visibility (and the colour, computed from
    /// it) is refused where it is not finite or lies outside [0, 1] (`check_visibility`).
    /// With several lights, the colour is the lights' combination and the other outputs are
    /// light 0's ([`Inspect::read_light_camera`] reads another light's,
    /// [`Inspect::read_visibilities`] every light's visibility).
    pub fn read_camera(&self, which: CameraOutput) -> Result<Image> {
        if let (CameraOutput::Visibility, Some(c)) = (which, &self.t.combine)
            && c.cascades
        {
            // cascades: the visibility is their combination (channel 0; channel 1 the cascade)
            let mut img = self.read_visibilities()?;
            for p in &mut img.rgba {
                *p = [p[0], 0.0, 0.0, 1.0];
            }
            return Ok(img);
        }
        if let (CameraOutput::Color, Some(c)) = (which, &self.t.combine) {
            // the colour is computed from every light's visibility
            for l in 0..self.t.bound.len() {
                self.read_light_camera(l, CameraOutput::Visibility)?;
            }
            let (w, h) = self.t.camera_size();
            return read_back(&self.t.gpu, &c.color, 0, 0, w, h, Format::Rgba8Unorm);
        }
        self.read_light_camera(0, which)
    }

    /// Read a camera output of light `light`'s Shade (that light alone).
    pub fn read_light_camera(&self, light: usize, which: CameraOutput) -> Result<Image> {
        if which == CameraOutput::Color {
            // The shaded colour is computed from the visibility: a visibility the check
            // refuses is not passed on through the colour either.
            self.read_light_camera(light, CameraOutput::Visibility)?;
        }
        let b = self.t.light(light)?;
        let (w, h) = b.camera_size;
        let format = match which {
            CameraOutput::Visibility => Format::R32Float,
            CameraOutput::Color => Format::Rgba8Unorm,
            CameraOutput::Position => Format::Rgba32Float,
            CameraOutput::Normal => Format::Rgba16Float,
        };
        let gpu = &self.t.gpu;
        let img = read_back(gpu, &b.camera[which as usize], 0, 0, w, h, format)?;
        if which == CameraOutput::Visibility {
            let shade = shade_name(self.t.technique.graph());
            check_visibility(&img.channel(0), w, shade)?;
            // the Shade wrote a finite visibility where the technique's was not: the
            // normal's w says where (`graph::CAMERA_OUTPUTS`)
            let normal = read_back(gpu, &b.camera[CameraOutput::Normal as usize], 0, 0, w, h, Format::Rgba16Float)?;
            check_finite_visibility(&normal.channel(3), w, shade)?;
        }
        Ok(img)
    }

    /// The visibilities of lights 0 to 3, channel `l` for light `l` (the combining step's
    /// gathering with several lights; light 0's visibility in channel 0 with one), checked
    /// as [`Inspect::read_camera`] checks one: [`Inspect::read_visibility_layer`] 0.
    pub fn read_visibilities(&self) -> Result<Image> {
        self.read_visibility_layer(0)
    }

    /// Layer `k` of the gathered visibilities: lights `4k` to `4k + 3` in channels 0 to 3
    /// (those past the last light 0), each checked as [`Inspect::read_camera`] checks one.
    /// With one light, layer 0 is light 0's visibility in channel 0; with cascades, their
    /// mixture in channel 0 and the cascade in channel 1.
    pub fn read_visibility_layer(&self, k: u32) -> Result<Image> {
        let Some(c) = &self.t.combine else {
            if k > 0 {
                return Err(RuntimeError::NotFound(format!("visibility layer {k}: one light has layer 0 only")));
            }
            return self.read_light_camera(0, CameraOutput::Visibility);
        };
        let layers = c.visibility.depth_or_array_layers();
        if k >= layers {
            return Err(RuntimeError::NotFound(format!(
                "visibility layer {k}: {} light(s) are gathered in {layers} layer(s), four a layer",
                self.t.bound.len()
            )));
        }
        let (w, h) = self.t.camera_size();
        let img = read_back(&self.t.gpu, &c.visibility, k, 0, w, h, Format::Rgba32Float)?;
        // cascades: channel 1 is the cascade, checked by nothing
        let lights = if c.cascades { 1 } else { self.t.bound.len() };
        let shade = shade_name(self.t.technique.graph());
        for l in (4 * k as usize..lights).take(4) {
            check_visibility(&img.channel(l % 4), w, shade)?;
        }
        Ok(img)
    }

    /// Bytes of every graph texture made for these targets: (name, bytes), transient ones
    /// included, each made texture once. With several lights, each light's own textures
    /// (named `texture (light l)`), the ones the lights share (`texture (shared by the
    /// lights)`) and the combining step's.
    pub fn memory(&self) -> Vec<(String, u64)> {
        let bound = &self.t.bound;
        let first = self.texture_bytes(&bound[0]);
        if bound.len() == 1 {
            return first;
        }
        let shared = |n: &str| self.t.shared.iter().any(|s| s == n);
        let mut all: Vec<(String, u64)> = first
            .iter()
            .filter(|(n, _)| shared(n))
            .map(|(n, b)| (format!("{n} (shared by the lights)"), *b))
            .collect();
        for (l, res) in bound.iter().enumerate() {
            all.extend(
                self.texture_bytes(res)
                    .into_iter()
                    .filter(|(n, _)| !shared(n))
                    .map(|(n, b)| (format!("{n} (light {l})"), b)),
            );
        }
        all.push((
            "lights' colours and visibilities, combined (camera size)".to_string(),
            Combine::bytes(self.t.camera_size(), bound.len()),
        ));
        all
    }

    fn texture_bytes(&self, b: &Resources) -> Vec<(String, u64)> {
        self.t
            .technique
            .graph()
            .textures
            .iter()
            .map(|t: &TextureDecl| (t.name.clone(), texture_bytes(t, b.shadow_size, b.camera_size)))
            .collect()
    }

    /// What the last frame generated into buffer `name` (a Geometry pass's records, light
    /// 0's): read back from the draw arguments at the buffer's start, so this waits for
    /// the GPU.
    pub fn generated(&self, name: &str) -> Result<Generated> {
        let b = &self.t.bound[0];
        let decl = self
            .t
            .technique
            .graph()
            .buffer(name)
            .ok_or_else(|| RuntimeError::NotFound(format!("no generated buffer `{name}`")))?;
        let gpu = &self.t.gpu;
        let read = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("draw arguments read-back"),
            size: graph::GENERATED_HEADER_BYTES as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(b.generated(name)?, 0, &read, 0, graph::GENERATED_HEADER_BYTES as u64);
        gpu.scoped("reading draw arguments", || gpu.queue.submit([encoder.finish()]))?;
        let raw = gpu.map_read(&read)?;
        let word = |i: usize| u32::from_le_bytes([raw[4 * i], raw[4 * i + 1], raw[4 * i + 2], raw[4 * i + 3]]);
        let vertices = word(0);
        Ok(Generated {
            records: vertices / decl.vertices_per_record,
            vertices,
            instances: word(1),
            claimed: word(4),
            dropped: word(5),
        })
    }
}

/// The Shade's debug outputs `graph` writes ([`Inspect::debug_outputs`]).
pub fn debug_outputs(graph: &graph::PassGraph) -> Vec<DebugOutput> {
    graph
        .textures
        .iter()
        .filter(|t| t.extent == graph::Extent::Camera)
        .filter_map(|t| {
            Some(DebugOutput {
                name: t.name.strip_prefix(graph::DEBUG_PREFIX)?.to_string(),
                texture: t.name.clone(),
                components: t.channels.len().clamp(1, 4),
            })
        })
        .collect()
}
