//! `sshc render`: compile a technique (or load a compiled graph), bind a scene, run it on
//! the GPU and write the images.

use crate::image_io::ImageFiles;
use crate::run::Bound;
use crate::session::{Overrides, rt};
use sshc_runtime::gpu::{CameraOutput, Gpu, RuntimeError};
use sshc_runtime::graph::{Draw, cost};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct RenderArgs {
    /// A technique (`.ron`) or a compiled pass graph (`.graph.ron`).
    input: PathBuf,
    /// The scene (RON).
    #[arg(long)]
    scene: PathBuf,
    /// The shaded image (PNG).
    #[arg(short, long, default_value = "render.png")]
    out: PathBuf,
    /// The visibility buffer: one-channel float PFM at camera resolution (1 where no surface
    /// is seen); with several lights (at most 3), a three-channel PFM, channel i light i's.
    #[arg(long)]
    visibility: Option<PathBuf>,
    /// World-space position of the surface seen at each pixel: three-channel PFM (NaN where none).
    #[arg(long)]
    positions: Option<PathBuf>,
    /// World-space normal of the surface seen at each pixel: three-channel PFM (NaN where none).
    #[arg(long)]
    normals: Option<PathBuf>,
    #[command(flatten)]
    over: Overrides,
    /// Write every intermediate texture (each layer and mip level, each channel) as PNG and PFM here.
    #[arg(long)]
    dump: Option<PathBuf>,
    /// Frames to run; GPU times per pass are the median over them.
    #[arg(long, default_value_t = 1)]
    frames: usize,
    /// The device's memory bandwidth in GB/s, for each pass's lower bound (its compulsory
    /// bytes over the bandwidth). Default: measured on the device by a buffer copy of
    /// 64 MiB (median of 5).
    #[arg(long, allow_negative_numbers = true)]
    bandwidth: Option<f64>,
}

/// The median of `v` (0 for none).
fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// Bytes of the copy that measures the bandwidth, and how many times it runs.
const BANDWIDTH_COPY_BYTES: u64 = 64 << 20;
const BANDWIDTH_RUNS: usize = 5;

