//! Generated against hand-written: every technique's shaders as sshc generates them, the
//! hand-written WGSL of `sshc_tests::reference` and its f64 CPU evaluator, on identical
//! inputs: synthetic depth fields (ramps, steps, checkerboards, noise, the extremes 0 and 1)
//! and depth maps rendered from the bundled scenes, fed to the passes after Depth (the
//! runtime's depth override), read at the shading points of the query plane (a receiver
//! whose depth runs across [0, 1]; see `support::QueryPlane`).
//!
//! Both GPU results must lie in the interval the error model of
//! `sshc_tests::reference::tolerance` allows about the CPU value, per query: storage
//! rounding at the precision under test, sin/cos 2^-11, exp 3 + 2|x| ulp, 8-bit filtering
//! weights, f32 arithmetic (the list is at the top of that module). Binary tests at exact
//! ties (the result changes when d or uv moves by 2^-22) are skipped and counted.
//!
//! Two cameras: 2N pixels over the N-texel map (implicit level of detail -1: the base
//! level, sampled a quarter texel from texel centres) and N/2 (level of detail 1: level 1
//! at its texel centres, level 0 half way between texels). Fractional implicit levels of
//! detail are not compared pointwise: the hardware's log2 of the derivative scale is an
//! approximation Vulkan leaves to the device (measured on lavapipe: 0.389 for
//! log2(4/3) = 0.415, 0.640 for 0.678, 0.153 for 0.193), while the references take the
//! exact value; powers of two come out exact.
//!
//! Each test writes its table to `target/agreement/<test>.md`; docs/agreement.md is their
//! concatenation.

mod support;

use sshc_tests::reference::tolerance::{Allowed, allowed};
use sshc_tests::reference::{DepthMap, GpuReference, LightFrame, Query, Storage, cpu};
use support::{FIELDS, QueryPlane, compile_source, depth_field, gpu, run_inputs, scene_depth, technique_source};

const N: u32 = 32;

/// One selectable variant of a technique: params (`--set`) and the precision of its
/// stored channel or expansion (`--precision`).
#[derive(Clone)]
struct Variant {
    technique: &'static str,
    params: Vec<(&'static str, f64)>,
    storage: Option<Storage>,
    /// The width of the square area light over the query plane (world units; the plane is
    /// 2 wide), for the soft techniques.
    light: Option<f64>,
}

impl Variant {
    fn new(technique: &'static str, params: &[(&'static str, f64)], storage: Option<Storage>) -> Variant {
        Variant {
            technique,
            params: params.to_vec(),
            storage,
            light: None,
        }
    }

    /// Under a square light `width` wide.
    fn lit(mut self, width: f64) -> Variant {
        self.light = Some(width);
        self
    }

    fn inputs(&self, plane: &QueryPlane) -> sshc_runtime::gpu::SceneInputs {
        match self.light {
            Some(w) => plane.lit_inputs(w as f32),
            None => plane.inputs(),
        }
    }

    fn label(&self) -> String {
        let mut s = self.technique.to_string();
        for (k, v) in &self.params {
            s.push_str(&format!(" {k}={v}"));
        }
        if let Some(p) = self.storage {
            s.push_str(&format!(" {p:?}"));
        }
        if let Some(w) = self.light {
            s.push_str(&format!(" light {w}"));
        }
        s
    }

    /// The channels or expansions the storage override applies to, as the compiler names them.
    fn stored_names(&self) -> &'static [&'static str] {
        match self.technique {
            "vsm" => &["m1", "m2"],
            "esm" => &["e"],
            "csm" => &["f"],
            _ => &[],
        }
    }

    fn compiled(&self) -> sshc::Compiled {
        // slope-scaled bias needs screen-space derivatives the references do not model
        let mut set: Vec<(&str, String)> = vec![("slope_bias", "0.0".into())];
        for (k, v) in &self.params {
            // integral values as integers: i32 params refuse `3.0`, f32 params take `3`
            set.push((
                k,
                if v.fract() == 0.0 {
                    format!("{}", *v as i64)
                } else {
                    format!("{v:?}")
                },
            ));
        }
        let precision: Vec<(&str, &str)> = match self.storage {
            Some(p) => {
                let name = match p {
                    Storage::Unorm8 => "Unorm8",
                    Storage::Unorm16 => "Unorm16",
                    Storage::F16 => "F16",
                    Storage::F32 => "F32",
                };
                self.stored_names().iter().map(|c| (*c, name)).collect()
            }
            None => vec![],
        };
        compile_source(self.technique, &technique_source(self.technique), &set, &precision)
    }

    fn reference(&self) -> sshc_tests::reference::Technique {
        let mut t = sshc_tests::reference::Technique::new(self.technique).with("slope_bias", 0.0);
        for (k, v) in &self.params {
            t = t.with(k, *v);
        }
        t.storage = self.storage;
        match self.light {
            Some(w) => t.lit(LightFrame::query_plane(w)),
            None => t,
        }
    }
}

