//! What the measurement commands share: one *session* is a scene loaded with the command
//! line's overrides, a GPU, and a technique loaded (compiled here) or a compiled
//! graph; plus the ground-truth options and the cached, progress-reporting truth, and the
//! reading, reporting and argument helpers of the `sshc` command line.

use crate::run::{Bound, Loaded};
use crate::scene::Scene;
use crate::truth::{self, Source, Truth, TruthCache, TruthSettings};
use codespan_reporting::term::termcolor::{ColorChoice, StandardStream};
use glam::Vec3;
use sshc::Diagnostics;
use sshc_runtime::gpu::{CameraOutput, Gpu, RuntimeError};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// The repository sshc's bundled files (scenes/, techniques/) come from, whatever the
/// working folder (issue 51): the first folder above the running binary that holds both
/// (a build under the repository's `target/`), else the one this crate was built from.
pub fn repository() -> Option<PathBuf> {
    let is_root = |d: &Path| d.join("scenes").is_dir() && d.join("techniques").is_dir();
    let beside_binary = std::env::current_exe()
        .ok()
        .and_then(|exe| exe.ancestors().skip(1).find(|d| is_root(d)).map(Path::to_path_buf));
    beside_binary.or_else(|| {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .parent()
            .filter(|d| is_root(d))
            .map(Path::to_path_buf)
    })
}

/// Reads a text file, with the path in the error.
pub fn read(path: &Path) -> Result<String, String> {
    read_capped(path, sshc_scene::MAX_TEXT_BYTES)
}

/// Reads a text file of at most `max` bytes that is a regular file (not a FIFO, a device or
/// a folder): a hostile path neither hangs the reader nor fills its memory.
pub fn read_capped(path: &Path, max: u64) -> Result<String, String> {
    sshc_scene::read_text(path, max).map_err(|e| format!("error: cannot read `{}`: {e}", path.display()))
}

pub use crate::files::{append_to, output_file, output_folder, save_image, writable, write_new};

/// Prints diagnostics against their source file on standard error (coloured on a terminal).
pub fn report(diags: &Diagnostics, path: &Path, source: &str) {
    let choice = if std::io::stderr().is_terminal() {
        ColorChoice::Auto
    } else {
        ColorChoice::Never
    };
    let mut stderr = StandardStream::stderr(choice);
    for d in &diags.0 {
        d.emit_to(&mut stderr, &path.display().to_string(), source);
    }
}

/// Parses `--fit`: `scene`, `casters` or `view`.
pub fn shadow_fit(s: &str) -> Result<sshc_scene::ShadowFit, String> {
    match s {
        "scene" => Ok(sshc_scene::ShadowFit::Scene),
        "casters" => Ok(sshc_scene::ShadowFit::Casters),
        "view" => Ok(sshc_scene::ShadowFit::View),
        _ => Err(format!("unknown fit `{s}`: expected scene, casters or view")),
    }
}

/// Parses `NAME=VALUE` (the `--set` and `--precision` arguments).
pub fn pair(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((k, v)) if !k.trim().is_empty() => Ok((k.trim().to_string(), v.trim().to_string())),
        _ => Err(format!("expected NAME=VALUE, found `{s}`")),
    }
}

/// The compile-time variants of a technique the command line can ask for without editing
/// it: `compile`, `check`, `explain` and `verify` flatten it.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct Variants {
    /// Override a param: NAME=VALUE (a RON literal such as 16, 2.5 or true). Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = pair)]
    pub set: Vec<(String, String)>,
    /// Override the precision of a channel or expansion: NAME=unorm8|unorm16|f16|f32|auto. Repeatable.
    #[arg(long = "precision", value_name = "NAME=PRECISION", value_parser = pair)]
    pub precision: Vec<(String, String)>,
    /// Override the schedule of a Map, Filter, Mipmap or Shade pass: PASS=fragment|compute (`*` for all of them). Repeatable.
    #[arg(long = "schedule", value_name = "PASS=SCHEDULE", value_parser = pair)]
    pub schedule: Vec<(String, String)>,
    /// Compile the Shade's debug outputs (`debug: {...}`): each becomes a camera-sized
    /// texture `debug_<name>` (`render --dump` writes them, `verify` compares them).
    #[arg(long)]
    pub debug: bool,
}

