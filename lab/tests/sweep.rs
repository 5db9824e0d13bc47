//! `sshc sweep` end to end on a sweep of under 20 configurations (tests/sweep.ron): the
//! CSV and Markdown hold one row per configuration with finite figures, the shards of a
//! split sweep together hold exactly the configurations of the whole, and the Pareto
//! charts are written as SVG and PNG. Shards merged by `sshc sweep merge` equal the
//! unsharded sweep, a shard stopped by a signal resumes, and every bad merge is refused
//! (docs/cluster.md). Runs on the GPU (lavapipe without one).

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::{assert_merged_equals, csv_rows as rows};

fn run(out: &Path, extra: &[&str]) -> String {
    run_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/sweep.ron"), out, extra)
}

fn run_file(sweep: &Path, out: &Path, extra: &[&str]) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .arg("sweep")
        .arg(sweep)
        .arg("-o")
        .arg(out)
        .args(["--samples", "16", "--runs", "2", "--cache"])
        .arg(out.join("cache"))
        .args(extra)
        .env("LP_NUM_THREADS", "2")
        .output()
        .expect("sshc runs");
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "sshc sweep failed:\n{text}");
    std::fs::read_to_string(out.join("sweep.csv")).expect("sweep.csv written")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sshc-sweep-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn sweep_writes_a_row_per_configuration_and_the_charts() {
    let out = tmp("whole");
    let csv = run(&out, &[]);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name}"));
    let rows = rows(&csv);
    // 2 + 2 + 2 GPU configurations and one CPU baseline
    assert_eq!(rows.len(), 7, "{csv}");
    let num = |r: &Vec<String>, c: &str| -> f64 {
        r[col(c)]
            .parse()
            .unwrap_or_else(|_| panic!("{c} = `{}` is not a number in {r:?}", r[col(c)]))
    };
    // Every row compares with the same truth over the same pixels: the camera pass of every
    // technique (and of the CPU baseline's reference) sees the same surfaces.
    let (facing, penumbra) = (num(&rows[0], "facing_pixels"), num(&rows[0], "penumbra_pixels"));
    assert!(facing > 0.0 && facing <= 40.0 * 40.0 && penumbra > 0.0, "{csv}");
    // the CSV prints errors with 3 decimals
    let printed = 0.0005;
    for r in &rows {
        assert_eq!(r.len(), header.len(), "{r:?}");
        assert_eq!((num(r, "facing_pixels"), num(r, "penumbra_pixels")), (facing, penumbra), "{r:?}");
        let (rms_f, max_f, rms_p, max_p) = (
            num(r, "rms_facing"),
            num(r, "max_facing"),
            num(r, "rms_penumbra"),
            num(r, "max_penumbra"),
        );
        // What the definitions imply, whatever the technique: an RMS never exceeds the
        // largest error it averages; the penumbra pixels are some of the facing pixels, so
        // their largest error and their sum of squared errors are at most the facing ones'.
        assert!(rms_f.is_finite() && rms_p.is_finite() && max_f.is_finite(), "{r:?}");
        assert!(
            rms_f <= max_f + 2.0 * printed && rms_p <= max_p + 2.0 * printed,
            "RMS above max: {r:?}"
        );
        assert!(max_p <= max_f + 2.0 * printed, "penumbra max above facing max: {r:?}");
        let sq = |rms: f64, n: f64| (rms + printed).powi(2) * n;
        assert!(
            (rms_p - printed).max(0.0).powi(2) * penumbra <= sq(rms_f, facing),
            "penumbra sum of squares above the facing one: {r:?}"
        );
        if r[col("technique")] == "16 samples (CPU)" {
            // Monte Carlo bound: the baseline is 16 stratified light samples, the truth 2
            // runs of 16; stratified sampling's variance is at most the binomial
            // f (1 - f) / n <= 1 / (4 n) per pixel. Whether or not the two are independent,
            // the root-mean-square difference per pixel is at most the sum of their
            // standard deviations, 1/8 + 1/sqrt(128) = 0.2134, or 54.4 in 0..255 units; one
            // sample per pixel (the wrong stratification) would give up to 0.5 + 0.088.
            // (Over a penumbra f (1 - f) averages nearer 1/6, for about 32 expected.)
            let bound = 255.0 * (0.125 + (1.0f64 / 128.0).sqrt());
            assert!(rms_f <= bound && rms_p <= bound, "CPU baseline RMS above {bound:.1}: {r:?}");
            // 16 samples are not exact in the penumbra
            assert!(rms_p > 0.0, "{r:?}");
        }
        // FLIP (0..1) in every row, above 0 where the RMS is (none here is exact)
        let flip = num(r, "flip");
        assert!(flip > 0.0 && flip < 1.0, "FLIP {flip}: {r:?}");
        if r[col("technique")] != "16 samples (CPU)" {
            let ratio: f64 = r[col("time_ratio")].parse().unwrap();
            assert!(ratio.is_finite() && ratio > 0.0, "time ratio {ratio}");
            assert!(!r[col("device")].is_empty(), "every row names the device");
        }
    }
    // more shadow-map texels, less error for the hard shadow map (25 vs 14 at 256^2 pixels;
    // on 40^2 pixels the same trend)
    let hard = |n: &str| -> f64 {
        rows.iter()
            .find(|r| r[col("technique")] == "hard" && r[col("shadow_map")] == n)
            .map(|r| r[col("rms_facing")].parse().unwrap())
            .unwrap()
    };
    assert!(hard("128") < hard("32"), "hard: {} at 128 vs {} at 32", hard("128"), hard("32"));
    for f in [
        "sweep.md",
        "pareto-triangle-time.svg",
        "pareto-triangle-time.png",
        "pareto-triangle-memory.svg",
        "pareto-triangle-memory.png",
        "pareto-triangle-time-flip.svg",
        "pareto-triangle-time-flip.png",
        "pareto-triangle-memory-flip.svg",
        "pareto-triangle-memory-flip.png",
    ] {
        let bytes = std::fs::read(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(bytes.len() > 100, "{f} is nearly empty");
    }
    let png = std::fs::read(out.join("pareto-triangle-time.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let svg = std::fs::read_to_string(out.join("pareto-triangle-time.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("Pareto front"));
    // Issue 51: each point of the front is labelled with its configuration; the legend
    // lies right of the plot (its entries' x beyond every tick's); the frames' spread
    // (2 frames a configuration here) is drawn and said to be.
    let gpu: Vec<&Vec<String>> = rows.iter().filter(|r| !r[col("technique")].contains("(CPU)")).collect();
    let mut order: Vec<(f64, f64, String)> = gpu
        .iter()
        .map(|r| {
            let label = format!("{}: {}", r[col("technique")], r[col("config")]);
            (num(r, "time_ratio"), num(r, "rms_penumbra"), label)
        })
        .collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut best = f64::INFINITY;
    for (_, err, label) in &order {
        if *err < best {
            best = *err;
            assert!(svg.contains(&format!(">\n{label}\n</text>")), "no label `{label}` on the chart");
        }
    }
    let text_x = |body: &str| -> i32 {
        let at = svg
            .find(&format!(">\n{body}\n</text>"))
            .unwrap_or_else(|| panic!("no text `{body}`"));
        let start = svg[..at].rfind("<text").unwrap();
        let x = svg[start..at].split(" x=\"").nth(1).unwrap().split('"').next().unwrap();
        x.parse().unwrap()
    };
    assert!(
        text_x("Pareto front (labelled)") > 800 && text_x("csm") > 800,
        "the legend is beside the plot"
    );
    assert!(
        svg.contains("error bars: fastest to slowest"),
        "no error bars for 2 frames a configuration"
    );
    for r in &gpu {
        let (lo, ms, hi) = (num(r, "gpu_ms_min"), num(r, "gpu_ms"), num(r, "gpu_ms_max"));
        assert!(lo > 0.0 && lo <= ms + 1e-4 && ms <= hi + 1e-4, "{r:?}");
    }

    // `--redraw` (issue 51): sweep.md and every chart written again from sweep.csv alone,
    // nothing measured: the same files as the run wrote
    let written: Vec<(String, Vec<u8>)> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with("pareto-") || n == "sweep.md" || n == "sweep.csv")
        .map(|n| (n.clone(), std::fs::read(out.join(&n)).unwrap()))
        .collect();
    assert_eq!(written.len(), 10, "{:?}", written.iter().map(|w| &w.0).collect::<Vec<_>>());
    for (n, _) in &written {
        if n != "sweep.csv" {
            std::fs::remove_file(out.join(n)).unwrap();
        }
    }
    std::fs::remove_file(out.join("records.ron")).unwrap();
    run(&out, &["--redraw"]);
    // What the CSV keeps is rounded (times to 4 decimals, FLIP to 5), so what is drawn
    // again from it is the run's output up to that rounding: every CSV field the same but
    // the time ratio, which is computed again from the rounded times (it moves by at most
    // their half-units' relative error, plus its own rounding); the table the same but
    // its time ratio, within one unit of its 2 decimals; every chart's texts (title, axes,
    // ticks, labels, legend) the same, its points moved only by the rounding.
    let again = |n: &str| std::fs::read(out.join(n)).unwrap_or_else(|e| panic!("{n} not drawn again: {e}"));
    let before = |n: &str| &written.iter().find(|w| w.0 == n).unwrap().1;
    let records = |b: &[u8]| self::rows(&String::from_utf8_lossy(b));
    let (old_rows, new_rows) = (records(before("sweep.csv")), records(&again("sweep.csv")));
    assert_eq!(old_rows.len(), new_rows.len());
    for (o, n) in old_rows.iter().zip(&new_rows) {
        for (k, (a, b)) in o.iter().zip(n).enumerate() {
            if header[k] == "time_ratio" && a != b {
                let (ms, reference, ratio) = (num(o, "gpu_ms"), num(o, "reference_ms"), num(o, "time_ratio"));
                let moved = ratio * (0.5e-4 / ms + 0.5e-4 / reference) + 1e-4;
                assert!(
                    (a.parse::<f64>().unwrap() - b.parse::<f64>().unwrap()).abs() <= moved,
                    "{a} vs {b}: {o:?}"
                );
            } else {
                assert_eq!(a, b, "{}: {o:?}", header[k]);
            }
        }
    }
    let md = |b: &[u8]| String::from_utf8_lossy(b).lines().map(str::to_string).collect::<Vec<_>>();
    let (old_md, new_md) = (md(before("sweep.md")), md(&again("sweep.md")));
    assert_eq!(old_md.len(), new_md.len());
    let mut ratio_cell = None;
    for (o, n) in old_md.iter().zip(&new_md) {
        let (oc, nc): (Vec<&str>, Vec<&str>) = (o.split('|').collect(), n.split('|').collect());
        if let Some(k) = oc.iter().position(|c| c.trim() == "time ratio") {
            ratio_cell = Some(k);
        }
        for (k, (a, b)) in oc.iter().zip(&nc).enumerate() {
            if a != b {
                assert_eq!(Some(k), ratio_cell, "sweep.md: `{o}` became `{n}`");
                let d = a.trim().parse::<f64>().unwrap() - b.trim().parse::<f64>().unwrap();
                assert!(d.abs() <= 0.0101, "sweep.md: `{o}` became `{n}`");
            }
        }
    }
    let texts = |svg: &[u8]| -> Vec<String> {
        let svg = String::from_utf8_lossy(svg);
        svg.split("</text>")
            .filter_map(|t| t.rsplit_once(">\n").map(|(_, body)| body.trim().to_string()))
            .collect()
    };
    for (n, _) in written.iter().filter(|w| w.0.starts_with("pareto-")) {
        let drawn = again(n);
        if n.ends_with(".svg") {
            assert_eq!(texts(&drawn), texts(before(n)), "{n}");
        } else {
            assert_eq!(&drawn[1..4], b"PNG", "{n}");
        }
    }
    // a CSV without FLIP (a sweep of an older version): no FLIP charts, the others drawn
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&header).unwrap();
    for mut r in rows.clone() {
        r[col("flip")] = String::new();
        w.write_record(&r).unwrap();
    }
    let no_flip = String::from_utf8(w.into_inner().unwrap()).unwrap();
    let old = tmp("redraw-old");
    std::fs::create_dir_all(&old).unwrap();
    std::fs::write(old.join("sweep.csv"), &no_flip).unwrap();
    run(&old, &["--redraw"]);
    assert!(old.join("pareto-triangle-time.svg").exists() && !old.join("pareto-triangle-time-flip.svg").exists());
    // a bad line is refused with its file and line
    std::fs::write(old.join("sweep.csv"), no_flip.replacen("0/1,", "7/1,", 1)).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .args(["sweep", concat!(env!("CARGO_MANIFEST_DIR"), "/tests/sweep.ron"), "--redraw", "-o"])
        .arg(&old)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("sweep.csv:2: shard `7/1`"), "{err}");
    // nothing to draw: said, with what to do
    let empty = tmp("redraw-empty");
    let o = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .args(["sweep", concat!(env!("CARGO_MANIFEST_DIR"), "/tests/sweep.ron"), "--redraw", "-o"])
        .arg(&empty)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("sweep.csv") && err.contains("run the sweep there first"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&old);

    // two shards hold exactly the configurations of the whole
    let (a, b) = (tmp("shard0"), tmp("shard1"));
    let (s0, s1) = (run(&a, &["--shard", "0/2"]), run(&b, &["--shard", "1/2"]));
    let key = |r: &Vec<String>| format!("{}|{}|{}", r[col("scene")], r[col("technique")], r[col("config")]);
    let mut whole: Vec<String> = rows.iter().map(key).collect();
    let mut split: Vec<String> = self::rows(&s0).iter().chain(self::rows(&s1).iter()).map(key).collect();
    whole.sort();
    split.sort();
    assert_eq!(whole, split);
    // every shard timed the reference itself
    for r in self::rows(&s0).iter().chain(self::rows(&s1).iter()) {
        assert!(r[col("reference_ms")].parse::<f64>().is_ok_and(|t| t > 0.0), "{r:?}");
    }
    for d in [out, a, b] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// `pixels: ShadowOnGround` (Lawlor's set, on triangle-lawlor.ron): every row has its error
