//! A sweep's shard folder as the lab writes it and reads it back (`sshc sweep --shard i/n
//! -o DIR`, `sshc sweep merge`): `shard.ron`, the [`Manifest`] (what the shard belongs to,
//! its index and count, its device, whether it finished, each run that worked on it), and
//! `records.ron`, one [`Record`] per line (a finished configuration's [`Row`], each timing
//! of the reference technique). Every file of a shard folder is read as hostile: a cluster's
//! tasks share them. The lab does the file I/O (the one reader, the one writer); the
//! reading of their contents is here, where the fuzz target `shard` reaches it.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;
use xxhash_rust::xxh3::Xxh3;

/// The pixel set a sweep's charts rank by.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum PixelSet {
    #[default]
    Penumbra,
    ShadowOnGround,
}

impl PixelSet {
    /// The RMS error of `r` over this set.
    pub fn rms(self, r: &Row) -> f64 {
        match self {
            PixelSet::Penumbra => r.acc.penumbra.rms,
            PixelSet::ShadowOnGround => r.acc.ground.map_or(f64::NAN, |g| g.rms),
        }
    }
}

/// One measured row: what a shard stores per configuration as it finishes
/// (`records.ron`, this module) and what the outputs print. The last
/// three fields are the shard's, not stored per row: they are filled when the shard's
/// rows are gathered.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    pub scene: String,
    pub label: String,
    pub config: String,
    pub shadow_map: u32,
    pub light_scale: f64,
    /// Median GPU ms per frame (all passes), or none for CPU baselines.
    pub ms: Option<f64>,
    /// The fastest and the slowest of the timed frames whose median is `ms` (the charts'
    /// error bars); none for CPU baselines and for rows recorded before it was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ms_range: Option<(f64, f64)>,
    pub peak_bytes: u64,
    pub fetches: f64,
    pub ops: f64,
    pub acc: crate::accuracy::Accuracy,
    pub truth_se: f64,
    /// The median of the reference technique's times on this row's scene, in its shard
    /// (none for CPU baselines' scenes where the shard timed nothing).
    #[serde(skip)]
    pub reference_ms: Option<f64>,
    /// The shard that measured it, `(i, n)`.
    #[serde(skip)]
    pub shard: (usize, usize),
    /// That shard's device: in full, and its adapter's name alone.
    #[serde(skip)]
    pub device: (String, String),
}

impl Row {
    pub fn ratio(&self) -> Option<f64> {
        Some(self.ms? / self.reference_ms?)
    }
}

pub const MANIFEST: &str = "shard.ron";
pub const RECORDS: &str = "records.ron";
/// The largest `records.ron` read: about 200,000 rows of a sweep.
pub const MAX_RECORDS_BYTES: u64 = 256 << 20;
/// The manifest's format; a folder of another is refused by the merge and started
/// afresh by a run.
pub const FORMAT: u32 = 1;
/// The most shards a split has (`--shard i/n`): Slurm's own array limit is 1001 by
/// default and 4,000,001 at most, and a merge of more folders than this is no one's
/// plan. A count beyond it in `shard.ron` was written by no run (a count of 2^64-1 made
/// the merge's table of shards panic; issue 48, item 2).
pub const MAX_SHARDS: usize = 1 << 16;
/// The most rows (GPU configurations and CPU baselines) a sweep has: `records.ron` holds
/// about 200,000 at its size cap ([`MAX_RECORDS_BYTES`]), and a sweep file whose grid is
/// larger is refused at load.
pub const MAX_ROWS: usize = 1 << 20;

/// What a shard belongs to and where it stands.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub format: u32,
    /// The sweep file as the command line named it.
    pub sweep: String,
    /// A hash of the sweep file, every file it pulls in and the measurement options: the
    /// shards of one sweep have the same.
    pub identity: String,
    /// Each file the sweep pulls in, with the hash of its bytes: the sweep file, the
    /// reference and every technique, every scene file and the meshes it loads.
    pub inputs: Vec<(String, String)>,
    /// The options that change what is measured (truth, cascades), in words.
    pub options: String,
    /// The code: `git COMMIT` when the binary was built from a clean checkout, else
    /// `exe HASH`, a hash of the executable.
    pub code: String,
    /// `(i, n)`.
    pub shard: (usize, usize),
    /// The device in full, and its adapter's name alone (charts).
    pub device: (String, String),
    /// The reference technique's file as the sweep file names it.
    pub reference: String,
    pub pixels: PixelSet,
    /// Scene entries (`PATH#k` for light k alone of a scene of several).
    pub scenes: Vec<String>,
    /// GPU configurations in the whole sweep, and CPU baseline rows (shard 0 writes them).
    pub configurations: usize,
    pub baselines: usize,
    /// Rows this shard writes.
    pub rows: usize,
    pub finished: bool,
    /// Every run that worked on the shard, the first one first.
    pub runs: Vec<Run>,
}

/// One process that worked on a shard.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Run {
    pub host: String,
    pub pid: u32,
    /// Seconds since the Unix epoch, by the host's clock.
    pub started: u64,
    /// Rows found done when it started.
    pub resumed_at: usize,
    /// Its wall time, once it finished the shard (none for a run that was stopped).
    pub seconds: Option<f64>,
}

