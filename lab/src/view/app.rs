//! The window: winit's event loop, the wgpu surface, the technique's stages and the
//! egui panels.

use super::ViewArgs;
use super::present::{Part, Pick, Present};
use super::refine::{Estimate, Refiner};
use super::script::{Event, Log};
use super::state::{self, ColourMap, Mode, Orbit, ViewState};
use super::worker::{Answer, Controls, Watch, Worker};
use crate::image_io::ImageFiles as _;
use crate::run::Bound;
use crate::scene::Scene;
use serde_json::json;
use sshc_runtime::gpu::{CameraOutput, Gpu};
use sshc_runtime::graph::ParamType;
use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

pub fn run(args: ViewArgs) -> Result<(), String> {
    let event_loop = EventLoop::new().map_err(|e| format!("error: cannot open a window: {e}; {}", super::NO_DISPLAY))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App::new(args, &event_loop)?;
    event_loop
        .run_app(&mut app)
        .map_err(|e| format!("error: the window's event loop failed: {e}"))?;
    match app.exit.take() {
        Some(r) => r,
        None => Ok(()),
    }
}

/// The device, the window's surface and what draws into it.
struct Gfx {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    device: wgpu::Device,
    queue: wgpu::Queue,
    present: Present,
    egui: egui::Context,
    egui_winit: egui_winit::State,
    egui_wgpu: egui_wgpu::Renderer,
}

/// The mouse, for camera and light drags.
#[derive(Default)]
struct Mouse {
    at: Option<(f64, f64)>,
    left: bool,
    right: bool,
    shift: bool,
    ctrl: bool,
}

/// The last GPU times, per pass (ms), and the frame time.
#[derive(Default)]
struct Times {
    passes: Vec<(String, f64)>,
    /// The last 60 frames: sshc's GPU time (its passes' timestamps), the panels' CPU time
    /// (egui's pass and tessellation), the frame interval.
    gpu_ms: VecDeque<f64>,
    ui_ms: VecDeque<f64>,
    /// Acquiring the window's next texture and presenting it (CPU, waits included).
    present_ms: VecDeque<f64>,
    frame_ms: VecDeque<f64>,
    last: Option<Instant>,
    /// The frame number of the last GPU times taken.
    gpu_frame: Option<u64>,
    /// Each pass's GPU times over the same frames.
    pass_ms: BTreeMap<String, VecDeque<f64>>,
}

fn push(v: &mut VecDeque<f64>, x: f64) {
    v.push_back(x);
    if v.len() > 60 {
        v.pop_front();
    }
}

/// The median of a window of times (NaN when empty).
fn median(v: &VecDeque<f64>) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().collect();
    s.sort_by(f64::total_cmp);
    s.get(s.len() / 2).copied().unwrap_or(f64::NAN)
}

/// What the panels asked for, applied after they are drawn.
enum Action {
    Event(Event),
    Screenshot,
    CopyCommand,
}

struct App {
    args: ViewArgs,
    /// The technique files the picker lists: `techniques/*.ron` and the one given.
    techniques: Vec<PathBuf>,
    /// Whether the panels are drawn (Tab, or a script's `Panels`).
    show_panels: bool,
    /// The scene (its camera and lights the window's, set in place: `sync_scene`), the
    /// file's camera and lights, and the window's state.
    scene: Scene,
    file: (crate::scene::Camera, Vec<crate::scene::Light>),
    /// The frame the camera or a light last moved: the truth starts over once they stand.
    last_move: u64,
    state: ViewState,
    orbit: Orbit,
    gfx: Option<Gfx>,
    worker: Option<Worker>,
    ex: Option<Bound>,
    /// The split view's right half: its own worker and bound technique.
    worker_b: Option<Worker>,
    ex_b: Option<Bound>,
    controls: Controls,
    /// The diagnostics of the last compilation that failed, until one succeeds.
    diagnostics: Option<String>,
    status: String,
    /// The camera or lights changed since the frame's state last had them.
    moved: bool,
    /// The window's size changed: the targets are resized.
    resized: bool,
    frame: u64,
    script: VecDeque<Event>,
    waiting: u32,
    wait_ready: bool,
    /// Compilations answered so far, and the count a `WaitCompiled` waits for.
    answers: u64,
    wait_answers: Option<u64>,
    wait_truth: Option<u32>,
    /// When the wait for a compilation or the truth began (bounded by `--wait-limit`).
    wait_since: Option<Instant>,
    log: Log,
    watch: Option<Watch>,
    mouse: Mouse,
    times: Times,
    /// The truth, refined on its own thread while a mode that shows it is on.
    refiner: Refiner,
    truth: Option<Estimate>,
    /// The truth, the error and the standard error as textures (camera-sized R32Float).
    truth_textures: Option<[wgpu::Texture; 3]>,
    /// RMS of the error over the surface and over the penumbra.
    rms: Option<(f64, f64)>,
    /// The view changed since the truth was started.
    truth_stale: bool,
    /// A summed-area table shown: its read-back, as a texture.
    table: Option<wgpu::Texture>,
    /// A screenshot to write after the next frame is drawn.
    screenshot: Option<PathBuf>,
    /// When the script last saved a file, and the new graph's compile, pipeline and bind
    /// times until its first frame is drawn.
    saved_at: Option<Instant>,
    fresh: Option<(f64, f64, f64)>,
    command: String,
    exit: Option<Result<(), String>>,
}

impl App {
    fn new(args: ViewArgs, _event_loop: &EventLoop<()>) -> Result<App, String> {
        let mut scene = crate::session::load_scene(&args.scene, args.size, args.shadow_map)?;
        // a tuned technique names its map size: it outranks the scene's, `--shadow-map` it
        if args.shadow_map.is_none()
            && let Some(n) = crate::session::read_capped(&args.technique, 4 << 20)
                .ok()
                .and_then(|s| sshc::tune::space(&s).ok())
                .and_then(|s| s.shadow_map)
        {
            scene.shadow_map = n;
            scene.check_precision().map_err(|e| e.to_string())?;
        }
        if let Some((w, h)) = args.size {
            scene.set_camera_size(w, h);
        }
        let techniques = technique_files(&args.technique);
        let state = ViewState {
            technique: args.technique.clone(),
            scene: args.scene.clone(),
            camera: scene.camera.clone(),
            lights: scene.lights.clone(),
            params: BTreeMap::new(),
            fixed: args.variants.set.iter().cloned().collect(),
            precisions: args.variants.precision.iter().cloned().collect(),
            schedules: args.variants.schedule.iter().cloned().collect(),
            shadow_map: scene.shadow_map,
            mode: Mode::Shaded,
            split: None,
        };
        let script = match &args.script {
            Some(p) => super::script::load(p)?.into(),
            None => VecDeque::new(),
        };
        let log = Log::open(args.log.as_deref())?;
        Ok(App {
            orbit: Orbit::of(&scene.camera),
            file: (scene.camera.clone(), scene.lights.clone()),
            last_move: 0,
            techniques,
            show_panels: true,
            scene,
            state,
            gfx: None,
            worker: None,
            ex: None,
            worker_b: None,
            ex_b: None,
            controls: Controls::default(),
            diagnostics: None,
            status: "compiling".into(),
            moved: false,
            resized: false,
            frame: 0,
            script,
            waiting: 0,
            wait_ready: false,
            answers: 0,
            wait_answers: None,
            wait_truth: None,
            wait_since: None,
            log,
            watch: None,
            mouse: Mouse::default(),
            times: Times::default(),
            screenshot: None,
            saved_at: None,
            fresh: None,
            refiner: Refiner::start(),
            truth: None,
            truth_textures: None,
            rms: None,
            truth_stale: true,
            table: None,
            command: String::new(),
            exit: None,
            args,
        })
    }

