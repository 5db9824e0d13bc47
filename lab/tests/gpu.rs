//! Two-sided surfaces on a real adapter (lavapipe without a GPU; nextest's `gpu` group):
//! an open mesh, a single quad, lit from above. Seen from above it is lit; seen from below
//! (the side facing away from the light) it is shadowed by its own surface, in every
//! bundled technique and in the ground truth alike (the scene format's convention,
//! scenes/README.md). Before, both read the back of a one-sided surface as lit.

use std::path::Path;

use glam::Vec3;
use sshc_lab::scene::Scene;
use sshc_lab::session::{compile_technique, positions_normals};
use sshc_lab::visibility::Visibility;
use sshc_runtime::gpu::{CameraOutput, Gpu};

mod common;

/// Every bundled technique whose `light:` takes the sphere light of [`quad_scene`], found
/// in `techniques/` (issue 52: no hand-kept list; a technique for other lights only, such
/// as the linear-light ones, is left out by its own declaration).
fn sphere_techniques() -> Vec<String> {
    let names: Vec<String> = common::bundled_techniques()
        .into_iter()
        .filter(|t| !t.starts_with("examples/"))
        .collect();
    let taken: Vec<String> = names
        .iter()
        .filter(|t| {
            let path = root().join("techniques").join(format!("{t}.ron"));
            let source = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let c = sshc::compile_str(&source, &Default::default()).unwrap_or_else(|d| panic!("{}", d.render(t, &source)));
            c.graph.lights.iter().any(|m| m.accepts(sshc_graph::LightKind::Sphere))
        })
        .cloned()
        .collect();
    assert!(
        taken.len() >= 15 && taken.len() < names.len(),
        "{} of {} techniques take a sphere light",
        taken.len(),
        names.len()
    );
    taken
}

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
    let loaded = compile_technique(gpu, &path, &source, &Default::default()).unwrap_or_else(|e| panic!("{technique}: {e}"));
    let inputs = sshc_lab::bind::scene_inputs(scene).unwrap();
    let mut ex = loaded.bind_scene(&inputs).unwrap_or_else(|e| panic!("{technique}: {e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{technique}: {e}"));
    let vis = ex
        .inspect()
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
    for t in &sphere_techniques() {
        let t = t.as_str();
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

/// A 3 x 3 ground at y = 0 and a quad at height 0.5 over x in [-2, 0] under a distant disk
/// straight overhead, seen from straight above by an orthographic camera at height 0.25
/// (the quad is behind it). The ground comes first in the file, so the executor's vertex
/// buffer reorders it behind the caster.
fn ground_scene(ground_casts: bool, quad_casts: bool, fit: &str) -> Scene {
    let text = format!(
        "Scene(camera: Orthographic(position: (0.0, 0.25, 0.0), target: (0.0, 0.0, 0.0), up: (0.0, 0.0, -1.0), half_height: 1.0, width: 16, height: 16),
               shadow_map: 64, shadow_fit: {fit},
               lights: [DistantDisk(direction: (0.0, 1.0, 0.0), angle_degrees: 10.0)],
               objects: [Object(name: \"ground\", mesh: Plane(size: (3.0, 3.0)), casts: {ground_casts}),
                         Object(name: \"quad\", mesh: Quad(a: (-2.0, 0.5, -2.0), b: (-2.0, 0.5, 2.0), c: (0.0, 0.5, 2.0), d: (0.0, 0.5, -2.0)), casts: {quad_casts})])"
    );
    Scene::from_str(&text, ".").unwrap_or_else(|e| panic!("{e}"))
}

/// Per pixel: the technique's visibility, the world position and the truth.
fn render_positions(gpu: &Gpu, technique: &str, scene: &Scene) -> Vec<(f32, Vec3, f32)> {
    let path = root().join("techniques").join(format!("{technique}.ron"));
    let source = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let loaded = compile_technique(gpu, &path, &source, &Default::default()).unwrap_or_else(|e| panic!("{technique}: {e}"));
    let mut ex = loaded
        .bind_scene(&sshc_lab::bind::scene_inputs(scene).unwrap())
        .unwrap_or_else(|e| panic!("{technique}: {e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{technique}: {e}"));
    let vis = ex.inspect().read_camera(CameraOutput::Visibility).unwrap().channel(0);
    let (positions, normals) = positions_normals(&ex).unwrap();
    let truth = Visibility::new(scene).visible_fractions(&positions, &normals, &scene.lights[0], 8);
    positions
        .iter()
        .enumerate()
        .filter(|(_, p)| p.is_finite())
        .map(|(i, p)| (vis[i], *p, truth[i]))
        .collect()
}

/// A ground marked `casts: false` still receives the quad's shadow, with either fit, in
/// the depth-map techniques and the Geometry-pass one (penumbra maps, whose edges now come
/// from the quad alone), and the truth agrees; a quad marked `casts: false` casts none.
/// Without the runtime drawing only the casters from the light, the quad-less cases would
/// be shadowed wherever the ground's own depth shadows it; without the truth skipping
/// non-casters, the truth under a non-casting quad would be 0.
#[test]
fn a_non_casting_ground_receives_shadows_and_a_non_casting_occluder_casts_none() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("no adapter (install lavapipe): {e}"));
    // Outside the penumbra (reach 0.5 tan 5 degrees = 0.044) by more than a few texels and pixels.
    let (umbra, lit) = (-0.4f32, 0.4f32);
    for t in ["hard", "pcf", "pcss", "penumbra-maps"] {
        for fit in ["Scene", "Casters"] {
            let seen = render_positions(&gpu, t, &ground_scene(false, true, fit));
            assert!(seen.len() > 200, "{t}, {fit}: {} pixels", seen.len());
            let (mut dark, mut light) = (0, 0);
            for &(v, p, truth) in &seen {
                if p.x < umbra {
                    assert!(v < 0.05 && truth == 0.0, "{t}, {fit}: under the quad at {p}: {v}, truth {truth}");
                    dark += 1;
                } else if p.x > lit {
                    assert!(v > 0.95 && truth == 1.0, "{t}, {fit}: beside the quad at {p}: {v}, truth {truth}");
                    light += 1;
                }
            }
            assert!(dark > 50 && light > 50, "{t}, {fit}: {dark} shadowed and {light} lit pixels");
        }
        // The quad does not cast: the ground is lit everywhere, in the technique and the truth.
        let seen = render_positions(&gpu, t, &ground_scene(false, false, "Scene"));
        for &(v, p, truth) in &seen {
            assert!(v > 0.95 && truth == 1.0, "{t}, non-casting quad: at {p}: {v}, truth {truth}");
        }
    }
}

/// A glTF file and an OBJ file of the same triangles give the same scene and the same
/// visibility, bit for bit, in the techniques and in the truth. The triangles are a small
/// generated city (towers placed by scaled, turned nodes), placed once by the glTF importer
/// and then written out twice: as a GLB of the placed triangles (one node at the identity)
/// and as an OBJ (`v`, `vn` and `f` lines, floats written in Rust's shortest form, which
/// reads back to the same f32).
#[test]
fn a_gltf_file_and_the_same_geometry_as_obj_give_the_same_visibility() {
    use sshc_lab::scene::generate::{city_glb, soup_glb};
    use std::fmt::Write;
    let city = Scene::from_gltf_slice(&city_glb(3000, 3)).unwrap_or_else(|e| panic!("{e}"));
    let (tris, normals) = (city.triangles(), city.normals());
    let dir = std::env::temp_dir().join(format!("sshc-gltf-obj-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("city.glb"), soup_glb(tris, normals)).unwrap();
    let mut obj = String::new();
    for v in tris.iter().flatten() {
        writeln!(obj, "v {} {} {}", v.x, v.y, v.z).unwrap();
    }
    for n in normals.iter().flatten() {
        writeln!(obj, "vn {} {} {}", n.x, n.y, n.z).unwrap();
    }
    for t in 0..tris.len() {
        let k = 3 * t + 1;
        writeln!(obj, "f {k}//{k} {}//{} {}//{}", k + 1, k + 1, k + 2, k + 2).unwrap();
    }
    std::fs::write(dir.join("city.obj"), obj).unwrap();
    let scene = |mesh: &str| {
        let text = format!(
            "Scene(camera: Perspective(position: (1.2, 2.2, 2.6), target: (0.0, 0.2, 0.0), fov_y_degrees: 60.0, width: 48, height: 48),
                   shadow_map: 256, lights: [DistantDisk(direction: (0.8, 0.4, 0.45), angle_degrees: 3.0)],
                   objects: [Object(mesh: {mesh})])"
        );
        Scene::from_str(&text, &dir).unwrap_or_else(|e| panic!("{mesh}: {e}"))
    };
    let (gltf, obj) = (scene("Gltf(path: \"city.glb\")"), scene("Obj(path: \"city.obj\")"));
    let bits = |s: &Scene| s.vertex_data().iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(gltf.triangles().len(), tris.len());
    assert!(bits(&gltf) == bits(&obj), "the two files' scenes differ");
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("no adapter (install lavapipe): {e}"));
    for t in ["hard", "pcss"] {
        let (a, b) = (render(&gpu, t, &gltf), render(&gpu, t, &obj));
        assert!(a.len() > 500, "{t}: the camera sees {} pixels", a.len());
        // the comparison covers shadow and light: at least 1 pixel in 20 of each
        let shadowed = a.iter().filter(|p| p.0 < 1.0).count();
        assert!(
            20 * shadowed > a.len() && 20 * (a.len() - shadowed) > a.len(),
            "{t}: {shadowed} of {} pixels in shadow",
            a.len()
        );
        let same = a.len() == b.len()
            && a.iter()
                .zip(&b)
                .all(|(p, q)| p.0.to_bits() == q.0.to_bits() && p.2.to_bits() == q.2.to_bits());
        assert!(same, "{t}: the glTF and OBJ scenes' visibility or truth differ");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Cascades (`Loaded::bind_cascades`, fitted by `bind::cascade_inputs`): one cascade is
/// the plain binding, bit for bit, for every bundled technique a sun serves; with several,
/// each pixel takes the cascade whose slice holds its view distance, mixed with the next
/// over the band at its slice's far end, exactly as the combining step states (channel 1
/// of the visibilities says which: `k + t`).
#[test]
fn cascades_select_by_view_distance_and_one_cascade_is_the_plain_binding() {
    use sshc_lab::bind::Cascading;
    let text = "Scene(camera: Perspective(position: (0.0, 1.5, 9.0), target: (0.0, 0.0, -4.0), fov_y_degrees: 55.0, width: 48, height: 48),
        shadow_map: 128, lights: [DistantDisk(direction: (0.5, 0.8, 0.3), angle_degrees: 2.0)],
        objects: [Object(mesh: Plane(size: (30.0, 30.0)), casts: false),
                  Object(mesh: Box(size: (1.0, 1.0, 1.0)), transform: (translate: (0.3, 0.9, 7.3))),
                  Object(mesh: Box(size: (2.0, 3.0, 2.0)), transform: (translate: (-2.0, 1.5, -6.0)))])";
    let scene = Scene::from_str(text, ".").unwrap_or_else(|e| panic!("{e}"));
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("no adapter (install lavapipe): {e}"));
    let cascading = |n| Cascading {
        cascades: Some(n),
        cascade_lambda: Some(0.75),
        cascade_band: Some(0.2),
        no_snap: false,
        cascade_offset: None,
    };
    // every bundled technique that renders a light at infinity, found in techniques/ (not
    // listed): the per-sample ones look from points on a local light, and cascades refuse
    // them
    let at_infinity: Vec<String> = common::bundled_techniques()
        .into_iter()
        .filter(|t| !t.starts_with("examples/"))
        .filter(|t| {
            let path = root().join("techniques").join(format!("{t}.ron"));
            let source = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let graph = sshc::compile_str(&source, &Default::default())
                .unwrap_or_else(|d| panic!("{}", d.render(t, &source)))
                .graph;
            !graph.passes.iter().any(|p| p.views == sshc_graph::Views::PerLightSample)
        })
        .collect();
    assert!(at_infinity.len() >= 16, "{at_infinity:?}");
    for t in at_infinity.iter().map(String::as_str) {
        let path = root().join("techniques").join(format!("{t}.ron"));
        let source = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let loaded = compile_technique(&gpu, &path, &source, &Default::default()).unwrap_or_else(|e| panic!("{t}: {e}"));
        let mut ex = loaded
            .bind_scene(&sshc_lab::bind::scene_inputs_for(&scene, loaded.graph()).unwrap())
            .unwrap_or_else(|e| panic!("{t}: {e}"));
        ex.run_frame().unwrap_or_else(|e| panic!("{t}: {e}"));
        let plain = ex.inspect().read_camera(CameraOutput::Visibility).unwrap().channel(0);
        // one cascade: bound as the scene is
        assert!(cascading(1).bind(&loaded, &scene).unwrap_or_else(|e| panic!("{t}: {e}")).is_none());
        let one = sshc_lab::bind::cascade_inputs(&scene, loaded.graph(), 1, 0.75, true, [0.0; 3]).unwrap_or_else(|e| panic!("{t}: {e}"));
        assert_eq!(one.lights.len(), 1);
        let inputs = sshc_lab::bind::scene_inputs_for(&scene, loaded.graph()).unwrap();
        let mut ex = loaded
            .bind_cascades(&inputs, &[inputs.light_inputs()], &one.slices(0.2))
            .unwrap_or_else(|e| panic!("{t}: {e}"));
        ex.run_frame().unwrap_or_else(|e| panic!("{t}: {e}"));
        let again = ex.inspect().read_camera(CameraOutput::Visibility).unwrap().channel(0);
        assert!(
            plain.iter().zip(&again).all(|(a, b)| a.to_bits() == b.to_bits()),
            "{t}: one cascade differs"
        );

        // three cascades: the selection and the mixture, pixel by pixel
        let (mut ex, _) = cascading(3)
            .bind(&loaded, &scene)
            .unwrap_or_else(|e| panic!("{t}: {e}"))
            .expect("three cascades are bound");
        let c = sshc_lab::bind::cascade_inputs(&scene, loaded.graph(), 3, 0.75, true, [0.0; 3]).unwrap();
        ex.run_frame().unwrap_or_else(|e| panic!("{t}: {e}"));
        let combined = ex.inspect().read_visibilities().unwrap_or_else(|e| panic!("{t}: {e}"));
        let own: Vec<Vec<f32>> = (0..3)
            .map(|k| ex.inspect().read_light_camera(k, CameraOutput::Visibility).unwrap().channel(0))
            .collect();
        let positions = ex.inspect().read_light_camera(0, CameraOutput::Position).unwrap();
        let (eye, forward) = (Vec3::from_array(c.eye), Vec3::from_array(c.forward));
        let mut seen = [0usize; 3];
        for (i, p) in positions.rgba.iter().enumerate() {
            let [v, which, ..] = combined.rgba[i];
            let p = Vec3::new(p[0], p[1], p[2]);
            if !p.is_finite() {
                assert_eq!((v, which), (own[0][i], 0.0), "{t}: pixel {i} sees no surface");
                continue;
            }
            let d = (p - eye).dot(forward);
            let k = (0..2).find(|&k| d <= c.splits[k + 1]).unwrap_or(2);
            // f32 rounding of the distance on either side of a split or a band's start
            let near_edge = c.splits.iter().any(|s| (d - s).abs() < 1e-4 * s.abs().max(1.0));
            if near_edge {
                continue;
            }
            seen[k] += 1;
            let (kk, tt) = (which.floor() as usize, which.fract());
            assert_eq!(kk, k, "{t}: pixel {i} at distance {d} in slice {k} took cascade {which}");
            let want = own[k][i] * (1.0 - tt) + own[(k + 1).min(2)][i] * tt;
            // WGSL's mix in f32: a few roundings of values in [0, 1]
            assert!((v - want).abs() <= 4.0 * f32::EPSILON, "{t}: pixel {i}: {v} against {want}");
        }
        assert!(
            seen.iter().all(|&n| n > 20),
            "{t}: pixels per slice {seen:?}, splits {:?}",
            c.splits
        );
    }
}

/// A host moving its camera refits the cascades in place (the frame's state: the
/// lights' views, the camera and the splits written by prepare, nothing created); the frame equals a
/// fresh binding of the new fit, bit for bit.
#[test]
fn cascades_refitted_in_place_equal_a_fresh_binding() {
    let scene_at = |x: f32| {
        let text = format!(
            "Scene(camera: Perspective(position: ({x}, 1.5, 9.0), target: ({x}, 0.0, -4.0), fov_y_degrees: 55.0, width: 32, height: 32),
            shadow_map: 128, lights: [DistantDisk(direction: (0.5, 0.8, 0.3), angle_degrees: 2.0)],
            objects: [Object(mesh: Plane(size: (30.0, 30.0)), casts: false),
                      Object(mesh: Box(size: (1.0, 1.0, 1.0)), transform: (translate: (0.3, 0.9, 7.3))),
                      Object(mesh: Box(size: (2.0, 3.0, 2.0)), transform: (translate: (-2.0, 1.5, -6.0)))])"
        );
        Scene::from_str(&text, ".").unwrap_or_else(|e| panic!("{e}"))
    };
    let (first, moved) = (scene_at(0.0), scene_at(0.7));
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("no adapter (install lavapipe): {e}"));
    for t in ["hard", "pcss"] {
        let path = root().join("techniques").join(format!("{t}.ron"));
        let source = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let loaded = compile_technique(&gpu, &path, &source, &Default::default()).unwrap_or_else(|e| panic!("{t}: {e}"));
        let fit =
            |s: &Scene| sshc_lab::bind::cascade_inputs(s, loaded.graph(), 3, 0.75, true, [0.0; 3]).unwrap_or_else(|e| panic!("{t}: {e}"));
        let frame = |ex: &mut sshc_lab::run::Bound| {
            ex.run_frame().unwrap_or_else(|e| panic!("{t}: {e}"));
            ex.inspect().read_visibilities().unwrap_or_else(|e| panic!("{t}: {e}")).rgba
        };
        let a = fit(&first);
        let mut ex = loaded
            .bind_cascades(&a.scene, &a.lights, &a.slices(0.2))
            .unwrap_or_else(|e| panic!("{t}: {e}"));
        let before = frame(&mut ex);
        let b = fit(&moved);
        // the frame's state changed in place: the next prepare checks and writes it
        ex.state.lights.clone_from(&b.lights);
        ex.state.camera = sshc_lab::bind::camera(&moved);
        ex.state.slices = Some(b.slices(0.2));
        let in_place = frame(&mut ex);
        let mut fresh = loaded
            .bind_cascades(&b.scene, &b.lights, &b.slices(0.2))
            .unwrap_or_else(|e| panic!("{t}: {e}"));
        let fresh = frame(&mut fresh);
        let bits = |v: &[[f32; 4]]| v.iter().flat_map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
        assert!(
            bits(&in_place) == bits(&fresh),
            "{t}: refitted in place differs from a fresh binding"
        );
        assert!(
            bits(&in_place) != bits(&before),
            "{t}: the camera's move changed nothing (a test of nothing)"
        );
    }
}

