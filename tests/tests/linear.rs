//! Soft shadow maps for linear lights (`techniques/linear-light.ron`; Heidrich, Brabec &
//! Seidel 2000) and N point samples (`techniques/point-samples.ron`) as the compiler
//! generates them, run on a GPU (lavapipe without one), against the limits the issue
//! states: one sample is the hard shadow map; a segment of length 0 is the hard shadow map
//! for every N; no NaN or infinity where skins degenerate; no cracks between skins.

mod support;

use sshc_lab::run::{Bound, Loaded};
use sshc_lab::scene::Scene;
use sshc_runtime::gpu::{CameraOutput, SceneInputs};
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
    let ex = Loaded::new(gpu(), compiled.graph, compiled.shaders).unwrap_or_else(|e| panic!("{e}"));
    let mut ex = ex.bind_scene(inputs).unwrap_or_else(|e| panic!("{e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    ex.inspect()
        .read_camera(CameraOutput::Visibility)
        .unwrap_or_else(|e| panic!("{e}"))
        .channel(0)
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

/// A scene of a blocker strip (x in [x0, x1], z within +-`z_half`) 1 above a casting floor,
/// under a segment light from (-0.5, 2, 0) to (0.5, 2, 0), and its inputs with `n` samples.
fn strip(x0: f32, x1: f32, z_half: f32, shadow: u32, n: u32) -> (Scene, SceneInputs) {
    let text = format!(
        "Scene(
    camera: Orthographic(position: (0.0, 3.0, 0.0), target: (0.0, 0.0, 0.0), up: (0.0, 0.0, -1.0),
        half_height: 1.5, width: 128, height: 128),
    shadow_map: {shadow},
    lights: [Segment(a: (-0.5, 2.0, 0.0), b: (0.5, 2.0, 0.0))],
    objects: [
        Object(name: \"floor\", mesh: Plane(size: (4.0, 4.0))),
        Object(name: \"blocker\", mesh: Quad(a: ({x0:?}, 1.0, {zl:?}), b: ({x0:?}, 1.0, {z_half:?}), c: ({x1:?}, 1.0, {z_half:?}), d: ({x1:?}, 1.0, {zl:?}))),
    ],
)",
        zl = -z_half
    );
    let s = Scene::from_str(&text, root().join("scenes")).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let inputs = sample_inputs(&s, n);
    (s, inputs)
}

/// The executor after one frame of `technique` with `set`.
fn frame(technique: &str, set: &[(&str, String)], inputs: &SceneInputs) -> Bound {
    let compiled = compile_source(technique, &technique_source(technique), set, &[]);
    let ex = Loaded::new(gpu(), compiled.graph, compiled.shaders).unwrap_or_else(|e| panic!("{e}"));
    let mut ex = ex.bind_scene(inputs).unwrap_or_else(|e| panic!("{e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    ex
}

/// Every visibility channel of every sample finite and in [0, 1] (stored), and the camera's
/// visibility too (`read_camera` refuses a non-finite value or one outside [0, 1]).
fn assert_finite(what: &str, ex: &Bound, n: u32) {
    ex.inspect()
        .read_camera(CameraOutput::Visibility)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    for t in ["vis_prev", "vis_next"] {
        for k in 0..n {
            let v = ex.inspect().read_texture(t, k, 0).unwrap_or_else(|e| panic!("{e}")).channel(0);
            assert!(
                v.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)),
                "{what}: {t} of sample {k}"
            );
        }
    }
}

/// Where a skin degenerates: an occluder edge parallel to the segment (its skins are seen
/// edge-on from the other sample; the strip's ends), an occluder narrower than a texel,
/// and an occluder reaching past the map's border (discontinuities on the border texels):
/// no NaN, no infinity, nothing outside [0, 1], at 2 and 3 samples.
#[test]
fn degenerate_skins_stay_finite() {
    let cases = [
        ("parallel edges", strip(-0.4, 0.4, 0.6, 64, 2).1),
        // 0.01 wide: a fraction of a texel of a 64-texel map over the scene
        ("one texel wide", strip(-0.005, 0.005, 0.6, 64, 3).1),
        ("past the border", strip(-0.4, 3.0, 3.0, 64, 2).1),
    ];
    for (what, inputs) in cases {
        let n = inputs.samples.len() as u32;
        let ex = frame(LINEAR, &[("N", n.to_string())], &inputs);
        assert_finite(what, &ex, n);
    }
}

/// No cracks between skins: along a long straight edge perpendicular to the light, every
/// floor texel of sample 0's map that lies between covered texels (its two neighbours along
/// a row or a column both hold a skin) holds one too. The mesh of texel centres shares its
/// vertices between neighbouring cells, so adjacent skins meet exactly; a gap would leave
/// a texel at its cleared value (1) inside the skinned band. (Dropping every seventh cell's
/// first triangle leaves 257 such texels.)
///
/// And the skins' values: the strip's left edge (x = -0.4, 1 above the floor) under the
/// segment from x = -0.5 to 0.5 (2 above) leaves floor point x the light's part left of
/// x = -0.8 - x: V(x) = clamp(-0.3 - x, 0, 1), linear between x = -1.3 and -0.3, where only
/// sample 0 sees the floor. Light and floor are parallel, so eq. 1 is linear and the
/// technique's linear transition is exact but for: where the skins end (their corners at
/// texel centres: half a texel at each end), the nearest-texel lookup (half a texel), the
/// Unorm8 storage of half the value (2 / 255 in V), and Gouraud interpolation in the
/// sample's image rather than on the floor (the sample's view is tilted; bounded from the
/// clip w of the band's two ends, below).
#[test]
fn skins_leave_no_cracks_along_a_straight_edge() {
    let shadow = 256;
    let (_, inputs) = strip(-0.4, 0.4, 1.5, shadow, 2);
    let ex = frame(LINEAR, &[("N", "2".into())], &inputs);
    // sample 0's v_next: the skins of sample 1 warped into view 0
    let v = ex.inspect().read_texture("vis_next", 0, 0).unwrap().channel(0);
    let z = ex.inspect().read_texture("shadow", 0, 0).unwrap().channel(0);
    let n = shadow as usize;
    let covered = |x: usize, y: usize| v[y * n + x] < 0.75;
    // the floor's texels: the floor lies a whole unit behind the strip (a quarter of the
    // map's depth range or more), and texels at 1 see nothing; skins are hidden behind the
    // strip itself, so its texels cannot be cracks
    let nearest = z.iter().copied().fold(f32::INFINITY, f32::min);
    let floor = |x: usize, y: usize| z[y * n + x] > nearest + 0.1 && z[y * n + x] < 1.0;
    let (mut holes, mut skinned) = (0, 0);
    for y in 1..n - 1 {
        for x in 1..n - 1 {
            skinned += usize::from(covered(x, y));
            let between = (covered(x - 1, y) && covered(x + 1, y)) || (covered(x, y - 1) && covered(x, y + 1));
            if between && floor(x, y) && !covered(x, y) {
                holes += 1;
            }
        }
    }
    assert!(skinned > 1000, "{skinned} skinned texels");
    assert_eq!(holes, 0, "{holes} texels left bare between skins");

    // the visibility across the left penumbra
    let view = &inputs.samples[0];
    let vp = glam::Mat4::from_cols_array(&view.light_view_proj);
    let w = |x: f32| (vp * glam::Vec4::new(x, 0.0, 0.0, 1.0)).w;
    let (wa, wb) = (w(-1.3), w(-0.3));
    // screen-linear t against floor-linear s: s = t wb / ((1 - t) wa + t wb)
    let projective = (0..=1000)
        .map(|i| {
            let t = i as f32 / 1000.0;
            (t * wb / ((1.0 - t) * wa + t * wb) - t).abs()
        })
        .fold(0.0f32, f32::max);
    // one texel of the map on the floor (its widest, at the band's far end; view distance
    // is the clip w) over the penumbra's width 1.0: the skins' ends and the lookup, 1.5
    // texels in all
    let texel = 2.0 * w(-1.3) / (view.light_proj_y * shadow as f32);
    let tol = 1.5 * texel + 2.0 / 255.0 + projective;
    let vis = ex.inspect().read_camera(CameraOutput::Visibility).unwrap().channel(0);
    let pos = ex.inspect().read_camera(CameraOutput::Position).unwrap().rgba;
    let (mut worst, mut count) = (0.0f32, 0);
    for (v, p) in vis.iter().zip(&pos) {
        // the floor, inside the band (a margin at each end), away from the strip's ends
        if !(p[1].abs() < 1e-3 && (-1.3 + 0.02..=-0.3 - 0.02).contains(&p[0]) && p[2].abs() < 1.0) {
            continue;
        }
        let want = (-0.3 - p[0]).clamp(0.0, 1.0);
        worst = worst.max((v - want).abs());
        count += 1;
    }
    assert!(count > 500, "{count} pixels in the band");
    assert!(
        worst <= tol,
        "worst {worst} over {count} pixels, tolerance {tol} (texel {texel}, projective {projective})"
    );
}

/// The technique's channels against the independent f64 reference (tests/src/reference/
/// linear.rs, written from the paper), fed the technique's own depth maps so that both warp
/// the same discontinuities: texel by texel, which texels a skin covers and the value it
/// leaves, at 2 and 3 samples, on the strip (a straight edge across the light) and on
/// `scenes/linear.ron` (edges at several angles, a raised corner), and at 4 and 8 samples
/// around the rectangle light of `scenes/linear-rectangle.ron` (a closed chain).
///
/// Tolerances: the technique stores half the skin's value in Unorm8, so a covered texel's
/// value is off by at most 1/255 after decoding; the f32 interpolation against f64 adds
/// far less (the reference's own f32 twin agrees within 1.3e-6). Texels whose centre lies on
/// a skin's edge (within f32 rounding) may be covered by one and not the other, and a texel
/// where two skins lie within f32 rounding of each other in depth (at an occluder's rim,
/// where a skin's occluder end meets the next one's) may take either's value: such texels
/// are counted, at most 1 % of the covered texels plus 2 (one texel of the 8-sample
/// rectangle takes 0.27 against the reference's 0.0008 there).
#[test]
fn the_channels_agree_with_the_f64_reference() {
    use sshc_tests::reference::linear::{Interpolation, LinearSetup, LinearView, linear_maps_from_depth};
    let strip_scene = strip(-0.4, 0.4, 1.5, 64, 2).0;
    let load = |name: &str| {
        let mut s = Scene::load(root().join("scenes").join(name)).unwrap_or_else(|e| panic!("{e}"));
        s.shadow_map = 64;
        s.set_camera_size(32, 32);
        s
    };
    let (segment, rectangle) = (load("linear.ron"), load("linear-rectangle.ron"));
    // the rectangle's edges close the chain: every sample has both neighbours
    let cases: [(&str, &Scene, &[u32]); 3] = [
        ("strip", &strip_scene, &[2, 3]),
        ("linear.ron", &segment, &[2, 3]),
        ("linear-rectangle.ron", &rectangle, &[4, 8]),
    ];
    for (what, s, ns) in cases {
        for &n in ns {
            let inputs = sample_inputs(s, n);
            let ex = frame(LINEAR, &[("N", n.to_string())], &inputs);
            let size = s.shadow_map as usize;
            let depth: Vec<Vec<f64>> = (0..n)
                .map(|k| {
                    ex.inspect()
                        .read_texture("shadow", k, 0)
                        .unwrap()
                        .channel(0)
                        .iter()
                        .map(|&z| f64::from(z))
                        .collect()
                })
                .collect();
            let setup = LinearSetup {
                views: inputs.samples.iter().map(LinearView::from_sample).collect(),
                closed: inputs.samples_closed,
                size,
                skin_threshold: 0.02,
                keep_bias: 0.005,
                bias: 0.0005,
                interpolation: Interpolation::Screen,
            };
            let maps = linear_maps_from_depth(depth, &setup).unwrap_or_else(|e| panic!("{e}"));
            for (texture, reference) in [("vis_prev", &maps.v_prev), ("vis_next", &maps.v_next)] {
                for (k, want) in reference.iter().enumerate() {
                    let got = ex.inspect().read_texture(texture, k as u32, 0).unwrap().channel(0);
                    // a texel's value is within the Unorm8 step of the reference's, or the
                    // texel counts as a different winner (below)
                    let tol = 1.0 / 255.0 + 1e-5;
                    let (mut covered, mut differ) = (0usize, 0usize);
                    for (t, g) in got.iter().enumerate() {
                        let (ours, theirs) = (*g < 0.75, want.winner[t].is_some());
                        covered += usize::from(ours || theirs);
                        if ours != theirs || (ours && (2.0 * f64::from(*g) - want.value[t]).abs() > tol) {
                            differ += 1;
                        }
                    }
                    let label = format!("{what}, N = {n}, {texture} of sample {k}");
                    // an end of the open chain has no neighbour on that side: nothing to warp
                    let neighbour = inputs.samples_closed || if texture == "vis_prev" { k > 0 } else { k + 1 < n as usize };
                    assert_eq!(covered > 20, neighbour, "{label}: {covered} texels covered");
                    assert!(differ <= 2 + covered / 100, "{label}: {differ} of {covered} texels differ");
                }
            }
        }
    }
}
