//! What a graph's passes read and write at one scene's sizes: textures, summed-area tables,
//! the scene's vertices, the fixed attachments (depth buffers, the camera outputs) and the
//! `Frame` uniform. Sizes are checked against the device before anything is allocated
//! (lavapipe keeps allocating past its limits).

use crate::device::{Gpu, Result, RuntimeError};
use crate::frame::SceneInputs;
use crate::geometry::{EdgeBuffers, HostScene, SceneDraw};
use crate::graph::{self, FRAME_SIZE, GENERATED_HEADER_BYTES, LIGHT_SAMPLES_SIZE, PassGraph, SampleViewUniform, TextureDecl};
use crate::pipeline::{CAMERA_FORMATS, DEPTH_FORMAT, mip_count, wgpu_format};
use std::collections::HashMap;

/// Bytes of a summed-area table at a shadow-map size: one `vec4` per texel and layer.
fn table_bytes(t: &TextureDecl, shadow_size: u32) -> u64 {
    t.format.bytes_per_texel() as u64 * t.layers as u64 * shadow_size as u64 * shadow_size as u64
}

/// What the resources of a graph are used as, from its steps' declared reads and writes
/// and their plans: the one source of the usages that
/// [`Resources::new`] gives them.
#[derive(Default)]
pub(crate) struct Usages {
    /// Each graph texture's usages: `RENDER_ATTACHMENT` where a raster step writes it,
    /// `STORAGE_BINDING` where a compute step stores into it, `TEXTURE_BINDING` where a
    /// step reads it, `COPY_DST` where a Depth pass writes it (the lab's depth override
    /// writes its output from the CPU), and `COPY_SRC` on every one (read-back:
    /// [`crate::gpu::Inspect::read_texture`]), and `TEXTURE_BINDING` on a Shade's debug
    /// outputs (a host looks at them: [`crate::gpu::Targets::texture`]). A texture no step
    /// writes or reads is only `COPY_SRC`.
    pub textures: std::collections::HashMap<String, wgpu::TextureUsages>,
    /// A compute step stores the camera outputs (a deferred Shade).
    pub camera_stored: bool,
    /// A raster step draws the G-buffer (a deferred Shade).
    pub gbuffer: bool,
    /// Generated buffers filled per cell of the map (`Discontinuities`), not per edge.
    pub per_cell: std::collections::HashSet<String>,
    /// A step classifies the scene's edges (`Silhouettes`): the edge adjacency is built.
    pub edges: bool,
}

/// Bytes of a graph texture at a shadow-map and camera size: the shadow map's texels, or
/// the camera's for a camera-sized one (a Shade's debug output), a mip chain's 4/3 included
/// (the cost model's [`TextureDecl::bytes`]).
pub(crate) fn texture_bytes(t: &TextureDecl, shadow: u32, camera: (u32, u32)) -> u64 {
    t.bytes(graph::cost::Sizes { shadow, camera })
}

pub(crate) fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Bytes of a generated buffer of `records` records: the header (draw arguments, records
/// claimed and dropped) and the records, at least one (a scene with no edge, such as one
/// whose objects all have `casts: false`, still binds a buffer as large as the shader's
/// record array needs).
pub(crate) fn generated_bytes(record_bytes: u32, records: u64) -> u64 {
    GENERATED_HEADER_BYTES as u64 + record_bytes as u64 * records.max(1)
}

/// Bounds on what Geometry passes bind and generate. `None` is the device's own bound: the
/// edges classified in chunks of as many as one storage binding holds, and each generated
/// buffer holding as many records as one binding holds (at most one per edge). A host (or a
/// test) may set smaller ones: a frame whose silhouettes pass the record bound draws the
/// records that fit and counts the rest as dropped ([`crate::gpu::Generated::dropped`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GeneratedLimits {
    /// Edges a classification dispatch binds at once (rounded down to the device's storage
    /// offset alignment, at least one alignment's worth).
    pub edges_per_chunk: Option<u32>,
    /// Records a silhouettes buffer holds.
    pub records: Option<u64>,
}

