//! The plugin inside a real Bevy 0.20 app, headless on lavapipe: a small scene (a ground,
//! a box, a sphere) under a sun with sshc's shadow, rendered into an image and read back.
//! Each capture is an app of its own in a process of its own (this test binary run again
//! on the hidden test `capture_child`: two Bevy apps made one after the other in one
//! process were seen to read back the same frame), stepped frame by frame until the
//! technique has loaded, the pipelines are ready and the read-backs have settled.

use bevy::app::AppExit;
use bevy::asset::RenderAssetUsages;
use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat, TextureUsages};
use bevy::render::view::Tonemapping;
use bevy::window::ExitCondition;
use bevy_sshc::{SshcShadow, SshcShadowsPlugin, Status};
use std::sync::{Arc, Mutex};

/// The frame's size: rows of 128 pixels of 4 bytes are already aligned for read-back.
const SIZE: u32 = 128;
/// Frames stepped after sshc first shades the light before the read-backs are looked at:
/// Bevy compiles its pipelines in the background, so the first frames may lack a mesh.
/// The scene and sun stand still, so the frames then settle: a run ends when SETTLE
/// read-backs in a row are the same.
const SETTLE: u32 = 10;
/// Frames at most before a test gives up (lavapipe: about 20 ms a frame here).
const MAX_FRAMES: u32 = 600;

/// One run's set-up.
#[derive(Clone, Debug)]
struct Run {
    technique: String,
    enabled: bool,
    /// The sun's turn about y, degrees (its elevation is 40 degrees).
    turn: f32,
    sun_degrees: f32,
    /// Bevy's shadow maps for the light (on unless a test turns them off).
    maps: bool,
    illuminance: f32,
    keep_bevy_shadow: bool,
    /// After the first settled frame: a box spawned, and the frame settled again.
    spawn: bool,
    /// A glTF scene (`GLTF_PATH`, written by the test) loaded by Bevy's loader beside the rest.
    gltf: bool,
    /// The camera's projection jittered as temporal anti-aliasing jitters it.
    jitter: bool,
    /// Bevy's device with WebGPU's defaults only (no feature beyond them).
    webgpu: bool,
    /// The component's map size (`None`: the technique's own, else the default).
    map: Option<u32>,
    /// A second camera (order 1, another view, a 64^2 image of its own), as a minimap.
    second_camera: bool,
}

impl Run {
    fn of(technique: &str) -> Run {
        Run {
            technique: format!("techniques/{technique}.ron"),
            enabled: true,
            turn: 30.0,
            sun_degrees: 4.0,
            maps: true,
            illuminance: 8000.0,
            keep_bevy_shadow: false,
            spawn: false,
            gltf: false,
            jitter: false,
            webgpu: false,
            map: Some(512),
            second_camera: false,
        }
    }
}

/// What a run read back, and the main world's state to compute the same frame without Bevy.
#[derive(Default, Clone)]
struct Captured {
    rgba: Vec<u8>,
    visibility: Vec<f32>,
    /// sshc's error for the light at the end (`None`: sshc shades it).
    status: Option<String>,
    /// The same frame by sshc's runtime alone, on its own device, from the main world's
    /// meshes, transforms, camera and light (empty where sshc does not shade the light).
    alone: Vec<f32>,
}

/// The last read-backs of the frame and of the visibility, and how many of each arrived.
#[derive(Resource, Clone, Default)]
struct Shared(Arc<Mutex<Readbacks>>);

/// The frame's bytes, the visibility's, and the count of each read back.
type Readbacks = (Vec<u8>, Vec<u8>, u64, u64);

/// A mesh entity as the plugin extracts it: entity, mesh, transform, casts, receives.
type Extracted = (Entity, AssetId<Mesh>, [f32; 16], bool, bool);

fn sun(turn: f32) -> Transform {
    let t = turn.to_radians();
    let to_sun = Vec3::new(t.cos() * 0.77, 0.64, t.sin() * 0.77);
    Transform::from_translation(to_sun * 10.0).looking_at(Vec3::ZERO, Vec3::Y)
}