/// Agreement of one variant over a set of inputs.
#[derive(Default)]
struct Row {
    label: String,
    checked: usize,
    ties: usize,
    gen_cpu: f64,
    gen_hand: f64,
    hand_cpu: f64,
    /// Widest half-width of an allowed interval.
    allowance: f64,
    /// Every half-width (for the median).
    allowances: Vec<f64>,
    failures: Vec<String>,
}

/// The depth fields: the synthetic ones and the light's depth maps of two bundled scenes.
fn inputs(fields: &[&str]) -> Vec<(String, Vec<f32>)> {
    fields
        .iter()
        .map(|f| {
            let z = match *f {
                "bunny" | "fence" | "contact" => scene_depth(f, N),
                f => depth_field(f, N),
            };
            (f.to_string(), z)
        })
        .collect()
}

fn compare(v: &Variant, hand: &GpuReference, inputs: &[(String, Vec<f32>)], row: &mut Row) {
    let compiled = v.compiled();
    let t = v.reference();
    for camera in [2 * N, N / 2] {
        let plane = QueryPlane { shadow: N, camera };
        for (name, z) in inputs {
            let run = run_inputs(&compiled, &v.inputs(&plane), z, &[], 1);
            let mut queries = Vec::new();
            let mut generated = Vec::new();
            for (g, p) in run.visibility.iter().zip(&run.positions) {
                if !p.iter().all(|c| c.is_finite()) {
                    continue;
                }
                let (uv, d) = plane.project(*p);
                queries.push(Query {
                    uv: [uv[0] as f32, uv[1] as f32],
                    d: d as f32,
                    lod: plane.lod().max(0.0),
                });
                generated.push(*g as f64);
            }
            let map = DepthMap { size: N, z: z.clone() };
            let pre = cpu::prefilter(&t, &map).unwrap_or_else(|e| panic!("{}: {e}", v.label()));
            let (hand_v, _) = hand.visibility(&t, &map, &queries).unwrap_or_else(|e| panic!("{}: {e}", v.label()));
            for ((q, g), h) in queries.iter().zip(&generated).zip(&hand_v) {
                let h = *h as f64;
                let c = cpu::evaluate(&pre, q);
                let (lo, hi) = match allowed(&pre, q) {
                    Allowed::Tie => {
                        row.ties += 1;
                        continue;
                    }
                    Allowed::Within(lo, hi) => (lo, hi),
                };
                row.checked += 1;
                row.gen_cpu = row.gen_cpu.max((g - c).abs());
                row.gen_hand = row.gen_hand.max((g - h).abs());
                row.hand_cpu = row.hand_cpu.max((h - c).abs());
                row.allowance = row.allowance.max((c - lo).max(hi - c));
                row.allowances.push((c - lo).max(hi - c));
                if !(lo..=hi).contains(g) && row.failures.len() < 6 {
                    row.failures.push(format!(
                        "{} on {name}, camera {camera}: at {q:?} generated {g:.7}, hand-written {h:.7}, CPU {c:.7}; allowed [{lo:.7}, {hi:.7}]",
                        v.label()
                    ));
                }
            }
        }
    }
}