impl GeneratedLimits {
    /// The edges per classification chunk on `limits`: a whole number of 48-byte edges
    /// whose bytes are a multiple of the storage offset alignment, within one binding.
    pub(crate) fn chunk(&self, limits: &wgpu::Limits) -> u64 {
        let align = u64::from(limits.min_storage_buffer_offset_alignment.max(1));
        let step = align / gcd(48, align);
        let binding = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size) / 48;
        let wanted = self.edges_per_chunk.map_or(binding, |n| u64::from(n).min(binding));
        (wanted / step * step).max(step)
    }

    /// Records a generated buffer of `record_bytes` holds for `edges` edges on `limits`.
    fn silhouette_records(&self, limits: &wgpu::Limits, record_bytes: u32, edges: u64) -> u64 {
        let binding = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        let fits = binding.saturating_sub(u64::from(GENERATED_HEADER_BYTES)) / u64::from(record_bytes.max(1));
        edges.min(fits).min(self.records.unwrap_or(u64::MAX))
    }
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// What an upload or a set of targets may take unless the host says otherwise
/// ([`crate::gpu::Scene::upload_within`], [`TargetLimits::max_bytes`]).
pub const DEFAULT_MAX_BYTES: u64 = 4 << 30;

/// Bounds and choices for making targets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TargetLimits {
    /// Refuse targets whose textures and generated buffers would take more than this many
    /// bytes.
    pub max_bytes: u64,
    /// Bounds on what Geometry passes bind and generate (default: the device's).
    pub generated: GeneratedLimits,
    /// Every shadow-map-sized texture (and summed-area table, and the light's depth
    /// buffer) is one, shared by the lights: they run one after another and nothing after
    /// a light's passes reads them, so peak memory does not grow with the lights. `false`
    /// gives each light its own, to read a light's textures back after the frame
    /// ([`crate::gpu::Inspect::read_light_texture`]). Transient textures are shared either
    /// way.
    pub share_light_textures: bool,
    /// Time every pass on the GPU: two timestamp writes a pass and light, resolved and
    /// copied at the end of each frame into a ring read back without waiting
    /// ([`crate::gpu::Targets::frame_times`]). Off by default: a host with its own GPU
    /// profiler does not pay the host CPU it costs (about a fifth of a frame's `record` on
    /// lavapipe, docs/embedding.md section 6); the lab's commands turn it on.
    pub timestamps: bool,
}

impl Default for TargetLimits {
    fn default() -> TargetLimits {
        TargetLimits {
            max_bytes: DEFAULT_MAX_BYTES,
            generated: GeneratedLimits::default(),
            share_light_textures: true,
            timestamps: false,
        }
    }
}

/// What a light's resources take from the scene ([`Resources::scene_parts`]).
pub(crate) struct SceneParts {
    draw: SceneDraw,
    edges: Option<EdgeBuffers>,
    generated: HashMap<String, wgpu::Buffer>,
}

/// The resources of one graph bound to one scene.
pub(crate) struct Resources {
    pub shadow_size: u32,
    pub camera_size: (u32, u32),
    /// What the scene's draws bind and draw (the geometry's buffers and draws).
    pub draw: SceneDraw,
    textures: HashMap<String, wgpu::Texture>,
    /// Summed-area tables, by texture name.
    tables: HashMap<String, wgpu::Buffer>,
    pub light_depth: wgpu::Texture,
    /// Visibility, colour, position, normal ([`CAMERA_FORMATS`]).
    pub camera: Vec<wgpu::Texture>,
    pub camera_depth: wgpu::Texture,
    /// A deferred Shade's G-buffer ([`graph::GBUFFER`]), at the camera's size; empty when
    /// no step draws one.
    pub gbuffer: Vec<wgpu::Texture>,
    /// Every view's `Frame` in one uniform buffer, written once a frame: the centre view's
    /// at offset 0, light sample k's (`SceneInputs::sample_frame`, for the passes that
    /// render one view per sample) at `(k + 1) * frame_stride`.
    pub frames: wgpu::Buffer,
    /// `FRAME_SIZE` rounded up to the device's uniform offset alignment.
    pub frame_stride: u64,
    /// The `LightSamples` uniform (every sample's view).
    pub light_samples: wgpu::Buffer,
    /// Light samples bound, and whether they close a loop.
    pub samples: u32,
    pub samples_closed: bool,
    /// The edge adjacency, when the graph has Geometry passes.
    pub edges: Option<EdgeBuffers>,
    /// Buffers generated on the GPU, by name.
    generated: HashMap<String, wgpu::Buffer>,
    /// Edges a classification dispatch binds at once ([`GeneratedLimits::chunk`]).
    pub edges_per_chunk: u64,
}

