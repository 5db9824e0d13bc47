//! `sshc truth` and `sshc compare` end to end on a real adapter (lavapipe on machines
//! without a GPU), at tiny resolutions. They never skip: with no adapter the commands
//! fail, and so do these tests (`scripts/test.sh` installs lavapipe).

use std::path::Path;
use std::process::{Command, Output};

mod common;
use common::{root, temp_dir};

/// `sshc ARGS` from the repository's root, on lavapipe's two threads.
fn command(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sshc"));
    c.args(args)
        .current_dir(root())
        .env("LP_NUM_THREADS", std::env::var("LP_NUM_THREADS").unwrap_or_else(|_| "2".into()))
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or_else(|_| "/tmp".into()),
        );
    c
}

fn sshc(args: &[&str]) -> Output {
    command(args).output().expect("the sshc binary runs")
}

/// Runs `sshc` and returns its standard output; fails with its output when it fails.
fn ok(args: &[&str]) -> String {
    let out = sshc(args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "sshc {} failed ({}):\n{stdout}\n{}",
        args.join(" "),
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// The number printed right after `label` in `out`.
fn number_after(label: &str, out: &str) -> f64 {
    let rest = &out[out.find(label).unwrap_or_else(|| panic!("{label}: {out}")) + label.len()..];
    let token: String = rest.trim_start().chars().take_while(|c| c.is_ascii_digit() || *c == '.').collect();
    token.parse().unwrap_or_else(|_| panic!("no number after `{label}` in:\n{out}"))
}

fn read_pfm(path: &Path) -> pxm::PFM {
    let mut f = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    pxm::PFM::read_from(&mut f).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

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

/// `sshc compare` reads the truth that `sshc truth` cached (every technique's camera pass
/// writes the same positions), writes one image with three panels and the figures, and
/// prints them.
#[test]
fn compare_command_writes_the_comparison_and_its_figures() {
    let dir = temp_dir("compare");
    let cache = dir.join("cache");
    let common = [
        "--scene",
        "scenes/contact.ron",
        "--size",
        "32x32",
        "--samples",
        "16",
        "--runs",
        "2",
        "--cache",
    ];
    let mut truth_args = vec!["truth"];
    truth_args.extend(common);
    let truth_out = dir.join("truth.pfm");
    truth_args.extend([cache.to_str().unwrap(), "-o", truth_out.to_str().unwrap()]);
    ok(&truth_args);
    let png = dir.join("compare.png");
    let mut args = vec!["compare", "techniques/pcf.ron"];
    args.extend(common);
    args.extend([
        cache.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--set",
        "N=5",
        "--frames",
        "3",
        "--stability-frames",
        "3",
    ]);
    let out = ok(&args);
    for needle in [
        "truth: read from the cache",
        "pcf.ron on contact.ron: 32x32 px",
        "N=5",
        "error facing the light: RMS",
        "error in penumbra (0 < truth < 1): RMS",
        "temporal: mean |change|",
        "GPU time per frame:",
        "memory peak",
        "device:",
    ] {
        assert!(out.contains(needle), "`{needle}` missing from:\n{out}");
    }
    // The figures, recomputed here from what `sshc truth` and `sshc render` write: the
    // truth read from the cache, and the same technique's visibility, positions and normals.
    let (vis, pos, nrm) = (dir.join("vis.pfm"), dir.join("pos.pfm"), dir.join("nrm.pfm"));
    ok(&[
        "render",
        "techniques/pcf.ron",
        "--scene",
        "scenes/contact.ron",
        "--size",
        "32x32",
        "--set",
        "N=5",
        "-o",
        dir.join("render.png").to_str().unwrap(),
        "--visibility",
        vis.to_str().unwrap(),
        "--positions",
        pos.to_str().unwrap(),
        "--normals",
        nrm.to_str().unwrap(),
    ]);
    let (vis, truth, pos, nrm) = (read_pfm(&vis), read_pfm(&truth_out), read_pfm(&pos), read_pfm(&nrm));
    assert_eq!(
        (vis.data.len(), truth.data.len(), pos.data.len(), nrm.data.len()),
        (1024, 1024, 3072, 3072)
    );
    // contact.ron's sphere light is centred at (-0.8, 3.2, 1.6): a pixel faces it when its
    // normal points to that side of its surface
    let centre = [-0.8f32, 3.2, 1.6];
    let (mut facing, mut penumbra) = (Vec::new(), Vec::new());
    for i in 0..1024 {
        let (p, n) = (&pos.data[3 * i..3 * i + 3], &nrm.data[3 * i..3 * i + 3]);
        if !p.iter().chain(n).all(|c| c.is_finite()) {
            continue;
        }
        let dot: f32 = (0..3).map(|k| n[k] * (centre[k] - p[k])).sum();
        if dot > 0.0 {
            // signed error in 0..255 units
            let e = 255.0 * (vis.data[i] as f64 - truth.data[i] as f64);
            facing.push(e);
            if truth.data[i] > 0.0 && truth.data[i] < 1.0 {
                penumbra.push(e);
            }
        }
    }
    let stats = |e: &[f64]| {
        let rms = (e.iter().map(|x| x * x).sum::<f64>() / e.len().max(1) as f64).sqrt();
        (rms, e.iter().fold(0.0f64, |m, x| m.max(x.abs())), e.len())
    };
    // "error <what>: RMS r, max m (0..255) over n px", as printed: r to 2 decimals, m to 1
    let printed = |what: &str| -> (f64, f64, usize) {
        let line = out
            .lines()
            .find(|l| l.starts_with(&format!("error {what}: RMS ")))
            .unwrap_or_else(|| panic!("no `error {what}` line in:\n{out}"));
        let field = |after: &str, end: &str| -> String {
            let rest = &line[line.find(after).unwrap_or_else(|| panic!("{line}")) + after.len()..];
            rest[..rest.find(end).unwrap_or_else(|| panic!("{line}"))].to_string()
        };
        let parse = |t: String| -> f64 { t.parse().unwrap_or_else(|_| panic!("`{t}` in `{line}`")) };
        (
            parse(field("RMS ", ",")),
            parse(field("max ", " ")),
            parse(field("over ", " px")) as usize,
        )
    };
    for (what, errors) in [("facing the light", &facing), ("in penumbra (0 < truth < 1)", &penumbra)] {
        let (rms, max, n) = stats(errors);
        let (p_rms, p_max, p_n) = printed(what);
        assert_eq!(p_n, n, "{what}: pixels\n{out}");
        // half a unit in the last printed digit, and f32 storage of the PFMs (2^-24 of 255)
        assert!(
            (p_rms - rms).abs() <= 0.005 + 1e-4,
            "{what}: RMS printed {p_rms}, recomputed {rms:.4}\n{out}"
        );
        assert!(
            (p_max - max).abs() <= 0.05 + 1e-4,
            "{what}: max printed {p_max}, recomputed {max:.4}\n{out}"
        );
    }
    assert!(stats(&penumbra).0 > 0.0, "PCF is not exact in the penumbra:\n{out}");
    // FLIP, recomputed from the same files: the image shaded with the visibility against
    // it shaded with the truth's, averaged over the facing pixels (printed to 4 decimals)
    let vec3s = |d: &[f32]| -> Vec<glam::Vec3> { d.chunks(3).map(|c| glam::Vec3::new(c[0], c[1], c[2])).collect() };
    let (p3, n3) = (vec3s(&pos.data), vec3s(&nrm.data));
    let light = sshc_lab::scene::Scene::load(root().join("scenes/contact.ron")).unwrap().lights[0].clone();
    let mask = sshc_lab::metrics::facing_light(&p3, &n3, &light).unwrap();
    let flip = sshc_lab::metrics::flip(&vis.data, &truth.data, &p3, &n3, &light, (32, 32), &mask).unwrap();
    let line = out
        .lines()
        .find(|l| l.starts_with("FLIP facing the light: "))
        .unwrap_or_else(|| panic!("no FLIP line:\n{out}"));
    let printed: f64 = line["FLIP facing the light: ".len()..].split(' ').next().unwrap().parse().unwrap();
    assert!(
        (printed - flip).abs() <= 0.00005 + 1e-7,
        "FLIP printed {printed}, recomputed {flip:.6}\n{out}"
    );
    assert!(flip > 0.0 && flip < 1.0, "{flip}");
    // Temporal: the mean |change| per frame while the light moves 0.25 texel per frame. It
    // is above 0 (a penumbra in view moves) and below what one frame can change a PCF
    // pixel by: N x N bilinear taps over (N + 1)^2 texels with N = 5. Moving the kernel by
    // t texels over fixed depths changes the lit fraction by at most t / N (the weights of
    // its first and last columns move by t, the others not: (1/N^2) N t); the depth map is
    // rasterised anew, and an edge that moves by under a texel flips at most one texel per
    // row of the kernel: N + 1 taps of weight at most 1/N^2. With t < 2 x 0.25 (the step is
    // set at the scene's centre; the occluders are no nearer the light than half its
    // distance to the centre, parallax at most doubles it), at most
    // 255 ((N + 1) / N^2 + 0.5 / N) = 86.7 per pixel (depth tests at near-ties aside, which
    // flip single taps of weight 1/N^2 on few pixels), so also on average.
    let temporal = number_after("temporal: mean |change|", &out);
    let bound = 255.0 * (6.0 / 25.0 + 0.5 / 5.0);
    assert!(temporal > 0.0 && temporal <= bound, "temporal {temporal}, bound {bound:.1}:\n{out}");
    // Three 32-pixel panels scaled by 8, side by side, text below.
    let img = image::open(&png).unwrap().to_rgb8();
    assert!(img.width() >= 3 * 256 && img.height() > 256 + 8 * 19, "{:?}", img.dimensions());
    // The error panel (third) holds red or blue somewhere: PCF errs in the penumbra.
    let x0 = 12 + 2 * (256 + 12);
    let coloured = (0..256)
        .flat_map(|y| (0..256).map(move |x| (x, y)))
        .map(|(x, y)| img.get_pixel(x0 + x, 34 + y).0)
        .filter(|p| p[0].abs_diff(p[2]) > 40)
        .count();
    assert!(coloured > 0, "the error panel is blank");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_arguments_are_errors_that_say_why() {
    let out = sshc(&["truth", "--scene", "scenes/edge.ron", "--runs", "1", "--no-cache"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--runs") && err.contains("at least 2"), "{err}");

    let dir = temp_dir("bad");
    let scene = dir.join("bad.ron");
    std::fs::write(&scene, "Scene(\n  camera: Perspective(position: (0.0, 1.0, 2.0)),\n)\n").unwrap();
    let out = sshc(&["compare", "techniques/pcf.ron", "--scene", scene.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("{}:2:", scene.display())), "file:line:column expected: {err}");

    let out = sshc(&["compare", "techniques/pcf.ron", "--scene", "scenes/edge.ron", "--size", "0x4"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("at least one pixel"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `sshc` expecting a refusal within `secs` seconds; returns its standard error.
fn refused(args: &[&str], secs: u64) -> String {
    let start = std::time::Instant::now();
    let out = sshc(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "sshc {} succeeded:\n{stderr}", args.join(" "));
    assert!(
        start.elapsed().as_secs() < secs,
        "sshc {} took {:?}",
        args.join(" "),
        start.elapsed()
    );
    stderr
}

#[test]
fn huge_truth_budgets_sizes_frames_and_a_cache_file_are_refused_at_once() {
    // Bound: each refusal within 60 s (before: hours, or gigabytes of memory).
    let e = refused(
        &["truth", "--scene", "scenes/edge.ron", "--samples", "4294967295", "--no-cache"],
        60,
    );
    assert!(
        e.contains("`--samples 4294967295` x `--runs 4` x 65536 pixels") && e.contains("above the budget of 2^36"),
        "{e}"
    );
    let e = refused(&["truth", "--scene", "scenes/edge.ron", "--runs", "1000000000", "--no-cache"], 60);
    assert!(
        e.contains("`--runs 1000000000`") && e.contains("light samples, above the budget"),
        "{e}"
    );
    let dir = temp_dir("refusals");
    let file = dir.join("cache-file");
    std::fs::write(&file, "x").unwrap();
    let out = dir.join("t.pfm");
    let e = refused(
        &[
            "truth",
            "--scene",
            "scenes/edge.ron",
            "--size",
            "8x8",
            "--cache",
            file.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        60,
    );
    assert!(e.contains("is a file, not a folder") && !e.contains("os error 17"), "{e}");
    let e = refused(&["truth", "--scene", "scenes/edge.ron", "--size", "8192x8192", "--no-cache"], 60);
    assert!(e.contains("above the limit of 16777216 (4096x4096)"), "{e}");
    let e = refused(
        &[
            "compare",
            "techniques/hard.ron",
            "--scene",
            "scenes/edge.ron",
            "--size",
            "8x8",
            "--stability-frames",
            "1000000",
            "--no-cache",
        ],
        60,
    );
    assert!(e.contains("`--stability-frames 1000000` is above the limit of 1024"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `sshc render` states the shadow map's fit and the world size of one texel: on
/// triangle-lawlor.ron the map is fitted to the triangle (half-width 0.5) padded by the
/// penumbra's reach 0.6 tan(5 degrees) and one guard texel a side, so a texel is
/// 2 (0.5 + 0.0525) / (n - 2); on triangle.ron, the whole scene.
#[test]
fn render_states_the_fit_and_the_texel_size() {
    let dir = temp_dir("fit");
    let png = dir.join("r.png");
    let png = png.to_str().unwrap();
    let reach = 0.6 * 5f64.to_radians().tan();
    for n in [16u32, 32] {
        let out = ok(&[
            "render",
            "techniques/hard.ron",
            "--scene",
            "scenes/triangle-lawlor.ron",
            "--size",
            "8x8",
            "--shadow-map",
            &n.to_string(),
            "-o",
            png,
        ]);
        assert!(out.contains("shadow map fitted to the casters (1 of 2 objects)"), "{out}");
        let texel = number_after("one texel =", &out);
        let expected = 2.0 * (0.5 + reach) / f64::from(n - 2);
        // printed with 4 decimals
        assert!((texel - expected).abs() < 6e-5, "{n} texels: {texel} against {expected}\n{out}");
        assert!((number_after("penumbra's reach", &out) - reach).abs() < 6e-5, "{out}");
    }
    let out = ok(&[
        "render",
        "techniques/hard.ron",
        "--scene",
        "scenes/triangle.ron",
        "--size",
        "8x8",
        "--shadow-map",
        "16",
        "-o",
        png,
    ]);
    assert!(out.contains("shadow map fitted to the whole scene (2 objects)"), "{out}");
    assert!(number_after("one texel =", &out) > 0.15, "{out}");
    let _ = std::fs::remove_dir_all(dir);
}

/// `sshc render` sets each pass's time against its compulsory bytes: at 1024^2 texels
/// esm's `exponential` reads and writes one R32Float texel (8.39 MB), which at a given
/// 100 GB/s bound it to 0.084 ms; without `--bandwidth` the bandwidth is measured.
#[test]
fn render_sets_each_pass_against_its_bytes_bound() {
    let dir = temp_dir("bytes");
    let png = dir.join("r.png");
    let png = png.to_str().unwrap();
    let args = [
        "render",
        "techniques/esm.ron",
        "--scene",
        "scenes/contact.ron",
        "--size",
        "8x8",
        "--shadow-map",
        "1024",
        "-o",
        png,
    ];
    let out = ok(&[&args[..], &["--bandwidth", "100"]].concat());
    assert!(out.contains("bandwidth: 100.0 GB/s (given)"), "{out}");
    assert!(out.contains("| compulsory MB | GB/s | bound ms | ms / bound | schedule |"), "{out}");
    let row: Vec<&str> = out
        .lines()
        .find(|l| l.starts_with("| exponential |"))
        .unwrap_or_else(|| panic!("{out}"))
        .split('|')
        .map(str::trim)
        .collect();
    // | pass | ms | invocations | fetches | operations | MB | GB/s | bound | ratio | schedule |
    assert_eq!(row[10], "fragment", "{row:?}");
    let num = |i: usize| row[i].parse::<f64>().unwrap_or_else(|_| panic!("column {i} of {row:?}"));
    assert_eq!(row[6], "8.39", "{row:?}");
    assert_eq!(row[8], "0.084", "{row:?}");
    // achieved GB/s and the ratio follow from the measured time, printed to 3 decimals
    // (a relative rounding of 0.0005 / ms) and themselves printed to 1 (0.05)
    let ms = num(2);
    assert!(ms > 0.0, "{row:?}");
    let rel = 0.0005 / ms;
    assert!((num(7) - 8.388608 / ms).abs() <= 0.05 + rel * num(7) * 1.01, "{row:?}");
    assert!((num(9) - ms / 0.08388608).abs() <= 0.05 + rel * num(9) * 1.01, "{row:?}");
    // the compute schedule, asked for on the command line, shows in the table
    let out = ok(&[&args[..], &["--bandwidth", "100", "--schedule", "exponential=compute"]].concat());
    let row = out
        .lines()
        .find(|l| l.starts_with("| exponential |"))
        .unwrap_or_else(|| panic!("{out}"));
    assert!(row.ends_with("| compute |"), "{row}");
    let out = ok(&args);
    assert!(number_after("bandwidth:", &out) > 0.0, "{out}");
    assert!(out.contains("(measured: a copy of 64 MiB, read and written, median of 5)"), "{out}");
    let bad = sshc(&[&args[..], &["--bandwidth", "-1"]].concat());
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--bandwidth -1: a bandwidth is a positive number of GB/s"));
    let _ = std::fs::remove_dir_all(dir);
}

/// `scripts/gpu-bench.sh`, the script for GPU machines without a toolchain, runs from a
/// given binary and reports every bundled technique at every map size asked for.
#[test]
fn the_gpu_bench_script_reports_every_technique() {
    let dir = temp_dir("gpu-bench");
    let report = dir.join("gpu.md");
    let out = Command::new("bash")
        .args([
            "scripts/gpu-bench.sh",
            env!("CARGO_BIN_EXE_sshc"),
            report.to_str().unwrap(),
            "16x16",
            "8,16",
            "1",
        ])
        .current_dir(root())
        .env("LP_NUM_THREADS", "2")
        .output()
        .expect("bash runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let md = std::fs::read_to_string(&report).unwrap();
    assert!(md.contains("Device: ") && md.contains("bandwidth: "), "{md}");
    let techniques = std::fs::read_dir(root().join("techniques"))
        .unwrap()
        .filter(|e| e.as_ref().is_ok_and(|e| e.path().extension().is_some_and(|x| x == "ron")))
        .count();
    for map in ["## Shadow map 8^2", "## Shadow map 16^2"] {
        assert!(md.contains(map), "{md}");
    }
    assert_eq!(md.matches("### ").count(), 2 * techniques, "{md}");
    // every technique's table has its shade row, with a bound
    assert_eq!(
        md.lines()
            .filter(|l| l.starts_with("| shade |") || l.starts_with("| shade|"))
            .count(),
        2 * techniques,
        "{md}"
    );
    // the compute row runs the Shade deferred where the technique allows it (11 of the 13
    // bundled ones: linear-light and point-samples read a light sample's depth slope), and
    // every table ends with the two wall-clock rows
    let deferred = md
        .lines()
        .filter(|l| l.starts_with("| shade") && l.trim_end().ends_with("deferred |"))
        .count();
    assert_eq!(deferred, 2 * (techniques - 2), "{md}");
    assert_eq!(
        md.matches("| **whole frame, wall clock, only the Shade deferred** |").count(),
        2 * techniques,
        "{md}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// Scene specialisation on the command line: `compile --scene` records the
/// facts and refuses a light the technique does not admit, naming both files; `explain
/// --scene` says what folded and compares the work with the generic build; `render`
/// specialises by default where admitted, warns and stays generic where not, and a
/// graph specialised for one light kind is refused on a scene with another.
#[test]
fn scene_specialisation_is_recorded_explained_and_enforced() {
    let dir = std::env::temp_dir().join(format!("sshc-specialise-{}", std::process::id()));
    let out = dir.to_string_lossy().into_owned();
    ok(&["compile", "techniques/pcss.ron", "--scene", "scenes/contact.ron", "-o", &out]);
    let graph = std::fs::read_to_string(dir.join("pcss.graph.ron")).unwrap();
    assert!(graph.contains("specialised: Some((") && graph.contains("light: Sphere"), "{graph}");
    let e = refused(
        &["compile", "techniques/penumbra-maps.ron", "--scene", "scenes/bunny.ron", "-o", &out],
        30,
    );
    assert!(e.contains("does not admit the Rectangle light of scene scenes/bunny.ron"), "{e}");
    assert!(e.contains("techniques/penumbra-maps.ron:22:13"), "{e}");
    let text = ok(&["explain", "techniques/pcss.ron", "--scene", "scenes/contact.ron"]);
    assert!(text.contains("`light_spread` is 0 for a Sphere light: folded"), "{text}");
    assert!(text.contains("| shade | 100 | 100 |"), "{text}");
    // render: specialised by default; not where the list does not admit the light
    let png = dir.join("r.png").to_string_lossy().into_owned();
    let small = ["--size", "16x16", "--shadow-map", "32", "-o", &png];
    let r = sshc(
        &[
            &["render", "techniques/penumbra-maps.ron", "--scene", "scenes/bunny.ron"][..],
            &small[..],
        ]
        .concat(),
    );
    assert!(r.status.success());
    assert!(
        String::from_utf8_lossy(&r.stderr)
            .contains("warning: techniques/penumbra-maps.ron does not admit the Rectangle light of scenes/bunny.ron")
    );
    // the graph specialised for contact's sphere, run on bunny's rectangle
    let g = dir.join("pcss.graph.ron").to_string_lossy().into_owned();
    let e = refused(&[&["render", &g, "--scene", "scenes/bunny.ron"][..], &small[..]].concat(), 60);
    assert!(
        e.contains("was specialised for the Sphere light of scene scenes/contact.ron, but this scene's light is Rectangle"),
        "{e}"
    );
    ok(&[&["render", &g, "--scene", "scenes/contact.ron"][..], &small[..]].concat());
    let _ = std::fs::remove_dir_all(dir);
}

/// Several lights: `render` gives each light its own passes and textures in one
/// frame and combines them on the GPU. Channel i of the visibility file is, bit for bit, a
/// render of the scene with light i alone; the image is the mean of the lights' images
/// within one 8-bit quantum (the mean of three 8-bit values lies between two codes, and the
/// GPU's store may round to either); three lights share one set of shadow-map-sized
/// textures, plus the combining step's; `--lights K` keeps the first K lights;
/// `compare` gives each light its own truth and error.
#[test]
fn each_light_of_a_scene_renders_with_its_own_passes_and_compares_alone() {
    let dir = std::env::temp_dir().join(format!("sshc-lights-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let small = ["--size", "24x24", "--shadow-map", "64"];
    let render = |scene: &str, vis: &str, png: &str, extra: &[&str]| {
        ok(&[
            &[
                "render",
                "techniques/pcf.ron",
                "--scene",
                scene,
                "--visibility",
                &p(vis),
                "-o",
                &p(png),
            ][..],
            &small[..],
            extra,
        ]
        .concat())
    };
    let out = render("scenes/three-lights.ron", "v.pfm", "v.png", &[]);
    assert!(out.contains("| 1 | Sphere |") && out.contains("| 2 | DistantDisk |"), "{out}");
    // each light alone, from the same file with the other lights removed (compiled for any
    // scene, as the three-light scene of several kinds is)
    let text = std::fs::read_to_string(root().join("scenes/three-lights.ron")).unwrap();
    let (head, rest) = text.split_once("    lights: [").unwrap();
    let (lights, tail) = rest.split_once("\n    ],").unwrap();
    // the lights' lines: a rectangle over several lines, then one line each
    let rect_end = lights.find("        ),").unwrap() + "        ),".len();
    let alone = [
        &lights[..rect_end],
        lights[rect_end..].lines().nth(1).unwrap(),
        lights[rect_end..].lines().nth(2).unwrap(),
    ];
    let combined = read_pfm(&dir.join("v.pfm"));
    assert!(combined.color, "three lights: one channel each");
    let png = |name: &str| image::open(dir.join(name)).unwrap().to_rgb8();
    let mean_png = png("v.png");
    let mut sum = vec![0.0f64; mean_png.as_raw().len()];
    let mut one_peak = None;
    for (i, light) in alone.iter().enumerate() {
        let file = format!("l{i}.ron");
        std::fs::write(dir.join(&file), format!("{head}    lights: [\n{light}\n    ],{tail}")).unwrap();
        let o = render(&p(&file), &format!("l{i}.pfm"), &format!("l{i}.png"), &["--generic"]);
        one_peak.get_or_insert(number_after("| peak (all textures resident) |", &o));
        let single = read_pfm(&dir.join(format!("l{i}.pfm")));
        assert!(!single.color);
        let channel: Vec<f32> = combined.data.chunks_exact(3).map(|c| c[i]).collect();
        assert_eq!(channel, single.data, "light {i}: channel {i} is that light alone, bit for bit");
        for (s, v) in sum.iter_mut().zip(png(&format!("l{i}.png")).as_raw()) {
            *s += *v as f64;
        }
    }
    let worst = sum
        .iter()
        .zip(mean_png.as_raw())
        .map(|(s, v)| (s / 3.0 - *v as f64).abs())
        .fold(0.0, f64::max);
    assert!(worst <= 1.0, "the image is the lights' mean within one 8-bit code: {worst} codes");
    // three lights: one light's textures (PCF's are all shadow-map sized, and the lights
    // share them: issue 49) and the combining step's: per pixel, each light's visibility
    // (4 bytes) and colour (4 bytes), then the combined colour (4) and visibilities (16)
    let peak = number_after("| peak (all textures resident) |", &out);
    assert_eq!(peak, one_peak.unwrap() + (24.0 * 24.0) * (3.0 * 8.0 + 20.0), "{out}");
    // the first two lights: two channels written, the third 0
    let two = render("scenes/three-lights.ron", "v2.pfm", "v2.png", &["--lights", "2"]);
    assert!(two.contains("| 1 | Sphere |") && !two.contains("| 2 |"), "{two}");
    let v2 = read_pfm(&dir.join("v2.pfm"));
    assert!(v2.data.chunks_exact(3).all(|c| c[2] == 0.0));
    let e = refused(
        &[
            "render",
            "techniques/pcf.ron",
            "--scene",
            "scenes/three-lights.ron",
            "--lights",
            "4",
            "-o",
            &p("x.png"),
        ],
        60,
    );
    assert!(
        e.contains("`--lights 4`: scenes/three-lights.ron has 3 light(s); keep between 1 and 3"),
        "{e}"
    );
    // four lights render; their visibility does not fit a PFM's three channels; five are
    // more than one frame combines
    let sphere = alone[1];
    let four = format!("{head}    lights: [\n{lights}\n{sphere}\n    ],{tail}");
    std::fs::write(dir.join("four.ron"), four).unwrap();
    let o = ok(&[
        &["render", "techniques/pcf.ron", "--scene", &p("four.ron"), "-o", &p("4.png")][..],
        &small[..],
    ]
    .concat());
    assert!(o.contains("| 3 | Sphere |"), "{o}");
    let e = refused(
        &[
            &[
                "render",
                "techniques/pcf.ron",
                "--scene",
                &p("four.ron"),
                "--visibility",
                &p("4.pfm"),
                "-o",
                &p("4.png"),
            ][..],
            &small[..],
        ]
        .concat(),
        60,
    );
    assert!(
        e.contains("a PFM holds one channel per light, at most 3") && e.contains("has 4 lights"),
        "{e}"
    );
    // five lights render (their visibilities in two RGBA layers); seventeen are more than
    // one frame combines, refused where the scene file is read
    std::fs::write(
        dir.join("five.ron"),
        format!("{head}    lights: [\n{lights}\n{sphere}\n{sphere}\n    ],{tail}"),
    )
    .unwrap();
    let o = ok(&[
        &["render", "techniques/pcf.ron", "--scene", &p("five.ron"), "-o", &p("5.png")][..],
        &small[..],
    ]
    .concat());
    assert!(o.contains("| 4 | Sphere |"), "{o}");
    let many = vec![sphere; 17 - 3].join("\n");
    std::fs::write(
        dir.join("seventeen.ron"),
        format!("{head}    lights: [\n{lights}\n{many}\n    ],{tail}"),
    )
    .unwrap();
    let e = refused(
        &[
            &["render", "techniques/pcf.ron", "--scene", &p("seventeen.ron"), "-o", &p("17.png")][..],
            &small[..],
        ]
        .concat(),
        60,
    );
    assert!(e.contains("17 lights, above the runtime's limit of 16 a frame"), "{e}");
    let cmp = ok(&[
        &[
            "compare",
            "techniques/pcf.ron",
            "--scene",
            "scenes/three-lights.ron",
            "--stability-frames",
            "0",
            "-o",
            &p("c.png"),
        ][..],
        &small[..],
    ]
    .concat());
    for want in [
        "light 1 (Sphere): error facing the light: RMS",
        "light 2 (DistantDisk): error facing the light: RMS",
        "lights: 3",
    ] {
        assert!(cmp.contains(want), "{cmp}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// A precision left open (`Auto`) is chosen from the scene's depths: the scaled
/// ESM of compiler/tests/fixtures/esm-auto.ron stores its basis at F16 on the contact scene
/// (its casters start at normalised depth 0.28) and at F32 for any scene. The two builds'
/// visibilities differ by the F16 storage only: Vulkan lets a conversion to a 16-bit float
/// round to nearest or towards zero, one F16 ulp or 2^-10 of the value, and the product
/// with exp(-c (d - 1)) adds one f32 rounding (2^-23; clamping to [0, 1] only brings the two
/// nearer). A graph compiled for contact is refused on a scene whose casters come nearer
/// the light.
#[test]
fn a_precision_chosen_from_the_scene_renders_within_its_rounding_and_is_checked() {
    let dir = temp_dir("auto-precision");
    let p = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let technique = "compiler/tests/fixtures/esm-auto.ron";
    let text = ok(&["explain", technique, "--scene", "scenes/contact.ron"]);
    assert!(text.contains("channel `e` (Auto): F16"), "{text}");
    let small = ["--size", "48x48", "--shadow-map", "128"];
    let render = |vis: &str, extra: &[&str]| {
        ok(&[
            &[
                "render",
                technique,
                "--scene",
                "scenes/contact.ron",
                "--visibility",
                &p(vis),
                "-o",
                &p("r.png"),
            ][..],
            &small[..],
            extra,
        ]
        .concat())
    };
    render("f16.pfm", &[]);
    render("f32.pfm", &["--generic"]);
    let (a, b) = (read_pfm(&dir.join("f16.pfm")).data, read_pfm(&dir.join("f32.pfm")).data);
    let mut differ = 0;
    for (x, y) in a.iter().zip(&b) {
        let bound = x.max(*y) as f64 * (2f64.powi(-10) + 2f64.powi(-23));
        assert!(((x - y).abs() as f64) <= bound, "{x} against {y}: more than {bound}");
        differ += (x != y) as usize;
    }
    assert!(differ > 0, "the F16 storage shows somewhere");
    // the graph assumes contact's depths; a box near the light breaks them
    let graph_dir = p("graph");
    ok(&["compile", technique, "--scene", "scenes/contact.ron", "-o", &graph_dir]);
    let contact = std::fs::read_to_string(root().join("scenes/contact.ron")).unwrap();
    let nearer = contact.replace(
        "    objects: [\n",
        "    objects: [\n        Object(name: \"near the light\", mesh: Box(size: (0.1, 0.1, 0.1)), transform: (translate: (-0.7, 2.7, 1.3))),\n",
    );
    assert_ne!(nearer, contact);
    std::fs::write(dir.join("nearer.ron"), nearer).unwrap();
    let graph = dir.join("graph/esm_auto.graph.ron").to_string_lossy().into_owned();
    let e = refused(
        &[&["render", &graph, "--scene", &p("nearer.ron"), "-o", &p("n.png")][..], &small[..]].concat(),
        60,
    );
    assert!(
        e.contains("was specialised for scene scenes/contact.ron, whose casters lie at normalised depth 0.27")
            && e.contains("but this scene's come to"),
        "{e}"
    );
    ok(&[
        &["render", &graph, "--scene", "scenes/contact.ron", "-o", &p("c.png")][..],
        &small[..],
    ]
    .concat());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `sshc compile` warns where storage rounding can move the visibility by more than 0.05
/// (VSM's moments at Unorm8), not at the technique's own F32; `sshc explain`
/// prints the estimate per channel and precision.
#[test]
fn compile_warns_about_rounding_and_explain_prints_the_estimate() {
    let dir = temp_dir("rounding");
    let out = dir.to_string_lossy().into_owned();
    let r = sshc(&["compile", "techniques/vsm.ron", "--precision", "m1,m2=unorm8", "-o", &out]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{stderr}");
    assert!(
        stderr.contains("storage rounding can move the visibility by up to 1.758") && stderr.contains("techniques/vsm.ron:24:34"),
        "{stderr}"
    );
    let r = sshc(&["compile", "techniques/vsm.ron", "-o", &out]);
    assert!(!String::from_utf8_lossy(&r.stderr).contains("storage rounding"));
    let text = ok(&["explain", "techniques/vsm.ron"]);
    assert!(
        text.contains("| m1 | F32 | 7.838e-6 | 8.965e-1 | 1.070e-3 | 6.796e-1 | 7.838e-6 |"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The small inputs the verify tests run on (the command's defaults, 32^2 and eight
/// inputs, are what docs/verify.md records): a 16^2 map, an edge, noise and a scene.
const VERIFY_SMALL: [&str; 6] = ["--shadow-map", "16", "--fields", "step,noise", "--depth-of", "scenes/bunny.ron"];

/// `sshc verify` agrees on every bundled technique and on the authoring examples: those
/// without Geometry passes on depth fields and a scene's depth map (per-sample views see
/// them translated), those with Geometry passes on casters above the plane (their Depth
/// and Geometry outputs read back), each named in the output.
#[test]
fn verify_agrees_on_every_bundled_technique() {
    // every file in techniques/ and techniques/examples/, found, not listed: those with a
    // Geometry pass verified on casters, the others on depth fields and a scene's depth map
    let all = common::bundled_techniques();
    let (geometry, depth_only): (Vec<String>, Vec<String>) = all.iter().cloned().partition(|t| common::has_geometry_pass(t));
    // guards against a folder read as empty, or a Geometry pass no longer seen
    assert!(depth_only.len() >= 18 && geometry.len() >= 5, "{depth_only:?} {geometry:?}");
    for t in depth_only.iter().chain(&geometry) {
        let t = t.as_str();
        let path = format!("techniques/{t}.ron");
        let mut args = vec!["verify", path.as_str()];
        if geometry.iter().any(|g| g == t) {
            // a 16^2 map, one caster set and a scene's casters
            args.extend(["--shadow-map", "16", "--casters", "bars", "--depth-of", "scenes/bunny.ron"]);
        } else {
            args.extend(VERIFY_SMALL);
        }
        let out = ok(&args);
        let inputs = if geometry.iter().any(|g| g == t) { 2 } else { 3 };
        // each input under two cameras, each a row that agrees
        assert_eq!(out.matches("| agrees |").count(), 2 * inputs, "{t}:\n{out}");
        assert!(out.contains("verdict: agrees on every input"), "{t}:\n{out}");
    }
    // a depth field cannot stand in for what a Geometry pass rasterises
    let err = refused(&["verify", "techniques/smoothies.ron", "--fields", "step"], 60);
    assert!(
        err.contains("rasterises Geometry pass `smoothies` from meshes: give it casters"),
        "{err}"
    );
}

/// A precision that loses the signal is caught: ESM's exp(c z) at Unorm8 rounds every
/// texel of the ramp to the same few steps, and storage alone moves the visibility by
/// more than 0.05 at over 1 % of the receivers (LOSSY); VSM's moments at Unorm8 too.
#[test]
fn verify_calls_a_precision_that_loses_the_signal_lossy() {
    for (t, precision) in [
        ("esm", vec!["--precision", "e=unorm8"]),
        ("vsm", vec!["--precision", "m1=unorm8", "--precision", "m2=unorm8"]),
    ] {
        let path = format!("techniques/{t}.ron");
        let mut args = vec!["verify", path.as_str(), "--fields", "ramp", "--depth-of", "scenes/bunny.ron"];
        args.extend(precision);
        let out = sshc(&args);
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{t}: {stdout}");
        assert!(stdout.contains("| LOSSY |"), "{t}: {stdout}");
        assert!(
            !stdout.contains("| DIFFERS |"),
            "{t}: the GPU still agrees with the model: {stdout}"
        );
        assert!(stderr.contains("LOSSY"), "{t}: {stderr}");
    }
    // `--images`: one picture per input and camera, three panels of the camera's pixels
    // scaled to at least 128 screen pixels, and red where the GPU leaves its interval
    let dir = temp_dir("verify-images");
    let images = dir.to_string_lossy().into_owned();
    ok(&[
        "verify",
        "techniques/hard.ron",
        "--fields",
        "step",
        "--depth-of",
        "scenes/bunny.ron",
        "--images",
        images.as_str(),
    ]);
    for (input, camera) in [("step", 64u32), ("step", 16), ("bunny", 64), ("bunny", 16)] {
        let path = dir.join(format!("{input}-{camera}.png"));
        let img = image::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8();
        let scale = 128u32.div_ceil(camera);
        assert_eq!(
            img.dimensions(),
            (3 * camera * scale + 2 * scale, camera * scale),
            "{}",
            path.display()
        );
        assert!(
            !img.pixels().any(|p| p.0 == [230, 20, 20]),
            "{}: a receiver outside",
            path.display()
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A reference technique checks the math: MSM by Cholesky against MSM by Cramer's rule
/// agrees; the same reference with one sign of the bound's numerator flipped does not.
#[test]
fn verify_checks_a_technique_against_an_independent_reference() {
    let mut args = vec![
        "verify",
        "techniques/msm.ron",
        "--reference",
        "techniques/examples/msm-reference.ron",
    ];
    args.extend(VERIFY_SMALL);
    let out = ok(&args);
    // the column "reference outside" of every row: no receiver outside
    let header: Vec<&str> = out
        .lines()
        .find(|l| l.starts_with("| input"))
        .expect("a table")
        .split('|')
        .collect();
    let column = header
        .iter()
        .position(|c| c.trim() == "reference outside")
        .expect("the reference's column");
    let rows: Vec<&str> = out.lines().filter(|l| l.ends_with("| agrees |")).collect();
    assert_eq!(rows.len(), 6, "{out}");
    for row in rows {
        assert_eq!(row.split('|').nth(column).map(str::trim), Some("0"), "{row}");
    }
    let good = std::fs::read_to_string(root().join("techniques/examples/msm-reference.ron")).unwrap();
    let wrong = good.replacen("zf * z3 - b.x * (zf + z3) + b.y", "zf * z3 + b.x * (zf + z3) + b.y", 1);
    assert_ne!(good, wrong, "the mutation applies");
    let dir = temp_dir("verify-reference");
    let path = dir.join("wrong.ron");
    std::fs::write(&path, wrong).unwrap();
    let path = path.to_string_lossy().into_owned();
    let mut args = vec!["verify", "techniques/msm.ron", "--reference", path.as_str()];
    args.extend(VERIFY_SMALL);
    let out = sshc(&args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(!out.status.success(), "{stdout}");
    assert!(stdout.contains("| DIFFERS |"), "{stdout}");
}

/// Bad `verify` arguments are refused at once with the reason, before any GPU work.
#[test]
fn verify_refuses_bad_arguments_with_reasons() {
    for (args, why) in [
        (vec!["--shadow-map", "12"], "must be a power of two in 4..=1024"),
        (vec!["--shadow-map", "0"], "must be a power of two in 4..=1024"),
        (vec!["--light-width=-1"], "must lie in [0, 2]"),
        (vec!["--light-width", "NaN"], "must lie in [0, 2]"),
        (vec!["--reference-tolerance=-1"], "must be finite and not negative"),
        (vec!["--fields", "ramp,bogus"], "no depth field `bogus` (there are: ramp, step"),
        (vec!["--depth-of", "/nonexistent.ron"], "cannot read the scene"),
        (vec!["--casters", "box,bogus"], "no caster set `bogus` (there are: box, bars)"),
        (
            vec!["--reference", "techniques/smoothies.ron"],
            "the reference `smoothies` has a Geometry pass (`smoothies`)",
        ),
    ] {
        let mut all = vec!["verify", "techniques/hard.ron"];
        all.extend(args.iter().copied());
        let err = refused(&all, 60);
        assert!(err.contains(why), "{args:?}: {err}");
    }
    let err = refused(&["verify", "lab/tests/data/does-not-exist.ron"], 10);
    assert!(err.contains("does-not-exist.ron"), "{err}");
}

/// `sshc check` reports every diagnostic `sshc compile` would (it runs every phase and
/// writes nothing): the same standard error and the same exit status, on every error
/// fixture (front-end, lowering, analysis, packing and codegen refusals alike) and on every
/// bundled technique, also under precision overrides that warn or refuse. Its `ok` line
/// counts the warnings.
#[test]
fn check_says_everything_compile_says() {
    let mut cases: Vec<Vec<String>> = Vec::new();
    for dir in ["compiler/tests/errors", "techniques"] {
        let mut files: Vec<_> = std::fs::read_dir(root().join(dir))
            .unwrap()
            .filter_map(|e| e.ok())
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == "ron"))
            .collect();
        files.sort();
        cases.extend(
            files
                .iter()
                .map(|p| vec![format!("{dir}/{}", p.file_name().unwrap().to_string_lossy())]),
        );
    }
    for extra in [
        // rounding that moves the visibility (a warning), a precision the range refuses
        // (analyse), a summed-area table of floats (pack)
        "techniques/vsm.ron --precision m1=Unorm8 --precision m2=Unorm8",
        "techniques/esm.ron --precision e=F16",
        "techniques/cssm.ron --precision zhs=F32",
    ] {
        cases.push(extra.split(' ').map(str::to_string).collect());
    }
    let out = temp_dir("check-and-compile");
    let results: Vec<(Vec<String>, Output, Output)> = std::thread::scope(|scope| {
        let chunks: Vec<_> = cases.chunks(cases.len().div_ceil(2)).collect();
        let handles: Vec<_> = chunks
            .into_iter()
            .enumerate()
            .map(|(k, chunk)| {
                let out = out.join(k.to_string());
                scope.spawn(move || {
                    chunk
                        .iter()
                        .map(|args| {
                            let a: Vec<&str> = args.iter().map(String::as_str).collect();
                            let check = sshc(&[&["check"], &a[..]].concat());
                            let compile = sshc(&[&["compile"], &a[..], &["-o", out.to_str().unwrap()]].concat());
                            (args.clone(), check, compile)
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    let (mut refused, mut warned) = (0, 0);
    for (args, check, compile) in &results {
        let (e1, e2) = (String::from_utf8_lossy(&check.stderr), String::from_utf8_lossy(&compile.stderr));
        assert_eq!(e1, e2, "{args:?}: check and compile report differently");
        assert_eq!(check.status.success(), compile.status.success(), "{args:?}");
        let warnings = e1.matches("\nwarning[").count() + usize::from(e1.starts_with("warning["));
        if check.status.success() {
            let stdout = String::from_utf8_lossy(&check.stdout);
            let said = match warnings {
                0 => ": ok\n".to_string(),
                1 => ": ok (1 warning)\n".to_string(),
                n => format!(": ok ({n} warnings)\n"),
            };
            assert!(stdout.ends_with(&said), "{args:?}: {stdout}");
            warned += usize::from(warnings > 0);
        } else {
            refused += 1;
            assert!(e1.contains("error["), "{args:?}: {e1}");
        }
    }
    // the fixtures refuse; what check missed before is among them (the phases after check)
    assert!(refused >= 60 && warned >= 2, "{refused} refused, {warned} warned");
    for phase in ["error[pack]", "error[analyse]", "error[lower]"] {
        assert!(
            results.iter().any(|(_, c, _)| String::from_utf8_lossy(&c.stderr).contains(phase)),
            "no case shows `check` reporting {phase}"
        );
    }
}

/// `compare --cascades 2` binds the cascades, states them, and keeps them through the
/// temporal run (each moved light's frame bound with its cascades), and `render` refuses
/// cascades of a light at a finite position, saying why.
#[test]
fn compare_with_cascades_states_them_and_keeps_them_while_the_light_moves() {
    let dir = std::env::temp_dir().join(format!("sshc-cli-cascades-{}", std::process::id()));
    let out = ok(&[
        "compare",
        "techniques/pcss.ron",
        "--scene",
        "scenes/triangle.ron",
        "--cascades",
        "2",
        "--size",
        "32x32",
        "--samples",
        "16",
        "--runs",
        "2",
        "--stability-frames",
        "3",
        "--cache",
        &dir.join("cache").to_string_lossy(),
        "-o",
        &dir.join("c.png").to_string_lossy(),
    ]);
    assert!(out.contains("cascades: 2 of 512 texels"), "{out}");
    assert!(out.contains("temporal: mean |change|") && out.contains("3 frames"), "{out}");
    let o = sshc(&[
        "render",
        "techniques/pcss.ron",
        "--scene",
        "scenes/bunny.ron",
        "--cascades",
        "2",
        "-o",
        &dir.join("r.png").to_string_lossy(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("a light at infinity") && err.contains("Rectangle"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `sshc render --dump` compiles the Shade's debug outputs in and writes each as PFM (the
/// f32 values) and PNG (viridis over the printed [min, max]): a technique's `pixel` (its
/// closed form: column x, row y from the top, at every pixel that sees a surface; NaN, as
/// the positions, where none is seen) and the receiver's depth `d` (in [0, 1] wherever
/// the visibility is defined). Without `--dump` nothing is compiled in.
#[test]
fn render_dump_writes_debug_outputs_as_pfm_and_png() {
    let dir = temp_dir("debug-dump");
    let technique = dir.join("probe.ron");
    std::fs::write(
        &technique,
        r#"Technique(name: "probe", params: { "bias": Param(ty: F32, default: 0.002) },
            channels: { "z": Channel(precision: F32) },
            passes: [
                Depth(name: "depth", writes: "shadow", channel: "z"),
                Shade(name: "shade", reads: ["shadow"], visibility: "select(0.0, 1.0, d - bias <= sample(z))",
                      debug: { "px": "pixel", "depth": "d" }),
            ])"#,
    )
    .unwrap();
    let (t, dump, pos) = (technique.to_str().unwrap(), dir.join("dump"), dir.join("pos.pfm"));
    let png = dir.join("r.png");
    let base = [
        "render",
        t,
        "--scene",
        "scenes/contact.ron",
        "--size",
        "48x32",
        "--shadow-map",
        "64",
        "-o",
        png.to_str().unwrap(),
    ];
    let plain = ok(&base);
    assert!(!plain.contains("debug_"), "no debug output without --dump:\n{plain}");
    let out = ok(&[&base[..], &["--dump", dump.to_str().unwrap(), "--positions", pos.to_str().unwrap()]].concat());
    let positions = read_pfm(&pos);
    let seen: Vec<bool> = positions.data.chunks(3).map(|p| p.iter().all(|c| c.is_finite())).collect();
    assert_eq!(seen.len(), 48 * 32);
    assert!(
        seen.iter().filter(|s| **s).count() > 48 * 32 / 2,
        "the contact scene fills most of the view"
    );
    for (stem, closed) in [
        ("debug_px.x", (|x: usize, _y: usize| x as f32) as fn(usize, usize) -> f32),
        ("debug_px.y", |_x, y| y as f32),
    ] {
        let img = read_pfm(&dump.join(format!("{stem}.pfm")));
        assert_eq!((img.width, img.height, img.color), (48, 32, false), "{stem}");
        for y in 0..32 {
            for x in 0..48 {
                let v = img.data[y * 48 + x];
                if seen[y * 48 + x] {
                    assert_eq!(v, closed(x, y), "{stem} at ({x}, {y})");
                } else {
                    assert!(v.is_nan(), "{stem} at ({x}, {y}): {v} where no surface is seen");
                }
            }
        }
        // the printed range is the values' and the PNG maps it through viridis
        let finite: Vec<f32> = img.data.iter().copied().filter(|v| v.is_finite()).collect();
        let (lo, hi) = (
            finite.iter().copied().fold(f32::MAX, f32::min),
            finite.iter().copied().fold(f32::MIN, f32::max),
        );
        assert!(
            out.contains(&format!("debug output {stem}: [{lo:e}, {hi:e}]")),
            "{stem}: [{lo}, {hi}] in\n{out}"
        );
        let picture = image::open(dump.join(format!("{stem}.png"))).unwrap().to_rgb8();
        let at = img.data.iter().position(|v| *v == hi).unwrap();
        let top = colorous::VIRIDIS.eval_continuous(1.0);
        assert_eq!(
            picture.get_pixel((at % 48) as u32, (at / 48) as u32).0,
            [top.r, top.g, top.b],
            "{stem}"
        );
    }
    let depth = read_pfm(&dump.join("debug_depth.pfm"));
    let depths: Vec<f32> = depth.data.iter().copied().filter(|v| v.is_finite()).collect();
    assert_eq!(depths.len(), seen.iter().filter(|s| **s).count());
    // the camera sees what the light's fitted depth range holds
    assert!(
        depths.iter().all(|d| (0.0..=1.0).contains(d)),
        "{:?}",
        depths.iter().fold((f32::MAX, f32::MIN), |a, d| (a.0.min(*d), a.1.max(*d)))
    );
    assert!(dump.join("debug_depth.png").is_file() && dump.join("visibility.pfm").is_file());
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

/// Issue 48, item 6: a visibility expression that is NaN, or infinite, at the receivers
/// facing the light is reported and the image refused; lavapipe folded the Shade's
/// `raw != raw` test away and drew NaN as 0 (shadowed) with exit 0. The hard shadow of the
/// same scene renders.
#[test]
fn a_visibility_that_is_not_a_number_is_reported_not_drawn_as_shadow() {
    let dir = temp_dir("nan");
    let png = dir.join("r.png");
    for (name, visibility, want) in [
        ("nan", "sqrt(-1.0 - d)", "not a finite number (NaN or infinite)"),
        ("inf", "1.0 / (d - d)", "not a finite number (NaN or infinite)"),
        ("finite", "select(0.0, 1.0, d - 0.001 <= nearest(z))", ""),
    ] {
        let t = dir.join(format!("{name}.ron"));
        std::fs::write(
            &t,
            format!(
                r#"Technique(name: "{name}", channels: {{ "z": Channel(precision: F32) }},
    passes: [Depth(name: "depth", writes: "shadow", channel: "z"),
        Shade(name: "shade", reads: ["shadow"], visibility: "{visibility}")])"#
            ),
        )
        .unwrap();
        let args = [
            "render",
            t.to_str().unwrap(),
            "--scene",
            "scenes/contact.ron",
            "--size",
            "16x16",
            "-o",
            png.to_str().unwrap(),
        ];
        let out = sshc(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        if want.is_empty() {
            assert!(out.status.success(), "{name}: {stderr}");
        } else {
            assert!(
                !out.status.success() && stderr.contains(want) && stderr.contains("at pixel ("),
                "{name}: {stderr}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// Issue 48, item 16: `--camera` takes the scene file's own syntax (`near: 0.01`, an
/// implicit `Some`, was refused); a `--light` inside the geometry is warned about as the
/// scene file's lights are (it was not); `sshc scene city` refuses a count it would write
/// a file the loader refuses for (the last tower carried 2^24 past the limit) and a count
/// of 0, writing nothing.
#[test]
fn camera_and_light_overrides_and_the_city_generator_are_checked_as_scene_files_are() {
    let dir = temp_dir("overrides");
    let png = dir.join("r.png");
    let png = png.to_str().unwrap();
    let base = [
        "render",
        "techniques/pcf.ron",
        "--scene",
        "scenes/contact.ron",
        "--size",
        "16x16",
        "-o",
        png,
    ];
    let camera = "Perspective(position: (0.3, 2.4, 3.6), target: (0.1, 0.3, -0.4), fov_y_degrees: 45.0, width: 16, height: 16, near: 0.01)";
    let mut args = base.to_vec();
    args.extend(["--camera", camera]);
    ok(&args);
    // a sphere light inside the resting box
    let mut args = base.to_vec();
    args.extend(["--light", "Sphere(center: (-0.8, 0.4, 0.0), radius: 0.1)"]);
    let out = sshc(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("warning: --light: lights[0]") && stderr.contains("objects[1] (\"resting\")"),
        "{stderr}"
    );
    for (n, want) in [
        ("0", "`--triangles 0`: a city has a ground and at least one tower"),
        ("16777216", "`--triangles 16777216`: the city drawn would be refused"),
    ] {
        let glb = dir.join(format!("city-{n}.glb"));
        let out = sshc(&["scene", "city", "--triangles", n, "-o", glb.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && stderr.contains(want), "{n}: {stderr}");
        assert!(!glb.exists(), "{n}: a file was written");
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// Issue 48, item 15: no command writes through a link planted where its output goes.
/// Each output of each command gets a link to a file outside the output folder; the
/// command refuses, naming the link, and the file outside is as it was.
#[test]
fn no_command_writes_through_a_link_planted_at_its_output() {
    let dir = temp_dir("links");
    let outside = dir.join("outside.txt");
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let p = |name: &str| out.join(name).to_str().unwrap().to_string();
    let scene = ["--scene", "scenes/contact.ron", "--size", "8x8"];
    let truth = ["--samples", "4", "--runs", "2", "--no-cache"];
    // (the command, the output it plants a link at)
    let runs: Vec<(Vec<String>, String)> = vec![
        (
            ["render", "techniques/hard.ron"]
                .iter()
                .chain(&scene)
                .map(|s| s.to_string())
                .chain(["-o".into(), p("r.png")])
                .collect(),
            p("r.png"),
        ),
        (
            ["render", "techniques/hard.ron"]
                .iter()
                .chain(&scene)
                .map(|s| s.to_string())
                .chain(["-o".into(), p("r2.png"), "--visibility".into(), p("v.pfm")])
                .collect(),
            p("v.pfm"),
        ),
        (
            ["render", "techniques/vsm.ron"]
                .iter()
                .chain(&scene)
                .map(|s| s.to_string())
                .chain(["-o".into(), p("r3.png"), "--dump".into(), p("dump")])
                .collect(),
            p("dump/visibility.pfm"),
        ),
        (
            ["truth"]
                .iter()
                .chain(&scene)
                .chain(&truth)
                .map(|s| s.to_string())
                .chain(["-o".into(), p("t.pfm")])
                .collect(),
            p("t.png"),
        ),
        (
            ["compare", "techniques/hard.ron"]
                .iter()
                .chain(&scene)
                .chain(&truth)
                .map(|s| s.to_string())
                .chain(["-o".into(), p("c.png")])
                .collect(),
            p("c.png"),
        ),
        (
            ["compile", "techniques/hard.ron", "-o", &p("compiled")]
                .iter()
                .map(|s| s.to_string())
                .collect(),
            p("compiled/hard.graph.ron"),
        ),
        (
            ["scene", "city", "--triangles", "100", "-o", &p("city.glb")]
                .iter()
                .map(|s| s.to_string())
                .collect(),
            p("city.glb"),
        ),
    ];
    for (args, link) in runs {
        std::fs::write(&outside, "kept").unwrap();
        let link = Path::new(&link);
        std::fs::create_dir_all(link.parent().unwrap()).unwrap();
        let _ = std::fs::remove_file(link);
        std::os::unix::fs::symlink(&outside, link).unwrap();
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = sshc(&refs);
        let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
        assert!(
            !o.status.success() && text.contains("is not a regular file"),
            "sshc {}: {text}",
            args.join(" ")
        );
        assert_eq!(
            std::fs::read_to_string(&outside).unwrap(),
            "kept",
            "sshc {} wrote through the link",
            args.join(" ")
        );
        std::fs::remove_file(link).unwrap();
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// Issue 48, item 14: a scene of 12 M triangles under a 4 GB address-space cap
/// (`ulimit -v`) was read until an allocation failed (the BVH builder panicked at 2^24);
/// it is refused before its triangles are decoded, with the memory it needs and what
/// bounds what is available.
#[test]
fn a_scene_larger_than_the_memory_available_is_refused_before_it_is_built() {
    let dir = temp_dir("memory");
    std::fs::write(dir.join("big.glb"), sshc_lab::scene::generate::city_glb(12_000_000, 1)).unwrap();
    std::fs::write(
        dir.join("big.ron"),
        r#"Scene(camera: Perspective(position: (-6.0, 5.0, 15.0), target: (1.0, 0.0, 2.0), fov_y_degrees: 50.0, width: 8, height: 8),
                 shadow_map: 64, lights: [DistantDisk(direction: (0.77, 0.342, 0.54), angle_degrees: 0.53)],
                 objects: [Object(mesh: Gltf(path: "big.glb"))])"#,
    )
    .unwrap();
    let script = format!(
        "ulimit -v 4000000 && exec '{}' render techniques/hard.ron --scene '{}' -o '{}'",
        env!("CARGO_BIN_EXE_sshc"),
        dir.join("big.ron").display(),
        dir.join("big.png").display()
    );
    let start = std::time::Instant::now();
    let o = Command::new("bash")
        .args(["-c", &script])
        .current_dir(root())
        .env("LP_NUM_THREADS", "2")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    assert!(
        stderr.contains("triangles need about")
            && stderr.contains("the address-space limit (ulimit -v) leaves")
            && !stderr.contains("panicked"),
        "{stderr}"
    );
    assert!(start.elapsed().as_secs() < 30, "took {:?}", start.elapsed());
    let _ = std::fs::remove_dir_all(dir);
}

/// Issue 48, item 17: messages that named the wrong thing. A bad `--camera` read
/// "error: --camera: <scene>: error: ..."; `--cascade-offset 1e30,0,0` was "light 0: a
/// matrix ... is not finite"; a glTF corner at 3e38 was blamed on the camera, a `yfov` in
/// radians reported as `fov_y_degrees`; a glTF in a subfolder naming `../sub2.bin`, inside
/// the scene's folder, was "leaving the folder"; a cache folder that cannot be written
/// ended the run with a bare OS error, the computed truth lost.
#[test]
fn messages_name_the_option_the_file_and_the_unit_at_fault() {
    let dir = temp_dir("messages");
    let png = dir.join("r.png");
    let png = png.to_str().unwrap();
    let fails = |args: &[&str]| -> String {
        let o = sshc(args);
        let e = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!o.status.success(), "sshc {} succeeded: {e}", args.join(" "));
        e
    };
    let e = fails(&[
        "render",
        "techniques/hard.ron",
        "--scene",
        "scenes/contact.ron",
        "--size",
        "8x8",
        "-o",
        png,
        "--camera",
        "Perspective(position: (0.0, 2.0, 4.0), target: (0.0, 2.0, 4.0), fov_y_degrees: 40.0, width: 8, height: 8)",
    ]);
    assert!(
        e.contains("error: --camera: the camera looks at its own position") && !e.contains("<scene>"),
        "{e}"
    );
    assert_eq!(e.matches("error:").count(), 1, "{e}");
    let e = fails(&[
        "render",
        "techniques/csm.ron",
        "--scene",
        "scenes/triangle.ron",
        "--size",
        "8x8",
        "-o",
        png,
        "--cascades",
        "2",
        "--cascade-offset",
        "1e30,0,0",
    ]);
    assert!(
        e.contains("`--cascade-offset 1e30,0,0`: moves the camera the cascades are fitted to"),
        "{e}"
    );
    // glTF files: a triangle with a corner at `corner`, a camera of `yfov` radians
    let gltf = |name: &str, corner: f32, yfov: f32, uri: &str| {
        let floats: Vec<f32> = vec![corner, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0];
        let mut bin: Vec<u8> = floats.iter().flat_map(|x| x.to_le_bytes()).collect();
        bin.extend([0u32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
        let doc = format!(
            r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0, 1]}}], "nodes": [{{"mesh": 0}}, {{"camera": 0, "translation": [0, 0, 5]}}],
               "cameras": [{{"type": "perspective", "perspective": {{"yfov": {yfov}, "znear": 0.1}}}}],
               "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
               "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [{corner}, 1, 1]}},
                             {{"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}}],
               "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 12}}],
               "buffers": [{{"byteLength": 48, "uri": "{uri}"}}]}}"#
        );
        let path = dir.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, doc).unwrap();
        (path, bin)
    };
    let render = |scene: &Path| -> std::process::Output {
        sshc(&[
            "render",
            "techniques/hard.ron",
            "--scene",
            scene.to_str().unwrap(),
            "--size",
            "8x8",
            "-o",
            png,
        ])
    };
    let (huge, bin) = gltf("huge.gltf", 3e38, 0.8, "huge.bin");
    std::fs::write(dir.join("huge.bin"), &bin).unwrap();
    let e = String::from_utf8_lossy(&render(&huge).stderr).into_owned();
    assert!(
        e.contains("the placed triangles span from") && e.contains("overflow f32") && !e.contains("camera (Perspective)"),
        "{e}"
    );
    let (wide, bin) = gltf("wide.gltf", 1.0, 3.5, "wide.bin");
    std::fs::write(dir.join("wide.bin"), &bin).unwrap();
    let e = String::from_utf8_lossy(&render(&wide).stderr).into_owned();
    assert!(e.contains("camera 0's yfov is 3.5 radians (200.5 degrees), outside (0, pi)"), "{e}");
    // a scene file beside `sub2.bin`, naming `sub/x.gltf`, whose buffer is `../sub2.bin`
    let (_, bin) = gltf("sub/x.gltf", 1.0, 0.8, "../sub2.bin");
    std::fs::write(dir.join("sub2.bin"), &bin).unwrap();
    std::fs::write(
        dir.join("s.ron"),
        r#"Scene(camera: Perspective(position: (0.5, 2.0, 3.0), target: (0.3, 0.3, 0.3), fov_y_degrees: 40.0, width: 8, height: 8),
                 shadow_map: 64, lights: [Point(position: (0.0, 3.0, 1.0))], objects: [Object(mesh: Gltf(path: "sub/x.gltf"))])"#,
    )
    .unwrap();
    let o = render(&dir.join("s.ron"));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // four `--light`s on a scene file of one: the count is theirs, not the file's
    let l = "Sphere(center: (0.0, 3.0, 0.0), radius: 0.3)";
    let e = fails(&[
        "render",
        "techniques/pcf.ron",
        "--scene",
        "scenes/contact.ron",
        "--size",
        "8x8",
        "-o",
        png,
        "--light",
        l,
        "--light",
        l,
        "--light",
        l,
        "--light",
        l,
        "--lights",
        "5",
    ]);
    assert!(
        e.contains("`--lights 5`: scenes/contact.ron with its 4 `--light`(s) has 4 light(s)"),
        "{e}"
    );
    // a cache folder below a file: warned, and the truth computed and written
    std::fs::write(dir.join("a-file"), "").unwrap();
    let t = dir.join("t.pfm");
    let o = sshc(&[
        "truth",
        "--scene",
        "scenes/contact.ron",
        "--size",
        "8x8",
        "--samples",
        "4",
        "--runs",
        "2",
        "--cache",
        dir.join("a-file/cache").to_str().unwrap(),
        "-o",
        t.to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && e.contains("the truth cache cannot be written") && e.contains("--no-cache") && t.exists(),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// Issue 51: `render`, `compare` and `truth` create the folders of their outputs where
/// missing, and refuse at once (before any frame is rendered, naming the option) an output
/// whose folder cannot be made.
#[test]
fn outputs_in_missing_folders_are_created_or_refused_before_rendering() {
    let dir = temp_dir("folders");
    let render = dir.join("a/b/render.png");
    let vis = dir.join("c/vis.pfm");
    ok(&[
        "render",
        "techniques/hard.ron",
        "--scene",
        "scenes/triangle.ron",
        "--size",
        "8x8",
        "--shadow-map",
        "16",
        "-o",
        render.to_str().unwrap(),
        "--visibility",
        vis.to_str().unwrap(),
    ]);
    assert!(render.is_file() && vis.is_file());
    let truth = dir.join("d/e/truth.pfm");
    let se = dir.join("f/se.pfm");
    let fast_truth = ["--size", "8x8", "--samples", "4", "--runs", "2", "--no-cache"];
    let mut args = vec!["truth", "--scene", "scenes/edge.ron", "-o", truth.to_str().unwrap()];
    args.extend(["--std-error", se.to_str().unwrap()]);
    args.extend(fast_truth);
    ok(&args);
    assert!(truth.is_file() && dir.join("d/e/truth.png").is_file() && se.is_file());
    let compare = dir.join("g/h/compare.png");
    let mut args = vec!["compare", "techniques/hard.ron", "--scene", "scenes/edge.ron"];
    args.extend(["-o", compare.to_str().unwrap(), "--frames", "1", "--stability-frames", "0"]);
    args.extend(fast_truth);
    ok(&args);
    assert!(compare.is_file());

    // a file where a folder must be: refused before the GPU is touched
    let file = dir.join("file");
    std::fs::write(&file, "x").unwrap();
    let inside = file.join("sub/out.png");
    let inside = inside.to_str().unwrap();
    let inside_pfm = inside.replace(".png", ".pfm");
    for (command, args) in [
        (
            "render",
            vec!["render", "techniques/hard.ron", "--scene", "scenes/triangle.ron", "-o", inside],
        ),
        (
            "compare",
            vec!["compare", "techniques/hard.ron", "--scene", "scenes/edge.ron", "-o", inside],
        ),
        ("truth", vec!["truth", "--scene", "scenes/edge.ron", "-o", &inside_pfm]),
    ] {
        let out = sshc(&args);
        let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
        assert!(!out.status.success(), "{command}: {stdout}");
        assert!(
            stderr.contains("`-o ")
                && stderr.contains("cannot create the folder")
                && stderr.contains(&format!("`{}` is a file, not a folder", file.display())),
            "{command}: {stderr}"
        );
        // nothing rendered: the device was never asked for, no line printed
        assert!(stdout.is_empty(), "{command} worked before refusing:\n{stdout}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 51: `verify`'s default scene inputs (the bundled bunny and fence) come from the
/// repository, not the working folder: run from a folder holding a partial `scenes/` (a
/// bunny.ron without its mesh), it verifies both scenes.
#[test]
fn verify_finds_its_default_scenes_from_any_working_folder() {
    let dir = temp_dir("verify-cwd");
    std::fs::create_dir_all(dir.join("scenes")).unwrap();
    std::fs::copy(root().join("scenes/bunny.ron"), dir.join("scenes/bunny.ron")).unwrap();
    let technique = root().join("techniques/hard.ron");
    let out = command(&["verify", technique.to_str().unwrap(), "--fields", "ramp"])
        .current_dir(&dir)
        .output()
        .expect("sshc runs");
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{stdout}\n{stderr}");
    for input in ["| ramp", "| bunny", "| fence"] {
        assert!(stdout.contains(input), "`{input}` missing:\n{stdout}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 51: a GPU command run with XDG_RUNTIME_DIR unset prints no `XDG_RUNTIME_DIR`
/// line (the Vulkan loader's and Mesa's complaint) and still works.
#[test]
fn a_gpu_command_without_xdg_runtime_dir_prints_no_noise_about_it() {
    let dir = temp_dir("xdg");
    let png = dir.join("r.png");
    let out = command(&[
        "render",
        "techniques/hard.ron",
        "--scene",
        "scenes/triangle.ron",
        "--size",
        "8x8",
        "--shadow-map",
        "16",
        "-o",
        png.to_str().unwrap(),
    ])
    .env_remove("XDG_RUNTIME_DIR")
    .output()
    .expect("sshc runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(png.is_file());
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}
