//! `sshc verify T.ron`: the technique on the GPU against its f64 evaluation on the CPU, over
//! the synthetic depth fields and scene depth maps of the agreement tests (see
//! [`crate::verify`]); a table and a verdict per input, a summary line counting each
//! verdict, and a failing exit status when any input differs or is lossy (an UNCHECKED one
//! is said to be such, and fails nothing by itself).

use crate::session::{Variants, read, report, rt};
use crate::verify::{self, CASTERS, FIELDS, Input, Options, Source};
use sshc_runtime::gpu::Gpu;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct VerifyArgs {
    /// The technique file (RON).
    technique: PathBuf,
    #[command(flatten)]
    variants: Variants,
    /// An independent technique file computing the same visibility (written another way,
    /// every channel at F32, say): its f64 CPU evaluation must agree with the technique's.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// How far the reference may differ beyond what the conditioning of both f64
    /// evaluations allows (constants written differently, guards such as `1e-12`).
    #[arg(long, default_value_t = 1e-6)]
    reference_tolerance: f64,
    /// Shadow-map size N (a power of two; the cameras are 2N and N/2 pixels wide).
    #[arg(long, default_value_t = 32)]
    shadow_map: u32,
    /// Width of the square light over the query plane, world units (the plane spans 2).
    #[arg(long, default_value_t = 0.5)]
    light_width: f64,
    /// Synthetic depth fields, comma-separated (ramp, step, checker, noise, zero, one;
    /// default: all of them, for a technique without Geometry passes).
    #[arg(long, value_delimiter = ',')]
    fields: Option<Vec<String>>,
    /// Caster sets above the plane, rasterised by the Depth and Geometry passes,
    /// comma-separated (box, bars; default: both, for a technique with Geometry passes).
    #[arg(long, value_delimiter = ',')]
    casters: Option<Vec<String>>,
    /// Scenes as inputs too: their light's depth map or, for a technique with Geometry
    /// passes, their shadow casters fitted above the plane. Repeatable (default: the
    /// bundled bunny and fence, where `scenes/` is found).
    #[arg(long = "depth-of")]
    scenes: Vec<PathBuf>,
    /// Split the light's view into N cascades (1 to 4): cascade k is 2^(k/2) times as wide
    /// as the query plane's square, each holds the whole plane, and the combining step
    /// takes each receiver's by its view distance; the CPU evaluates every cascade from
    /// what its own passes rasterised and mixes them as the GPU does.
    #[arg(long, default_value_t = 1)]
    cascades: u32,
    /// With `--cascades`: the practical split's weight of the logarithmic split, in [0, 1].
    #[arg(long, default_value_t = 0.75)]
    cascade_lambda: f32,
    /// With `--cascades`: the fraction of each slice, at its far end, mixed into the next.
    #[arg(long, default_value_t = 0.1)]
    cascade_band: f32,
    /// Write the table (Markdown) here as well.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write one PNG per input and camera into this folder: the GPU's visibility, the
    /// CPU's, and their difference over the allowance (red where outside it).
    #[arg(long)]
    images: Option<PathBuf>,
}

/// The scenes `verify` takes as inputs when `--depth-of` names none.
const DEFAULT_SCENES: [&str; 2] = ["bunny.ron", "fence.ron"];

/// The bundled scenes' folder, found from the repository (the binary's or the one it was
/// built from, [`crate::session::repository`]), never the working folder (issue 51): a
/// `scenes/` where the command runs is not sshc's.
fn bundled_scenes() -> Result<PathBuf, String> {
    crate::session::repository()
        .map(|r| r.join("scenes"))
        .filter(|d| DEFAULT_SCENES.iter().all(|s| d.join(s).is_file()))
        .ok_or_else(|| {
            format!(
                "error: verify's default scene inputs ({}) were not found in a repository above the `sshc` binary or where it was built: name scenes with `--depth-of SCENE.ron`",
                DEFAULT_SCENES.join(", ")
            )
        })
}

fn compile(path: &Path, args: &VerifyArgs, overrides: bool) -> Result<sshc::Compiled, String> {
    let source = read(path)?;
    // the reference is compiled as written: the variants name the technique's params
    let opts = if overrides {
        args.variants.options()
    } else {
        sshc::CompileOptions::default()
    };
    let c = sshc::compile_str(&source, &opts).map_err(|d| {
        report(&d, path, &source);
        String::new()
    })?;
    report(&sshc::Diagnostics(c.warnings.clone()), path, &source);
    Ok(c)
}

