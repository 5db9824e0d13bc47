//! A sweep shard's folder as `sshc sweep merge` and a resumed run read it
//! (`sshc_records::sweep::parse_manifest` on `shard.ron`, then `parse_records` on
//! `records.ron` against that manifest): every task of a cluster job reads these files.
//!
//! Two kinds of input. One whose first byte is 0xFF drives a generator: a `Manifest` with
//! counts at the edges (0, 1, the limits `MAX_SHARDS` and `MAX_ROWS` and one past them,
//! `usize::MAX`) and a few `Record` lines (rows and reference timings whose indices,
//! scenes and figures sit at the edges: NaN, infinities, -0, FLIP above 1), written as RON
//! and then edited as text (`mutate.rs`). Any other input is the two files as they are,
//! split at its first 0x00 byte (the seeds are folders of real runs).
//!
//! Oracle: no panic, no allocation over libFuzzer's limits; an accepted manifest has a
//! split some `--shard i/n` names, counts within the limits and the rows its split gives
//! it; accepted records are each of the shard's rows once, of the manifest's scenes, with
//! values a run writes, at most as many as the manifest's rows; gathering them gives one
//! row each.
#![no_main]

use libfuzzer_sys::arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use sshc_records::accuracy::{Accuracy, ErrorStats};
use sshc_records::sweep::*;
use std::path::Path;

#[path = "mutate.rs"]
mod mutate;

const WORDS: &[&str] = &[
    "format", "sweep", "identity", "inputs", "options", "code", "shard", "device", "reference", "pixels", "scenes",
    "configurations", "baselines", "rows", "finished", "runs", "host", "pid", "started", "resumed_at", "seconds", "Row",
    "Reference", "index", "scene", "row", "label", "config", "shadow_map", "light_scale", "ms", "peak_bytes", "fetches",
    "ops", "acc", "facing", "penumbra", "lit", "umbra", "ground", "flip", "rms", "max", "mean", "non_finite", "truth_se",
    "Penumbra", "ShadowOnGround", "\n",
];

fn count(u: &mut Unstructured) -> Result<usize> {
    Ok(match u.int_in_range(0..=11u8)? {
        0 => 0,
        1 => MAX_SHARDS,
        2 => MAX_SHARDS + 1,
        3 => MAX_ROWS,
        4 => MAX_ROWS + 1,
        5 => usize::MAX,
        6 => u.arbitrary()?,
        _ => u.int_in_range(1..=9)?,
    })
}

fn float(u: &mut Unstructured) -> Result<f64> {
    Ok(match u.int_in_range(0..=11u8)? {
        0 => f64::NAN,
        1 => f64::INFINITY,
        2 => f64::NEG_INFINITY,
        3 => -0.0,
        4 => -1.0,
        5 => 7.5,
        6 => u.arbitrary()?,
        _ => f64::from(u.int_in_range(0u8..=8)?) * 0.25,
    })
}

fn stats(u: &mut Unstructured) -> Result<ErrorStats> {
    Ok(ErrorStats {
        rms: float(u)?,
        max: float(u)?,
        mean: float(u)?,
        pixels: count(u)?,
        non_finite: count(u)?,
    })
}

fn manifest(u: &mut Unstructured) -> Result<Manifest> {
    let scenes = (0..u.int_in_range(0..=3u8)?).map(|k| format!("s{k}.ron")).collect();
    let mut m = Manifest {
        format: if u.ratio(1, 8)? { u.arbitrary()? } else { FORMAT },
        sweep: "s.ron".into(),
        identity: "0123".into(),
        inputs: vec![("s.ron".into(), "0a".into())],
        options: "samples 16".into(),
        code: "git abc".into(),
        shard: (count(u)?, count(u)?),
        device: ("gpu (driver)".into(), "gpu".into()),
        reference: "hard.ron".into(),
        pixels: if u.arbitrary()? { PixelSet::Penumbra } else { PixelSet::ShadowOnGround },
        scenes,
        configurations: count(u)?,
        baselines: count(u)?,
        rows: 0,
        finished: u.arbitrary()?,
        runs: vec![],
    };
    // the rows its split gives it, mostly: a count no split gives otherwise
    m.rows = if u.ratio(3, 4)? && m.shard.1 > 0 && m.shard.1 <= MAX_SHARDS { m.expected_rows() } else { count(u)? };
    Ok(m)
}

