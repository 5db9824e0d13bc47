//! Soft shadow maps for linear lights (`techniques/linear-light.ron`; Heidrich, Brabec &
//! Seidel 2000) and N point samples (`techniques/point-samples.ron`) as the compiler
//! generates them, run on a GPU (lavapipe without one), against the limits the issue
//! states: one sample is the hard shadow map; a segment of length 0 is the hard shadow map
//! for every N; no NaN or infinity where skins degenerate; no cracks between skins.

mod support;

use sshc_lab::scene::Scene;
use sshc_runtime::gpu::{CameraOutput, Executor, SceneInputs};
use support::{compile_source, gpu, root, technique_source};

const LINEAR: &str = "linear-light";
const POINTS: &str = "point-samples";
const HARD: &str = "hard";

/// A blocker (a quad) 1 above a floor, under `light`; the floor casts, so that the sample
/// maps hold the receiver (skins join an occluder to the receiver behind it, section 3.2).
fn scene_with(light: &str, shadow: u32) -> Scene {
    let text = format!(
        "Scene(
    camera: Orthographic(position: (0.0, 3.0, 0.0), target: (0.0, 0.0, 0.0), up: (0.0, 0.0, -1.0),
        half_height: 1.0, width: 128, height: 128),
    shadow_map: {shadow},
    lights: [{light}],
    objects: [
        Object(name: \"floor\", mesh: Plane(size: (4.0, 4.0))),
        Object(name: \"blocker\", mesh: Quad(a: (-0.4, 1.0, -0.3), b: (-0.4, 1.0, 0.3), c: (0.4, 1.0, 0.3), d: (0.4, 1.0, -0.3))),
    ],
)"
    );
    Scene::from_str(&text, root().join("scenes")).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// [`scene_with`] under a segment light from `a` to `b`.
fn scene(a: [f32; 3], b: [f32; 3], shadow: u32) -> Scene {
    let t = |p: [f32; 3]| format!("({:?}, {:?}, {:?})", p[0], p[1], p[2]);
    scene_with(&format!("Segment(a: {}, b: {})", t(a), t(b)), shadow)
}

/// The scene's inputs with `n` light-sample views along its light.
fn sample_inputs(scene: &Scene, n: u32) -> SceneInputs {
    sshc_lab::bind::scene_inputs_with_samples(scene, n).unwrap_or_else(|e| panic!("{e}"))
}

/// The visibility of every camera pixel.
fn run(technique: &str, set: &[(&str, String)], inputs: &SceneInputs) -> Vec<f32> {
    let compiled = compile_source(technique, &technique_source(technique), set, &[]);
    let mut ex = Executor::new(gpu(), compiled.graph, compiled.shaders).unwrap_or_else(|e| panic!("{e}"));
    ex.bind_scene(inputs).unwrap_or_else(|e| panic!("{e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    ex.read_camera(CameraOutput::Visibility)
        .unwrap_or_else(|e| panic!("{e}"))
        .channel(0)
}
