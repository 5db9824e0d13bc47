//! Shards, merging and resuming (docs/cluster.md): shards merged equal the unsharded sweep,
//! a killed shard resumes, and every bad merge and tampered shard is refused.

use super::{run, sshc, sweep_file, tmp};
use crate::common::{assert_merged_equals, csv_rows as rows};
use std::path::{Path, PathBuf};
use std::process::Command;

/// `sshc sweep tests/sweep.ron --shard SHARD -o DIR` with a small truth cached in `cache`.
fn shard_of_sweep(shard: &str, dir: &Path, cache: &Path) -> (bool, String) {
    sshc(&[
        "sweep".as_ref(),
        sweep_file("sweep.ron").as_os_str(),
        "-o".as_ref(),
        dir.as_os_str(),
        "--shard".as_ref(),
        shard.as_ref(),
        "--samples".as_ref(),
        "16".as_ref(),
        "--runs".as_ref(),
        "2".as_ref(),
        "--cache".as_ref(),
        cache.as_os_str(),
    ])
}

/// `sshc sweep merge DIRS -o OUT`.
fn merge(dirs: &[&Path], out: &Path) -> (bool, String) {
    let mut args: Vec<&std::ffi::OsStr> = vec!["sweep".as_ref(), "merge".as_ref()];
    args.extend(dirs.iter().map(|d| d.as_os_str()));
    args.extend(["-o".as_ref(), out.as_os_str()]);
    sshc(&args)
}