fn record(u: &mut Unstructured, m: &Manifest) -> Result<Record> {
    let index = match u.int_in_range(0..=3u8)? {
        0 => count(u)?,
        _ => m.shard.0.saturating_add(m.shard.1.max(1).saturating_mul(u.int_in_range(0..=4)?)),
    };
    let scene = if u.ratio(3, 4)? { u.int_in_range(0..=2)? } else { count(u)? };
    Ok(if u.ratio(1, 3)? {
        Record::Reference { scene, ms: float(u)? }
    } else {
        let acc = Accuracy {
            facing: stats(u)?,
            penumbra: stats(u)?,
            lit: stats(u)?,
            umbra: stats(u)?,
            ground: if u.arbitrary()? { Some(stats(u)?) } else { None },
            flip: if u.arbitrary()? { Some(float(u)?) } else { None },
        };
        Record::Row {
            index,
            scene,
            row: Box::new(Row {
                scene: "s0".into(),
                label: "pcf".into(),
                config: "N=3".into(),
                shadow_map: u.arbitrary()?,
                light_scale: float(u)?,
                ms: if u.arbitrary()? { Some(float(u)?) } else { None },
                peak_bytes: u.arbitrary()?,
                fetches: float(u)?,
                ops: float(u)?,
                acc,
                truth_se: float(u)?,
                reference_ms: None,
                shard: (0, 1),
                device: Default::default(),
                ms_range: if u.arbitrary()? { Some((float(u)?, float(u)?)) } else { None },
            }),
        }
    })
}

fn drive(manifest: &str, records: &[u8]) {
    let m = match parse_manifest(manifest, Path::new("shard.ron")) {
        Ok(m) => m,
        Err(e) => {
            assert!(e.starts_with("error: shard.ron"), "{e}");
            return;
        }
    };
    let (i, n) = m.shard;
    assert!(n >= 1 && n <= MAX_SHARDS && i < n, "{:?}", m.shard);
    assert!(m.configurations >= 1 && m.configurations <= MAX_ROWS && m.baselines <= MAX_ROWS && !m.scenes.is_empty());
    assert_eq!(m.rows, m.expected_rows());
    // the bytes up to the last newline (the reader cuts or refuses a half-written line)
    let whole = records.iter().rposition(|&b| b == b'\n').map_or(0, |k| k + 1);
    let Ok(done) = parse_records(&records[..whole], Path::new("records.ron"), &m) else {
        return;
    };
    assert!(done.rows.len() <= m.rows, "{} rows for a shard of {}", done.rows.len(), m.rows);
    for (index, (scene, row)) in &done.rows {
        assert!(m.holds(*index) && *scene < m.scenes.len());
        let r = Record::Row {
            index: *index,
            scene: *scene,
            row: Box::new(row.clone()),
        };
        assert!(r.impossible().is_none());
    }
    for (scene, times) in &done.reference {
        assert!(*scene < m.scenes.len() && times.iter().all(|t| t.is_finite() && *t > 0.0));
    }
    assert_eq!(done.gathered(&m).len(), done.rows.len());
}

fuzz_target!(|data: &[u8]| {
    if let [0xFF, rest @ ..] = data {
        let mut u = Unstructured::new(rest);
        let Ok(m) = manifest(&mut u) else { return };
        let pretty = u.arbitrary().unwrap_or(true);
        let text = if pretty {
            ron::ser::to_string_pretty(&m, ron::ser::PrettyConfig::default())
        } else {
            ron::to_string(&m)
        };
        let Ok(text) = text else { return };
        let mut lines = String::new();
        for _ in 0..u.int_in_range(0..=4u8).unwrap_or(0) {
            let Ok(r) = record(&mut u, &m) else { break };
            if let Ok(l) = ron::to_string(&r) {
                lines.push_str(&l);
                lines.push('\n');
            }
        }
        let which = u.int_in_range(0..=2u8).unwrap_or(0);
        let (text, lines) = match which {
            0 => (mutate::mutate(&mut u, text, WORDS), lines),
            1 => (text, mutate::mutate(&mut u, lines, WORDS)),
            _ => (text, lines),
        };
        drive(&text, lines.as_bytes());
    } else {
        let split = data.iter().position(|&b| b == 0).unwrap_or(data.len());
        if let Ok(text) = std::str::from_utf8(&data[..split]) {
            drive(text, data.get(split + 1..).unwrap_or_default());
        }
    }
});
