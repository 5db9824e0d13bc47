//! A Bevy scene under an orbiting sun with sshc's shadows (docs/bevy.md).
//!
//! Windowed: `T` cycles the techniques, `B` toggles Bevy's own shadows for comparison; the
//! window's title line names the technique and what shades the light.
//!
//! Headless: `--frames N --out DIR` renders N frames into an image (no window) and writes
//! each as `DIR/frame-NNN.png`; `--technique NAME` picks the first technique (a bundled one,
//! `techniques/NAME.ron`), `--bevy` renders Bevy's own shadows instead, `--size W` the
//! frame's width and height, `--sun-degrees D` the sun's angular diameter (3 by default:
//! a wide penumbra, to see it at this size).
//!
//! The windowed mode needs the `window` feature (`--features window`).
//!
//! Every build of this crate passes `--ignore-rust-version` (Bevy 0.20 declares Rust
//! 1.97.1; it builds on 1.95):
//! `cargo run --ignore-rust-version --example shadows -- --frames 4 --out out/bevy`

use bevy::app::{AppExit, ScheduleRunnerPlugin};
use bevy::asset::RenderAssetUsages;
use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat, TextureUsages};
use bevy::render::view::Tonemapping;
use bevy::window::ExitCondition;
use bevy_sshc::{SshcShadow, SshcShadowsPlugin, SshcTechnique};
use std::path::PathBuf;

/// The techniques `T` cycles through (bundled files).
const TECHNIQUES: [&str; 5] = ["pcss", "pcf", "vssm", "mssm", "penumbra-limit-maps"];

#[derive(Resource, Clone, Debug)]
struct Args {
    frames: Option<u32>,
    out: Option<PathBuf>,
    technique: String,
    bevy: bool,
    size: u32,
    sun_degrees: f32,
    /// Print the plugin's CPU time and the GPU times of sshc's and Bevy's passes.
    stats: bool,
    /// Keep Bevy's casters in its shadow maps too (`SshcShadow::keep_bevy_shadow`): both
    /// shadows computed in one run, for `--stats`' ratio.
    keep_bevy: bool,
}

fn args() -> Result<Args, String> {
    let mut a = Args {
        frames: None,
        out: None,
        technique: TECHNIQUES[0].into(),
        bevy: false,
        size: 256,
        sun_degrees: 3.0,
        stats: false,
        keep_bevy: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{flag} needs a value"));
        match flag.as_str() {
            "--frames" => a.frames = Some(value()?.parse().map_err(|e| format!("--frames: {e}"))?),
            "--out" => a.out = Some(PathBuf::from(value()?)),
            "--technique" => a.technique = value()?,
            "--size" => {
                a.size = value()?.parse().map_err(|e| format!("--size: {e}"))?;
                if !(16..=4096).contains(&a.size) {
                    return Err(format!("--size {}: from 16 to 4096", a.size));
                }
            }
            "--bevy" => a.bevy = true,
            "--stats" => a.stats = true,
            "--keep-bevy-shadow" => a.keep_bevy = true,
            "--sun-degrees" => {
                a.sun_degrees = value()?.parse().map_err(|e| format!("--sun-degrees: {e}"))?;
                if !(0.0..=30.0).contains(&a.sun_degrees) {
                    return Err(format!("--sun-degrees {}: from 0 to 30", a.sun_degrees));
                }
            }
            _ => {
                return Err(format!(
                    "unknown argument `{flag}` (--frames N --out DIR --technique NAME --size W --sun-degrees D --bevy --stats --keep-bevy-shadow)"
                ));
            }
        }
    }
    if a.frames.is_some() != a.out.is_some() {
        return Err("--frames and --out go together (headless)".into());
    }
    if !a.technique.chars().all(|c| c.is_ascii_alphanumeric() || c == '-') {
        return Err(format!("--technique `{}`: a bundled technique's name", a.technique));
    }
    Ok(a)
}

fn main() -> AppExit {
    let args = match args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            return AppExit::error();
        }
    };
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let assets = AssetPlugin {
        file_path: root.into(),
        watch_for_changes_override: Some(args.frames.is_none()),
        ..default()
    };
    let mut app = App::new();
    match args.frames {
        Some(_) => {
            let plugins = DefaultPlugins
                .set(assets)
                .set(WindowPlugin {
                    primary_window: None,
                    exit_condition: ExitCondition::DontExit,
                    ..default()
                })
                // every pipeline ready in the frame that needs it: no frame lacks a mesh
                .set(bevy::render::RenderPlugin {
                    synchronous_pipeline_compilation: true,
                    ..default()
                });
            #[cfg(feature = "window")]
            let plugins = plugins.disable::<bevy::winit::WinitPlugin>();
            app.add_plugins(plugins)
                .add_plugins(ScheduleRunnerPlugin::run_loop(std::time::Duration::ZERO));
        }
        None if cfg!(feature = "window") => {
            app.add_plugins(DefaultPlugins.set(assets)).add_systems(Update, keys);
        }
        None => {
            eprintln!("error: the windowed example needs the `window` feature (`--features window`); headless: --frames N --out DIR");
            return AppExit::error();
        }
    }
    if args.stats {
        app.add_plugins(bevy::render::diagnostic::RenderDiagnosticsPlugin)
            .add_systems(Update, frame_wall);
    }
    app.add_plugins(SshcShadowsPlugin)
        .insert_resource(args)
        .insert_resource(Frame(0))
        .init_resource::<LastFrame>()
        .add_systems(Last, finish)
        .add_systems(Startup, setup)
        .add_systems(Update, orbit)
        .run()
}

