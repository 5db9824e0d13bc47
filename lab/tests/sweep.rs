//! `sshc sweep` end to end on a sweep of under 20 configurations (tests/sweep.ron): the
//! CSV and Markdown hold one row per configuration with finite figures, the shards of a
//! split sweep together hold exactly the configurations of the whole, and the Pareto
//! charts are written as SVG and PNG. Runs on the GPU (lavapipe without one).

use std::path::{Path, PathBuf};
use std::process::Command;

fn run(out: &Path, extra: &[&str]) -> String {
    let sweep = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/sweep.ron");
    let o = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .arg("sweep")
        .arg(&sweep)
        .arg("-o")
        .arg(out)
        .args(["--samples", "16", "--runs", "2", "--cache"])
        .arg(out.join("cache"))
        .args(extra)
        .env("LP_NUM_THREADS", "2")
        .output()
        .expect("sshc runs");
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "sshc sweep failed:\n{text}");
    std::fs::read_to_string(out.join("sweep.csv")).expect("sweep.csv written")
}

fn rows(csv: &str) -> Vec<Vec<String>> {
    // quoted fields hold no commas except the device name, which is quoted
    csv.lines()
        .skip(1)
        .map(|l| {
            let mut fields = Vec::new();
            let mut cur = String::new();
            let mut quoted = false;
            for ch in l.chars() {
                match ch {
                    '"' => quoted = !quoted,
                    ',' if !quoted => fields.push(std::mem::take(&mut cur)),
                    c => cur.push(c),
                }
            }
            fields.push(cur);
            fields
        })
        .collect()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sshc-sweep-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn sweep_writes_a_row_per_configuration_and_the_charts() {
    let out = tmp("whole");
    let csv = run(&out, &[]);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name}"));
    let rows = rows(&csv);
    // 2 + 2 + 2 GPU configurations and one CPU baseline
    assert_eq!(rows.len(), 7, "{csv}");
    for r in &rows {
        assert_eq!(r.len(), header.len(), "{r:?}");
        for c in ["rms_facing", "max_facing", "rms_penumbra"] {
            let v: f64 = r[col(c)].parse().unwrap();
            assert!(v.is_finite() && (0.0..=255.0).contains(&v), "{c} = {v} in {r:?}");
        }
        if r[col("technique")] != "16 samples (CPU)" {
            let ratio: f64 = r[col("time_ratio")].parse().unwrap();
            assert!(ratio.is_finite() && ratio > 0.0, "time ratio {ratio}");
            assert!(!r[col("device")].is_empty(), "every row names the device");
        }
    }
    // more shadow-map texels, less error for the hard shadow map (25 vs 14 at 256^2 pixels;
    // on 40^2 pixels the same trend)
    let hard = |n: &str| -> f64 {
        rows.iter()
            .find(|r| r[col("technique")] == "hard" && r[col("shadow_map")] == n)
            .map(|r| r[col("rms_facing")].parse().unwrap())
            .unwrap()
    };
    assert!(hard("128") < hard("32"), "hard: {} at 128 vs {} at 32", hard("128"), hard("32"));
    for f in [
        "sweep.md",
        "pareto-triangle-time.svg",
        "pareto-triangle-time.png",
        "pareto-triangle-memory.svg",
        "pareto-triangle-memory.png",
    ] {
        let bytes = std::fs::read(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(bytes.len() > 100, "{f} is nearly empty");
    }
    let png = std::fs::read(out.join("pareto-triangle-time.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let svg = std::fs::read_to_string(out.join("pareto-triangle-time.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("Pareto front"));

    // two shards hold exactly the configurations of the whole
    let (a, b) = (tmp("shard0"), tmp("shard1"));
    let (s0, s1) = (run(&a, &["--shard", "0/2"]), run(&b, &["--shard", "1/2"]));
    let key = |r: &Vec<String>| format!("{}|{}|{}", r[col("scene")], r[col("technique")], r[col("config")]);
    let mut whole: Vec<String> = rows.iter().map(key).collect();
    let mut split: Vec<String> = self::rows(&s0).iter().chain(self::rows(&s1).iter()).map(key).collect();
    whole.sort();
    split.sort();
    assert_eq!(whole, split);
    // every shard timed the reference itself
    for r in self::rows(&s0).iter().chain(self::rows(&s1).iter()) {
        assert!(r[col("reference_ms")].parse::<f64>().is_ok_and(|t| t > 0.0), "{r:?}");
    }
    for d in [out, a, b] {
        let _ = std::fs::remove_dir_all(d);
    }
}
