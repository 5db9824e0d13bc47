//! Inputs refused, at once and saying why: bad arguments, budgets and sizes past their
//! limits, `--camera` and `--light` overrides and the city generator checked as scene files
//! are, a scene larger than the memory available, and messages that name what is at fault.

use super::{ok, refused, sshc};
use crate::common::{root, temp_dir};
use std::path::Path;
use std::process::Command;

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
