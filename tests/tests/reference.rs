//! The hand-written references of the bundled techniques (`sshc_tests::reference`) agree
//! with themselves: the CPU evaluator (f64, no quantisation) and the WGSL one (intermediate
//! images at the storage precision, hardware-filtered lookups) give the same visibility on
//! small synthetic depth maps, within tolerances derived below, per query, from the storage
//! precision and Vulkan's precision rules. The CPU evaluator is also checked against
//! closed forms of the papers' equations.
//!
//! GPU tests never skip: with no adapter they fail with the error (lavapipe, Mesa's CPU
//! Vulkan driver, is enough; run with `LP_NUM_THREADS=2`).
//!
//! Binary shadow tests are guarded against exact ties: a query whose f64 result changes when
//! its depth (or, for `nearest` lookups, its uv) moves by 2^-22 (four times the rounding of
//! f32 values in [0, 1]) is skipped and counted, since the f32 arithmetic of a GPU may land
//! on either side.

use sshc_runtime::gpu::Gpu;
use sshc_tests::compare::{Comparison, Layout};
use sshc_tests::reference::cpu;
use sshc_tests::reference::tolerance::allowed;
use sshc_tests::reference::{DepthMap, GpuReference, LightFrame, Query, Storage, Technique, cpu_visibility};
use std::sync::OnceLock;

// ---------------------------------------------------------------------------------------
// Inputs

fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| Gpu::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}")))
}

fn depth_map(size: u32, f: impl Fn(u32, u32) -> f32) -> DepthMap {
    DepthMap {
        size,
        z: (0..size * size).map(|i| f(i % size, i / size)).collect(),
    }
}

/// A deterministic xorshift64* generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn pick<T: Copy>(&mut self, v: &[T]) -> T {
        v[(self.next() % v.len() as u64) as usize]
    }
}

/// Synthetic depth maps: a tilted plane, a step edge, a checkerboard of a size that is no
/// power of two, value noise, and the extremes all-0 and all-1.
fn maps() -> Vec<(&'static str, DepthMap)> {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let noise: Vec<f32> = (0..64 * 64).map(|_| rng.unit()).collect();
    vec![
        ("ramp32", depth_map(32, |x, y| 0.1 + 0.8 * (x as f32 + 0.5 * y as f32) / 46.5)),
        ("step16", depth_map(16, |x, y| if x + y / 4 < 8 { 0.3 } else { 0.7 })),
        (
            "checker24",
            depth_map(24, |x, y| if (x / 3 + y / 3) % 2 == 0 { 0.25 } else { 0.75 }),
        ),
        ("noise64", depth_map(64, |x, y| noise[(y * 64 + x) as usize])),
        ("zeros16", depth_map(16, |_, _| 0.0)),
        ("ones16", depth_map(16, |_, _| 1.0)),
    ]
}

