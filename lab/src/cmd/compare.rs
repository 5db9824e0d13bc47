//! `sshc compare`: render a technique on a scene, compute (or read from the cache) the
//! ground truth at the same world positions, and write one PNG with the technique's
//! visibility, the truth and the signed error side by side, the figures written under
//! them: RMS and max error over the pixels facing the light and over the penumbra
//! (`crate::metrics`), temporal stability while the light moves by sub-texel steps,
//! GPU time per frame, peak memory and the device.

use crate::metrics::{self, Accuracy};
use crate::run::Loaded;
use crate::scene::{Light, Scene};
use crate::session::Overrides;
use crate::session::{TruthOpts, describe, positions_normals, rt, truth_at};
use glam::Vec3;
use plotters::prelude::*;
use sshc_runtime::gpu::{CameraOutput, Gpu};
use std::path::PathBuf;

/// The most frames of the temporal-stability run (each frame's visibility is kept).
pub const MAX_STABILITY_FRAMES: usize = 1024;

#[derive(clap::Args)]
pub struct CompareArgs {
    /// A technique (`.ron`) or a compiled pass graph (`.graph.ron`).
    input: PathBuf,
    /// The scene (RON).
    #[arg(long)]
    scene: PathBuf,
    /// The comparison image (PNG).
    #[arg(short, long, default_value = "compare.png")]
    out: PathBuf,
    #[command(flatten)]
    over: Overrides,
    /// Frames timed; the GPU time per frame is their median.
    #[arg(long, default_value_t = 5)]
    frames: usize,
    /// Frames of the temporal-stability run (the light moves between consecutive ones); 0 or 1 skips it.
    #[arg(long, default_value_t = 8)]
    stability_frames: usize,
    /// How far the light moves per frame of the stability run, in shadow-map texels.
    #[arg(long, default_value_t = 0.25)]
    stability_step: f32,
    /// Half-width of the error image's colour range in 0..255 units (default: the largest
    /// error rounded up to 4, 8, 16, ..., 255).
    #[arg(long)]
    range: Option<f64>,
    #[command(flatten)]
    truth: TruthOpts,
}

/// World size of one shadow-map texel of `light` near the centre of what the map is fitted
/// to ([`Scene::fit_report`]).
fn texel_world(light: &Light, scene: &Scene) -> f32 {
    scene.fit_report(light).texel
}

/// `light` moved by `texels` shadow-map texels (at the centre of the scene) along its
/// view's x axis: a light with a position is translated; a light at infinity is turned
/// by the angle that moves a point half the bounds' diagonal from the centre by that much.
pub(crate) fn moved_light(light: &Light, scene: &Scene, texels: f32) -> Light {
    let bounds = scene.bounds();
    let v = scene.light_view(light);
    let right = v.view.inverse().transform_vector3(Vec3::X).normalize_or(Vec3::X);
    let d = right * texels * texel_world(light, scene);
    let half_diagonal = (0.5 * (bounds.1 - bounds.0).length()).max(f32::MIN_POSITIVE);
    let angle = texels * texel_world(light, scene) / half_diagonal;
    light.translated(d).turned(|dir| (dir + right * angle.tan()).normalize_or(dir))
}

/// Visibility of `frames` frames, the light moving by `step` texels between consecutive
/// ones (`first` is frame 0, as already rendered), bound with `cascading`'s cascades where
/// it asks for them.
pub(crate) fn moving_light_frames(
    ex: &Loaded,
    scene: &Scene,
    cascading: &crate::bind::Cascading,
    first: Vec<f32>,
    frames: usize,
    step: f32,
) -> Result<Vec<Vec<f32>>, String> {
    let mut out = vec![first];
    let Some(light) = scene.lights.first() else {
        return Ok(out);
    };
    for i in 1..frames {
        let mut s = scene.clone();
        s.lights[0] = moved_light(light, scene, i as f32 * step);
        let (mut bound, _) = cascading.bind_or_scene(ex, &s, false)?;
        bound.run_frame().map_err(rt)?;
        out.push(bound.inspect().read_camera(CameraOutput::Visibility).map_err(rt)?.channel(0));
    }
    Ok(out)
}

/// What the comparison image shows besides the images.
struct Figures {
    lines: Vec<String>,
    range: f64,
}

