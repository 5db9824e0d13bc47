//! The executor: loads a compiled pass graph (treated as untrusted input) into step nodes,
//! binds a scene, runs frames with GPU timestamps per pass, and reads any texture back.

use crate::device::{Gpu, Result, RuntimeError};
use crate::fit::Fit;
use crate::frame::{Camera, LightInputs, SceneInputs};
use crate::geometry::{Geometry, GeometryBuffers};
use crate::graph::{self, Format, PassGraph, TextureDecl};
use crate::image::{Image, read_back, read_table};
use crate::lights::{Combine, Combining, MAX_LIGHTS, Slices};
use crate::pipeline::mip_count;
use crate::pixels::{HostPixels, PixelsStep};
use crate::receivers::Unshadowed;
use crate::resources::{Resources, f32_bytes, texture_bytes};
use crate::steps::{Group0, StepBinding};
use crate::technique::{MAX_PASSES, Technique};
use crate::timing::{FrameTimes, Timestamps};
use crate::update::{FrameWriter, LightUniforms};
use sshc_light::MAX_CASCADES;
use std::path::Path;

/// How far outside [0, 1] a visibility may lie (rounding of the technique's arithmetic).
pub const VISIBILITY_EPSILON: f32 = 1e-3;

/// Refuses an image of pass `pass` (row-major, `width` per row) where `bad` holds at some
/// pixel: `say` words the first such pixel's value, its `(x, y)` and the count of them.
fn refuse_pixels(
    values: &[f32],
    width: u32,
    pass: &str,
    bad: impl Fn(f32) -> bool,
    say: impl Fn(f32, (usize, usize), usize) -> String,
) -> Result<()> {
    let Some(i) = values.iter().position(|v| bad(*v)) else {
        return Ok(());
    };
    let count = values.iter().filter(|v| bad(**v)).count();
    let w = width.max(1) as usize;
    Err(RuntimeError::Output {
        pass: pass.to_string(),
        message: say(values[i], (i % w, i / w), count),
    })
}

/// Check a visibility image (row-major, `width` per row) that pass `pass` wrote: every value
/// finite and within [0, 1] up to [`VISIBILITY_EPSILON`]; the first bad pixel is named.
pub fn check_visibility(values: &[f32], width: u32, pass: &str) -> Result<()> {
    refuse_pixels(
        values,
        width,
        pass,
        |v| !v.is_finite() || !(-VISIBILITY_EPSILON..=1.0 + VISIBILITY_EPSILON).contains(&v),
        |v, (x, y), count| {
            format!(
                "visibility {v} at pixel ({x}, {y}) ({count} pixel(s) non-finite or outside [0, 1] by more than {VISIBILITY_EPSILON}); the image is refused"
            )
        },
    )
}

/// Refuses a frame where the technique's visibility expression was not a finite number at
/// a receiver facing the light: `flags` is the Shade's normal output's w, 1 there (the
/// visibility written there is finite, so [`check_visibility`] cannot see it).
pub fn check_finite_visibility(flags: &[f32], width: u32, pass: &str) -> Result<()> {
    refuse_pixels(
        flags,
        width,
        pass,
        |f| f > 0.5,
        |_, (x, y), count| {
            format!(
                "the visibility expression is not a finite number (NaN or infinite) at pixel ({x}, {y}) and {} more pixel(s) facing the light (drawn lit where NaN, clamped where infinite); look for a division by zero, or the log or square root of a negative number; the image is refused",
                count - 1
            )
        },
    )
}

/// The camera outputs of the Shade pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraOutput {
    Visibility = 0,
    Color = 1,
    Position = 2,
    Normal = 3,
}

/// A debug output of the Shade pass ([`Executor::debug_outputs`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DebugOutput {
    /// Its name in the technique (`debug: {"name": "..."}`).
    pub name: String,
    /// The camera-sized texture holding it (`debug_<name>`).
    pub texture: String,
    /// Its components: 1 for an f32, 2 to 4 for a vector.
    pub components: usize,
}

/// What a frame generated into one buffer ([`Executor::generated`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Generated {
    /// Records appended (silhouette edges, for the Geometry passes of this runtime).
    pub records: u32,
    /// Vertices the indirect draw drew: `records` times the buffer's `vertices_per_record`.
    pub vertices: u32,
    /// Instances of the indirect draw (1).
    pub instances: u32,
    /// Records the step asked for: `records + dropped`.
    pub claimed: u32,
    /// Records past the buffer's capacity, written nowhere and not drawn: the frame's
    /// silhouettes passed its bound ([`crate::resources::GeneratedLimits`]).
    pub dropped: u32,
}

/// A loaded pass graph, ready to run. It owns its [`Gpu`] handle (a clone: the device,
/// queue and caches are shared), so a host can keep it in its own structs.
///
/// Two paths, kept apart:
/// - **allocation**: [`Executor::bind_scene`] and [`Executor::bind_lights`] create every
///   texture, buffer and bind group at the scene's sizes, and bump [`Executor::generation`];
/// - **per frame**: [`Executor::set_camera`], [`Executor::set_light`] and
///   [`Executor::set_param`] write uniforms only, and [`Executor::encode`] records the
///   passes into the host's encoder. Neither creates a wgpu object (the writer holds the
///   queue and never the device: `update.rs`).
pub struct Executor {
    gpu: Gpu,
    pub graph: PassGraph,
    /// The loaded technique: its pipelines, shared.
    technique: Technique,
    params: Vec<u8>,
    params_buf: Option<wgpu::Buffer>,
    /// The resources of each bound light (one for `bind_scene`; see [`Executor::bind_lights`]).
    bound: Vec<Resources>,
    /// What each step binds on each light's resources: per light, pass, step and view.
    bindings: Vec<Vec<Vec<Vec<StepBinding>>>>,
    /// What each bound light's uniforms were last set from, and the camera.
    lights_state: Vec<LightInputs>,
    /// Each bound light's uniforms as the next frame writes them.
    uniforms: Vec<LightUniforms>,
    /// The params changed since they were last written.
    params_dirty: bool,
    camera: Option<Camera>,
    /// The bound casters' bounding box (world space): the per-frame re-check of a
    /// specialised graph's depth floor ([`Executor::set_light`]).
    caster_bounds: Option<[[f32; 3]; 2]>,
    /// Bumped by every binding (every reallocation).
    generation: u64,
    /// Frames prepared since the last binding.
    frames: u64,
    /// The frame [`Executor::prepare`] began (its counter), its timestamp slot, and whether
    /// it places the instances again.
    frame: u64,
    slot: Option<usize>,
    place: bool,
    /// The bound geometry, shared by every light: a host's ([`Executor::bind_geometry`]) or
    /// a triangle soup's ([`Executor::bind_lights`], through [`Geometry::from_soup`]).
    geometry: Option<GeometryBuffers>,
    /// A host's pixels in place of the deferred Shade's G-buffer raster
    /// ([`Executor::set_host_pixels`]).
    pixels: Option<PixelsStep>,
    /// Several lights: the step that combines their shaded images.
    combine: Option<Combine>,
    /// The draw of the objects that receive no shadow, when the bound draws have some.
    unshadowed: Option<Unshadowed>,
    timestamps: Option<Timestamps>,
    /// Linear depth written into the Depth pass's output instead of rasterising the scene.
    /// One map per view of the Depth pass (a single map serves every view).
    depth_override: Option<Vec<Vec<f32>>>,
    /// Refuse scenes whose textures would take more than this many bytes.
    pub max_bytes: u64,
    /// Bounds on what Geometry passes bind and generate (default: the device's), read at
    /// binding.
    pub generated_limits: crate::resources::GeneratedLimits,
}

