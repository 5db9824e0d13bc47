//! Running verify: each (input, camera) bound and drawn on the GPU, what its passes
//! rasterised read back and given to the CPU evaluation, and every receiver (and debug
//! output) compared into a row.

use super::cascade::{Cascade, evaluate};
use super::fields::{Input, Source};
use super::options::Options;
use super::plane::QueryPlane;
use super::verdict::{DebugRow, LOSSY_SHARE, Row};
use crate::run::{Bound, Loaded};
use rayon::prelude::*;
use sshc::eval::{Allowed, Evaluation, Given, GivenSlot, Model, Rounding, Scratch};
use sshc_runtime::gpu::{CameraOutput, Gpu, SampleView};

/// Read back every channel of `slots` after a frame, light (cascade) `light`'s: one decoded
/// map per view.
fn read_given(ex: &Bound, slots: &[GivenSlot], light: usize) -> Result<Given, String> {
    let mut given = Given::default();
    for s in slots {
        let views = (0..s.views)
            .map(|k| {
                let image = ex
                    .inspect()
                    .read_light_texture(light, &s.texture, s.array_layer(k), 0)
                    .map_err(crate::session::rt)?;
                Ok(image.channel(s.component as usize).into_iter().map(|v| s.decode(v)).collect())
            })
            .collect::<Result<Vec<Vec<f64>>, String>>()?;
        given.insert(s.resource, s.channel, views);
    }
    Ok(given)
}

/// The Depth pass's output in `given` (for a reference evaluated from the same maps).
fn depth_views(given: &Given, slots: &[GivenSlot]) -> Vec<Vec<f32>> {
    slots
        .iter()
        .find(|s| !s.geometry)
        .and_then(|s| given.maps(s.resource, s.channel))
        .map(|v| v.iter().map(|m| m.iter().map(|&z| z as f32).collect()).collect())
        .unwrap_or_default()
}

