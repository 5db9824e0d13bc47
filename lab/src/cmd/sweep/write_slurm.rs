//! `sshc sweep S.ron --slurm --shards N -o OUT`: the sweep file checked as a run checks
//! it, then [`super::slurm`]'s job scripts written into the output folder, with the options
//! every shard runs with.

use super::file::{configs, load};
use super::{SweepArgs, slurm};
use std::path::Path;

/// `--slurm`: the job scripts of the sweep in `--shards` array tasks (after checking the
/// sweep file as a run would, so that a mistake shows before anything is submitted).
pub(super) fn write_slurm(a: SweepArgs) -> Result<(), String> {
    let sweep_path = a.sweep.clone().ok_or("error: name a sweep file")?;
    // every path the scripts carry, before anything is read
    slurm::no_control_characters("the sweep file", &sweep_path.display().to_string())?;
    slurm::no_control_characters("the output folder", &a.out.display().to_string())?;
    slurm::no_control_characters("the truth cache", &a.truth.cache.display().to_string())?;
    if let Some(p) = &a.slurm.sshc {
        slurm::no_control_characters("--sshc", &p.display().to_string())?;
    }
    let n = a
        .slurm
        .shards
        .ok_or("error: --slurm needs --shards N, the number of array tasks (one shard each)")?;
    let l = load(&sweep_path)?;
    // what every task will check, checked here first: the cascades and the truth's budget
    // on each scene (issue 48, item 11)
    for entry in &l.file.scenes {
        let scene = l.scene(entry)?;
        crate::bind::check_cascades(&scene, &a.cascading)?;
        let (w, h) = scene.camera_size();
        a.truth.check(u64::from(w) * u64::from(h))?;
    }
    let rows = configs(&l.file).len();
    if n == 0 || n > rows.max(1) {
        return Err(format!(
            "error: --shards {n}: the sweep has {rows} configurations; give 1 to {} shards",
            rows.max(1)
        ));
    }
    let s = &a.slurm;
    let absolute = |p: &Path| std::path::absolute(p).map_err(|e| format!("error: {}: {e}", p.display()));
    let out = absolute(&a.out)?;
    slurm::check_options(s, &out)?;
    let out_text = out.display().to_string();
    let sshc = match &s.sshc {
        Some(p) => absolute(p)?,
        None => std::env::current_exe().map_err(|e| format!("error: cannot find this executable: {e}"))?,
    };
    let sweep = absolute(&sweep_path)?;
    // each shard's options: the truth's (the cache on the shared folder) and the cascades'
    let t = &a.truth;
    let mut options: Vec<String> = vec!["--samples".into(), t.samples.to_string(), "--runs".into(), t.runs.to_string()];
    if let Some(se) = t.target_se {
        options.extend([
            "--target-se".into(),
            se.to_string(),
            "--max-samples".into(),
            t.max_samples.to_string(),
        ]);
    }
    options.extend(["--seed".into(), t.seed.to_string()]);
    if t.no_cache {
        options.push("--no-cache".into());
    } else {
        let cache = if t.cache == Path::new(crate::truth::TruthCache::DEFAULT_DIR) {
            out.join("truth-cache")
        } else {
            absolute(&t.cache)?
        };
        options.extend([
            "--cache".into(),
            cache.display().to_string(),
            "--claim-stale".into(),
            t.claim_stale.to_string(),
        ]);
    }
    let c = &a.cascading;
    if let Some(n) = c.cascades {
        options.extend(["--cascades".into(), n.to_string()]);
    }
    if let Some(x) = c.cascade_lambda {
        options.extend(["--cascade-lambda".into(), x.to_string()]);
    }
    if let Some(x) = c.cascade_band {
        options.extend(["--cascade-band".into(), x.to_string()]);
    }
    if c.no_snap {
        options.push("--no-snap".into());
    }
    if let Some([x, y, z]) = c.cascade_offset {
        options.extend(["--cascade-offset".into(), format!("{x},{y},{z}")]);
    }
    let job = slurm::Job {
        sshc: &sshc,
        sweep: &sweep,
        out: &out,
        shards: n,
        options: &options,
        slurm: s,
    };
    let logs = out.join("logs");
    std::fs::create_dir_all(&logs).map_err(|e| format!("error: {}: {e}", logs.display()))?;
    for (name, text) in slurm::scripts(&job) {
        let p = out.join(name);
        // a link planted in the folder is refused, not written through (and not made 0755)
        crate::session::write_new(&p, &text)?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt as _;
            std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).map_err(|e| format!("error: {}: {e}", p.display()))?;
        }
        println!("wrote {}", p.display());
    }
    println!(
        "{} configurations of {} in {n} shards; submit with {}/submit.sh (the merge writes {out_text}/sweep.csv)",
        rows,
        l.path.display(),
        out_text
    );
    Ok(())
}
