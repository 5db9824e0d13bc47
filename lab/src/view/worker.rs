//! Compilation off the window's thread: a technique is compiled, its pipelines created and
//! its scene bound on a worker, and the window keeps drawing the last good graph until the
//! new one is ready. Also the file watcher that asks for a recompilation on save.

use crate::bind::Cascading;
use crate::run::{Bound, Loaded};
use crate::scene::Scene;
use notify::Watcher as _;
use sshc_runtime::gpu::Gpu;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// What to compile and bind.
pub struct Request {
    /// Increases with every request; a result answers the request of its id.
    pub id: u64,
    pub technique: PathBuf,
    pub options: sshc::CompileOptions,
    /// The scene as the window has it (its camera and lights as they are now).
    pub scene: Scene,
    /// Its cascades, when asked for.
    pub cascading: Cascading,
}

/// The compiled technique's controls: what the panels list.
#[derive(Clone, Debug, Default)]
pub struct Controls {
    /// Channels and expansions, whose precision can be set.
    pub storage: Vec<String>,
    /// Passes that have a fragment and a compute schedule, and whether each runs in compute.
    pub schedules: Vec<(String, bool)>,
    /// Warnings, rendered as the terminal shows them.
    pub warnings: String,
}

/// A request's answer.
pub enum Answer {
    Ready(Box<Ready>),
    /// The technique (or its scene) does not compile or bind: the diagnostics as the
    /// terminal shows them (file:line:column and help).
    Failed {
        id: u64,
        diagnostics: String,
    },
}

pub struct Ready {
    pub id: u64,
    pub bound: Bound,
    pub controls: Controls,
    /// Compilation, pipeline creation and binding, in ms.
    pub compile_ms: f64,
    pub pipelines_ms: f64,
    pub bind_ms: f64,
}

/// The worker thread.
pub struct Worker {
    /// `None` once dropped: the thread's `recv` then ends and it returns.
    to: Option<mpsc::Sender<Request>>,
    thread: Option<std::thread::JoinHandle<()>>,
    from: mpsc::Receiver<Answer>,
    next: u64,
    /// The latest request not yet answered.
    pub pending: Option<u64>,
}

impl Worker {
    pub fn start(gpu: Gpu) -> Worker {
        let (to, requests) = mpsc::channel::<Request>();
        let (answers, from) = mpsc::channel();
        let thread = std::thread::spawn(move || {
            while let Ok(mut r) = requests.recv() {
                // only the latest of the requests waiting is worth compiling
                while let Ok(newer) = requests.try_recv() {
                    r = newer;
                }
                let id = r.id;
                let answer = match build(&gpu, r) {
                    Ok(ready) => Answer::Ready(Box::new(ready)),
                    Err(diagnostics) => Answer::Failed { id, diagnostics },
                };
                if answers.send(answer).is_err() {
                    break;
                }
            }
        });
        Worker {
            to: Some(to),
            thread: Some(thread),
            from,
            next: 0,
            pending: None,
        }
    }

    /// Ask for a compilation; returns its id.
    pub fn request(&mut self, technique: &Path, options: sshc::CompileOptions, scene: Scene, cascading: Cascading) -> u64 {
        self.next += 1;
        let id = self.next;
        self.pending = Some(id);
        let Some(to) = &self.to else { return id };
        let _ = to.send(Request {
            id,
            technique: technique.to_path_buf(),
            options,
            scene,
            cascading,
        });
        id
    }

    /// The answer to the latest request, once it has come (older answers are dropped).
    pub fn poll(&mut self) -> Option<Answer> {
        let mut latest = None;
        while let Ok(a) = self.from.try_recv() {
            let id = match &a {
                Answer::Ready(r) => r.id,
                Answer::Failed { id, .. } => *id,
            };
            if Some(id) == self.pending {
                self.pending = None;
                latest = Some(a);
            }
        }
        latest
    }

    /// Wait for the latest request's answer (scripts and the first frame).
    pub fn wait(&mut self) -> Option<Answer> {
        while self.pending.is_some() {
            let a = self.from.recv().ok()?;
            let id = match &a {
                Answer::Ready(r) => r.id,
                Answer::Failed { id, .. } => *id,
            };
            if Some(id) == self.pending {
                self.pending = None;
                return Some(a);
            }
        }
        None
    }
}

