//! A Bevy scene under an orbiting sun with sshc's shadows (docs/bevy.md).
//!
//! Windowed: `T` cycles the techniques, `B` toggles Bevy's own shadows for comparison; the
//! window's title line names the technique and sshc's GPU time beside Bevy's shadow pass's
//! (Bevy's render diagnostics, smoothed).
//!
//! Headless: `--frames N --out DIR` renders N frames into an image (no window) and writes
//! each as `DIR/frame-NNN.png`; `--technique NAME` picks the first technique (a bundled one,
//! `techniques/NAME.ron`), `--bevy` renders Bevy's own shadows instead, `--size W` the
//! frame's width and height, `--sun-degrees D` the sun's angular diameter. `--still`,
//! `--float`, `--light`, `--export` and `--visibility` are the measurement against sshc's
//! truth (`scripts/bevy-truth.sh`); `--help` lists them all.
//!
//! The windowed mode needs the `window` feature (`--features window`).
//!
//! Every build of this crate passes `--ignore-rust-version` (Bevy 0.20 declares Rust
//! 1.97.1; it builds on 1.95):
//! `cargo run --ignore-rust-version --example shadows -- --frames 4 --out out/bevy`

use bevy::app::{AppExit, ScheduleRunnerPlugin};
use bevy::asset::RenderAssetUsages;
use bevy::camera::Hdr;
use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat, TextureUsages};
use bevy::render::view::{DebandDither, Tonemapping};
use bevy::window::ExitCondition;
use bevy_sshc::{SshcShadow, SshcShadowsPlugin, SshcTechnique};
use std::path::PathBuf;

/// The techniques `T` cycles through (bundled files).
const TECHNIQUES: [&str; 5] = ["pcss", "pcf", "vssm", "mssm", "penumbra-limit-maps"];

/// What a shaded frame's light is, for measuring a shadow's visibility from frames
/// (docs/bevy.md, "Against the truth").
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum LightMode {
    /// The light and its shadow (sshc's, or Bevy's with `--bevy`).
    Shadowed,
    /// The light with no shadow at all: sshc off and Bevy's shadow maps off.
    Unshadowed,
    /// The light's illuminance 0: the rest of the lighting alone.
    Off,
}

/// A Bevy scene under an orbiting sun with sshc's shadows (docs/bevy.md).
#[derive(Resource, Clone, Debug, clap::Parser)]
struct Args {
    /// Headless: frames to render into an image and write (with `--out`).
    #[arg(long, requires = "out")]
    frames: Option<u32>,
    /// Headless: the folder the frames are written into (`frame-NNN.png`, or `.pfm` with
    /// `--float`).
    #[arg(long, requires = "frames")]
    out: Option<PathBuf>,
    /// The first technique: a bundled one, `techniques/NAME.ron`.
    #[arg(long, default_value = TECHNIQUES[0], value_parser = technique_name)]
    technique: String,
    /// Bevy's own shadows instead of sshc's.
    #[arg(long)]
    bevy: bool,
    /// Bevy's PCSS (`DirectionalLight::soft_shadow_size`, its experimental feature; this
    /// crate's `pcss` feature), with `--bevy`.
    #[arg(long, value_name = "SIZE", requires = "bevy")]
    bevy_pcss: Option<f32>,
    /// The frame's width and height in pixels.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(16..=4096))]
    size: u32,
    /// The sun's angular diameter in degrees (3 by default: a wide penumbra, to see it at
    /// this size).
    #[arg(long, default_value_t = 3.0, value_parser = sun_degrees)]
    sun_degrees: f32,
    /// Print the plugin's CPU time and the GPU times of sshc's and Bevy's passes.
    #[arg(long)]
    stats: bool,
    /// Keep Bevy's casters in its shadow maps too (`SshcShadow::keep_bevy_shadow`): both
    /// shadows computed in one run, for `--stats`' ratio.
    #[arg(long = "keep-bevy-shadow")]
    keep_bevy: bool,
    /// The sun stays where it is in the first frame.
    #[arg(long)]
    still: bool,
    /// The sun's turn about the vertical in the first frame, degrees (it turns 3 degrees a
    /// frame unless `--still`).
    #[arg(long, default_value_t = 0.0, value_parser = turn_degrees)]
    sun_turn: f32,
    /// Headless frames in linear light, as one-channel-per-colour float PFM (no tonemapping,
    /// no dithering): what a visibility is measured from.
    #[arg(long, requires = "frames")]
    float: bool,
    /// What the frame's light is (`unshadowed` and `off` are the two frames a shadow's
    /// visibility is measured between).
    #[arg(long, value_enum, default_value_t = LightMode::Shadowed)]
    light: LightMode,
    /// With the first frame written, also write the scene as the plugin shades it into
    /// this folder (`bevy_sshc::ExportScene`), for `sshc truth --scene DIR/scene.ron`.
    #[arg(long, value_name = "DIR", requires_all = ["frames", "still"])]
    export: Option<PathBuf>,
    /// Also write sshc's visibility image of each frame as `visibility-NNN.pfm`.
    #[arg(long, requires = "frames")]
    visibility: bool,
    /// Windowed: close after this many frames (the suite's run under a virtual X server).
    #[arg(long, value_name = "N", conflicts_with = "frames")]
    window_frames: Option<u32>,
    /// Windowed, with `--window-frames`: a screenshot of the window in the last frame, and
    /// the window's title line printed.
    #[arg(long, value_name = "PNG", requires = "window_frames")]
    screenshot: Option<PathBuf>,
}

