//! Render a bundled scene with PCF compiled into this program at build time: no technique
//! file, no compiler and no shader file is read at run time.
//!
//! ```sh
//! LP_NUM_THREADS=2 XDG_RUNTIME_DIR=/tmp cargo run -p sshc-render-embedded -- [OUT.png] [SCENE.ron]
//! ```
//!
//! `OUT.png` defaults to `out/embedded.png`, `SCENE.ron` to the bundled `scenes/bunny.ron`.
//! The test suite runs this file too: `tests/embed.rs` beside it includes it as a module and
//! calls [`run`] with the arguments it would get on the command line.
//!
//! This example is a package of its own (`sshc-render-embedded`) so that the macro crate
//! needs no GPU runtime among its dev-dependencies: trybuild builds those for every case.

use sshc_lab::image_io::ImageFiles;
use sshc_lab::scene::Scene;
use sshc_runtime::gpu::{CameraOutput, FrameState, Gpu, Scene as Uploaded, Sizes, Targets, Technique};
use sshc_runtime::graph::ValidGraph;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

// The path is relative to this package's Cargo.toml (shaders-gen/examples/render_embedded/).
sshc_shaders_gen::technique!(pub mod pcf = "../../../techniques/pcf.ron");

/// What one run produced.
#[derive(Debug)]
pub struct Summary {
    pub out: PathBuf,
    pub size: (u32, u32),
    /// Visibility per camera pixel (1 where no surface is seen).
    pub visibility: Vec<f32>,
    /// GPU time per pass, where the device has timestamp queries.
    pub times: Vec<(String, Option<f64>)>,
}

/// The whole program: `args` are the command-line arguments after the program name.
pub fn run(args: impl IntoIterator<Item = OsString>) -> Result<Summary, String> {
    let mut args = args.into_iter();
    let out = args.next().map(PathBuf::from).unwrap_or_else(|| PathBuf::from("out/embedded.png"));
    let scene_path = args
        .next()
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../scenes/bunny.ron"));
    if let Some(extra) = args.next() {
        return Err(format!(
            "unexpected argument `{}`; usage: render_embedded [OUT.png] [SCENE.ron]",
            extra.to_string_lossy()
        ));
    }
    let scene = Scene::load(&scene_path).map_err(|e| e.to_string())?;
    let gpu = Gpu::new().map_err(|e| format!("no GPU adapter: {e}"))?;
    let graph = pcf::graph().map_err(|e| format!("embedded graph: {e}"))?;
    let graph = ValidGraph::try_from(graph).map_err(|e| e.to_string())?;
    let technique = Technique::new(&gpu, graph, pcf::shaders()).map_err(|e| e.to_string())?;
    let inputs = sshc_lab::bind::scene_inputs(&scene)?;
    let mut uploaded = Uploaded::from_inputs(&gpu, &inputs, &[&technique]).map_err(|e| e.to_string())?;
    let mut state = FrameState::of_inputs(&technique, &inputs);
    // The technique's defaults, through the generated Params struct (whose layout the
    // build checked against the WGSL uniform); the frame's params hold them at their offsets.
    let params = pcf::Params::default();
    for (name, value) in params.values() {
        state.params.set(name, value).map_err(|e| e.to_string())?;
    }
    let mut targets = Targets::new(&technique, &uploaded, &state, Sizes::of(&inputs)).map_err(|e| e.to_string())?;
    let times = targets.run_frame(&mut uploaded, &state).map_err(|e| e.to_string())?;
    let color = targets.inspect().read_camera(CameraOutput::Color).map_err(|e| e.to_string())?;
    let visibility = targets.inspect().read_camera(CameraOutput::Visibility).map_err(|e| e.to_string())?;
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    color.write_png(&out, None, (0.0, 1.0)).map_err(|e| e.to_string())?;
    Ok(Summary {
        out,
        size: (color.width, color.height),
        visibility: visibility.channel(0),
        times: times.passes,
    })
}

fn main() -> ExitCode {
    match run(std::env::args_os().skip(1)) {
        Ok(s) => {
            println!(
                "technique `{}` ({} bytes of Params), embedded at build time",
                pcf::TECHNIQUE,
                pcf::Params::SIZE
            );
            for (pass, ms) in &s.times {
                match ms {
                    Some(ms) => println!("  {pass}: {ms:.3} ms"),
                    None => println!("  {pass}: no timestamp queries"),
                }
            }
            println!("wrote {} ({} x {})", s.out.display(), s.size.0, s.size.1);
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
