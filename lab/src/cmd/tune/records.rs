//! A tune's records: each measurement a line of `records.ron` (`records-I-of-N.ron` for
//! shard i of n), read back with a half-written last line left out, and an earlier run of
//! the same tune resumed from them (`tune.id` says whether it is the same).

use super::measure::Detail;
use super::search::Measured;
use crate::session::read_capped;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The largest `records.ron` a resumed run reads (bytes): about 100,000 records.
const MAX_RECORDS_BYTES: u64 = 64 << 20;

/// One line of `records.ron`: a configuration measured at a rung, or why it was not.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(crate) struct Record {
    pub(super) technique: String,
    pub(super) config: String,
    pub(super) rung: usize,
    pub(crate) result: Result<(Measured, Detail), String>,
}

impl Record {
    /// Refuses records a run could not have written: non-finite or negative figures.
    fn check(&self) -> Result<(), String> {
        if let Ok((m, d)) = &self.result {
            let finite = [m.error, d.flip, d.rms_facing, d.rms_penumbra, d.ms]
                .iter()
                .chain(&m.times)
                .all(|x| x.is_finite() && *x >= 0.0);
            if !finite || m.times.is_empty() {
                return Err(format!(
                    "the record of {} {} at rung {} holds a figure that is not a finite number >= 0",
                    self.technique, self.config, self.rung
                ));
            }
        }
        Ok(())
    }
}

const RECORDS: &str = "records.ron";
const IDENTITY: &str = "tune.id";

/// The records file of shard `(i, n)`: `records.ron` unsharded, else `records-I-of-N.ron`.
pub(super) fn records_name((i, n): (usize, usize)) -> String {
    if n <= 1 {
        RECORDS.to_string()
    } else {
        format!("records-{i}-of-{n}.ron")
    }
}

/// The records in one file. A last line that does not parse is a record being written (by
/// another shard) or cut short by a kill: left out, and reported as `true`. A line before
/// it that does not parse, or a record with a figure a run cannot write, is refused with
/// its line.
pub(super) fn read_records(path: &Path) -> Result<(Vec<Record>, bool), String> {
    let text = read_capped(path, MAX_RECORDS_BYTES)?;
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        match ron::from_str::<Record>(line) {
            Ok(r) => {
                r.check()
                    .map_err(|e| format!("error: {}:{}: {e}; run again with --fresh", path.display(), i + 1))?;
                out.push(r);
            }
            Err(_) if i + 1 == lines.len() => return Ok((out, true)),
            Err(e) => {
                return Err(format!(
                    "error: {}:{}: not a record ({}); run again with --fresh",
                    path.display(),
                    i + 1,
                    e.code
                ));
            }
        }
    }
    Ok((out, false))
}

/// Every shard's records files in `out` (`records.ron`, `records-I-of-N.ron`).
pub(super) fn records_files(out: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(out)
        .map(|d| {
            d.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.file_name()
                        .and_then(|n| n.to_str())
                        .is_some_and(|n| n.starts_with("records") && n.ends_with(".ron"))
                })
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// The records of an earlier run of the same tune in `out`, every shard's, by (technique,
/// config, rung): none where the folder is new, `--fresh` is given, or the run differs (its
/// identity, the hash of its inputs and options, says so). Starting afresh, a shard
/// forgets its own records only.
pub(super) fn resume(
    out: &Path,
    identity: &str,
    fresh: bool,
    shard: (usize, usize),
) -> Result<HashMap<(String, String, usize), Record>, String> {
    let id_path = out.join(IDENTITY);
    let mine = out.join(records_name(shard));
    let old = read_capped(&id_path, 4096).ok();
    let mut found = HashMap::new();
    if !fresh && old.as_deref() == Some(identity) {
        for path in records_files(out) {
            let (records, cut) = read_records(&path)?;
            if cut && path == mine {
                // cut short by a kill: dropped, and the file rewritten without it so that
                // the next record starts a line of its own
                eprintln!("tune: dropped the half-written last record of a stopped run");
                let kept: Result<Vec<String>, String> = records
                    .iter()
                    .map(|r| ron::to_string(r).map_err(|e| format!("error: a record: {e}")))
                    .collect();
                let kept: String = kept?.iter().map(|l| format!("{l}\n")).collect();
                crate::cmd::tune::report::write_new(&mine, &kept)?;
            }
            for r in records {
                found.insert((r.technique.clone(), r.config.clone(), r.rung), r);
            }
        }
        if !found.is_empty() {
            eprintln!(
                "tune: resuming in {}: {} measurements of an earlier run",
                out.display(),
                found.len()
            );
        }
    } else {
        if old.is_some() && !fresh {
            eprintln!("tune: {} holds another tune's records: starting afresh", out.display());
        }
        match std::fs::remove_file(&mine) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(format!("error: {}: {e}", mine.display())),
            _ => {}
        }
        crate::cmd::tune::report::write_new(&id_path, identity)?;
    }
    Ok(found)
}