fn app(run: &Run) -> (App, Shared) {
    let mut app = App::new();
    let plugins = DefaultPlugins
        .set(AssetPlugin {
            file_path: concat!(env!("CARGO_MANIFEST_DIR"), "/../..").into(),
            // the hot-reload test watches its technique file; the others read once
            watch_for_changes_override: Some(run.technique == RELOAD_PATH),
            ..default()
        })
        .set(WindowPlugin {
            primary_window: None,
            exit_condition: ExitCondition::DontExit,
            ..default()
        })
        .set(bevy::render::RenderPlugin {
            // every pipeline ready in the frame that first needs it: a frame read back
            // is whole (with background compilation the first ones lack meshes)
            synchronous_pipeline_compilation: true,
            render_creation: bevy::render::settings::RenderCreation::Automatic(Box::new(bevy::render::settings::WgpuSettings {
                priority: match run.webgpu {
                    true => bevy::render::settings::WgpuSettingsPriority::WebGPU,
                    false => bevy::render::settings::WgpuSettingsPriority::Functionality,
                },
                ..default()
            })),
            ..default()
        });
    // the suite builds with the example's window (feature `window`): no window here
    #[cfg(feature = "window")]
    let plugins = plugins.disable::<bevy::winit::WinitPlugin>();
    app.add_plugins(plugins).add_plugins(SshcShadowsPlugin);
    let shared = Shared::default();
    app.insert_resource(shared.clone());
    let run = run.clone();
    app.add_systems(
        Startup,
        move |mut commands: Commands,
              server: Res<AssetServer>,
              mut meshes: ResMut<Assets<Mesh>>,
              mut materials: ResMut<Assets<StandardMaterial>>,
              mut images: ResMut<Assets<Image>>| {
            let grey = materials.add(StandardMaterial {
                base_color: Color::srgb(0.8, 0.8, 0.8),
                perceptual_roughness: 1.0,
                ..default()
            });
            commands.spawn((
                Mesh3d(meshes.add(Plane3d::default().mesh().size(6.0, 6.0))),
                MeshMaterial3d(grey.clone()),
            ));
            commands.spawn((
                Mesh3d(meshes.add(Cuboid::new(0.8, 1.2, 0.8))),
                MeshMaterial3d(grey.clone()),
                Transform::from_xyz(-0.4, 0.6, 0.0),
            ));
            commands.spawn((
                Mesh3d(meshes.add(Sphere::new(0.4).mesh().uv(24, 12))),
                MeshMaterial3d(grey),
                Transform::from_xyz(0.9, 0.9, 0.6),
            ));
            if run.gltf {
                commands.spawn((
                    bevy::world_serialization::WorldAssetRoot(server.load(GltfAssetLabel::Scene(0).from_asset(GLTF_PATH))),
                    Transform::from_xyz(1.2, 0.0, -1.0),
                ));
            }
            let mut shadow = SshcShadow::new(server.load(run.technique.clone()), &mut images);
            shadow.enabled = run.enabled;
            shadow.keep_bevy_shadow = run.keep_bevy_shadow;
            shadow.angular_diameter_degrees = run.sun_degrees;
            shadow.map_size = run.map;
            let visibility = shadow.visibility.clone();
            commands.spawn((
                DirectionalLight {
                    shadow_maps_enabled: run.maps,
                    illuminance: run.illuminance,
                    ..default()
                },
                sun(run.turn),
                shadow,
            ));
            let mut target = Image::new_fill(
                Extent3d {
                    width: SIZE,
                    height: SIZE,
                    depth_or_array_layers: 1,
                },
                TextureDimension::D2,
                &[0, 0, 0, 255],
                TextureFormat::Rgba8UnormSrgb,
                RenderAssetUsages::default(),
            );
            target.texture_descriptor.usage = TextureUsages::RENDER_ATTACHMENT | TextureUsages::COPY_SRC | TextureUsages::TEXTURE_BINDING;
            let target = images.add(target);
            let mut camera = commands.spawn((
                Camera3d::default(),
                // no tonemapping tables in this build (Bevy's default reads them)
                Tonemapping::Reinhard,
                RenderTarget::Image(target.clone().into()),
                Transform::from_xyz(-2.5, 3.0, 3.5).looking_at(Vec3::new(0.0, 0.3, 0.0), Vec3::Y),
            ));
            if run.jitter {
                camera.insert(bevy::render::camera::TemporalJitter {
                    offset: Vec2::new(0.375, -0.25),
                });
            }
            if run.second_camera {
                let mut minimap = Image::new_fill(
                    Extent3d {
                        width: 64,
                        height: 64,
                        depth_or_array_layers: 1,
                    },
                    TextureDimension::D2,
                    &[0, 0, 0, 255],
                    TextureFormat::Rgba8UnormSrgb,
                    RenderAssetUsages::default(),
                );
                minimap.texture_descriptor.usage =
                    TextureUsages::RENDER_ATTACHMENT | TextureUsages::COPY_SRC | TextureUsages::TEXTURE_BINDING;
                commands.spawn((
                    Camera3d::default(),
                    bevy::camera::Camera { order: 1, ..default() },
                    Tonemapping::Reinhard,
                    RenderTarget::Image(images.add(minimap).into()),
                    Transform::from_xyz(0.5, 6.0, 0.5).looking_at(Vec3::ZERO, Vec3::Z),
                ));
            }
            commands
                .spawn(Readback::texture(target))
                .observe(|done: On<ReadbackComplete>, shared: Res<Shared>| {
                    if let Ok(mut s) = shared.0.lock() {
                        s.0 = done.data.clone();
                        s.2 += 1;
                    }
                });
            commands
                .spawn(Readback::texture(visibility))
                .observe(|done: On<ReadbackComplete>, shared: Res<Shared>| {
                    if let Ok(mut s) = shared.0.lock() {
                        s.1 = done.data.clone();
                        s.3 += 1;
                    }
                });
        },
    );
    app.finish();
    app.cleanup();
    (app, shared)
}

