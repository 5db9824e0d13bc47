//! `sshc verify`: a compiled technique run on the GPU over the inputs of the
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
//! signal; **UNCHECKED** when nothing differs or is lossy, but at some receiver the GPU's
//! value is [`TELLS_APART`] or more from the CPU's and only an allowance of [`TELLS_APART`]
//! or more admits it: an allowance that wide cannot tell a lit pixel from a shadowed one, so
//! the comparison there checked nothing, and the row is not reported as agreement (nor as a
//! failure: the bound is honest, only too loose to decide). With a reference technique
//! (`--reference`), its f64 CPU evaluation is compared with the technique's under the same
//! allowance: an independent reading of the math.

use crate::run::{Bound, Loaded};
use crate::scene;
use glam::{Mat4, Vec3};
use rayon::prelude::*;
use sshc::interp::{Allowed, Evaluation, Frame, Given, GivenSlot, Model, Receiver, Rounding, Scratch, Seen};
use sshc::ir::Program;
use sshc_runtime::gpu::{CameraOutput, Gpu, SampleView, SceneInputs};
use std::fmt::Write as _;
use std::path::Path;

/// The query plane: an orthographic light looking straight down at a receiver tilted
/// along x, seen by an orthographic camera with the light's own view, so that camera pixel
/// (i, j) shades light uv ((i + 0.5) / camera, (j + 0.5) / camera) and the receiver's
/// normalised depth runs linearly from 1 to 0 across u (`d = 1 - u`). A camera of 2N pixels
/// over an N-texel map samples every texel at sub-texel offsets 1/4 and 3/4 and filters at
/// level of detail -1 (the base level); a camera of N / 2^k filters at level k.
///
/// With `casters`, the light's depth range starts higher (view distance 6.5, height 3.5),
/// leaving a slab above the receiver (heights [`CASTER_SLAB`]) for caster meshes that the
/// light draws and the camera does not (its near plane clips everything above height 2.2,
/// the receiver's top): the depth map and Geometry passes' primitives are then rasterised
/// from real meshes while every camera pixel still shades the plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueryPlane {
    pub shadow: u32,
    pub camera: u32,
    pub casters: bool,
    /// The light view's half-extent (world units; 1: the plane's own square) and the x its
    /// eye stands over (0: the plane's centre): a cascade of [`QueryPlane::cascade`]. The
    /// camera keeps the plane's square whatever these are.
    pub half: f32,
    pub centre: f32,
}

/// Light eye height and the fitted depth range of the query plane.
const EYE: f32 = 10.0;
const NEAR: f32 = 8.0;
const FAR: f32 = 12.0;
/// The depth range with room for casters above the receiver.
const CASTER_NEAR: f32 = 6.5;
const CASTER_FAR: f32 = 12.5;
/// Heights the casters of [`QueryPlane::casters`] are fitted into.
pub const CASTER_SLAB: (f32, f32) = (2.35, 3.3);
/// The camera's near distance with casters: heights above 2.2 are clipped.
const CAMERA_NEAR_CASTERS: f32 = EYE - 2.2;

impl QueryPlane {
    /// The plane without casters.
    pub fn new(shadow: u32, camera: u32) -> QueryPlane {
        QueryPlane {
            shadow,
            camera,
            casters: false,
            half: 1.0,
            centre: 0.0,
        }
    }

    /// Cascade `k` of the plane for `verify --cascades`: a light view `2^(k/2)` times as
    /// wide as the plane's square (a half-extent `h`), its eye over `x = 1 - h`, so that
    /// every cascade holds the whole plane (x from `1 - 2h` to 1) and each is coarser than
    /// the one before, as cascades further from a camera are. The camera looks down at the
    /// plane, so a receiver's view distance is `EYE - 2x`: the nearest slice lies at x = 1,
    /// the edge every cascade shares.
    pub fn cascade(self, k: u32) -> QueryPlane {
        let half = (0.5 * k as f32).exp2();
        QueryPlane {
            half,
            centre: 1.0 - half,
            ..self
        }
    }

    /// The camera's eye and unit forward axis (looking down at the plane), from which
    /// cascades measure view distance.
    pub fn camera_axis() -> ([f32; 3], [f32; 3]) {
        ([0.0, EYE, 0.0], [0.0, -1.0, 0.0])
    }

    /// The range of view distances the camera sees the receiver at (`EYE - 2x`, x in
    /// [-1, 1]), which cascades split.
    pub fn view_depths() -> (f32, f32) {
        (EYE - 2.0, EYE + 2.0)
    }

    /// The light's fitted depth range (view distances).
    fn range(&self) -> (f32, f32) {
        if self.casters { (CASTER_NEAR, CASTER_FAR) } else { (NEAR, FAR) }
    }

    pub fn light_view(&self) -> Mat4 {
        self.view_at(self.centre)
    }

    /// The light's view translated by `x` along the plane's tilt: light sample views.
    fn view_at(&self, x: f32) -> Mat4 {
        scene::look_at(Vec3::new(x, EYE, 0.0), Vec3::new(x, 0.0, 0.0), Vec3::new(0.0, 0.0, -1.0))
    }

