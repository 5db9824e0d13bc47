//! The importer's unit tests, on glTF documents written here (JSON with its buffer as a
//! data URI) and on the generated city.

use super::mesh::triangle_list;
use super::*;
use crate::Scene;
use serde_json::{Value, json};

/// A glTF (JSON) whose one buffer is a data URI holding `floats` then `indices`.
/// Accessor 0: the positions (`floats.len() / 3` VEC3); accessor 1: the indices.
fn with_buffer(mut root: Value, floats: &[f32], indices: &[u32]) -> Vec<u8> {
    use base64::Engine;
    let mut bin: Vec<u8> = floats.iter().flat_map(|x| x.to_le_bytes()).collect();
    let split = bin.len();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for v in floats.chunks_exact(3) {
        for k in 0..3 {
            (lo[k], hi[k]) = (lo[k].min(v[k]), hi[k].max(v[k]));
        }
    }
    // glTF 2.0 requires POSITION's bounds; a NaN corner keeps them finite (min/max skip it)
    let defaults = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len(), "uri": uri}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": split},
            {"buffer": 0, "byteOffset": split, "byteLength": bin.len() - split},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": floats.len() / 3, "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": indices.len(), "type": "SCALAR"},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    });
    let (Value::Object(d), Value::Object(r)) = (defaults, &mut root) else {
        unreachable!()
    };
    for (k, v) in d {
        r.entry(k).or_insert(v);
    }
    root.to_string().into_bytes()
}

const TRIANGLE: [f32; 9] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0];

fn error_of(bytes: &[u8]) -> String {
    match Scene::from_gltf_slice(bytes) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.to_string(),
    }
}

/// glTF 2.0 section 3.5.2: a node's world matrix is its parent's times its own, its own
/// being T * R * S. The expected corners are worked by hand, child first: child scale
/// 0.5 and move +Y; parent scale 2, turn 90 degrees about +Y, move +X. The reverse order
/// (parent's matrix applied first) would put (1, 0, 0) at (0.5, 1, -1), not (1, 2, -1).
#[test]
fn nested_node_transforms_apply_the_child_first_then_the_parent() {
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let root = json!({
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"children": [1], "translation": [1.0, 0.0, 0.0], "rotation": [0.0, s, 0.0, s], "scale": [2.0, 2.0, 2.0]},
            {"mesh": 0, "translation": [0.0, 1.0, 0.0], "scale": [0.5, 0.5, 0.5]},
        ],
    });
    let scene = Scene::from_gltf_slice(&with_buffer(root, &TRIANGLE, &[0, 1, 2])).unwrap_or_else(|e| panic!("{e}"));
    let tri = scene.triangles()[0];
    // (1,0,0) -> child (0.5,1,0) -> parent scale (1,2,0) -> turn (0,2,-1) -> move (1,2,-1)
    // (0,0,1) -> (0,1,0.5) -> (0,2,1) -> (1,2,0) -> (2,2,0)
    // (0,1,0) -> (0,1.5,0) -> (0,3,0) -> (0,3,0) -> (1,3,0)
    let want = [Vec3::new(1.0, 2.0, -1.0), Vec3::new(2.0, 2.0, 0.0), Vec3::new(1.0, 3.0, 0.0)];
    for (got, want) in tri.iter().zip(want) {
        // a turn by 90 degrees in f32 (cos is 4e-8, not 0), scaled by 2: a few ulps of 3
        assert!(got.distance(want) < 4.0 * f32::EPSILON * 3.0, "{tri:?} against {want:?}");
    }
}

/// Issue 48, item 7: two nested scales of 1e20 multiply past f32 (each finite), and a
/// finite scale of 1e30 carries a corner past it: both are refused naming the node,
/// where they placed NaN and infinite triangles and drew an empty, all-lit image.
#[test]
fn transforms_that_overflow_f32_are_refused_naming_the_node() {
    let nested = json!({
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"name": "outer", "children": [1], "scale": [1e20, 1e20, 1e20]},
            {"name": "inner", "mesh": 0, "scale": [1e20, 1e20, 1e20]},
        ],
    });
    let e = Scene::from_gltf_slice(&with_buffer(nested, &TRIANGLE, &[0, 1, 2]))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("inner") && e.contains("world transform (its parents' times its own) overflows f32"),
        "{e}"
    );
    let far = json!({
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "far", "mesh": 0, "scale": [1e30, 1e30, 1e30]}],
    });
    let big = [1e10f32, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0];
    let e = Scene::from_gltf_slice(&with_buffer(far, &big, &[0, 1, 2])).unwrap_err().to_string();
    assert!(e.contains("far") && e.contains("outside f32's range"), "{e}");
}

