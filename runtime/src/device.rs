//! The device: opening one or taking a host's, wgpu errors as values (error scopes), and
//! the caches of shader modules and pipelines shared by every technique and set of targets on it.

pub use crate::error::{Result, RuntimeError};
use crate::pipeline::{PipelineKey, StepPipeline};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// What to install when no adapter exists.
pub const INSTALL_HINT: &str = "install the Vulkan loader and Mesa's lavapipe CPU driver (Debian/Ubuntu: `apt-get install -y libvulkan1 mesa-vulkan-drivers`), or a GPU driver with Vulkan support";

/// The features the runtime asks for when it opens its own device ([`Gpu::new`]), where
/// the adapter has them. A host's device ([`Gpu::from_host`]) has what the host asked for;
/// [`crate::gpu::Requirements`] says which of these a graph needs.
pub const WANTED_FEATURES: wgpu::Features = wgpu::Features::TIMESTAMP_QUERY
    .union(wgpu::Features::FLOAT32_FILTERABLE)
    .union(wgpu::Features::FLOAT32_BLENDABLE)
    .union(wgpu::Features::TEXTURE_FORMAT_16BIT_NORM)
    // what the adapter allows beyond WebGPU's guarantees: 16-bit norm formats as render
    // targets (Unorm16 channels written by raster passes)
    .union(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES);

/// A device the runtime runs on: its own ([`Gpu::new`]) or a host renderer's
/// ([`Gpu::from_host`]). A handle: cloning it is cheap, and every clone shares the device,
/// the queue and the caches of shader modules and pipelines, so an [`crate::gpu::Technique`] or [`crate::gpu::Targets`]
/// owns one and a host can keep them in its own structs.
#[derive(Clone)]
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub features: wgpu::Features,
    pub limits: wgpu::Limits,
    /// The 16-bit norm formats the device can render to (an adapter-specific format
    /// feature beyond `TEXTURE_FORMAT_16BIT_NORM`).
    pub renderable_norm16: Vec<wgpu::TextureFormat>,
    shared: Arc<Shared>,
}

/// What every clone of a [`Gpu`] shares.
struct Shared {
    /// Errors that escaped every error scope, collected by the handler [`Gpu::new`]
    /// installs. `None` on a host's device: its own handler sees them, untouched.
    uncaptured: Option<Mutex<Vec<String>>>,
    /// Pipelines by everything that determines them ([`PipelineKey`]): lavapipe compiles
    /// each pipeline through LLVM, so loads of one technique on several devices' clones share them.
    pipelines: Mutex<HashMap<PipelineKey, Arc<StepPipeline>>>,
    /// Shader modules by their WGSL source.
    modules: Mutex<HashMap<Arc<str>, wgpu::ShaderModule>>,
}

