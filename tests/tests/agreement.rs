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

use sshc_tests::compare::{Comparison, Layout};
use sshc_tests::reference::tolerance::{Allowed, allowed};
use sshc_tests::reference::{DepthMap, GpuReference, Query, Storage, cpu};
use support::variant::Variant;
use support::{FIELDS, QueryPlane, depth_field, gpu, run_inputs, scene_depth};

const N: u32 = 32;

/// Agreement of one variant over a set of inputs: per camera and input, the generated
/// and the hand-written shaders, each against the CPU reference under the tolerance model.
#[derive(Default)]
struct Row {
    label: String,
    generated: Vec<Comparison>,
    hand_written: Vec<Comparison>,
    /// max |generated - hand-written| (printed; each side is asserted against the CPU).
    gen_hand: f64,
    /// Queries whose allowed interval is the whole of [0, 1]: compared, but any value in
    /// range passes (the error models' fallbacks where no tighter bound is derived).
    whole: usize,
}

impl Row {
    fn checked(&self) -> usize {
        self.generated.iter().map(|c| c.checked).sum()
    }
    fn ties(&self) -> usize {
        self.generated.iter().map(|c| c.ties).sum()
    }
    fn max_diff(v: &[Comparison]) -> f64 {
        v.iter().map(|c| c.max_diff).fold(0.0, f64::max)
    }
    /// Every allowance (the same intervals bound both sides).
    fn allowances(&self) -> Vec<f64> {
        self.generated.iter().flat_map(|c| c.allowances.iter().copied()).collect()
    }
}

/// The depth fields: the synthetic ones and the light's depth maps of two bundled scenes.
fn inputs(fields: &[&str]) -> Vec<(String, Vec<f32>)> {
    fields
        .iter()
        .map(|f| {
            let z = match *f {
                "bunny" | "fence" | "contact" => scene_depth(f, N),
                "tracking" => tracking_field(N),
                f => depth_field(f, N),
            };
            (f.to_string(), z)
        })
        .collect()
}

