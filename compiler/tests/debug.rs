//! Debug outputs (`debug: {"name": "expr"}` on a Shade, docs/language.md section 7): a
//! build that does not ask for them is the build of the technique without them, byte for
//! byte; a build that asks writes each to a camera-sized texture in both Shade schedules,
//! with the visibility's code untouched.

use sshc::CompileOptions;
use sshc_graph::{Draw, Extent, Format, PassKind};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every bundled technique and example: (name, source).
fn all_techniques() -> Vec<(String, String)> {
    let mut out = Vec::new();
    for dir in ["techniques", "techniques/examples"] {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
            .unwrap()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "ron"))
            .collect();
        paths.sort();
        for p in paths {
            out.push((
                p.file_stem().unwrap().to_string_lossy().into_owned(),
                std::fs::read_to_string(&p).unwrap(),
            ));
        }
    }
    assert!(out.len() >= 20, "the bundled techniques and examples: {}", out.len());
    out
}

/// `src` with `debug` (the text of a RON map) given to its Shade pass, right after the
/// visibility string; `None` where the Shade already has debug outputs.
fn with_debug(src: &str, debug: &str) -> Option<String> {
    let shade = src.find("Shade(")?;
    let start = shade + src[shade..].find("visibility: \"")? + "visibility: \"".len();
    let mut escaped = false;
    let end = start
        + src[start..]
            .char_indices()
            .find(|&(_, c)| {
                let close = c == '"' && !escaped;
                escaped = c == '\\' && !escaped;
                close
            })?
            .0
        + 1;
    let rest = &src[end..];
    if rest.trim_start().starts_with(", debug:") {
        return None;
    }
    Some(format!("{}, debug: {debug}{rest}", &src[..end]))
}

fn compile(name: &str, src: &str, opts: &CompileOptions) -> sshc::Compiled {
    sshc::compile_str(src, opts).unwrap_or_else(|d| panic!("{name}: {}", d.render(name, src)))
}

/// The options of a build with its debug outputs.
fn debugged() -> CompileOptions {
    CompileOptions {
        debug: true,
        ..Default::default()
    }
}

fn shade_source(c: &sshc::Compiled) -> &str {
    let shade = c.graph.passes.iter().find(|p| p.kind == PassKind::Shade).expect("a Shade pass");
    &c.shaders.iter().find(|(f, _)| *f == shade.shader).expect("its module").1
}

/// Every bundled technique and example, given two debug outputs (the receiver's depth, an
/// f32, and the pixel, a vec2): without `debug` its graph and every module are those of
/// the file as written; with it, in the forward and the deferred schedule (where the
/// technique can take it), the Shade's module is that build's with the debug lines added
/// and nothing else changed, naga accepts it (codegen validates every module), and the
/// graph declares each output as a camera-sized texture the Shade's camera steps write.
#[test]
fn debug_outputs_change_nothing_unless_asked_for_and_leave_the_visibility_untouched() {
    let debug = r#"{ "receiver_depth": "d", "at_pixel": "pixel" }"#;
    let (mut seen, mut declared) = (0, Vec::new());
    for (name, src) in all_techniques() {
        let Some(with) = with_debug(&src, debug) else {
            declared.push(name);
            continue;
        };
        seen += 1;
        for schedule in ["fragment", "compute"] {
            let plain_opts = CompileOptions {
                schedule: vec![("*".into(), schedule.into())],
                ..Default::default()
            };
            let plain = compile(&name, &src, &plain_opts);
            let off = compile(&name, &with, &plain_opts);
            assert_eq!(
                off.graph.to_ron(),
                plain.graph.to_ron(),
                "{name} ({schedule}): the graph without --debug"
            );
            assert_eq!(off.shaders, plain.shaders, "{name} ({schedule}): the modules without --debug");
            let on = compile(
                &name,
                &with,
                &CompileOptions {
                    debug: true,
                    ..plain_opts.clone()
                },
            );
            // only the Shade's module changes, and only by lines that name the outputs (and
            // the `pixel` input, defined where some code reads it)
            assert_eq!(on.shaders.len(), plain.shaders.len());
            for ((f, a), (_, b)) in on.shaders.iter().zip(&plain.shaders) {
                let pixel = |l: &str| l.contains("let in_pixel =") && !b.contains("in_pixel");
                let kept: Vec<&str> = a.lines().filter(|l| !l.contains("debug") && !pixel(l)).collect();
                assert_eq!(
                    kept,
                    b.lines().collect::<Vec<_>>(),
                    "{name} ({schedule}): {f} beyond its debug lines"
                );
            }
            let wgsl = shade_source(&on);
            assert!(
                wgsl.contains("debug_receiver_depth") && wgsl.contains("debug_at_pixel"),
                "{name}: {wgsl}"
            );
            for (texture, format) in [("debug_receiver_depth", Format::R32Float), ("debug_at_pixel", Format::Rg32Float)] {
                let t = on.graph.texture(texture).unwrap_or_else(|| panic!("{name}: no texture {texture}"));
                assert_eq!((t.format, t.extent, t.layers, t.mips), (format, Extent::Camera, 1, false), "{name}");
            }
            // the camera steps write them, in the order written, after the camera outputs
            let shade = on.graph.passes.iter().find(|p| p.kind == PassKind::Shade).unwrap();
            for s in &shade.steps {
                let writes: Vec<&str> = s.writes.iter().map(|w| w.texture.as_str()).collect();
                let expected: &[&str] = if s.draw.writes_camera_textures() {
                    &["debug_receiver_depth", "debug_at_pixel"]
                } else {
                    &[]
                };
                assert_eq!(writes, expected, "{name} ({schedule}): {:?}", s.draw);
            }
            let deferred = shade.steps.iter().any(|s| s.draw == Draw::ComputePixels);
            assert_eq!(wgsl.contains("o_debug_at_pixel"), deferred, "{name} ({schedule})");
            // what the graph declares reads back
            assert_eq!(sshc::PassGraph::from_ron(&on.graph.to_ron()).as_ref(), Ok(&on.graph), "{name}");
        }
    }
    assert!(seen >= 19, "techniques given debug outputs: {seen}");
    assert_eq!(
        declared,
        ["mssm", "vssm", "vssm-subdivided"],
        "the techniques that declare debug outputs already"
    );
}

