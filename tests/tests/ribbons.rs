//! Smoothies and single-sample shadows outside Lawlor's set-up (issue 37): the rules of
//! their papers that the shared ribbons (`Ribbons`, penumbra limit maps) must keep when
//! each technique draws only its half of them.
//!
//! - Chan & Durand 2003: a smoothie darkens only receivers farther from the light than
//!   itself, beyond the silhouette: a lit face of the occluder it was extruded from reads 1.
//! - An open boundary of a surface that casts draws no shadow on that surface: a casting
//!   floor under a low sun, alone, reads 1 everywhere.
//! - Kirsch & Doellner 2003: the light returns over the inner penumbra, from the hard edge
//!   to the umbra's, so a quad wider than twice its inner penumbra has an umbra (0) at its
//!   shadow's centre.
//!
//! Every scene is tiny (64 x 64 pixels, a 256-texel map): each test renders two
//! techniques once.

mod support;

use sshc_lab::run::Loaded;
use sshc_lab::scene::Scene;
use sshc_runtime::gpu::CameraOutput;
use support::{compile_source, gpu, technique_source};

const SMOOTHIES: &str = "smoothies";
const SINGLE_SAMPLE: &str = "single-sample";

/// The visibility and world position of every camera pixel.
fn run(technique: &str, scene: &Scene) -> (Vec<f32>, Vec<[f32; 3]>) {
    let compiled = compile_source(technique, &technique_source(technique), &[], &[]);
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
    (vis, pos.rgba.iter().map(|p| [p[0], p[1], p[2]]).collect())
}

