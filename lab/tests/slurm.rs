//! The job scripts of `sshc sweep --slurm` on a real Slurm cluster: a sweep of 4 shards
//! submitted with its `submit.sh`, the array and the merge waited for, and the merged
//! sweep compared with the unsharded run. Ignored in a plain `cargo test`:
//! scripts/slurm-test.sh installs Slurm and munge where missing (as root), starts a
//! single-node cluster (scripts/slurm-local.sh), runs this test and stops the cluster
//! whatever the outcome. `SSHC_SLURM_REPEATS=N` submits the sweep N times and prints the
//! median times (docs/cluster.md, "The cost of sharding"); `SSHC_SLURM_SWEEP` and
//! `SSHC_SLURM_SAMPLES` choose another sweep file and truth.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

mod common;
use common::{assert_merged_equals, root, temp_dir};

/// Runs a command to its end: its standard output and error together, or a failure.
fn run(cmd: &mut Command) -> String {
    let o = cmd.output().unwrap_or_else(|e| panic!("{cmd:?}: {e}"));
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{cmd:?} failed:\n{text}");
    text
}

fn sshc() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sshc"));
    c.env("LP_NUM_THREADS", "2").env(
        "XDG_RUNTIME_DIR",
        std::env::var("XDG_RUNTIME_DIR").unwrap_or_else(|_| "/tmp".into()),
    );
    c
}