fn technique_name(s: &str) -> Result<String, String> {
    match !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '-') {
        true => Ok(s.to_string()),
        false => Err("a bundled technique's name (letters, digits and '-')".into()),
    }
}

fn turn_degrees(s: &str) -> Result<f32, String> {
    let d: f32 = s.parse().map_err(|e| format!("{e}"))?;
    match (-360.0..=360.0).contains(&d) {
        true => Ok(d),
        false => Err("from -360 to 360".into()),
    }
}

fn sun_degrees(s: &str) -> Result<f32, String> {
    let d: f32 = s.parse().map_err(|e| format!("{e}"))?;
    match (0.0..=30.0).contains(&d) {
        true => Ok(d),
        false => Err("from 0 to 30".into()),
    }
}

fn main() -> AppExit {
    let args = <Args as clap::Parser>::parse();
    if args.bevy_pcss.is_some() && !cfg!(feature = "pcss") {
        eprintln!("error: --bevy-pcss needs this crate's `pcss` feature (Bevy's `experimental_pbr_pcss`)");
        return AppExit::error();
    }
    if let Some(out) = &args.out
        && let Err(e) = std::fs::create_dir_all(out)
    {
        eprintln!("error: {}: {e}", out.display());
        return AppExit::error();
    }
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
            // the suite's run (`--window-frames`) in a small window: lavapipe's frames cost
            // by the pixel
            let window = match args.window_frames {
                Some(_) => WindowPlugin {
                    primary_window: Some(Window {
                        resolution: (640, 360).into(),
                        ..default()
                    }),
                    ..default()
                },
                None => WindowPlugin::default(),
            };
            app.add_plugins(DefaultPlugins.set(assets).set(window))
                .add_plugins(bevy::render::diagnostic::RenderDiagnosticsPlugin)
                .add_systems(Update, (keys, close_after));
        }
        None => {
            eprintln!("error: the windowed example needs the `window` feature (`--features window`); headless: --frames N --out DIR");
            return AppExit::error();
        }
    }
    if args.stats {
        if args.frames.is_some() {
            app.add_plugins(bevy::render::diagnostic::RenderDiagnosticsPlugin);
        }
        app.add_systems(Update, frame_wall);
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
    shadow.enabled = !args.bevy && args.light == LightMode::Shadowed;
    shadow.angular_diameter_degrees = args.sun_degrees;
    shadow.keep_bevy_shadow = args.keep_bevy;
    let visibility = shadow.visibility.clone();
    let map_size = shadow.map_size.unwrap_or(bevy_sshc::DEFAULT_MAP_SIZE);
    #[cfg_attr(not(feature = "pcss"), allow(unused_mut))]
    let mut light = DirectionalLight {
        shadow_maps_enabled: args.light == LightMode::Shadowed,
        illuminance: if args.light == LightMode::Off { 0.0 } else { 8000.0 },
        ..default()
    };
    #[cfg(feature = "pcss")]
    {
        light.soft_shadow_size = args.bevy_pcss;
    }
    // Bevy's shadow as a user would set it for this small scene: one cascade over the
    // whole view (its default, four up to 150 units, spreads the map over empty space),
    // at sshc's map size, so that both shadows are compared at one resolution
    let cascades = bevy::light::CascadeShadowConfigBuilder {
        num_cascades: 1,
        maximum_distance: 12.0,
        first_cascade_far_bound: 12.0,
        ..default()
    };
    commands.insert_resource(bevy::light::DirectionalLightShadowMap { size: map_size as usize });
    commands.spawn((light, cascades.build(), sun_at(args.sun_turn, 0), Sun, shadow));
    commands.insert_resource(GlobalAmbientLight {
        brightness: 400.0,
        ..default()
    });
    let eye = Transform::from_xyz(-3.0, 3.2, 4.2).looking_at(Vec3::new(0.0, 0.4, 0.0), Vec3::Y);
    match args.frames {
        Some(_) => {
            // linear light (`--float`): an HDR main pass, no tonemapping, no dithering, into
            // 32-bit floats; else sRGB bytes under a tonemapper that needs no tables
            // (Bevy's default reads them: feature `window`)
            let (format, bytes) = match args.float {
                true => (TextureFormat::Rgba32Float, 16),
                false => (TextureFormat::Rgba8UnormSrgb, 4),
            };
            let mut image = Image::new_fill(
                Extent3d {
                    width: args.size,
                    height: args.size,
                    depth_or_array_layers: 1,
                },
                TextureDimension::D2,
                &vec![0; bytes],
                format,
                RenderAssetUsages::default(),
            );
            image.texture_descriptor.usage = TextureUsages::RENDER_ATTACHMENT | TextureUsages::COPY_SRC | TextureUsages::TEXTURE_BINDING;
            let target = images.add(image);
            let mut camera = commands.spawn((Camera3d::default(), RenderTarget::Image(target.clone().into()), eye));
            match args.float {
                true => camera.insert((Hdr, Tonemapping::None, DebandDither::Disabled)),
                false => camera.insert(Tonemapping::Reinhard),
            };
            commands.spawn(Readback::texture(target)).observe(save_frame);
            if args.visibility {
                commands.spawn(Readback::texture(visibility)).observe(save_visibility);
            }
        }
        None => {
            commands.spawn((Camera3d::default(), eye));
        }
    }
}

