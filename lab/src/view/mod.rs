//! `sshc view`: a live window on a technique. It is a host of the runtime's public API, as
//! an engine would be (docs/embedding.md): its own device and window surface, the camera
//! and lights updated in place every frame (`set_camera`, `set_light`), the passes
//! recorded into its own encoder (`encode`), and the graph's textures drawn into the
//! window. Compilation runs on a worker thread ([`worker`]); the last good graph keeps
//! rendering until the new one is ready, and a file that no longer compiles shows its
//! diagnostics in the window. docs/viewer.md is the guide.

mod app;
mod present;
mod refine;
pub mod script;
pub mod state;
mod worker;

use crate::session::{Variants, size};
use std::path::{Path, PathBuf};

/// The scene `sshc view` opens when none is named: `scenes/bunny.ron` of the repository
/// the binary belongs to (`session::repository`), else of the working folder.
fn default_scene() -> PathBuf {
    let bunny = Path::new("scenes").join("bunny.ron");
    crate::session::repository().map_or(bunny.clone(), |r| r.join(bunny))
}

/// `sshc view`'s arguments.
#[derive(clap::Args)]
pub struct ViewArgs {
    /// The technique file (RON).
    pub technique: PathBuf,
    /// The scene (RON; default: the bundled bunny scene, the main job's).
    #[arg(long, default_value_os_t = default_scene())]
    pub scene: PathBuf,
    /// Params, precisions and schedules to start with.
    #[command(flatten)]
    pub variants: Variants,
    /// The window's inner size, WIDTHxHEIGHT (default: the scene camera's).
    #[arg(long, value_parser = size)]
    pub size: Option<(u32, u32)>,
    /// Cascaded shadow maps for the scene's light at infinity (its file's `cascades:`
    /// otherwise); refitted in place as the camera moves, drawn by the `cascades` view.
    #[command(flatten)]
    pub cascading: crate::bind::Cascading,
    /// Override the scene's shadow-map resolution.
    #[arg(long)]
    pub shadow_map: Option<u32>,
    /// Render this many frames, then exit (with `--screenshot`, after writing it).
    #[arg(long)]
    pub frames: Option<u64>,
    /// With `--frames`: write the window's contents to this PNG before exiting.
    #[arg(long, requires = "frames")]
    pub screenshot: Option<PathBuf>,
    /// Replay this script (a RON list of events; docs/viewer.md), then exit.
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// Write what happens as JSON lines: each event, each recompilation with its
    /// diagnostics, each screenshot with the view's state.
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// The longest a script's `WaitReady`, `WaitCompiled` or `WaitTruth` waits, in seconds,
    /// before the script fails saying what it waited for.
    #[arg(long, value_name = "SECONDS", default_value_t = script::MAX_WAIT_SECONDS, value_parser = clap::value_parser!(u64).range(1..=86_400))]
    pub wait_limit: u64,
}

/// What to install for a display, for the message shown without one.
pub const NO_DISPLAY: &str = "no display: `sshc view` opens a window. Without a desktop, run it under a virtual X server: `xvfb-run -a sshc view ...` (Debian: `apt-get install -y xvfb xauth`)";

/// Runs the viewer until its window closes (or its frames or script end).
pub fn view(args: ViewArgs) -> Result<(), String> {
    let has_display = ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()));
    if !has_display {
        return Err(format!("error: {NO_DISPLAY}"));
    }
    app::run(args)
}
