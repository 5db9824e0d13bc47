//! The render world's side: sshc's stages kept across frames, fed from what was extracted.
//!
//! - **Extract** (Bevy's `ExtractSchedule`): the mesh entities (their mesh asset, world
//!   transform, and whether they cast and receive), each mesh asset sshc does not hold yet
//!   (its positions, normals and indices, read from the main world's `Assets<Mesh>`), the
//!   light carrying [`crate::SshcShadow`], and the techniques that loaded or reloaded.
//! - **Prepare** (`RenderSystems::Prepare`): the scene changed in place (meshes and
//!   instances added or removed: `Scene::add_mesh`, `add_instance`, `remove_instance`;
//!   every transform set), the targets made, resized or given the changed scene, the light
//!   fitted to the casters, then `Targets::prepare` (queue writes only).
//! - **Record** (Bevy's `Core3d` schedule, before the main pass): `Targets::record` into
//!   Bevy's command encoder, then sshc's visibility copied into the image the receivers'
//!   material reads.
//!
//! Nothing here hands an error to Bevy's device error handler: every sshc call returns its
//! error as a value, which is logged once (naming the light entity and the technique file)
//! and put in [`Status`], so that the main world leaves Bevy's own shadow in place for that
//! light.

use crate::asset::SshcTechnique;
use bevy::asset::AssetId;
use bevy::ecs::entity::EntityHashMap;
use bevy::log::{error, info, warn};
use bevy::prelude::*;
use bevy::render::Extract;
use bevy::render::camera::TemporalJitter;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_asset::RenderAssets;
use bevy::render::renderer::{RenderAdapter, RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::sync_world::MainEntity;
use bevy::render::texture::GpuImage;
use bevy::render::view::ExtractedView;
use sshc_runtime::gpu::{self as sshc_gpu, Camera as SshcCamera, Fit, FrameState, Gpu, LightInputs, Scene, Sizes, Targets, Technique};
use sshc_runtime::graph::ValidGraph;
use sshc_runtime::light::Light;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Per light entity (main world): the error that stopped sshc's shadow for it, if any. Shared
/// by both worlds: the render world writes it, the main world reads it to leave Bevy's own
/// shadow in place for a light sshc cannot shade.
#[derive(Resource, Clone, Default)]
pub struct Status(pub Arc<Mutex<HashMap<Entity, String>>>);

impl Status {
    /// The error for `light`, if sshc's shadow does not run for it.
    pub fn error(&self, light: Entity) -> Option<String> {
        self.0.lock().ok().and_then(|m| m.get(&light).cloned())
    }

    fn set(&self, light: Entity, e: Option<String>) {
        if let Ok(mut m) = self.0.lock() {
            match e {
                Some(e) => m.insert(light, e),
                None => m.remove(&light),
            };
        }
    }
}

/// The host CPU time of the plugin's render-world work per frame, microseconds: prepare
/// (the scene's changes, the targets, `Targets::prepare`) and record (`Targets::record` and
/// the visibility's copy); the last [`CpuTimes::KEPT`] frames, in both worlds.
#[derive(Resource, Clone, Default)]
pub struct CpuTimes(pub Arc<Mutex<std::collections::VecDeque<[f64; 2]>>>);

impl CpuTimes {
    pub const KEPT: usize = 1024;

    fn push(&self, k: usize, us: f64) {
        if let Ok(mut v) = self.0.lock() {
            if k == 0 {
                if v.len() == Self::KEPT {
                    v.pop_front();
                }
                v.push_back([us, 0.0]);
            } else if let Some(last) = v.back_mut() {
                last[1] += us;
            }
        }
    }

    /// The medians of prepare and of record over the frames kept.
    pub fn medians(&self) -> Option<[f64; 2]> {
        let v = self.0.lock().ok()?;
        let median = |k: usize| {
            let mut x: Vec<f64> = v.iter().map(|t| t[k]).collect();
            x.sort_by(f64::total_cmp);
            x.get(x.len() / 2).copied()
        };
        Some([median(0)?, median(1)?])
    }
}

/// The shadow map's size where neither the component nor the technique gives one.
pub const DEFAULT_MAP_SIZE: u32 = 1024;

/// One mesh entity as extracted.
#[derive(Clone, Debug)]
pub struct ExtractedInstance {
    pub entity: Entity,
    pub mesh: AssetId<Mesh>,
    pub transform: [f32; 16],
    pub casts: bool,
    pub receives: bool,
}

/// The light with sshc's shadow, as extracted.
#[derive(Clone, Debug)]
pub struct ExtractedLight {
    pub entity: Entity,
    pub technique: AssetId<SshcTechnique>,
    /// The technique's asset path, for messages.
    pub path: String,
    pub params: Vec<(String, f64)>,
    /// The component's map size, if it sets one.
    pub map_size: Option<u32>,
    /// From the scene towards the sun (glam 0.34's order: x, y, z).
    pub direction: [f32; 3],
    pub angle_degrees: f32,
    /// The image the receivers read sshc's visibility from.
    pub visibility: AssetId<Image>,
    /// The technique file's load: still loading (`Some(None)`), or failed (the asset
    /// server's error, which carries sshc's diagnostic).
    pub failed: Option<Option<String>>,
}

/// What the extract step hands the prepare step for one frame.
#[derive(Resource, Default)]
pub struct Extracted {
    pub instances: Vec<ExtractedInstance>,
    /// Meshes sshc does not hold yet: converted, or why they cannot be.
    pub new_meshes: Vec<(AssetId<Mesh>, Result<sshc_gpu::Mesh, String>)>,
    /// Mesh assets sshc holds (or refused) that changed in the main world
    /// (`AssetEvent::Modified`), read again.
    pub changed_meshes: Vec<(AssetId<Mesh>, Result<sshc_gpu::Mesh, String>)>,
    pub light: Option<ExtractedLight>,
    /// The main-world camera whose view sshc shades ([`shaded_camera`]), and whether
    /// other active 3D cameras render too.
    pub camera: Option<(Entity, bool)>,
    /// Techniques loaded or reloaded since the last frame.
    pub techniques: Vec<(AssetId<SshcTechnique>, SshcTechnique)>,
    /// Meshes entities place whose asset is not in the main world yet: frames waited.
    pub missing: HashMap<AssetId<Mesh>, u32>,
}

/// The camera whose view sshc shades: the active `Camera3d` of the lowest `Camera::order`
/// (Bevy draws it first: a game's main view, before a minimap or an overlay), the lowest
/// entity among equals. The receivers' material holds one visibility image, so one view
/// is shaded; the others' receivers read it too (docs/bevy.md, "Not yet"), which the
/// plugin logs once.
pub fn shaded_camera<'a>(cameras: impl Iterator<Item = (Entity, &'a Camera)>) -> Option<(Entity, &'a Camera)> {
    cameras.filter(|(_, c)| c.is_active).min_by_key(|(e, c)| (c.order, *e))
}

