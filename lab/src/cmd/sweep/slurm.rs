//! `sshc sweep S.ron --slurm --shards N -o OUT`: job scripts for a Slurm cluster, plain
//! for a user to read and adapt (docs/cluster.md):
//!
//! - `OUT/sweep.sbatch`, an array job of N tasks, task i running shard i/N into
//!   `OUT/shard-i` (its log `OUT/logs/shard-i.log`);
//! - `OUT/merge.sbatch`, `sshc sweep merge` of the N folders into `OUT`;
//! - `OUT/submit.sh`, which submits the array (`sbatch --parsable`), then the merge with
//!   `--dependency=afterok:ARRAY --kill-on-invalid-dep=yes`: a task that fails cancels the
//!   merge instead of leaving it pending for ever.
//!
//! Paths in the scripts are absolute, so that they run from any folder; OUT and the truth
//! cache belong on the filesystem every node shares.

use std::path::{Path, PathBuf};

/// The command line's Slurm options.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct SlurmArgs {
    /// Write Slurm job scripts into the output folder instead of running the sweep:
    /// `sweep.sbatch` (an array of `--shards` tasks), `merge.sbatch` and `submit.sh`,
    /// which submits both, the merge after the array (docs/cluster.md).
    #[arg(long, conflicts_with_all = ["shard", "fresh"])]
    pub slurm: bool,
    /// With --slurm: how many shards, one array task each.
    #[arg(long, value_name = "N", requires = "slurm", conflicts_with = "shard")]
    pub shards: Option<usize>,
    /// With --slurm: the partition (`#SBATCH --partition`).
    #[arg(long, value_name = "NAME", requires = "slurm")]
    pub partition: Option<String>,
    /// With --slurm: generic resources per task, `gpu:1` for one GPU (`#SBATCH --gres`).
    #[arg(long, value_name = "SPEC", requires = "slurm")]
    pub gres: Option<String>,
    /// With --slurm: each task's time limit, as sbatch reads it (`4:00:00`).
    #[arg(long, value_name = "LIMIT", requires = "slurm")]
    pub time: Option<String>,
    /// With --slurm: CPUs per task; the truth's ray casting uses them all.
    #[arg(long, value_name = "N", requires = "slurm")]
    pub cpus_per_task: Option<u32>,
    /// With --slurm: memory per task, as sbatch reads it (`16G`).
    #[arg(long, value_name = "SIZE", requires = "slurm")]
    pub mem: Option<String>,
    /// With --slurm: the `sshc` the jobs run (default: this one, by its absolute path).
    #[arg(long, value_name = "PATH", requires = "slurm")]
    pub sshc: Option<PathBuf>,
}

/// What the scripts run.
pub struct Job<'a> {
    pub sshc: &'a Path,
    pub sweep: &'a Path,
    pub out: &'a Path,
    pub shards: usize,
    /// Each shard's options after `--shard i/N -o DIR` (truth, cache, cascades).
    pub options: &'a [String],
    pub slurm: &'a SlurmArgs,
}

/// A word for a shell: as it is when it is plain, else in single quotes.
pub fn quote(s: &str) -> String {
    if !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "/._-+=:,@%".contains(c)) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// Text for a comment line of a script: control characters (a newline would end the
