//! From a [`Scene`] to the plain data the runtime's stages are made from ([`SceneInputs`]).

use crate::run::{Bound, Loaded};
use crate::scene::{Light, Scene};
use sshc_runtime::gpu::{Camera, Geometry, IDENTITY, Instance, LightInputs, Mesh, SceneInputs, Slices};
use sshc_runtime::graph::{MAX_LIGHT_SAMPLES, PassGraph};
use sshc_runtime::light::{SampleFit, sample_views};

/// The scene's geometry, camera and first light, as the runtime takes them.
///
/// The vertex buffer lists the objects that cast shadows first, in file order, then those
/// that do not (`casts: false`), in file order: the light's draws take only the first
/// `casting_vertices`, and the meshes whose edges Geometry passes extrude are the casters
/// only. Objects with `receives: false` are listed in `unshadowed` (drawn unshadowed). With every object casting, the buffer is [`Scene::vertex_data`] as it is.
/// The light's view is fitted as the scene's `shadow_fit` says ([`Scene::light_view`]).
/// No light samples: for graphs without `PerLightSample` passes (see
/// [`scene_inputs_for`] and [`scene_inputs_with_samples`]).
pub fn scene_inputs(scene: &Scene) -> Result<SceneInputs, String> {
    scene_inputs_with_samples(scene, 0)
}

/// The scene as host geometry ([`sshc_runtime::gpu::Geometry`]), where an object holds a
/// glTF file's shared meshes ([`Scene::instancing`]): each such mesh once, indexed as the
/// file has it, and an instance per node with the node's matrix (`moves: false`: placed
/// once, at upload); every other object a mesh of its triangles listed out, in world space.
/// Casting objects first, in file order, then the others, as [`scene_inputs`] lists the
/// soup. `None` when no object shares meshes, or when the placements would exceed
/// [`sshc_runtime::gpu::MAX_INSTANCES`] (the soup is then what is bound).
pub fn scene_geometry(scene: &Scene) -> Option<Geometry> {
    let n = scene.objects().len();
    if !(0..n).any(|i| scene.instancing(i).is_some()) {
        return None;
    }
    // past the runtime's bound on instances a geometry is refused at bind; the soup (the
    // same triangles, already placed in world space) draws the same pixels with more
    // memory (issue 48, item 13: 70,000 nodes of one mesh failed to bind)
    let placements: usize = (0..n).map(|i| scene.instancing(i).map_or(1, |inst| inst.instances.len())).sum();
    if placements > sshc_runtime::gpu::MAX_INSTANCES {
        return None;
    }
    let order = (0..n).filter(|&i| scene.casts(i)).chain((0..n).filter(|&i| !scene.casts(i)));
    let mut g = Geometry::default();
    let (tris, normals) = (scene.triangles(), scene.normals());
    for i in order {
        let (casts, receives) = (scene.casts(i), scene.receives(i));
        let name = scene.objects()[i].name.clone().unwrap_or_else(|| format!("object {i}"));
        match scene.instancing(i) {
            Some(inst) => {
                let first = g.meshes.len();
                g.meshes.extend(inst.meshes.iter().map(|m| Mesh {
                    name: format!("{name}: {}", m.name),
                    positions: m.positions.clone(),
                    normals: m.normals.clone(),
                    indices: m.indices.clone(),
                }));
                g.instances
                    .extend(inst.instances.iter().enumerate().map(|(k, (m, world))| Instance {
                        name: format!("{name}: node instance {k}"),
                        mesh: first + m,
                        transform: *world,
                        casts,
                        receives,
                        moves: false,
                    }));
            }
            None => {
                let r = scene.object_triangles(i);
                let corners = || {
                    tris[r.clone()]
                        .iter()
                        .zip(&normals[r.clone()])
                        .flat_map(|(t, n)| (0..3).map(move |k| (t[k], n[k])))
                };
                g.meshes.push(Mesh {
                    name: name.clone(),
                    positions: corners().map(|(p, _)| p.to_array()).collect(),
                    normals: corners().map(|(_, n)| n.to_array()).collect(),
                    indices: (0..3 * r.len() as u32).collect(),
                });
                g.instances.push(Instance {
                    name,
                    mesh: g.meshes.len() - 1,
                    transform: IDENTITY,
                    casts,
                    receives,
                    moves: false,
                });
            }
        }
    }
    Some(g)
}

/// A scene made ready to bind ([`SceneBinding::of`]), then bound ([`SceneBinding::bind`]):
/// the two stages `sshc render` times apart.
pub enum SceneBinding {
    /// The triangle soup, one [`SceneInputs`] a light (`bind_lights`).
    Soup(Vec<SceneInputs>),
    /// Host geometry ([`scene_geometry`]: a glTF file's shared meshes once, an instance a
    /// node) seen by the scene's camera under each light (`bind_geometry`).
    Instances {
        geometry: Geometry,
        camera: Camera,
        lights: Vec<LightInputs>,
        camera_size: (u32, u32),
        shadow_size: u32,
    },
}