/// over the same ground pixels, fewer than the facing ones, and the Markdown table and the
/// charts rank by it. A sweep over a scene where every object casts is refused before any
/// GPU work, naming the scene and the fix.
#[test]
fn a_sweep_over_the_shadow_on_the_ground_reports_it() {
    let out = tmp("ground");
    let csv = run_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/sweep-ground.ron"), &out, &[]);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name}"));
    let rows = rows(&csv);
    assert_eq!(rows.len(), 3, "{csv}");
    let num = |r: &Vec<String>, c: &str| -> f64 { r[col(c)].parse().unwrap_or_else(|_| panic!("{c} in {r:?}")) };
    let ground = num(&rows[0], "ground_pixels");
    for r in &rows {
        assert_eq!(num(r, "ground_pixels"), ground, "{r:?}");
        assert!(ground > 0.0 && ground < num(r, "facing_pixels"), "{r:?}");
        let (rms, max) = (num(r, "rms_ground"), num(r, "max_ground"));
        assert!(rms.is_finite() && rms > 0.0 && rms <= max + 0.001, "{r:?}");
    }
    let md = std::fs::read_to_string(out.join("sweep.md")).unwrap();
    assert!(md.contains("| technique | config | RMS shadow on ground | RMS facing |"), "{md}");
    let svg = std::fs::read_to_string(out.join("pareto-triangle-lawlor-time.svg")).unwrap();
    assert!(svg.contains("shadow on the ground"), "the chart's axis names the pixel set");
    let _ = std::fs::remove_dir_all(&out);

    let bad = tmp("ground-refused");
    std::fs::create_dir_all(&bad).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let file = bad.join("bad.ron");
    std::fs::write(
        &file,
        format!(
            "(scenes: [\"{0}/scenes/triangle.ron\"], camera: Some((8, 8)), reference: \"{0}/techniques/hard.ron\", pixels: ShadowOnGround, techniques: [(file: \"{0}/techniques/hard.ron\")])",
            root.display()
        ),
    )
    .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .arg("sweep")
        .arg(&file)
        .arg("-o")
        .arg(bad.join("out"))
        .output()
        .expect("sshc runs");
    let text = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        text.contains("`pixels: ShadowOnGround` needs a ground that casts no shadow")
            && text.contains("triangle.ron")
            && text.contains("casts: false"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&bad);
}