impl Variants {
    /// The compile options these variants ask for (everything else at its default).
    pub fn options(&self) -> sshc::CompileOptions {
        sshc::CompileOptions {
            set: self.set.clone(),
            precision: self.precision.clone(),
            schedule: self.schedule.clone(),
            debug: self.debug,
            ..Default::default()
        }
    }
}

/// What `render` and `compare` let the command line change: params, precisions, the
/// shadow-map resolution and the camera size.
#[derive(clap::Args)]
pub struct Overrides {
    /// Params, precisions and schedules (`--set` of a compiled graph sets its uniforms;
    /// `--precision` and `--schedule` need a technique).
    #[command(flatten)]
    pub variants: Variants,
    /// Compile the technique for any scene instead of specialising it for this one (by
    /// default a technique is specialised for the scene's light where its `light:` list
    /// admits it: the light inputs that are 0 for it fold).
    #[arg(long)]
    pub generic: bool,
    /// Override what the light's view is fitted to: scene (every object), casters (the
    /// casting objects and their penumbra) or view (what the camera sees and the casters
    /// over it).
    #[arg(long, value_parser = shadow_fit)]
    pub fit: Option<sshc_scene::ShadowFit>,
    /// Override the scene's shadow-map resolution.
    #[arg(long)]
    pub shadow_map: Option<u32>,
    /// Override the scene's camera size, WIDTHxHEIGHT.
    #[arg(long, value_parser = size)]
    pub size: Option<(u32, u32)>,
    /// Keep only the scene's first K lights (to measure time and memory against the number
    /// of lights).
    #[arg(long, value_name = "K")]
    pub lights: Option<usize>,
    /// Replace the scene's camera: a RON value as a scene file writes it, such as
    /// 'Perspective(position: (0, 2, 5), target: (0, 0, 0), fov_y_degrees: 40, width: 512,
    /// height: 512)' (`--size` still sets its size; `sshc view`'s "copy as command" writes it).
    #[arg(long, value_name = "RON", value_parser = ron_value::<crate::scene::Camera>)]
    pub camera: Option<crate::scene::Camera>,
    /// Replace the scene's lights in order, the K-th `--light` light K (a RON value as a
    /// scene file writes it, such as 'Sphere(center: (0, 4, 0), radius: 0.2)'). Repeatable.
    #[arg(long = "light", value_name = "RON", value_parser = ron_value::<crate::scene::Light>)]
    pub light: Vec<crate::scene::Light>,
    #[command(flatten)]
    pub cascading: crate::bind::Cascading,
}

/// Parses a RON value of the scene file's syntax (`--camera`, `--light`), with its
/// implicit `Some` (`near: 0.01`, as a scene file writes it, was refused; issue 48, item 16).
fn ron_value<T: serde::de::DeserializeOwned>(s: &str) -> Result<T, String> {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(s)
        .map_err(|e| format!("{}:{}: {}", e.span.start.line, e.span.start.col, e.code))
}