    /// Stop with `r` (the first reason given stands).
    fn finish(&mut self, event_loop: &ActiveEventLoop, r: Result<(), String>) {
        if self.exit.is_none() {
            self.exit = Some(r);
        }
        event_loop.exit();
    }

    /// The scene as the window has it: the file's, with the state's camera and lights.
    fn current_scene(&mut self) -> Scene {
        self.sync_scene().clone()
    }

    /// The scene made the window's in place (its camera, lights and map size: no copy of
    /// its triangles, which a frame that moves the light must not pay for).
    fn sync_scene(&mut self) -> &Scene {
        self.scene.camera = self.state.camera.clone();
        self.scene.lights = self.state.lights.clone();
        self.scene.shadow_map = self.state.shadow_map;
        &self.scene
    }

    /// The window's image size (the state's camera's).
    fn view_size(&self) -> (u32, u32) {
        match &self.state.camera {
            crate::scene::Camera::Perspective { width, height, .. } | crate::scene::Camera::Orthographic { width, height, .. } => {
                (*width, *height)
            }
        }
    }

    /// The compile options of the state: its fixed params, precisions and schedules; a
    /// graph for any scene (lights move).
    fn options(&self) -> sshc::CompileOptions {
        options(&self.state)
    }

    /// Compile the split's right half (or drop it).
    fn recompile_split(&mut self) {
        let scene = self.current_scene();
        match (self.state.right(), &mut self.worker_b) {
            (Some(right), Some(w)) => {
                w.request(&right.technique, options(&right), scene, self.args.cascading);
            }
            (None, _) => self.ex_b = None,
            (Some(_), None) => {}
        }
    }