/// A scene of several lights is swept one light at a time: each light gets its
/// own rows, truth and figures, named `SCENE light K`.
#[test]
fn a_sweep_over_several_lights_reports_each_light() {
    let out = tmp("lights");
    let csv = run_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/sweep-lights.ron"), &out, &[]);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let scene = header.iter().position(|h| *h == "scene").expect("a scene column");
    let rms = header.iter().position(|h| *h == "rms_facing").expect("an rms_facing column");
    let rows = rows(&csv);
    let scenes: Vec<&str> = rows.iter().map(|r| r[scene].as_str()).collect();
    assert_eq!(
        scenes,
        ["three-lights light 0", "three-lights light 1", "three-lights light 2"],
        "{csv}"
    );
    // three lights of different kinds: three different errors
    let errors: Vec<&str> = rows.iter().map(|r| r[rms].as_str()).collect();
    assert!(errors[0] != errors[1] && errors[1] != errors[2], "{csv}");
    let _ = std::fs::remove_dir_all(out);
}

/// `sshc sweep --cascades 2` runs every configuration, and the reference, with two
/// cascades: the same rows, finite figures, and a visibility that is not the one map's (the
/// cascades are fitted to the camera's slices, not to the scene).
/// A `cascades` axis in the sweep file gives, row by row, what `--cascades N` gives.
#[test]
fn a_sweep_with_cascades_runs_every_configuration_with_them() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/sweep-ground.ron");
    let (plain, cascaded) = (tmp("plain"), tmp("cascades"));
    let one = rows(&run_file(&file, &plain, &[]));
    let csv = run_file(&file, &cascaded, &["--cascades", "2"]);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name}"));
    let two = rows(&csv);
    assert_eq!(two.len(), one.len(), "{csv}");
    for r in &two {
        let rms: f64 = r[col("rms_ground")].parse().unwrap_or_else(|_| panic!("{r:?}"));
        assert!(rms.is_finite() && rms > 0.0, "{r:?}");
        // the GPU rows are timed against the reference (the CPU baseline's row is not)
        if !r[col("technique")].contains("(CPU)") {
            assert!(!r[col("time_ratio")].is_empty(), "{r:?}");
        }
    }
    assert!(
        one.iter().zip(&two).any(|(a, b)| a[col("rms_ground")] != b[col("rms_ground")]),
        "two cascades gave every row the one map's error: were they bound?"
    );
    // a `cascades` axis: each of its rows is the run with that many cascades, to the digit
    let axis = tmp("cascades-axis");
    let csv = run_file(&file.with_file_name("sweep-cascades.ron"), &axis, &[]);
    let swept = rows(&csv);
    assert_eq!(swept.len(), 4, "{csv}");
    for r in &swept {
        let config = &r[col("config")];
        let (n, map) = (
            if config.contains("cascades=2") { &two } else { &one },
            if config.contains("shadow_map=16") {
                "shadow_map=16"
            } else {
                "shadow_map=64"
            },
        );
        let same = n
            .iter()
            .find(|x| x[col("config")].contains(map) && !x[col("technique")].contains("(CPU)"))
            .unwrap_or_else(|| panic!("no row {map} in {n:?}"));
        assert_eq!(r[col("rms_ground")], same[col("rms_ground")], "{config}: {r:?} against {same:?}");
    }
    let _ = std::fs::remove_dir_all(&plain);
    let _ = std::fs::remove_dir_all(&cascaded);
    let _ = std::fs::remove_dir_all(&axis);
}

