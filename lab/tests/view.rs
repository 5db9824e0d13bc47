//! `sshc view` in a real window: an X server of its own (`xvfb-run`, which
//! `scripts/setup.sh --test` installs), lavapipe drawing into the window's surface, scripts
//! replayed frame by frame and the JSON-lines log read back. Never skipped: without
//! `xvfb-run` these tests fail and say what to install.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

mod common;
use common::{root, temp_dir};

/// A viewer run's bound: a few compilations and pipeline creations on lavapipe and some
/// tens of frames at 160 x 120 take seconds; a hang is stopped here.
const LIMIT: Duration = Duration::from_secs(240);

/// Runs `sshc view ARGS` under its own virtual X server; returns (success, stdout+stderr).
fn view(args: &[&str]) -> (bool, String) {
    let out = view_output(args);
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    (out.status.success(), text)
}

/// Runs `sshc view ARGS` under its own virtual X server; returns what it did.
fn view_output(args: &[&str]) -> std::process::Output {
    let xvfb = which("xvfb-run").unwrap_or_else(|| {
        panic!("xvfb-run is missing: `sshc view`'s tests open real windows on a virtual X server (as root, `scripts/setup.sh --test` installs it; or `apt-get install -y xvfb xauth`)")
    });
    let mut child = Command::new(xvfb)
        .args(["-a", "-s", "-screen 0 640x480x24"])
        .arg(env!("CARGO_BIN_EXE_sshc"))
        .arg("view")
        .args(args)
        .current_dir(root())
        .env("LP_NUM_THREADS", std::env::var("LP_NUM_THREADS").unwrap_or_else(|_| "2".into()))
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or_else(|_| "/tmp".into()),
        )
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("xvfb-run starts");
    let start = Instant::now();
    loop {
        if child.try_wait().expect("the viewer can be waited on").is_some() {
            break;
        }
        if start.elapsed() > LIMIT {
            let _ = child.kill();
            let out = child.wait_with_output().expect("its output");
            panic!(
                "sshc view {} ran past {LIMIT:?}:\n{}{}",
                args.join(" "),
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    child.wait_with_output().expect("its output")
}

/// `sshc view TECHNIQUE --scene SCENE --size SIZE --shadow-map 256 --script S --log L`.
fn scripted(technique: &str, scene: &str, size: &str, script: &Path, log: &Path) -> (bool, String) {
    let (script, log) = (script.display().to_string(), log.display().to_string());
    view(&[
        technique,
        "--scene",
        scene,
        "--size",
        size,
        "--shadow-map",
        "256",
        "--script",
        &script,
        "--log",
        &log,
    ])
}

fn which(name: &str) -> Option<PathBuf> {
    std::env::var_os("PATH")?
        .to_str()?
        .split(':')
        .map(|d| Path::new(d).join(name))
        .find(|p| p.is_file())
}

/// The log's entries.
fn log(path: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect()
}

fn entries<'a>(log: &'a [serde_json::Value], event: &str) -> Vec<&'a serde_json::Value> {
    log.iter().filter(|e| e["event"] == event).collect()
}

fn png(path: &Path) -> image::RgbaImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8()
}

fn pfm(path: &Path) -> Vec<f32> {
    let mut f = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    pxm::PFM::read_from(&mut f)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .data
}

/// The number of distinct colours in an image below the panels' title bar (on a window this
/// small the panels start folded: a bar 24 points high at the top left).
fn colours_below_panels(img: &image::RgbaImage) -> usize {
    let mut seen = std::collections::HashSet::new();
    for y in 32.min(img.height())..img.height() {
        for x in 0..img.width() {
            seen.insert(img.get_pixel(x, y).0);
        }
    }
    seen.len()
}

/// The visibility a screenshot's log entry wrote (`pixels` of them), asserted equal to
/// `sshc render`'s with the command the entry gives (its `--out` in `dir`), bit for bit.
fn renders_as_logged(dir: &Path, shot: &serde_json::Value, pixels: usize) -> Vec<f32> {
    let (viewer, rendered) = render_logged(dir, shot);
    assert_eq!(viewer.len(), pixels);
    let same = viewer.iter().zip(&rendered).filter(|(a, b)| a.to_bits() == b.to_bits()).count();
    assert_eq!(
        same,
        viewer.len(),
        "{} of {} visibilities differ from `sshc render`'s",
        viewer.len() - same,
        viewer.len()
    );
    viewer
}