/// Blockers that follow the query plane's receiver (its depth is 1 - u): half the texels
/// (by a hash) at depth 0.85 (1 - u), the rest background at 1. A search region then finds
/// blockers where the filter region (smaller: the blockers are near the receiver) reads a
/// mean behind the receiver, unevenly over its quadrants: VSSM's subdivision changes the
/// result there (60 queries by more than 0.02 under a light 0.5 wide, camera 2N).
fn tracking_field(n: u32) -> Vec<f32> {
    let n = n as usize;
    let hash = |k: usize| ((k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as f32 / (1u64 << 24) as f32;
    (0..n * n)
        .map(|k| {
            let u = ((k % n) as f32 + 0.5) / n as f32;
            if hash(k) < 0.5 { 0.85 * (1.0 - u) } else { 1.0 }
        })
        .collect()
}

fn compare(v: &Variant, hand: &GpuReference, inputs: &[(String, Vec<f32>)], row: &mut Row) {
    let compiled = v.compiled();
    let t = v.reference();
    for camera in [2 * N, N / 2] {
        let plane = QueryPlane::new(N, camera);
        for (name, z) in inputs {
            let run = run_inputs(&compiled, &v.inputs(&plane), z, &[], 1);
            // the camera pixels that see the plane, their queries and generated values
            let mut pixels = Vec::new();
            let mut queries = Vec::new();
            let mut generated = Vec::new();
            for (i, (g, p)) in run.visibility.iter().zip(&run.positions).enumerate() {
                if !p.iter().all(|c| c.is_finite()) {
                    continue;
                }
                let (uv, d) = plane.project(*p);
                pixels.push(i);
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
            assert_eq!(hand_v.len(), queries.len(), "{}: one hand-written value per query", v.label());
            let layout = Layout::Image { width: camera as usize };
            let mut gen_cmp = Comparison::new(format!("{} generated on {name}, camera {camera}", v.label()), layout);
            let mut hand_cmp = Comparison::new(format!("{} hand-written on {name}, camera {camera}", v.label()), layout);
            for (((&px, q), &g), &h) in pixels.iter().zip(&queries).zip(&generated).zip(&hand_v) {
                let h = h as f64;
                let c = cpu::evaluate(&pre, q);
                let allowed = allowed(&pre, q);
                let context = || format!("{q:?}; generated {g:.7}, hand-written {h:.7}");
                gen_cmp.push(px, g, c, &allowed, context);
                hand_cmp.push(px, h, c, &allowed, context);
                if let Allowed::Within(lo, hi) = allowed {
                    row.gen_hand = row.gen_hand.max((g - h).abs());
                    row.whole += usize::from(lo <= 0.0 && hi >= 1.0);
                }
            }
            row.generated.push(gen_cmp);
            row.hand_written.push(hand_cmp);
        }
    }
}

/// The share of a variant's queries that may be ties (skipped, unchecked). Ties are inputs on
/// a decision's edge: a depth within 2^-22 of a blocker's, a uv on a texel's boundary; on the
/// continuous fields and scenes here they are rare (docs/agreement.md: PCSS's 4- and
/// 3-sample variants, whose few blocker samples make every sample a decision, 1.9 %; every
/// other variant under 0.5 %). Over 5 % means the inputs sit on boundaries (a quantised
/// field, a degenerate camera) and the comparison checks too little to mean agreement.
const MAX_TIE_SHARE: f64 = 0.05;

/// The share of a variant's checked queries whose allowance may be the whole of [0, 1]
/// (compared, but any value in range passes): where an error model cannot bound a result
/// more tightly, which on these inputs is rare (every variant not in [`WIDE_VARIANTS`]
/// measured under 1.2 %, docs/agreement.md). More means a model fell back broadly and the
/// comparison checks less than its row says.
const MAX_WHOLE_SHARE: f64 = 0.02;

/// Variants whose error models legitimately leave more of their queries unbounded: (label
/// prefix, the share allowed, why). Each share is the measured one (lavapipe, these inputs:
/// deterministic) rounded up to the next percent, so that a model that widens fails.
const WIDE_VARIANTS: &[(&str, f64, &str)] = &[
    (
        "msm-hausdorff",
        0.40,
        "Hausdorff MSM: every query whose footprint lies wholly at depth 1 (the scenes' background, the step's far half: 7660 of the 21760 queries, 35.2 %; at K = 1, less blur, 8523, 39.2 %) gets all of [0, 1], and 31 others (0.14 %; K = 1: 18). There the exact moments are those of {0, t, 1} after the bias (A = B = 0, G = R / t = 1 - b1, the four-point branch) and moments_tolerance::hausdorff_four_point_enclosure finds A's interval holding 0: over the box of independent errors (about 2e-6 per moment) A and B both change sign, B / A takes every value and G meets its poles, so [0, 1] is G's exact range over that box, not a loose step (the generated values there lie within 1.4e-6 of the CPU's). A tighter enclosure needs correlated errors: texels at 0 or 1 have z^k = z, so the four channels are equal texel by texel, and sampled with shared weights and biased alike they are bit-identical on the GPU (D1 = D2 = D3 = 0, G = 1 - b1 in both shaders' four-point paths); the model would have to detect such footprints, carry one error for all four moments there, and bound each shader's degenerate path (the hand-written |A| < 1e-12 guard; the generated div_or fallback g = 1/2, whose w_g divides rounding noise by zf - 1/2) and the Hamburger branch, whose choice at the clamped last pivot is a rounding. The 31 others are mixed footprints where B / A's interval holds 0 (w_g's jump, 21) or the box's corners disagree on the branch (10)",
    ),
    (
        "mssm quantise=0 light 1",
        0.16,
        "MSSM without quantisation decodes its moments with coefficients up to 80 (moments_tolerance::mssm_decode_err; the quantised transform's are at most 2.05), so its tables' error reaches the ill-conditioned 4MSM solve 40 times larger; under the widest light (the largest boxes) 15.0 % of the queries get all of [0, 1]",
    ),
];

/// The share of `label`'s checked queries allowed the whole of [0, 1], and why.
fn whole_share_allowed(label: &str) -> (f64, &'static str) {
    WIDE_VARIANTS
        .iter()
        .find(|(prefix, ..)| label.starts_with(prefix))
        .map_or((MAX_WHOLE_SHARE, "the default bound (MAX_WHOLE_SHARE)"), |&(_, share, why)| {
            (share, why)
        })
}

/// Compare every variant on every input; write the table; fail on any disagreement, when
/// ties hollow a comparison out (more than [`MAX_TIE_SHARE`] of its queries) or when more
/// of its queries than [`whole_share_allowed`] are allowed the whole of [0, 1].
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
        "### {test}\n\nDevice: {}. Inputs: {} ({N} x {N} texels); cameras {} and {} pixels.\n\n| variant | checked | ties | whole [0, 1] allowed | max \\|gen - CPU\\| | max \\|gen - hand\\| | max \\|hand - CPU\\| | median allowance | widest allowance |\n|---|---|---|---|---|---|---|---|---|\n",
        gpu().describe(),
        fields.join(", "),
        2 * N,
        N / 2
    );
    let mut failures = Vec::new();
    for r in &rows {
        let (checked, ties) = (r.checked(), r.ties());
        let allowances = r.allowances();
        md.push_str(&format!(
            "| {} | {checked} | {ties} | {} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {:.2e} |\n",
            r.label,
            r.whole,
            Row::max_diff(&r.generated),
            r.gen_hand,
            Row::max_diff(&r.hand_written),
            median_of(&allowances),
            allowances.iter().copied().fold(0.0, f64::max)
        ));
        // A tie (the result changes when d or uv moves by 2^-22) is skipped, not checked: at
        // most MAX_TIE_SHARE of a variant's queries may be (the rule before, "fewer checked
        // than 4/3 of the ties, and fewer than 1000", let up to 43 % go unchecked; issue 52)
        if ties as f64 > MAX_TIE_SHARE * (checked + ties) as f64 {
            failures.push(format!(
                "{}: {ties} of {} queries are ties, unchecked: more than {:.0} %",
                r.label,
                checked + ties,
                100.0 * MAX_TIE_SHARE
            ));
        }
        let (allowed, why) = whole_share_allowed(&r.label);
        if r.whole as f64 > allowed * checked as f64 {
            failures.push(format!(
                "{}: {} of {checked} checked queries allowed the whole of [0, 1]: more than {:.0} % ({why})",
                r.label,
                r.whole,
                100.0 * allowed
            ));
        }
        for c in r.generated.iter().chain(&r.hand_written) {
            failures.extend(c.errors());
        }
    }
    eprintln!("{md}");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/agreement");
    let _ = std::fs::create_dir_all(&dir);
    let _ = std::fs::write(dir.join(format!("{test}.md")), &md);
    assert!(
        failures.is_empty(),
        "generated or hand-written shaders disagree with the CPU reference:\n{}",
        failures.join("\n")
    );
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
    // the compute schedule of its Map and Filter passes
    v.push(Variant::new("vsm", &[], None).scheduled("compute"));
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
    v.push(Variant::new("esm", &[], None).scheduled("compute"));
    agree("esm", &v, &all_fields());
}

#[test]
fn evsm_agrees() {
    let v = vec![
        Variant::new("evsm", &[], None),
        Variant::new("evsm", &[("c_pos", 20.0), ("c_neg", 10.0), ("bleed", 0.2)], None),
        // F16 holds exp(2 c) for c <= ln(65504) / 2 = 5.54 (the compiler refuses more); its
        // rounding needs a larger minimum variance to determine the variance
        Variant::new(
            "evsm",
            &[("c_pos", 5.0), ("c_neg", 5.0), ("min_variance", 0.002)],
            Some(Storage::F16),
        ),
        // the compute schedule of its Map, Filter and Mipmap passes
        Variant::new("evsm", &[], None).scheduled("compute"),
    ];
    agree("evsm", &v, &all_fields());
}

#[test]
fn msm_agrees() {
    let v = vec![
        Variant::new("msm", &[], None),
        Variant::new("msm", &[("K", 7.0)], None),
        Variant::new("msm", &[("K", 1.0), ("alpha", 0.0001)], None),
        Variant::new("msm", &[], None).scheduled("compute"),
    ];
    agree("msm", &v, &all_fields());
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
    v.push(Variant::new("csm", &[], None).scheduled("compute"));
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
    v.push(Variant::new("cssm", &[("filter", 0.0)], None).lit(1.0).scheduled("compute"));
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

#[test]
fn vssm_agrees() {
    let v = vec![
        Variant::new("vssm", &[], None).lit(1.0),
        Variant::new("vssm", &[("subdivide", 0.0)], None).lit(1.0),
        Variant::new("vssm", &[], None).lit(0.5),
        Variant::new("vssm", &[], None).lit(1.0).scheduled("compute"),
    ];
    // the fields whose regions mix depths and two scenes; "one" (no occluder) adds nothing;
    // "tracking" (blockers near the receiver beside background) is where the subdivision
    // changes the result at many queries (ramp: at a few)
    agree("vssm", &v, &["ramp", "step", "noise", "tracking", "bunny", "fence"]);
}

#[test]
fn msm_hausdorff_agrees() {
    let v = vec![
        Variant::new("msm-hausdorff", &[], None),
        Variant::new("msm-hausdorff", &[("K", 1.0)], None),
        Variant::new("msm-hausdorff", &[], None).scheduled("compute"),
    ];
    // the f32 forward error of the four-point branch is measured at 17 points per corner of
    // the weights: five fields (an edge, noise, a ramp, two scenes) keep it near 5 s
    agree("msm-hausdorff", &v, &["ramp", "step", "noise", "bunny", "fence"]);
}

#[test]
fn mssm_agrees() {
    let v = vec![
        Variant::new("mssm", &[], None).lit(1.0),
        Variant::new("mssm", &[("quantise", 0.0)], None).lit(1.0),
        Variant::new("mssm", &[], None).lit(0.5),
        Variant::new("mssm", &[], None).lit(1.0).scheduled("compute"),
    ];
    // the error model evaluates the Hamburger bound at 512 corners twice per query: five fields
    agree("mssm", &v, &["step", "noise", "one", "bunny", "fence"]);
}
