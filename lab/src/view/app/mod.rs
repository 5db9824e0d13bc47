//! The window: winit's event loop, the wgpu surface, the technique's stages and the
//! egui panels.
//!
//! The files: `handler.rs` winit's events (the window's, the keyboard's, the mouse's drags),
//! `device.rs` the window, the device and its surface, `frame.rs` one frame drawn,
//! `shown.rs` the texture a mode shows, `compile.rs` the workers' compilations and the
//! files watched, `events.rs` the scripted and panel events and the script's waits,
//! `capture.rs` screenshots and the view's command line, `truth.rs` the truth refined
//! while it is shown, `timing.rs` the frame's times, and `panels/` the egui panels, one
//! file per group.
//!
//! This file: `run`, the application's state (`App`) made from the arguments, and the
//! scene and sizes its parts share.

mod capture;
mod compile;
mod device;
mod events;
mod frame;
mod handler;
mod panels;
mod shown;
mod timing;
mod truth;

use super::ViewArgs;
use super::refine::{Estimate, Refiner};
use super::script::{Event, Log};
use super::state::{self, Mode, Orbit, ViewState};
use super::worker::{Controls, Watch, Worker};
use crate::run::Bound;
use crate::scene::Scene;
use device::Gfx;
use handler::Mouse;
use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};
use std::time::Instant;
use timing::Times;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};

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

    fn set_camera_size(&mut self, w: u32, h: u32) {
        self.state.camera = state::with_size(&self.state.camera, w, h);
    }
}

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