impl Overrides {
    /// The scene at `path` with the size and shadow-map overrides, and `input` loaded (a
    /// technique compiled with the overrides, or a graph with params set).
    pub fn load(&self, gpu: &Gpu, input: &Path, scene: &Path) -> Result<(Scene, Loaded), String> {
        let path = scene;
        let mut scene = load_scene(path, self.size, self.shadow_map)?;
        if let Some(c) = &self.camera {
            scene
                .set_camera(c.clone())
                .map_err(|e| format!("error: --camera: {}", e.describe()))?;
            if let Some((w, h)) = self.size {
                scene.set_camera_size(w, h);
            }
        }
        for (i, l) in self.light.iter().enumerate() {
            scene
                .set_light(i, l.clone())
                .map_err(|e| format!("error: --light (light {i}): {}", e.describe()))?;
        }
        if self.camera.is_some() || !self.light.is_empty() {
            scene.check_precision().map_err(|e| format!("error: {e}"))?;
        }
        // the scene file's lights were checked at load; a replaced one is checked here
        // (`--light` inside the geometry was not warned about; issue 48, item 16)
        if !self.light.is_empty() {
            for w in light_warnings(&scene) {
                eprintln!("warning: --light: {w}");
            }
        }
        if let Some(k) = self.lights {
            let n = scene.lights.len();
            if k == 0 || k > n {
                // the lights counted are the file's as `--light` left them
                let whose = if self.light.is_empty() {
                    path.display().to_string()
                } else {
                    format!("{} with its {} `--light`(s)", path.display(), self.light.len())
                };
                return Err(format!("error: `--lights {k}`: {whose} has {n} light(s); keep between 1 and {n}"));
            }
            scene.lights.truncate(k);
        }
        if let Some(fit) = self.fit {
            scene.set_shadow_fit(fit).map_err(|e| e.to_string())?;
            scene.check_precision().map_err(|e| e.to_string())?;
        }
        let mut stages = Stages::default();
        let mut opts = self.variants.options();
        crate::bind::check_cascades(&scene, &self.cascading)?;
        // a graph specialised for the scene's light view would refuse the cascades' views
        specialise(&mut opts, input, path, &scene, self.generic || self.cascading.on(&scene))?;
        let ex = load_technique(gpu, input, &opts)?;
        stages.done("compile");
        // a tuned technique names its shadow-map size: it outranks the scene file's, and
        // `--shadow-map` outranks it
        if let (None, Some(n)) = (self.shadow_map, ex.graph().shadow_map)
            && n != scene.shadow_map
        {
            eprintln!(
                "note: shadow map {n} x {n} texels, as the technique's `shadow_map:` names (the scene's is {}; `--shadow-map` overrides both)",
                scene.shadow_map
            );
            scene.shadow_map = n;
            scene.check_precision().map_err(|e| e.to_string())?;
        }
        Ok((scene, ex))
    }
}

/// Options of the ground truth, shared by `truth` and `compare`.
#[derive(clap::Args, Clone)]
pub struct TruthOpts {
    /// Light samples per pixel in each run (rounded up to a square n x n stratified grid).
    #[arg(long, default_value_t = 256)]
    pub samples: u32,
    /// Independent runs per pixel (at least 2): the truth is their mean, their spread the
    /// measured standard error.
    #[arg(long, default_value_t = 4)]
    pub runs: u32,
    /// Double the samples per run until the largest per-pixel standard error (0..1 units) is
    /// at most this, or `--max-samples` is reached.
    #[arg(long = "target-se", value_name = "SE")]
    pub target_se: Option<f32>,
    /// The cap on samples per run with `--target-se`.
    #[arg(long, default_value_t = 4096)]
    pub max_samples: u32,
    /// Seed of the first run.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Cache folder of ground truths.
    #[arg(long, default_value = TruthCache::DEFAULT_DIR)]
    pub cache: PathBuf,
    /// Neither read nor write the cache.
    #[arg(long)]
    pub no_cache: bool,
    /// Seconds a claim on a truth may stand still (its owner beats four times in this
    /// time) before another process takes it over: the cache folder may be shared by the
    /// tasks of a cluster, of which one computes each truth while the others wait.
    #[arg(long, value_name = "SECONDS", default_value_t = 120.0, value_parser = claim_seconds)]
    pub claim_stale: f64,
}

/// `--claim-stale`: a finite number of seconds, at least 0.1.
fn claim_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && (0.1..=1e7).contains(&x) => Ok(x),
        _ => Err(format!("`{s}`: need a number of seconds from 0.1 to 10000000")),
    }
}

/// The most light samples one truth may take: samples per run (as the stratified grid
/// rounds them, or `--max-samples` with `--target-se`) x runs x pixels.
pub const MAX_TRUTH_SAMPLES: u64 = 1 << 36;

/// The most pixels a camera may have (4096 x 4096): read-backs hold several float images
/// of this size.
pub const MAX_CAMERA_PIXELS: u64 = 4096 * 4096;

