//! `sshc verify` (issue 17): a compiled technique run on the GPU over the inputs of the
//! agreement tests and compared, receiver by receiver, with the compiler's f64 evaluation
//! of the same technique on the CPU (`sshc::interp`), within that evaluation's allowance.
//!
//! The inputs: synthetic depth fields ([`FIELDS`]: a ramp, a step, a checkerboard, noise,
//! all 0 and all 1) and the light's depth maps of bundled scenes, each fed to the passes
//! after Depth in place of the Depth pass's output (the runtime's depth override), read at
//! the shading points of the [`QueryPlane`] (a receiver whose depth runs across [0, 1]),
//! seen by two cameras: 2N pixels over the N-texel map (implicit level of detail -1) and
//! N/2 (level 1).
//!
//! Each (input, camera) gets a verdict ([`Verdict`]): **agrees** when every receiver's GPU
//! value lies within the allowance about the CPU value; **differs** when one does not (a
//! code generation bug, or a technique whose result the model does not bound); **lossy**
//! when the GPU agrees but storage rounding alone (the CPU evaluation with every texel
//! rounded as stored, against the exact one) moves the visibility by more than
//! [`sshc::rounding::WARN_ABOVE`] at 1 % of the receivers or more: a precision that loses the
//! signal. With a reference technique (`--reference`), its f64 CPU evaluation is compared
//! with the technique's under the same allowance: an independent reading of the math.

use crate::scene;
use glam::{Mat4, Vec3};
use rayon::prelude::*;
use sshc::interp::{Allowed, Evaluation, Frame, Model, Receiver, Rounding, Scratch};
use sshc::ir::Program;
use sshc_runtime::gpu::{CameraOutput, Executor, Gpu, SceneInputs};
use std::fmt::Write as _;
use std::path::Path;

