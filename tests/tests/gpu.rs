//! GPU tests on a real adapter (lavapipe on machines without a GPU). They never skip: with
//! no adapter they fail and name what to install (`scripts/test.sh` installs it).

use glam::Vec3;
use sshc_lab::run::Loaded;
use sshc_lab::scene::Scene;
use sshc_lab::visibility::Visibility;
use sshc_runtime::gpu::{CameraOutput, Gpu, Image, RuntimeError};
use std::path::{Path, PathBuf};

/// One device per test process: `cargo test` runs every test of this binary on it (and
/// pipelines are cached on it); nextest gives each test its own process.
fn gpu() -> &'static Gpu {
    static GPU: std::sync::OnceLock<Gpu> = std::sync::OnceLock::new();
    GPU.get_or_init(|| Gpu::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}")))
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The `.ron` files of a folder of the repository, by name, sorted: every bundled
/// technique and scene is tested without being listed here.
fn bundled(folder: &str) -> Vec<String> {
    let dir = root().join(folder);
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort();
    names
}

fn compile(technique: &str, set: &[(&str, &str)]) -> sshc::Compiled {
    let src = std::fs::read_to_string(root().join("techniques").join(format!("{technique}.ron"))).unwrap();
    let opts = sshc::CompileOptions {
        set: set.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect(),
        ..Default::default()
    };
    sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render(technique, &src)))
}

fn scene(name: &str, size: u32, shadow: u32) -> Scene {
    let mut s = Scene::load(root().join("scenes").join(format!("{name}.ron"))).unwrap_or_else(|e| panic!("{name}: {e}"));
    s.set_camera_size(size, size);
    s.shadow_map = shadow;
    s
}

struct Frame {
    visibility: Image,
    position: Image,
    normal: Image,
}

fn render(gpu: &Gpu, c: &sshc::Compiled, s: &Scene) -> Frame {
    let ex = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
    let mut ex = ex
        .bind_scene(&sshc_lab::bind::scene_inputs_for(s, &c.graph).unwrap_or_else(|e| panic!("{e}")))
        .unwrap_or_else(|e| panic!("{e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    Frame {
        visibility: ex.inspect().read_camera(CameraOutput::Visibility).unwrap(),
        position: ex.inspect().read_camera(CameraOutput::Position).unwrap(),
        normal: ex.inspect().read_camera(CameraOutput::Normal).unwrap(),
    }
}

/// World size of one shadow-map texel at `p` (perspective or orthographic light view).
fn texel_world(s: &Scene, p: Vec3) -> f32 {
    let v = s.lights[0].view(s.bounds());
    let n = s.shadow_map as f32;
    let span = 2.0 / (v.proj.y_axis.y * n);
    if v.orthographic {
        span
    } else {
        span * -(v.view.transform_point3(p).z)
    }
}

/// Whether the light's centre is hidden from `p` (for point-like lights: its centre;
/// for distant lights: its direction).
fn centre_hidden(vis: &Visibility, s: &Scene, p: Vec3, n: Vec3) -> bool {
    let l = &s.lights[0];
    let o = p + n * vis.epsilon() * 4.0;
    let target = match l.center() {
        Some(c) => c,
        None => o + l.direction().unwrap_or(Vec3::Y) * (s.bounds().1 - s.bounds().0).length() * 4.0,
    };
    vis.occluded(o, target)
}

/// Points on the receiver's tangent plane within `k` steps of `step` around `p`, on a
/// square grid (so that occluders as thin as one step cannot slip between the samples).
fn footprint_grid(p: Vec3, n: Vec3, step: f32, k: i32) -> Vec<Vec3> {
    let t = n.any_orthonormal_vector();
    let b = n.cross(t);
    let mut out = Vec::new();
    for i in -k..=k {
        for j in -k..=k {
            out.push(p + t * (i as f32 * step) + b * (j as f32 * step));
        }
    }
    out
}

/// Shaded points whose light-centre visibility is the same everywhere within `footprint`
/// shadow-map texels: (pixel, hidden).
fn unambiguous(s: &Scene, f: &Frame, footprint: f32) -> Vec<(usize, bool)> {
    unambiguous_with(s, f, &|_| footprint)
}

/// Whether a receiver at `p` with normal `n` meets the light's centre at a grazing angle
/// (n.l < 0.3): ambiguous for every shadow map, so [`unambiguous`] leaves it out.
fn grazing(s: &Scene, p: Vec3, n: Vec3) -> bool {
    let to_light = match s.lights[0].center() {
        Some(c) => (c - p).normalize_or_zero(),
        None => s.lights[0].direction().unwrap_or(Vec3::Y),
    };
    n.dot(to_light) < 0.3
}

/// The pixels that see a surface not at a grazing angle to the light ([`grazing`]).
fn not_grazing(s: &Scene, f: &Frame) -> usize {
    f.position
        .rgba
        .iter()
        .zip(&f.normal.rgba)
        .filter(|(pp, nn)| {
            !pp[0].is_nan()
                && !grazing(
                    s,
                    Vec3::new(pp[0], pp[1], pp[2]),
                    Vec3::new(nn[0], nn[1], nn[2]).normalize_or_zero(),
                )
        })
        .count()
}

/// As [`unambiguous`], with a footprint (in texels) per pixel.
fn unambiguous_with(s: &Scene, f: &Frame, footprint_of: &dyn Fn(usize) -> f32) -> Vec<(usize, bool)> {
    let vis = Visibility::new(s);
    let mut out = Vec::new();
    for (i, (pp, nn)) in f.position.rgba.iter().zip(&f.normal.rgba).enumerate() {
        if pp[0].is_nan() {
            continue;
        }
        let p = Vec3::new(pp[0], pp[1], pp[2]);
        let n = Vec3::new(nn[0], nn[1], nn[2]).normalize_or_zero();
        if grazing(s, p, n) {
            continue;
        }
        let h = centre_hidden(&vis, s, p, n);
        // half-texel spacing over the footprint
        let step = 0.5 * texel_world(s, p);
        let footprint = footprint_of(i);
        if !footprint.is_finite() {
            continue;
        }
        if footprint_grid(p, n, step, (2.0 * footprint).ceil() as i32)
            .into_iter()
            .all(|q| centre_hidden(&vis, s, q, n) == h)
        {
            out.push((i, h));
        }
    }
    out
}

#[test]
fn every_technique_on_every_scene_is_finite_and_in_range() {
    let gpu = gpu();
    let (techniques, scenes) = (bundled("techniques"), bundled("scenes"));
    assert!(techniques.len() >= 11 && scenes.len() >= 6, "{techniques:?} {scenes:?}");
    let mut sampled: std::collections::HashMap<&str, usize> = Default::default();
    for t in &techniques {
        let c = compile(t, &[]);
        for sc in &scenes {
            let s = scene(sc, 48, 256);
            // A technique of light samples runs under the lights that have its samples (a
            // segment; N a multiple of the edges of a triangle or rectangle); on the others
            // binding refuses it, saying why.
            if sshc_lab::bind::graph_samples(&c.graph) > 0 {
                match sshc_lab::bind::scene_inputs_for(&s, &c.graph) {
                    Ok(_) => *sampled.entry(t.as_str()).or_default() += 1,
                    Err(e) => {
                        assert!(e.contains("sample"), "{t} on {sc}: {e}");
                        continue;
                    }
                }
            }
            let f = render(gpu, &c, &s);
            for (i, v) in f.visibility.channel(0).iter().enumerate() {
                assert!(
                    v.is_finite() && (0.0..=1.0).contains(v),
                    "{t} on {sc}: pixel {i} has visibility {v}"
                );
                // pixels where no surface is seen hold 1
                if f.position.rgba[i][0].is_nan() {
                    assert_eq!(*v, 1.0, "{t} on {sc}: empty pixel {i} reads {v}");
                }
            }
        }
    }
    // both light-sample techniques ran (at their default N = 2, on the segment light)
    for t in ["linear-light", "point-samples"] {
        assert!(sampled.get(t).is_some_and(|n| *n >= 1), "{t} ran on no scene: {sampled:?}");
    }
}

#[test]
fn hard_shadow_map_is_zero_where_the_light_centre_is_hidden_and_one_where_it_is_seen() {
    // Binary test of Annen eq. 3.2: exact away from the footprint of an edge. The footprint
    // is the nearest texel plus the slope-scaled bias (1.5 texels per unit slope, slope <=
    // tan(acos 0.3) = 3.2): 6 texels covers both.
    let gpu = gpu();
    let c = compile("hard", &[]);
    let (mut judged, mut all_grazing) = (0, Vec::new());
    for sc in &bundled("scenes") {
        let s = scene(sc, 48, 512);
        let f = render(gpu, &c, &s);
        // A scene whose every seen receiver is grazing (plm-low-sun-10: the ground under a
        // sun 10 degrees up, n.l = 0.17) has nothing this test can judge; every other scene
        // must give more than 100 unambiguous pixels.
        if not_grazing(&s, &f) == 0 {
            all_grazing.push(sc.clone());
            continue;
        }
        judged += 1;
        let checked = unambiguous(&s, &f, 6.0);
        assert!(checked.len() > 100, "{sc}: only {} unambiguous pixels", checked.len());
        let vis = f.visibility.channel(0);
        let wrong: Vec<_> = checked.iter().filter(|(i, h)| vis[*i] != if *h { 0.0 } else { 1.0 }).collect();
        assert!(
            wrong.is_empty(),
            "{sc}: {} of {} pixels disagree with the CPU query, e.g. {:?}",
            wrong.len(),
            checked.len(),
            &wrong[..wrong.len().min(5)]
        );
    }
    eprintln!("{judged} scenes judged; every seen receiver grazing, not judged: {all_grazing:?}");
    assert!(judged >= 6, "{judged} scenes judged");
}

#[test]
fn pcf_is_one_where_lit_and_zero_where_hidden_beyond_its_footprint() {
    // N x N bilinear taps reach N/2 + 1 texels, plus the bias (scaled by the same): with
    // N = 3 a footprint of 10 texels is safely outside every tap.
    let gpu = gpu();
    let c = compile("pcf", &[("N", "3")]);
    for sc in &bundled("scenes") {
        let s = scene(sc, 48, 512);
        let f = render(gpu, &c, &s);
        let checked = unambiguous(&s, &f, 10.0);
        let vis = f.visibility.channel(0);
        // bilinear weights (1 - f) + f sum to 1 up to f32 rounding of the products
        let tol = 4.0 * f32::EPSILON;
        let wrong: Vec<_> = checked
            .iter()
            .filter(|(i, h)| (vis[*i] - if *h { 0.0 } else { 1.0 }).abs() > tol)
            .map(|(i, h)| (*i, *h, vis[*i]))
            .collect();
        assert!(
            wrong.is_empty(),
            "{sc}: {} of {} pixels wrong, e.g. {:?}",
            wrong.len(),
            checked.len(),
            &wrong[..wrong.len().min(5)]
        );
    }
}

#[test]
fn shadow_maps_of_one_texel_and_2048_squared_render() {
    let gpu = gpu();
    let c = compile("hard", &[]);
    for n in [1, 2048] {
        let s = scene("contact", 32, n);
        let f = render(gpu, &c, &s);
        assert!(
            f.visibility.channel(0).iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)),
            "shadow map {n}"
        );
    }
}

