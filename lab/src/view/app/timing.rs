//! The frame's times: each pass's GPU time, the panels' and the presentation's CPU time,
//! the frame interval, over the last 60 frames, and their medians.

use std::collections::{BTreeMap, VecDeque};
use std::time::Instant;

/// The last GPU times, per pass (ms), and the frame time.
#[derive(Default)]
pub(super) struct Times {
    pub(super) passes: Vec<(String, f64)>,
    /// The last 60 frames: sshc's GPU time (its passes' timestamps), the panels' CPU time
    /// (egui's pass and tessellation), the frame interval.
    pub(super) gpu_ms: VecDeque<f64>,
    pub(super) ui_ms: VecDeque<f64>,
    /// Acquiring the window's next texture and presenting it (CPU, waits included).
    pub(super) present_ms: VecDeque<f64>,
    pub(super) frame_ms: VecDeque<f64>,
    pub(super) last: Option<Instant>,
    /// The frame number of the last GPU times taken.
    pub(super) gpu_frame: Option<u64>,
    /// Each pass's GPU times over the same frames.
    pub(super) pass_ms: BTreeMap<String, VecDeque<f64>>,
}

pub(super) fn push(v: &mut VecDeque<f64>, x: f64) {
    v.push_back(x);
    if v.len() > 60 {
        v.pop_front();
    }
}

/// The median of a window of times (NaN when empty).
pub(super) fn median(v: &VecDeque<f64>) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().collect();
    s.sort_by(f64::total_cmp);
    s.get(s.len() / 2).copied().unwrap_or(f64::NAN)
}