impl TruthOpts {
    /// Refuses a truth over [`MAX_TRUTH_SAMPLES`] for `pixels` pixels, naming the arguments
    /// and their product; and a `--cache` that is not a folder.
    pub fn check(&self, pixels: u64) -> Result<(), String> {
        // The n x n grid `truth::strata` rounds to, in u64 (n * n overflows u32 near u32::MAX).
        let per_pixel = |n: u32| {
            let s = u64::from(n.max(1));
            let mut a = (s as f64).sqrt().floor() as u64;
            while a * a < s {
                a += 1;
            }
            a * a
        };
        let (flag, n) = match self.target_se {
            Some(_) => ("--max-samples", self.max_samples.max(self.samples)),
            None => ("--samples", self.samples),
        };
        let total = u128::from(per_pixel(n)) * u128::from(self.runs) * u128::from(pixels);
        if total > u128::from(MAX_TRUTH_SAMPLES) {
            return Err(format!(
                "error: `{flag} {n}` x `--runs {}` x {pixels} pixels = {total} light samples, above the budget of 2^36 ({MAX_TRUTH_SAMPLES}); lower the samples, the runs or the camera size",
                self.runs
            ));
        }
        if !self.no_cache && self.cache.exists() && !self.cache.is_dir() {
            return Err(format!(
                "error: `--cache {}` is a file, not a folder: name a folder for the truth cache (it is created if missing), or pass --no-cache",
                self.cache.display()
            ));
        }
        Ok(())
    }

    pub fn settings(&self) -> TruthSettings {
        TruthSettings {
            samples: self.samples,
            runs: self.runs,
            target_std_error: self.target_se,
            max_samples: self.max_samples,
            seed: self.seed,
        }
    }
}

pub fn size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once('x').ok_or_else(|| format!("expected WIDTHxHEIGHT, found `{s}`"))?;
    let (w, h): (u32, u32) = (
        w.trim().parse().map_err(|e| format!("width `{w}`: {e}"))?,
        h.trim().parse().map_err(|e| format!("height `{h}`: {e}"))?,
    );
    if w == 0 || h == 0 {
        return Err(format!("`{s}`: the image needs at least one pixel"));
    }
    let pixels = u64::from(w) * u64::from(h);
    if pixels > MAX_CAMERA_PIXELS {
        return Err(format!(
            "`{s}` is {pixels} pixels, above the limit of {MAX_CAMERA_PIXELS} (4096x4096): the read-backs would not fit in memory"
        ));
    }
    Ok((w, h))
}

pub fn rt(e: RuntimeError) -> String {
    format!("error: {e}")
}

/// Warnings about lights inside or on the scene's geometry
/// ([`crate::visibility::Visibility::light_warnings`]; builds the scene's BVH).
pub fn light_warnings(scene: &Scene) -> Vec<String> {
    crate::visibility::Visibility::new(scene).light_warnings(scene)
}

/// The stages of a long command, each printed to stderr as it ends with its wall time and
/// the process's resident memory then (Linux's `VmRSS`; `-` elsewhere): `stage NAME: S s,
/// resident M MB`. docs/scale.md reads them (scripts/scale.sh).
pub struct Stages {
    last: std::time::Instant,
}

impl Default for Stages {
    fn default() -> Self {
        Stages {
            last: std::time::Instant::now(),
        }
    }
}

impl Stages {
    /// Ends the stage begun at the last call (or at creation).
    pub fn done(&mut self, what: &str) {
        let secs = self.last.elapsed().as_secs_f64();
        let rss = resident_mb().map_or("-".to_string(), |m| format!("{m:.0}"));
        eprintln!("stage {what}: {secs:.3} s, resident {rss} MB");
        self.last = std::time::Instant::now();
    }
}

/// The process's resident memory in MB (`VmRSS` of /proc/self/status), where the system
/// has it.
pub fn resident_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb: f64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb / 1024.0)
}

