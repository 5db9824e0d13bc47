//! The window, the device and its surface: the window opened, an adapter that can draw
//! into it, the device with every feature and limit it has, the surface configured, and
//! what draws into it (the texture presenter and egui's renderer).

use super::App;
use crate::view::present::Present;
use crate::view::worker::Worker;
use sshc_runtime::gpu::Gpu;
use std::sync::Arc;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

/// The device, the window's surface and what draws into it.
pub(super) struct Gfx {
    pub(super) window: Arc<Window>,
    pub(super) surface: wgpu::Surface<'static>,
    pub(super) config: wgpu::SurfaceConfiguration,
    pub(super) device: wgpu::Device,
    pub(super) queue: wgpu::Queue,
    pub(super) present: Present,
    pub(super) egui: egui::Context,
    pub(super) egui_winit: egui_winit::State,
    pub(super) egui_wgpu: egui_wgpu::Renderer,
}

impl App {
    pub(super) fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<(), String> {
        let (w, h) = self.scene.camera_size();
        let attrs = Window::default_attributes()
            .with_title(format!("sshc view: {}", self.state.technique.display()))
            .with_inner_size(winit::dpi::PhysicalSize::new(w, h));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .map_err(|e| format!("error: cannot open a window: {e}; {}", crate::view::NO_DISPLAY))?,
        );
        let instance = wgpu::Instance::new(
            wgpu::InstanceDescriptor {
                backends: wgpu::Backends::VULKAN,
                ..wgpu::InstanceDescriptor::new_without_display_handle()
            }
            .with_display_handle(Box::new(event_loop.owned_display_handle())),
        );
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| format!("error: cannot draw into the window: {e}"))?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(|e| {
            format!(
                "error: no GPU adapter can draw into the window: {e}; {}",
                sshc_runtime::gpu::INSTALL_HINT
            )
        })?;
        // every feature and limit the adapter has: techniques are switched at run time
        let features = adapter.features() - wgpu::Features::MAPPABLE_PRIMARY_BUFFERS;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("sshc view"),
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| format!("error: cannot open the device: {e}"))?;
        let caps = surface.get_capabilities(&adapter);
        // a format that stores what the shader writes (no sRGB encoding), as the PNGs do
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| matches!(f, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm))
            .or_else(|| caps.formats.first().copied())
            .ok_or("error: the window's surface offers no format")?;
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        if caps.usages.contains(wgpu::TextureUsages::COPY_SRC) {
            usage |= wgpu::TextureUsages::COPY_SRC;
        }
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::Fifo,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes.first().copied().unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&device, &config);
        let gpu = Gpu::from_host(&adapter, device.clone(), queue.clone());
        let present = Present::new(&device, &queue, format);
        let egui = egui::Context::default();
        let egui_winit = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(device.limits().max_texture_dimension_2d as usize),
        );
        let egui_wgpu = egui_wgpu::Renderer::new(&device, format, egui_wgpu::RendererOptions::default());
        self.worker = Some(Worker::start(gpu.clone()));
        self.worker_b = Some(Worker::start(gpu.clone()));
        self.gfx = Some(Gfx {
            window,
            surface,
            config,
            device,
            queue,
            present,
            egui,
            egui_winit,
            egui_wgpu,
        });
        self.set_camera_size(size.width, size.height);
        self.watch_files();
        self.recompile();
        Ok(())
    }
}
