//! Stage 4 of the runtime: what a loaded technique renders into on one uploaded scene at
//! one camera and shadow-map size, for a number of lights ([`Targets`]), and the frame
//! path over it: [`Targets::prepare`] (queue writes only) and [`Targets::record`] (encoder
//! commands only).
//!
//! The textures come from a pool keyed by each texture's declaration (the size is the
//! targets' own): a transient texture (a separable filter's intermediate) is made once and
//! shared by every light, as is, by default, every shadow-map-sized texture, since the
//! lights' passes run one light after another and nothing after a light's passes reads
//! them ([`TargetLimits::share_light_textures`]).

use crate::device::{Gpu, Result, RuntimeError};
use crate::fit::Fit;
use crate::frame::{Camera, LightInputs, SceneInputs};
use crate::geometry::Changes;
use crate::graph::Format;
use crate::graph::{self, PassGraph};
use crate::lights::{Combine, Combining, MAX_LIGHTS, Slices};
use crate::pixels::{HostPixels, PixelsStep};
use crate::receivers::Unshadowed;
use crate::resources::{Pool, Resources, TargetLimits, f32_bytes, frame_stride, texture_bytes};
use crate::scene::Scene;
use crate::state::FrameState;
use crate::steps::{Group0, StepBinding, StepNode, begin_compute};
use crate::technique::{MAX_PASSES, Technique};
use crate::timing::{FrameTimes, Timestamps};
use crate::update::{FrameWriter, LightUniforms};
use sshc_light::MAX_CASCADES;

/// The camera outputs of the Shade pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraOutput {
    Visibility = 0,
    Color = 1,
    Position = 2,
    Normal = 3,
}

/// The sizes targets are made at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sizes {
    /// The camera image, pixels.
    pub camera: (u32, u32),
    /// The shadow map, texels per side.
    pub shadow: u32,
}

impl Sizes {
    /// The sizes of a triangle-soup scene ([`SceneInputs`]).
    pub fn of(s: &SceneInputs) -> Sizes {
        Sizes {
            camera: s.camera_size,
            shadow: s.shadow_size,
        }
    }
}

/// A loaded technique's targets on one [`Scene`] at one [`Sizes`], for 1 to [`MAX_LIGHTS`]
/// lights or 1 to [`MAX_CASCADES`] cascades of one light: the textures, buffers and bind
/// groups every pass binds, the lights' combination, the GPU timestamps. Made once; a
/// camera resize ([`Targets::resize`]) makes only what depends on the camera's size.
///
/// Per frame: [`Targets::prepare`] writes what changed in the host's [`FrameState`]
/// (queue writes only), [`Targets::record`] records the passes into the host's encoder
/// (encoder commands only, from `&self`). Neither creates a wgpu object nor allocates.
pub struct Targets {
    pub(crate) gpu: Gpu,
    pub(crate) technique: Technique,
    /// The scene they were made on ([`Scene`]'s identity), and what had changed in it
    /// when they last took it ([`Targets::set_scene`]).
    scene: u64,
    scene_changes: Changes,
    params_buf: Option<wgpu::Buffer>,
    /// The params as last written (empty before the first frame).
    params_written: Vec<u8>,
    /// Each light's resources.
    pub(crate) bound: Vec<Resources>,
    /// The textures the lights share ([`Pool`]), by name.
    pub(crate) shared: Vec<String>,
    /// What each step binds on each light's resources: per light, pass, step and view.
    bindings: Vec<Vec<Vec<Vec<StepBinding>>>>,
    /// What `record` encodes for each light and pass, decided when the steps are bound
    /// ([`Targets::plan_passes`]): a frame walks it and decides nothing.
    plans: Vec<Vec<PassPlan>>,
    /// What each light's uniforms were last set from, and the camera.
    lights_state: Vec<LightInputs>,
    camera: Camera,
    /// Each light's uniforms as the next frame writes them.
    uniforms: Vec<LightUniforms>,
    /// The casters' bounds the lights were last checked against.
    bounds_checked: Option<[[f32; 3]; 2]>,
    /// The cascades' slices as last written.
    slices: Option<Slices>,
    generation: u64,
    frames: u64,
    frame: u64,
    slot: Option<usize>,
    place: bool,
    pixels: Option<PixelsStep>,
    pub(crate) combine: Option<Combine>,
    unshadowed: Option<Unshadowed>,
    timestamps: Option<Timestamps>,
    limits: TargetLimits,
    /// [`Targets::step_bindings_made`].
    bindings_made: u64,
}

/// A step bound again: its light, pass and step, and its bindings per view.
type Rebound = (usize, usize, usize, Vec<StepBinding>);

impl Targets {
    /// Make `technique`'s targets on `scene` at `sizes` for the lights of `state` (their
    /// number, and each one's number of sample views, are sizes), within
    /// [`TargetLimits::default`]. `state` is checked as [`Targets::prepare`] checks it.
    pub fn new(technique: &Technique, scene: &Scene, state: &FrameState, sizes: Sizes) -> Result<Targets> {
        Targets::with_limits(technique, scene, state, sizes, TargetLimits::default())
    }

