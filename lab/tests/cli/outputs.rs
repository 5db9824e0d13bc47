//! Where commands write: never through a link planted at an output, and into missing
//! folders created before anything is rendered (or refused at once).

use super::{ok, sshc};
use crate::common::temp_dir;
use std::path::Path;

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
