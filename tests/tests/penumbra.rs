//! Penumbra maps (`techniques/penumbra-maps.ron`, Wyman & Hansen 2003) as the compiler
//! generates them, run on a GPU (lavapipe without one), against the f64 CPU reference
//! (`sshc_tests::reference::penumbra`, written from the paper alone), texel by texel of
//! the penumbra map; and the limits the issue names: a light of radius 0 gives exactly the
//! hard shadow map, and open or non-manifold meshes give finite values in [0, 1].

mod support;

use sshc_lab::run::{Bound, Loaded};
use sshc_lab::scene::Scene;
use sshc_runtime::adjacency::Adjacency;
use sshc_runtime::gpu::{CameraOutput, SceneInputs};
use sshc_tests::reference::penumbra::{self as reference, AreaLight, LightProjection, PenumbraSetup, Primitive, Resolve};
use support::{compile_source, gpu, technique_source};

const TECHNIQUE: &str = "penumbra-maps";

/// Cones are drawn with `CONE_SEGMENTS` = 16 triangles whose base polygon is circumscribed
/// about the cone's circle, so the drawn cone is up to 1 / cos(pi / 16) - 1 = 1.96 % wider
/// than the paper's: at a texel it meets the drawn cone nearer its tip, `Z_F - Z_v` (and
/// with it eq. 1's I) smaller by up to that fraction. The Bernstein interpolant's slope is
/// at most 3/2, so s differs by at most 1.5 x 0.0196 = 0.029 where a cone wins.
const CONE_TOLERANCE: f64 = 1.5 * 0.019_6;
/// Sheets of an edge whose end points lie at one light distance are planar and drawn
/// exactly; what remains is the f16 target (11 significant bits: 2^-11 of a value <= 1)
/// and f32 arithmetic on Z (a few ulp of Z, relative 1e-6, divided by Z_P - Z_v, which is
/// at least a tenth of Z here: 1e-5).
const SHEET_TOLERANCE: f64 = 1.0 / 2048.0 + 1e-5;
/// The smallest s on the part of a drawn cone outside the exact cone: there I >= cos(pi/16),
/// so s >= 3 c^2 - 2 c^3 for c = cos(pi / 16) = 0.98079 (0.99889), less one f16 step.
const RIM_S: f64 = 0.998_89 - 1.0 / 2048.0;

/// A 1.5-wide square 2 units above a floor, a sphere light of radius `radius` 6 units above
/// the floor's centre.
fn scene(radius: f32, shadow: u32) -> Scene {
    scene_with(
        radius,
        shadow,
        "Object(name: \"square\", mesh: Plane(size: (1.5, 1.5)), transform: (translate: (0.0, 2.0, 0.0))),",
    )
}