pub fn render(mut a: RenderArgs) -> Result<(), String> {
    // a dump shows the Shade's debug outputs: compiled in for it
    a.over.variants.debug |= a.dump.is_some();
    if let Some(b) = a.bandwidth
        && !(b.is_finite() && b > 0.0)
    {
        return Err(format!("error: --bandwidth {b}: a bandwidth is a positive number of GB/s"));
    }
    let gpu = Gpu::new().map_err(rt)?;
    let (scene, mut loaded) = a.over.load(&gpu, &a.input, &a.scene)?;
    // every output's folder made (or refused) once the inputs are read and checked, before
    // the frame is rendered
    crate::session::output_file(&a.out, "-o")?;
    for (p, option) in [
        (&a.visibility, "--visibility"),
        (&a.positions, "--positions"),
        (&a.normals, "--normals"),
    ] {
        if let Some(p) = p {
            crate::session::output_file(p, option)?;
        }
    }
    if let Some(dir) = &a.dump {
        crate::session::output_folder(dir, "--dump", dir)?;
    }
    // a dump reads every light's textures back: each light keeps its own
    loaded.limits.share_light_textures = a.dump.is_none();
    // Several lights: each light gets its own resources and passes in the same
    // frame, and the GPU combines their shaded images (`crate::run::Loaded::bind_lights`).
    let n_lights = scene.lights.len().max(1);
    if let Some(p) = &a.visibility
        && n_lights > 3
    {
        return Err(format!(
            "error: --visibility {}: a PFM holds one channel per light, at most 3; {} has {n_lights} lights (keep 3 with `--lights 3`)",
            p.display(),
            a.scene.display()
        ));
    }
    let mut stages = crate::session::Stages::default();
    // cascades build their own inputs (one soup, a view per cascade)
    let mut ex = match a.over.cascading.bind(&loaded, &scene)? {
        Some((bound, line)) => {
            stages.done("scene inputs and the cascades' binding");
            println!("{line}");
            bound
        }
        None => {
            let binding = crate::bind::SceneBinding::of(&scene, loaded.graph(), true)?;
            stages.done(match binding {
                crate::bind::SceneBinding::Soup(_) => "scene inputs (the triangle soup)",
                crate::bind::SceneBinding::Instances { .. } => "scene inputs (meshes and their instances)",
            });
            if let crate::bind::SceneBinding::Instances { .. } = binding {
                println!("geometry: {}", binding.describe());
            }
            binding.bind(&loaded)?
        }
    };
    gpu.wait().map_err(rt)?;
    stages.done("bind (upload, edge adjacency, resources)");
    let mut all: Vec<Vec<Option<f64>>> = Vec::new();
    let mut names = Vec::new();
    let mut light_times: Vec<Vec<f64>> = vec![Vec::new(); n_lights];
    // the wall time of each frame, submission to completion: on lavapipe a compute pass's
    // end timestamp does not wait for its dispatches (docs/gpu.md), so schedules are
    // compared there by this
    let mut walls = Vec::new();
    for _ in 0..a.frames.max(1) {
        let start = std::time::Instant::now();
        let t = ex.run_frame().map_err(rt)?;
        gpu.wait().map_err(rt)?;
        walls.push(start.elapsed().as_secs_f64() * 1e3);
        names = t.passes.iter().map(|p| p.0.clone()).collect();
        all.push(t.passes.into_iter().map(|p| p.1).collect());
        for (l, ms) in t.lights.iter().enumerate() {
            if let (Some(ms), Some(v)) = (ms, light_times.get_mut(l)) {
                v.push(*ms);
            }
        }
    }
    stages.done(&format!("{} frame(s)", a.frames.max(1)));
    let color = ex.inspect().read_camera(CameraOutput::Color).map_err(rt)?;
    if let Some(p) = &a.visibility {
        let vis = ex.inspect().read_visibilities().map_err(rt)?;
        if n_lights == 1 {
            vis.write_pfm_gray(p, 0).map_err(rt)?;
            println!("wrote {}", p.display());
        } else {
            vis.write_pfm_rgb(p).map_err(rt)?;
            println!("wrote {} (channel i: light i's visibility)", p.display());
        }
    }
    if n_lights > 1 {
        println!(
            "| light | kind | GPU ms, its passes (median of {} frame(s)) |\n|---|---|---|",
            a.frames.max(1)
        );
        for (i, l) in scene.lights.iter().enumerate() {
            let ms = light_times.get(i).filter(|v| !v.is_empty()).map(|v| format!("{:.3}", median(v)));
            println!("| {i} | {} | {} |", l.kind().name(), ms.as_deref().unwrap_or("-"));
        }
        println!(
            "lights: {n_lights}, each with its own passes and textures in one frame, combined on the GPU; the pass times below are summed over the lights"
        );
    }
    color.write_png(&a.out, None, (0.0, 1.0)).map_err(rt)?;
    println!("wrote {}", a.out.display());
    if let Some(p) = &a.positions {
        ex.inspect()
            .read_camera(CameraOutput::Position)
            .map_err(rt)?
            .write_pfm_rgb(p)
            .map_err(rt)?;
        println!("wrote {}", p.display());
    }
    if let Some(p) = &a.normals {
        ex.inspect()
            .read_camera(CameraOutput::Normal)
            .map_err(rt)?
            .write_pfm_rgb(p)
            .map_err(rt)?;
        println!("wrote {}", p.display());
    }
    if let Some(dir) = &a.dump {
        dump(&ex, dir).map_err(rt)?;
    }
    println!("device: {}", gpu.describe());
    for (i, light) in scene.lights.iter().enumerate() {
        match scene.lights.len() {
            // cascades are fitted each to its slice (their line above)
            1 if a.over.cascading.on(&scene) => {}
            1 => println!("{}", scene.fit_report(light)),
            _ => println!("light {i}: {}", scene.fit_report(light)),
        }
    }
    // Every texture is allocated when the scene is bound and lives for the whole frame, so
    // the peak is the sum.
    let memory = ex.inspect().memory();
    let total: u64 = memory.iter().map(|(_, b)| b).sum();
    println!("| texture | bytes |\n|---|---|");
    for (name, bytes) in &memory {
        println!("| {name} | {bytes} |");
    }
    println!("| peak (all textures resident) | {total} |");
    // Geometry passes: the scene's edges and what the last frame generated from them.
    let edges = ex.scene.edge_counts();
    if let Some(c) = edges {
        println!(
            "edges: {} in {} mesh(es): {} open boundary, {} non-manifold; {} degenerate triangle(s) skipped; {} vertex position(s) welded within {} of their mesh's extent",
            c.edges,
            c.meshes,
            c.boundary,
            c.non_manifold,
            c.degenerate_faces,
            c.welded_near,
            sshc_runtime::adjacency::WELD_TOLERANCE
        );
        for b in &ex.graph().buffers {
            let g = ex.inspect().generated(&b.name).map_err(rt)?;
            // skins come from a neighbouring sample's depth steps, the rest from silhouettes
            let skins = ex
                .graph()
                .passes
                .iter()
                .flat_map(|p| &p.steps)
                .any(|s| s.draw.joins_sample_views() && s.draw.appends_to() == Some(b.name.as_str()));
            let what = if skins {
                "skin triangle(s) in the last view of the last frame"
            } else {
                "silhouette edge(s) in the last frame"
            };
            println!("{}: {} {what}, {} primitive vertices drawn", b.name, g.records, g.vertices);
            if g.dropped > 0 {
                eprintln!(
                    "warning: {}: {} of {} records did not fit in the buffer and were not drawn (the frame's silhouettes passed the bound of one storage binding): the shadow is missing their penumbrae",
                    b.name, g.dropped, g.claimed
                );
            }
        }
    }
    let sizes = cost::Sizes {
        shadow: scene.shadow_map,
        camera: scene.camera_size(),
    };
    let work = cost::work::passes(ex.graph(), sizes, edges.map_or(0, |c| u64::from(c.edges)));
    let bytes = cost::traffic::passes(ex.graph(), sizes);
    let gbps = match a.bandwidth {
        Some(b) => {
            println!("bandwidth: {b:.1} GB/s (given)");
            b
        }
        None => {
            let b = gpu.copy_bandwidth(BANDWIDTH_COPY_BYTES, BANDWIDTH_RUNS).map_err(rt)?;
            println!(
                "bandwidth: {b:.1} GB/s (measured: a copy of {} MiB, read and written, median of {BANDWIDTH_RUNS})",
                BANDWIDTH_COPY_BYTES >> 20
            );
            b
        }
    };
    walls.sort_by(f64::total_cmp);
    println!(
        "frame wall time: {:.3} ms (median of {} frame(s), submission to completion)",
        walls[walls.len() / 2],
        walls.len()
    );
    println!(
        "| pass | GPU ms (median of {} frame(s)) | invocations | fetches | operations | compulsory MB | GB/s | bound ms | ms / bound | schedule |\n|---|---|---|---|---|---|---|---|---|---|",
        all.len()
    );
    for (i, n) in names.iter().enumerate() {
        let mut v: Vec<f64> = all.iter().filter_map(|f| f[i]).collect();
        v.sort_by(f64::total_cmp);
        let median = v.get(v.len() / 2).copied();
        let shown = median
            .map(|m| format!("{m:.3}"))
            .unwrap_or_else(|| "n/a (no timestamp queries)".into());
        let counts = match work.iter().find(|w| &w.pass == n) {
            Some(w) => format!("{:.3e} | {:.3e} | {:.3e}", w.invocations, w.fetches, w.ops),
            None => " | ".into(),
        };
        let memory = match bytes.iter().find(|b| &b.0 == n) {
            Some((_, t)) => {
                let bound = t.bound_ms(gbps);
                let (achieved, ratio) = match median {
                    Some(ms) if ms > 0.0 => (format!("{:.1}", t.total() / (ms * 1e-3) / 1e9), format!("{:.1}", ms / bound)),
                    _ => (String::new(), String::new()),
                };
                format!("{:.2} | {achieved} | {bound:.3} | {ratio}", t.total() / 1e6)
            }
            None => " | | | ".into(),
        };
        let schedule = ex.graph().passes.iter().find(|p| &p.name == n).map_or("", |p| schedule(&p.steps));
        println!("| {n} | {shown} | {counts} | {memory} | {schedule} |");
    }
    Ok(())
}