    pub fn light_proj(&self) -> Mat4 {
        let (near, far) = self.range();
        let h = self.half;
        scene::orthographic(-h, h, -h, h, near, far)
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
        let (near, far) = self.range();
        let camera_near = if self.casters { CAMERA_NEAR_CASTERS } else { 0.1 };
        let camera_proj = scene::orthographic(-1.0, 1.0, -1.0, 1.0, camera_near, 40.0);
        // the camera keeps the plane's own view and square under any cascade's light
        let camera_view = self.view_at(0.0);
        SceneInputs {
            vertices,
            meshes: vec![],
            casting_vertices: None,
            unshadowed: vec![],
            camera_view_proj: (camera_proj * camera_view).to_cols_array(),
            camera_position: [0.0, EYE, 0.0],
            camera_size: (self.camera, self.camera),
            shadow_size: self.shadow,
            light_view: view.to_cols_array(),
            light_view_proj: (proj * view).to_cols_array(),
            light_position: [0.0, 1.0, 0.0, 0.0],
            near,
            far,
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
    /// light's eye; with casters, a distant light of angular diameter
    /// [`QueryPlane::light_angle`] instead (the casters' primitives grow with its angle).
    pub fn lit_inputs(&self, width: f32) -> SceneInputs {
        if self.casters {
            return SceneInputs {
                light_angle: Self::light_angle(width as f64) as f32,
                ..self.inputs()
            };
        }
        SceneInputs {
            light_size: 0.5 * width,
            light_half_extents: [0.5 * width, 0.5 * width],
            ..self.inputs()
        }
    }

    /// The angular diameter of the distant light over casters `width` wide: `2 atan(width
    /// / 8)`, a spread (`2 tan(angle / 2)`) of `width / 4` (0.125 at the default width: a
    /// caster 2 units above the receiver casts a penumbra 0.25 wide, 4 texels of a 32^2 map).
    pub fn light_angle(width: f64) -> f64 {
        2.0 * (width / 8.0).atan()
    }

    /// [`QueryPlane::lit_inputs`] with `casters` (world position and normal per vertex,
    /// three vertices a triangle, fitted into [`CASTER_SLAB`]; `meshes`: their ranges of
    /// triangles) drawn from the light before the receiver, which is its own mesh.
    pub fn caster_inputs(&self, width: f32, casters: &[f32], meshes: &[std::ops::Range<u32>]) -> SceneInputs {
        let receiver = self.lit_inputs(width);
        let first = (casters.len() / 18) as u32;
        let mut meshes = meshes.to_vec();
        if meshes.is_empty() {
            meshes.push(0..first);
        }
        meshes.push(first..first + (receiver.vertices.len() / 18) as u32);
        SceneInputs {
            vertices: casters.iter().chain(&receiver.vertices).copied().collect(),
            meshes,
            casting_vertices: Some((casters.len() / 6) as u32),
            unshadowed: vec![],
            ..receiver
        }
    }

    /// The x of light sample `k` of `samples` spread over `width` along the plane's tilt.
    fn sample_x(samples: u32, k: u32, width: f64) -> f64 {
        if samples < 2 {
            0.0
        } else {
            width * (k as f64 / (samples - 1) as f64 - 0.5)
        }
    }

    /// The views of `samples` light samples along a segment `width` wide across x: each is
    /// the light's view translated to its sample (orthographic like the centre's, so that
    /// every receiver input of each view is affine over the plane and the CPU computes it
    /// exactly); each of the N - 1 segments weighs 1 / (N - 1), a lone sample [1, 1] (as
    /// the lab binds a segment light).
    pub fn sample_views(&self, samples: u32, width: f64) -> Vec<SampleView> {
        let proj = self.light_proj();
        let (near, far) = self.range();
        let w = if samples > 1 { 1.0 / (samples - 1) as f32 } else { 1.0 };
        (0..samples)
            .map(|k| {
                let x = Self::sample_x(samples, k, width) as f32;
                let view = self.view_at(x);
                SampleView {
                    light_view: view.to_cols_array(),
                    light_view_proj: (proj * view).to_cols_array(),
                    position: [x, EYE, 0.0],
                    near,
                    far,
                    light_proj_y: proj.y_axis.y,
                    weights: if samples < 2 {
                        [1.0, 1.0]
                    } else {
                        [if k > 0 { w } else { 0.0 }, if k + 1 < samples { w } else { 0.0 }]
                    },
                }
            })
            .collect()
    }

    /// `depth` (a map of the centre's view) as sample `k` of `samples` over `width` sees
    /// it: translated by the sample's offset, rounded to whole texels, clamped at the edge
    /// (occluders fixed in the world, seen from a translated view).
    pub fn sample_depth(&self, depth: &[f32], samples: u32, k: u32, width: f64) -> Vec<f32> {
        let n = self.shadow as i64;
        let shift = (Self::sample_x(samples, k, width) * n as f64 / 2.0).round() as i64;
        (0..n * n)
            .map(|t| {
                let (i, j) = (t % n, t / n);
                depth[(j * n + (i + shift).clamp(0, n - 1)) as usize]
            })
            .collect()
    }

    /// Light uv and normalised depth of a world position, in f64.
    pub fn project(&self, p: [f32; 3]) -> ([f64; 2], f64) {
        let (uv, dist) = self.seen_from(self.centre as f64, p);
        let (near, far) = self.range();
        (uv, (dist - near as f64) / (far as f64 - near as f64))
    }

    /// Light uv and view distance of a world position from the view translated by `x`.
    fn seen_from(&self, x: f64, p: [f32; 3]) -> ([f64; 2], f64) {
        let v = self.view_at(x as f32).as_dmat4();
        let vp = self.light_proj().as_dmat4() * v;
        let w = glam::DVec4::new(p[0] as f64, p[1] as f64, p[2] as f64, 1.0);
        let clip = vp * w;
        let uv = [clip.x / clip.w * 0.5 + 0.5, -clip.y / clip.w * 0.5 + 0.5];
        (uv, -(v * w).z)
    }

    /// The level of detail of implicit `sample` lookups: texels per camera pixel, log2.
    pub fn lod(&self) -> f32 {
        (self.shadow as f32 / (self.camera as f32 * self.half)).log2()
    }

    /// The frame-wide inputs under a light `width` wide (`lit_inputs`; 0: `inputs`).
    pub fn frame(&self, width: f64) -> Frame {
        let n = self.shadow as f64;
        let (near, far) = self.range();
        // without casters: a square light of `width` and no angular size; with casters, a
        // distant light of no size and the spread the GPU computes from its f32 angle
        let (size, spread) = if self.casters {
            (0.0, 2.0 * (0.5 * Self::light_angle(width) as f32 as f64).tan())
        } else {
            (width, 0.0)
        };
        Frame {
            shadow_size: self.shadow,
            near: near as f64,
            far: far as f64,
            light_size: 0.5 * size,
            light_width: [size, size],
            light_spread: spread,
            light_distant: true,
            // orthographic: 2h world units over the map (light_proj_y is 1 / h)
            texel_world: [0.0, 2.0 * self.half as f64 / n],
            frame: 0,
        }
    }

    /// The receiver the GPU shaded at camera pixel `pixel` from world position `p`, seen
    /// from the centre and from each light sample's view of `views` ([`QueryPlane::sample_views`]).
    pub fn receiver(&self, pixel: usize, p: [f32; 3], views: &[SampleView]) -> Receiver {
        let (uv, d_world) = self.seen_from(self.centre as f64, p);
        let (near, far) = self.range();
        let (near, far) = (near as f64, far as f64);
        let n = Self::normal().as_dvec3();
        // d = (EYE - 2x - near) / (far - near) with x = centre + h (2u - 1): a gradient of
        // 4h / (far - near) over uv (1 on the plane's own square without casters: d = 1 -
        // u), one texel's worth per texel
        let depth_slope = (4.0 * self.half as f64 / (far - near) / self.shadow as f64).min(0.1);
        let lod = self.lod().max(0.0) as f64;
        let seen = views
            .iter()
            .map(|v| {
                let x = v.position[0] as f64;
                let (uv, d_world) = self.seen_from(x, p);
                let to = glam::DVec3::new(x - p[0] as f64, EYE as f64 - p[1] as f64, -p[2] as f64).normalize();
                Seen {
                    uv,
                    d_world,
                    near,
                    far,
                    ndotl: n.dot(to),
                    depth_slope,
                    lod,
                    texel_world: 2.0 / (v.light_proj_y as f64 * self.shadow as f64),
                    weights: v.weights.map(f64::from),
                }
            })
            .collect();
        Receiver {
            uv,
            d_world,
            ndotl: n.dot(glam::DVec3::Y),
            depth_slope,
            lod,
            pixel: [(pixel % self.camera as usize) as f64, (pixel / self.camera as usize) as f64],
            samples: seen,
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
    let loaded = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).map_err(crate::session::rt)?;
    let mut ex = loaded.bind_scene(&crate::bind::scene_inputs(&s)?).map_err(crate::session::rt)?;
    ex.run_frame().map_err(crate::session::rt)?;
    let depth = c
        .graph
        .passes
        .iter()
        .find(|p| p.kind == sshc_runtime::graph::PassKind::Depth)
        .ok_or("the hard technique has no Depth pass")?;
    Ok(ex
        .inspect()
        .read_texture(&depth.steps[0].writes[0].texture, 0, 0)
        .map_err(crate::session::rt)?
        .channel(0))
}

/// The caster sets of [`caster_set`], by name.
pub const CASTERS: [&str; 2] = ["box", "bars"];

/// Triangles (position and normal per vertex) of an axis-aligned box from `lo` to `hi`,
/// turned by `turn` radians about the vertical through its centre.
fn box_triangles(lo: Vec3, hi: Vec3, turn: f32) -> Vec<f32> {
    let c = 0.5 * (lo + hi);
    let rot = glam::Quat::from_rotation_y(turn);
    let h = 0.5 * (hi - lo);
    let mut out = Vec::new();
    // each face: its normal axis and sign; corners in counter-clockwise order seen from outside
    for (axis, sign) in [(0, 1.0f32), (0, -1.0), (1, 1.0), (1, -1.0), (2, 1.0), (2, -1.0)] {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let corner = |a: f32, b: f32| {
            let mut p = Vec3::ZERO;
            p[axis] = sign * h[axis];
            p[u] = a * h[u];
            p[v] = b * h[v] * sign;
            c + rot * p
        };
        let mut n = Vec3::ZERO;
        n[axis] = sign;
        let n = rot * n;
        let q = [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)];
        for i in [0, 1, 2, 0, 2, 3] {
            out.extend([q[i].x, q[i].y, q[i].z, n.x, n.y, n.z]);
        }
    }
    out
}

/// A bundled caster set above the query plane (heights within [`CASTER_SLAB`]), by name
/// ([`CASTERS`]): its triangles and meshes (ranges of triangles), or `None`.
///
/// - `box`: one box, 0.7 wide, its silhouette square to the map;
/// - `bars`: three boxes at three heights, one turned by 30 degrees (diagonal silhouettes).
pub fn caster_set(name: &str) -> Option<(Vec<f32>, Vec<std::ops::Range<u32>>)> {
    let boxes: Vec<(Vec3, Vec3, f32)> = match name {
        "box" => vec![(Vec3::new(-0.35, 2.45, -0.35), Vec3::new(0.35, 2.9, 0.35), 0.0)],
        "bars" => vec![
            (Vec3::new(-0.75, 2.4, -0.7), Vec3::new(-0.45, 2.6, 0.7), 0.0),
            (Vec3::new(-0.1, 2.7, -0.5), Vec3::new(0.15, 2.95, 0.5), std::f32::consts::FRAC_PI_6),
            (Vec3::new(0.45, 3.05, -0.6), Vec3::new(0.7, 3.25, 0.2), 0.0),
        ],
        _ => return None,
    };
    let mut vertices = Vec::new();
    let mut meshes = Vec::new();
    for (lo, hi, turn) in boxes {
        let first = (vertices.len() / 18) as u32;
        vertices.extend(box_triangles(lo, hi, turn));
        meshes.push(first..(vertices.len() / 18) as u32);
    }
    Some((vertices, meshes))
}

/// A scene's shadow casters fitted into the slab above the query plane: uniformly scaled
/// and moved so that they span at most 1.5 across x and z and lie within [`CASTER_SLAB`].
pub fn scene_casters(path: &Path) -> Result<(Vec<f32>, Vec<std::ops::Range<u32>>), String> {
    let s = crate::session::load_scene(path, Some((8, 8)), Some(8))?;
    let inputs = crate::bind::scene_inputs(&s)?;
    let casting = inputs.casting_vertices.map_or(inputs.vertices.len() / 6, |n| n as usize);
    let triangles = (casting / 3) as u32;
    let all = 0..triangles;
    let meshes = if inputs.meshes.is_empty() {
        std::slice::from_ref(&all)
    } else {
        &inputs.meshes[..]
    };
    let bounds = |m: &std::ops::Range<u32>| {
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for t in m.start..m.end.min(triangles) {
            for v in inputs.vertices[t as usize * 18..t as usize * 18 + 18].chunks(6) {
                lo = lo.min(Vec3::new(v[0], v[1], v[2]));
                hi = hi.max(Vec3::new(v[0], v[1], v[2]));
            }
        }
        (lo, hi)
    };
    // floors (flat and level) receive; they are left out, as the plane receives here
    let kept: Vec<std::ops::Range<u32>> = meshes
        .iter()
        .filter(|m| m.start < triangles)
        .filter(|m| {
            let (lo, hi) = bounds(m);
            let e = hi - lo;
            e.y > 0.01 * e.x.max(e.z)
        })
        .cloned()
        .collect();
    if kept.is_empty() {
        return Err(format!("scene `{}` has no shadow casters but floors", path.display()));
    }
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for m in &kept {
        let (a, b) = bounds(m);
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let ext = hi - lo;
    let scale = (1.5 / ext.x.max(ext.z).max(f32::MIN_POSITIVE)).min((CASTER_SLAB.1 - CASTER_SLAB.0) / ext.y.max(f32::MIN_POSITIVE));
    let centre = Vec3::new(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
    let mut out = Vec::new();
    let mut out_meshes = Vec::new();
    for m in &kept {
        let first = (out.len() / 18) as u32;
        for v in inputs.vertices[m.start as usize * 18..m.end.min(triangles) as usize * 18].chunks(6) {
            let p = (Vec3::new(v[0], v[1], v[2]) - centre) * scale + Vec3::new(0.0, CASTER_SLAB.0, 0.0);
            out.extend([p.x, p.y, p.z, v[3], v[4], v[5]]);
        }
        out_meshes.push(first..(out.len() / 18) as u32);
    }
    Ok((out, out_meshes))
}

/// What an input gives the passes.
#[derive(Clone, Debug)]
pub enum Source {
    /// A depth map of the light's centre view, fed in place of the Depth pass's output
    /// (each light sample's view sees it translated by the sample's offset).
    Depth(Vec<f32>),
    /// Caster meshes above the query plane (triangles, position and normal per vertex, and
    /// their meshes): the Depth pass and Geometry passes rasterise them, and their outputs
    /// are read back and given to the CPU evaluation.
    Casters(Vec<f32>, Vec<std::ops::Range<u32>>),
}

/// One input to verify on.
#[derive(Clone, Debug)]
pub struct Input {
    pub name: String,
    pub source: Source,
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
    /// Cascades of the query plane's light ([`QueryPlane::cascade`]; 1: none), split at
    /// `cascade_lambda` by the practical scheme and mixed over the last `cascade_band` of
    /// each slice, as `render --cascades` binds them.
    pub cascades: u32,
    pub cascade_lambda: f32,
    pub cascade_band: f32,
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
        let max = sshc_runtime::light::MAX_CASCADES;
        if !(1..=max).contains(&self.cascades) {
            return Err(format!("{} cascades: a light has 1 to {max}", self.cascades));
        }
        if !(0.0..=1.0).contains(&self.cascade_lambda) {
            return Err(format!("cascade lambda {}: a weight in [0, 1]", self.cascade_lambda));
        }
        if !(0.0..1.0).contains(&self.cascade_band) {
            return Err(format!("cascade band {}: a fraction of a slice, in [0, 1)", self.cascade_band));
        }
        Ok(())
    }

    /// The view distances bounding the cascades (`cascades + 1` of them).
    pub fn splits(&self) -> Vec<f32> {
        let (near, far) = QueryPlane::view_depths();
        sshc_runtime::light::practical_splits(near, far, self.cascades, self.cascade_lambda).unwrap_or_else(|| vec![near, far])
    }
}

impl Default for Options {
    fn default() -> Options {
        Options {
            shadow: 32,
            light_width: 0.5,
            reference_tolerance: 1e-6,
            cascades: 1,
            cascade_lambda: 0.75,
            cascade_band: 0.1,
        }
    }
}

/// The verdict of one (input, camera).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Every receiver within its allowance, and none whose agreement rests on an allowance
    /// too wide to have caught a real difference ([`TELLS_APART`]).
    Agrees,
    Differs,
    Lossy,
    /// Nothing outside its allowance and nothing lossy, but some receiver's GPU value is
    /// [`TELLS_APART`] or more from the CPU's, admitted only by an allowance of
    /// [`TELLS_APART`] or more: not a failure, never agreement.
    Unchecked,
}

impl Verdict {
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Agrees => "agrees",
            Verdict::Differs => "DIFFERS",
            Verdict::Lossy => "LOSSY",
            Verdict::Unchecked => "UNCHECKED",
        }
    }