/// A glTF file whose nodes share meshes (the generated city: seven tower meshes placed by
/// sixteen nodes) binds as the runtime's meshes and instances (`bind::bind_scene`:
/// `bind_geometry`, each mesh once with its indices, each node an instance placed at
/// upload), not as a flattened soup, and renders what the soup renders.
#[test]
fn a_gltf_of_shared_meshes_binds_as_instances_and_renders_as_its_soup() {
    let mut scene = Scene::from_gltf_slice(&sshc_lab::scene::generate::city_glb(20_000, 3)).unwrap_or_else(|e| panic!("{e}"));
    scene.set_camera_size(96, 96);
    scene.shadow_map = 512;
    let (nodes, meshes) = scene.placements();
    assert!(nodes > meshes, "{nodes} nodes place {meshes} meshes: nothing is shared");
    let inst = scene.instancing(0).expect("the city keeps its instancing");
    assert_eq!(inst.instances.len(), nodes);
    assert_eq!(inst.triangles(), scene.triangles().len());
    let g = sshc_lab::bind::scene_geometry(&scene).expect("host geometry");
    assert_eq!(g.meshes.len(), meshes);
    assert!(g.instances.iter().all(|i| i.placed_at_upload() || i.in_world_space()));
    // each mesh once: fewer vertices than the soup's three a triangle
    let vertices: usize = g.meshes.iter().map(|m| m.positions.len()).sum();
    assert!(vertices * 2 < scene.triangles().len() * 3, "{vertices} vertices");
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("no adapter (install lavapipe): {e}"));
    for t in ["hard", "pcss", "penumbra-limit-maps"] {
        let path = root().join("techniques").join(format!("{t}.ron"));
        let source = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let run = |instances: bool| {
            let loaded = compile_technique(&gpu, &path, &source, &Default::default()).unwrap_or_else(|e| panic!("{t}: {e}"));
            let mut ex = if instances {
                let b = sshc_lab::bind::SceneBinding::of(&scene, loaded.graph(), true).unwrap();
                assert!(matches!(b, sshc_lab::bind::SceneBinding::Instances { .. }), "{t}");
                b.bind(&loaded).unwrap_or_else(|e| panic!("{t}: {e}"))
            } else {
                loaded
                    .bind_scene(&sshc_lab::bind::scene_inputs_for(&scene, loaded.graph()).unwrap())
                    .unwrap()
            };
            ex.run_frame().unwrap_or_else(|e| panic!("{t}: {e}"));
            ex.inspect().read_camera(CameraOutput::Visibility).unwrap().channel(0)
        };
        let (a, b) = (run(true), run(false));
        let differ = a.iter().zip(&b).filter(|(x, y)| x.to_bits() != y.to_bits()).count();
        let max = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
        assert!(a.iter().any(|v| *v < 0.5), "{t}: no shadow in view");
        assert_eq!(differ, 0, "{t}: {differ} pixels differ from the soup's, by up to {max}");
    }
    // three cascades of its sun, on its instances (`bind_geometry_cascades`) and on its soup
    let path = root().join("techniques/pcss.ron");
    let source = std::fs::read_to_string(&path).unwrap();
    let cascading = sshc_lab::bind::Cascading {
        cascades: Some(3),
        cascade_lambda: Some(0.75),
        cascade_band: Some(0.2),
        no_snap: false,
        cascade_offset: None,
    };
    let loaded = compile_technique(&gpu, &path, &source, &Default::default()).unwrap();
    let (mut instanced, _) = cascading.bind(&loaded, &scene).unwrap().expect("cascades are bound");
    assert!(instanced.targets.cascades() == 3);
    let c = sshc_lab::bind::cascade_inputs(&scene, loaded.graph(), 3, 0.75, true, [0.0; 3]).unwrap();
    let mut soup = loaded.bind_cascades(&c.scene, &c.lights, &c.slices(0.2)).unwrap();
    let frame = |ex: &mut sshc_lab::run::Bound| {
        ex.run_frame().unwrap();
        ex.inspect().read_visibilities().unwrap().rgba
    };
    assert!(
        frame(&mut instanced) == frame(&mut soup),
        "cascades on the instances differ from the soup's"
    );
}

