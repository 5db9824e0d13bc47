//! The `sshc` command line: a thin shell over the compiler library (`compile`, `check`,
//! `explain`, `bench-compile`) and the lab (`render`, `truth`, `compare`, `sweep`).

use clap::{Parser, Subcommand};
use sshc::{CompileOptions, Diagnostics, DumpPhase};
use sshc_lab::cmd::{compare, render, sweep, truth, tune, verify};
use sshc_lab::session::{Variants, pair, read, report};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "sshc",
    version,
    about = "Compile soft-shadow techniques written in RON into WGSL and a pass graph"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Args, Clone)]
struct Common {
    /// The technique file (RON).
    technique: PathBuf,
    #[command(flatten)]
    variants: Variants,
    /// Print the IR after this phase.
    #[arg(long = "dump-ir-after", value_name = "PHASE", value_parser = dump_phase)]
    dump_ir_after: Option<DumpPhase>,
    /// Specialise for this scene (RON): refuse it if the technique's `light:` list does not
    /// admit its light, fold the light inputs that are 0 for it, record it in the graph.
    #[arg(long)]
    scene: Option<PathBuf>,
}

#[derive(Subcommand)]
enum Command {
    /// Compile a technique: WGSL files, the pass graph and a cost report.
    Compile {
        #[command(flatten)]
        common: Common,
        /// Output folder (default: ./out).
        #[arg(short, long, default_value = "out")]
        out: PathBuf,
    },
    /// Check a technique: every phase of `compile` runs and every diagnostic it would
    /// report is printed (errors and warnings, the rounding estimate included); nothing is
    /// written.
    Check {
        #[command(flatten)]
        common: Common,
    },
    /// Describe the compiled technique in plain words: passes, channels, packing, cost.
    Explain {
        #[command(flatten)]
        common: Common,
    },
    /// Render a bundled or compiled technique on a scene: the shaded image, and on request
    /// the visibility buffer and the world position and normal of every pixel.
    Render(render::RenderArgs),
    /// Ground truth: the fraction of the light visible from the world position of every
    /// pixel (rendered on the GPU), by CPU ray casting, with its measured standard error.
    Truth(truth::TruthArgs),
    /// Render a technique and compare it with the ground truth at the same positions: one
    /// PNG with its visibility, the truth, the signed error and the figures.
    Compare(compare::CompareArgs),
    /// Sweep techniques x their parameter axes x scenes: error against the ground truth,
    /// GPU time (as a ratio to a reference technique) and memory; CSV, Markdown and Pareto
    /// charts. A run resumes where an earlier one in its folder stopped; `--shard i/n` runs
    /// a slice, `--slurm` writes job scripts for a Slurm cluster, and `sshc sweep merge`
    /// joins the shards' folders (docs/cluster.md).
    Sweep(sweep::SweepCommand),
    /// Choose the most accurate configuration a budget allows on your scenes: techniques,
    /// params in their declared ranges, precisions, schedules and the shadow-map size,
    /// searched by successive halving against the ray-traced truth; writes tuned.ron (a
    /// technique file with the chosen values), tune.md and tune.csv (docs/tune.md).
    Tune(Box<tune::TuneArgs>),
    /// Run a technique on the GPU over synthetic depth fields and scene depth maps and
    /// compare every receiver with an f64 evaluation of the same technique on the CPU: a
    /// table and a verdict per input (agrees, differs, lossy).
    Verify(verify::VerifyArgs),
    /// A live window on a technique: orbit the camera, drag the light, params as sliders,
    /// precisions and schedules recompiled in the background, hot reload on save, any
    /// texture of the graph (docs/viewer.md).
    #[cfg(feature = "view")]
    View(sshc_lab::view::ViewArgs),
    /// A live window on a technique (docs/viewer.md): not in this build, which was made
    /// without the `view` feature (as `scripts/run.sh` makes it, for a quicker first build);
    /// the message names the command that builds it.
    #[cfg(not(feature = "view"))]
    View {
        /// The viewer's arguments (docs/viewer.md).
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Generate a scene: `sshc scene city` writes the procedural city as a GLB file (the
    /// mesh a scene file names `City(triangles: N, seed: S)`), to load as `--scene`.
    #[command(subcommand)]
    Scene(SceneCommand),
    /// Time compilation of techniques in a warm process (naga validation included).
    BenchCompile {
        /// Technique files.
        techniques: Vec<PathBuf>,
        /// Compilations per technique; the median is reported.
        #[arg(long, default_value_t = 50)]
        runs: usize,
        /// Override a param of every technique that has it: NAME=VALUE. Repeatable.
        #[arg(long = "set", value_name = "NAME=VALUE", value_parser = pair)]
        set: Vec<(String, String)>,
    },
}

#[derive(Subcommand)]
enum SceneCommand {
    /// A city of towers on a ground plane, about `--triangles` triangles, reproducible from
    /// `--seed`; its towers are nodes instancing six meshes. It has no camera and no light:
    /// loaded as `--scene`, it gets a framing camera and a sun (each noted).
    City {
        /// Triangles to reach (10 k to 16 M).
        #[arg(long, default_value_t = 1_000_000)]
        triangles: u32,
        /// Seed of the layout.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// The GLB file to write.
        #[arg(short, long)]
        out: PathBuf,
    },
}

/// `--dump-ir-after NAME`: the phase names of [`DumpPhase::name`].
fn dump_phase(s: &str) -> Result<DumpPhase, String> {
    s.parse()
}

fn options(c: &Common) -> Result<CompileOptions, String> {
    let scene = match &c.scene {
        Some(path) => {
            let scene = sshc_lab::session::load_scene(path, None, None)?;
            Some(sshc_lab::session::scene_facts(path, &scene).ok_or_else(|| format!("error: {} has no light", path.display()))?)
        }
        None => None,
    };
    Ok(CompileOptions {
        dump_after: c.dump_ir_after,
        scene,
        rounding: true,
        ..c.variants.options()
    })
}

/// Compile the technique of `common`, printing the IR dump asked for and every diagnostic.
fn compile_reported(common: &Common) -> Result<sshc::Compiled, String> {
    let source = read(&common.technique)?;
    let outcome = sshc::compile_with_dump(&source, &options(common)?);
    if let Some(d) = &outcome.dump {
        print!("{d}");
    }
    let c = outcome.result.map_err(|d| {
        report(&d, &common.technique, &source);
        String::new()
    })?;
    report(&Diagnostics(c.warnings.clone()), &common.technique, &source);
    Ok(c)
}

/// Where XDG_RUNTIME_DIR is unset, sets it to a private folder of this process (0700,
/// removed when the returned guard drops) before any thread starts: the Vulkan loader and
/// Mesa read it on every device and print `error: XDG_RUNTIME_DIR ...` without it (issue 51).
/// A value already set is left as it is.
fn private_runtime_dir() -> Option<tempfile::TempDir> {
    if std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|v| !v.is_empty()) {
        return None;
    }
    let dir = tempfile::Builder::new().prefix("sshc-runtime-").tempdir().ok()?;
    // SAFETY: called from `main` before any thread is started (nothing else reads or
    // writes the environment yet), as `set_var` requires.
    unsafe { std::env::set_var("XDG_RUNTIME_DIR", dir.path()) };
    Some(dir)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // kept to the end of `main`: the folder goes when the command is done
    let _runtime_dir = private_runtime_dir();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            if !msg.is_empty() {
                eprintln!("{msg}");
            }
            ExitCode::FAILURE
        }
    }
}