impl SceneBinding {
    /// `scene` for `graph`, every light with its own passes (`all`) or its first light only:
    /// as host geometry where the scene shares meshes, else as the triangle soup of each
    /// light ([`scene_inputs_for`]).
    pub fn of(scene: &Scene, graph: &PassGraph, all: bool) -> Result<SceneBinding, String> {
        let lights = if all { scene.lights.len().max(1) } else { 1 };
        let named = |i: usize, e: String| {
            if scene.lights.len() > 1 {
                format!("error: light {i}: {e}")
            } else {
                format!("error: {e}")
            }
        };
        if let Some(geometry) = scene_geometry(scene).filter(|_| !scene.lights.is_empty()) {
            let samples = graph_samples(graph);
            let lights = scene
                .lights
                .iter()
                .take(lights)
                .enumerate()
                .map(|(i, l)| light_inputs_with_samples(scene, l, samples).map_err(|e| named(i, e)))
                .collect::<Result<Vec<_>, String>>()?;
            return Ok(SceneBinding::Instances {
                geometry,
                camera: camera(scene),
                lights,
                camera_size: scene.camera_size(),
                shadow_size: scene.shadow_map,
            });
        }
        // light i alone (`session::single_light`, which imports this module); a scene of
        // one light as it is, without a copy of its triangles
        let inputs_of = |i: usize| {
            if scene.lights.len() > 1 {
                let mut s = scene.clone();
                s.lights = vec![scene.lights[i].clone()];
                scene_inputs_for(&s, graph)
            } else {
                scene_inputs_for(scene, graph)
            }
        };
        (0..lights)
            .map(|i| inputs_of(i).map_err(|e| named(i, e)))
            .collect::<Result<Vec<_>, String>>()
            .map(SceneBinding::Soup)
    }

    /// What it binds, for a stage line: the soup, or the meshes, the instances and their
    /// bytes on the GPU ([`Geometry::gpu_bytes`]).
    pub fn describe(&self) -> String {
        match self {
            SceneBinding::Soup(_) => "the triangle soup".into(),
            SceneBinding::Instances { geometry: g, .. } => format!(
                "{} meshes placed by {} instances, {:.1} MB of vertices and indices on the GPU ({:.1} B a triangle)",
                g.meshes.len(),
                g.instances.len(),
                g.gpu_bytes() as f64 / 1e6,
                g.gpu_bytes() as f64 / (g.triangles().max(1) as f64)
            ),
        }
    }

    pub fn bind(&self, ex: &Loaded) -> Result<Bound, String> {
        match self {
            SceneBinding::Soup(inputs) => ex.bind_lights(inputs),
            SceneBinding::Instances {
                geometry,
                camera,
                lights,
                camera_size,
                shadow_size,
            } => ex.bind_geometry(geometry, camera, lights, *camera_size, *shadow_size),
        }
        .map_err(|e| format!("error: {e}"))
    }
}

/// Bind `scene` on `ex`, every light with its own passes (`all`) or its first light only,
/// as [`SceneBinding::of`] makes it ready.
pub fn bind_scene(ex: &Loaded, scene: &Scene, all: bool) -> Result<Bound, String> {
    SceneBinding::of(scene, ex.graph(), all)?.bind(ex)
}

/// The light samples `graph` renders views of: [`PassGraph::samples`] when some pass has
/// `views: PerLightSample`, else 0 (bind none).
pub fn graph_samples(graph: &PassGraph) -> u32 {
    if graph.passes.iter().any(|p| p.views.is_per_sample()) {
        graph.samples
    } else {
        0
    }
}

/// [`scene_inputs_with_samples`] with the samples `graph` renders ([`graph_samples`]): what
/// every command binds a scene for a graph with.
pub fn scene_inputs_for(scene: &Scene, graph: &PassGraph) -> Result<SceneInputs, String> {
    scene_inputs_with_samples(scene, graph_samples(graph))
}