// ---------------------------------------------------------------------------------------
// Shards, merging and resuming (docs/cluster.md)
// ---------------------------------------------------------------------------------------

fn sweep_file(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests").join(name)
}

/// `sshc ARGS`, its status and its standard output and error together.
fn sshc(args: &[&std::ffi::OsStr]) -> (bool, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .args(args)
        .env("LP_NUM_THREADS", "2")
        .output()
        .expect("sshc runs");
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    (o.status.success(), text)
}

/// `sshc sweep tests/sweep.ron --shard SHARD -o DIR` with a small truth cached in `cache`.
fn shard_of_sweep(shard: &str, dir: &Path, cache: &Path) -> (bool, String) {
    sshc(&[
        "sweep".as_ref(),
        sweep_file("sweep.ron").as_os_str(),
        "-o".as_ref(),
        dir.as_os_str(),
        "--shard".as_ref(),
        shard.as_ref(),
        "--samples".as_ref(),
        "16".as_ref(),
        "--runs".as_ref(),
        "2".as_ref(),
        "--cache".as_ref(),
        cache.as_os_str(),
    ])
}

/// `sshc sweep merge DIRS -o OUT`.
fn merge(dirs: &[&Path], out: &Path) -> (bool, String) {
    let mut args: Vec<&std::ffi::OsStr> = vec!["sweep".as_ref(), "merge".as_ref()];
    args.extend(dirs.iter().map(|d| d.as_os_str()));
    args.extend(["-o".as_ref(), out.as_os_str()]);
    sshc(&args)
}

