//! Objects that cast no shadow (`casts: false`) and the `Casters` shadow-map fit, on the
//! CPU: the scene options and their errors, the fitted extent against its formula (a
//! distant disk and a sphere light), the vertex order the executor binds, the ground
//! truth's shadow rays, which object a pixel shows, and Lawlor's "shadow on the ground"
//! pixel set on a constructed case; the runtime's fit to a host's boxes against the
//! scene's to its vertices. The GPU side is in tests/gpu.rs.

use glam::Vec3;
use sshc_lab::metrics;
use sshc_lab::scene::{Scene, SceneErrorKind, ShadowFit, fit_guard};
use sshc_lab::visibility::Visibility;

const CAMERA: &str = "camera: Perspective(position: (0.0, 3.0, 5.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 45.0, width: 32, height: 32)";

fn scene(extra: &str, lights: &str, objects: &str) -> Result<Scene, String> {
    let text = format!("Scene({CAMERA}, shadow_map: 64, {extra} lights: [{lights}], objects: [{objects}])");
    Scene::from_str(&text, ".").map_err(|e| e.to_string())
}

const OVERHEAD: &str = "DistantDisk(direction: (0.0, 1.0, 0.0), angle_degrees: 10.0)";
const GROUND: &str = "Object(name: \"ground\", mesh: Plane(size: (4.0, 4.0)), casts: false)";
/// A quad at height 0.5 over x in [-0.3, 0.5], z in [-0.2, 0.2].
const QUAD: &str = "Object(name: \"quad\", mesh: Quad(a: (-0.3, 0.5, -0.2), b: (-0.3, 0.5, 0.2), c: (0.5, 0.5, 0.2), d: (0.5, 0.5, -0.2)))";

#[test]
fn casts_defaults_to_true_and_enters_the_fingerprint() {
    let a = scene("", OVERHEAD, &format!("{GROUND}, {QUAD}")).unwrap();
    assert!(!a.casts(0) && a.casts(1));
    assert_eq!(a.shadow_fit(), ShadowFit::Scene);
    assert_eq!(a.casting_triangles(), vec![false, false, true, true]);
    assert_eq!(a.caster_triangles(), 2);
    let b = scene("", OVERHEAD, &format!("{}, {QUAD}", GROUND.replace(", casts: false", ""))).unwrap();
    assert!(b.casts(0));
    // Same triangles, camera and light: only `casts` differs, and the truth differs with it.
    assert_ne!(a.fingerprint(), b.fingerprint());
    assert_eq!(
        (a.object_of_triangle(1), a.object_of_triangle(2), a.object_of_triangle(4)),
        (Some(0), Some(1), None)
    );
}

#[test]
fn a_casters_fit_without_a_caster_is_refused_with_the_field_and_a_fix() {
    let e = scene("shadow_fit: Casters,", OVERHEAD, GROUND).unwrap_err();
    assert!(e.contains("at: shadow_fit"), "{e}");
    assert!(e.contains("every object has `casts: false`"), "{e}");
    assert!(e.contains("hint: mark at least one object `casts: true`"), "{e}");
    let mut s = scene("", OVERHEAD, GROUND).unwrap();
    let e = s.set_shadow_fit(ShadowFit::Casters).unwrap_err();
    assert_eq!(e.kind(), SceneErrorKind::Invalid);
    assert_eq!(s.shadow_fit(), ShadowFit::Scene);
    // An unknown fit names the ones allowed.
    let e = scene("shadow_fit: Occluders,", OVERHEAD, QUAD).unwrap_err();
    assert!(e.contains("Scene") && e.contains("Casters"), "{e}");
}

/// Linear depth of `p` in `v` ((-z - near) / (far - near)), as the shaders compute it.
fn depth(v: &sshc_lab::scene::LightView, p: Vec3) -> f32 {
    (-v.view.transform_point3(p).z - v.near) / (v.far - v.near)
}