/// The sun at frame `f`: 40 degrees up, turning 3 degrees a frame from `turn` degrees.
fn sun_at(turn: f32, f: u32) -> Transform {
    let turn = (turn + f as f32 * 3.0).to_radians();
    let to_sun = Vec3::new(turn.cos() * 0.77, 0.64, turn.sin() * 0.77);
    Transform::from_translation(to_sun * 10.0).looking_at(Vec3::ZERO, Vec3::Y)
}

fn orbit(mut frame: ResMut<Frame>, args: Res<Args>, mut sun: Query<&mut Transform, With<Sun>>) {
    for mut t in &mut sun {
        *t = sun_at(args.sun_turn, if args.still { 0 } else { frame.0 });
    }
    frame.0 += 1;
}

/// Each frame's pixels, read back, as a PNG (or a float PFM with `--float`); the app exits
/// after the last. With `--export`, the scene is written with the first.
fn save_frame(
    done: On<ReadbackComplete>,
    mut commands: Commands,
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
    if frame.0.saturating_sub(1) < WARM_FRAMES || *saved >= frames {
        return;
    }
    let size = args.size;
    let path = out.join(format!("frame-{:03}.{}", *saved, if args.float { "pfm" } else { "png" }));
    let written = match args.float {
        true => floats(&done.data, size, 4).and_then(|rgba| {
            let rgb = rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
            write_pfm(&path, size, true, rgb)
        }),
        false => unpadded(&done.data, size, 4).and_then(|pixels| {
            image::RgbaImage::from_raw(size, size, pixels)
                .ok_or_else(|| format!("{} bytes for a {size}^2 frame", done.data.len()))?
                .save(&path)
                .map_err(|e| e.to_string())
        }),
    };
    if let Err(e) = written {
        eprintln!("error: {}: {e}", path.display());
        exit.write(AppExit::error());
        return;
    }
    if *saved == 0
        && let Some(dir) = &args.export
    {
        commands.insert_resource(bevy_sshc::ExportScene(dir.clone()));
    }
    *saved += 1;
    if *saved >= frames {
        last.0 = true;
    }
}

/// sshc's visibility image of each frame (`--visibility`), as a one-channel PFM.
fn save_visibility(done: On<ReadbackComplete>, args: Res<Args>, frame: Res<Frame>, mut saved: Local<u32>) {
    let (Some(frames), Some(out)) = (args.frames, &args.out) else {
        return;
    };
    if frame.0.saturating_sub(1) < WARM_FRAMES || *saved >= frames {
        return;
    }
    let path = out.join(format!("visibility-{:03}.pfm", *saved));
    // the image is the camera's size once the plugin has sized it
    if done.data.len() < (args.size * args.size * 4) as usize {
        return;
    }
    if let Err(e) = floats(&done.data, args.size, 1).and_then(|v| write_pfm(&path, args.size, false, v)) {
        eprintln!("error: {}: {e}", path.display());
    }
    *saved += 1;
}

/// A read-back texture's rows without wgpu's copy alignment (256 bytes).
fn unpadded(data: &[u8], size: u32, texel: usize) -> Result<Vec<u8>, String> {
    let (row, stride) = (size as usize * texel, (size as usize * texel).next_multiple_of(256));
    if data.len() < stride * (size as usize - 1) + row {
        return Err(format!("{} bytes for a {size}^2 image of {texel}-byte texels", data.len()));
    }
    Ok(data.chunks(stride).take(size as usize).flat_map(|r| &r[..row]).copied().collect())
}