/// Frames a mesh asset an entity places may be missing from the main world (still
/// loading) before it is refused (not kept there).
pub const MISSING_FRAMES: u32 = 600;

/// sshc's stages in the render world.
#[derive(Resource)]
pub struct SshcRender {
    gpu: Gpu,
    /// Each technique asset's compiled form, its loaded technique (made on first use) and
    /// its version (each load or reload a new one).
    techniques: HashMap<AssetId<SshcTechnique>, Loaded>,
    versions: u64,
    scene: Option<Scene>,
    /// Mesh asset -> sshc's mesh index in `scene`.
    meshes: HashMap<AssetId<Mesh>, usize>,
    /// Instance order in `scene`: the main-world entity of each instance and the mesh
    /// asset it places.
    order: Vec<(Entity, AssetId<Mesh>)>,
    /// The frame's instances by entity (index into the extracted ones), and the entities
    /// the scene holds: kept across frames so that a frame allocates nothing.
    wanted: EntityHashMap<usize>,
    held: bevy::ecs::entity::EntityHashSet,
    /// Meshes or instances added or removed so far (the targets take the scene again when
    /// theirs is older).
    scene_changes: u64,
    transforms: Vec<[f32; 16]>,
    /// Per view (render-world entity): its targets, the technique they run, their sizes.
    views: EntityHashMap<ViewTargets>,
    /// The last error logged, so that a failing frame logs once, not every frame.
    logged: Option<String>,
    /// The last failed reload logged.
    reload_logged: Option<String>,
    /// Whether "several cameras, one view shaded" was logged.
    views_logged: bool,
    status: Status,
    /// What prepare decided for record: the views that are ready, and the image to copy into.
    ready: Vec<(Entity, AssetId<Image>)>,
    /// Mesh assets that could not be converted (logged once each).
    refused: HashMap<AssetId<Mesh>, String>,
}

