//! The wgpu executor: loads a compiled pass graph (treated as untrusted input), binds a
//! scene, runs frames with GPU timestamps per pass, and reads any texture back.
//!
//! Every wgpu object is created inside an error scope and its error returned as a value;
//! errors that escape a scope are collected by the device's uncaptured-error handler
//! instead of wgpu's default, which panics. Sizes are checked against the device's limits
//! before anything is allocated (lavapipe keeps allocating past its limits).

use crate::graph::{self, Binding, Draw, Format, PassGraph, Step, TextureDecl, View};
use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Why the runtime could not do what was asked.
#[derive(Clone, Debug, PartialEq)]
pub enum RuntimeError {
    /// No GPU adapter: the message names what to install.
    NoAdapter(String),
    Device(String),
    Graph(graph::GraphError),
    /// A file named by the graph could not be read, or lies outside the graph's folder.
    File {
        path: PathBuf,
        message: String,
    },
    /// A shader module of the graph does not validate.
    Shader {
        file: String,
        message: String,
    },
    /// A resource exceeds the device's limits.
    Limit {
        what: String,
        needed: u64,
        limit: u64,
    },
    /// wgpu refused an object or a command.
    Wgpu {
        context: String,
        message: String,
    },
    Param(String),
    NotFound(String),
}

impl fmt::Display for RuntimeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RuntimeError::NoAdapter(m) => write!(f, "no GPU adapter: {m}"),
            RuntimeError::Device(m) => write!(f, "cannot open the GPU device: {m}"),
            RuntimeError::Graph(e) => write!(f, "{e}"),
            RuntimeError::File { path, message } => write!(f, "{}: {message}", path.display()),
            RuntimeError::Shader { file, message } => write!(f, "shader `{file}` does not validate:\n{message}"),
            RuntimeError::Limit { what, needed, limit } => write!(f, "{what} needs {needed}, above the device's limit of {limit}"),
            RuntimeError::Wgpu { context, message } => write!(f, "{context}: {message}"),
            RuntimeError::Param(m) => write!(f, "{m}"),
            RuntimeError::NotFound(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for RuntimeError {}

impl From<graph::GraphError> for RuntimeError {
    fn from(e: graph::GraphError) -> Self {
        RuntimeError::Graph(e)
    }
}

pub type Result<T> = std::result::Result<T, RuntimeError>;

/// What to install when no adapter exists.
pub const INSTALL_HINT: &str = "install the Vulkan loader and Mesa's lavapipe CPU driver (Debian/Ubuntu: `apt-get install -y libvulkan1 mesa-vulkan-drivers`), or a GPU driver with Vulkan support";

/// An open device.
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub features: wgpu::Features,
    pub limits: wgpu::Limits,
    uncaptured: Arc<Mutex<Vec<String>>>,
    /// Pipelines by what determines them (shader source, entry points, formats, bindings):
    /// lavapipe compiles each pipeline through LLVM, so executors of one technique on
    /// several scenes share them.
    pipelines: Mutex<HashMap<u64, Arc<StepPipeline>>>,
    modules: Mutex<HashMap<u64, wgpu::ShaderModule>>,
}

impl Gpu {
    /// Open the first Vulkan adapter, headless.
    pub fn new() -> Result<Gpu> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::VULKAN,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            apply_limit_buckets: false,
        }))
        .map_err(|e| RuntimeError::NoAdapter(format!("{e}; {INSTALL_HINT}")))?;
        let wanted = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::FLOAT32_FILTERABLE | wgpu::Features::TEXTURE_FORMAT_16BIT_NORM;
        let features = adapter.features() & wanted;
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("sshc"),
            required_features: features,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| RuntimeError::Device(e.to_string()))?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        Ok(Gpu {
            device,
            queue,
            info: adapter.get_info(),
            features,
            limits,
            uncaptured,
            pipelines: Mutex::new(HashMap::new()),
            modules: Mutex::new(HashMap::new()),
        })
    }

    /// Number of pipelines built on this device so far (each is built once per distinct
    /// shader, entry points, formats and bindings).
    pub fn cached_pipelines(&self) -> usize {
        self.pipelines.lock().map(|c| c.len()).unwrap_or(0)
    }

    /// "name (backend, driver)" for reports.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {} {})",
            self.info.name, self.info.backend, self.info.driver, self.info.driver_info
        )
    }

    /// Run `f` inside validation and out-of-memory error scopes; wgpu's error becomes a value.
    pub fn scoped<T>(&self, context: &str, f: impl FnOnce() -> T) -> Result<T> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let v = f();
        let e1 = pollster::block_on(validation.pop());
        let e2 = pollster::block_on(oom.pop());
        match e1.or(e2) {
            Some(e) => Err(RuntimeError::Wgpu {
                context: context.to_string(),
                message: e.to_string(),
            }),
            None => self.take_uncaptured(context).map(|_| v),
        }
    }

    fn take_uncaptured(&self, context: &str) -> Result<()> {
        let mut v = self
            .uncaptured
            .lock()
            .map_err(|_| RuntimeError::Device("error sink poisoned".into()))?;
        if v.is_empty() {
            Ok(())
        } else {
            let message = v.join("\n");
            v.clear();
            Err(RuntimeError::Wgpu {
                context: context.to_string(),
                message,
            })
        }
    }
}

/// Everything the executor needs from a scene, as plain data (column-major matrices).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneInputs {
    /// Interleaved world-space position xyz and normal xyz, three vertices per triangle.
    pub vertices: Vec<f32>,
    pub camera_view_proj: [f32; 16],
    pub camera_position: [f32; 3],
    pub camera_size: (u32, u32),
    pub shadow_size: u32,
    pub light_view: [f32; 16],
    pub light_view_proj: [f32; 16],
    /// xyz position (w = 1) or direction towards the light (w = 0).
    pub light_position: [f32; 4],
    pub near: f32,
    pub far: f32,
    /// Radius or half-extent, world units.
    pub light_size: f32,
    /// Half-extents of the light along the shadow map's u and v axes, world units.
    pub light_half_extents: [f32; 2],
    /// Full angular diameter, radians.
    pub light_angle: f32,
    /// Element [1][1] of the light's projection (1 / tan(fov / 2), or 2 / height for an orthographic light).
    pub light_proj_y: f32,
    pub light_orthographic: bool,
}

