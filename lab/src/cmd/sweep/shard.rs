//! A shard's folder: what `sshc sweep S.ron --shard i/n -o DIR` keeps there so that a
//! killed run resumes where it stopped, and so that `sshc sweep merge` needs nothing but
//! the folders.
//!
//! - `shard.ron`, the [`Manifest`]: what the shard belongs to (a hash of the sweep file and
//!   of every file it pulls in, the measurement options, the code), its index and count,
//!   its device, whether it finished, and each run that worked on it. Written whole (a
//!   temporary file renamed over it).
//! - `records.ron`, one [`Record`] per line, appended as each happens: a finished
//!   configuration's row, and each timing of the reference technique. A killed run leaves
//!   at most a partial last line, which the next run drops.

use crate::cmd::sweep::report::{PixelSet, Row};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::{BufRead as _, Write as _};
use std::path::{Path, PathBuf};
use xxhash_rust::xxh3::{Xxh3, xxh3_128};

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
        gpu + if i == 0 { self.baselines } else { 0 }
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

fn io(path: &Path) -> impl Fn(std::io::Error) -> String + '_ {
    move |e| format!("error: {}: {e}", path.display())
}

/// The manifest in `dir`, none if there is no `shard.ron`.
pub fn read_manifest(dir: &Path) -> Result<Option<Manifest>, String> {
    let path = dir.join(MANIFEST);
    let text = match sshc_scene::read_text(&path, sshc_scene::MAX_TEXT_BYTES) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(io(&path)(e)),
    };
    let m: Manifest =
        ron::from_str(&text).map_err(|e| format!("error: {}:{}:{}: {}", path.display(), e.span.start.line, e.span.start.col, e.code))?;
    if let Some(what) = m.impossible() {
        return Err(format!(
            "error: {}: {what}: no run writes it, the file was changed (remove the folder, or pass --fresh, to measure the shard again)",
            path.display()
        ));
    }
    Ok(Some(m))
}

/// Writes `m` as `dir/shard.ron`, whole: a temporary file of this process's own renamed
/// over it.
pub fn write_manifest(dir: &Path, m: &Manifest) -> Result<(), String> {
    let path = dir.join(MANIFEST);
    let text = ron::ser::to_string_pretty(m, ron::ser::PrettyConfig::default()).map_err(|e| format!("error: {}: {e}", path.display()))?;
    let mut tmp = tempfile::Builder::new()
        .prefix(&format!("shard.{}.", crate::claim::process_tag()))
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(io(dir))?;
    tmp.write_all(format!("{text}\n").as_bytes()).map_err(io(tmp.path()))?;
    tmp.persist(&path).map_err(|e| io(&path)(e.error))?;
    Ok(())
}

