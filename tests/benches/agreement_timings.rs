//! The agreement timings: GPU time of the generated passes after Depth against the hand-written ones, in the same
//! process on the same inputs.
//!
//! The generated Shade pass is a render pass over the scene seen from the camera that also
//! writes the camera's position, normal and colour images; the hand-written shade is a
//! compute pass over a list of shading points. So that the comparison is of the code each
//! side writes and not of that fixed cost, every round also times a baseline: the same
//! graph with the visibility expression replaced (the pass, its rasterisation and
//! its outputs, and the receiver's inputs `uv`, `d` and `depth_slope` kept live by a
//! visibility `saturate(d + depth_slope + uv.x + uv.y)` that reads no resource: what the
//! hand-written side is handed in its query buffer); a technique's own time is its time
//! minus the baseline's.
//!
//! The hand-written passes are timed in two parts. On lavapipe the end timestamp of a
//! compute pass does not wait for its last dispatch, the Shade dispatch (measured: the
//! hand-written PCSS reads 0.15 ms by its timestamps against 110 ms of wall time; neither a
//! barrier behind it nor a second pass carrying the timestamp made it wait). So the
//! timestamps give the passes before Shade, and the Shade dispatch's own cost is the wall
//! time with it dispatched three times less the wall time with it dispatched once, halved:
//! every fixed cost (upload, submission, read-back, the passes before it) cancels.
//!
//! `ROUNDS` rounds, each timing `FRAMES` frames (medians) of the baseline, the generated and
//! the hand-written passes in turn, so that drifts of the machine hit all three. Reported:
//! medians over rounds, the ratio generated-own / hand-written, and the noise bound: the
//! run-to-run spread (max - min over rounds) of the three, added, in milliseconds. The
//! generated code is slower only when its own time exceeds the hand-written by more than
//! that. Prints the table and writes it to `target/agreement/times.md` (quoted in
//! docs/agreement.md); exits with status 1 when a technique is slower beyond the noise.
//! A measurement, minutes on lavapipe: `cargo bench -p sshc-tests --bench
//! agreement_timings`. The test suite only builds it (`cargo clippy --all-targets`).

#[path = "../tests/support/mod.rs"]
mod support;

use sshc_tests::reference::{DepthMap, GpuReference, Query};
use support::variant::Variant;
use support::{QueryPlane, compile_source, gpu, run_inputs, scene_depth, technique_source};

fn main() {
    const SHADOW: u32 = 256;
    const CAMERA: u32 = 512;
    const ROUNDS: usize = 5;
    const FRAMES: usize = 7;
    let hand = GpuReference::new(gpu()).unwrap_or_else(|e| panic!("{e}"));
    let plane = QueryPlane {
        shadow: SHADOW,
        camera: CAMERA,
    };
    let z = scene_depth("bunny", SHADOW);
    let map = DepthMap {
        size: SHADOW,
        z: z.clone(),
    };
    let variants = [
        Variant::new("hard", &[], None),
        Variant::new("pcf", &[("N", 3.0)], None),
        Variant::new("vsm", &[], None),
        Variant::new("esm", &[], None),
        Variant::new("csm", &[], None),
        Variant::new("cssm", &[("filter", 0.0)], None).lit(0.2),
        Variant::new("cssm", &[("filter", 1.0)], None).lit(0.2),
        Variant::new("pcss", &[], None).lit(0.2),
    ];
    let median = |v: &[f64]| {
        let mut s = v.to_vec();
        s.sort_by(f64::total_cmp);
        s[s.len() / 2]
    };
    let range = |v: &[f64]| v.iter().copied().fold(f64::MIN, f64::max) - v.iter().copied().fold(f64::MAX, f64::min);
    let time_generated = |c: &sshc::Compiled, v: &Variant| {
        run_inputs(c, &v.inputs(&plane), &z, &[], FRAMES + 1)
            .ms_after_depth
            .unwrap_or_else(|| panic!("the device gives no timestamps"))
    };
    let mut md = format!(
        "Device: {}. Bunny depth map {SHADOW} x {SHADOW}, {CAMERA} x {CAMERA} shading points; {ROUNDS} rounds of {FRAMES} frames each; times in ms, medians over rounds.\n\n| technique | generated | baseline | generated own | hand-written before Shade (timestamps) | hand-written Shade (wall difference) | hand-written | own / hand | noise bound (ms) | own - hand (ms) | verdict |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
        gpu().describe()
    );
    let mut slower = Vec::new();
    for v in &variants {
        let compiled = v.compiled();
        // the baseline: the same technique, a visibility that reads no resource
        let src = technique_source(v.technique);
        let (a, b) = (src.find("visibility: \"").unwrap() + 13, src.rfind("\"),").unwrap());
        let base_src = format!("{}saturate(d + depth_slope + uv.x + uv.y){}", &src[..a], &src[b..]);
        let baseline = compile_source(&format!("{} baseline", v.technique), &base_src, &[], &[]);
        let t = v.reference();
        // the shading points of the generated run, projected, are the hand-written queries
        let first = run_inputs(&compiled, &v.inputs(&plane), &z, &[], 1);
        let queries: Vec<Query> = first
            .positions
            .iter()
            .filter(|p| p.iter().all(|c| c.is_finite()))
            .map(|p| {
                let (uv, d) = plane.project(*p);
                Query {
                    uv: [uv[0] as f32, uv[1] as f32],
                    d: d as f32,
                    lod: plane.lod().max(0.0),
                }
            })
            .collect();
        let (mut generated, mut base, mut own) = (Vec::new(), Vec::new(), Vec::new());
        let (mut stamped, mut shade, mut hw) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..ROUNDS {
            let b = time_generated(&baseline, v);
            let g = time_generated(&compiled, v);
            // (timestamp ms, wall ms) of the hand-written passes with the Shade dispatch
            // run `repeats` times
            let hand_run = |repeats: u32| -> (Vec<f64>, Vec<f64>) {
                (0..FRAMES)
                    .map(|_| {
                        let (_, stamp, wall) = hand
                            .visibility_repeated(&t, &map, &queries, repeats)
                            .unwrap_or_else(|e| panic!("{e}"));
                        (stamp / 1e6, wall / 1e6)
                    })
                    .unzip()
            };
            let (stamps, wall1) = hand_run(1);
            let (_, wall3) = hand_run(3);
            let s = median(&stamps);
            let d = (median(&wall3) - median(&wall1)) / 2.0;
            generated.push(g);
            base.push(b);
            own.push(g - b);
            stamped.push(s);
            shade.push(d);
            hw.push(s + d);
        }
        let (g, b, o, h) = (median(&generated), median(&base), median(&own), median(&hw));
        let noise = range(&generated) + range(&base) + range(&hw);
        let ok = o - h <= noise;
        if !ok {
            slower.push(v.label());
        }
        md.push_str(&format!(
            "| {} | {g:.3} | {b:.3} | {o:.3} | {:.3} | {:.3} | {h:.3} | {:.2} | {noise:.3} | {:.3} | {} |\n",
            v.label(),
            median(&stamped),
            median(&shade),
            o / h,
            o - h,
            if ok { "within noise" } else { "slower" }
        ));
        eprintln!("{}: own {o:.3} ms, hand-written {h:.3} ms, noise {noise:.3} ms", v.label());
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/agreement");
    let _ = std::fs::create_dir_all(&dir);
    let _ = std::fs::write(dir.join("times.md"), &md);
    println!("{md}");
    if !slower.is_empty() {
        eprintln!("generated shaders slower beyond the noise: {slower:?}");
        std::process::exit(1);
    }
}
