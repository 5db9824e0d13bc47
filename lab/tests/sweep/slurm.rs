//! `--slurm`: the job scripts are not written for a control character in a path, for
//! options every task would refuse, or through a planted link.

use super::{sshc, sweep_file, tmp};

/// Issue 48, item 1: a newline in the sweep file's name would end the job script's comment
/// and run as a command on every node: `--slurm` refuses it before writing anything.
#[test]
fn slurm_scripts_refuse_a_control_character_in_a_path() {
    let dir = tmp("slurm-newline");
    std::fs::create_dir_all(&dir).unwrap();
    let evil = dir.join("s\nrm -rf ~\n#.ron");
    std::fs::copy(sweep_file("sweep.ron"), &evil).unwrap();
    let out = dir.join("jobs");
    let (ok, text) = sshc(&[
        "sweep".as_ref(),
        evil.as_os_str(),
        "--slurm".as_ref(),
        "--shards".as_ref(),
        "1".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(!ok && text.contains("holds a control character"), "{text}");
    assert!(!out.exists(), "nothing written");
}

/// Issue 48, item 11: `--slurm` checks the options every task would refuse before writing
/// the scripts (docs/cluster.md promises the check on the login node).
#[test]
fn slurm_scripts_are_not_written_for_options_every_task_refuses() {
    let dir = tmp("slurm-options");
    std::fs::create_dir_all(&dir).unwrap();
    let sweep = sweep_file("sweep.ron");
    for (bad, want) in [
        (&["--cascades", "7"][..], "`--cascades 7`"),
        (&["--cascade-lambda", "NaN"][..], "`--cascade-lambda NaN`"),
        (&["--samples", "4294967295"][..], "--samples 4294967295"),
        (&["--cpus-per-task", "0"][..], "`--cpus-per-task 0`"),
    ] {
        let out = dir.join(bad[0].trim_start_matches('-'));
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "sweep".as_ref(),
            sweep.as_os_str(),
            "--slurm".as_ref(),
            "--shards".as_ref(),
            "1".as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
        ];
        args.extend(bad.iter().map(|s| std::ffi::OsStr::new(*s)));
        let (ok, text) = sshc(&args);
        assert!(!ok && text.contains(want), "{bad:?}: {text}");
        assert!(!out.join("sweep.sbatch").exists(), "{bad:?}: scripts written");
    }
}

/// Issue 48, item 15: `--slurm` does not write through a link planted in its output folder
/// (nor make its target 0755): it refuses, naming the file.
#[test]
fn slurm_scripts_are_not_written_through_a_planted_link() {
    let dir = tmp("slurm-link");
    let out = dir.join("jobs");
    std::fs::create_dir_all(&out).unwrap();
    let outside = dir.join("outside.sh");
    std::fs::write(&outside, "kept").unwrap();
    std::os::unix::fs::symlink(&outside, out.join("submit.sh")).unwrap();
    let sweep = sweep_file("sweep.ron");
    let (ok, text) = sshc(&[
        "sweep".as_ref(),
        sweep.as_os_str(),
        "--slurm".as_ref(),
        "--shards".as_ref(),
        "1".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(!ok && text.contains("submit.sh` exists and is not a regular file"), "{text}");
    assert_eq!(std::fs::read_to_string(&outside).unwrap(), "kept");
    use std::os::unix::fs::PermissionsExt as _;
    assert_eq!(
        std::fs::metadata(&outside).unwrap().permissions().mode() & 0o111,
        0,
        "made executable"
    );
}