    /// [`Targets::new`] within `limits`.
    pub fn with_limits(technique: &Technique, scene: &Scene, state: &FrameState, sizes: Sizes, limits: TargetLimits) -> Result<Targets> {
        let gpu = technique.gpu().clone();
        let graph = technique.graph();
        if technique.usages().edges && !scene.has_edges() {
            return Err(RuntimeError::Param(format!(
                "technique `{}` classifies silhouettes, but the scene was uploaded without edge adjacency: upload it for this technique (`Scene::upload(gpu, geometry, &[&technique])`)",
                graph.technique
            )));
        }
        let n = state.lights.len();
        if n == 0 || n > MAX_LIGHTS {
            return Err(RuntimeError::Param(format!(
                "{n} light(s) bound: a frame combines 1 to {MAX_LIGHTS} lights"
            )));
        }
        if let Some(slices) = &state.slices {
            check_cascades(&state.lights, slices)?;
        }
        check_params(technique, state)?;
        state.camera.check()?;
        for (l, light) in state.lights.iter().enumerate() {
            light.check(l)?;
            check_light_kind(graph, l, light.kind)?;
        }
        check_floor_exact(graph, scene, &state.lights)?;
        if graph.passes.iter().any(|p| p.views.is_per_sample())
            && let Some(l) = state.lights.iter().position(|l| l.samples.len() != graph.samples as usize)
        {
            return Err(RuntimeError::Param(format!(
                "technique `{}` renders {} light-sample view(s), but light {l} gives {} (`LightInputs::samples`)",
                graph.technique,
                graph.samples,
                state.lights[l].samples.len()
            )));
        }
        // one timestamp pair per pass and light, in one query set
        let steps = graph.passes.len() * n;
        if steps > MAX_PASSES {
            return Err(RuntimeError::Limit {
                what: format!(
                    "technique `{}`: passes times lights (two GPU timestamps each, one query set)",
                    graph.technique
                ),
                needed: steps as u64,
                limit: MAX_PASSES as u64,
            });
        }
        let params_buf = (graph.params_size > 0).then(|| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("params"),
                size: graph.params_size as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let mut pool = Pool::new(limits.share_light_textures);
        let mut used = 0u64;
        let mut bound = Vec::with_capacity(n);
        for light in &state.lights {
            let s = SceneInputs::of(&state.camera, light, sizes.camera, sizes.shadow);
            let before = pool.bytes();
            let res = Resources::new(
                &gpu,
                graph,
                technique.usages(),
                &s,
                &scene.buffers().scene,
                TargetLimits {
                    max_bytes: limits.max_bytes.saturating_sub(used),
                    ..limits
                },
                &mut pool,
            )?;
            // what this light made: its own textures, and the shared ones made for it
            used += own_bytes(graph, &res, &pool) + (pool.bytes() - before);
            bound.push(res);
        }
        let mut targets = Targets {
            gpu: gpu.clone(),
            technique: technique.clone(),
            scene: scene.id(),
            scene_changes: scene.changes(),
            params_buf,
            params_written: Vec::new(),
            shared: pool.names(),
            bindings: Vec::new(),
            plans: Vec::new(),
            lights_state: state.lights.clone(),
            camera: state.camera,
            uniforms: state
                .lights
                .iter()
                .map(|l| LightUniforms::new(&state.camera, l, sizes.shadow, frame_stride(&gpu), true))
                .collect(),
            bounds_checked: scene.caster_bounds(),
            slices: None,
            generation: 0,
            frames: 0,
            frame: 0,
            slot: None,
            place: false,
            pixels: None,
            combine: None,
            unshadowed: None,
            timestamps: limits
                .timestamps
                .then(|| Timestamps::new(&gpu, graph.passes.iter().map(|p| p.name.clone()).collect(), n))
                .flatten(),
            limits,
            bound,
            bindings_made: 0,
        };
        targets.bindings = targets.bind_all_steps()?;
        targets.plans = targets.plan_passes();
        if n > 1 {
            let need = used.saturating_add(Combine::bytes(sizes.camera, n));
            if need > limits.max_bytes {
                return Err(RuntimeError::Limit {
                    what: format!("textures of {n} lights at these sizes (bytes)"),
                    needed: need,
                    limit: limits.max_bytes,
                });
            }
            let position = &targets.bound[0].camera[CameraOutput::Position as usize];
            let mode = match &state.slices {
                Some(s) => Combining::Cascades(s.clone()),
                None => Combining::Lights,
            };
            targets.combine = Some(Combine::new(&gpu, sizes.camera, n, &mode, position)?);
            targets.slices = state.slices.clone();
        }
        targets.unshadowed = Unshadowed::new(&gpu, &targets.bound)?;
        Ok(targets)
    }

    /// What every step binds on each light's resources (counted in
    /// [`Targets::step_bindings_made`]).
    fn bind_all_steps(&mut self) -> Result<Vec<Vec<Vec<Vec<StepBinding>>>>> {
        let all: Vec<_> = self.bound.iter().map(|res| self.bind_steps(res)).collect::<Result<_>>()?;
        self.bindings_made += all.iter().flatten().flatten().map(|views| views.len() as u64).sum::<u64>();
        Ok(all)
    }

    /// Bind again only the steps whose bindings come from the scene
    /// ([`StepNode::binds_scene`]: draws, edges, generated buffers), every light's, after
    /// the lights took a new scene's parts; every other step keeps its bind groups and
    /// bundles. Nothing is replaced unless every one is made.
    fn rebind_scene_steps(&mut self) -> Result<()> {
        let gpu = self.gpu.clone();
        let made = gpu.scoped("binding the scene's steps", || -> Result<Vec<Rebound>> {
            let mut made = Vec::new();
            for (l, res) in self.bound.iter().enumerate() {
                let shared = Group0 {
                    light_samples: &res.light_samples,
                    params: self.params_buf.as_ref(),
                    sampler: self.technique.sampler(),
                };
                for (pi, p) in self.technique.passes().iter().enumerate() {
                    for (si, node) in p.steps.iter().enumerate().filter(|(_, n)| n.binds_scene()) {
                        made.push((l, pi, si, node.bind(&gpu, res, &shared)?));
                    }
                }
            }
            Ok(made)
        })??;
        for (l, pi, si, b) in made {
            self.bindings_made += b.len() as u64;
            let slot = self.bindings.get_mut(l).and_then(|x| x.get_mut(pi)).and_then(|x| x.get_mut(si));
            match slot {
                Some(slot) => *slot = b,
                None => return Err(RuntimeError::NotFound(crate::error::NOTHING_BOUND.into())),
            }
        }
        Ok(())
    }

    /// Step bindings (one step's bind groups, attachment views and render bundles, for one
    /// light and view) these targets have made since they were made: every step's at
    /// making, on a resize and when host pixels change; only the steps that bind the scene
    /// on [`Targets::set_scene`]. What a host can read to see what a change cost.
    pub fn step_bindings_made(&self) -> u64 {
        self.bindings_made
    }

    /// What every step binds on one light's resources.
    fn bind_steps(&self, res: &Resources) -> Result<Vec<Vec<Vec<StepBinding>>>> {
        let shared = Group0 {
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

    /// A new camera size (a window resized): only what depends on it is made again: each
    /// light's camera-sized targets (the camera outputs and depth, a deferred Shade's
    /// G-buffer, camera-sized debug outputs), the lights' combination, and the step
    /// bindings over them. The scene, the shadow-map-sized textures and tables, the
    /// uniforms, the pipelines and the timestamps stay. Bumps [`Targets::generation`] (the
    /// host's views of the visibility changed); host pixels are given again. Refused, with
    /// nothing changed, for a size the device or [`TargetLimits::max_bytes`] cannot take.
    pub fn resize(&mut self, camera_size: (u32, u32)) -> Result<()> {
        if self.bound[0].camera_size == camera_size {
            return Ok(());
        }
        let lights = self.bound.len();
        let graph = self.technique.graph();
        let shadow_size = self.shadow_size();
        // every light's textures and the combination, checked before anything is created
        let per_light: u64 = graph
            .textures
            .iter()
            .filter(|t| !self.shared.contains(&t.name))
            .map(|t| texture_bytes(t, shadow_size, camera_size))
            .sum();
        let shared: u64 = graph
            .textures
            .iter()
            .filter(|t| self.shared.contains(&t.name))
            .map(|t| texture_bytes(t, shadow_size, camera_size))
            .sum();
        let need = (per_light * lights as u64).saturating_add(shared).saturating_add(if lights > 1 {
            Combine::bytes(camera_size, lights)
        } else {
            0
        });
        if need > self.limits.max_bytes {
            return Err(RuntimeError::Limit {
                what: format!("textures of {lights} light(s) at this camera size (bytes)"),
                needed: need,
                limit: self.limits.max_bytes,
            });
        }
        self.pixels = None;
        let technique = self.technique.clone();
        for res in &mut self.bound {
            res.resize_camera(&self.gpu, technique.graph(), technique.usages(), camera_size, self.limits.max_bytes)?;
        }
        self.bindings = self.bind_all_steps()?;
        self.plans = self.plan_passes();
        if let Some(c) = &mut self.combine {
            c.resize(&self.gpu, camera_size, &self.bound[0].camera[CameraOutput::Position as usize])?;
        }
        if let Some(u) = &mut self.unshadowed {
            u.resize(&self.bound);
        }
        self.generation += 1;
        Ok(())
    }

    /// Run on another scene (the host's meshes or instances changed: a new [`Scene`]
    /// uploaded), keeping every texture: the lights' draws and edges are taken from it,
    /// the generated buffers (sized from its edges) made again, and the steps that bind
    /// the scene bound again (its draws, edges and generated buffers; every other step
    /// keeps its bind groups and bundles: [`Targets::step_bindings_made`]).
    /// The camera-sized and shadow-map-sized targets, the uniforms, the pipelines and the
    /// timestamps stay; [`Targets::generation`] is bumped and host pixels are given again.
    /// Refused, with nothing changed, for a scene without the edge adjacency this
    /// technique's Geometry passes need, or one whose casters break a specialised graph's
    /// depth floor under the lights of the last frame.
    pub fn set_scene(&mut self, scene: &Scene) -> Result<()> {
        if scene.id() == self.scene && scene.changes().bindings == self.scene_changes.bindings {
            return self.take_draws(scene);
        }
        let graph = self.technique.graph();
        if self.technique.usages().edges && !scene.has_edges() {
            return Err(RuntimeError::Param(format!(
                "technique `{}` classifies silhouettes, but the scene was uploaded without edge adjacency: upload it for this technique (`Scene::upload(gpu, geometry, &[&technique])`)",
                graph.technique
            )));
        }
        check_floor_exact(graph, scene, &self.lights_state)?;
        let technique = self.technique.clone();
        // the textures stay: what is left of the budget is for the generated buffers
        let mut left = self
            .limits
            .max_bytes
            .saturating_sub(self.inspect().memory().iter().map(|m| m.1).sum());
        // every light's parts checked and made before any is taken
        let mut parts = Vec::with_capacity(self.bound.len());
        for res in &self.bound {
            let limits = TargetLimits {
                max_bytes: left,
                ..self.limits
            };
            let (p, bytes) = res.scene_parts(&self.gpu, technique.graph(), technique.usages(), &scene.buffers().scene, limits)?;
            left = left.saturating_sub(bytes);
            parts.push(p);
        }
        for (res, p) in self.bound.iter_mut().zip(parts) {
            res.take_scene(p);
        }
        self.pixels = None;
        self.rebind_scene_steps()?;
        self.plans = self.plan_passes();
        self.unshadowed = Unshadowed::new(&self.gpu, &self.bound)?;
        self.scene = scene.id();
        self.scene_changes = scene.changes();
        self.bounds_checked = None;
        self.place = false;
        self.generation += 1;
        Ok(())
    }

    /// [`Targets::set_scene`] of the same scene whose buffers stayed (a mesh or an instance
    /// added or removed in the room they had, no edges changed): each light takes the new
    /// draws and the steps that draw the scene record their bundles again. No buffer,
    /// texture or bind group is made.
    fn take_draws(&mut self, scene: &Scene) -> Result<()> {
        let draw = &scene.buffers().scene.draw;
        let gpu = self.gpu.clone();
        let technique = self.technique.clone();
        gpu.scoped("recording the scene's new draws", || -> Result<()> {
            for (res, per_pass) in self.bound.iter_mut().zip(&mut self.bindings) {
                res.draw = draw.clone();
                for (p, per_step) in technique.passes().iter().zip(per_pass.iter_mut()) {
                    for (node, views) in p.steps.iter().zip(per_step.iter_mut()).filter(|(n, _)| n.draws_scene()) {
                        for bound in views {
                            node.record_draws(&gpu, res, bound)?;
                        }
                    }
                }
            }
            Ok(())
        })??;
        // the draw of objects that receive no shadow is made when the first appears
        if self.unshadowed.is_none() != draw.unshadowed.is_empty() {
            self.unshadowed = Unshadowed::new(&self.gpu, &self.bound)?;
        }
        self.scene_changes = scene.changes();
        self.bounds_checked = None;
        Ok(())
    }

    /// Shade the host's pixels ([`HostPixels`]: world position and normal textures at the
    /// camera's size) instead of rasterising the scene from the camera: the deferred
    /// Shade's G-buffer is written from them by a step of the runtime's
    /// (`runtime/src/pixels.rs`, where the tolerance of the derived depth slope and
    /// footprint is stated). `None` rasterises again. Given again after a resize (the
    /// textures are bound to the G-buffers it made). Refused for a technique whose Shade
    /// runs forward, with the reason; the textures' formats, sizes and usages are checked.
    pub fn set_host_pixels(&mut self, pixels: Option<HostPixels>) -> Result<()> {
        self.pixels = None;
        let Some(pixels) = pixels else { return Ok(()) };
        if !self.technique.usages().gbuffer {
            return Err(RuntimeError::Unsupported {
                pass: shade_name(self.technique.graph()).to_string(),
                feature: format!(
                    "host pixels, which need the deferred Shade (G-buffer, then compute); technique `{}` shades forward. Compile its Shade pass with the compute schedule (`--schedule SHADE=compute`); a Shade that reads a light sample's depth slope or an implicit-level lookup in a sample's view cannot run deferred, and the compiler says so",
                    self.technique.graph().technique
                ),
            });
        }
        self.pixels = Some(PixelsStep::new(&self.gpu, &pixels, &self.bound)?);
        Ok(())
    }

    /// Light `l` of what a host knows of it ([`crate::light::Light`]: kind, position or
    /// direction, size), its view fitted to `scene`'s instances under their current
    /// transforms ([`LightInputs::fit`] of [`Scene::boxes`]), with light `l`'s number of
    /// sample views: what the host puts in its [`FrameState`].
    pub fn fit_light(&self, scene: &Scene, l: usize, light: &crate::light::Light, fit: Fit) -> Result<LightInputs> {
        let res = self.light(l)?;
        LightInputs::fit(light, scene.boxes(), fit, res.shadow_size, res.samples)
    }

    /// Begin a frame of `state` on `scene` (the scene these targets were made on): check
    /// what changed since the last frame (the camera, each light, the params, the slices,
    /// the casters' bounds) and write it through the queue, with each light's frame
    /// counter; take the frame's timestamp slot; note whether the scene's instances are
    /// placed again (the first targets prepared on a moved scene place it). Queue writes
    /// only: nothing created, nothing allocated, nothing waits; wgpu applies the writes at
    /// the next submission, before its command buffers. A refused state writes nothing.
    pub fn prepare(&mut self, scene: &mut Scene, state: &FrameState) -> Result<()> {
        self.check_scene(scene)?;
        let changed = self.check_state(scene, state)?;
        if let Some(t) = &mut self.timestamps {
            // the host's submissions fire the mapping callbacks: no poll here
            t.collect(&self.gpu, false)?;
        }
        let writer = FrameWriter::new(&self.gpu.queue);
        if let Some(buf) = &self.params_buf
            && self.params_written.as_slice() != state.params.bytes()
        {
            writer.params(buf, state.params.bytes());
            self.params_written.clear();
            self.params_written.extend_from_slice(state.params.bytes());
        }
        let camera_moved = self.camera != state.camera;
        let shadow_size = self.shadow_size();
        for (l, light) in state.lights.iter().enumerate() {
            if changed[l] {
                // in place: nothing is allocated once the light's samples are bound
                self.uniforms[l].set(&state.camera, light, shadow_size, false);
                self.lights_state[l].assign(light);
            } else if camera_moved {
                self.uniforms[l].set_camera(&state.camera, light, shadow_size);
            }
        }
        self.camera = state.camera;
        self.bounds_checked = scene.caster_bounds();
        if let (Some(c), Some(s)) = (&self.combine, &state.slices)
            && self.slices.as_ref() != Some(s)
        {
            c.set_slices(&self.gpu.queue, s);
            match &mut self.slices {
                Some(w) => {
                    w.splits.clear();
                    w.splits.extend_from_slice(&s.splits);
                    (w.eye, w.forward, w.band) = (s.eye, s.forward, s.band);
                }
                None => self.slices = Some(s.clone()),
            }
        }
        self.frame = self.frames;
        self.frames += 1;
        for (res, u) in self.bound.iter().zip(&mut self.uniforms) {
            writer.light(res, u, self.frame as u32);
        }
        // a host geometry's instances, placed again after their transforms changed
        self.place = scene.buffers_mut().take_due();
        self.slot = self.timestamps.as_mut().and_then(|t| t.begin(self.frame));
        Ok(())
    }

    /// Refuse a scene these targets were not made on.
    fn check_scene(&self, scene: &Scene) -> Result<()> {
        if scene.id() != self.scene {
            return Err(RuntimeError::Param(
                "these targets were made on another scene (their bind groups hold its buffers): make targets on this one (`Targets::new`)"
                    .into(),
            ));
        }
        if scene.changes() != self.scene_changes {
            return Err(RuntimeError::Param(
                "a mesh or an instance was added to or removed from the scene since these targets took it: give it to them again (`Targets::set_scene`)"
                    .into(),
            ));
        }
        Ok(())
    }

    /// Refuse a state these targets cannot run: checked where it changed (the camera, a
    /// light, the casters' bounds, the slices), so an unchanged frame costs comparisons.
    /// Returns which lights changed since the last frame (compared once, here).
    fn check_state(&self, scene: &Scene, state: &FrameState) -> Result<[bool; MAX_LIGHTS]> {
        let graph = self.technique.graph();
        let n = self.bound.len();
        if state.lights.len() != n {
            return Err(RuntimeError::Param(format!(
                "{} light(s) in the frame for targets made for {n}: a new number of lights is new targets",
                state.lights.len()
            )));
        }
        check_params(&self.technique, state)?;
        if self.camera != state.camera {
            state.camera.check()?;
        }
        let bounds = scene.caster_bounds();
        let bounds_moved = bounds != self.bounds_checked;
        let mut changed = [false; MAX_LIGHTS];
        for (l, (light, res)) in state.lights.iter().zip(&self.bound).enumerate() {
            changed[l] = self.lights_state[l] != *light;
            if !bounds_moved && !changed[l] {
                continue;
            }
            light.check(l)?;
            if light.samples.len() != res.samples as usize {
                return Err(RuntimeError::Param(format!(
                    "light {l} has {} sample view(s), its targets {}: a new number of samples is new targets",
                    light.samples.len(),
                    res.samples
                )));
            }
            check_light_kind(graph, l, light.kind)?;
            check_floor_from_bounds(graph, l, light, bounds)?;
        }
        match (&state.slices, self.combine.as_ref().is_some_and(|c| c.cascades)) {
            (Some(s), true) => {
                if self.slices.as_ref() != Some(s) || changed.iter().any(|c| *c) {
                    check_cascades(&state.lights, s)?;
                }
            }
            // one cascade is the light itself: its slices select nothing
            (None, false) => {}
            (Some(s), false) if n == 1 => check_cascades(&state.lights, s)?,
            (Some(_), false) => {
                return Err(RuntimeError::Param(
                    "the frame gives cascade slices, but these targets were made for lights, not cascades".into(),
                ));
            }
            (None, true) => {
                return Err(RuntimeError::Param(
                    "these targets were made for cascades: the frame must give their slices (`FrameState::slices`)".into(),
                ));
            }
        }
        Ok(changed)
    }

    /// Record the frame [`Targets::prepare`] began into the host's `encoder`: the scene's
    /// placement when prepare took it, every pass once for each light, then the lights'
    /// combination. Encoder commands only (nothing written through the queue, nothing
    /// created, nothing waits), from `&self`: a host may record the prepared frame more
    /// than once in a submission, and every recording sees the same uniforms. The host
    /// submits; the visibility ([`Targets::visibility`]) holds the frame's result once the
    /// submission completes. The GPU times come back a frame or more later
    /// ([`Targets::frame_times`]).
    pub fn record(&self, scene: &Scene, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        self.record_passes(scene, encoder, false)
    }

    /// [`Targets::record`], without the Depth passes when `skip_depth` (their outputs were
    /// written by the host: [`Targets::run_frame_with_depth`]).
    pub(crate) fn record_passes(&self, scene: &Scene, encoder: &mut wgpu::CommandEncoder, skip_depth: bool) -> Result<()> {
        self.check_scene(scene)?;
        if self.frames == 0 {
            return Err(RuntimeError::NotFound(
                "no frame was prepared: call prepare (queue writes), then record (encoder commands)".into(),
            ));
        }
        if self.place {
            scene.buffers().record(encoder);
        }
        let slot = self.slot;
        for (l, res) in self.bound.iter().enumerate() {
            for (pi, pass) in self.technique.passes().iter().enumerate() {
                if skip_depth && pass.kind.is_depth() {
                    continue;
                }
                let (Some(plan), Some(bindings)) = (
                    self.plans.get(l).and_then(|p| p.get(pi)),
                    self.bindings.get(l).and_then(|b| b.get(pi)),
                ) else {
                    return Err(RuntimeError::NotFound(crate::error::NOTHING_BOUND.into()));
                };
                let step = |(si, view): (usize, u32)| {
                    let bound = bindings.get(si).and_then(|b| b.get(view as usize));
                    pass.steps
                        .get(si)
                        .zip(bound)
                        .map(|(n, b)| (n, b, view))
                        .ok_or_else(|| RuntimeError::NotFound(format!("pass `{}`: a planned step is not bound", pass.name)))
                };
                // the pass's first render or compute pass writes its start, the last its end
                let passes = plan.iter().filter(|r| !matches!(r, Recorded::Reset(_))).count();
                let mut at = 0;
                let mut stamps = || {
                    at += 1;
                    match (&self.timestamps, slot) {
                        (Some(t), Some(slot)) => Some(t.stamps(slot, l, pi, at == 1, at == passes)),
                        _ => None,
                    }
                };
                for r in plan {
                    match r {
                        Recorded::Reset(s) => {
                            let (node, bound, _) = step(*s)?;
                            node.clear_generated(encoder, bound);
                        }
                        Recorded::Raster(s) => {
                            let (node, bound, view) = step(*s)?;
                            match &self.pixels {
                                // the host's pixels in place of the G-buffer raster
                                Some(p) if node.draws_gbuffer() => p.record(encoder, l, stamps()),
                                Some(_) | None => node.record(encoder, bound, res, stamps(), view)?,
                            }
                        }
                        Recorded::Compute(steps) => {
                            let (node, bound, _) = step(steps[0])?;
                            node.clear_generated(encoder, bound);
                            let mut cpass = begin_compute(encoder, node.label(), stamps());
                            for &s in steps {
                                let (node, bound, view) = step(s)?;
                                node.dispatch(&mut cpass, bound, res, view)?;
                            }
                        }
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

    /// What `record` encodes for every light and pass, from the steps as bound: each pass's
    /// steps in recording order (every step for one view, then the next), a step with
    /// nothing to record left out (a mip chain of one level), a compute step with nothing
    /// to dispatch only resetting its buffers ([`StepNode::dispatches_nothing`]), and the
    /// compute steps that follow one another in one compute pass where they may join it
    /// ([`joins`]). Made whenever the bindings change, so that a frame decides nothing.
    fn plan_passes(&self) -> Vec<Vec<PassPlan>> {
        let passes = self.technique.passes();
        self.bindings
            .iter()
            .zip(&self.bound)
            .map(|(light, res)| {
                passes
                    .iter()
                    .zip(light)
                    .map(|(pass, steps)| {
                        let views = pass.steps.iter().map(|n| n.views()).max().unwrap_or(1);
                        let mut plan: PassPlan = Vec::new();
                        for v in 0..views {
                            for (si, (node, bound)) in pass.steps.iter().zip(steps).enumerate() {
                                let Some(b) = bound.get(v as usize).filter(|b| b.passes() > 0) else {
                                    continue;
                                };
                                let here = (si, v);
                                if node.dispatches_nothing(b, res, v) {
                                    plan.push(Recorded::Reset(here));
                                } else if !node.is_compute() {
                                    plan.push(Recorded::Raster(here));
                                } else if let (Some(Recorded::Compute(open)), true) = (plan.last_mut(), joins(node, b)) {
                                    open.push(here);
                                } else {
                                    plan.push(Recorded::Compute(vec![here]));
                                }
                            }
                        }
                        plan
                    })
                    .collect()
            })
            .collect()
    }

    /// The render and compute passes one [`Targets::record`] encodes (the placement of a
    /// moved scene's instances aside): what a frame costs the host scales with it, each
    /// pass a descriptor and a driver command list (docs/embedding.md, "Host CPU").
    pub fn recorded_passes(&self) -> usize {
        let mut steps = 0;
        for (plans, bindings) in self.plans.iter().zip(&self.bindings) {
            for (plan, bound) in plans.iter().zip(bindings) {
                steps += plan
                    .iter()
                    .map(|r| match r {
                        Recorded::Reset(_) => 0,
                        // one render pass per level it writes
                        Recorded::Raster((si, v)) => bound.get(*si).and_then(|b| b.get(*v as usize)).map_or(0, StepBinding::passes),
                        Recorded::Compute(_) => 1,
                    })
                    .sum::<usize>();
            }
        }
        let unshadowed = match (&self.unshadowed, &self.pixels) {
            (Some(_), None) => self.bound.len(),
            _ => 0,
        };
        steps + unshadowed + usize::from(self.combine.is_some())
    }

    /// The newest frame whose GPU times have come back (its number, counted from the
    /// targets' making, and its times), without waiting: `None` before any has, or without
    /// timestamp queries.
    pub fn frame_times(&mut self) -> Result<Option<(u64, FrameTimes)>> {
        let Some(t) = &mut self.timestamps else { return Ok(None) };
        t.collect(&self.gpu, true)?;
        Ok(t.latest().cloned())
    }

    /// Run one frame of `state` on its own: [`Targets::prepare`] and [`Targets::record`]
    /// into an encoder of its own, submitted, then wait for the frame's GPU times (the
    /// lab's path; a host records into its own frame instead). Returns the GPU time of
    /// each pass (summed over the lights) and of each light when timestamps are available.
    pub fn run_frame(&mut self, scene: &mut Scene, state: &FrameState) -> Result<FrameTimes> {
        self.run(scene, state, None)
    }

    /// Run a frame whose Depth passes' outputs are `maps` (linear depths, row-major, row 0
    /// first, `shadow_size`^2 values; one per view of a per-sample Depth pass, in sample
    /// order, or one for every view) instead of the scene rasterised from the light: for
    /// feeding synthetic depth fields to the passes after Depth (`sshc verify`). Out of the
    /// frame path: the maps are written through the queue and the Depth passes not recorded.
    pub fn run_frame_with_depth(&mut self, scene: &mut Scene, state: &FrameState, maps: &[Vec<f32>]) -> Result<FrameTimes> {
        self.run(scene, state, Some(maps))
    }

    fn run(&mut self, scene: &mut Scene, state: &FrameState, depth: Option<&[Vec<f32>]>) -> Result<FrameTimes> {
        let gpu = self.gpu.clone();
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        gpu.scoped("recording the frame", || -> Result<()> {
            self.prepare(scene, state)?;
            if let Some(maps) = depth {
                write_depth_overrides(self, maps)?;
            }
            self.record_passes(scene, &mut encoder, depth.is_some())
        })??;
        let frame = self.frames - 1;
        gpu.scoped("submitting the frame", || gpu.queue.submit([encoder.finish()]))?;
        let names: Vec<String> = self.technique.passes().iter().map(|p| p.name.clone()).collect();
        let Some(t) = &mut self.timestamps else {
            gpu.wait()?;
            return Ok(FrameTimes::untimed(&names, self.bound.len()));
        };
        // map this frame's slot, wait for the device, and take its times
        t.collect(&gpu, false)?;
        gpu.wait()?;
        t.collect(&gpu, false)?;
        Ok(match t.latest() {
            Some((f, times)) if *f == frame => times.clone(),
            // the slot was still pending (frames recorded by the host without waiting)
            _ => FrameTimes::untimed(&names, self.bound.len()),
        })
    }

    /// Bumped by every resize: the host's views of the targets' textures changed.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Frames prepared since the targets were made.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Lights (or cascades) the targets were made for.
    pub fn lights(&self) -> usize {
        self.bound.len()
    }

    /// Cascades the targets were made for (2 or more); 1 otherwise.
    pub fn cascades(&self) -> usize {
        if self.combine.as_ref().is_some_and(|c| c.cascades) {
            self.bound.len()
        } else {
            1
        }
    }

    /// The shadow map's resolution.
    pub fn shadow_size(&self) -> u32 {
        self.bound[0].shadow_size
    }

    /// The camera image's size.
    pub fn camera_size(&self) -> (u32, u32) {
        self.bound[0].camera_size
    }

    /// The technique the targets run.
    pub fn technique(&self) -> &Technique {
        &self.technique
    }

    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    pub(crate) fn light(&self, l: usize) -> Result<&Resources> {
        self.bound
            .get(l)
            .ok_or_else(|| RuntimeError::NotFound(format!("light {l} is not in these targets ({} light(s) are)", self.bound.len())))
    }

    /// A camera output of the Shade pass as a texture the host can bind, valid until the
    /// next resize ([`Targets::generation`]): the colour is every light's combination where
    /// several are made, the others light 0's. Camera-sized, `TEXTURE_BINDING` usage,
    /// formats as `sshc_graph::CAMERA_OUTPUTS`.
    pub fn camera_texture(&self, which: CameraOutput) -> &wgpu::Texture {
        match (which, &self.combine) {
            (CameraOutput::Color, Some(c)) => &c.color,
            (CameraOutput::Color | CameraOutput::Visibility | CameraOutput::Position | CameraOutput::Normal, _) => {
                &self.bound[0].camera[which as usize]
            }
        }
    }

    /// A texture of the graph (light 0's), for a host to bind and look at, valid until the
    /// next resize. Summed-area tables are storage buffers, not textures: refused.
    pub fn texture(&self, name: &str) -> Result<&wgpu::Texture> {
        self.bound[0].texture(name)
    }

    /// The visibility as a texture the host can bind and sample, valid until the next
    /// resize ([`Targets::generation`]): with one light, light 0's `R32Float` visibility
    /// (1 where the camera sees no surface); with several, an `Rgba32Float` texture with
    /// light `l`'s visibility in layer `l / 4`, channel `l % 4` (one layer up to four
    /// lights, so that its default view is a 2D texture as with one light; a host binding
    /// more than four views it as an array). Both are camera-sized, with `TEXTURE_BINDING`
    /// usage; 32-bit floats filter only with `FLOAT32_FILTERABLE`, so sample them with
    /// `textureLoad` or a non-filtering sampler. The check that
    /// [`crate::gpu::Inspect::read_camera`] applies (every value finite and within [0, 1])
    /// cannot run on a texture the host samples directly.
    pub fn visibility(&self) -> &wgpu::Texture {
        match &self.combine {
            Some(c) => &c.visibility,
            None => &self.bound[0].camera[CameraOutput::Visibility as usize],
        }
    }
}

/// Bytes of the graph textures light `res` holds alone (not from the pool).
fn own_bytes(graph: &PassGraph, res: &Resources, pool: &Pool) -> u64 {
    graph
        .textures
        .iter()
        .filter(|t| !pool.holds(&t.name))
        .map(|t| texture_bytes(t, res.shadow_size, res.camera_size))
        .sum()
}

/// Refuse params made for another load of the technique.
fn check_params(technique: &Technique, state: &FrameState) -> Result<()> {
    if !state.params.of(technique) {
        return Err(RuntimeError::Param(
            "the frame's params were made for another technique (`Params::new(&technique)`)".into(),
        ));
    }
    Ok(())
}

/// Refuse cascades that cannot run: a count outside 1 to [`MAX_CASCADES`], slices they
/// cannot take ([`Slices::check`]), lights that are not one light at infinity.
fn check_cascades(cascades: &[LightInputs], slices: &Slices) -> Result<()> {
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
    Ok(())
}

/// A technique is written for the light models its file lists (`light:`; none or `Any`:
/// every kind), and a graph specialised for a scene's light kind folded inputs another
/// kind needs: light `l`, where the host says its kind (`LightInputs::kind`), must be one
/// of them. A light of no stated kind is not judged.
fn check_light_kind(graph: &PassGraph, l: usize, kind: Option<graph::LightKind>) -> Result<()> {
    if let Some(k) = kind
        && !graph.written_for(k)
    {
        let listed: Vec<String> = graph.lights.iter().map(|m| format!("{m:?}")).collect();
        return Err(RuntimeError::Param(format!(
            "technique `{}` is written for {} lights (its `light:` list), and light {l} is a {} light: its equations assume a light of those kinds; choose a technique that lists it, or list the kind in the technique if its model holds for it",
            graph.technique,
            listed.join(", "),
            k.name()
        )));
    }
    match &graph.specialised {
        Some(facts) if kind != Some(facts.light) => Err(RuntimeError::Param(format!(
            "technique `{}` was specialised for the {} light of scene {}, but this scene's light{} is {}; compile it for this scene (`--scene`) or without one",
            graph.technique,
            facts.light.name(),
            facts.scene,
            if l > 0 { format!(" {l}") } else { String::new() },
            kind.map_or("not given (`LightInputs::kind`)", |k| k.name())
        ))),
        Some(_) | None => Ok(()),
    }
}

/// A specialised graph's depth floor, checked exactly on the scene's casting triangles
/// (kept by the scene for a specialised technique) under each light.
fn check_floor_exact(graph: &PassGraph, scene: &Scene, lights: &[LightInputs]) -> Result<()> {
    let Some((facts, floor)) = graph.specialised.as_ref().and_then(|f| Some((f, f.depth_floor?))) else {
        return Ok(());
    };
    let Some((soup, casting)) = scene.soup() else {
        return Ok(());
    };
    for (l, light) in lights.iter().enumerate() {
        if let Some(here) = graph::caster_depth_floor(soup, casting, &light.view, light.near, light.far)
            && here < floor
        {
            return Err(RuntimeError::Param(format!(
                "technique `{}` was specialised for scene {}, whose casters lie at normalised depth {floor} or more in the light's view, but this scene's{} come to {here}; compile it for this scene (`--scene`) or without one",
                graph.technique,
                facts.scene,
                if l > 0 { format!(" (light {l})") } else { String::new() },
            )));
        }
    }
    Ok(())
}

/// A specialised graph's depth floor, re-checked for light `l` from the casters' bounding
/// box: its corners' least depth is a lower bound of the triangles', so a state the bounds
/// pass cannot break the specialisation; one they fail is refused.
fn check_floor_from_bounds(graph: &PassGraph, l: usize, light: &LightInputs, bounds: Option<[[f32; 3]; 2]>) -> Result<()> {
    let (Some(facts), Some(bounds)) = (&graph.specialised, bounds) else {
        return Ok(());
    };
    let Some(floor) = facts.depth_floor else { return Ok(()) };
    // on the stack: this runs on every frame whose light or casters moved
    let mut corners = [0.0f32; 48];
    for (i, v) in corners.chunks_exact_mut(6).enumerate() {
        for axis in 0..3 {
            v[axis] = bounds[(i >> axis) & 1][axis];
        }
    }
    match graph::caster_depth_floor(&corners, None, &light.view, light.near, light.far) {
        Some(here) if here < floor => Err(RuntimeError::Param(format!(
            "technique `{}` was specialised for scene {}, whose casters lie at normalised depth {floor} or more in the light's view; under light {l} as set, the casters' bounding box reaches {here}, so the specialisation may not hold; make the targets again (which checks the triangles themselves) or compile without `--scene`",
            graph.technique, facts.scene,
        ))),
        Some(_) | None => Ok(()),
    }
}

/// The name of the graph's (last) Shade pass.
pub(crate) fn shade_name(graph: &PassGraph) -> &str {
    graph
        .passes
        .iter()
        .rev()
        .find(|p| p.kind.is_shade())
        .map_or("shade", |p| p.name.as_str())
}

/// Write the depth override of every light's Depth pass (each of its views): `maps` holds
/// one map per view, or one for every view.
fn write_depth_overrides(t: &Targets, maps: &[Vec<f32>]) -> Result<()> {
    let graph = t.technique.graph();
    for res in &t.bound {
        for decl in graph.passes.iter().filter(|p| p.kind.is_depth()) {
            let views = graph.views_of(decl);
            if maps.is_empty() || (maps.len() != 1 && maps.len() != views as usize) {
                return Err(RuntimeError::Param(format!(
                    "depth override has {} maps, the Depth pass `{}` {views} view(s)",
                    maps.len(),
                    decl.name
                )));
            }
            for view in 0..views {
                let depth = &maps[(view as usize).min(maps.len() - 1)];
                write_depth_override(t, res, decl, depth, view)?;
            }
        }
    }
    Ok(())
}

/// Upload the depth override of view `view` into the Depth pass's output.
fn write_depth_override(t: &Targets, b: &Resources, pass: &graph::PassDecl, depth: &[f32], view: u32) -> Result<()> {
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
    let decl = t
        .technique
        .graph()
        .texture(&target.texture)
        .ok_or_else(|| RuntimeError::NotFound(format!("no texture `{}`", target.texture)))?;
    if decl.format != Format::R32Float {
        return Err(RuntimeError::Param(format!(
            "the Depth pass writes {:?}; a depth override needs R32Float",
            decl.format
        )));
    }
    let tex = b.texture(&target.texture)?;
    t.gpu.scoped("writing the depth override", || {
        t.gpu.queue.write_texture(
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

/// Whether a compute step joins the compute pass of the compute step recorded just before
/// it (in the same pass of the graph, for the same light): it must reset no buffer first
/// (resets are encoder commands, outside any pass). wgpu orders the dispatches of one
/// compute pass that write and read the same resource, so joining changes no value; it
/// saves the host a pass descriptor and the driver a command list (docs/embedding.md,
/// "Host CPU").
fn joins(node: &StepNode, bound: &StepBinding) -> bool {
    node.is_compute() && !StepNode::resets_buffers(bound)
}

/// One entry of what `record` encodes for a pass: a step (its index in the pass, and the
/// view) whose buffers are reset with no pass, a raster step's render passes, or compute
/// steps dispatched in one compute pass.
enum Recorded {
    Reset((usize, u32)),
    Raster((usize, u32)),
    Compute(Vec<(usize, u32)>),
}

/// What `record` encodes for one pass of the graph, for one light, in order.
type PassPlan = Vec<Recorded>;