/// The frame counter: the sun's orbit is by frame, so headless frames are the same each run.
#[derive(Resource)]
struct Frame(u32);

#[derive(Component)]
struct Sun;

fn setup(
    mut commands: Commands,
    args: Res<Args>,
    server: Res<AssetServer>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    mut images: ResMut<Assets<Image>>,
) {
    let ground = materials.add(StandardMaterial {
        base_color: Color::srgb(0.8, 0.8, 0.75),
        perceptual_roughness: 0.9,
        ..default()
    });
    let clay = materials.add(StandardMaterial {
        base_color: Color::srgb(0.8, 0.45, 0.3),
        perceptual_roughness: 0.7,
        ..default()
    });
    commands.spawn((Mesh3d(meshes.add(Plane3d::default().mesh().size(8.0, 8.0))), MeshMaterial3d(ground)));
    commands.spawn((
        Mesh3d(meshes.add(Cuboid::new(0.8, 1.6, 0.8))),
        MeshMaterial3d(clay.clone()),
        Transform::from_xyz(-0.8, 0.8, 0.0),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Sphere::new(0.5).mesh().uv(32, 16))),
        MeshMaterial3d(clay.clone()),
        Transform::from_xyz(0.9, 1.1, 0.4),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Torus::new(0.25, 0.5))),
        MeshMaterial3d(clay),
        Transform::from_xyz(0.3, 0.35, -1.2),
    ));
    let technique: Handle<SshcTechnique> = server.load(format!("techniques/{}.ron", args.technique));
    let mut shadow = SshcShadow::new(technique, &mut images);
    shadow.enabled = !args.bevy;
    shadow.angular_diameter_degrees = args.sun_degrees;
    shadow.keep_bevy_shadow = args.keep_bevy;
    commands.spawn((
        DirectionalLight {
            shadow_maps_enabled: true,
            illuminance: 8000.0,
            ..default()
        },
        sun_at(0),
        Sun,
        shadow,
    ));
    commands.insert_resource(GlobalAmbientLight {
        brightness: 400.0,
        ..default()
    });
    let eye = Transform::from_xyz(-3.0, 3.2, 4.2).looking_at(Vec3::new(0.0, 0.4, 0.0), Vec3::Y);
    match args.frames {
        Some(_) => {
            let mut image = Image::new_fill(
                Extent3d {
                    width: args.size,
                    height: args.size,
                    depth_or_array_layers: 1,
                },
                TextureDimension::D2,
                &[0, 0, 0, 255],
                TextureFormat::Rgba8UnormSrgb,
                RenderAssetUsages::default(),
            );
            image.texture_descriptor.usage = TextureUsages::RENDER_ATTACHMENT | TextureUsages::COPY_SRC | TextureUsages::TEXTURE_BINDING;
            let target = images.add(image);
            // a tonemapper that needs no tables (Bevy's default reads them: feature `window`)
            commands.spawn((
                Camera3d::default(),
                Tonemapping::Reinhard,
                RenderTarget::Image(target.clone().into()),
                eye,
            ));
            commands.spawn(Readback::texture(target)).observe(save_frame);
        }
        None => {
            commands.spawn((Camera3d::default(), eye));
        }
    }
}

/// The sun at frame `f`: 40 degrees up, turning 3 degrees a frame.
fn sun_at(f: u32) -> Transform {
    let turn = (f as f32 * 3.0).to_radians();
    let to_sun = Vec3::new(turn.cos() * 0.77, 0.64, turn.sin() * 0.77);
    Transform::from_translation(to_sun * 10.0).looking_at(Vec3::ZERO, Vec3::Y)
}

fn orbit(mut frame: ResMut<Frame>, mut sun: Query<&mut Transform, With<Sun>>) {
    for mut t in &mut sun {
        *t = sun_at(frame.0);
    }
    frame.0 += 1;
}

