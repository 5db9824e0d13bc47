//! Scenes (loading, errors, light views) and the CPU visibility query (against exact
//! answers: a box over a point light, half-blocked lights, the straight edge's closed
//! form).

use std::path::{Path, PathBuf};

use glam::{Vec3, Vec4};
use sshc_lab::scene::{Light, Scene, SceneErrorKind, ShadowFit, corners};
use sshc_lab::visibility::Visibility;

mod common;
use common::{bundled_scenes, temp_dir};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")
}

fn bundled(name: &str) -> Scene {
    let path = scenes_dir().join(format!("{name}.ron"));
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

const CAMERA: &str = "camera: Perspective(position: (0.0, 3.0, 5.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 45.0, width: 32, height: 32)";

fn scene_with(lights: &str, objects: &str) -> Scene {
    let text = format!("Scene({CAMERA}, shadow_map: 64, lights: [{lights}], objects: [{objects}])");
    Scene::from_str(&text, ".").unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn every_bundled_scene_loads() {
    let names = bundled_scenes();
    assert!(names.len() >= 9, "{names:?}");
    for name in &names {
        let name = name.as_str();
        let scene = bundled(name);
        let tris = scene.triangles();
        assert!(!tris.is_empty(), "{name}: no triangles");
        assert_eq!(scene.normals().len(), tris.len());
        assert_eq!(
            scene.vertex_data().len(),
            tris.len() * 18,
            "{name}: 3 vertices x (position + normal)"
        );
        assert!(!scene.lights.is_empty(), "{name}: no light");
        assert_eq!(scene.camera_size(), (256, 256), "{name}");
        // 512 texels but where a paper's set-up says otherwise (triangle-lawlor: 32)
        assert!(
            scene.shadow_map.is_power_of_two() && (16..=2048).contains(&scene.shadow_map),
            "{name}"
        );
        for n in scene.normals().iter().flatten() {
            assert!((n.length() - 1.0).abs() < 1e-4, "{name}: normal {n}");
        }
        let (lo, hi) = scene.bounds();
        assert!(lo.is_finite() && hi.is_finite() && lo.cmple(hi).all(), "{name}: bounds");
        let vp = scene.camera_view_proj();
        assert!(vp.is_finite(), "{name}: camera matrix");
        // The bounds' centre is in front of the camera.
        let c = vp * ((lo + hi) * 0.5).extend(1.0);
        assert!(c.w > 0.0, "{name}: the scene is behind the camera");
    }
    assert_eq!(bundled("bunny").triangles().len(), 3674 + 2, "bunny + floor");
}

#[test]
fn camera_size_can_be_overridden() {
    let mut scene = bundled("edge");
    scene.set_camera_size(16, 8);
    scene.shadow_map = 32;
    assert_eq!(scene.camera_size(), (16, 8));
    // Orthographic: a point half_height above the centre line lands on the top edge.
    let p = scene.camera_view_proj() * Vec4::new(0.0, 0.0, -0.25, 1.0);
    assert!((p.y / p.w - 1.0).abs() < 1e-5, "{p}");
}

#[test]
fn a_syntax_error_names_line_and_column() {
    let dir = temp_dir("syntax");
    let path = dir.join("bad.ron");
    std::fs::write(&path, "Scene(\n    camera: Orthographic(position: (0.0, 1.0, 0.0), target: (0.0, 0.0, 0.0),\n        half_height: 1.0 width: 8, height: 8),\n)\n")
        .unwrap();
    let err = Scene::load(&path).unwrap_err();
    assert_eq!(err.kind(), SceneErrorKind::Syntax);
    let (line, col) = err.line_col().expect("a position");
    assert_eq!(line, 3, "{err}");
    assert!(col > 1, "{err}");
    let text = err.to_string();
    assert!(text.starts_with(&format!("{}:3:{col}: error:", path.display())), "{text}");
    assert!(text.contains("hint:"), "{text}");
}

#[test]
fn an_unknown_field_names_line_column_and_the_fields_allowed() {
    let text = "Scene(\n  camera: Perspective(position: (0.0, 1.0, 2.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 40.0, width: 8, height: 8),\n  shadow_map: 8,\n  lights: [Sphere(center: (0.0, 2.0, 0.0), radius: 0.5, colour: (1.0, 1.0, 1.0))],\n)";
    let err = Scene::from_str(text, ".").unwrap_err();
    assert_eq!(err.line_col().map(|p| p.0), Some(4), "{err}");
    assert!(err.hint().unwrap().contains("center, radius"), "{err}");
    assert!(err.to_string().starts_with("<scene>:4:"), "{err}");

    let missing = "Scene(camera: Perspective(position: (0.0, 1.0, 2.0), target: (0.0, 0.0, 0.0), width: 8, height: 8), shadow_map: 8)";
    let err = Scene::from_str(missing, ".").unwrap_err();
    assert!(err.message().contains("fov_y_degrees"), "{err}");
    assert!(err.line_col().is_some());
}

#[test]
fn a_value_out_of_range_names_its_path_and_a_fix() {
    let text = format!(
        "Scene({CAMERA}, shadow_map: 64, lights: [Point(position: (0.0, 1.0, 0.0)), Disk(center: (0.0, 2.0, 0.0), normal: (0.0, -1.0, 0.0), radius: -1.0)])"
    );
    let err = Scene::from_str(&text, ".").unwrap_err();
    assert_eq!(err.kind(), SceneErrorKind::Invalid);
    assert_eq!(err.at(), Some("lights[1] (Disk).radius"));
    assert!(err.hint().is_some());

    let text = "Scene(camera: Orthographic(position: (0.0, 1.0, 0.0), target: (0.0, 0.0, 0.0), half_height: 1.0, width: 8, height: 8), shadow_map: 8)";
    let err = Scene::from_str(text, ".").unwrap_err();
    assert_eq!(
        err.at(),
        Some("camera (Orthographic).up"),
        "looking straight down with up = +Y: {err}"
    );
    assert!(err.hint().unwrap().contains("(0.0, 0.0, -1.0)"));

    let text = format!("Scene({CAMERA}, shadow_map: 0)");
    assert_eq!(Scene::from_str(&text, ".").unwrap_err().at(), Some("shadow_map"));
}

#[test]
fn obj_paths_may_not_leave_the_scene_folder() {
    let root = temp_dir("escape");
    let inner = root.join("scenes");
    std::fs::create_dir_all(&inner).unwrap();
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::fs::write(root.join("outside.obj"), obj).unwrap();
    std::fs::write(inner.join("inside.obj"), obj).unwrap();
    let scene = |path: &str| format!("Scene({CAMERA}, shadow_map: 8, objects: [Object(mesh: Obj(path: {path:?}))])");

    let ok = Scene::from_str(&scene("inside.obj"), &inner).unwrap();
    assert_eq!(ok.triangles().len(), 1);

    for bad in ["../outside.obj", "./../scenes/../outside.obj", "/etc/passwd", ""] {
        let err = Scene::from_str(&scene(bad), &inner).unwrap_err();
        assert_eq!(err.kind(), SceneErrorKind::Mesh, "{bad}: {err}");
        assert_eq!(err.at(), Some("objects[0].mesh.path"), "{bad}: {err}");
    }
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(root.join("outside.obj"), inner.join("link.obj")).unwrap();
        let err = Scene::from_str(&scene("link.obj"), &inner).unwrap_err();
        assert!(err.message().contains("link"), "{err}");
    }
    // A material library is never opened, even one that names a file outside.
    std::fs::write(inner.join("mtl.obj"), format!("mtllib ../outside.mtl\n{obj}")).unwrap();
    assert_eq!(Scene::from_str(&scene("mtl.obj"), &inner).unwrap().triangles().len(), 1);
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn obj_normals_are_used_when_present_and_computed_when_not() {
    let dir = temp_dir("normals");
    // A quad in the XZ plane facing +Y, with tilted normals in the file.
    std::fs::write(
        dir.join("with.obj"),
        "v 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nvn 0.6 0.8 0\nf 1//1 2//1 3//1 4//1\n",
    )
    .unwrap();
    std::fs::write(dir.join("without.obj"), "v 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nf 1 2 3 4\n").unwrap();
    let load = |file: &str| {
        let text =
            format!("Scene({CAMERA}, shadow_map: 8, objects: [Object(mesh: Obj(path: {file:?}), transform: (scale: (2.0, 1.0, 1.0)))])");
        Scene::from_str(&text, &dir).unwrap_or_else(|e| panic!("{e}"))
    };
    let with = load("with.obj");
    assert_eq!(with.triangles().len(), 2, "triangulated");
    // Normals transform by the inverse transpose: (0.6, 0.8, 0) scaled x2 in x -> (0.3, 0.8, 0).
    let expect = Vec3::new(0.3, 0.8, 0.0).normalize();
    assert!(with.normals()[0][0].abs_diff_eq(expect, 1e-5), "{}", with.normals()[0][0]);
    let without = load("without.obj");
    for n in without.normals().iter().flatten() {
        assert!(n.abs_diff_eq(Vec3::Y, 1e-5), "{n}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn degenerate_triangles_are_dropped_and_an_empty_scene_works() {
    let scene = scene_with(
        "Point(position: (0.0, 2.0, 0.0))",
        "Object(mesh: Triangle(a: (0.0, 0.0, 0.0), b: (1.0, 0.0, 0.0), c: (2.0, 0.0, 0.0))), Object(mesh: Triangle(a: (0.0, 1.0, 0.0), b: (0.0, 1.0, 0.0), c: (1.0, 1.0, 1.0)))",
    );
    assert!(scene.triangles().is_empty());
    assert_eq!(scene.bounds(), (Vec3::ZERO, Vec3::ZERO));
    let vis = Visibility::new(&scene);
    assert_eq!(vis.visible_fraction(Vec3::ZERO, &scene.lights[0], 4, 0), 1.0);
    let view = scene.lights[0].view(scene.bounds());
    assert!(view.view_proj.is_finite() && view.near > 0.0 && view.far > view.near);
    assert!(scene.camera_view_proj().is_finite());
}

#[test]
fn mirrored_objects_keep_their_faces_outwards() {
    let scene = scene_with(
        "Point(position: (0.0, 2.0, 0.0))",
        "Object(mesh: Box(size: (1.0, 1.0, 1.0)), transform: (scale: (-1.0, 1.0, 1.0)))",
    );
    for (t, n) in scene.triangles().iter().zip(scene.normals()) {
        let face = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        let centroid = (t[0] + t[1] + t[2]) / 3.0;
        assert!(face.dot(centroid) > 0.0, "winding points in");
        assert!(n[0].abs_diff_eq(face, 1e-5), "normal {} vs face {face}", n[0]);
    }
}

/// Every corner of the bounds projects inside the clip volume, and its linear depth
/// `(-(view * p).z - near) / (far - near)` is in [0, 1].
fn check_view(what: &str, light: &Light, bounds: (Vec3, Vec3)) {
    let v = light.view(bounds);
    assert!(v.near > 0.0 && v.far > v.near, "{what}: near {} far {}", v.near, v.far);
    assert!(v.view_proj.abs_diff_eq(v.proj * v.view, 1e-5));
    assert_eq!(v.orthographic, light.is_distant(), "{what}");
    for c in corners(bounds) {
        let clip = v.view_proj * c.extend(1.0);
        let w = clip.w;
        let tol = 1e-5 * w.abs();
        assert!(w > 0.0, "{what}: corner {c} behind the light");
        assert!(
            clip.x.abs() <= w + tol && clip.y.abs() <= w + tol,
            "{what}: corner {c} outside ({clip})"
        );
        assert!(clip.z >= -tol && clip.z <= w + tol, "{what}: corner {c} depth {}", clip.z / w);
        let depth = (-(v.view * c.extend(1.0)).z - v.near) / (v.far - v.near);
        assert!((0.0..=1.0).contains(&depth), "{what}: corner {c} linear depth {depth}");
    }
}

#[test]
fn light_views_hold_the_whole_scene() {
    for name in bundled_scenes() {
        let name = name.as_str();
        let scene = bundled(name);
        for light in &scene.lights {
            check_view(name, light, scene.bounds());
        }
    }
    // Every kind, over a flat floor-like box and a tall one, from several sides.
    let boxes = [
        (Vec3::new(-3.0, 0.0, -3.0), Vec3::new(3.0, 0.0, 3.0)),
        (Vec3::new(-0.5, 0.0, -0.5), Vec3::new(0.5, 10.0, 0.5)),
    ];
    let dirs = [Vec3::Y, Vec3::new(0.3, 1.0, -0.4), Vec3::new(1.0, 0.01, 0.0), -Vec3::Y];
    for bounds in boxes {
        for d in dirs {
            let d = d.normalize();
            let p = (bounds.0 + bounds.1) * 0.5 + d * 20.0;
            let lights = [
                Light::Point { position: p },
                Light::Directional { direction: d },
                Light::Sphere { center: p, radius: 0.5 },
                Light::Disk {
                    center: p,
                    normal: -d,
                    radius: 0.5,
                },
                Light::Rectangle {
                    center: p,
                    normal: -d,
                    u_axis: d.any_orthonormal_vector(),
                    half_width: 0.5,
                    half_height: 0.2,
                },
                Light::Segment {
                    a: p - Vec3::X,
                    b: p + Vec3::X,
                },
                Light::DistantDisk {
                    direction: d,
                    angle_degrees: 5.0,
                },
                Light::Triangle {
                    a: p - Vec3::X,
                    b: p + Vec3::X,
                    c: p + Vec3::Z,
                },
            ];
            for light in &lights {
                check_view(&format!("{light:?} over {bounds:?}"), light, bounds);
            }
        }
    }
    // Depth range extremes: a light 1e-3 above a tiny box and 1e4 away from a large one.
    check_view(
        "near",
        &Light::Point {
            position: Vec3::new(0.0, 1e-3 + 1e-3, 0.0),
        },
        (Vec3::splat(-1e-3), Vec3::splat(1e-3)),
    );
    check_view(
        "far",
        &Light::Point {
            position: Vec3::new(0.0, 1e4, 0.0),
        },
        (Vec3::splat(-10.0), Vec3::splat(10.0)),
    );
}

#[test]
fn light_view_describes_the_light() {
    let bounds = (Vec3::splat(-1.0), Vec3::splat(1.0));
    let v = Light::DistantDisk {
        direction: Vec3::new(0.0, 2.0, 0.0),
        angle_degrees: 10.0,
    }
    .view(bounds);
    assert_eq!(v.position_or_direction, Vec4::new(0.0, 1.0, 0.0, 0.0));
    assert!((v.angle - 10f32.to_radians()).abs() < 1e-6);
    let v = Light::Rectangle {
        center: Vec3::Y * 5.0,
        normal: -Vec3::Y,
        u_axis: Vec3::X,
        half_width: 0.5,
        half_height: 0.25,
    }
    .view(bounds);
    assert_eq!(v.position_or_direction, Vec4::new(0.0, 5.0, 0.0, 1.0));
    assert_eq!(v.size, 0.5);
    assert_eq!(v.angle, 0.0);
    let seg = Light::Segment { a: Vec3::ZERO, b: Vec3::X };
    assert_eq!(seg.segment_samples(3).unwrap(), vec![Vec3::ZERO, Vec3::X * 0.5, Vec3::X]);
}

/// The linear-light scenes (Heidrich et al. 2000, figure 9's setting): the whole shadow
/// (every ground point that does not see all of the light, on a grid of 0.05 over the
/// 4 x 4 ground) is inside the camera's frame with a 5 % margin and clear of the ground's
/// edge, and there are wide penumbrae: under the segment light, the grid row z = -0.3
/// across the blocker has over 0.9 of partly lit ground (its two side edges' penumbrae,
/// about 0.75 and 1.1 wide there by similar triangles; 1.9 measured).
#[test]
fn the_linear_scenes_show_their_whole_shadow() {
    for name in ["linear", "linear-triangle", "linear-rectangle"] {
        let scene = bundled(name);
        let vis = Visibility::new(&scene);
        let light = &scene.lights[0];
        let vp = scene.camera_view_proj();
        let (mut shadowed, mut partial) = (0, 0);
        for i in 0..=80 {
            for j in 0..=80 {
                let p = Vec3::new(-2.0 + 0.05 * i as f32, 0.0, -2.0 + 0.05 * j as f32);
                // 16 x 16 stratified samples: a point sharing a few percent of the light
                // with the blocker is found
                let v = vis.visible_fraction_at(p, Vec3::Y, light, 16, (i * 81 + j) as u64);
                if v >= 1.0 {
                    continue;
                }
                shadowed += 1;
                partial += usize::from(v > 0.0);
                assert!(
                    p.x.abs() < 1.9 && p.z.abs() < 1.9,
                    "{name}: the shadow reaches the ground's edge at {p}"
                );
                let c = vp * p.extend(1.0);
                assert!(
                    c.w > 0.0 && c.x.abs() < 0.95 * c.w && c.y.abs() < 0.95 * c.w,
                    "{name}: shadowed ground at {p} is out of frame ({c})"
                );
            }
        }
        eprintln!("{name}: {shadowed} grid points shadowed, {partial} partly");
        assert!(
            shadowed > 400 && partial > shadowed / 2,
            "{name}: {shadowed} shadowed, {partial} partly"
        );
    }
    // the wide penumbrae: z = -0.3, across the blocker's side edges (the one down from the
    // raised corner (0.35, 1.3, -0.45) to (0.5, 1.0, 0.45), and (-0.2, 1.0, -0.35) to
    // (-0.5, 1.0, 0.45))
    let scene = bundled("linear");
    let vis = Visibility::new(&scene);
    let row: Vec<f32> = (0..=80)
        .map(|i| vis.visible_fraction_at(Vec3::new(-2.0 + 0.05 * i as f32, 0.0, -0.3), Vec3::Y, &scene.lights[0], 16, i))
        .collect();
    let wide = row.iter().filter(|v| **v > 0.0 && **v < 1.0).count() as f32 * 0.05;
    eprintln!("linear: {wide} of partly lit ground along z = -0.3");
    assert!(wide > 0.9, "{wide} of partly lit ground along z = -0.3: {row:?}");
}

#[test]
fn a_box_over_the_floor_shadows_a_point_light() {
    let scene = scene_with(
        "Point(position: (0.0, 3.0, 0.0))",
        "Object(mesh: Plane(size: (10.0, 10.0))), Object(mesh: Box(size: (1.0, 1.0, 1.0)), transform: (translate: (0.0, 1.0, 0.0)))",
    );
    let vis = Visibility::new(&scene);
    let light = &scene.lights[0];
    assert_eq!(vis.visible_fraction(Vec3::ZERO, light, 4, 0), 0.0);
    assert_eq!(vis.visible_fraction(Vec3::new(4.0, 0.0, 0.0), light, 4, 0), 1.0);
    assert_eq!(vis.visible_fraction_at(Vec3::ZERO, Vec3::Y, light, 4, 0), 0.0);
    assert_eq!(vis.visible_fraction_at(Vec3::new(4.0, 0.0, 0.0), Vec3::Y, light, 4, 0), 1.0);
    assert!(vis.occluded(Vec3::ZERO, Vec3::new(0.0, 3.0, 0.0)));
    assert!(!vis.occluded(Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0)));
    // The top of the box sees the light; its underside does not.
    assert_eq!(vis.visible_fraction_at(Vec3::new(0.1, 1.5, 0.0), Vec3::Y, light, 4, 0), 1.0);
    assert_eq!(vis.visible_fraction_at(Vec3::new(0.1, 0.5, 0.0), -Vec3::Y, light, 4, 0), 0.0);
    // No surface: lit.
    let v = vis.visible_fractions(&[Vec3::NAN, Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0)], &[], light, 4);
    assert_eq!(v, vec![1.0, 0.0, 1.0]);
}

#[test]
fn half_blocked_lights_are_half_visible() {
    // A large quad at height 1 over x < 0 and a receiver at the origin: any light centred
    // straight above at height 2 is cut exactly in half, and with an even number of
    // strata per axis the strata split exactly on the cut line for the rectangle, the
    // disk (concentric map) and the segment.
    let occluder = "Object(mesh: Quad(a: (-10.0, 1.0, -10.0), b: (-10.0, 1.0, 10.0), c: (0.0, 1.0, 10.0), d: (0.0, 1.0, -10.0)))";
    let lights = [
        "Rectangle(center: (0.0, 2.0, 0.0), normal: (0.0, -1.0, 0.0), u_axis: (1.0, 0.0, 0.0), half_width: 0.5, half_height: 0.3)",
        "Disk(center: (0.0, 2.0, 0.0), normal: (0.0, -1.0, 0.0), radius: 0.5)",
        "Segment(a: (-0.5, 2.0, 0.0), b: (0.5, 2.0, 0.0))",
    ];
    for light in lights {
        let scene = scene_with(light, occluder);
        let vis = Visibility::new(&scene);
        for seed in 0..4 {
            assert_eq!(vis.visible_fraction(Vec3::ZERO, &scene.lights[0], 8, seed), 0.5, "{light}");
        }
    }
    // A sphere's cone is sampled in polar coordinates: about half, within sampling error.
    let scene = scene_with("Sphere(center: (0.0, 2.0, 0.0), radius: 0.5)", occluder);
    let vis = Visibility::new(&scene);
    let v = vis.visible_fraction(Vec3::ZERO, &scene.lights[0], 32, 7);
    assert!((v - 0.5).abs() < 0.02, "{v}");
    // Inside the sphere light: all of it is visible.
    assert_eq!(vis.visible_fraction(Vec3::new(0.0, 2.1, 0.0), &scene.lights[0], 4, 0), 1.0);
}

#[test]
fn results_are_deterministic_and_seeds_independent() {
    let scene = bundled("contact");
    let vis = Visibility::new(&scene);
    let light = &scene.lights[0];
    // A grid on the floor behind the boxes, where their shadows fall.
    let points: Vec<Vec3> = (0..100)
        .map(|i| Vec3::new(-1.5 + 0.3 * (i % 10) as f32, 0.0, -0.5 - 0.15 * (i / 10) as f32))
        .collect();
    let normals = vec![Vec3::Y; points.len()];
    let a = vis.visible_fractions(&points, &normals, light, 4);
    let b = vis.visible_fractions(&points, &normals, light, 4);
    assert_eq!(a, b);
    let c = vis.visible_fractions_seeded(&points, &normals, light, 4, 99);
    assert!(a.iter().zip(&c).any(|(x, y)| x != y), "another seed draws other samples");
    assert!(a.iter().any(|&v| v > 0.0 && v < 1.0), "the row crosses a penumbra");
}

/// Area of the part of a unit disk on the far side of a chord at signed distance `u`
/// from its centre, as a fraction of the disk: 1 at u >= 1, 0 at u <= -1.
fn disk_fraction(u: f64) -> f64 {
    let u = u.clamp(-1.0, 1.0);
    0.5 + (u * (1.0 - u * u).sqrt() + u.asin()) / std::f64::consts::PI
}

#[test]
fn a_straight_edge_under_a_distant_disk_matches_the_closed_form() {
    let scene = bundled("edge");
    let vis = Visibility::new(&scene);
    let light = &scene.lights[0];
    let Light::DistantDisk { angle_degrees, .. } = light else {
        panic!("edge.ron has a distant disk")
    };
    // The occluder: every triangle above the floor; its edge is its largest x.
    let occluder: Vec<Vec3> = scene.triangles().iter().flatten().copied().filter(|p| p.y > 1e-3).collect();
    let h = occluder[0].y as f64;
    let edge_x = occluder.iter().map(|p| p.x).fold(f32::NEG_INFINITY, f32::max) as f64;
    assert!(occluder.iter().all(|p| (p.y as f64 - h).abs() < 1e-6), "a flat occluder");
    // Receivers on the floor (y = 0) at h below the edge; the light is straight overhead,
    // so the shadow line is at x = edge_x and the penumbra's half-width is h tan(theta / 2).
    let w = h * (0.5 * (*angle_degrees as f64).to_radians()).tan();
    let n = 32u32;
    let samples = f64::from(n * n);
    let mut worst: f64 = 0.0;
    for k in -30..=30 {
        let s = 1.3 * w * k as f64 / 25.0;
        let z = 0.01 * k as f32;
        let x = Vec3::new((edge_x + s) as f32, 0.0, z);
        let f = disk_fraction(s / w);
        let est = vis.visible_fraction_at(x, Vec3::Y, light, n, k as u64) as f64;
        // Tolerance. Stratified sampling is unbiased and its variance is never above that
        // of N = n^2 independent samples (proportional allocation), so 3 binomial standard
        // errors sqrt(f (1 - f) / N) bound the random error with margin; in fact only the
        // O(n) strata that the chord cuts contribute any variance. Near u = +-1 the
        // binomial term vanishes while a few rim strata can still be cut: 2 / N allows
        // two samples to fall either way there. The f32 geometry (ray offset 1e-4 of the
        // scene size along a vertical ray, 1e-6 barycentric tolerance) moves the chord by
        // less than 1e-5 w, far below both terms.
        let tol = 3.0 * (f * (1.0 - f) / samples).sqrt() + 2.0 / samples;
        assert!(
            (est - f).abs() <= tol,
            "s = {s:.5} (u = {:.3}): estimate {est:.4}, closed form {f:.4}, tolerance {tol:.4}",
            s / w
        );
        worst = worst.max((est - f).abs());
    }
    assert!(worst > 0.0, "a penumbra was sampled");
}

/// Runs `f` on a thread and fails unless it ends within `secs` seconds.
fn within<T: Send + 'static>(secs: u64, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(std::time::Duration::from_secs(secs))
        .unwrap_or_else(|_| panic!("not done within {secs} s"))
}

#[test]
fn huge_spheres_and_triangle_counts_are_refused_before_allocating() {
    // Bound: each refusal in under 5 s and without building a mesh (100,000 segments would
    // take 4.8 GB).
    for segments in [100_000u64, 4_294_967_295, 1025] {
        let err = within(5, move || {
            let text = format!("Scene({CAMERA}, shadow_map: 8, objects: [Object(mesh: Sphere(radius: 0.5, segments: {segments}))])");
            Scene::from_str(&text, ".").unwrap_err()
        });
        assert_eq!(err.kind(), SceneErrorKind::Invalid, "{err}");
        assert_eq!(err.at(), Some("objects[0].mesh.segments"), "{err}");
        assert!(err.message().contains("limit of 1024"), "{err}");
    }
    // 1024 segments is allowed (1,048,576 triangles), but 17 of them exceed 2^24 triangles:
    // refused before any is built.
    let objects = vec!["Object(mesh: Sphere(radius: 0.5, segments: 1024))"; 17].join(", ");
    let err = within(5, move || {
        let text = format!("Scene({CAMERA}, shadow_map: 8, objects: [{objects}])");
        Scene::from_str(&text, ".").unwrap_err()
    });
    assert_eq!(err.at(), Some("objects[16].mesh"), "{err}");
    assert!(err.message().contains("above the limit of 16777216"), "{err}");
}

#[test]
fn obj_files_must_be_regular_and_below_the_size_cap() {
    let dir = temp_dir("objcap");
    let scene = |path: &str| format!("Scene({CAMERA}, shadow_map: 8, objects: [Object(mesh: Obj(path: {path:?}))])");
    // A sparse file just over 256 MiB: refused from its size, without reading it.
    let big = std::fs::File::create(dir.join("big.obj")).unwrap();
    big.set_len((256 << 20) + 1).unwrap();
    drop(big);
    let d = dir.clone();
    let text = scene("big.obj");
    let err = within(5, move || Scene::from_str(&text, &d).unwrap_err());
    assert_eq!(err.at(), Some("objects[0].mesh.path"), "{err}");
    assert!(err.message().contains("above the limit of 268435456"), "{err}");
    // A folder is not a regular file.
    std::fs::create_dir_all(dir.join("folder.obj")).unwrap();
    let err = Scene::from_str(&scene("folder.obj"), &dir).unwrap_err();
    assert!(err.message().contains("not a regular file"), "{err}");
    // A FIFO would block a read forever: refused at once.
    #[cfg(unix)]
    {
        let fifo = dir.join("fifo.obj");
        let ok = std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success());
        if ok {
            let d = dir.clone();
            let text = scene("fifo.obj");
            let err = within(5, move || Scene::from_str(&text, &d).unwrap_err());
            assert!(err.message().contains("not a regular file"), "{err}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn tiny_scales_and_huge_camera_distances_say_what_is_wrong() {
    let object = |scale: &str| {
        format!("Scene({CAMERA}, shadow_map: 8, objects: [Object(mesh: Box(size: (1.0, 1.0, 1.0)), transform: (scale: {scale}))])")
    };
    let err = Scene::from_str(&object("(1e-30, 1e-30, 1e-30)"), ".").unwrap_err();
    assert_eq!(err.at(), Some("objects[0].transform.scale"), "{err}");
    assert!(err.message().contains("too small") && err.message().contains("1e-30"), "{err}");
    assert!(!err.message().contains("scale of 0"), "{err}");
    let err = Scene::from_str(&object("(0.0, 1.0, 1.0)"), ".").unwrap_err();
    assert!(err.message().contains("scale of 0"), "{err}");
    assert!(Scene::from_str(&object("(1e-3, 1e-3, 1e-3)"), ".").is_ok());

    let camera = |extra: &str, position: &str| {
        format!(
            "Scene(camera: Perspective(position: {position}, target: (0.0, 0.0, 0.0), fov_y_degrees: 45.0, width: 8, height: 8{extra}), shadow_map: 8, objects: [Object(mesh: Box(size: (1.0, 1.0, 1.0)))])"
        )
    };
    // far 1e30 made the default near 1e27 and near x far overflow f32 (a NaN projection).
    let err = Scene::from_str(&camera(", far: 1e30", "(0.0, 3.0, 5.0)"), ".").unwrap_err();
    assert_eq!(err.at(), Some("camera (Perspective).far"), "{err}");
    assert!(err.message().contains("overflows f32") && !err.message().contains("up"), "{err}");
    let err = Scene::from_str(&camera("", "(0.0, 3.0, 1e30)"), ".").unwrap_err();
    assert_eq!(err.at(), Some("camera (Perspective).target"), "{err}");
    assert!(!err.message().contains("`up`"), "{err}");
    let big = "Scene(camera: Perspective(position: (0.0, 3.0, 5.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 45.0, width: 8192, height: 8192), shadow_map: 8)";
    let err = Scene::from_str(big, ".").unwrap_err();
    assert_eq!(err.at(), Some("camera (Perspective).width"), "{err}");
    assert!(err.message().contains("above the limit of 16777216"), "{err}");
    let ok = Scene::from_str(&camera(", far: 1e6", "(0.0, 3.0, 5.0)"), ".").unwrap();
    assert!(ok.camera_view_proj().is_finite());
}

/// The `View` fit holds every point the camera sees inside the light's view,
/// laterally and in depth, on every bundled scene, with texels at the receivers no larger
/// than the whole-scene fit's; a caster over the visible receivers lies within its depth
/// range even when all its corners lie outside the footprint (the edge scene's half-plane).
#[test]
fn the_view_fit_holds_what_the_camera_sees_in_finer_texels() {
    let names: Vec<String> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    assert!(names.len() >= 9, "{names:?}");
    for name in names {
        let mut s = bundled(&name);
        let light = s.lights[0].clone();
        // against the whole-scene fit (triangle-lawlor fits its casters, finer still there:
        // its seen ground is wider than the triangle's shadow)
        s.set_shadow_fit(ShadowFit::Scene).unwrap();
        let before = s.fit_report(&light);
        s.set_shadow_fit(ShadowFit::View).unwrap();
        let after = s.fit_report(&light);
        assert_eq!(after.fit, ShadowFit::View, "{name}");
        let v = s.light_view(&light);
        let seen = s.visible_points();
        assert!(!seen.is_empty(), "{name}");
        // f32 rounding of the transforms: a few ulps of the clip coordinates
        let eps = 1e-5;
        for p in &seen {
            let c = v.view_proj * p.extend(1.0);
            let ndc = c.truncate() / c.w;
            assert!(ndc.x.abs() <= 1.0 + eps && ndc.y.abs() <= 1.0 + eps, "{name}: {p} at {ndc}");
            let d = -v.view.transform_point3(*p).z;
            assert!(
                d >= v.near * (1.0 - eps) && d <= v.far * (1.0 + eps),
                "{name}: {p} at depth {d} outside [{}, {}]",
                v.near,
                v.far
            );
        }
        assert!(
            after.at_receivers <= before.at_receivers * (1.0 + eps),
            "{name}: {} against {}",
            after.at_receivers,
            before.at_receivers
        );
        if name == "edge" {
            // the half-plane caster above the receiver: its depth, not only the receiver's
            assert!(after.far - after.near > 0.5 * (before.far - before.near), "{name}: {after}");
        }
    }
}

/// A scene file's `cascades:` is checked where it is written, and the command line's
/// options override it field by field (`bind::Cascading::resolved`).
#[test]
fn the_scene_files_cascades_are_checked_and_the_command_line_overrides_them() {
    let sun = "DistantDisk(direction: (0.3, 1.0, 0.2), angle_degrees: 1.0)";
    let with = |lights: &str, cascades: &str| {
        let text = format!(
            "Scene({CAMERA}, shadow_map: 64, lights: [{lights}], cascades: {cascades}, objects: [Object(mesh: Box(size: (1.0, 1.0, 1.0)))])"
        );
        Scene::from_str(&text, ".")
    };
    let scene = with(sun, "(count: 3, lambda: 0.5)").unwrap_or_else(|e| panic!("{e}"));
    let c = scene.cascades().unwrap_or_else(|| panic!("no cascades"));
    assert_eq!((c.count, c.lambda, c.band), (3, 0.5, 0.1));
    for (lights, cascades, at) in [
        (sun, "(count: 5)", "cascades.count"),
        (sun, "(count: 2, lambda: 2.0)", "cascades.lambda"),
        (sun, "(count: 2, band: 1.0)", "cascades.band"),
        ("Point(position: (0.0, 5.0, 0.0))", "(count: 2)", "cascades.count"),
    ] {
        let e = with(lights, cascades).expect_err(cascades);
        assert_eq!(e.at(), Some(at), "{e}");
        assert!(e.hint().is_some(), "{e}");
    }
    let mut cli = sshc_lab::bind::Cascading {
        cascades: None,
        cascade_lambda: Some(0.9),
        cascade_band: None,
        no_snap: false,
        cascade_offset: None,
    };
    let r = cli.resolved(&scene);
    assert_eq!((r.count, r.lambda, r.band), (3, 0.9, 0.1));
    cli.cascades = Some(1);
    assert!(!cli.on(&scene), "the command line's one cascade overrides the file's three");
}

/// The large scenes (scenes/large/, out of the suite's every-scene walks: each generates a
/// million triangles) parse as scene files and name a city of a million triangles under one
/// sun; scripts/scale.sh and scripts/cascades.sh load them whole.
#[test]
fn the_large_scenes_parse_and_name_a_city() {
    let dir = scenes_dir().join("large");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.unwrap_or_else(|e| panic!("{e}")).path();
        if path.extension().is_none_or(|e| e != "ron") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let options = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
        let desc: sshc_lab::scene::SceneDesc = options.from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            matches!(
                desc.objects[..],
                [sshc_lab::scene::Object {
                    mesh: sshc_lab::scene::Mesh::City { triangles: 1_000_000, .. },
                    ..
                }]
            ),
            "{}",
            path.display()
        );
        assert!(matches!(desc.lights[..], [Light::DistantDisk { .. }]), "{}", path.display());
        seen += 1;
    }
    assert!(seen >= 2, "{seen} large scenes");
}

/// Issue 48, item 12: a camera f32 cannot resolve is refused by the precision check that
/// every command runs (it drew nothing and was accepted): a near of 1e-9 against a fitted
/// far, an orthographic half height of 1e-30; the bundled scenes' cameras pass.
#[test]
fn a_camera_f32_cannot_resolve_is_refused() {
    let scene = |camera: &str| {
        Scene::from_str(
            &format!(
                "Scene(camera: {camera}, shadow_map: 64, lights: [Point(position: (0.0, 4.0, 0.0))], objects: [Object(mesh: Plane(size: (4.0, 4.0)))])"
            ),
            ".",
        )
        .and_then(|s| s.check_precision().map(|_| s))
        .map_err(|e| e.to_string())
    };
    let e =
        scene("Perspective(position: (0.0, 3.0, 5.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 45.0, width: 32, height: 32, near: 1e-9)")
            .unwrap_err();
    assert!(e.contains("camera (Perspective).near") && e.contains("far / near is"), "{e}");
    let e = scene(
        "Orthographic(position: (0.0, 3.0, 0.0), target: (0.0, 0.0, 0.0), up: (0.0, 0.0, -1.0), half_height: 1e-30, width: 32, height: 32)",
    )
    .unwrap_err();
    assert!(
        e.contains("camera (Orthographic).half_height") && e.contains("cannot place its pixels"),
        "{e}"
    );
    for ok in [
        "Perspective(position: (0.0, 3.0, 5.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 45.0, width: 32, height: 32, near: 0.01)",
        "Orthographic(position: (0.0, 3.0, 0.0), target: (0.0, 0.0, 0.0), up: (0.0, 0.0, -1.0), half_height: 0.5, width: 32, height: 32)",
    ] {
        assert!(scene(ok).is_ok(), "{ok}: {:?}", scene(ok).err());
    }
    for name in bundled_scenes() {
        let s = Scene::load(common::root().join("scenes").join(format!("{name}.ron"))).unwrap();
        assert!(s.check_precision().is_ok(), "{name}");
    }
}