/// [`scene_inputs`] with `n` light-sample views of the scene's first light (Heidrich et
/// al. 2000), as [`light_samples`] makes them; `n = 0` binds none.
pub fn scene_inputs_with_samples(scene: &Scene, n: u32) -> Result<SceneInputs, String> {
    let light = scene
        .lights
        .first()
        .ok_or_else(|| "the scene has no light: add one to `lights`".to_string())?;
    let light = light_inputs_with_samples(scene, light, n)?;
    let n = scene.objects().len();
    let order: Vec<usize> = (0..n)
        .filter(|&i| scene.casts(i))
        .chain((0..n).filter(|&i| !scene.casts(i)))
        .collect();
    // Built straight from the triangles: one copy of the geometry (1.2 GB at the scene
    // limit of 2^24 triangles), not a second for `Scene::vertex_data`'s order.
    let (tris, normals) = (scene.triangles(), scene.normals());
    let mut vertices = Vec::with_capacity(tris.len() * 18);
    // One mesh per casting object: Geometry passes find edges within each.
    let mut meshes = Vec::new();
    let mut casting = 0usize;
    // the objects that receive no shadow, as ranges of vertices
    let mut unshadowed = Vec::new();
    for &i in &order {
        let r = scene.object_triangles(i);
        let start = vertices.len() / 18;
        for (tri, nrm) in tris[r.clone()].iter().zip(&normals[r]) {
            for k in 0..3 {
                vertices.extend_from_slice(&tri[k].to_array());
                vertices.extend_from_slice(&nrm[k].to_array());
            }
        }
        if !scene.receives(i) {
            unshadowed.push(start as u32 * 3..(vertices.len() / 6) as u32);
        }
        if scene.casts(i) {
            meshes.push(start as u32..(vertices.len() / 18) as u32);
            casting = vertices.len() / 6;
        }
    }
    if meshes.is_empty() {
        // no caster: an empty mesh (an empty list would mean one mesh of everything)
        meshes.push(0..0);
    }
    let every = casting == vertices.len() / 6;
    let camera = camera(scene);
    Ok(SceneInputs {
        vertices,
        meshes,
        casting_vertices: (!every).then_some(casting as u32),
        unshadowed,
        ..SceneInputs::of(&camera, &light, scene.camera_size(), scene.shadow_map)
    })
}

/// Cascaded shadow maps for a light at infinity (`bind::cascade_inputs`).
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub struct Cascading {
    /// Split the light's view into N cascades (1 to 4) over the camera's view depth, each
    /// fitted to its slice and `--shadow-map` texels wide; 1 is the scene's own fit. A
    /// light at infinity only, alone in the scene; the technique is compiled generic.
    #[arg(long, value_name = "N")]
    pub cascades: Option<u32>,
    /// The practical split scheme's weight: 0 uniform, 1 logarithmic (Zhang et al. 2006,
    /// eq. 6). Default: the scene file's, else 0.75.
    #[arg(long)]
    pub cascade_lambda: Option<f32>,
    /// The fraction of each cascade's slice, at its far end, mixed into the next.
    /// Default: the scene file's, else 0.1.
    #[arg(long)]
    pub cascade_band: Option<f32>,
    /// Do not snap the cascades to whole texels (to measure the shimmer snapping removes).
    #[arg(long)]
    pub no_snap: bool,
    /// Fit the cascades as if the camera stood this far away, X,Y,Z in world units, the
    /// image's camera unmoved: the shadow's change from one offset to the next is then the
    /// cascades' alone (scripts/shimmer.sh).
    #[arg(long, value_name = "X,Y,Z", value_parser = offset, allow_hyphen_values = true)]
    pub cascade_offset: Option<[f32; 3]>,
}

/// `--cascade-offset X,Y,Z`: three finite numbers.
fn offset(s: &str) -> Result<[f32; 3], String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{s}: {e}"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([x, y, z]),
        _ => Err(format!("{s}: write three finite numbers, X,Y,Z")),
    }
}

impl Cascading {
    /// The cascades asked for: the command line's options, else the scene file's
    /// (`cascades:`), else one cascade, lambda 0.75, band 0.1.
    pub fn resolved(&self, scene: &Scene) -> crate::scene::Cascades {
        let file = scene.cascades();
        crate::scene::Cascades {
            count: self.cascades.or(file.map(|c| c.count)).unwrap_or(1),
            lambda: self.cascade_lambda.or(file.map(|c| c.lambda)).unwrap_or(0.75),
            band: self.cascade_band.or(file.map(|c| c.band)).unwrap_or(0.1),
        }
    }

    /// The options as command-line words (for the `sshc render` line of a view).
    pub fn words(&self) -> Vec<String> {
        let mut w = Vec::new();
        let mut push = |flag: &str, v: Option<String>| {
            if let Some(v) = v {
                w.extend([flag.to_string(), v]);
            }
        };
        push("--cascades", self.cascades.map(|n| n.to_string()));
        push("--cascade-lambda", self.cascade_lambda.map(|x| x.to_string()));
        push("--cascade-band", self.cascade_band.map(|x| x.to_string()));
        push("--cascade-offset", self.cascade_offset.map(|[x, y, z]| format!("{x},{y},{z}")));
        if self.no_snap {
            w.push("--no-snap".into());
        }
        w
    }

