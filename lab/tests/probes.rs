//! The probes of hostile and extreme inputs that crashed, hung, were accepted
//! or were answered unclearly, run as they were first run: the actual input, through the
//! `sshc` binary, on lavapipe where a GPU is needed. docs/reliability.md ("Probe audit")
//! lists every probe with the test that covers it; these are the end-to-end ones.
//!
//! Bounds, for every probe here: refused (exit status 1, so no panic, abort or signal)
//! within 20 s, debug build, under an address-space limit of 2 GiB (`ulimit -v`; a plain
//! render on lavapipe needs under 1 GiB). The inputs took 4.3 to 6.4 GB, or hung.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

mod common;
use common::{root, temp_dir};

/// Address space allowed to each run, in KiB (2 GiB).
const MEMORY_KIB: u64 = 2 << 20;
/// Time allowed to each refusal.
const TIME: Duration = Duration::from_secs(20);

/// Runs `sshc` from the repository root under the memory limit; (status, stdout, stderr).
fn sshc(args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {MEMORY_KIB} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_sshc"))
        .args(args)
        .current_dir(root())
        .env("LP_NUM_THREADS", std::env::var("LP_NUM_THREADS").unwrap_or_else(|_| "2".into()))
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or_else(|_| "/tmp".into()),
        )
        .output()
        .expect("sh and the sshc binary run");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `sshc args` is refused within the bounds, and its standard error holds every `want`.
fn refused(args: &[&str], want: &[&str]) -> String {
    let start = Instant::now();
    let (code, stdout, stderr) = sshc(args);
    let took = start.elapsed();
    let cmd = args.join(" ");
    assert_eq!(
        code,
        Some(1),
        "sshc {cmd}: exit {code:?} (1 expected: a refusal)\n{stdout}\n{stderr}"
    );
    assert!(took < TIME, "sshc {cmd}: took {took:?}, above {TIME:?}");
    assert!(
        !stderr.contains("panicked") && !stderr.contains("internal compiler error"),
        "sshc {cmd}:\n{stderr}"
    );
    for w in want {
        assert!(stderr.contains(w), "sshc {cmd}: `{w}` expected in\n{stderr}");
    }
    stderr
}