    fn recompile(&mut self) {
        let (technique, options, scene) = (self.state.technique.clone(), self.options(), self.current_scene());
        if let Some(w) = &mut self.worker {
            w.request(&technique, options, scene, self.args.cascading);
            self.status = format!("compiling {}", technique.display());
        }
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<(), String> {
        let (w, h) = self.scene.camera_size();
        let attrs = Window::default_attributes()
            .with_title(format!("sshc view: {}", self.state.technique.display()))
            .with_inner_size(winit::dpi::PhysicalSize::new(w, h));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .map_err(|e| format!("error: cannot open a window: {e}; {}", super::NO_DISPLAY))?,
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

    fn watch_files(&mut self) {
        let mut files = vec![self.state.technique.clone(), self.state.scene.clone()];
        files.extend(self.state.split.as_ref().map(|s| s.technique.clone()));
        match Watch::new(&files) {
            Ok(w) => self.watch = Some(w),
            Err(e) => self.status = e,
        }
    }

    fn set_camera_size(&mut self, w: u32, h: u32) {
        self.state.camera = state::with_size(&self.state.camera, w, h);
    }

    /// Take the worker's answer, if it has come.
    fn take_answer(&mut self, answer: Answer) {
        self.answers += 1;
        match answer {
            Answer::Ready(r) => {
                let mut ex = r.bound;
                // the worker bound the scene as it was asked; the view may have moved since
                self.resized |= self.view_size() != first_size(&ex);
                self.moved = true;
                // runtime params the new graph still has keep their values
                self.state.params.retain(|k, v| ex.state.params.set(k, *v).is_ok());
                self.ex = Some(ex);
                self.fresh = Some((r.compile_ms, r.pipelines_ms, r.bind_ms));
                // GPU times are the new graph's from here
                self.times.gpu_ms.clear();
                self.times.pass_ms.clear();
                self.times.gpu_frame = None;
                self.controls = r.controls;
                self.diagnostics = None;
                self.status = format!(
                    "ready: compiled in {:.0} ms, pipelines {:.0} ms, bound in {:.0} ms",
                    r.compile_ms, r.pipelines_ms, r.bind_ms
                );
                self.log.write(
                    self.frame,
                    json!({"event": "compiled", "ok": true, "technique": self.state.technique, "compile_ms": r.compile_ms,
                           "pipelines_ms": r.pipelines_ms, "bind_ms": r.bind_ms, "warnings": self.controls.warnings}),
                );
            }
            Answer::Failed { diagnostics, .. } => {
                // a save that does not compile has no first frame
                self.saved_at = None;
                self.status = "the file does not compile: the previous graph keeps rendering".into();
                self.log.write(
                    self.frame,
                    json!({"event": "compiled", "ok": false, "technique": self.state.technique, "diagnostics": diagnostics}),
                );
                self.diagnostics = Some(diagnostics);
            }
        }
    }

    /// Apply one scripted or panel event; returns false where the script must wait.
    fn apply(&mut self, e: Event) -> Result<(), String> {
        self.log.write(self.frame, json!({"event": "script", "step": e}));
        match e {
            Event::Wait(n) => self.waiting = n,
            Event::WaitReady => self.wait_ready = true,
            Event::WaitCompiled => self.wait_answers = Some(self.answers + 1),
            Event::WaitTruth(n) => {
                if !matches!(self.state.mode, Mode::Truth | Mode::Error { .. } | Mode::StdError { .. }) {
                    return Err(
                        "error: WaitTruth: no mode that shows the truth is on (Show(Truth), Show(Error(..)) or Show(StdError(..)))".into(),
                    );
                }
                self.wait_truth = Some(n);
            }
            Event::Orbit { yaw, pitch } => {
                self.orbit.turn(yaw.to_radians(), pitch.to_radians());
                self.orbit_moved();
            }
            Event::Pan { x, y } => {
                self.orbit.pan(x, y);
                self.orbit_moved();
            }
            Event::Zoom(f) => {
                if !(f.is_finite() && f > 0.0) {
                    return Err(format!("error: Zoom({f}): a zoom is a positive factor"));
                }
                self.orbit.zoom(f);
                self.orbit_moved();
            }
            Event::MoveLight { light, by } => {
                let l = self.light(light)?;
                self.set_light(l, state::moved(&self.state.lights[l], by))?;
            }
            Event::LightSize { light, size } => {
                let l = self.light(light)?;
                self.set_light(l, state::resized(&self.state.lights[l], size))?;
            }
            Event::Set { name, value } => self.set(&name, value)?,
            Event::Precision { name, value } => {
                self.state.precisions.insert(name, value);
                self.recompile();
            }
            Event::Schedule { pass, value } => {
                self.state.schedules.insert(pass, value);
                self.recompile();
            }
            Event::Show(m) => {
                if let (Mode::Texture { name, .. }, Some(ex)) = (&m, &self.ex)
                    && ex.graph().texture(name).is_none()
                    && !ex.inspect().debug_outputs().iter().any(|o| o.texture == *name)
                {
                    let mut known: Vec<String> = ex.graph().textures.iter().map(|t| t.name.clone()).collect();
                    known.extend(ex.inspect().debug_outputs().into_iter().map(|o| o.texture));
                    return Err(format!(
                        "error: Show: the graph has no texture `{name}`; it has {}",
                        known.join(", ")
                    ));
                }
                self.state.mode = m;
            }
            Event::Split(split) => {
                self.state.split = split;
                self.watch_files();
                self.recompile_split();
            }
            Event::Technique(t) => {
                self.state.technique = t;
                self.state.params.clear();
                self.state.fixed.clear();
                self.state.precisions.clear();
                self.state.schedules.clear();
                self.watch_files();
                self.recompile();
            }
            Event::Edit { path, from, to } => {
                let text = crate::session::read(&path)?;
                if !text.contains(&from) {
                    return Err(format!("error: Edit: `{from}` is not in {}", path.display()));
                }
                crate::session::write_new(&path, text.replacen(&from, &to, 1))?;
                self.saved_at = Some(Instant::now());
            }
            Event::Screenshot(p) => self.screenshot = Some(p),
            Event::Panels(on) => self.show_panels = on,
            Event::ShowChannel { name, level, lo, hi, map } => {
                let Some(ex) = &self.ex else {
                    return Err(format!(
                        "error: ShowChannel: `{name}`: no technique is compiled yet (a WaitReady first)"
                    ));
                };
                let found = ex
                    .graph()
                    .textures
                    .iter()
                    .find_map(|t| t.channels.iter().find(|c| c.name == name).map(|c| (t, c)));
                let Some((texture, channel)) = found else {
                    let known: Vec<&str> = ex
                        .graph()
                        .textures
                        .iter()
                        .flat_map(|t| t.channels.iter().map(|c| c.name.as_str()))
                        .collect();
                    return Err(format!(
                        "error: ShowChannel: the graph has no channel `{name}`; it has {}",
                        known.join(", ")
                    ));
                };
                self.state.mode = Mode::Texture {
                    name: texture.name.clone(),
                    layer: channel.layer,
                    level,
                    channel: channel.component,
                    lo,
                    hi,
                    map,
                };
            }
            Event::State(s) => {
                let recompile = s.technique != self.state.technique
                    || s.fixed != self.state.fixed
                    || s.precisions != self.state.precisions
                    || s.schedules != self.state.schedules
                    || s.shadow_map != self.state.shadow_map;
                let size = self.view_size();
                self.state = *s;
                self.set_camera_size(size.0, size.1);
                self.orbit = Orbit::of(&self.state.camera);
                if let Some(ex) = &mut self.ex {
                    for (k, v) in &self.state.params {
                        ex.state.params.set(k, *v).map_err(|e| format!("error: {e}"))?;
                    }
                }
                self.moved = true;
                if recompile {
                    self.recompile();
                }
                self.recompile_split();
            }
            Event::Reset => {
                let size = self.view_size();
                self.state.camera = self.file.0.clone();
                self.state.lights = self.file.1.clone();
                self.set_camera_size(size.0, size.1);
                self.orbit = Orbit::of(&self.state.camera);
                let defaults: Vec<String> = self.state.params.keys().cloned().collect();
                self.state.params.clear();
                if let Some(ex) = &mut self.ex {
                    for k in defaults {
                        if let Some(p) = ex.graph().params.iter().find(|p| p.name == k) {
                            let v = p.value;
                            let _ = ex.state.params.set(&k, v);
                        }
                    }
                }
                self.moved = true;
            }
        }
        Ok(())
    }

    fn light(&self, l: usize) -> Result<usize, String> {
        if l < self.state.lights.len() {
            Ok(l)
        } else {
            Err(format!("error: light {l}: the scene has {} light(s)", self.state.lights.len()))
        }
    }

    /// Light `l` replaced, checked as a scene file's light is (so that `sshc render`
    /// reading it back checks the same value).
    fn set_light(&mut self, l: usize, light: crate::scene::Light) -> Result<(), String> {
        self.state.lights[l] = crate::scene::checked_light(l, light).map_err(|e| format!("error: {e}"))?;
        self.moved = true;
        Ok(())
    }

    fn orbit_moved(&mut self) {
        self.orbit.apply(&mut self.state.camera);
        self.moved = true;
    }

    /// Set a param: a runtime uniform in place, a fixed one by recompiling.
    fn set(&mut self, name: &str, value: f64) -> Result<(), String> {
        let decl = self
            .ex
            .as_ref()
            .and_then(|ex| ex.graph().params.iter().find(|p| p.name == name).cloned());
        match decl {
            Some(d) if d.offset.is_some() => {
                if let Some(ex) = &mut self.ex {
                    ex.state.params.set(name, value).map_err(|e| format!("error: {e}"))?;
                }
                self.state.params.insert(name.to_string(), value);
            }
            Some(d) => {
                let text = match d.ty {
                    ParamType::F32 => state::param_literal(value),
                    ParamType::I32 => format!("{}", value.round() as i64),
                    ParamType::Bool => (value != 0.0).to_string(),
                };
                self.state.fixed.insert(name.to_string(), text);
                self.recompile();
            }
            None => return Err(format!("error: Set: the technique has no param `{name}`")),
        }
        Ok(())
    }

    /// Run the script until it must wait.
    fn step_script(&mut self) -> Result<(), String> {
        let waiting_for = if self.wait_truth.is_some() {
            Some("WaitTruth: the truth's rounds")
        } else if self.wait_answers.is_some() {
            Some(
                "WaitCompiled: a compilation's answer (it waits for the next one asked for: a save, an Edit, a Precision, a Schedule or a fixed param's Set; WaitReady waits for one in flight)",
            )
        } else if self.wait_ready {
            Some("WaitReady: the compilation in flight")
        } else {
            None
        };
        match (waiting_for, self.wait_since) {
            (None, _) => self.wait_since = None,
            (Some(_), None) => self.wait_since = Some(Instant::now()),
            (Some(what), Some(t)) if t.elapsed().as_secs() >= self.args.wait_limit => {
                return Err(format!("error: waited {} s (--wait-limit) for {what}", self.args.wait_limit));
            }
            _ => {}
        }
        if let Some(n) = self.wait_truth {
            if self.truth_stale || self.truth.as_ref().is_none_or(|t| t.rounds < n) {
                return Ok(());
            }
            self.wait_truth = None;
            self.waiting = 1;
        }
        if let Some(n) = self.wait_answers {
            if self.answers < n {
                return Ok(());
            }
            self.wait_answers = None;
            self.waiting = 1;
        }
        if self.wait_ready {
            if [&self.worker, &self.worker_b].into_iter().flatten().any(|w| w.pending.is_some()) {
                return Ok(());
            }
            self.wait_ready = false;
            // one frame more, so that what is shown is the answer's
            self.waiting = 1;
        }
        while self.waiting == 0 && !self.wait_ready && self.wait_answers.is_none() && self.wait_truth.is_none() && self.screenshot.is_none()
        {
            let Some(e) = self.script.pop_front() else { break };
            self.apply(e)?;
        }
        Ok(())
    }

    /// Put the camera and lights as they are now in the frame's state.
    fn update_state(&mut self) -> Result<(), String> {
        if !(self.moved || self.resized) {
            return Ok(());
        }
        self.truth_stale = true;
        self.last_move = self.frame;
        self.sync_scene();
        let scene = &self.scene;
        for ex in [&mut self.ex, &mut self.ex_b].into_iter().flatten() {
            if self.resized {
                // only the camera-sized targets are made again: the geometry, its edges,
                // the shadow maps and the pipelines stay (issue 49); the camera and lights
                // of the new aspect follow below
                ex.targets.resize(scene.camera_size()).map_err(|e| format!("error: {e}"))?;
            }
            if ex.targets.cascades() > 1 {
                // the cascades follow the camera: refitted to its slices in place
                self.args.cascading.refit(ex, scene)?;
                continue;
            }
            // plain state: checked and written by the next frame's prepare
            ex.state.camera = crate::bind::camera(scene);
            // each light's view depends on the geometry and that light alone
            for (l, light) in scene.lights.iter().enumerate() {
                let inputs = crate::bind::light_inputs(scene, light, ex.graph())?;
                match ex.state.lights.get_mut(l) {
                    Some(slot) => *slot = inputs,
                    None => {
                        return Err(format!(
                            "error: light {l}: the view was bound with {} light(s)",
                            ex.state.lights.len()
                        ));
                    }
                }
            }
        }
        self.resized = false;
        self.moved = false;
        Ok(())
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<(), String> {
        if let Some(w) = &mut self.worker {
            // the first graph: wait for it (a window with nothing in it tells nothing)
            let answer = if self.ex.is_none() && self.diagnostics.is_none() {
                w.wait()
            } else {
                w.poll()
            };
            if let Some(a) = answer {
                self.take_answer(a);
            }
        }
        if let Some(a) = self.worker_b.as_mut().and_then(Worker::poll) {
            match a {
                Answer::Ready(r) => {
                    let mut ex = r.bound;
                    if let Some(split) = &mut self.state.split {
                        split.params.retain(|k, v| ex.state.params.set(k, *v).is_ok());
                    }
                    self.resized |= self.view_size() != first_size(&ex);
                    self.moved = true;
                    self.ex_b = Some(ex);
                    self.log.write(self.frame, json!({"event": "compiled", "ok": true, "split": true, "technique": self.state.split.as_ref().map(|s| &s.technique)}));
                }
                Answer::Failed { diagnostics, .. } => {
                    self.log.write(
                        self.frame,
                        json!({"event": "compiled", "ok": false, "split": true, "diagnostics": diagnostics}),
                    );
                    self.diagnostics = Some(format!("the split's right half:\n{diagnostics}"));
                }
            }
        }
        if let Some(watch) = &self.watch {
            let changed = watch.changed(Duration::from_millis(50));
            for p in &changed {
                self.log.write(self.frame, json!({"event": "file changed", "path": p}));
            }
            let scene_changed = changed.iter().any(|p| same_file(p, &self.state.scene));
            if scene_changed {
                match crate::session::load_scene(&self.state.scene, None, None) {
                    Ok(s) => {
                        let size = self.view_size();
                        self.file = (s.camera.clone(), s.lights.clone());
                        self.scene = s;
                        self.state.camera = state::with_size(&self.file.0, size.0, size.1);
                        self.state.lights = self.file.1.clone();
                        self.orbit = Orbit::of(&self.state.camera);
                    }
                    Err(e) => {
                        self.log.write(self.frame, json!({"event": "scene", "ok": false, "diagnostics": e}));
                        self.diagnostics = Some(e);
                    }
                }
            }
            if !changed.is_empty() {
                self.recompile();
                self.recompile_split();
            }
        }
        self.step_script()?;
        self.update_state()?;
        let Some(gfx) = &mut self.gfx else { return Ok(()) };
        let acquire = Instant::now();
        let frame = match gfx.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f) | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                gfx.surface.configure(&gfx.device, &gfx.config);
                return Ok(());
            }
            other => {
                // a timeout or an occluded window: try again next frame
                let _ = other;
                return Ok(());
            }
        };
        let mut present_ms = acquire.elapsed().as_secs_f64() * 1e3;
        let target = frame.texture.create_view(&Default::default());
        let mut encoder = gfx.device.create_command_encoder(&Default::default());
        let size = (gfx.config.width, gfx.config.height);
        let mut shown_any = false;
        if let Some(ex) = &mut self.ex {
            ex.encode(&mut encoder).map_err(|e| format!("error: {e}"))?;
            // a summed-area table is a storage buffer: read back and shown as a texture
            if let Mode::Texture { name, layer, level, .. } = &self.state.mode
                && ex.graph().texture(name).is_some_and(|t| t.format.is_table())
            {
                let img = ex.inspect().read_texture(name, *layer, *level).map_err(|e| format!("error: {e}"))?;
                self.table = Some(upload(&gfx.device, &gfx.queue, &img));
            } else {
                self.table = None;
            }
            let truth = self.truth_textures.as_ref();
            let (mut texture, mut pick) = shown(&self.state.mode, ex, truth);
            if let Some(t) = &self.table {
                texture = Some(t);
                pick.layer = 0;
                pick.level = 0;
            }
            let part = if self.ex_b.is_some() { Part::Left } else { Part::Whole };
            if let Some(t) = texture {
                gfx.present.draw(&mut encoder, &target, size, t, pick, part);
                shown_any = true;
            }
            if let Some(b) = &mut self.ex_b {
                b.encode(&mut encoder).map_err(|e| format!("error: split: {e}"))?;
                if let (Some(t), pick) = shown(&self.state.mode, b, truth) {
                    gfx.present.draw(&mut encoder, &target, size, t, pick, Part::Right);
                }
            }
        }
        if !shown_any {
            Present::clear(&mut encoder, &target);
        }
        let mut actions = Vec::new();
        let ui_start = Instant::now();
        let raw = gfx.egui_winit.take_egui_input(&gfx.window);
        let ui = UiData {
            state: &self.state,
            ex: self.ex.as_ref(),
            controls: &self.controls,
            diagnostics: self.diagnostics.as_deref(),
            status: &self.status,
            times: &self.times,
            techniques: &self.techniques,
            command: &self.command,
            truth: self.truth.as_ref(),
            rms: self.rms,
        };
        let show_panels = self.show_panels;
        let out = gfx.egui.run_pass(raw, |ctx| {
            if show_panels {
                panels(ctx, &ui, &mut actions);
            }
        });
        gfx.egui_winit.handle_platform_output(&gfx.window, out.platform_output);
        let jobs = gfx.egui.tessellate(out.shapes, out.pixels_per_point);
        push(&mut self.times.ui_ms, ui_start.elapsed().as_secs_f64() * 1e3);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [size.0, size.1],
            pixels_per_point: out.pixels_per_point,
        };
        let mut textures = out.textures_delta;
        for (id, deltas) in textures.set.drain() {
            for delta in &deltas {
                gfx.egui_wgpu.update_texture(&gfx.device, &gfx.queue, id, delta);
            }
        }
        let extra = gfx.egui_wgpu.update_buffers(&gfx.device, &gfx.queue, &mut encoder, &jobs, &screen);
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("sshc view: panels"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            gfx.egui_wgpu.render(&mut pass.forget_lifetime(), &jobs, &screen);
        }
        for id in textures.free.drain() {
            gfx.egui_wgpu.free_texture(&id);
        }
        let shot = self.screenshot.take().map(|p| {
            let buffer = copy_out(&gfx.device, &mut encoder, &frame.texture);
            (p, buffer)
        });
        gfx.queue.submit(extra.into_iter().chain([encoder.finish()]));
        if let Some((path, buffer)) = shot {
            let Some(buffer) = buffer else {
                return Err("error: the window's surface cannot be read back (no COPY_SRC usage): no screenshot".into());
            };
            write_png(&gfx.device, &buffer, size, gfx.config.format, &path)?;
            let vis = match &self.ex {
                Some(ex) => write_visibility(ex, &path)?,
                None => None,
            };
            self.command = with_words(self.state.command(&path.display().to_string()), &self.args.cascading);
            self.log.write(
                self.frame,
                json!({"event": "screenshot", "path": path, "visibility": vis, "state": self.state, "command": self.command,
                       "split_command": self.state.right().map(|r| with_words(r.command(&path.display().to_string()), &self.args.cascading)),
                       "gpu_ms": median(&self.times.gpu_ms), "ui_ms": median(&self.times.ui_ms), "present_ms": median(&self.times.present_ms), "frame_ms": median(&self.times.frame_ms),
                       "frames_timed": self.times.gpu_ms.len(),
                       "pass_ms": self.times.pass_ms.iter().map(|(k, v)| (k.clone(), median(v))).collect::<BTreeMap<_, _>>()}),
            );
        }
        gfx.window.pre_present_notify();
        let presenting = Instant::now();
        gfx.queue.present(frame);
        present_ms += presenting.elapsed().as_secs_f64() * 1e3;
        push(&mut self.times.present_ms, present_ms);
        if let Some((compile_ms, pipelines_ms, bind_ms)) = self.fresh.take() {
            // the new graph's first frame, to the GPU's end of it
            gfx.device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| format!("error: {e}"))?;
            let since_save = self.saved_at.take().map(|t| t.elapsed().as_secs_f64() * 1e3);
            self.log.write(
                self.frame,
                json!({"event": "first frame", "technique": self.state.technique, "compile_ms": compile_ms, "pipelines_ms": pipelines_ms,
                       "bind_ms": bind_ms, "save_to_frame_ms": since_save}),
            );
        }
        self.frame += 1;
        self.refine()?;
        if let Some(ex) = &mut self.ex
            && let Ok(Some((n, t))) = ex.targets.frame_times()
            && self.times.gpu_frame != Some(n)
        {
            self.times.gpu_frame = Some(n);
            self.times.passes = t.passes.into_iter().filter_map(|(n, ms)| Some((n, ms?))).collect();
            push(&mut self.times.gpu_ms, self.times.passes.iter().map(|p| p.1).sum());
            for (name, ms) in &self.times.passes {
                push(self.times.pass_ms.entry(name.clone()).or_default(), *ms);
            }
        }
        let now = Instant::now();
        if let Some(last) = self.times.last.replace(now) {
            push(&mut self.times.frame_ms, (now - last).as_secs_f64() * 1e3);
        }
        for a in actions {
            match a {
                Action::Event(e) => {
                    if let Err(e) = self.apply(e) {
                        self.status = e;
                    }
                }
                Action::Screenshot => {
                    let name = format!("sshc-view-{}.png", self.frame);
                    self.screenshot = Some(PathBuf::from(name));
                }
                Action::CopyCommand => {
                    self.command = with_words(self.state.command("view.png"), &self.args.cascading);
                    println!("{}", self.command);
                    if let Some(gfx) = &self.gfx {
                        gfx.egui.copy_text(self.command.clone());
                    }
                    self.log.write(self.frame, json!({"event": "command", "command": self.command}));
                }
            }
        }
        if self.waiting > 0 {
            self.waiting -= 1;
        }
        let script_done = self.args.script.is_some()
            && self.script.is_empty()
            && self.waiting == 0
            && !self.wait_ready
            && self.wait_answers.is_none()
            && self.wait_truth.is_none()
            && self.screenshot.is_none();
        let frames_done = self.args.frames.is_some_and(|n| self.frame >= n);
        if frames_done && let Some(p) = self.args.screenshot.take() {
            // one frame more, which writes it
            self.screenshot = Some(p);
            self.args.frames = Some(self.frame + 1);
            return Ok(());
        }
        if script_done || (frames_done && self.screenshot.is_none()) {
            self.log.write(self.frame, json!({"event": "exit"}));
            let end = if script_done {
                Ok(())
            } else {
                frames_end(self.diagnostics.as_deref())
            };
            self.finish(event_loop, end);
        }
        Ok(())
    }

    /// Keep the truth going while a mode shows it: start it over where the view changed,
    /// and take a new estimate (its textures and the RMS against the visibility).
    fn refine(&mut self) -> Result<(), String> {
        let shows = matches!(self.state.mode, Mode::Truth | Mode::Error { .. } | Mode::StdError { .. });
        self.refiner.pause(!shows);
        if self.ex.is_none() {
            return Ok(());
        }
        // started over once the view has stood for a few frames, not at every frame of a
        // drag (each start reads the camera's positions back from the GPU)
        if shows && self.truth_stale && self.frame >= self.last_move + TRUTH_SETTLE {
            let Some(ex) = &self.ex else { return Ok(()) };
            let (p, n) = crate::session::positions_normals(ex)?;
            let mut scene = self.current_scene();
            scene.lights.truncate(1);
            self.refiner.restart(scene, p, n);
            self.truth_stale = false;
            self.truth = None;
            self.truth_textures = None;
            self.rms = None;
        }
        let Some(ex) = &self.ex else { return Ok(()) };
        let Some(e) = self.refiner.poll() else { return Ok(()) };
        let vis = ex.inspect().read_visibilities().map_err(|e| format!("error: {e}"))?.channel(0);
        let error: Vec<f32> = vis
            .iter()
            .zip(&e.visibility)
            .map(|(v, t)| if t.is_finite() { v - t } else { 0.0 })
            .collect();
        let truth: Vec<f32> = e.visibility.iter().map(|t| if t.is_finite() { *t } else { 1.0 }).collect();
        self.rms = Some(super::refine::rms(&vis, &e.visibility, &e.facing));
        let (mean_se, max_se) = e.std_errors();
        self.log.write(
            self.frame,
            json!({"event": "truth", "rounds": e.rounds, "seconds": e.seconds, "mean_std_error": mean_se, "max_std_error": max_se,
                   "rms": self.rms.map(|r| r.0), "rms_penumbra": self.rms.map(|r| r.1)}),
        );
        if let Some(gfx) = &self.gfx {
            let make = |data: &[f32]| {
                let t = gfx.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("sshc view: truth"),
                    size: wgpu::Extent3d {
                        width: e.width,
                        height: e.height,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wgpu::TextureFormat::R32Float,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                });
                let bytes: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
                gfx.queue.write_texture(
                    t.as_image_copy(),
                    &bytes,
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(e.width * 4),
                        rows_per_image: None,
                    },
                    t.size(),
                );
                t
            };
            self.truth_textures = Some([make(&truth), make(&error), make(&e.std_error)]);
        }
        self.truth = Some(e);
        Ok(())
    }

    fn mouse_moved(&mut self, x: f64, y: f64) {
        let Some((px, py)) = self.mouse.at.replace((x, y)) else { return };
        let (dx, dy) = ((x - px) as f32, (y - py) as f32);
        let Some(gfx) = &self.gfx else { return };
        if gfx.egui.egui_wants_pointer_input() {
            return;
        }
        let h = gfx.config.height.max(1) as f32;
        if self.mouse.left && (self.mouse.shift || self.mouse.ctrl) && !self.state.lights.is_empty() {
            // drag the light: across the view and away (shift), or up and down (ctrl)
            let eye = self.orbit.position();
            let forward = (self.orbit.target - eye).normalize_or_zero();
            let flat = glam::Vec3::new(forward.x, 0.0, forward.z).normalize_or_zero();
            let right = flat.cross(glam::Vec3::Y);
            let scale = self.orbit.distance * 2.0 / h;
            let by = if self.state.lights[0].is_distant() {
                glam::Vec3::new(dx * 2.0 / h, -dy * 2.0 / h, 0.0)
            } else if self.mouse.ctrl {
                glam::Vec3::Y * -dy * scale
            } else {
                (right * dx - flat * dy) * scale
            };
            if let Err(e) = self.set_light(0, state::moved(&self.state.lights[0], by)) {
                self.status = e;
            }
        } else if self.mouse.left {
            self.orbit.turn(-dx * 3.0 / h, dy * 3.0 / h);
            self.orbit_moved();
        } else if self.mouse.right {
            self.orbit.pan(dx / h, dy / h);
            self.orbit_moved();
        }
    }
}