    /// Refit the cascades bound by [`Cascading::bind`] to the scene's camera and light as
    /// they are now, in the frame's state (nothing created: the next prepare writes them).
    pub fn refit(&self, ex: &mut Bound, scene: &Scene) -> Result<(), String> {
        let r = self.resolved(scene);
        let c = cascade_fit(
            scene,
            ex.graph(),
            r.count,
            r.lambda,
            !self.no_snap,
            self.cascade_offset.unwrap_or_default(),
        )
        .map_err(|e| format!("error: {e}"))?;
        if c.lights.len() != ex.state.lights.len() {
            return Err(format!(
                "error: {} cascade(s) for the {} bound: a new count is a new binding",
                c.lights.len(),
                ex.state.lights.len()
            ));
        }
        ex.state.camera = camera(scene);
        for (slot, light) in ex.state.lights.iter_mut().zip(&c.lights) {
            slot.clone_from(light);
        }
        ex.state.slices = Some(c.slices(r.band));
        Ok(())
    }

    /// Binds the scene's cascades where they are asked for ([`Cascading::bind`], its line
    /// returned), else the scene itself ([`bind_scene`], every light or the first).
    pub fn bind_or_scene(&self, ex: &Loaded, scene: &Scene, all: bool) -> Result<(Bound, Option<String>), String> {
        match self.bind(ex, scene)? {
            Some((bound, line)) => Ok((bound, Some(line))),
            None => bind_scene(ex, scene, all).map(|b| (b, None)),
        }
    }

    /// More than one cascade asked for, here or by the scene file.
    pub fn on(&self, scene: &Scene) -> bool {
        self.resolved(scene).count > 1
    }

    /// Binds the scene's cascades when more than one is asked for: a line saying where
    /// they split and how fine each is; `None` (nothing bound) otherwise.
    pub fn bind(&self, ex: &Loaded, scene: &Scene) -> Result<Option<(Bound, String)>, String> {
        let r = self.resolved(scene);
        let n = r.count;
        if n < 2 {
            return Ok(None);
        }
        let c = cascade_fit(
            scene,
            ex.graph(),
            n,
            r.lambda,
            !self.no_snap,
            self.cascade_offset.unwrap_or_default(),
        )
        .map_err(|e| format!("error: {e}"))?;
        // a scene of shared meshes as its meshes and instances, else its soup
        let bound = match scene_geometry(scene) {
            Some(g) => ex.bind_geometry_cascades(
                &g,
                &camera(scene),
                &c.lights,
                scene.camera_size(),
                scene.shadow_map,
                &c.slices(r.band),
            ),
            None => ex.bind_cascades(
                &scene_inputs_for(scene, ex.graph()).map_err(|e| format!("error: {e}"))?,
                &c.lights,
                &c.slices(r.band),
            ),
        }
        .map_err(|e| format!("error: {e}"))?;
        let slices: Vec<String> = c
            .splits
            .windows(2)
            .zip(&c.texels)
            .map(|(w, t)| format!("{:.3}..{:.3} at {t:.4} world units a texel", w[0], w[1]))
            .collect();
        let line = format!(
            "cascades: {n} of {} texels, split at lambda {} ({}), mixed over the last {} of each slice: {}",
            scene.shadow_map,
            r.lambda,
            if self.no_snap { "not snapped" } else { "snapped to whole texels" },
            r.band,
            slices.join("; ")
        );
        Ok(Some((bound, line)))
    }
}

/// Refuses what cascades cannot split: a count outside 1 to `MAX_CASCADES`, a weight
/// outside [0, 1], a band outside [0, 1), several lights, a light at a finite position.
pub fn check_cascades(scene: &Scene, c: &Cascading) -> Result<(), String> {
    let max = sshc_runtime::light::MAX_CASCADES;
    let r = c.resolved(scene);
    let n = r.count;
    if !(1..=max).contains(&n) {
        return Err(format!("error: `--cascades {n}`: a light has 1 to {max} cascades"));
    }
    if !(0.0..=1.0).contains(&r.lambda) {
        return Err(format!("error: `--cascade-lambda {}`: a weight in [0, 1]", r.lambda));
    }
    if !(0.0..1.0).contains(&r.band) {
        return Err(format!("error: `--cascade-band {}`: a fraction of a slice, in [0, 1)", r.band));
    }
    if let Some(o) = c.cascade_offset {
        // the camera the cascades are fitted to, moved: within a thousand scene sizes of
        // where it was (farther, the cascades fit nothing of the scene, and at 1e30 the
        // fit overflowed and was reported as light 0's non-finite matrix)
        let (lo, hi) = scene.bounds();
        let size = (hi - lo).length().max(1.0);
        let len = o.iter().map(|&x| f64::from(x) * f64::from(x)).sum::<f64>().sqrt();
        if !len.is_finite() || len > 1000.0 * f64::from(size) {
            let num = |x: f32| if x.abs() >= 1e6 { format!("{x:e}") } else { x.to_string() };
            return Err(format!(
                "error: `--cascade-offset {},{},{}`: moves the camera the cascades are fitted to by {len:.3e}, more than 1000 times the scene's size ({size:.3})",
                num(o[0]),
                num(o[1]),
                num(o[2])
            ));
        }
    }
    if n > 1 {
        if scene.lights.len() != 1 {
            return Err(format!(
                "error: `--cascades {n}`: cascades split one light's view; the scene has {} lights (keep one with `--lights 1`)",
                scene.lights.len()
            ));
        }
        if scene.lights[0].direction().is_none() {
            return Err(format!(
                "error: `--cascades {n}`: cascades split the view of a light at infinity (Directional or DistantDisk); the scene's light is a {}",
                scene.lights[0].kind_name()
            ));
        }
    }
    Ok(())
}