pub fn verify(args: VerifyArgs) -> Result<(), String> {
    let c = compile(&args.technique, &args, true)?;
    let reference = args.reference.as_ref().map(|r| compile(r, &args, false)).transpose()?;
    let opts = Options {
        shadow: args.shadow_map,
        light_width: args.light_width,
        reference_tolerance: args.reference_tolerance,
        cascades: args.cascades,
        cascade_lambda: args.cascade_lambda,
        cascade_band: args.cascade_band,
    };
    opts.check().map_err(|e| format!("error: {e}"))?;
    if let Some(out) = &args.out {
        crate::session::output_file(out, "--out")?;
    }
    let gpu = Gpu::new().map_err(rt)?;
    let n = args.shadow_map;
    // a technique with Geometry passes is verified from rasterised casters; the others from
    // depth maps unless casters are asked for
    let geometry = sshc::eval::given_slots(&c).iter().any(|s| s.geometry);
    let default = |on: bool, names: &[&str]| on.then(|| names.iter().map(|s| s.to_string()).collect::<Vec<_>>());
    let fields = args.fields.clone().or_else(|| default(!geometry, &FIELDS)).unwrap_or_default();
    let casters = args.casters.clone().or_else(|| default(geometry, &CASTERS)).unwrap_or_default();
    let mut inputs = Vec::new();
    for f in &fields {
        let depth = verify::depth_field(f, n).ok_or_else(|| format!("error: no depth field `{f}` (there are: {})", FIELDS.join(", ")))?;
        inputs.push(Input {
            name: f.clone(),
            source: Source::Depth(depth),
        });
    }
    for s in &casters {
        let (vertices, meshes) =
            verify::caster_set(s).ok_or_else(|| format!("error: no caster set `{s}` (there are: {})", CASTERS.join(", ")))?;
        inputs.push(Input {
            name: s.clone(),
            source: Source::Casters(vertices, meshes),
        });
    }
    let defaults = args.scenes.is_empty();
    let scenes = if defaults {
        let dir = bundled_scenes()?;
        DEFAULT_SCENES.iter().map(|s| dir.join(s)).collect()
    } else {
        args.scenes.clone()
    };
    // a default scene that fails to load says how to name another
    let named = |e: String| {
        if defaults {
            format!("{e}\n(a default scene input of verify: name other scenes with `--depth-of SCENE.ron`)")
        } else {
            e
        }
    };
    for s in &scenes {
        let name = s.file_stem().map_or("scene".into(), |x| x.to_string_lossy().into_owned());
        let source = if geometry {
            let (vertices, meshes) = verify::scene_casters(s).map_err(named)?;
            Source::Casters(vertices, meshes)
        } else {
            Source::Depth(verify::scene_depth(&gpu, s, n).map_err(named)?)
        };
        inputs.push(Input { name, source });
    }
    if inputs.is_empty() {
        return Err("error: no inputs (name a depth field with --fields, casters with --casters or a scene with --depth-of)".into());
    }
    let total = inputs.len() * 2;
    let mut done = 0;
    let rows = verify::verify(&gpu, &c, reference.as_ref(), &inputs, &opts, &mut |input, camera| {
        done += 1;
        eprintln!("verify [{done}/{total}] {input}, camera {camera}");
    })
    .map_err(|e| format!("error: {e}"))?;
    let table = verify::table(&rows);
    let cascades = if args.cascades > 1 {
        let splits: Vec<String> = opts.splits().iter().map(|s| format!("{s:.3}")).collect();
        format!(
            ", {} cascades split at {} (lambda {}), mixed over the last {} of each slice",
            args.cascades,
            splits.join(", "),
            args.cascade_lambda,
            args.cascade_band
        )
    } else {
        String::new()
    };
    println!(
        "{} on {}, shadow map {n}, light width {}{cascades}\n",
        args.technique.display(),
        gpu.describe(),
        args.light_width
    );
    print!("{table}");
    for r in &rows {
        for (channel, n) in &r.clamped {
            println!(
                "note: {} (camera {}): `{channel}` was clamped to its declared range at {n} texel(s)",
                r.input, r.camera
            );
        }
    }
    if !c.debug_omitted().is_empty() {
        println!(
            "note: debug outputs {} were left out of this build: `--debug` compiles them in and compares each with its CPU evaluation",
            c.debug_omitted().iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
        );
    }
    if let Some(dir) = &args.images {
        std::fs::create_dir_all(dir).map_err(|e| format!("error: cannot create `{}`: {e}", dir.display()))?;
        for r in &rows {
            let path = dir.join(format!("{}-{}.png", r.input, r.camera));
            // at least 128 screen pixels per panel
            let scale = 128u32.div_ceil(r.camera.max(1)).max(1);
            crate::session::save_image(&r.picture(scale), &path)?;
        }
        println!("wrote {} pictures to {}", rows.len(), dir.display());
    }
    if let Some(out) = &args.out {
        crate::session::write_new(out, &table)?;
    }
    for note in rows.iter().filter_map(verify::unchecked_note) {
        println!("{note}");
    }
    let summary = verify::Summary::of(&rows);
    let bad: Vec<String> = rows
        .iter()
        .filter(|r| r.verdict.fails())
        .map(|r| format!("{} (camera {}): {}", r.input, r.camera, r.verdict.name()))
        .collect();
    if bad.is_empty() {
        println!("\n{}", summary.line());
        Ok(())
    } else {
        Err(format!(
            "verdict: {} of {} inputs fail: {}; {}",
            bad.len(),
            rows.len(),
            bad.join("; "),
            summary.counts()
        ))
    }
}
