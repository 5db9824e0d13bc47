//! `sshc tune ... --slurm --shards N -o OUT`: the job scripts that run a tune as a Slurm
//! array of N shards (docs/tune.md, docs/cluster.md): `OUT/tune.sbatch`, task i running
//! the same tune with `--shard i/N -o OUT` (each measures its part of a rung and waits for
//! the others' records in OUT; task 0 writes the outputs), and `OUT/submit.sh`. Every value
//! on a command line is quoted ([`crate::cmd::sweep::slurm::quote`]); values in `#SBATCH`
//! lines are refused unless sbatch reads them as written; the paths are absolute, and OUT
//! and the truth cache belong on the filesystem every node shares.

use super::TuneArgs;
use crate::cmd::sweep::slurm::{TASK_PREAMBLE, check_options, directives, no_control_characters, quote};
use std::path::{Path, PathBuf};

/// Absolute, without `..` taken apart (the nodes resolve it as this one does).
fn absolute(p: &Path) -> Result<PathBuf, String> {
    std::path::absolute(p).map_err(|e| format!("error: {}: {e}", p.display()))
}

/// Each task's arguments after `sshc tune`, but `--shard` and `-o`: the tune as given, its
/// files made absolute, the truth cache in OUT unless one is named.
pub fn task_arguments(a: &TuneArgs, out: &Path) -> Result<Vec<String>, String> {
    let mut v: Vec<String> = Vec::new();
    let mut push = |k: &str, x: String| {
        v.push(k.to_string());
        v.push(x);
    };
    for s in &a.scenes {
        push("--scene", absolute(s)?.display().to_string());
    }
    for t in &a.techniques {
        push("--technique", absolute(t)?.display().to_string());
    }
    if let Some(ms) = a.budget_ms {
        push("--budget-ms", ms.to_string());
    }
    if let Some((r, f)) = &a.budget_vs {
        let r = if r.is_file() { absolute(r)? } else { r.clone() };
        push("--budget-vs", format!("{}={f}", r.display()));
    }
    if let Some(m) = a.memory_mb {
        push("--memory-mb", m.to_string());
    }
    push("--metric", a.metric.clone());
    for (k, x) in [
        ("--views", a.views),
        ("--holdout", a.holdout),
        ("--candidates", a.candidates),
        ("--rungs", a.rungs),
        ("--eta", a.eta),
        ("--refine", a.refine),
        ("--repeats", a.repeats),
        ("--frames", a.frames),
    ] {
        push(k, x.to_string());
    }
    push("--light-jitter", a.light_jitter.to_string());
    push("--noise", a.noise.to_string());
    push("--wait", a.wait.to_string());
    if let Some((w, h)) = a.size {
        push("--size", format!("{w}x{h}"));
    }
    if !a.ladder.is_empty() {
        push("--ladder", a.ladder.iter().map(f64::to_string).collect::<Vec<_>>().join(","));
    }
    for (k, x) in &a.axes {
        push("--axis", format!("{k}={x}"));
    }
    let t = &a.truth;
    push("--samples", t.samples.to_string());
    push("--runs", t.runs.to_string());
    if let Some(se) = t.target_se {
        push("--target-se", se.to_string());
        push("--max-samples", t.max_samples.to_string());
    }
    push("--seed", t.seed.to_string());
    if t.no_cache {
        v.push("--no-cache".into());
    } else {
        let cache = if t.cache == Path::new(crate::truth::TruthCache::DEFAULT_DIR) {
            out.join("truth-cache")
        } else {
            absolute(&t.cache)?
        };
        let mut push = |k: &str, x: String| {
            v.push(k.to_string());
            v.push(x);
        };
        push("--cache", cache.display().to_string());
        push("--claim-stale", t.claim_stale.to_string());
    }
    if a.grid {
        v.push("--grid".into());
    }
    Ok(v)
}