impl Executor {
    /// Load `T.graph.ron` and the shader files it names, from the graph's own folder
    /// ([`Technique::load`]).
    pub fn load(gpu: &Gpu, graph_path: &Path) -> Result<Executor> {
        Executor::from_technique(&Technique::load(gpu, graph_path)?)
    }

    /// Build from a graph and its shader sources (as the compiler's API returns them),
    /// checked as a graph file is ([`graph::ValidGraph`], [`Technique::new`]).
    pub fn new(gpu: &Gpu, graph: PassGraph, shaders: Vec<(String, String)>) -> Result<Executor> {
        Executor::from_technique(&Technique::new(gpu, graph::ValidGraph::try_from(graph)?, shaders)?)
    }

    /// Run a loaded technique (shared: its pipelines are not built again).
    pub fn from_technique(technique: &Technique) -> Result<Executor> {
        let graph = technique.graph().clone();
        let gpu = technique.gpu().clone();
        let gpu = &gpu;
        let params = graph.default_params();
        let params_buf = (graph.params_size > 0).then(|| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("params"),
                size: graph.params_size as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let timestamps = Timestamps::new(gpu, graph.passes.iter().map(|p| p.name.clone()).collect(), 1);
        Ok(Executor {
            gpu: gpu.clone(),
            graph,
            technique: technique.clone(),
            params,
            params_buf,
            bound: Vec::new(),
            bindings: Vec::new(),
            lights_state: Vec::new(),
            uniforms: Vec::new(),
            params_dirty: true,
            camera: None,
            caster_bounds: None,
            generation: 0,
            frames: 0,
            frame: 0,
            slot: None,
            place: false,
            geometry: None,
            pixels: None,
            combine: None,
            unshadowed: None,
            timestamps,
            depth_override: None,
            max_bytes: 4 << 30,
            generated_limits: Default::default(),
        })
    }

    /// Set a runtime param (a uniform); fixed params were compiled in and cannot change.
    pub fn set_param(&mut self, name: &str, value: f64) -> Result<()> {
        let p = self
            .graph
            .params
            .iter()
            .find(|p| p.name == name)
            .ok_or_else(|| RuntimeError::Param(format!("the technique has no param `{name}`")))?;
        let Some(off) = p.offset else {
            return Err(RuntimeError::Param(format!(
                "param `{name}` is fixed at compile time; recompile with `--set {name}={value}`"
            )));
        };
        if let Some((lo, hi)) = p.range
            && !(lo..=hi).contains(&value)
        {
            return Err(RuntimeError::Param(format!(
                "param `{name}` = {value} is outside its range [{lo}, {hi}]"
            )));
        }
        let bytes = p.ty.bytes(value);
        self.params[off as usize..off as usize + 4].copy_from_slice(&bytes);
        self.params_dirty = true;
        Ok(())
    }

    /// Create the scene's buffers and every texture at the scene's sizes, then bind every
    /// step node to them.
    pub fn bind_scene(&mut self, s: &SceneInputs) -> Result<()> {
        self.bind_lights(std::slice::from_ref(s))
    }

    /// Bind a scene of several lights: `lights[l]` is the scene with light `l`
    /// alone. Each light gets its own resources (its light-dependent textures, its camera
    /// outputs: memory grows linearly with the lights), every pass runs once per light in
    /// each frame, and a last compute step combines the lights' shaded colours (their mean)
    /// and gathers their visibilities, one channel per light ([`crate::lights`]). At most
    /// [`MAX_LIGHTS`]; every light's camera must have the same size.
    ///
    /// The lights share one scene: their soups must be the same (vertices, meshes, casting
    /// and unshadowed ranges). It is bound as geometry ([`Geometry::from_soup`]: one mesh
    /// and one world-space instance per object, drawn straight from its vertices), uploaded
    /// once with its edge adjacency built once, for every light.
    pub fn bind_lights(&mut self, lights: &[SceneInputs]) -> Result<()> {
        // checked before anything is dropped: a refused set leaves the bound one as it was
        let Some(first) = lights.first() else {
            return self.bind_all(lights);
        };
        let same = |s: &SceneInputs| {
            s.vertices.len() == first.vertices.len()
                && s.vertices.iter().zip(&first.vertices).all(|(a, b)| a.to_bits() == b.to_bits())
                && (&s.meshes, s.casting_vertices, &s.unshadowed) == (&first.meshes, first.casting_vertices, &first.unshadowed)
        };
        if let Some(l) = lights.iter().position(|s| !same(s)) {
            return Err(RuntimeError::Param(format!(
                "light {l}'s scene differs from light 0's (its vertices, meshes, casting or unshadowed ranges): the lights of a frame share one scene"
            )));
        }
        self.bind_soup(first, lights)
    }

    /// Upload `soup`'s vertices as geometry ([`Geometry::from_soup`]) and bind `lights` on it
    /// (their own vertices are not read).
    fn bind_soup(&mut self, soup: &SceneInputs, lights: &[SceneInputs]) -> Result<()> {
        let geometry = Geometry::from_soup(&soup.vertices, &soup.meshes, soup.casting_vertices, &soup.unshadowed)?;
        self.geometry = None;
        self.bound = Vec::new();
        let buffers = crate::resources::scene_buffers(
            &self.gpu,
            &self.graph,
            self.technique.usages().edges,
            soup,
            &geometry,
            self.max_bytes,
        );
        // the soup's copy is freed before the textures are made
        drop(geometry);
        self.geometry = Some(buffers?);
        self.bind_on_geometry(lights)
    }

    /// Bind the cascades of one light at infinity (1 to [`MAX_CASCADES`]): `scene` gives the
    /// geometry (a soup) and camera, uploaded once for every cascade as
    /// [`Executor::bind_lights`] shares one scene; `cascades[i]` is cascade `i`'s light (the
    /// same light, its view fitted by [`crate::light::cascade_views`]); `slices` where they
    /// split the camera's view. Each cascade gets its own resources and runs every pass, as
    /// a light of [`Executor::bind_lights`] does (so one width in texels serves every
    /// cascade: a technique's texel-sized kernels cover less of the world in nearer
    /// cascades); the combining step then takes, per pixel, the cascade of its view
    /// distance, mixed with the next over the last `band` fraction of its slice. The
    /// visibility texture holds it in channel 0 and the cascade (fractional in a band) in
    /// channel 1. One cascade is [`Executor::bind_scene`] with its light.
    pub fn bind_cascades(&mut self, scene: &SceneInputs, cascades: &[LightInputs], slices: &Slices) -> Result<()> {
        let camera = scene.camera();
        self.check_cascades(&camera, cascades, slices)?;
        self.check_floor(&scene.vertices, scene.casting_vertices, cascades)?;
        let inputs: Vec<SceneInputs> = cascades
            .iter()
            .map(|l| SceneInputs::of(&camera, l, scene.camera_size, scene.shadow_size))
            .collect();
        self.bind_soup(scene, &inputs)?;
        self.combine_cascades(slices)
    }

    /// [`Executor::bind_cascades`] on a host's geometry ([`Executor::bind_geometry`]'s
    /// meshes and instances), seen by `camera` at these sizes.
    pub fn bind_geometry_cascades(
        &mut self,
        geometry: &Geometry,
        camera: &Camera,
        cascades: &[LightInputs],
        camera_size: (u32, u32),
        shadow_size: u32,
        slices: &Slices,
    ) -> Result<()> {
        self.check_cascades(camera, cascades, slices)?;
        self.bind_geometry(geometry, camera, cascades, camera_size, shadow_size)?;
        self.combine_cascades(slices)
    }

    /// Refuse cascades that cannot be bound: a count outside 1 to [`MAX_CASCADES`], slices
    /// they cannot take ([`Slices::check`]), lights that are not one light at infinity, a
    /// camera or a light whose values the per-frame calls would refuse.
    fn check_cascades(&self, camera: &Camera, cascades: &[LightInputs], slices: &Slices) -> Result<()> {
        let n = cascades.len();
        if !(1..=MAX_CASCADES as usize).contains(&n) {
            return Err(RuntimeError::Param(format!("{n} cascades: a light has 1 to {MAX_CASCADES}")));
        }
        slices.check(n)?;
        if let Some(s) = cascades.iter().find(|s| s.position != cascades[0].position || s.position[3] != 0.0) {
            return Err(RuntimeError::Param(format!(
                "cascades are views of one light at infinity: light position or direction {:?} against {:?}",
                s.position, cascades[0].position
            )));
        }
        camera.check()?;
        for (l, light) in cascades.iter().enumerate() {
            light.check(l)?;
        }
        Ok(())
    }

    /// After the cascades' lights are bound: the combining step that selects among them.
    fn combine_cascades(&mut self, slices: &Slices) -> Result<()> {
        let n = self.bound.len();
        if n > 1 {
            let camera = self.bound[0].camera_size;
            let position = &self.bound[0].camera[CameraOutput::Position as usize];
            let mode = Combining::Cascades(slices.clone());
            self.combine = Some(Combine::new(&self.gpu, camera, n, &mode, position)?);
        }
        Ok(())
    }

    /// Refit the bound cascades for a frame whose camera moved: each cascade's light
    /// (`lights[i]`, its view fitted to its new slice), the camera and the slices, all
    /// checked as [`Executor::bind_cascades`] checks them (the same count; the band may
    /// change). Uniforms are written, nothing is created, nothing waits: the next frame
    /// renders as a fresh binding of these cascades would.
    pub fn set_cascades(&mut self, lights: &[LightInputs], camera: &Camera, slices: &Slices) -> Result<()> {
        let n = self.bound.len();
        if self.cascades() < 2 {
            return Err(RuntimeError::NotFound(
                "no cascades are bound (bind_cascades with 2 or more)".into(),
            ));
        }
        if lights.len() != n {
            return Err(RuntimeError::Param(format!(
                "{} cascade light(s) for the {n} bound cascades",
                lights.len()
            )));
        }
        // every value checked before anything is written
        self.check_cascades(camera, lights, slices)?;
        self.set_camera(camera)?;
        for (l, light) in lights.iter().enumerate() {
            self.set_light(l, light)?;
        }
        if let Some(c) = &self.combine {
            c.set_slices(&self.gpu.queue, slices);
        }
        Ok(())
    }

    /// Bind a host's geometry ([`Geometry`]: indexed meshes uploaded once, instances with
    /// transforms) seen by `camera` under `lights` (1 to [`MAX_LIGHTS`]), at these sizes.
    /// Per frame, [`Executor::set_transforms`] moves the instances, without reallocation.
    /// For a graph with Geometry passes, each mesh's edge adjacency is built once, in object
    /// space, and placed with its instances.
    pub fn bind_geometry(
        &mut self,
        geometry: &Geometry,
        camera: &Camera,
        lights: &[LightInputs],
        camera_size: (u32, u32),
        shadow_size: u32,
    ) -> Result<()> {
        camera.check()?;
        for (l, light) in lights.iter().enumerate() {
            light.check(l)?;
        }
        // the exact check of a specialised graph's depth floor, on the placed casters
        if self.graph.specialised.as_ref().is_some_and(|f| f.depth_floor.is_some()) {
            let (soup, casting) = geometry.soup()?;
            self.check_floor(&soup, Some(casting), lights)?;
        }
        let inputs: Vec<SceneInputs> = lights
            .iter()
            .map(|l| SceneInputs::of(camera, l, camera_size, shadow_size))
            .collect();
        let Some(first) = inputs.first() else {
            return self.bind_all(&inputs);
        };
        self.geometry = None;
        self.bound = Vec::new();
        self.geometry = Some(crate::resources::scene_buffers(
            &self.gpu,
            &self.graph,
            self.technique.usages().edges,
            first,
            geometry,
            self.max_bytes,
        )?);
        self.bind_on_geometry(&inputs)
    }

    /// A specialised graph's depth floor, checked exactly on the casters of `soup` (world
    /// position and normal per vertex; the first `casting` vertices cast) under each light.
    fn check_floor(&self, soup: &[f32], casting: Option<u32>, lights: &[LightInputs]) -> Result<()> {
        let Some((facts, floor)) = self.graph.specialised.as_ref().and_then(|f| Some((f, f.depth_floor?))) else {
            return Ok(());
        };
        for (l, light) in lights.iter().enumerate() {
            if let Some(here) = graph::caster_depth_floor(soup, casting, &light.view, light.near, light.far)
                && here < floor
            {
                return Err(RuntimeError::Param(format!(
                    "technique `{}` was specialised for scene {}, whose casters lie at normalised depth {floor} or more in the light's view, but under light {l} these come to {here}; compile it for this scene (`--scene`) or without one",
                    self.graph.technique, facts.scene,
                )));
            }
        }
        Ok(())
    }

    /// Bind `lights` on the geometry just uploaded; a refusal drops it (nothing is bound).
    fn bind_on_geometry(&mut self, lights: &[SceneInputs]) -> Result<()> {
        let bound = self.bind_all(lights);
        if bound.is_err() {
            self.geometry = None;
        }
        bound?;
        self.caster_bounds = self.geometry.as_ref().and_then(|g| g.caster_bounds_at(&g.transforms));
        Ok(())
    }

    /// Set every instance's transform (column-major, one per instance of the bound
    /// geometry, each finite, affine and invertible): the placement records are written and
    /// the next frame places the instances again; nothing is allocated. A specialised
    /// graph's depth floor is re-checked from the casters' bounding box, as
    /// [`Executor::set_light`] does.
    pub fn set_transforms(&mut self, transforms: &[[f32; 16]]) -> Result<()> {
        let Some(g) = &self.geometry else {
            return Err(RuntimeError::NotFound("no geometry is bound: call bind_geometry first".into()));
        };
        // everything checked before anything is written: a refused set changes nothing
        g.check_transforms(transforms)?;
        let bounds = g.caster_bounds_at(transforms);
        for (l, light) in self.lights_state.iter().enumerate() {
            self.check_floor_from_bounds(l, light, bounds)?;
        }
        if let Some(g) = &mut self.geometry {
            g.write_transforms(&self.gpu.queue, transforms);
        }
        self.caster_bounds = bounds;
        Ok(())
    }

    /// A specialised graph's depth floor, re-checked for light `l` from the casters'
    /// bounding box: its corners' least depth is a lower bound of the triangles', so a
    /// state the bounds pass cannot break the specialisation; one they fail is refused.
    fn check_floor_from_bounds(&self, l: usize, light: &LightInputs, bounds: Option<[[f32; 3]; 2]>) -> Result<()> {
        let (Some(facts), Some(bounds)) = (&self.graph.specialised, bounds) else {
            return Ok(());
        };
        let Some(floor) = facts.depth_floor else { return Ok(()) };
        // on the stack: this runs on every `set_light` and `set_transforms`
        let mut corners = [0.0f32; 48];
        for (i, v) in corners.chunks_exact_mut(6).enumerate() {
            for axis in 0..3 {
                v[axis] = bounds[(i >> axis) & 1][axis];
            }
        }
        match graph::caster_depth_floor(&corners, None, &light.view, light.near, light.far) {
            Some(here) if here < floor => Err(RuntimeError::Param(format!(
                "technique `{}` was specialised for scene {}, whose casters lie at normalised depth {floor} or more in the light's view; under light {l} as set, the casters' bounding box reaches {here}, so the specialisation may not hold; bind again (binding checks the triangles themselves) or compile without `--scene`",
                self.graph.technique, facts.scene,
            ))),
            Some(_) | None => Ok(()),
        }
    }

    /// Shade the host's pixels ([`HostPixels`]: world position and normal textures at the
    /// camera's size) instead of rasterising the scene from the camera: the deferred
    /// Shade's G-buffer is written from them by a step of the runtime's
    /// (`runtime/src/pixels.rs`, where the tolerance of the derived depth slope and
    /// footprint is stated). `None` rasterises again. Given after binding, and again after
    /// every binding (the textures are bound to the G-buffers it made). Refused for a graph
    /// whose Shade runs forward, with the reason; the textures' formats, sizes and usages
    /// are checked.
    pub fn set_host_pixels(&mut self, pixels: Option<HostPixels>) -> Result<()> {
        self.pixels = None;
        let Some(pixels) = pixels else { return Ok(()) };
        self.bound()?;
        if !self.technique.usages().gbuffer {
            let shade = self.shade_name().to_string();
            return Err(RuntimeError::Unsupported {
                pass: shade,
                feature: format!(
                    "host pixels, which need the deferred Shade (G-buffer, then compute); technique `{}` shades forward. Compile its Shade pass with the compute schedule (`--schedule SHADE=compute`); a Shade that reads a light sample's depth slope or an implicit-level lookup in a sample's view cannot run deferred, and the compiler says so",
                    self.graph.technique
                ),
            });
        }
        self.pixels = Some(PixelsStep::new(&self.gpu, &pixels, &self.bound)?);
        Ok(())
    }

    /// Bind `lights` on the bound geometry.
    fn bind_all(&mut self, lights: &[SceneInputs]) -> Result<()> {
        let gpu = self.gpu.clone();
        self.pixels = None;
        self.bound = Vec::new();
        self.bindings = Vec::new();
        self.lights_state = Vec::new();
        self.combine = None;
        self.unshadowed = None;
        if lights.is_empty() || lights.len() > MAX_LIGHTS {
            return Err(RuntimeError::Param(format!(
                "{} light(s) bound: a frame combines 1 to {MAX_LIGHTS} lights (their visibilities share one RGBA texel a pixel)",
                lights.len()
            )));
        }
        if let Some(s) = lights.iter().find(|s| s.camera_size != lights[0].camera_size) {
            return Err(RuntimeError::Param(format!(
                "the lights' cameras differ ({} x {} against {} x {}): lights are combined pixel by pixel",
                s.camera_size.0, s.camera_size.1, lights[0].camera_size.0, lights[0].camera_size.1
            )));
        }
        // one timestamp pair per pass and light, in one query set
        let steps = self.graph.passes.len() * lights.len();
        if steps > MAX_PASSES {
            return Err(RuntimeError::Limit {
                what: format!(
                    "technique `{}`: passes times lights (two GPU timestamps each, one query set)",
                    self.graph.technique
                ),
                needed: steps as u64,
                limit: MAX_PASSES as u64,
            });
        }
        let mut used = 0u64;
        let (mut bound, mut bindings) = (Vec::new(), Vec::new());
        for (l, s) in lights.iter().enumerate() {
            let res = self.bind_light(s, l, self.max_bytes.saturating_sub(used))?;
            used += self.light_bytes(&res);
            bindings.push(self.bind_steps(&res)?);
            bound.push(res);
        }
        if lights.len() > 1 {
            let camera = lights[0].camera_size;
            let need = used.saturating_add(Combine::bytes(camera, lights.len()));
            if need > self.max_bytes {
                return Err(RuntimeError::Limit {
                    what: format!("textures of {} lights at this scene's sizes (bytes)", lights.len()),
                    needed: need,
                    limit: self.max_bytes,
                });
            }
            let position = &bound[0].camera[CameraOutput::Position as usize];
            self.combine = Some(Combine::new(&gpu, camera, lights.len(), &Combining::Lights, position)?);
        }
        self.timestamps = Timestamps::new(&gpu, self.technique.passes().iter().map(|p| p.name.clone()).collect(), lights.len());
        self.unshadowed = Unshadowed::new(&gpu, &bound)?;
        self.bound = bound;
        self.bindings = bindings;
        self.lights_state = lights.iter().map(SceneInputs::light_inputs).collect();
        // binding wrote every uniform: nothing is pending
        self.uniforms = lights
            .iter()
            .map(|s| LightUniforms::new(&s.camera(), &s.light_inputs(), s.shadow_size, true))
            .collect();
        self.camera = Some(lights[0].camera());
        self.generation += 1;
        self.frames = 0;
        Ok(())
    }

    /// Bumped by every binding: every time the textures, buffers and bind groups were
    /// created again, so that a host knows its views of them ([`Executor::visibility`])
    /// changed. The per-frame calls never bump it.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Set the camera of every bound light: their `Frame` uniforms change (written by the
    /// next [`Executor::encode`]), nothing else. Its size is the bound one (a new size is a
    /// new binding).
    pub fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        camera.check()?;
        self.bound()?;
        for ((res, light), u) in self.bound.iter().zip(&self.lights_state).zip(&mut self.uniforms) {
            u.set_camera(camera, light, res.shadow_size);
        }
        self.camera = Some(*camera);
        Ok(())
    }