struct Loaded {
    compiled: SshcTechnique,
    technique: Option<Technique>,
    version: u64,
}

struct ViewTargets {
    /// The scene's change count these targets last took (`Targets::set_scene`).
    scene_seen: u64,
    technique: AssetId<SshcTechnique>,
    technique_version: u64,
    targets: Targets,
    state: FrameState,
    sizes: Sizes,
}

impl SshcRender {
    pub fn new(adapter: &RenderAdapter, device: &RenderDevice, queue: &RenderQueue, status: Status) -> SshcRender {
        let gpu = Gpu::from_host(adapter, device.wgpu_device().clone(), (**queue).clone());
        SshcRender {
            gpu,
            techniques: HashMap::new(),
            versions: 0,
            scene: None,
            meshes: HashMap::new(),
            order: Vec::new(),
            wanted: EntityHashMap::default(),
            held: Default::default(),
            scene_changes: 0,
            transforms: Vec::new(),
            views: EntityHashMap::default(),
            logged: None,
            reload_logged: None,
            views_logged: false,
            status,
            ready: Vec::new(),
            refused: HashMap::new(),
        }
    }

    /// Whether sshc holds mesh `id` (or refused it): the extract step converts only the others.
    pub fn knows_mesh(&self, id: AssetId<Mesh>) -> bool {
        self.meshes.contains_key(&id) || self.refused.contains_key(&id)
    }
}

