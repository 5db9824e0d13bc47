//! A viewer script as `sshc view --script` reads it: a RON list of [`Event`]s, each checked
//! before the window opens, and the [`ViewState`] a script sets and the log records. The
//! viewer (the lab's `view`) replays them; their reading is here, where the fuzz target
//! `script` reaches it.

use glam::Vec3;
use serde::{Deserialize, Serialize};
use sshc_scene::{Camera, Light};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What the window shows.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Mode {
    /// The shaded image (the Shade pass's colour; every light's combination).
    Shaded,
    /// Light 0's visibility, 0 black to 1 white.
    Visibility,
    /// Which cascade each pixel takes (`--cascades` or the scene's `cascades:`): the
    /// cascade's index through viridis, dark blue for the nearest, yellow for the farthest,
    /// blended across the band where two mix. One colour without cascades.
    Cascades,
    /// The ray-traced truth of light 0, refined while the view stands still.
    Truth,
    /// The visibility less the truth, blue below, red above, white where they agree;
    /// `range` is the error at full colour.
    Error { range: f32 },
    /// The truth's standard error, 0 to `range` (viridis).
    StdError { range: f32 },
    /// One channel of one layer and level of a texture of the graph, mapped from
    /// `[lo, hi]` through a colour map.
    Texture {
        name: String,
        layer: u32,
        level: u32,
        /// 0 to 3: r, g, b, a.
        channel: u32,
        lo: f32,
        hi: f32,
        map: ColourMap,
    },
}

/// How a value in `[0, 1]` becomes a colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ColourMap {
    Grey,
    /// Perceptually ordered, dark blue to yellow (a polynomial fit of matplotlib's viridis).
    Viridis,
    /// Blue below the middle, white at it, red above: for signed values.
    Diverging,
    /// Viridis over the logarithm: `lo` to `hi` (both above 0) spread by their ratio, so
    /// that a mip level of `exp(-80 z)` reads across its decades; values at or below 0 take
    /// `lo`'s colour.
    LogViridis,
}

impl ColourMap {
    pub const ALL: [ColourMap; 4] = [ColourMap::Grey, ColourMap::Viridis, ColourMap::Diverging, ColourMap::LogViridis];

    pub fn name(self) -> &'static str {
        match self {
            ColourMap::Grey => "grey",
            ColourMap::Viridis => "viridis",
            ColourMap::Diverging => "diverging",
            ColourMap::LogViridis => "log viridis",
        }
    }

    /// The index the present shader switches on.
    pub fn index(self) -> u32 {
        match self {
            ColourMap::Grey => 0,
            ColourMap::Viridis => 1,
            ColourMap::Diverging => 2,
            ColourMap::LogViridis => 3,
        }
    }
}

/// The camera and lights, the technique's settings and what is shown.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewState {
    /// The technique file.
    pub technique: PathBuf,
    /// The scene file.
    pub scene: PathBuf,
    /// The scene's camera as it is now (its size is the window's).
    pub camera: Camera,
    /// The scene's lights as they are now.
    pub lights: Vec<Light>,
    /// Runtime params moved from their defaults (uniforms: no recompile).
    pub params: BTreeMap<String, f64>,
    /// Fixed params set at compile time (`--set`: a recompile).
    pub fixed: BTreeMap<String, String>,
    /// Precision overrides (`--precision`).
    pub precisions: BTreeMap<String, String>,
    /// Schedule overrides (`--schedule`).
    pub schedules: BTreeMap<String, String>,
    pub shadow_map: u32,
    pub mode: Mode,
    /// A second technique or setting on the right half of the window, on the same camera
    /// and lights (the left half is the one above).
    #[serde(default)]
    pub split: Option<Split>,
}

/// The right half of a split view: its technique and settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Split {
    pub technique: PathBuf,
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
    #[serde(default)]
    pub fixed: BTreeMap<String, String>,
    #[serde(default)]
    pub precisions: BTreeMap<String, String>,
    #[serde(default)]
    pub schedules: BTreeMap<String, String>,
}

impl ViewState {
    /// The split's own state: this one with the split's technique and settings.
    pub fn right(&self) -> Option<ViewState> {
        let s = self.split.as_ref()?;
        Some(ViewState {
            technique: s.technique.clone(),
            params: s.params.clone(),
            fixed: s.fixed.clone(),
            precisions: s.precisions.clone(),
            schedules: s.schedules.clone(),
            split: None,
            ..self.clone()
        })
    }