/// A mesh placed by two nodes is read once and placed twice; the scene says so.
#[test]
fn a_mesh_shared_by_nodes_is_placed_by_each() {
    let root = json!({
        "nodes": [{"mesh": 0}, {"mesh": 0, "translation": [0.0, 0.0, 5.0]}],
    });
    let scene = Scene::from_gltf_slice(&with_buffer(root, &TRIANGLE, &[0, 1, 2])).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.triangles().len(), 2);
    assert_eq!(scene.placements(), (2, 1));
    assert_eq!(scene.triangles()[1][0], Vec3::new(1.0, 0.0, 5.0));
    // no camera and no light: a framing camera and a sun, both noted
    let notes = scene.notes().join("\n");
    assert!(notes.contains("no camera") && notes.contains("no light"), "{notes}");
    assert!(matches!(scene.lights[..], [Light::DistantDisk { .. }]));
}

/// KHR_lights_punctual: a light shines along its node's -Z. Directional: a distant disk
/// towards +Z of the node, `extras.angle_degrees` wide (default 0.5). Point: a sphere of
/// `extras.radius` (default 1 % of the diagonal). Spot: a disk facing along the spot.
#[test]
fn each_light_kind_maps_as_documented() {
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let root = json!({
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "directional", "extras": {"angle_degrees": 2.0}},
            {"type": "directional"},
            {"type": "point", "extras": {"radius": 0.25}},
            {"type": "spot", "spot": {"outerConeAngle": 0.5}},
        ]}},
        "nodes": [
            {"mesh": 0},
            // turned -90 degrees about X: -Z becomes -Y (shining down), +Z becomes +Y
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "rotation": [-s, 0.0, 0.0, s]},
            {"extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"extensions": {"KHR_lights_punctual": {"light": 2}}, "translation": [0.0, 4.0, 0.0]},
            {"extensions": {"KHR_lights_punctual": {"light": 3}}, "translation": [0.0, 3.0, 0.0], "rotation": [-s, 0.0, 0.0, s]},
        ],
    });
    let scene = Scene::from_gltf_slice(&with_buffer(root, &TRIANGLE, &[0, 1, 2])).unwrap_or_else(|e| panic!("{e}"));
    let diagonal = (scene.bounds().1 - scene.bounds().0).length();
    let near = |a: Vec3, b: Vec3| a.distance(b) < 1e-6;
    match &scene.lights[..] {
        [
            Light::DistantDisk {
                direction: d0,
                angle_degrees: a0,
            },
            Light::DistantDisk {
                direction: d1,
                angle_degrees: a1,
            },
            Light::Sphere { center, radius },
            Light::Disk {
                center: c3,
                normal,
                radius: r3,
            },
        ] => {
            assert!(near(*d0, Vec3::Y) && *a0 == 2.0, "{d0} {a0}");
            assert!(near(*d1, Vec3::Z) && *a1 == DEFAULT_SUN_DEGREES, "{d1} {a1}");
            assert!(*center == Vec3::new(0.0, 4.0, 0.0) && *radius == 0.25);
            assert!(near(*normal, Vec3::NEG_Y) && *c3 == Vec3::new(0.0, 3.0, 0.0));
            assert_eq!(*r3, DEFAULT_RADIUS_FRACTION * diagonal);
        }
        other => panic!("{other:?}"),
    }
    assert!(
        scene.notes().iter().any(|n| n.contains("cone angles are ignored")),
        "{:?}",
        scene.notes()
    );
}

#[test]
fn more_lights_than_the_runtime_binds_are_refused_with_the_count() {
    let n = MAX_LIGHTS + 1;
    let lights: Vec<Value> = (0..n).map(|_| json!({"type": "point"})).collect();
    let mut nodes = vec![json!({"mesh": 0})];
    nodes.extend((0..n).map(|i| json!({"extensions": {"KHR_lights_punctual": {"light": i}}})));
    let root = json!({"extensions": {"KHR_lights_punctual": {"lights": lights}}, "nodes": nodes});
    let e = error_of(&with_buffer(root, &TRIANGLE, &[0, 1, 2]));
    assert!(
        e.contains(&format!("{n} lights")) && e.contains(&format!("limit of {MAX_LIGHTS}")),
        "{e}"
    );
}

/// The first camera the traversal meets: its node's position, looking down its -Z.
#[test]
fn the_first_camera_is_placed_by_its_node() {
    let root = json!({
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1, "aspectRatio": 2.0}}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0.0, 0.5, 6.0]}],
    });
    let scene = Scene::from_gltf_slice(&with_buffer(root, &TRIANGLE, &[0, 1, 2])).unwrap_or_else(|e| panic!("{e}"));
    match scene.camera {
        Camera::Perspective {
            position,
            target,
            fov_y_degrees,
            width,
            height,
            ..
        } => {
            assert_eq!(position, Vec3::new(0.0, 0.5, 6.0));
            assert_eq!(target, Vec3::new(0.0, 0.5, 5.0));
            assert_eq!((width, height), (2 * CAMERA_HEIGHT, CAMERA_HEIGHT));
            assert!((fov_y_degrees - 0.5f32.to_degrees()).abs() < 1e-4);
        }
        Camera::Orthographic { .. } => panic!("orthographic"),
    }
}