/// The distance between two views' `Frame`s in a light's one buffer ([`Resources::frames`]):
/// `FRAME_SIZE` rounded up to the device's uniform offset alignment.
pub(crate) fn frame_stride(gpu: &Gpu) -> u64 {
    u64::from(FRAME_SIZE).next_multiple_of(u64::from(gpu.limits.min_uniform_buffer_offset_alignment.max(1)))
}

/// Each of `frames` into its slot of `bytes` (one every `stride` bytes), as
/// [`Resources::frames`] holds them: at binding, and every frame ([`crate::update`]).
pub(crate) fn pack_frames<F: std::borrow::Borrow<graph::FrameUniform>>(bytes: &mut [u8], stride: usize, frames: impl Iterator<Item = F>) {
    for (chunk, f) in bytes.chunks_exact_mut(stride).zip(frames) {
        chunk[..FRAME_SIZE as usize].copy_from_slice(&f.borrow().to_array());
    }
}

impl Resources {
    /// The centre view's `Frame`, as a binding.
    pub fn centre_frame(&self) -> wgpu::BindingResource<'_> {
        self.frame_at(0)
    }

    /// Light sample `k`'s `Frame`, as a binding; `None` past the samples bound.
    pub fn sample_frame(&self, k: usize) -> Option<wgpu::BindingResource<'_>> {
        (k < self.samples as usize).then(|| self.frame_at(k as u64 + 1))
    }

    /// The `Frame` in slot `slot` of [`Resources::frames`].
    fn frame_at(&self, slot: u64) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.frames,
            offset: slot * self.frame_stride,
            size: wgpu::BufferSize::new(u64::from(FRAME_SIZE)),
        })
    }

    /// Check the scene's sizes against the device and `limits.max_bytes` (what is left of
    /// the targets' budget), then create everything; textures the lights share are taken
    /// from `pool` (made there by the first light).
    ///
    /// `scene`: what the draws bind and the edges Silhouettes steps classify, shared by
    /// every light (the uploaded [`crate::gpu::Scene`]); `s` gives the sizes, the camera and
    /// the light, and its `vertices` are not read here.
    pub fn new(
        gpu: &Gpu,
        graph: &PassGraph,
        usages: &Usages,
        s: &SceneInputs,
        scene: &HostScene,
        limits: TargetLimits,
        pool: &mut Pool,
    ) -> Result<Resources> {
        let (max_bytes, limits) = (limits.max_bytes, limits.generated);
        // every size checked before anything is created (lavapipe keeps allocating past
        // its limits); the textures the pool already holds are not made again (checked
        // against `max_bytes` below, with the generated buffers)
        let all = check_sizes(gpu, graph, s.shadow_size, s.camera_size, u64::MAX)?;
        let texture_bytes = all.saturating_sub(pool.bytes());
        let edge_count = scene.edges.as_ref().map_or(0, |e| e.extent.into());
        let bytes = texture_bytes + check_generated(gpu, graph, usages, s.shadow_size, edge_count, limits)?;
        if bytes > max_bytes {
            return Err(RuntimeError::Limit {
                what: "textures and generated buffers of this graph at this scene's sizes (bytes)".into(),
                needed: bytes,
                limit: max_bytes,
            });
        }
        let frame_stride = frame_stride(gpu);
        gpu.scoped("scene resources", || {
            let make = Make { gpu };
            let (textures, tables) = make.graph_textures(graph, usages, s.shadow_size, s.camera_size, None, Some(pool));
            let (camera, camera_depth, gbuffer) = make.camera_targets(usages, s.camera_size);
            Resources {
                shadow_size: s.shadow_size,
                camera_size: s.camera_size,
                draw: scene.draw.clone(),
                textures,
                tables,
                light_depth: pool.light_depth(|| {
                    make.attachment(
                        "light depth",
                        (s.shadow_size, s.shadow_size),
                        DEPTH_FORMAT,
                        wgpu::TextureUsages::empty(),
                    )
                }),
                camera,
                camera_depth,
                gbuffer,
                frames: {
                    let mut bytes = vec![0u8; frame_stride as usize * (1 + s.samples.len())];
                    let views = std::iter::once(s.frame()).chain((0..s.samples.len()).filter_map(|k| s.sample_frame(k)));
                    pack_frames(&mut bytes, frame_stride as usize, views);
                    make.uniform_sized("frames", &bytes, bytes.len())
                },
                frame_stride,
                light_samples: make.uniform_sized(
                    "light samples",
                    &SampleViewUniform::light_samples_bytes(&s.light_samples()),
                    LIGHT_SAMPLES_SIZE as usize,
                ),
                samples: s.samples.len() as u32,
                samples_closed: s.samples_closed,
                edges: scene.edges.clone(),
                generated: make.generated(graph, usages, edge_count, s.shadow_size, limits),
                edges_per_chunk: limits.chunk(&gpu.limits),
            }
        })
    }

    /// A new camera size: the camera-sized targets (the camera outputs and depth, a
    /// deferred Shade's G-buffer, camera-sized graph textures such as debug outputs) are
    /// created again, checked first as at binding; the shadow-map-sized ones, the tables,
    /// the uniforms and the generated buffers stay. The caller binds the steps again.
    pub fn resize_camera(&mut self, gpu: &Gpu, graph: &PassGraph, usages: &Usages, camera_size: (u32, u32), max_bytes: u64) -> Result<()> {
        check_sizes(gpu, graph, self.shadow_size, camera_size, max_bytes)?;
        let (textures, targets) = gpu.scoped("camera-sized targets", || {
            let make = Make { gpu };
            let (textures, _) = make.graph_textures(graph, usages, self.shadow_size, camera_size, Some(graph::Extent::Camera), None);
            (textures, make.camera_targets(usages, camera_size))
        })?;
        let (camera, camera_depth, gbuffer) = targets;
        self.textures.extend(textures);
        (self.camera, self.camera_depth, self.gbuffer) = (camera, camera_depth, gbuffer);
        self.camera_size = camera_size;
        Ok(())
    }

    /// What these resources take from another scene under the same targets (meshes added
    /// or removed: a new upload): its draws, its edge adjacency, and generated buffers
    /// sized from its edges, checked first as at binding (against `limits.max_bytes`, what
    /// is left of the budget). Nothing here changes until [`Resources::take_scene`].
    pub fn scene_parts(
        &self,
        gpu: &Gpu,
        graph: &PassGraph,
        usages: &Usages,
        scene: &HostScene,
        limits: TargetLimits,
    ) -> Result<(SceneParts, u64)> {
        let edge_count = scene.edges.as_ref().map_or(0, |e| e.extent.into());
        let bytes = check_generated(gpu, graph, usages, self.shadow_size, edge_count, limits.generated)?;
        if bytes > limits.max_bytes {
            return Err(RuntimeError::Limit {
                what: "generated buffers of this graph on this scene (bytes)".into(),
                needed: bytes,
                limit: limits.max_bytes,
            });
        }
        let generated = gpu.scoped("generated buffers", || {
            Make { gpu }.generated(graph, usages, edge_count, self.shadow_size, limits.generated)
        })?;
        let parts = SceneParts {
            draw: scene.draw.clone(),
            edges: scene.edges.clone(),
            generated,
        };
        Ok((parts, bytes))
    }

    /// Take another scene's parts ([`Resources::scene_parts`]); the caller binds the steps
    /// again.
    pub fn take_scene(&mut self, parts: SceneParts) {
        self.draw = parts.draw;
        self.edges = parts.edges;
        self.generated = parts.generated;
    }

    pub fn texture(&self, name: &str) -> Result<&wgpu::Texture> {
        self.textures
            .get(name)
            .ok_or_else(|| RuntimeError::NotFound(format!("no texture `{name}`")))
    }

    pub fn generated(&self, name: &str) -> Result<&wgpu::Buffer> {
        self.generated
            .get(name)
            .ok_or_else(|| RuntimeError::NotFound(format!("no generated buffer `{name}`")))
    }

    pub fn edges(&self) -> Result<&EdgeBuffers> {
        self.edges
            .as_ref()
            .ok_or_else(|| RuntimeError::NotFound("the graph has no Geometry pass: no edge adjacency was built".into()))
    }

    pub fn table(&self, name: &str) -> Result<&wgpu::Buffer> {
        self.tables
            .get(name)
            .ok_or_else(|| RuntimeError::NotFound(format!("no summed-area table `{name}`")))
    }
}