pub fn compare(a: CompareArgs) -> Result<(), String> {
    if a.stability_frames > MAX_STABILITY_FRAMES {
        return Err(format!(
            "error: `--stability-frames {}` is above the limit of {MAX_STABILITY_FRAMES}: every frame's visibility is kept in memory",
            a.stability_frames
        ));
    }
    let gpu = Gpu::new().map_err(rt)?;
    let (scene, loaded) = a.over.load(&gpu, &a.input, &a.scene)?;
    // the image's folder made (or refused) once the inputs are read and checked, before
    // the frames are rendered
    crate::session::output_file(&a.out, "-o")?;
    let light = scene
        .lights
        .first()
        .cloned()
        .ok_or_else(|| format!("error: {}: the scene has no light: add one to `lights`", a.scene.display()))?;
    if a.truth.runs < 2 {
        return Err("error: `--runs` must be at least 2: the standard error is measured from independent runs".into());
    }
    if !(a.stability_step.is_finite() && a.stability_step > 0.0) {
        return Err(format!("error: `--stability-step {}`: expected a step > 0", a.stability_step));
    }
    if let Some(r) = a.range
        && !(r.is_finite() && r > 0.0)
    {
        return Err(format!("error: `--range {r}`: expected a half-width > 0 in 0..255 units"));
    }
    let (mut ex, line) = a.over.cascading.bind_or_scene(&loaded, &scene, false)?;
    if let Some(line) = line {
        println!("{line}");
    }
    let mut frame_ms = Vec::new();
    for _ in 0..a.frames.max(1) {
        let t = ex.run_frame().map_err(rt)?;
        // A frame's time is the sum of its passes, when every pass was timed.
        if let Some(ms) = t.passes.iter().map(|p| p.1).sum::<Option<f64>>() {
            frame_ms.push(ms);
        }
    }
    frame_ms.sort_by(f64::total_cmp);
    let median_ms = frame_ms.get(frame_ms.len() / 2).copied();
    let peak: u64 = ex.inspect().memory().iter().map(|(_, b)| b).sum();
    let visibility = ex.inspect().read_camera(CameraOutput::Visibility).map_err(rt)?.channel(0);
    let (positions, normals) = positions_normals(&ex)?;
    let (w, h) = scene.camera_size();

    let (truth, source) = truth_at(&scene, &positions, &normals, &a.truth)?;
    let facing = metrics::facing_light(&positions, &normals, &light).map_err(|e| format!("error: {e}"))?;
    metrics::check_visibility("the technique's visibility", &visibility, &facing).map_err(|e| format!("error: {e}"))?;
    let mut acc = metrics::accuracy(&visibility, &truth.visibility, &facing).map_err(|e| format!("error: {e}"))?;
    acc.flip = Some(
        metrics::flip(&visibility, &truth.visibility, &positions, &normals, &light, (w, h), &facing).map_err(|e| format!("error: {e}"))?,
    );
    if let Some(set) = metrics::ground_set(&scene, &truth.visibility, &positions, &facing).map_err(|e| format!("error: {e}"))? {
        acc.ground = Some(metrics::error_stats(&visibility, &truth.visibility, &set).map_err(|e| format!("error: {e}"))?);
    }
    let range = match a.range {
        Some(r) => r,
        None => metrics::error_range(&visibility, &truth.visibility, &facing).map_err(|e| format!("error: {e}"))?,
    };
    let error = metrics::error_image(&visibility, &truth.visibility, Some(&facing), w, h, range).map_err(|e| format!("error: {e}"))?;
    let stability = if a.stability_frames >= 2 {
        let frames = moving_light_frames(
            &loaded,
            &scene,
            &a.over.cascading,
            visibility.clone(),
            a.stability_frames,
            a.stability_step,
        )?;
        for (k, f) in frames.iter().enumerate() {
            metrics::check_visibility(&format!("the technique's visibility in stability frame {k}"), f, &facing)
                .map_err(|e| format!("error: {e}"))?;
        }
        Some(metrics::mean_frame_change(&frames, &facing).map_err(|e| format!("error: {e}"))?)
    } else {
        None
    };

    let name = |p: &std::path::Path| p.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let mut overrides: Vec<String> = a.over.variants.set.iter().map(|(k, v)| format!("{k}={v}")).collect();
    overrides.extend(a.over.variants.precision.iter().map(|(k, v)| format!("{k}:{v}")));
    overrides.extend(a.over.variants.schedule.iter().map(|(k, v)| format!("schedule {k}:{v}")));
    let lines = figure_lines(&FigureInputs {
        title: format!(
            "{} on {}: {w}x{h} px, shadow map {}{}",
            name(&a.input),
            name(&a.scene),
            scene.shadow_map,
            if overrides.is_empty() {
                String::new()
            } else {
                format!(", {}", overrides.join(" "))
            }
        ),
        acc,
        fit: scene.fit_report(&light).to_string(),
        stability,
        stability_frames: a.stability_frames,
        step: a.stability_step,
        median_ms,
        frames: a.frames.max(1),
        peak,
        truth: &truth,
        device: gpu.describe(),
        range,
    });
    // Several lights: each light alone, its own truth and error; the panels
    // show light 0.
    let mut lines = lines;
    for i in 1..scene.lights.len() {
        let alone = crate::session::single_light(&scene, i);
        let mut ex = crate::bind::bind_scene(&loaded, &alone, false).map_err(|e| format!("light {i}: {e}"))?;
        ex.run_frame().map_err(rt)?;
        let vis = ex.inspect().read_camera(CameraOutput::Visibility).map_err(rt)?.channel(0);
        let (t, _) = truth_at(&alone, &positions, &normals, &a.truth)?;
        let facing = metrics::facing_light(&positions, &normals, &alone.lights[0]).map_err(|e| format!("error: {e}"))?;
        metrics::check_visibility(&format!("the technique's visibility under light {i}"), &vis, &facing)
            .map_err(|e| format!("error: {e}"))?;
        let acc = metrics::accuracy(&vis, &t.visibility, &facing).map_err(|e| format!("error: {e}"))?;
        let flip = metrics::flip(&vis, &t.visibility, &positions, &normals, &alone.lights[0], (w, h), &facing)
            .map_err(|e| format!("error: {e}"))?;
        lines.push(format!(
            "light {i} ({}): error facing the light: RMS {:.2}, max {:.1} over {} px; in penumbra RMS {:.2} over {} px; FLIP {flip:.4}",
            alone.lights[0].kind().name(),
            acc.facing.rms,
            acc.facing.max,
            acc.facing.pixels,
            acc.penumbra.rms,
            acc.penumbra.pixels
        ));
    }
    if scene.lights.len() > 1 {
        lines.push(format!(
            "lights: {}; the figures above the per-light lines and the panels are light 0's ({})",
            scene.lights.len(),
            light.kind().name()
        ));
    }
    let figures = Figures { lines, range };
    let panels = [
        ("technique visibility", grey(&visibility, w, h)),
        ("ground truth", grey(&truth.visibility, w, h)),
        ("signed error (technique - truth)", error),
    ];
    let img = composite(&panels, &figures)?;
    crate::session::save_image(&img, &a.out)?;
    println!("wrote {}", a.out.display());
    for l in describe(&truth, &source) {
        println!("{l}");
    }
    for l in &figures.lines {
        println!("{l}");
    }
    Ok(())
}