impl Manifest {
    /// What no run writes (issue 48, items 2 and 10): a split no `--shard` names, counts
    /// beyond [`MAX_SHARDS`] and [`MAX_ROWS`], a sweep of no configuration or no scene,
    /// baselines that are not a whole number per scene, and a row count other than the
    /// split gives this shard. Checked before any count sizes anything.
    pub fn impossible(&self) -> Option<String> {
        let (i, n) = self.shard;
        let (c, b) = (self.configurations, self.baselines);
        if n > MAX_SHARDS {
            return Some(format!("a split into {n} shards (at most {MAX_SHARDS})"));
        }
        if n == 0 || i >= n {
            return Some(format!("shard {i}/{n}, which no split has"));
        }
        if c > MAX_ROWS || b > MAX_ROWS {
            return Some(format!(
                "{c} configurations and {b} baselines (a sweep has at most {MAX_ROWS} rows)"
            ));
        }
        if c == 0 {
            return Some("a sweep of no configuration".to_string());
        }
        if self.scenes.is_empty() {
            return Some("no scene".to_string());
        }
        if self.scenes.len() > c || !b.is_multiple_of(self.scenes.len()) {
            return Some(format!(
                "{} scenes for {c} configurations and {b} baselines (each scene has its configurations and as many baselines)",
                self.scenes.len()
            ));
        }
        let expected = self.expected_rows();
        if self.rows != expected {
            return Some(format!(
                "{} rows for shard {i}/{n} of a sweep of {c} configurations and {b} baselines, which gives it {expected}",
                self.rows
            ));
        }
        None
    }

    /// The rows shard `i` of `n` writes: every n-th configuration from the i-th, and shard
    /// 0 the baselines too.
    pub fn expected_rows(&self) -> usize {
        let (i, n) = self.shard;
        let gpu = if i < self.configurations {
            (self.configurations - i - 1) / n.max(1) + 1
        } else {
            0
        };
        gpu.saturating_add(if i == 0 { self.baselines } else { 0 })
    }

    /// Whether row `index` of the whole sweep is this shard's.
    pub fn holds(&self, index: usize) -> bool {
        let (i, n) = self.shard;
        if index < self.configurations {
            index % n.max(1) == i
        } else {
            i == 0 && index - self.configurations < self.baselines
        }
    }

    /// Why a shard run with `self` cannot carry on the folder's `old` work, or none.
    pub fn differs_from(&self, old: &Manifest) -> Option<String> {
        if old.format != self.format {
            return Some(format!(
                "its manifest is of format {} (this sshc writes {})",
                old.format, self.format
            ));
        }
        if old.identity != self.identity {
            return Some(format!("another sweep: {}", input_changes(old, self)));
        }
        if old.code != self.code {
            return Some(format!("other code ({} there, {} here)", old.code, self.code));
        }
        if old.device != self.device {
            return Some(format!("another device ({} there, {} here)", old.device.0, self.device.0));
        }
        None
    }
}

/// The inputs and options in which two manifests differ, in words.
pub fn input_changes(a: &Manifest, b: &Manifest) -> String {
    let mut out = Vec::new();
    for (name, hash) in &b.inputs {
        match a.inputs.iter().find(|(n, _)| n == name) {
            Some((_, h)) if h == hash => {}
            Some(_) => out.push(format!("`{name}` differs")),
            None => out.push(format!("`{name}` is new")),
        }
    }
    for (name, _) in &a.inputs {
        if !b.inputs.iter().any(|(n, _)| n == name) {
            out.push(format!("`{name}` is no longer used"));
        }
    }
    if a.options != b.options {
        out.push(format!("the options differ (`{}` against `{}`)", a.options, b.options));
    }
    if out.is_empty() {
        // the same contents under other names: the files moved
        out.push("the files are the same but named otherwise".to_string());
    }
    out.join(", ")
}

/// A line of `records.ron`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Record {
    /// Configuration `index` of the whole sweep (CPU baselines after the GPU ones), on
    /// scene entry `scene`, done.
    Row { index: usize, scene: usize, row: Box<Row> },
    /// One timing of the reference technique on scene entry `scene`: the median GPU ms of
    /// its frames.
    Reference { scene: usize, ms: f64 },
}

