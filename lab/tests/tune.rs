//! `sshc tune` end to end on a real adapter (lavapipe without a GPU), at tiny sizes: the
//! chosen configuration is inside the budget and no better one it measured there is left
//! out, its `tuned.ron` loads in every command, a second run resumes, and bad input gets
//! a clear error. They never skip: with no adapter the commands fail, and so do these.

use std::path::Path;
use std::process::Output;

mod common;
use common::{root, temp_dir};

fn sshc(args: &[&str]) -> Output {
    common::sshc(env!("CARGO_BIN_EXE_sshc"), args)
}

fn ok(args: &[&str]) -> (String, String) {
    let out = sshc(args);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    );
    assert!(out.status.success(), "sshc {} failed:\n{stdout}\n{stderr}", args.join(" "));
    (stdout, stderr)
}

fn fails(args: &[&str]) -> String {
    let out = sshc(args);
    assert!(!out.status.success(), "sshc {} succeeded", args.join(" "));
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The smallest tune: a 16 x 16 image, one fidelity, the scene's own view, few samples.
const QUICK: [&str; 21] = [
    "--size",
    "16x16",
    "--candidates",
    "4",
    "--rungs",
    "1",
    "--views",
    "0",
    "--holdout",
    "0",
    "--samples",
    "16",
    "--runs",
    "2",
    "--frames",
    "1",
    "--repeats",
    "1",
    "--refine",
    "0",
    "--no-cache",
];

/// The budget of the tune below: PCF and PCSS against 2.5 times the hard shadow map.
const BUDGET: f64 = 2.5;

/// The tiny tune every check below reads: contact.ron at 32 x 32, two techniques, two
/// fidelities, one training view besides the scene's own and one held out.
fn tune_args(out: &Path) -> Vec<String> {
    [
        "tune",
        "--scene",
        "scenes/contact.ron",
        "--technique",
        "techniques/pcf.ron",
        "--technique",
        "techniques/pcss.ron",
        "--budget-vs",
        "techniques/hard.ron=2.5",
        "--size",
        "32x32",
        "--candidates",
        "5",
        "--rungs",
        "2",
        "--views",
        "1",
        "--holdout",
        "1",
        "--samples",
        "32",
        "--runs",
        "2",
        "--frames",
        "2",
        "--repeats",
        "2",
        "--refine",
        "1",
        "--no-cache",
        "-o",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain(std::iter::once(out.display().to_string()))
    .collect()
}

/// The CSV's rows as maps from column to field (no field holds a comma but the quoted
/// configuration, which holds none either).
fn rows(csv: &str) -> Vec<std::collections::HashMap<String, String>> {
    let mut lines = csv.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(str::to_string).collect();
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), head.len(), "{l}");
            head.iter()
                .cloned()
                .zip(f.iter().map(|s| s.trim_matches('"').to_string()))
                .collect()
        })
        .collect()
}