/// A view's `sshc render` line with its cascade options.
/// How a `--frames` run ends (issue 51): where the technique (or its scene) did not compile
/// or bind, with a failing status and its diagnostics (file:line:column), printed on
/// standard error by `main`, so that a script can tell; the window showed them too.
fn frames_end(diagnostics: Option<&str>) -> Result<(), String> {
    match diagnostics {
        Some(d) => Err(format!(
            "{}\nerror: `sshc view --frames`: the technique does not compile (above); the window drew the diagnostics, not the technique",
            d.trim_end()
        )),
        None => Ok(()),
    }
}

fn with_words(mut command: String, cascading: &crate::bind::Cascading) -> String {
    for w in cascading.words() {
        command.push(' ');
        command.push_str(&w);
    }
    command
}

/// The compile options of a state: its fixed params, precisions and schedules; a graph for
/// any scene (lights move).
fn options(state: &ViewState) -> sshc::CompileOptions {
    sshc::CompileOptions {
        set: state.fixed.clone().into_iter().collect(),
        precision: state.precisions.clone().into_iter().collect(),
        schedule: state.schedules.clone().into_iter().collect(),
        // the Shade's debug outputs, to look at (nothing where it declares none)
        debug: true,
        ..Default::default()
    }
}

/// The texture a mode shows from `ex` (the truth's from `truth`: the truth, the error, the
/// standard error), and how to read it.
fn shown<'a>(mode: &Mode, ex: &'a Bound, truth: Option<&'a [wgpu::Texture; 3]>) -> (Option<&'a wgpu::Texture>, Pick) {
    match mode {
        Mode::Shaded => (Some(ex.targets.camera_texture(CameraOutput::Color)), shaded()),
        // light 0's visibility, or the cascades' combination
        Mode::Visibility => (
            Some(ex.targets.visibility()),
            Pick {
                layer: 0,
                level: 0,
                channel: 0,
                map: ColourMap::Grey.index(),
                lo: 0.0,
                hi: 1.0,
                square: false,
            },
        ),
        // the combining step's channel 1: the cascade, `k + t` in a band
        Mode::Cascades => {
            let n = ex.targets.cascades();
            let texture = if n > 1 {
                ex.targets.visibility()
            } else {
                ex.targets.camera_texture(CameraOutput::Visibility)
            };
            (
                Some(texture),
                Pick {
                    layer: 0,
                    level: 0,
                    // one R32Float channel without cascades: its g reads 0, cascade 0
                    channel: 1,
                    map: ColourMap::Viridis.index(),
                    lo: 0.0,
                    hi: (n.max(2) - 1) as f32,
                    square: false,
                },
            )
        }
        Mode::Truth | Mode::Error { .. } | Mode::StdError { .. } => {
            let (i, map, lo, hi) = match *mode {
                Mode::Error { range } => (1, ColourMap::Diverging, -range, range),
                Mode::StdError { range } => (2, ColourMap::Viridis, 0.0, range),
                _ => (0, ColourMap::Grey, 0.0, 1.0),
            };
            (
                truth.map(|t| &t[i]),
                Pick {
                    layer: 0,
                    level: 0,
                    channel: 0,
                    map: map.index(),
                    lo,
                    hi,
                    square: false,
                },
            )
        }
        Mode::Texture {
            name,
            layer,
            level,
            channel,
            lo,
            hi,
            map,
        } => (
            ex.targets.texture(name).ok(),
            Pick {
                layer: *layer,
                level: *level,
                channel: *channel,
                map: map.index(),
                lo: *lo,
                hi: *hi,
                // a shadow map's texture in a square; a debug output over the camera's view
                square: ex
                    .graph()
                    .texture(name)
                    .is_none_or(|t| t.extent != sshc_runtime::graph::Extent::Camera),
            },
        ),
    }
}