/// A sweep run unsharded and as 3 shards merged (`sshc sweep merge`): every accuracy,
/// memory and count column equal, the time ratios present, the Markdown table and the
/// charts written. Each shard prints plain progress lines (its stderr is not a terminal),
/// and a second run of a finished shard measures nothing and says so.
#[test]
fn three_shards_merged_equal_the_unsharded_sweep() {
    let whole = tmp("merge-whole");
    let whole_csv = run(&whole, &[]);
    let base = tmp("merge-shards");
    let cache = base.join("cache");
    let dirs: Vec<PathBuf> = (0..3).map(|i| base.join(format!("shard-{i}"))).collect();
    for (i, d) in dirs.iter().enumerate() {
        let (ok, text) = shard_of_sweep(&format!("{i}/3"), d, &cache);
        assert!(ok, "{text}");
        // configurations i, i + 3 (and shard 0's CPU baseline): the last line says none is left
        let rows = if i == 0 { 3 } else { 2 };
        assert!(
            text.contains(&format!("sweep {i}/3: 1 of {rows} done, {} left", rows - 1))
                && text.contains(&format!("sweep {i}/3: {rows} of {rows} done, 0 left"))
                && text.contains("to go"),
            "progress lines: {text}"
        );
    }
    let out = base.join("merged");
    let refs: Vec<&Path> = dirs.iter().map(|d| d.as_path()).collect();
    // in any order
    let (ok, text) = merge(&[refs[2], refs[0], refs[1]], &out);
    assert!(ok, "{text}");
    assert!(text.contains("merge: 3 shards") && text.contains("merge: one device"), "{text}");
    for i in 0..3 {
        assert!(text.contains(&format!("  shard {i}/3: ")), "a summary line per shard: {text}");
    }
    let merged = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert_merged_equals(&whole_csv, &merged, 3);
    let (md_whole, md_merged) = (
        std::fs::read_to_string(whole.join("sweep.md")).unwrap(),
        std::fs::read_to_string(out.join("sweep.md")).unwrap(),
    );
    assert_eq!(md_whole.lines().count(), md_merged.lines().count(), "{md_merged}");
    assert!(md_merged.starts_with("Device: "), "{md_merged}");
    for f in ["pareto-triangle-time.svg", "pareto-triangle-time.png", "pareto-triangle-memory.png"] {
        assert!(std::fs::metadata(out.join(f)).is_ok_and(|m| m.len() > 100), "{f}");
    }
    // run again: nothing measured, the same rows written
    let (ok, text) = shard_of_sweep("1/3", &dirs[1], &cache);
    assert!(ok, "{text}");
    assert!(
        text.contains("2 of its 2 rows done by an earlier run, skipped; 0 left") && text.contains("nothing left to measure"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&whole);
    let _ = std::fs::remove_dir_all(&base);
}

/// A shard stopped by a signal (SIGKILL) between two configurations keeps the rows it
/// finished: the merge refuses it as unfinished, the same command run again says what it
/// skips and measures only the rest, and the merged sweep still equals the unsharded one.
/// (tests/sweep-slow.ron is tests/sweep.ron with more timed frames: the same figures.)
#[test]
fn a_killed_shard_resumes_and_the_merge_still_equals_the_unsharded_sweep() {
    let whole = tmp("kill-whole");
    let whole_csv = run(&whole, &[]);
    let base = tmp("kill-shards");
    let cache = base.join("cache");
    let slow = sweep_file("sweep-slow.ron");
    let dirs: Vec<PathBuf> = (0..3).map(|i| base.join(format!("shard-{i}"))).collect();
    let args = |i: usize| -> Vec<std::ffi::OsString> {
        let mut a: Vec<std::ffi::OsString> = vec!["sweep".into(), slow.clone().into(), "-o".into(), dirs[i].clone().into()];
        a.extend(["--shard".into(), format!("{i}/3").into(), "--samples".into(), "16".into()]);
        a.extend(["--runs".into(), "2".into(), "--cache".into(), cache.clone().into()]);
        a
    };
    // shard 1: stopped once its first configuration is recorded, inside the second (CSM)
    let mut child = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .args(args(1))
        .env("LP_NUM_THREADS", "2")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("sshc starts");
    let records = dirs[1].join("records.ron");
    let start = std::time::Instant::now();
    let rows_recorded = || {
        std::fs::read_to_string(&records)
            .map(|t| t.lines().filter(|l| l.starts_with("Row(")).count())
            .unwrap_or(0)
    };
    while rows_recorded() < 1 {
        assert!(child.try_wait().unwrap().is_none(), "the shard ended before it was stopped");
        assert!(start.elapsed().as_secs() < 120, "no row recorded in 120 s");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let kept = rows_recorded();
    // shard 1 has configurations 1 (the hard shadow map) and 4 (CSM, 100 frames of some
    // milliseconds each)
    assert_eq!(kept, 1, "rows recorded when stopped");
    for i in [0, 2] {
        let (ok, text) = sshc(&args(i).iter().map(|a| a.as_os_str()).collect::<Vec<_>>());
        assert!(ok, "{text}");
    }
    let refs: Vec<&Path> = dirs.iter().map(|d| d.as_path()).collect();
    let out = base.join("merged");
    let (ok, text) = merge(&refs, &out);
    assert!(!ok, "an unfinished shard is merged: {text}");
    assert!(
        text.contains("shard-1 (shard 1/3) is unfinished: 1 of its 2 rows done; run its command again to resume it"),
        "{text}"
    );
    let (ok, text) = sshc(&args(1).iter().map(|a| a.as_os_str()).collect::<Vec<_>>());
    assert!(ok, "{text}");
    assert!(
        text.contains(&format!(
            "resuming shard 1/3 in {}: 1 of its 2 rows done by an earlier run, skipped; 1 left",
            dirs[1].display()
        )) && text.contains("sweep 1/3: 2 of 2 done, 0 left"),
        "{text}"
    );
    let manifest = std::fs::read_to_string(dirs[1].join("shard.ron")).unwrap();
    assert!(
        manifest.contains("finished: true") && manifest.contains("seconds: None"),
        "two runs, the first stopped: {manifest}"
    );
    let (ok, text) = merge(&refs, &out);
    assert!(ok, "{text}");
    assert!(text.contains("stopped on "), "the summary names the stopped run: {text}");
    assert_merged_equals(&whole_csv, &std::fs::read_to_string(out.join("sweep.csv")).unwrap(), 3);
    let _ = std::fs::remove_dir_all(&whole);
    let _ = std::fs::remove_dir_all(&base);
}

/// Copies the files of folder `from` into `to` (created), applying `edit` to `shard.ron`.
fn copy_shard(from: &Path, to: &Path, edit: impl Fn(String) -> String) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        if p.is_file() {
            std::fs::copy(&p, to.join(p.file_name().unwrap())).unwrap();
        }
    }
    let m = std::fs::read_to_string(to.join("shard.ron")).unwrap();
    std::fs::write(to.join("shard.ron"), edit(m)).unwrap();
}