/// A texture read back, as f32 RGBA per texel (missing components 0, alpha 1), rows top first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<[f32; 4]>,
}

impl Image {
    pub fn channel(&self, c: usize) -> Vec<f32> {
        self.rgba.iter().map(|p| p[c]).collect()
    }

    pub fn at(&self, x: u32, y: u32) -> [f32; 4] {
        self.rgba[(y * self.width + x) as usize]
    }

    /// Write component `c` as a one-channel PFM (float) file.
    pub fn write_pfm_gray(&self, path: &Path, c: usize) -> Result<()> {
        write_pfm(path, self.width, self.height, false, self.channel(c))
    }

    /// Write components xyz as a three-channel PFM file.
    pub fn write_pfm_rgb(&self, path: &Path) -> Result<()> {
        let data = self.rgba.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
        write_pfm(path, self.width, self.height, true, data)
    }

    /// Write component `c` (or RGB when `None`) as an 8-bit PNG, values clamped to [0, 1].
    /// `range` maps [lo, hi] to [0, 1] first (for depth and basis images).
    pub fn write_png(&self, path: &Path, c: Option<usize>, range: (f32, f32)) -> Result<()> {
        let scale = |v: f32| {
            let t = if range.1 > range.0 {
                (v - range.0) / (range.1 - range.0)
            } else {
                v
            };
            (t.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
        };
        let err = |e: image::ImageError| RuntimeError::File {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        match c {
            Some(c) => {
                let buf: Vec<u8> = self.rgba.iter().map(|p| scale(p[c])).collect();
                image::GrayImage::from_raw(self.width, self.height, buf)
                    .ok_or_else(|| RuntimeError::NotFound("image size mismatch".into()))?
                    .save(path)
                    .map_err(err)
            }
            None => {
                let buf: Vec<u8> = self.rgba.iter().flat_map(|p| [scale(p[0]), scale(p[1]), scale(p[2])]).collect();
                image::RgbImage::from_raw(self.width, self.height, buf)
                    .ok_or_else(|| RuntimeError::NotFound("image size mismatch".into()))?
                    .save(path)
                    .map_err(err)
            }
        }
    }
}

fn write_pfm(path: &Path, w: u32, h: u32, color: bool, data: Vec<f32>) -> Result<()> {
    let pfm = pxm::PFMBuilder::new()
        .size(w as usize, h as usize)
        .color(color)
        .scale(-1.0)
        .data(data)
        .build()
        .map_err(|e| RuntimeError::File {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
    let mut f = std::fs::File::create(path).map_err(|e| RuntimeError::File {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    pfm.write_into(&mut f).map_err(|e| RuntimeError::File {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

fn wgpu_format(f: Format) -> Option<wgpu::TextureFormat> {
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
        Format::SummedAreaU32 => return None,
    })
}

/// Number of levels of a full mip chain.
pub fn mip_count(size: u32) -> u32 {
    32 - size.max(1).leading_zeros()
}

/// GPU time of each pass of one frame, in milliseconds (None without timestamp queries).
#[derive(Clone, Debug, PartialEq)]
pub struct FrameTimes {
    pub passes: Vec<(String, Option<f64>)>,
}

const CAMERA_FORMATS: [wgpu::TextureFormat; 4] = [
    wgpu::TextureFormat::R32Float,
    wgpu::TextureFormat::Rgba8Unorm,
    wgpu::TextureFormat::Rgba32Float,
    wgpu::TextureFormat::Rgba16Float,
];
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The camera outputs of the Shade pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraOutput {
    Visibility = 0,
    Color = 1,
    Position = 2,
    Normal = 3,
}

enum Pipeline {
    Render(wgpu::RenderPipeline),
    Compute(wgpu::ComputePipeline),
}

struct StepPipeline {
    pipeline: Pipeline,
    group0: wgpu::BindGroupLayout,
    /// What the step reads: textures, and summed-area tables as read-only storage buffers.
    group1: Option<wgpu::BindGroupLayout>,
    /// What a compute step writes: summed-area tables as read-write storage buffers.
    group2: Option<wgpu::BindGroupLayout>,
}

struct Bound {
    shadow_size: u32,
    camera_size: (u32, u32),
    vertices: wgpu::Buffer,
    vertex_count: u32,
    textures: HashMap<String, wgpu::Texture>,
    /// Summed-area tables, by texture name.
    buffers: HashMap<String, wgpu::Buffer>,
    light_depth: wgpu::Texture,
    camera: Vec<wgpu::Texture>,
    camera_depth: wgpu::Texture,
    frame: wgpu::Buffer,
}

/// A loaded pass graph, ready to run.
pub struct Executor<'g> {
    gpu: &'g Gpu,
    pub graph: PassGraph,
    /// Shader module and the hash of its source, by file name.
    modules: HashMap<String, (wgpu::ShaderModule, u64)>,
    pipelines: Vec<Vec<Arc<StepPipeline>>>,
    params: Vec<u8>,
    params_buf: Option<wgpu::Buffer>,
    sampler: wgpu::Sampler,
    bound: Option<Bound>,
    timestamps: Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
    /// Linear depth written into the Depth pass's output instead of rasterising the scene.
    depth_override: Option<Vec<f32>>,
    /// Refuse scenes whose textures would take more than this many bytes.
    pub max_bytes: u64,
}

impl<'g> Executor<'g> {
    /// Load `T.graph.ron` and the shader files it names, from the graph's own folder.
    pub fn load(gpu: &'g Gpu, graph_path: &Path) -> Result<Executor<'g>> {
        let io = |path: &Path, e: std::io::Error| RuntimeError::File {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let text = std::fs::read_to_string(graph_path).map_err(|e| io(graph_path, e))?;
        let graph = PassGraph::from_ron(&text)?;
        let dir = graph_path.parent().unwrap_or(Path::new("."));
        let canon_dir = dir.canonicalize().map_err(|e| io(dir, e))?;
        let mut shaders = Vec::new();
        for p in &graph.passes {
            let path = dir.join(&p.shader);
            let canon = path.canonicalize().map_err(|e| io(&path, e))?;
            if !canon.starts_with(&canon_dir) {
                return Err(RuntimeError::File {
                    path,
                    message: "lies outside the graph's folder (through a link)".into(),
                });
            }
            let src = std::fs::read_to_string(&canon).map_err(|e| io(&path, e))?;
            shaders.push((p.shader.clone(), src));
        }
        Executor::new(gpu, graph, shaders)
    }

    /// Build from a graph and its shader sources (as the compiler's API returns them).
    pub fn new(gpu: &'g Gpu, graph: PassGraph, shaders: Vec<(String, String)>) -> Result<Executor<'g>> {
        // The graph is untrusted: check references, re-validate every module with naga,
        // and check declared sizes against the device before creating anything.
        let text = graph.to_ron();
        let graph = PassGraph::from_ron(&text)?;
        let mut modules = HashMap::new();
        for p in &graph.passes {
            let src = shaders
                .iter()
                .find(|(f, _)| f == &p.shader)
                .map(|(_, s)| s.as_str())
                .ok_or_else(|| RuntimeError::NotFound(format!("pass `{}` names shader `{}`, which was not given", p.name, p.shader)))?;
            validate_wgsl(src).map_err(|message| RuntimeError::Shader {
                file: p.shader.clone(),
                message,
            })?;
            if !modules.contains_key(&p.shader) {
                let key = hash_of(&[src]);
                let cached = gpu.modules.lock().ok().and_then(|c| c.get(&key).cloned());
                let m = match cached {
                    Some(m) => m,
                    None => {
                        let m = gpu.scoped(&format!("shader `{}`", p.shader), || {
                            gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                                label: Some(&p.shader),
                                source: wgpu::ShaderSource::Wgsl(src.into()),
                            })
                        })?;
                        if let Ok(mut c) = gpu.modules.lock() {
                            c.insert(key, m.clone());
                        }
                        m
                    }
                };
                modules.insert(p.shader.clone(), (m, key));
            }
        }
        for t in &graph.textures {
            let limit = gpu.limits.max_texture_array_layers;
            if t.layers > limit {
                return Err(RuntimeError::Limit {
                    what: format!("texture `{}` (array layers)", t.name),
                    needed: t.layers as u64,
                    limit: limit as u64,
                });
            }
            if t.format == Format::SummedAreaU32 && t.mips {
                return Err(RuntimeError::NotFound(format!(
                    "texture `{}`: a summed-area table has no mip levels",
                    t.name
                )));
            }
            if matches!(t.format, Format::R16Unorm | Format::Rg16Unorm | Format::Rgba16Unorm)
                && !gpu.features.contains(wgpu::Features::TEXTURE_FORMAT_16BIT_NORM)
            {
                return Err(RuntimeError::Device(format!(
                    "texture `{}` is {:?}, which this device cannot store (no 16-bit norm formats)",
                    t.name, t.format
                )));
            }
        }
        // Params: the uniform must fit the device, and every field must lie inside it.
        let max_uniform = gpu.limits.max_uniform_buffer_binding_size;
        if graph.params_size as u64 > max_uniform || graph.params_size % 4 != 0 {
            return Err(RuntimeError::Limit {
                what: "the Params uniform (bytes, a multiple of 4)".into(),
                needed: graph.params_size as u64,
                limit: max_uniform,
            });
        }
        for p in &graph.params {
            if let Some(off) = p.offset
                && (off % 4 != 0 || off as u64 + 4 > graph.params_size as u64)
            {
                return Err(RuntimeError::Param(format!(
                    "param `{}` lies at byte {off}, outside the {}-byte Params uniform",
                    p.name, graph.params_size
                )));
            }
        }
        let params = default_params(&graph);
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("sshc linear clamp"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            address_mode_w: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let mut ex = Executor {
            gpu,
            graph,
            modules,
            pipelines: vec![],
            params,
            params_buf: None,
            sampler,
            bound: None,
            timestamps: None,
            depth_override: None,
            max_bytes: 4 << 30,
        };
        ex.build_pipelines()?;
        if ex.graph.params_size > 0 {
            ex.params_buf = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("params"),
                size: ex.graph.params_size as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        if gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
            let n = (ex.graph.passes.len() * 2) as u32;
            let qs = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass times"),
                ty: wgpu::QueryType::Timestamp,
                count: n,
            });
            let resolve = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: n as u64 * 8,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let read = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps read"),
                size: n as u64 * 8,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            ex.timestamps = Some((qs, resolve, read));
        }
        Ok(ex)
    }

    fn texture_format(&self, name: &str) -> Result<wgpu::TextureFormat> {
        let t = self
            .graph
            .texture(name)
            .ok_or_else(|| RuntimeError::NotFound(format!("no texture `{name}`")))?;
        wgpu_format(t.format).ok_or_else(|| RuntimeError::NotFound(format!("texture `{name}` has no texture format")))
    }

    /// A summed-area table (a storage buffer, not a texture).
    fn is_table(&self, name: &str) -> bool {
        self.graph.texture(name).is_some_and(|t| t.format == Format::SummedAreaU32)
    }

    fn build_pipelines(&mut self) -> Result<()> {
        let gpu = self.gpu;
        let filterable_floats = gpu.features.contains(wgpu::Features::FLOAT32_FILTERABLE);
        let mut all = Vec::new();
        for pass in &self.graph.passes {
            let (module, source_key) = &self.modules[&pass.shader];
            let mut steps = Vec::new();
            for step in &pass.steps {
                let ctx = format!("pipeline of pass `{}` ({:?})", pass.name, step.fragment);
                let compute = matches!(step.draw, Draw::ComputeRows | Draw::ComputeColumns);
                let formats: Vec<String> = match step.draw {
                    Draw::SceneFromCamera => CAMERA_FORMATS.iter().map(|f| format!("{f:?}")).collect(),
                    _ if compute => step.writes.iter().map(|t| format!("table {}", t.texture)).collect(),
                    _ => step
                        .writes
                        .iter()
                        .map(|t| self.texture_format(&t.texture).map(|f| format!("{f:?}")))
                        .collect::<Result<_>>()?,
                };
                let key = hash_of(&[
                    &source_key.to_string(),
                    &format!("{:?}{:?}{:?}{:?}", step.vertex, step.fragment, step.compute, step.draw),
                    &formats.join(","),
                    &format!("{}:{}:{}:{}", step.reads.len(), step.params, step.sampler, filterable_floats),
                ]);
                if let Some(p) = gpu.pipelines.lock().ok().and_then(|c| c.get(&key).cloned()) {
                    steps.push(p);
                    continue;
                }
                let group0 = group0_layout(gpu, step);
                let group1 = if step.reads.is_empty() {
                    None
                } else {
                    let mut entries = Vec::new();
                    for b in &step.reads {
                        if self.is_table(&b.texture) {
                            entries.push(storage_entry(b.binding, true));
                            continue;
                        }
                        let fmt = self.texture_format(&b.texture)?;
                        let is_f32 = matches!(
                            fmt,
                            wgpu::TextureFormat::R32Float | wgpu::TextureFormat::Rg32Float | wgpu::TextureFormat::Rgba32Float
                        );
                        if step.sampler && is_f32 && !filterable_floats {
                            return Err(RuntimeError::Device(format!(
                                "pass `{}` filters 32-bit float texture `{}`, but this device cannot filter 32-bit floats",
                                pass.name, b.texture
                            )));
                        }
                        entries.push(wgpu::BindGroupLayoutEntry {
                            binding: b.binding,
                            visibility: wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
                            ty: wgpu::BindingType::Texture {
                                sample_type: wgpu::TextureSampleType::Float { filterable: step.sampler },
                                view_dimension: wgpu::TextureViewDimension::D2Array,
                                multisampled: false,
                            },
                            count: None,
                        });
                    }
                    Some(gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                        label: Some("textures"),
                        entries: &entries,
                    }))
                };
                let group2 = compute.then(|| {
                    let entries: Vec<wgpu::BindGroupLayoutEntry> = (0..step.writes.len() as u32).map(|i| storage_entry(i, false)).collect();
                    gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                        label: Some("tables"),
                        entries: &entries,
                    })
                });
                // An empty group 1 keeps group 2 at its index when a compute step reads nothing.
                let empty = gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("empty"),
                    entries: &[],
                });
                let mut layouts: Vec<Option<&wgpu::BindGroupLayout>> = vec![Some(&group0)];
                if group1.is_some() || group2.is_some() {
                    layouts.push(Some(group1.as_ref().unwrap_or(&empty)));
                }
                if let Some(g2) = &group2 {
                    layouts.push(Some(g2));
                }
                let layout = gpu.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(&ctx),
                    bind_group_layouts: &layouts,
                    immediate_size: 0,
                });
                if compute {
                    let pipeline = gpu.scoped(&ctx, || {
                        gpu.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                            label: Some(&ctx),
                            layout: Some(&layout),
                            module,
                            entry_point: step.compute.as_deref(),
                            compilation_options: Default::default(),
                            cache: None,
                        })
                    })?;
                    let p = Arc::new(StepPipeline {
                        pipeline: Pipeline::Compute(pipeline),
                        group0,
                        group1: Some(group1.unwrap_or(empty)),
                        group2,
                    });
                    if let Ok(mut c) = gpu.pipelines.lock() {
                        c.insert(key, p.clone());
                    }
                    steps.push(p);
                    continue;
                }
                let targets: Vec<Option<wgpu::ColorTargetState>> = match step.draw {
                    Draw::SceneFromCamera => CAMERA_FORMATS.iter().map(|f| Some((*f).into())).collect(),
                    _ => step
                        .writes
                        .iter()
                        .map(|t| self.texture_format(&t.texture).map(|f| Some(f.into())))
                        .collect::<Result<_>>()?,
                };
                let vertex_layout = wgpu::VertexBufferLayout {
                    array_stride: 24,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &[
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
                    ],
                };
                let scene_draw = matches!(step.draw, Draw::SceneFromLight | Draw::SceneFromCamera);
                let buffers: Vec<Option<wgpu::VertexBufferLayout>> = if scene_draw { vec![Some(vertex_layout)] } else { vec![] };
                let pipeline = gpu.scoped(&ctx, || {
                    gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some(&ctx),
                        layout: Some(&layout),
                        vertex: wgpu::VertexState {
                            module,
                            entry_point: step.vertex.as_deref(),
                            compilation_options: Default::default(),
                            buffers: &buffers,
                        },
                        primitive: wgpu::PrimitiveState {
                            cull_mode: None,
                            ..Default::default()
                        },
                        depth_stencil: scene_draw.then(|| wgpu::DepthStencilState {
                            format: DEPTH_FORMAT,
                            depth_write_enabled: Some(true),
                            depth_compare: Some(wgpu::CompareFunction::Less),
                            stencil: Default::default(),
                            bias: Default::default(),
                        }),
                        multisample: Default::default(),
                        fragment: Some(wgpu::FragmentState {
                            module,
                            entry_point: step.fragment.as_deref(),
                            compilation_options: Default::default(),
                            targets: &targets,
                        }),
                        multiview_mask: None,
                        cache: None,
                    })
                })?;
                let p = Arc::new(StepPipeline {
                    pipeline: Pipeline::Render(pipeline),
                    group0,
                    group1,
                    group2: None,
                });
                if let Ok(mut c) = gpu.pipelines.lock() {
                    c.insert(key, p.clone());
                }
                steps.push(p);
            }
            all.push(steps);
        }
        self.pipelines = all;
        Ok(())
    }

    /// Set a runtime param (a uniform); fixed params were compiled in and cannot change.
    pub fn set_param(&mut self, name: &str, value: f64) -> Result<()> {
        let p = self
            .graph
            .params
            .iter()
            .find(|p| p.name == name)
            .ok_or_else(|| RuntimeError::Param(format!("the technique has no param `{name}`")))?;
        let Some(off) = p.offset else {
            return Err(RuntimeError::Param(format!(
                "param `{name}` is fixed at compile time; recompile with `--set {name}={value}`"
            )));
        };
        if let Some((lo, hi)) = p.range
            && !(lo..=hi).contains(&value)
        {
            return Err(RuntimeError::Param(format!(
                "param `{name}` = {value} is outside its range [{lo}, {hi}]"
            )));
        }
        let bytes = param_bytes(p.ty, value);
        self.params[off as usize..off as usize + 4].copy_from_slice(&bytes);
        Ok(())
    }

    /// Create the scene's buffers and every texture at the scene's sizes.
    pub fn bind_scene(&mut self, s: &SceneInputs) -> Result<()> {
        let gpu = self.gpu;
        let max_dim = gpu.limits.max_texture_dimension_2d;
        if s.shadow_size == 0 || s.shadow_size > max_dim {
            return Err(RuntimeError::Limit {
                what: "shadow map (texels per side)".into(),
                needed: s.shadow_size as u64,
                limit: max_dim as u64,
            });
        }
        let (cw, ch) = s.camera_size;
        if cw == 0 || ch == 0 || cw.max(ch) > max_dim {
            return Err(RuntimeError::Limit {
                what: "camera image (pixels per side)".into(),
                needed: cw.max(ch) as u64,
                limit: max_dim as u64,
            });
        }
        let texels = s.shadow_size as u64 * s.shadow_size as u64;
        let mut bytes: u64 = texels * 4 + cw as u64 * ch as u64 * (4 + 4 + 16 + 8 + 4);
        for t in &self.graph.textures {
            let per = t.format.bytes_per_texel() as u64 * t.layers as u64 * texels;
            bytes += if t.mips { per * 4 / 3 } else { per };
        }
        if bytes > self.max_bytes {
            return Err(RuntimeError::Limit {
                what: "textures of this graph at this scene's sizes (bytes)".into(),
                needed: bytes,
                limit: self.max_bytes,
            });
        }
        for t in self.graph.textures.iter().filter(|t| t.format == Format::SummedAreaU32) {
            let size = table_bytes(t, s.shadow_size);
            let limit = gpu.limits.max_storage_buffer_binding_size.min(gpu.limits.max_buffer_size);
            if size > limit {
                return Err(RuntimeError::Limit {
                    what: format!("summed-area table `{}` (storage buffer bytes)", t.name),
                    needed: size,
                    limit,
                });
            }
        }
        let vertex_count = (s.vertices.len() / 6) as u32;
        let vb_size = (s.vertices.len() * 4).max(24) as u64;
        if vb_size > gpu.limits.max_buffer_size {
            return Err(RuntimeError::Limit {
                what: "vertex buffer (bytes)".into(),
                needed: vb_size,
                limit: gpu.limits.max_buffer_size,
            });
        }
        let bound = gpu.scoped("scene resources", || {
            let vertices = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("scene vertices"),
                size: vb_size,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            if !s.vertices.is_empty() {
                gpu.queue.write_buffer(&vertices, 0, f32_bytes(&s.vertices).as_slice());
            }
            let mut textures = HashMap::new();
            let mut buffers = HashMap::new();
            for t in &self.graph.textures {
                let Some(format) = wgpu_format(t.format) else {
                    let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(&t.name),
                        size: table_bytes(t, s.shadow_size),
                        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                        mapped_at_creation: false,
                    });
                    buffers.insert(t.name.clone(), buf);
                    continue;
                };
                let tex = gpu.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(&t.name),
                    size: wgpu::Extent3d {
                        width: s.shadow_size,
                        height: s.shadow_size,
                        depth_or_array_layers: t.layers,
                    },
                    mip_level_count: if t.mips { mip_count(s.shadow_size) } else { 1 },
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::TEXTURE_BINDING
                        | wgpu::TextureUsages::COPY_SRC
                        | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                });
                textures.insert(t.name.clone(), tex);
            }
            let plain = |label: &str, w: u32, h: u32, format: wgpu::TextureFormat| {
                gpu.device.create_texture(&wgpu::TextureDescriptor {
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
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                })
            };
            let light_depth = plain("light depth", s.shadow_size, s.shadow_size, DEPTH_FORMAT);
            let camera = ["visibility", "color", "position", "normal"]
                .iter()
                .zip(CAMERA_FORMATS)
                .map(|(n, f)| plain(n, cw, ch, f))
                .collect();
            let camera_depth = plain("camera depth", cw, ch, DEPTH_FORMAT);
            let frame = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("frame"),
                size: graph::FRAME_SIZE as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            gpu.queue.write_buffer(&frame, 0, &frame_bytes(s));
            Bound {
                shadow_size: s.shadow_size,
                camera_size: s.camera_size,
                vertices,
                vertex_count,
                textures,
                buffers,
                light_depth,
                camera,
                camera_depth,
                frame,
            }
        })?;
        self.bound = Some(bound);
        Ok(())
    }

    fn bound(&self) -> Result<&Bound> {
        self.bound
            .as_ref()
            .ok_or_else(|| RuntimeError::NotFound("no scene is bound: call bind_scene first".into()))
    }

    fn group0(&self, sp: &StepPipeline, step: &Step) -> Result<wgpu::BindGroup> {
        let b = self.bound()?;
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: b.frame.as_entire_binding(),
        }];
        if step.params {
            let buf = self
                .params_buf
                .as_ref()
                .ok_or_else(|| RuntimeError::NotFound("step binds params, but the graph has none".into()))?;
            entries.push(wgpu::BindGroupEntry {
                binding: 1,
                resource: buf.as_entire_binding(),
            });
        }
        if step.sampler {
            entries.push(wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::Sampler(&self.sampler),
            });
        }
        Ok(self.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &sp.group0,
            entries: &entries,
        }))
    }

    fn texture(&self, name: &str) -> Result<&wgpu::Texture> {
        self.bound()?
            .textures
            .get(name)
            .ok_or_else(|| RuntimeError::NotFound(format!("no texture `{name}`")))
    }

    fn table(&self, name: &str) -> Result<&wgpu::Buffer> {
        self.bound()?
            .buffers
            .get(name)
            .ok_or_else(|| RuntimeError::NotFound(format!("no summed-area table `{name}`")))
    }

    fn group1(&self, sp: &StepPipeline, reads: &[Binding], level: u32) -> Result<Option<wgpu::BindGroup>> {
        let Some(layout) = &sp.group1 else { return Ok(None) };
        let mut views = Vec::new();
        for b in reads.iter().filter(|b| !self.is_table(&b.texture)) {
            let t = self.texture(&b.texture)?;
            let (base, count) = match b.view {
                View::All => (0, None),
                View::Base => (0, Some(1)),
                View::PreviousLevel => (level - 1, Some(1)),
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
        for b in reads.iter().filter(|b| self.is_table(&b.texture)) {
            entries.push(wgpu::BindGroupEntry {
                binding: b.binding,
                resource: self.table(&b.texture)?.as_entire_binding(),
            });
        }
        Ok(Some(self.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout,
            entries: &entries,
        })))
    }

    /// Compute steps: the summed-area tables they write, as read-write storage buffers.
    fn group2(&self, sp: &StepPipeline, writes: &[graph::Target]) -> Result<Option<wgpu::BindGroup>> {
        let Some(layout) = &sp.group2 else { return Ok(None) };
        let mut entries = Vec::new();
        for (i, w) in writes.iter().enumerate() {
            entries.push(wgpu::BindGroupEntry {
                binding: i as u32,
                resource: self.table(&w.texture)?.as_entire_binding(),
            });
        }
        Ok(Some(self.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout,
            entries: &entries,
        })))
    }

    /// Replace the Depth pass: its output takes these linear depths (row-major, row 0 first,
    /// `shadow_size`^2 values) instead of the scene rasterised from the light. For feeding
    /// synthetic depth fields to the passes after Depth; `None` rasterises again.
    pub fn set_depth_override(&mut self, depth: Option<Vec<f32>>) {
        self.depth_override = depth;
    }

    /// Upload the depth override into the Depth pass's output.
    fn write_depth_override(&self, pass: &graph::PassDecl, depth: &[f32]) -> Result<()> {
        let b = self.bound()?;
        let n = b.shadow_size as usize;
        if depth.len() != n * n {
            return Err(RuntimeError::Param(format!(
                "depth override has {} values, the shadow map {n} x {n}",
                depth.len()
            )));
        }
        let target = pass
            .steps
            .first()
            .and_then(|s| s.writes.first())
            .ok_or_else(|| RuntimeError::NotFound(format!("Depth pass `{}` writes nothing", pass.name)))?;
        let decl = self
            .graph
            .texture(&target.texture)
            .ok_or_else(|| RuntimeError::NotFound(format!("no texture `{}`", target.texture)))?;
        if decl.format != Format::R32Float {
            return Err(RuntimeError::Param(format!(
                "the Depth pass writes {:?}; a depth override needs R32Float",
                decl.format
            )));
        }
        let tex = self.texture(&target.texture)?;
        self.gpu.scoped("writing the depth override", || {
            self.gpu.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: tex,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: target.layer,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                &f32_bytes(depth),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(4 * n as u32),
                    rows_per_image: Some(n as u32),
                },
                wgpu::Extent3d {
                    width: n as u32,
                    height: n as u32,
                    depth_or_array_layers: 1,
                },
            )
        })
    }

    /// Run every pass once. Returns the GPU time of each pass when timestamps are available.
    pub fn run_frame(&mut self) -> Result<FrameTimes> {
        let gpu = self.gpu;
        if let Some(buf) = &self.params_buf {
            gpu.queue.write_buffer(buf, 0, &self.params);
        }
        let b = self.bound()?;
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        gpu.scoped("recording the frame", || -> Result<()> {
            for (pi, pass) in self.graph.passes.iter().enumerate() {
                if pass.kind == graph::PassKind::Depth
                    && let Some(depth) = &self.depth_override
                {
                    self.write_depth_override(pass, depth)?;
                    continue;
                }
                // Every render pass of this graph pass, in order: (step index, mip level).
                let mut work: Vec<(usize, u32)> = Vec::new();
                for (si, step) in pass.steps.iter().enumerate() {
                    if step.draw == Draw::MipLevels {
                        for level in 1..mip_count(b.shadow_size) {
                            work.push((si, level));
                        }
                    } else {
                        work.push((si, 0));
                    }
                }
                let last = work.len().saturating_sub(1);
                for (wi, (si, level)) in work.into_iter().enumerate() {
                    let step = &pass.steps[si];
                    let sp = &self.pipelines[pi][si];
                    let g0 = self.group0(sp, step)?;
                    let g1 = self.group1(sp, &step.reads, level)?;
                    let timestamp_writes = self
                        .timestamps
                        .as_ref()
                        .map(|(qs, _, _)| (qs, (wi == 0).then_some(2 * pi as u32), (wi == last).then_some(2 * pi as u32 + 1)));
                    let pipeline = match &sp.pipeline {
                        Pipeline::Compute(cp) => {
                            let g2 = self.group2(sp, &step.writes)?;
                            let mut cpass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                                label: Some(&pass.name),
                                timestamp_writes: timestamp_writes.filter(|(_, a, z)| a.is_some() || z.is_some()).map(|(qs, a, z)| {
                                    wgpu::ComputePassTimestampWrites {
                                        query_set: qs,
                                        beginning_of_pass_write_index: a,
                                        end_of_pass_write_index: z,
                                    }
                                }),
                            });
                            cpass.set_pipeline(cp);
                            cpass.set_bind_group(0, &g0, &[]);
                            if let Some(g1) = &g1 {
                                cpass.set_bind_group(1, g1, &[]);
                            }
                            if let Some(g2) = &g2 {
                                cpass.set_bind_group(2, g2, &[]);
                            }
                            cpass.dispatch_workgroups(b.shadow_size.div_ceil(graph::COMPUTE_WORKGROUP), 1, 1);
                            continue;
                        }
                        Pipeline::Render(rp) => rp,
                    };
                    let views: Vec<wgpu::TextureView> = match step.draw {
                        Draw::SceneFromCamera => b.camera.iter().map(|t| t.create_view(&Default::default())).collect(),
                        _ => step
                            .writes
                            .iter()
                            .map(|w| {
                                self.texture(&w.texture).map(|t| {
                                    t.create_view(&wgpu::TextureViewDescriptor {
                                        dimension: Some(wgpu::TextureViewDimension::D2),
                                        base_array_layer: w.layer,
                                        array_layer_count: Some(1),
                                        base_mip_level: level,
                                        mip_level_count: Some(1),
                                        ..Default::default()
                                    })
                                })
                            })
                            .collect::<Result<_>>()?,
                    };
                    let clear = |i: usize| match step.draw {
                        // no occluder: the far plane; no surface: visibility 1, position and normal NaN
                        Draw::SceneFromLight => wgpu::Color {
                            r: 1.0,
                            g: 1.0,
                            b: 1.0,
                            a: 1.0,
                        },
                        Draw::SceneFromCamera => match i {
                            0 => wgpu::Color {
                                r: 1.0,
                                g: 0.0,
                                b: 0.0,
                                a: 1.0,
                            },
                            1 => wgpu::Color {
                                r: 0.02,
                                g: 0.02,
                                b: 0.03,
                                a: 1.0,
                            },
                            _ => wgpu::Color {
                                r: f64::NAN,
                                g: f64::NAN,
                                b: f64::NAN,
                                a: f64::NAN,
                            },
                        },
                        _ => wgpu::Color::TRANSPARENT,
                    };
                    let attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = views
                        .iter()
                        .enumerate()
                        .map(|(i, v)| {
                            Some(wgpu::RenderPassColorAttachment {
                                view: v,
                                depth_slice: None,
                                resolve_target: None,
                                ops: wgpu::Operations {
                                    load: wgpu::LoadOp::Clear(clear(i)),
                                    store: wgpu::StoreOp::Store,
                                },
                            })
                        })
                        .collect();
                    let depth_view = match step.draw {
                        Draw::SceneFromLight => Some(b.light_depth.create_view(&Default::default())),
                        Draw::SceneFromCamera => Some(b.camera_depth.create_view(&Default::default())),
                        _ => None,
                    };
                    let timestamp_writes = timestamp_writes.map(|(qs, a, z)| wgpu::RenderPassTimestampWrites {
                        query_set: qs,
                        beginning_of_pass_write_index: a,
                        end_of_pass_write_index: z,
                    });
                    let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some(&pass.name),
                        color_attachments: &attachments,
                        depth_stencil_attachment: depth_view.as_ref().map(|v| wgpu::RenderPassDepthStencilAttachment {
                            view: v,
                            depth_ops: Some(wgpu::Operations {
                                load: wgpu::LoadOp::Clear(1.0),
                                store: wgpu::StoreOp::Store,
                            }),
                            stencil_ops: None,
                        }),
                        timestamp_writes: timestamp_writes
                            .filter(|t| t.beginning_of_pass_write_index.is_some() || t.end_of_pass_write_index.is_some()),
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                    rp.set_pipeline(pipeline);
                    rp.set_bind_group(0, &g0, &[]);
                    if let Some(g1) = &g1 {
                        rp.set_bind_group(1, g1, &[]);
                    }
                    match step.draw {
                        Draw::SceneFromLight | Draw::SceneFromCamera => {
                            if b.vertex_count > 0 {
                                rp.set_vertex_buffer(0, b.vertices.slice(..));
                                rp.draw(0..b.vertex_count, 0..1);
                            }
                        }
                        _ => rp.draw(0..3, 0..1),
                    }
                }
            }
            Ok(())
        })??;
        if let Some((qs, resolve, read)) = &self.timestamps {
            let n = (self.graph.passes.len() * 2) as u32;
            encoder.resolve_query_set(qs, 0..n, resolve, 0);
            encoder.copy_buffer_to_buffer(resolve, 0, read, 0, n as u64 * 8);
        }
        gpu.scoped("submitting the frame", || gpu.queue.submit([encoder.finish()]))?;
        let times = match &self.timestamps {
            Some((_, _, read)) => {
                let raw = map_read(gpu, read)?;
                let ticks: Vec<u64> = raw
                    .chunks_exact(8)
                    .map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                    .collect();
                let period = gpu.queue.get_timestamp_period() as f64;
                self.graph
                    .passes
                    .iter()
                    .enumerate()
                    .map(|(i, p)| {
                        let (a, z) = (ticks[2 * i], ticks[2 * i + 1]);
                        (p.name.clone(), (z >= a && a > 0).then(|| (z - a) as f64 * period * 1e-6))
                    })
                    .collect()
            }
            None => self.graph.passes.iter().map(|p| (p.name.clone(), None)).collect(),
        };
        Ok(FrameTimes { passes: times })
    }

    /// Read one layer and mip level of a texture of the graph.
    pub fn read_texture(&self, name: &str, layer: u32, level: u32) -> Result<Image> {
        let b = self.bound()?;
        let decl = self
            .graph
            .texture(name)
            .ok_or_else(|| RuntimeError::NotFound(format!("no texture `{name}`")))?;
        if layer >= decl.layers {
            return Err(RuntimeError::NotFound(format!(
                "texture `{name}` has {} layer(s), not {}",
                decl.layers,
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
        if decl.format == Format::SummedAreaU32 {
            return read_table(self.gpu, self.table(name)?, layer, size);
        }
        read_back(self.gpu, self.texture(name)?, layer, level, size, size, decl.format)
    }

    /// Read a camera output of the Shade pass.
    pub fn read_camera(&self, which: CameraOutput) -> Result<Image> {
        let b = self.bound()?;
        let (w, h) = b.camera_size;
        let format = match which {
            CameraOutput::Visibility => Format::R32Float,
            CameraOutput::Color => Format::Rgba8Unorm,
            CameraOutput::Position => Format::Rgba32Float,
            CameraOutput::Normal => Format::Rgba16Float,
        };
        read_back(self.gpu, &b.camera[which as usize], 0, 0, w, h, format)
    }

    /// Bytes of every texture at the bound sizes: (name, bytes); transient ones included.
    pub fn memory(&self) -> Result<Vec<(String, u64)>> {
        let b = self.bound()?;
        let texels = b.shadow_size as u64 * b.shadow_size as u64;
        Ok(self
            .graph
            .textures
            .iter()
            .map(|t: &TextureDecl| {
                let per = t.format.bytes_per_texel() as u64 * t.layers as u64 * texels;
                (t.name.clone(), if t.mips { per * 4 / 3 } else { per })
            })
            .collect())
    }

    /// The bound scene's shadow-map resolution.
    pub fn shadow_size(&self) -> Result<u32> {
        Ok(self.bound()?.shadow_size)
    }

    pub fn gpu(&self) -> &Gpu {
        self.gpu
    }
}

fn hash_of(parts: &[&str]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    parts.hash(&mut h);
    h.finish()
}

/// A storage-buffer binding (summed-area tables), visible to fragment and compute stages.
fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: if read_only {
            wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE
        } else {
            wgpu::ShaderStages::COMPUTE
        },
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn group0_layout(gpu: &Gpu, step: &Step) -> wgpu::BindGroupLayout {
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
    if step.params {
        entries.push(uniform(1));
    }
    if step.sampler {
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 2,
            visibility: vis,
            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
            count: None,
        });
    }
    gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("frame"),
        entries: &entries,
    })
}