/// An image of the runtime's as an `Rgba32Float` texture.
fn upload(device: &wgpu::Device, queue: &wgpu::Queue, img: &sshc_runtime::gpu::Image) -> wgpu::Texture {
    let t = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("sshc view: read back"),
        size: wgpu::Extent3d {
            width: img.width,
            height: img.height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let bytes: Vec<u8> = img.rgba.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    queue.write_texture(
        t.as_image_copy(),
        &bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(img.width * 16),
            rows_per_image: None,
        },
        t.size(),
    );
    t
}

fn first_size(ex: &Bound) -> (u32, u32) {
    ex.targets.camera_size()
}

fn same_file(a: &Path, b: &Path) -> bool {
    let c = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    c(a) == c(b)
}

/// The shaded colour as it is.
fn shaded() -> Pick {
    Pick {
        layer: 0,
        level: 0,
        channel: 4,
        map: 0,
        lo: 0.0,
        hi: 1.0,
        square: false,
    }
}

/// A copy of the surface texture into a buffer (rows padded to 256 bytes), where the
/// surface allows it.
fn copy_out(device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, texture: &wgpu::Texture) -> Option<wgpu::Buffer> {
    if !texture.usage().contains(wgpu::TextureUsages::COPY_SRC) {
        return None;
    }
    let row = (texture.width() * 4).div_ceil(256) * 256;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("sshc view: screenshot"),
        size: u64::from(row) * u64::from(texture.height()),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: None,
            },
        },
        texture.size(),
    );
    Some(buffer)
}