/// 240 receivers: uv anywhere on the map (a few on its edges), d near the stored depth
/// (where the tests switch), uniform, or at the extremes 0 and 1; lod at whole levels,
/// between levels, and beyond the chain (clamped).
fn queries(map: &DepthMap, seed: u64) -> Vec<Query> {
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let n = map.size as f32;
    let levels = (32 - map.size.leading_zeros()) as f32;
    (0..240)
        .map(|i| {
            let mut uv = [rng.unit(), rng.unit()];
            if i % 37 == 0 {
                uv[i % 2] = if i % 3 == 0 { 0.0 } else { 1.0 };
            }
            let texel = |c: f32| ((c * n).floor() as u32).min(map.size - 1);
            let z = map.z[(texel(uv[1]) * map.size + texel(uv[0])) as usize];
            let d = match i % 4 {
                0 => rng.unit(),
                1 => z + rng.pick(&[-0.2, -0.03, -0.004, 0.0, 0.002, 0.01, 0.03, 0.1, 0.3]),
                2 => z + 0.04 * (rng.unit() - 0.5),
                _ => rng.pick(&[0.0, 1.0, z]),
            };
            let lod = match i % 5 {
                0 => 0.0,
                1 => 1.0,
                2 => rng.unit() * (levels - 1.0),
                3 => levels - 0.5 + rng.unit(),
                _ => 2.0 + 0.5 * rng.unit(),
            };
            Query {
                uv,
                d: d.clamp(0.0, 1.0),
                lod,
            }
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// CPU against GPU

/// One configuration on one map: the comparison and the GPU time of the run.
struct Row {
    cmp: Comparison,
    nanoseconds: f64,
}

fn compare(reference: &GpuReference, label: &str, t: &Technique, map_name: &str, map: &DepthMap, seed: u64) -> Row {
    let qs = queries(map, seed);
    let pre = cpu::prefilter(t, map).unwrap_or_else(|e| panic!("{label}: {e}"));
    let cpu_v = cpu_visibility(t, map, &qs).unwrap_or_else(|e| panic!("{label}: {e}"));
    let (gpu_v, ns) = reference
        .visibility(t, map, &qs)
        .unwrap_or_else(|e| panic!("{label} on {map_name}: {e}"));
    assert_eq!(gpu_v.len(), qs.len(), "{label}: one visibility per query");
    for ((q, &c), &g) in qs.iter().zip(&cpu_v).zip(&gpu_v) {
        assert!((0.0..=1.0).contains(&g), "{label}: GPU visibility {g} outside [0, 1] at {q:?}");
        assert!((0.0..=1.0).contains(&c), "{label}: CPU visibility {c} outside [0, 1] at {q:?}");
    }
    let gpu_v: Vec<f64> = gpu_v.iter().map(|&g| g as f64).collect();
    let mut cmp = Comparison::new(format!("{label} / {map_name}"), Layout::Buffer);
    for (i, q) in qs.iter().enumerate() {
        cmp.push(i, gpu_v[i], cpu_v[i], &allowed(&pre, q), || format!("{q:?}"));
    }
    Row { cmp, nanoseconds: ns }
}

/// Compare every configuration on every map; print a table (per technique and map: queries
/// checked, ties skipped, max and mean |GPU - CPU|, the widest allowance, the largest
/// difference over its allowance, queries allowed more than 0.1, GPU microseconds of the
/// run); fail with every disagreement.
fn agree(configs: &[(&str, Technique)]) {
    agree_on(configs, &maps());
}

/// [`agree`] on chosen maps.
fn agree_on(configs: &[(&str, Technique)], maps: &[(&'static str, DepthMap)]) {
    let reference = GpuReference::new(gpu()).unwrap_or_else(|e| panic!("{e}"));
    eprintln!("device: {}", gpu().describe());
    eprintln!(
        "{:<44} {:>7} {:>5} {:>10} {:>10} {:>10} {:>7} {:>5} {:>10}",
        "technique / map", "checked", "ties", "max |d|", "mean |d|", "max allow", "d/allow", "loose", "GPU us"
    );
    let mut failures = Vec::new();
    for (ci, (label, t)) in configs.iter().enumerate() {
        for (mi, (map_name, map)) in maps.iter().enumerate() {
            let Row { cmp, nanoseconds } = compare(&reference, label, t, map_name, map, (ci * 16 + mi) as u64 + 1);
            eprintln!(
                "{:<44} {:>7} {:>5} {:>10.3e} {:>10.3e} {:>10.3e} {:>7.3} {:>5} {:>10.1}",
                cmp.label,
                cmp.checked,
                cmp.ties,
                cmp.max_diff,
                cmp.mean_diff(),
                cmp.max_allowance(),
                cmp.worst_ratio(),
                cmp.loose(0.1),
                nanoseconds * 1e-3
            );
            // The guard must not hollow the comparison out. (On the all-0 and all-1 maps
            // many receivers sit exactly at the stored depth, d = z: genuine ties.)
            if cmp.checked < 100 {
                failures.push(format!(
                    "{}: {} of {} queries are ties",
                    cmp.label,
                    cmp.ties,
                    cmp.checked + cmp.ties
                ));
            }
            failures.extend(cmp.errors());
        }
    }
    assert!(failures.is_empty(), "CPU and GPU references disagree:\n{}", failures.join("\n"));
}

fn technique(name: &str, params: &[(&str, f64)], storage: Option<Storage>) -> Technique {
    let mut t = Technique::new(name);
    for (k, v) in params {
        t = t.with(k, *v);
    }
    t.storage = storage;
    t
}

#[test]
fn gpu_hard_agrees_with_cpu() {
    agree(&[
        ("hard", technique("hard", &[], None)),
        ("hard bias=0", technique("hard", &[("bias", 0.0)], None)),
    ]);
}

#[test]
fn gpu_pcf_agrees_with_cpu() {
    agree(&[
        ("pcf N=3", technique("pcf", &[], None)),
        ("pcf N=1", technique("pcf", &[("N", 1.0)], None)),
        ("pcf N=4 bias=0", technique("pcf", &[("N", 4.0), ("bias", 0.0)], None)),
        ("pcf N=15", technique("pcf", &[("N", 15.0)], None)),
    ]);
}

#[test]
fn gpu_vsm_agrees_with_cpu() {
    agree(&[
        ("vsm F32", technique("vsm", &[], None)),
        ("vsm Unorm8", technique("vsm", &[], Some(Storage::Unorm8))),
        ("vsm Unorm16", technique("vsm", &[], Some(Storage::Unorm16))),
        ("vsm F16", technique("vsm", &[], Some(Storage::F16))),
        ("vsm F32 K=1", technique("vsm", &[("K", 1.0)], None)),
        (
            "vsm F16 K=7 bleed=0 minvar=1e-3",
            technique("vsm", &[("K", 7.0), ("bleed", 0.0), ("min_variance", 1e-3)], Some(Storage::F16)),
        ),
    ]);
}

#[test]
fn gpu_esm_agrees_with_cpu() {
    agree(&[
        ("esm F32 c=80 threshold", technique("esm", &[], None)),
        ("esm F32 c=80 none", technique("esm", &[("classify", 0.0)], None)),
        ("esm F32 c=80 z-max", technique("esm", &[("classify", 2.0)], None)),
        (
            "esm F32 c=40 K=1 z-max",
            technique("esm", &[("c", 40.0), ("K", 1.0), ("classify", 2.0)], None),
        ),
        ("esm F16 c=10 threshold", technique("esm", &[("c", 10.0)], Some(Storage::F16))),
        ("esm Unorm16 c=8 threshold", technique("esm", &[("c", 8.0)], Some(Storage::Unorm16))),
        (
            "esm Unorm8 c=5 none",
            technique("esm", &[("c", 5.0), ("classify", 0.0)], Some(Storage::Unorm8)),
        ),
    ]);
}

#[test]
fn gpu_evsm_agrees_with_cpu() {
    agree(&[
        ("evsm F32 c=40,5", technique("evsm", &[], None)),
        (
            "evsm F32 c=20,10 K=1 bleed=0.2",
            technique("evsm", &[("c_pos", 20.0), ("c_neg", 10.0), ("K", 1.0), ("bleed", 0.2)], None),
        ),
        // (not c = 42: at d = 0 its least variance min_variance (c e^{-c})^2 = 1.1e-38 falls
        // below f32's normal range, which a device may flush to 0)
        (
            "evsm F32 c=30,30 K=5",
            technique("evsm", &[("c_pos", 30.0), ("c_neg", 30.0), ("K", 5.0)], None),
        ),
        // F16 holds exp(2 c) for c <= ln(65504) / 2 = 5.54; its 2^-11 rounding needs a
        // minimum variance well above 2^-10 of the squared warp to determine the variance
        (
            "evsm F16 c=5,5 minvar=2e-3",
            technique(
                "evsm",
                &[("c_pos", 5.0), ("c_neg", 5.0), ("min_variance", 2e-3)],
                Some(Storage::F16),
            ),
        ),
    ]);
}

#[test]
fn gpu_msm_agrees_with_cpu() {
    agree(&[
        ("msm F32 alpha=3e-5 K=3", technique("msm", &[], None)),
        ("msm F32 K=1", technique("msm", &[("K", 1.0)], None)),
        ("msm F32 K=7 alpha=1e-4", technique("msm", &[("K", 7.0), ("alpha", 1e-4)], None)),
    ]);
}

#[test]
fn gpu_csm_agrees_with_cpu() {
    agree(&[
        ("csm Unorm8 M=4", technique("csm", &[], None)),
        ("csm Unorm8 M=1 fix=0", technique("csm", &[("M", 1.0), ("fix", 0.0)], None)),
        (
            "csm Unorm16 M=16 fix=2 K=5 s=2",
            technique(
                "csm",
                &[("M", 16.0), ("fix", 2.0), ("K", 5.0), ("sigma", 2.0)],
                Some(Storage::Unorm16),
            ),
        ),
        (
            "csm F16 M=8 alpha=0",
            technique("csm", &[("M", 8.0), ("alpha", 0.0)], Some(Storage::F16)),
        ),
        ("csm F32 M=4", technique("csm", &[], Some(Storage::F32))),
        ("csm Unorm8 M=64 K=1", technique("csm", &[("M", 64.0), ("K", 1.0)], None)),
    ]);
}

/// The soft-shadow techniques on the query plane (orthographic, extent [-1, 1]^2, near 8,
/// far 12) under a light `width` wide (x, y).
fn soft(name: &str, params: &[(&str, f64)], width: [f64; 2]) -> Technique {
    let mut light = LightFrame::query_plane(0.0);
    light.width = width;
    technique(name, params, None).lit(light)
}

/// A step edge, a ramp and noise (of `maps`).
fn soft_maps() -> Vec<(&'static str, DepthMap)> {
    maps()
        .into_iter()
        .filter(|(n, _)| matches!(*n, "step16" | "ramp32" | "noise64"))
        .collect()
}

#[test]
fn gpu_cssm_mipmaps_agree_with_cpu() {
    agree_on(
        &[
            ("cssm mips W=1", soft("cssm", &[("slope_bias", 0.0)], [1.0, 1.0])),
            (
                "cssm mips M=2 fix=2 K=1 W=2",
                soft("cssm", &[("slope_bias", 0.0), ("M", 2.0), ("fix", 2.0), ("K", 1.0)], [2.0, 2.0]),
            ),
        ],
        &soft_maps(),
    );
}

#[test]
fn gpu_cssm_tables_agree_with_cpu() {
    agree_on(
        &[
            (
                "cssm table W=1x0.4",
                soft("cssm", &[("slope_bias", 0.0), ("filter", 1.0)], [1.0, 0.4]),
            ),
            (
                "cssm table M=8 K=5 A=30 B=32 W=0.5",
                soft(
                    "cssm",
                    &[
                        ("slope_bias", 0.0),
                        ("filter", 1.0),
                        ("M", 8.0),
                        ("K", 5.0),
                        ("A", 30.0),
                        ("B", 32.0),
                    ],
                    [0.5, 0.5],
                ),
            ),
        ],
        &soft_maps(),
    );
}

#[test]
fn gpu_pcss_agrees_with_cpu() {
    agree_on(
        &[
            ("pcss W=1", soft("pcss", &[("slope_bias", 0.0)], [1.0, 1.0])),
            (
                "pcss N=3 M=5 W=2x0.5",
                soft("pcss", &[("slope_bias", 0.0), ("N", 3.0), ("M", 5.0)], [2.0, 0.5]),
            ),
            (
                "pcss N=16 M=16 bias=0 W=0.3",
                soft("pcss", &[("slope_bias", 0.0), ("N", 16.0), ("M", 16.0), ("bias", 0.0)], [0.3, 0.3]),
            ),
        ],
        &soft_maps(),
    );
}

#[test]
fn soft_shadows_at_light_width_0_are_their_point_light_bases() {
    // A point light: CSSM's kernels are 0, so it reads the CSM series at mip level 0 (or a
    // one-texel box: bilinear); with no ringing suppression and no sharpening it is CSM at
    // the finest level. PCSS samples the receiver's own texel: the hard shadow map.
    let reference = GpuReference::new(gpu()).unwrap_or_else(|e| panic!("{e}"));
    let mut worst = (0.0f64, 0.0f64, 0.0f64);
    for (name, map) in soft_maps() {
        let qs: Vec<Query> = queries(&map, 3).into_iter().map(|q| Query { lod: 0.0, ..q }).collect();
        let csm = technique("csm", &[("slope_bias", 0.0)], None);
        let (csm_cpu, csm_gpu) = (
            cpu_visibility(&csm, &map, &qs).unwrap_or_else(|e| panic!("{e}")),
            reference.visibility(&csm, &map, &qs).unwrap_or_else(|e| panic!("{e}")).0,
        );
        for filter in [0.0, 1.0] {
            let cssm = soft(
                "cssm",
                &[("slope_bias", 0.0), ("ring", 0.0), ("A", 0.0), ("filter", filter)],
                [0.0, 0.0],
            );
            let cpu_v = cpu_visibility(&cssm, &map, &qs).unwrap_or_else(|e| panic!("{e}"));
            let gpu_v = reference.visibility(&cssm, &map, &qs).unwrap_or_else(|e| panic!("{e}")).0;
            for i in 0..qs.len() {
                let d = (cpu_v[i] - csm_cpu[i]).abs();
                assert!(
                    d < 1e-12,
                    "{name} filter {filter}: CPU CSSM {} vs CSM {} at {:?}",
                    cpu_v[i],
                    csm_cpu[i],
                    qs[i]
                );
                worst.0 = worst.0.max(d);
                if filter == 0.0 {
                    // the same texture, sampler and series: only pow(s, 1) and f32 order differ
                    let d = (gpu_v[i] - csm_gpu[i]).abs() as f64;
                    assert!(d < 1e-5, "{name}: GPU CSSM {} vs CSM {} at {:?}", gpu_v[i], csm_gpu[i], qs[i]);
                    worst.1 = worst.1.max(d);
                }
            }
        }
        for bias in [0.0, 0.0005] {
            let hard = technique("hard", &[("bias", bias), ("slope_bias", 0.0)], None);
            let pcss = soft("pcss", &[("bias", bias), ("slope_bias", 0.0)], [0.0, 0.0]);
            assert_eq!(
                cpu_visibility(&pcss, &map, &qs).unwrap_or_else(|e| panic!("{e}")),
                cpu_visibility(&hard, &map, &qs).unwrap_or_else(|e| panic!("{e}")),
                "{name}: CPU PCSS at width 0 is the hard shadow"
            );
            let a = reference.visibility(&pcss, &map, &qs).unwrap_or_else(|e| panic!("{e}")).0;
            let b = reference.visibility(&hard, &map, &qs).unwrap_or_else(|e| panic!("{e}")).0;
            assert_eq!(a, b, "{name}: GPU PCSS at width 0 is the hard shadow");
        }
    }
    eprintln!("width 0: |CSSM - CSM| CPU {:.3e}, GPU (mipmaps) {:.3e}", worst.0, worst.1);
}

#[test]
fn gpu_refuses_what_cpu_refuses() {
    let reference = GpuReference::new(gpu()).unwrap_or_else(|e| panic!("{e}"));
    let map = depth_map(8, |x, _| x as f32 / 8.0);
    let q = [Query {
        uv: [0.5, 0.5],
        d: 0.5,
        lod: 0.0,
    }];
    for t in refused() {
        let cpu = cpu_visibility(&t, &map, &q);
        let gpu = reference.visibility(&t, &map, &q);
        match (cpu, gpu) {
            (Err(a), Err(b)) => assert_eq!(a, b, "{t:?}: the references refuse with different messages"),
            (a, b) => panic!("{t:?}: expected both references to refuse it, got CPU {a:?}, GPU {b:?}"),
        }
    }
    let bad = DepthMap { size: 4, z: vec![0.5; 15] };
    assert!(reference.visibility(&Technique::new("hard"), &bad, &q).is_err());
    let over = depth_map(4, |_, _| 1.5);
    assert!(reference.visibility(&Technique::new("hard"), &over, &q).is_err());
    // no queries: nothing to run
    assert_eq!(reference.visibility(&Technique::new("csm"), &map, &[]), Ok((Vec::new(), 0.0)));
    // ln 65504 = 11.09: c = 11 fits F16
    let t = technique("esm", &[("c", 11.0)], Some(Storage::F16));
    let (v, _) = reference.visibility(&t, &map, &q).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(v.len(), 1);
}

// ---------------------------------------------------------------------------------------
// The CPU evaluator against the papers' equations

fn refused() -> Vec<Technique> {
    let mut inverted = LightFrame::query_plane(1.0);
    inverted.far = 4.0;
    vec![
        Technique::new("pcss"),
        Technique::new("cssm"),
        Technique::new("cssm").lit(inverted),
        Technique::new("cssm").lit(LightFrame::query_plane(1.0)).stored(Storage::F16),
        soft("pcss", &[("N", 0.0)], [1.0, 1.0]),
        soft("cssm", &[("filter", 2.0)], [1.0, 1.0]),
        technique("csm", &[("Q", 1.0)], None),
        technique("csm", &[("M", 65.0)], None),
        technique("csm", &[("M", 2.5)], None),
        technique("csm", &[("K", 4.0)], None),
        technique("csm", &[("alpha", f64::NAN)], None),
        technique("esm", &[], Some(Storage::F16)),
        // exp(2 c_pos) = e^80 does not fit F16
        technique("evsm", &[], Some(Storage::F16)),
        technique("evsm", &[("bias", 0.01)], None),
        technique("msm", &[("K", 2.0)], None),
        technique("hard", &[], Some(Storage::Unorm8)),
        technique("pcf", &[("N", 0.0)], None),
    ]
}

#[test]
fn cpu_refuses_bad_inputs_with_a_message() {
    let map = depth_map(8, |x, _| x as f32 / 8.0);
    let q = [Query {
        uv: [0.5, 0.5],
        d: 0.5,
        lod: 0.0,
    }];
    for t in refused() {
        let e = cpu_visibility(&t, &map, &q).expect_err(&format!("{t:?} should be refused"));
        assert!(!e.is_empty());
    }
    let e = cpu_visibility(&technique("esm", &[], Some(Storage::F16)), &map, &q).unwrap_err();
    assert!(e.contains("F16"), "{e}");
    for bad in [
        DepthMap { size: 0, z: vec![] },
        DepthMap { size: 2, z: vec![0.0; 3] },
        depth_map(2, |_, _| f32::NAN),
        depth_map(2, |_, _| -0.5),
    ] {
        assert!(cpu_visibility(&Technique::new("hard"), &bad, &q).is_err(), "{bad:?}");
    }
    // storage F32 is the depth's own precision: accepted for hard
    assert!(cpu_visibility(&technique("hard", &[], Some(Storage::F32)), &map, &q).is_ok());
}

#[test]
fn cpu_defaults_come_from_the_technique_files() {
    let r = sshc_tests::reference::resolve(&Technique::new("csm")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((r.int("M"), r.int("fix"), r.int("K"), r.storage), (4, 1, 3, Storage::Unorm8));
    let r = sshc_tests::reference::resolve(&Technique::new("esm")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((r.get("c"), r.int("classify"), r.storage), (80.0, 1, Storage::F32));
    let r = sshc_tests::reference::resolve(&Technique::new("pcf").with("N", 5.0)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(r.int("N"), 5);
}

/// A constant map: filters and mip chains leave it unchanged.
fn flat(size: u32, z: f32) -> DepthMap {
    depth_map(size, |_, _| z)
}

fn at(uv: [f32; 2], d: f32, lod: f32) -> Query {
    Query { uv, d, lod }
}

fn one(t: &Technique, map: &DepthMap, q: Query) -> f64 {
    cpu_visibility(t, map, &[q]).unwrap_or_else(|e| panic!("{e}"))[0]
}

#[test]
fn cpu_hard_is_the_binary_test() {
    // eq. 3.2 with the stored depth of the texel containing uv
    let map = depth_map(16, |x, _| if x < 8 { 0.3 } else { 0.7 });
    let t = technique("hard", &[("bias", 0.0)], None);
    assert_eq!(one(&t, &map, at([7.9 / 16.0, 0.5], 0.5, 0.0)), 0.0);
    assert_eq!(one(&t, &map, at([8.1 / 16.0, 0.5], 0.5, 0.0)), 1.0);
    assert_eq!(one(&t, &map, at([0.2, 0.5], 0.3, 0.0)), 1.0, "d = z is lit");
    assert_eq!(one(&t, &map, at([1.0, 1.0], 0.7, 0.0)), 1.0, "uv = 1 clamps to the last texel");
    let biased = technique("hard", &[("bias", 0.01)], None);
    assert_eq!(one(&biased, &map, at([0.2, 0.5], 0.305, 0.0)), 1.0);
}

#[test]
fn cpu_pcf_is_the_bilinear_tent() {
    // An edge between texels 7 (z = 0.3) and 8 (z = 0.7), receiver at 0.5: N = 1 is
    // bilinear PCF, lit fraction tf between the two texel centres.
    let map = depth_map(16, |x, _| if x < 8 { 0.3 } else { 0.7 });
    let pcf = |n: f64| technique("pcf", &[("N", n), ("bias", 0.0)], None);
    for t in [0.0, 0.25, 0.5, 0.9] {
        let uv = [(7.5 + t) as f32 / 16.0, 0.5];
        let v = one(&pcf(1.0), &map, at(uv, 0.5, 0.0));
        assert!((v - t).abs() < 1e-6, "N = 1 at tf = {t}: {v}");
        // N = 3: taps at texels 6..9 with weights (1 - tf, 1, 1, tf) / 9 per row, rows sum to 3
        let v = one(&pcf(3.0), &map, at(uv, 0.5, 0.0));
        assert!((v - (1.0 + t) / 3.0).abs() < 1e-6, "N = 3 at tf = {t}: {v}");
    }
    // far from the edge PCF is the binary test
    assert_eq!(one(&pcf(3.0), &map, at([0.1, 0.5], 0.5, 0.0)), 0.0);
    assert_eq!(one(&pcf(3.0), &map, at([0.9, 0.5], 0.5, 0.0)), 1.0);
}

#[test]
fn cpu_vsm_is_chebyshevs_bound() {
    let z0 = 0.4;
    let map = flat(16, z0 as f32);
    let t = technique("vsm", &[("bleed", 0.0), ("bias", 0.0)], None);
    let min_variance = 2e-5;
    assert_eq!(one(&t, &map, at([0.3, 0.6], 0.4, 1.5)), 1.0, "at the mean: lit");
    assert_eq!(one(&t, &map, at([0.3, 0.6], 0.2, 0.0)), 1.0, "in front: lit");
    for d in [0.41f32, 0.45, 0.9] {
        let delta = d as f64 - z0;
        // variance of a constant map: 0, clamped to the minimum (float rounding of z^2
        // leaves at most 1e-8)
        let expected = min_variance / (min_variance + delta * delta);
        let v = one(&t, &map, at([0.3, 0.6], d, 2.0));
        assert!((v - expected).abs() < 1e-3 * expected.max(1e-3), "d = {d}: {v} vs {expected}");
    }
    // an edge 0.3 | 0.7 averaged half-half: mean 0.5, variance 0.04, receiver at 0.9
    let map = depth_map(16, |x, _| if x < 8 { 0.3 } else { 0.7 });
    let t = technique("vsm", &[("bleed", 0.0), ("bias", 0.0), ("K", 1.0)], None);
    let v = one(&t, &map, at([0.5, 0.5], 0.9, 0.0));
    assert!((v - 0.04 / (0.04 + 0.16)).abs() < 1e-9, "{v}");
    // light-bleeding reduction: linstep(0.2, 1, p)
    let bled = technique("vsm", &[("bleed", 0.2), ("bias", 0.0), ("K", 1.0)], None);
    let w = one(&bled, &map, at([0.5, 0.5], 0.9, 0.0));
    assert!((w - (0.2 - 0.2) / 0.8).abs() < 1e-9, "{w}");
}

#[test]
fn cpu_esm_is_the_exponential_test() {
    // eq. 7.1-7.2 on a constant map: s = exp(-c (d - z)), clamped
    let z0 = 0.4;
    let map = flat(16, z0 as f32);
    let t = technique("esm", &[("classify", 0.0)], None);
    for (d, c) in [(0.45f32, 80.0), (0.41, 80.0), (0.7, 80.0)] {
        let expected = (-c * (d as f64 - z0 as f32 as f64)).exp();
        let v = one(&t, &map, at([0.5, 0.5], d, 0.0));
        assert!((v - expected).abs() < 1e-12 + 1e-9 * expected, "d = {d}: {v} vs {expected}");
    }
    assert_eq!(one(&t, &map, at([0.5, 0.5], 0.3, 0.0)), 1.0, "d < z overflows and clamps to lit");
    // Threshold classification (7.3.2) at a step: a receiver on the near side sees
    // e^{c (0.7 - 0.31)} under the kernel, falls back to the 2 x 2 ESM, which is lit at the
    // texels of the near side and ~0 at the far side's.
    let map = depth_map(16, |x, _| if x < 8 { 0.3 } else { 0.7 });
    let plain = technique("esm", &[("classify", 0.0), ("K", 3.0)], None);
    let threshold = technique("esm", &[("classify", 1.0), ("K", 3.0)], None);
    let zmax = technique("esm", &[("classify", 2.0), ("K", 3.0)], None);
    let q = at([(7.5 + 0.25) / 16.0, 0.5], 0.31, 0.0);
    assert_eq!(one(&plain, &map, q), 1.0, "without classification the overflow reads lit");
    // fallback: texel 7 (z = 0.3, d = 0.31): blurred e^{cz} = (2 e^{0.3c} + e^{0.7c}) / 3 per
    // row, times e^{-0.31c}, clamps to 1; texel 8: (e^{0.3c} + 2 e^{0.7c}) / 3 e^{-0.31c}
    // clamps to 1 too: the fallback reads 1.
    assert_eq!(one(&threshold, &map, q), 1.0);
    assert_eq!(one(&zmax, &map, q), 1.0);
    // a receiver behind the far side near the edge: e^{-c d} e^{c z} with z = 0.7 < d
    let q = at([(7.5 + 0.25) / 16.0, 0.5], 0.9, 0.0);
    let v = one(&threshold, &map, q);
    assert!(v < 1e-6, "{v}");
}

/// The warps of EVSM (Lauritzen & McCool 2008) at depth z: t = 2z - 1, w+ = e^{c+ t},
/// w- = -e^{-c- t}.
fn evsm_warps(z: f64, cp: f64, cn: f64) -> (f64, f64) {
    let t = 2.0 * z - 1.0;
    ((cp * t).exp(), -(-cn * t).exp())
}

#[test]
fn cpu_evsm_is_chebyshevs_bound_in_both_warps() {
    let (cp, cn, mv) = (40.0, 5.0, 2e-5);
    // a constant map: lit at and in front of it; behind it each warp's variance is the
    // least one, mv (c w(d))^2, and the smaller of the two bounds is the visibility
    let z0 = 0.4f32;
    let map = flat(16, z0);
    let t = technique("evsm", &[("bleed", 0.0)], None);
    for d in [0.0f32, 0.2, 0.399, 0.4] {
        // (the blur and the mip chain of a constant round by a few ulps)
        let v = one(&t, &map, at([0.3, 0.6], d, 1.5));
        assert!(v >= 1.0 - 1e-9, "d = {d}: in front of the map, lit: {v}");
    }
    let (p0, n0) = evsm_warps(z0 as f64, cp, cn);
    for d in [0.401f32, 0.41, 0.45, 0.9] {
        let (p, n) = evsm_warps(d as f64, cp, cn);
        let bound = |w: f64, w0: f64, c: f64| {
            let least = mv * (c * w) * (c * w);
            least / (least + (w - w0) * (w - w0))
        };
        let expected = bound(p, p0, cp).min(bound(n, n0, cn));
        let v = one(&t, &map, at([0.3, 0.6], d, 2.0));
        assert!((v - expected).abs() <= 1e-9 * expected.max(1e-6), "d = {d}: {v} vs {expected}");
    }
    // two planes 0.3 | 0.7 averaged half-half (K = 1, between the texels on the edge):
    // Chebyshev's bound is an upper bound of the lit fraction P(z >= d) in each warp, so the
    // visibility is at least 1/2 between the planes and the exact formula of the mixture
    let map = depth_map(16, |x, _| if x < 8 { 0.3 } else { 0.7 });
    let t = technique("evsm", &[("bleed", 0.0), ("K", 1.0), ("min_variance", 0.0)], None);
    let (pa, na) = evsm_warps(0.3f32 as f64, cp, cn);
    let (pb, nb) = evsm_warps(0.7f32 as f64, cp, cn);
    for d in [0.35f32, 0.5, 0.65, 0.69] {
        let v = one(&t, &map, at([0.5, 0.5], d, 0.0));
        assert!(v >= 0.5 - 1e-12, "d = {d}: {v} below the lit fraction 1/2");
        let (p, n) = evsm_warps(d as f64, cp, cn);
        let bound = |a: f64, b: f64, w: f64| {
            let mean = 0.5 * (a + b);
            let var = 0.5 * (a * a + b * b) - mean * mean;
            if w <= mean { 1.0 } else { var / (var + (w - mean) * (w - mean)) }
        };
        let expected = bound(pa, pb, p).min(bound(na, nb, n));
        assert!((v - expected).abs() <= 1e-9, "d = {d}: {v} vs {expected}");
    }
    // behind both planes the positive warp's bound is tiny (e^{16} against e^{32}), where
    // VSM's would be 0.04 / (0.04 + 0.16) = 0.2: EVSM's reduction of light bleeding
    let v = one(&t, &map, at([0.5, 0.5], 0.9, 0.0));
    assert!(v < 0.05, "{v}");
    // light-bleeding reduction: linstep(bleed, 1, p)
    let bled = technique("evsm", &[("bleed", 0.3), ("K", 1.0), ("min_variance", 0.0)], None);
    let w = one(&bled, &map, at([0.5, 0.5], 0.5, 0.0));
    let v = one(&t, &map, at([0.5, 0.5], 0.5, 0.0));
    assert!((w - ((v - 0.3) / 0.7).clamp(0.0, 1.0)).abs() < 1e-12, "{w} vs {v}");
}

/// MSM's biased moments (Peters & Klein 2015) of a distribution given as (depth, weight).
fn biased_moments(atoms: &[(f64, f64)], alpha: f64) -> [f64; 4] {
    std::array::from_fn(|k| {
        let m: f64 = atoms.iter().map(|(z, w)| w * z.powi(k as i32 + 1)).sum();
        (1.0 - alpha) * m + alpha * 0.5
    })
}

#[test]
fn cpu_msm_bounds_the_shadow_intensity() {
    let alpha = 3e-5;
    // G is a lower bound of the fraction in front of z_f over every distribution with the
    // biased moments, among them the actual one: the filter's depths with weight 1 - alpha
    // and the bias's atoms 0 and 1 with alpha / 2 each. And it is at least Chebyshev's
    // (Cantelli's) bound from the first two of them, 1 - var / (var + (z_f - mean)^2).
    let cantelli = |b: [f64; 4], zf: f64| {
        let var = b[1] - b[0] * b[0];
        if zf <= b[0] { 0.0 } else { 1.0 - var / (var + (zf - b[0]).powi(2)) }
    };
    let check = |atoms: &[(f64, f64)], zf: f64| -> f64 {
        let b = biased_moments(atoms, alpha);
        let g = cpu::msm_intensity(b, zf);
        let front: f64 = atoms.iter().filter(|(z, _)| *z < zf).map(|(_, w)| w).sum::<f64>() * (1.0 - alpha)
            + if zf > 0.0 { 0.5 * alpha } else { 0.0 }
            + if zf > 1.0 { 0.5 * alpha } else { 0.0 };
        assert!(g <= front + 1e-9, "{atoms:?} at {zf}: G = {g} above the actual fraction {front}");
        assert!(
            g >= cantelli(b, zf) - 1e-9,
            "{atoms:?} at {zf}: G = {g} below Cantelli's {}",
            cantelli(b, zf)
        );
        assert!((-1e-9..=1.0 + 1e-9).contains(&g), "{atoms:?} at {zf}: G = {g}");
        g
    };
    for atoms in [
        vec![(0.4, 1.0)],
        vec![(0.3, 0.5), (0.7, 0.5)],
        vec![(0.2, 0.25), (0.5, 0.5), (0.9, 0.25)],
        vec![(0.1, 0.1), (0.6, 0.9)],
    ] {
        for i in 0..=40 {
            check(&atoms, i as f64 / 40.0);
        }
    }
    // a single plane: a step at it (in front lit up to alpha / 2, behind within Cantelli's
    // bound of a variance of order alpha)
    let map = flat(16, 0.4);
    let t = technique("msm", &[("bias", 0.0)], None);
    for d in [0.0f32, 0.2, 0.39] {
        let v = one(&t, &map, at([0.3, 0.6], d, 1.0));
        assert!(v >= 1.0 - 0.5 * alpha - 1e-9, "d = {d}: {v}");
    }
    for d in [0.45f32, 0.6, 0.9] {
        let v = one(&t, &map, at([0.3, 0.6], d, 1.0));
        assert!(v <= 1e-2, "d = {d}: {v}");
    }
    // two planes 0.3 | 0.7 half-half (K = 1 at the edge): the CPU evaluator is the bound of
    // their biased moments, and between the planes it is within a few alpha of the
    // fraction 1/2 (without the bias the distribution would be determined by its moments)
    let map = depth_map(16, |x, _| if x < 8 { 0.3 } else { 0.7 });
    let t = technique("msm", &[("bias", 0.0), ("K", 1.0)], None);
    let atoms = [(0.3f32 as f64, 0.5), (0.7f32 as f64, 0.5)];
    for d in [0.35f32, 0.5, 0.65] {
        let v = one(&t, &map, at([0.5, 0.5], d, 0.0));
        let g = check(&atoms, d as f64);
        assert!((v - (1.0 - g)).abs() < 1e-9, "d = {d}: {v} vs 1 - {g}");
        eprintln!("two planes, d = {d}: visibility {v}");
        assert!((v - 0.5).abs() < 0.01, "d = {d}: {v}");
    }
}

#[test]
fn cpu_csm_approaches_the_step_as_m_grows() {
    // eq. 6.3 with c_k = pi (2k - 1): 1/2 + 2 sum sin(c_k (z - d)) / c_k is the square wave
    // of period 2, so it converges to 1 for d < z and to 0 for d > z (away from the jump,
    // at rate 1/(M |d - z|)); at d = z it reads 1/2 (fig. 6.3).
    let z0 = 0.5;
    let map = flat(16, z0);
    let csm = |m: f64| technique("csm", &[("M", m), ("alpha", 0.0), ("fix", 0.0), ("K", 1.0)], Some(Storage::F32));
    // the series before the final clamp
    let series = |m: f64, d: f32| {
        let pre = cpu::prefilter(&csm(m), &map).unwrap_or_else(|e| panic!("{e}"));
        cpu::shade(&pre, &at([0.5, 0.5], d, 0.0))
    };
    for d in [0.1f32, 0.3, 0.45, 0.55, 0.7, 0.9] {
        let step = if d < z0 { 1.0 } else { 0.0 };
        let errors: Vec<f64> = [1.0, 4.0, 16.0, 64.0].iter().map(|&m| (series(m, d) - step).abs()).collect();
        assert!(errors.windows(2).all(|w| w[1] < w[0]), "d = {d}: errors {errors:?}");
        // the tail (2/pi) sum_{k>M} sin((2k-1) pi t)/(2k-1), t = z - d, is bounded by Abel
        // summation: (2/pi) / ((2M + 1) |sin(pi t)|)
        let pi = std::f64::consts::PI;
        let tail = 2.0 / pi / (129.0 * (pi * (d - z0) as f64).sin().abs());
        assert!(errors[3] < tail, "d = {d}: {errors:?}, bound {tail}");
    }
    for m in [1.0, 4.0, 64.0] {
        let v = series(m, z0);
        assert!((v - 0.5).abs() < 1e-12, "M = {m}: d = z reads {v}");
    }
    // The fixes: offsetting d by 1/(2M) or scaling by 2 light the surface at d = z.
    let offset = technique("csm", &[("fix", 1.0)], None);
    let scaled = technique("csm", &[("fix", 2.0)], None);
    assert!(one(&offset, &map, at([0.5, 0.5], z0, 0.0)) > 0.95);
    assert_eq!(one(&scaled, &map, at([0.5, 0.5], z0, 0.0)), 1.0);
    // and both still shadow a receiver well behind
    assert!(one(&offset, &map, at([0.5, 0.5], 0.9, 0.0)) < 0.05);
    assert!(one(&scaled, &map, at([0.5, 0.5], 0.9, 0.0)) < 0.05);
}

#[test]
fn cpu_filters_and_mip_chains_follow_the_conventions() {
    let g = cpu::gaussian_weights(5, 1.5);
    assert!((g.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    assert!((g[0] - g[4]).abs() < 1e-15 && g[2] > g[1] && g[1] > g[0]);
    assert!((g[1] / g[2] - (-1.0f64 / (2.0 * 1.5 * 1.5)).exp()).abs() < 1e-12);
    // mip chain of a 24 x 24 map: 24, 12, 6, 3, 1; the 1 x 1 level is the mean of the
    // 2 x 2 texels at the corner of the 3 x 3 level (the odd edge clamps)
    let map = depth_map(24, |x, y| ((x * 7 + y * 3) % 11) as f32 / 11.0);
    let t = technique("vsm", &[("K", 1.0)], None);
    let pre = cpu::prefilter(&t, &map).unwrap_or_else(|e| panic!("{e}"));
    let chain = pre.channel("m1").unwrap_or_else(|| panic!("m1"));
    let sizes: Vec<usize> = chain.levels.iter().map(|l| l.size).collect();
    assert_eq!(sizes, [24, 12, 6, 3, 1]);
    let l3 = &chain.levels[3];
    let expected = (l3.at(0, 0) + l3.at(1, 0) + l3.at(0, 1) + l3.at(1, 1)) / 4.0;
    assert!((chain.levels[4].texels[0] - expected).abs() < 1e-15);
    // a box blur clamps at the edge: texel 0 of a ramp is (2 z0 + z1) / 3
    let ramp = depth_map(8, |x, _| x as f32 / 8.0);
    let blurred = cpu::convolve(
        &cpu::prefilter(&t, &ramp).unwrap_or_else(|e| panic!("{e}")).depth.levels[0],
        &cpu::box_weights(3),
    );
    assert!((blurred.at(0, 3) - (2.0 * 0.0 + 0.125) / 3.0).abs() < 1e-15);
    // sampling at texel centres returns the texels; lod beyond the chain clamps
    let q = [0.5 + 0.5 / 24.0, 0.5 / 24.0];
    assert!((chain.sample(q, 0.0) - chain.base().at(12, 0)).abs() < 1e-15);
    assert_eq!(chain.sample(q, 9.0), chain.levels[4].texels[0]);
    // fetch and nearest
    assert_eq!(chain.nearest([0.999, 0.0]), chain.base().at(23, 0));
    assert_eq!(chain.fetch([0.5 / 24.0, 0.5 / 24.0], -1, 1), chain.base().at(0, 1));
}

#[test]
fn cpu_results_stay_in_the_unit_interval() {
    let configs = [
        technique("hard", &[], None),
        technique("pcf", &[("N", 15.0)], None),
        technique("vsm", &[("min_variance", 0.0), ("bleed", 0.0)], None),
        technique("esm", &[("c", 88.0), ("classify", 2.0)], None),
        technique("evsm", &[("min_variance", 0.0), ("c_pos", 42.0), ("c_neg", 0.0)], None),
        technique("msm", &[("alpha", 0.0)], None),
        technique("msm", &[("alpha", 0.1), ("K", 1.0)], None),
        technique("csm", &[("M", 64.0), ("alpha", 0.0), ("fix", 2.0)], None),
        soft("cssm", &[("M", 16.0), ("alpha", 0.0), ("min_blocker", 0.0)], [4.0, 4.0]),
        soft("cssm", &[("filter", 1.0), ("A", 100.0), ("B", 1000.0)], [4.0, 0.0]),
        soft("pcss", &[("N", 2.0), ("M", 3.0)], [20.0, 20.0]),
    ];
    let mut extremes = vec![
        at([0.0, 0.0], 0.0, 0.0),
        at([1.0, 1.0], 1.0, 100.0),
        at([0.5, 0.5], 0.5, -3.0),
        at([-0.5, 1.5], 0.5, 0.0),
        at([0.5, 0.5], f32::NAN, f32::NAN),
    ];
    for (_, map) in maps() {
        extremes.extend(queries(&map, 7).into_iter().take(40));
        for t in &configs {
            let v = cpu_visibility(t, &map, &extremes).unwrap_or_else(|e| panic!("{e}"));
            assert!(v.iter().all(|v| (0.0..=1.0).contains(v)), "{t:?}: {v:?}");
        }
    }
}

#[test]
fn cpu_summed_area_boxes_follow_the_conventions() {
    // sample_box integrates the piecewise-constant texels over the clipped box: a one-texel
    // box is bilinear interpolation, the whole map its mean, and boxes never shrink below a
    // texel.
    let map = depth_map(8, |x, y| ((x * 5 + y * 3) % 7) as f32 / 7.0);
    let level = cpu::Level {
        size: 8,
        texels: map.z.iter().map(|&z| z as f64).collect(),
    };
    let table = cpu::Table::new(&level);
    for uv in [[0.31, 0.62], [0.5, 0.5], [0.07, 0.93], [1.0 / 16.0, 3.0 / 16.0]] {
        let bilinear = level.bilinear(uv).value;
        assert!((table.box_mean(uv, [1.0 / 8.0, 1.0 / 8.0]) - bilinear).abs() < 1e-12, "{uv:?}");
        assert!((table.box_mean(uv, [0.0, 0.01]) - bilinear).abs() < 1e-12, "{uv:?}");
    }
    let mean = level.texels.iter().sum::<f64>() / 64.0;
    assert!((table.box_mean([0.5, 0.5], [1.0, 1.0]) - mean).abs() < 1e-12);
    assert!((table.box_mean([0.5, 0.5], [5.0, 3.0]) - mean).abs() < 1e-12, "clipped to the map");
    // a box over the left half-map's corner: clipped to [0, 2] x [0, 2] texels
    let corner = (level.at(0, 0) + level.at(1, 0) + level.at(0, 1) + level.at(1, 1)) / 4.0;
    assert!((table.box_mean([0.0, 0.0], [0.5, 0.5]) - corner).abs() < 1e-12);
}

#[test]
fn cpu_cssm_follows_eq_8_6_to_8_9() {
    // A flat occluder at z0 over the whole map: the filtered series equals the point series
    // at any kernel, 1 - s_f the complementary test, and num / (1 - s_f) = z0 exactly (the
    // z-weighted series is z0 times the complementary one, eq. 8.5-8.8).
    let z0 = 0.3f32;
    let map = flat(16, z0);
    let t = soft(
        "cssm",
        &[
            ("slope_bias", 0.0),
            ("alpha", 0.0),
            ("ring", 0.0),
            ("A", 0.0),
            ("fix", 0.0),
            ("M", 16.0),
        ],
        [1.0, 1.0],
    );
    for filter in [0.0, 1.0] {
        let t = t.clone().with("filter", filter);
        let pre = cpu::prefilter(&t, &map).unwrap_or_else(|e| panic!("{e}"));
        for d in [0.5f32, 0.7, 0.9] {
            let tr = cpu::cssm_trace(&pre, &at([0.4, 0.6], d, 0.0));
            assert!(!tr.no_blocker, "d = {d}");
            assert!((tr.zavg - z0 as f64).abs() < 1e-9, "d = {d}: z_avg {} vs {z0}", tr.zavg);
            // 8.3.1: f_w = (W / d) ((d - z_avg) / z_avg) near in world units, / 2 in uv
            let (near, far) = (8.0, 12.0);
            let (dw, zw) = (near + d as f64 * (far - near), near + z0 as f64 * (far - near));
            let fw = (1.0 / dw) * ((dw - zw) / zw) * near / 2.0;
            assert!(
                (tr.u1[0] - fw).abs() < 1e-12 && (tr.u1[1] - fw).abs() < 1e-12,
                "{:?} vs {fw}",
                tr.u1
            );
            // deep behind the occluder the series is near 0
            assert!(tr.value < 0.05, "d = {d}: {}", tr.value);
        }
        // in front of the occluder: lit
        let v = cpu_visibility(&t, &map, &[at([0.4, 0.6], 0.1, 0.0)]).unwrap_or_else(|e| panic!("{e}"))[0];
        assert!(v > 0.95, "{v}");
    }
    // eq. 8.9: the sharpening exponent p = 1 + A exp(-B (d - z_avg))
    let r = sshc_tests::reference::resolve(&soft("cssm", &[("A", 10.0), ("B", 16.0)], [1.0, 1.0])).unwrap_or_else(|e| panic!("{e}"));
    assert!((cpu::cssm_sharpening(&r, 0.5, 0.5) - 11.0).abs() < 1e-12);
    assert!((cpu::cssm_sharpening(&r, 0.6, 0.5) - (1.0 + 10.0 * (-1.6f64).exp())).abs() < 1e-12);
    // 8.2.3: (s - ring) / (1 - 2 ring), clamped
    assert!((cpu::cssm_ringing(&r, 0.5) - 0.5).abs() < 1e-12);
    assert_eq!(cpu::cssm_ringing(&r, 0.04), 0.0);
    assert_eq!(cpu::cssm_ringing(&r, 0.96), 1.0);
}

#[test]
fn cpu_pcss_penumbra_follows_the_blocker_distance() {
    // A half-plane occluder at z_b (x < 8 of 16 texels), an empty rest (z = 1): across the
    // edge the lit fraction rises from 0 to 1 over the penumbra width
    // w = (d_r - d_b) light_width / d_b projected to the near plane.
    let zb = 0.25f32;
    let map = depth_map(16, |x, _| if x < 8 { zb } else { 1.0 });
    let t = soft("pcss", &[("slope_bias", 0.0), ("bias", 0.0), ("M", 16.0)], [1.0, 1.0]);
    let d = 0.75f32;
    let pre = cpu::prefilter(&t, &map).unwrap_or_else(|e| panic!("{e}"));
    let (near, far) = (8.0, 12.0);
    let (dr, db) = (near + d as f64 * (far - near), near + zb as f64 * (far - near));
    let width = (dr - db) / db * near / dr / 2.0;
    let mut last = -1.0;
    for i in 0..=20 {
        let u = 0.5 + width * (i as f64 / 10.0 - 1.0);
        let tr = cpu::pcss_trace(&pre, &at([u as f32, 0.5], d, 0.0));
        if tr.count > 0 {
            assert!((tr.zb - zb as f64).abs() < 1e-12);
            assert!((tr.pu[0] - width).abs() < 1e-12, "{:?} vs {width}", tr.pu);
        }
        assert!(tr.value >= last, "monotone across the edge");
        last = tr.value;
    }
    let v = |u: f32| cpu::pcss_trace(&pre, &at([u, 0.5], d, 0.0)).value;
    assert_eq!(v(0.5 - 1.2 * width as f32), 0.0);
    assert_eq!(v(0.5 + 1.2 * width as f32), 1.0);
    assert!((v(0.5) - 0.5).abs() <= 1.0 / 16.0, "{}", v(0.5));
}