/// Re-validate WGSL with naga (the runtime does not trust the compiler's output).
pub fn validate_wgsl(src: &str) -> std::result::Result<(), String> {
    let module = naga::front::wgsl::parse_str(src).map_err(|e| e.emit_to_string(src))?;
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .map_err(|e| e.emit_to_string(src))?;
    Ok(())
}

fn param_bytes(ty: graph::ParamType, v: f64) -> [u8; 4] {
    match ty {
        graph::ParamType::F32 => (v as f32).to_le_bytes(),
        graph::ParamType::I32 => (v as i32).to_le_bytes(),
        graph::ParamType::Bool => ((v != 0.0) as u32).to_le_bytes(),
    }
}

fn default_params(g: &PassGraph) -> Vec<u8> {
    let mut bytes = vec![0u8; g.params_size as usize];
    for p in &g.params {
        if let Some(off) = p.offset {
            let o = off as usize;
            if o + 4 <= bytes.len() {
                bytes[o..o + 4].copy_from_slice(&param_bytes(p.ty, p.value));
            }
        }
    }
    bytes
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// The `Frame` uniform (layout of [`graph::FRAME_WGSL`]).
fn frame_bytes(s: &SceneInputs) -> Vec<u8> {
    let n = s.shadow_size as f32;
    let range = (s.far - s.near).max(f32::MIN_POSITIVE);
    let mut v: Vec<f32> = Vec::with_capacity(graph::FRAME_SIZE as usize / 4);
    v.extend_from_slice(&s.light_view_proj);
    v.extend_from_slice(&s.light_view);
    v.extend_from_slice(&s.camera_view_proj);
    v.extend_from_slice(&s.light_position);
    v.extend_from_slice(&[s.camera_position[0], s.camera_position[1], s.camera_position[2], 1.0]);
    v.extend_from_slice(&[s.near, s.far, 1.0 / range, 0.0]);
    v.extend_from_slice(&[n, n, 1.0 / n, 1.0 / n]);
    v.extend_from_slice(&[s.light_size, s.light_angle, s.light_half_extents[0], s.light_half_extents[1]]);
    v.extend_from_slice(&[n, n, 1.0 / n, 1.0 / n]);
    let texel = 2.0 / (s.light_proj_y.max(f32::MIN_POSITIVE) * n);
    if s.light_orthographic {
        v.extend_from_slice(&[0.0, texel, 0.0, 0.0]);
    } else {
        v.extend_from_slice(&[texel, 0.0, 0.0, 0.0]);
    }
    f32_bytes(&v)
}

fn map_read(gpu: &Gpu, buf: &wgpu::Buffer) -> Result<Vec<u8>> {
    let slice = buf.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| RuntimeError::Device(e.to_string()))?;
    rx.recv()
        .map_err(|e| RuntimeError::Device(e.to_string()))?
        .map_err(|e| RuntimeError::Wgpu {
            context: "reading back".into(),
            message: e.to_string(),
        })?;
    let data = slice
        .get_mapped_range()
        .map_err(|e| RuntimeError::Wgpu {
            context: "reading back".into(),
            message: e.to_string(),
        })?
        .to_vec();
    buf.unmap();
    Ok(data)
}

