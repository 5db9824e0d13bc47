//! Shared by the agreement tests: a device per test process, compilation of bundled
//! techniques, the query plane (a receiver whose shading points map to known light-space
//! coordinates), and synthetic depth fields fed to the passes after Depth.
#![allow(dead_code)]

pub mod host;
pub mod variant;

use sshc_lab::run::Loaded;
use sshc_runtime::gpu::{CameraOutput, Gpu, SceneInputs};
use std::path::{Path, PathBuf};

/// One device per test process (nextest runs each test in its own process).
pub fn gpu() -> &'static Gpu {
    static GPU: std::sync::OnceLock<Gpu> = std::sync::OnceLock::new();
    GPU.get_or_init(|| Gpu::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}")))
}

pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The `.ron` files of a folder of the repository, by name, sorted: every bundled
/// technique (or scene) is tested without being listed.
pub fn bundled(folder: &str) -> Vec<String> {
    let dir = root().join(folder);
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort();
    names
}

pub fn technique_source(name: &str) -> String {
    std::fs::read_to_string(root().join("techniques").join(format!("{name}.ron"))).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Compile technique source with `--set` and `--precision` overrides; panics with the
/// rendered diagnostics.
pub fn compile_source(name: &str, src: &str, set: &[(&str, String)], precision: &[(&str, &str)]) -> sshc::Compiled {
    let opts = sshc::CompileOptions {
        set: set.iter().map(|(a, b)| (a.to_string(), b.clone())).collect(),
        precision: precision.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect(),
        ..Default::default()
    };
    sshc::compile_str(src, &opts).unwrap_or_else(|d| panic!("{}", d.render(name, src)))
}

/// The query plane and the synthetic depth fields are `sshc verify`'s (the lab's
/// `verify` module), so that the agreement tests and the command read the same inputs.
#[allow(unused_imports)]
pub use sshc_lab::verify::{FIELDS, QueryPlane};

/// One run of compiled shaders over the query plane with a given depth field.
pub struct PlaneRun {
    pub visibility: Vec<f32>,
    /// World positions of the shaded points (NaN where none).
    pub positions: Vec<[f32; 3]>,
    /// Median GPU milliseconds of the passes after Depth over the frames run.
    pub ms_after_depth: Option<f64>,
}

/// Run `c` over the query plane with `depth` as the Depth pass's output, `frames` times
/// (the first builds pipelines and is not timed when more than one frame runs).
pub fn run_plane(c: &sshc::Compiled, plane: &QueryPlane, depth: &[f32], params: &[(&str, f64)], frames: usize) -> PlaneRun {
    run_inputs(c, &plane.inputs(), depth, params, frames)
}

/// [`run_plane`] with any scene inputs (the query plane under an area light, say).
pub fn run_inputs(c: &sshc::Compiled, inputs: &SceneInputs, depth: &[f32], params: &[(&str, f64)], frames: usize) -> PlaneRun {
    let mut ex = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
    for (k, v) in params {
        ex.set_param(k, *v).unwrap_or_else(|e| panic!("{e}"));
    }
    let mut ex = ex.bind_scene(inputs).unwrap_or_else(|e| panic!("{e}"));
    ex.set_depth_override(Some(depth.to_vec()));
    let mut times = Vec::new();
    for f in 0..frames.max(1) {
        let t = ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
        if f > 0 || frames == 1 {
            let after: Option<f64> = t
                .passes
                .iter()
                .filter(|(n, _)| {
                    c.graph
                        .passes
                        .iter()
                        .any(|p| &p.name == n && p.kind != sshc_runtime::graph::PassKind::Depth)
                })
                .map(|(_, ms)| *ms)
                .sum();
            if let Some(ms) = after {
                times.push(ms);
            }
        }
    }
    times.sort_by(f64::total_cmp);
    let visibility = ex.inspect().read_camera(CameraOutput::Visibility).unwrap().channel(0);
    let positions = ex
        .inspect()
        .read_camera(CameraOutput::Position)
        .unwrap()
        .rgba
        .iter()
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    PlaneRun {
        visibility,
        positions,
        ms_after_depth: times.get(times.len() / 2).copied(),
    }
}

/// Synthetic depth fields of `n` x `n` texels, linear depth in [0, 1], by name.
pub fn depth_field(name: &str, n: u32) -> Vec<f32> {
    sshc_lab::verify::depth_field(name, n).unwrap_or_else(|| panic!("no depth field `{name}`"))
}

/// The depth map a bundled scene renders from its light (with the hard technique).
pub fn scene_depth(scene: &str, n: u32) -> Vec<f32> {
    sshc_lab::verify::scene_depth(gpu(), &root().join("scenes").join(format!("{scene}.ron")), n).unwrap_or_else(|e| panic!("{scene}: {e}"))
}
