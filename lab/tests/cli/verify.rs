//! `sshc verify`: agreement on every bundled technique, a precision that loses the signal,
//! a check against an independent reference, bad arguments, and the default scenes found
//! from any working folder.

use super::{command, ok, refused, sshc};
use crate::common::{self, root, temp_dir};

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