/// techniques/examples/pcf-min-early-out.ron returns 1 where the receiver is in front of
/// the min mip chain's blocks under its 7 x 7 footprint: exactly where every tap passes,
/// so its visibility is its PCF's, bit for bit (the same file with the early-out taken
/// out), on scenes with contact and with open penumbrae; and the early-out is taken (at a
/// quarter of the pixels or more).
#[test]
fn the_min_mip_early_out_gives_its_pcf_bit_for_bit() {
    let path = root().join("techniques/examples/pcf-min-early-out.ron");
    let source = std::fs::read_to_string(&path).unwrap();
    // the early-out's condition folded to false: the `else` arm alone, the plain PCF
    let plain = source.replace("if r <= nearest_blocker {", "if false && r <= nearest_blocker {");
    assert_ne!(plain, source);
    // the taps taken out: 0 wherever the early-out is not taken
    let taps = "sum(i in 0..=6, sum(j in 0..=6, select(0.0, 1.0, r <= fetch(z, i - 3, j - 3)))) / 49.0";
    let early = source.replace(taps, "0.0");
    assert_ne!(early, source);
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("no adapter (install lavapipe): {e}"));
    for sc in ["bunny", "contact"] {
        let scene = Scene::load(root().join(format!("scenes/{sc}.ron"))).unwrap_or_else(|e| panic!("{e}"));
        let run = |src: &str| {
            let loaded = compile_technique(&gpu, &path, src, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
            let mut ex = loaded
                .bind_scene(&sshc_lab::bind::scene_inputs_for(&scene, loaded.graph()).unwrap())
                .unwrap();
            ex.run_frame().unwrap();
            ex.inspect().read_camera(CameraOutput::Visibility).unwrap().channel(0)
        };
        let (a, b) = (run(&source), run(&plain));
        let differ = a.iter().zip(&b).filter(|(x, y)| x.to_bits() != y.to_bits()).count();
        assert_eq!(differ, 0, "{sc}: the early-out changed {differ} pixels");
        let taken = run(&early).iter().filter(|v| **v == 1.0).count();
        // docs/language.md 8.7 quotes the bunny's count
        eprintln!("{sc}: the early-out is taken at {taken} of {} pixels", a.len());
        assert!(taken * 4 > a.len(), "{sc}: the early-out is taken at {taken} of {} pixels", a.len());
        assert!(a.iter().any(|v| *v < 0.5), "{sc}: no shadow");
    }
}

