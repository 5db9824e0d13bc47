//! The runtime's stages as the lab holds them: a technique loaded with its params
//! ([`Loaded`]), and that technique on one scene ([`Bound`]: the uploaded scene, its
//! targets and the frame's state, each the runtime's own type, used directly).
//!
//! The lab's scenes come as triangle soups with one camera and light per [`SceneInputs`]
//! (`crate::bind`), or as shared meshes and instances ([`Geometry`]); both become a
//! [`Scene`], [`Targets`] at the scene's sizes and a [`FrameState`] of its camera and lights.

use sshc_runtime::gpu::{
    Camera, FrameState, FrameTimes, Geometry, Gpu, Inspect, LightInputs, Params, Result, RuntimeError, Scene, SceneInputs, Sizes, Slices,
    TargetLimits, Targets, Technique,
};
use sshc_runtime::graph::{PassGraph, ValidGraph};
use std::path::Path;

/// A loaded technique and the params the lab runs it with.
#[derive(Clone, Debug)]
pub struct Loaded {
    pub technique: Technique,
    pub params: Params,
    /// What its targets may take ([`TargetLimits`]).
    pub limits: TargetLimits,
}

impl Loaded {
    /// Load a graph (checked: [`ValidGraph`]) and its shaders, as the compiler's API returns them.
    pub fn new(gpu: &Gpu, graph: PassGraph, shaders: Vec<(String, String)>) -> Result<Loaded> {
        Ok(Loaded::of(Technique::new(gpu, ValidGraph::try_from(graph)?, shaders)?))
    }

    /// Load `T.graph.ron` and the shader files it names ([`Technique::load`]).
    pub fn load(gpu: &Gpu, path: &Path) -> Result<Loaded> {
        Ok(Loaded::of(Technique::load(gpu, path)?))
    }

    /// A loaded technique at its default params.
    pub fn of(technique: Technique) -> Loaded {
        Loaded {
            params: Params::new(&technique),
            technique,
            // the lab measures: every pass timed on the GPU
            limits: TargetLimits {
                timestamps: true,
                ..TargetLimits::default()
            },
        }
    }

    pub fn graph(&self) -> &PassGraph {
        self.technique.graph()
    }

    pub fn gpu(&self) -> &Gpu {
        self.technique.gpu()
    }

    /// Set a runtime param ([`Params::set`]) for every scene bound from now on.
    pub fn set_param(&mut self, name: &str, value: f64) -> Result<()> {
        self.params.set(name, value)
    }

    /// A scene of one light ([`Loaded::bind_lights`]).
    pub fn bind_scene(&self, s: &SceneInputs) -> Result<Bound> {
        self.bind_lights(std::slice::from_ref(s))
    }

    /// A scene of several lights: `lights[l]` is the scene with light `l` alone; their
    /// soups must be the same (one scene, uploaded once), their cameras and sizes too.
    pub fn bind_lights(&self, lights: &[SceneInputs]) -> Result<Bound> {
        let Some(first) = lights.first() else {
            return Err(RuntimeError::Param("no light: a frame has 1 or more".into()));
        };
        check_one_scene(lights)?;
        let scene = self.soup(first)?;
        let states: Vec<LightInputs> = lights.iter().map(SceneInputs::light_inputs).collect();
        self.bound(scene, first.camera(), states, None, sizes_of(first))
    }

    /// The cascades of one light at infinity on `scene`'s soup and camera: `cascades[i]`
    /// is cascade `i`'s view, `slices` where they split the camera's view.
    pub fn bind_cascades(&self, scene: &SceneInputs, cascades: &[LightInputs], slices: &Slices) -> Result<Bound> {
        let uploaded = self.soup(scene)?;
        self.bound(uploaded, scene.camera(), cascades.to_vec(), Some(slices.clone()), sizes_of(scene))
    }

    /// A host geometry (meshes and instances) seen by `camera` under `lights`, at these sizes.
    pub fn bind_geometry(
        &self,
        geometry: &Geometry,
        camera: &Camera,
        lights: &[LightInputs],
        camera_size: (u32, u32),
        shadow_size: u32,
    ) -> Result<Bound> {
        let scene = Scene::upload_within(self.gpu(), geometry, &[&self.technique], self.limits.max_bytes)?;
        let sizes = Sizes {
            camera: camera_size,
            shadow: shadow_size,
        };
        self.bound(scene, *camera, lights.to_vec(), None, sizes)
    }

    /// [`Loaded::bind_cascades`] on a host geometry.
    pub fn bind_geometry_cascades(
        &self,
        geometry: &Geometry,
        camera: &Camera,
        cascades: &[LightInputs],
        camera_size: (u32, u32),
        shadow_size: u32,
        slices: &Slices,
    ) -> Result<Bound> {
        let scene = Scene::upload_within(self.gpu(), geometry, &[&self.technique], self.limits.max_bytes)?;
        let sizes = Sizes {
            camera: camera_size,
            shadow: shadow_size,
        };
        self.bound(scene, *camera, cascades.to_vec(), Some(slices.clone()), sizes)
    }

    fn soup(&self, s: &SceneInputs) -> Result<Scene> {
        Scene::from_soup(
            self.gpu(),
            &s.vertices,
            &s.meshes,
            s.casting_vertices,
            &s.unshadowed,
            &[&self.technique],
            self.limits.max_bytes,
        )
    }