/// Step `app` until sshc shades the light (or, `expect_error`, until it reports an error
/// for it) and SETTLE frames more; the read-backs then.
fn settle(app: &mut App, shared: &Shared, expect_error: bool) -> Captured {
    let mut since = None;
    let (mut last, mut counts, mut same) = ((Vec::new(), Vec::new()), (0, 0), 0);
    for frame in 0..MAX_FRAMES {
        app.update();
        if let Some(AppExit::Error(e)) = app.should_exit() {
            panic!("the app exited with {e:?}");
        }
        let status = {
            let world = app.world_mut();
            let light = world.query_filtered::<Entity, With<SshcShadow>>().iter(world).next();
            light.and_then(|l| world.resource::<Status>().error(l))
        };
        // "loading" is not the outcome looked for either way
        let decided = match &status {
            Some(e) => expect_error && !e.contains("is loading"),
            None => !expect_error,
        };
        if decided && since.is_none() {
            since = Some(frame);
        }
        if since.is_some_and(|s| frame >= s + SETTLE) {
            let (rgba, vis, frames, visibilities) = shared.0.lock().map(|s| s.clone()).unwrap_or_default();
            // only a new read-back of each counts towards settling
            if frames > counts.0 && visibilities > counts.1 {
                let now = (rgba.clone(), vis.clone());
                same = if now == last { same + 1 } else { 0 };
                last = now;
                counts = (frames, visibilities);
            }
            if same >= SETTLE && rgba.len() == (SIZE * SIZE * 4) as usize {
                return Captured {
                    rgba,
                    visibility: floats(&vis),
                    status,
                    alone: Vec::new(),
                };
            }
        }
    }
    panic!("no settled frame within {MAX_FRAMES} frames");
}

/// Capture `run` in a child process: this binary's `capture_child` test, given the run in
/// the environment, writes what it read back into a file.
fn capture(run: &Run, expect_error: bool) -> Captured {
    let dir = std::env::temp_dir().join(format!("bevy-sshc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join(format!(
        "capture-{}.bin",
        CAPTURES.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    ));
    let spec = format!(
        "{}|{}|{}|{}|{}|{}|{}|{}|{}|{}|{}|{}|{}|{}",
        run.technique,
        run.enabled,
        run.turn,
        run.sun_degrees,
        run.maps,
        run.illuminance,
        run.keep_bevy_shadow,
        expect_error,
        run.spawn,
        run.gltf,
        run.jitter,
        run.webgpu,
        run.map.map_or(0, |m| m),
        run.second_camera
    );
    let status = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "capture_child",
            "--exact",
            "--include-ignored",
            "--nocapture",
            "--test-threads",
            "1",
        ])
        .env("BEVY_SSHC_CAPTURE", &spec)
        .env("BEVY_SSHC_OUT", &out)
        .status()
        .unwrap();
    assert!(status.success(), "the capture of {run:?} failed");
    let bytes = std::fs::read(&out).unwrap();
    let _ = std::fs::remove_file(&out);
    let word = |k: usize| u64::from_le_bytes(bytes[8 * k..8 * k + 8].try_into().unwrap()) as usize;
    let (n_rgba, n_vis, n_status, n_alone) = (word(0), word(1), word(2), word(3));
    let mut at = 32;
    let rgba = bytes[at..at + n_rgba].to_vec();
    at += n_rgba;
    let visibility = floats(&bytes[at..at + n_vis]);
    at += n_vis;
    let status = (n_status > 0).then(|| String::from_utf8_lossy(&bytes[at..at + n_status - 1]).into_owned());
    at += n_status;
    let alone = floats(&bytes[at..at + n_alone]);
    Captured {
        rgba,
        visibility,
        status,
        alone,
    }
}

/// Pixels whose visibility inside Bevy differs, in any bit, from the runtime alone's.
fn differing(c: &Captured) -> usize {
    c.visibility
        .iter()
        .zip(&c.alone)
        .filter(|(a, b)| a.to_bits() != b.to_bits())
        .count()
}

fn floats(b: &[u8]) -> Vec<f32> {
    b.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect()
}