/// The sizes of a scene checked against the device and `max_bytes`: the shadow map and
/// the camera image, the graph's textures and the summed-area tables. Returns the
/// textures' bytes.
fn check_sizes(gpu: &Gpu, graph: &PassGraph, shadow_size: u32, camera_size: (u32, u32), max_bytes: u64) -> Result<u64> {
    let max_dim = gpu.limits.max_texture_dimension_2d;
    // a size of 0 is no image at all, not one above the device's limit (a camera of
    // (0, 240) read "needs 240, above the device's limit of 8192"; issue 49)
    if shadow_size == 0 {
        return Err(RuntimeError::Param("the shadow map is 0 texels wide: it needs at least 1".into()));
    }
    if camera_size.0 == 0 || camera_size.1 == 0 {
        return Err(RuntimeError::Param(format!(
            "the camera image is {} x {} pixels: it needs at least 1 x 1",
            camera_size.0, camera_size.1
        )));
    }
    if shadow_size > max_dim {
        return Err(RuntimeError::Limit {
            what: "shadow map (texels per side)".into(),
            needed: shadow_size as u64,
            limit: max_dim as u64,
        });
    }
    let (cw, ch) = camera_size;
    if cw.max(ch) > max_dim {
        return Err(RuntimeError::Limit {
            what: "camera image (pixels per side)".into(),
            needed: cw.max(ch) as u64,
            limit: max_dim as u64,
        });
    }
    // the light's depth attachment, the camera's four targets and its depth
    let (depth, camera) = (
        u64::from(graph::cost::DEPTH_BYTES_PER_TEXEL),
        u64::from(graph::cost::CAMERA_BYTES_PER_PIXEL),
    );
    let mut bytes: u64 = shadow_size as u64 * shadow_size as u64 * depth + cw as u64 * ch as u64 * (camera + depth);
    for t in &graph.textures {
        bytes += texture_bytes(t, shadow_size, camera_size);
    }
    if bytes > max_bytes {
        return Err(RuntimeError::Limit {
            what: "textures of this graph at this scene's sizes (bytes)".into(),
            needed: bytes,
            limit: max_bytes,
        });
    }
    let storage_limit = gpu.limits.max_storage_buffer_binding_size.min(gpu.limits.max_buffer_size);
    for t in graph.textures.iter().filter(|t| t.format.is_table()) {
        let size = table_bytes(t, shadow_size);
        if size > storage_limit {
            return Err(RuntimeError::Limit {
                what: format!("summed-area table `{}` (storage buffer bytes)", t.name),
                needed: size,
                limit: storage_limit,
            });
        }
    }
    Ok(bytes)
}

