//! `sshc compile`, `check` and `explain`: scene specialisation recorded, explained and
//! enforced, a precision chosen from the scene's depths, rounding warnings and estimates,
//! and `check` saying all that `compile` says.

use super::{ok, read_pfm, refused, sshc};
use crate::common::{root, temp_dir};
use std::process::Output;

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