/// Two images equal bit for bit; otherwise how many pixels differ and the first.
fn same_bits(a: &[f32], b: &[f32], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}");
    let diff: Vec<usize> = (0..a.len()).filter(|&i| a[i].to_bits() != b[i].to_bits()).collect();
    if let Some(&i) = diff.first() {
        panic!(
            "{what}: {} of {} pixels differ; the first, {i}: {} against {}",
            diff.len(),
            a.len(),
            a[i],
            b[i]
        );
    }
}

/// Long bodies, and long arms of branches, are emitted as functions (`sshc::Split`:
/// naga's WGSL front end is quadratic in a function's expressions). Split at every fifth `let` here, every bundled
/// technique's passes run as chains of small functions, and the visibility is the same, bit
/// for bit: the split moves code into functions that the shader compiler inlines, in the
/// same order, so no rounding may differ.
#[test]
fn bodies_split_into_functions_compute_the_same_visibility() {
    let gpu = gpu();
    let tiny = sshc::Split { max_run: 4, part: 3 };
    let (mut split_passes, mut split_arms) = (0, 0);
    for t in bundled("techniques") {
        let src = std::fs::read_to_string(root().join("techniques").join(format!("{t}.ron"))).unwrap();
        let whole = compile(&t, &[]);
        let opts = sshc::CompileOptions {
            split: tiny,
            ..Default::default()
        };
        let split = sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render(&t, &src)));
        let parts = split.shaders.iter().filter(|(_, s)| s.contains("_part1_f(")).count();
        assert!(parts >= 1, "{t}: no pass was split");
        split_passes += parts;
        // an arm of a branch split into functions of its own: `ENTRY_eN{t,f}_part1_f`
        split_arms += split
            .shaders
            .iter()
            .filter(|(_, s)| {
                s.split("_part1_f(").any(|before| {
                    let arm = before.trim_end_matches(['t', 'f']);
                    arm.len() < before.len() && arm.trim_end_matches(|c: char| c.is_ascii_digit()).ends_with("_e")
                })
            })
            .count();
        // the same operation counts: a called function counts at its call site
        assert_eq!(whole.cost.passes, split.cost.passes, "{t}");
        let sc = if sshc_lab::bind::graph_samples(&whole.graph) > 0 {
            "linear"
        } else {
            "contact"
        };
        let s = scene(sc, 32, 128);
        let (a, b) = (render(gpu, &whole, &s), render(gpu, &split, &s));
        same_bits(&a.visibility.channel(0), &b.visibility.channel(0), &format!("{t} on {sc}"));
    }
    assert!(split_passes >= 13, "{split_passes} split passes");
    // VSSM's branches (issue 48, item 4: long arms are split as long bodies are)
    assert!(split_arms >= 1, "no arm of a branch was split");
}