/// The visibility a screenshot's log entry wrote, and `sshc render`'s with the command the
/// entry gives (its `--out` in `dir`).
fn render_logged(dir: &Path, shot: &serde_json::Value) -> (Vec<f32>, Vec<f32>) {
    let command = shot["command"].as_str().expect("a command");
    let words = shell_words(command);
    assert_eq!(&words[..2], ["sshc", "render"]);
    let out_png = dir.join("render.png");
    let out_pfm = dir.join("render.pfm");
    let mut args: Vec<String> = words[1..].to_vec();
    let at = args.iter().position(|w| w == "--out").expect("--out");
    args[at + 1] = out_png.display().to_string();
    args.extend(["--visibility".to_string(), out_pfm.display().to_string()]);
    let r = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .args(&args)
        .current_dir(root())
        .output()
        .expect("sshc render runs");
    assert!(r.status.success(), "sshc render {args:?}:\n{}", String::from_utf8_lossy(&r.stderr));
    let viewer = pfm(Path::new(shot["visibility"].as_str().expect("a visibility file")));
    (viewer, pfm(&out_pfm))
}

fn write_script(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("script.ron");
    std::fs::write(&p, text).expect("the script is written");
    p
}

/// One scripted session of PCSS on the contact scene: the light moves, a param is set, every
/// view mode is shown. The screenshot after the light moved differs from the one before;
/// the visibility after `Set` is `sshc render`'s with the command the log gives, bit for
/// bit (the same graph, camera and light, the same arithmetic); every mode draws an image.
#[test]
fn a_scripted_session_moves_the_light_sets_a_param_and_matches_render_bit_for_bit() {
    let dir = temp_dir("session");
    let d = dir.display();
    let script = write_script(
        &dir,
        &format!(
            r#"[
    Wait(2),
    Screenshot("{d}/before.png"),
    MoveLight(light: 0, by: (1.2, 0.0, -0.6)),
    Wait(2),
    Screenshot("{d}/moved.png"),
    Set(name: "slope_bias", value: 2.5),
    Wait(2),
    Screenshot("{d}/set.png"),
    Show(Visibility),
    Wait(1),
    Screenshot("{d}/visibility.png"),
    Show(Texture(name: "shadow", layer: 0, level: 0, channel: 0, lo: 0.0, hi: 1.0, map: Viridis)),
    Wait(1),
    Screenshot("{d}/texture.png"),
]"#
        ),
    );
    let log_path = dir.join("log.jsonl");
    let (ok, out) = scripted("techniques/pcss.ron", "scenes/contact.ron", "160x120", &script, &log_path);
    assert!(ok, "sshc view failed:\n{out}");
    let log = log(&log_path);
    assert_eq!(entries(&log, "screenshot").len(), 5, "{log:?}");
    assert_eq!(entries(&log, "exit").len(), 1);
    let (before, moved) = (png(&dir.join("before.png")), png(&dir.join("moved.png")));
    assert_eq!((before.width(), before.height()), (160, 120));
    let differ = before.pixels().zip(moved.pixels()).filter(|(a, b)| a != b).count();
    assert!(differ > 100, "moving the light changed {differ} pixels");
    // the visibility after `Set`, and `sshc render` of the logged command
    let shot = entries(&log, "screenshot")[2];
    let command = shot["command"].as_str().expect("a command");
    assert!(
        command.contains("--set 'slope_bias=2.5'") || command.contains("--set slope_bias=2.5"),
        "{command}"
    );
    let viewer = renders_as_logged(&dir, shot, 160 * 120);
    // a penumbra: not every pixel lit or hidden
    assert!(viewer.iter().any(|v| *v > 0.05 && *v < 0.95));
    for mode in ["set", "visibility", "texture"] {
        let img = png(&dir.join(format!("{mode}.png")));
        assert!(
            colours_below_panels(&img) > 8,
            "{mode}: an image of {} colours",
            colours_below_panels(&img)
        );
    }
}

