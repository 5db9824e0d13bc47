//! GPU tests on a real adapter (lavapipe on machines without a GPU). They never skip: with
//! no adapter they fail and name what to install (`scripts/test.sh` installs it).

use glam::Vec3;
use sshc_runtime::gpu::{CameraOutput, Executor, Gpu, Image, RuntimeError};
use sshc_runtime::scene::Scene;
use sshc_runtime::visibility::Visibility;
use std::path::{Path, PathBuf};

fn gpu() -> Gpu {
    Gpu::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"))
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

const SCENES: [&str; 5] = ["bunny", "contact", "fence", "edge", "triangle"];
const TECHNIQUES: [&str; 5] = ["hard", "pcf", "vsm", "esm", "csm"];

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
    let mut ex = Executor::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
    ex.bind_scene(&sshc_runtime::bind::scene_inputs(s).unwrap())
        .unwrap_or_else(|e| panic!("{e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    Frame {
        visibility: ex.read_camera(CameraOutput::Visibility).unwrap(),
        position: ex.read_camera(CameraOutput::Position).unwrap(),
        normal: ex.read_camera(CameraOutput::Normal).unwrap(),
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

/// Points on the receiver's tangent plane around `p`, `r` away.
fn ring(p: Vec3, n: Vec3, r: f32) -> Vec<Vec3> {
    let t = n.any_orthonormal_vector();
    let b = n.cross(t);
    (0..8)
        .map(|i| {
            let a = i as f32 * std::f32::consts::FRAC_PI_4;
            p + (t * a.cos() + b * a.sin()) * r
        })
        .collect()
}

/// Shaded points whose light-centre visibility is the same everywhere within `footprint`
/// shadow-map texels: (pixel, hidden).
fn unambiguous(s: &Scene, f: &Frame, footprint: f32) -> Vec<(usize, bool)> {
    let vis = Visibility::new(s);
    let mut out = Vec::new();
    for (i, (pp, nn)) in f.position.rgba.iter().zip(&f.normal.rgba).enumerate() {
        if pp[0].is_nan() {
            continue;
        }
        let p = Vec3::new(pp[0], pp[1], pp[2]);
        let n = Vec3::new(nn[0], nn[1], nn[2]).normalize_or_zero();
        let to_light = match s.lights[0].center() {
            Some(c) => (c - p).normalize_or_zero(),
            None => s.lights[0].direction().unwrap_or(Vec3::Y),
        };
        // grazing receivers are ambiguous for every shadow map
        if n.dot(to_light) < 0.3 {
            continue;
        }
        let r = texel_world(s, p) * footprint;
        let h = centre_hidden(&vis, s, p, n);
        if ring(p, n, r)
            .into_iter()
            .chain(ring(p, n, 0.5 * r))
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
    for t in TECHNIQUES {
        let c = compile(t, &[]);
        for sc in SCENES {
            let s = scene(sc, 48, 256);
            let f = render(&gpu, &c, &s);
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
}

#[test]
fn hard_shadow_map_is_zero_where_the_light_centre_is_hidden_and_one_where_it_is_seen() {
    // Binary test of Annen eq. 3.2: exact away from the footprint of an edge. The footprint
    // is the nearest texel plus the slope-scaled bias (1.5 texels per unit slope, slope <=
    // tan(acos 0.3) = 3.2): 6 texels covers both.
    let gpu = gpu();
    let c = compile("hard", &[]);
    for sc in SCENES {
        let s = scene(sc, 48, 512);
        let f = render(&gpu, &c, &s);
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
}

#[test]
fn pcf_is_one_where_lit_and_zero_where_hidden_beyond_its_footprint() {
    // N x N bilinear taps reach N/2 + 1 texels, plus the bias (scaled by the same): with
    // N = 3 a footprint of 10 texels is safely outside every tap.
    let gpu = gpu();
    let c = compile("pcf", &[("N", "3")]);
    for sc in SCENES {
        let s = scene(sc, 48, 512);
        let f = render(&gpu, &c, &s);
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
        let f = render(&gpu, &c, &s);
        assert!(
            f.visibility.channel(0).iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)),
            "shadow map {n}"
        );
    }
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
    Executor::load(&gpu, &ok).unwrap_or_else(|e| panic!("{e}"));

    // Another schema version.
    let g = write_compiled(&c, &base.join("version"));
    let text = std::fs::read_to_string(&g).unwrap().replacen("version: 1", "version: 2", 1);
    std::fs::write(&g, text).unwrap();
    let e = Executor::load(&gpu, &g).err().expect("version 2 must be refused");
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
    let e = Executor::load(&gpu, &g).err().expect("a path leaving the folder must be refused");
    assert!(matches!(e, RuntimeError::Graph(sshc_runtime::GraphError::Path { .. })), "{e}");

    // A link that leaves the folder.
    let g = write_compiled(&c, &base.join("link"));
    let shade = g.parent().unwrap().join("hard.shade.wgsl");
    std::fs::remove_file(&shade).unwrap();
    std::os::unix::fs::symlink(base.join("ok").join("hard.shade.wgsl"), &shade).unwrap();
    let e = Executor::load(&gpu, &g).err().expect("a link leaving the folder must be refused");
    assert!(e.to_string().contains("outside the graph's folder"), "{e}");

    // A shader that does not validate.
    let g = write_compiled(&c, &base.join("shader"));
    let shade = g.parent().unwrap().join("hard.shade.wgsl");
    let text = std::fs::read_to_string(&shade).unwrap().replace("let vis = ", "let vis: i32 = ");
    std::fs::write(&shade, text).unwrap();
    let e = Executor::load(&gpu, &g).err().expect("an invalid shader must be refused");
    assert!(matches!(e, RuntimeError::Shader { .. }), "{e}");

    // A shadow map one texel above the device's limit is refused before allocation.
    let mut ex = Executor::load(&gpu, &ok).unwrap();
    let mut s = scene("contact", 16, 16);
    s.shadow_map = gpu.limits.max_texture_dimension_2d + 1;
    let e = ex
        .bind_scene(&sshc_runtime::bind::scene_inputs(&s).unwrap())
        .err()
        .expect("over the limit");
    assert!(
        matches!(e, RuntimeError::Limit { needed, limit, .. } if needed == limit as u64 + 1 || needed == limit + 1),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&base);
}