/// How a pass's steps run: `compute` (a dispatch), `fragment` (full-screen triangles over
/// a texture) or `raster` (the scene or generated primitives), `deferred` for a deferred
/// Shade (a G-buffer raster, then a compute step per pixel); `mixed` for several kinds.
fn schedule(steps: &[sshc_runtime::graph::Step]) -> &'static str {
    if steps.iter().any(|s| s.draw.reads_gbuffer()) {
        return "deferred";
    }
    let kind = |d: &Draw| match d {
        Draw::FullScreen | Draw::MipLevels => "fragment",
        Draw::SceneFromLight | Draw::SceneFromCamera | Draw::CameraGBuffer | Draw::Primitives { .. } => "raster",
        Draw::ComputeRows
        | Draw::ComputeColumns
        | Draw::ComputeTexels
        | Draw::ComputePixels
        | Draw::ComputeMipLevels
        | Draw::Silhouettes { .. }
        | Draw::Discontinuities { .. } => "compute",
    };
    let mut kinds = steps.iter().map(|s| kind(&s.draw));
    let first = kinds.next().unwrap_or("");
    if kinds.all(|k| k == first) { first } else { "mixed" }
}

/// Every texture, layer, mip level and channel as PNG (scaled by the channel's range) and PFM.
fn dump(ex: &Bound, dir: &Path) -> Result<(), RuntimeError> {
    let io = |e: std::io::Error| RuntimeError::File {
        path: dir.to_path_buf(),
        message: e.to_string(),
    };
    std::fs::create_dir_all(dir).map_err(io)?;
    let levels_of = |mips: bool, size: u32| if mips { sshc_runtime::gpu::mip_count(size) } else { 1 };
    let size = ex.targets.shadow_size();
    // the camera-sized debug outputs: below, each light's
    for t in ex
        .graph()
        .textures
        .iter()
        .filter(|t| t.extent == sshc_runtime::graph::Extent::ShadowMap)
    {
        for layer in 0..t.layers {
            for level in 0..levels_of(t.mips, size) {
                let img = ex.inspect().read_texture(&t.name, layer, level)?;
                let comps: Vec<(String, usize, (f32, f32))> = if t.channels.is_empty() {
                    (0..4).map(|c| (format!("c{c}"), c, (0.0, 1.0))).collect()
                } else {
                    t.channels
                        .iter()
                        .filter(|c| c.layer == layer)
                        .map(|c| {
                            // stored values: the range encoded, for viewing
                            let lo = ((c.range.0 - c.bias) * c.scale) as f32;
                            let hi = ((c.range.1 - c.bias) * c.scale) as f32;
                            (c.name.clone(), c.component as usize, (lo, hi))
                        })
                        .collect()
                };
                for (name, c, mut range) in comps {
                    if t.format.is_table() {
                        // prefix sums (of codes, or of f32 values less their midpoint):
                        // viewed over what they hold (the far corner's is the largest)
                        let (lo, hi) = img
                            .rgba
                            .iter()
                            .map(|p| p[c])
                            .fold((0.0f32, 1.0f32), |(a, b), v| (a.min(v), b.max(v)));
                        range = (lo, hi);
                    }
                    let stem = format!("{}.layer{layer}.level{level}.{name}", t.name);
                    img.write_png(&dir.join(format!("{stem}.png")), Some(c), range)?;
                    img.write_pfm_gray(&dir.join(format!("{stem}.pfm")), c)?;
                }
            }
        }
    }
    for (which, name) in [
        (CameraOutput::Visibility, "visibility"),
        (CameraOutput::Color, "color"),
        (CameraOutput::Position, "position"),
        (CameraOutput::Normal, "normal"),
    ] {
        let img = ex.inspect().read_camera(which)?;
        match which {
            CameraOutput::Visibility => img.write_pfm_gray(&dir.join(format!("{name}.pfm")), 0)?,
            _ => img.write_pfm_rgb(&dir.join(format!("{name}.pfm")))?,
        }
        img.write_png(
            &dir.join(format!("{name}.png")),
            if which == CameraOutput::Visibility { Some(0) } else { None },
            (0.0, 1.0),
        )?;
    }
    dump_debug(ex, dir)?;
    println!("wrote every texture to {}", dir.display());
    Ok(())
}