/// A file saved broken: the log has its diagnostic with file:line:column and the image
/// keeps the previous graph's; saved fixed with a new default, the new graph renders. A
/// fixed param set from the panels recompiles, and the scene file saved reloads.
#[test]
fn a_broken_save_logs_its_diagnostic_and_keeps_rendering_and_a_fixed_one_renders_anew() {
    let dir = temp_dir("reload");
    let technique = dir.join("pcss.ron");
    std::fs::copy(root().join("techniques/pcss.ron"), &technique).expect("the technique is copied");
    let scene = dir.join("contact.ron");
    // (the contact scene names no mesh file: its copy reads the same anywhere)
    std::fs::copy(root().join("scenes/contact.ron"), &scene).expect("the scene is copied");
    let t = technique.display();
    let s = scene.display();
    let d = dir.display();
    let script = write_script(
        &dir,
        &format!(
            r#"[
    Wait(1),
    Screenshot("{d}/first.png"),
    Edit(path: "{t}", from: "\"bias\": Param(", to: "\"bias\": Parm("),
    WaitCompiled,
    Screenshot("{d}/broken.png"),
    Edit(path: "{t}", from: "\"bias\": Parm(", to: "\"bias\": Param("),
    WaitCompiled,
    Edit(path: "{t}", from: "default: 0.0005", to: "default: 0.05"),
    WaitCompiled,
    Screenshot("{d}/fixed.png"),
    Set(name: "N", value: 2.0),
    WaitReady,
    Screenshot("{d}/n2.png"),
    Edit(path: "{s}", from: "radius: 0.35", to: "radius: 0.7"),
    WaitCompiled,
    Screenshot("{d}/scene.png"),
]"#
        ),
    );
    let log_path = dir.join("log.jsonl");
    let (ok, out) = scripted(technique.to_str().unwrap(), scene.to_str().unwrap(), "160x120", &script, &log_path);
    assert!(ok, "sshc view failed:\n{out}");
    let log = log(&log_path);
    let compiled = entries(&log, "compiled");
    let failed: Vec<_> = compiled.iter().filter(|e| e["ok"] == false).collect();
    assert_eq!(failed.len(), 1, "{compiled:?}");
    let diag = failed[0]["diagnostics"].as_str().unwrap_or_default();
    // file:line:column, as the terminal shows it
    let located = format!("{}:", technique.display());
    assert!(diag.contains(&located) && diag.contains("Parm"), "{diag}");
    let at = &diag[diag.find(&located).unwrap() + located.len()..];
    let (line, rest) = at.split_once(':').unwrap_or_else(|| panic!("{diag}"));
    let column: String = rest.chars().take_while(char::is_ascii_digit).collect();
    assert!(
        line.parse::<u32>().is_ok() && column.parse::<u32>().is_ok(),
        "no line:column after the path: {diag}"
    );
    assert!(compiled.iter().filter(|e| e["ok"] == true).count() >= 3, "{compiled:?}");
    let vis = |name: &str| pfm(&dir.join(format!("{name}.visibility.pfm")));
    assert_eq!(vis("first"), vis("broken"), "the broken save changed the image");
    let (first, fixed) = (vis("first"), vis("fixed"));
    let moved = first.iter().zip(&fixed).filter(|(a, b)| a != b).count();
    assert!(moved > 0, "the fixed save's bias of 0.05 changed no visibility");
    // a fixed param recompiles (the log has its compilation) and changes the image; the
    // scene file saved with a larger light reloads and widens the penumbra
    assert!(compiled.iter().filter(|e| e["ok"] == true).count() >= 4, "{compiled:?}");
    assert_ne!(vis("fixed"), vis("n2"), "N = 2 changed nothing");
    let penumbra = |v: &[f32]| v.iter().filter(|x| **x > 0.02 && **x < 0.98).count();
    let (before, after) = (penumbra(&vis("n2")), penumbra(&vis("scene")));
    assert!(
        after > before,
        "the light's radius 0.35 -> 0.7 gave {before} -> {after} penumbra pixels"
    );
    let shots = entries(&log, "screenshot");
    let last = &shots[shots.len() - 1]["state"]["lights"][0]["Sphere"]["radius"];
    assert_eq!(last.as_f64(), Some(0.7f32 as f64), "{last}");
}