/// Compare every variant on every input; write the table; fail on any disagreement or
/// when ties hollow a comparison out.
fn agree(test: &str, variants: &[Variant], fields: &[&str]) {
    let hand = GpuReference::new(gpu()).unwrap_or_else(|e| panic!("{e}"));
    let inputs = inputs(fields);
    let mut rows = Vec::new();
    for v in variants {
        let mut row = Row {
            label: v.label(),
            ..Default::default()
        };
        compare(v, &hand, &inputs, &mut row);
        rows.push(row);
    }
    let mut md = format!(
        "### {test}\n\nDevice: {}. Inputs: {} ({N} x {N} texels); cameras {} and {} pixels.\n\n| variant | checked | ties | max \\|gen - CPU\\| | max \\|gen - hand\\| | max \\|hand - CPU\\| | median allowance | widest allowance |\n|---|---|---|---|---|---|---|---|\n",
        gpu().describe(),
        fields.join(", "),
        2 * N,
        N / 2
    );
    let mut failures = Vec::new();
    for r in &rows {
        md.push_str(&format!(
            "| {} | {} | {} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {:.2e} |\n",
            r.label,
            r.checked,
            r.ties,
            r.gen_cpu,
            r.gen_hand,
            r.hand_cpu,
            median_of(&r.allowances),
            r.allowance
        ));
        if r.checked < 4 * r.ties.max(1) / 3 && r.checked < 1000 {
            failures.push(format!("{}: only {} queries checked against {} ties", r.label, r.checked, r.ties));
        }
        failures.extend(r.failures.iter().cloned());
    }
    eprintln!("{md}");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/agreement");
    let _ = std::fs::create_dir_all(&dir);
    let _ = std::fs::write(dir.join(format!("{test}.md")), &md);
    assert!(failures.is_empty(), "generated shaders disagree:\n{}", failures.join("\n"));
}

fn median_of(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s.get(s.len() / 2).copied().unwrap_or(0.0)
}

fn all_fields() -> Vec<&'static str> {
    FIELDS.iter().copied().chain(["bunny", "fence"]).collect()
}

#[test]
fn hard_agrees() {
    let v = [Variant::new("hard", &[], None), Variant::new("hard", &[("bias", 0.01)], None)];
    agree("hard", &v, &all_fields());
}

#[test]
fn pcf_agrees() {
    let v: Vec<Variant> = [1.0, 2.0, 3.0, 5.0]
        .iter()
        .map(|&n| Variant::new("pcf", &[("N", n)], None))
        .collect();
    agree("pcf", &v, &all_fields());
}

#[test]
fn vsm_agrees() {
    let mut v = vec![Variant::new("vsm", &[], None)];
    for k in [1.0, 7.0] {
        v.push(Variant::new("vsm", &[("K", k)], Some(Storage::F32)));
    }
    v.push(Variant::new("vsm", &[("bleed", 0.0)], None));
    // F16 moments: the variance is then not determined by the precision at small
    // variances (the allowance says so); a larger minimum variance keeps it meaningful
    v.push(Variant::new("vsm", &[("min_variance", 0.001)], Some(Storage::F16)));
    agree("vsm", &v, &all_fields());
}

#[test]
fn esm_agrees() {
    let mut v = Vec::new();
    for classify in [0.0, 1.0, 2.0] {
        v.push(Variant::new("esm", &[("classify", classify)], None));
    }
    v.push(Variant::new("esm", &[("K", 1.0)], None));
    // F16 needs c <= ln 65504 = 11.09 (the compiler refuses more)
    v.push(Variant::new("esm", &[("c", 10.0)], Some(Storage::F16)));
    agree("esm", &v, &all_fields());
}