/// Verify `c` (and optionally a reference technique) on each input, under both cameras.
/// `progress` is told each (input, camera) as it starts.
///
/// A depth input replaces the Depth pass's output (every view's, each light sample's view
/// translated); a caster input is rasterised. Either way what the GPU rasterised (the
/// Depth pass's output and Geometry passes') is read back and given to the CPU evaluation,
/// so a technique with Geometry passes is checked from its Geometry outputs on, and needs
/// caster inputs.
pub fn verify(
    gpu: &Gpu,
    c: &sshc::Compiled,
    reference: Option<&sshc::Compiled>,
    inputs: &[Input],
    opts: &Options,
    progress: &mut dyn FnMut(&str, u32),
) -> Result<Vec<Row>, String> {
    opts.check()?;
    let n = opts.shadow;
    let slots = sshc::eval::given_slots(c);
    let geometry = slots.iter().find(|s| s.geometry).map(|s| s.pass.clone());
    let per_sample = c.graph.passes.iter().any(|p| p.views == sshc_runtime::graph::Views::PerLightSample);
    let samples = if per_sample { c.graph.samples } else { 0 };
    if let Some(r) = reference
        && let Some(s) = sshc::eval::given_slots(r).into_iter().find(|s| s.geometry)
    {
        return Err(format!(
            "the reference `{}` has a Geometry pass (`{}`): a reference is evaluated from the technique's depth maps alone",
            r.technique(),
            s.pass
        ));
    }
    if opts.cascades > 1 && per_sample {
        return Err(format!(
            "cascades and per-sample techniques do not mix: `{}` renders views from points on a local light, and cascades split the view of a light at infinity",
            c.technique()
        ));
    }
    let splits = opts.splits();
    let mut rows = Vec::new();
    let mut loaded = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).map_err(crate::session::rt)?;
    // every cascade's textures are read back: each keeps its own
    loaded.limits.share_light_textures = false;
    for input in inputs {
        if let Source::Depth(depth) = &input.source {
            if let Some(pass) = &geometry {
                return Err(format!(
                    "input `{}` is a depth map, but `{}` rasterises Geometry pass `{pass}` from meshes: give it casters",
                    input.name,
                    c.technique()
                ));
            }
            if depth.len() != (n * n) as usize {
                return Err(format!("input `{}` has {} depths, not {n} x {n}", input.name, depth.len()));
            }
        }
        for camera in [2 * n, n / 2] {
            progress(&input.name, camera);
            let plane = QueryPlane {
                shadow: n,
                camera,
                casters: matches!(input.source, Source::Casters(..)),
                ..QueryPlane::new(n, camera)
            };
            let width = opts.light_width as f32;
            let mut depth_maps = None;
            let mut scene = match &input.source {
                Source::Depth(depth) => {
                    let maps = if per_sample {
                        (0..samples)
                            .map(|k| plane.sample_depth(depth, samples, k, opts.light_width))
                            .collect()
                    } else {
                        vec![depth.clone()]
                    };
                    depth_maps = Some(maps);
                    plane.lit_inputs(width)
                }
                Source::Casters(vertices, meshes) => plane.caster_inputs(width, vertices, meshes),
            };
            scene.samples = plane.sample_views(samples, opts.light_width);
            // cascade k's light over the plane (cascade 0 is the plane's own square)
            let planes: Vec<QueryPlane> = (0..opts.cascades).map(|k| plane.cascade(k)).collect();
            let mut ex = if planes.len() > 1 {
                let lights: Vec<_> = planes.iter().map(|p| p.lit_inputs(width).light_inputs()).collect();
                let (eye, forward) = QueryPlane::camera_axis();
                let slices = sshc_runtime::gpu::Slices {
                    eye,
                    forward,
                    splits: splits.clone(),
                    band: opts.cascade_band,
                };
                loaded.bind_cascades(&scene, &lights, &slices)
            } else {
                loaded.bind_scene(&scene)
            }
            .map_err(crate::session::rt)?;
            match &depth_maps {
                Some(maps) => ex.run_frame_with_depth(maps),
                None => ex.run_frame(),
            }
            .map_err(crate::session::rt)?;
            let got = ex
                .inspect()
                .read_camera(CameraOutput::Visibility)
                .map_err(crate::session::rt)?
                .channel(0);
            let positions = ex.inspect().read_camera(CameraOutput::Position).map_err(crate::session::rt)?.rgba;
            let points: Vec<(usize, [f32; 3])> = positions
                .iter()
                .enumerate()
                .filter(|(_, p)| p[..3].iter().all(|c| c.is_finite()))
                .map(|(i, p)| (i, [p[0], p[1], p[2]]))
                .collect();
            // each cascade's evaluations, from what its own passes rasterised
            let mut cascades = Vec::with_capacity(planes.len());
            for (k, &p) in planes.iter().enumerate() {
                let given = read_given(&ex, &slots, k)?;
                let frame = p.frame(opts.light_width);
                // the technique and its reference, each with what f64 rounding allows it
                let pair = reference
                    .map(|r| -> Result<_, String> {
                        let theirs = Given::depth(r, depth_views(&given, &slots));
                        Ok((
                            Evaluation::new(c, &given, frame, Rounding::Exact, Model::F64)?,
                            Evaluation::new(r, &theirs, frame, Rounding::Exact, Model::F64)?,
                        ))
                    })
                    .transpose()?;
                cascades.push(Cascade {
                    plane: p,
                    exact: Evaluation::new(c, &given, frame, Rounding::Exact, Model::Gpu)?,
                    rounded: Evaluation::new(c, &given, frame, Rounding::Stored, Model::Gpu)?,
                    pair,
                });
            }
            let band = opts.cascade_band as f64;
            let evaluated: Vec<_> = points
                .par_iter()
                .map_init(Scratch::default, |scratch, &(i, p)| {
                    let (e, s, f) = evaluate(&cascades, &splits, band, i, p, &scene.samples, scratch);
                    (i, e, s, f)
                })
                .collect();
            let mut row = Row {
                receivers: evaluated.len(),
                compared: Vec::with_capacity(evaluated.len()),
                debug: debug_rows(&ex, &cascades, &points, camera as usize, &scene.samples)?,
                ..Row::new(&input.name, camera, reference.is_some())
            };
            for c in &cascades {
                for (name, n) in c.exact.clamped() {
                    match row.clamped.iter_mut().find(|(m, _)| *m == name) {
                        Some((_, total)) => *total += n,
                        None => row.clamped.push((name, n)),
                    }
                }
            }
            let mut allowances = Vec::new();
            let mut storage = Vec::new();
            for &(i, e, s, f) in &evaluated {
                let g = got.get(i).copied().unwrap_or(f32::NAN) as f64;
                row.compare(i, g, &e);
                allowances.push(e.half_width());
                storage.push((s - e.value).abs());
                if let Some((t, f)) = f {
                    row.compare_reference(i, &t, &f, opts.reference_tolerance);
                }
            }
            allowances.sort_by(f64::total_cmp);
            storage.sort_by(f64::total_cmp);
            row.median_allowance = allowances.get(allowances.len() / 2).copied().unwrap_or(0.0);
            row.storage = storage
                .get(((storage.len() as f64) * (1.0 - LOSSY_SHARE)) as usize)
                .or(storage.last())
                .copied()
                .unwrap_or(0.0);
            row.verdict = row.judge();
            rows.push(row);
        }
    }
    Ok(rows)
}

/// Every debug output of the build compared at every receiver: each cascade's texture
/// (every cascade's Shade writes its own at every pixel) against that cascade's
/// evaluation, component by component.
fn debug_rows(
    ex: &Bound,
    cascades: &[Cascade],
    points: &[(usize, [f32; 3])],
    camera: usize,
    samples: &[SampleView],
) -> Result<Vec<DebugRow>, String> {
    let Some(first) = cascades.first() else { return Ok(Vec::new()) };
    let mut rows = Vec::new();
    for (d, name) in first.exact.debug_names().into_iter().enumerate() {
        let mut row = DebugRow {
            name: name.to_string(),
            values: 0,
            outside: 0,
            max_diff: 0.0,
            worst: None,
        };
        for (k, c) in cascades.iter().enumerate() {
            let got = ex.inspect().read_debug(k, name).map_err(crate::session::rt)?.rgba;
            let expected: Vec<(usize, Vec<Allowed>)> = points
                .par_iter()
                .map_init(Scratch::default, |scratch, &(i, p)| {
                    (i, c.exact.debug(d, &c.plane.receiver(i, p, samples), scratch))
                })
                .collect();
            for (i, e) in expected {
                let g = got.get(i).copied().unwrap_or([f32::NAN; 4]);
                for (component, e) in e.iter().enumerate() {
                    row.add((i % camera, i / camera), g[component] as f64, e);
                }
            }
        }
        rows.push(row);
    }
    Ok(rows)
}