/// The compute schedule of Map, Filter and Mipmap passes (`--schedule *=compute`): every
/// bundled technique with such a pass whose formats a compute step can store runs it as
/// `ComputeTexels` steps (a Filter reading its tile and apron from workgroup memory) or
/// `ComputeMipLevels` steps (one dispatch per level), and
/// the visibility is the same as under the fragment schedule, bit for bit: the same
/// expression per texel, the same taps in the same order, stored at the same format.
#[test]
fn map_filter_and_mipmap_passes_give_the_same_visibility_under_either_schedule() {
    use sshc_runtime::graph::{Draw, PassKind};
    let gpu = gpu();
    let mut computed = Vec::new();
    for t in bundled("techniques") {
        let src = std::fs::read_to_string(root().join("techniques").join(format!("{t}.ron"))).unwrap();
        // every Map, Filter and Mipmap pass as fragment, then as compute (`*` would make the
        // Shade deferred too; the mipmapped techniques' files schedule their chain as compute)
        let default = compile(&t, &[]);
        let every = |schedule: &str| {
            let opts = sshc::CompileOptions {
                schedule: default
                    .graph
                    .passes
                    .iter()
                    .filter(|p| matches!(p.kind, PassKind::Map | PassKind::Filter | PassKind::Mipmap))
                    .map(|p| (p.name.clone(), schedule.into()))
                    .collect(),
                ..Default::default()
            };
            sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render(&t, &src)))
        };
        let (fragment, compute) = (every("fragment"), every("compute"));
        let texels = |c: &sshc::Compiled| {
            c.graph
                .passes
                .iter()
                .flat_map(|p| &p.steps)
                .filter(|s| matches!(s.draw, Draw::ComputeTexels | Draw::ComputeMipLevels))
                .count()
        };
        assert_eq!(texels(&fragment), 0, "{t}: every pass scheduled as fragment");
        // a Map, Filter or Mipmap pass runs as compute where its formats allow it
        let maps = fragment
            .graph
            .passes
            .iter()
            .filter(|p| matches!(p.kind, PassKind::Map | PassKind::Filter | PassKind::Mipmap));
        let storable: Vec<&str> = maps
            .filter(|p| {
                p.steps
                    .iter()
                    .flat_map(|s| &s.writes)
                    .all(|w| fragment.graph.texture(&w.texture).is_some_and(|x| x.format.storable()))
            })
            .map(|p| p.name.as_str())
            .collect();
        // every step of those passes, and no other, is compute in the compute schedule (a
        // fragment Filter over several textures packs them into fewer steps than its
        // compute schedule's one per texture and axis: the passes are compared, not the
        // step counts)
        let in_storable = compute
            .graph
            .passes
            .iter()
            .filter(|p| storable.contains(&p.name.as_str()))
            .inspect(|p| {
                assert!(
                    p.steps
                        .iter()
                        .all(|s| matches!(s.draw, Draw::ComputeTexels | Draw::ComputeMipLevels)),
                    "{t}: pass `{}` under the compute schedule",
                    p.name
                )
            })
            .map(|p| p.steps.len())
            .sum::<usize>();
        assert_eq!(texels(&compute), in_storable, "{t}");
        let storable = storable.len();
        if storable == 0 {
            continue;
        }
        computed.push(t.clone());
        let sc = if sshc_lab::bind::graph_samples(&fragment.graph) > 0 {
            "linear"
        } else {
            "contact"
        };
        let s = scene(sc, 32, 128);
        let (a, b) = (render(gpu, &fragment, &s), render(gpu, &compute, &s));
        same_bits(&a.visibility.channel(0), &b.visibility.channel(0), &format!("{t} on {sc}"));
    }
    // esm's exponential map and blur (R32Float) at least; the others as their formats allow
    assert!(computed.contains(&"esm".to_string()), "{computed:?}");
    let esm = sshc::compile_str(
        &std::fs::read_to_string(root().join("techniques/esm.ron")).unwrap(),
        &sshc::CompileOptions {
            schedule: vec![("blur".into(), "compute".into())],
            ..Default::default()
        },
    )
    .unwrap();
    let blur = esm.graph.passes.iter().find(|p| p.name == "blur").unwrap();
    assert!(blur.steps.iter().all(|s| s.draw == sshc_runtime::graph::Draw::ComputeTexels));
}

fn write_compiled(c: &sshc::Compiled, dir: &Path) -> PathBuf {
    let _ = std::fs::remove_dir_all(dir);
    sshc::write_outputs(c, dir).unwrap();
    dir.join(format!("{}.graph.ron", c.graph.technique))
}

#[test]
fn rejected_graphs_say_why() {
    let gpu = gpu();
    let c = compile("hard", &[]);
    let base = std::env::temp_dir().join(format!("sshc-rejected-{}", std::process::id()));

    // A compiled graph loads from its folder.
    let ok = write_compiled(&c, &base.join("ok"));
    Loaded::load(gpu, &ok).unwrap_or_else(|e| panic!("{e}"));

    // Another schema version.
    let g = write_compiled(&c, &base.join("version"));
    let text = std::fs::read_to_string(&g).unwrap().replacen("version: 1", "version: 2", 1);
    std::fs::write(&g, text).unwrap();
    let e = Loaded::load(gpu, &g).expect_err("version 2 must be refused");
    assert!(
        matches!(e, RuntimeError::Graph(sshc_runtime::GraphError::Version { found: 2, expected: 1 })),
        "{e}"
    );

    // A shader path that leaves the folder.
    let g = write_compiled(&c, &base.join("path"));
    let text = std::fs::read_to_string(&g)
        .unwrap()
        .replace("\"hard.shade.wgsl\"", "\"../ok/hard.shade.wgsl\"");
    std::fs::write(&g, text).unwrap();
    let e = Loaded::load(gpu, &g).expect_err("a path leaving the folder must be refused");
    assert!(matches!(e, RuntimeError::Graph(sshc_runtime::GraphError::Path { .. })), "{e}");

    // A link that leaves the folder.
    let g = write_compiled(&c, &base.join("link"));
    let shade = g.parent().unwrap().join("hard.shade.wgsl");
    std::fs::remove_file(&shade).unwrap();
    std::os::unix::fs::symlink(base.join("ok").join("hard.shade.wgsl"), &shade).unwrap();
    let e = Loaded::load(gpu, &g).expect_err("a link leaving the folder must be refused");
    assert!(e.to_string().contains("outside the graph's folder"), "{e}");

    // A shader that does not validate.
    let g = write_compiled(&c, &base.join("shader"));
    let shade = g.parent().unwrap().join("hard.shade.wgsl");
    let text = std::fs::read_to_string(&shade).unwrap().replace("let vis = ", "let vis: i32 = ");
    std::fs::write(&shade, text).unwrap();
    let e = Loaded::load(gpu, &g).expect_err("an invalid shader must be refused");
    assert!(matches!(e, RuntimeError::Shader { .. }), "{e}");

    // A Params uniform larger than the device allows, and a param outside the uniform.
    let mut g = c.graph.clone();
    g.params_size = u32::try_from(gpu.limits.max_uniform_buffer_binding_size + 16).unwrap_or(u32::MAX);
    let e = Loaded::new(gpu, g, c.shaders.clone()).expect_err("an oversized uniform must be refused");
    assert!(
        matches!(&e, RuntimeError::Unsatisfied { missing, .. } if missing.iter().any(|m| m.contains("max_uniform_buffer_binding_size") && m.contains("Params uniform"))),
        "{e}"
    );
    let mut g = c.graph.clone();
    if let Some(p) = g.params.iter_mut().find(|p| p.offset.is_some()) {
        p.offset = Some(g.params_size);
    }
    let e = Loaded::new(gpu, g, c.shaders.clone()).expect_err("a param outside the uniform must be refused");
    assert!(matches!(e, RuntimeError::Param(_)), "{e}");

    // A shadow map one texel above the device's limit is refused before allocation.
    let ex = Loaded::load(gpu, &ok).unwrap();
    let mut s = scene("contact", 16, 16);
    s.shadow_map = gpu.limits.max_texture_dimension_2d + 1;
    let e = ex
        .bind_scene(&sshc_lab::bind::scene_inputs(&s).unwrap())
        .expect_err("over the limit");
    assert!(matches!(e, RuntimeError::Limit { needed, limit, .. } if needed == limit + 1), "{e}");
    let _ = std::fs::remove_dir_all(&base);
}