/// The example declaring debug outputs (vssm-subdivided) without them in its text compiles
/// to the same graph and modules as the example does without `--debug`.
#[test]
fn the_example_with_debug_outputs_builds_as_if_it_had_none() {
    let src = std::fs::read_to_string(root().join("techniques/examples/vssm-subdivided.ron")).unwrap();
    let start = src.find(", debug: {").expect("the example declares debug outputs");
    let end = start + src[start..].find("\n        }").expect("the map's end") + "\n        }".len();
    let without = format!("{}{}", &src[..start], &src[end..]);
    assert!(!without.contains("debug:"), "{without}");
    let (a, b) = (
        compile("vssm-subdivided", &src, &CompileOptions::default()),
        compile("without", &without, &CompileOptions::default()),
    );
    assert_eq!(a.graph.to_ron(), b.graph.to_ron());
    assert_eq!(a.shaders, b.shaders);
    assert!(a.explain().contains("left out of this build"));
    let on = compile("vssm-subdivided", &src, &debugged());
    let explained = on.explain();
    assert!(explained.contains("z_mean -> debug_z_mean (R32Float)"), "{explained}");
}

/// A debug output sees the visibility's leading `let`s and shares their code: the
/// receiver's biased depth `r` is the visibility's `let` node, emitted once; vectors take
/// the formats of their width; a debug output on a per-sample technique reads a sample's
/// view with `at_sample`.
#[test]
fn debug_outputs_share_the_visibilitys_lets_and_take_their_widths_formats() {
    let src = r#"Technique(name: "t", params: { "bias": Param(ty: F32, default: 0.001) },
        channels: { "z": Channel(precision: F32) },
        passes: [
            Depth(name: "depth", writes: "shadow", channel: "z"),
            Shade(name: "shade", reads: ["shadow"], visibility: "let r = d - bias; select(0.0, 1.0, r <= sample(z))", debug: {
                "r": "r", "three": "vec3(r, d, 1.0)", "four": "vec4(sample(z), r, d, 2.0)",
            }),
        ])"#;
    let on = compile("t", src, &debugged());
    let formats: Vec<(String, Format)> = on
        .graph
        .textures
        .iter()
        .filter(|t| t.extent == Extent::Camera)
        .map(|t| (t.name.clone(), t.format))
        .collect();
    assert_eq!(
        formats,
        [
            ("debug_r".to_string(), Format::R32Float),
            ("debug_three".to_string(), Format::Rgba32Float),
            ("debug_four".to_string(), Format::Rgba32Float)
        ]
    );
    let wgsl = shade_source(&on);
    // `d - bias` once, shared by the visibility and every output that names `r`
    assert_eq!(wgsl.matches("in_d - params.bias").count(), 1, "{wgsl}");
    assert_eq!(wgsl.matches("textureSample").count(), 1, "one lookup of z, shared: {wgsl}");
    // the per-sample technique: sample 1's depth, only through `at_sample`
    let ps = std::fs::read_to_string(root().join("techniques/point-samples.ron")).unwrap();
    let ps = with_debug(&ps, r#"{ "d1": "at_sample(1, d)" }"#).unwrap();
    let on = compile("point-samples", &ps, &debugged());
    assert!(
        shade_source(&on).contains("out.debug_d1 = vec4<f32>(in_d_v1, 0.0, 0.0, 0.0);"),
        "{}",
        shade_source(&on)
    );
    // outside `at_sample`, a lookup of a per-sample resource is refused as in the visibility
    let bad = with_debug(
        &std::fs::read_to_string(root().join("techniques/point-samples.ron")).unwrap(),
        r#"{ "z": "nearest(z)" }"#,
    )
    .unwrap();
    let e = sshc::compile_str(&bad, &CompileOptions::default()).expect_err("a per-sample lookup outside at_sample");
    assert!(
        e.render("point-samples", &bad).contains("at_sample"),
        "{}",
        e.render("point-samples", &bad)
    );
}