    /// Whether the verdict fails the command (DIFFERS, LOSSY): UNCHECKED does not by itself.
    pub fn fails(self) -> bool {
        matches!(self, Verdict::Differs | Verdict::Lossy)
    }
}

/// The allowance (half-width of the interval allowed about the CPU's visibility, in [0, 1])
/// from which a comparison can no longer tell a lit pixel from a shadowed one, and the
/// difference that is a real one: 1/2 of the visibility's range.
///
/// Derivation. The allowed interval `[lo, hi]` lies within `value -+ a`, of width at most
/// `2a`. A fully lit receiver reads 1 and a fully shadowed one 0, a distance of 1 apart:
/// an interval of width `2a < 1` never holds both, so wherever it lies, a GPU that reads
/// lit where the CPU reads shadowed (or the reverse) is caught; at `a >= 1/2` an interval
/// about `1/2` holds both, and a comparison under it can pass a pixel lit for one that is
/// shadowed. Conversely, two visibilities in [0, 1] that are 1/2 or more apart lie on
/// either side of 1/2 (if both were below it, or both above, they would be closer): one
/// reads more lit than shadowed, the other more shadowed than lit. So a receiver whose
/// GPU value is within its allowance but 1/2 or more from the CPU's, under an allowance
/// of 1/2 or more, is a real difference that only the allowance excuses: UNCHECKED.
/// A receiver under a wide allowance whose values are closer than 1/2 shows no such
/// difference, and one under an allowance below 1/2 would have been caught (DIFFERS), so
/// a row with neither kind of receiver AGREES. The same 1/2 is the `loose` count's.
pub const TELLS_APART: f64 = 0.5;

