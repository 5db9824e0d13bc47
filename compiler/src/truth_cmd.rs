//! `sshc truth`: render a scene's world positions and normals on the GPU (with the bundled
//! hard shadow-map technique; every technique's camera pass writes the same positions),
//! then compute the ground-truth visibility at exactly those points on the CPU
//! (`sshc_runtime::truth`), through the on-disk cache.
//!
//! Also the pieces `sshc compare` shares: loading a technique into an executor, the
//! truth options and the cached, progress-reporting truth computation.

use crate::{read, report};
use glam::Vec3;
use sshc_runtime::gpu::{CameraOutput, Executor, Gpu, RuntimeError};
use sshc_runtime::scene::Scene;
use sshc_runtime::truth::{self, Source, Truth, TruthCache, TruthSettings};
use std::path::{Path, PathBuf};

/// The technique `sshc truth` renders positions with.
const HARD: &str = include_str!("../../techniques/hard.ron");

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
}

impl TruthOpts {
    fn settings(&self) -> TruthSettings {
        TruthSettings {
            samples: self.samples,
            runs: self.runs,
            target_std_error: self.target_se,
            max_samples: self.max_samples,
            seed: self.seed,
        }
    }
}

#[derive(clap::Args)]
pub struct TruthArgs {
    /// The scene (RON).
    #[arg(long)]
    scene: PathBuf,
    /// The ground truth: one-channel float PFM at camera resolution; a PNG of it is written
    /// beside it (same name, `.png`).
    #[arg(short, long, default_value = "truth.pfm")]
    out: PathBuf,
    /// Also write the per-pixel standard error as a one-channel PFM.
    #[arg(long = "std-error", value_name = "PFM")]
    std_error: Option<PathBuf>,
    /// Override the scene's camera size, WIDTHxHEIGHT.
    #[arg(long, value_parser = size)]
    size: Option<(u32, u32)>,
    #[command(flatten)]
    truth: TruthOpts,
}

pub(crate) fn size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once('x').ok_or_else(|| format!("expected WIDTHxHEIGHT, found `{s}`"))?;
    let (w, h): (u32, u32) = (
        w.trim().parse().map_err(|e| format!("width `{w}`: {e}"))?,
        h.trim().parse().map_err(|e| format!("height `{h}`: {e}"))?,
    );
    if w == 0 || h == 0 {
        return Err(format!("`{s}`: the image needs at least one pixel"));
    }
    Ok((w, h))
}

pub(crate) fn rt(e: RuntimeError) -> String {
    format!("error: {e}")
}

/// Loads a scene and applies the size and shadow-map overrides.
pub(crate) fn load_scene(path: &Path, size: Option<(u32, u32)>, shadow_map: Option<u32>) -> Result<Scene, String> {
    let mut scene = Scene::load(path).map_err(|e| e.to_string())?;
    if let Some(n) = shadow_map {
        if n == 0 {
            return Err("error: `--shadow-map 0`: the shadow map needs at least one texel".into());
        }
        scene.shadow_map = n;
    }
    if let Some((w, h)) = size {
        scene.set_camera_size(w, h);
    }
    Ok(scene)
}

/// An executor for a technique (`.ron`, compiled with the overrides) or a compiled graph
/// (`.graph.ron`, params set as uniforms), as `sshc render` does.
pub(crate) fn executor<'g>(
    gpu: &'g Gpu,
    input: &Path,
    set: &[(String, String)],
    precision: &[(String, String)],
) -> Result<Executor<'g>, String> {
    if input.to_string_lossy().ends_with(".graph.ron") {
        if !precision.is_empty() {
            return Err("error: `--precision` needs a technique, not a compiled graph".into());
        }
        let mut ex = Executor::load(gpu, input).map_err(rt)?;
        for (k, v) in set {
            let v: f64 = v.parse().map_err(|_| format!("error: `--set {k}={v}`: expected a number"))?;
            ex.set_param(k, v).map_err(rt)?;
        }
        return Ok(ex);
    }
    let source = read(input)?;
    compile_executor(gpu, input, &source, set, precision)
}