/// Shadow-map texels between each pixel and its right and lower neighbours (the larger).
fn texels_per_pixel(s: &Scene, f: &Frame) -> Vec<f32> {
    let v = s.lights[0].view(s.bounds());
    let n = s.shadow_map as f32;
    let w = f.position.width as usize;
    let uv: Vec<Option<glam::Vec2>> = f
        .position
        .rgba
        .iter()
        .map(|p| {
            if p[0].is_nan() {
                return None;
            }
            let c = v.view_proj * glam::Vec4::new(p[0], p[1], p[2], 1.0);
            Some(glam::Vec2::new(c.x / c.w, c.y / c.w) * 0.5 * n)
        })
        .collect();
    (0..uv.len())
        .map(|i| {
            let here = uv[i];
            [i + 1, i + w, i.wrapping_sub(1), i.wrapping_sub(w)]
                .into_iter()
                .filter_map(|j| Some((here?, *uv.get(j)?)))
                .filter_map(|(a, b)| b.map(|b| (a - b).length()))
                .fold(0.0, f32::max)
        })
        .collect()
}

/// Largest change of visibility between horizontally or vertically adjacent pixels that
/// both see a surface.
fn largest_step(v: &[f32], surface: &[bool], w: usize) -> f32 {
    let mut m: f32 = 0.0;
    for i in 0..v.len() {
        for j in [i + 1, i + w] {
            if j < v.len() && (j != i + 1 || j % w != 0) && surface[i] && surface[j] {
                m = m.max((v[i] - v[j]).abs());
            }
        }
    }
    m
}

#[test]
fn soft_techniques_change_smoothly_across_the_edge() {
    // The straight edge under a distant disk (scenes/edge.ron): no step between neighbouring
    // pixels may exceed the truth's own largest step plus the technique's quantisation
    // (1/N^2 for N x N PCF: one tap; 1/255 for CSM's unorm8 basis; 0 for float storage)
    // plus the truth's Monte Carlo error (3 standard errors of a fraction estimated from
    // 24 x 24 stratified samples: 3 * 0.5 / 24).
    //
    // The techniques' penumbrae come from their filters, in shadow-map texels; the truth's
    // from the light. The property compares them where the filters span about the true
    // penumbra: a 64-texel shadow map over this scene (at 128 texels PCF 3x3 steps by
    // 0.17 against the truth's 0.07: sharper than the light, not broken). The hard shadow
    // map is the control: it must fail the same bound.
    let gpu = gpu();
    let shadow = 64;
    let s = scene("edge", 64, shadow);
    let size = 64usize;
    for (t, set, quantum) in [
        ("hard", vec![], 0.0),
        ("pcf", vec![("N", "3")], 1.0 / 9.0),
        ("pcf", vec![("N", "7")], 1.0 / 49.0),
        ("vsm", vec![], 0.0),
        ("esm", vec![], 0.0),
        ("csm", vec![], 1.0 / 255.0),
        // the soft techniques take the distant disk's spread from `light_spread`: one of
        // PCSS's 8 x 8 binary taps; CSSM's unorm8 basis
        ("pcss", vec![], 1.0 / 64.0),
        ("cssm", vec![], 1.0 / 255.0),
        ("cssm", vec![("filter", "1")], 1.0 / 255.0),
    ] {
        let c = compile(t, &set);
        let f = render(gpu, &c, &s);
        let pos: Vec<Vec3> = f.position.rgba.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        let nrm: Vec<Vec3> = f.normal.rgba.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        let surface: Vec<bool> = pos.iter().map(|p| p.x.is_finite()).collect();
        let truth = Visibility::new(&s).visible_fractions(&pos, &nrm, &s.lights[0], 24);
        let gpu_v = f.visibility.channel(0);
        let t_step = largest_step(&truth, &surface, size);
        let g_step = largest_step(&gpu_v, &surface, size);
        let bound = t_step + quantum + 3.0 * 0.5 / 24.0;
        assert!(
            t_step < 0.5,
            "the edge scene's penumbra should span several pixels, but the truth steps by {t_step}"
        );
        if t == "hard" {
            assert!(
                g_step > bound,
                "the hard shadow map should step by more than {bound}, found {g_step}: the test cannot tell hard from soft"
            );
            continue;
        }
        assert!(
            g_step <= bound,
            "{t} {set:?}: step {g_step} between neighbouring pixels, above the truth's {t_step} + {quantum} + MC error"
        );
    }
}