/// The cascades of the scene's one light at infinity, as
/// [`crate::run::Loaded::bind_cascades`] binds them ([`cascade_inputs`]) or
/// [`Cascading::refit`] refits them ([`cascade_fit`]: no scene).
pub struct Cascades<S = SceneInputs> {
    /// The scene (geometry and camera; light 0's view), bound once for every cascade.
    pub scene: S,
    /// Each cascade's light.
    pub lights: Vec<LightInputs>,
    pub eye: [f32; 3],
    pub forward: [f32; 3],
    pub splits: Vec<f32>,
    /// World units per texel of each cascade's map.
    pub texels: Vec<f32>,
}

impl<S> Cascades<S> {
    /// The slices the combining step selects by, mixed over `band` of each.
    pub fn slices(&self, band: f32) -> Slices {
        Slices {
            eye: self.eye,
            forward: self.forward,
            splits: self.splits.clone(),
            band,
        }
    }
}

/// `n` cascades of the scene's light over the view depth the camera sees surfaces at (the
/// nearest and farthest view distance of the triangles clipped to its frustum,
/// [`Scene::visible_points`]; the camera's near and far when it sees none), split by the
/// practical scheme with `lambda`, each fitted to its slice padded by the casters'
/// penumbra reach, `scene.shadow_map` texels wide, snapped to whole texels unless `snap` is
/// false ([`sshc_runtime::light::cascade_views`]), with the light's size and angle
/// ([`Light::with_extent`]).
/// `offset` moves the camera the cascades are fitted to (not the image's).
pub fn cascade_inputs(scene: &Scene, graph: &PassGraph, n: u32, lambda: f32, snap: bool, offset: [f32; 3]) -> Result<Cascades, String> {
    let fit = cascade_fit(scene, graph, n, lambda, snap, offset)?;
    Ok(Cascades {
        scene: scene_inputs_for(scene, graph)?,
        lights: fit.lights,
        eye: fit.eye,
        forward: fit.forward,
        splits: fit.splits,
        texels: fit.texels,
    })
}

/// [`cascade_inputs`] without the scene's triangles: what a frame whose camera or light
/// moved refits ([`Cascading::refit`]).
pub fn cascade_fit(scene: &Scene, graph: &PassGraph, n: u32, lambda: f32, snap: bool, offset: [f32; 3]) -> Result<Cascades<()>, String> {
    use sshc_runtime::light::{CameraFrustum, cascade_views, practical_splits};
    let light = scene.lights.first().ok_or("the scene has no light")?;
    let dir = light.direction().ok_or_else(|| {
        format!(
            "cascades split the view of a light at infinity; the scene's light is a {}",
            light.kind_name()
        )
    })?;
    if graph_samples(graph) > 0 {
        return Err("cascades and per-sample techniques do not mix: per-sample views look from points on a local light".into());
    }
    let mut frustum =
        CameraFrustum::from_matrices(scene.camera_view(), scene.camera_proj()).ok_or("the camera's matrices cannot be inverted")?;
    frustum.eye += glam::Vec3::from_array(offset);
    let (camera_near, camera_far) = scene.camera_near_far();
    let (mut near, mut far) = (f32::INFINITY, 0.0f32);
    scene.for_each_visible_point(|p| {
        let d = (p - frustum.eye).dot(frustum.forward);
        (near, far) = (near.min(d), far.max(d));
    });
    let (near, far) = if near < far {
        (near.max(camera_near), far.min(camera_far).max(near * (1.0 + 1e-3)))
    } else {
        (camera_near, camera_far)
    };
    let splits = practical_splits(near, far, n, lambda).ok_or_else(|| format!("no splits of [{near}, {far}] into {n}"))?;
    let views = cascade_views(
        dir,
        &frustum,
        &splits,
        scene.shadow_map,
        scene.penumbra_reach(light),
        scene.bounds(),
        snap,
    )
    .ok_or("the cascades cannot be fitted")?;
    let lights = views
        .iter()
        .map(|c| LightInputs::from_view(light, &light.with_extent(c.view), &[], false))
        .collect();
    Ok(Cascades {
        scene: (),
        lights,
        eye: frustum.eye.to_array(),
        forward: frustum.forward.to_array(),
        splits,
        texels: views.iter().map(|c| c.texel).collect(),
    })
}