/// Bytes of a summed-area table at a shadow-map size: one `vec4<u32>` per texel and layer.
fn table_bytes(t: &TextureDecl, shadow_size: u32) -> u64 {
    Format::SummedAreaU32.bytes_per_texel() as u64 * t.layers as u64 * shadow_size as u64 * shadow_size as u64
}

/// One layer of a summed-area table: the u32 sums (wrapping) as f32, rows top first.
fn read_table(gpu: &Gpu, table: &wgpu::Buffer, layer: u32, size: u32) -> Result<Image> {
    let bytes = Format::SummedAreaU32.bytes_per_texel() as u64 * size as u64 * size as u64;
    let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read back table"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    gpu.scoped("copying a summed-area table for read-back", || {
        enc.copy_buffer_to_buffer(table, layer as u64 * bytes, &buf, 0, bytes);
        gpu.queue.submit([enc.finish()]);
    })?;
    let raw = map_read(gpu, &buf)?;
    let rgba = raw
        .chunks_exact(16)
        .map(|t| {
            let mut v = [0.0f32; 4];
            for (i, c) in t.chunks_exact(4).enumerate() {
                v[i] = u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f32;
            }
            v
        })
        .collect();
    Ok(Image {
        width: size,
        height: size,
        rgba,
    })
}