/// The frame the plugin shaded, by sshc's runtime alone: the main world's mesh entities (in
/// the plugin's order, by entity; every one moving, as the plugin adds them), its camera
/// (Bevy's reverse-Z projection mapped by `Camera::from_reverse_z`, the product formed as
/// the plugin forms it) and its sun, fitted to the casters, on a device of its own.
fn alone(app: &mut App, run: &Run) -> Vec<f32> {
    use sshc_runtime::gpu::{
        Camera as SshcCamera, Fit, FrameState, Geometry, Gpu, Instance, LightInputs, Scene, Sizes, Targets, Technique,
    };
    let world = app.world_mut();
    let mut entities: Vec<Extracted> = world
        .query::<(
            Entity,
            &Mesh3d,
            &GlobalTransform,
            Has<bevy::light::NotShadowCaster>,
            Has<bevy::light::NotShadowReceiver>,
        )>()
        .iter(world)
        .map(|(e, m, t, nc, nr)| (e, m.0.id(), t.to_matrix().to_cols_array(), !nc, !nr))
        .collect();
    entities.sort_by_key(|e| e.0);
    let meshes = world.resource::<Assets<Mesh>>();
    let mut geometry = Geometry::default();
    let mut index = std::collections::HashMap::new();
    for (e, id, transform, casts, receives) in &entities {
        let mesh = *index.entry(*id).or_insert_with(|| {
            geometry.meshes.push(bevy_sshc::convert_mesh(meshes.get(*id).unwrap()).unwrap());
            geometry.meshes.len() - 1
        });
        geometry.instances.push(Instance {
            name: format!("{e}"),
            mesh,
            transform: *transform,
            casts: *casts,
            receives: *receives,
            moves: true,
        });
    }
    let (camera, view, jitter) = world
        .query::<(
            &bevy::camera::Camera,
            &GlobalTransform,
            Option<&bevy::render::camera::TemporalJitter>,
        )>()
        .iter(world)
        .find(|(c, _, _)| c.order == 0)
        .unwrap();
    // the main pass's projection, jittered as Bevy's `prepare_view_uniforms` does
    let mut clip_from_view = camera.clip_from_view();
    if let Some(j) = jitter {
        j.jitter_projection(&mut clip_from_view, Vec2::splat(SIZE as f32));
    }
    let clip_from_world = clip_from_view * view.to_matrix().inverse();
    let cam = SshcCamera::from_reverse_z(clip_from_world.to_cols_array(), view.translation().to_array());
    let (light, shadow) = world.query::<(&GlobalTransform, &SshcShadow)>().iter(world).next().unwrap();
    let sun = sshc_runtime::light::Light::DistantDisk {
        direction: sshc_runtime::light::glam::Vec3::from_array(light.back().to_array()),
        angle_degrees: run.sun_degrees,
    };
    let compiled = world
        .resource::<Assets<bevy_sshc::SshcTechnique>>()
        .get(&shadow.technique)
        .unwrap()
        .compiled
        .clone();
    let map = shadow.map_size.or(compiled.graph.shadow_map).unwrap_or(bevy_sshc::DEFAULT_MAP_SIZE);
    let gpu = Gpu::new().unwrap();
    let technique = Technique::new(
        &gpu,
        sshc_runtime::graph::ValidGraph::try_from(compiled.graph).unwrap(),
        compiled.shaders,
    )
    .unwrap();
    let mut scene = Scene::upload(&gpu, &geometry, &[&technique]).unwrap();
    let first = LightInputs::fit(&sun, scene.boxes(), Fit::Casters, map, 0).unwrap();
    let mut state = FrameState::new(&technique, cam, vec![first]);
    let sizes = Sizes {
        camera: (SIZE, SIZE),
        shadow: map,
    };
    let mut targets = Targets::new(&technique, &scene, &state, sizes).unwrap();
    state.lights[0] = targets.fit_light(&scene, 0, &sun, Fit::Casters).unwrap();
    targets.run_frame(&mut scene, &state).unwrap();
    targets.inspect().read_visibilities().unwrap().rgba.iter().map(|p| p[0]).collect()
}