/// Without a display the viewer says how to get one; `--frames` with `--screenshot` writes
/// the window after N frames and exits; without `--scene` it opens the bundled bunny scene
/// (the researcher's walkthrough of issue 51 found `--scene` required).
#[test]
fn without_a_display_the_viewer_says_how_to_get_one_and_frames_end_a_run() {
    let out = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .args(["view", "techniques/hard.ron", "--scene", "scenes/contact.ron"])
        .current_dir(root())
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("sshc runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("xvfb-run") && err.contains("apt-get install -y xvfb xauth"),
        "{err}"
    );
    let dir = temp_dir("frames");
    let shot = dir.join("shot.png");
    let (ok, out) = view(&[
        "techniques/hard.ron",
        "--size",
        "96x64",
        "--frames",
        "3",
        "--screenshot",
        shot.to_str().unwrap(),
    ]);
    assert!(ok, "{out}");
    let img = png(&shot);
    assert_eq!((img.width(), img.height()), (96, 64));
    assert!(colours_below_panels(&img) > 4);
}

/// Issue 51: `--frames N --screenshot` on a technique that does not compile exits with a
/// failing status and prints the diagnostic (file:line:column) on standard error, not only
/// in the window: a script can tell.
#[test]
fn frames_on_a_technique_that_does_not_compile_fail_with_the_diagnostic_on_stderr() {
    let dir = temp_dir("frames-broken");
    let technique = dir.join("broken.ron");
    let source = std::fs::read_to_string(root().join("techniques/pcss.ron")).expect("pcss.ron reads");
    assert!(source.contains("\"bias\": Param("));
    std::fs::write(&technique, source.replace("\"bias\": Param(", "\"bias\": Parm(")).expect("written");
    let shot = dir.join("shot.png");
    let out = view_output(&[
        technique.to_str().unwrap(),
        "--scene",
        "scenes/contact.ron",
        "--size",
        "96x64",
        "--frames",
        "3",
        "--screenshot",
        shot.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "exited 0 on a technique that does not compile:\n{stderr}");
    // the window (with its diagnostics) is still written, as asked
    assert!(shot.is_file(), "no screenshot written:\n{stderr}");
    let located = format!("{}:", technique.display());
    assert!(stderr.contains(&located) && stderr.contains("Parm"), "{stderr}");
    let at = &stderr[stderr.find(&located).unwrap() + located.len()..];
    let (line, rest) = at.split_once(':').unwrap_or_else(|| panic!("{stderr}"));
    let column: String = rest.chars().take_while(char::is_ascii_digit).collect();
    assert!(
        line.parse::<u32>().is_ok() && column.parse::<u32>().is_ok(),
        "no line:column after the path: {stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Splits a command line as a POSIX shell does for the quoting `ViewState::command` writes
/// (single quotes, and `'\''` for a quote inside them).
fn shell_words(s: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut word = String::new();
    let mut in_word = false;
    let mut chars = s.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\'' => {
                in_word = true;
                for q in chars.by_ref() {
                    if q == '\'' {
                        break;
                    }
                    word.push(q);
                }
            }
            '\\' => {
                in_word = true;
                if let Some(n) = chars.next() {
                    word.push(n);
                }
            }
            ' ' => {
                if in_word {
                    words.push(std::mem::take(&mut word));
                    in_word = false;
                }
            }
            c => {
                in_word = true;
                word.push(c);
            }
        }
    }
    if in_word {
        words.push(word);
    }
    words
}

/// The truth refines while the view stands still (its standard error falls as rounds are
/// added) and starts over when the light moves; the error view and the RMS come with it.
#[test]
fn the_truth_refines_while_the_view_stands_still_and_starts_over_when_the_light_moves() {
    let dir = temp_dir("truth");
    let d = dir.display();
    let script = write_script(
        &dir,
        &format!(
            r#"[
    Show(Error(range: 0.25)),
    WaitTruth(4),
    Screenshot("{d}/error.png"),
    MoveLight(light: 0, by: (0.5, 0.0, 0.0)),
    WaitTruth(1),
    Show(StdError(range: 0.05)),
    Wait(1),
    Screenshot("{d}/std-error.png"),
]"#
        ),
    );
    let log_path = dir.join("log.jsonl");
    let (ok, out) = scripted("techniques/pcss.ron", "scenes/contact.ron", "96x72", &script, &log_path);
    assert!(ok, "sshc view failed:\n{out}");
    let log = log(&log_path);
    let truth = entries(&log, "truth");
    let rounds: Vec<u64> = truth.iter().map(|e| e["rounds"].as_u64().unwrap()).collect();
    // rounds rising to at least 4 (WaitTruth(4) waits for the fourth; the truth's thread
    // goes on refining while the screenshot is taken), then the moved light's first. Each
    // frame shows the newest estimate (`Refiner::poll`), so rounds that end within one
    // frame are logged once, the newest: the rounds rise, not necessarily by one.
    let restart = rounds
        .windows(2)
        .position(|w| w[1] < w[0])
        .expect("the truth starts over after the light moved");
    assert!(rounds[..restart + 1].windows(2).all(|w| w[0] < w[1]), "{rounds:?}");
    assert!(rounds[0] <= 2 && rounds[restart] >= 4, "{rounds:?}");
    assert!(rounds[restart + 1] <= 2, "{rounds:?}");
    let se = |i: usize| truth[i]["mean_std_error"].as_f64().unwrap();
    // the mean of at least twice the rounds has at most 1 / sqrt(2) of the standard error;
    // the estimates of the spread are themselves noisy, so only the direction is asserted
    assert!(
        se(restart) < se(0),
        "standard error {} after {} round(s), {} after {}",
        se(0),
        rounds[0],
        se(restart),
        rounds[restart]
    );
    let rms = truth[restart]["rms"].as_f64().unwrap();
    assert!(rms.is_finite() && rms > 0.0 && rms < 0.5, "RMS {rms}");
    for name in ["error", "std-error"] {
        let img = png(&dir.join(format!("{name}.png")));
        assert!(colours_below_panels(&img) > 8, "{name}: {} colours", colours_below_panels(&img));
    }
}