/// The extract step (main world read through `Extract`).
#[expect(
    clippy::type_complexity,
    clippy::too_many_arguments,
    reason = "a Bevy system takes its world access as parameters"
)]
pub fn extract(
    mut out: ResMut<Extracted>,
    render: Option<Res<SshcRender>>,
    meshes: Extract<Res<Assets<Mesh>>>,
    techniques: Extract<Res<Assets<SshcTechnique>>>,
    mut technique_events: Extract<MessageReader<AssetEvent<SshcTechnique>>>,
    mut mesh_events: Extract<MessageReader<AssetEvent<Mesh>>>,
    entities: Extract<
        Query<(
            Entity,
            &Mesh3d,
            &GlobalTransform,
            &ViewVisibility,
            Has<bevy::light::NotShadowCaster>,
            Has<bevy::light::NotShadowReceiver>,
        )>,
    >,
    lights: Extract<Query<(Entity, &crate::SshcShadow, &GlobalTransform), With<DirectionalLight>>>,
    cameras: Extract<Query<(Entity, &Camera), With<Camera3d>>>,
    server: Extract<Res<AssetServer>>,
) {
    out.camera = shaded_camera(cameras.iter()).map(|(e, _)| (e, cameras.iter().filter(|(_, c)| c.is_active).count() > 1));
    out.instances.clear();
    out.new_meshes.clear();
    out.changed_meshes.clear();
    out.techniques.clear();
    let Some(render) = render else {
        mesh_events.clear();
        return;
    };
    // a mesh sshc holds, changed in place in the main world: read again (once a frame
    // however many times it changed); one whose data left the main world keeps sshc's copy
    for e in mesh_events.read() {
        if let AssetEvent::Modified { id } = e
            && render.knows_mesh(*id)
            && !out.changed_meshes.iter().any(|(c, _)| c == id)
            && let Some(m) = meshes.get(*id)
        {
            out.changed_meshes.push((*id, convert_mesh(m)));
        }
    }
    let mut seen = std::collections::HashSet::new();
    for (entity, mesh, transform, visible, no_cast, no_receive) in &entities {
        if !visible.get() && no_cast {
            continue;
        }
        let id = mesh.0.id();
        if !render.knows_mesh(id) && seen.insert(id) {
            // a mesh still loading waits; one absent for MISSING_FRAMES frames is refused
            // (its data is not kept in the main world)
            match meshes.get(id) {
                Some(m) => {
                    out.missing.remove(&id);
                    out.new_meshes.push((id, convert_mesh(m)));
                }
                None => {
                    let frames = out.missing.entry(id).or_insert(0);
                    *frames += 1;
                    if *frames == MISSING_FRAMES {
                        out.new_meshes.push((
                            id,
                            Err(format!(
                                "its mesh asset was not in the main world for {MISSING_FRAMES} frames: sshc reads the vertices there (`RenderAssetUsages::MAIN_WORLD`)"
                            )),
                        ));
                    }
                }
            }
        }
        out.instances.push(ExtractedInstance {
            entity,
            mesh: id,
            transform: transform.to_matrix().to_cols_array(),
            casts: !no_cast,
            receives: !no_receive,
        });
    }
    // a stable draw order: by entity (each once: an unstable sort, which allocates nothing)
    out.instances.sort_unstable_by_key(|i| i.entity);
    for e in technique_events.read() {
        if let AssetEvent::LoadedWithDependencies { id } | AssetEvent::Modified { id } = e
            && let Some(t) = techniques.get(*id)
        {
            out.techniques.push((*id, t.clone()));
        }
    }
    // the light, updated in place: a frame whose light and technique are the ones before
    // allocates nothing (the path is made again only for another technique)
    let Some((entity, s, transform)) = lights.iter().find(|(_, s, _)| s.enabled) else {
        out.light = None;
        return;
    };
    let technique = s.technique.id();
    let failed = match server.get_load_state(technique) {
        Some(bevy::asset::LoadState::Failed(e)) => Some(Some(e.to_string())),
        Some(bevy::asset::LoadState::Loaded) => None,
        _ => Some(None),
    };
    let same = out.light.as_ref().is_some_and(|l| l.entity == entity && l.technique == technique);
    if !same {
        out.light = Some(ExtractedLight {
            entity,
            technique,
            path: server
                .get_path(technique)
                .map_or_else(|| "(a technique not loaded from a file)".into(), |p| p.to_string()),
            params: Vec::new(),
            map_size: None,
            direction: [0.0; 3],
            angle_degrees: 0.0,
            visibility: s.visibility.id(),
            failed: None,
        });
    }
    if let Some(l) = &mut out.light {
        l.params.clone_from(&s.params);
        l.map_size = s.map_size;
        l.direction = transform.back().to_array();
        l.angle_degrees = s.angular_diameter_degrees;
        l.visibility = s.visibility.id();
        l.failed = failed;
    }
}

/// A Bevy mesh as sshc's: triangle lists with positions and normals, indexed or not.
pub fn convert_mesh(mesh: &Mesh) -> Result<sshc_gpu::Mesh, String> {
    use bevy::mesh::{Indices, PrimitiveTopology, VertexAttributeValues};
    if mesh.primitive_topology() != PrimitiveTopology::TriangleList {
        return Err(format!(
            "its topology is {:?}; sshc draws triangle lists",
            mesh.primitive_topology()
        ));
    }
    let positions = match mesh.attribute(Mesh::ATTRIBUTE_POSITION) {
        Some(VertexAttributeValues::Float32x3(p)) => p.clone(),
        _ => return Err("it has no Float32x3 positions".into()),
    };
    let normals = match mesh.attribute(Mesh::ATTRIBUTE_NORMAL) {
        Some(VertexAttributeValues::Float32x3(n)) => n.clone(),
        _ => return Err("it has no Float32x3 normals (`Mesh::compute_normals` makes them)".into()),
    };
    let indices: Vec<u32> = match mesh.indices() {
        Some(Indices::U16(i)) => i.iter().map(|&x| u32::from(x)).collect(),
        Some(Indices::U32(i)) => i.clone(),
        None => (0..positions.len() as u32).collect(),
    };
    Ok(sshc_gpu::Mesh {
        name: String::new(),
        positions,
        normals,
        indices,
    })
}

