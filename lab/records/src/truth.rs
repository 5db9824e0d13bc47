//! The ground truth of one camera image and its cache record as the lab stores it
//! (`.sshc-cache/truth/KEY.ron`, shared by every task of a cluster job): the types and the
//! checked reading of a record's text. The lab computes truths, keys them and does the file
//! I/O; the reading is here, where the fuzz target `truth` reaches it.

use serde::{Deserialize, Serialize};
use std::path::Path;
use xxhash_rust::xxh3::xxh3_64;

/// One level of the doubling: its samples per run and the standard errors it reached.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Level {
    /// Light samples per pixel per run (`n x n`; 1 for a point or directional light).
    pub samples: u32,
    /// Largest per-pixel standard error over the pixels that show a surface.
    pub max_std_error: f32,
    /// Root-mean-square per-pixel standard error over the same pixels.
    pub rms_std_error: f32,
    /// Seconds this level took.
    pub seconds: f64,
}

/// The ground truth of one camera image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Visible fraction of the light per pixel (rows top first): the mean of the runs.
    pub visibility: Vec<f32>,
    /// Standard error of [`Truth::visibility`] per pixel (0 where no surface is seen).
    pub std_error: Vec<f32>,
    /// Light samples per pixel per run of the final level.
    pub samples: u32,
    /// Independent runs of the final level.
    pub runs: u32,
    /// Every level computed, the final one last.
    pub levels: Vec<Level>,
    /// Pixels that show a surface (finite position).
    pub surface_pixels: u64,
    /// Light samples evaluated, all levels and runs (a pixel answered without rays by the
    /// visibility query's conservative skip test counts with all its samples).
    pub samples_evaluated: u64,
    /// Rays certainly cast: the samples of the pixels that read below 1 in a run (each of
    /// those casts one ray per sample). A lower bound of the rays cast.
    pub rays_at_least: u64,
    /// Wall-clock seconds of the computation (all levels).
    pub seconds: f64,
    /// Rayon worker threads used.
    pub threads: u32,
}

impl Truth {
    fn surface_errors(&self) -> impl Iterator<Item = f32> + '_ {
        self.std_error.iter().copied().filter(|e| e.is_finite())
    }

    /// Largest per-pixel standard error.
    pub fn max_std_error(&self) -> f32 {
        self.levels.last().map_or(0.0, |l| l.max_std_error)
    }

    /// Mean per-pixel standard error over the pixels that show a surface.
    pub fn mean_std_error(&self) -> f32 {
        if self.surface_pixels == 0 {
            return 0.0;
        }
        let sum: f64 = self.surface_errors().map(f64::from).sum();
        // Pixels without a surface hold 0 and add nothing.
        (sum / self.surface_pixels as f64) as f32
    }

    /// Root-mean-square per-pixel standard error over the pixels that show a surface.
    pub fn rms_std_error(&self) -> f32 {
        self.levels.last().map_or(0.0, |l| l.rms_std_error)
    }

    /// Light samples per second (see [`Truth::samples_evaluated`]).
    pub fn samples_per_second(&self) -> f64 {
        self.samples_evaluated as f64 / self.seconds.max(1e-9)
    }

    /// Rays per second, a lower bound (see [`Truth::rays_at_least`]).
    pub fn rays_per_second_at_least(&self) -> f64 {
        self.rays_at_least as f64 / self.seconds.max(1e-9)
    }
}

/// The record stored per key (the key is checked again on load).
#[derive(Serialize, Deserialize)]
pub struct Record {
    pub key: String,
    /// The xxh3 of the truth as written (its RON text), so that a record altered after it
    /// was written is told from one written by a run (issue 48, item 9). Records without
    /// it (written before it existed) are recomputed.
    #[serde(default)]
    pub checksum: Option<String>,
    pub truth: Truth,
}

/// The checksum a record stores of its truth.
pub fn checksum(truth: &Truth) -> Result<String, String> {
    let text = ron::to_string(truth).map_err(|e| e.to_string())?;
    Ok(format!("{:016x}", xxh3_64(text.as_bytes())))
}

/// A cache record's text, read as the truth of `key`: refused, saying why, where it is not
/// RON, is another key's, holds a visibility outside [0, 1] or a standard error that is not
/// finite and >= 0, or lacks its checksum or does not match it (altered after it was
/// written); `path` names the file in messages.
pub fn parse_record(text: &str, key: &str, path: &Path) -> Result<Truth, String> {
    let record: Record =
        ron::from_str(text).map_err(|e| format!("{}:{}:{}: {}", path.display(), e.span.start.line, e.span.start.col, e.code))?;
    let t = &record.truth;
    let pixels = t.width as usize * t.height as usize;
    if record.key != key || t.visibility.len() != pixels || t.std_error.len() != pixels {
        return Err(format!("{}: the record does not match its key", path.display()));
    }
    // values a run can write: a visibility in [0, 1], a standard error finite and >= 0
    if let Some(i) = t.visibility.iter().position(|v| !(0.0..=1.0).contains(v)) {
        return Err(format!(
            "{}: pixel {i} holds a visibility of {}, outside [0, 1]",
            path.display(),
            t.visibility[i]
        ));
    }
    if let Some(i) = t.std_error.iter().position(|e| !(e.is_finite() && *e >= 0.0)) {
        return Err(format!(
            "{}: pixel {i} holds a standard error of {}",
            path.display(),
            t.std_error[i]
        ));
    }
    match (&record.checksum, checksum(t)) {
        (Some(stored), Ok(now)) if *stored == now => {}
        (Some(_), _) => {
            return Err(format!(
                "{}: its checksum does not match its contents: the record was altered after it was written",
                path.display()
            ));
        }
        (None, _) => return Err(format!("{}: the record has no checksum (an older sshc wrote it)", path.display())),
    }
    Ok(record.truth)
}