/// A split view shows the main technique on the left half and the second on the right, at
/// the same pixels as each alone.
#[test]
fn a_split_view_shows_each_half_as_its_technique_alone() {
    let dir = temp_dir("split");
    let d = dir.display();
    let script = write_script(
        &dir,
        &format!(
            r#"[
    Wait(20),
    Screenshot("{d}/pcss.png"),
    Split(Some((technique: "techniques/hard.ron"))),
    WaitReady,
    Screenshot("{d}/split.png"),
    Split(None),
    Technique("techniques/hard.ron"),
    WaitReady,
    Screenshot("{d}/hard.png"),
]"#
        ),
    );
    let log_path = dir.join("log.jsonl");
    let (ok, out) = scripted("techniques/pcss.ron", "scenes/contact.ron", "320x120", &script, &log_path);
    assert!(ok, "sshc view failed:\n{out}");
    let (pcss, split, hard) = (png(&dir.join("pcss.png")), png(&dir.join("split.png")), png(&dir.join("hard.png")));
    // (the folded panels and their shadow fade in over the first frames: the first
    // screenshot waits for that)
    let half = |img: &image::RgbaImage, right: bool| -> Vec<[u8; 4]> {
        let xs = if right { 160..320 } else { 0..160 };
        (0..120)
            .flat_map(|y| xs.clone().map(move |x| (x, y)))
            .map(|(x, y)| img.get_pixel(x, y).0)
            .collect()
    };
    assert!(half(&split, false) == half(&pcss, false), "the left half is not PCSS's");
    assert!(
        half(&split, true) == half(&hard, true),
        "the right half is not the hard shadow map's"
    );
    assert!(
        half(&pcss, true) != half(&hard, true),
        "PCSS and hard shadows look the same here: the test shows nothing"
    );
    let shot = entries(&log(&log_path), "screenshot")[1].clone();
    assert!(
        shot["split_command"].as_str().is_some_and(|c| c.contains("techniques/hard.ron")),
        "{shot}"
    );
}

