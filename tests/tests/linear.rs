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
    ex.read_camera(CameraOutput::Visibility).unwrap_or_else(|e| panic!("{e}")).channel(0)
}

/// The visibility, positions and normals of every camera pixel.
fn run_full(technique: &str, set: &[(&str, String)], inputs: &SceneInputs) -> (Vec<f32>, Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let compiled = compile_source(technique, &technique_source(technique), set, &[]);
    let mut ex = Executor::new(gpu(), compiled.graph, compiled.shaders).unwrap_or_else(|e| panic!("{e}"));
    ex.bind_scene(inputs).unwrap_or_else(|e| panic!("{e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    let v = ex.read_camera(CameraOutput::Visibility).unwrap_or_else(|e| panic!("{e}")).channel(0);
    let p = ex.read_camera(CameraOutput::Position).unwrap_or_else(|e| panic!("{e}")).rgba;
    let n = ex.read_camera(CameraOutput::Normal).unwrap_or_else(|e| panic!("{e}")).rgba;
    (v, p, n)
}

/// Every camera pixel of two runs equal (the same shadow tests of the same depth maps).
fn assert_same(what: &str, a: &[f32], b: &[f32]) {
    let differ = a.iter().zip(b).filter(|(x, y)| x != y).count();
    assert_eq!(differ, 0, "{what}: {differ} of {} pixels differ", a.len());
}

/// One sample at the light's centre is the hard shadow map: the same depth map (the sample's
/// view is the point light's at the centre) and the same test; its two segment weights are
/// 1 and its channels keep their initial one half, so the sum is the test itself.
#[test]
fn one_sample_is_the_hard_shadow_map() {
    let s = scene([-0.5, 2.0, 0.0], [0.5, 2.0, 0.0], 128);
    let point = scene_with("Point(position: (0.0, 2.0, 0.0))", 128);
    let hard = run(HARD, &[], &sshc_lab::bind::scene_inputs(&point).unwrap());
    for t in [LINEAR, POINTS] {
        let v = run(t, &[("N", "1".into())], &sample_inputs(&s, 1));
        assert_same(t, &v, &hard);
    }
}

/// A segment of length 0: every sample sees what the point light there sees, the skins
/// between coinciding views have no area (none is drawn), and the weights sum to 1.
#[test]
fn a_segment_of_length_zero_is_the_hard_shadow_map_for_every_n() {
    let s = scene([0.2, 2.0, 0.1], [0.2, 2.0, 0.1], 128);
    let point = scene_with("Point(position: (0.2, 2.0, 0.1))", 128);
    let hard = run(HARD, &[], &sshc_lab::bind::scene_inputs(&point).unwrap());
    for n in [2, 3, 5] {
        for t in [LINEAR, POINTS] {
            let v = run(t, &[("N", n.to_string())], &sample_inputs(&s, n));
            assert_same(&format!("{t} N={n}"), &v, &hard);
        }
    }
}

#[test]
fn smoke() {
    let s = scene([-0.5, 2.0, 0.0], [0.5, 2.0, 0.0], 256);
    let inputs = sample_inputs(&s, 2);
    let (_, pos, nrm) = run_full(HARD, &[], &inputs);
    let pts: Vec<glam::Vec3> = pos.iter().map(|p| glam::Vec3::new(p[0], p[1], p[2])).collect();
    let ns: Vec<glam::Vec3> = nrm.iter().map(|p| glam::Vec3::new(p[0], p[1], p[2])).collect();
    let vis = sshc_lab::visibility::Visibility::new(&s);
    let truth = vis.visible_fractions(&pts, &ns, &s.lights[0], 64);
    let img = |name: &str, v: &[f32]| {
        let mut bytes: Vec<u8> = b"P5 128 128 255\n".to_vec();
        bytes.extend(v.iter().map(|x| (x.clamp(0.0, 1.0) * 255.0) as u8));
        std::fs::write(format!("/tmp/lin-{name}.pgm"), bytes).unwrap();
    };
    img("truth", &truth);
    for (t, n) in [(POINTS, 2), (POINTS, 10), (LINEAR, 2), (LINEAR, 3)] {
        let inputs = sample_inputs(&s, n);
        let v = run(t, &[("N", n.to_string())], &inputs);
        img(&format!("{t}-{n}"), &v);
        let rms = (v.iter().zip(&truth).map(|(a, b)| ((a - b) as f64).powi(2)).sum::<f64>() / v.len() as f64).sqrt();
        let mean: f32 = v.iter().sum::<f32>() / v.len() as f32;
        eprintln!("{t} N={n}: mean {mean} rms {rms}");
    }
    eprintln!("truth mean {}", truth.iter().sum::<f32>() / truth.len() as f32);
}

#[test]
fn smoke_old() {
    let s = scene([-0.5, 2.0, 0.0], [0.5, 2.0, 0.0], 128);
    for (t, n) in [(POINTS, 2), (LINEAR, 2), (LINEAR, 3)] {
        let inputs = sample_inputs(&s, n);
        let v = run(t, &[("N", n.to_string())], &inputs);
        let mean: f32 = v.iter().sum::<f32>() / v.len() as f32;
        let partial = v.iter().filter(|x| **x > 0.02 && **x < 0.98).count();
        eprintln!("{t} N={n}: mean {mean} partial {partial}");
    }
    let _ = HARD;
}

#[test]
fn debug_skins() {
    let s = scene([-0.5, 2.0, 0.0], [0.5, 2.0, 0.0], 64);
    let inputs = sample_inputs(&s, 2);
    let compiled = compile_source(LINEAR, &technique_source(LINEAR), &[("N", "2".into())], &[]);
    let mut ex = Executor::new(gpu(), compiled.graph, compiled.shaders).unwrap_or_else(|e| panic!("{e}"));
    ex.bind_scene(&inputs).unwrap_or_else(|e| panic!("{e}"));
    ex.set_param("skin_threshold", 0.0).unwrap();
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    for b in ["skins_prev.skins", "skins_next.skins"] {
        eprintln!("{b}: {:?}", ex.generated(b));
    }
    for layer in 0..2 {
        let z = ex.read_texture("shadow", layer, 0).unwrap().channel(0);
        let zs: Vec<f32> = z.iter().copied().filter(|v| *v < 1.0).collect();
        eprintln!("z layer {layer}: {} covered, min {:?}", zs.len(), zs.iter().cloned().fold(f32::INFINITY, f32::min));
        for t in ["vis_prev", "vis_next"] {
            let v = ex.read_texture(t, layer, 0).unwrap().channel(0);
            eprintln!("{t} layer {layer}: {} below 1", v.iter().filter(|x| **x < 1.0).count());
        }
    }
}
