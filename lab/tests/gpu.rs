//! Two-sided surfaces on a real adapter (lavapipe without a GPU; nextest's `gpu` group):
//! an open mesh, a single quad, lit from above. Seen from above it is lit; seen from below
//! (the side facing away from the light) it is shadowed by its own surface, in every
//! bundled technique and in the ground truth alike (the scene format's convention,
//! scenes/README.md). Before, both read the back of a one-sided surface as lit.

use std::path::Path;

use glam::Vec3;
use sshc_lab::scene::Scene;
use sshc_lab::session::{compile_executor, positions_normals};
use sshc_lab::visibility::Visibility;
use sshc_runtime::gpu::{CameraOutput, Gpu};

const TECHNIQUES: [&str; 7] = ["hard", "pcf", "vsm", "esm", "csm", "pcss", "cssm"];

fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

/// A 2 x 2 quad at y = 0 under a sphere light, seen by a camera at `eye`.
fn quad_scene(eye: Vec3) -> Scene {
    let text = format!(
        "Scene(camera: Perspective(position: ({}, {}, {}), target: (0.0, 0.0, 0.0), fov_y_degrees: 30.0, width: 16, height: 16),
               shadow_map: 64,
               lights: [Sphere(center: (0.2, 2.0, 0.1), radius: 0.2)],
               objects: [Object(name: \"quad\", mesh: Quad(a: (-1.0, 0.0, -1.0), b: (-1.0, 0.0, 1.0), c: (1.0, 0.0, 1.0), d: (1.0, 0.0, -1.0)))])",
        eye.x, eye.y, eye.z
    );
    Scene::from_str(&text, ".").unwrap_or_else(|e| panic!("{e}"))
}

/// Per pixel showing the quad: the technique's visibility, the camera pass's normal and
/// the truth at its position and normal.
fn render(gpu: &Gpu, technique: &str, scene: &Scene) -> Vec<(f32, Vec3, f32)> {
    let path = root().join("techniques").join(format!("{technique}.ron"));
    let source = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut ex = compile_executor(gpu, &path, &source, &[], &[]).unwrap_or_else(|e| panic!("{technique}: {e}"));
    let inputs = sshc_lab::bind::scene_inputs(scene).unwrap();
    ex.bind_scene(&inputs).unwrap_or_else(|e| panic!("{technique}: {e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{technique}: {e}"));
    let vis = ex
        .read_camera(CameraOutput::Visibility)
        .unwrap_or_else(|e| panic!("{technique}: {e}"));
    let (positions, normals) = positions_normals(&ex).unwrap();
    let truth = Visibility::new(scene).visible_fractions(&positions, &normals, &scene.lights[0], 8);
    positions
        .iter()
        .enumerate()
        .filter(|(_, p)| p.is_finite())
        .map(|(i, _)| (vis.rgba[i][0], normals[i], truth[i]))
        .collect()
}

#[test]
fn an_open_quad_is_shadowed_seen_from_behind_and_lit_seen_from_the_front() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("no adapter (install lavapipe): {e}"));
    let below = quad_scene(Vec3::new(0.3, -3.0, 0.8));
    let above = quad_scene(Vec3::new(0.3, 3.0, 0.8));
    for t in TECHNIQUES {
        let seen = render(&gpu, t, &below);
        assert!(seen.len() > 100, "{t}: the camera below sees {} pixels of the quad", seen.len());
        for &(v, n, truth) in &seen {
            // The camera pass turns the normal to the side the camera sees.
            assert!(n.y < -0.99, "{t}, from below: normal {n} should face down, to the camera");
            assert_eq!(v, 0.0, "{t}, from below: the back of the quad reads {v}, a light leak");
            assert_eq!(truth, 0.0, "{t}, from below: the truth reads {truth}");
        }
        let seen = render(&gpu, t, &above);
        assert!(seen.len() > 100, "{t}: the camera above sees {} pixels of the quad", seen.len());
        let mean = seen.iter().map(|s| f64::from(s.0)).sum::<f64>() / seen.len() as f64;
        for &(_, n, truth) in &seen {
            assert!(n.y > 0.99, "{t}, from above: normal {n} should face up, to the camera");
            assert_eq!(truth, 1.0, "{t}, from above: nothing lies between the quad and the light");
        }
        // Nothing lies between the quad and the light: only a technique's own bias
        // (self-shadowing of the quad's depth) can darken it.
        eprintln!("{t}: mean visibility from above {mean:.4}");
        assert!(mean > 0.9, "{t}, from above: mean visibility {mean}, the quad should be lit");
    }
}