    /// Set bound light `l`: its `Frame` and `LightSamples` uniforms change (written by the
    /// next [`Executor::encode`]), nothing else.
    /// Its number of samples is the bound one (a new number is a new binding). A graph
    /// specialised for a scene is re-checked here from the casters' bounding box: its
    /// corners' least depth is a lower bound of the triangles', so a light the bounds
    /// pass cannot break the specialisation; one they fail is refused (binding again runs
    /// the exact check on the triangles).
    pub fn set_light(&mut self, l: usize, light: &LightInputs) -> Result<()> {
        light.check(l)?;
        let (Some(res), Some(camera)) = (self.bound.get(l), self.camera) else {
            return Err(RuntimeError::NotFound(format!(
                "light {l} is not bound ({} light(s) are)",
                self.bound.len()
            )));
        };
        if light.samples.len() != res.samples as usize {
            return Err(RuntimeError::Param(format!(
                "light {l} has {} sample view(s), the bound one {}: a new number of samples is a new binding (`bind_lights`)",
                light.samples.len(),
                res.samples
            )));
        }
        self.check_light_kind(l, light.kind)?;
        self.check_floor_from_bounds(l, light, self.caster_bounds)?;
        // in place: nothing is allocated once the light's samples are bound
        self.uniforms[l].set(&camera, light, res.shadow_size, false);
        self.lights_state[l].assign(light);
        Ok(())
    }