/// The scene's camera, as the runtime takes it.
pub fn camera(scene: &Scene) -> Camera {
    Camera {
        view_proj: scene.camera_view_proj().to_cols_array(),
        position: scene.camera_position().to_array(),
    }
}

/// `light`'s inputs in `scene` for `graph` (its view fitted as the scene's `shadow_fit`
/// says, and the light-sample views `graph` renders): what [`scene_inputs_for`] binds, for
/// a light that moves between frames (the frame's state: `FrameState::lights`). `scene` is the light's alone
/// where a scene has several ([`crate::session::single_light`]), as it is for binding.
pub fn light_inputs(scene: &Scene, light: &Light, graph: &PassGraph) -> Result<LightInputs, String> {
    let mut inputs = light_inputs_with_samples(scene, light, graph_samples(graph))?;
    crate::run::outside_the_model(graph, &mut inputs);
    Ok(inputs)
}

fn light_inputs_with_samples(scene: &Scene, light: &Light, n: u32) -> Result<LightInputs, String> {
    let (samples, closed) = light_samples(scene, light, n)?;
    Ok(LightInputs::from_view(light, &scene.light_view(light), &samples, closed))
}

/// `n` sample views of `light` in `scene`, in order along the light, and whether they
/// close a loop: [`sshc_runtime::light::sample_views`] (the conventions of
/// Heidrich et al. 2000, sections 3 and 4), each view the one a point light at the sample
/// would get ([`Scene::light_view`] of `Light::Point`, so the scene's `shadow_fit` holds).
///
/// Errors: `n` above [`MAX_LIGHT_SAMPLES`], a light at infinity, a point, sphere or disk
/// with `n > 1`, `n` not a multiple of a triangle's or rectangle's edges.
pub fn light_samples(scene: &Scene, light: &Light, n: u32) -> Result<(Vec<SampleFit>, bool), String> {
    sample_views(light, n, MAX_LIGHT_SAMPLES, |l| scene.light_view(l))
        .map_err(|e| format!("the scene's light ({}): {e}", light.kind_name()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::ShadowFit;
    use glam::{Mat4, Vec3, Vec4};

    fn scene(light: &str, fit: &str) -> Scene {
        let text = format!(
            "Scene(camera: Perspective(position: (0.0, 3.4, 3.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 45.0, width: 8, height: 8),
             shadow_map: 64, shadow_fit: {fit}, lights: [{light}],
             objects: [Object(mesh: Plane(size: (4.0, 4.0)), casts: false),
                       Object(mesh: Quad(a: (-0.5, 1.0, 0.45), b: (0.5, 1.0, 0.45), c: (0.35, 1.3, -0.45), d: (-0.2, 1.0, -0.35))),
                       Object(mesh: Box(size: (0.3, 0.3, 0.3)), transform: (translate: (1.2, 0.5, 0.8)))])"
        );
        Scene::from_str(&text, ".").unwrap_or_else(|e| panic!("{e}"))
    }

    const SEGMENT: &str = "Segment(a: (-0.6, 2.5, 0.0), b: (0.6, 2.5, 0.0))";
    const TRIANGLE: &str = "Triangle(a: (-0.6, 2.5, 0.3), b: (0.6, 2.5, 0.3), c: (0.0, 2.5, -0.5))";
    const RECTANGLE: &str =
        "Rectangle(center: (0.0, 2.5, 0.0), normal: (0.0, -1.0, 0.0), u_axis: (1.0, 0.0, 0.0), half_width: 0.6, half_height: 0.3)";

    fn positions(s: &SceneInputs) -> Vec<Vec3> {
        s.samples.iter().map(|v| Vec3::from_array(v.position)).collect()
    }

    /// Each weight is a ratio of f32 lengths summed in f32: a few ulps of 1 per sample.
    fn sum_tolerance(n: usize) -> f32 {
        4.0 * n as f32 * f32::EPSILON
    }

    fn half_sums(s: &SceneInputs) -> f32 {
        s.samples.iter().map(|v| 0.5 * (v.weights[0] + v.weights[1])).sum()
    }

    #[test]
    fn no_samples_unless_asked() {
        let s = scene(SEGMENT, "Scene");
        let plain = scene_inputs(&s).unwrap();
        assert!(plain.samples.is_empty() && !plain.samples_closed);
        assert_eq!(scene_inputs_with_samples(&s, 0).unwrap(), plain);
    }

    #[test]
    fn segment_samples_are_evenly_spaced_with_their_ends_and_weigh_their_segments() {
        let s = scene(SEGMENT, "Scene");
        let (a, b) = (Vec3::new(-0.6, 2.5, 0.0), Vec3::new(0.6, 2.5, 0.0));
        for n in 2..=MAX_LIGHT_SAMPLES {
            let inputs = scene_inputs_with_samples(&s, n).unwrap();
            assert!(!inputs.samples_closed);
            let p = positions(&inputs);
            assert_eq!(p.len(), n as usize);
            for (k, q) in p.iter().enumerate() {
                let want = a.lerp(b, k as f32 / (n - 1) as f32);
                assert!(q.distance(want) < 1e-6, "n = {n}, sample {k}: {q} != {want}");
            }
            // equal segments: 1 / (n - 1) each, none before the first or after the last
            let w = 1.0 / (n - 1) as f32;
            let first = inputs.samples[0].weights;
            let last = inputs.samples[n as usize - 1].weights;
            assert_eq!(first[0], 0.0);
            assert_eq!(last[1], 0.0);
            assert!((first[1] - w).abs() < 1e-6 && (last[0] - w).abs() < 1e-6, "{first:?} {last:?}");
            let sum = half_sums(&inputs);
            assert!((sum - 1.0).abs() <= sum_tolerance(n as usize), "n = {n}: {sum}");
        }
    }

    #[test]
    fn one_sample_is_the_centre_with_both_weights_one() {
        for (light, centre) in [
            (SEGMENT, Vec3::new(0.0, 2.5, 0.0)),
            (TRIANGLE, Vec3::new(0.0, 2.5, 0.1 / 3.0)),
            (RECTANGLE, Vec3::new(0.0, 2.5, 0.0)),
            ("Point(position: (0.2, 2.5, 0.1))", Vec3::new(0.2, 2.5, 0.1)),
            ("Sphere(center: (0.2, 2.5, 0.1), radius: 0.2)", Vec3::new(0.2, 2.5, 0.1)),
            (
                "Disk(center: (0.2, 2.5, 0.1), normal: (0.0, -1.0, 0.0), radius: 0.2)",
                Vec3::new(0.2, 2.5, 0.1),
            ),
        ] {
            let s = scene(light, "Scene");
            let inputs = scene_inputs_with_samples(&s, 1).unwrap();
            assert_eq!(inputs.samples.len(), 1, "{light}");
            let v = &inputs.samples[0];
            assert!(Vec3::from_array(v.position).distance(centre) < 1e-6, "{light}: {:?}", v.position);
            assert_eq!(v.weights, [1.0, 1.0], "{light}");
            assert!(!inputs.samples_closed);
            // the view of a point light at the centre
            let position = s.lights[0].center().unwrap();
            let p = s.light_view(&Light::Point { position });
            assert_eq!(v.light_view_proj, p.view_proj.to_cols_array(), "{light}");
            assert_eq!((v.near, v.far, v.light_proj_y), (p.near, p.far, p.proj.y_axis.y), "{light}");
        }
    }

    #[test]
    fn area_lights_walk_their_edges_corners_included_and_close_the_loop() {
        let tri = [Vec3::new(-0.6, 2.5, 0.3), Vec3::new(0.6, 2.5, 0.3), Vec3::new(0.0, 2.5, -0.5)];
        let rect = [
            Vec3::new(-0.6, 2.5, -0.3),
            Vec3::new(0.6, 2.5, -0.3),
            Vec3::new(0.6, 2.5, 0.3),
            Vec3::new(-0.6, 2.5, 0.3),
        ];
        for (light, corners) in [(TRIANGLE, &tri[..]), (RECTANGLE, &rect[..])] {
            let s = scene(light, "Scene");
            let e = corners.len();
            let perimeter: f32 = (0..e).map(|i| corners[i].distance(corners[(i + 1) % e])).sum();
            for n in (e..=MAX_LIGHT_SAMPLES as usize).step_by(e) {
                let inputs = scene_inputs_with_samples(&s, n as u32).unwrap();
                assert!(inputs.samples_closed, "{light}");
                let p = positions(&inputs);
                assert_eq!(p.len(), n);
                let per = n / e;
                for (k, q) in p.iter().enumerate() {
                    let (edge, j) = (k / per, k % per);
                    let want = corners[edge].lerp(corners[(edge + 1) % e], j as f32 / per as f32);
                    assert!(q.distance(want) < 1e-6, "{light}, n = {n}, sample {k}: {q} != {want}");
                }
                // every segment: its length over the perimeter; sample k's after is
                // sample k + 1's before, and the last's after is the first's before
                for k in 0..n {
                    let len = p[k].distance(p[(k + 1) % n]);
                    let after = inputs.samples[k].weights[1];
                    let before = inputs.samples[(k + 1) % n].weights[0];
                    assert!((after - len / perimeter).abs() < 1e-6, "{light}, n = {n}, segment {k}");
                    assert_eq!(after, before, "{light}, n = {n}, segment {k}");
                }
                let sum = half_sums(&inputs);
                assert!((sum - 1.0).abs() <= sum_tolerance(n), "{light}, n = {n}: {sum}");
            }
        }
    }

    #[test]
    fn samples_that_cannot_be_are_refused_with_the_reason() {
        for (light, n, want) in [
            ("Point(position: (0.0, 2.5, 0.0))", 2, "no edges to sample"),
            ("Sphere(center: (0.0, 2.5, 0.0), radius: 0.2)", 3, "no edges to sample"),
            (
                "Disk(center: (0.0, 2.5, 0.0), normal: (0.0, -1.0, 0.0), radius: 0.2)",
                2,
                "no edges to sample",
            ),
            ("Directional(direction: (0.0, 1.0, 0.0))", 1, "at infinity"),
            ("DistantDisk(direction: (0.0, 1.0, 0.0), angle_degrees: 5.0)", 2, "at infinity"),
            (TRIANGLE, 4, "multiple of 3, not 4"),
            (RECTANGLE, 6, "multiple of 4, not 6"),
            (SEGMENT, MAX_LIGHT_SAMPLES + 1, "above the limit of 16"),
        ] {
            let s = scene(light, "Scene");
            let e = scene_inputs_with_samples(&s, n).expect_err(light);
            assert!(e.contains(want), "{light}, {n}: {e}");
            assert!(e.starts_with("the scene's light ("), "{e}");
        }
    }

    /// Under either fit, every corner of every caster is inside each sample's clip volume
    /// and its linear depth in [0, 1]: each sample's map holds every caster.
    #[test]
    fn every_sample_view_sees_every_caster() {
        for fit in ["Scene", "Casters"] {
            for (light, n) in [(SEGMENT, 9), (SEGMENT, 2), (TRIANGLE, 12), (RECTANGLE, 16), (SEGMENT, 1)] {
                let s = scene(light, fit);
                assert_eq!(s.shadow_fit() == ShadowFit::Casters, fit == "Casters");
                let inputs = scene_inputs_with_samples(&s, n).unwrap();
                let casting = s.casting_triangles();
                for (k, v) in inputs.samples.iter().enumerate() {
                    let (vp, view) = (Mat4::from_cols_array(&v.light_view_proj), Mat4::from_cols_array(&v.light_view));
                    for (t, tri) in s.triangles().iter().enumerate().filter(|(t, _)| casting[*t]) {
                        for c in tri {
                            let clip: Vec4 = vp * c.extend(1.0);
                            let w = clip.w;
                            // f32 rounding of the projection (the fits pad by 0.1 % or a texel)
                            let tol = 1e-5 * w;
                            assert!(w > 0.0, "{fit} {light} view {k}: triangle {t} behind");
                            assert!(
                                clip.x.abs() <= w + tol && clip.y.abs() <= w + tol,
                                "{fit} {light} view {k}: corner {c} outside ({clip})"
                            );
                            let depth = (-(view * c.extend(1.0)).z - v.near) / (v.far - v.near);
                            assert!((-1e-5..=1.0 + 1e-5).contains(&depth), "{fit} {light} view {k}: depth {depth}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn the_graph_says_how_many_samples_to_bind() {
        let source = include_str!("../../techniques/hard.ron");
        let mut g = sshc::compile_str(source, &sshc::CompileOptions::default()).unwrap().graph;
        let s = scene(SEGMENT, "Casters");
        // no per-sample pass: none bound, whatever `samples` says
        g.samples = 5;
        assert_eq!(graph_samples(&g), 0);
        assert!(scene_inputs_for(&s, &g).unwrap().samples.is_empty());
        g.passes[0].views = sshc_runtime::graph::Views::PerLightSample;
        for n in [1, 2, 5, 9, 16] {
            g.samples = n;
            assert_eq!(graph_samples(&g), n);
            assert_eq!(scene_inputs_for(&s, &g).unwrap().samples.len(), n as usize);
        }
    }
}