/// Bad files name the file and the node, mesh, primitive or accessor at fault.
#[test]
fn bad_files_are_errors_that_name_the_part_at_fault() {
    let ok = json!({"nodes": [{"mesh": 0}]});
    let tri = |root: Value| with_buffer(root, &TRIANGLE, &[0, 1, 2]);
    let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        ("not glTF", b"{ nonsense".to_vec(), &["cannot read it"]),
        (
            "a short GLB header",
            b"glTF\x02\x00\x00\x00\x05\x00\x00\x00".to_vec(),
            &["GLB header"],
        ),
        (
            "an index past the vertices",
            with_buffer(ok.clone(), &TRIANGLE, &[0, 1, 7]),
            &["mesh 0 primitive 0", "index 2 is 7"],
        ),
        (
            "NaN positions",
            with_buffer(ok.clone(), &[f32::NAN, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0], &[0, 1, 2]),
            &["POSITION (accessor 0)", "vertex 0 is NaN"],
        ),
        (
            "a cycle of nodes",
            tri(json!({"scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "children": [1]}, {"children": [0]}]})),
            &["node 0", "reached twice"],
        ),
        (
            "a required extension",
            tri(
                json!({"nodes": [{"mesh": 0}], "extensionsRequired": ["KHR_draco_mesh_compression"], "extensionsUsed": ["KHR_draco_mesh_compression"]}),
            ),
            &["KHR_draco_mesh_compression"],
        ),
        (
            "a missing buffer file",
            tri(json!({"nodes": [{"mesh": 0}], "buffers": [{"byteLength": 48, "uri": "missing.bin"}]})),
            &["buffer 0", "missing.bin"],
        ),
        (
            "an accessor out of its view",
            tri(json!({"nodes": [{"mesh": 0}], "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 1000, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1]},
                {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"},
            ]})),
            &["accessor 0", "1000 elements", "out of range"],
        ),
        (
            "a view out of its buffer",
            tri(json!({"nodes": [{"mesh": 0}], "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": 36},
                {"buffer": 0, "byteOffset": 36, "byteLength": 400},
            ]})),
            &["buffer view 1", "outside its buffer"],
        ),
        (
            "positions of the wrong type",
            tri(json!({"nodes": [{"mesh": 0}], "accessors": [
                {"bufferView": 0, "componentType": 5123, "count": 9, "type": "SCALAR", "min": [0], "max": [1]},
                {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"},
            ]})),
            &["meshes[0].primitives[0]", "POSITION"],
        ),
    ];
    for (what, bytes, wants) in cases {
        let e = error_of(&bytes);
        assert!(e.contains("glTF `<memory>`"), "{what}: {e}");
        for w in wants {
            assert!(e.contains(w), "{what}: `{w}` missing from: {e}");
        }
        assert!(e.contains("hint:"), "{what}: {e}");
    }
}

/// Points and lines are skipped and counted; materials are ignored, said once.
#[test]
fn what_is_ignored_is_said_once() {
    let root = json!({
        "materials": [{}, {}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": 0}, "indices": 1, "material": 0},
            {"attributes": {"POSITION": 0}, "mode": 1},
        ]}],
    });
    let scene = Scene::from_gltf_slice(&with_buffer(root, &TRIANGLE, &[0, 1, 2])).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.triangles().len(), 1);
    let notes = scene.notes();
    assert_eq!(notes.iter().filter(|n| n.contains("2 material(s)")).count(), 1, "{notes:?}");
    assert_eq!(
        notes.iter().filter(|n| n.contains("1 primitive(s) of points or lines")).count(),
        1,
        "{notes:?}"
    );
}

/// Strips and fans become the triangles glTF 2.0 section 3.7.2.1 lists.
#[test]
fn strips_and_fans_become_triangle_lists() {
    assert_eq!(triangle_list(Mode::TriangleStrip, &[0, 1, 2, 3, 4]), [0, 1, 2, 2, 1, 3, 2, 3, 4]);
    assert_eq!(triangle_list(Mode::TriangleFan, &[0, 1, 2, 3]), [1, 2, 0, 2, 3, 0]);
    assert_eq!(triangle_list(Mode::Triangles, &[0, 1, 2, 3]), [0, 1, 2]);
}

/// The generated city: the same bytes for the same seed, at least the triangles asked
/// for and less than one tower more, each tower a node placing one of six meshes.
#[test]
fn the_city_is_reproducible_and_reaches_its_size() {
    let a = crate::generate::city_glb(20_000, 7);
    assert_eq!(a, crate::generate::city_glb(20_000, 7));
    assert_ne!(a, crate::generate::city_glb(20_000, 8));
    let scene = Scene::from_gltf_slice(&a).unwrap_or_else(|e| panic!("{e}"));
    let n = scene.triangles().len();
    // the largest tower has 8 * 12 * 32 + 12 = 3084 triangles
    assert!((20_000..20_000 + 3084).contains(&n), "{n}");
    let (nodes, meshes) = scene.placements();
    // the ground and some of the six towers' meshes, each read once
    assert!((3..=7).contains(&meshes), "{meshes}");
    assert!(nodes > 10, "{nodes}");
    // every tower stands on the ground
    assert!(scene.bounds().0.y.abs() < 1e-6, "{:?}", scene.bounds());
}