/// A read-back texture of `channels` f32 per texel, unpadded.
fn floats(data: &[u8], size: u32, channels: usize) -> Result<Vec<f32>, String> {
    let bytes = unpadded(data, size, 4 * channels)?;
    Ok(bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

/// A PFM file (rows top first in `data`), made by the `pxm` crate, as the lab writes them.
fn write_pfm(path: &std::path::Path, size: u32, color: bool, data: Vec<f32>) -> Result<(), String> {
    let pfm = pxm::PFMBuilder::new()
        .size(size as usize, size as usize)
        .color(color)
        .scale(-1.0)
        .data(data)
        .build()
        .map_err(|e| e.to_string())?;
    let mut file = std::fs::File::create(path).map_err(|e| e.to_string())?;
    pfm.write_into(&mut file).map_err(|e| e.to_string())
}

/// The app ends in the frame after the last one was saved (so that `--stats` reports in
/// its Update first).
fn finish(last: Res<LastFrame>, mut exit: MessageWriter<AppExit>, mut armed: Local<bool>) {
    if last.0 && std::mem::replace(&mut *armed, true) {
        exit.write(AppExit::Success);
    }
}

/// `--window-frames N`: in frame N the window's screenshot is taken (`--screenshot`) and
/// its title printed, and the app closes once it is saved.
fn close_after(mut commands: Commands, args: Res<Args>, frame: Res<Frame>, windows: Query<&Window>, mut exit: MessageWriter<AppExit>) {
    let Some(n) = args.window_frames else { return };
    if frame.0 != n {
        return;
    }
    for w in &windows {
        println!("title: {}", w.title);
    }
    match &args.screenshot {
        Some(path) => {
            commands
                .spawn(bevy::render::view::screenshot::Screenshot::primary_window())
                .observe(bevy::render::view::screenshot::save_to_disk(path.clone()))
                .observe(
                    |_: On<bevy::render::view::screenshot::ScreenshotCaptured>, mut exit: MessageWriter<AppExit>| {
                        exit.write(AppExit::Success);
                    },
                );
        }
        None => {
            exit.write(AppExit::Success);
        }
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

/// The title line's state, kept across frames so that a frame allocates nothing: the
/// diagnostic paths (made once), the line's buffer, and when it was last written.
#[derive(Default)]
struct TitleLine {
    paths: Option<[bevy::diagnostic::DiagnosticPath; 2]>,
    line: String,
    written: Option<std::time::Instant>,
}

/// How often the title's times are written again (their values are smoothed anyway).
const TITLE_EVERY: std::time::Duration = std::time::Duration::from_millis(500);

fn keys(
    input: Res<ButtonInput<KeyCode>>,
    server: Res<AssetServer>,
    store: Res<bevy::diagnostic::DiagnosticsStore>,
    mut lights: Query<&mut SshcShadow>,
    mut index: Local<usize>,
    mut title: Local<TitleLine>,
    mut windows: Query<&mut Window>,
) {
    use std::fmt::Write as _;
    let mut pressed = false;
    for mut shadow in &mut lights {
        if input.just_pressed(KeyCode::KeyT) {
            *index = (*index + 1) % TECHNIQUES.len();
            shadow.technique = server.load(format!("techniques/{}.ron", TECHNIQUES[*index]));
            pressed = true;
        }
        if input.just_pressed(KeyCode::KeyB) {
            shadow.enabled = !shadow.enabled;
            pressed = true;
        }
    }
    let now = std::time::Instant::now();
    if !pressed && title.written.is_some_and(|t| now - t < TITLE_EVERY) {
        return;
    }
    let title = &mut *title;
    title.written = Some(now);
    // sshc's GPU time, and Bevy's shadow pass's, smoothed by Bevy's render diagnostics
    let [sshc, bevy_shadow] = title.paths.get_or_insert_with(|| {
        ["sshc_shadows", "per_view_shadow_pass"].map(|name| bevy::diagnostic::DiagnosticPath::new(format!("render/{name}/elapsed_gpu")))
    });
    let time = |path: &bevy::diagnostic::DiagnosticPath| store.get(path).and_then(|d| d.smoothed()).unwrap_or(f64::NAN);
    let (sshc, bevy_shadow) = (time(sshc), time(bevy_shadow));
    let line = &mut title.line;
    line.clear();
    // `write!` into the kept buffer: no allocation once it has grown to the line's length
    let _ = match lights.iter().next().map(|s| s.enabled) {
        Some(true) => write!(
            line,
            "sshc: {}, GPU {sshc:.2} ms (Bevy's shadow pass {bevy_shadow:.2} ms) | T: next technique, B: Bevy's own shadows",
            TECHNIQUES[*index]
        ),
        _ => write!(line, "Bevy's own shadows, GPU {bevy_shadow:.2} ms | B: sshc's"),
    };
    for mut w in &mut windows {
        if w.title != *line {
            w.title.clone_from(line);
        }
    }
}