    /// Set bound light `l` from what a host knows of it ([`Light`]: kind, position or
    /// direction, size), its view fitted by the runtime to the bound geometry's instances
    /// under their current transforms ([`LightInputs::fit`] of [`Geometry::boxes`]), with
    /// the bound number of sample views. Then as [`Executor::set_light`]: uniforms only.
    /// Over a bound triangle soup, the instances are its objects ([`Geometry::from_soup`]).
    pub fn place_light(&mut self, l: usize, light: &crate::light::Light, fit: Fit) -> Result<()> {
        let (Some(g), Some(res)) = (&self.geometry, self.bound.get(l)) else {
            return Err(RuntimeError::NotFound(match self.geometry {
                None => {
                    "no geometry is bound: place_light fits the light to the bound instances (bind_geometry or bind_scene first)".into()
                }
                Some(_) => format!("light {l} is not bound ({} light(s) are)", self.bound.len()),
            }));
        };
        let inputs = LightInputs::fit(light, g.boxes(), fit, res.shadow_size, res.samples)?;
        self.set_light(l, &inputs)
    }

    /// A graph specialised for a scene's light kind folded inputs another kind needs: light
    /// `l` must be of that kind.
    fn check_light_kind(&self, l: usize, kind: Option<graph::LightKind>) -> Result<()> {
        match &self.graph.specialised {
            Some(facts) if kind != Some(facts.light) => Err(RuntimeError::Param(format!(
                "technique `{}` was specialised for the {} light of scene {}, but this scene's light{} is {}; compile it for this scene (`--scene`) or without one",
                self.graph.technique,
                facts.light.name(),
                facts.scene,
                if l > 0 { format!(" {l}") } else { String::new() },
                kind.map_or("not given (`SceneInputs::light`, `LightInputs::kind`)", |k| k.name())
            ))),
            Some(_) | None => Ok(()),
        }
    }