static CAPTURES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// The child side of [`capture`]: not a test of its own (ignored unless run by it).
#[test]
#[ignore = "run by `capture` in a process of its own"]
fn capture_child() {
    let (Ok(spec), Ok(out)) = (std::env::var("BEVY_SSHC_CAPTURE"), std::env::var("BEVY_SSHC_OUT")) else {
        return;
    };
    let f: Vec<&str> = spec.split('|').collect();
    let run = Run {
        technique: f[0].into(),
        enabled: f[1] == "true",
        turn: f[2].parse().unwrap(),
        sun_degrees: f[3].parse().unwrap(),
        maps: f[4] == "true",
        illuminance: f[5].parse().unwrap(),
        keep_bevy_shadow: f[6] == "true",
        spawn: f[8] == "true",
        gltf: f[9] == "true",
        jitter: f[10] == "true",
        webgpu: f[11] == "true",
        map: Some(f[12].parse().unwrap()).filter(|&m: &u32| m > 0),
        second_camera: f[13] == "true",
    };
    let (mut app, shared) = app(&run);
    let reload = run.technique == RELOAD_PATH;
    let mut c = match reload {
        true => reload_child(&mut app, &shared),
        false => settle(&mut app, &shared, f[7] == "true"),
    };
    if run.spawn {
        // a box spawned beside the others, with a StandardMaterial as a game gives it
        let before = c.visibility.clone();
        let world = app.world_mut();
        let mesh = world.resource_mut::<Assets<Mesh>>().add(Cuboid::new(0.5, 0.5, 0.5));
        let material = world.resource_mut::<Assets<StandardMaterial>>().add(StandardMaterial::default());
        world.spawn((Mesh3d(mesh.clone()), MeshMaterial3d(material), Transform::from_xyz(1.3, 0.25, -1.0)));
        c = settle(&mut app, &shared, false);
        assert!(c.visibility != before, "the spawned box changed nothing");
        // then the scene's first box despawned (an instance removed in place)
        let spawned = c.visibility.clone();
        let world = app.world_mut();
        let first_box = world
            .query::<(Entity, &Transform, &Mesh3d)>()
            .iter(world)
            .find(|(_, t, _)| t.translation == Vec3::new(-0.4, 0.6, 0.0))
            .map(|(e, _, _)| e)
            .unwrap();
        world.despawn(first_box);
        c = settle(&mut app, &shared, false);
        assert!(c.visibility != spawned, "the despawned box changed nothing");
        // then the spawned box's mesh asset changed in place (`AssetEvent::Modified`):
        // read again, its instance placing the new version
        let despawned = c.visibility.clone();
        let world = app.world_mut();
        let mut meshes = world.resource_mut::<Assets<Mesh>>();
        let grown = Mesh::from(Cuboid::new(0.5, 1.2, 0.5));
        *meshes.get_mut(mesh.id()).expect("the spawned box's mesh") = grown;
        c = settle(&mut app, &shared, false);
        assert!(c.visibility != despawned, "the box's changed mesh changed nothing");
    }
    if c.status.is_none() && run.enabled && !reload {
        c.alone = alone(&mut app, &run);
    }
    if let Ok(dir) = std::env::var("BEVY_SSHC_DUMP") {
        let name = spec.replace(['|', '/', '.'], "_");
        let _ = image::RgbaImage::from_raw(SIZE, SIZE, c.rgba.clone()).map(|i| i.save(format!("{dir}/{name}.png")));
        let v: Vec<u8> = c.visibility.iter().map(|x| (x.clamp(0.0, 1.0) * 255.0) as u8).collect();
        let _ = image::GrayImage::from_raw(SIZE, SIZE, v).map(|i| i.save(format!("{dir}/{name}-vis.png")));
    }
    let status = c.status.map(|s| format!("{s}\0")).unwrap_or_default();
    let vis: Vec<u8> = c.visibility.iter().flat_map(|x| x.to_le_bytes()).collect();
    let mut bytes = Vec::new();
    let alone: Vec<u8> = c.alone.iter().flat_map(|x| x.to_le_bytes()).collect();
    for n in [c.rgba.len(), vis.len(), status.len(), alone.len()] {
        bytes.extend((n as u64).to_le_bytes());
    }
    bytes.extend(&c.rgba);
    bytes.extend(&vis);
    bytes.extend(status.as_bytes());
    bytes.extend(&alone);
    std::fs::write(out, bytes).unwrap();
}

/// Pixels whose visibility is strictly between 0 and 1 (a penumbra), and those at 0.
fn penumbra_and_umbra(v: &[f32]) -> (usize, usize) {
    (
        v.iter().filter(|&&x| x > 0.0 && x < 1.0).count(),
        v.iter().filter(|&&x| x == 0.0).count(),
    )
}

#[test]
fn sshc_shades_the_sun_and_its_shadow_moves_with_it() {
    let a = capture(&Run::of("pcss"), false);
    assert_eq!(a.visibility.len(), (SIZE * SIZE) as usize);
    let (penumbra, umbra) = penumbra_and_umbra(&a.visibility);
    assert!(
        umbra > 100 && penumbra > 100,
        "a shadow with an umbra and a penumbra: {umbra} and {penumbra} pixels"
    );
    let b = capture(
        &Run {
            turn: 120.0,
            ..Run::of("pcss")
        },
        false,
    );
    let moved = a
        .visibility
        .iter()
        .zip(&b.visibility)
        .filter(|(x, y)| (*x - *y).abs() > 0.5)
        .count();
    assert!(moved > 200, "the sun turned 90 degrees and {moved} pixels changed by more than 0.5");
    // the shaded frame shows it: darker where sshc's visibility is 0 than where it is 1
    let luma = |c: &Captured, want: f32| {
        let px: Vec<f32> = c
            .visibility
            .iter()
            .zip(c.rgba.chunks_exact(4))
            .filter(|(v, _)| **v == want)
            .map(|(_, p)| f32::from(p[0]) + f32::from(p[1]) + f32::from(p[2]))
            .collect();
        px.iter().sum::<f32>() / px.len().max(1) as f32
    };
    assert!(
        luma(&a, 0.0) < 0.8 * luma(&a, 1.0),
        "the receivers' colour follows sshc's visibility"
    );
}

#[test]
fn switching_techniques_changes_the_penumbra() {
    let pcss = capture(&Run::of("pcss"), false);
    let hard = capture(&Run::of("hard"), false);
    let (p_pcss, _) = penumbra_and_umbra(&pcss.visibility);
    let (p_hard, _) = penumbra_and_umbra(&hard.visibility);
    assert!(
        p_pcss > 4 * p_hard.max(1),
        "PCSS's penumbra ({p_pcss} pixels) is wider than hard shadows' ({p_hard})"
    );
}