#[test]
fn tune_chooses_inside_the_budget_the_best_it_measured_and_its_file_loads_everywhere() {
    let dir = temp_dir("tune");
    let out = dir.join("out");
    let args = tune_args(&out);
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let (stdout, stderr) = ok(&refs);
    assert!(stderr.contains("tune: rung 1/2") && stderr.contains("best:"), "{stderr}");
    assert!(stdout.contains("tune: tuned:") && stdout.contains("held-out gap"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("tune.csv")).unwrap();
    let rows = rows(&csv);
    let num = |r: &std::collections::HashMap<String, String>, k: &str| -> f64 { r[k].parse().unwrap_or_else(|_| panic!("{k}: {r:?}")) };
    let chosen: Vec<_> = rows.iter().filter(|r| r["chosen"] == "true").collect();
    assert_eq!(chosen.len(), 1, "{csv}");
    let chosen = chosen[0];
    // the budget: the median of its interleaved timings against the reference
    assert!(num(chosen, "time_median") <= BUDGET, "{chosen:?}");
    assert_ne!(chosen["verdict"], "Over");
    // no configuration measured at the final fidelity inside the budget beats it
    for r in rows.iter().filter(|r| r["outcome"] == "measured" && r["rung"] == "1") {
        if r["verdict"] != "Over" && num(r, "time_median") <= BUDGET {
            assert!(num(r, "error") >= num(chosen, "error"), "{r:?} beats the chosen {chosen:?}");
        }
    }
    // the cheap rung measured more configurations than the final one
    let at = |rung: &str| rows.iter().filter(|r| r["rung"] == rung && r["outcome"] == "measured").count();
    assert!(at("0") > 0 && at("1") > 0, "{csv}");
    let md = std::fs::read_to_string(out.join("tune.md")).unwrap();
    for needle in [
        "**Chosen**",
        "lit mean",
        "umbra mean",
        "held-out",
        "Sensitivity",
        "Runners-up",
        "pareto-tuned-time.png",
    ] {
        assert!(md.contains(needle), "`{needle}` missing from tune.md:\n{md}");
    }
    for f in [
        "pareto-tuned-time.png",
        "pareto-tuned-memory.png",
        "error-chosen.png",
        "error-default.png",
    ] {
        assert!(std::fs::metadata(out.join(f)).unwrap().len() > 100, "{f}");
    }
    // tuned.ron: a technique file every command loads, with the chosen values as defaults
    // and the map size recorded
    let tuned = out.join("tuned.ron");
    let text = std::fs::read_to_string(&tuned).unwrap();
    assert!(
        text.starts_with("// Tuned by `sshc tune`") && text.contains("shadow_map:"),
        "{text}"
    );
    assert!(text.contains("// command: "), "{text}");
    let t = tuned.to_str().unwrap();
    let (check, _) = ok(&["check", t]);
    assert!(check.contains(": ok"), "{check}");
    let (cmp, _) = ok(&[
        "compare",
        t,
        "--scene",
        "scenes/contact.ron",
        "--size",
        "32x32",
        "--samples",
        "32",
        "--runs",
        "2",
        "--no-cache",
        "-o",
        dir.join("compare.png").to_str().unwrap(),
    ]);
    assert!(
        cmp.contains("error by region") && cmp.contains("signed mean error facing the light"),
        "{cmp}"
    );
    ok(&[
        "render",
        t,
        "--scene",
        "scenes/contact.ron",
        "--size",
        "32x32",
        "-o",
        dir.join("render.png").to_str().unwrap(),
    ]);
    // the same command again resumes: nothing is measured twice, and the choice is the same
    let (stdout2, stderr2) = ok(&refs);
    assert!(stderr2.contains("tune: resuming in"), "{stderr2}");
    let first = |s: &str| s.lines().find(|l| l.starts_with("tune: tuned:")).map(str::to_string);
    let strip = |l: Option<String>| l.map(|l| l.split(" held-out").next().unwrap_or_default().to_string());
    assert_eq!(strip(first(&stdout)), strip(first(&stdout2)));
    // a record cut short by a kill is dropped, the rest kept
    let records = out.join("records.ron");
    let r = std::fs::read_to_string(&records).unwrap();
    std::fs::write(&records, &r[..r.len() - 20]).unwrap();
    let (_, stderr3) = ok(&refs);
    assert!(stderr3.contains("dropped the half-written last record"), "{stderr3}");
    // a tampered record is refused, naming the line
    std::fs::write(&records, r.replacen("error:", "error:-", 1)).unwrap();
    let e = fails(&refs);
    assert!(e.contains("records.ron:1:") && e.contains("--fresh"), "{e}");
}

#[test]
fn tune_refuses_bad_input_with_clear_errors() {
    let dir = temp_dir("tune-bad");
    let out = dir.join("out");
    let o = out.to_str().unwrap();
    let quick = QUICK;
    // a budget no configuration meets: which came closest, by how much
    let mut a = vec![
        "tune",
        "--scene",
        "scenes/contact.ron",
        "--technique",
        "techniques/pcf.ron",
        "--budget-ms",
        "0.000001",
        "-o",
        o,
    ];
    a.extend(quick);
    let e = fails(&a);
    assert!(
        e.contains("no configuration meets the budget") && e.contains("the closest was pcf") && e.contains("% over"),
        "{e}"
    );
    // a technique whose `light:` list does not admit the scene's light
    let mut a = vec![
        "tune",
        "--scene",
        "scenes/contact.ron",
        "--technique",
        "techniques/linear-light.ron",
        "-o",
        o,
    ];
    a.extend(quick);
    let e = fails(&a);
    assert!(
        e.contains("linear-light.ron does not admit the Sphere light of scenes/contact.ron"),
        "{e}"
    );
    // a `tune:` axis outside the param's range, and an unknown param, at file:line:column
    let pcf = std::fs::read_to_string(root().join("techniques/pcf.ron")).unwrap();
    let at = pcf.rfind(')').unwrap();
    for (tune, want) in [
        (r#"tune: { "N": [3, 99] },"#, "`N` = 99 is outside the param's declared range"),
        (r#"tune: { "NN": [3] },"#, "unknown axis `NN`"),
    ] {
        let path = dir.join("t.ron");
        std::fs::write(&path, format!("{}    {tune}\n)", &pcf[..at])).unwrap();
        let mut a = vec![
            "tune",
            "--scene",
            "scenes/contact.ron",
            "--technique",
            path.to_str().unwrap(),
            "-o",
            o,
        ];
        a.extend(quick);
        let e = fails(&a);
        assert!(e.contains(want) && e.contains("t.ron:"), "{e}");
        // `check` reports the same, so the author sees it before tuning
        let out = sshc(&["check", path.to_str().unwrap()]);
        assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains(want));
    }
    // a technique that does not compile (an empty declared range: the search would draw
    // from it) is refused with its diagnostic, before any measurement
    let empty = dir.join("empty-range.ron");
    std::fs::write(&empty, pcf.replace("range: (0.0, 0.1)", "range: (0.1, 0.0)")).unwrap();
    let mut a = vec![
        "tune",
        "--scene",
        "scenes/contact.ron",
        "--technique",
        empty.to_str().unwrap(),
        "-o",
        o,
    ];
    a.extend(quick);
    let e = fails(&a);
    assert!(
        e.contains("has an empty range") && e.contains("empty-range.ron:") && e.contains("does not compile"),
        "{e}"
    );
    // a link planted in the output folder is not written through
    let planted = dir.join("planted");
    std::fs::create_dir_all(&planted).unwrap();
    let outside = dir.join("outside.txt");
    std::fs::write(&outside, "kept").unwrap();
    std::os::unix::fs::symlink(&outside, planted.join("tune.csv")).unwrap();
    let mut a = vec![
        "tune",
        "--scene",
        "scenes/contact.ron",
        "--technique",
        "techniques/pcf.ron",
        "-o",
        planted.to_str().unwrap(),
    ];
    a.extend(quick);
    let e = fails(&a);
    assert!(e.contains("tune.csv` exists and is not a regular file"), "{e}");
    assert_eq!(std::fs::read_to_string(&outside).unwrap(), "kept");
    // options out of range
    for bad in [
        ["--budget-ms", "NaN"],
        ["--rungs", "0"],
        ["--light-jitter", "-1"],
        ["--memory-mb", "0"],
    ] {
        let mut a = vec!["tune", "--scene", "scenes/contact.ron", "-o", o];
        a.extend(bad);
        let e = fails(&a);
        assert!(e.contains(bad[0]), "{bad:?}: {e}");
    }
}

/// `--ladder`: one configuration per budget in one run, the measurements shared (each
/// configuration measured once whatever the number of tiers), `tiers.ron` and a technique
/// file per tier, a larger budget never choosing a worse configuration.
#[test]
fn a_ladder_tunes_one_configuration_per_budget_sharing_measurements() {
    let dir = temp_dir("tune-ladder");
    let out = dir.join("out");
    let mut args = vec![
        "tune",
        "--scene",
        "scenes/contact.ron",
        "--technique",
        "techniques/pcf.ron",
        "--ladder",
        "3,1000",
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend(QUICK);
    ok(&args);
    let tiers = std::fs::read_to_string(out.join("tiers.ron")).unwrap();
    assert!(tiers.contains("name: \"low\"") && tiers.contains("name: \"medium\""), "{tiers}");
    for f in ["tier-low.ron", "tier-medium.ron"] {
        let (c, _) = ok(&["check", out.join(f).to_str().unwrap()]);
        assert!(c.contains(": ok"), "{c}");
    }
    assert_eq!(
        std::fs::read_to_string(out.join("tuned.ron")).unwrap(),
        std::fs::read_to_string(out.join("tier-medium.ron")).unwrap()
    );
    let csv = std::fs::read_to_string(out.join("tune.csv")).unwrap();
    let rows = rows(&csv);
    let measured = |tier: &str| rows.iter().filter(|r| r["tier"] == tier && r["outcome"] == "measured").count();
    assert!(measured("0") > 0 && measured("1") > 0, "{csv}");
    // shared: the records hold each configuration and fidelity once, whatever the tiers
    let records = std::fs::read_to_string(out.join("records.ron")).unwrap();
    let mut keys: Vec<&str> = records.lines().map(|l| &l[..l.find(",result:").unwrap()]).collect();
    let n = keys.len();
    keys.sort();
    keys.dedup();
    assert_eq!(keys.len(), n, "{records}");
    let error = |tier: &str| -> f64 {
        rows.iter().find(|r| r["tier"] == tier && r["chosen"] == "true").unwrap()["error"]
            .parse()
            .unwrap()
    };
    assert!(error("1") <= error("0"), "{csv}");
}

/// The tune of `tune_args`'s shape with a budget nothing reaches (errors alone decide, and
/// they are deterministic), into `out`, as shard `shard` when given.
fn shard_args(out: &Path, shard: Option<&str>) -> Vec<String> {
    let mut v: Vec<String> = [
        "tune",
        "--scene",
        "scenes/contact.ron",
        "--technique",
        "techniques/pcf.ron",
        "--technique",
        "techniques/pcss.ron",
        "--budget-vs",
        "techniques/hard.ron=1000",
        "--size",
        "16x16",
        "--candidates",
        "4",
        "--rungs",
        "2",
        "--views",
        "1",
        "--holdout",
        "0",
        "--samples",
        "16",
        "--runs",
        "2",
        "--frames",
        "1",
        "--repeats",
        "1",
        "--refine",
        "1",
        "--no-cache",
        "--wait",
        "30",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    if let Some(s) = shard {
        v.extend(["--shard".to_string(), s.to_string()]);
    }
    v.extend(["-o".to_string(), out.display().to_string()]);
    v
}

/// `--shard i/n`: two processes on one folder each measure a part of every rung, wait for
/// the other's records and choose what one process chooses; shard 0 writes the outputs.
#[test]
fn two_shards_share_each_rung_and_choose_as_one_process() {
    let dir = temp_dir("tune-shards");
    let (one, two) = (dir.join("one"), dir.join("two"));
    let args = shard_args(&one, None);
    ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let spawn = |s: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_sshc"))
            .args(shard_args(&two, Some(s)))
            .current_dir(root())
            .env("LP_NUM_THREADS", "1")
            .env(
                "XDG_RUNTIME_DIR",
                std::env::var("XDG_RUNTIME_DIR").unwrap_or_else(|_| "/tmp".into()),
            )
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("sshc starts")
    };
    // shard 1 starts once shard 0 has measured: it finds part of the first batch done, and
    // must still take its own part of it (it dealt what was left, took shard 0's, and both
    // waited out `--wait`: 138 s in a loaded suite run)
    let s0 = spawn("0/2");
    let first = two.join("records-0-of-2.ron");
    let start = std::time::Instant::now();
    while std::fs::read_to_string(&first).map_or(0, |t| t.lines().count()) == 0 && start.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let s1 = spawn("1/2");
    let (o0, o1) = (s0.wait_with_output().unwrap(), s1.wait_with_output().unwrap());
    let text = |o: &Output| format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(
        o0.status.success() && o1.status.success(),
        "shard 0:\n{}\nshard 1:\n{}",
        text(&o0),
        text(&o1)
    );
    for o in [&o0, &o1] {
        assert!(
            !text(o).contains("not measured by the other shards"),
            "a shard waited out --wait:\n{}",
            text(o)
        );
    }
    assert!(text(&o1).contains("shard 0 writes the outputs"), "{}", text(&o1));
    // each measured a part
    for r in ["records-0-of-2.ron", "records-1-of-2.ron"] {
        let n = std::fs::read_to_string(two.join(r)).unwrap().lines().count();
        assert!(n > 0, "{r} is empty");
    }
    let chosen = |out: &Path| -> String {
        let csv = std::fs::read_to_string(out.join("tune.csv")).unwrap();
        let r = rows(&csv).into_iter().find(|r| r["chosen"] == "true").unwrap();
        format!("{} {} {}", r["technique"], r["config"], r["error"])
    };
    assert_eq!(chosen(&one), chosen(&two));
    let body = |out: &Path| -> String {
        std::fs::read_to_string(out.join("tuned.ron"))
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(body(&one), body(&two));
}