/// Every refusal of `sshc sweep merge`, each naming the shard and the reason, with
/// nothing written: a folder that is no shard, a missing shard, a shard given twice,
/// shards of different sweeps (a technique file changed) and of different code, an
/// unfinished shard. Shards of different devices merge, and the outputs say so. Also: a
/// sweep file named `merge` runs as `./merge`; `--slurm` refuses what it cannot write.
#[test]
fn bad_merges_are_refused_naming_the_shard_and_the_reason() {
    let base = tmp("refusals");
    // a sweep in a folder of its own, its technique and scene beside it
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let sweep_in = |dir: &Path, comment: &str| -> PathBuf {
        std::fs::create_dir_all(dir).unwrap();
        let hard = std::fs::read_to_string(root.join("techniques/hard.ron")).unwrap();
        std::fs::write(dir.join("hard.ron"), format!("{comment}{hard}")).unwrap();
        std::fs::copy(root.join("scenes/triangle.ron"), dir.join("triangle.ron")).unwrap();
        let s = dir.join("s.ron");
        std::fs::write(
            &s,
            r#"(scenes: ["triangle.ron"], camera: Some((16, 16)), frames: 1, reference: "hard.ron", techniques: [(file: "hard.ron", axes: { "shadow_map": [16, 32] })])"#,
        )
        .unwrap();
        s
    };
    let a = sweep_in(&base.join("a"), "");
    let b = sweep_in(&base.join("b"), "// changed\n");
    let shard = |s: &Path, i: usize, dir: &Path| {
        let shard = format!("{i}/2");
        let (ok, text) = sshc(&[
            "sweep".as_ref(),
            s.as_os_str(),
            "-o".as_ref(),
            dir.as_os_str(),
            "--shard".as_ref(),
            shard.as_ref(),
            "--samples".as_ref(),
            "4".as_ref(),
            "--runs".as_ref(),
            "2".as_ref(),
            "--cache".as_ref(),
            base.join("cache").as_os_str(),
        ]);
        assert!(ok, "{text}");
    };
    let (s0, s1, other) = (base.join("s0"), base.join("s1"), base.join("other1"));
    shard(&a, 0, &s0);
    shard(&a, 1, &s1);
    shard(&b, 1, &other);
    let out = base.join("out");
    let refused = |dirs: &[&Path], want: &[&str]| {
        let (ok, text) = merge(dirs, &out);
        assert!(!ok, "merged: {text}");
        for w in want {
            assert!(text.contains(w), "`{w}` not in:\n{text}");
        }
        assert!(text.contains("error: nothing merged") && !out.join("sweep.csv").exists(), "{text}");
    };
    let empty = base.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    refused(
        &[&s0, &empty],
        &[&format!("{} is not a shard folder: it has no shard.ron", empty.display())],
    );
    refused(&[&s0], &["shard 1/2 is missing: no folder given holds it"]);
    let twice = base.join("s0-again");
    copy_shard(&s0, &twice, |m| m);
    refused(
        &[&s0, &s1, &twice],
        &[&format!(
            "{} and {} all hold shard 0/2: give each shard once",
            s0.display(),
            twice.display()
        )],
    );
    refused(
        &[&s0, &other],
        &[
            &format!("{} is a shard of another sweep than {}", other.display(), s0.display()),
            "`hard.ron` differs",
        ],
    );
    let code = base.join("code1");
    copy_shard(&s1, &code, |m| {
        let line = m.lines().find(|l| l.trim_start().starts_with("code:")).unwrap().to_string();
        m.replace(&line, "    code: \"git 0123\",")
    });
    refused(
        &[&s0, &code],
        &[&format!(
            "{} was run by other code than {} (git 0123 against ",
            code.display(),
            s0.display()
        )],
    );
    let unfinished = base.join("unfinished1");
    copy_shard(&s1, &unfinished, |m| m.replace("finished: true", "finished: false"));
    std::fs::write(unfinished.join("records.ron"), "").unwrap();
    refused(
        &[&s0, &unfinished],
        &[&format!("{} (shard 1/2) is unfinished: 0 of its 1 rows done", unfinished.display())],
    );
    // another device: merged, and said so
    let device = base.join("device1");
    copy_shard(&s1, &device, |m| {
        let line = m.lines().find(|l| l.trim_start().starts_with("device:")).unwrap().to_string();
        m.replace(&line, "    device: (\"Another GPU (driver 1)\", \"Another GPU\"),")
    });
    let (ok, text) = merge(&[&s0, &device], &out);
    assert!(ok, "{text}");
    assert!(
        text.contains("merge: 2 devices; each row's time ratio is against the reference timed on its own shard's device")
            && text.contains("Another GPU (driver 1) (shards 1/2)"),
        "{text}"
    );
    let md = std::fs::read_to_string(out.join("sweep.md")).unwrap();
    assert!(
        md.starts_with("Devices: ") && md.contains("Time ratios are per device") && md.contains("| Another GPU |"),
        "{md}"
    );
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert!(csv.contains("1/2,\"Another GPU (driver 1)\""), "{csv}");

    // `merge` as a sweep file's name: `./merge`, from its folder
    std::fs::copy(&a, base.join("a/merge")).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .current_dir(base.join("a"))
        .args([
            "sweep",
            "./merge",
            "-o",
            "named-merge",
            "--samples",
            "4",
            "--runs",
            "2",
            "--no-cache",
        ])
        .env("LP_NUM_THREADS", "2")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        rows(&std::fs::read_to_string(base.join("a/named-merge/sweep.csv")).unwrap()).len(),
        2
    );
    let (ok, text) = sshc(&["sweep".as_ref(), "merge".as_ref()]);
    assert!(!ok && text.contains("Usage: sshc sweep merge"), "{text}");

    // --slurm: the scripts are written only for what an #SBATCH line holds
    let jobs = base.join("jobs");
    let slurm = |extra: &[&str]| {
        let mut args: Vec<&std::ffi::OsStr> = vec!["sweep".as_ref(), a.as_os_str(), "-o".as_ref(), jobs.as_os_str(), "--slurm".as_ref()];
        args.extend(extra.iter().map(std::ffi::OsStr::new));
        sshc(&args)
    };
    let (ok, text) = slurm(&[]);
    assert!(!ok && text.contains("--slurm needs --shards N"), "{text}");
    let (ok, text) = slurm(&["--shards", "3"]);
    assert!(!ok && text.contains("--shards 3: the sweep has 2 configurations"), "{text}");
    let (ok, text) = slurm(&["--shards", "2", "--partition", "a b"]);
    assert!(!ok && text.contains("`--partition a b`: an #SBATCH line cannot hold it"), "{text}");
    let (ok, text) = slurm(&["--shards", "2", "--gres", "gpu:1", "--time", "10:00"]);
    assert!(ok, "{text}");
    let script = std::fs::read_to_string(jobs.join("sweep.sbatch")).unwrap();
    assert!(
        script.contains("#SBATCH --array=0-1\n") && script.contains("#SBATCH --gres=gpu:1\n") && script.contains("#SBATCH --time=10:00\n"),
        "{script}"
    );
    // the truth cache on the shared folder
    assert!(
        script.contains(&format!("--cache {}", jobs.join("truth-cache").display())),
        "{script}"
    );
    let _ = std::fs::remove_dir_all(&base);
}