    /// Create light `l`'s resources and bind every step node to them.
    fn bind_light(&mut self, s: &SceneInputs, l: usize, max_bytes: u64) -> Result<Resources> {
        let gpu = self.gpu.clone();
        let gpu = &gpu;
        self.check_light_kind(l, s.light)?;
        // and narrowed the range of what its Depth pass writes to the casters' least depth
        if let Some(facts) = &self.graph.specialised
            && let Some(floor) = facts.depth_floor
            && let Some(here) = graph::caster_depth_floor(&s.vertices, s.casting_vertices, &s.light_view, s.near, s.far)
            && here < floor
        {
            return Err(RuntimeError::Param(format!(
                "technique `{}` was specialised for scene {}, whose casters lie at normalised depth {floor} or more in the light's view, but this scene's{} come to {here}; compile it for this scene (`--scene`) or without one",
                self.graph.technique,
                facts.scene,
                if l > 0 { format!(" (light {l})") } else { String::new() },
            )));
        }
        let scene = self
            .geometry
            .as_ref()
            .map(|g| &g.scene)
            .ok_or_else(|| RuntimeError::NotFound("no scene geometry: bind_scene, bind_lights or bind_geometry".into()))?;
        let res = Resources::new(
            gpu,
            &self.graph,
            self.technique.usages(),
            s,
            scene,
            max_bytes,
            self.generated_limits,
        )?;
        if self.graph.passes.iter().any(|p| p.views == graph::Views::PerLightSample) && s.samples.len() != self.graph.samples as usize {
            return Err(RuntimeError::Param(format!(
                "technique `{}` renders {} light-sample view(s), but the scene gives {} (`SceneInputs::samples`)",
                self.graph.technique,
                self.graph.samples,
                s.samples.len()
            )));
        }
        Ok(res)
    }

    /// What every step binds on one light's resources.
    fn bind_steps(&self, res: &Resources) -> Result<Vec<Vec<Vec<StepBinding>>>> {
        let shared = Group0 {
            frame: &res.frame,
            sample_frames: &res.sample_frames,
            light_samples: &res.light_samples,
            params: self.params_buf.as_ref(),
            sampler: self.technique.sampler(),
        };
        let gpu = &self.gpu;
        gpu.scoped("binding the passes to the scene", || -> Result<Vec<Vec<Vec<StepBinding>>>> {
            self.technique
                .passes()
                .iter()
                .map(|p| p.steps.iter().map(|node| node.bind(gpu, res, &shared)).collect())
                .collect()
        })?
    }

    /// A new camera size (a window resized): only what depends on it is created again:
    /// each light's camera-sized targets (the camera outputs and depth, a deferred Shade's
    /// G-buffer, camera-sized debug outputs), the lights' combination, and the step
    /// bindings over them. The geometry, its edge adjacency, the shadow-map-sized textures
    /// and tables, the uniforms, the pipelines and the timestamps stay; the camera, lights
    /// and params stay as set. Bumps [`Executor::generation`] (the host's views of the
    /// visibility changed); host pixels are given again, as after a binding. Refused, with
    /// nothing changed, for a size the device or [`Executor::max_bytes`] cannot take.
    pub fn resize(&mut self, camera_size: (u32, u32)) -> Result<()> {
        let shadow_size = self.bound()?.shadow_size;
        if self.bound[0].camera_size == camera_size {
            return Ok(());
        }
        let lights = self.bound.len();
        // every light's textures and the combination, checked before anything is created
        let per_light: u64 = self.graph.textures.iter().map(|t| texture_bytes(t, shadow_size, camera_size)).sum();
        let need = (per_light * lights as u64).saturating_add(if lights > 1 { Combine::bytes(camera_size, lights) } else { 0 });
        if need > self.max_bytes {
            return Err(RuntimeError::Limit {
                what: format!("textures of {lights} light(s) at this camera size (bytes)"),
                needed: need,
                limit: self.max_bytes,
            });
        }
        self.pixels = None;
        let resized = self.resize_targets(camera_size);
        if resized.is_err() {
            // a failure past the checks (out of memory): nothing half-resized stays bound
            self.bound = Vec::new();
            self.combine = None;
            self.unshadowed = None;
        }
        resized?;
        self.generation += 1;
        Ok(())
    }

    fn resize_targets(&mut self, camera_size: (u32, u32)) -> Result<()> {
        let technique = self.technique.clone();
        for res in &mut self.bound {
            res.resize_camera(&self.gpu, &self.graph, technique.usages(), camera_size, self.max_bytes)?;
        }
        for l in 0..self.bound.len() {
            self.bindings[l] = self.bind_steps(&self.bound[l])?;
        }
        if let Some(c) = &mut self.combine {
            c.resize(&self.gpu, camera_size, &self.bound[0].camera[CameraOutput::Position as usize])?;
        }
        if let Some(u) = &mut self.unshadowed {
            u.resize(&self.bound);
        }
        Ok(())
    }