/// The query plane: an orthographic light looking straight down at a receiver tilted
/// along x, seen by an orthographic camera with the light's own view, so that camera pixel
/// (i, j) shades light uv ((i + 0.5) / camera, (j + 0.5) / camera) and the receiver's
/// normalised depth runs linearly from 1 to 0 across u (`d = 1 - u`). A camera of 2N pixels
/// over an N-texel map samples every texel at sub-texel offsets 1/4 and 3/4 and filters at
/// level of detail -1 (the base level); a camera of N / 2^k filters at level k.
#[derive(Clone, Copy, Debug, PartialEq)]
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

    /// The receiver's normal, `normalize(-2, 1, 0)`.
    fn normal() -> Vec3 {
        Vec3::new(-2.0, 1.0, 0.0).normalize()
    }

    pub fn inputs(&self) -> SceneInputs {
        // a quad a little larger than the light's square, so every pixel sees it
        let (a, b) = (-1.05f32, 1.05f32);
        let corner = |x: f32, z: f32| Vec3::new(x, Self::height(x), z);
        let n = Self::normal();
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
    /// light's eye.
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

    /// The frame-wide inputs under a light `width` wide (`lit_inputs`; 0: `inputs`).
    pub fn frame(&self, width: f64) -> Frame {
        let n = self.shadow as f64;
        Frame {
            shadow_size: self.shadow,
            near: NEAR as f64,
            far: FAR as f64,
            light_size: 0.5 * width,
            light_width: [width, width],
            // a directional light of no angular size
            light_spread: 0.0,
            light_distant: true,
            // orthographic: 2 world units over the map (light_proj_y is 1)
            texel_world: [0.0, 2.0 / n],
            frame: 0,
        }
    }

    /// The receiver the GPU shaded at camera pixel `pixel` from world position `p`.
    pub fn receiver(&self, pixel: usize, p: [f32; 3]) -> Receiver {
        let (uv, d) = self.project(p);
        Receiver {
            uv,
            d_world: NEAR as f64 + d * (FAR - NEAR) as f64,
            ndotl: Self::normal().as_dvec3().dot(glam::DVec3::Y),
            // d = 1 - u: a unit gradient over uv, one texel's worth per texel
            depth_slope: (1.0 / self.shadow as f64).min(0.1),
            lod: self.lod().max(0.0) as f64,
            pixel: [(pixel % self.camera as usize) as f64, (pixel / self.camera as usize) as f64],
        }
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

/// The synthetic depth fields, by name.
pub const FIELDS: [&str; 6] = ["ramp", "step", "checker", "noise", "zero", "one"];

/// A synthetic depth field of `n` x `n` texels, linear depth in [0, 1], by name
/// ([`FIELDS`]); `None` for another name.
pub fn depth_field(name: &str, n: u32) -> Option<Vec<f32>> {
    let n = n as usize;
    let texel = |k: usize| -> Option<f32> {
        let (i, j) = (k % n, k / n);
        let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
        Some(match name {
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
            _ => return None,
        })
    };
    (0..n * n).map(texel).collect()
}

/// The depth map a scene renders from its (first) light, `n` x `n`, with the bundled hard
/// technique.
pub fn scene_depth(gpu: &Gpu, path: &Path, n: u32) -> Result<Vec<f32>, String> {
    let hard = include_str!("../../techniques/hard.ron");
    let c = sshc::compile_str(hard, &sshc::CompileOptions::default()).map_err(|d| d.render("techniques/hard.ron", hard))?;
    let mut s = crate::session::load_scene(path, Some((8, 8)), Some(n))?;
    if s.lights.len() > 1 {
        s.lights.truncate(1);
    }
    let mut ex = Executor::new(gpu, c.graph.clone(), c.shaders.clone()).map_err(crate::session::rt)?;
    ex.bind_scene(&crate::bind::scene_inputs(&s)?).map_err(crate::session::rt)?;
    ex.run_frame().map_err(crate::session::rt)?;
    let depth = c
        .graph
        .passes
        .iter()
        .find(|p| p.kind == sshc_runtime::graph::PassKind::Depth)
        .ok_or("the hard technique has no Depth pass")?;
    Ok(ex
        .read_texture(&depth.steps[0].writes[0].texture, 0, 0)
        .map_err(crate::session::rt)?
        .channel(0))
}

/// One depth map to verify on.
#[derive(Clone, Debug)]
pub struct Input {
    pub name: String,
    pub depth: Vec<f32>,
}

/// What `verify` runs.
#[derive(Clone, Debug)]
pub struct Options {
    /// The shadow map's size N (the cameras are 2N and N/2).
    pub shadow: u32,
    /// The width of the square light over the query plane (world units; the plane spans 2).
    pub light_width: f64,
    /// How far a reference may differ from the technique beyond what the conditioning of
    /// both f64 evaluations allows (constants written differently, guards such as `1e-12`).
    pub reference_tolerance: f64,
}

impl Options {
    /// Refuse sizes and widths the query plane cannot take.
    pub fn check(&self) -> Result<(), String> {
        let n = self.shadow;
        if !(4..=1024).contains(&n) || !n.is_power_of_two() {
            return Err(format!("the shadow map's size {n} must be a power of two in 4..=1024"));
        }
        if !(self.light_width.is_finite() && (0.0..=2.0).contains(&self.light_width)) {
            return Err(format!(
                "the light's width {} must lie in [0, 2] (the query plane spans 2 world units)",
                self.light_width
            ));
        }
        if !(self.reference_tolerance.is_finite() && self.reference_tolerance >= 0.0) {
            return Err(format!(
                "the reference tolerance {} must be finite and not negative",
                self.reference_tolerance
            ));
        }
        Ok(())
    }
}

impl Default for Options {
    fn default() -> Options {
        Options {
            shadow: 32,
            light_width: 0.5,
            reference_tolerance: 1e-6,
        }
    }
}

/// The verdict of one (input, camera).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Agrees,
    Differs,
    Lossy,
}

impl Verdict {
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Agrees => "agrees",
            Verdict::Differs => "DIFFERS",
            Verdict::Lossy => "LOSSY",
        }
    }
}

/// One receiver compared, kept for the worst of a row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Worst {
    pub pixel: (usize, usize),
    pub got: f64,
    pub expected: f64,
    pub allowance: f64,
}

impl Worst {
    /// |got - expected| over the allowance.
    pub fn ratio(&self) -> f64 {
        let diff = (self.got - self.expected).abs();
        if diff == 0.0 { 0.0 } else { diff / self.allowance }
    }
}

/// The comparison of one (input, camera).
#[derive(Clone, Debug)]
pub struct Row {
    pub input: String,
    pub camera: u32,
    /// Receivers compared.
    pub receivers: usize,
    /// Receivers whose allowance is at least 1/2: a site there jumps (a tie).
    pub loose: usize,
    /// Receivers outside their allowance.
    pub outside: usize,
    pub max_diff: f64,
    pub median_allowance: f64,
    /// The receiver with the largest difference over its allowance.
    pub worst: Option<Worst>,
    /// The 99th percentile over receivers of what storage rounding alone does.
    pub storage: f64,
    /// The reference's comparison: receivers outside, largest difference and its worst.
    pub reference: Option<(usize, f64, Option<Worst>)>,
    pub verdict: Verdict,
    /// Every receiver compared: its pixel index, the GPU's value, the CPU's, and the
    /// difference over the allowance (above 1: outside).
    pub compared: Vec<(usize, f64, f64, f64)>,
}

