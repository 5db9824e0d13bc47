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

use std::io::{BufRead as _, Write as _};
use std::path::{Path, PathBuf};
use xxhash_rust::xxh3::{Xxh3, xxh3_128};

pub use sshc_records::sweep::{
    Done, FORMAT, MANIFEST, MAX_RECORDS_BYTES, MAX_ROWS, MAX_SHARDS, Manifest, RECORDS, Record, Run, identity, input_changes,
};

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
    sshc_records::sweep::parse_manifest(&text, &path).map(Some)
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
    let done = sshc_records::sweep::parse_records(&bytes[..whole], &path, m)?;
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
    use crate::cmd::sweep::report::{PixelSet, Row};

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
            ms_range: None,
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
        // the frames' spread is kept (written only where known: a row without it, as
        // written before, reads as none), and one that does not hold the median is refused
        let mut spread = row.clone();
        spread.ms_range = Some((0.5, 1.25));
        let with_spread = Record::Row {
            index: 0,
            scene: 0,
            row: Box::new(spread.clone()),
        };
        assert!(!line(&good).contains("ms_range") && line(&with_spread).contains("ms_range"));
        std::fs::write(dir.join(RECORDS), line(&with_spread)).unwrap();
        assert_eq!(read_records(&dir, false, &m).unwrap().0.rows[&0].1.ms_range, Some((0.5, 1.25)));
        let mut outside = spread.clone();
        outside.ms_range = Some((2.0, 3.0));
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
                    row: Box::new(outside),
                },
                "a row timed at Some(1.0) ms with frames from 2 to 3 ms",
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
