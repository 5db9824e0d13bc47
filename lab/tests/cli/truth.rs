//! `sshc truth`: the closed form on edge.ron, the cache, and two processes sharing one
//! cache key.

use super::{command, ok, read_pfm};
use crate::common::temp_dir;
use std::process::Command;

/// Area of the part of a unit disk on the far side of a chord at signed distance `u`.
fn disk_fraction(u: f64) -> f64 {
    let u = u.clamp(-1.0, 1.0);
    0.5 + (u * (1.0 - u * u).sqrt() + u.asin()) / std::f64::consts::PI
}

/// The truth that `sshc truth` computes at the GPU's positions on edge.ron agrees with the
/// closed form at the pixel centres (the orthographic camera sees x in [-0.25, 0.25]
/// left to right), and the second call reads it from the cache.
#[test]
fn truth_command_matches_the_closed_form_and_is_cached() {
    let dir = temp_dir("truth");
    let (out, se, cache) = (dir.join("truth.pfm"), dir.join("se.pfm"), dir.join("cache"));
    let args = [
        "truth",
        "--scene",
        "scenes/edge.ron",
        "--size",
        "32x32",
        "--samples",
        "64",
        "--runs",
        "4",
        "-o",
        out.to_str().unwrap(),
        "--std-error",
        se.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
    ];
    let first = ok(&args);
    for needle in [
        "truth: computed, cached in",
        "64 light samples per pixel per run x 4 runs",
        "standard error",
        "rays/s",
    ] {
        assert!(first.contains(needle), "`{needle}` missing from:\n{first}");
    }
    let truth = read_pfm(&out);
    let std_error = read_pfm(&se);
    assert_eq!((truth.width, truth.height, truth.color), (32, 32, false));
    let png = image::open(dir.join("truth.png")).unwrap();
    assert_eq!((png.width(), png.height()), (32, 32));
    let se_max = std_error.data.iter().copied().fold(0f32, f32::max) as f64;
    assert!(se_max > 0.0 && se_max < 0.05, "max standard error {se_max}");
    // 4 x the largest measured standard error, plus the bias bound of the ray caster on
    // this scene (runtime/tests/truth.rs: 1e-3, which also covers the GPU's f32
    // interpolation of positions, about 1e-6 of the scene size).
    let tol = 4.0 * se_max + 1e-3;
    let w = (5f64).to_radians().tan();
    for y in 0..32 {
        for x in 0..32 {
            let px = -0.25 + (x as f64 + 0.5) / 32.0 * 0.5;
            let f = disk_fraction(px / w);
            let t = truth.data[y * 32 + x] as f64;
            assert!(
                (t - f).abs() <= tol,
                "pixel ({x}, {y}) at x = {px:.4}: truth {t:.5}, closed form {f:.5}, tolerance {tol:.5}"
            );
        }
    }
    let second = ok(&args);
    assert!(second.contains("truth: read from the cache"), "{second}");
    assert_eq!(read_pfm(&out).data, truth.data);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two `sshc truth` processes fill the same key of one cache folder at once (as two tasks
/// of a cluster do on a shared filesystem): one claims the key and computes, the other
/// waits for it and reads the stored truth. Both write the same truth, the cache holds
/// one whole record and nothing else (no claim, temporary or beat file), and the truth is
/// computed once. Then a claim that stands still (an owner on another host that stopped
/// beating) is taken over after `--claim-stale` seconds.
#[test]
fn two_truth_commands_at_once_compute_the_truth_once_and_share_it() {
    let dir = temp_dir("truth-race");
    let cache = dir.join("cache");
    // about 3 s of ray casting, well beyond the time the second process takes to start
    let truth = |name: &str, extra: &[&str]| -> Command {
        let (cache, out) = (cache.to_str().unwrap(), dir.join(format!("{name}.pfm")));
        let mut args = vec!["truth", "--scene", "scenes/triangle.ron", "--size", "48x48"];
        args.extend(["--samples", "4096", "--runs", "4", "--cache", cache, "-o", out.to_str().unwrap()]);
        args.extend(extra);
        command(&args)
    };
    let spawn = |name: &str| {
        truth(name, &[])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("sshc starts")
    };
    let (a, b) = (spawn("a"), spawn("b"));
    let text = |c: std::process::Child| {
        let o = c.wait_with_output().unwrap();
        let t = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
        assert!(o.status.success(), "{t}");
        t
    };
    let (ta, tb) = (text(a), text(b));
    let computed = [&ta, &tb].iter().filter(|t| t.contains("truth: computed, cached in")).count();
    let read = [&ta, &tb].iter().filter(|t| t.contains("truth: read from the cache")).count();
    assert_eq!((computed, read), (1, 1), "one computes, one reads:\n{ta}\n---\n{tb}");
    let waited = if ta.contains("truth: read from the cache") { &ta } else { &tb };
    // the owner is named once it has written its claim; a reader that looks between the
    // claim's creation and that write waits for "an owner not named yet" (seen in a
    // loaded suite run)
    assert!(
        (waited.contains("truth: waiting for host ") || waited.contains("truth: waiting for an owner not named yet"))
            && waited.contains(", which is computing this truth"),
        "the reader waited for the claim's owner:\n{waited}"
    );
    let (va, vb) = (read_pfm(&dir.join("a.pfm")), read_pfm(&dir.join("b.pfm")));
    assert_eq!(va.data, vb.data, "the same truth");
    let files: Vec<String> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        files.len() == 1 && files[0].ends_with(".ron"),
        "one record and nothing else: {files:?}"
    );
    let key = u128::from_str_radix(files[0].trim_end_matches(".ron"), 16).unwrap();
    let record = sshc_lab::truth::TruthCache::new(&cache).load(sshc_lab::truth::CacheKey(key));
    assert!(
        matches!(record, sshc_lab::truth::CacheLookup::Hit(_)),
        "the record is whole: {record:?}"
    );

    // A claim on another host whose beats stopped: taken over after 1 s, then computed.
    std::fs::remove_file(cache.join(&files[0])).unwrap();
    let claim = cache.join(files[0].replace(".ron", ".claim"));
    std::fs::write(&claim, "host=elsewhere pid=1 since=0\nbeat=3\n").unwrap();
    let start = std::time::Instant::now();
    let o = truth("c", &["--claim-stale", "1"]).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{out}{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("truth: computed, cached in"), "{out}");
    assert!(
        start.elapsed().as_secs_f64() >= 1.0,
        "the stale claim was waited on for its stale time"
    );
    assert_eq!(read_pfm(&dir.join("c.pfm")).data, va.data);
    assert!(!claim.exists(), "the claim taken over is released");
    let _ = std::fs::remove_dir_all(&dir);
}