/// The camera views prepare reads: render entity, main-world camera, view, size, jitter.
type Views<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static MainEntity,
        &'static ExtractedView,
        &'static bevy::render::camera::ExtractedCamera,
        Option<&'static TemporalJitter>,
    ),
>;

/// The prepare step: the scene, the targets and the frame's uniforms.
pub fn prepare(times: Res<CpuTimes>, render: Option<ResMut<SshcRender>>, mut extracted: ResMut<Extracted>, views: Views) {
    let Some(mut render) = render else { return };
    let start = std::time::Instant::now();
    let render = &mut *render;
    render.ready.clear();
    for (id, t) in extracted.techniques.drain(..) {
        info!("sshc: technique `{}` loaded", t.name());
        render.versions += 1;
        let version = render.versions;
        render.techniques.insert(
            id,
            Loaded {
                compiled: t,
                technique: None,
                version,
            },
        );
    }
    // taken for the frame and put back after: the next extract updates it in place
    let Some(light) = extracted.light.take() else {
        return;
    };
    // a file that failed to load (or to reload): a technique loaded before keeps rendering
    let held = render.techniques.contains_key(&light.technique);
    let outcome = match &light.failed {
        Some(None) if !held => Err("its technique is loading".to_string()),
        Some(Some(e)) if !held => Err(format!("its file did not load: {e}")),
        _ => prepare_light(render, &mut extracted, &light, &views),
    };
    if let (Some(Some(e)), true) = (&light.failed, held) {
        let m = format!(
            "sshc: technique file {} did not reload, the previous version keeps rendering: {e}",
            light.path
        );
        if render.reload_logged.as_ref() != Some(&m) {
            error!("{m}");
            render.reload_logged = Some(m);
        }
    }
    let loading = matches!(light.failed, Some(None)) && !held;
    let message = outcome
        .err()
        .map(|e| format!("sshc's shadow for light {} (technique {}): {e}", light.entity, light.path));
    if message != render.logged {
        if let (Some(m), false) = (&message, loading) {
            error!("{m}; Bevy's own shadow stays for this light");
        }
        render.logged = message.clone();
    }
    render.status.set(light.entity, message);
    extracted.light = Some(light);
    times.push(0, start.elapsed().as_secs_f64() * 1e6);
}