#[test]
fn prefiltered_techniques_read_one_where_fully_lit_beyond_their_footprint() {
    // VSM: p = 1 where d <= mean (Chebyshev applies behind the mean only), exactly.
    // ESM: saturate(exp(-c (d - z))) = 1 where every z under the kernel is >= d, exactly.
    // CSM: with the scale fix (fix = 2), saturate(2 f) = 1 wherever f >= 1/2, which holds on
    //      lit receivers (d - z <= 0) up to the basis' unorm8 quantisation, bounded by 1/255
    //      times the sum of |coefficients| (2 / pi * sum 1/(2k-1) < 1.3 for M = 4): tolerance
    //      1.3 / 255. With the offset fix a lit surface reads the truncated, attenuated series
    //      at d - z = -1/(2M) (0.96 for M = 4, alpha = 1; Annen fig. 6.1): by design, not 1.
    // Footprint per pixel: the 3-texel blur, the bilinear lookup (1 texel), and for mip
    // chains the texels one level of the trilinear lookup averages: the sampler picks level
    // log2(texels per pixel) and blends with the next, so up to 2x the texels per pixel,
    // measured from the neighbouring pixels' shadow-map coordinates.
    let gpu = gpu();
    for (t, set, tol) in [
        ("vsm", vec![], 0.0f32),
        ("esm", vec![], 0.0),
        ("csm", vec![("fix", "2")], 1.3 / 255.0),
    ] {
        let c = compile(t, &set);
        for sc in &bundled("scenes") {
            let s = scene(sc, 48, 512);
            let f = render(gpu, &c, &s);
            let vis = f.visibility.channel(0);
            let per_pixel = texels_per_pixel(&s, &f);
            // pixels whose footprint exceeds 12 texels are too blurred to call (and costly)
            let footprint = |i: usize| {
                let t = 3.0 + 1.0 + 2.0 * per_pixel[i].max(1.0) + 1.0;
                if t <= 12.0 { t } else { f32::INFINITY }
            };
            let lit: Vec<usize> = unambiguous_with(&s, &f, &footprint)
                .into_iter()
                .filter(|(_, h)| !h)
                .map(|(i, _)| i)
                .collect();
            let wrong: Vec<(usize, f32)> = lit.iter().filter(|i| vis[**i] < 1.0 - tol).map(|i| (*i, vis[*i])).collect();
            eprintln!("{t} {sc}: {} lit pixels checked, {} wrong", lit.len(), wrong.len());
            assert!(
                wrong.is_empty(),
                "{t} on {sc}: {} of {} fully lit pixels read below 1, e.g. {:?}",
                wrong.len(),
                lit.len(),
                &wrong[..wrong.len().min(5)]
            );
        }
    }
}

/// Techniques written with functions: the bundled EVSM and MSM
/// (`techniques/evsm.ron`, `msm.ron`) and the examples (`techniques/examples/`: Poisson-disk
/// PCF rotated per pixel, VSM with its bound and bleeding reduction as functions), written
/// with functions, arrays, `pixel`, `frame` and `noise`: on every bundled scene their
/// visibility is finite and in [0, 1], and on the receivers whose light-centre visibility
/// is the same over a footprint of 8 texels (wider than any example's filter: Poisson's
/// 2.5-texel disk, the 3-texel box plus bilinear or trilinear lookups) at least 95 % read
/// on the right side of 1/2. Not 100 %: these are approximations (MSM's moment bias and
/// EVSM's bound leave a little shadow on lit receivers near occluders; the rotated disk
/// is noisy by design), and a wrong sign or a broken solve would get most pixels wrong.
#[test]
fn the_example_techniques_render_and_separate_lit_from_hidden() {
    let gpu = gpu();
    let examples = bundled("techniques/examples");
    assert!(examples.len() >= 2, "{examples:?}");
    let mut paths: Vec<(String, std::path::PathBuf)> = ["evsm", "msm"]
        .iter()
        .map(|t| (t.to_string(), root().join("techniques").join(format!("{t}.ron"))))
        .collect();
    paths.extend(
        examples
            .iter()
            .map(|t| (t.clone(), root().join("techniques/examples").join(format!("{t}.ron")))),
    );
    for (t, path) in &paths {
        let src = std::fs::read_to_string(path).unwrap();
        let c = sshc::compile_str(&src, &Default::default()).unwrap_or_else(|d| panic!("{}", d.render(t, &src)));
        let (mut right, mut checked) = (0usize, 0usize);
        for sc in &bundled("scenes") {
            let s = scene(sc, 48, 512);
            if sshc_lab::bind::scene_inputs_for(&s, &c.graph).is_err() {
                continue;
            }
            let f = render(gpu, &c, &s);
            let vis = f.visibility.channel(0);
            for (i, v) in vis.iter().enumerate() {
                assert!(v.is_finite() && (0.0..=1.0).contains(v), "{t} on {sc}: pixel {i} reads {v}");
            }
            for (i, hidden) in unambiguous(&s, &f, 8.0) {
                checked += 1;
                right += usize::from((vis[i] < 0.5) == hidden);
            }
        }
        eprintln!("{t}: {right} of {checked} unambiguous pixels right");
        assert!(checked >= 200, "{t}: only {checked} unambiguous pixels");
        assert!(right as f64 >= 0.95 * checked as f64, "{t}: {right} of {checked} right");
    }
}

#[test]
fn gpu_times_and_memory_are_reported_per_pass_and_texture() {
    let gpu = gpu();
    let c = compile("csm", &[]);
    let s = scene("contact", 32, 64);
    let ex = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap();
    let mut ex = ex.bind_scene(&sshc_lab::bind::scene_inputs(&s).unwrap()).unwrap();
    let times = ex.run_frame().unwrap();
    let names: Vec<&str> = times.passes.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["depth", "basis", "blur", "mips", "shade"]);
    if gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
        for (n, t) in &times.passes {
            let t = t.unwrap_or_else(|| panic!("pass {n} has no GPU time"));
            assert!(t.is_finite() && t >= 0.0, "pass {n}: {t} ms");
        }
    }
    // CSM M = 4 at unorm8: 8 basis channels in 2 RGBA8 layers; with a full mip chain the
    // blurred copy takes 4/3 of its level 0; the blur's scratch is F16 (8 bytes x 2 layers).
    let texels = 64u64 * 64;
    let memory: std::collections::HashMap<String, u64> = ex.inspect().memory().into_iter().collect();
    assert_eq!(memory["shadow"], texels * 4);
    assert_eq!(memory["basis"], texels * 4 * 2);
    assert_eq!(memory["blurred"], texels * 4 * 2 * 4 / 3);
    assert_eq!(memory["blurred_tmp"], texels * 8 * 2);
}

#[test]
fn pipelines_are_built_once_per_device() {
    // Fresh device: this test must not share one with others (it counts its pipelines).
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let c = compile("vsm", &[]);
    let steps: usize = c.graph.passes.iter().map(|p| p.steps.len()).sum();
    let first = Loaded::new(&gpu, c.graph.clone(), c.shaders.clone()).unwrap();
    assert_eq!(gpu.cached_pipelines(), steps);
    drop(first);
    // The same technique on another scene reuses every pipeline.
    for sc in ["contact", "edge"] {
        let ex = Loaded::new(&gpu, c.graph.clone(), c.shaders.clone()).unwrap();
        let mut ex = ex.bind_scene(&sshc_lab::bind::scene_inputs(&scene(sc, 16, 32)).unwrap()).unwrap();
        ex.run_frame().unwrap();
    }
    assert_eq!(gpu.cached_pipelines(), steps);
    // Another variant adds only the pipelines whose shaders changed.
    let c2 = compile("vsm", &[("K", "5")]);
    let _ = Loaded::new(&gpu, c2.graph.clone(), c2.shaders.clone()).unwrap();
    let blur_steps = c2.graph.passes.iter().find(|p| p.name == "blur").map(|p| p.steps.len()).unwrap();
    assert_eq!(gpu.cached_pipelines(), steps + blur_steps);
}