/// The Shade's debug outputs, each light's (or cascade's), each component: PFM (the f32
/// values as computed, NaN where no surface is seen) and a PNG through viridis over the
/// component's finite [min, max], which is printed (NaN black).
fn dump_debug(ex: &Bound, dir: &Path) -> Result<(), RuntimeError> {
    let lights = ex.targets.lights();
    for d in ex.inspect().debug_outputs() {
        for light in 0..lights {
            let img = ex.inspect().read_debug(light, &d.name)?;
            for c in 0..d.components {
                let mut stem = d.texture.clone();
                if d.components > 1 {
                    stem.push('.');
                    stem.push(['x', 'y', 'z', 'w'][c]);
                }
                if lights > 1 {
                    stem.push_str(&format!(".light{light}"));
                }
                img.write_pfm_gray(&dir.join(format!("{stem}.pfm")), c)?;
                let range = img.write_png_viridis(&dir.join(format!("{stem}.png")), c)?;
                match range {
                    Some((lo, hi)) => println!("debug output {stem}: [{lo:e}, {hi:e}] (the PNG maps it through viridis; NaN black)"),
                    None => println!("debug output {stem}: no finite value"),
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use sshc_runtime::graph::cost;

    /// Every pass of CSSM with summed-area tables (`filter = 1`, defaults otherwise: M = 4,
    /// K = 3) counted by hand from its generated WGSL (the snapshots
    /// `techniques__cssm-filter1.cssm.*.wgsl.snap`) and its graph:
    ///
    /// - the basis: 2M = 8 basis images `fs`, 8 z-weighted `gs` and `zhs`: 17 Unorm8
    ///   channels, 4 per RGBA layer: 5 layers of `basis_sat`, `blurred_sat` and `table`;
    /// - `depth`: the scene from the light, one invocation per texel, no fetch;
    /// - `basis_sat`: one full-screen invocation per texel, one `textureLoad` of the depth;
    /// - `blur_sat`: K = 3 taps per layer and direction. The horizontal pass writes a
    ///   Rgba16Float intermediate (8 bytes per texel: 32 / 8 = 4 layers per render pass),
    ///   so it takes two steps (layers 0-3: 12 loads; layer 4: 3 loads); the vertical pass
    ///   writes Rgba8Unorm (8 layers at once): one step of 5 x 3 = 15 loads. Three
    ///   invocations per texel, 30 loads per texel;
    /// - `sat`: one invocation per row, then per column; each walks the 512 texels of its
    ///   row or column in each of the 5 layers, one load per texel (rows: the blurred
    ///   texture; columns: the table);
    /// - `shade`: one invocation per pixel; 7 box lookups (`box_table`: 3 for the
    ///   z-weighted numerator, layers 2-4; 2 for the blocker fraction and 2 for the final
    ///   lookup, layers 0-1), each reading 16 prefix sums (`sat_table`: one storage load).
    #[test]
    fn pass_work_counts_every_invocation_and_fetch_of_cssm_with_tables() {
        let src = include_str!("../../../techniques/cssm.ron");
        let opts = sshc::CompileOptions {
            set: vec![("filter".into(), "1".into())],
            ..Default::default()
        };
        let c = sshc::compile_str(src, &opts).unwrap_or_else(|d| panic!("{}", d.render("cssm.ron", src)));
        let (shadow, camera) = (512u32, (256u32, 128u32));
        let work = cost::work::passes(&c.graph, cost::Sizes { shadow, camera }, 0);
        let names: Vec<&str> = work.iter().map(|w| w.pass.as_str()).collect();
        assert_eq!(names, ["depth", "basis_sat", "blur_sat", "sat", "shade"]);
        let texels = 512.0 * 512.0;
        let pixels = 256.0 * 128.0;
        // (pass, invocations, fetches), by hand as above
        let expected = [
            ("depth", texels, 0.0),
            ("basis_sat", texels, texels),
            ("blur_sat", 3.0 * texels, (12.0 + 3.0 + 15.0) * texels),
            ("sat", 2.0 * 512.0, 2.0 * 512.0 * 5.0 * 512.0),
            ("shade", pixels, 7.0 * 16.0 * pixels),
        ];
        for (w, (name, invocations, fetches)) in work.iter().zip(expected) {
            assert_eq!(
                (w.pass.as_str(), w.invocations, w.fetches),
                (name, invocations, fetches),
                "pass `{name}`: (invocations, fetches)"
            );
        }
    }
}