/// A sweep run unsharded and as 3 shards merged (`sshc sweep merge`): every accuracy,
/// memory and count column equal, the time ratios present, the Markdown table and the
/// charts written. Each shard prints plain progress lines (its stderr is not a terminal),
/// and a second run of a finished shard measures nothing and says so.
#[test]
fn three_shards_merged_equal_the_unsharded_sweep() {
    let whole = tmp("merge-whole");
    let whole_csv = run(&whole, &[]);
    let base = tmp("merge-shards");
    let cache = base.join("cache");
    let dirs: Vec<PathBuf> = (0..3).map(|i| base.join(format!("shard-{i}"))).collect();
    for (i, d) in dirs.iter().enumerate() {
        let (ok, text) = shard_of_sweep(&format!("{i}/3"), d, &cache);
        assert!(ok, "{text}");
        // configurations i, i + 3 (and shard 0's CPU baseline): the last line says none is left
        let rows = if i == 0 { 3 } else { 2 };
        assert!(
            text.contains(&format!("sweep {i}/3: 1 of {rows} done, {} left", rows - 1))
                && text.contains(&format!("sweep {i}/3: {rows} of {rows} done, 0 left"))
                && text.contains("to go"),
            "progress lines: {text}"
        );
    }
    let out = base.join("merged");
    let refs: Vec<&Path> = dirs.iter().map(|d| d.as_path()).collect();
    // in any order
    let (ok, text) = merge(&[refs[2], refs[0], refs[1]], &out);
    assert!(ok, "{text}");
    assert!(text.contains("merge: 3 shards") && text.contains("merge: one device"), "{text}");
    for i in 0..3 {
        assert!(text.contains(&format!("  shard {i}/3: ")), "a summary line per shard: {text}");
    }
    let merged = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert_merged_equals(&whole_csv, &merged, 3);
    let (md_whole, md_merged) = (
        std::fs::read_to_string(whole.join("sweep.md")).unwrap(),
        std::fs::read_to_string(out.join("sweep.md")).unwrap(),
    );
    assert_eq!(md_whole.lines().count(), md_merged.lines().count(), "{md_merged}");
    assert!(md_merged.starts_with("Device: "), "{md_merged}");
    for f in ["pareto-triangle-time.svg", "pareto-triangle-time.png", "pareto-triangle-memory.png"] {
        assert!(std::fs::metadata(out.join(f)).is_ok_and(|m| m.len() > 100), "{f}");
    }
    // run again: nothing measured, the same rows written
    let (ok, text) = shard_of_sweep("1/3", &dirs[1], &cache);
    assert!(ok, "{text}");
    assert!(
        text.contains("2 of its 2 rows done by an earlier run, skipped; 0 left") && text.contains("nothing left to measure"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&whole);
    let _ = std::fs::remove_dir_all(&base);
}

/// A shard stopped by a signal (SIGKILL) between two configurations keeps the rows it
/// finished: the merge refuses it as unfinished, the same command run again says what it
/// skips and measures only the rest, and the merged sweep still equals the unsharded one.
/// (tests/sweep-slow.ron is tests/sweep.ron with more timed frames: the same figures.)
#[test]
fn a_killed_shard_resumes_and_the_merge_still_equals_the_unsharded_sweep() {
    let whole = tmp("kill-whole");
    let whole_csv = run(&whole, &[]);
    let base = tmp("kill-shards");
    let cache = base.join("cache");
    let slow = sweep_file("sweep-slow.ron");
    let dirs: Vec<PathBuf> = (0..3).map(|i| base.join(format!("shard-{i}"))).collect();
    let args = |i: usize| -> Vec<std::ffi::OsString> {
        let mut a: Vec<std::ffi::OsString> = vec!["sweep".into(), slow.clone().into(), "-o".into(), dirs[i].clone().into()];
        a.extend(["--shard".into(), format!("{i}/3").into(), "--samples".into(), "16".into()]);
        a.extend(["--runs".into(), "2".into(), "--cache".into(), cache.clone().into()]);
        a
    };
    // shard 1: stopped once its first configuration is recorded, inside the second (CSM)
    let mut child = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .args(args(1))
        .env("LP_NUM_THREADS", "2")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("sshc starts");
    let records = dirs[1].join("records.ron");
    let start = std::time::Instant::now();
    let rows_recorded = || {
        std::fs::read_to_string(&records)
            .map(|t| t.lines().filter(|l| l.starts_with("Row(")).count())
            .unwrap_or(0)
    };
    while rows_recorded() < 1 {
        assert!(child.try_wait().unwrap().is_none(), "the shard ended before it was stopped");
        assert!(start.elapsed().as_secs() < 120, "no row recorded in 120 s");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let kept = rows_recorded();
    // shard 1 has configurations 1 (the hard shadow map) and 4 (CSM, 100 frames of some
    // milliseconds each)
    assert_eq!(kept, 1, "rows recorded when stopped");
    for i in [0, 2] {
        let (ok, text) = sshc(&args(i).iter().map(|a| a.as_os_str()).collect::<Vec<_>>());
        assert!(ok, "{text}");
    }
    let refs: Vec<&Path> = dirs.iter().map(|d| d.as_path()).collect();
    let out = base.join("merged");
    let (ok, text) = merge(&refs, &out);
    assert!(!ok, "an unfinished shard is merged: {text}");
    assert!(
        text.contains("shard-1 (shard 1/3) is unfinished: 1 of its 2 rows done; run its command again to resume it"),
        "{text}"
    );
    let (ok, text) = sshc(&args(1).iter().map(|a| a.as_os_str()).collect::<Vec<_>>());
    assert!(ok, "{text}");
    assert!(
        text.contains(&format!(
            "resuming shard 1/3 in {}: 1 of its 2 rows done by an earlier run, skipped; 1 left",
            dirs[1].display()
        )) && text.contains("sweep 1/3: 2 of 2 done, 0 left"),
        "{text}"
    );
    let manifest = std::fs::read_to_string(dirs[1].join("shard.ron")).unwrap();
    assert!(
        manifest.contains("finished: true") && manifest.contains("seconds: None"),
        "two runs, the first stopped: {manifest}"
    );
    let (ok, text) = merge(&refs, &out);
    assert!(ok, "{text}");
    assert!(text.contains("stopped on "), "the summary names the stopped run: {text}");
    assert_merged_equals(&whole_csv, &std::fs::read_to_string(out.join("sweep.csv")).unwrap(), 3);
    let _ = std::fs::remove_dir_all(&whole);
    let _ = std::fs::remove_dir_all(&base);
}

/// Copies the files of folder `from` into `to` (created), applying `edit` to `shard.ron`.
fn copy_shard(from: &Path, to: &Path, edit: impl Fn(String) -> String) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        if p.is_file() {
            std::fs::copy(&p, to.join(p.file_name().unwrap())).unwrap();
        }
    }
    let m = std::fs::read_to_string(to.join("shard.ron")).unwrap();
    std::fs::write(to.join("shard.ron"), edit(m)).unwrap();
}