fn prepare_light(render: &mut SshcRender, extracted: &mut Extracted, light: &ExtractedLight, views: &Views) -> Result<(), String> {
    let e = |e: sshc_gpu::RuntimeError| e.to_string();
    let gpu = render.gpu.clone();
    let loaded = render
        .techniques
        .get_mut(&light.technique)
        .ok_or_else(|| "the technique has not loaded (see the asset log for why)".to_string())?;
    if loaded.technique.is_none() {
        let graph = ValidGraph::try_from(loaded.compiled.compiled.graph.clone()).map_err(|e| e.to_string())?;
        loaded.technique = Some(Technique::new(&gpu, graph, loaded.compiled.compiled.shaders.clone()).map_err(e)?);
    }
    let (technique, version) = (loaded.technique.clone().ok_or("no technique")?, loaded.version);
    // the component's size, else the technique's (a tuned technique's), else 1024
    let map_size = light.map_size.or(technique.graph().shadow_map).unwrap_or(DEFAULT_MAP_SIZE);
    // the scene: uploaded empty once, for this technique's needs, then changed in place
    let edges = technique.needs_edge_adjacency();
    if render.scene.as_ref().is_none_or(|s| edges && !s.has_edges()) {
        render.scene = Some(Scene::upload(&gpu, &sshc_gpu::Geometry::default(), &[&technique]).map_err(e)?);
        render.meshes.clear();
        render.order.clear();
        render.transforms.clear();
        render.views.clear();
    }
    let scene = render.scene.as_mut().ok_or("no scene")?;
    // a changed mesh: its instances and the mesh removed, the new version added as a new
    // mesh (its instances are added again below, as entities new to the scene)
    for (id, mesh) in extracted.changed_meshes.drain(..) {
        render.refused.remove(&id);
        if let Some(old) = render.meshes.remove(&id) {
            for k in (0..render.order.len()).rev() {
                if render.order[k].1 == id {
                    scene.remove_instance(k).map_err(e)?;
                    render.order.remove(k);
                    render.transforms.remove(k);
                }
            }
            scene.remove_mesh(old).map_err(e)?;
            render.scene_changes += 1;
        }
        extracted.new_meshes.push((id, mesh));
    }
    for (id, mesh) in extracted.new_meshes.drain(..) {
        match mesh.and_then(|m| scene.add_mesh(&m).map_err(|e| e.to_string())) {
            Ok(index) => {
                render.meshes.insert(id, index);
                render.scene_changes += 1;
            }
            Err(why) => {
                error!("sshc: mesh {id:?} is not drawn in sshc's shadows: {why}");
                render.refused.insert(id, why);
            }
        }
    }
    // instances removed (their entity gone, or its mesh changed), from the last down
    // the frame's wanted instances (entity -> index into the extracted ones) and those the
    // scene holds: maps kept across frames, cleared, so that a frame allocates nothing
    render.wanted.clear();
    for (k, i) in extracted.instances.iter().enumerate() {
        if render.meshes.contains_key(&i.mesh) {
            render.wanted.insert(i.entity, k);
        }
    }
    for k in (0..render.order.len()).rev() {
        let (entity, mesh) = render.order[k];
        let same = render.wanted.get(&entity).is_some_and(|&w| extracted.instances[w].mesh == mesh);
        if !same {
            scene.remove_instance(k).map_err(e)?;
            render.order.remove(k);
            render.transforms.remove(k);
            render.scene_changes += 1;
        }
    }
    render.held.clear();
    render.held.extend(render.order.iter().map(|o| o.0));
    for i in extracted.instances.iter().filter(|i| !render.held.contains(&i.entity)) {
        let Some(&mesh) = render.meshes.get(&i.mesh) else { continue };
        scene
            .add_instance(&sshc_gpu::Instance {
                name: format!("{}", i.entity),
                mesh,
                transform: i.transform,
                casts: i.casts,
                receives: i.receives,
                moves: true,
            })
            .map_err(e)?;
        render.order.push((i.entity, i.mesh));
        render.transforms.push(i.transform);
        render.scene_changes += 1;
    }
    // the transforms, written (and the instances placed again) only when one moved
    let mut moved = false;
    for (k, (entity, _)) in render.order.iter().enumerate() {
        if let Some(i) = render.wanted.get(entity).map(|&w| &extracted.instances[w])
            && render.transforms[k].map(f32::to_bits) != i.transform.map(f32::to_bits)
        {
            render.transforms[k] = i.transform;
            moved = true;
        }
    }
    if moved {
        scene.set_transforms(&render.transforms).map_err(e)?;
    }
    let sun = Light::DistantDisk {
        direction: sshc_runtime::light::glam::Vec3::from_array(light.direction),
        angle_degrees: light.angle_degrees,
    };
    let Some((shaded, others)) = extracted.camera else {
        return Ok(());
    };
    if others && !render.views_logged {
        warn!(
            "sshc: several active 3D cameras; sshc shades camera {shaded}'s view only (the lowest order), and the receivers in the others read its visibility"
        );
        render.views_logged = true;
    }
    for (view, main, extracted_view, camera, jitter) in views {
        if main.id() != shaded {
            continue;
        }
        let Some(size) = camera.physical_viewport_size else { continue };
        let view_size = size.as_vec2();
        let size = (size.x, size.y);
        // the main pass's own projection: jittered as Bevy jitters it under temporal
        // anti-aliasing (`prepare_view_uniforms`), so that sshc's visibility lies on the
        // pixels the receivers are drawn at in this frame
        let view_from_world = extracted_view.world_from_view.to_matrix().inverse();
        let clip_from_world = match jitter {
            Some(jitter) => {
                let mut clip_from_view = extracted_view.clip_from_view;
                jitter.jitter_projection(&mut clip_from_view, view_size);
                clip_from_view * view_from_world
            }
            None => extracted_view
                .clip_from_world
                .unwrap_or_else(|| extracted_view.clip_from_view * view_from_world),
        };
        // Bevy's projection is reverse-Z (and infinite): mapped to sshc's forward depth
        let cam = SshcCamera::from_reverse_z(
            clip_from_world.to_cols_array(),
            extracted_view.world_from_view.translation().to_array(),
        );
        let sizes = Sizes {
            camera: size,
            shadow: map_size,
        };
        let fresh = match render.views.get(&view) {
            Some(v) => v.technique != light.technique || v.technique_version != version || v.sizes.shadow != sizes.shadow,
            None => true,
        };
        if fresh {
            let first = LightInputs::fit(&sun, scene.boxes(), Fit::Casters, sizes.shadow, 0).map_err(e)?;
            let state = FrameState::new(&technique, cam, vec![first]);
            let targets = Targets::new(&technique, scene, &state, sizes).map_err(e)?;
            render.views.insert(
                view,
                ViewTargets {
                    scene_seen: render.scene_changes,
                    technique: light.technique,
                    technique_version: version,
                    targets,
                    state,
                    sizes,
                },
            );
        }
        let v = render.views.get_mut(&view).ok_or("no targets")?;
        if v.sizes.camera != size {
            v.targets.resize(size).map_err(e)?;
            v.sizes.camera = size;
        }
        if v.scene_seen != render.scene_changes {
            v.targets.set_scene(scene).map_err(e)?;
            v.scene_seen = render.scene_changes;
        }
        v.state.camera = cam;
        v.state.lights[0] = v.targets.fit_light(scene, 0, &sun, Fit::Casters).map_err(e)?;
        for (name, value) in &light.params {
            v.state.params.set(name, *value).map_err(e)?;
        }
        v.targets.prepare(scene, &v.state).map_err(e)?;
        render.ready.push((view, light.visibility));
    }
    Ok(())
}