/// Each frame's pixels, read back, as a PNG; the app exits after the last.
fn save_frame(
    done: On<ReadbackComplete>,
    args: Res<Args>,
    frame: Res<Frame>,
    mut exit: MessageWriter<AppExit>,
    mut saved: Local<u32>,
    mut last: ResMut<LastFrame>,
) {
    let (Some(frames), Some(out)) = (args.frames, &args.out) else {
        return;
    };
    // the first frames render before the pipelines are ready: wait for them to settle
    let index = frame.0.saturating_sub(1);
    if index < WARM_FRAMES {
        return;
    }
    let path = out.join(format!("frame-{:03}.png", *saved));
    let size = args.size;
    if let Err(e) = std::fs::create_dir_all(out).map_err(|e| e.to_string()).and_then(|_| {
        // rows come padded to wgpu's copy alignment (256 bytes)
        let (row, stride) = (size as usize * 4, (size as usize * 4).next_multiple_of(256));
        let pixels: Vec<u8> = done.data.chunks(stride).flat_map(|r| &r[..row.min(r.len())]).copied().collect();
        image::RgbaImage::from_raw(size, size, pixels)
            .ok_or_else(|| format!("{} bytes for a {size}^2 frame", done.data.len()))?
            .save(&path)
            .map_err(|e| e.to_string())
    }) {
        eprintln!("error: {}: {e}", path.display());
        exit.write(AppExit::error());
        return;
    }
    *saved += 1;
    if *saved >= frames {
        last.0 = true;
    }
}

/// The app ends in the frame after the last one was saved (so that `--stats` reports in
/// its Update first).
fn finish(last: Res<LastFrame>, mut exit: MessageWriter<AppExit>, mut armed: Local<bool>) {
    if last.0 && std::mem::replace(&mut *armed, true) {
        exit.write(AppExit::Success);
    }
}

/// The last frame was saved: `--stats` reports.
#[derive(Resource, Default)]
struct LastFrame(bool);

/// Each frame's wall time, milliseconds (`--stats`), the previous frame's start, and
/// whether the report was printed.
#[derive(Default)]
struct Walls(Vec<f64>, Option<std::time::Instant>, bool);

/// `--stats`: the frames' wall times, and on the last frame the medians: the plugin's
/// render-world CPU time, and the GPU times of sshc's passes and of Bevy's shadow and main
/// passes (Bevy's render diagnostics), as ratios from the one run.
fn frame_wall(
    mut walls: Local<Walls>,
    frame: Res<Frame>,
    last: Res<LastFrame>,
    store: Res<bevy::diagnostic::DiagnosticsStore>,
    times: Res<bevy_sshc::CpuTimes>,
) {
    let now = std::time::Instant::now();
    if let Some(t) = walls.1.replace(now)
        && frame.0 > WARM_FRAMES
    {
        walls.0.push((now - t).as_secs_f64() * 1e3);
    }
    if !last.0 || walls.2 {
        return;
    }
    walls.2 = true;
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    let gpu = |name: &str| {
        let path = bevy::diagnostic::DiagnosticPath::new(format!("render/{name}/elapsed_gpu"));
        median(store.get(&path).map(|d| d.values().copied().collect()).unwrap_or_default())
    };
    let [prepare, record] = times.medians().unwrap_or([f64::NAN; 2]);
    let wall = median(walls.0.clone());
    let (sshc, shadows, opaque) = (gpu("sshc_shadows"), gpu("per_view_shadow_pass"), gpu("main_opaque_pass_3d"));
    println!("medians over {} frames (lavapipe: CPU and GPU share the cores):", walls.0.len());
    println!(
        "  frame wall time {wall:.2} ms; the plugin's render-world CPU: prepare {prepare:.0} us + record {record:.0} us = {:.1} % of the frame",
        (prepare + record) / 10.0 / wall
    );
    println!(
        "  GPU: sshc's passes {sshc:.3} ms, Bevy's shadow pass {shadows:.3} ms, Bevy's main opaque pass {opaque:.3} ms; sshc / Bevy's shadow pass = {:.2}",
        sshc / shadows
    );
}

/// Frames rendered before the first one saved (the technique loading and compiling).
const WARM_FRAMES: u32 = 30;

fn keys(
    input: Res<ButtonInput<KeyCode>>,
    server: Res<AssetServer>,
    mut lights: Query<&mut SshcShadow>,
    mut index: Local<usize>,
    mut windows: Query<&mut Window>,
) {
    for mut shadow in &mut lights {
        if input.just_pressed(KeyCode::KeyT) {
            *index = (*index + 1) % TECHNIQUES.len();
            shadow.technique = server.load(format!("techniques/{}.ron", TECHNIQUES[*index]));
        }
        if input.just_pressed(KeyCode::KeyB) {
            shadow.enabled = !shadow.enabled;
        }
        let line = match shadow.enabled {
            true => format!("sshc: {} (T: next technique, B: Bevy's own shadows)", TECHNIQUES[*index]),
            false => "Bevy's own shadows (B: sshc's)".to_string(),
        };
        for mut w in &mut windows {
            if w.title != line {
                w.title = line.clone();
            }
        }
    }
}