/// Loads a scene and applies the size and shadow-map overrides, then checks its precision
/// budget again (the shadow map's resolution is part of it), and prints a warning for each
/// light inside or on its geometry (once per file).
pub fn load_scene(path: &Path, size: Option<(u32, u32)>, shadow_map: Option<u32>) -> Result<Scene, String> {
    let mut stages = Stages::default();
    let mut scene = Scene::load(path).map_err(|e| e.to_string())?;
    stages.done(&format!("scene read ({} triangles)", scene.triangles().len()));
    if let Some(n) = shadow_map {
        if n == 0 {
            return Err("error: `--shadow-map 0`: the shadow map needs at least one texel".into());
        }
        scene.shadow_map = n;
    }
    if let Some((w, h)) = size {
        scene.set_camera_size(w, h);
    }
    // The precision budget depends on the shadow map's resolution: checked again.
    scene.check_precision().map_err(|e| e.to_string())?;
    // Lights inside or on the geometry: warned once per scene file and process.
    static WARNED: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());
    let mut warned = WARNED.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    if !warned.iter().any(|p| p == path) {
        warned.push(path.to_path_buf());
        for note in scene.notes() {
            eprintln!("note: {note}");
        }
        let warnings = light_warnings(&scene);
        stages.done("light check (a BVH of the scene)");
        for w in warnings {
            eprintln!("warning: {}: {w}", path.display());
        }
    }
    Ok(scene)
}

/// A technique (`.ron`, compiled with the overrides) or a compiled graph (`.graph.ron`,
/// params set as uniforms) loaded, as `sshc render` does.
/// `opts` holds the command line's `--set`, `--precision` and `--schedule`; a graph takes
/// `--set` only.
pub fn load_technique(gpu: &Gpu, input: &Path, opts: &sshc::CompileOptions) -> Result<Loaded, String> {
    if input.to_string_lossy().ends_with(".graph.ron") {
        if !opts.precision.is_empty() {
            return Err("error: `--precision` needs a technique, not a compiled graph".into());
        }
        if !opts.schedule.is_empty() {
            return Err("error: `--schedule` needs a technique, not a compiled graph".into());
        }
        let mut ex = Loaded::load(gpu, input).map_err(rt)?;
        for (k, v) in &opts.set {
            let v: f64 = v.parse().map_err(|_| format!("error: `--set {k}={v}`: expected a number"))?;
            ex.set_param(k, v).map_err(rt)?;
        }
        return Ok(ex);
    }
    let source = read(input)?;
    compile_technique(gpu, input, &source, opts)
}

pub fn compile_technique(gpu: &Gpu, path: &Path, source: &str, opts: &sshc::CompileOptions) -> Result<Loaded, String> {
    let c = sshc::compile_str(source, opts).map_err(|d| {
        report(&d, path, source);
        String::new()
    })?;
    Loaded::new(gpu, c.graph, c.shaders).map_err(rt)
}

/// `scene` with its light `i` alone (each light of a scene has its own light
/// views, passes and truth).
pub fn single_light(scene: &Scene, i: usize) -> Scene {
    let mut s = scene.clone();
    s.lights = vec![scene.lights[i].clone()];
    s
}

/// The facts a technique is specialised for on `scene` (read from `path`): its first
/// light's kind (the light the techniques render) and the least depth of its casters in
/// any light's view (`sshc_graph::caster_depth_floor`, on the inputs the runtime binds, so
/// that its check computes the same). None for a scene without a light.
pub fn scene_facts(path: &Path, scene: &Scene) -> Option<sshc::SceneFacts> {
    let first = scene.lights.first()?;
    let floors: Vec<Option<f32>> = (0..scene.lights.len())
        .map(|i| {
            let s = crate::bind::scene_inputs(&single_light(scene, i)).ok()?;
            sshc_runtime::graph::caster_depth_floor(&s.vertices, s.casting_vertices, &s.light_view, s.near, s.far)
        })
        .collect();
    // every light must have a floor for the facts to hold one
    let depth_floor = floors
        .iter()
        .copied()
        .collect::<Option<Vec<f32>>>()
        .and_then(|f| f.into_iter().reduce(f32::min));
    Some(sshc::SceneFacts {
        scene: path.display().to_string(),
        light: first.kind(),
        depth_floor,
    })
}