/// Whether the GPU's `got` is admitted by `e` only because `e`'s allowance is too wide to
/// tell lit from shadowed ([`TELLS_APART`]): within the allowance, but a real difference.
/// Judged on visibilities (and a reference's), whose range is [0, 1]; debug outputs, of
/// any range, are not.
pub fn unchecked(got: f64, e: &Allowed) -> bool {
    e.admits(got) && e.half_width() >= TELLS_APART && (got - e.value).abs() >= TELLS_APART
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
    /// Receivers whose allowance is at least 1/2 ([`TELLS_APART`]): a site there jumps (a
    /// tie), and a GPU value 1/2 or more from the CPU's there leaves the row UNCHECKED.
    pub loose: usize,
    /// Receivers outside their allowance.
    pub outside: usize,
    /// Receivers within their allowance only because it is too wide to tell lit from
    /// shadowed ([`unchecked`]; with a reference, its comparisons counted too).
    pub unchecked: usize,
    /// The unchecked receiver with the largest difference.
    pub unchecked_worst: Option<Worst>,
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
    /// Channels with a declared range (`range: (lo, hi)`) whose stored values it clamped,
    /// and at how many texels (every cascade's summed).
    pub clamped: Vec<(String, usize)>,
    /// The Shade's debug outputs (a build with them, `--debug`), each compared as the
    /// visibility is: every component at every receiver, each cascade's own.
    pub debug: Vec<DebugRow>,
}

/// One debug output's comparison over a row's receivers: the GPU's value (read back from
/// its texture) against the CPU's f64 evaluation of the same expression, within the same
/// running error bound as the visibility's, without the clamp.
#[derive(Clone, Debug, PartialEq)]
pub struct DebugRow {
    pub name: String,
    /// Values compared (receivers x components x cascades).
    pub values: usize,
    /// Values outside their allowance.
    pub outside: usize,
    pub max_diff: f64,
    /// The value with the largest difference over its allowance.
    pub worst: Option<Worst>,
}

impl DebugRow {
    /// Compare the GPU's `got` with the CPU's allowed value `e` at `pixel` (two NaNs agree:
    /// the expression is undefined there on both).
    fn add(&mut self, pixel: (usize, usize), got: f64, e: &Allowed) {
        self.values += 1;
        if got.is_nan() && e.value.is_nan() {
            return;
        }
        tally((&mut self.outside, &mut self.max_diff, &mut self.worst), pixel, got, e);
    }
}

/// Count one receiver's `got` against its allowed `e` into a row's (outside, largest
/// difference, worst): whether it lies outside, and the difference kept where largest.
fn tally((outside, max_diff, worst): (&mut usize, &mut f64, &mut Option<Worst>), pixel: (usize, usize), got: f64, e: &Allowed) -> Worst {
    let w = Worst {
        pixel,
        got,
        expected: e.value,
        allowance: e.half_width(),
    };
    let diff = (got - e.value).abs();
    *max_diff = if diff.is_nan() { f64::NAN } else { max_diff.max(diff) };
    if !e.admits(got) {
        *outside += 1;
    }
    if worst.is_none_or(|x| w.ratio() > x.ratio() || w.ratio().is_nan()) {
        *worst = Some(w);
    }
    w
}

impl Row {
    /// An empty row of `input` under `camera` (nothing compared yet: it agrees).
    pub fn new(input: &str, camera: u32, reference: bool) -> Row {
        Row {
            input: input.to_string(),
            camera,
            receivers: 0,
            loose: 0,
            outside: 0,
            unchecked: 0,
            unchecked_worst: None,
            max_diff: 0.0,
            median_allowance: 0.0,
            worst: None,
            storage: 0.0,
            reference: reference.then_some((0, 0.0, None)),
            verdict: Verdict::Agrees,
            compared: Vec::new(),
            clamped: Vec::new(),
            debug: Vec::new(),
        }
    }