    /// Bytes of the graph's textures on one light's resources ([`Executor::memory`]).
    fn light_bytes(&self, res: &Resources) -> u64 {
        self.texture_bytes(res).iter().map(|t| t.1).sum()
    }

    fn bound(&self) -> Result<&Resources> {
        self.bound
            .first()
            .ok_or_else(|| RuntimeError::NotFound(crate::error::NOTHING_BOUND.into()))
    }

    /// Cascades bound ([`Executor::bind_cascades`] with 2 or more); 1 otherwise.
    pub fn cascades(&self) -> usize {
        if self.combine.as_ref().is_some_and(|c| c.cascades) {
            self.bound.len()
        } else {
            1
        }
    }

    /// Lights bound ([`Executor::bind_lights`]); 0 before a scene is bound.
    pub fn lights(&self) -> usize {
        self.bound.len()
    }

    /// Replace the Depth pass: its output takes these linear depths (row-major, row 0 first,
    /// `shadow_size`^2 values) instead of the scene rasterised from the light. For feeding
    /// synthetic depth fields to the passes after Depth; `None` rasterises again.
    pub fn set_depth_override(&mut self, depth: Option<Vec<f32>>) {
        self.depth_override = depth.map(|d| vec![d]);
    }

    /// [`Executor::set_depth_override`] with one map per view of a per-sample Depth pass
    /// (`views: PerLightSample`), in sample order; a single map serves every view.
    pub fn set_depth_override_views(&mut self, views: Option<Vec<Vec<f32>>>) {
        self.depth_override = views;
    }

