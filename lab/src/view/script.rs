//! Scripted use: a list of events a script replays frame by frame, and the JSON-lines log
//! of what happened (each event, each recompilation with its diagnostics, each screenshot
//! with the view's state). Tests read the log, not pixels, for what is text.

use super::state::{Mode, ViewState};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// One step of a script (a RON list of these).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Event {
    /// Let this many frames pass.
    Wait(u32),
    /// Wait until the compilation in flight (if any) has been answered, then one frame
    /// more, so that what is shown is the answer's.
    WaitReady,
    /// Wait until the next compilation is answered (one asked for by a file saved, say),
    /// then one frame more.
    WaitCompiled,
    /// Wait until the truth of the current view has refined this many rounds (a mode that
    /// shows the truth must be on), then one frame more.
    WaitTruth(u32),
    /// Orbit the camera: degrees around the vertical and up.
    Orbit { yaw: f32, pitch: f32 },
    /// Pan the camera in the view plane, in units of its distance to the target.
    Pan { x: f32, y: f32 },
    /// Scale the camera's distance to its target.
    Zoom(f32),
    /// Move light `light` (each of its points) by `by`; a light at infinity turns by
    /// `by.x` radians around the vertical and `by.y` up.
    MoveLight { light: usize, by: Vec3 },
    /// Set light `light`'s size (radius, half extent, half length, or angle in degrees).
    LightSize { light: usize, size: f32 },
    /// Set a param: a runtime one at once, a fixed one by recompiling.
    Set { name: String, value: f64 },
    /// Set a channel's or expansion's precision (recompiles).
    Precision { name: String, value: String },
    /// Set a pass's schedule (recompiles).
    Schedule { pass: String, value: String },
    /// Show this.
    Show(Mode),
    /// Show a second technique or setting on the right half (`None`: the whole window is
    /// the main one again).
    Split(Option<super::state::Split>),
    /// Switch to this technique file.
    Technique(PathBuf),
    /// Edit a file as an editor saves it: replace the first `from` by `to` and write it.
    Edit { path: PathBuf, from: String, to: String },
    /// Write the window's contents to this PNG, and the visibility beside it
    /// (`NAME.visibility.pfm`, light 0's, or each light's in a channel).
    Screenshot(PathBuf),
    /// Set the whole state.
    State(Box<ViewState>),
    /// Back to the scene file's camera and lights and the technique's defaults.
    Reset,
}

/// Reads a script file.
pub fn load(path: &Path) -> Result<Vec<Event>, String> {
    let text = crate::session::read(path)?;
    ron::from_str(&text).map_err(|e| {
        let p = e.span.start;
        format!("error: {}:{}:{}: {}", path.display(), p.line, p.col, e.code)
    })
}

/// The log: one JSON object a line, flushed as written.
pub struct Log {
    file: Option<std::fs::File>,
}

impl Log {
    pub fn open(path: Option<&Path>) -> Result<Log, String> {
        let file = path
            .map(|p| std::fs::File::create(p).map_err(|e| format!("error: cannot write `{}`: {e}", p.display())))
            .transpose()?;
        Ok(Log { file })
    }

    /// Writes `entry` (a JSON object) with the frame number added.
    pub fn write(&mut self, frame: u64, mut entry: serde_json::Value) {
        if let Some(f) = &mut self.file {
            if let Some(o) = entry.as_object_mut() {
                o.insert("frame".into(), frame.into());
            }
            let _ = writeln!(f, "{entry}");
            let _ = f.flush();
        }
    }
}
