//! Whole sweeps: one row per configuration with finite figures, the Markdown table and the
//! charts, `--redraw`, and sweeps over the shadow on the ground, several lights and cascades.

use super::{run, run_file, tmp};
use crate::common::csv_rows as rows;
use std::path::Path;
use std::process::Command;

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