/// Compile options specialised for `scene` where the technique at `input` admits its light
///, else generic with a warning on stderr naming both files; generic for a
/// compiled graph (which carries its own facts, checked when bound) or with `generic`.
pub fn specialise(opts: &mut sshc::CompileOptions, input: &Path, scene_path: &Path, scene: &Scene, generic: bool) -> Result<(), String> {
    if generic || input.to_string_lossy().ends_with(".graph.ron") {
        return Ok(());
    }
    let Some(facts) = scene_facts(scene_path, scene) else {
        return Ok(());
    };
    // one graph serves every light: specialised only where they are all of one kind
    if scene.lights.iter().any(|l| l.kind() != facts.light) {
        eprintln!(
            "note: {} has lights of several kinds: {} compiled for any scene, not specialised",
            scene_path.display(),
            input.display()
        );
        return Ok(());
    }
    if sshc::admits(&read(input)?, facts.light) {
        opts.scene = Some(facts);
    } else {
        eprintln!(
            "warning: {} does not admit the {} light of {} (its `light:` list): compiled for any scene, not specialised (`sshc compile --scene` refuses it)",
            input.display(),
            facts.light.name(),
            scene_path.display()
        );
    }
    Ok(())
}

/// The camera pass's world positions and normals (NaN where no surface is seen).
pub fn positions_normals(ex: &Bound) -> Result<(Vec<Vec3>, Vec<Vec3>), String> {
    let xyz = |img: sshc_runtime::gpu::Image| img.rgba.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect::<Vec<_>>();
    let p = xyz(ex.inspect().read_camera(CameraOutput::Position).map_err(rt)?);
    let n = xyz(ex.inspect().read_camera(CameraOutput::Normal).map_err(rt)?);
    Ok((p, n))
}

/// The truth at `positions`, through the cache unless `--no-cache`, with a progress bar
/// on a terminal. Prints where it came from.
pub fn truth_at(scene: &Scene, positions: &[Vec3], normals: &[Vec3], opts: &TruthOpts) -> Result<(Truth, Source), String> {
    let (w, h) = scene.camera_size();
    opts.check(u64::from(w) * u64::from(h))?;
    let cache =
        (!opts.no_cache).then(|| TruthCache::new(&opts.cache).with_stale_after(std::time::Duration::from_secs_f64(opts.claim_stale)));
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template("truth {msg} [{bar:40}] {percent}% {elapsed_precise} (eta {eta})")
            .map_err(|e| format!("error: {e}"))?
            .progress_chars("=> "),
    );
    // Not on a terminal (a cluster job's log), a plain line at each tenth of a truth that
    // has taken over 10 s so far.
    let plain = !std::io::stderr().is_terminal();
    let start = std::time::Instant::now();
    let tenth_shown = std::sync::atomic::AtomicU64::new(0);
    let progress = |p: truth::Progress| {
        if bar.length() != Some(p.total) {
            bar.set_length(p.total);
            bar.set_message(format!("{} samples x {} runs", p.samples, opts.runs));
        }
        bar.set_position(p.done);
        if plain && p.total > 0 && start.elapsed().as_secs() >= 10 {
            let tenth = p.done * 10 / p.total;
            let mark = (u64::from(p.samples) << 8) | tenth;
            if tenth_shown.swap(mark, std::sync::atomic::Ordering::Relaxed) != mark {
                eprintln!(
                    "truth: {} samples x {} runs: {}% after {:.0} s",
                    p.samples,
                    opts.runs,
                    tenth * 10,
                    start.elapsed().as_secs_f64()
                );
            }
        }
    };
    let points = truth::Points {
        width: w,
        height: h,
        positions,
        normals,
    };
    let note = |m: &str| bar.suspend(|| eprintln!("{m}"));
    let result = truth::compute_cached(scene, &points, &opts.settings(), cache.as_ref(), &progress, &note);
    bar.finish_and_clear();
    result.map_err(|e| format!("error: {e}"))
}