fn write_png(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    (w, h): (u32, u32),
    format: wgpu::TextureFormat,
    path: &Path,
) -> Result<(), String> {
    let slice = buffer.slice(..);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| format!("error: reading the window back: {e}"))?;
    let data = slice
        .get_mapped_range()
        .map_err(|e| format!("error: reading the window back: {e}"))?;
    let row = (w * 4).div_ceil(256) * 256;
    let bgra = matches!(format, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb);
    let mut img = image::RgbaImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let i = (y * row + x * 4) as usize;
            let p = &data[i..i + 4];
            let px = if bgra { [p[2], p[1], p[0], 255] } else { [p[0], p[1], p[2], 255] };
            img.put_pixel(x, y, image::Rgba(px));
        }
    }
    drop(data);
    buffer.unmap();
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("error: {}: {e}", dir.display()))?;
    }
    crate::session::save_image(&img, path)
}

/// The visibility beside a screenshot: `NAME.visibility.pfm`, as `sshc render --visibility`
/// writes it (light 0's alone, or each light's in a channel).
fn write_visibility(ex: &Bound, png: &Path) -> Result<Option<PathBuf>, String> {
    let p = png.with_extension("visibility.pfm");
    let vis = ex.inspect().read_visibilities().map_err(|e| format!("error: {e}"))?;
    // cascades: their combination in channel 0 (`sshc render --visibility` writes it)
    match if ex.targets.cascades() > 1 { 1 } else { ex.targets.lights() } {
        1 => vis.write_pfm_gray(&p, 0),
        2 | 3 => vis.write_pfm_rgb(&p),
        _ => return Ok(None),
    }
    .map_err(|e| format!("error: {e}"))?;
    Ok(Some(p))
}

/// What the panels read.
struct UiData<'a> {
    state: &'a ViewState,
    ex: Option<&'a Bound>,
    controls: &'a Controls,
    diagnostics: Option<&'a str>,
    status: &'a str,
    times: &'a Times,
    techniques: &'a [PathBuf],
    command: &'a str,
    truth: Option<&'a Estimate>,
    rms: Option<(f64, f64)>,
}

/// Frames the view must stand still before the truth starts over.
const TRUTH_SETTLE: u64 = 3;

const PRECISIONS: [&str; 5] = ["auto", "unorm8", "unorm16", "f16", "f32"];

/// The panels: technique, params, storage and schedules, lights, what is shown, times.
/// The technique files the picker lists: the working folder's `techniques/*.ron` (a
/// researcher's own), the repository's bundled ones where `sshc` runs from elsewhere, and
/// the file given; each once (by its canonical path), sorted.
fn technique_files(given: &Path) -> Vec<PathBuf> {
    let mut dirs = vec![PathBuf::from("techniques")];
    if let Some(repo) = crate::session::repository() {
        dirs.push(repo.join("techniques"));
    }
    let mut seen = std::collections::HashSet::new();
    let mut files: Vec<PathBuf> = dirs
        .iter()
        .filter_map(|d| std::fs::read_dir(d).ok())
        .flat_map(|d| d.filter_map(|e| e.ok().map(|e| e.path())))
        .filter(|p| p.extension().is_some_and(|x| x == "ron") && p.is_file())
        .chain(std::iter::once(given.to_path_buf()))
        .filter(|p| seen.insert(p.canonicalize().unwrap_or_else(|_| p.clone())))
        .collect();
    files.sort();
    files
}

