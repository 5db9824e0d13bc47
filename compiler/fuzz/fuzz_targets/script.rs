//! A viewer script as `sshc view --script` reads it (`sshc_records::script::parse`: RON,
//! then every event's values checked before the window opens).
//!
//! Two kinds of input. One whose first byte is 0xFF drives a generator of event lists (up
//! to 8 events of every kind, numbers at the edges: NaN, infinities, -0, 1e30, u32::MAX
//! frames, sizes below 0, colour ranges reversed or empty, channels past 3), written as
//! RON and then edited as text (`mutate.rs`). Any other input is a script's text as it is
//! (the seeds are the scripts of the viewer's tests).
//!
//! Oracle: no panic, no allocation over libFuzzer's limits; every accepted script passes
//! the check again, holds only finite numbers where the view takes them, waits within
//! their caps, and each `State` event's `sshc render` line (`ViewState::command`) is
//! written without a panic.
#![no_main]

use glam::Vec3;
use libfuzzer_sys::arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use sshc_records::script::*;
use std::path::Path;

#[path = "mutate.rs"]
mod mutate;

const WORDS: &[&str] = &[
    "Wait", "WaitReady", "WaitCompiled", "WaitTruth", "Orbit", "Pan", "Zoom", "MoveLight", "LightSize", "Set", "Precision",
    "Schedule", "Show", "Split", "Technique", "Edit", "Screenshot", "State", "Reset", "Shaded", "Visibility", "Cascades",
    "Truth", "Error", "StdError", "Texture", "range", "lo", "hi", "channel", "layer", "level", "map", "Grey", "Viridis",
    "Diverging", "yaw", "pitch", "light", "by", "size", "name", "value",
];

fn float(u: &mut Unstructured) -> Result<f32> {
    Ok(match u.int_in_range(0..=11u8)? {
        0 => f32::NAN,
        1 => f32::INFINITY,
        2 => f32::NEG_INFINITY,
        3 => -0.0,
        4 => -1.0,
        5 => 1e30,
        6 => u.arbitrary()?,
        _ => f32::from(u.int_in_range(0u8..=8)?) * 0.25,
    })
}

fn frames(u: &mut Unstructured) -> Result<u32> {
    Ok(match u.int_in_range(0..=5u8)? {
        0 => u32::MAX,
        1 => MAX_WAIT_FRAMES,
        2 => MAX_WAIT_FRAMES + 1,
        3 => MAX_TRUTH_ROUNDS + 1,
        _ => u.int_in_range(0..=8)?,
    })
}

fn mode(u: &mut Unstructured) -> Result<Mode> {
    Ok(match u.int_in_range(0..=6u8)? {
        0 => Mode::Shaded,
        1 => Mode::Visibility,
        2 => Mode::Cascades,
        3 => Mode::Truth,
        4 => Mode::Error { range: float(u)? },
        5 => Mode::StdError { range: float(u)? },
        _ => Mode::Texture {
            name: "moments".into(),
            layer: u.arbitrary()?,
            level: u.arbitrary()?,
            channel: u.int_in_range(0..=5)?,
            lo: float(u)?,
            hi: float(u)?,
            map: ColourMap::ALL[u.int_in_range(0..=ColourMap::ALL.len() - 1)?],
        },
    })
}

fn event(u: &mut Unstructured) -> Result<Event> {
    Ok(match u.int_in_range(0..=16u8)? {
        0 => Event::Wait(frames(u)?),
        1 => Event::WaitReady,
        2 => Event::WaitCompiled,
        3 => Event::WaitTruth(frames(u)?),
        4 => Event::Orbit { yaw: float(u)?, pitch: float(u)? },
        5 => Event::Pan { x: float(u)?, y: float(u)? },
        6 => Event::Zoom(float(u)?),
        7 => Event::MoveLight {
            light: u.int_in_range(0..=4)?,
            by: Vec3::new(float(u)?, float(u)?, float(u)?),
        },
        8 => Event::LightSize { light: u.int_in_range(0..=4)?, size: float(u)? },
        9 => Event::Set {
            name: "bias".into(),
            value: f64::from(float(u)?),
        },
        10 => Event::Precision { name: "z".into(), value: "F16".into() },
        11 => Event::Show(mode(u)?),
        12 => Event::Screenshot("shot.png".into()),
        13 => Event::Technique("techniques/pcf.ron".into()),
        14 => Event::Panels(u.arbitrary()?),
        15 => Event::ShowChannel {
            name: "z".into(),
            level: u.arbitrary()?,
            lo: float(u)?,
            hi: float(u)?,
            map: ColourMap::ALL[u.int_in_range(0..=ColourMap::ALL.len() - 1)?],
        },
        _ => Event::Reset,
    })
}

fn finite(e: &Event) -> bool {
    let f = |x: f32| x.is_finite();
    match e {
        Event::Wait(n) => *n <= MAX_WAIT_FRAMES,
        Event::WaitTruth(n) => *n <= MAX_TRUTH_ROUNDS,
        Event::Orbit { yaw, pitch } => f(*yaw) && f(*pitch),
        Event::Pan { x, y } => f(*x) && f(*y),
        Event::Zoom(z) => f(*z) && *z > 0.0,
        Event::MoveLight { by, .. } => by.is_finite(),
        Event::LightSize { size, .. } => f(*size) && *size >= 0.0,
        Event::Set { value, .. } => value.is_finite(),
        Event::Show(Mode::Error { range } | Mode::StdError { range }) => f(*range) && *range > 0.0,
        Event::Show(Mode::Texture { lo, hi, channel, map, .. }) => {
            f(*lo) && f(*hi) && lo < hi && *channel <= 3 && (*map != ColourMap::LogViridis || *lo > 0.0)
        }
        Event::ShowChannel { lo, hi, map, .. } => f(*lo) && f(*hi) && lo < hi && (*map != ColourMap::LogViridis || *lo > 0.0),
        _ => true,
    }
}

fn drive(text: &str) {
    let Ok(events) = parse(text, Path::new("s.ron")) else {
        return;
    };
    assert_eq!(check(&events), Ok(()));
    for e in &events {
        assert!(finite(e), "accepted {e:?}");
        if let Event::State(s) = e {
            let _ = s.command("out.png");
            let _ = s.right();
        }
    }
}

fuzz_target!(|data: &[u8]| {
    if let [0xFF, rest @ ..] = data {
        let mut u = Unstructured::new(rest);
        let mut events = Vec::new();
        for _ in 0..u.int_in_range(0..=8u8).unwrap_or(0) {
            match event(&mut u) {
                Ok(e) => events.push(e),
                Err(_) => break,
            }
        }
        let Ok(text) = ron::to_string(&events) else { return };
        let text = mutate::mutate(&mut u, text, WORDS);
        drive(&text);
    } else if let Ok(text) = std::str::from_utf8(data) {
        drive(text);
    }
});