impl Row {
    /// The row as a picture, `scale` screen pixels per camera pixel: the GPU's visibility,
    /// the CPU's, and the difference over the allowance (black: equal; through the viridis
    /// map up to the allowance; red: outside it). Pixels not compared stay dark blue.
    pub fn picture(&self, scale: u32) -> image::RgbImage {
        let n = self.camera;
        let s = scale.max(1);
        let mut img = image::RgbImage::from_pixel(3 * n * s + 2 * s, n * s, image::Rgb([16, 16, 48]));
        let grey = |v: f64| {
            let g = (v.clamp(0.0, 1.0) * 255.0).round() as u8;
            image::Rgb([g, g, g])
        };
        for &(i, got, expected, ratio) in &self.compared {
            let (x, y) = ((i as u32) % n, (i as u32) / n);
            let diff = if ratio > 1.0 || ratio.is_nan() {
                image::Rgb([230, 20, 20])
            } else if ratio == 0.0 {
                image::Rgb([0, 0, 0])
            } else {
                let c = colorous::VIRIDIS.eval_continuous(ratio);
                image::Rgb([c.r, c.g, c.b])
            };
            for (panel, colour) in [grey(got), grey(expected), diff].into_iter().enumerate() {
                let x0 = panel as u32 * (n * s + s) + x * s;
                for dy in 0..s {
                    for dx in 0..s {
                        img.put_pixel(x0 + dx, y * s + dy, colour);
                    }
                }
            }
        }
        img
    }
}

/// Receivers at or past this share of storage error make a row lossy.
const LOSSY_SHARE: f64 = 0.01;

/// Verify `c` (and optionally a reference technique) on each input, under both cameras.
/// `progress` is told each (input, camera) as it starts.
pub fn verify(
    gpu: &Gpu,
    c: &sshc::Compiled,
    reference: Option<&sshc::Compiled>,
    inputs: &[Input],
    opts: &Options,
    progress: &mut dyn FnMut(&str, u32),
) -> Result<Vec<Row>, String> {
    let program = Program::new(&c.ir, &c.layout);
    if let Some(why) = sshc::interp::unsupported(&program) {
        return Err(format!("`sshc verify` cannot evaluate `{}` on the CPU: {why}", c.ir.technique));
    }
    opts.check()?;
    let n = opts.shadow;
    let reference_program = reference.map(|r| Program::new(&r.ir, &r.layout));
    if let Some(p) = &reference_program
        && let Some(why) = sshc::interp::unsupported(p)
    {
        return Err(format!("the reference `{}` cannot be evaluated on the CPU: {why}", p.ir.technique));
    }
    let mut rows = Vec::new();
    let mut ex = Executor::new(gpu, c.graph.clone(), c.shaders.clone()).map_err(crate::session::rt)?;
    for input in inputs {
        if input.depth.len() != (n * n) as usize {
            return Err(format!("input `{}` has {} depths, not {n} x {n}", input.name, input.depth.len()));
        }
        for camera in [2 * n, n / 2] {
            progress(&input.name, camera);
            let plane = QueryPlane { shadow: n, camera };
            let frame = plane.frame(opts.light_width);
            ex.bind_scene(&plane.lit_inputs(opts.light_width as f32))
                .map_err(crate::session::rt)?;
            ex.set_depth_override(Some(input.depth.clone()));
            ex.run_frame().map_err(crate::session::rt)?;
            let got = ex.read_camera(CameraOutput::Visibility).map_err(crate::session::rt)?.channel(0);
            let positions = ex.read_camera(CameraOutput::Position).map_err(crate::session::rt)?.rgba;
            let receivers: Vec<(usize, Receiver)> = positions
                .iter()
                .enumerate()
                .filter(|(_, p)| p[..3].iter().all(|c| c.is_finite()))
                .map(|(i, p)| (i, plane.receiver(i, [p[0], p[1], p[2]])))
                .collect();
            let exact = Evaluation::new(program, &input.depth, frame, Rounding::Exact, Model::Gpu)?;
            let rounded = Evaluation::new(program, &input.depth, frame, Rounding::Stored, Model::Gpu)?;
            // the technique and its reference, each with what f64 rounding allows it
            let pair = reference_program
                .map(|p| -> Result<_, String> {
                    Ok((
                        Evaluation::new(program, &input.depth, frame, Rounding::Exact, Model::F64)?,
                        Evaluation::new(p, &input.depth, frame, Rounding::Exact, Model::F64)?,
                    ))
                })
                .transpose()?;
            let evaluated: Vec<_> = receivers
                .par_iter()
                .map_init(Scratch::default, |scratch, (i, r)| {
                    let e = exact.visibility(r, scratch);
                    let s = rounded.value(r, scratch);
                    let f = pair.as_ref().map(|(t, x)| (t.visibility(r, scratch), x.visibility(r, scratch)));
                    (*i, e, s, f)
                })
                .collect();
            let mut row = Row {
                input: input.name.clone(),
                camera,
                receivers: evaluated.len(),
                loose: 0,
                outside: 0,
                max_diff: 0.0,
                median_allowance: 0.0,
                worst: None,
                storage: 0.0,
                reference: reference_program.map(|_| (0, 0.0, None)),
                verdict: Verdict::Agrees,
                compared: Vec::with_capacity(evaluated.len()),
            };
            let mut allowances = Vec::new();
            let mut storage = Vec::new();
            for &(i, e, s, f) in &evaluated {
                let at = (i % camera as usize, i / camera as usize);
                let g = got.get(i).copied().unwrap_or(f32::NAN) as f64;
                let w = Worst {
                    pixel: at,
                    got: g,
                    expected: e.value,
                    allowance: e.half_width(),
                };
                let diff = (g - e.value).abs();
                row.max_diff = if diff.is_nan() { f64::NAN } else { row.max_diff.max(diff) };
                if !e.admits(g) {
                    row.outside += 1;
                }
                let ratio = if e.admits(g) {
                    w.ratio().min(1.0)
                } else {
                    w.ratio().max(1.0 + f64::EPSILON)
                };
                row.compared.push((i, g, e.value, ratio));
                if row.worst.is_none_or(|x| w.ratio() > x.ratio() || w.ratio().is_nan()) {
                    row.worst = Some(w);
                }
                if e.half_width() >= 0.5 {
                    row.loose += 1;
                }
                allowances.push(e.half_width());
                storage.push((s - e.value).abs());
                if let (Some((t, f)), Some((out, max, worst))) = (f, row.reference.as_mut()) {
                    let tol = opts.reference_tolerance;
                    let w = Worst {
                        pixel: at,
                        got: f.value,
                        expected: t.value,
                        allowance: t.half_width() + f.half_width() + tol,
                    };
                    *max = max.max((f.value - t.value).abs());
                    if !overlap(&t, &f, tol) {
                        *out += 1;
                    }
                    if worst.is_none_or(|x| w.ratio() > x.ratio()) {
                        *worst = Some(w);
                    }
                }
            }
            allowances.sort_by(f64::total_cmp);
            storage.sort_by(f64::total_cmp);
            row.median_allowance = allowances.get(allowances.len() / 2).copied().unwrap_or(0.0);
            row.storage = storage
                .get(((storage.len() as f64) * (1.0 - LOSSY_SHARE)) as usize)
                .or(storage.last())
                .copied()
                .unwrap_or(0.0);
            row.verdict = if row.outside > 0 || row.reference.is_some_and(|r| r.0 > 0) {
                Verdict::Differs
            } else if row.storage > sshc::rounding::WARN_ABOVE {
                Verdict::Lossy
            } else {
                Verdict::Agrees
            };
            rows.push(row);
        }
    }
    Ok(rows)
}