impl Gpu {
    /// Open the first Vulkan adapter, headless, with the [`WANTED_FEATURES`] it has and
    /// its own limits. Errors that escape the runtime's error scopes are collected, not
    /// passed to wgpu's default handler (which panics).
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
        let features = adapter.features() & WANTED_FEATURES;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("sshc"),
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| RuntimeError::Device(e.to_string()))?;
        let gpu = Gpu::wrap(&adapter, device, queue, Some(Mutex::new(Vec::new())));
        let shared = gpu.shared.clone();
        gpu.device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Some(Ok(mut v)) = shared.uncaptured.as_ref().map(|m| m.lock()) {
                v.push(e.to_string());
            }
        }));
        Ok(gpu)
    }

    /// Run on a host renderer's device. The features and limits are the device's own (what
    /// the host asked for); the adapter answers which formats are renderable. The host's
    /// uncaptured-error handler stays as it is: every object the runtime creates is
    /// created inside error scopes, and their errors come back as values. A graph the
    /// device cannot run is refused when it is loaded ([`crate::gpu::Requirements`]).
    pub fn from_host(adapter: &wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue) -> Gpu {
        Gpu::wrap(adapter, device, queue, None)
    }

    fn wrap(adapter: &wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue, uncaptured: Option<Mutex<Vec<String>>>) -> Gpu {
        let features = device.features();
        let renderable_norm16 = if features.contains(wgpu::Features::TEXTURE_FORMAT_16BIT_NORM) {
            [
                wgpu::TextureFormat::R16Unorm,
                wgpu::TextureFormat::Rg16Unorm,
                wgpu::TextureFormat::Rgba16Unorm,
            ]
            .into_iter()
            .filter(|f| {
                features.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES)
                    && adapter
                        .get_texture_format_features(*f)
                        .allowed_usages
                        .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
            })
            .collect()
        } else {
            vec![]
        };
        Gpu {
            limits: device.limits(),
            device,
            queue,
            info: adapter.get_info(),
            features,
            renderable_norm16,
            shared: Arc::new(Shared {
                uncaptured,
                pipelines: Mutex::new(HashMap::new()),
                modules: Mutex::new(HashMap::new()),
            }),
        }
    }

    /// Whether this is a host's device ([`Gpu::from_host`]).
    pub fn is_host_device(&self) -> bool {
        self.shared.uncaptured.is_none()
    }

    /// Number of pipelines built on this device so far (each is built once per distinct
    /// [`PipelineKey`]: shader, entry points, formats, bindings, depth and blend state).
    pub fn cached_pipelines(&self) -> usize {
        self.shared.pipelines.lock().map(|c| c.len()).unwrap_or(0)
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
        let Some(sink) = &self.shared.uncaptured else {
            return Ok(());
        };
        let mut v = sink.lock().map_err(|_| RuntimeError::Device("error sink poisoned".into()))?;
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

    /// The shader module of a (validated) WGSL source, created once per device.
    pub(crate) fn module(&self, label: &str, source: &Arc<str>) -> Result<wgpu::ShaderModule> {
        if let Some(m) = self.shared.modules.lock().ok().and_then(|c| c.get(source).cloned()) {
            return Ok(m);
        }
        let m = self.scoped(&format!("shader `{label}`"), || {
            self.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(source.as_ref().into()),
            })
        })?;
        if let Ok(mut c) = self.shared.modules.lock() {
            c.insert(source.clone(), m.clone());
        }
        Ok(m)
    }

    /// The pipeline of `key`, built (from the key alone) once per device.
    pub(crate) fn pipeline(&self, key: &PipelineKey, label: &str) -> Result<Arc<StepPipeline>> {
        if let Some(p) = self.shared.pipelines.lock().ok().and_then(|c| c.get(key).cloned()) {
            return Ok(p);
        }
        let module = self.module(label, &key.source)?;
        let p = Arc::new(self.scoped(label, || StepPipeline::build(&self.device, key, &module, label))?);
        if let Ok(mut c) = self.shared.pipelines.lock() {
            c.insert(key.clone(), p.clone());
        }
        Ok(p)
    }

    /// Block until the device has finished everything submitted.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| RuntimeError::Device(e.to_string()))
    }

    /// The device's memory bandwidth as a copy achieves it: a buffer-to-buffer copy of
    /// `bytes`, timed on the host from submission to completion, after one untimed copy;
    /// bytes read plus written over the median time of `runs`, in GB/s (10^9 bytes a
    /// second). The host's submission overhead counts against the device, so this
    /// understates it slightly for small copies: 256 MiB keeps that under 1 % on lavapipe.
    pub fn copy_bandwidth(&self, bytes: u64, runs: usize) -> Result<f64> {
        let bytes = (bytes.max(4) / 4) * 4;
        let make = |label, usage| {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage,
                mapped_at_creation: false,
            })
        };
        let (src, dst) = self.scoped("allocating the bandwidth buffers", || {
            (
                make("bandwidth source", wgpu::BufferUsages::COPY_SRC),
                make("bandwidth destination", wgpu::BufferUsages::COPY_DST),
            )
        })?;
        let mut times = Vec::with_capacity(runs);
        for run in 0..=runs {
            let mut enc = self.device.create_command_encoder(&Default::default());
            enc.copy_buffer_to_buffer(&src, 0, &dst, 0, bytes);
            let t = std::time::Instant::now();
            self.queue.submit([enc.finish()]);
            self.device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| RuntimeError::Device(e.to_string()))?;
            if run > 0 {
                times.push(t.elapsed().as_secs_f64());
            }
        }
        self.take_uncaptured("copying for the bandwidth")?;
        times.sort_by(f64::total_cmp);
        let median = times.get(times.len() / 2).copied().unwrap_or(f64::NAN);
        Ok(2.0 * bytes as f64 / median / 1e9)
    }

    /// Map a `MAP_READ` buffer and copy its bytes out.
    pub(crate) fn map_read(&self, buf: &wgpu::Buffer) -> Result<Vec<u8>> {
        let slice = buf.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device
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
}