struct FigureInputs<'a> {
    title: String,
    acc: Accuracy,
    fit: String,
    stability: Option<f64>,
    stability_frames: usize,
    step: f32,
    median_ms: Option<f64>,
    frames: usize,
    peak: u64,
    truth: &'a crate::truth::Truth,
    device: String,
    range: f64,
}

fn figure_lines(f: &FigureInputs) -> Vec<String> {
    let stats = |what: &str, s: &metrics::ErrorStats| {
        let mut l = format!("error {what}: RMS {:.2}, max {:.1} (0..255) over {} px", s.rms, s.max, s.pixels);
        if s.non_finite > 0 {
            l.push_str(&format!(", {} not finite", s.non_finite));
        }
        l
    };
    let mut lines = vec![
        f.title.clone(),
        f.fit.clone(),
        stats("facing the light", &f.acc.facing),
        stats("in penumbra (0 < truth < 1)", &f.acc.penumbra),
        metrics::split_line(&f.acc),
        format!("signed mean error facing the light: {:+.2} (0..255)", f.acc.facing.mean),
    ];
    if let Some(g) = &f.acc.ground {
        lines.push(stats("on the shadow on the ground (Lawlor 2006, fig. 10)", g));
    }
    if let Some(flip) = f.acc.flip {
        lines.push(format!(
            "FLIP facing the light: {flip:.4} (mean, 0..1; the image shaded with this visibility against it shaded with the truth's, {} pixels per degree)",
            metrics::FLIP_PIXELS_PER_DEGREE
        ));
    }
    lines.extend([
        match f.stability {
            Some(s) => format!(
                "temporal: mean |change| {s:.3} per frame (0..255), {} frames, light moving {} texel per frame",
                f.stability_frames, f.step
            ),
            None => "temporal: not measured (--stability-frames < 2)".into(),
        },
        format!(
            "GPU time per frame: {} (median of {}); memory peak {:.2} MiB ({} bytes)",
            f.median_ms
                .map_or_else(|| "n/a (no timestamp queries)".into(), |m| format!("{m:.3} ms")),
            f.frames,
            f.peak as f64 / (1024.0 * 1024.0),
            f.peak
        ),
        format!(
            "truth: {} samples x {} runs per pixel; standard error max {:.3}, mean {:.4} (0..255)",
            f.truth.samples,
            f.truth.runs,
            255.0 * f.truth.max_std_error(),
            255.0 * f.truth.mean_std_error()
        ),
        format!("device: {}", f.device),
        format!(
            "error colours: red = technique brighter than truth, blue = darker, range ±{} (0..255); grey = faces away",
            f.range
        ),
    ]);
    lines
}

