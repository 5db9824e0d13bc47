//! sshc's FLIP (`metrics::flip_map`: NVIDIA's C++ LDR-FLIP through the crate `nv-flip`)
//! against an independent run of NVIDIA's Python package `flip-evaluator`, whose values
//! `scripts/flip-reference.py` wrote once into lab/tests/data/flip/expected.ron with the
//! image pairs it generated (a penumbra against a hard edge, a dark band, a checker moved
//! one pixel). No GPU.

use sshc_lab::metrics;
use std::path::Path;

#[derive(serde::Deserialize)]
struct Expected {
    name: String,
    mean: f64,
    pixels: Vec<((u32, u32), f64)>,
}

/// How far the two implementations may differ: both compute in f32, and each FLIP value
/// comes out of spatial filters summing a few hundred f32 products, whose order differs
/// between the two builds: a few hundred roundings of 6e-8 of values below 1 bound it near
/// 1e-5 (the pairs here differ by at most 3e-7 in their means), while the tables print 4
/// digits.
const TOLERANCE: f64 = 1e-5;

fn rgb(path: &Path) -> (Vec<u8>, u32, u32) {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8();
    let (w, h) = img.dimensions();
    (img.into_raw(), w, h)
}

#[test]
fn flip_agrees_with_nvidias_python_package_on_generated_pairs() {
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/flip"));
    let text = std::fs::read_to_string(dir.join("expected.ron")).unwrap();
    let expected: Vec<Expected> = ron::from_str(&text).unwrap_or_else(|e| panic!("expected.ron: {e}"));
    assert_eq!(expected.len(), 3);
    for e in &expected {
        let (reference, w, h) = rgb(&dir.join(format!("{}-reference.png", e.name)));
        let (test, tw, th) = rgb(&dir.join(format!("{}-test.png", e.name)));
        assert_eq!((w, h), (tw, th), "{}", e.name);
        let map = metrics::flip_map(&reference, &test, w, h).unwrap();
        let mean = map.iter().map(|v| f64::from(*v)).sum::<f64>() / map.len() as f64;
        eprintln!("{}: mean FLIP {mean:.9} (flip-evaluator {:.9})", e.name, e.mean);
        assert!((mean - e.mean).abs() <= TOLERANCE, "{}: mean {mean} against {}", e.name, e.mean);
        for &((x, y), v) in &e.pixels {
            let got = f64::from(map[(y * w + x) as usize]);
            assert!((got - v).abs() <= TOLERANCE, "{} at ({x}, {y}): {got} against {v}", e.name);
        }
        // a pair that differs is seen to differ; an image against itself is 0
        assert!(mean > 0.05, "{}", e.name);
        let same = metrics::flip_map(&reference, &reference, w, h).unwrap();
        assert!(same.iter().all(|v| *v == 0.0), "{}: an image against itself", e.name);
    }
}

/// The shaded images FLIP compares: the runtime's grey `0.12 + 0.88 v max(n . l, 0)` as
/// 8-bit codes, black without a surface; FLIP over a mask is the map's mean there.
#[test]
fn shading_and_the_masked_mean() {
    use glam::Vec3;
    let light = sshc_lab::scene::Light::Directional { direction: Vec3::Y };
    let positions = vec![Vec3::ZERO, Vec3::ZERO, Vec3::splat(f32::NAN), Vec3::ZERO];
    let normals = vec![Vec3::Y, Vec3::Y, Vec3::Y, -Vec3::Y];
    let img = metrics::shaded(&[1.0, 0.5, 1.0, 1.0], &positions, &normals, &light).unwrap();
    // 255 (0.12 + 0.88) = 255; 255 (0.12 + 0.44) = 142.8 -> 143; no surface 0; facing away 0.12 -> 31
    assert_eq!(img, vec![255, 255, 255, 143, 143, 143, 0, 0, 0, 31, 31, 31]);
    let all = [true; 4];
    let f = metrics::flip(
        &[1.0, 0.5, 1.0, 1.0],
        &[1.0, 1.0, 1.0, 1.0],
        &positions,
        &normals,
        &light,
        (2, 2),
        &all,
    )
    .unwrap();
    let map = metrics::flip_map(&metrics::shaded(&[1.0; 4], &positions, &normals, &light).unwrap(), &img, 2, 2).unwrap();
    assert_eq!(f, map.iter().map(|v| f64::from(*v)).sum::<f64>() / 4.0);
    assert!(f > 0.0);
}