#[test]
fn the_fit_to_the_casters_of_a_distant_disk_is_their_extent_plus_the_penumbra_reach() {
    let s = scene("shadow_fit: Casters,", OVERHEAD, &format!("{GROUND}, {QUAD}")).unwrap();
    let light = &s.lights[0];
    // The quad is 0.5 above the lowest receiver (the ground): reach 0.5 tan(5 degrees).
    let reach = 0.5 * 5f32.to_radians().tan();
    assert!((s.penumbra_reach(light) - reach).abs() < 1e-6, "{}", s.penumbra_reach(light));
    // Half the quad's larger side (0.8 / 2), plus the reach, plus one guard texel a side.
    let half = (0.4 + reach) * 64.0 / 62.0;
    assert_eq!(fit_guard(64), 64.0 / 62.0);
    let v = s.light_view(light);
    assert!(v.orthographic);
    let fitted = 1.0 / v.proj.y_axis.y;
    assert!((fitted - half).abs() < 1e-5 * half, "half extent {fitted}, formula {half}");
    assert!((1.0 / v.proj.x_axis.x - half).abs() < 1e-5 * half);
    // Centred on the casters: the quad's centre (0.1, 0.5, 0) maps to the map's centre.
    let c = v.view_proj.project_point3(Vec3::new(0.1, 0.5, 0.0));
    assert!(c.x.abs() < 1e-5 && c.y.abs() < 1e-5, "{c}");
    // Near and far still hold every receiver: the ground's corners and the quad.
    for p in s.triangles().iter().flatten() {
        let d = depth(&v, *p);
        assert!((0.0..=1.0).contains(&d), "{p}: depth {d}");
    }
    let r = s.fit_report(light);
    assert_eq!(r.fit, ShadowFit::Casters);
    assert!((r.texel - 2.0 * half / 64.0).abs() < 1e-6, "{r:?}");
    assert!((r.reach - reach).abs() < 1e-6);
    // The whole-scene fit (the 4 x 4 ground) has texels about 4 times coarser.
    let mut whole = s.clone();
    whole.set_shadow_fit(ShadowFit::Scene).unwrap();
    let w = whole.fit_report(light);
    assert_eq!(w.fit, ShadowFit::Scene);
    assert!(w.texel > 4.0 * r.texel, "{w:?} against {r:?}");
    assert_eq!(whole.light_view(light), light.view(whole.bounds()));
    let text = r.to_string();
    assert!(
        text.contains("fitted to the casters (1 of 2 objects)") && text.contains("one texel ="),
        "{text}"
    );
}

#[test]
fn the_fit_to_the_casters_of_a_local_light_adds_the_penumbra_in_tangent_units() {
    // A sphere light of radius 0.2 at height 3 over a 0.6 x 0.6 quad at height 1 and the
    // ground: d_c = 2, d_r = 3 along the view axis (straight down).
    let quad = "Object(mesh: Quad(a: (-0.3, 1.0, -0.3), b: (-0.3, 1.0, 0.3), c: (0.3, 1.0, 0.3), d: (0.3, 1.0, -0.3)))";
    let s = scene(
        "shadow_fit: Casters,",
        "Sphere(center: (0.0, 3.0, 0.0), radius: 0.2)",
        &format!("{GROUND}, {quad}"),
    )
    .unwrap();
    let light = &s.lights[0];
    // The penumbra of the quad's edge on the ground: s (d_r - d_c) / d_c = 0.2 / 2.
    assert!((s.penumbra_reach(light) - 0.1).abs() < 1e-5, "{}", s.penumbra_reach(light));
    let v = s.light_view(light);
    assert!(!v.orthographic);
    let axis = v.view.inverse().transform_vector3(-Vec3::Z);
    assert!(axis.dot(-Vec3::Y) > 1.0 - 1e-5, "axis {axis}");
    // tan of the half-angle: the quad's 0.3 / 2, plus 0.2 (1/2 - 1/3), plus a guard texel.
    let tan = (0.15 + 0.2 * (0.5 - 1.0 / 3.0)) * 64.0 / 62.0;
    let fitted = 1.0 / v.proj.y_axis.y;
    assert!((fitted - tan).abs() < 1e-4 * tan, "tan {fitted}, formula {tan}");
    for p in s.triangles().iter().flatten() {
        let d = depth(&v, *p);
        assert!((0.0..=1.0).contains(&d), "{p}: depth {d}");
    }
}