    /// Count the GPU's `got` at camera pixel `i` against the CPU's allowed `e`: outside,
    /// loose (allowance of 1/2 or more), unchecked ([`unchecked`]), and the largest
    /// difference and worst receiver.
    pub fn compare(&mut self, i: usize, got: f64, e: &Allowed) {
        let camera = self.camera.max(1) as usize;
        let at = (i % camera, i / camera);
        let w = tally((&mut self.outside, &mut self.max_diff, &mut self.worst), at, got, e);
        let ratio = if e.admits(got) {
            w.ratio().min(1.0)
        } else {
            w.ratio().max(1.0 + f64::EPSILON)
        };
        self.compared.push((i, got, e.value, ratio));
        if e.half_width() >= TELLS_APART {
            self.loose += 1;
        }
        if unchecked(got, e) {
            self.note_unchecked(w);
        }
    }

    /// Count the reference's f64 evaluation `f` against the technique's `t` at camera pixel
    /// `i`, their intervals widened by `tol`: outside where they do not meet, unchecked where
    /// they meet only because they are wide ([`TELLS_APART`] or more apart).
    pub fn compare_reference(&mut self, i: usize, t: &Allowed, f: &Allowed, tol: f64) {
        let camera = self.camera.max(1) as usize;
        let w = Worst {
            pixel: (i % camera, i / camera),
            got: f.value,
            expected: t.value,
            allowance: t.half_width() + f.half_width() + tol,
        };
        let Some((out, max, worst)) = self.reference.as_mut() else { return };
        let diff = (f.value - t.value).abs();
        *max = max.max(diff);
        let met = overlap(t, f, tol);
        if !met {
            *out += 1;
        }
        if worst.is_none_or(|x| w.ratio() > x.ratio()) {
            *worst = Some(w);
        }
        // intervals that meet across a difference of 1/2 or more are together that wide
        if met && diff >= TELLS_APART {
            self.note_unchecked(w);
        }
    }

    fn note_unchecked(&mut self, w: Worst) {
        self.unchecked += 1;
        let diff = |w: &Worst| (w.got - w.expected).abs();
        if self.unchecked_worst.is_none_or(|x| diff(&w) > diff(&x)) {
            self.unchecked_worst = Some(w);
        }
    }