/// Every refusal of `sshc sweep merge`, each naming the shard and the reason, with
/// nothing written: a folder that is no shard, a missing shard, a shard given twice,
/// shards of different sweeps (a technique file changed) and of different code, an
/// unfinished shard. Shards of different devices merge, and the outputs say so. Also: a
/// sweep file named `merge` runs as `./merge`; `--slurm` refuses what it cannot write.
#[test]
fn bad_merges_are_refused_naming_the_shard_and_the_reason() {
    let base = tmp("refusals");
    // a sweep in a folder of its own, its technique and scene beside it
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let sweep_in = |dir: &Path, comment: &str| -> PathBuf {
        std::fs::create_dir_all(dir).unwrap();
        let hard = std::fs::read_to_string(root.join("techniques/hard.ron")).unwrap();
        std::fs::write(dir.join("hard.ron"), format!("{comment}{hard}")).unwrap();
        std::fs::copy(root.join("scenes/triangle.ron"), dir.join("triangle.ron")).unwrap();
        let s = dir.join("s.ron");
        std::fs::write(
            &s,
            r#"(scenes: ["triangle.ron"], camera: Some((16, 16)), frames: 1, reference: "hard.ron", techniques: [(file: "hard.ron", axes: { "shadow_map": [16, 32] })])"#,
        )
        .unwrap();
        s
    };
    let a = sweep_in(&base.join("a"), "");
    let b = sweep_in(&base.join("b"), "// changed\n");
    let shard = |s: &Path, i: usize, dir: &Path| {
        let shard = format!("{i}/2");
        let (ok, text) = sshc(&[
            "sweep".as_ref(),
            s.as_os_str(),
            "-o".as_ref(),
            dir.as_os_str(),
            "--shard".as_ref(),
            shard.as_ref(),
            "--samples".as_ref(),
            "4".as_ref(),
            "--runs".as_ref(),
            "2".as_ref(),
            "--cache".as_ref(),
            base.join("cache").as_os_str(),
        ]);
        assert!(ok, "{text}");
    };
    let (s0, s1, other) = (base.join("s0"), base.join("s1"), base.join("other1"));
    shard(&a, 0, &s0);
    shard(&a, 1, &s1);
    shard(&b, 1, &other);
    let out = base.join("out");
    let refused = |dirs: &[&Path], want: &[&str]| {
        let (ok, text) = merge(dirs, &out);
        assert!(!ok, "merged: {text}");
        for w in want {
            assert!(text.contains(w), "`{w}` not in:\n{text}");
        }
        assert!(text.contains("error: nothing merged") && !out.join("sweep.csv").exists(), "{text}");
    };
    let empty = base.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    refused(
        &[&s0, &empty],
        &[&format!("{} is not a shard folder: it has no shard.ron", empty.display())],
    );
    refused(&[&s0], &["shard 1/2 is missing: no folder given holds it"]);
    let twice = base.join("s0-again");
    copy_shard(&s0, &twice, |m| m);
    refused(
        &[&s0, &s1, &twice],
        &[&format!(
            "{} and {} all hold shard 0/2: give each shard once",
            s0.display(),
            twice.display()
        )],
    );
    refused(
        &[&s0, &other],
        &[
            &format!("{} is a shard of another sweep than {}", other.display(), s0.display()),
            "`hard.ron` differs",
        ],
    );
    let code = base.join("code1");
    copy_shard(&s1, &code, |m| {
        let line = m.lines().find(|l| l.trim_start().starts_with("code:")).unwrap().to_string();
        m.replace(&line, "    code: \"git 0123\",")
    });
    refused(
        &[&s0, &code],
        &[&format!(
            "{} was run by other code than {} (git 0123 against ",
            code.display(),
            s0.display()
        )],
    );
    let unfinished = base.join("unfinished1");
    copy_shard(&s1, &unfinished, |m| m.replace("finished: true", "finished: false"));
    std::fs::write(unfinished.join("records.ron"), "").unwrap();
    refused(
        &[&s0, &unfinished],
        &[&format!("{} (shard 1/2) is unfinished: 0 of its 1 rows done", unfinished.display())],
    );
    // another device: merged, and said so
    let device = base.join("device1");
    copy_shard(&s1, &device, |m| {
        let line = m.lines().find(|l| l.trim_start().starts_with("device:")).unwrap().to_string();
        m.replace(&line, "    device: (\"Another GPU (driver 1)\", \"Another GPU\"),")
    });
    let (ok, text) = merge(&[&s0, &device], &out);
    assert!(ok, "{text}");
    assert!(
        text.contains("merge: 2 devices; each row's time ratio is against the reference timed on its own shard's device")
            && text.contains("Another GPU (driver 1) (shards 1/2)"),
        "{text}"
    );
    let md = std::fs::read_to_string(out.join("sweep.md")).unwrap();
    assert!(
        md.starts_with("Devices: ") && md.contains("Time ratios are per device") && md.contains("| Another GPU |"),
        "{md}"
    );
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert!(csv.contains("1/2,\"Another GPU (driver 1)\""), "{csv}");

    // `merge` as a sweep file's name: `./merge`, from its folder
    std::fs::copy(&a, base.join("a/merge")).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .current_dir(base.join("a"))
        .args([
            "sweep",
            "./merge",
            "-o",
            "named-merge",
            "--samples",
            "4",
            "--runs",
            "2",
            "--no-cache",
        ])
        .env("LP_NUM_THREADS", "2")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        rows(&std::fs::read_to_string(base.join("a/named-merge/sweep.csv")).unwrap()).len(),
        2
    );
    let (ok, text) = sshc(&["sweep".as_ref(), "merge".as_ref()]);
    assert!(!ok && text.contains("Usage: sshc sweep merge"), "{text}");

    // --slurm: the scripts are written only for what an #SBATCH line holds
    let jobs = base.join("jobs");
    let slurm = |extra: &[&str]| {
        let mut args: Vec<&std::ffi::OsStr> = vec!["sweep".as_ref(), a.as_os_str(), "-o".as_ref(), jobs.as_os_str(), "--slurm".as_ref()];
        args.extend(extra.iter().map(std::ffi::OsStr::new));
        sshc(&args)
    };
    let (ok, text) = slurm(&[]);
    assert!(!ok && text.contains("--slurm needs --shards N"), "{text}");
    let (ok, text) = slurm(&["--shards", "3"]);
    assert!(!ok && text.contains("--shards 3: the sweep has 2 configurations"), "{text}");
    let (ok, text) = slurm(&["--shards", "2", "--partition", "a b"]);
    assert!(!ok && text.contains("`--partition a b`: an #SBATCH line cannot hold it"), "{text}");
    let (ok, text) = slurm(&["--shards", "2", "--gres", "gpu:1", "--time", "10:00"]);
    assert!(ok, "{text}");
    let script = std::fs::read_to_string(jobs.join("sweep.sbatch")).unwrap();
    assert!(
        script.contains("#SBATCH --array=0-1\n") && script.contains("#SBATCH --gres=gpu:1\n") && script.contains("#SBATCH --time=10:00\n"),
        "{script}"
    );
    // the truth cache on the shared folder
    assert!(
        script.contains(&format!("--cache {}", jobs.join("truth-cache").display())),
        "{script}"
    );
    let _ = std::fs::remove_dir_all(&base);
}