#[test]
fn the_executor_gets_the_casters_first_and_only_their_meshes() {
    // The ground comes first in the file: the buffer puts the quad (2 triangles) first.
    let s = scene("", OVERHEAD, &format!("{GROUND}, {QUAD}")).unwrap();
    let inputs = sshc_lab::bind::scene_inputs(&s).unwrap();
    let all = s.vertex_data();
    assert_eq!(inputs.vertices.len(), all.len());
    assert_eq!(&inputs.vertices[..36], &all[36..], "the quad's triangles first");
    assert_eq!(&inputs.vertices[36..], &all[..36], "then the ground's");
    assert_eq!(inputs.casting_vertices, Some(6));
    assert_eq!(inputs.meshes, vec![0..2]);
    // Every object casting: the buffer as it was, every vertex drawn from the light.
    let s = scene("", OVERHEAD, QUAD).unwrap();
    let inputs = sshc_lab::bind::scene_inputs(&s).unwrap();
    assert_eq!(inputs.vertices, s.vertex_data());
    assert_eq!(inputs.casting_vertices, None);
    assert_eq!(inputs.meshes, vec![0..2]);
    // Nothing casting: no vertex from the light, one empty mesh (not "one mesh of all").
    let s = scene("", OVERHEAD, GROUND).unwrap();
    let inputs = sshc_lab::bind::scene_inputs(&s).unwrap();
    assert_eq!(inputs.casting_vertices, Some(0));
    assert_eq!(inputs.meshes, vec![0..0]);
}

#[test]
fn shadow_rays_pass_through_objects_that_do_not_cast() {
    let casting = scene("", OVERHEAD, &format!("{}, {QUAD}", GROUND.replace(", casts: false", ""))).unwrap();
    let ground_only = scene("", OVERHEAD, &format!("{GROUND}, {QUAD}")).unwrap();
    let quad_off = scene(
        "",
        OVERHEAD,
        &format!("{GROUND}, {}", QUAD.strip_suffix(')').unwrap().to_string() + ", casts: false)"),
    )
    .unwrap();
    assert!(!quad_off.casts(1));
    let under = Vec3::new(0.1, 0.0, 0.0);
    let up = Vec3::Y;
    for (what, s, expected) in [
        ("every object casts", &casting, 0.0),
        ("the ground does not cast", &ground_only, 0.0),
        ("the quad does not cast", &quad_off, 1.0),
    ] {
        let vis = Visibility::new(s);
        let f = vis.visible_fraction_at(under, up, &s.lights[0], 8, 1);
        assert_eq!(f, expected, "{what}: under the quad");
        // Beside it, lit in every case; a point on the quad's top sees the whole light.
        assert_eq!(
            vis.visible_fraction_at(Vec3::new(1.5, 0.0, 0.0), up, &s.lights[0], 8, 1),
            1.0,
            "{what}"
        );
        assert_eq!(
            vis.visible_fraction_at(Vec3::new(0.1, 0.5, 0.0), up, &s.lights[0], 8, 1),
            1.0,
            "{what}"
        );
        // From below the ground, a ray up meets the ground only if it casts.
        let below = vis.visible_fraction(Vec3::new(1.5, -0.5, 0.0), &s.lights[0], 8, 1);
        assert_eq!(below, if s.casts(0) { 0.0 } else { 1.0 }, "{what}: below the ground");
    }
}