    /// The row's verdict from what it counted: DIFFERS where anything (the visibility, the
    /// reference, a debug output) lies outside its allowance; LOSSY where storage rounding
    /// alone moves the visibility by more than [`sshc::rounding::WARN_ABOVE`] at
    /// [`LOSSY_SHARE`] of the receivers; UNCHECKED where some receiver agrees only under an
    /// allowance too wide to tell lit from shadowed; agrees otherwise.
    pub fn judge(&self) -> Verdict {
        if self.outside > 0 || self.reference.is_some_and(|r| r.0 > 0) || self.debug.iter().any(|d| d.outside > 0) {
            Verdict::Differs
        } else if self.storage > sshc::rounding::WARN_ABOVE {
            Verdict::Lossy
        } else if self.unchecked > 0 {
            Verdict::Unchecked
        } else {
            Verdict::Agrees
        }
    }

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
pub const LOSSY_SHARE: f64 = 0.01;

/// Read back every channel of `slots` after a frame, light (cascade) `light`'s: one decoded
/// map per view.
fn read_given(ex: &Bound, slots: &[GivenSlot], light: usize) -> Result<Given, String> {
    let mut given = Given::default();
    for s in slots {
        let views = (0..s.views)
            .map(|k| {
                let image = ex
                    .inspect()
                    .read_light_texture(light, &s.texture, s.array_layer(k), 0)
                    .map_err(crate::session::rt)?;
                Ok(image.channel(s.component as usize).into_iter().map(|v| s.decode(v)).collect())
            })
            .collect::<Result<Vec<Vec<f64>>, String>>()?;
        given.insert(s.resource, s.channel, views);
    }
    Ok(given)
}

/// The Depth pass's output in `given` (for a reference evaluated from the same maps).
fn depth_views(given: &Given, slots: &[GivenSlot]) -> Vec<Vec<f32>> {
    slots
        .iter()
        .find(|s| !s.geometry)
        .and_then(|s| given.maps(s.resource, s.channel))
        .map(|v| v.iter().map(|m| m.iter().map(|&z| z as f32).collect()).collect())
        .unwrap_or_default()
}

/// Verify `c` (and optionally a reference technique) on each input, under both cameras.
/// `progress` is told each (input, camera) as it starts.
///
/// A depth input replaces the Depth pass's output (every view's, each light sample's view
/// translated); a caster input is rasterised. Either way what the GPU rasterised (the
/// Depth pass's output and Geometry passes') is read back and given to the CPU evaluation,
/// so a technique with Geometry passes is checked from its Geometry outputs on, and needs
/// caster inputs.
pub fn verify(
    gpu: &Gpu,
    c: &sshc::Compiled,
    reference: Option<&sshc::Compiled>,
    inputs: &[Input],
    opts: &Options,
    progress: &mut dyn FnMut(&str, u32),
) -> Result<Vec<Row>, String> {
    let program = Program::new(&c.ir, &c.layout);
    opts.check()?;
    let n = opts.shadow;
    let slots = sshc::interp::given_slots(&program);
    let geometry = slots.iter().find(|s| s.geometry).map(|s| s.pass.clone());
    let per_sample = c.graph.passes.iter().any(|p| p.views == sshc_runtime::graph::Views::PerLightSample);
    let samples = if per_sample { c.graph.samples } else { 0 };
    let reference_program = reference.map(|r| Program::new(&r.ir, &r.layout));
    if let Some(p) = &reference_program
        && let Some(s) = sshc::interp::given_slots(p).into_iter().find(|s| s.geometry)
    {
        return Err(format!(
            "the reference `{}` has a Geometry pass (`{}`): a reference is evaluated from the technique's depth maps alone",
            p.ir.technique, s.pass
        ));
    }
    if opts.cascades > 1 && per_sample {
        return Err(format!(
            "cascades and per-sample techniques do not mix: `{}` renders views from points on a local light, and cascades split the view of a light at infinity",
            c.ir.technique
        ));
    }
    let splits = opts.splits();
    let mut rows = Vec::new();
    let mut loaded = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).map_err(crate::session::rt)?;
    // every cascade's textures are read back: each keeps its own
    loaded.limits.share_light_textures = false;
    for input in inputs {
        if let Source::Depth(depth) = &input.source {
            if let Some(pass) = &geometry {
                return Err(format!(
                    "input `{}` is a depth map, but `{}` rasterises Geometry pass `{pass}` from meshes: give it casters",
                    input.name, c.ir.technique
                ));
            }
            if depth.len() != (n * n) as usize {
                return Err(format!("input `{}` has {} depths, not {n} x {n}", input.name, depth.len()));
            }
        }
        for camera in [2 * n, n / 2] {
            progress(&input.name, camera);
            let plane = QueryPlane {
                shadow: n,
                camera,
                casters: matches!(input.source, Source::Casters(..)),
                ..QueryPlane::new(n, camera)
            };
            let width = opts.light_width as f32;
            let mut depth_maps = None;
            let mut scene = match &input.source {
                Source::Depth(depth) => {
                    let maps = if per_sample {
                        (0..samples)
                            .map(|k| plane.sample_depth(depth, samples, k, opts.light_width))
                            .collect()
                    } else {
                        vec![depth.clone()]
                    };
                    depth_maps = Some(maps);
                    plane.lit_inputs(width)
                }
                Source::Casters(vertices, meshes) => plane.caster_inputs(width, vertices, meshes),
            };
            scene.samples = plane.sample_views(samples, opts.light_width);
            // cascade k's light over the plane (cascade 0 is the plane's own square)
            let planes: Vec<QueryPlane> = (0..opts.cascades).map(|k| plane.cascade(k)).collect();
            let mut ex = if planes.len() > 1 {
                let lights: Vec<_> = planes.iter().map(|p| p.lit_inputs(width).light_inputs()).collect();
                let (eye, forward) = QueryPlane::camera_axis();
                let slices = sshc_runtime::gpu::Slices {
                    eye,
                    forward,
                    splits: splits.clone(),
                    band: opts.cascade_band,
                };
                loaded.bind_cascades(&scene, &lights, &slices)
            } else {
                loaded.bind_scene(&scene)
            }
            .map_err(crate::session::rt)?;
            match &depth_maps {
                Some(maps) => ex.run_frame_with_depth(maps),
                None => ex.run_frame(),
            }
            .map_err(crate::session::rt)?;
            let got = ex
                .inspect()
                .read_camera(CameraOutput::Visibility)
                .map_err(crate::session::rt)?
                .channel(0);
            let positions = ex.inspect().read_camera(CameraOutput::Position).map_err(crate::session::rt)?.rgba;
            let points: Vec<(usize, [f32; 3])> = positions
                .iter()
                .enumerate()
                .filter(|(_, p)| p[..3].iter().all(|c| c.is_finite()))
                .map(|(i, p)| (i, [p[0], p[1], p[2]]))
                .collect();
            // each cascade's evaluations, from what its own passes rasterised
            let mut cascades = Vec::with_capacity(planes.len());
            for (k, &p) in planes.iter().enumerate() {
                let given = read_given(&ex, &slots, k)?;
                let frame = p.frame(opts.light_width);
                // the technique and its reference, each with what f64 rounding allows it
                let pair = reference_program
                    .map(|r| -> Result<_, String> {
                        let theirs = Given::depth(&r, depth_views(&given, &slots));
                        Ok((
                            Evaluation::new(program, &given, frame, Rounding::Exact, Model::F64)?,
                            Evaluation::new(r, &theirs, frame, Rounding::Exact, Model::F64)?,
                        ))
                    })
                    .transpose()?;
                cascades.push(Cascade {
                    plane: p,
                    exact: Evaluation::new(program, &given, frame, Rounding::Exact, Model::Gpu)?,
                    rounded: Evaluation::new(program, &given, frame, Rounding::Stored, Model::Gpu)?,
                    pair,
                });
            }
            let band = opts.cascade_band as f64;
            let evaluated: Vec<_> = points
                .par_iter()
                .map_init(Scratch::default, |scratch, &(i, p)| {
                    let (e, s, f) = evaluate(&cascades, &splits, band, i, p, &scene.samples, scratch);
                    (i, e, s, f)
                })
                .collect();
            let mut row = Row {
                receivers: evaluated.len(),
                compared: Vec::with_capacity(evaluated.len()),
                debug: debug_rows(&ex, &cascades, &points, camera as usize, &scene.samples)?,
                ..Row::new(&input.name, camera, reference_program.is_some())
            };
            for c in &cascades {
                for (name, n) in c.exact.clamped() {
                    match row.clamped.iter_mut().find(|(m, _)| *m == name) {
                        Some((_, total)) => *total += n,
                        None => row.clamped.push((name, n)),
                    }
                }
            }
            let mut allowances = Vec::new();
            let mut storage = Vec::new();
            for &(i, e, s, f) in &evaluated {
                let g = got.get(i).copied().unwrap_or(f32::NAN) as f64;
                row.compare(i, g, &e);
                allowances.push(e.half_width());
                storage.push((s - e.value).abs());
                if let Some((t, f)) = f {
                    row.compare_reference(i, &t, &f, opts.reference_tolerance);
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
            row.verdict = row.judge();
            rows.push(row);
        }
    }
    Ok(rows)
}

/// Every debug output of the build compared at every receiver: each cascade's texture
/// (every cascade's Shade writes its own at every pixel) against that cascade's
/// evaluation, component by component.
fn debug_rows(
    ex: &Bound,
    cascades: &[Cascade],
    points: &[(usize, [f32; 3])],
    camera: usize,
    samples: &[SampleView],
) -> Result<Vec<DebugRow>, String> {
    let Some(first) = cascades.first() else { return Ok(Vec::new()) };
    let mut rows = Vec::new();
    for (d, name) in first.exact.debug_names().into_iter().enumerate() {
        let mut row = DebugRow {
            name: name.to_string(),
            values: 0,
            outside: 0,
            max_diff: 0.0,
            worst: None,
        };
        for (k, c) in cascades.iter().enumerate() {
            let got = ex.inspect().read_debug(k, name).map_err(crate::session::rt)?.rgba;
            let expected: Vec<(usize, Vec<Allowed>)> = points
                .par_iter()
                .map_init(Scratch::default, |scratch, &(i, p)| {
                    (i, c.exact.debug(d, &c.plane.receiver(i, p, samples), scratch))
                })
                .collect();
            for (i, e) in expected {
                let g = got.get(i).copied().unwrap_or([f32::NAN; 4]);
                for (component, e) in e.iter().enumerate() {
                    row.add((i % camera, i / camera), g[component] as f64, e);
                }
            }
        }
        rows.push(row);
    }
    Ok(rows)
}

/// One cascade of the query plane and its evaluations: the technique's (exact and as
/// stored) and, with a reference, both f64 evaluations.
struct Cascade<'p> {
    plane: QueryPlane,
    exact: Evaluation<'p>,
    rounded: Evaluation<'p>,
    pair: Option<(Evaluation<'p>, Evaluation<'p>)>,
}

/// What one cascade gives a receiver: the allowed visibility, the stored-rounding value
/// and the pair's allowed visibilities.
type Evaluated = (Allowed, f64, Option<(Allowed, Allowed)>);

/// The receiver at camera pixel `i` (world position `p`) evaluated as the GPU shades it:
/// one cascade's evaluations, or with several the combining step's mixture
/// (`CASCADES_WGSL` in runtime/src/lights.rs) of the cascade whose slice holds its view
/// distance and the next. The GPU measures that distance in f32, so the allowance is the
/// hull of the mixtures over every distance within its rounding (`D_ROUNDING`), the slices'
/// kinks included: where the band is 0 the mixture jumps at a split, and both sides are
/// allowed there.
fn evaluate(
    cascades: &[Cascade],
    splits: &[f32],
    band: f64,
    i: usize,
    p: [f32; 3],
    samples: &[SampleView],
    scratch: &mut Scratch,
) -> Evaluated {
    let one = |k: usize, scratch: &mut Scratch| -> Evaluated {
        let c = &cascades[k];
        let r = c.plane.receiver(i, p, samples);
        (
            c.exact.visibility(&r, scratch),
            c.rounded.value(&r, scratch),
            c.pair.as_ref().map(|(t, x)| (t.visibility(&r, scratch), x.visibility(&r, scratch))),
        )
    };
    if cascades.len() == 1 {
        return one(0, scratch);
    }
    let (eye, forward) = QueryPlane::camera_axis();
    let d: f64 = (0..3).map(|a| (p[a] as f64 - eye[a] as f64) * forward[a] as f64).sum();
    let last = splits.last().copied().unwrap_or(0.0) as f64;
    let dd = D_ROUNDING * (d.abs() + last);
    let mut seen: [Option<Evaluated>; sshc_runtime::light::MAX_CASCADES as usize] = Default::default();
    let mut at = |k: usize, scratch: &mut Scratch| *seen[k].get_or_insert_with(|| one(k, scratch));
    let (k, t) = cascade_at(d, splits, band);
    let next = (k + 1).min(cascades.len() - 1);
    let (a, b) = (at(k, scratch), at(next, scratch));
    let mut e = mixed(&a.0, &b.0, t);
    // the distances the GPU may have measured: either end of the rounding, and every split
    // and band start between them
    let kinks = splits.windows(2).flat_map(|w| {
        let (near, far) = (w[0] as f64, w[1] as f64);
        [far, far - band * (far - near)]
    });
    for x in [d - dd, d + dd].into_iter().chain(kinks.filter(|x| (x - d).abs() <= dd)) {
        let (k, t) = cascade_at(x, splits, band);
        let next = (k + 1).min(cascades.len() - 1);
        let m = mixed(&at(k, scratch).0, &at(next, scratch).0, t);
        (e.lo, e.hi) = (e.lo.min(m.lo), e.hi.max(m.hi));
    }
    e.allowance = (e.hi - e.value).max(e.value - e.lo);
    let s = a.1 * (1.0 - t) + b.1 * t;
    let f = a.2.zip(b.2).map(|((ta, xa), (tb, xb))| (mixed(&ta, &tb, t), mixed(&xa, &xb, t)));
    (e, s, f)
}

/// The relative rounding of the view distance the combining step measures in f32 (a
/// subtraction and a three-term dot product, each rounding at most 2^-24 of a term no larger
/// than the distance plus the last split), with a factor of 4 to spare.
const D_ROUNDING: f64 = 16.0 * f32::EPSILON as f64 / 2.0;

/// The rounding of WGSL's `mix(a, b, t)` in f32 with a, b in [0, 1] and t itself rounded
/// (a quotient of f32 differences): a few units of 2^-24, four on either side.
const MIX_ROUNDING: f64 = 8.0 * f32::EPSILON as f64 / 2.0;

/// The cascade the combining step takes at view distance `d` and how far it mixes into the
/// next (`CASCADES_WGSL`): the first slice whose far split is at or beyond `d` (the last
/// beyond every split), and the fraction of the band at its far end that `d` has crossed.
fn cascade_at(d: f64, splits: &[f32], band: f64) -> (usize, f64) {
    let n = splits.len().saturating_sub(1).max(1);
    let split = |i: usize| splits.get(i).copied().unwrap_or(f32::MAX) as f64;
    let k = (0..n - 1).find(|&i| d <= split(i + 1)).unwrap_or(n - 1);
    if k + 1 >= n {
        return (k, 0.0);
    }
    let far = split(k + 1);
    let start = far - band * (far - split(k));
    (k, ((d - start) / (far - start).max(1e-30)).clamp(0.0, 1.0))
}

/// Two cascades' allowed values mixed at `t` as the combining step mixes them, with the
/// mixture's f32 rounding.
fn mixed(a: &Allowed, b: &Allowed, t: f64) -> Allowed {
    let m = |x: f64, y: f64| x * (1.0 - t) + y * t;
    let value = m(a.value, b.value);
    let (lo, hi) = (m(a.lo, b.lo) - MIX_ROUNDING, m(a.hi, b.hi) + MIX_ROUNDING);
    Allowed {
        value,
        lo,
        hi,
        raw: value,
        allowance: (hi - value).max(value - lo),
    }
}

/// Whether two evaluations' intervals meet once widened by `tol`.
fn overlap(a: &Allowed, b: &Allowed, tol: f64) -> bool {
    a.lo - tol <= b.hi && b.lo - tol <= a.hi
}

/// How many rows got each verdict.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    pub agree: usize,
    pub unchecked: usize,
    pub differ: usize,
    pub lossy: usize,
}