/// Whether two evaluations' intervals meet once widened by `tol`.
fn overlap(a: &Allowed, b: &Allowed, tol: f64) -> bool {
    a.lo - tol <= b.hi && b.lo - tol <= a.hi
}

/// The rows as a Markdown table.
pub fn table(rows: &[Row]) -> String {
    let with_reference = rows.iter().any(|r| r.reference.is_some());
    let mut s = String::from(
        "| input | camera | receivers | loose | outside | max diff | median allowance | worst (pixel: got, expected, allowance) | storage p99 |",
    );
    if with_reference {
        s.push_str(" reference outside | reference max diff |");
    }
    s.push_str(" verdict |\n|---|---|---|---|---|---|---|---|---|");
    if with_reference {
        s.push_str("---|---|");
    }
    s.push_str("---|\n");
    for r in rows {
        let worst = r.worst.map_or("-".into(), |w| {
            format!(
                "({}, {}): {:.6}, {:.6}, {:.2e} ({:.2} of it)",
                w.pixel.0,
                w.pixel.1,
                w.got,
                w.expected,
                w.allowance,
                w.ratio()
            )
        });
        let _ = write!(
            s,
            "| {} | {} | {} | {} | {} | {:.2e} | {:.2e} | {} | {:.2e} |",
            r.input, r.camera, r.receivers, r.loose, r.outside, r.max_diff, r.median_allowance, worst, r.storage
        );
        if with_reference {
            match r.reference {
                Some((out, max, _)) => {
                    let _ = write!(s, " {out} | {max:.2e} |");
                }
                None => s.push_str(" - | - |"),
            }
        }
        let _ = writeln!(s, " {} |", r.verdict.name());
    }
    s
}