#[test]
fn the_object_a_pixel_shows_is_found_by_the_camera_ray() {
    let s = scene("", OVERHEAD, &format!("{GROUND}, {QUAD}")).unwrap();
    let vis = Visibility::new(&s);
    let (mut ground, mut quad) = (0, 0);
    for i in 0..32 * 32 {
        let (u, v) = (((i % 32) as f32 + 0.5) / 32.0, ((i / 32) as f32 + 0.5) / 32.0);
        let Some((p, _)) = vis.seen_by_camera(&s, u, v) else { continue };
        let o = vis.object_seen(&s, p);
        let expected = if p.y > 0.25 { 1 } else { 0 };
        assert_eq!(o, Some(expected), "pixel {i} at {p}");
        if expected == 0 {
            ground += 1;
        } else {
            quad += 1;
        }
    }
    assert!(ground > 100 && quad > 4, "{ground} ground and {quad} quad pixels");
    assert_eq!(
        vis.on_non_casters(&s, &[Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.1, 0.5, 0.0), Vec3::NAN]),
        vec![true, false, false]
    );
}

#[test]
fn the_shadow_on_the_ground_is_the_shadow_and_the_penumbra_reach_around_it() {
    // 100 ground pixels 0.01 apart along x; the truth is below 1 at pixels 20..=29.
    let n = 100;
    let positions: Vec<Vec3> = (0..n).map(|i| Vec3::new(0.01 * i as f32, 0.0, 0.0)).collect();
    let mut truth = vec![1.0f32; n];
    for t in &mut truth[20..30] {
        *t = 0.5;
    }
    let mut ground = vec![true; n];
    let mut facing = vec![true; n];
    // Pixel 60 is in shadow but not on the ground (an occluder's own pixel): not in the set,
    // and it does not pull its neighbours in.
    truth[60] = 0.0;
    ground[60] = false;
    // Pixel 17 faces away: never in the set.
    facing[17] = false;
    let set = metrics::shadow_on_ground(&truth, &positions, &ground, &facing, 0.055).unwrap();
    let inside: Vec<usize> = (0..n).filter(|&i| set[i]).collect();
    // Within 0.055 of pixels 20..=29: 15..=34, less 17.
    let expected: Vec<usize> = (15..=34).filter(|&i| i != 17).collect();
    assert_eq!(inside, expected);
    // No reach: the shadowed ground pixels only.
    let set = metrics::shadow_on_ground(&truth, &positions, &ground, &facing, 0.0).unwrap();
    assert_eq!((0..n).filter(|&i| set[i]).collect::<Vec<_>>(), (20..30).collect::<Vec<_>>());
    // Lengths must agree.
    assert!(metrics::shadow_on_ground(&truth, &positions[1..], &ground, &facing, 0.1).is_err());
    // A reach so small that the grid's cells saturate i64: no overflow, the shadow only.
    // (x / 1e-30 is past i64::MAX for every pixel but the first, so their cells are all
    // i64::MAX, whose neighbours would overflow.)
    let set = metrics::shadow_on_ground(&truth, &positions, &ground, &facing, 1e-30).unwrap();
    assert_eq!((0..n).filter(|&i| set[i]).count(), 10);
    // In 3D: a pixel 0.05 above the shadow's plane is within a reach of 0.055.
    let p = vec![Vec3::ZERO, Vec3::new(0.0, 0.05, 0.0), Vec3::new(0.0, 0.06, 0.0)];
    let set = metrics::shadow_on_ground(&[0.0, 1.0, 1.0], &p, &[true; 3], &[true; 3], 0.055).unwrap();
    assert_eq!(set, vec![true, true, false]);
}