/// The Shade pass of every bundled technique deferred (the compute schedule: a G-buffer
/// raster, then one compute invocation per pixel) against forward (the default).
///
/// Both compute the receiver's inputs by the same code from the same f32 values, with one
/// exception: the footprint of implicit-LOD lookups (`sample`), `dpdx(uv)` and `dpdy(uv)`,
/// which the G-buffer holds at F16 (relative error 2^-11, a level of detail off by up to
/// log2(1 + 2^-11) = 7e-4 of a level; the normal goes through an octahedral f32 encoding,
/// which here changes no value). So a technique with no implicit-LOD lookup gives the same
/// visibility bit for bit; one with them (CSM, VSM, EVSM, MSM) may differ where the level of detail
/// moves the trilinear weight across one of its quanta (8 bits on lavapipe, as few as 4 in
/// Vulkan), which its reconstruction then amplifies: that is the 8-bit filtering term of the
/// agreement tests' error model, and tests/tests/agreement.rs checks these techniques'
/// compute variants (`*=compute`, the deferred Shade included) against the f64 reference
/// with it. Here their differences are only reported. Position is bit for bit, the normal
/// within one F16 ulp, the background the forward form's clear values.
/// The bundled techniques whose Shade the compiler keeps forward when compute is asked
/// for, and why (the refusal `explain` prints).
const FORWARD_ONLY: &[(&str, &str)] = &[
    (
        "linear-light",
        "it reads `depth_slope` in light sample 0's view, and the G-buffer carries the centre view's only",
    ),
    (
        "point-samples",
        "it reads `depth_slope` in light sample 0's view, and the G-buffer carries the centre view's only",
    ),
];

#[test]
fn a_deferred_shade_gives_the_forward_values() {
    use sshc_runtime::graph::{Draw, PassKind};
    let gpu = gpu();
    let (mut deferred_ones, mut refused) = (Vec::new(), Vec::new());
    for t in bundled("techniques") {
        let src = std::fs::read_to_string(root().join("techniques").join(format!("{t}.ron"))).unwrap();
        let forward = compile(&t, &[]);
        let shade = forward
            .graph
            .passes
            .iter()
            .find(|p| p.kind == PassKind::Shade)
            .expect("a Shade pass");
        let opts = sshc::CompileOptions {
            schedule: vec![(shade.name.clone(), "compute".into())],
            ..Default::default()
        };
        let deferred = sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render(&t, &src)));
        let draws = |c: &sshc::Compiled| -> Vec<Draw> {
            let p = c.graph.passes.iter().find(|p| p.kind == PassKind::Shade).unwrap();
            p.steps.iter().map(|s| s.draw.clone()).collect()
        };
        assert_eq!(draws(&forward), [Draw::SceneFromCamera], "{t}: the default is forward");
        let text = deferred.explain();
        if draws(&deferred) == [Draw::SceneFromCamera] {
            let why = FORWARD_ONLY
                .iter()
                .find(|(n, _)| *n == t)
                .map_or("(not in FORWARD_ONLY)", |(_, why)| why);
            assert!(
                text.contains(&format!("compute (deferred) was asked for, but {why}")),
                "{t}: the refusal is explained\n{text}"
            );
            refused.push(t.clone());
            continue;
        }
        assert_eq!(draws(&deferred), [Draw::CameraGBuffer, Draw::ComputePixels], "{t}");
        assert!(text.contains("schedule: compute (deferred)"), "{t}\n{text}");
        deferred_ones.push(t.clone());
        // implicit-LOD lookups in the Shade (`textureSample`, forward)
        let implicit_lod = forward
            .shaders
            .iter()
            .any(|(f, src)| f.ends_with("shade.wgsl") && src.contains("textureSample("));
        let sc = if sshc_lab::bind::graph_samples(&forward.graph) > 0 {
            "linear"
        } else {
            "contact"
        };
        let s = scene(sc, 48, 128);
        let outputs = |c: &sshc::Compiled| {
            let ex = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
            let mut ex = ex
                .bind_scene(&sshc_lab::bind::scene_inputs_for(&s, &c.graph).unwrap_or_else(|e| panic!("{e}")))
                .unwrap_or_else(|e| panic!("{e}"));
            ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
            [
                CameraOutput::Visibility,
                CameraOutput::Color,
                CameraOutput::Position,
                CameraOutput::Normal,
            ]
            .map(|o| ex.inspect().read_camera(o).unwrap_or_else(|e| panic!("{e}")))
        };
        let (a, b) = (outputs(&forward), outputs(&deferred));
        let what = format!("{t} on {sc}");
        let mut background = 0;
        let (mut vis_max, mut vis_diff) = (0.0f32, 0);
        for y in 0..a[0].height {
            for x in 0..a[0].width {
                let [va, ca, pa, na] = [0, 1, 2, 3].map(|i| a[i].at(x, y));
                let [vb, cb, pb, nb] = [0, 1, 2, 3].map(|i| b[i].at(x, y));
                if pa[0].is_nan() {
                    // the background: the forward form's clear values
                    background += 1;
                    assert!(pb.iter().chain(&nb).all(|v| v.is_nan()), "{what} ({x}, {y}): {pb:?} {nb:?}");
                    assert_eq!((va[0], ca), (vb[0], cb), "{what} ({x}, {y})");
                    continue;
                }
                assert_eq!(pa.map(f32::to_bits), pb.map(f32::to_bits), "{what} ({x}, {y}): position");
                for (u, v) in na.iter().zip(&nb) {
                    assert!(
                        (u - v).abs() <= u.abs().max(v.abs()) * 2f32.powi(-10),
                        "{what} ({x}, {y}): normal {na:?} {nb:?}"
                    );
                }
                let d = (va[0] - vb[0]).abs();
                vis_max = vis_max.max(d);
                vis_diff += usize::from(d > 0.0);
                assert!(
                    implicit_lod || va[0].to_bits() == vb[0].to_bits(),
                    "{what} ({x}, {y}): visibility {} against {}",
                    va[0],
                    vb[0]
                );
            }
        }
        eprintln!("{what}: {background} background pixels; visibility differs at {vis_diff} pixels, at most {vis_max:e}");
        assert!(
            background > 0 && background < a[0].width * a[0].height,
            "{what}: the view holds surface and background"
        );
    }
    // every technique but the two that read a light sample's view's derivatives
    // (linear-light and point-samples: `depth_slope` inside `at_sample`), which stay forward
    // the techniques whose Shade cannot be deferred, each with its reason (a new technique
    // that can be is checked with no change here; one that cannot is named)
    let forward_only: Vec<&str> = FORWARD_ONLY.iter().map(|(t, _)| *t).collect();
    assert_eq!(refused, forward_only, "deferred: {deferred_ones:?}");
    assert!(deferred_ones.len() >= 16, "{deferred_ones:?}");
}