/// Reads `dir/records.ron`. A last line without its newline is what a killed run left
/// half written: with `repair` it is cut off the file (and counted in the answer's second
/// field), otherwise refused. Any other line that does not read is refused with its
/// position, and so is a record of a scene or a row that `m`, the shard's manifest, has
/// not.
pub fn read_records(dir: &Path, repair: bool, m: &Manifest) -> Result<(Done, bool), String> {
    let path = dir.join(RECORDS);
    let bytes = match sshc_scene::read_capped(&path, MAX_RECORDS_BYTES) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok((Done::default(), false)),
        Err(e) => return Err(io(&path)(e)),
    };
    let whole = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    let cut = whole < bytes.len();
    if cut {
        if !repair {
            return Err(format!(
                "error: {}: the last line is half written (its run was stopped): run the shard's command again to resume it",
                path.display()
            ));
        }
        crate::session::writable(&path)?;
        let f = std::fs::OpenOptions::new().write(true).open(&path).map_err(io(&path))?;
        f.set_len(whole as u64).map_err(io(&path))?;
    }
    let mut done = Done::default();
    for (n, line) in bytes[..whole].lines().enumerate() {
        let line = line.map_err(io(&path))?;
        if line.trim().is_empty() {
            continue;
        }
        let record: Record = ron::from_str(&line).map_err(|e| {
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
    Ok((done, cut))
}

/// `records.ron` open for appending.
pub struct Log {
    path: PathBuf,
    file: std::fs::File,
}

impl Log {
    pub fn open(dir: &Path) -> Result<Log, String> {
        let path = dir.join(RECORDS);
        let file = crate::session::append_to(&path)?;
        Ok(Log { path, file })
    }

    /// Appends `r` as one line, in one write, and waits for the disk: a run stopped at any
    /// moment leaves every earlier record whole.
    pub fn append(&mut self, r: &Record) -> Result<(), String> {
        let line = ron::to_string(r).map_err(|e| format!("error: {}: {e}", self.path.display()))?;
        self.file.write_all(format!("{line}\n").as_bytes()).map_err(io(&self.path))?;
        self.file.sync_data().map_err(io(&self.path))
    }
}

/// The hash of a file's bytes, as 32 hexadecimal digits.
pub fn hash_file(path: &Path) -> Result<String, String> {
    let bytes =
        sshc_scene::read_capped(path, crate::scene::MAX_OBJ_BYTES).map_err(|e| format!("error: cannot read `{}`: {e}", path.display()))?;
    Ok(format!("{:032x}", xxh3_128(&bytes)))
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

/// The code this binary runs: `git COMMIT` when built from a checkout with nothing
/// changed in the files compiled in (`lab/build.rs`), else `exe HASH`.
pub fn code() -> Result<String, String> {
    let commit = env!("SSHC_GIT_COMMIT");
    if !commit.is_empty() {
        return Ok(format!("git {commit}"));
    }
    let exe = std::env::current_exe().map_err(|e| format!("error: cannot find this executable: {e}"))?;
    let mut f = std::io::BufReader::with_capacity(1 << 20, std::fs::File::open(&exe).map_err(io(&exe))?);
    let mut h = Xxh3::new();
    loop {
        let chunk = f.fill_buf().map_err(io(&exe))?;
        if chunk.is_empty() {
            break;
        }
        h.update(chunk);
        let n = chunk.len();
        f.consume(n);
    }
    Ok(format!("exe {:032x}", h.digest128()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 48, item 10: records holding what no run writes (a NaN or infinite timing, a
    /// NaN error, a FLIP above 1) are refused with their line, in resume and merge alike.
    #[test]
    fn records_no_run_writes_are_refused_with_their_line() {
        let dir = std::env::temp_dir().join(format!("sshc-shard-records-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let row = Row {
            scene: "a".into(),
            label: "pcf".into(),
            config: "N=3".into(),
            shadow_map: 64,
            light_scale: 1.0,
            ms: Some(1.0),
            peak_bytes: 1,
            fetches: 1.0,
            ops: 1.0,
            acc: crate::metrics::Accuracy::default(),
            truth_se: 0.5,
            reference_ms: None,
            shard: (0, 1),
            device: Default::default(),
        };
        let line = |r: &Record| format!("{}\n", ron::to_string(r).unwrap());
        let good = Record::Row {
            index: 0,
            scene: 0,
            row: Box::new(row.clone()),
        };
        std::fs::write(dir.join(RECORDS), line(&good) + &line(&Record::Reference { scene: 0, ms: 2.0 })).unwrap();
        let m = Manifest {
            shard: (0, 1),
            rows: 3,
            ..manifest()
        };
        assert_eq!(m.impossible(), None);
        assert_eq!(read_records(&dir, false, &m).unwrap().0.rows.len(), 1);
        let mut nan_error = row.clone();
        nan_error.acc.facing.rms = f64::NAN;
        let mut big_flip = row.clone();
        big_flip.acc.flip = Some(7.5);
        let mut inf_ms = row.clone();
        inf_ms.ms = Some(f64::INFINITY);
        for (bad, want) in [
            (Record::Reference { scene: 0, ms: f64::NAN }, "a reference timing of NaN ms"),
            (
                Record::Row {
                    index: 1,
                    scene: 0,
                    row: Box::new(inf_ms),
                },
                "a row timed at inf ms",
            ),
            (
                Record::Row {
                    index: 1,
                    scene: 0,
                    row: Box::new(nan_error),
                },
                "a row with an error of RMS NaN",
            ),
            (
                Record::Row {
                    index: 1,
                    scene: 0,
                    row: Box::new(big_flip),
                },
                "a row with a FLIP of Some(7.5)",
            ),
        ] {
            std::fs::write(dir.join(RECORDS), line(&good) + &line(&bad)).unwrap();
            let e = read_records(&dir, false, &m).unwrap_err();
            assert!(e.contains("records.ron:2:") && e.contains(want), "{e}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    fn manifest() -> Manifest {
        Manifest {
            format: FORMAT,
            sweep: "s.ron".into(),
            identity: identity(&[("s.ron".into(), "1".into())], "o"),
            inputs: vec![("s.ron".into(), "1".into()), ("t.ron".into(), "2".into())],
            options: "o".into(),
            code: "git abc".into(),
            shard: (0, 2),
            device: ("gpu (driver)".into(), "gpu".into()),
            reference: "t.ron".into(),
            pixels: PixelSet::Penumbra,
            scenes: vec!["a.ron".into()],
            configurations: 3,
            baselines: 0,
            rows: 2,
            finished: false,
            runs: vec![],
        }
    }

    /// The rows of each shard of a split are the split's, once each, and a count no split
    /// gives is refused before it sizes anything.
    #[test]
    fn a_split_gives_each_row_to_one_shard_and_impossible_counts_are_named() {
        for (c, b) in [(1, 0), (3, 0), (7, 2), (5, 5)] {
            for n in 1..=9 {
                let shards: Vec<Manifest> = (0..n)
                    .map(|i| {
                        let mut m = Manifest {
                            shard: (i, n),
                            configurations: c,
                            baselines: b,
                            ..manifest()
                        };
                        m.rows = m.expected_rows();
                        m
                    })
                    .collect();
                let rows: usize = shards.iter().map(|m| m.rows).sum();
                assert_eq!(rows, c + b, "{c} {b} {n}");
                for index in 0..c + b + 3 {
                    let owners = shards.iter().filter(|m| m.holds(index)).count();
                    assert_eq!(owners, usize::from(index < c + b), "row {index} of {c}+{b} in {n}");
                }
                assert!(shards.iter().all(|m| m.impossible().is_none()));
            }
        }
        let m = manifest();
        assert_eq!(m.impossible(), None);
        for (bad, want) in [
            (
                Manifest {
                    shard: (0, usize::MAX),
                    ..m.clone()
                },
                "a split into",
            ),
            (
                Manifest {
                    shard: (2, 2),
                    ..m.clone()
                },
                "shard 2/2, which no split has",
            ),
            (
                Manifest {
                    configurations: usize::MAX,
                    ..m.clone()
                },
                "configurations and 0 baselines (a sweep has at most",
            ),
            (
                Manifest {
                    baselines: usize::MAX,
                    ..m.clone()
                },
                "baselines (a sweep has at most",
            ),
            (
                Manifest {
                    configurations: 0,
                    ..m.clone()
                },
                "a sweep of no configuration",
            ),
            (
                Manifest {
                    scenes: vec![],
                    ..m.clone()
                },
                "no scene",
            ),
            (
                Manifest {
                    baselines: 1,
                    scenes: vec!["a".into(), "b".into()],
                    ..m.clone()
                },
                "2 scenes for 3 configurations and 1 baselines",
            ),
            (
                Manifest { rows: 3, ..m.clone() },
                "3 rows for shard 0/2 of a sweep of 3 configurations and 0 baselines, which gives it 2",
            ),
        ] {
            let e = bad.impossible().unwrap_or_else(|| panic!("{bad:?} passed"));
            assert!(e.contains(want), "`{want}` not in `{e}`");
        }
    }

    #[test]
    fn a_half_written_last_line_is_cut_and_the_rest_read() {
        let dir = std::env::temp_dir().join(format!("sshc-shard-records-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let mut log = Log::open(&dir).unwrap();
        log.append(&Record::Reference { scene: 0, ms: 1.5 }).unwrap();
        log.append(&Record::Reference { scene: 0, ms: 0.1 + 0.2 }).unwrap();
        drop(log);
        let mut f = std::fs::OpenOptions::new().append(true).open(dir.join(RECORDS)).unwrap();
        f.write_all(b"Reference(scene: 0, m").unwrap();
        drop(f);
        assert!(read_records(&dir, false, &manifest()).unwrap_err().contains("half written"));
        let (done, cut) = read_records(&dir, true, &manifest()).unwrap();
        assert!(cut);
        // every value read back bit for bit
        assert_eq!(done.reference[&0], [1.5, 0.1 + 0.2]);
        assert_eq!(
            read_records(&dir, false, &manifest()).unwrap(),
            (done, false),
            "the file was repaired"
        );
        // a damaged line inside is refused with its line
        std::fs::write(
            dir.join(RECORDS),
            "Reference(scene: 0, ms: 1.0)\nRow(\nReference(scene: 0, ms: 1.0)\n",
        )
        .unwrap();
        let e = read_records(&dir, true, &manifest()).unwrap_err();
        assert!(e.contains("records.ron:2:"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_changed_input_code_or_device_is_named() {
        let a = manifest();
        assert_eq!(a.differs_from(&a), None);
        let mut b = manifest();
        b.inputs[1].1 = "3".into();
        b.identity = identity(&b.inputs, &b.options);
        assert_eq!(b.differs_from(&a).unwrap(), "another sweep: `t.ron` differs");
        let mut c = manifest();
        c.code = "exe 12".into();
        assert!(c.differs_from(&a).unwrap().contains("other code (git abc there, exe 12 here)"));
        let mut d = manifest();
        d.device.0 = "other".into();
        assert!(d.differs_from(&a).unwrap().contains("another device"));
    }
}
