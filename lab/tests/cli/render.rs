//! `sshc render`: the fit and texel size it states, each pass against its bytes bound, the
//! GPU bench script, several lights in one frame, debug outputs, a visibility that is not a
//! number, and a run without XDG_RUNTIME_DIR.

use super::{command, number_after, ok, read_pfm, refused, sshc};
use crate::common::{root, temp_dir};
use std::process::Command;

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