/// Specialised for its scene, every bundled technique gives the generic build's
/// visibility bit for bit on every bundled scene whose light its `light:` list admits: what
/// the scene's light kind folds (the light inputs that are 0 for it, the local or distant
/// form of the Shade's direction to the light and texel size) is exactly what the generic
/// code computes there (x * 0 = 0, x + 0 = x, a select on a known condition), for finite x.
/// A point light, which no bundled scene has, folds the most: it is checked on the contact
/// scene with its sphere shrunk to a point.
#[test]
fn specialised_builds_give_the_generic_visibility_bit_for_bit() {
    let gpu = gpu();
    let mut checked = 0;
    let mut folded_ops = 0;
    let mut scenes: Vec<(String, Scene)> = bundled("scenes").iter().map(|n| (n.clone(), scene(n, 32, 64))).collect();
    let mut point = scene("contact", 32, 64);
    let centre = match point.lights[0] {
        sshc_lab::scene::Light::Sphere { center, .. } => center,
        ref other => panic!("contact's light is a sphere, not {other:?}"),
    };
    point.lights[0] = sshc_lab::scene::Light::Point { position: centre };
    scenes.push(("contact with a point light".into(), point));
    for t in bundled("techniques") {
        let src = std::fs::read_to_string(root().join("techniques").join(format!("{t}.ron"))).unwrap();
        let generic = compile(&t, &[]);
        for (name, s) in &scenes {
            let kind = s.lights[0].kind();
            let facts = sshc::SceneFacts {
                scene: name.clone(),
                light: kind,
                depth_floor: None,
            };
            let opts = sshc::CompileOptions {
                scene: Some(facts.clone()),
                ..Default::default()
            };
            if !sshc::admits(&src, kind) {
                let e = sshc::compile_str(&src, &opts).expect_err("refused");
                assert!(e.render(&t, &src).contains("does not admit the"), "{t} on {name}");
                continue;
            }
            // per-sample techniques need a light they can sample, the others one view
            let Ok(inputs) = sshc_lab::bind::scene_inputs_for(s, &generic.graph) else {
                continue;
            };
            let special = sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render(&t, &src)));
            assert_eq!(special.graph.specialised.as_ref(), Some(&facts));
            let visibility = |c: &sshc::Compiled| {
                let ex = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
                let mut ex = ex.bind_scene(&inputs).unwrap_or_else(|e| panic!("{t} on {name}: {e}"));
                ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
                ex.inspect().read_camera(CameraOutput::Visibility).unwrap().channel(0)
            };
            same_bits(&visibility(&generic), &visibility(&special), &format!("{t} on {name}"));
            // never more work, per pass
            for (g, p) in generic.cost.passes.iter().zip(&special.cost.passes) {
                assert!(p.3.ops <= g.3.ops && p.3.fetches <= g.3.fetches, "{t} on {name}: {g:?} {p:?}");
                folded_ops += g.3.ops - p.3.ops;
            }
            checked += 1;
        }
    }
    eprintln!("{checked} technique-scene pairs; {folded_ops} operations per invocation folded in all");
    assert!(checked >= 40 && folded_ops > 0, "{checked} {folded_ops}");
}

/// PCG3D (Jarzynski & Olano 2020, section 2), as `noise` states it: the CPU reference.
fn pcg3d_noise(x: i32, y: i32, k: i32) -> f32 {
    let mut v = [x as u32, y as u32, k as u32].map(|c| c.wrapping_mul(1_664_525).wrapping_add(1_013_904_223));
    let mix = |v: &mut [u32; 3]| {
        v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[2]));
        v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
        v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    };
    mix(&mut v);
    for c in &mut v {
        *c ^= *c >> 16;
    }
    mix(&mut v);
    (v[0] >> 8) as f32 / 16_777_216.0
}

/// Renders the visibility expression `visibility` (over a depth channel `z`) on the contact
/// scene under each Shade schedule, frames 0 and 1, and asserts that every lit pixel
/// holds the CPU reference `pcg3d_noise(x, y, frame)` bit for bit (24 bits of an integer,
/// exact in f32), and that most surface pixels are lit.
fn assert_pcg3d_per_pixel(visibility: &str, schedules: &[&str]) {
    let gpu = gpu();
    let src = format!(
        r#"Technique(
    name: "hashed",
    channels: {{ "z": Channel(precision: F32) }},
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Shade(name: "shade", reads: ["shadow"], visibility: "{visibility}"),
    ],
)"#
    );
    let s = scene("contact", 32, 64);
    for schedule in schedules {
        let opts = sshc::CompileOptions {
            schedule: vec![("shade".into(), schedule.to_string())],
            ..Default::default()
        };
        let c = sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render("hashed.ron", &src)));
        let ex = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
        let mut ex = ex.bind_scene(&sshc_lab::bind::scene_inputs_for(&s, &c.graph).unwrap()).unwrap();
        for frame in 0..2 {
            ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
            let vis = ex.inspect().read_camera(CameraOutput::Visibility).unwrap();
            let pos = ex.inspect().read_camera(CameraOutput::Position).unwrap();
            let (mut lit, mut surface) = (0, 0);
            for y in 0..vis.height {
                for x in 0..vis.width {
                    if pos.at(x, y)[0].is_nan() {
                        continue;
                    }
                    surface += 1;
                    let v = vis.at(x, y)[0];
                    // 0 where the receiver faces away from the light
                    if v != 0.0 {
                        lit += 1;
                        let want = pcg3d_noise(x as i32, y as i32, frame);
                        assert_eq!(
                            v.to_bits(),
                            want.to_bits(),
                            "{schedule}, frame {frame}, ({x}, {y}): {v} against {want}"
                        );
                    }
                }
            }
            assert!(2 * lit > surface, "{schedule}: {lit} of {surface} pixels lit");
        }
    }
}

/// The `pixel` and `frame` inputs and `noise`: a Shade whose visibility is
/// `noise(pixel.x, pixel.y, f32(frame))` gives, at every pixel it lights, the CPU
/// reference of the stated hash, for frames 0 and 1, forward and deferred.
#[test]
fn pixel_frame_and_noise_give_the_stated_hash_per_pixel_and_frame() {
    assert_pcg3d_per_pixel("noise(pixel.x, pixel.y, f32(frame)) + 0.0 * nearest(z)", &["fragment", "compute"]);
}