/// Each generated buffer, sized from the edge count, against the storage-binding limit:
/// their bytes together.
fn check_generated(
    gpu: &Gpu,
    graph: &PassGraph,
    usages: &Usages,
    shadow_size: u32,
    edge_count: u64,
    limits: GeneratedLimits,
) -> Result<u64> {
    let storage_limit = gpu.limits.max_storage_buffer_binding_size.min(gpu.limits.max_buffer_size);
    let mut bytes = 0;
    for b in &graph.buffers {
        let records = buffer_records(&gpu.limits, usages, b, edge_count, shadow_size, limits);
        let size = generated_bytes(b.record_bytes, records);
        if size > storage_limit {
            return Err(RuntimeError::Limit {
                what: format!("generated buffer `{}` ({records} records x {} bytes)", b.name, b.record_bytes),
                needed: size,
                limit: storage_limit,
            });
        }
        bytes += size;
    }
    Ok(bytes)
}

/// A graph texture as made: a texture, or a summed-area table's storage buffer.
#[derive(Clone)]
enum Made {
    Texture(wgpu::Texture),
    Table(wgpu::Buffer),
}

/// The textures the lights of one set of targets share, made once at the targets' sizes
/// and keyed by declaration: every transient one, and, when the lights share their
/// textures, every shadow-map-sized one (tables included) and the light's depth buffer.
/// Each light's passes run before the next light's, and nothing after a light's passes
/// reads these, so one serves every light.
pub(crate) struct Pool {
    share_light: bool,
    entries: HashMap<String, (Made, u64)>,
    light_depth: Option<wgpu::Texture>,
}