/// An f32 summed-area table (`SummedArea(sum: F32)`) is the CPU's f32 emulation
/// (`sshc::eval::f32_table`: the same additions in the same order) bit for bit, at
/// 2048 x 2048 on the bunny's depth map; and that table's rounding against the f64 sums,
/// which docs/language.md quotes (run with `--no-capture`), lies within the stated bounds.
#[test]
fn an_f32_table_is_its_cpu_emulation_bit_for_bit_and_within_the_stated_bound() {
    const TECHNIQUE: &str = r#"Technique(
        name: "f32_table",
        channels: {
            "z": Channel(precision: F32),
            "m": Channel(precision: F32, value: "z", range: (0.0, 1.0)),
        },
        passes: [
            Depth(name: "depth", writes: "shadow", channel: "z"),
            Map(name: "map", reads: ["shadow"], writes: "mapped", channels: ["m"]),
            SummedArea(name: "sat", reads: "mapped", writes: "table", sum: F32),
            Shade(name: "shade", reads: ["table"], visibility: "saturate(sample_box(m, 4.0 * texel_size, 4.0 * texel_size))"),
        ],
    )"#;
    let n = 2048usize;
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("no adapter (install lavapipe): {e}"));
    let mut scene = Scene::load(root().join("scenes/bunny.ron")).unwrap_or_else(|e| panic!("{e}"));
    scene.shadow_map = n as u32;
    let loaded = compile_technique(&gpu, Path::new("f32_table.ron"), TECHNIQUE, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
    let mut ex = loaded
        .bind_scene(&sshc_lab::bind::scene_inputs_for(&scene, loaded.graph()).unwrap())
        .unwrap();
    ex.run_frame().unwrap();
    let values = ex.inspect().read_texture("mapped", 0, 0).unwrap().channel(0);
    let table = ex.inspect().read_texture("table", 0, 0).unwrap().channel(0);
    let cpu = sshc::eval::f32_table(&values, n, 0.5);
    let differ = table.iter().zip(&cpu).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
    assert_eq!(differ, 0, "{differ} of {} entries differ from the emulation", n * n);
    // the rounding against the exact sums: entries, and box means of side k anywhere
    let exact = sshc::eval::f64_table(&values, n, 0.5);
    let entry = table.iter().zip(&exact).map(|(a, b)| (f64::from(*a) - b).abs()).fold(0.0, f64::max);
    let bound = sshc::eval::f32_entry_bound(n as f64, 0.5);
    eprintln!("f32 table, bunny depth, {n}^2: largest entry error {entry:.3e} (stated bound {bound:.3e})");
    assert!(entry <= bound);
    let at = |t: &dyn Fn(usize) -> f64, x: isize, y: isize| if x < 0 || y < 0 { 0.0 } else { t(y as usize * n + x as usize) };
    for k in [1usize, 4, 16, 64, 256] {
        let (gpu_t, f64_t) = (|i: usize| f64::from(table[i]), |i: usize| exact[i]);
        let mean = |t: &dyn Fn(usize) -> f64, x: usize, y: usize| {
            let (x0, y0, x1, y1) = (x as isize - 1, y as isize - 1, (x + k - 1) as isize, (y + k - 1) as isize);
            (at(t, x1, y1) - at(t, x0, y1) - at(t, x1, y0) + at(t, x0, y0)) / (k * k) as f64
        };
        let (mut worst, mut sq, mut count) = (0.0f64, 0.0f64, 0usize);
        for y in (0..=n - k).step_by(k.max(3)) {
            for x in (0..=n - k).step_by(k.max(3)) {
                let e = (mean(&gpu_t, x, y) - mean(&f64_t, x, y)).abs();
                worst = worst.max(e);
                sq += e * e;
                count += 1;
            }
        }
        let stated = sshc::eval::f32_box_bound(n as f64, 0.5, (k * k) as f64);
        eprintln!(
            "  boxes of {k} x {k}: largest error {worst:.3e}, RMS {:.3e} over {count} boxes (stated bound {stated:.3e})",
            (sq / count as f64).sqrt()
        );
        assert!(worst <= stated, "{k} x {k}: {worst} above the stated bound {stated}");
    }
}