impl Summary {
    pub fn of(rows: &[Row]) -> Summary {
        let mut s = Summary::default();
        for r in rows {
            *match r.verdict {
                Verdict::Agrees => &mut s.agree,
                Verdict::Unchecked => &mut s.unchecked,
                Verdict::Differs => &mut s.differ,
                Verdict::Lossy => &mut s.lossy,
            } += 1;
        }
        s
    }

    /// The counts in words: `14 agree, 2 UNCHECKED, 0 DIFFER, 0 LOSSY (16 rows)`.
    pub fn counts(&self) -> String {
        format!(
            "{} agree, {} UNCHECKED, {} DIFFER, {} LOSSY ({} rows)",
            self.agree,
            self.unchecked,
            self.differ,
            self.lossy,
            self.agree + self.unchecked + self.differ + self.lossy
        )
    }

    /// The command's last line when nothing fails (DIFFERS, LOSSY): agreement on every
    /// input only where every row agrees; UNCHECKED rows said to be such.
    pub fn line(&self) -> String {
        if self.unchecked == 0 {
            format!("verdict: agrees on every input: {}", self.counts())
        } else {
            format!(
                "verdict: nothing differs, but {} row{} UNCHECKED (an allowance of 1/2 or more admits a GPU value 1/2 or more from the CPU's: lit cannot be told from shadowed there): {}",
                self.unchecked,
                if self.unchecked == 1 { " is" } else { "s are" },
                self.counts()
            )
        }
    }
}

