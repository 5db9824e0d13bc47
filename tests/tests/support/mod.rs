//! Shared by the agreement tests: a device per test process, compilation of bundled
//! techniques, the query plane (a receiver whose shading points map to known light-space
//! coordinates), and synthetic depth fields fed to the passes after Depth.
#![allow(dead_code)]

pub mod variant;

use glam::{Mat4, Vec3};
use sshc_lab::scene;
use sshc_runtime::gpu::{CameraOutput, Executor, Gpu, SceneInputs};
use std::path::{Path, PathBuf};

/// One device per test process (nextest runs each test in its own process).
pub fn gpu() -> &'static Gpu {
    static GPU: std::sync::OnceLock<Gpu> = std::sync::OnceLock::new();
    GPU.get_or_init(|| Gpu::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}")))
}

pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
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

/// The query plane: an orthographic light looking straight down at a receiver tilted
/// along x, seen by an orthographic camera with the light's own view, so that camera pixel
/// (i, j) shades light uv ((i + 0.5) / camera, (j + 0.5) / camera) and the receiver's
/// normalised depth runs linearly from about 0 to 1 across x. A camera of 2N pixels over an
/// N-texel map samples every texel at sub-texel offsets 1/4 and 3/4 and filters at level
/// of detail -1 (the base level); a camera of N / 2^k filters at level k.
pub struct QueryPlane {
    pub shadow: u32,
    pub camera: u32,
}

/// Light eye height and the fitted depth range of the query plane.
const EYE: f32 = 10.0;
const NEAR: f32 = 8.0;
const FAR: f32 = 12.0;

impl QueryPlane {
    pub fn light_view(&self) -> Mat4 {
        scene::look_at(Vec3::new(0.0, EYE, 0.0), Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0))
    }

    pub fn light_proj(&self) -> Mat4 {
        scene::orthographic(-1.0, 1.0, -1.0, 1.0, NEAR, FAR)
    }

    /// Height of the receiver at x: view distance 10 - y runs from 8 to 12 over x in [-1, 1].
    fn height(x: f32) -> f32 {
        2.0 * x
    }

    pub fn inputs(&self) -> SceneInputs {
        // a quad a little larger than the light's square, so every pixel sees it
        let (a, b) = (-1.05f32, 1.05f32);
        let corner = |x: f32, z: f32| Vec3::new(x, Self::height(x), z);
        let n = Vec3::new(-2.0, 1.0, 0.0).normalize();
        let quad = [corner(a, a), corner(b, a), corner(b, b), corner(a, a), corner(b, b), corner(a, b)];
        let vertices = quad.iter().flat_map(|p| [p.x, p.y, p.z, n.x, n.y, n.z]).collect();
        let view = self.light_view();
        let proj = self.light_proj();
        let camera_proj = scene::orthographic(-1.0, 1.0, -1.0, 1.0, 0.1, 40.0);
        SceneInputs {
            vertices,
            meshes: vec![],
            casting_vertices: None,
            camera_view_proj: (camera_proj * view).to_cols_array(),
            camera_position: [0.0, EYE, 0.0],
            camera_size: (self.camera, self.camera),
            shadow_size: self.shadow,
            light_view: view.to_cols_array(),
            light_view_proj: (proj * view).to_cols_array(),
            light_position: [0.0, 1.0, 0.0, 0.0],
            near: NEAR,
            far: FAR,
            light_size: 0.0,
            light_half_extents: [0.0, 0.0],
            light_angle: 0.0,
            light_proj_y: proj.y_axis.y,
            light_orthographic: true,
            samples: Vec::new(),
            samples_closed: false,
            light: None,
        }
    }

    /// [`QueryPlane::inputs`] under a square light `width` world units wide, centred on the
    /// light's eye (the reference's `LightFrame::query_plane(width)`).
    pub fn lit_inputs(&self, width: f32) -> SceneInputs {
        SceneInputs {
            light_size: 0.5 * width,
            light_half_extents: [0.5 * width, 0.5 * width],
            ..self.inputs()
        }
    }

    /// Light uv and normalised depth of a world position, in f64.
    pub fn project(&self, p: [f32; 3]) -> ([f64; 2], f64) {
        let vp = (self.light_proj() * self.light_view()).as_dmat4();
        let v = self.light_view().as_dmat4();
        let w = glam::DVec4::new(p[0] as f64, p[1] as f64, p[2] as f64, 1.0);
        let clip = vp * w;
        let uv = [clip.x / clip.w * 0.5 + 0.5, -clip.y / clip.w * 0.5 + 0.5];
        let dist = -(v * w).z;
        (uv, (dist - NEAR as f64) / (FAR as f64 - NEAR as f64))
    }

    /// The level of detail of implicit `sample` lookups: texels per camera pixel, log2.
    pub fn lod(&self) -> f32 {
        (self.shadow as f32 / self.camera as f32).log2()
    }
}

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
    let mut ex = Executor::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
    for (k, v) in params {
        ex.set_param(k, *v).unwrap_or_else(|e| panic!("{e}"));
    }
    ex.bind_scene(inputs).unwrap_or_else(|e| panic!("{e}"));
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
    let visibility = ex.read_camera(CameraOutput::Visibility).unwrap().channel(0);
    let positions = ex
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

/// Deterministic noise in [0, 1) (a 64-bit LCG hashed per texel).
pub fn noise(i: u64) -> f32 {
    let mut x = i.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51afd7ed558ccd);
    x ^= x >> 33;
    (x >> 40) as f32 / (1u64 << 24) as f32
}

/// Synthetic depth fields of `n` x `n` texels, linear depth in [0, 1], by name.
pub fn depth_field(name: &str, n: u32) -> Vec<f32> {
    let n = n as usize;
    (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            match name {
                // occluders rising across the map, crossing the receiver's depth ramp
                "ramp" => 0.1 + 0.8 * v,
                // a straight occluder edge half way
                "step" => {
                    if u < 0.5 {
                        0.3
                    } else {
                        1.0
                    }
                }
                "checker" => {
                    if ((i / 4) + (j / 4)) % 2 == 0 {
                        0.2
                    } else {
                        0.8
                    }
                }
                "noise" => noise(k as u64),
                "zero" => 0.0,
                "one" => 1.0,
                _ => panic!("no depth field `{name}`"),
            }
        })
        .collect()
}

pub const FIELDS: [&str; 6] = ["ramp", "step", "checker", "noise", "zero", "one"];

/// The depth map a bundled scene renders from its light (with the hard technique).
pub fn scene_depth(scene: &str, n: u32) -> Vec<f32> {
    let c = compile_source("hard", &technique_source("hard"), &[], &[]);
    let mut s = sshc_lab::scene::Scene::load(root().join("scenes").join(format!("{scene}.ron"))).unwrap_or_else(|e| panic!("{e}"));
    s.shadow_map = n;
    s.set_camera_size(8, 8);
    let mut ex = Executor::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
    ex.bind_scene(&sshc_lab::bind::scene_inputs(&s).unwrap())
        .unwrap_or_else(|e| panic!("{e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    let depth = c
        .graph
        .passes
        .iter()
        .find(|p| p.kind == sshc_runtime::graph::PassKind::Depth)
        .unwrap();
    ex.read_texture(&depth.steps[0].writes[0].texture, 0, 0).unwrap().channel(0)
}