#[test]
fn the_ground_set_of_a_scene_follows_its_non_casters() {
    // The ground set is defined only where an object casts no shadow.
    let s = scene("", OVERHEAD, QUAD).unwrap();
    assert_eq!(metrics::ground_set(&s, &[1.0], &[Vec3::ZERO], &[true]).unwrap(), None);
    let s = scene("", OVERHEAD, &format!("{GROUND}, {QUAD}")).unwrap();
    // Under the quad (shadowed), beside it within the reach 0.0437, beyond it, and on the quad.
    let reach = s.penumbra_reach(&s.lights[0]);
    let p = [
        Vec3::new(0.1, 0.0, 0.0),
        Vec3::new(0.5 + 0.9 * reach, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.1, 0.5, 0.0),
    ];
    let truth = [0.0, 1.0, 1.0, 1.0];
    // The point on the quad is 0.5 from a shadowed ground point: outside the reach anyway,
    // and not on the ground.
    let set = metrics::ground_set(&s, &truth, &p, &[true; 4]).unwrap().unwrap();
    assert_eq!(set, vec![true, false, false, false], "reach {reach}");
    let truth = [0.0, 1.0, 1.0, 0.0];
    let p2 = [p[0], Vec3::new(0.1 + 0.9 * reach, 0.0, 0.0), p[2], p[3]];
    let set = metrics::ground_set(&s, &truth, &p2, &[true; 4]).unwrap().unwrap();
    assert_eq!(set, vec![true, true, false, false], "reach {reach}");
}

/// The precision budget (`Scene::check_precision`) takes the fitted map's texels: a
/// 2 cm caster on a 200-unit ground under a sphere light 1000 units away resolves within
/// the whole scene's texels (2 x 141 / 64 = 4.4 units, against f32's 1000 x 2^-23 x 16 =
/// 0.0019) but not within the casters' (about 2 x 0.011 / 64 = 0.00034).
#[test]
fn the_precision_budget_uses_the_casters_texels() {
    let light = "Sphere(center: (0.0, 1000.0, 0.0), radius: 0.5)";
    let objects = "Object(name: \"ground\", mesh: Plane(size: (200.0, 200.0)), casts: false), \
        Object(name: \"chip\", mesh: Quad(a: (-0.01, 0.5, -0.01), b: (-0.01, 0.5, 0.01), c: (0.01, 0.5, 0.01), d: (0.01, 0.5, -0.01)))";
    assert!(scene("", light, objects).is_ok(), "the whole scene's texels resolve");
    let e = scene("shadow_fit: Casters,", light, objects).expect_err("the casters' texels do not");
    assert!(e.contains("coarser than 1/16 of a shadow-map texel"), "{e}");
}