impl Record {
    /// What no run writes (issue 48, item 10): a time that is not a finite number above 0,
    /// an error figure or count that is not finite or negative, a FLIP outside [0, 1].
    pub fn impossible(&self) -> Option<String> {
        let bad = |x: f64| !(x.is_finite() && x >= 0.0);
        match self {
            Record::Reference { ms, .. } if !(ms.is_finite() && *ms > 0.0) => Some(format!("a reference timing of {ms} ms")),
            Record::Reference { .. } => None,
            Record::Row { row, .. } => {
                let a = &row.acc;
                let stats = [&a.facing, &a.penumbra, &a.lit, &a.umbra].into_iter().chain(a.ground.as_ref());
                if let Some(ms) = row.ms
                    && !(ms.is_finite() && ms > 0.0)
                {
                    return Some(format!("a row timed at {ms} ms"));
                }
                if let Some((lo, hi)) = row.ms_range {
                    // the median of frames lies between their fastest and their slowest
                    let inside = row.ms.is_some_and(|ms| lo <= ms && ms <= hi);
                    if !(lo.is_finite() && lo > 0.0 && hi.is_finite() && inside) {
                        return Some(format!("a row timed at {:?} ms with frames from {lo} to {hi} ms", row.ms));
                    }
                }
                for s in stats {
                    if bad(s.rms) || bad(s.max) || !s.mean.is_finite() {
                        return Some(format!("a row with an error of RMS {}, max {}, mean {}", s.rms, s.max, s.mean));
                    }
                }
                if a.flip.is_some_and(|f| !(0.0..=1.0).contains(&f)) {
                    return Some(format!("a row with a FLIP of {:?}", a.flip));
                }
                if bad(row.fetches) || bad(row.ops) || bad(row.truth_se) || bad(row.light_scale) {
                    return Some(format!(
                        "a row with {} fetches, {} operations, a truth standard error of {}, a light scale of {}",
                        row.fetches, row.ops, row.truth_se, row.light_scale
                    ));
                }
                None
            }
        }
    }
}

/// What `records.ron` holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Done {
    /// Rows by configuration index, with their scene entry.
    pub rows: BTreeMap<usize, (usize, Row)>,
    /// The reference's timings per scene entry.
    pub reference: BTreeMap<usize, Vec<f64>>,
}

impl Done {
    /// The rows in order, each with the median of its scene's reference timings, the shard
    /// and the device of `m`.
    pub fn gathered(&self, m: &Manifest) -> Vec<Row> {
        let median = |scene: usize| -> Option<f64> {
            let mut t = self.reference.get(&scene)?.clone();
            t.sort_by(f64::total_cmp);
            t.get(t.len() / 2).copied()
        };
        self.rows
            .values()
            .map(|(scene, row)| Row {
                reference_ms: median(*scene),
                shard: m.shard,
                device: m.device.clone(),
                ..row.clone()
            })
            .collect()
    }
}

/// `shard.ron`'s text, read as a [`Manifest`] and checked ([`Manifest::impossible`]);
/// `path` names the file in messages.
pub fn parse_manifest(text: &str, path: &Path) -> Result<Manifest, String> {
    let m: Manifest =
        ron::from_str(text).map_err(|e| format!("error: {}:{}:{}: {}", path.display(), e.span.start.line, e.span.start.col, e.code))?;
    if let Some(what) = m.impossible() {
        return Err(format!(
            "error: {}: {what}: no run writes it, the file was changed (remove the folder, or pass --fresh, to measure the shard again)",
            path.display()
        ));
    }
    Ok(m)
}

/// `records.ron`'s bytes up to the last newline, read: every line a [`Record`] that a run
/// of the shard of `m` writes (its rows, its scenes, values no run writes refused with
/// their line); `path` names the file in messages. A half-written last line (after the
/// last newline) is the caller's to cut or refuse.
pub fn parse_records(bytes: &[u8], path: &Path, m: &Manifest) -> Result<Done, String> {
    let mut done = Done::default();
    for (n, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = std::str::from_utf8(line).map_err(|e| format!("error: {}:{}: {e}", path.display(), n + 1))?;
        if line.trim().is_empty() {
            continue;
        }
        let record: Record = ron::from_str(line).map_err(|e| {
            format!(
                "error: {}:{}:{}: {} (remove the folder, or pass --fresh, to measure the shard again)",
                path.display(),
                n + 1,
                e.span.start.col,
                e.code
            )
        })?;
        let (si, sn) = m.shard;
        let scenes = m.scenes.len();
        let misplaced = match &record {
            Record::Row { index, .. } if !m.holds(*index) => Some(format!(
                "row {index} is not shard {si}/{sn}'s (the sweep has {} configurations and {} baselines)",
                m.configurations, m.baselines
            )),
            Record::Row { scene, .. } | Record::Reference { scene, .. } if *scene >= scenes => Some(format!(
                "scene entry {scene} of a sweep of {scenes} scene{}",
                if scenes == 1 { "" } else { "s" }
            )),
            _ => None,
        };
        if let Some(what) = misplaced.or_else(|| record.impossible()) {
            return Err(format!(
                "error: {}:{}: {what}: no run writes it (remove the folder, or pass --fresh, to measure the shard again)",
                path.display(),
                n + 1
            ));
        }
        match record {
            Record::Row { index, scene, row } => {
                done.rows.insert(index, (scene, *row));
            }
            Record::Reference { scene, ms } => done.reference.entry(scene).or_default().push(ms),
        }
    }
    Ok(done)
}

/// The identity of a sweep: a hash of the hashes of its inputs, in order, and of the
/// options.
pub fn identity(inputs: &[(String, String)], options: &str) -> String {
    let mut h = Xxh3::new();
    for (_, hash) in inputs {
        h.update(hash.as_bytes());
    }
    h.update(options.as_bytes());
    format!("{:032x}", h.digest128())
}