#[test]
fn a_missing_or_mismatched_technique_logs_and_leaves_bevys_own_shadow() {
    let bevy = capture(
        &Run {
            enabled: false,
            ..Run::of("pcss")
        },
        false,
    );
    for (technique, says) in [("missing-technique", "did not load"), ("linear-light", "light")] {
        let c = capture(&Run::of(technique), true);
        check(technique, says, &c, &bevy);
    }
    // a technique needing what Bevy did not ask of its device (WebGPU's defaults only:
    // the Shade's 36 bytes a sample of colour attachments pass their limit of 32)
    let run = Run {
        webgpu: true,
        ..Run::of("pcss")
    };
    let bevy = capture(
        &Run {
            enabled: false,
            ..run.clone()
        },
        false,
    );
    check("pcss", "cannot run on this device, which lacks", &capture(&run, true), &bevy);
}

/// `c`'s error names the light's technique file and says `says`; its frame is Bevy's own.
fn check(technique: &str, says: &str, c: &Captured, bevy: &Captured) {
    {
        let e = c.status.clone().unwrap_or_default();
        eprintln!("{technique}: {e}");
        assert!(
            e.contains(says) && e.contains(&format!("techniques/{technique}.ron")),
            "{technique}: {e}"
        );
        assert!(c.rgba == bevy.rgba, "{technique}: the frame is not Bevy's own shadow");
        assert!(
            c.visibility.iter().all(|&v| v == 1.0),
            "{technique}: the receivers' factor is not 1"
        );
    }
}

/// What Bevy 0.20's `directional_shadow_factor` does, and what the plugin applies
/// (docs/bevy.md, "The shadow term"). Frames of one scene and sun:
/// - `unshadowed`: the light with no shadow at all (sshc off, Bevy's maps off);
/// - `unlit`: the light's illuminance 0 (the rest of the lighting);
/// - `sshc`: the plugin as it runs (Bevy's maps on, with no caster in them);
/// - `product`: the factor alone (`keep_bevy_shadow`: Bevy's casters kept).
///
/// Where sshc's visibility is 1 its frame is the unshadowed one, and where it is 0 the
/// unlit one, bit for bit: the term applied is sshc's alone. The factor alone multiplies
/// Bevy's own shadow: in sshc's penumbra, where Bevy's harder shadow is already dark,
/// `product` is darker than `sshc`.
#[test]
fn the_shadow_term_applied_is_sshcs_visibility_alone() {
    let run = Run::of("pcss");
    let sshc = capture(&run, false);
    let unshadowed = capture(
        &Run {
            enabled: false,
            maps: false,
            ..run.clone()
        },
        false,
    );
    let unlit = capture(
        &Run {
            enabled: false,
            illuminance: 0.0,
            ..run.clone()
        },
        false,
    );
    let product = capture(
        &Run {
            keep_bevy_shadow: true,
            ..run.clone()
        },
        false,
    );
    let pixels = |c: &Captured| c.rgba.chunks_exact(4).map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>();
    let (s, u, d, p) = (pixels(&sshc), pixels(&unshadowed), pixels(&unlit), pixels(&product));
    let (mut lit, mut dark, mut darker) = (0, 0, 0);
    for (k, &v) in sshc.visibility.iter().enumerate() {
        if v == 1.0 {
            assert_eq!(s[k], u[k], "pixel {k}: sshc's visibility is 1, the frame is not the unshadowed one");
            lit += 1;
        } else if v == 0.0 {
            assert_eq!(s[k], d[k], "pixel {k}: sshc's visibility is 0, the frame is not the unlit one");
            dark += 1;
        } else {
            // the factor alone: Bevy's shadow on top of sshc's, darker where it is dark
            darker += usize::from(p[k].iter().map(|&c| u32::from(c)).sum::<u32>() < s[k].iter().map(|&c| u32::from(c)).sum::<u32>());
        }
    }
    eprintln!("{lit} pixels at visibility 1, {dark} at 0; with Bevy's casters kept, {darker} of the penumbra's are darker");
    assert!(lit > 1000 && dark > 100, "{lit} lit and {dark} dark pixels: too few to test");
    assert!(
        darker > 0,
        "Bevy's own shadow never darkened sshc's penumbra: the factor alone was not measured"
    );
}

/// For one frame, sshc's visibility inside Bevy (copied into the receivers' image and read
/// back) equals sshc's runtime alone on the same meshes, camera, light and map size, bit
/// for bit: the same shaders on the same f32 inputs (the plugin's scene is changed in place
/// mesh by mesh and instance by instance, which frames as a fresh upload bit for bit:
/// `a_mesh_or_instance_added_or_removed_in_place_frames_as_a_fresh_upload`), on the same
/// kind of device (lavapipe, two devices here). So the tolerance is 0. For PCSS, and for
/// penumbra limit maps (Geometry passes: edges, generated primitives).
#[test]
fn sshc_inside_bevy_equals_the_runtime_alone() {
    for technique in ["pcss", "penumbra-limit-maps"] {
        let c = capture(&Run::of(technique), false);
        assert_eq!(c.alone.len(), c.visibility.len(), "{technique}");
        let differ = differing(&c);
        assert_eq!(differ, 0, "{technique}: {differ} pixels differ from the runtime alone");
        let (penumbra, umbra) = penumbra_and_umbra(&c.alone);
        assert!(
            penumbra > 50 && umbra > 50,
            "{technique}: a shadow to compare ({umbra} umbra, {penumbra} penumbra pixels)"
        );
    }
}