/// Issue 48, items 2 and 10: a shard folder is read as hostile. A shard count or a
/// configuration count no split has (2^64-1 panicked allocating, 2^40 aborted, a sum of
/// counts wrapped to 0), an emptied scene list, a sweep of no configuration, and records
/// naming a scene or a row the sweep does not have are refused, naming the file and the
/// line, by the merge and by a resumed run, with nothing written.
#[test]
fn tampered_shard_counts_and_records_are_refused() {
    let base = tmp("tampered");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    std::fs::create_dir_all(&base).unwrap();
    std::fs::copy(root.join("techniques/hard.ron"), base.join("hard.ron")).unwrap();
    std::fs::copy(root.join("scenes/triangle.ron"), base.join("triangle.ron")).unwrap();
    let s = base.join("s.ron");
    std::fs::write(
        &s,
        r#"(scenes: ["triangle.ron"], camera: Some((16, 16)), frames: 1, reference: "hard.ron", techniques: [(file: "hard.ron", axes: { "shadow_map": [16, 32] })])"#,
    )
    .unwrap();
    let run = |i: usize, dir: &Path, fresh: bool| {
        let shard = format!("{i}/2");
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "sweep".as_ref(),
            s.as_os_str(),
            "-o".as_ref(),
            dir.as_os_str(),
            "--shard".as_ref(),
            shard.as_ref(),
            "--samples".as_ref(),
            "4".as_ref(),
            "--runs".as_ref(),
            "2".as_ref(),
            "--no-cache".as_ref(),
        ];
        if fresh {
            args.push("--fresh".as_ref());
        }
        sshc(&args)
    };
    let (s0, s1) = (base.join("s0"), base.join("s1"));
    for (i, d) in [(0, &s0), (1, &s1)] {
        let (ok, text) = run(i, d, false);
        assert!(ok, "{text}");
    }
    let out = base.join("out");
    let field = |m: &str, key: &str, value: &str| -> String {
        let line = m.lines().find(|l| l.trim_start().starts_with(key)).unwrap().to_string();
        m.replace(&line, &format!("    {key} {value},"))
    };
    let count = |k: &str| base.join(format!("tampered-{k}"));
    type Edit = Box<dyn Fn(String) -> String>;
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "max",
            Box::new(move |m| field(&m, "shard:", "(1, 18446744073709551615)")),
            "shard.ron: a split into 18446744073709551615 shards",
        ),
        (
            "huge",
            Box::new(move |m| field(&m, "shard:", "(1, 1099511627776)")),
            "shard.ron: a split into 1099511627776 shards",
        ),
        (
            "configs",
            Box::new(move |m| field(&m, "configurations:", "18446744073709551615")),
            "shard.ron: 18446744073709551615 configurations",
        ),
        (
            "none",
            Box::new(move |m| field(&m, "configurations:", "0")),
            "shard.ron: a sweep of no configuration",
        ),
        (
            "rows",
            Box::new(move |m| field(&m, "rows:", "5")),
            "shard.ron: 5 rows for shard 1/2",
        ),
        (
            "scenes",
            Box::new(|m: String| {
                let start = m.find("scenes: [").unwrap();
                let end = start + m[start..].find(']').unwrap();
                format!("{}scenes: []{}", &m[..start], &m[end + 1..])
            }),
            "shard.ron: no scene",
        ),
    ];
    for (k, edit, want) in &cases {
        let d = count(k);
        copy_shard(&s1, &d, edit);
        // a split's count alone decides what the merge expects: given alone, the folder
        // of a tampered count is all the merge sees
        let dirs: Vec<&Path> = if *k == "max" || *k == "huge" { vec![&d] } else { vec![&s0, &d] };
        let (ok, text) = merge(&dirs, &out);
        assert!(
            !ok && text.contains(want) && text.contains("error: nothing merged"),
            "{k}: `{want}` not in:\n{text}"
        );
        assert!(!out.join("sweep.csv").exists(), "{k}");
        // a resumed run refuses the folder too, and --fresh starts it afresh
        let (ok, text) = run(1, &d, false);
        assert!(!ok && text.contains(want), "{k}: {text}");
    }
    // records naming a scene or a configuration the sweep has not
    let records = std::fs::read_to_string(s1.join("records.ron")).unwrap();
    let row = records.lines().position(|l| l.starts_with("Row(")).unwrap() + 1;
    for (k, from, to, want) in [
        (
            "scene99",
            "scene:0,",
            "scene:99,",
            format!("records.ron:{row}: scene entry 99 of a sweep of 1 scene"),
        ),
        (
            "row99",
            "Row(index:1,",
            "Row(index:99,",
            format!("records.ron:{row}: row 99 is not shard 1/2's (the sweep has 2 configurations and 0 baselines)"),
        ),
    ] {
        let d = count(k);
        copy_shard(&s1, &d, |m| m);
        let edited: Vec<String> = records
            .lines()
            .map(|l| {
                if l.starts_with("Row(") {
                    l.replacen(from, to, 1)
                } else {
                    l.to_string()
                }
            })
            .collect();
        std::fs::write(d.join("records.ron"), edited.join("\n") + "\n").unwrap();
        let (ok, text) = merge(&[&s0, &d], &out);
        assert!(!ok && text.contains(&want), "{k}: `{want}` not in:\n{text}");
        let (ok, text) = run(1, &d, false);
        assert!(!ok && text.contains(&want), "{k}: {text}");
        let (ok, text) = run(1, &d, true);
        assert!(ok, "{k}: --fresh: {text}");
    }
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&base);
}
