//! Ground truth (CPU, no GPU): the closed form of a straight edge under a distant disk,
//! convergence measured from independent runs, and the on-disk cache.
//!
//! Positions come from casting the camera's pixel rays on the CPU (the GPU renders the
//! same points; `compiler/tests/gpu.rs` checks that path).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use glam::Vec3;
use sshc_lab::scene::{Light, Scene};
use sshc_lab::truth::{self, CacheLookup, Points, Source, Truth, TruthCache, TruthError, TruthFiles as _, TruthSettings};
use sshc_lab::visibility::Visibility;

mod common;
use common::temp_dir;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")
}

fn edge(size: u32) -> Scene {
    let mut s = Scene::load(scenes_dir().join("edge.ron")).unwrap_or_else(|e| panic!("{e}"));
    s.set_camera_size(size, size);
    s
}

/// World position and normal of the surface each pixel's centre sees (NaN where none),
/// by casting the camera ray through it from the near plane to the far plane.
fn camera_points(scene: &Scene) -> (Vec<Vec3>, Vec<Vec3>) {
    let vis = Visibility::new(scene);
    let (w, h) = scene.camera_size();
    (0..w * h)
        .map(|i| {
            let (u, v) = (((i % w) as f32 + 0.5) / w as f32, ((i / w) as f32 + 0.5) / h as f32);
            vis.seen_by_camera(scene, u, v).unwrap_or((Vec3::NAN, Vec3::NAN))
        })
        .unzip()
}

fn no_progress(_: truth::Progress) {}

/// `f` of the points `scene`'s camera sees, one per pixel.
fn at_camera_points<R>(scene: &Scene, f: impl FnOnce(&Points) -> R) -> R {
    let (w, h) = scene.camera_size();
    let (p, n) = camera_points(scene);
    f(&Points {
        width: w,
        height: h,
        positions: &p,
        normals: &n,
    })
}

/// The cache key of `scene`'s camera pixels under `settings`, as [`cached`] computes it.
fn camera_key(scene: &Scene, settings: &TruthSettings) -> truth::CacheKey {
    at_camera_points(scene, |points| truth::cache_key(scene, points, settings)).unwrap_or_else(|e| panic!("{e}"))
}