/// comment and start a command on every node) written as escapes.
pub fn comment(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// Refuses a path or value with a control character (a newline, a carriage return) that a
/// job script would carry, naming what it is.
pub fn no_control_characters(what: &str, value: &str) -> Result<(), String> {
    if value.chars().any(char::is_control) {
        return Err(format!(
            "error: {what} `{}` holds a control character (a newline, say): the job scripts would carry it to every node; rename it",
            comment(value)
        ));
    }
    Ok(())
}

/// What an array task runs first: the truth's ray casting gets a thread per CPU the task was
/// given, and `i` is the task's index.
pub const TASK_PREAMBLE: &str = "set -euo pipefail\n\
     # the truth's ray casting: a thread per CPU the task was given\n\
     export RAYON_NUM_THREADS=\"${SLURM_CPUS_PER_TASK:-${SLURM_CPUS_ON_NODE:-$(nproc)}}\"\n\
     i=\"$SLURM_ARRAY_TASK_ID\"\n";

/// The checks every `--slurm` makes before writing (the sweep's and the tune's): each
/// `#SBATCH` value as sbatch reads it, at least one CPU per task, and an output folder
/// (named in `#SBATCH --output` lines, which read no quotes) of plain characters.
pub fn check_options(s: &SlurmArgs, out: &Path) -> Result<(), String> {
    for (option, value) in [
        ("--partition", &s.partition),
        ("--gres", &s.gres),
        ("--time", &s.time),
        ("--mem", &s.mem),
    ] {
        if let Some(v) = value {
            check_value(option, v)?;
        }
    }
    check_cpus(s)?;
    let out_text = out.display().to_string();
    if out_text.chars().any(|c| !(c.is_ascii_alphanumeric() || "/._-+=:,@".contains(c))) {
        return Err(format!(
            "error: `-o {out_text}`: the scripts name the output folder in #SBATCH lines, which read no quotes: choose a path of letters, digits and `/._-+=:,@`"
        ));
    }
    Ok(())
}

/// Refuses `--cpus-per-task 0`, which sbatch refuses for every task.
pub fn check_cpus(s: &SlurmArgs) -> Result<(), String> {
    match s.cpus_per_task {
        Some(0) => Err("error: `--cpus-per-task 0`: a task needs at least one CPU".into()),
        _ => Ok(()),
    }
}

/// Refuses a value that an `#SBATCH` line cannot hold (sbatch splits them at white space
/// and reads no quotes), naming the option.
pub fn check_value(option: &str, value: &str) -> Result<(), String> {
    if value.is_empty() || value.chars().any(|c| c.is_whitespace() || c.is_control() || "'\"\\#".contains(c)) {
        return Err(format!(
            "error: `{option} {value}`: an #SBATCH line cannot hold it (white space, quotes, `\\` and `#` are not read as written)"
        ));
    }
    Ok(())
}

pub(crate) fn directives(s: &mut String, slurm: &SlurmArgs, gpu: bool) {
    let mut line = |k: &str, v: &str| s.push_str(&format!("#SBATCH --{k}={v}\n"));
    if let Some(p) = &slurm.partition {
        line("partition", p);
    }
    if let (true, Some(g)) = (gpu, &slurm.gres) {
        line("gres", g);
    }
    if let Some(t) = &slurm.time {
        line("time", t);
    }
    if let (true, Some(c)) = (gpu, slurm.cpus_per_task) {
        line("cpus-per-task", &c.to_string());
    }
    if let (true, Some(m)) = (gpu, &slurm.mem) {
        line("mem", m);
    }
}

/// `sweep.sbatch`, `merge.sbatch` and `submit.sh`.
pub fn scripts(j: &Job) -> [(&'static str, String); 3] {
    let out = j.out.display().to_string();
    let shard_dir = |i: &str| format!("{out}/shard-{i}");
    let n = j.shards;
    let mut sweep = format!(
        "#!/bin/bash\n\
         # The shards of {sweep}: array task i runs shard i/{n} into {out}/shard-i.\n\
         # Written by `sshc sweep --slurm`; submitted by submit.sh. A task that stopped (a time\n\
         # limit, a node lost) resumes where it stopped when run again:\n\
         #   sbatch --array=I {out}/sweep.sbatch\n\
         #SBATCH --job-name=sshc-sweep\n\
         #SBATCH --array=0-{last}\n\
         #SBATCH --output={out}/logs/shard-%a.log\n",
        sweep = comment(&j.sweep.display().to_string()),
        last = n - 1,
    );
    directives(&mut sweep, j.slurm, true);
    let options: Vec<String> = j.options.iter().map(|o| quote(o)).collect();
    let dir = format!("\"{}\"", shard_dir("$i").replace('"', "\\\""));
    sweep.push_str(TASK_PREAMBLE);
    sweep.push_str(&format!(
        "exec {sshc} sweep {sweep} --shard \"$i/{n}\" -o {dir} {options}\n",
        sshc = quote(&j.sshc.display().to_string()),
        sweep = quote(&j.sweep.display().to_string()),
        options = options.join(" "),
    ));
    let mut merge = format!(
        "#!/bin/bash\n\
         # The merge of the {n} shards of {sweep} into {out}: sweep.csv, sweep.md and the charts.\n\
         # submit.sh starts it once every array task has ended well.\n\
         #SBATCH --job-name=sshc-sweep-merge\n\
         #SBATCH --output={out}/logs/merge.log\n",
        sweep = comment(&j.sweep.display().to_string()),
    );
    directives(&mut merge, j.slurm, false);
    let dirs: Vec<String> = (0..n).map(|i| quote(&shard_dir(&i.to_string()))).collect();
    merge.push_str(&format!(
        "set -euo pipefail\n\
         exec {sshc} sweep merge {dirs} -o {out}\n",
        sshc = quote(&j.sshc.display().to_string()),
        dirs = dirs.join(" "),
        out = quote(&out),
    ));
    let submit = format!(
        "#!/bin/sh\n\
         # Submits the array of {n} shards, then the merge, which waits for every task to end\n\
         # well (afterok); a task that fails cancels it (--kill-on-invalid-dep=yes) instead of\n\
         # leaving it pending. Prints the two job ids.\n\
         set -eu\n\
         cd {out}\n\
         array=$(sbatch --parsable sweep.sbatch)\n\
         array=${{array%%;*}}\n\
         merge=$(sbatch --parsable --dependency=afterok:\"$array\" --kill-on-invalid-dep=yes merge.sbatch)\n\
         merge=${{merge%%;*}}\n\
         echo \"array job $array ({n} tasks), merge job $merge\"\n",
        out = quote(&out),
    );
    [("sweep.sbatch", sweep), ("merge.sbatch", merge), ("submit.sh", submit)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scripts_ask_for_what_was_given_and_chain_the_merge() {
        let slurm = SlurmArgs {
            slurm: true,
            shards: Some(4),
            partition: Some("gpu".into()),
            gres: Some("gpu:1".into()),
            time: Some("4:00:00".into()),
            cpus_per_task: Some(8),
            mem: Some("16G".into()),
            sshc: None,
        };
        let options = ["--cache".to_string(), "/shared/my cache".to_string()];
        let job = Job {
            sshc: Path::new("/opt/sshc"),
            sweep: Path::new("/home/u/s.ron"),
            out: Path::new("/shared/out"),
            shards: 4,
            options: &options,
            slurm: &slurm,
        };
        let [(_, sweep), (_, merge), (_, submit)] = scripts(&job);
        for line in [
            "#SBATCH --array=0-3\n",
            "#SBATCH --output=/shared/out/logs/shard-%a.log\n",
            "#SBATCH --partition=gpu\n",
            "#SBATCH --gres=gpu:1\n",
            "#SBATCH --time=4:00:00\n",
            "#SBATCH --cpus-per-task=8\n",
            "#SBATCH --mem=16G\n",
            "exec /opt/sshc sweep /home/u/s.ron --shard \"$i/4\" -o \"/shared/out/shard-$i\" --cache '/shared/my cache'\n",
        ] {
            assert!(sweep.contains(line), "{line} in\n{sweep}");
        }
        // the merge asks for no GPU
        assert!(!merge.contains("--gres") && merge.contains("#SBATCH --partition=gpu\n"), "{merge}");
        assert!(
            merge.contains(
                "exec /opt/sshc sweep merge /shared/out/shard-0 /shared/out/shard-1 /shared/out/shard-2 /shared/out/shard-3 -o /shared/out\n"
            ),
            "{merge}"
        );
        assert!(submit.contains("array=$(sbatch --parsable sweep.sbatch)"), "{submit}");
        assert!(
            submit.contains("sbatch --parsable --dependency=afterok:\"$array\" --kill-on-invalid-dep=yes merge.sbatch"),
            "{submit}"
        );
        assert_eq!(quote("it's"), r"'it'\''s'");
        // a newline in the sweep file's name neither ends a comment nor starts a command
        let evil = Job {
            sweep: Path::new("/home/u/s\nrm -rf ~\n#.ron"),
            ..job
        };
        for (name, text) in scripts(&evil) {
            // the comments hold it escaped (`--slurm` refuses such a path before writing:
            // `no_control_characters`)
            for l in text.lines().filter(|l| l.starts_with("# The ")) {
                assert!(l.contains("/home/u/s\\nrm -rf ~\\n#.ron"), "{name}:\n{text}");
            }
        }
        assert!(no_control_characters("the sweep file", "/a\nb").unwrap_err().contains("`/a\\nb`"));
        assert!(no_control_characters("the sweep file", "/a b").is_ok());
        assert!(check_value("--partition", "a b").unwrap_err().contains("`--partition a b`"));
        assert!(check_value("--gres", "gpu:1").is_ok());
    }
}