/// The command that builds `sshc` with its viewer.
#[cfg(not(feature = "view"))]
const VIEW_BUILD: &str = "cargo build --release -p sshc-lab (then ./target/release/sshc view ...)";

fn run(cli: Cli) -> Result<(), String> {
    match cli.command {
        Command::Render(args) => render::render(args),
        Command::Truth(args) => truth::truth(args),
        Command::Compare(args) => compare::compare(args),
        Command::Sweep(args) => sweep::sweep(args),
        Command::Tune(args) => tune::tune(*args),
        #[cfg(feature = "view")]
        Command::View(args) => sshc_lab::view::view(args),
        #[cfg(not(feature = "view"))]
        Command::View { .. } => Err(format!(
            "error: this `sshc` was built without the viewer (feature `view`; `scripts/run.sh` leaves it out for a quicker first build); build it with: {VIEW_BUILD}"
        )),
        Command::Verify(args) => verify::verify(args),
        Command::Scene(SceneCommand::City { triangles, seed, out }) => {
            let limit = sshc_lab::scene::MAX_SCENE_TRIANGLES;
            if triangles as usize > limit {
                return Err(format!("error: `--triangles {triangles}` is above the scene limit of {limit}"));
            }
            if triangles == 0 {
                return Err("error: `--triangles 0`: a city has a ground and at least one tower; ask for 1 or more".into());
            }
            let bytes = sshc_lab::scene::generate::city_glb(triangles as usize, seed);
            // read back before writing: the last tower may carry the count past the limit,
            // and a file the scene loader refuses is not written (issue 48, item 16)
            let scene = sshc_lab::scene::Scene::from_gltf_slice(&bytes)
                .map_err(|e| format!("error: `--triangles {triangles}`: the city drawn would be refused: {e}; ask for fewer"))?;
            sshc_lab::session::write_new(&out, &bytes)?;
            let (nodes, meshes) = scene.placements();
            println!(
                "wrote {}: {} triangles, {nodes} nodes placing {meshes} meshes, {} bytes",
                out.display(),
                scene.triangles().len(),
                bytes.len()
            );
            Ok(())
        }
        Command::Compile { common, out } => {
            let c = compile_reported(&common)?;
            let files = sshc::write_outputs(&c, &out).map_err(|e| format!("error: cannot write to `{}`: {e}", out.display()))?;
            for f in files {
                println!("wrote {}", f.display());
            }
            Ok(())
        }
        Command::Check { common } => {
            // the whole pipeline but the writing: what `compile` would say, said here
            let c = compile_reported(&common)?;
            let n = c.warnings.len();
            let warned = match n {
                0 => String::new(),
                1 => " (1 warning)".into(),
                _ => format!(" ({n} warnings)"),
            };
            println!("{}: ok{warned}", common.technique.display());
            Ok(())
        }
        Command::Explain { common } => {
            let c = compile_reported(&common)?;
            print!("{}", c.explain());
            if common.scene.is_some() {
                let generic = Common {
                    scene: None,
                    ..common.clone()
                };
                let g = sshc::compile_str(&read(&common.technique)?, &options(&generic)?).map_err(|d| {
                    report(&d, &common.technique, &read(&common.technique).unwrap_or_default());
                    String::new()
                })?;
                print!("{}", g.specialisation(&c));
            }
            Ok(())
        }
        Command::BenchCompile { techniques, runs, set } => {
            if techniques.is_empty() {
                return Err("error: name at least one technique file".into());
            }
            let runs = runs.max(1);
            println!("| technique | median ms | min ms | max ms | runs |\n|---|---|---|---|---|");
            for t in &techniques {
                let source = read(t)?;
                // only the overrides this technique has a param for
                let has = |name: &str| source.contains(&format!("\"{name}\": Param("));
                let opts = CompileOptions {
                    set: set.iter().filter(|(n, _)| has(n)).cloned().collect(),
                    ..Default::default()
                };
                // warm up
                sshc::compile_str(&source, &opts).map_err(|d| {
                    report(&d, t, &source);
                    String::new()
                })?;
                let mut times: Vec<f64> = (0..runs)
                    .map(|_| {
                        let start = Instant::now();
                        let r = sshc::compile_str(&source, &opts);
                        let ms = start.elapsed().as_secs_f64() * 1e3;
                        std::hint::black_box(r.is_ok());
                        ms
                    })
                    .collect();
                times.sort_by(f64::total_cmp);
                let name = t.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
                println!(
                    "| {name} | {:.3} | {:.3} | {:.3} | {runs} |",
                    times[times.len() / 2],
                    times[0],
                    times[times.len() - 1]
                );
            }
            Ok(())
        }
    }
}