fn panels(ctx: &egui::Context, d: &UiData, actions: &mut Vec<Action>) {
    // the panels start folded on a small window, which they would cover
    let wide = ctx.content_rect().width() >= 600.0;
    egui::Window::new("sshc").default_width(280.0).default_open(wide).show(ctx, |ui| {
        ui.label(d.status);
        let mut technique = d.state.technique.clone();
        egui::ComboBox::from_label("technique")
            .selected_text(technique.display().to_string())
            .show_ui(ui, |ui| {
                for t in d.techniques {
                    ui.selectable_value(&mut technique, t.clone(), t.display().to_string());
                }
            });
        if technique != d.state.technique {
            actions.push(Action::Event(Event::Technique(technique)));
        }
        ui.horizontal(|ui| {
            if ui.button("reset view").clicked() {
                actions.push(Action::Event(Event::Reset));
            }
            if ui.button("screenshot").clicked() {
                actions.push(Action::Screenshot);
            }
            if ui.button("copy as command").clicked() {
                actions.push(Action::CopyCommand);
            }
        });
        if !d.command.is_empty() {
            ui.add(egui::Label::new(egui::RichText::new(d.command).monospace().small()).wrap());
        }
        if let Some(ex) = d.ex {
            egui::CollapsingHeader::new("params")
                .default_open(true)
                .show(ui, |ui| params(ui, d, ex, actions));
            egui::CollapsingHeader::new("precisions and schedules").show(ui, |ui| storage(ui, d, actions));
            egui::CollapsingHeader::new("lights").show(ui, |ui| lights(ui, d, actions));
            egui::CollapsingHeader::new("show")
                .default_open(true)
                .show(ui, |ui| show(ui, d, ex, actions));
            egui::CollapsingHeader::new("GPU times and memory").show(ui, |ui| times(ui, d, ex));
        }
    });
    if let Some(diag) = d.diagnostics {
        egui::Window::new("diagnostics").default_width(560.0).show(ctx, |ui| {
            egui::ScrollArea::vertical().max_height(320.0).show(ui, |ui| {
                ui.label(egui::RichText::new(diag).monospace().color(egui::Color32::from_rgb(255, 140, 120)));
            });
        });
    }
}

fn params(ui: &mut egui::Ui, d: &UiData, ex: &Bound, actions: &mut Vec<Action>) {
    for p in &ex.graph().params {
        let uniform = p.offset.is_some();
        let mut v = d.state.params.get(&p.name).copied().unwrap_or(p.value);
        if !uniform && let Some(f) = d.state.fixed.get(&p.name).and_then(|s| s.parse::<f64>().ok()) {
            v = f;
        }
        let before = v;
        let (lo, hi) = p.range.unwrap_or(if v == 0.0 {
            (0.0, 1.0)
        } else {
            (v.min(0.0) * 4.0, v.max(0.0) * 4.0)
        });
        let label = if uniform { p.name.clone() } else { format!("{} (fixed)", p.name) };
        let r = match p.ty {
            ParamType::Bool => {
                let mut b = v != 0.0;
                let r = ui.checkbox(&mut b, &label);
                v = f64::from(u8::from(b));
                r
            }
            ParamType::I32 => ui.add(egui::Slider::new(&mut v, lo..=hi).step_by(1.0).text(&label)),
            ParamType::F32 => ui.add(egui::Slider::new(&mut v, lo..=hi).text(&label)),
        };
        let r = match &p.doc {
            Some(doc) => r.on_hover_text(doc),
            None => r,
        };
        // a fixed param recompiles when the drag ends, not at every step
        let commit = if uniform {
            v != before
        } else {
            v != before && !r.dragged() || r.drag_stopped()
        };
        if commit {
            actions.push(Action::Event(Event::Set {
                name: p.name.clone(),
                value: v,
            }));
        }
    }
}

fn storage(ui: &mut egui::Ui, d: &UiData, actions: &mut Vec<Action>) {
    for name in &d.controls.storage {
        let now = d.state.precisions.get(name).cloned().unwrap_or_else(|| "auto".into());
        let mut pick = now.clone();
        egui::ComboBox::from_label(name).selected_text(&pick).show_ui(ui, |ui| {
            for p in PRECISIONS {
                ui.selectable_value(&mut pick, p.to_string(), p);
            }
        });
        if pick != now {
            actions.push(Action::Event(Event::Precision {
                name: name.clone(),
                value: pick,
            }));
        }
    }
    for (pass, compute) in &d.controls.schedules {
        let now = if *compute { "compute" } else { "fragment" };
        let mut pick = now.to_string();
        egui::ComboBox::from_label(format!("{pass} schedule"))
            .selected_text(&pick)
            .show_ui(ui, |ui| {
                for s in ["fragment", "compute"] {
                    ui.selectable_value(&mut pick, s.to_string(), s);
                }
            });
        if pick != now {
            actions.push(Action::Event(Event::Schedule {
                pass: pass.clone(),
                value: pick,
            }));
        }
    }
}

fn lights(ui: &mut egui::Ui, d: &UiData, actions: &mut Vec<Action>) {
    ui.label("shift-drag: move light 0 across; ctrl-drag: up and down");
    for (i, l) in d.state.lights.iter().enumerate() {
        ui.label(format!("light {i}: {}", l.kind_name()));
        if let Some(mut s) = state::size(l) {
            let before = s;
            let max = if l.is_distant() { 20.0 } else { (before * 4.0).max(1.0) };
            ui.add(egui::Slider::new(&mut s, 0.0..=max).text("size"));
            if s != before {
                actions.push(Action::Event(Event::LightSize { light: i, size: s }));
            }
        }
    }
}