/// A box spawned into the running game (a new mesh asset and entity), then the scene's
/// first box despawned, then the new box's mesh asset changed in place: the plugin adds
/// the mesh and instance to the scene in place, removes the other instance in place
/// (`Scene::add_mesh`, `add_instance`, `remove_instance`; the rest is not uploaded again),
/// and replaces the changed mesh (`remove_mesh`, `add_mesh`); each change shows, and the
/// last frame still equals sshc's runtime alone on the scene as it then is, bit for bit.
#[test]
fn spawned_despawned_and_changed_meshes_change_the_scene_in_place_and_frame_as_the_runtime_alone() {
    let c = capture(
        &Run {
            spawn: true,
            ..Run::of("pcss")
        },
        false,
    );
    let differ = differing(&c);
    assert_eq!(differ, 0, "{differ} pixels differ from the runtime alone after the spawn");
}

/// A second camera (a minimap: order 1, its own view and 64^2 image) beside the main one:
/// sshc shades the main camera's view (the lowest order) and no other view overwrites its
/// visibility, which equals the runtime alone on the main camera, bit for bit.
#[test]
fn with_a_second_camera_the_main_view_is_shaded() {
    let c = capture(
        &Run {
            second_camera: true,
            ..Run::of("pcss")
        },
        false,
    );
    let differ = differing(&c);
    assert_eq!(differ, 0, "{differ} pixels differ from the runtime alone on the main camera");
    let (penumbra, umbra) = penumbra_and_umbra(&c.visibility);
    assert!(
        umbra > 100 && penumbra > 100,
        "a shadow to compare ({umbra} umbra, {penumbra} penumbra pixels)"
    );
}

/// Where the glTF test writes its scene, under the asset root (the repository).
const GLTF_PATH: &str = "runtime/bevy/target/test-assets/tower.gltf";

/// A glTF 2.0 scene of one node (a tower of half-size (0.25, 0.5, 0.25), its base raised
/// by a node translation of 0.5 and turned by 30 degrees about y) placing one indexed mesh
/// with normals: 24 vertices, 36 indices, in a base64 buffer.
fn write_tower_gltf() {
    let (h, mut positions, mut normals, mut indices) = ([0.25f32, 0.5, 0.25], Vec::new(), Vec::new(), Vec::new());
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::from_array(std::array::from_fn(|i| if i == axis { sign } else { 0.0 }));
            let (u, v) = n.any_orthonormal_pair();
            let scale = |w: Vec3| w * Vec3::from_array(h);
            let base = positions.len() as u16;
            for p in [n - u - v, n + u - v, n + u + v, n - u + v] {
                positions.push(scale(p));
                normals.push(n);
            }
            let quad = if u.cross(v).dot(n) > 0.0 {
                [0, 1, 2, 0, 2, 3]
            } else {
                [0, 2, 1, 0, 3, 2]
            };
            indices.extend(quad.map(|i| base + i));
        }
    }
    let mut buffer = Vec::new();
    for p in positions.iter().chain(&normals) {
        buffer.extend(p.to_array().iter().flat_map(|c| c.to_le_bytes()));
    }
    buffer.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let (vb, ib) = (positions.len() * 12, indices.len() * 2);
    use base64::Engine;
    let data = base64::engine::general_purpose::STANDARD.encode(&buffer);
    let turn = (15f32).to_radians();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0,"translation":[0,0.5,0],"rotation":[0,{},0,{}]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}},"indices":2}}]}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{data}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{vb}}},{{"buffer":0,"byteOffset":{vb},"byteLength":{vb}}},{{"buffer":0,"byteOffset":{},"byteLength":{ib}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":24,"type":"VEC3","min":[-0.25,-0.5,-0.25],"max":[0.25,0.5,0.25]}},
{{"bufferView":1,"componentType":5126,"count":24,"type":"VEC3"}},{{"bufferView":2,"componentType":5123,"count":36,"type":"SCALAR"}}]}}"#,
        turn.sin(),
        turn.cos(),
        buffer.len(),
        2 * vb,
    );
    let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).join(GLTF_PATH);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, json).unwrap();
}

/// A glTF scene loaded by Bevy's own loader (a `SceneRoot`, its node's transform under
/// the root's) gets sshc's shadow unchanged: the tower casts (the frame differs from the
/// scene without it) and the frame equals sshc's runtime alone on every mesh entity, bit for
/// bit.
#[test]
fn a_gltf_scene_loaded_by_bevy_gets_sshcs_shadow() {
    write_tower_gltf();
    let without = capture(&Run::of("pcss"), false);
    let with = capture(
        &Run {
            gltf: true,
            ..Run::of("pcss")
        },
        false,
    );
    assert!(with.visibility != without.visibility, "the glTF tower casts nothing");
    let differ = differing(&with);
    assert_eq!(differ, 0, "{differ} pixels differ from the runtime alone with the glTF scene");
}