/// A viewer run: its scene, its techniques in order, the `--set` of the first.
type Run = (&'static str, &'static [&'static str], &'static [(&'static str, &'static str)]);

/// Every texture of a technique's graph (the moments, the limits, the skins of every light
/// sample's layer, a mip level, a summed-area table) draws into the window: the centre of the window shows the
/// texture, not the background the viewer clears to where it has nothing to draw.
#[test]
fn every_texture_of_a_graph_draws_an_image() {
    let dir = temp_dir("textures");
    // (scene, techniques, `--set` of the first): CSSM's filter 1 takes summed-area tables,
    // storage buffers the viewer reads back to show
    // the example's debug outputs (the viewer compiles them in): camera-sized textures
    let runs: [Run; 4] = [
        ("contact", &["vsm", "msm", "cssm", "penumbra-limit-maps", "smoothies"], &[]),
        ("contact", &["cssm"], &[("filter", "1")]),
        ("linear", &["linear-light"], &[]),
        ("contact", &["examples/vssm-subdivided"], &[]),
    ];
    for (scene, techniques, set) in runs {
        let mut steps = String::from("[\n");
        let mut shots = Vec::new();
        for (i, t) in techniques.iter().enumerate() {
            let path = root().join(format!("techniques/{t}.ron"));
            let source = std::fs::read_to_string(&path).expect("the technique reads");
            let options = sshc::CompileOptions {
                set: if i == 0 {
                    set.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
                } else {
                    vec![]
                },
                debug: true,
                ..Default::default()
            };
            let graph = sshc::compile_str(&source, &options).expect("it compiles").graph;
            if !options.set.is_empty() {
                assert!(
                    graph.textures.iter().any(|t| t.format.is_table()),
                    "{t} with {set:?} has no summed-area table: the run shows none"
                );
            }
            if i > 0 {
                steps.push_str(&format!("    Technique(\"techniques/{t}.ron\"),\n"));
            }
            steps.push_str("    WaitReady,\n");
            for tex in &graph.textures {
                let shot = dir.join(format!("{}-{}{}.png", t.replace('/', "-"), tex.name, set.len()));
                let level = u32::from(tex.mips);
                steps.push_str(&format!(
                    "    Show(Texture(name: \"{}\", layer: {}, level: {level}, channel: 0, lo: 0.0, hi: 1.0, map: Viridis)),\n    Wait(1),\n    Screenshot(\"{}\"),\n",
                    tex.name,
                    tex.array_layers() - 1,
                    shot.display()
                ));
                shots.push(shot);
            }
        }
        steps.push(']');
        let script = write_script(&dir, &steps);
        let mut args = vec![
            format!("techniques/{}.ron", techniques[0]),
            "--scene".into(),
            format!("scenes/{scene}.ron"),
            "--size".into(),
            "96x96".into(),
            "--shadow-map".into(),
            "128".into(),
            "--script".into(),
            script.display().to_string(),
        ];
        for (k, v) in set {
            args.extend(["--set".to_string(), format!("{k}={v}")]);
        }
        let (ok, out) = view(&args.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(ok, "sshc view failed:\n{out}");
        assert!(shots.len() >= techniques.len(), "{shots:?}");
        let debug = shots.iter().filter(|s| s.to_string_lossy().contains("-debug_")).count();
        assert_eq!(debug, if techniques[0].starts_with("examples/") { 2 } else { 0 }, "{shots:?}");
        for shot in shots {
            let img = png(&shot);
            // the clear colour: (0.02, 0.02, 0.03) in unorm8
            let background = [5u8, 5, 8, 255];
            let centre: Vec<[u8; 4]> = (40..56)
                .flat_map(|y| (40..56).map(move |x| (x, y)))
                .map(|(x, y)| img.get_pixel(x, y).0)
                .collect();
            let drawn = centre.iter().filter(|p| **p != background).count();
            assert!(
                drawn == centre.len(),
                "{}: {drawn} of {} centre pixels drawn",
                shot.display(),
                centre.len()
            );
        }
    }
}

/// Cascades in the viewer (`--cascades 3`): the `cascades` view draws each pixel's cascade
/// through viridis, the nearest dark blue, the middle teal, the farthest yellow (an even
/// split, lambda 0.5, so each holds a band of the floor at this size); the camera
/// orbits and the cascades are refitted in place, and the visibility then is `sshc render`'s
/// with the logged command (its `--cascades 3` included), bit for bit: the in-place refit
/// is a fresh binding of the moved camera's cascades.
#[test]
fn the_viewer_draws_the_cascades_and_refits_them_as_the_camera_moves() {
    let dir = temp_dir("cascades");
    let d = dir.display();
    let scene = dir.join("sun.ron");
    std::fs::write(
        &scene,
        "Scene(camera: Perspective(position: (0.0, 1.5, 9.0), target: (0.0, 0.0, -4.0), fov_y_degrees: 55.0, width: 96, height: 72),
        shadow_map: 256, lights: [DistantDisk(direction: (0.5, 0.8, 0.3), angle_degrees: 2.0)],
        objects: [Object(mesh: Plane(size: (30.0, 30.0)), casts: false),
                  Object(mesh: Box(size: (1.0, 1.0, 1.0)), transform: (translate: (1.5, 0.5, 4.0))),
                  Object(mesh: Box(size: (2.0, 3.0, 2.0)), transform: (translate: (-2.0, 1.5, -6.0)))])",
    )
    .expect("the scene is written");
    let script = write_script(
        &dir,
        &format!(
            r#"[
    Show(Cascades),
    Wait(2),
    Screenshot("{d}/cascades.png"),
    Orbit(yaw: 15.0, pitch: 5.0),
    Show(Visibility),
    Wait(2),
    Screenshot("{d}/moved.png"),
]"#
        ),
    );
    let log_path = dir.join("log.jsonl");
    let (script, log_arg, scene) = (
        script.display().to_string(),
        log_path.display().to_string(),
        scene.display().to_string(),
    );
    let (ok, out) = view(&[
        "techniques/pcf.ron",
        "--scene",
        &scene,
        "--size",
        "160x120",
        "--cascades",
        "3",
        "--cascade-lambda",
        "0.5",
        "--cascade-band",
        "0.2",
        "--script",
        &script,
        "--log",
        &log_arg,
    ]);
    assert!(ok, "sshc view failed:\n{out}");
    let log = log(&log_path);
    let shots = entries(&log, "screenshot");
    assert_eq!(shots.len(), 2, "{log:?}");
    // viridis at 0, 1/2 and 1, below the panels' bar: each cascade holds pixels
    let img = png(&dir.join("cascades.png"));
    let count = |f: &dyn Fn([u8; 4]) -> bool| {
        (32..img.height())
            .flat_map(|y| (0..img.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| f(img.get_pixel(x, y).0))
            .count()
    };
    let near = count(&|[r, g, b, _]| r < 100 && g < 60 && b > 60);
    let middle = count(&|[r, g, b, _]| r < 80 && (110..180).contains(&g) && (100..170).contains(&b));
    let far = count(&|[r, g, b, _]| r > 180 && g > 180 && b < 110);
    assert!(
        near > 50 && middle > 50 && far > 50,
        "cascade pixels: {near} near, {middle} middle, {far} far"
    );
    assert!(
        shots[1]["command"].as_str().unwrap_or_default().contains("--cascades 3"),
        "{}",
        shots[1]["command"]
    );
    let viewer = renders_as_logged(&dir, shots[1], 160 * 120);
    assert!(viewer.iter().any(|v| *v < 0.5), "no shadow in view");
}

/// Issue 48, item 16: a `WaitCompiled` with nothing to compile never ended, and a texture
/// the graph has not was shown as nothing: the first fails after `--wait-limit` seconds
/// saying what it waited for, the second at once, naming the graph's textures.
#[test]
fn a_wait_for_nothing_ends_and_an_unknown_texture_is_named() {
    let dir = temp_dir("waits");
    let log = dir.join("log.jsonl");
    let run = |script: &str, limit: &str| {
        let script = write_script(&dir, script);
        let (script, logp) = (script.display().to_string(), log.display().to_string());
        view(&[
            "techniques/vsm.ron",
            "--scene",
            "scenes/contact.ron",
            "--size",
            "64x64",
            "--shadow-map",
            "128",
            "--script",
            &script,
            "--log",
            &logp,
            "--wait-limit",
            limit,
        ])
    };
    let start = Instant::now();
    let (ok, text) = run("[WaitReady, WaitCompiled]", "2");
    assert!(
        !ok && text.contains("waited 2 s (--wait-limit) for WaitCompiled: a compilation's answer"),
        "{text}"
    );
    assert!(start.elapsed() < Duration::from_secs(60), "took {:?}", start.elapsed());
    let (ok, text) = run(
        "[WaitReady, Show(Texture(name: \"no-such\", layer: 0, level: 0, channel: 0, lo: 0.0, hi: 1.0, map: Viridis))]",
        "60",
    );
    assert!(
        !ok && text.contains("the graph has no texture `no-such`; it has ") && text.contains("moments"),
        "{text}"
    );
    let (ok, text) = run("[LightSize(light: 0, size: NaN)]", "60");
    assert!(
        !ok && text.contains("event 0") && text.contains("a light's size is a finite number >= 0"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// Issue 51's viewer: a script folds the panels away (`Panels(false)`), a debug output's
/// background (NaN where the camera sees no surface) shows magenta as docs/viewer.md says
/// (it showed viridis(0), dark purple: `x != x` is no NaN test in WGSL), a channel is
/// shown by its name (`ShowChannel`) exactly as by its texture and component, and the
/// logarithmic map draws another image than the linear one.
#[test]
fn panels_fold_away_nan_shows_magenta_and_a_channel_is_shown_by_name() {
    let dir = temp_dir("panels");
    let technique = "techniques/examples/vssm-subdivided.ron";
    let source = std::fs::read_to_string(root().join(technique)).expect("the technique reads");
    let options = sshc::CompileOptions {
        debug: true,
        ..Default::default()
    };
    let graph = sshc::compile_str(&source, &options).expect("it compiles").graph;
    let debug = graph
        .textures
        .iter()
        .find(|t| t.name.starts_with("debug_"))
        .expect("a debug output");
    let (texture, channel) = graph
        .textures
        .iter()
        .filter(|t| !t.name.starts_with("debug_") && !t.format.is_table())
        .find_map(|t| t.channels.first().map(|c| (t, c)))
        .expect("a channel in a texture");
    let shot = |name: &str| dir.join(format!("{name}.png"));
    let texture_show = |map: &str, lo: f32| {
        format!(
            "Show(Texture(name: \"{}\", layer: {}, level: 0, channel: {}, lo: {lo:?}, hi: 1.0, map: {map}))",
            texture.name, channel.layer, channel.component
        )
    };
    let script = write_script(
        &dir,
        &format!(
            "[
    WaitReady,
    Show(Texture(name: \"{debug}\", layer: 0, level: 0, channel: 0, lo: 0.0, hi: 1.0, map: Viridis)), Wait(1), Screenshot({with_panels:?}),
    Panels(false), Wait(1), Screenshot({alone:?}),
    ShowChannel(name: \"{channel}\", level: 0, lo: 0.001, hi: 1.0, map: Viridis), Wait(1), Screenshot({by_name:?}),
    {by_number_show}, Wait(1), Screenshot({by_number:?}),
    {log_show}, Wait(1), Screenshot({log:?}),
]",
            debug = debug.name,
            with_panels = shot("with-panels"),
            alone = shot("alone"),
            channel = channel.name,
            by_name = shot("by-name"),
            by_number_show = texture_show("Viridis", 0.001),
            by_number = shot("by-number"),
            log_show = texture_show("LogViridis", 0.001),
            log = shot("log"),
        ),
    );
    let (ok, out) = scripted(technique, "scenes/bunny.ron", "96x96", &script, &dir.join("log.jsonl"));
    assert!(ok, "sshc view failed:\n{out}");
    let magenta = [255u8, 0, 255, 255];
    let alone = png(&shot("alone"));
    let with_panels = png(&shot("with-panels"));
    let count = |img: &image::RgbaImage| img.pixels().filter(|p| p.0 == magenta).count();
    // the bunny's camera sees the background above it: NaN in every debug output there
    assert!(
        count(&alone) > 500,
        "{} magenta pixels where the camera sees no surface",
        count(&alone)
    );
    assert_eq!(
        alone.get_pixel(2, 2).0,
        magenta,
        "the top-left corner, background, without the panels"
    );
    assert_ne!(
        with_panels.get_pixel(2, 2).0,
        magenta,
        "the panels' title bar covers the top-left corner when they are drawn"
    );
    let differ = alone.pixels().zip(with_panels.pixels()).filter(|(a, b)| a != b).count();
    assert!(differ > 100, "folding the panels changed {differ} pixels");
    let (by_name, by_number, log) = (png(&shot("by-name")), png(&shot("by-number")), png(&shot("log")));
    assert!(
        by_name == by_number,
        "channel `{}` by name differs from {} channel {}",
        channel.name,
        texture.name,
        channel.component
    );
    let changed = log.pixels().zip(by_number.pixels()).filter(|(a, b)| a != b).count();
    assert!(changed > 100, "the logarithmic map changed {changed} pixels of the linear one");
}
