//! Throughput of the CPU visibility query, a measurement (prints one line; run with
//! `cargo bench -p sshc-lab --bench visibility_throughput`; the
//! test suite only builds it): 10^4 floor points around the bunny, 8 x 8 samples of its
//! rectangle light. Without normals the floor can never be skipped, so every point casts
//! all 64 rays; with normals, most lit points cast none.

use glam::Vec3;
use sshc_lab::scene::Scene;
use sshc_lab::visibility::Visibility;
use std::path::Path;

fn bundled(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(format!("{name}.ron"));
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn main() {
    let scene = bundled("bunny");
    let t = std::time::Instant::now();
    let vis = Visibility::new(&scene);
    let build = t.elapsed();
    let light = &scene.lights[0];
    let points: Vec<Vec3> = (0..10_000)
        .map(|i| Vec3::new(-0.8 + 2.0 * (i % 100) as f32 / 100.0, 0.0, -1.2 + 2.0 * (i / 100) as f32 / 100.0))
        .collect();
    let normals = vec![Vec3::Y; points.len()];
    let _ = vis.visible_fractions(&points[..1000], &[], light, 8); // warm up the thread pool
    let runs = 5;
    let t = std::time::Instant::now();
    let mut shadowed = 0;
    for seed in 0..runs {
        let v = vis.visible_fractions_seeded(&points, &[], light, 8, seed);
        shadowed = v.iter().filter(|&&v| v < 1.0).count();
    }
    let all = t.elapsed().as_secs_f64() / runs as f64;
    let t = std::time::Instant::now();
    for seed in 0..runs {
        vis.visible_fractions_seeded(&points, &normals, light, 8, seed);
    }
    let skipping = t.elapsed().as_secs_f64() / runs as f64;
    let rays = (points.len() * 64) as f64;
    println!(
        "bunny ({} triangles, BVH built in {build:?}), {} rayon threads: {} points x 64 rays in {:.1} ms = {:.2} M rays/s ({shadowed} points not fully lit); with normals (skip test) {:.1} ms = {:.2} M points/s",
        vis.triangle_count(),
        rayon::current_num_threads(),
        points.len(),
        all * 1e3,
        rays / all / 1e6,
        skipping * 1e3,
        points.len() as f64 / skipping / 1e6
    );
}