/// `tune.sbatch` and `submit.sh` for `shards` tasks.
pub fn scripts(a: &TuneArgs, sshc: &Path, out: &Path, shards: usize) -> Result<[(&'static str, String); 2], String> {
    let s = &a.slurm;
    check_options(s, out)?;
    let out_text = out.display().to_string();
    let args = task_arguments(a, out)?;
    for x in args.iter().chain(std::iter::once(&sshc.display().to_string())) {
        no_control_characters("a value of the tune", x)?;
    }
    let args: Vec<String> = args.iter().map(|x| quote(x)).collect();
    let mut job = format!(
        "#!/bin/bash\n\
         # A tune in {shards} shards: array task i runs `sshc tune ... --shard i/{shards}` in {out_text};\n\
         # each measures its part of a rung and waits for the others' records there; task 0\n\
         # writes tuned.ron, tune.md and tune.csv. Written by `sshc tune --slurm`; submitted by\n\
         # submit.sh. A task that stopped resumes from its records when run again.\n\
         #SBATCH --job-name=sshc-tune\n\
         #SBATCH --array=0-{last}\n\
         #SBATCH --output={out_text}/logs/tune-%a.log\n",
        last = shards - 1,
    );
    directives(&mut job, s, true);
    job.push_str(TASK_PREAMBLE);
    job.push_str(&format!(
        "exec {sshc} tune {args} --shard \"$i/{shards}\" -o {out}\n",
        sshc = quote(&sshc.display().to_string()),
        args = args.join(" "),
        out = quote(&out_text),
    ));
    let submit = format!(
        "#!/bin/sh\n\
         # Submits the tune's array of {shards} tasks and prints its job id; task 0's log\n\
         # ({out_text}/logs/tune-0.log) names what it wrote.\n\
         set -eu\n\
         cd {out}\n\
         array=$(sbatch --parsable tune.sbatch)\n\
         echo \"array job ${{array%%;*}} ({shards} tasks)\"\n",
        out = quote(&out_text),
    );
    Ok([("tune.sbatch", job), ("submit.sh", submit)])
}

/// `--slurm`: the scripts written into `-o` (after the tune's inputs were checked as a run
/// checks them, so that a mistake shows before anything is submitted).
pub fn write(a: &TuneArgs) -> Result<(), String> {
    let n = a
        .slurm
        .shards
        .ok_or("error: --slurm needs --shards N, the number of array tasks (one shard each)")?;
    if n == 0 || n > 1000 {
        return Err(format!("error: --shards {n}: give 1 to 1000 shards"));
    }
    let out = absolute(&a.out)?;
    let sshc = match &a.slurm.sshc {
        Some(p) => absolute(p)?,
        None => std::env::current_exe().map_err(|e| format!("error: cannot find this executable: {e}"))?,
    };
    // the truth's budget on each scene, as every task will check it
    for s in &a.scenes {
        let scene = crate::session::load_scene(s, a.size, None)?;
        let (w, h) = scene.camera_size();
        a.truth.check(u64::from(w) * u64::from(h))?;
    }
    let scripts = scripts(a, &sshc, &out, n)?;
    let logs = out.join("logs");
    std::fs::create_dir_all(&logs).map_err(|e| format!("error: {}: {e}", logs.display()))?;
    for (name, text) in scripts {
        let p = out.join(name);
        super::report::write_new(&p, &text)?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt as _;
            std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).map_err(|e| format!("error: {}: {e}", p.display()))?;
        }
        println!("wrote {}", p.display());
    }
    println!("a tune in {n} shards; submit with {}/submit.sh", out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser as _;

    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        a: TuneArgs,
    }

    #[test]
    fn the_scripts_run_every_shard_of_the_same_tune_with_every_value_quoted() {
        let cli = Cli::try_parse_from([
            "tune",
            "--scene",
            "/s/a b.ron",
            "--technique",
            "/t/pcss.ron",
            "--axis",
            "N=[3, 6]",
            "--budget-ms",
            "2",
            "--slurm",
            "--shards",
            "3",
            "--partition",
            "gpu",
            "--gres",
            "gpu:1",
            "-o",
            "/shared/out",
        ])
        .unwrap();
        let [(_, job), (_, submit)] = scripts(&cli.a, Path::new("/opt/sshc"), Path::new("/shared/out"), 3).unwrap();
        for line in [
            "#SBATCH --array=0-2\n",
            "#SBATCH --output=/shared/out/logs/tune-%a.log\n",
            "#SBATCH --partition=gpu\n",
            "#SBATCH --gres=gpu:1\n",
        ] {
            assert!(job.contains(line), "{line} in\n{job}");
        }
        let exec = job.lines().find(|l| l.starts_with("exec ")).unwrap();
        assert!(
            exec.starts_with("exec /opt/sshc tune --scene '/s/a b.ron' --technique /t/pcss.ron --budget-ms 2 "),
            "{exec}"
        );
        assert!(
            exec.contains("--axis 'N=[3, 6]'") && exec.ends_with("--shard \"$i/3\" -o /shared/out"),
            "{exec}"
        );
        assert!(exec.contains("--cache /shared/out/truth-cache"), "{exec}");
        assert!(submit.contains("array=$(sbatch --parsable tune.sbatch)"), "{submit}");
        // a path with a newline cannot end the #SBATCH block: refused
        assert!(
            scripts(&cli.a, Path::new("/opt/sshc"), Path::new("/shared/o\nut"), 3)
                .unwrap_err()
                .contains("#SBATCH")
        );
        // a newline in a scene's path: refused, not carried to every node
        let evil = Cli::try_parse_from(["tune", "--scene", "/s/a\nrm -rf ~", "--slurm", "--shards", "2"]).unwrap();
        assert!(
            scripts(&evil.a, Path::new("/opt/sshc"), Path::new("/o"), 2)
                .unwrap_err()
                .contains("control character")
        );
        // a value an #SBATCH line cannot hold
        let bad = Cli::try_parse_from(["tune", "--scene", "a.ron", "--slurm", "--shards", "2", "--time", "1:00 #x"]).unwrap();
        assert!(
            scripts(&bad.a, Path::new("/opt/sshc"), Path::new("/o"), 2)
                .unwrap_err()
                .contains("`--time 1:00 #x`")
        );
    }
}
