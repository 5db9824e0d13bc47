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

/// The longest `Wait` of a script, in frames (about half an hour at 60 frames a second).
pub const MAX_WAIT_FRAMES: u32 = 100_000;
/// The most truth rounds a `WaitTruth` waits for.
pub const MAX_TRUTH_ROUNDS: u32 = 4096;
/// The longest a `WaitReady`, `WaitCompiled` or `WaitTruth` waits by default, in seconds,
/// before the script fails saying what it waited for (`--wait-limit`; a `WaitCompiled`
/// with nothing to compile never ended).
pub const MAX_WAIT_SECONDS: u64 = 600;

/// Reads a script file, and checks each event's values ([`check`]).
pub fn load(path: &Path) -> Result<Vec<Event>, String> {
    let text = crate::session::read(path)?;
    let events: Vec<Event> = ron::from_str(&text).map_err(|e| {
        let p = e.span.start;
        format!("error: {}:{}:{}: {}", path.display(), p.line, p.col, e.code)
    })?;
    check(&events).map_err(|(i, why)| format!("error: {}: event {i} ({:?}): {why}", path.display(), events[i]))?;
    Ok(events)
}

/// The first event whose values no view takes (its index and why): numbers that are not
/// finite, sizes below 0, zooms and colour ranges that are not positive, waits past their
/// caps (issue 48, item 16: `LightSize(NaN)` became 0, a NaN range was accepted, a wait
/// had no end).
pub fn check(events: &[Event]) -> Result<(), (usize, String)> {
    let finite = |xs: &[f32]| xs.iter().all(|x| x.is_finite());
    for (i, e) in events.iter().enumerate() {
        let why = match e {
            Event::Wait(n) if *n > MAX_WAIT_FRAMES => format!("a wait of at most {MAX_WAIT_FRAMES} frames"),
            Event::WaitTruth(n) if *n > MAX_TRUTH_ROUNDS => format!("at most {MAX_TRUTH_ROUNDS} rounds of the truth"),
            Event::Orbit { yaw, pitch } if !finite(&[*yaw, *pitch]) => "the angles must be finite".into(),
            Event::Pan { x, y } if !finite(&[*x, *y]) => "the offsets must be finite".into(),
            Event::Zoom(f) if !(f.is_finite() && *f > 0.0) => "a zoom is a finite factor above 0".into(),
            Event::MoveLight { by, .. } if !by.is_finite() => "the move must be finite".into(),
            Event::LightSize { size, .. } if !(size.is_finite() && *size >= 0.0) => "a light's size is a finite number >= 0".into(),
            Event::Set { value, .. } if !value.is_finite() => "a param's value must be finite".into(),
            Event::Show(Mode::Error { range } | Mode::StdError { range }) if !(range.is_finite() && *range > 0.0) => {
                "the range is a finite number above 0".into()
            }
            Event::Show(Mode::Texture { lo, hi, channel, .. }) if !(lo.is_finite() && hi.is_finite() && lo < hi) || *channel > 3 => {
                "a texture is shown from `lo` to `hi`, finite with lo < hi, in channel 0 to 3".into()
            }
            _ => continue,
        };
        return Err((i, why));
    }
    Ok(())
}

/// The log: one JSON object a line, flushed as written.
pub struct Log {
    file: Option<std::fs::File>,
}

impl Log {
    pub fn open(path: Option<&Path>) -> Result<Log, String> {
        let file = path
            .map(|p| {
                crate::session::writable(p)?;
                std::fs::File::create(p).map_err(|e| format!("error: cannot write `{}`: {e}", p.display()))
            })
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 48, item 16: values no view takes are refused at load, naming the event:
    /// `LightSize(NaN)` became 0, a NaN range was accepted, a wait had no cap.
    #[test]
    fn events_no_view_takes_are_refused_with_their_index() {
        let parse = |text: &str| -> Vec<Event> { ron::from_str(text).unwrap_or_else(|e| panic!("{text}: {e}")) };
        let good = parse("[Wait(3), LightSize(light: 0, size: 0.5), Show(Error(range: 0.1)), Zoom(2.0), WaitTruth(8)]");
        assert_eq!(check(&good), Ok(()));
        for (text, index, want) in [
            (
                "[Wait(1), LightSize(light: 0, size: NaN)]",
                1,
                "a light's size is a finite number >= 0",
            ),
            ("[LightSize(light: 0, size: -1.0)]", 0, "a light's size"),
            ("[Wait(4294967295)]", 0, "a wait of at most 100000 frames"),
            ("[WaitTruth(100000)]", 0, "at most 4096 rounds"),
            ("[Show(Error(range: NaN))]", 0, "the range is a finite number above 0"),
            ("[Show(StdError(range: 0.0))]", 0, "the range"),
            (
                "[Show(Texture(name: \"moments\", layer: 0, level: 0, channel: 0, lo: NaN, hi: 1.0, map: Viridis))]",
                0,
                "finite with lo < hi",
            ),
            (
                "[Show(Texture(name: \"moments\", layer: 0, level: 0, channel: 7, lo: 0.0, hi: 1.0, map: Viridis))]",
                0,
                "channel 0 to 3",
            ),
            ("[Orbit(yaw: inf, pitch: 0.0)]", 0, "the angles must be finite"),
            ("[MoveLight(light: 0, by: (NaN, 0.0, 0.0))]", 0, "the move must be finite"),
            ("[Set(name: \"bias\", value: inf)]", 0, "a param's value must be finite"),
            ("[Zoom(0.0)]", 0, "a zoom is a finite factor above 0"),
        ] {
            let (i, why) = check(&parse(text)).unwrap_err();
            assert_eq!(i, index, "{text}");
            assert!(why.contains(want), "{text}: {why}");
        }
    }
}