/// The thread ends (after the compilation in flight) and its device handle with it, before
/// the process exits: a device left to the driver's exit handlers can crash them.
impl Drop for Worker {
    fn drop(&mut self) {
        self.to = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Diagnostics rendered as the terminal shows them, without colour.
fn render_diagnostics(d: &sshc::Diagnostics, path: &Path, source: &str) -> String {
    d.render(&path.display().to_string(), source)
}

fn build(gpu: &Gpu, r: Request) -> Result<Ready, String> {
    let source = crate::session::read(&r.technique)?;
    let t = Instant::now();
    let compiled = sshc::compile_str(&source, &r.options).map_err(|d| render_diagnostics(&d, &r.technique, &source))?;
    let compile_ms = t.elapsed().as_secs_f64() * 1e3;
    let warnings = render_diagnostics(&sshc::Diagnostics(compiled.warnings.clone()), &r.technique, &source);
    let controls = Controls {
        storage: compiled.stored_names(),
        schedules: compiled.schedules(),
        warnings,
    };
    let t = Instant::now();
    let mut loaded = Loaded::new(gpu, compiled.graph, compiled.shaders).map_err(|e| format!("error: {e}"))?;
    // the viewer shows any texture of light 0: each light keeps its own
    loaded.limits.share_light_textures = false;
    let pipelines_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let bound = bind(&loaded, &r.scene, &r.cascading)?;
    let bind_ms = t.elapsed().as_secs_f64() * 1e3;
    Ok(Ready {
        id: r.id,
        bound,
        controls,
        compile_ms,
        pipelines_ms,
        bind_ms,
    })
}

/// Bind every light of `scene` as `sshc render` does (each light its own passes), or its
/// light's cascades where `cascading` or the scene asks for them.
fn bind(ex: &Loaded, scene: &Scene, cascading: &Cascading) -> Result<Bound, String> {
    crate::bind::check_cascades(scene, cascading)?;
    cascading.bind_or_scene(ex, scene, true).map(|(b, _)| b)
}

/// Watches files and says which of them changed.
pub struct Watch {
    _watcher: notify::RecommendedWatcher,
    events: mpsc::Receiver<notify::Result<notify::Event>>,
    files: Vec<PathBuf>,
}

impl Watch {
    /// Watch the folders of `files` (editors save by replacing a file, which a watch on the
    /// file itself would lose).
    pub fn new(files: &[PathBuf]) -> Result<Watch, String> {
        let (tx, events) = mpsc::channel();
        let mut watcher = notify::recommended_watcher(tx).map_err(|e| format!("error: cannot watch files: {e}"))?;
        let files: Vec<PathBuf> = files
            .iter()
            .map(|f| std::fs::canonicalize(f).unwrap_or_else(|_| f.clone()))
            .collect();
        let mut dirs: Vec<PathBuf> = files.iter().filter_map(|f| f.parent().map(Path::to_path_buf)).collect();
        dirs.sort();
        dirs.dedup();
        for d in &dirs {
            watcher
                .watch(d, notify::RecursiveMode::NonRecursive)
                .map_err(|e| format!("error: cannot watch {}: {e}", d.display()))?;
        }
        Ok(Watch {
            _watcher: watcher,
            events,
            files,
        })
    }

    /// The watched files written since the last call, after `settle` without a further
    /// event (a save is often several events).
    pub fn changed(&self, settle: Duration) -> Vec<PathBuf> {
        let mut out: Vec<PathBuf> = Vec::new();
        let mut wait = Duration::ZERO;
        loop {
            let next = if wait.is_zero() {
                self.events.try_recv().ok()
            } else {
                self.events.recv_timeout(wait).ok()
            };
            let Some(event) = next else { break };
            let Ok(event) = event else { continue };
            if matches!(event.kind, notify::EventKind::Access(_)) {
                continue;
            }
            for p in event.paths {
                let p = std::fs::canonicalize(&p).unwrap_or(p);
                if self.files.contains(&p) && !out.contains(&p) {
                    out.push(p);
                }
            }
            if !out.is_empty() {
                wait = settle;
            }
        }
        out
    }
}