impl Pool {
    pub fn new(share_light: bool) -> Pool {
        Pool {
            share_light,
            entries: HashMap::new(),
            light_depth: None,
        }
    }

    /// Whether `t` is made once for every light.
    fn shares(&self, t: &TextureDecl) -> bool {
        t.transient || (self.share_light && t.extent == graph::Extent::ShadowMap)
    }

    /// The light's depth buffer: shared when the lights share their textures.
    fn light_depth(&mut self, make: impl FnOnce() -> wgpu::Texture) -> wgpu::Texture {
        if !self.share_light {
            return make();
        }
        self.light_depth.get_or_insert_with(make).clone()
    }

    /// Bytes of the graph textures made so far.
    pub fn bytes(&self) -> u64 {
        self.entries.values().map(|e| e.1).sum()
    }

    /// Whether graph texture `name` was made here.
    pub fn holds(&self, name: &str) -> bool {
        self.entries.contains_key(name)
    }

    /// The names of the graph textures made here, sorted.
    pub fn names(&self) -> Vec<String> {
        let mut names: Vec<String> = self.entries.keys().cloned().collect();
        names.sort();
        names
    }
}

/// Creating the resources, inside the caller's error scope (the sizes are checked).
struct Make<'a> {
    gpu: &'a Gpu,
}