fn read_back(gpu: &Gpu, tex: &wgpu::Texture, layer: u32, level: u32, w: u32, h: u32, format: Format) -> Result<Image> {
    let bpp = format.bytes_per_texel();
    let row = (w * bpp).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read back"),
        size: row as u64 * h as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    gpu.scoped("copying a texture for read-back", || {
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: tex,
                mip_level: level,
                origin: wgpu::Origin3d { x: 0, y: 0, z: layer },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buf,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        gpu.queue.submit([enc.finish()]);
    })?;
    let raw = map_read(gpu, &buf)?;
    let mut rgba = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        let line = &raw[(y * row) as usize..];
        for x in 0..w {
            rgba.push(decode_texel(&line[(x * bpp) as usize..((x + 1) * bpp) as usize], format));
        }
    }
    Ok(Image { width: w, height: h, rgba })
}

fn decode_texel(b: &[u8], f: Format) -> [f32; 4] {
    let mut out = [0.0, 0.0, 0.0, 1.0];
    let (n, size) = match f {
        Format::R8Unorm | Format::R16Unorm | Format::R16Float | Format::R32Float => (1, f.bytes_per_texel()),
        Format::Rg8Unorm | Format::Rg16Unorm | Format::Rg16Float | Format::Rg32Float => (2, f.bytes_per_texel() / 2),
        _ => (4, f.bytes_per_texel() / 4),
    };
    for (i, o) in out.iter_mut().enumerate().take(n) {
        let c = &b[i * size as usize..(i + 1) * size as usize];
        *o = match f {
            Format::R8Unorm | Format::Rg8Unorm | Format::Rgba8Unorm => c[0] as f32 / 255.0,
            Format::R16Unorm | Format::Rg16Unorm | Format::Rgba16Unorm => u16::from_le_bytes([c[0], c[1]]) as f32 / 65535.0,
            Format::R16Float | Format::Rg16Float | Format::Rgba16Float => half::f16::from_bits(u16::from_le_bytes([c[0], c[1]])).to_f32(),
            _ => f32::from_le_bytes([c[0], c[1], c[2], c[3]]),
        };
    }
    out
}
