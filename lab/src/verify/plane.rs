//! The query plane: a receiver tilted under an orthographic light, seen by an orthographic
//! camera; the scene inputs the GPU binds for it (plain, under a lit square, with casters,
//! per light sample) and the frame and receivers the CPU evaluates from.

use crate::scene;
use glam::{Mat4, Vec3};
use sshc::eval::{Frame, Receiver, Seen};
use sshc_runtime::gpu::{SampleView, SceneInputs};

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