    /// The settings of this view as a split's (to compare them with others).
    pub fn as_split(&self) -> Split {
        Split {
            technique: self.technique.clone(),
            params: self.params.clone(),
            fixed: self.fixed.clone(),
            precisions: self.precisions.clone(),
            schedules: self.schedules.clone(),
        }
    }

    /// The `sshc render` line that renders this view: the same technique, settings,
    /// camera (with the window's size) and lights, bit for bit where the arithmetic is the
    /// same. Arguments are quoted for a POSIX shell.
    pub fn command(&self, out: &str) -> String {
        let mut words = vec![
            "sshc".to_string(),
            "render".to_string(),
            quote(&self.technique.display().to_string()),
            "--scene".to_string(),
            quote(&self.scene.display().to_string()),
            "--shadow-map".to_string(),
            self.shadow_map.to_string(),
            // the viewer's lights move: its graph is compiled for any scene
            "--generic".to_string(),
            "--camera".to_string(),
            quote(&ron_line(&self.camera)),
        ];
        for l in &self.lights {
            words.push("--light".to_string());
            words.push(quote(&ron_line(l)));
        }
        for (k, v) in &self.fixed {
            words.push("--set".to_string());
            words.push(quote(&format!("{k}={v}")));
        }
        for (k, v) in &self.params {
            words.push("--set".to_string());
            words.push(quote(&format!("{k}={}", param_literal(*v))));
        }
        for (k, v) in &self.precisions {
            words.push("--precision".to_string());
            words.push(quote(&format!("{k}={v}")));
        }
        for (k, v) in &self.schedules {
            words.push("--schedule".to_string());
            words.push(quote(&format!("{k}={v}")));
        }
        words.push("--out".to_string());
        words.push(quote(out));
        words.join(" ")
    }
}

/// A param's value as `--set` takes it: the shortest text that reads back as the same f64.
pub fn param_literal(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.1}")
    } else {
        format!("{v}")
    }
}

/// A value as one line of RON (what `--camera` and `--light` read).
pub fn ron_line<T: Serialize>(v: &T) -> String {
    ron::to_string(v).unwrap_or_default()
}

/// `s` quoted for a POSIX shell where it needs it.
fn quote(s: &str) -> String {
    if !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "-_./=:,+".contains(c)) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

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
    /// Show a channel of the technique by its name: the texture, layer and component its
    /// packing gave it (`sshc explain` lists them), mapped from `[lo, hi]` (stored values).
    ShowChannel {
        name: String,
        level: u32,
        lo: f32,
        hi: f32,
        map: ColourMap,
    },
    /// Draw the panels (`true`) or the view alone (`false`: screenshots without them; the
    /// Tab key does the same in the window).
    Panels(bool),
    /// Show a second technique or setting on the right half (`None`: the whole window is
    /// the main one again).
    Split(Option<Split>),
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

/// A script's text, read and checked ([`check`]); `path` names the file in messages.
pub fn parse(text: &str, path: &Path) -> Result<Vec<Event>, String> {
    let events: Vec<Event> = ron::from_str(text).map_err(|e| {
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
            Event::ShowChannel { lo, hi, .. } if !(lo.is_finite() && hi.is_finite() && lo < hi) => {
                "a channel is shown from `lo` to `hi`, finite with lo < hi".into()
            }
            Event::Show(Mode::Texture {
                lo,
                map: ColourMap::LogViridis,
                ..
            })
            | Event::ShowChannel {
                lo,
                map: ColourMap::LogViridis,
                ..
            } if *lo <= 0.0 => "a logarithmic map needs `lo` above 0".into(),
            _ => continue,
        };
        return Err((i, why));
    }
    Ok(())
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
                "[Panels(false), Show(Texture(name: \"m\", layer: 0, level: 0, channel: 0, lo: 0.0, hi: 1.0, map: LogViridis))]",
                1,
                "a logarithmic map needs `lo` above 0",
            ),
            (
                "[ShowChannel(name: \"z\", level: 0, lo: 1.0, hi: 1.0, map: Grey)]",
                0,
                "finite with lo < hi",
            ),
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