/// A host's light view, fitted by the runtime to its objects' boxes
/// (`LightInputs::fit`), is the scene's fitted to its vertices where the objects are
/// axis-aligned boxes: both fits are one code (the crate `sshc-light`), and a box's
/// vertices are its box's corners, so every min, max and view is the same f32 arithmetic.
/// Every light kind, the `Scene` and `Casters` fits, and the sample views of linear and
/// area lights, bit for bit.
#[test]
fn the_runtimes_fit_to_boxes_is_the_scenes_fit_to_box_vertices_bit_for_bit() {
    use sshc_runtime::gpu::{Boxes, Fit, LightInputs};
    let lights = [
        ("Point(position: (0.4, 2.5, 0.3))", 0),
        ("Directional(direction: (0.3, 1.0, 0.2))", 0),
        ("Sphere(center: (0.4, 2.5, 0.3), radius: 0.2)", 0),
        ("Disk(center: (0.4, 2.5, 0.3), normal: (0.0, -1.0, 0.2), radius: 0.3)", 0),
        (
            "Rectangle(center: (0.0, 2.5, 0.0), normal: (0.0, -1.0, 0.0), u_axis: (1.0, 0.0, 0.3), half_width: 0.4, half_height: 0.2)",
            8,
        ),
        ("Segment(a: (-0.6, 2.5, 0.0), b: (0.6, 2.4, 0.1))", 5),
        ("Triangle(a: (-0.6, 2.5, 0.3), b: (0.6, 2.5, 0.3), c: (0.0, 2.6, -0.5))", 6),
        ("DistantDisk(direction: (0.2, 1.0, -0.1), angle_degrees: 4.0)", 0),
    ];
    let boxes = "Object(mesh: Box(size: (0.6, 0.4, 0.8)), transform: (translate: (0.3, 0.9, -0.2))), \
                 Object(mesh: Box(size: (0.2, 1.0, 0.2)), transform: (translate: (-0.8, 0.5, 0.6)))";
    let ground = "Object(mesh: Box(size: (4.0, 0.1, 4.0)), casts: false)";
    for (light, samples) in lights {
        for (fit, runtime_fit) in [("Scene", Fit::Scene), ("Casters", Fit::Casters)] {
            let s = scene(&format!("shadow_fit: {fit},"), light, &format!("{ground}, {boxes}")).unwrap();
            let box_of = |i: usize| {
                let t = &s.triangles()[s.object_triangles(i)];
                let lo = t.iter().flatten().fold(Vec3::INFINITY, |a, p| a.min(*p));
                let hi = t.iter().flatten().fold(Vec3::NEG_INFINITY, |a, p| a.max(*p));
                [lo.to_array(), hi.to_array()]
            };
            let b = Boxes {
                casters: vec![box_of(1), box_of(2)],
                others: vec![box_of(0)],
            };
            let lab = sshc_lab::bind::scene_inputs_with_samples(&s, samples).unwrap().light_inputs();
            let runtime = LightInputs::fit(&s.lights[0], &b, runtime_fit, s.shadow_map, samples).unwrap();
            assert_eq!(runtime, lab, "{light}, {fit} fit");
            assert_eq!(runtime.samples.len(), samples as usize);
        }
    }
}

/// What the runtime's fit refuses, with the reason: lights made in code are checked as
/// a scene file's are when read.
#[test]
fn the_runtimes_fit_refuses_lights_and_boxes_no_view_can_hold() {
    use sshc_runtime::gpu::{Boxes, Fit, LightInputs};
    use sshc_runtime::light::Light;
    let b = Boxes {
        casters: vec![[[0.0; 3], [1.0; 3]]],
        others: vec![],
    };
    let cases = [
        (
            Light::Sphere {
                center: Vec3::new(0.0, f32::NAN, 0.0),
                radius: 0.1,
            },
            "centre",
        ),
        (
            Light::Sphere {
                center: Vec3::Y,
                radius: -1.0,
            },
            "radius -1",
        ),
        (Light::Directional { direction: Vec3::ZERO }, "direction is zero"),
        (
            Light::DistantDisk {
                direction: Vec3::Y,
                angle_degrees: 200.0,
            },
            "[0, 180)",
        ),
        (
            Light::Rectangle {
                center: Vec3::Y,
                normal: Vec3::Y,
                u_axis: Vec3::Y,
                half_width: 1.0,
                half_height: 1.0,
            },
            "parallel",
        ),
    ];
    for (light, says) in cases {
        let e = LightInputs::fit(&light, &b, Fit::Casters, 64, 0).unwrap_err().to_string();
        assert!(e.contains(says) && e.contains(light.kind_name()), "{light:?}: {e}");
    }
    // samples the light cannot give
    let e = LightInputs::fit(&Light::Point { position: Vec3::Y }, &b, Fit::Scene, 64, 4)
        .unwrap_err()
        .to_string();
    assert!(e.contains("Point") && e.contains("4 light samples"), "{e}");
    let bad = Boxes {
        casters: vec![[[0.0; 3], [-1.0, 1.0, 1.0]]],
        others: vec![],
    };
    let e = LightInputs::fit(&Light::Point { position: Vec3::Y }, &bad, Fit::Scene, 64, 0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("caster box 0 is not a box"), "{e}");
}
