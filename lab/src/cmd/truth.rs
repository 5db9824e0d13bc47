//! `sshc truth`: render a scene's world positions and normals on the GPU (with the bundled
//! hard shadow-map technique; every technique's camera pass writes the same positions),
//! then compute the ground-truth visibility at exactly those points on the CPU
//! (`crate::truth`), through the on-disk cache.
//!
//! Also the pieces `sshc compare` shares: loading a technique, the
//! truth options and the cached, progress-reporting truth computation.

use crate::session::{TruthOpts, compile_technique, describe, load_scene, positions_normals, rt, size, truth_at};
use crate::truth::TruthFiles as _;
use sshc_runtime::gpu::Gpu;
use std::path::{Path, PathBuf};

/// The technique `sshc truth` renders positions with.
const HARD: &str = include_str!("../../../techniques/hard.ron");

#[derive(clap::Args)]
pub struct TruthArgs {
    /// The scene (RON).
    #[arg(long)]
    scene: PathBuf,
    /// The ground truth: one-channel float PFM at camera resolution; a PNG of it is written
    /// beside it (same name, `.png`).
    #[arg(short, long, default_value = "truth.pfm")]
    out: PathBuf,
    /// Also write the per-pixel standard error as a one-channel PFM.
    #[arg(long = "std-error", value_name = "PFM")]
    std_error: Option<PathBuf>,
    /// Override the scene's camera size, WIDTHxHEIGHT.
    #[arg(long, value_parser = size)]
    size: Option<(u32, u32)>,
    #[command(flatten)]
    truth: TruthOpts,
}

/// The PNG beside a PFM: same name, `.png`.
fn png_beside(path: &Path) -> PathBuf {
    path.with_extension("png")
}

pub fn truth(a: TruthArgs) -> Result<(), String> {
    if a.out.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        return Err(format!(
            "error: `-o {}`: the truth is written as PFM (its PNG goes beside it); name a `.pfm` file",
            a.out.display()
        ));
    }
    let scene = load_scene(&a.scene, a.size, None)?;
    if scene.lights.is_empty() {
        return Err(format!("error: {}: the scene has no light: add one to `lights`", a.scene.display()));
    }
    if a.truth.runs < 2 {
        return Err("error: `--runs` must be at least 2: the standard error is measured from independent runs".into());
    }
    let (w, h) = scene.camera_size();
    a.truth.check(u64::from(w) * u64::from(h))?;
    // the outputs' folders made (or refused) before the truth is computed
    crate::session::output_file(&a.out, "-o")?;
    crate::session::output_file(&png_beside(&a.out), "-o")?;
    if let Some(p) = &a.std_error {
        crate::session::output_file(p, "--std-error")?;
    }
    let gpu = Gpu::new().map_err(rt)?;
    let loaded = compile_technique(&gpu, Path::new("techniques/hard.ron"), HARD, &Default::default())?;
    let mut ex = crate::bind::bind_scene(&loaded, &scene, false)?;
    ex.run_frame().map_err(rt)?;
    let (positions, normals) = positions_normals(&ex)?;
    let (t, source) = truth_at(&scene, &positions, &normals, &a.truth)?;
    t.write_pfm(&a.out).map_err(|e| format!("error: {e}"))?;
    println!("wrote {}", a.out.display());
    let png = png_beside(&a.out);
    t.write_png(&png).map_err(|e| format!("error: {e}"))?;
    println!("wrote {}", png.display());
    if let Some(p) = &a.std_error {
        t.write_std_error_pfm(p).map_err(|e| format!("error: {e}"))?;
        println!("wrote {}", p.display());
    }
    for line in describe(&t, &source) {
        println!("{line}");
    }
    println!("positions: {}", gpu.describe());
    Ok(())
}