fn compile_executor<'g>(
    gpu: &'g Gpu,
    path: &Path,
    source: &str,
    set: &[(String, String)],
    precision: &[(String, String)],
) -> Result<Executor<'g>, String> {
    let opts = sshc::CompileOptions {
        set: set.to_vec(),
        precision: precision.to_vec(),
        ..Default::default()
    };
    let c = sshc::compile_str(source, &opts).map_err(|d| {
        report(&d, path, source);
        String::new()
    })?;
    Executor::new(gpu, c.graph, c.shaders).map_err(rt)
}

/// The camera pass's world positions and normals (NaN where no surface is seen).
pub(crate) fn positions_normals(ex: &Executor) -> Result<(Vec<Vec3>, Vec<Vec3>), String> {
    let xyz = |img: sshc_runtime::gpu::Image| img.rgba.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect::<Vec<_>>();
    let p = xyz(ex.read_camera(CameraOutput::Position).map_err(rt)?);
    let n = xyz(ex.read_camera(CameraOutput::Normal).map_err(rt)?);
    Ok((p, n))
}

/// The truth at `positions`, through the cache unless `--no-cache`, with a progress bar
/// on a terminal. Prints where it came from.
pub(crate) fn truth_at(scene: &Scene, positions: &[Vec3], normals: &[Vec3], opts: &TruthOpts) -> Result<(Truth, Source), String> {
    let (w, h) = scene.camera_size();
    let cache = (!opts.no_cache).then(|| TruthCache::new(&opts.cache));
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template("truth {msg} [{bar:40}] {percent}% {elapsed_precise} (eta {eta})")
            .map_err(|e| format!("error: {e}"))?
            .progress_chars("=> "),
    );
    let progress = |p: truth::Progress| {
        if bar.length() != Some(p.total) {
            bar.set_length(p.total);
            bar.set_message(format!("{} samples x {} runs", p.samples, opts.runs));
        }
        bar.set_position(p.done);
    };
    let points = truth::Points {
        width: w,
        height: h,
        positions,
        normals,
    };
    let warn = |m: &str| eprintln!("warning: {m}");
    let result = truth::compute_cached(scene, &points, &opts.settings(), cache.as_ref(), &progress, &warn);
    bar.finish_and_clear();
    result.map_err(|e| format!("error: {e}"))
}

/// The lines `sshc truth` and `sshc compare` print about a truth.
pub(crate) fn describe(t: &Truth, source: &Source) -> Vec<String> {
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

/// The PNG beside a PFM: same name, `.png`.
fn png_beside(path: &Path) -> PathBuf {
    path.with_extension("png")
}

pub fn truth(a: TruthArgs) -> Result<(), String> {
    if a.out.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        return Err(format!(
            "error: `-o {}`: the truth is written as PFM (its PNG goes beside it); name a `.pfm` file",
            a.out.display()
        ));
    }
    let scene = load_scene(&a.scene, a.size, None)?;
    if scene.lights.is_empty() {
        return Err(format!("error: {}: the scene has no light: add one to `lights`", a.scene.display()));
    }
    if a.truth.runs < 2 {
        return Err("error: `--runs` must be at least 2: the standard error is measured from independent runs".into());
    }
    let gpu = Gpu::new().map_err(rt)?;
    let mut ex = compile_executor(&gpu, Path::new("techniques/hard.ron"), HARD, &[], &[])?;
    let inputs = sshc_runtime::bind::scene_inputs(&scene).map_err(|e| format!("error: {e}"))?;
    ex.bind_scene(&inputs).map_err(rt)?;
    ex.run_frame().map_err(rt)?;
    let (positions, normals) = positions_normals(&ex)?;
    let (t, source) = truth_at(&scene, &positions, &normals, &a.truth)?;
    t.write_pfm(&a.out).map_err(|e| format!("error: {e}"))?;
    println!("wrote {}", a.out.display());
    let png = png_beside(&a.out);
    t.write_png(&png).map_err(|e| format!("error: {e}"))?;
    println!("wrote {}", png.display());
    if let Some(p) = &a.std_error {
        t.write_std_error_pfm(p).map_err(|e| format!("error: {e}"))?;
        println!("wrote {}", p.display());
    }
    for line in describe(&t, &source) {
        println!("{line}");
    }
    println!("positions: {}", gpu.describe());
    Ok(())
}