fn show(ui: &mut egui::Ui, d: &UiData, ex: &Bound, actions: &mut Vec<Action>) {
    let mut mode = d.state.mode.clone();
    ui.horizontal(|ui| {
        ui.selectable_value(&mut mode, Mode::Shaded, "shaded");
        ui.selectable_value(&mut mode, Mode::Visibility, "visibility");
        ui.selectable_value(&mut mode, Mode::Truth, "truth");
        if ex.targets.cascades() > 1 {
            ui.selectable_value(&mut mode, Mode::Cascades, "cascades");
        }
    });
    ui.horizontal(|ui| {
        let error = match mode {
            Mode::Error { range } => range,
            _ => 0.25,
        };
        ui.selectable_value(&mut mode, Mode::Error { range: error }, "error");
        let se = match mode {
            Mode::StdError { range } => range,
            _ => 0.05,
        };
        ui.selectable_value(&mut mode, Mode::StdError { range: se }, "truth's std. error");
    });
    if let Mode::Error { range } | Mode::StdError { range } = &mut mode {
        ui.add(egui::Slider::new(range, 0.001..=1.0).logarithmic(true).text("full colour at"));
    }
    if let Some(t) = d.truth {
        let (mean, max) = t.std_errors();
        ui.label(format!(
            "truth: {} rounds of {} samples in {:.1} s; std. error mean {mean:.4}, max {max:.4}",
            t.rounds,
            super::refine::SAMPLES_PER_ROUND,
            t.seconds
        ));
    }
    if let Some((all, pen)) = d.rms {
        ui.label(format!(
            "RMS error: {all:.4} over the pixels facing the light, {pen:.4} over the penumbra"
        ));
    }
    // the Shade's debug outputs: each over the view, its values fitted to viridis
    let debug = ex.inspect().debug_outputs();
    if !debug.is_empty() {
        ui.horizontal(|ui| {
            ui.label("debug:");
            for o in &debug {
                let on = matches!(&mode, Mode::Texture { name, .. } if *name == o.texture);
                if ui.selectable_label(on, &o.name).clicked() && !on {
                    let (lo, hi) = ex
                        .inspect()
                        .read_debug(0, &o.name)
                        .ok()
                        .and_then(|img| crate::image_io::finite_range(img.rgba.iter().map(|p| p[0])))
                        .map_or((0.0, 1.0), |(lo, hi)| (lo, if hi > lo { hi } else { lo + 1.0 }));
                    mode = Mode::Texture {
                        name: o.texture.clone(),
                        layer: 0,
                        level: 0,
                        channel: 0,
                        lo,
                        hi,
                        map: ColourMap::Viridis,
                    };
                }
            }
        });
    }
    let current = match &mode {
        Mode::Texture { name, .. } => name.clone(),
        Mode::Shaded | Mode::Visibility | Mode::Cascades | Mode::Truth | Mode::Error { .. } | Mode::StdError { .. } => "a texture".into(),
    };
    let mut name = current.clone();
    egui::ComboBox::from_label("texture").selected_text(&name).show_ui(ui, |ui| {
        for t in &ex.graph().textures {
            ui.selectable_value(&mut name, t.name.clone(), &t.name);
        }
    });
    if name != current {
        mode = Mode::Texture {
            name,
            layer: 0,
            level: 0,
            channel: 0,
            lo: 0.0,
            hi: 1.0,
            map: ColourMap::Viridis,
        };
    }
    if let Mode::Texture {
        name,
        layer,
        level,
        channel,
        lo,
        hi,
        map,
    } = &mut mode
        && let Some(decl) = ex.graph().texture(name)
    {
        if decl.format.is_table() {
            ui.label("a summed-area table (prefix sums in a storage buffer): read back every frame");
        }
        let layers = decl.array_layers().max(1);
        let levels = if decl.mips {
            32 - ex.targets.shadow_size().leading_zeros()
        } else {
            1
        };
        ui.add(egui::Slider::new(layer, 0..=layers - 1).text("layer"));
        ui.add(egui::Slider::new(level, 0..=levels - 1).text("level"));
        ui.add(egui::Slider::new(channel, 0..=3).text("channel"));
        ui.horizontal(|ui| {
            ui.add(egui::DragValue::new(lo).speed(0.01).prefix("lo "));
            ui.add(egui::DragValue::new(hi).speed(0.01).prefix("hi "));
            // the channel's finite values, read back once
            if ui.button("fit").clicked()
                && let Ok(img) = ex.inspect().read_texture(name, *layer, *level)
            {
                let c = (*channel).min(3) as usize;
                let (a, b) = img
                    .rgba
                    .iter()
                    .map(|p| p[c])
                    .filter(|v| v.is_finite())
                    .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
                if a <= b {
                    (*lo, *hi) = (a, if b > a { b } else { a + 1.0 });
                }
            }
        });
        egui::ComboBox::from_label("colour map")
            .selected_text(map.name())
            .show_ui(ui, |ui| {
                for m in ColourMap::ALL {
                    ui.selectable_value(map, m, m.name());
                }
            });
    }
    if mode != d.state.mode {
        actions.push(Action::Event(Event::Show(mode)));
    }
    ui.separator();
    match &d.state.split {
        None => {
            if ui
                .button("split: keep these settings on the right")
                .on_hover_text("the right half keeps the technique and settings of now; change the left half to compare")
                .clicked()
            {
                actions.push(Action::Event(Event::Split(Some(d.state.as_split()))));
            }
        }
        Some(split) => {
            ui.label(format!("right half: {}", split.technique.display()));
            let mut t = split.technique.clone();
            egui::ComboBox::from_label("right technique")
                .selected_text(t.display().to_string())
                .show_ui(ui, |ui| {
                    for p in d.techniques {
                        ui.selectable_value(&mut t, p.clone(), p.display().to_string());
                    }
                });
            if t != split.technique {
                actions.push(Action::Event(Event::Split(Some(super::state::Split {
                    technique: t,
                    params: BTreeMap::new(),
                    fixed: BTreeMap::new(),
                    precisions: BTreeMap::new(),
                    schedules: BTreeMap::new(),
                }))));
            }
            if ui.button("end the split").clicked() {
                actions.push(Action::Event(Event::Split(None)));
            }
        }
    }
}

fn times(ui: &mut egui::Ui, d: &UiData, ex: &Bound) {
    ui.label(format!(
        "frame {:.1} ms; panels {:.2} ms and presentation {:.2} ms of CPU (medians of the last {})",
        median(&d.times.frame_ms),
        median(&d.times.ui_ms),
        median(&d.times.present_ms),
        d.times.frame_ms.len()
    ));
    let total: f64 = d.times.passes.iter().map(|p| p.1).sum();
    ui.label(format!("sshc's passes: {total:.3} ms on the GPU"));
    let widest = d.times.passes.iter().map(|p| p.1).fold(0.0, f64::max).max(1e-9);
    for (name, t) in &d.times.passes {
        ui.horizontal(|ui| {
            let (rect, _) = ui.allocate_exact_size(egui::vec2(120.0, 12.0), egui::Sense::hover());
            let w = rect.width() * (*t / widest) as f32;
            ui.painter().rect_filled(
                egui::Rect::from_min_size(rect.min, egui::vec2(w, rect.height())),
                2.0,
                egui::Color32::from_rgb(90, 160, 230),
            );
            ui.label(format!("{name} {t:.3} ms"));
        });
    }
    let mem = ex.inspect().memory();
    let sum: u64 = mem.iter().map(|m| m.1).sum();
    ui.label(format!("memory: {:.1} MiB", sum as f64 / 1048576.0));
    for (name, bytes) in mem {
        ui.label(format!("  {name}: {:.2} MiB", bytes as f64 / 1048576.0));
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_none()
            && let Err(e) = self.open(event_loop)
        {
            self.finish(event_loop, Err(e));
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        if let Some(gfx) = &mut self.gfx {
            let r = gfx.egui_winit.on_window_event(&gfx.window, &event);
            if r.consumed && !matches!(event, WindowEvent::RedrawRequested | WindowEvent::Resized(_)) {
                return;
            }
        }
        match event {
            WindowEvent::CloseRequested => {
                self.log.write(self.frame, json!({"event": "exit"}));
                self.finish(event_loop, Ok(()));
            }
            WindowEvent::Resized(size) => {
                if let Some(gfx) = &mut self.gfx
                    && size.width > 0
                    && size.height > 0
                    && (size.width, size.height) != (gfx.config.width, gfx.config.height)
                {
                    gfx.config.width = size.width;
                    gfx.config.height = size.height;
                    gfx.surface.configure(&gfx.device, &gfx.config);
                    self.set_camera_size(size.width, size.height);
                    self.resized = true;
                }
            }
            WindowEvent::KeyboardInput { event, .. }
                if event.state == ElementState::Pressed
                    && !event.repeat
                    && event.logical_key == winit::keyboard::Key::Named(winit::keyboard::NamedKey::Tab) =>
            {
                self.show_panels = !self.show_panels;
            }
            WindowEvent::ModifiersChanged(m) => {
                self.mouse.shift = m.state().shift_key();
                self.mouse.ctrl = m.state().control_key();
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.mouse.left = down,
                    MouseButton::Right | MouseButton::Middle => self.mouse.right = down,
                    MouseButton::Back | MouseButton::Forward | MouseButton::Other(_) => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => self.mouse_moved(position.x, position.y),
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.orbit.zoom(0.9f32.powf(lines));
                self.orbit_moved();
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.log.write(self.frame, json!({"event": "error", "error": e}));
                    if self.args.script.is_some() || self.args.frames.is_some() {
                        // scripted: an error ends the run with it
                        self.finish(event_loop, Err(e));
                    } else {
                        self.status = e;
                    }
                }
            }
            _ => {}
        }
    }

    /// The surface, the device and every handle to it (the workers') and the window go
    /// while the event loop (and its X connection) still lives: a swapchain destroyed
    /// after its display connection has closed, or a device left to the driver's exit
    /// handlers, can crash the driver.
    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        self.table = None;
        self.truth_textures = None;
        self.ex = None;
        self.ex_b = None;
        self.worker = None;
        self.worker_b = None;
        self.gfx = None;
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(gfx) = &self.gfx {
            gfx.window.request_redraw();
        }
    }
}