/// The lines `sshc truth` and `sshc compare` print about a truth.
pub fn describe(t: &Truth, source: &Source) -> Vec<String> {
    let mut out = Vec::new();
    match source {
        Source::Cached(p) => out.push(format!("truth: read from the cache {}", p.display())),
        Source::Computed(Some(p)) => out.push(format!("truth: computed, cached in {}", p.display())),
        Source::Computed(None) => out.push("truth: computed (not cached)".into()),
    }
    out.push(format!(
        "truth: {} x {} pixels, {} with a surface; {} light samples per pixel per run x {} runs",
        t.width, t.height, t.surface_pixels, t.samples, t.runs
    ));
    if t.levels.len() > 1 {
        let steps: Vec<String> = t
            .levels
            .iter()
            .map(|l| format!("{} (max se {:.5})", l.samples, l.max_std_error))
            .collect();
        out.push(format!("truth: samples per run doubled: {}", steps.join(" -> ")));
    }
    out.push(format!(
        "truth: standard error (0..1 units, from {} independent runs): max {:.5}, mean {:.6}, rms {:.6} (max {:.3} in 0..255 units)",
        t.runs,
        t.max_std_error(),
        t.mean_std_error(),
        t.rms_std_error(),
        255.0 * t.max_std_error()
    ));
    out.push(format!(
        "truth: {:.2} s on {} threads: {:.3} M light samples/s, at least {:.3} M rays/s ({:.3e} samples, at least {:.3e} rays)",
        t.seconds,
        t.threads,
        t.samples_per_second() / 1e6,
        t.rays_per_second_at_least() / 1e6,
        t.samples_evaluated as f64,
        t.rays_at_least as f64
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 48, item 8: every file a command reads goes through one capped, regular-file
    /// only reader (`sshc_scene::read_capped`). A FIFO is refused without being opened (it
    /// would hang the reader), a device such as /dev/zero too (it would fill the memory),
    /// and a file over the cap before it is read.
    #[test]
    fn the_one_reader_refuses_fifos_devices_and_files_over_the_cap() {
        let dir = std::env::temp_dir().join(format!("sshc-reader-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let fifo = dir.join("fifo.ron");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
        assert!(made.success());
        let start = std::time::Instant::now();
        let e = read(&fifo).unwrap_err();
        assert!(e.contains("not a regular file") && start.elapsed().as_secs() < 5, "{e}");
        let e = read(Path::new("/dev/zero")).unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
        let big = dir.join("big.ron");
        std::fs::write(&big, vec![b' '; 2048]).unwrap();
        let e = read_capped(&big, 1024).unwrap_err();
        assert!(e.contains("2048 bytes, above the limit of 1024"), "{e}");
        assert_eq!(read_capped(&big, 4096).unwrap().len(), 2048);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// No reader of files in the lab or the scene crate but the one: a `read_to_string`,
    /// `fs::read` or `File::open` outside it is a reader that a FIFO can hang. The two kept
    /// are named here with why.
    #[test]
    fn no_file_is_read_around_the_one_reader() {
        // (file, what it reads): not a user's file
        let allowed = [
            ("src/session.rs", "/proc/self/status"),        // the kernel's, for the memory in stage lines
            ("src/cmd/sweep/shard.rs", "File::open(&exe)"), // this executable, hashed as the shard's code
        ];
        let mut found = Vec::new();
        for (rel, text) in crate::files::tests::lab_sources() {
            // the code before the file's tests
            let code = text.split("#[cfg(test)]").next().unwrap_or_default();
            for (n, line) in code.lines().enumerate() {
                let reads = ["fs::read_to_string(", "fs::read(", "File::open("].iter().any(|r| line.contains(r));
                let kept = allowed.iter().any(|(file, what)| rel == *file && line.contains(what));
                if reads && !kept && !line.trim_start().starts_with("//") && rel != "scene/src/source.rs" {
                    found.push(format!("{rel}:{}: {}", n + 1, line.trim()));
                }
            }
        }
        assert!(found.is_empty(), "files read around sshc_scene::read_capped:\n{}", found.join("\n"));
    }
}
