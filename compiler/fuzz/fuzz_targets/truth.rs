//! A truth cache record as every task sharing a cache folder reads it
//! (`sshc_records::truth::parse_record`, the reading of `TruthCache::load`).
//!
//! Two kinds of input. One whose first byte is 0xFF drives a generator: a `Truth` of a
//! small or hostile size (0, a few pixels, `u32::MAX` with few values), visibilities and
//! standard errors at the edges (NaN, infinities, -0, 1 + 1 ulp, 7.5), under a key that
//! matches or not, with its checksum right, wrong or absent, written as RON and then edited
//! as text (`mutate.rs`). Any other input is the record's text as it is (the seeds are
//! records of real runs).
//!
//! Oracle: no panic, no allocation over libFuzzer's limits; an accepted record is the
//! key's, holds one visibility in [0, 1] and one finite standard error >= 0 per pixel, and
//! its checksum is that of what it holds.
#![no_main]

use libfuzzer_sys::arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use sshc_records::truth::*;
use std::path::Path;

#[path = "mutate.rs"]
mod mutate;

const KEY: &str = "338267f3e515b783151763d5902b5c3a";
const WORDS: &[&str] = &[
    "key", "checksum", "truth", "width", "height", "visibility", "std_error", "samples", "runs", "levels", "surface_pixels",
    "samples_evaluated", "rays_at_least", "seconds", "threads", "max_std_error", "rms_std_error", KEY,
];

fn float(u: &mut Unstructured) -> Result<f32> {
    Ok(match u.int_in_range(0..=11u8)? {
        0 => f32::NAN,
        1 => f32::INFINITY,
        2 => f32::NEG_INFINITY,
        3 => -0.0,
        4 => 1.0 + f32::EPSILON,
        5 => 7.5,
        6 => u.arbitrary()?,
        _ => f32::from(u.int_in_range(0u8..=4)?) * 0.25,
    })
}

fn truth(u: &mut Unstructured) -> Result<Truth> {
    let (width, height) = match u.int_in_range(0..=5u8)? {
        0 => (u32::MAX, u32::MAX),
        1 => (0, u.int_in_range(0..=4)?),
        _ => (u.int_in_range(0..=4)?, u.int_in_range(0..=4)?),
    };
    let pixels = (width as usize).saturating_mul(height as usize).min(16);
    let n = if u.ratio(7, 8)? { pixels } else { u.int_in_range(0..=17)? };
    let visibility = (0..n).map(|_| float(u)).collect::<Result<_>>()?;
    let n = if u.ratio(7, 8)? { pixels } else { u.int_in_range(0..=17)? };
    let std_error = (0..n).map(|_| float(u)).collect::<Result<_>>()?;
    Ok(Truth {
        width,
        height,
        visibility,
        std_error,
        samples: u.arbitrary()?,
        runs: u.arbitrary()?,
        levels: vec![Level {
            samples: u.arbitrary()?,
            max_std_error: float(u)?,
            rms_std_error: float(u)?,
            seconds: 0.5,
        }],
        surface_pixels: u.arbitrary()?,
        samples_evaluated: u.arbitrary()?,
        rays_at_least: u.arbitrary()?,
        seconds: 1.0,
        threads: 2,
    })
}

fn drive(text: &str) {
    let Ok(t) = parse_record(text, KEY, Path::new("r.ron")) else {
        return;
    };
    let pixels = t.width as usize * t.height as usize;
    assert!(t.visibility.len() == pixels && t.std_error.len() == pixels);
    assert!(t.visibility.iter().all(|v| (0.0..=1.0).contains(v)));
    assert!(t.std_error.iter().all(|e| e.is_finite() && *e >= 0.0));
    assert!(checksum(&t).is_ok());
    let _ = (t.mean_std_error(), t.max_std_error(), t.rms_std_error(), t.samples_per_second());
}

fuzz_target!(|data: &[u8]| {
    if let [0xFF, rest @ ..] = data {
        let mut u = Unstructured::new(rest);
        let Ok(t) = truth(&mut u) else { return };
        let sum = checksum(&t).ok();
        let record = Record {
            key: if u.ratio(7, 8).unwrap_or(true) { KEY.into() } else { "0".into() },
            checksum: match u.int_in_range(0..=3u8).unwrap_or(0) {
                0 => None,
                1 => Some("0123456789abcdef".into()),
                _ => sum,
            },
            truth: t,
        };
        let Ok(text) = ron::to_string(&record) else { return };
        let text = mutate::mutate(&mut u, text, WORDS);
        drive(&text);
    } else if let Ok(text) = std::str::from_utf8(data) {
        drive(text);
    }
});