    fn bound(&self, scene: Scene, camera: Camera, mut lights: Vec<LightInputs>, slices: Option<Slices>, sizes: Sizes) -> Result<Bound> {
        for l in &mut lights {
            outside_the_model(self.graph(), l);
        }
        let state = FrameState {
            camera,
            lights,
            params: self.params.clone(),
            slices,
        };
        let targets = Targets::with_limits(&self.technique, &scene, &state, sizes, self.limits)?;
        Ok(Bound {
            scene,
            targets,
            state,
            depth_override: None,
        })
    }
}

/// Refuse lights whose soups or sizes differ: the lights of a frame share one scene.
fn check_one_scene(lights: &[SceneInputs]) -> Result<()> {
    let first = &lights[0];
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
    if let Some(s) = lights.iter().find(|s| s.camera_size != first.camera_size) {
        return Err(RuntimeError::Param(format!(
            "the lights' cameras differ ({} x {} against {} x {}): lights are combined pixel by pixel",
            s.camera_size.0, s.camera_size.1, first.camera_size.0, first.camera_size.1
        )));
    }
    if let Some(s) = lights.iter().find(|s| s.shadow_size != first.shadow_size) {
        return Err(RuntimeError::Param(format!(
            "the lights' shadow maps differ ({} against {}): one set of targets has one size",
            s.shadow_size, first.shadow_size
        )));
    }
    Ok(())
}

fn sizes_of(s: &SceneInputs) -> Sizes {
    Sizes {
        camera: s.camera_size,
        shadow: s.shadow_size,
    }
}

/// A technique on one scene: the uploaded scene, the targets at its sizes and the frame's
/// state, each changed through the runtime's own calls (`state` is plain data).
pub struct Bound {
    pub scene: Scene,
    pub targets: Targets,
    pub state: FrameState,
    /// The Depth passes' outputs given instead of rasterised, one map per view (or one for
    /// every view): `sshc verify`'s synthetic depth fields ([`Targets::run_frame_with_depth`]).
    pub depth_override: Option<Vec<Vec<f32>>>,
}

impl Bound {
    /// One frame of the state, submitted and waited for ([`Targets::run_frame`]), with
    /// the depth override where one is set.
    pub fn run_frame(&mut self) -> Result<FrameTimes> {
        match &self.depth_override {
            Some(maps) => self.targets.run_frame_with_depth(&mut self.scene, &self.state, maps),
            None => self.targets.run_frame(&mut self.scene, &self.state),
        }
    }

    /// One frame with the Depth passes' outputs given ([`Targets::run_frame_with_depth`]).
    pub fn run_frame_with_depth(&mut self, maps: &[Vec<f32>]) -> Result<FrameTimes> {
        self.targets.run_frame_with_depth(&mut self.scene, &self.state, maps)
    }

    /// The Depth pass's output given as `depth` in every frame from now on (`None`:
    /// rasterised again).
    pub fn set_depth_override(&mut self, depth: Option<Vec<f32>>) {
        self.depth_override = depth.map(|d| vec![d]);
    }

    /// [`Bound::set_depth_override`] with one map per view of a per-sample Depth pass.
    pub fn set_depth_override_views(&mut self, views: Option<Vec<Vec<f32>>>) {
        self.depth_override = views;
    }

    /// Prepare and record a frame into a host's encoder.
    pub fn encode(&mut self, encoder: &mut sshc_runtime::wgpu::CommandEncoder) -> Result<()> {
        self.targets.prepare(&mut self.scene, &self.state)?;
        self.targets.record(&self.scene, encoder)
    }

    /// Read-backs and memory figures of the last frame.
    pub fn inspect(&self) -> Inspect<'_> {
        self.targets.inspect()
    }

    /// Light `l` fitted to the scene's instances as they are now ([`Targets::fit_light`]).
    pub fn place_light(&mut self, l: usize, light: &sshc_runtime::light::Light, fit: sshc_runtime::gpu::Fit) -> Result<()> {
        let mut inputs = self.targets.fit_light(&self.scene, l, light, fit)?;
        outside_the_model(self.graph(), &mut inputs);
        match self.state.lights.get_mut(l) {
            Some(slot) => *slot = inputs,
            None => return Err(RuntimeError::NotFound(format!("light {l} is not bound"))),
        }
        Ok(())
    }

    pub fn graph(&self) -> &PassGraph {
        self.targets.technique().graph()
    }
}

impl std::fmt::Debug for Bound {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Bound")
            .field("technique", &self.graph().technique)
            .field("lights", &self.targets.lights())
            .field("sizes", &(self.targets.camera_size(), self.targets.shadow_size()))
            .finish_non_exhaustive()
    }
}

/// The lab runs a technique under lights its file does not list on purpose (how far a
/// model holds outside its light is a measurement; `sshc render` and `compare` warn of it:
/// `session::specialise`). The runtime refuses a light whose stated kind the technique
/// does not list, so the lab gives such a light without its kind, which the runtime does
/// not judge.
pub fn outside_the_model(graph: &PassGraph, light: &mut LightInputs) {
    if let Some(k) = light.kind
        && !graph.written_for(k)
    {
        light.kind = None;
    }
}
