//! Penumbra limit maps and smoothies (`techniques/penumbra-limit-maps.ron`,
//! `techniques/smoothies.ron`; Lawlor 2006) as the compiler generates them, run on a GPU
//! (lavapipe without one), against the limits the paper states: exact for a straight edge
//! under a distant disk up to depth quantisation (section 4), the hard shadow map when the
//! light has no size, and finite values in [0, 1] where the receiver meets the occluder's
//! depth (z - c -> 0) and on the edge's line (p_i -> 0).

mod support;

use sshc_lab::run::{Bound, Loaded};
use sshc_lab::scene::Scene;
use sshc_runtime::gpu::CameraOutput;
use sshc_tests::reference::Storage;
use sshc_tests::reference::penumbra::{AreaLight, LightProjection, PenumbraSetup, Resolve};
use sshc_tests::reference::plm;
use support::{compile_source, gpu, root, technique_source};

const PLM: &str = "penumbra-limit-maps";
const SMOOTHIES: &str = "smoothies";

/// The visibility and world positions of every camera pixel, and the executor.
fn run(technique: &str, scene: &Scene, precision: &[(&str, &str)]) -> (Vec<f32>, Vec<[f32; 3]>, Bound) {
    run_set(technique, scene, &[], precision)
}

/// [`run`] with params set (`--set NAME=VALUE`).
fn run_set(technique: &str, scene: &Scene, set: &[(&str, String)], precision: &[(&str, &str)]) -> (Vec<f32>, Vec<[f32; 3]>, Bound) {
    let compiled = compile_source(technique, &technique_source(technique), set, precision);
    let ex = Loaded::new(gpu(), compiled.graph, compiled.shaders).unwrap_or_else(|e| panic!("{e}"));
    let inputs = sshc_lab::bind::scene_inputs(scene).unwrap_or_else(|e| panic!("{e}"));
    let mut ex = ex.bind_scene(&inputs).unwrap_or_else(|e| panic!("{e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    let vis = ex
        .inspect()
        .read_camera(CameraOutput::Visibility)
        .unwrap_or_else(|e| panic!("{e}"))
        .channel(0);
    let pos = ex.inspect().read_camera(CameraOutput::Position).unwrap_or_else(|e| panic!("{e}"));
    let pos = pos.rgba.iter().map(|p| [p[0], p[1], p[2]]).collect();
    (vis, pos, ex)
}

/// `scenes/edge.ron` with its shadow-map size and light angle replaced.
fn edge(shadow: u32, angle: f32) -> Scene {
    let text = std::fs::read_to_string(root().join("scenes/edge.ron")).unwrap_or_else(|e| panic!("{e}"));
    let text = text
        .replace("shadow_map: 512", &format!("shadow_map: {shadow}"))
        .replace("angle_degrees: 10.0", &format!("angle_degrees: {angle:?}"));
    Scene::from_str(&text, root().join("scenes")).unwrap_or_else(|e| panic!("{e}"))
}

/// The fraction of a uniform disk visible beside a straight edge: the chord at
/// u = x / (h tan(angle / 2)) from the centre, f(u) = 1/2 + (u sqrt(1 - u^2) + asin u) / pi
/// (`scenes/edge.ron`'s header).
fn closed_form(x: f64, angle_degrees: f64) -> f64 {
    let w = 1.0 * (0.5 * angle_degrees).to_radians().tan();
    let u = (x / w).clamp(-1.0, 1.0);
    0.5 + (u * (1.0 - u * u).sqrt() + u.asin()) / std::f64::consts::PI
}

/// Lawlor's claim (section 4): "up to depth quantization error penumbra limit shadows are
/// exact along straight occluder edges". The paper's storage is Unorm8: c is off by at most
/// 1/510 and p_i (stored p_i / 4 + 1/2) by 4/510; the receiver lies about 1 below the edge
/// in normalised depth, so eq. 1's l is off by at most 2/510 + 1/510 (through z - c), and
/// the disk's curve f(l) has slope at most 4 / pi: 1.27 x 3/510 = 1.9/255. Bilinear
/// interpolation reproduces p_i's plane exactly, so the RMS over the floor stays below the
/// 2/255 the issue asks for, at 16 texels (8 world units per... 0.125 world per texel) and
/// at 128.
#[test]
fn penumbra_limit_maps_are_exact_on_a_straight_edge_up_to_depth_quantisation() {
    // The paper's Unorm8 at both resolutions; the finer storages (the sweep axis) at 128,
    // where the same bound holds a fortiori.
    let cases = [(16, "Unorm8"), (128, "Unorm8"), (128, "Unorm16"), (128, "F16"), (128, "F32")];
    for (n, precision) in cases {
        let scene = edge(n, 10.0);
        let (vis, pos, ex) = run(PLM, &scene, &[("c,g,b,p", precision)]);
        let (mut sum, mut count, mut worst) = (0.0f64, 0usize, 0.0f64);
        let mut penumbra = 0;
        for (v, p) in vis.iter().zip(&pos) {
            assert!(v.is_finite() && (0.0..=1.0).contains(v), "{v}");
            if !p[0].is_finite() || p[1].abs() > 1e-3 {
                continue;
            }
            let want = closed_form(f64::from(p[0]), 10.0);
            if want > 0.0 && want < 1.0 {
                penumbra += 1;
            }
            let e = f64::from(*v) - want;
            sum += e * e;
            worst = worst.max(e.abs());
            count += 1;
        }
        let rms = (sum / count as f64).sqrt();
        eprintln!(
            "{n} texels, {precision}: RMS {:.3}/255, worst {:.3}/255 over {count} floor pixels ({penumbra} in the penumbra)",
            rms * 255.0,
            worst * 255.0
        );
        assert!(
            count > 60_000 && penumbra > 10_000,
            "{count} floor pixels, {penumbra} in the penumbra"
        );
        assert!(rms < 2.0 / 255.0, "{n} texels, {precision}: RMS {} / 255", rms * 255.0);
        // One silhouette edge per open boundary edge of the two quads (4 + 4).
        let g = ex.inspect().generated("ribbons.silhouettes").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(g.records, 8);
    }
}

/// A straight edge under a low sun (issue 35): the quad over x in [-4, 0], z in [-3, 3] at
/// height 1, wound to face down (from the light, a back face: its far side), under a distant
/// disk 10 degrees wide 20 degrees above the horizon, over a floor that casts nothing. The
/// quad recedes from its edge along the rays by 1 / tan 20 = 2.75 per unit across them, so
/// inside the silhouette it lies more than `bias_b` below c everywhere but within a sliver
/// of the edge; kept for b by the paper's wording alone (`b_limit = 0`), it clamps the
/// whole inner penumbra to 0 (eq. 2, "z > b"). It lies in the edge's umbra, though, where
/// every ray to the light is already blocked: with `b_limit = 1` (the default) it is left
/// out, and eq. 1 holds.
///
/// Against the closed form: a floor point at x < 0 sees the edge at elevation
/// phi = atan(1 / -x); the light directions below phi pass, so the visible fraction is the
/// disk's chord f(u) at u = (phi - 20 deg) / 5 deg. F32 storage and no depth bias (the
/// floor casts nothing, so no surface can shadow itself): eq. 1's only departure is
/// tan(delta) / tan(5 deg) for delta / 5 deg, and the flat chord for the spherical cap's,
/// both below 0.13 (5 deg)^2 = 0.001 in u and (2 / pi) 0.001 = 0.16/255 in visibility; with
/// f32 and the bilinear weights' 8 bits, the bound is 1/255 at every floor pixel.
#[test]
fn a_back_face_in_the_edges_umbra_leaves_the_inner_penumbra_to_eq_1() {
    let scene = Scene::from_str(
        "Scene(
    camera: Orthographic(position: (-2.7475, 0.5, 0.0), target: (-2.7475, 0.0, 0.0), up: (0.0, 0.0, -1.0),
        half_height: 1.0, width: 96, height: 96, near: 0.01, far: 1.0),
    shadow_map: 128,
    shadow_fit: Casters,
    lights: [DistantDisk(direction: (0.93969262, 0.34202014, 0.0), angle_degrees: 10.0)],
    objects: [
        Object(name: \"floor\", mesh: Plane(size: (6.0, 6.0)), casts: false, transform: (translate: (-2.75, 0.0, 0.0))),
        Object(name: \"occluder\", mesh: Quad(a: (-4.0, 1.0, -3.0), b: (0.0, 1.0, -3.0), c: (0.0, 1.0, 3.0), d: (-4.0, 1.0, 3.0))),
    ],
)",
        ".",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let (e, r) = (20.0f64.to_radians(), 5.0f64.to_radians());
    let want = |x: f64| {
        let u = (((1.0 / -x).atan() - e) / r).clamp(-1.0, 1.0);
        0.5 + (u * (1.0 - u * u).sqrt() + u.asin()) / std::f64::consts::PI
    };
    let mut worst_by_rule = [0.0f64; 2];
    for b_limit in [1, 0] {
        let set = [
            ("b_limit", b_limit.to_string()),
            ("bias", "0.0".to_string()),
            ("slope_bias", "0.0".to_string()),
        ];
        let (vis, pos, _) = run_set(PLM, &scene, &set, &[("c,g,b,p", "F32")]);
        let (mut sum, mut count, mut inner, mut worst) = (0.0f64, 0usize, 0usize, 0.0f64);
        for (v, p) in vis.iter().zip(&pos) {
            assert!(v.is_finite() && (0.0..=1.0).contains(v), "{v}");
            let want = want(f64::from(p[0]));
            if want > 0.0 && want < 0.5 {
                inner += 1;
            }
            let err = (f64::from(*v) - want).abs();
            sum += err * err;
            worst = worst.max(err);
            count += 1;
        }
        eprintln!(
            "b_limit {b_limit}: RMS {:.3}/255, worst {:.3}/255 over {count} floor pixels ({inner} in the inner penumbra)",
            (sum / count as f64).sqrt() * 255.0,
            worst * 255.0
        );
        assert!(
            count == 96 * 96 && inner > 1500,
            "{count} floor pixels, {inner} in the inner penumbra"
        );
        worst_by_rule[b_limit] = worst;
    }
    assert!(worst_by_rule[1] < 1.0 / 255.0, "worst {}/255", worst_by_rule[1] * 255.0);
    // The paper's wording alone blacks out the inner penumbra: at its middle, l = 1/4, the
    // error is f(-1/2) = 0.196 (50/255) and more towards the edge.
    assert!(worst_by_rule[0] > 50.0 / 255.0, "b_limit 0: worst {}/255", worst_by_rule[0] * 255.0);
}

/// A light without size has no penumbra: no ribbons are drawn, c stays 1 and eq. 2 keeps
/// only "lit above g": the hard shadow map's test against g. g is sampled bilinearly (the
/// paper's storage) where the hard map takes the nearest texel, so the two agree except
/// within one texel of the shadow's edge; everywhere the result is 0 or 1.
#[test]
fn penumbra_limit_maps_at_light_angle_zero_are_the_hard_shadow_map() {
    let n = 64;
    let scene = edge(n, 0.0);
    let (vis, pos, ex) = run(PLM, &scene, &[]);
    let (hard, _, _) = run("hard", &scene, &[]);
    let texel = 2.0 / n as f32;
    let mut compared = 0;
    for ((v, h), p) in vis.iter().zip(&hard).zip(&pos) {
        assert!(*v == 0.0 || *v == 1.0, "{v}");
        if p[0].is_finite() && p[0].abs() > texel {
            assert_eq!(v, h, "at x = {}", p[0]);
            compared += 1;
        }
    }
    assert!(compared > 50_000, "{compared}");
    assert_eq!(
        ex.inspect()
            .generated("ribbons.silhouettes")
            .unwrap_or_else(|e| panic!("{e}"))
            .records,
        0
    );
}

/// Smoothies keep the hard shadow whole and place the whole penumbra outside it
/// (Lawlor 2006, figure 11): 0 where the hard map says shadow, then the ramp
/// w / (2 h tan(angle / 2)) over the width of the full penumbra beside the edge. Same
/// quantisation argument as above with F16 storage (2^-11 relative) and a linear ramp:
/// within 1/255 of the closed ramp, away by a texel from the hard edge and from the
/// ramp's end, kinks that bilinear interpolation rounds over a texel.
#[test]
fn smoothies_are_an_outer_penumbra_only() {
    one_sided_penumbra(SMOOTHIES, 1.0, 2.0);
}

/// A one-sided technique on `edge.ron` at 128 texels: on the side `sign` points away from
/// (the hard shadow for smoothies, `sign` 1; the lit side for single-sample shadows, -1)
/// the hard map's value exactly; on the other, the ramp over `reaches` times the penumbra's
/// reach w = h tan(angle / 2), from the edge's value to the far side's, within 1/255 away by
/// a texel from the edge and from the ramp's end.
fn one_sided_penumbra(technique: &str, sign: f64, reaches: f64) {
    let n = 128;
    let scene = edge(n, 10.0);
    let (vis, pos, _) = run(technique, &scene, &[]);
    let w = (5.0f64).to_radians().tan();
    let texel = 2.0 / f64::from(n);
    let (mut checked, mut worst) = (0, 0.0f64);
    for (v, p) in vis.iter().zip(&pos) {
        assert!(v.is_finite() && (0.0..=1.0).contains(v), "{v}");
        if !p[0].is_finite() {
            continue;
        }
        // distance into the ramp's side
        let x = sign * f64::from(p[0]);
        if x < -texel {
            let hard = if sign > 0.0 { 0.0 } else { 1.0 };
            assert_eq!(f64::from(*v), hard, "{technique}: on the hard side at x = {}", p[0]);
        } else if x > texel && (x - reaches * w).abs() > texel {
            let ramp = (x / (reaches * w)).min(1.0);
            let want = if sign > 0.0 { ramp } else { 1.0 - ramp };
            worst = worst.max((f64::from(*v) - want).abs());
            checked += 1;
        }
    }
    eprintln!("{technique} ramp: worst {:.3}/255 over {checked} pixels", worst * 255.0);
    assert!(checked > 20_000, "{technique}: {checked} pixels");
    assert!(worst < 1.0 / 255.0, "{technique}: worst {}/255", worst * 255.0);
}

/// Receivers at the occluder's own depth (the triangle touching the ground, the contact
/// scene's sphere on the floor under a local light) and on the edge's line: finite values
/// in [0, 1] everywhere, at every storage precision.
#[test]
fn no_nan_where_the_receiver_meets_the_occluder() {
    for (scene, precision) in [
        ("scenes/triangle.ron", "Unorm8"),
        ("scenes/contact.ron", "Unorm8"),
        ("scenes/contact.ron", "F16"),
        ("scenes/triangle.ron", "F32"),
    ] {
        let s = Scene::load(root().join(scene)).unwrap_or_else(|e| panic!("{e}"));
        for technique in [PLM, SMOOTHIES, "single-sample"] {
            let prec: Vec<(&str, &str)> = if technique == PLM { vec![("c,g,b,p", precision)] } else { vec![] };
            let (vis, _, _) = run(technique, &s, &prec);
            let bad = vis.iter().filter(|v| !(v.is_finite() && (0.0..=1.0).contains(*v))).count();
            assert_eq!(bad, 0, "{technique} on {scene} at {precision}");
            let dark = vis.iter().filter(|v| **v < 0.5).count();
            assert!(dark > 100, "{technique} on {scene}: {dark} shadowed pixels");
        }
    }
}

/// Lawlor's step 3 draws the faces turned away from the light: for a box floating above a
/// floor under a light straight overhead, the lower limit at the box's centre texel is the
/// box's bottom (1.5 - 0.5 = 1.0 above the floor), not its top or the floor (both facing
/// the light). Without `keep`, every back face counts.
#[test]
fn back_faces_are_those_turned_away_from_the_light() {
    let src = r#"Technique(
    name: "back_faces",
    channels: { "b": Channel(precision: F32, value: "clamp((z_frag - near) / (far - near), 0.0, 1.0)") },
    passes: [
        Geometry(name: "back", reads: [], writes: "lower", primitive: BackFaces, channels: ["b"], resolve: Nearest),
        Shade(name: "shade", reads: ["lower"], visibility: "sample(b)"),
    ],
)"#;
    let scene = Scene::from_str(
        "Scene(
    camera: Orthographic(position: (0.0, 3.0, 0.0), target: (0.0, 0.0, 0.0), up: (0.0, 0.0, -1.0), half_height: 1.0, width: 8, height: 8),
    shadow_map: 64,
    lights: [DistantDisk(direction: (0.0, 1.0, 0.0), angle_degrees: 2.0)],
    objects: [
        Object(name: \"floor\", mesh: Plane(size: (4.0, 4.0))),
        Object(name: \"box\", mesh: Box(size: (1.0, 1.0, 1.0)), transform: (translate: (0.0, 1.5, 0.0))),
    ],
)",
        ".",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let compiled = compile_source("back_faces", src, &[], &[]);
    let ex = Loaded::new(gpu(), compiled.graph, compiled.shaders).unwrap_or_else(|e| panic!("{e}"));
    let inputs = sshc_lab::bind::scene_inputs(&scene).unwrap_or_else(|e| panic!("{e}"));
    let mut ex = ex.bind_scene(&inputs).unwrap_or_else(|e| panic!("{e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    let b = ex
        .inspect()
        .read_texture("lower", 0, 0)
        .unwrap_or_else(|e| panic!("{e}"))
        .channel(0);
    let (near, far) = (f64::from(inputs.near), f64::from(inputs.far));
    // the normalised light depth of the point at height y on the vertical through the centre
    let view = glam::Mat4::from_cols_array(&inputs.light_view);
    let depth = |y: f32| (f64::from(-view.transform_point3(glam::Vec3::new(0.0, y, 0.0)).z) - near) / (far - near);
    let n = 64;
    let centre = b[(n / 2) * n + n / 2];
    // The floor faces the light: outside the box nothing is drawn (the clear, 1).
    assert_eq!(b[0], 1.0, "the floor is not a back face");
    // The box's bottom at height 1.0, its top at 2.0. F32 target and f32 view transform:
    // a few ulp of depths below 1.
    let (want_bottom, want_top) = (depth(1.0), depth(2.0));
    let got = f64::from(centre);
    assert!(
        (got - want_bottom).abs() < 1e-5,
        "centre texel: {got}, the bottom is {want_bottom}, the top {want_top} (near {near}, far {far})"
    );
}

/// The reference's view of a bound scene: the same light view, depth range and map size.
/// The generator draws every ribbon at twice the penumbra's reach (one primitive serves
/// penumbra limit maps and smoothies), the reference's `reach_scale = 2`.
fn plm_setup(inputs: &sshc_runtime::gpu::SceneInputs) -> plm::PlmSetup {
    let light = PenumbraSetup {
        view: inputs.light_view.map(f64::from),
        projection: if inputs.light_orthographic {
            LightProjection::Orthographic {
                half_height: 1.0 / f64::from(inputs.light_proj_y),
            }
        } else {
            LightProjection::Perspective {
                f: f64::from(inputs.light_proj_y),
            }
        },
        near: f64::from(inputs.near),
        far: f64::from(inputs.far),
        size: inputs.shadow_size as usize,
        light: if inputs.light_orthographic {
            AreaLight::DistantDisk {
                angle: f64::from(inputs.light_angle),
            }
        } else {
            AreaLight::Sphere {
                radius: f64::from(inputs.light_size),
            }
        },
        resolve: Resolve::KeepMin,
    };
    plm::PlmSetup {
        reach_scale: 2.0,
        ..plm::PlmSetup::new(light)
    }
}

/// A 1.5-wide square 2 above a floor under a sphere light 6 above it (a local light: the
/// projective form of eq. 1), and a box floating above the floor (closed: back faces).
fn local_scene(objects: &str, shadow: u32) -> Scene {
    Scene::from_str(
        &format!(
            "Scene(
    camera: Perspective(position: (0.0, 6.0, 6.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 40.0, width: 64, height: 64),
    shadow_map: {shadow},
    lights: [Sphere(center: (0.0, 6.0, 0.0), radius: 0.5)],
    objects: [
        Object(name: \"floor\", mesh: Plane(size: (6.0, 6.0))),
        {objects}
    ],
)"
        ),
        ".",
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// The generated penumbra limit map (Unorm8, as the paper stores it) against the
/// independent f64 reference (`sshc_tests::reference::plm`, written from the paper alone),
/// texel by texel for c, g, b and p = p_i / 4 + 1/2. Both quantise to 8 bits, so a texel
/// agrees when it is within one step (1/255: a value within f32 error of a rounding
/// boundary rounds either way). Where ribbons' penumbra limits tie within f32 error (1e-5)
/// the depth test may pick any of them: texels where the tied ribbons store different
/// values are not compared, and there must be few of them.
#[test]
fn the_generated_map_agrees_with_the_f64_reference() {
    let scenes = [
        ("edge", edge(64, 10.0)),
        (
            "square, sphere light",
            local_scene(
                "Object(name: \"square\", mesh: Plane(size: (1.5, 1.5)), transform: (translate: (0.0, 2.0, 0.0))),",
                96,
            ),
        ),
        (
            "box, sphere light",
            local_scene(
                "Object(name: \"box\", mesh: Box(size: (1.0, 1.0, 1.0)), transform: (translate: (0.3, 1.5, 0.0))),",
                96,
            ),
        ),
    ];
    for (name, scene) in scenes {
        let (_, _, ex) = run(PLM, &scene, &[]);
        let inputs = sshc_lab::bind::scene_inputs(&scene).unwrap_or_else(|e| panic!("{e}"));
        let setup = plm_setup(&inputs);
        let tris: Vec<[[f64; 3]; 3]> = scene.triangles().iter().map(|t| t.map(|p| p.to_array().map(f64::from))).collect();
        let meshes: Vec<std::ops::Range<usize>> = (0..scene.objects().len()).map(|i| scene.object_triangles(i)).collect();
        let r = plm::PlmReference::new(&tris, &meshes, &setup).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            ex.inspect()
                .generated("ribbons.silhouettes")
                .unwrap_or_else(|e| panic!("{e}"))
                .records as usize,
            r.ribbons.len(),
            "{name}: ribbons"
        );
        let got = ex.inspect().read_texture("plm", 0, 0).unwrap_or_else(|e| panic!("{e}"));
        let n = setup.light.size;
        let m = &r.maps;
        let step = 1.0 / 255.0 + 1e-6;
        let (mut compared, mut ties, mut worst) = (0, 0, [0.0f64; 4]);
        for j in 0..n {
            for i in 0..n {
                let k = j * n + i;
                // Ribbons whose penumbra limits tie with the best within f32 error: the
                // depth test may keep any of them. Ties of equal values (beyond the shared
                // end point of two edges both ribbons measure the distance to that point)
                // are compared; ties of different values are counted and skipped.
                let q = setup.texel_centre(i, j);
                let samples: Vec<plm::RibbonSample> = r.ribbons.iter().filter_map(|rb| rb.at(&setup, q)).collect();
                let best = samples.iter().map(|s| s.key).fold(f64::INFINITY, f64::min);
                let tied: Vec<&plm::RibbonSample> = samples.iter().filter(|s| s.key - best < 1e-5).collect();
                let q8 = |v: f64| plm::quantise(v, Some(Storage::Unorm8));
                if tied
                    .iter()
                    .any(|s| q8(s.c) != q8(tied[0].c) || q8(s.p_i / 4.0 + 0.5) != q8(tied[0].p_i / 4.0 + 0.5))
                {
                    ties += 1;
                    continue;
                }
                let want = [q8(m.c[k]), q8(m.g[k]), q8(m.b[k]), q8(m.p_i[k] / 4.0 + 0.5)];
                let px = got.rgba[k];
                for ch in 0..4 {
                    let e = (f64::from(px[ch]) - want[ch]).abs();
                    worst[ch] = worst[ch].max(e);
                    assert!(
                        e <= step,
                        "{name}: texel ({i}, {j}) channel {}: generated {} reference {} (unquantised c {} g {} b {} p_i {})",
                        ["c", "g", "b", "p"][ch],
                        px[ch],
                        want[ch],
                        m.c[k],
                        m.g[k],
                        m.b[k],
                        m.p_i[k]
                    );
                }
                compared += 1;
            }
        }
        eprintln!(
            "{name}: {compared} texels agree (worst c {:.2}, g {:.2}, b {:.2}, p {:.2} steps of 1/255), {ties} ties skipped, {} ribbons",
            worst[0] * 255.0,
            worst[1] * 255.0,
            worst[2] * 255.0,
            worst[3] * 255.0,
            r.ribbons.len()
        );
        // A tie of different values is a texel centre equidistant from two edges, one on
        // each side (a corner's bisector through texel centres): a few lines of texels.
        assert!(ties <= 4 * n, "{name}: {ties} ties");
    }
}

/// Single-sample soft shadows (Kirsch & Doellner, as Lawlor 2006 describes them) keep the
/// lit side whole and return the light over the inner penumbra, inside the hard shadow: 1
/// beyond the edge, then 1 - w / (h tan(angle / 2)) at w inside it, 0 past the reach, where
/// the true umbra starts (issue 37; the whole penumbra's width before). Same F16 storage and
/// texel cuts as smoothies.
#[test]
fn single_sample_shadows_are_an_inner_penumbra_only() {
    one_sided_penumbra("single-sample", -1.0, 1.0);
}

/// Issue 49: a UV sphere whose seam an exporter duplicated (`scenes/seams/seam-sphere.obj`: the
/// last column computed again, a few ulps from the first) is welded within the tolerance,
/// so its shadow is the shadow of the same sphere with the seam's vertices made
/// bit-identical: the same silhouettes, and the same visibility up to the ulps the seam's
/// welded positions differ by (each may move a Unorm8 channel of the map by a code). A slit
/// of 10 tolerances (`scenes/seams/slit-sphere.obj`) stays open and draws its ribbons: the
/// test tells the two apart.
#[test]
fn a_sphere_whose_seam_is_a_few_ulps_wide_casts_the_shadow_of_its_welded_twin() {
    let dir = std::env::temp_dir().join(format!("sshc-seam-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let obj = std::fs::read_to_string(root().join("scenes/seams/seam-sphere.obj")).unwrap();
    // the seam's column copied from the first (vertex r (segments + 1) + segments of each
    // ring), and each pole's vertices (one a segment, sin(pi) apart at the south pole) from
    // the pole's first
    let (rings, segments) = (24, 48);
    let mut vertices: Vec<String> = obj.lines().filter(|l| l.starts_with("v ")).map(String::from).collect();
    assert_eq!(vertices.len(), (rings + 1) * (segments + 1));
    let mut moved = 0;
    for r in 0..=rings {
        let first = r * (segments + 1);
        let copies = if r == 0 || r == rings { 1..=segments } else { segments..=segments };
        for k in copies {
            moved += usize::from(vertices[first + k] != vertices[first]);
            vertices[first + k] = vertices[first].clone();
        }
    }
    assert!(moved > 10, "{moved}: the file's seam is bit-identical already (a test of nothing)");
    let faces = obj.lines().filter(|l| l.starts_with("f "));
    let exact: Vec<String> = vertices.into_iter().chain(faces.map(String::from)).collect();
    std::fs::write(dir.join("exact-sphere.obj"), exact.join("\n") + "\n").unwrap();
    let scene_text = std::fs::read_to_string(root().join("scenes/seams/seam-sphere.ron")).unwrap();
    let load = |name: &str| {
        let text = scene_text.replace("seam-sphere.obj", name);
        let mut s = Scene::from_str(&text, &dir).unwrap_or_else(|e| panic!("{e}"));
        s.set_camera_size(96, 96);
        s.shadow_map = 256;
        s
    };
    std::fs::copy(root().join("scenes/seams/seam-sphere.obj"), dir.join("seam-sphere.obj")).unwrap();
    std::fs::copy(root().join("scenes/seams/slit-sphere.obj"), dir.join("slit-sphere.obj")).unwrap();
    let (exact, _, ex) = run(PLM, &load("exact-sphere.obj"), &[]);
    let exact_edges = ex.scene.edge_counts().expect("edges");
    let (seam, _, ex) = run(PLM, &load("seam-sphere.obj"), &[]);
    let seam_edges = ex.scene.edge_counts().expect("edges");
    let (slit, _, ex) = run(PLM, &load("slit-sphere.obj"), &[]);
    let slit_edges = ex.scene.edge_counts().expect("edges");
    // the floor's 4 outline edges are the only boundary of the welded spheres
    assert_eq!((exact_edges.boundary, seam_edges.boundary), (4, 4), "{seam_edges:?}");
    assert_eq!(seam_edges.edges, exact_edges.edges);
    assert!(
        seam_edges.welded_near > 0 && exact_edges.welded_near == 0,
        "{seam_edges:?} {exact_edges:?}"
    );
    assert_eq!(slit_edges.boundary, 4 + 2 * rings as u32, "{slit_edges:?}");
    let differing = |a: &[f32], b: &[f32], by: f32| a.iter().zip(b).filter(|(x, y)| (*x - *y).abs() > by).count();
    // a Unorm8 code of a stored channel, and f32 rounding past it
    let code = 1.0 / 255.0 + 1e-6;
    assert_eq!(
        differing(&seam, &exact, code),
        0,
        "the welded seam's shadow differs from its twin's"
    );
    assert!(
        differing(&slit, &exact, code) > 20,
        "the open slit changes nothing: {} pixels",
        differing(&slit, &exact, code)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