    /// Upload the depth override of view `view` into the Depth pass's output.
    fn write_depth_override(&self, b: &Resources, pass: &graph::PassDecl, depth: &[f32], view: u32) -> Result<()> {
        let n = b.shadow_size as usize;
        if depth.len() != n * n {
            return Err(RuntimeError::Param(format!(
                "depth override has {} values, the shadow map {n} x {n}",
                depth.len()
            )));
        }
        let target = pass
            .steps
            .first()
            .and_then(|s| s.writes.first())
            .ok_or_else(|| RuntimeError::NotFound(format!("Depth pass `{}` writes nothing", pass.name)))?;
        let decl = self
            .graph
            .texture(&target.texture)
            .ok_or_else(|| RuntimeError::NotFound(format!("no texture `{}`", target.texture)))?;
        if decl.format != Format::R32Float {
            return Err(RuntimeError::Param(format!(
                "the Depth pass writes {:?}; a depth override needs R32Float",
                decl.format
            )));
        }
        let tex = b.texture(&target.texture)?;
        self.gpu.scoped("writing the depth override", || {
            self.gpu.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: tex,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: view * decl.layers + target.layer,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                &f32_bytes(depth),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(4 * n as u32),
                    rows_per_image: Some(n as u32),
                },
                wgpu::Extent3d {
                    width: n as u32,
                    height: n as u32,
                    depth_or_array_layers: 1,
                },
            )
        })
    }

    /// Record one frame into the host's `encoder`: [`Executor::prepare`], then
    /// [`Executor::record`].
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        self.prepare()?;
        self.record(encoder)
    }

    /// Begin a frame: write what changed since the last one (the params, each light's
    /// uniforms with the frame's counter, the cascades' slices) through the queue, take the
    /// frame's timestamp slot, and note whether the instances are placed again. Queue
    /// writes only: no encoder, nothing created, nothing waits. wgpu applies the writes at
    /// the next submission, before its command buffers.
    pub fn prepare(&mut self) -> Result<()> {
        self.bound()?;
        if let Some(t) = &mut self.timestamps {
            // the host's submissions fire the mapping callbacks: no poll here
            t.collect(&self.gpu, false)?;
        }
        let writer = FrameWriter::new(&self.gpu.queue);
        if let Some(buf) = &self.params_buf
            && self.params_dirty
        {
            writer.params(buf, &self.params);
            self.params_dirty = false;
        }
        self.frame = self.frames;
        self.frames += 1;
        for (res, u) in self.bound.iter().zip(&mut self.uniforms) {
            writer.light(res, u, self.frame as u32);
        }
        // a host geometry's instances, placed again after their transforms changed
        self.place = self.geometry.as_mut().is_some_and(GeometryBuffers::take_due);
        self.slot = self.timestamps.as_mut().and_then(|t| t.begin(self.frame));
        if let Some(maps) = &self.depth_override {
            self.write_depth_overrides(maps)?;
        }
        Ok(())
    }

    /// Record the frame [`Executor::prepare`] began into the host's `encoder`: every pass
    /// once for each bound light, then the lights' combination. Encoder commands only
    /// (nothing written through the queue, nothing created, nothing waits), from `&self`:
    /// a host may record the prepared frame more than once in a submission (several
    /// encoders, a frame recorded again), and every recording sees the same uniforms. The
    /// host submits; the visibility ([`Executor::visibility`]) holds the frame's result
    /// once the submission completes. The GPU times go into a ring of query sets and come
    /// back a frame or more later ([`Executor::frame_times`]). Validation errors of the
    /// recording surface where the host finishes its encoder.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        self.bound()?;
        if self.frames == 0 {
            return Err(RuntimeError::NotFound(
                "no frame was prepared: call prepare (queue writes), then record (encoder commands)".into(),
            ));
        }
        if let (true, Some(g)) = (self.place, &self.geometry) {
            g.record(encoder);
        }
        let slot = self.slot;
        for (l, res) in self.bound.iter().enumerate() {
            for (pi, pass) in self.technique.passes().iter().enumerate() {
                if pass.kind == graph::PassKind::Depth && self.depth_override.is_some() {
                    // written by `prepare` in its place
                    continue;
                }
                // The pass's first render or compute pass writes its start, the last its
                // end. A per-sample pass records all its steps for one view, then the next.
                let views = pass.steps.iter().map(|n| n.views()).max().unwrap_or(1);
                let Some(bindings) = self.bindings.get(l).and_then(|b| b.get(pi)) else {
                    return Err(RuntimeError::NotFound(crate::error::NOTHING_BOUND.into()));
                };
                let recording = || {
                    (0..views).flat_map(move |v| {
                        pass.steps
                            .iter()
                            .zip(bindings)
                            .filter_map(move |(n, b)| Some((n, b.get(v as usize).filter(|b| b.passes() > 0)?, v)))
                    })
                };
                let last = recording().count().saturating_sub(1);
                for (i, (node, bound, view)) in recording().enumerate() {
                    let stamps = match (&self.timestamps, slot) {
                        (Some(t), Some(slot)) => Some(t.stamps(slot, l, pi, i == 0, i == last)),
                        _ => None,
                    };
                    match &self.pixels {
                        // the host's pixels in place of the G-buffer raster
                        Some(p) if node.draws_gbuffer() => p.record(encoder, l, stamps),
                        Some(_) | None => node.record(encoder, bound, res, stamps, view)?,
                    }
                }
            }
            // the objects that receive no shadow, over this light's camera depth (none is
            // rasterised from a host's pixels: the host's pass applies its own rule)
            if let (Some(u), None) = (&self.unshadowed, &self.pixels) {
                u.record(encoder, l, res);
            }
        }
        if let Some(c) = &self.combine {
            c.record(encoder, &self.bound);
        }
        if let (Some(t), Some(slot)) = (&self.timestamps, slot) {
            t.finish(encoder, slot);
        }
        Ok(())
    }

    /// Write the depth override of every light's Depth pass (each of its views).
    fn write_depth_overrides(&self, maps: &[Vec<f32>]) -> Result<()> {
        for res in &self.bound {
            for decl in self.graph.passes.iter().filter(|p| p.kind == graph::PassKind::Depth) {
                let views = if decl.views == graph::Views::PerLightSample {
                    self.graph.samples
                } else {
                    1
                };
                if maps.len() != 1 && maps.len() != views as usize {
                    return Err(RuntimeError::Param(format!(
                        "depth override has {} maps, the Depth pass `{}` {views} view(s)",
                        maps.len(),
                        decl.name
                    )));
                }
                for view in 0..views {
                    let depth = &maps[(view as usize).min(maps.len() - 1)];
                    self.write_depth_override(res, decl, depth, view)?;
                }
            }
        }
        Ok(())
    }

    /// The newest frame whose GPU times have come back (its number, counted from the
    /// binding, and its times), without waiting: `None` before any has, or without
    /// timestamp queries.
    pub fn frame_times(&mut self) -> Result<Option<(u64, FrameTimes)>> {
        let Some(t) = &mut self.timestamps else { return Ok(None) };
        t.collect(&self.gpu, true)?;
        Ok(t.latest().cloned())
    }

    /// Frames recorded since the last binding.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Run every pass once, for each bound light, then combine the lights: [`Executor::encode`]
    /// into an encoder of its own, submitted, then wait for the frame's GPU times (the
    /// lab's path; a host records into its own frame instead). Returns the GPU time of
    /// each pass (summed over the lights) and of each light when timestamps are available.
    pub fn run_frame(&mut self) -> Result<FrameTimes> {
        let gpu = self.gpu.clone();
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        gpu.scoped("recording the frame", || self.encode(&mut encoder))??;
        let frame = self.frames - 1;
        gpu.scoped("submitting the frame", || gpu.queue.submit([encoder.finish()]))?;
        let names: Vec<String> = self.technique.passes().iter().map(|p| p.name.clone()).collect();
        let Some(t) = &mut self.timestamps else {
            return Ok(FrameTimes::untimed(&names, self.bound.len()));
        };
        // map this frame's slot, wait for the device, and take its times
        t.collect(&gpu, false)?;
        gpu.wait()?;
        t.collect(&gpu, false)?;
        Ok(match t.latest() {
            Some((f, times)) if *f == frame => times.clone(),
            // the slot was still pending (frames encoded by the host without waiting)
            _ => FrameTimes::untimed(&names, self.bound.len()),
        })
    }

    /// Read one layer and mip level of a texture of the graph (light 0's, with several).
    pub fn read_texture(&self, name: &str, layer: u32, level: u32) -> Result<Image> {
        self.read_light_texture(0, name, layer, level)
    }

    /// [`Executor::read_texture`] of light (or cascade) `light`'s resources.
    pub fn read_light_texture(&self, light: usize, name: &str, layer: u32, level: u32) -> Result<Image> {
        self.bound()?;
        let b = self
            .bound
            .get(light)
            .ok_or_else(|| RuntimeError::NotFound(format!("light {light} is not bound ({} light(s) are)", self.bound.len())))?;
        let decl = self
            .graph
            .texture(name)
            .ok_or_else(|| RuntimeError::NotFound(format!("no texture `{name}`")))?;
        if layer >= decl.array_layers() {
            return Err(RuntimeError::NotFound(format!(
                "texture `{name}` has {} layer(s), not {}",
                decl.array_layers(),
                layer + 1
            )));
        }
        let levels = if decl.mips { mip_count(b.shadow_size) } else { 1 };
        if level >= levels {
            return Err(RuntimeError::NotFound(format!(
                "texture `{name}` has {levels} level(s), not {}",
                level + 1
            )));
        }
        let size = (b.shadow_size >> level).max(1);
        if decl.format.is_table() {
            return read_table(&self.gpu, b.table(name)?, decl.format, layer, size);
        }
        let (w, h) = match decl.extent {
            graph::Extent::ShadowMap => (size, size),
            graph::Extent::Camera => b.camera_size,
        };
        read_back(&self.gpu, b.texture(name)?, layer, level, w, h, decl.format)
    }

    /// The Shade's debug outputs this graph writes (compiled with `CompileOptions::debug`):
    /// each one's name (`debug: {"name": ...}` in the technique), its texture
    /// (`debug_<name>`) and its components (1 to 4). Empty for a graph without them.
    pub fn debug_outputs(&self) -> Vec<DebugOutput> {
        self.graph
            .textures
            .iter()
            .filter(|t| t.extent == graph::Extent::Camera)
            .filter_map(|t| {
                Some(DebugOutput {
                    name: t.name.strip_prefix(graph::DEBUG_PREFIX)?.to_string(),
                    texture: t.name.clone(),
                    components: t.channels.len().clamp(1, 4),
                })
            })
            .collect()
    }

    /// Debug output `name` of light (or cascade) `light`'s Shade, at the camera's size, as
    /// computed (unclamped; NaN where the camera sees no surface): components 0.. of each
    /// pixel hold the output's, the others 0. Light `l`'s Shade writes its own; with
    /// cascades, each cascade's is evaluated at every pixel, not only in its slice.
    pub fn read_debug(&self, light: usize, name: &str) -> Result<Image> {
        let texture = format!("{}{name}", graph::DEBUG_PREFIX);
        if self.graph.texture(&texture).is_none_or(|t| t.extent != graph::Extent::Camera) {
            let known: Vec<String> = self.debug_outputs().into_iter().map(|d| d.name).collect();
            return Err(RuntimeError::NotFound(if known.is_empty() {
                format!(
                    "no debug output `{name}`: the graph has none (compile it with debug outputs: `CompileOptions::debug`, `sshc compile --debug`)"
                )
            } else {
                format!("no debug output `{name}`; the graph has {}", known.join(", "))
            }));
        }
        self.read_light_texture(light, &texture, 0, 0)
    }

    /// Read a camera output of the Shade pass. The visibility (and the colour, computed from
    /// it) is refused where it is not finite or lies outside [0, 1] (`check_visibility`).
    /// With several lights, the colour is the lights' combination and the other outputs are
    /// light 0's ([`Executor::read_light_camera`] reads another light's,
    /// [`Executor::read_visibilities`] every light's visibility).
    pub fn read_camera(&self, which: CameraOutput) -> Result<Image> {
        if let (CameraOutput::Visibility, Some(c)) = (which, &self.combine)
            && c.cascades
        {
            // cascades: the visibility is their combination (channel 0; channel 1 the cascade)
            let mut img = self.read_visibilities()?;
            for p in &mut img.rgba {
                *p = [p[0], 0.0, 0.0, 1.0];
            }
            return Ok(img);
        }
        if let (CameraOutput::Color, Some(c)) = (which, &self.combine) {
            // the colour is computed from every light's visibility
            for l in 0..self.bound.len() {
                self.read_light_camera(l, CameraOutput::Visibility)?;
            }
            let (w, h) = self.bound()?.camera_size;
            return read_back(&self.gpu, &c.color, 0, 0, w, h, Format::Rgba8Unorm);
        }
        self.read_light_camera(0, which)
    }

    /// Read a camera output of light `light`'s Shade (that light alone).
    pub fn read_light_camera(&self, light: usize, which: CameraOutput) -> Result<Image> {
        if which == CameraOutput::Color {
            // The shaded colour is computed from the visibility: a visibility the check
            // refuses is not passed on through the colour either.
            self.read_light_camera(light, CameraOutput::Visibility)?;
        }
        self.bound()?;
        let b = self
            .bound
            .get(light)
            .ok_or_else(|| RuntimeError::NotFound(format!("light {light} is not bound ({} light(s) are)", self.bound.len())))?;
        let (w, h) = b.camera_size;
        let format = match which {
            CameraOutput::Visibility => Format::R32Float,
            CameraOutput::Color => Format::Rgba8Unorm,
            CameraOutput::Position => Format::Rgba32Float,
            CameraOutput::Normal => Format::Rgba16Float,
        };
        let img = read_back(&self.gpu, &b.camera[which as usize], 0, 0, w, h, format)?;
        if which == CameraOutput::Visibility {
            check_visibility(&img.channel(0), w, self.shade_name())?;
            // the Shade wrote a finite visibility where the technique's was not: the
            // normal's w says where (`graph::CAMERA_OUTPUTS`)
            let normal = read_back(&self.gpu, &b.camera[CameraOutput::Normal as usize], 0, 0, w, h, Format::Rgba16Float)?;
            check_finite_visibility(&normal.channel(3), w, self.shade_name())?;
        }
        Ok(img)
    }

    /// Every light's visibility, channel `l` for light `l` (the combining step's gathering
    /// with several lights; light 0's visibility in channel 0 with one), checked as
    /// [`Executor::read_camera`] checks one.
    pub fn read_visibilities(&self) -> Result<Image> {
        let Some(c) = &self.combine else {
            return self.read_light_camera(0, CameraOutput::Visibility);
        };
        let (w, h) = self.bound()?.camera_size;
        let img = read_back(&self.gpu, &c.visibility, 0, 0, w, h, Format::Rgba32Float)?;
        // cascades: channel 1 is the cascade, checked by nothing
        let visibilities = if c.cascades { 1 } else { self.bound.len() };
        for l in 0..visibilities {
            check_visibility(&img.channel(l), w, self.shade_name())?;
        }
        Ok(img)
    }

    fn shade_name(&self) -> &str {
        self.graph
            .passes
            .iter()
            .rev()
            .find(|p| p.kind == graph::PassKind::Shade)
            .map_or("shade", |p| p.name.as_str())
    }

    /// Bytes of every texture at the bound sizes: (name, bytes); transient ones included.
    /// With several lights, each light's textures (named `texture (light l)`) and the
    /// combining step's.
    pub fn memory(&self) -> Result<Vec<(String, u64)>> {
        let first = self.texture_bytes(self.bound()?);
        if self.bound.len() == 1 {
            return Ok(first);
        }
        let mut all = Vec::new();
        for (l, res) in self.bound.iter().enumerate() {
            all.extend(self.texture_bytes(res).into_iter().map(|(n, b)| (format!("{n} (light {l})"), b)));
        }
        all.push((
            "lights' colours and visibilities, combined (camera size)".to_string(),
            Combine::bytes(first_camera(&self.bound), self.bound.len()),
        ));
        Ok(all)
    }

    fn texture_bytes(&self, b: &Resources) -> Vec<(String, u64)> {
        self.graph
            .textures
            .iter()
            .map(|t: &TextureDecl| (t.name.clone(), texture_bytes(t, b.shadow_size, b.camera_size)))
            .collect()
    }

    /// What the last frame generated into buffer `name` (a Geometry pass's records): read
    /// back from the draw arguments at the buffer's start, so this waits for the GPU.
    pub fn generated(&self, name: &str) -> Result<Generated> {
        let b = self.bound()?;
        let decl = self
            .graph
            .buffer(name)
            .ok_or_else(|| RuntimeError::NotFound(format!("no generated buffer `{name}`")))?;
        let gpu = &self.gpu;
        let read = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("draw arguments read-back"),
            size: graph::GENERATED_HEADER_BYTES as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(b.generated(name)?, 0, &read, 0, graph::GENERATED_HEADER_BYTES as u64);
        gpu.scoped("reading draw arguments", || gpu.queue.submit([encoder.finish()]))?;
        let raw = gpu.map_read(&read)?;
        let word = |i: usize| u32::from_le_bytes([raw[4 * i], raw[4 * i + 1], raw[4 * i + 2], raw[4 * i + 3]]);
        let vertices = word(0);
        Ok(Generated {
            records: vertices / decl.vertices_per_record,
            vertices,
            instances: word(1),
            claimed: word(4),
            dropped: word(5),
        })
    }

    /// The edge adjacency the bound scene gave the Geometry passes (`None` without them).
    pub fn edge_counts(&self) -> Result<Option<crate::adjacency::AdjacencyCounts>> {
        Ok(self.bound()?.edges.as_ref().map(|e| e.counts))
    }

    /// The bound scene's shadow-map resolution.
    pub fn shadow_size(&self) -> Result<u32> {
        Ok(self.bound()?.shadow_size)
    }

    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// A camera output of the Shade pass as a texture the host can bind (a host's view of
    /// it, as [`Executor::visibility`] is of the visibility), valid until the next binding:
    /// the colour is every light's combination where several are bound, the others light
    /// 0's. Camera-sized, `TEXTURE_BINDING` usage, formats as `sshc_graph::CAMERA_OUTPUTS`.
    pub fn camera_texture(&self, which: CameraOutput) -> Result<&wgpu::Texture> {
        let b = self.bound()?;
        Ok(match (which, &self.combine) {
            (CameraOutput::Color, Some(c)) => &c.color,
            (CameraOutput::Color | CameraOutput::Visibility | CameraOutput::Position | CameraOutput::Normal, _) => {
                &b.camera[which as usize]
            }
        })
    }

    /// A texture of the graph (light 0's), for a host to bind and look at, valid until the
    /// next binding. Summed-area tables are storage buffers, not textures: refused.
    pub fn texture(&self, name: &str) -> Result<&wgpu::Texture> {
        self.bound()?.texture(name)
    }

    /// The visibility as a texture the host can bind and sample, valid until the next
    /// binding ([`Executor::generation`]): with one light, light 0's `R32Float` visibility
    /// (1 where the camera sees no surface); with several, an `Rgba32Float` texture with
    /// light `l`'s visibility in channel `l`. Both are camera-sized, with `TEXTURE_BINDING`
    /// usage; 32-bit floats filter only with `FLOAT32_FILTERABLE`, so sample them with
    /// `textureLoad` or a non-filtering sampler.
    ///
    /// The check that [`Executor::read_camera`] applies (every value finite and within
    /// [0, 1]) cannot run on a texture the host samples directly;
    /// [`Executor::read_visibilities`] runs it, as a debugging call (it waits for the GPU).
    pub fn visibility(&self) -> Result<&wgpu::Texture> {
        let b = self.bound()?;
        Ok(match &self.combine {
            Some(c) => &c.visibility,
            None => &b.camera[CameraOutput::Visibility as usize],
        })
    }
}

fn first_camera(bound: &[Resources]) -> (u32, u32) {
    bound.first().map_or((0, 0), |b| b.camera_size)
}