/// What `sshc verify` says after its table of an UNCHECKED row: how many receivers, and the
/// one with the largest difference.
pub fn unchecked_note(r: &Row) -> Option<String> {
    let w = r.unchecked_worst?;
    Some(format!(
        "note: {} (camera {}): UNCHECKED at {} receiver{}: GPU and CPU 1/2 or more apart within an allowance of 1/2 or more, which tells a lit pixel from a shadowed one at none of them; the largest at ({}, {}): {:.6} against {:.6}, allowance {:.3}",
        r.input,
        r.camera,
        r.unchecked,
        if r.unchecked == 1 { "" } else { "s" },
        w.pixel.0,
        w.pixel.1,
        w.got,
        w.expected,
        w.allowance
    ))
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
    let debug: Vec<&str> = rows
        .first()
        .map(|r| r.debug.iter().map(|d| d.name.as_str()).collect())
        .unwrap_or_default();
    if !debug.is_empty() {
        s.push_str("\nDebug outputs, each against its CPU evaluation (every component, every cascade):\n\n| input | camera | output | values | outside | max diff | worst (pixel: got, expected, allowance) |\n|---|---|---|---|---|---|---|\n");
        for r in rows {
            for d in &r.debug {
                let worst = d.worst.map_or("-".into(), |w| {
                    format!(
                        "({}, {}): {:.6}, {:.6}, {:.2e}",
                        w.pixel.0, w.pixel.1, w.got, w.expected, w.allowance
                    )
                });
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {:.2e} | {worst} |",
                    r.input, r.camera, d.name, d.values, d.outside, d.max_diff
                );
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every vertex within the slab above the plane and the light's square (x, z in [-1, 1]).
    fn in_slab(vertices: &[f32]) -> bool {
        vertices
            .chunks(6)
            .all(|v| (CASTER_SLAB.0 - 1e-5..=CASTER_SLAB.1 + 1e-5).contains(&v[1]) && v[0].abs() < 1.0 && v[2].abs() < 1.0)
    }

    /// An allowed value as the Shade's evaluation gives it: `raw -+ allowance`, clamped to
    /// [0, 1] with the value.
    fn allowed(raw: f64, allowance: f64) -> Allowed {
        let value = raw.clamp(0.0, 1.0);
        Allowed {
            value,
            lo: (raw - allowance).clamp(0.0, 1.0),
            hi: (raw + allowance).clamp(0.0, 1.0),
            raw,
            allowance,
        }
    }

    /// Issue 51: GPU 0.040 against CPU 0.967 within an allowance of 0.967 was reported as
    /// agreement. It is UNCHECKED now, counted as such, and no failure; the receivers beside
    /// it, under tight allowances, still decide the rest.
    #[test]
    fn an_allowance_too_wide_to_tell_lit_from_shadowed_leaves_the_row_unchecked() {
        let mut row = Row::new("essm", 64, false);
        row.compare(0, 0.62, &allowed(0.62, 1e-3));
        row.compare(1, 0.040, &allowed(0.967, 0.967));
        assert_eq!(row.outside, 0, "the GPU value lies within the allowance");
        assert_eq!((row.loose, row.unchecked), (1, 1));
        assert_eq!(row.judge(), Verdict::Unchecked);
        let w = row.unchecked_worst.expect("the unchecked receiver");
        assert_eq!((w.pixel, w.got, w.expected), ((1, 0), 0.040, 0.967));
        // a wide allowance whose values are close shows no real difference
        let mut close = Row::new("tie", 64, false);
        close.compare(0, 0.9, &allowed(0.95, 0.95));
        assert_eq!((close.loose, close.unchecked, close.judge()), (1, 0, Verdict::Agrees));
        // just under 1/2 either way: a tight allowance decides, a close value shows nothing
        let mut edge = Row::new("edge", 64, false);
        edge.compare(0, 0.0, &allowed(0.49, 0.49));
        edge.compare(1, 1.0, &allowed(0.501, 0.5));
        assert_eq!((edge.unchecked, edge.judge()), (0, Verdict::Agrees));
        edge.compare(2, 0.0, &allowed(0.5, 0.5));
        assert_eq!((edge.unchecked, edge.judge()), (1, Verdict::Unchecked));
        // outside its allowance: DIFFERS, whatever else
        row.compare(2, 0.5, &allowed(0.62, 1e-3));
        assert_eq!(row.judge(), Verdict::Differs);
        assert!(Verdict::Differs.fails() && Verdict::Lossy.fails() && !Verdict::Unchecked.fails());

        // a reference that meets the technique only because both are wide
        let mut r = Row::new("reference", 16, true);
        r.compare(0, 0.5, &allowed(0.5, 1e-6));
        r.compare_reference(0, &allowed(0.9, 0.6), &allowed(0.1, 0.2), 1e-6);
        assert_eq!((r.reference.map(|x| x.0), r.unchecked, r.judge()), (Some(0), 1, Verdict::Unchecked));

        // the summary counts it, and says no agreement on every input
        let mut agreeing = Row::new("ramp", 64, false);
        agreeing.compare(0, 0.3, &allowed(0.3, 1e-3));
        let rows: Vec<Row> = [row.clone(), close, agreeing, {
            let mut u = Row::new("essm", 16, false);
            u.compare(0, 0.040, &allowed(0.967, 0.967));
            u
        }]
        .into_iter()
        .map(|mut r| {
            r.verdict = r.judge();
            r
        })
        .collect();
        let s = Summary::of(&rows);
        assert_eq!(
            s,
            Summary {
                agree: 2,
                unchecked: 1,
                differ: 1,
                lossy: 0
            }
        );
        assert_eq!(s.counts(), "2 agree, 1 UNCHECKED, 1 DIFFER, 0 LOSSY (4 rows)");
        let only = Summary::of(&rows[1..]);
        assert!(
            only.line().contains("1 row is UNCHECKED") && !only.line().contains("agrees on every input"),
            "{}",
            only.line()
        );
        assert!(Summary::of(&rows[1..3]).line().starts_with("verdict: agrees on every input"));
        let note = unchecked_note(&rows[3]).expect("a note");
        assert!(
            note.contains("essm (camera 16): UNCHECKED at 1 receiver") && note.contains("0.040000 against 0.967000"),
            "{note}"
        );
        assert!(table(&rows).contains("| UNCHECKED |"));
    }

    #[test]
    fn caster_sets_are_closed_boxes_in_the_slab_with_outward_normals() {
        for name in CASTERS {
            let (vertices, meshes) = caster_set(name).expect("a bundled set");
            assert!(in_slab(&vertices), "{name}");
            // one mesh of 12 triangles per box, covering every triangle in order
            assert!(meshes.iter().all(|m| m.end - m.start == 12), "{name}: {meshes:?}");
            assert_eq!(meshes.last().map(|m| m.end), Some((vertices.len() / 18) as u32), "{name}");
            for m in &meshes {
                let tri = |t: u32| &vertices[t as usize * 18..t as usize * 18 + 18];
                let centre = (m.start..m.end)
                    .flat_map(|t| tri(t).chunks(6).map(|v| Vec3::new(v[0], v[1], v[2])).collect::<Vec<_>>())
                    .sum::<Vec3>()
                    / (3.0 * 12.0);
                for t in m.clone() {
                    let v: Vec<Vec3> = tri(t).chunks(6).map(|v| Vec3::new(v[0], v[1], v[2])).collect();
                    let n = Vec3::new(tri(t)[3], tri(t)[4], tri(t)[5]);
                    let face = (v[1] - v[0]).cross(v[2] - v[0]);
                    // counter-clockwise seen from outside, the normal pointing away from the box
                    assert!(
                        face.dot(n) > 0.0 && n.dot((v[0] + v[1] + v[2]) / 3.0 - centre) > 0.0,
                        "{name}: triangle {t}"
                    );
                }
            }
        }
        assert!(caster_set("bogus").is_none());
    }

    #[test]
    fn a_scenes_casters_leave_its_floor_out_and_fit_the_slab() {
        let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/bunny.ron");
        let (vertices, meshes) = scene_casters(&bunny).unwrap_or_else(|e| panic!("{e}"));
        assert!(in_slab(&vertices));
        // the floor (flat and level) is left out: every mesh kept has height
        assert!(!meshes.is_empty());
        for m in &meshes {
            let ys: Vec<f32> = vertices[m.start as usize * 18..m.end as usize * 18]
                .chunks(6)
                .map(|v| v[1])
                .collect();
            let (lo, hi) = ys
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &y| (a.min(y), b.max(y)));
            assert!(hi - lo > 0.1, "a flat mesh was kept: {m:?}, heights {lo}..{hi}");
        }
    }
}