/// Issue 48, item 1: a newline in the sweep file's name would end the job script's comment
/// and run as a command on every node: `--slurm` refuses it before writing anything.
#[test]
fn slurm_scripts_refuse_a_control_character_in_a_path() {
    let dir = tmp("slurm-newline");
    std::fs::create_dir_all(&dir).unwrap();
    let evil = dir.join("s\nrm -rf ~\n#.ron");
    std::fs::copy(sweep_file("sweep.ron"), &evil).unwrap();
    let out = dir.join("jobs");
    let (ok, text) = sshc(&[
        "sweep".as_ref(),
        evil.as_os_str(),
        "--slurm".as_ref(),
        "--shards".as_ref(),
        "1".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(!ok && text.contains("holds a control character"), "{text}");
    assert!(!out.exists(), "nothing written");
}

/// Issue 48, item 11: `--slurm` checks the options every task would refuse before writing
/// the scripts (docs/cluster.md promises the check on the login node).
#[test]
fn slurm_scripts_are_not_written_for_options_every_task_refuses() {
    let dir = tmp("slurm-options");
    std::fs::create_dir_all(&dir).unwrap();
    let sweep = sweep_file("sweep.ron");
    for (bad, want) in [
        (&["--cascades", "7"][..], "`--cascades 7`"),
        (&["--cascade-lambda", "NaN"][..], "`--cascade-lambda NaN`"),
        (&["--samples", "4294967295"][..], "--samples 4294967295"),
        (&["--cpus-per-task", "0"][..], "`--cpus-per-task 0`"),
    ] {
        let out = dir.join(bad[0].trim_start_matches('-'));
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "sweep".as_ref(),
            sweep.as_os_str(),
            "--slurm".as_ref(),
            "--shards".as_ref(),
            "1".as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
        ];
        args.extend(bad.iter().map(|s| std::ffi::OsStr::new(*s)));
        let (ok, text) = sshc(&args);
        assert!(!ok && text.contains(want), "{bad:?}: {text}");
        assert!(!out.join("sweep.sbatch").exists(), "{bad:?}: scripts written");
    }
}

/// Issue 48, item 15: `--slurm` does not write through a link planted in its output folder
/// (nor make its target 0755): it refuses, naming the file.
#[test]
fn slurm_scripts_are_not_written_through_a_planted_link() {
    let dir = tmp("slurm-link");
    let out = dir.join("jobs");
    std::fs::create_dir_all(&out).unwrap();
    let outside = dir.join("outside.sh");
    std::fs::write(&outside, "kept").unwrap();
    std::os::unix::fs::symlink(&outside, out.join("submit.sh")).unwrap();
    let sweep = sweep_file("sweep.ron");
    let (ok, text) = sshc(&[
        "sweep".as_ref(),
        sweep.as_os_str(),
        "--slurm".as_ref(),
        "--shards".as_ref(),
        "1".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(!ok && text.contains("submit.sh` exists and is not a regular file"), "{text}");
    assert_eq!(std::fs::read_to_string(&outside).unwrap(), "kept");
    use std::os::unix::fs::PermissionsExt as _;
    assert_eq!(
        std::fs::metadata(&outside).unwrap().permissions().mode() & 0o111,
        0,
        "made executable"
    );
}

/// Issue 48, items 2 and 10: a shard folder is read as hostile. A shard count or a
/// configuration count no split has (2^64-1 panicked allocating, 2^40 aborted, a sum of
/// counts wrapped to 0), an emptied scene list, a sweep of no configuration, and records
/// naming a scene or a row the sweep does not have are refused, naming the file and the
/// line, by the merge and by a resumed run, with nothing written.
#[test]
fn tampered_shard_counts_and_records_are_refused() {
    let base = tmp("tampered");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    std::fs::create_dir_all(&base).unwrap();
    std::fs::copy(root.join("techniques/hard.ron"), base.join("hard.ron")).unwrap();
    std::fs::copy(root.join("scenes/triangle.ron"), base.join("triangle.ron")).unwrap();
    let s = base.join("s.ron");
    std::fs::write(
        &s,
        r#"(scenes: ["triangle.ron"], camera: Some((16, 16)), frames: 1, reference: "hard.ron", techniques: [(file: "hard.ron", axes: { "shadow_map": [16, 32] })])"#,
    )
    .unwrap();
    let run = |i: usize, dir: &Path, fresh: bool| {
        let shard = format!("{i}/2");
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "sweep".as_ref(),
            s.as_os_str(),
            "-o".as_ref(),
            dir.as_os_str(),
            "--shard".as_ref(),
            shard.as_ref(),
            "--samples".as_ref(),
            "4".as_ref(),
            "--runs".as_ref(),
            "2".as_ref(),
            "--no-cache".as_ref(),
        ];
        if fresh {
            args.push("--fresh".as_ref());
        }
        sshc(&args)
    };
    let (s0, s1) = (base.join("s0"), base.join("s1"));
    for (i, d) in [(0, &s0), (1, &s1)] {
        let (ok, text) = run(i, d, false);
        assert!(ok, "{text}");
    }
    let out = base.join("out");
    let field = |m: &str, key: &str, value: &str| -> String {
        let line = m.lines().find(|l| l.trim_start().starts_with(key)).unwrap().to_string();
        m.replace(&line, &format!("    {key} {value},"))
    };
    let count = |k: &str| base.join(format!("tampered-{k}"));
    type Edit = Box<dyn Fn(String) -> String>;
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "max",
            Box::new(move |m| field(&m, "shard:", "(1, 18446744073709551615)")),
            "shard.ron: a split into 18446744073709551615 shards",
        ),
        (
            "huge",
            Box::new(move |m| field(&m, "shard:", "(1, 1099511627776)")),
            "shard.ron: a split into 1099511627776 shards",
        ),
        (
            "configs",
            Box::new(move |m| field(&m, "configurations:", "18446744073709551615")),
            "shard.ron: 18446744073709551615 configurations",
        ),
        (
            "none",
            Box::new(move |m| field(&m, "configurations:", "0")),
            "shard.ron: a sweep of no configuration",
        ),
        (
            "rows",
            Box::new(move |m| field(&m, "rows:", "5")),
            "shard.ron: 5 rows for shard 1/2",
        ),
        (
            "scenes",
            Box::new(|m: String| {
                let start = m.find("scenes: [").unwrap();
                let end = start + m[start..].find(']').unwrap();
                format!("{}scenes: []{}", &m[..start], &m[end + 1..])
            }),
            "shard.ron: no scene",
        ),
    ];
    for (k, edit, want) in &cases {
        let d = count(k);
        copy_shard(&s1, &d, edit);
        // a split's count alone decides what the merge expects: given alone, the folder
        // of a tampered count is all the merge sees
        let dirs: Vec<&Path> = if *k == "max" || *k == "huge" { vec![&d] } else { vec![&s0, &d] };
        let (ok, text) = merge(&dirs, &out);
        assert!(
            !ok && text.contains(want) && text.contains("error: nothing merged"),
            "{k}: `{want}` not in:\n{text}"
        );
        assert!(!out.join("sweep.csv").exists(), "{k}");
        // a resumed run refuses the folder too, and --fresh starts it afresh
        let (ok, text) = run(1, &d, false);
        assert!(!ok && text.contains(want), "{k}: {text}");
    }
    // records naming a scene or a configuration the sweep has not
    let records = std::fs::read_to_string(s1.join("records.ron")).unwrap();
    let row = records.lines().position(|l| l.starts_with("Row(")).unwrap() + 1;
    for (k, from, to, want) in [
        (
            "scene99",
            "scene:0,",
            "scene:99,",
            format!("records.ron:{row}: scene entry 99 of a sweep of 1 scene"),
        ),
        (
            "row99",
            "Row(index:1,",
            "Row(index:99,",
            format!("records.ron:{row}: row 99 is not shard 1/2's (the sweep has 2 configurations and 0 baselines)"),
        ),
    ] {
        let d = count(k);
        copy_shard(&s1, &d, |m| m);
        let edited: Vec<String> = records
            .lines()
            .map(|l| {
                if l.starts_with("Row(") {
                    l.replacen(from, to, 1)
                } else {
                    l.to_string()
                }
            })
            .collect();
        std::fs::write(d.join("records.ron"), edited.join("\n") + "\n").unwrap();
        let (ok, text) = merge(&[&s0, &d], &out);
        assert!(!ok && text.contains(&want), "{k}: `{want}` not in:\n{text}");
        let (ok, text) = run(1, &d, false);
        assert!(!ok && text.contains(&want), "{k}: {text}");
        let (ok, text) = run(1, &d, true);
        assert!(ok, "{k}: --fresh: {text}");
    }
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&base);
}