/// Issue 48, item 13: a valid glTF of more instances of one mesh than the runtime binds
/// (`MAX_INSTANCES`, 65,536) failed at bind with no fallback; such a scene binds its soup
/// (the triangles the importer placed) and renders.
#[test]
fn more_instances_than_the_runtime_binds_fall_back_to_the_soup() {
    use sshc_lab::scene::generate::instances_glb;
    let copies = sshc_runtime::gpu::MAX_INSTANCES + 10;
    let dir = std::env::temp_dir().join(format!("sshc-instances-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("many.glb"), instances_glb(copies)).unwrap();
    let scene = Scene::from_str(
        "Scene(camera: Perspective(position: (-20.0, 60.0, -20.0), target: (128.0, 0.0, 128.0), fov_y_degrees: 60.0, width: 32, height: 32),
               shadow_map: 256, lights: [Directional(direction: (0.3, 1.0, 0.2))],
               objects: [Object(mesh: Plane(size: (600.0, 600.0))), Object(mesh: Gltf(path: \"many.glb\"))])",
        &dir,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.triangles().len(), 2 + copies);
    assert!(scene.instancing(1).is_some(), "the importer keeps the instancing");
    assert!(sshc_lab::bind::scene_geometry(&scene).is_none(), "bound as a soup");
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("no adapter (install lavapipe): {e}"));
    let pixels = render(&gpu, "hard", &scene);
    assert!(pixels.len() > 500, "the camera sees {} pixels", pixels.len());
    let _ = std::fs::remove_dir_all(&dir);
}