fn scene_with(radius: f32, shadow: u32, objects: &str) -> Scene {
    let text = format!(
        "Scene(
    camera: Perspective(position: (0.0, 6.0, 6.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 40.0, width: 32, height: 32),
    shadow_map: {shadow},
    lights: [Sphere(center: (0.0, 6.0, 0.0), radius: {radius})],
    objects: [
        Object(name: \"floor\", mesh: Plane(size: (6.0, 6.0))),
        {objects}
    ],
)"
    );
    Scene::from_str(&text, ".").unwrap_or_else(|e| panic!("{e}"))
}

/// The reference's view of the scene: the same triangles, light view and depth range.
fn setup(inputs: &SceneInputs, resolve: Resolve) -> PenumbraSetup {
    PenumbraSetup {
        view: inputs.light_view.map(f64::from),
        projection: LightProjection::Perspective {
            f: f64::from(inputs.light_proj_y),
        },
        near: f64::from(inputs.near),
        far: f64::from(inputs.far),
        size: inputs.shadow_size as usize,
        light: AreaLight::Sphere {
            radius: f64::from(inputs.light_size),
        },
        resolve,
    }
}

fn triangles(scene: &Scene) -> Vec<[[f64; 3]; 3]> {
    scene.triangles().iter().map(|t| t.map(|p| p.to_array().map(f64::from))).collect()
}

fn meshes(scene: &Scene) -> Vec<std::ops::Range<usize>> {
    (0..scene.objects().len()).map(|i| scene.object_triangles(i)).collect()
}

/// Run the generated technique on `scene`: the penumbra map (row 0 at the top), the hard
/// test's inputs and the visibility buffer.
fn run(scene: &Scene, set: &[(&str, String)]) -> (Vec<f32>, Vec<f32>, SceneInputs, Bound) {
    run_source(scene, &technique_source(TECHNIQUE), set)
}

fn run_source(scene: &Scene, source: &str, set: &[(&str, String)]) -> (Vec<f32>, Vec<f32>, SceneInputs, Bound) {
    let compiled = compile_source(TECHNIQUE, source, set, &[]);
    let ex = Loaded::new(gpu(), compiled.graph, compiled.shaders).unwrap_or_else(|e| panic!("{e}"));
    let inputs = sshc_lab::bind::scene_inputs(scene).unwrap_or_else(|e| panic!("{e}"));
    let mut ex = ex.bind_scene(&inputs).unwrap_or_else(|e| panic!("{e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    let pmap = ex.inspect().read_texture("pmap", 0, 0).unwrap_or_else(|e| panic!("{e}")).channel(0);
    let vis = ex
        .inspect()
        .read_camera(CameraOutput::Visibility)
        .unwrap_or_else(|e| panic!("{e}"))
        .channel(0);
    (pmap, vis, inputs, ex)
}

#[test]
fn the_generated_penumbra_map_agrees_with_the_f64_reference() {
    let scene = scene(0.5, 128);
    let (pmap, _, inputs, ex) = run(&scene, &[]);
    let setup = setup(&inputs, Resolve::KeepMin);
    let tris = triangles(&scene);
    let r = reference::PenumbraReference::new(&tris, &meshes(&scene), &setup).unwrap_or_else(|e| panic!("{e}"));

    // The silhouettes the GPU classified: the two quads' 8 boundary edges (their
    // diagonals are not silhouettes), as the CPU rule and the reference count them.
    let generated = ex.inspect().generated("penumbra.silhouettes").unwrap_or_else(|e| panic!("{e}"));
    let f32_tris: Vec<[[f32; 3]; 3]> = scene.triangles().iter().map(|t| t.map(|p| p.to_array())).collect();
    let adj = Adjacency::build(&f32_tris, meshes(&scene));
    assert_eq!(generated.records as usize, adj.silhouette_count(inputs.light_position));
    assert_eq!(generated.records as usize, r.silhouettes.edges.len());
    assert_eq!(generated.records, 8);

    let n = setup.size;
    let (mut worst_cone, mut worst_sheet, mut penumbra) = (0.0f64, 0.0f64, 0);
    for j in 0..n {
        for i in 0..n {
            let want = r.penumbra.value[j * n + i];
            let got = f64::from(pmap[j * n + i]);
            assert!(got.is_finite() && (0.0..=1.0).contains(&got), "texel ({i}, {j}): {got}");
            let frags = reference::fragments(&r.primitives, &r.shadow, &setup, i, j);
            let cone = frags.iter().any(|f| matches!(f.primitive, Primitive::Cone(_)));
            let err = (got - want).abs();
            if want < 1.0 {
                penumbra += 1;
            }
            // A texel covered only by the drawn (wider) cone, or only by the exact one,
            // lies at the cone's rim, where s is within the cone tolerance of 1.
            if cone || frags.is_empty() {
                worst_cone = worst_cone.max(err);
                assert!(err <= CONE_TOLERANCE, "texel ({i}, {j}): generated {got}, reference {want} (cone)");
            } else {
                worst_sheet = worst_sheet.max(err);
                assert!(
                    err <= SHEET_TOLERANCE,
                    "texel ({i}, {j}): generated {got}, reference {want} (sheet)"
                );
            }
        }
    }
    eprintln!("{penumbra} penumbra texels; worst error: {worst_cone:.2e} where cones win, {worst_sheet:.2e} on sheets");
    assert!(penumbra > 4 * 64, "the test must see a penumbra: {penumbra} texels");
}

#[test]
fn a_light_of_radius_zero_gives_exactly_the_hard_shadow_map() {
    let scene = scene(0.0, 64);
    let (pmap, vis, _, ex) = run(&scene, &[]);
    assert!(pmap.iter().all(|&p| p == 1.0), "no penumbra without a light radius");
    drop(ex);
    let hard = compile_source("hard", &technique_source("hard"), &[], &[]);
    let ex = Loaded::new(gpu(), hard.graph, hard.shaders).unwrap_or_else(|e| panic!("{e}"));
    let mut ex = ex
        .bind_scene(&sshc_lab::bind::scene_inputs(&scene).unwrap_or_else(|e| panic!("{e}")))
        .unwrap_or_else(|e| panic!("{e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    let hard_vis = ex
        .inspect()
        .read_camera(CameraOutput::Visibility)
        .unwrap_or_else(|e| panic!("{e}"))
        .channel(0);
    assert_eq!(vis, hard_vis, "same bias, same test, penumbra 1 everywhere");
    assert!(vis.contains(&0.0) && vis.contains(&1.0));
}

/// Fragments of overlapping penumbrae combine by each resolve rule (the paper's figure 6
/// and the lightest): two squares whose penumbrae overlap on the floor, the technique's
/// fixed param `rule` set to each, against the reference's combination of its exact
/// fragments. Each fragment's s carries its own error (the tolerances above), so a texel
/// of k fragments is within k times the tolerance for `Add` and `Multiply` (values <= 1)
/// and within one for `KeepMin` and `KeepMax`; each blend rounds to f16 once more.
#[test]
fn every_resolve_rule_agrees_with_the_reference() {
    let scene = scene_with(
        0.6,
        128,
        "Object(name: \"a\", mesh: Plane(size: (1.2, 1.2)), transform: (translate: (-0.75, 2.0, 0.0))),
        Object(name: \"b\", mesh: Plane(size: (1.2, 1.2)), transform: (translate: (0.75, 2.5, 0.3))),",
    );
    for (index, (rule, name)) in [
        (Resolve::KeepMin, "KeepMin"),
        (Resolve::KeepMax, "KeepMax"),
        (Resolve::Add, "Add"),
        (Resolve::Multiply, "Multiply"),
    ]
    .into_iter()
    .enumerate()
    {
        // the technique's fixed param `rule` picks the resolve rule
        let (pmap, _, inputs, ex) = run(&scene, &[("rule", index.to_string())]);
        let drawn = ex.graph().passes.iter().flat_map(|p| &p.steps).find_map(|st| match &st.draw {
            sshc_runtime::graph::Draw::Primitives { resolve, .. } => Some(format!("{resolve:?}")),
            _ => None,
        });
        assert_eq!(drawn.as_deref(), Some(name));
        let setup = setup(&inputs, rule);
        let r = reference::PenumbraReference::new(&triangles(&scene), &meshes(&scene), &setup).unwrap_or_else(|e| panic!("{e}"));
        let n = setup.size;
        let (mut worst, mut overlaps, mut rim) = (0.0f64, 0, 0);
        let covered = |i: usize, j: usize| r.penumbra.fragments[j * n + i] > 0;
        for j in 0..n {
            for i in 0..n {
                let mut want = r.penumbra.value[j * n + i];
                let raw = f64::from(pmap[j * n + i]);
                assert!(raw.is_finite() && raw <= 1.0, "{name}, texel ({i}, {j}): {raw}");
                // `Add` keeps 1 - sum(1 - s), below 0 where the shadows add past full
                // shadow: read clamped to [0, 1] (as the reference combines).
                let got = raw.max(0.0);
                assert!(rule == Resolve::Add || raw >= 0.0, "{name}, texel ({i}, {j}): {raw}");
                if rule == Resolve::KeepMax {
                    // KeepMax blends from its identity, 0, so a texel no fragment covers
                    // reads 0 (the reference reads 1 there). At the rim of the primitives
                    // the drawn cones cover texels the exact ones do not: those texels,
                    // with a neighbour of the other kind, are counted and left out.
                    let around =
                        (j.saturating_sub(1)..(j + 2).min(n)).flat_map(|y| (i.saturating_sub(1)..(i + 2).min(n)).map(move |x| (x, y)));
                    let kinds: Vec<bool> = around.map(|(x, y)| covered(x, y)).collect();
                    if kinds.iter().any(|&k| k != kinds[0]) {
                        rim += 1;
                        continue;
                    }
                    if !covered(i, j) {
                        want = 0.0;
                    }
                }
                let frags = reference::fragments(&r.primitives, &r.shadow, &setup, i, j);
                let cone = frags.iter().any(|f| matches!(f.primitive, Primitive::Cone(_)));
                let per = if cone || frags.is_empty() {
                    CONE_TOLERANCE
                } else {
                    SHEET_TOLERANCE
                };
                let k = match rule {
                    Resolve::Add | Resolve::Multiply => frags.len().max(1) as f64,
                    Resolve::KeepMin | Resolve::KeepMax => 1.0,
                };
                let tol = k * (per + 1.0 / 2048.0);
                let sheets = frags.iter().filter(|f| matches!(f.primitive, Primitive::Sheet(_))).count();
                if sheets > 1 {
                    overlaps += 1;
                }
                // KeepMax also keeps the fragments at the rim of a drawn cone outside the
                // exact one, where eq. 1 gives I >= cos(pi / 16) and s >= RIM_S: a texel
                // reading at least that where the reference's fragments are darker is one.
                if rule == Resolve::KeepMax && got > want + tol && got >= RIM_S {
                    rim += 1;
                    continue;
                }
                worst = worst.max((got - want).abs() / tol);
                assert!(
                    (got - want).abs() <= tol,
                    "{name}, texel ({i}, {j}): generated {got}, reference {want} ({} fragments)",
                    frags.len()
                );
            }
        }
        eprintln!("{name}: {overlaps} texels where sheets overlap; worst error {worst:.2} of its tolerance; {rim} rim texels left out");
        assert!(overlaps > 10, "{name}: the penumbrae must overlap ({overlaps} texels)");
        // The rim is one or two texels wide around every primitive's outline: far fewer
        // texels than the map holds.
        assert!(rim < n * n / 8, "{name}: {rim} rim texels");
    }
}

/// `edge.ron`: a straight edge 1 above the floor under a distant disk of 10 degrees. The
/// paper's sheet from the edge grows by tan(5 deg) per unit of depth, so on the floor it
/// covers the outer band 0 < x < w = h tan(5 deg) = 0.0875 beside the edge's shadow line
/// x = 0, where eq. 1 gives I = x / w exactly (the sheet is planar: the edge lies at one
/// light distance). The generated map against that closed form, texel by texel, in the
/// middle of the edge (|z| < 0.5, away from the corners' cones), and the band's width in
/// texels.
#[test]
fn the_penumbra_width_on_the_straight_edge_is_the_closed_form() {
    let scene = Scene::load(support::root().join("scenes/edge.ron")).unwrap_or_else(|e| panic!("{e}"));
    let (pmap, vis, inputs, _ex) = run(&scene, &[]);
    assert!(vis.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)));
    let w = 1.0 * (5.0f64).to_radians().tan();
    let n = inputs.shadow_size as usize;
    let half = 1.0 / f64::from(inputs.light_proj_y);
    let texel = 2.0 * half / n as f64;
    let to_world = glam::Mat4::from_cols_array(&inputs.light_view).inverse();
    let (mut checked, mut widths) = (0, Vec::new());
    for j in 0..n {
        let mut band = 0;
        let mut row_in_middle = false;
        for i in 0..n {
            // the texel's centre on the floor (y = 0), through the orthographic view
            let x_ndc = 2.0 * (i as f32 + 0.5) / n as f32 - 1.0;
            let y_ndc = 1.0 - 2.0 * (j as f32 + 0.5) / n as f32;
            let o = to_world.transform_point3(glam::Vec3::new(x_ndc * half as f32, y_ndc * half as f32, 0.0));
            let d = to_world.transform_vector3(glam::Vec3::new(0.0, 0.0, -1.0));
            let p = o + d * (-o.y / d.y);
            if p.z.abs() >= 0.5 || p.x.abs() > 0.5 {
                continue;
            }
            row_in_middle = true;
            let got = f64::from(pmap[j * n + i]);
            let x = f64::from(p.x);
            if x > 0.0 && got < 1.0 {
                band += 1;
            }
            // Away from the band's two ends by the floor position's f32 error and one
            // texel's coverage rule: the closed form at the texel centre.
            if x > texel && x < w - texel {
                let i_ = x / w;
                let want = i_ * i_ * (3.0 - 2.0 * i_);
                assert!(
                    (got - want).abs() <= SHEET_TOLERANCE,
                    "texel ({i}, {j}) at x = {x}: {got} against {want}"
                );
                checked += 1;
            }
        }
        if row_in_middle && band > 0 {
            widths.push(band);
        }
    }
    let want = w / texel;
    eprintln!(
        "band {want:.2} texels wide by the closed form; rows measure {:?}",
        widths.iter().min().zip(widths.iter().max())
    );
    assert!(checked > 100, "{checked} texels checked");
    // The band holds the texel centres with 0 < x < w: floor(w / texel) or one more.
    for b in &widths {
        assert!(
            (*b as f64 - want).abs() <= 1.0,
            "a row's band is {b} texels, the closed form {want:.2}"
        );
    }
}

/// Meshes that are not closed manifolds, contact and edge-on silhouettes: an open quad, a
/// fin of three triangles sharing one edge (from an OBJ file), a box resting on the floor
/// (Z_P - Z_v -> 0 along its foot), a vertical quad seen edge-on by the light overhead, and
/// the bunny. No NaN or Inf and values in [0, 1] in the penumbra map and the visibility;
/// the silhouette edges the generated classification appends are the CPU rule's count.
#[test]
fn open_non_manifold_contact_and_edge_on_meshes_stay_finite_and_count_their_silhouettes() {
    let dir = std::env::temp_dir().join(format!("sshc-penumbra-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    std::fs::write(
        dir.join("fins.obj"),
        "v 0 0 0\nv 0 1 0\nv 1 0 0\nv -0.5 0 0.8\nv -0.5 0 -0.8\nf 1 2 3\nf 1 2 4\nf 2 1 5\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let objects = "Object(name: \"floor\", mesh: Plane(size: (6.0, 6.0))),
        Object(name: \"quad\", mesh: Plane(size: (0.8, 0.8)), transform: (translate: (-1.5, 1.5, -1.0))),
        Object(name: \"fins\", mesh: Obj(path: \"fins.obj\"), transform: (translate: (1.2, 0.8, 0.6))),
        Object(name: \"box\", mesh: Box(size: (0.8, 0.8, 0.8)), transform: (translate: (0.0, 0.4, 1.2))),
        Object(name: \"wall\", mesh: Quad(a: (-0.5, 0.0, -1.8), b: (-0.5, 1.0, -1.8), c: (0.5, 1.0, -1.8), d: (0.5, 0.0, -1.8))),";
    let mut scenes = Vec::new();
    for light in [
        "Sphere(center: (0.0, 6.0, 0.0), radius: 0.5)",
        "DistantDisk(direction: (0.0, 1.0, 0.0), angle_degrees: 8.0)",
    ] {
        let text = format!(
            "Scene(
    camera: Perspective(position: (0.0, 5.0, 5.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 50.0, width: 48, height: 48),
    shadow_map: 128,
    lights: [{light}],
    objects: [{objects}],
)"
        );
        scenes.push(Scene::from_str(&text, &dir).unwrap_or_else(|e| panic!("{e}")));
    }
    scenes.push(Scene::load(support::root().join("scenes/bunny.ron")).unwrap_or_else(|e| panic!("{e}")));
    for scene in &scenes {
        let (pmap, vis, inputs, ex) = run(scene, &[]);
        assert!(pmap.iter().all(|p| p.is_finite() && (0.0..=1.0).contains(p)), "penumbra map");
        assert!(vis.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)), "visibility");
        assert!(pmap.iter().any(|&p| p < 0.5), "a penumbra is drawn");
        let tris: Vec<[[f32; 3]; 3]> = scene.triangles().iter().map(|t| t.map(|p| p.to_array())).collect();
        let adj = Adjacency::build(&tris, meshes(scene));
        let generated = ex.inspect().generated("penumbra.silhouettes").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(generated.records as usize, adj.silhouette_count(inputs.light_position));
        let counts = ex.scene.edge_counts().expect("edges");
        assert_eq!(counts, adj.counts);
    }
    let c = Adjacency::build(
        &scenes[0].triangles().iter().map(|t| t.map(|p| p.to_array())).collect::<Vec<_>>(),
        meshes(&scenes[0]),
    )
    .counts;
    assert_eq!(c.non_manifold, 1, "the fins' shared edge");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The built-in sphere is a closed manifold: its seam and poles weld, so no spurious
/// boundary edge is a silhouette all around it.
#[test]
fn the_built_in_sphere_is_closed() {
    for segments in [3, 8, 32, 101] {
        let text = format!(
            "Scene(camera: Perspective(position: (0.0, 0.0, 5.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 40.0, width: 8, height: 8),
             shadow_map: 16, lights: [Point(position: (0.0, 5.0, 0.0))],
             objects: [Object(mesh: Sphere(radius: 1.0, segments: {segments}))])"
        );
        let scene = Scene::from_str(&text, ".").unwrap_or_else(|e| panic!("{e}"));
        let tris: Vec<[[f32; 3]; 3]> = scene.triangles().iter().map(|t| t.map(|p| p.to_array())).collect();
        let c = Adjacency::build(&tris, meshes(&scene)).counts;
        assert_eq!((c.boundary, c.non_manifold), (0, 0), "{segments} segments: {c:?}");
    }
}