/// A visibility buffer as an RGB image: grey levels, magenta where not finite.
fn grey(v: &[f32], w: u32, h: u32) -> image::RgbImage {
    image::RgbImage::from_fn(w, h, |x, y| {
        let x = v.get((y * w + x) as usize).copied().unwrap_or(f32::NAN);
        if x.is_finite() {
            let g = (x.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
            image::Rgb([g, g, g])
        } else {
            image::Rgb([255, 0, 255])
        }
    })
}

const FONT: &str = "hack";
const MARGIN: u32 = 12;
const TITLE_H: u32 = 22;
const LINE_H: u32 = 19;
const TEXT_PX: u32 = 14;
/// Hack's advance width is 0.602 em.
const CHAR_W: f64 = 0.61 * TEXT_PX as f64;
const BAR_H: u32 = 10;
const BAR_BLOCK: u32 = 36;

/// The panels side by side (scaled up by a whole factor to at least 256 pixels), titles
/// above, the error colour bar under the last, and the figures as text below.
fn composite(panels: &[(&str, image::RgbImage)], f: &Figures) -> Result<image::RgbImage, String> {
    plotters::style::register_font(FONT, FontStyle::Normal, epaint_default_fonts::HACK_REGULAR)
        .map_err(|_| "error: the bundled font cannot be read".to_string())?;
    let (pw0, ph0) = panels.first().map_or((1, 1), |p| p.1.dimensions());
    let k = (256 / pw0.max(ph0)).max(1);
    let (pw, ph) = (pw0 * k, ph0 * k);
    let n = panels.len() as u32;
    let longest = f.lines.iter().map(|l| l.chars().count()).max().unwrap_or(0);
    let width = (n * pw + (n + 1) * MARGIN).max(2 * MARGIN + (longest as f64 * CHAR_W).ceil() as u32);
    let text_top = MARGIN + TITLE_H + ph + BAR_BLOCK + 8;
    let height = text_top + f.lines.len() as u32 * LINE_H + MARGIN;
    let mut img = image::RgbImage::from_pixel(width, height, image::Rgb([255, 255, 255]));
    let top = MARGIN + TITLE_H;
    for (i, (_, p)) in panels.iter().enumerate() {
        let x0 = MARGIN + i as u32 * (pw + MARGIN);
        for y in 0..ph {
            for x in 0..pw {
                img.put_pixel(
                    x0 + x,
                    top + y,
                    *p.get_pixel((x / k).min(p.width() - 1), (y / k).min(p.height() - 1)),
                );
            }
        }
    }
    // The error colour bar under the last panel: -range on the left, +range on the right.
    let bar_x = MARGIN + (n - 1) * (pw + MARGIN);
    let bar_y = top + ph + 6;
    for x in 0..pw {
        let e = (-1.0 + 2.0 * (f64::from(x) + 0.5) / f64::from(pw)) * f.range;
        let c = metrics::error_colour(e, f.range);
        for y in 0..BAR_H {
            img.put_pixel(bar_x + x, bar_y + y, image::Rgb(c));
        }
    }
    let (w, h) = img.dimensions();
    let mut buf = img.into_raw();
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let style = TextStyle::from((FONT, TEXT_PX as f64).into_font()).color(&BLACK);
        let small = TextStyle::from((FONT, 12.0).into_font()).color(&BLACK);
        let err = |e: DrawingAreaErrorKind<_>| format!("error: drawing the comparison image: {e}");
        for (i, (title, _)) in panels.iter().enumerate() {
            let x0 = MARGIN + i as u32 * (pw + MARGIN);
            root.draw_text(title, &style, (x0 as i32, MARGIN as i32)).map_err(err)?;
        }
        let label_y = (bar_y + BAR_H + 4) as i32;
        let r = format_range(f.range);
        root.draw_text(&format!("-{r}"), &small, (bar_x as i32, label_y)).map_err(err)?;
        let zero_x = (bar_x + pw / 2) as i32 - 4;
        root.draw_text("0", &small, (zero_x, label_y)).map_err(err)?;
        let plus = format!("+{r}");
        let plus_x = (bar_x + pw) as i32 - (plus.len() as f64 * 0.61 * 12.0) as i32;
        root.draw_text(&plus, &small, (plus_x, label_y)).map_err(err)?;
        for (i, line) in f.lines.iter().enumerate() {
            root.draw_text(line, &style, (MARGIN as i32, (text_top + i as u32 * LINE_H) as i32))
                .map_err(err)?;
        }
        root.present().map_err(err)?;
    }
    image::RgbImage::from_raw(w, h, buf).ok_or_else(|| "error: the comparison image has the wrong size".to_string())
}

fn format_range(r: f64) -> String {
    if r.fract() == 0.0 { format!("{r:.0}") } else { format!("{r}") }
}