fn run(scene: &Scene, settings: &TruthSettings) -> Truth {
    at_camera_points(scene, |points| {
        truth::compute(scene, &Visibility::new(scene), points, settings, &no_progress)
    })
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Area of the part of a unit disk on the far side of a chord at signed distance `u`
/// from its centre, as a fraction of the disk: 1 at u >= 1, 0 at u <= -1.
fn disk_fraction(u: f64) -> f64 {
    let u = u.clamp(-1.0, 1.0);
    0.5 + (u * (1.0 - u * u).sqrt() + u.asin()) / std::f64::consts::PI
}

/// The closed form of edge.ron at `p` on the floor: the shadow line is x = 0 (the
/// occluder's edge straight below it, the light overhead) and the penumbra's half-width
/// is h tan(angle / 2) with h = 1.
fn closed_form(scene: &Scene, p: Vec3) -> f64 {
    let Light::DistantDisk { angle_degrees, .. } = scene.lights[0] else {
        panic!("edge.ron has a distant disk")
    };
    let w = (0.5 * f64::from(angle_degrees).to_radians()).tan();
    disk_fraction(f64::from(p.x) / w)
}

/// Bias bound of the ray caster on edge.ron, in visibility units. The estimator is
/// unbiased (jittered stratified samples); what remains is geometric. Rays start at most
/// 2^-16 of the point's largest coordinate (at most 3e-5 here, see `visibility`) above
/// the floor, which narrows the penumbra by a fraction 3e-5 and moves f by at most
/// |df/du| * |u| * 3e-5 <= (2 / pi) * 3e-5 = 2e-5; the barycentric tolerance (1e-6 of the occluder's size) and f32 rounding of
/// positions (1e-7) move the chord far less. 1e-3 bounds them all with margin.
const EDGE_BIAS: f64 = 1e-3;

#[test]
fn truth_on_the_straight_edge_matches_the_closed_form() {
    let scene = edge(32);
    let settings = TruthSettings {
        samples: 256,
        runs: 4,
        ..Default::default()
    };
    let t = run(&scene, &settings);
    let (points, _) = camera_points(&scene);
    assert_eq!(t.surface_pixels, 32 * 32);
    assert_eq!((t.samples, t.runs), (256, 4));
    let se_max = f64::from(t.max_std_error());
    assert!(se_max > 0.0 && se_max < 0.02, "max standard error {se_max}");
    let tol = 4.0 * se_max + EDGE_BIAS;
    let (mut sq_err, mut sq_se, mut penumbra) = (0.0, 0.0, 0);
    for (i, p) in points.iter().enumerate() {
        let f = closed_form(&scene, *p);
        let est = f64::from(t.visibility[i]);
        assert!(
            (est - f).abs() <= tol,
            "pixel {i} at x = {:.4}: truth {est:.5}, closed form {f:.5}, tolerance {tol:.5} (4 x max se + {EDGE_BIAS})",
            p.x
        );
        if f > 0.0 && f < 1.0 {
            penumbra += 1;
            sq_err += (est - f) * (est - f);
            sq_se += f64::from(t.std_error[i]).powi(2);
        }
    }
    assert!(penumbra > 200, "{penumbra} penumbra pixels");
    // The measured standard error describes the actual error: over the penumbra, the RMS
    // error against the closed form and the RMS measured standard error agree. Both are
    // RMS over > 200 pixels of unbiased variance estimates, so a factor of 2 either way
    // leaves a wide margin for chance, and catches an error estimate that is off by the
    // usual mistakes (a missing sqrt(runs), a variance taken for a standard deviation).
    let (rms_err, rms_se) = ((sq_err / penumbra as f64).sqrt(), (sq_se / penumbra as f64).sqrt());
    assert!(
        rms_err <= 2.0 * rms_se + EDGE_BIAS && rms_err >= 0.5 * rms_se,
        "RMS error {rms_err:.6} against RMS standard error {rms_se:.6}"
    );
    // Lit and umbra pixels have no variance.
    for (i, p) in points.iter().enumerate() {
        if closed_form(&scene, *p) == 1.0 || closed_form(&scene, *p) == 0.0 {
            assert!(t.std_error[i] <= 1e-6, "pixel {i}: se {}", t.std_error[i]);
        }
    }
}

/// RMS measured standard error over the penumbra of edge.ron at `samples` per run.
fn penumbra_rms_se(scene: &Scene, samples: u32) -> f64 {
    let t = run(
        scene,
        &TruthSettings {
            samples,
            runs: 4,
            ..Default::default()
        },
    );
    let pen: Vec<f64> = t
        .visibility
        .iter()
        .zip(&t.std_error)
        .filter(|(v, _)| **v > 0.0 && **v < 1.0)
        .map(|(_, se)| f64::from(*se).powi(2))
        .collect();
    (pen.iter().sum::<f64>() / pen.len() as f64).sqrt()
}

#[test]
fn standard_error_falls_at_least_as_one_over_sqrt_samples() {
    // 16 x the samples: independent sampling would cut the standard error by 4 (slope
    // -1/2); stratified sampling across a straight edge does better, about samples^-3/4
    // (only the O(n) strata the edge cuts vary), i.e. by 8 (measured: -0.73). The slope
    // must lie between -1 and -0.4: at least about as fast as 1/sqrt(samples), with a
    // margin for chance, and no faster than 1/samples. The runs are seeded, so the test
    // is deterministic.
    let scene = edge(24);
    let (lo, hi) = (16, 256);
    let (a, b) = (penumbra_rms_se(&scene, lo), penumbra_rms_se(&scene, hi));
    let slope = (b / a).ln() / (f64::from(hi) / f64::from(lo)).ln();
    eprintln!("penumbra rms standard error: {a:.6} at {lo} samples, {b:.6} at {hi}: slope {slope:.3}");
    assert!(
        (-1.0..=-0.4).contains(&slope),
        "rms se {a:.6} at {lo} samples, {b:.6} at {hi}: slope {slope:.3}"
    );
}

#[test]
fn doubling_stops_at_the_target_or_the_cap() {
    let scene = edge(12);
    let t = run(
        &scene,
        &TruthSettings {
            samples: 16,
            runs: 4,
            target_std_error: Some(0.01),
            max_samples: 4096,
            ..Default::default()
        },
    );
    assert!(t.levels.len() > 1, "16 samples are not enough: {:?}", t.levels);
    assert!(t.max_std_error() <= 0.01, "{:?}", t.levels);
    assert!(t.levels.windows(2).all(|l| l[1].samples > l[0].samples), "{:?}", t.levels);
    assert_eq!(t.samples, t.levels.last().unwrap().samples);
    // An unreachable target stops at the cap.
    let t = run(
        &scene,
        &TruthSettings {
            samples: 16,
            runs: 2,
            target_std_error: Some(1e-9),
            max_samples: 100,
            ..Default::default()
        },
    );
    assert_eq!(t.samples, 100, "{:?}", t.levels);
    // A point light needs one ray per run: no variance, no doubling.
    let mut point = scene.clone();
    point.lights = vec![Light::Point {
        position: Vec3::new(0.3, 3.0, 0.0),
    }];
    let t = run(
        &point,
        &TruthSettings {
            samples: 64,
            runs: 2,
            target_std_error: Some(1e-9),
            ..Default::default()
        },
    );
    assert_eq!((t.samples, t.levels.len(), t.max_std_error()), (1, 1, 0.0));
    assert!(t.visibility.iter().all(|&v| v == 0.0 || v == 1.0));
}

#[test]
fn results_are_deterministic_and_seeds_independent() {
    let scene = edge(16);
    let s = TruthSettings {
        samples: 16,
        runs: 2,
        ..Default::default()
    };
    let a = run(&scene, &s);
    let b = run(&scene, &s);
    assert_eq!(a.visibility, b.visibility);
    let c = run(&scene, &TruthSettings { seed: 7, ..s });
    assert_ne!(a.visibility, c.visibility);
}

#[test]
fn bad_inputs_are_errors() {
    let scene = edge(4);
    let vis = Visibility::new(&scene);
    let p = vec![Vec3::ZERO; 16];
    let s = TruthSettings::default();
    let err = |r: Result<Truth, TruthError>| r.err().map(|e| e.to_string()).unwrap_or_default();
    let at = |positions, normals| Points {
        width: 4,
        height: 4,
        positions,
        normals,
    };
    let e = err(truth::compute(&scene, &vis, &at(&p[..15], &[]), &s, &no_progress));
    assert!(e.contains("15 positions"), "{e}");
    let e = err(truth::compute(&scene, &vis, &at(&p, &p[..3]), &s, &no_progress));
    assert!(e.contains("3 normals"), "{e}");
    let one_run = TruthSettings { runs: 1, ..s.clone() };
    let e = err(truth::compute(&scene, &vis, &at(&p, &[]), &one_run, &no_progress));
    assert!(e.contains("at least 2"), "{e}");
    let e = err(truth::compute(&scene, &vis, &Points { width: 0, ..at(&[], &[]) }, &s, &no_progress));
    assert!(e.contains("at least one pixel"), "{e}");
    let mut dark = scene.clone();
    dark.lights.clear();
    assert_eq!(
        truth::compute(&dark, &vis, &at(&p, &[]), &s, &no_progress).unwrap_err(),
        TruthError::NoLight
    );
    // No surface anywhere: all lit, no error, no sample evaluated.
    let t = truth::compute(&scene, &vis, &at(&[Vec3::NAN; 16], &[]), &s, &no_progress).unwrap();
    assert!(t.visibility.iter().all(|&v| v == 1.0) && t.max_std_error() == 0.0);
    assert_eq!((t.surface_pixels, t.samples_evaluated), (0, 0));
}

#[test]
fn progress_reaches_the_total() {
    let scene = edge(8);
    let (p, n) = camera_points(&scene);
    let last = AtomicU64::new(0);
    let total = AtomicU64::new(0);
    let progress = |pr: truth::Progress| {
        last.store(pr.done, Ordering::Relaxed);
        total.store(pr.total, Ordering::Relaxed);
    };
    let s = TruthSettings {
        samples: 4,
        runs: 3,
        ..Default::default()
    };
    let points = Points {
        width: 8,
        height: 8,
        positions: &p,
        normals: &n,
    };
    truth::compute(&scene, &Visibility::new(&scene), &points, &s, &progress).unwrap();
    assert_eq!(total.load(Ordering::Relaxed), 64 * 3);
    assert_eq!(last.load(Ordering::Relaxed), 64 * 3);
}

/// [`truth::compute_cached`] of `scene` with a cache in `dir`.
fn cached(scene: &Scene, settings: &TruthSettings, dir: &Path) -> (Truth, Source) {
    let cache = TruthCache::new(dir);
    at_camera_points(scene, |points| {
        truth::compute_cached(scene, points, settings, Some(&cache), &no_progress, &|m| eprintln!("{m}"))
    })
    .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn the_cache_hits_on_the_second_call_and_misses_when_samples_or_scene_change() {
    let dir = temp_dir("cache");
    let cache_dir = dir.join("cache");
    let scene_text = std::fs::read_to_string(scenes_dir().join("edge.ron")).unwrap();
    let scene_path = dir.join("edge.ron");
    std::fs::write(&scene_path, &scene_text).unwrap();
    let load = || {
        let mut s = Scene::load(&scene_path).unwrap();
        s.set_camera_size(16, 16);
        s
    };
    let s = TruthSettings {
        samples: 16,
        runs: 2,
        ..Default::default()
    };
    let (first, src) = cached(&load(), &s, &cache_dir);
    let Source::Computed(Some(file)) = src else {
        panic!("first call: {src:?}")
    };
    assert!(file.starts_with(&cache_dir) && file.exists());
    let (second, src) = cached(&load(), &s, &cache_dir);
    assert_eq!(src, Source::Cached(file.clone()), "second call");
    assert_eq!(first, second, "the cache keeps every value bit for bit");

    // Other samples, runs or seed: a miss.
    for other in [
        TruthSettings { samples: 25, ..s.clone() },
        TruthSettings { runs: 3, ..s.clone() },
        TruthSettings { seed: 1, ..s.clone() },
    ] {
        let (_, src) = cached(&load(), &other, &cache_dir);
        assert!(matches!(src, Source::Computed(Some(_))), "{other:?}: {src:?}");
    }
    // Another resolution: a miss.
    let mut big = load();
    big.set_camera_size(20, 20);
    assert!(matches!(cached(&big, &s, &cache_dir).1, Source::Computed(_)));
    // Another shadow-map resolution changes no position: a hit.
    let mut shadow = load();
    shadow.shadow_map = 64;
    assert!(matches!(cached(&shadow, &s, &cache_dir).1, Source::Cached(_)));
    // The scene file changes (a wider light): a miss; even a comment changes the key.
    std::fs::write(&scene_path, scene_text.replace("angle_degrees: 10.0", "angle_degrees: 12.0")).unwrap();
    let (wider, src) = cached(&load(), &s, &cache_dir);
    assert!(matches!(src, Source::Computed(_)), "{src:?}");
    assert_ne!(wider.visibility, first.visibility);
    std::fs::write(&scene_path, format!("// a comment\n{scene_text}")).unwrap();
    assert!(matches!(cached(&load(), &s, &cache_dir).1, Source::Computed(_)));

    // A damaged file is recomputed and replaced.
    std::fs::write(&file, "Record(key: ").unwrap();
    std::fs::write(&scene_path, &scene_text).unwrap();
    let key = camera_key(&load(), &s);
    assert!(matches!(TruthCache::new(&cache_dir).load(key), CacheLookup::Unreadable(_)));
    let (again, src) = cached(&load(), &s, &cache_dir);
    assert!(matches!(src, Source::Computed(_)));
    assert_eq!(
        (&again.visibility, &again.std_error),
        (&first.visibility, &first.std_error),
        "deterministic"
    );
    assert!(matches!(TruthCache::new(&cache_dir).load(key), CacheLookup::Hit(_)));
    // Issue 48, item 9: a record altered after it was written (a value changed, its
    // structure intact) is not trusted, nor is one whose values no run writes (7.5, NaN)
    // even with a matching checksum: both are recomputed.
    let stored = std::fs::read_to_string(&file).unwrap();
    let altered = stored
        .replacen("visibility:[", "visibility:[0.5,", 1)
        .replacen("std_error:[", "std_error:[0.0,", 1);
    let first_value = |text: &str| -> String {
        let at = text.find("visibility:[").unwrap() + "visibility:[".len();
        text[at..].split([',', ']']).next().unwrap().to_string()
    };
    let v0 = first_value(&stored);
    let swapped = stored.replacen(
        &format!("visibility:[{v0}"),
        &format!("visibility:[{}", if v0 == "1.0" { "0.0" } else { "1.0" }),
        1,
    );
    assert_ne!(swapped, stored);
    for (what, text) in [
        ("a value changed", swapped),
        ("a pixel added", altered),
        ("7.5", stored.replacen(&format!("visibility:[{v0}"), "visibility:[7.5", 1)),
        ("NaN", stored.replacen(&format!("visibility:[{v0}"), "visibility:[NaN", 1)),
    ] {
        std::fs::write(&file, text).unwrap();
        match TruthCache::new(&cache_dir).load(key) {
            CacheLookup::Unreadable(why) => assert!(
                why.contains("checksum") || why.contains("outside [0, 1]") || why.contains("does not match its key"),
                "{what}: {why}"
            ),
            other => panic!(
                "{what}: {}",
                if matches!(other, CacheLookup::Hit(_)) {
                    "trusted"
                } else {
                    "a miss"
                }
            ),
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Writers of one record at once (threads of one process here: the same pid, as two nodes
/// of a cluster may have) each write a temporary file of their own: every store succeeds
/// and the record is always whole.
#[test]
fn concurrent_stores_of_one_key_all_succeed_and_leave_a_whole_record() {
    let dir = temp_dir("concurrent");
    let cache_dir = dir.join("cache");
    let mut scene = Scene::load(scenes_dir().join("edge.ron")).unwrap();
    scene.set_camera_size(8, 8);
    let s = TruthSettings {
        samples: 4,
        runs: 2,
        ..Default::default()
    };
    let (t, src) = cached(&scene, &s, &cache_dir);
    let Source::Computed(Some(file)) = src else { panic!("{src:?}") };
    let key = camera_key(&scene, &s);
    let cache = TruthCache::new(&cache_dir);
    std::thread::scope(|sc| {
        for _ in 0..8 {
            sc.spawn(|| {
                for _ in 0..40 {
                    assert_eq!(cache.store(key, &t).unwrap_or_else(|e| panic!("{e}")), file);
                    match cache.load(key) {
                        CacheLookup::Hit(r) => assert_eq!(*r, t),
                        other => panic!("a reader saw {other:?}"),
                    }
                }
            });
        }
    });
    let left: Vec<_> = std::fs::read_dir(&cache_dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left.len(), 1, "temporary files left behind: {left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_key_hashes_mesh_bytes_and_positions() {
    let dir = temp_dir("key");
    let obj = "v 0 0.5 0\nv 1 0.5 0\nv 0 0.5 1\nf 1 2 3\n";
    std::fs::write(dir.join("m.obj"), obj).unwrap();
    let text = "Scene(camera: Orthographic(position: (0.0, 2.0, 0.0), target: (0.0, 0.0, 0.0), up: (0.0, 0.0, -1.0), half_height: 1.0, width: 4, height: 4), shadow_map: 8, lights: [Point(position: (0.0, 3.0, 0.0))], objects: [Object(mesh: Plane(size: (2.0, 2.0))), Object(mesh: Obj(path: \"m.obj\"))])";
    std::fs::write(dir.join("s.ron"), text).unwrap();
    let scene = Scene::load(dir.join("s.ron")).unwrap();
    let p = vec![Vec3::ZERO; 16];
    let s = TruthSettings::default();
    let key = |positions: &[Vec3]| {
        let points = Points {
            width: 4,
            height: 4,
            positions,
            normals: &[],
        };
        truth::cache_key(&scene, &points, &s)
    };
    let k1 = key(&p).unwrap();
    assert_eq!(k1, key(&p).unwrap(), "stable");
    // The same triangles, other bytes (a comment): another key.
    std::fs::write(dir.join("m.obj"), format!("# moved\n{obj}")).unwrap();
    let k2 = key(&p).unwrap();
    assert_ne!(k1, k2);
    // One position one ulp away: another key.
    let mut q = p.clone();
    q[5].x = f32::from_bits(1);
    assert_ne!(k2, key(&q).unwrap());
    // A mesh that disappeared is an error naming it.
    std::fs::remove_file(dir.join("m.obj")).unwrap();
    let e = key(&p).unwrap_err().to_string();
    assert!(e.contains("m.obj"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn truth_files_are_written() {
    let scene = edge(8);
    let t = run(
        &scene,
        &TruthSettings {
            samples: 4,
            runs: 2,
            ..Default::default()
        },
    );
    let dir = temp_dir("files");
    t.write_pfm(&dir.join("t.pfm")).unwrap();
    t.write_std_error_pfm(&dir.join("se.pfm")).unwrap();
    t.write_png(&dir.join("t.png")).unwrap();
    let png = image::open(dir.join("t.png")).unwrap().to_luma8();
    assert_eq!(png.dimensions(), (8, 8));
    // Rows top first: the camera looks down with -Z up, so left columns are in umbra.
    assert_eq!(png.get_pixel(0, 0).0[0], 0);
    assert_eq!(png.get_pixel(7, 7).0[0], 255);
    let pfm = std::fs::read(dir.join("t.pfm")).unwrap();
    assert!(pfm.starts_with(b"Pf\n8 8\n-1\n"), "{:?}", &pfm[..12]);
    assert_eq!(pfm.len(), 10 + 64 * 4);
    let _ = std::fs::remove_dir_all(&dir);
}