/// The record step, per camera view: sshc's passes into Bevy's encoder, then the
/// visibility copied into the receivers' image.
pub fn record(
    view: ViewQuery<&ExtractedView>,
    render: Option<Res<SshcRender>>,
    images: Res<RenderAssets<GpuImage>>,
    times: Res<CpuTimes>,
    mut ctx: RenderContext,
) {
    let Some(render) = render else { return };
    let start = std::time::Instant::now();
    let entity = view.entity();
    let Some(&(_, image)) = render.ready.iter().find(|(v, _)| *v == entity) else {
        return;
    };
    let (Some(scene), Some(v)) = (&render.scene, render.views.get(&entity)) else {
        return;
    };
    // sshc's passes as one span of Bevy's render diagnostics (`render/sshc_shadows/...`,
    // with `RenderDiagnosticsPlugin`), beside Bevy's own passes
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let span = diagnostics.time_span(ctx.command_encoder(), "sshc_shadows");
    let recorded = v.targets.record(scene, ctx.command_encoder());
    span.end(ctx.command_encoder());
    times.push(1, start.elapsed().as_secs_f64() * 1e6);
    if let Err(e) = recorded {
        error!("sshc: recording the shadow passes: {e}");
        return;
    }
    let encoder = ctx.command_encoder();
    let Some(gpu_image) = images.get(image) else { return };
    let source = v.targets.visibility();
    let (w, h) = (
        source.width().min(gpu_image.texture.width()),
        source.height().min(gpu_image.texture.height()),
    );
    if source.format() != gpu_image.texture.format() || w == 0 || h == 0 {
        return;
    }
    encoder.copy_texture_to_texture(
        source.as_image_copy(),
        gpu_image.texture.as_image_copy(),
        sshc_runtime::wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
}