/// `u32` and the bit operators on the GPU: PCG3D written in the language
/// (wrapping products, `^`, `>>`, conversions between f32, i32 and u32) gives the
/// built-in `noise` bit for bit, at every lit pixel of frames 0 and 1; its arithmetic
/// `>>` of an i32 and its `&`, `|`, `~` on i32 bits give the CPU's values too (a wrong
/// one turns the visibility into 2, clamped to 1, which is not the hash).
#[test]
fn a_hash_written_with_u32_operations_matches_the_builtin_noise() {
    let hash = "let hx = u32(i32(floor(pixel.x))) * 1664525u + 1013904223u; \
         let hy = u32(i32(floor(pixel.y))) * 1664525u + 1013904223u; \
         let hk = u32(frame) * 1664525u + 1013904223u; \
         let ax = hx + hy * hk; let ay = hy + hk * ax; let ak = hk + ax * ay; \
         let bx = ax ^ (ax >> 16u); let by = ay ^ (ay >> 16u); let bk = ak ^ (ak >> 16u); \
         let cx = bx + by * bk; \
         let s = -i32(pixel.x) - 1; \
         let ok = (s >> 1u) == -((i32(pixel.x) + 2) / 2) && (~s) == i32(pixel.x) && (s & 1) == (1 - (i32(pixel.x) & 1)) && (s | 1) == select(s, s + 1, (s & 1) == 0); \
         select(2.0, f32(cx >> 8u) / 16777216.0, ok) + 0.0 * nearest(z)";
    assert_pcg3d_per_pixel(hash, &["fragment"]);
}

/// `sample_at(ch, du, dv)`: a bilinear tap at an offset. One texel to the right,
/// it is the bilinear blend of the four texels one to the right of the receiver's, with
/// the receiver's own weights `tf`, up to the GPU's filtering precision: Vulkan gives
/// bilinear weights at least 8 bits (lavapipe 8), so a weight is off by at most 2^-8 and
/// the blend of depths in [0, 1] by at most 2^-8, plus f32 rounding.
#[test]
fn a_bilinear_tap_at_an_offset_is_the_blend_of_the_shifted_texels() {
    let gpu = gpu();
    let technique = |vis: &str| {
        format!(
            r#"Technique(
    name: "tap",
    channels: {{ "z": Channel(precision: F32) }},
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Shade(name: "shade", reads: ["shadow"], visibility: "{vis}"),
    ],
)"#
        )
    };
    let s = scene("contact", 32, 64);
    let render = |vis: &str| {
        let src = technique(vis);
        let c = sshc::compile_str(&src, &sshc::CompileOptions::default()).unwrap_or_else(|d| panic!("{}", d.render("tap.ron", &src)));
        render(gpu, &c, &s)
    };
    let tap = render("sample_at(z, texel_size, 0.0)");
    let blend = render("mix(mix(fetch(z, 1, 0), fetch(z, 2, 0), tf.x), mix(fetch(z, 1, 1), fetch(z, 2, 1), tf.x), tf.y)");
    let (a, b) = (tap.visibility.channel(0), blend.visibility.channel(0));
    let tolerance = 2f32.powi(-8) + 4.0 * f32::EPSILON;
    let mut compared = 0;
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        // 0 where the receiver faces away; 1 on the background (both forms)
        if tap.position.rgba[i][0].is_nan() || (*x == 0.0 && *y == 0.0) {
            continue;
        }
        assert!((x - y).abs() <= tolerance, "pixel {i}: {x} against {y}");
        compared += 1;
    }
    assert!(compared > 200, "{compared}");
}

/// `neighbour(ch, dx, dy)`: a Map pass reading a 3 x 3 neighbourhood computes
/// what the Filter pass's Box 3 computes, up to the order of the sums (nine f32 additions
/// against two separable passes of three at F32: a few ulps of values in [0, 1]).
#[test]
fn a_map_over_a_neighbourhood_computes_the_box_filter() {
    let gpu = gpu();
    let technique = |passes: &str| {
        format!(
            r#"Technique(
    name: "box",
    channels: {{
        "z": Channel(precision: F32),
        "b": Channel(precision: F32, value: "sum(dy in -1..=1, sum(dx in -1..=1, neighbour(z, dx, dy))) / 9.0"),
    }},
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
{passes}
    ],
)"#
        )
    };
    let map = technique(
        r#"        Map(name: "blur", reads: ["shadow"], writes: "blurred", channels: ["b"]),
        Shade(name: "shade", reads: ["blurred"], visibility: "nearest(b)"),"#,
    );
    let filter = technique(
        r#"        Filter(name: "blur", reads: "shadow", writes: "blurred", kernel: Box(size: 3)),
        Shade(name: "shade", reads: ["blurred"], visibility: "nearest(z)"),"#,
    );
    let s = scene("contact", 32, 64);
    let vis = |src: &str, schedule: &str| {
        let opts = sshc::CompileOptions {
            schedule: vec![("blur".into(), schedule.into())],
            ..Default::default()
        };
        let c = sshc::compile_str(src, &opts).unwrap_or_else(|d| panic!("{}", d.render("box.ron", src)));
        render(gpu, &c, &s).visibility.channel(0)
    };
    let want = vis(&filter, "fragment");
    for schedule in ["fragment", "compute"] {
        let got = vis(&map, schedule);
        let worst = got.iter().zip(&want).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
        assert!(worst <= 8.0 * f32::EPSILON, "{schedule}: {worst}");
        assert!(got.iter().any(|v| *v > 0.0 && *v < 1.0), "the map holds depths");
    }
}

/// `compare_at(ch, r, dx, dy)`: the bilinear PCF tap of the bundled PCF at
/// offset (0, 0) is `compare_at(z, d - bias, 0, 0)`: the same visibility bit for bit as
/// the four tests and weights written out, and a 3 x 3 grid of taps is a 4 x 4 PCF.
#[test]
fn a_comparison_tap_at_an_offset_is_the_written_out_bilinear_test() {
    let gpu = gpu();
    let technique = |vis: &str| {
        format!(
            r#"Technique(
    name: "taps",
    params: {{ "bias": Param(ty: F32, default: 0.003) }},
    channels: {{ "z": Channel(precision: F32) }},
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Shade(name: "shade", reads: ["shadow"], visibility: "{vis}"),
    ],
)"#
        )
    };
    let s = scene("contact", 32, 64);
    let vis = |v: &str| {
        let src = technique(v);
        let c = sshc::compile_str(&src, &sshc::CompileOptions::default()).unwrap_or_else(|d| panic!("{}", d.render("taps.ron", &src)));
        render(gpu, &c, &s).visibility.channel(0)
    };
    let t = |i: i32, j: i32| format!("select(0.0, 1.0, d - bias <= fetch(z, {i}, {j}))");
    let written = format!(
        "mix(mix({}, {}, tf.x), mix({}, {}, tf.x), tf.y)",
        t(0, 0),
        t(1, 0),
        t(0, 1),
        t(1, 1)
    );
    same_bits(
        &vis("compare_at(z, d - bias, 0, 0)"),
        &vis(&written),
        "compare_at against the written-out tap",
    );
    let grid = vis("sum(j in -1..=1, sum(i in -1..=1, compare_at(z, d - bias, i, j))) / 9.0");
    assert!(grid.iter().any(|v| *v > 0.0 && *v < 1.0), "a 4 x 4 PCF has a penumbra");
}