fn scene(camera: &str, light: &str, objects: &str) -> Scene {
    Scene::from_str(
        &format!(
            "Scene(
    camera: {camera},
    shadow_map: 256,
    lights: [{light}],
    objects: [{objects}],
)"
        ),
        ".",
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// The world size of one texel of a map `extent` wide at `texels`, padded to three texels:
/// pixels this close to a silhouette are left out of exact checks, since the hard test and
/// the ribbons' coverage are decided at texel centres (a texel either side of the edge) and
/// the slope bias moves the test by up to 1.5 texels of depth slope.
fn margin(extent: f32, texels: u32) -> f32 {
    3.0 * extent / texels as f32
}

/// A floating quad's lit top face under a sphere light to its side. The light's view is
/// perspective, so the face lies deeper from the light than its two edges nearer the light:
/// the inner half of those edges' ribbons, drawn by smoothies before issue 37, read 0 there
/// (alpha = ramp / (z - c) with a ramp of 0 inside the silhouette). Both half-penumbra
/// techniques must leave the whole face, away from its outline, at exactly 1: the face is
/// the topmost surface (the hard test passes) and no smoothie lies over it.
#[test]
fn a_lit_occluder_face_reads_one() {
    let s = scene(
        "Perspective(position: (0.0, 2.6, 1.6), target: (0.0, 0.8, 0.0), fov_y_degrees: 50.0, width: 64, height: 64)",
        "Sphere(center: (1.2, 3.0, 1.0), radius: 0.3)",
        "Object(name: \"floor\", mesh: Plane(size: (3.0, 3.0))),
         Object(name: \"quad\", mesh: Quad(a: (-0.6, 0.8, -0.6), b: (-0.6, 0.8, 0.6), c: (0.6, 0.8, 0.6), d: (0.6, 0.8, -0.6)))",
    );
    // the whole-scene fit spans the 3-unit floor and more: a texel is under 0.03
    let inset = 0.6 - margin(5.0, 256);
    for technique in [SMOOTHIES, SINGLE_SAMPLE] {
        let (vis, pos) = run(technique, &s);
        let face: Vec<f32> = vis
            .iter()
            .zip(&pos)
            .filter(|(_, p)| (p[1] - 0.8).abs() < 1e-3 && p[0].abs() < inset && p[2].abs() < inset)
            .map(|(v, _)| *v)
            .collect();
        let dark = face.iter().filter(|v| **v != 1.0).count();
        let least = face.iter().copied().fold(1.0f32, f32::min);
        eprintln!("{technique}: {} face pixels, {dark} below 1 (least {least})", face.len());
        assert!(face.len() > 400, "{technique}: {} face pixels", face.len());
        assert_eq!(dark, 0, "{technique}: {dark} lit face pixels below 1, least {least}");
    }
}

/// A floor that casts, alone under a low sun (a distant disk 4 degrees wide, 27 degrees
/// above the horizon). Its boundary edges are silhouettes (open boundaries); under a low
/// sun its depth from the light grows across it, so the inner half of the boundary nearer
/// the sun lay over the floor at depths beyond its edge's: smoothies drew a dark band there
/// before issue 37. Nothing shadows the floor, so every floor pixel away from its outline
/// reads exactly 1.
#[test]
fn a_casting_floors_own_boundary_leaves_the_floor_lit() {
    let s = scene(
        "Perspective(position: (0.0, 3.5, 2.5), target: (0.0, 0.0, 0.0), fov_y_degrees: 60.0, width: 64, height: 64)",
        "DistantDisk(direction: (-0.8, 0.45, -0.3), angle_degrees: 4.0)",
        "Object(name: \"floor\", mesh: Plane(size: (3.0, 3.0)))",
    );
    // the map spans the floor's 3 units seen obliquely: under 4.3 units wide
    let inset = 1.5 - margin(4.3, 256);
    for technique in [SMOOTHIES, SINGLE_SAMPLE] {
        let (vis, pos) = run(technique, &s);
        let floor: Vec<f32> = vis
            .iter()
            .zip(&pos)
            .filter(|(_, p)| p[1].abs() < 1e-3 && p[0].abs() < inset && p[2].abs() < inset)
            .map(|(v, _)| *v)
            .collect();
        let dark = floor.iter().filter(|v| **v != 1.0).count();
        let least = floor.iter().copied().fold(1.0f32, f32::min);
        eprintln!("{technique}: {} floor pixels, {dark} below 1 (least {least})", floor.len());
        assert!(floor.len() > 1000, "{technique}: {} floor pixels", floor.len());
        assert_eq!(dark, 0, "{technique}: {dark} floor pixels below 1, least {least}");
    }
}

/// A quad 0.7 wide, 1 above a floor, under a sphere light of radius 0.5 straight above it
/// at height 3. On the floor the penumbra of each edge reaches L (Z - C) / C = 0.5 x 1 / 2 =
/// 0.25 either side of the hard edge (Z and C the floor's and the quad's distances from
/// the light), so the quad's half-width 0.35 exceeds its inner penumbra: the truth has an
/// umbra at the centre. (From the floor's centre every ray to the light's disk crosses the
/// quad's plane within 0.5 / 3 = 0.17 of the axis, inside the quad: visibility 0.) Kirsch &
/// Doellner's ramp spans that inner penumbra, so single-sample shadows read 0 within 0.1 of
/// the centre; with the whole penumbra (0.5) inside, as before issue 37, the centre read
/// up to 0.14 (measured). Smoothies keep the hard shadow whole: 0 there too.
#[test]
fn a_quad_wider_than_twice_its_inner_penumbra_has_an_umbra_under_single_sample() {
    let s = scene(
        "Perspective(position: (0.0, 2.0, 1.2), target: (0.0, 0.0, 0.0), fov_y_degrees: 50.0, width: 64, height: 64)",
        "Sphere(center: (0.0, 3.0, 0.0), radius: 0.5)",
        "Object(name: \"floor\", mesh: Plane(size: (3.0, 3.0))),
         Object(name: \"quad\", mesh: Quad(a: (-0.35, 1.0, -0.35), b: (-0.35, 1.0, 0.35), c: (0.35, 1.0, 0.35), d: (0.35, 1.0, -0.35)))",
    );
    for technique in [SINGLE_SAMPLE, SMOOTHIES] {
        let (vis, pos) = run(technique, &s);
        let centre: Vec<f32> = vis
            .iter()
            .zip(&pos)
            .filter(|(_, p)| p[1].abs() < 1e-3 && p[0].abs() < 0.1 && p[2].abs() < 0.1)
            .map(|(v, _)| *v)
            .collect();
        let most = centre.iter().copied().fold(0.0f32, f32::max);
        eprintln!("{technique}: {} pixels at the shadow's centre, brightest {most}", centre.len());
        assert!(centre.len() > 20, "{technique}: {} centre pixels", centre.len());
        assert_eq!(most, 0.0, "{technique}: the umbra's centre reads up to {most}");
    }
}