/// The wall time a shard folder's runs recorded (one run each here).
fn seconds(dir: &Path) -> f64 {
    let m = sshc_lab::cmd::sweep::shard::read_manifest(dir)
        .unwrap_or_else(|e| panic!("{e}"))
        .unwrap_or_else(|| panic!("{}: no shard.ron", dir.display()));
    m.runs.iter().map(|r| r.seconds.expect("a finished run")).sum()
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
#[ignore = "needs a Slurm cluster: run scripts/slurm-test.sh"]
fn the_job_scripts_run_a_sweep_of_4_shards_on_slurm_and_merge_it() {
    assert!(
        Command::new("sinfo").output().is_ok_and(|o| o.status.success()),
        "no Slurm cluster answers (`sinfo` fails): run scripts/slurm-test.sh"
    );
    // what is measured: `SSHC_SLURM_SWEEP` (a sweep file, from the repository's root) and
    // `SSHC_SLURM_SAMPLES` (the truth's light samples per run) for the cost of sharding
    let sweep = root().join(std::env::var("SSHC_SLURM_SWEEP").unwrap_or_else(|_| "lab/tests/sweep.ron".into()));
    let samples = std::env::var("SSHC_SLURM_SAMPLES").unwrap_or_else(|_| "16".into());
    let repeats: usize = std::env::var("SSHC_SLURM_REPEATS").ok().and_then(|r| r.parse().ok()).unwrap_or(1);
    let (mut whole_s, mut cluster_s, mut ratio_s, mut tasks_s, mut overhead_s) = (vec![], vec![], vec![], vec![], vec![]);
    for r in 0..repeats {
        let base = temp_dir(&format!("slurm-{r}"));
        // the unsharded run, its truth cache its own
        let whole = base.join("whole");
        let t = Instant::now();
        run(sshc()
            .arg("sweep")
            .arg(&sweep)
            .arg("-o")
            .arg(&whole)
            .args(["--samples", &samples, "--runs", "2", "--cache"])
            .arg(base.join("whole-cache")));
        let whole_wall = t.elapsed().as_secs_f64();
        if r == 0 {
            // scripts that ask for a GPU: written as asked (this machine has no GPU for Slurm)
            let gpu = base.join("gpu-jobs");
            run(sshc().arg("sweep").arg(&sweep).arg("--slurm").arg("-o").arg(&gpu).args([
                "--shards",
                "4",
                "--gres",
                "gpu:1",
                "--partition",
                "local",
                "--cpus-per-task",
                "1",
                "--mem",
                "1G",
            ]));
            let script = std::fs::read_to_string(gpu.join("sweep.sbatch")).unwrap();
            for line in ["#SBATCH --gres=gpu:1\n", "#SBATCH --partition=local\n", "#SBATCH --array=0-3\n"] {
                assert!(script.contains(line), "{line} in:\n{script}");
            }
        }
        let jobs = base.join("jobs");
        run(sshc().arg("sweep").arg(&sweep).arg("--slurm").arg("-o").arg(&jobs).args([
            "--shards",
            "4",
            "--samples",
            &samples,
            "--runs",
            "2",
            "--time",
            "5:00",
        ]));
        let t = Instant::now();
        let submitted = run(Command::new(jobs.join("submit.sh")).env("LP_NUM_THREADS", "1"));
        // "array job A (4 tasks), merge job M"
        let words: Vec<&str> = submitted.split_whitespace().collect();
        let (array, merge) = match words.as_slice() {
            ["array", "job", a, "(4", "tasks),", "merge", "job", m] => (a.to_string(), m.to_string()),
            _ => panic!("submit.sh printed: {submitted}"),
        };
        let deadline = Duration::from_secs(240);
        loop {
            let queued = run(Command::new("squeue").args(["-h", "-o", "%i %T", "-j", &format!("{array},{merge}")]));
            if queued.trim().is_empty() {
                break;
            }
            if t.elapsed() > deadline {
                let logs: Vec<String> = std::fs::read_dir(jobs.join("logs"))
                    .map(|d| {
                        d.flatten()
                            .map(|e| format!("{}:\n{}", e.path().display(), std::fs::read_to_string(e.path()).unwrap_or_default()))
                            .collect()
                    })
                    .unwrap_or_default();
                panic!("still queued after {deadline:?}:\n{queued}\n{}", logs.join("\n"));
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        let cluster_wall = t.elapsed().as_secs_f64();
        // every array task and the merge completed
        let states = |id: &str| -> Vec<String> {
            run(Command::new("scontrol").args(["show", "job", id]))
                .split_whitespace()
                .filter_map(|w| w.strip_prefix("JobState=").map(str::to_string))
                .collect()
        };
        assert_eq!(states(&array), ["COMPLETED"; 4], "the array's tasks");
        assert_eq!(states(&merge), ["COMPLETED"], "the merge");
        let merge_log = std::fs::read_to_string(jobs.join("logs/merge.log")).unwrap();
        assert!(merge_log.contains("merge: 4 shards"), "{merge_log}");
        for i in 0..4 {
            let log = std::fs::read_to_string(jobs.join(format!("logs/shard-{i}.log"))).unwrap();
            assert!(
                log.contains(&format!("sweep {i}/4: ")) && log.contains(" left, "),
                "progress in the task's log: {log}"
            );
        }
        assert_merged_equals(
            &std::fs::read_to_string(whole.join("sweep.csv")).unwrap(),
            &std::fs::read_to_string(jobs.join("sweep.csv")).unwrap(),
            4,
        );
        let tasks: Vec<f64> = (0..4).map(|i| seconds(&jobs.join(format!("shard-{i}")))).collect();
        let whole_run = seconds(&whole);
        let overhead = (tasks.iter().sum::<f64>() - whole_run) / 4.0;
        println!(
            "slurm run {r}: unsharded {whole_wall:.2} s ({whole_run:.2} s in sshc); 4 shards on the local cluster {cluster_wall:.2} s from submit.sh to the merge done ({:.2}x); tasks {} s in sshc; per-task overhead {overhead:.2} s",
            cluster_wall / whole_wall,
            tasks.iter().map(|t| format!("{t:.2}")).collect::<Vec<_>>().join(", ")
        );
        whole_s.push(whole_wall);
        cluster_s.push(cluster_wall);
        ratio_s.push(cluster_wall / whole_wall);
        tasks_s.push(tasks.iter().sum::<f64>());
        overhead_s.push(overhead);
        let _ = std::fs::remove_dir_all(&base);
    }
    let (w, c) = (median(&mut whole_s), median(&mut cluster_s));
    println!(
        "slurm cost, medians of {repeats}: unsharded {w:.2} s; 4 shards on the local cluster {c:.2} s (each run's ratio, median: {:.2}x); the 4 tasks' sshc time {:.2} s in all; per-task overhead {:.2} s",
        median(&mut ratio_s),
        median(&mut tasks_s),
        median(&mut overhead_s)
    );
}

/// `sshc tune --slurm --shards 2`: the array's two tasks share each rung of the tune
/// through the output folder, task 0 writes the outputs, and the choice is the unsharded
/// run's (a budget nothing reaches: errors alone decide, and they are deterministic).
#[test]
#[ignore = "needs a Slurm cluster: run scripts/slurm-test.sh"]
fn the_job_scripts_run_a_tune_of_2_shards_on_slurm() {
    assert!(
        Command::new("sinfo").output().is_ok_and(|o| o.status.success()),
        "no Slurm cluster answers (`sinfo` fails): run scripts/slurm-test.sh"
    );
    let base = temp_dir("slurm-tune");
    let r = root();
    let file = |p: &str| r.join(p).display().to_string();
    let hard = format!("{}=1000", file("techniques/hard.ron"));
    let tune: Vec<String> = [
        "--scene",
        &file("scenes/contact.ron"),
        "--technique",
        &file("techniques/pcf.ron"),
        "--budget-vs",
        &hard,
        "--size",
        "16x16",
        "--candidates",
        "4",
        "--rungs",
        "2",
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
        "1",
        "--no-cache",
        "--wait",
        "10",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let whole = base.join("whole");
    run(sshc().arg("tune").args(&tune).arg("-o").arg(&whole));
    let jobs = base.join("jobs");
    run(sshc()
        .arg("tune")
        .args(&tune)
        .arg("--slurm")
        .arg("-o")
        .arg(&jobs)
        .args(["--shards", "2", "--time", "5:00"]));
    let t = Instant::now();
    let submitted = run(Command::new(jobs.join("submit.sh")).env("LP_NUM_THREADS", "1"));
    // "array job A (2 tasks)"
    let words: Vec<&str> = submitted.split_whitespace().collect();
    let array = match words.as_slice() {
        ["array", "job", a, "(2", "tasks)"] => a.to_string(),
        _ => panic!("submit.sh printed: {submitted}"),
    };
    let deadline = Duration::from_secs(300);
    loop {
        let queued = run(Command::new("squeue").args(["-h", "-o", "%i %T", "-j", &array]));
        if queued.trim().is_empty() {
            break;
        }
        assert!(t.elapsed() < deadline, "still queued after {deadline:?}:\n{queued}");
        std::thread::sleep(Duration::from_millis(100));
    }
    let states: Vec<String> = run(Command::new("scontrol").args(["show", "job", &array]))
        .split_whitespace()
        .filter_map(|w| w.strip_prefix("JobState=").map(str::to_string))
        .collect();
    let logs = || {
        (0..2)
            .map(|i| std::fs::read_to_string(jobs.join(format!("logs/tune-{i}.log"))).unwrap_or_default())
            .collect::<Vec<_>>()
            .join("\n----\n")
    };
    assert_eq!(states, ["COMPLETED"; 2], "the array's tasks:\n{}", logs());
    let chosen = |out: &Path| -> String {
        let csv = std::fs::read_to_string(out.join("tune.csv")).unwrap_or_else(|e| panic!("{}: {e}\n{}", out.display(), logs()));
        let head: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let col = |k: &str| head.iter().position(|h| *h == k).unwrap();
        let row: Vec<&str> = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').collect::<Vec<_>>())
            .find(|f| f[col("chosen")] == "true")
            .unwrap();
        format!("{} {} {}", row[col("technique")], row[col("config")], row[col("error")])
    };
    assert_eq!(chosen(&whole), chosen(&jobs), "{}", logs());
    assert!(logs().contains("shard 0 writes the outputs"), "{}", logs());
    // whether the tasks ran side by side (they share each rung) or one after the other (the
    // first measured the second's part past `--wait`): the logs say
    let waited = logs().contains("measuring them here");
    println!(
        "slurm tune: the tasks ran {}",
        if waited { "one after the other" } else { "side by side" }
    );
    println!(
        "slurm tune: 2 shards on the local cluster {:.2} s from submit.sh to the outputs",
        t.elapsed().as_secs_f64()
    );
    let _ = std::fs::remove_dir_all(&base);
}
