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
//! medians over rounds and the ratio generated-own / hand-written. The verdict is taken on
//! the rounds' paired differences e = (generated - baseline) - hand-written, in which a
//! drift common to the three cancels: with 9 rounds the 2nd and 8th smallest of them bound
//! their median with 96 % confidence (a binomial order-statistic interval: 1 - 2 x 10/512),
//! and the generated code is *slower* when the whole interval lies above 0 (8 of 9 rounds
//! slower), *faster* when it lies below 0, and *within noise* otherwise; the noise bound
//! printed is the interval's half-width. A control row checks that the verdict can fail:
//! PCF with N = 5 (121 taps) generated against the hand-written hard shadow map (one tap)
//! must read slower, or the run fails. Prints the table and writes it to `target/agreement/times.md`
//! (quoted in docs/agreement.md); exits with status 1 when a technique is slower or the
//! control is not. A measurement, minutes on lavapipe: `cargo bench -p sshc-tests --bench
//! agreement_timings`; sizes from the environment, `SSHC_TIMINGS_SHADOW` (map, default 256)
//! and `SSHC_TIMINGS_CAMERA` (shading points on a side, default 512), so that a GPU can be
//! given sizes it takes long enough to time. The test suite only builds it (`cargo clippy
//! --all-targets`).

#[path = "../tests/support/mod.rs"]
mod support;

use sshc_tests::reference::{DepthMap, GpuReference, Query};
use support::variant::Variant;
use support::{QueryPlane, compile_source, gpu, run_inputs, scene_depth, technique_source};

/// A size from the environment, or its default.
fn size(var: &str, default: u32) -> u32 {
    match std::env::var(var) {
        Ok(v) => v
            .parse()
            .ok()
            .filter(|n| (1..=8192).contains(n))
            .unwrap_or_else(|| panic!("{var}={v}: a size from 1 to 8192")),
        Err(_) => default,
    }
}

/// Rounds, and the order statistics of their paired differences that bound the median:
/// P(2nd smallest <= median <= 8th smallest) = 1 - 2 P(Bin(9, 1/2) <= 1) = 1 - 20/512.
const ROUNDS: usize = 9;
const LOW: usize = 1;
const HIGH: usize = 7;

fn main() {
    let (shadow, camera) = (size("SSHC_TIMINGS_SHADOW", 256), size("SSHC_TIMINGS_CAMERA", 512));
    const FRAMES: usize = 7;
    let hand = GpuReference::new(gpu()).unwrap_or_else(|e| panic!("{e}"));
    let plane = QueryPlane::new(shadow, camera);
    let z = scene_depth("bunny", shadow);
    let map = DepthMap {
        size: shadow,
        z: z.clone(),
    };
    let variants = [
        Variant::new("hard", &[], None),
        Variant::new("pcf", &[("N", 3.0)], None),
        Variant::new("vsm", &[], None),
        Variant::new("esm", &[], None),
        Variant::new("evsm", &[], None),
        Variant::new("msm", &[], None),
        Variant::new("csm", &[], None),
        Variant::new("cssm", &[("filter", 0.0)], None).lit(0.2),
        Variant::new("cssm", &[("filter", 1.0)], None).lit(0.2),
        Variant::new("pcss", &[], None).lit(0.2),
    ];
    // the control: 121 generated taps against one hand-written (on lavapipe the hand-written
    // compute passes cost more per point than the generated fragments, PCF N = 3 12.9 ms
    // against 5.2, so the control's gap must be wide on every device)
    let control = (Variant::new("pcf", &[("N", 5.0)], None), Variant::new("hard", &[], None));
    let runs: Vec<(Variant, Variant, bool)> = variants
        .iter()
        .map(|v| (v.clone(), v.clone(), false))
        .chain([(control.0, control.1, true)])
        .collect();
    let median = |v: &[f64]| {
        let mut s = v.to_vec();
        s.sort_by(f64::total_cmp);
        s[s.len() / 2]
    };
    let time_generated = |c: &sshc::Compiled, v: &Variant| {
        run_inputs(c, &v.inputs(&plane), &z, &[], FRAMES + 1)
            .ms_after_depth
            .unwrap_or_else(|| panic!("the device gives no timestamps"))
    };
    let mut md = format!(
        "Device: {}. Bunny depth map {shadow} x {shadow}, {camera} x {camera} shading points; {ROUNDS} rounds of {FRAMES} frames each; times in ms, medians over rounds; own - hand: the median of the rounds' paired differences and its 96 % interval (2nd and 8th of 9).\n\n| technique | generated | baseline | generated own | hand-written before Shade (timestamps) | hand-written Shade (wall difference) | hand-written | own / hand | own - hand (ms) | 96 % interval (ms) | noise bound (ms) | verdict |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        gpu().describe()
    );
    let mut slower = Vec::new();
    for (v, hand_v, is_control) in &runs {
        let compiled = v.compiled();
        // the baseline: the same technique, a visibility that reads no resource
        let src = technique_source(v.technique);
        let (a, b) = (src.find("visibility: \"").unwrap() + 13, src.rfind("\"),").unwrap());
        let base_src = format!("{}saturate(d + depth_slope + uv.x + uv.y){}", &src[..a], &src[b..]);
        let baseline = compile_source(&format!("{} baseline", v.technique), &base_src, &[], &[]);
        let t = hand_v.reference();
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
        // paired by round: a drift common to the round cancels
        let mut e: Vec<f64> = own.iter().zip(&hw).map(|(o, h)| o - h).collect();
        e.sort_by(f64::total_cmp);
        let (lo, hi) = (e[LOW], e[HIGH]);
        let noise = (hi - lo) / 2.0;
        let verdict = if lo > 0.0 {
            "slower"
        } else if hi < 0.0 {
            "faster"
        } else {
            "within noise"
        };
        let label = if *is_control {
            format!("control: {} against hand-written {}", v.label(), hand_v.label())
        } else {
            v.label()
        };
        if (verdict == "slower") != *is_control {
            slower.push(label.clone());
        }
        md.push_str(&format!(
            "| {label} | {g:.3} | {b:.3} | {o:.3} | {:.3} | {:.3} | {h:.3} | {:.2} | {:.3} | [{lo:.3}, {hi:.3}] | {noise:.3} | {verdict} |\n",
            median(&stamped),
            median(&shade),
            o / h,
            median(&e),
        ));
        eprintln!("{label}: own {o:.3} ms, hand-written {h:.3} ms, own - hand in [{lo:.3}, {hi:.3}]: {verdict}");
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/agreement");
    let _ = std::fs::create_dir_all(&dir);
    let _ = std::fs::write(dir.join("times.md"), &md);
    println!("{md}");
    if !slower.is_empty() {
        eprintln!("generated shaders slower beyond the noise, or a control the verdict did not catch: {slower:?}");
        std::process::exit(1);
    }
}