/// Where a command would write its image (`.png`) or truth (`.pfm`); refused runs write nothing.
fn out(ext: &str) -> String {
    std::env::temp_dir()
        .join(format!("sshc-probes-{}-out.{ext}", std::process::id()))
        .to_string_lossy()
        .into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `techniques/hard.ron` compiled into `dir`; the path of its graph.
fn compiled_hard(dir: &Path) -> PathBuf {
    let (code, stdout, stderr) = sshc(&["compile", "techniques/hard.ron", "-o", s(dir)]);
    assert_eq!(code, Some(0), "{stdout}\n{stderr}");
    dir.join("hard.graph.ron")
}

/// A copy of the compiled graph's folder under `name`, its graph text changed by `edit`.
fn tampered(base: &Path, name: &str, edit: impl Fn(&str) -> String) -> PathBuf {
    let dir = base.join(name);
    std::fs::create_dir_all(&dir).unwrap();
    for f in ["hard.graph.ron", "hard.depth.wgsl", "hard.shade.wgsl"] {
        std::fs::copy(base.join("g").join(f), dir.join(f)).unwrap();
    }
    let graph = dir.join("hard.graph.ron");
    let text = std::fs::read_to_string(&graph).unwrap();
    let changed = edit(&text);
    assert_ne!(changed, text, "{name}: the edit changed nothing");
    std::fs::write(&graph, changed).unwrap();
    graph
}

fn render(graph: &Path, want: &[&str]) -> String {
    refused(
        &["render", s(graph), "--scene", "scenes/edge.ron", "--size", "8x8", "-o", &out("png")],
        want,
    )
}

#[test]
fn tampered_graphs_are_refused_naming_the_field() {
    let base = temp_dir("graphs");
    compiled_hard(&base.join("g"));
    let g = |name: &str, from: &str, to: &str| tampered(&base, name, |t| t.replacen(from, to, 1));
    // Accepted before: NaN rendered mean visibility 0.233 instead of 0.974, inf all lit.
    render(
        &g("nan", "value: 0.0005", "value: NaN"),
        &["param `bias`: value NaN is not a finite number"],
    );
    render(
        &g("inf", "value: 0.0005", "value: inf"),
        &["param `bias`: value inf is not a finite number"],
    );
    render(&g("range", "value: 0.0005", "value: 0.5"), &["param `bias`", "outside its range"]);
    // Duplicated names (was "two passs").
    let tex = |t: &str| {
        let a = t.find("  textures: [\n").unwrap() + "  textures: [\n".len();
        let b = t.find("  ],\n  passes:").unwrap();
        format!("{}{}{}", &t[..b], &t[a..b], &t[b..])
    };
    render(&tampered(&base, "duptex", tex), &["two textures are named `shadow`"]);
    render(
        &g("duppass", "name: \"shade\",", "name: \"depth\","),
        &["two passes are named `depth`"],
    );
    render(
        &g("dupparam", "name: \"slope_bias\",", "name: \"bias\","),
        &["two params are named `bias`"],
    );
    // A texture nothing writes, read by the Shade pass.
    let ghost = tampered(&base, "unwritten", |t| {
        t.replacen("texture: \"shadow\",\n              view:", "texture: \"ghost\",\n              view:", 1).replacen(
            "  textures: [\n",
            "  textures: [\n    (name: \"ghost\", format: R32Float, layers: 1, extent: ShadowMap, mips: false, transient: false, channels: []),\n",
            1,
        )
    });
    render(&ghost, &["pass `shade` reads texture `ghost`, which no earlier step writes"]);
    // An unknown field: file:line:column (was the line and column without the file).
    let unknown = g("unknown", "  params_size: 16,\n", "  params_size: 16,\n  colour: 3,\n");
    let line = std::fs::read_to_string(&unknown)
        .unwrap()
        .lines()
        .position(|l| l == "  colour: 3,")
        .unwrap()
        + 1;
    render(
        &unknown,
        &[&format!(
            "{}:{line}:3: not a valid pass graph: Unexpected field named `colour`",
            s(&unknown)
        )],
    );
    // Unclear before: "Dimension Z is zero", a layer of 99 naming no pass, and "QuerySets
    // cannot be made with zero queries".
    render(
        &g("layers", "layers: 1,", "layers: 0,"),
        &["texture `shadow`, field `layers`: 0 layers; a texture has at least 1"],
    );
    render(
        &g(
            "layer99",
            "layer: 0,\n            ),\n          ],\n          params: false",
            "layer: 99,\n            ),\n          ],\n          params: false",
        ),
        &["pass `depth` writes layer 99 of texture `shadow`, which has 1 layer(s)"],
    );
    let nopass = tampered(&base, "nopass", |t| {
        let a = t.find("  passes: [\n").unwrap();
        let b = t.find("  removed:").unwrap();
        format!("{}  passes: [],\n{}", &t[..a], &t[b..])
    });
    render(&nopass, &["the graph has no passes; there is nothing to run"]);
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn a_shade_shader_writing_nan_or_1e30_fails_render_and_compare() {
    // Was: exit 0, and compare printed "RMS 1.6e32".
    let base = temp_dir("shaders");
    compiled_hard(&base.join("g"));
    for (name, value, shown) in [
        ("nan", "(vis - vis) / (vis - vis)", "visibility NaN"),
        ("big", "vis * 0.0 + 1e30", "visibility 1000000000000000000000000000000"),
    ] {
        let dir = base.join(name);
        let graph = tampered(&base, name, |t| t.to_string() + "\n");
        let shader = dir.join("hard.shade.wgsl");
        let text = std::fs::read_to_string(&shader).unwrap();
        let line = "out.visibility = vec4<f32>(vis, 0.0, 0.0, 1.0);";
        assert!(text.contains(line), "the Shade shader writes `vis` as before");
        std::fs::write(
            &shader,
            text.replace(line, &format!("out.visibility = vec4<f32>({value}, 0.0, 0.0, 1.0);")),
        )
        .unwrap();
        let want = ["pass `shade` wrote", shown, "the image is refused"];
        render(&graph, &want);
        let e = refused(
            &[
                "compare",
                s(&graph),
                "--scene",
                "scenes/edge.ron",
                "--size",
                "8x8",
                "--samples",
                "4",
                "--runs",
                "2",
                "--no-cache",
                "-o",
                // a regular file: an output that is not one (`/dev/null`) is refused before
                // anything is rendered (issue 51), and the refusal looked for here comes after
                s(&dir.join("compare.png")),
            ],
            &want,
        );
        assert!(!e.contains("RMS"), "{e}");
    }
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn huge_linked_and_fifo_files_are_refused_unread() {
    let base = temp_dir("files");
    compiled_hard(&base.join("g"));
    // A 3 GB sparse shader (was a 6.4 GB allocation and an abort).
    let graph = tampered(&base, "sparse", |t| t.to_string() + "\n");
    std::fs::File::options()
        .write(true)
        .open(base.join("sparse/hard.shade.wgsl"))
        .unwrap()
        .set_len(3 << 30)
        .unwrap();
    render(&graph, &["hard.shade.wgsl: is 3221225472 bytes, above the limit of 16777216 bytes"]);
    // A graph path linked to /dev/zero (read 4.27 GB before failing).
    #[cfg(unix)]
    {
        let zero = base.join("zero.graph.ron");
        std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
        render(&zero, &["zero.graph.ron: is not a regular file"]);
    }
    // A shader and an OBJ that are FIFOs (hung on the read).
    let graph = tampered(&base, "fifo", |t| t.to_string() + "\n");
    let fifo = base.join("fifo/hard.shade.wgsl");
    std::fs::remove_file(&fifo).unwrap();
    let made = |p: &Path| Command::new("mkfifo").arg(p).status().is_ok_and(|s| s.success());
    if made(&fifo) {
        render(&graph, &["hard.shade.wgsl: is not a regular file"]);
        let scene = base.join("fifo-obj.ron");
        let text = std::fs::read_to_string(root().join("scenes/edge.ron")).unwrap().replacen(
            "    objects: [\n",
            "    objects: [\n        Object(name: \"pipe\", mesh: Obj(path: \"pipe.obj\")),\n",
            1,
        );
        std::fs::write(&scene, text).unwrap();
        assert!(made(&base.join("pipe.obj")));
        refused(
            &[
                "render",
                "techniques/hard.ron",
                "--scene",
                s(&scene),
                "--size",
                "8x8",
                "-o",
                "/dev/null",
            ],
            &["it is not a regular file", "objects[0] (\"pipe\").mesh.path"],
        );
    }
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn extreme_scenes_are_refused_naming_the_field() {
    let base = temp_dir("scenes");
    let edge = std::fs::read_to_string(root().join("scenes/edge.ron")).unwrap();
    let floor = "Object(name: \"floor\", mesh: Plane(size: (2.0, 2.0))),";
    let scene = |name: &str, text: String| {
        assert_ne!(text, edge, "{name}: the edit changed nothing");
        let p = base.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    // Spheres of 100,000 and 2^32 - 1 segments (a 4.8 GB allocation and an abort).
    for segments in ["100000", "4294967295"] {
        let p = scene(
            "sphere.ron",
            edge.replacen(
                floor,
                &format!("{floor}\n        Object(name: \"s\", mesh: Sphere(radius: 0.5, segments: {segments})),"),
                1,
            ),
        );
        let want = [
            &format!("{segments} segments is above the limit of 1024")[..],
            "objects[1] (\"s\").mesh.segments",
        ];
        refused(
            &[
                "render",
                "techniques/hard.ron",
                "--scene",
                s(&p),
                "--size",
                "8x8",
                "-o",
                "/dev/null",
            ],
            &want,
        );
        refused(
            &["truth", "--scene", s(&p), "--size", "8x8", "--no-cache", "-o", &out("pfm")],
            &want,
        );
    }
    // Scale 1e-30 said "a scale of 0 flattens the object"; far 1e30 blamed `up`.
    let p = scene(
        "tiny.ron",
        edge.replacen(
            floor,
            "Object(name: \"floor\", mesh: Plane(size: (2.0, 2.0)), transform: (scale: (1e-30, 1e-30, 1e-30))),",
            1,
        ),
    );
    let e = refused(
        &[
            "render",
            "techniques/hard.ron",
            "--scene",
            s(&p),
            "--size",
            "8x8",
            "-o",
            "/dev/null",
        ],
        &["scale (1e-30, 1e-30, 1e-30) is too small", "objects[0] (\"floor\").transform.scale"],
    );
    assert!(!e.contains("scale of 0"), "{e}");
    let p = scene("far.ron", edge.replacen("half_height: 0.25,", "half_height: 0.25, far: 1e30,", 1));
    let e = refused(
        &[
            "render",
            "techniques/hard.ron",
            "--scene",
            s(&p),
            "--size",
            "8x8",
            "-o",
            "/dev/null",
        ],
        &["far 1e30 is beyond the limit of 1e15", "camera (Orthographic).far"],
    );
    assert!(!e.contains("`up`"), "{e}");
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn hostile_techniques_are_refused_at_their_line_and_column() {
    let base = temp_dir("techniques");
    let technique = |name: &str, vis: &str, extra: &str| {
        let p = base.join(format!("{name}.ron"));
        std::fs::write(
            &p,
            format!(
                "Technique(\n    name: \"{name}\",\n    channels: {{ \"z\": Channel(precision: F32) }},\n    passes: [\n        Depth(name: \"depth\", writes: \"shadow\", channel: \"z\"),{extra}\n        Shade(name: \"shade\", reads: [\"shadow\"], visibility: \"{vis}\"),\n    ],\n)\n"
            ),
        )
        .unwrap();
        p
    };
    let chain = |term: &str, op: &str| vec![term; 15_000].join(&format!(" {op} "));
    // 15,000-term chains overflowed the stack (rc 134) in every command that compiles.
    let add = technique("add", &chain("d", "+"), "");
    let depth = "expression is deeper than 256 levels";
    let at = format!("{}:6:", s(&add));
    for cmd in [
        vec!["check", s(&add)],
        vec!["compile", s(&add), "-o", s(&base)],
        vec!["explain", s(&add)],
        vec!["render", s(&add), "--scene", "scenes/edge.ron", "--size", "8x8", "-o", &out("png")],
        vec!["bench-compile", s(&add), "--runs", "1"],
    ] {
        refused(&cmd, &[depth, &at]);
    }
    let mul = technique("mul", &chain("d", "*"), "");
    refused(&["check", s(&mul)], &[depth]);
    let and = technique("and", &format!("select(0.0, 1.0, {})", chain("(d < 1.0)", "&&")), "");
    refused(&["check", s(&and)], &[depth]);
    // --dump-ir-after parse was cubic in a chain (1,000 terms over 60 s): refused at the
    // depth limit now, and a legal 250-term chain dumps at once.
    let long = technique("long", &format!("clamp({}, 0.0, 1.0)", vec!["d"; 1000].join(" + ")), "");
    refused(&["compile", s(&long), "--dump-ir-after", "parse", "-o", s(&base)], &[depth]);
    let legal = technique("legal", &format!("clamp({}, 0.0, 1.0)", vec!["d"; 250].join(" + ")), "");
    let start = Instant::now();
    let (code, stdout, stderr) = sshc(&["check", s(&legal), "--dump-ir-after", "parse"]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stdout.contains("(d + d)"), "{stdout}");
    assert!(start.elapsed() < TIME);
    // Three (or two) nested 4,096-term series hung; so did nests with dependent bounds.
    for (name, vis) in [
        (
            "nest3",
            "clamp(sum(i in 0..=4095, sum(j in 0..=4095, sum(k in 0..=4095, d * 0.0))), 0.0, 1.0)",
        ),
        ("nest2", "clamp(sum(i in 0..=4095, sum(j in 0..=4095, d * 0.0)), 0.0, 1.0)"),
        (
            "dependent",
            "clamp(sum(i in 0..=4095, sum(j in 0..=i, sum(k in 0..=j, d * 0.0))), 0.0, 1.0)",
        ),
    ] {
        let p = technique(name, vis, "");
        refused(
            &["compile", s(&p), "-o", s(&base)],
            &["nested series unroll", "at most 4096 in all", &format!("{}:6:", s(&p))],
        );
    }
    // Integer faults gave an internal error located in the generated WGSL (`wgsl:79:14`).
    for (name, vis, want) in [
        ("div", "f32(7 / 0)", "integer division by zero"),
        ("rem", "f32(7 % 0)", "integer remainder by zero"),
        (
            "min",
            "f32((-2147483647 - 1) / -1)",
            "integer overflow: -2147483648 / -1 does not fit in i32",
        ),
        ("add", "f32(2147483647 + 1)", "integer overflow: 2147483647 + 1 does not fit in i32"),
        ("series", "sum(k in 0..=1, f32(7 / k))", "integer division by zero"),
    ] {
        let p = technique(name, vis, "");
        let e = refused(&["compile", s(&p), "-o", s(&base)], &[want, &format!("{}:6:", s(&p))]);
        assert!(!e.contains("wgsl:"), "{e}");
    }
    // 2,100 passes compiled, then failed at render ("4204 is too many queries for a single
    // QuerySet"); refused at the first pass too many.
    let filters: String = (0..2_098)
        .map(|i| format!("\n        Filter(name: \"f{i}\", reads: \"shadow\", writes: \"s{i}\", kernel: Box(size: 3)),"))
        .collect();
    let many = technique("many", "1.0", &filters);
    refused(
        &["render", s(&many), "--scene", "scenes/edge.ron", "--size", "8x8", "-o", &out("png")],
        &["technique has 2100 passes: at most 256", &format!("{}:261:", s(&many))],
    );
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn bad_sweep_axes_are_refused_before_any_row() {
    let base = temp_dir("sweeps");
    let sweep = |name: &str, axes: &str, stochastic: &str| {
        let p = base.join(format!("{name}.ron"));
        let r = root();
        let r = r.canonicalize().unwrap();
        std::fs::write(
            &p,
            format!(
                "(\n    scenes: [\"{0}/scenes/triangle.ron\"],\n    camera: Some((8, 8)),\n    frames: 1,\n    reference: \"{0}/techniques/hard.ron\",\n    techniques: [(file: \"{0}/techniques/hard.ron\", axes: {{ {axes} }})],\n    stochastic: {stochastic},\n)\n",
                r.display()
            ),
        )
        .unwrap();
        p
    };
    let out = base.join("out");
    let run = |p: &Path, want: &[&str]| {
        refused(&["sweep", s(p), "-o", s(&out), "--no-cache", "--samples", "4", "--runs", "2"], want);
        assert!(!out.join("sweep.csv").exists(), "{}: rows were written", p.display());
    };
    let axis = "techniques[0] (`";
    run(
        &sweep("nan", "\"light_scale\": [NaN]", "[4]"),
        &[axis, "axis `light_scale`: `NaN`: a light scale must be a finite number >= 0"],
    );
    run(
        &sweep("neg", "\"light_scale\": [-1.0]", "[4]"),
        &[axis, "axis `light_scale`: `-1`: a light scale must be a finite number >= 0"],
    );
    run(
        &sweep("empty", "\"shadow_map\": []", "[4]"),
        &[axis, "axis `shadow_map`: the list of values is empty"],
    );
    // Said "needs 0, above the device's limit".
    run(
        &sweep("zero", "\"shadow_map\": [0]", "[4]"),
        &[
            axis,
            "axis `shadow_map`: `0`: the shadow map needs a whole number of at least 1 texel",
        ],
    );
    // Hung.
    run(
        &sweep("stochastic", "\"shadow_map\": [32]", "[4294967295]"),
        &["stochastic[0] = 4294967295 light samples per pixel is outside 1..=4096"],
    );
    let _ = std::fs::remove_dir_all(&base);
}