/// The hot-reload test's technique file, under the asset root (the repository).
const RELOAD_PATH: &str = "runtime/bevy/target/test-assets/reload.ron";

fn reload_file() -> std::path::PathBuf {
    std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).join(RELOAD_PATH)
}

fn bundled(name: &str) -> String {
    std::fs::read_to_string(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../techniques")).join(format!("{name}.ron")))
        .unwrap()
}

/// Step `app` (a little wall time a frame, for the file watcher) until `done` or a time
/// limit; false at the limit.
fn step_until(app: &mut App, mut done: impl FnMut(&mut App) -> bool) -> bool {
    let start = std::time::Instant::now();
    while start.elapsed() < std::time::Duration::from_secs(60) {
        app.update();
        if done(app) {
            return true;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    false
}

/// The child side of the hot-reload test: the file's PCSS settles; the file saved broken
/// fails to reload, and PCSS keeps rendering (the same visibility) with sshc still shading
/// the light; the file saved as hard shadows reloads, and the penumbra goes.
fn reload_child(app: &mut App, shared: &Shared) -> Captured {
    let first = settle(app, shared, false);
    let load = |app: &mut App| {
        let world = app.world_mut();
        let handle = world
            .query::<&SshcShadow>()
            .iter(world)
            .next()
            .map(|s| s.technique.clone())
            .unwrap();
        world.resource::<AssetServer>().get_load_state(&handle)
    };
    std::fs::write(reload_file(), "Technique(name: \"broken\", passes: [ oops").unwrap();
    assert!(
        step_until(app, |app| matches!(load(app), Some(bevy::asset::LoadState::Failed(_)))),
        "the broken save was not seen as a failed reload"
    );
    let kept = settle(app, shared, false);
    assert!(kept.status.is_none(), "sshc stopped shading the light: {:?}", kept.status);
    assert!(kept.visibility == first.visibility, "a failed reload changed the shadow");
    std::fs::write(reload_file(), bundled("hard")).unwrap();
    let hard = |app: &mut App, shared: &Shared| {
        let vis = floats(&shared.0.lock().unwrap().1);
        matches!(load(app), Some(bevy::asset::LoadState::Loaded))
            && penumbra_and_umbra(&vis).0 < penumbra_and_umbra(&first.visibility).0 / 4
    };
    assert!(
        step_until(app, |app| hard(app, shared)),
        "the file saved as hard shadows did not reload"
    );
    let last = settle(app, shared, false);
    let (before, after) = (penumbra_and_umbra(&first.visibility).0, penumbra_and_umbra(&last.visibility).0);
    eprintln!("penumbra pixels: {before} under PCSS, {after} after the file was saved as hard shadows");
    assert!(
        after * 4 < before,
        "the reloaded technique did not change the penumbra ({before} -> {after})"
    );
    last
}

/// Hot reload through Bevy's asset watcher: a technique file saved broken keeps the last
/// good technique rendering, unchanged (the failed reload is logged with sshc's
/// diagnostic); saved as another technique, it reloads and renders that one.
#[test]
fn a_technique_file_saved_reloads_and_a_broken_save_keeps_the_last_good_one() {
    let path = reload_file();
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(&path, bundled("pcss")).unwrap();
    let run = Run {
        technique: RELOAD_PATH.into(),
        ..Run::of("pcss")
    };
    // the child asserts each step; its last frame is hard shadows'
    let last = capture(&run, false);
    let hard = capture(&Run::of("hard"), false);
    assert!(
        last.visibility == hard.visibility,
        "the reloaded file does not frame as the bundled hard shadows"
    );
}

/// Under temporal anti-aliasing's jitter, sshc's camera takes the main pass's jittered
/// projection, as Bevy forms it: the frame differs from the unjittered one and equals the
/// runtime alone on the jittered projection, bit for bit.
#[test]
fn the_jittered_projection_of_temporal_anti_aliasing_is_followed() {
    let still = capture(&Run::of("pcss"), false);
    let jittered = capture(
        &Run {
            jitter: true,
            ..Run::of("pcss")
        },
        false,
    );
    assert!(jittered.visibility != still.visibility, "the jitter moved nothing");
    let differ = differing(&jittered);
    assert_eq!(
        differ, 0,
        "{differ} pixels differ from the runtime alone on the jittered projection"
    );
}

/// A `tuned.ron` from `sshc tune` (docs/tune/grid-edge: PCSS with tuned params and a
/// 256^2 map) as the light's technique, the component setting no map size: it loads as any
/// technique, runs at its own map size, and frames as the runtime alone at that size.
#[test]
fn a_tuned_technique_runs_at_its_own_map_size() {
    let run = Run {
        technique: "docs/tune/grid-edge/tuned.ron".into(),
        map: None,
        ..Run::of("pcss")
    };
    let c = capture(&run, false);
    let differ = differing(&c);
    assert_eq!(differ, 0, "{differ} pixels differ from the runtime alone at the tuned map size");
    // at another size the frame differs: the size used was the file's
    let other = capture(&Run { map: Some(1024), ..run }, false);
    assert!(other.visibility != c.visibility, "the tuned map size made no difference");
}