impl Make<'_> {
    /// The graph's textures at the shadow map's size (a Shade's debug outputs at the
    /// camera's), and its summed-area tables (storage buffers), by name.
    fn graph_textures(
        &self,
        graph: &PassGraph,
        usages: &Usages,
        shadow_size: u32,
        camera_size: (u32, u32),
        only: Option<graph::Extent>,
        mut pool: Option<&mut Pool>,
    ) -> (HashMap<String, wgpu::Texture>, HashMap<String, wgpu::Buffer>) {
        let (mut textures, mut tables) = (HashMap::new(), HashMap::new());
        // every texture, or those of one extent (tables are shadow-map sized)
        let wanted = |t: &&TextureDecl| only.is_none_or(|e| t.extent == e && !t.format.is_table());
        for t in graph.textures.iter().filter(wanted) {
            // made once for the lights that share it
            if let Some(pool) = pool.as_deref_mut()
                && pool.shares(t)
            {
                let bytes = texture_bytes(t, shadow_size, camera_size);
                let (made, _) = pool
                    .entries
                    .entry(t.name.clone())
                    .or_insert_with(|| (self.graph_texture(t, usages, shadow_size, camera_size), bytes));
                match made.clone() {
                    Made::Texture(tex) => textures.insert(t.name.clone(), tex).map(drop),
                    Made::Table(buf) => tables.insert(t.name.clone(), buf).map(drop),
                };
                continue;
            }
            match self.graph_texture(t, usages, shadow_size, camera_size) {
                Made::Texture(tex) => textures.insert(t.name.clone(), tex).map(drop),
                Made::Table(buf) => tables.insert(t.name.clone(), buf).map(drop),
            };
        }
        (textures, tables)
    }

    /// One graph texture (or summed-area table) at these sizes.
    fn graph_texture(&self, t: &TextureDecl, usages: &Usages, shadow_size: u32, camera_size: (u32, u32)) -> Made {
        {
            let Some(format) = wgpu_format(t.format) else {
                let buf = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(&t.name),
                    size: table_bytes(t, shadow_size),
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                return Made::Table(buf);
            };
            let (width, height) = match t.extent {
                graph::Extent::ShadowMap => (shadow_size, shadow_size),
                graph::Extent::Camera => camera_size,
            };
            let tex = self.gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(&t.name),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: t.array_layers(),
                },
                mip_level_count: if t.mips { mip_count(shadow_size) } else { 1 },
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                // from the steps that declare it (`Usages::of`)
                usage: usages.texture(&t.name),
                view_formats: &[],
            });
            Made::Texture(tex)
        }
    }

    /// The camera-sized attachments: the camera outputs ([`CAMERA_FORMATS`]), the camera's
    /// depth, and a deferred Shade's G-buffer ([`graph::GBUFFER`]; empty without one).
    fn camera_targets(&self, usages: &Usages, (cw, ch): (u32, u32)) -> (Vec<wgpu::Texture>, wgpu::Texture, Vec<wgpu::Texture>) {
        let none = wgpu::TextureUsages::empty();
        let sampled = wgpu::TextureUsages::TEXTURE_BINDING;
        // a deferred Shade stores the camera outputs from a compute step
        let camera_stored = if usages.camera_stored {
            wgpu::TextureUsages::STORAGE_BINDING
        } else {
            none
        };
        let gbuffer = if usages.gbuffer {
            ["g-buffer world", "g-buffer normal", "g-buffer footprint"]
                .iter()
                .zip(graph::GBUFFER)
                // storage: a host's pixels are written into it by a compute step
                .filter_map(|(n, f)| {
                    wgpu_format(f).map(|f| self.attachment(n, (cw, ch), f, sampled | wgpu::TextureUsages::STORAGE_BINDING))
                })
                .collect()
        } else {
            Vec::new()
        };
        (
            ["visibility", "color", "position", "normal"]
                .iter()
                .zip(CAMERA_FORMATS)
                .map(|(n, f)| self.attachment(n, (cw, ch), f, camera_stored | sampled))
                .collect(),
            self.attachment("camera depth", (cw, ch), DEPTH_FORMAT, none),
            gbuffer,
        )
    }

    /// A render attachment of one layer and level (a depth buffer, a camera output, the
    /// G-buffer), readable back, with `usage` besides.
    fn attachment(&self, label: &str, (w, h): (u32, u32), format: wgpu::TextureFormat, usage: wgpu::TextureUsages) -> wgpu::Texture {
        self.gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC | usage,
            view_formats: &[],
        })
    }

    /// A uniform of `size` bytes holding `bytes` at its start.
    fn uniform_sized(&self, label: &str, bytes: &[u8], size: usize) -> wgpu::Buffer {
        let buf = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: size as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.gpu.queue.write_buffer(&buf, 0, bytes);
        buf
    }

    /// A storage buffer holding `data`, at least `min` bytes (a storage binding may not be
    /// empty: every buffer holds at least one element).
    fn storage(&self, label: &str, data: &[u8], min: usize, usage: wgpu::BufferUsages) -> wgpu::Buffer {
        let buf = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: data.len().max(min) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | usage,
            mapped_at_creation: false,
        });
        if !data.is_empty() {
            self.gpu.queue.write_buffer(&buf, 0, data);
        }
        buf
    }

    /// The generated buffers, by name: draw arguments at their start (vertex count 0, reset
    /// every frame; instance count 1), then their records.
    fn generated(
        &self,
        graph: &PassGraph,
        usages: &Usages,
        edge_count: u64,
        shadow_size: u32,
        limits: GeneratedLimits,
    ) -> HashMap<String, wgpu::Buffer> {
        // the header: draw arguments (instance count 1), records claimed and dropped, padding
        let args: Vec<u8> = [0u32, 1, 0, 0, 0, 0, 0, 0].iter().flat_map(|x| x.to_le_bytes()).collect();
        graph
            .buffers
            .iter()
            .map(|b| {
                let size = generated_bytes(
                    b.record_bytes,
                    buffer_records(&self.gpu.limits, usages, b, edge_count, shadow_size, limits),
                ) as usize;
                let usage = wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_SRC;
                (b.name.clone(), self.storage(&b.name, &args, size, usage))
            })
            .collect()
    }
}

/// Records a generated buffer holds: for a `Silhouettes` step's, one per edge but no more
/// than one storage binding holds (or [`GeneratedLimits::records`]); for a
/// `Discontinuities` step's, one per triangle of the mesh of texel centres (two per cell,
/// at most [`graph::MAX_DISCONTINUITY_RECORDS`]).
fn buffer_records(
    device: &wgpu::Limits,
    usages: &Usages,
    b: &graph::BufferDecl,
    edges: u64,
    shadow_size: u32,
    limits: GeneratedLimits,
) -> u64 {
    if usages.per_cell.contains(&b.name) {
        let cells = u64::from(shadow_size.saturating_sub(1)).pow(2);
        (2 * cells).min(u64::from(graph::MAX_DISCONTINUITY_RECORDS))
    } else {
        limits.silhouette_records(device, b.record_bytes, edges)
    }
}