#[test]
fn csm_agrees() {
    let mut v = Vec::new();
    for storage in [Storage::Unorm8, Storage::F16, Storage::F32] {
        v.push(Variant::new("csm", &[], Some(storage)));
    }
    for (m, fix) in [(1.0, 0.0), (8.0, 2.0), (16.0, 1.0)] {
        v.push(Variant::new("csm", &[("M", m), ("fix", fix)], None));
    }
    v.push(Variant::new("csm", &[("K", 1.0), ("alpha", 0.0)], None));
    agree("csm", &v, &all_fields());
}

#[test]
fn cssm_agrees() {
    let mut v = Vec::new();
    for (filter, w) in [(0.0, 1.0), (1.0, 0.5), (1.0, 1.0)] {
        v.push(Variant::new("cssm", &[("filter", filter)], None).lit(w));
    }
    // a longer series, no blur, no sharpening; and a light of width 0 (plain CSM)
    v.push(Variant::new("cssm", &[("M", 8.0), ("K", 1.0), ("A", 0.0)], None).lit(1.0));
    v.push(Variant::new("cssm", &[("filter", 1.0)], None).lit(0.0));
    // the CPU error model of CSSM evaluates the series at many perturbed kernels per query:
    // the fields that exercise it differently (an edge, noise, no occluder, two scenes)
    agree("cssm", &v, &["step", "noise", "one", "bunny", "fence"]);
}

#[test]
fn pcss_agrees() {
    let mut v = Vec::new();
    for (n, m, w) in [(6.0, 8.0, 1.0), (3.0, 5.0, 0.5), (16.0, 16.0, 0.3), (4.0, 4.0, 0.0)] {
        v.push(Variant::new("pcss", &[("N", n), ("M", m)], None).lit(w));
    }
    agree("pcss", &v, &all_fields());
}

/// GPU time of the generated passes after Depth against the hand-written ones, in the same
/// process on the same inputs.
///
/// The generated Shade pass is a render pass over the scene seen from the camera that also
/// writes the camera's position, normal and colour images; the hand-written shade is a
/// compute pass over a list of shading points. So that the comparison is of the code each
/// side writes and not of that fixed cost, every round also times a baseline: the same
/// graph with the visibility expression replaced (the pass, its rasterisation and
/// its outputs, and the receiver's inputs `uv`, `d` and `depth_slope` kept live by a
/// visibility `saturate(d + depth_slope + uv.x + uv.y)` that reads no resource: what the
/// hand-written side is handed in its query buffer); a technique's own time is its time
/// minus the baseline's.
///
/// The hand-written passes are timed in two parts. On lavapipe the end timestamp of a
/// compute pass does not wait for its last dispatch, the Shade dispatch (measured: the
/// hand-written PCSS reads 0.15 ms by its timestamps against 110 ms of wall time; neither a
/// barrier behind it nor a second pass carrying the timestamp made it wait). So the
/// timestamps give the passes before Shade, and the Shade dispatch's own cost is the wall
/// time with it dispatched three times less the wall time with it dispatched once, halved:
/// every fixed cost (upload, submission, read-back, the passes before it) cancels.
///
/// `ROUNDS` rounds, each timing `FRAMES` frames (medians) of the baseline, the generated and
/// the hand-written passes in turn, so that drifts of the machine hit all three. Reported:
/// medians over rounds, the ratio generated-own / hand-written, and the noise bound: the
/// run-to-run spread (max - min over rounds) of the three, added, in milliseconds. The
/// generated code is slower only when its own time exceeds the hand-written by more than
/// that. Writes `target/agreement/times.md` (quoted in docs/agreement.md). A measurement
/// and slow on lavapipe: `cargo test -p sshc-tests --test agreement -- --ignored
/// --nocapture timings`.
#[test]
#[ignore = "measurement (minutes on lavapipe); run with --ignored"]
fn timings() {
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
    eprintln!("{md}");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/agreement");
    let _ = std::fs::create_dir_all(&dir);
    let _ = std::fs::write(dir.join("times.md"), &md);
    assert!(slower.is_empty(), "generated shaders slower beyond the noise: {slower:?}\n{md}");
}
