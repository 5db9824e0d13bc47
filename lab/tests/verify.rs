//! `sshc verify` catches code generation bugs: the shaders of a compiled technique with a
//! bug injected into their WGSL (as a faulty code generator would emit it) run on the GPU
//! and are compared with the CPU evaluation of the unchanged IR; every injected bug must
//! make some input DIFFER, and the shaders as generated must agree. On a real adapter
//! (lavapipe without a GPU); never skipped.

use sshc_lab::verify::{self, Input, Options, Source, Verdict};
use sshc_runtime::gpu::Gpu;

mod common;
use common::root;

fn compile(name: &str) -> sshc::Compiled {
    let path = root().join("techniques").join(format!("{name}.ron"));
    let src = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    sshc::compile_str(&src, &sshc::CompileOptions::default()).unwrap_or_else(|d| panic!("{}", d.render(name, &src)))
}

/// The rows of `c` on a 16^2 map: an edge, noise and the bunny's depth map.
fn rows(gpu: &Gpu, c: &sshc::Compiled) -> Vec<verify::Row> {
    let n = 16;
    let mut inputs: Vec<Input> = ["step", "noise"]
        .iter()
        .map(|f| Input {
            name: f.to_string(),
            source: Source::Depth(verify::depth_field(f, n).expect("a bundled field")),
        })
        .collect();
    inputs.push(Input {
        name: "bunny".into(),
        source: Source::Depth(verify::scene_depth(gpu, &root().join("scenes/bunny.ron"), n).unwrap_or_else(|e| panic!("{e}"))),
    });
    let opts = Options {
        shadow: n,
        ..Options::default()
    };
    verify::verify(gpu, c, None, &inputs, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{e}"))
}

fn verdicts(rows: &[verify::Row]) -> Vec<Verdict> {
    rows.iter().map(|r| r.verdict).collect()
}

/// `c` with `from` replaced by `to` in the module of pass `pass` (which must contain it).
fn injected(c: &sshc::Compiled, pass: &str, from: &str, to: &str) -> sshc::Compiled {
    let mut bad = c.clone();
    let file = format!("{}.{pass}.wgsl", c.technique());
    let module = bad
        .shaders
        .iter_mut()
        .find(|(name, _)| *name == file)
        .unwrap_or_else(|| panic!("no module {file}"));
    assert!(module.1.contains(from), "{file} lacks `{from}`");
    module.1 = module.1.replacen(from, to, 1);
    bad
}

#[test]
fn injected_code_generation_bugs_are_caught() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("verify needs an adapter: {e}"));
    // the receiver's normalised depth off by 2 % (a wrong depth range in the prelude)
    let depth = (
        "let in_d = (in_d_world - frame.depth_range.x) * frame.depth_range.z;",
        "let in_d = (in_d_world - frame.depth_range.x) * frame.depth_range.z * 1.02;",
    );
    for (technique, pass, from, to) in [
        ("hard", "shade", depth.0, depth.1),
        ("pcf", "shade", depth.0, depth.1),
        ("vsm", "shade", depth.0, depth.1),
        ("esm", "shade", depth.0, depth.1),
        // a built-in mapped to the wrong WGSL function: CSM's basis sin(c_k z) as cos
        ("csm", "basis", "sin(", "cos("),
    ] {
        let c = compile(technique);
        let good = verdicts(&rows(&gpu, &c));
        assert!(good.iter().all(|v| *v == Verdict::Agrees), "{technique} as generated: {good:?}");
        let bad = rows(&gpu, &injected(&c, pass, from, to));
        assert!(
            verdicts(&bad).contains(&Verdict::Differs),
            "{technique} with `{from}` -> `{to}` in `{pass}` was not caught: {:?}",
            verdicts(&bad)
        );
        // the picture of a row that differs shows where, in red
        let row = bad.iter().find(|r| r.verdict == Verdict::Differs).expect("a row that differs");
        let red = row.picture(1).pixels().filter(|p| p.0 == [230, 20, 20]).count();
        assert_eq!(red, row.outside, "{technique}: one red pixel per receiver outside");
    }
}

/// The rows of `c` on a 16^2 map over two caster sets above the plane.
fn caster_rows(gpu: &Gpu, c: &sshc::Compiled) -> Vec<verify::Row> {
    let inputs: Vec<Input> = ["box", "bars"]
        .iter()
        .map(|s| {
            let (vertices, meshes) = verify::caster_set(s).expect("a bundled caster set");
            Input {
                name: s.to_string(),
                source: Source::Casters(vertices, meshes),
            }
        })
        .collect();
    let opts = Options {
        shadow: 16,
        ..Options::default()
    };
    verify::verify(gpu, c, None, &inputs, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{e}"))
}

/// Bugs are caught in light samples' views and downstream of Geometry passes: one sample's
/// receiver depth off by 2 % (point samples, on depth fields), sample 0's depth test reading
/// sample 1's layer (linear light, on casters), and Geometry outputs read at the wrong
/// place: the penumbra map's `nearest` rounding instead of flooring (half a texel), the
/// smoothies' filtered lookup one texel off.
#[test]
fn injected_bugs_in_sample_views_and_after_geometry_passes_are_caught() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("verify needs an adapter: {e}"));
    let sample = |k: u32| {
        (
            format!("let in_d_v{k} = (in_d_world_v{k} - sv{k}.depth_range.x) * sv{k}.depth_range.z;"),
            format!("let in_d_v{k} = (in_d_world_v{k} - sv{k}.depth_range.x) * sv{k}.depth_range.z * 1.02;"),
        )
    };
    let layer = ("1i), 0i, 0i);".to_string(), "1i), 1i, 0i);".to_string());
    for (technique, (from, to), casters) in [
        ("point-samples", sample(1), false),
        ("linear-light", layer, true),
        (
            "penumbra-maps",
            (
                "floor(in_uv * frame.shadow_size.xy)".into(),
                "round(in_uv * frame.shadow_size.xy)".into(),
            ),
            true,
        ),
        (
            "smoothies",
            (
                "textureSample(t_ramps, smp, in_uv,".into(),
                "textureSample(t_ramps, smp, in_uv + frame.shadow_size.zw,".into(),
            ),
            true,
        ),
    ] {
        let c = compile(technique);
        let rows = |c: &sshc::Compiled| if casters { caster_rows(&gpu, c) } else { rows(&gpu, c) };
        let good = verdicts(&rows(&c));
        assert!(good.iter().all(|v| *v == Verdict::Agrees), "{technique} as generated: {good:?}");
        let bad = verdicts(&rows(&injected(&c, "shade", &from, &to)));
        assert!(bad.contains(&Verdict::Differs), "{technique} with `{to}` was not caught: {bad:?}");
    }
}

/// `verify --cascades 3`: the light's view split into three cascades of the query plane,
/// each rasterised and shaded by its own passes and mixed by the combining step, against
/// the CPU's evaluation of each cascade from what that cascade rasterised, mixed as
/// `runtime/src/lights.rs` states. Every receiver agrees, for a depth-map technique and a
/// Geometry technique, and the cascades are not the single map in disguise: the GPU's
/// visibility differs from one cascade's at many receivers.
#[test]
fn cascaded_techniques_are_verified_on_the_cpu() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("verify needs an adapter: {e}"));
    let n = 16;
    let field = Input {
        name: "checker".into(),
        source: Source::Depth(verify::depth_field("checker", n).expect("a bundled field")),
    };
    let (vertices, meshes) = verify::caster_set("box").expect("a bundled caster set");
    let casters = Input {
        name: "box".into(),
        source: Source::Casters(vertices, meshes),
    };
    for (t, input) in [("pcss", field), ("penumbra-limit-maps", casters)] {
        let c = compile(t);
        let run = |cascades| {
            let opts = Options {
                shadow: n,
                cascades,
                cascade_band: 0.2,
                ..Options::default()
            };
            verify::verify(&gpu, &c, None, std::slice::from_ref(&input), &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{t}: {e}"))
        };
        let (one, three) = (run(1), run(3));
        for r in &three {
            assert_eq!(r.verdict, Verdict::Agrees, "{t}, {} (camera {}): {:?}", r.input, r.camera, r.worst);
        }
        let moved: usize = one
            .iter()
            .zip(&three)
            .map(|(a, b)| a.compared.iter().zip(&b.compared).filter(|(x, y)| x.1 != y.1).count())
            .sum();
        let receivers: usize = three.iter().map(|r| r.receivers).sum();
        assert!(
            moved * 10 > receivers,
            "{t}: only {moved} of {receivers} receivers changed under three cascades"
        );
    }
}

/// A probe of the region and level lookups: `sample_box_at` and `nearest` / `nearest_at` on
/// a summed-area table, `sample_width_at` on a mean mip chain, `nearest_level` on a max mip
/// chain. The GPU agrees with the CPU's f64 evaluation (the compiler's own reading of each
/// lookup) on every input, and a bug injected into each lookup's WGSL is caught.
const REGION_PROBE: &str = r#"Technique(
    name: "region_probe",
    channels: {
        "z": Channel(precision: F32),
        "m": Channel(precision: Unorm8, value: "z"),
        "a": Channel(precision: F16, value: "z"),
        "x": Channel(precision: F16, value: "z"),
    },
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Map(name: "map", reads: ["shadow"], writes: "mapped", channels: ["m"]),
        SummedArea(name: "sat", reads: "mapped", writes: "table"),
        Map(name: "mean", reads: ["shadow"], writes: "means", channels: ["a"]),
        Mipmap(name: "mips", reads: "means", writes: "mean_mips", reduce: Mean),
        Map(name: "maxes", reads: ["shadow"], writes: "max_base", channels: ["x"]),
        Mipmap(name: "max_mips", reads: "max_base", writes: "max_chain", reduce: Max),
        Shade(name: "shade", reads: ["table", "mean_mips", "max_chain"],
              visibility: "saturate(0.2 * (sample_box_at(m, 2.0 * texel_size, -1.0 * texel_size, 3.0 * texel_size, 2.0 * texel_size) + nearest(m) + nearest_at(m, texel_size, 0.0) + sample_width_at(a, -2.0 * texel_size, texel_size, 4.0 * texel_size) + nearest_level(x, 2)))"),
    ],
)"#;

#[test]
fn region_and_level_lookups_agree_and_injected_bugs_are_caught() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("verify needs an adapter: {e}"));
    let c = sshc::compile_str(REGION_PROBE, &sshc::CompileOptions::default())
        .unwrap_or_else(|d| panic!("{}", d.render("region_probe", REGION_PROBE)));
    let good = verdicts(&rows(&gpu, &c));
    assert!(good.iter().all(|v| *v == Verdict::Agrees), "as generated: {good:?}");
    for (what, from, to) in [
        // the box's centre moved the wrong way
        ("sample_box_at", "box_table(in_uv + vec2<f32>(", "box_table(in_uv - vec2<f32>("),
        // the table's texel rounded instead of floored
        (
            "nearest on a table",
            "floor(uv * n)), vec2<i32>(0i)",
            "floor(uv * n + 0.5)), vec2<i32>(0i)",
        ),
        // the footprint's centre moved the wrong way
        ("sample_width_at", "smp, in_uv + vec2<f32>(", "smp, in_uv - vec2<f32>("),
        // the texel looked up at level 2's coordinates in level 1
        (
            "nearest_level",
            "), 0i, clamp(2i, 0i, i32(textureNumLevels(t_max_base)) - 1i));",
            "), 0i, clamp(1i, 0i, i32(textureNumLevels(t_max_base)) - 1i));",
        ),
    ] {
        let bad = rows(&gpu, &injected(&c, "shade", from, to));
        assert!(
            verdicts(&bad).contains(&Verdict::Differs),
            "{what}: `{from}` -> `{to}` was not caught: {:?}",
            verdicts(&bad)
        );
    }
}

/// `sample_mip_box` and `sample_mip_box_at` (issue 51) on a Mean chain at F16 and Unorm8:
/// the GPU agrees with the CPU's f64 reading (`interp`'s `Texels::mip_box`) on every
/// input, and a bug injected into the WGSL's box (its lower edge a tenth too near) is
/// caught.
const MIP_BOX_PROBE: &str = r#"Technique(
    name: "mip_box_probe",
    channels: {
        "z": Channel(precision: F32),
        "a": Channel(precision: F16, value: "z"),
        "b": Channel(precision: Unorm8, value: "z * z"),
    },
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Map(name: "mean", reads: ["shadow"], writes: "means", channels: ["a", "b"]),
        Mipmap(name: "mips", reads: "means", writes: "chain", reduce: Mean),
        Shade(name: "shade", reads: ["chain"],
              visibility: "saturate(0.25 * (sample_mip_box(a, 3.0 * texel_size) + sample_mip_box_at(b, 1.5 * texel_size, -0.5 * texel_size, 5.0 * texel_size) + sample_mip_box(b, 1.0 * texel_size) + sample_mip_box_at(a, -2.0 * texel_size, 0.0, 9.0 * texel_size)))"),
    ],
)"#;

#[test]
fn mip_box_lookups_agree_and_an_injected_bug_is_caught() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("verify needs an adapter: {e}"));
    let c = sshc::compile_str(MIP_BOX_PROBE, &sshc::CompileOptions::default())
        .unwrap_or_else(|d| panic!("{}", d.render("mip_box_probe", MIP_BOX_PROBE)));
    let good = verdicts(&rows(&gpu, &c));
    assert!(good.iter().all(|v| *v == Verdict::Agrees), "as generated: {good:?}");
    let bad = rows(
        &gpu,
        &injected(&c, "shade", "max((c - 0.5 * width) / s", "max((c - 0.45 * width) / s"),
    );
    assert!(verdicts(&bad).contains(&Verdict::Differs), "not caught: {:?}", verdicts(&bad));
}

/// A probe of real branches (`if c { a } else { b }`): a branch in a Map channel's value,
/// and in the Shade an `else if` chain whose arms share a value, read a lookup with an
/// implicit level bound before the `if`, and hold a series whose branch folds per term.
/// The GPU agrees with the CPU's f64 evaluation on every input; the arms really are
/// inside the `if` (the taps of the last arm are read there only); a negated condition is
/// caught on either side.
const BRANCH_PROBE: &str = r#"Technique(
    name: "branch_probe",
    channels: {
        "z": Channel(precision: F32),
        "w": Channel(precision: F32, value: "if z > 0.5 { z * z } else { 1.0 - z }"),
    },
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Map(name: "map", reads: ["shadow"], writes: "mapped", channels: ["w"]),
        Shade(name: "shade", reads: ["shadow", "mapped"], visibility: "
            let s = sample(z);
            let shared = 0.5 * nearest(w);
            let v = if d <= s {
                shared + 0.5
            } else if d < s + 0.05 {
                shared + 0.1 * sum(i in -1..=1, if i == 0 { 0.0 } else { nearest_at(w, f32(i) * texel_size, 0.0) })
            } else {
                shared * select(0.0, 1.0, d <= fetch(z, 1, 0))
            };
            saturate(v)
        "),
    ],
)"#;

#[test]
fn branches_agree_and_a_negated_condition_is_caught() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("verify needs an adapter: {e}"));
    let c = sshc::compile_str(BRANCH_PROBE, &sshc::CompileOptions::default())
        .unwrap_or_else(|d| panic!("{}", d.render("branch_probe", BRANCH_PROBE)));
    let good = verdicts(&rows(&gpu, &c));
    assert!(good.iter().all(|v| *v == Verdict::Agrees), "as generated: {good:?}");
    let shade = &c
        .shaders
        .iter()
        .find(|(n, _)| n.ends_with(".shade.wgsl"))
        .expect("a shade module")
        .1;
    // the last arm's tap is read inside the inner `if`'s `else`, after both conditions
    let (inner_else, fetch) = (shade.find("    } else {\n").expect("an else"), shade.find("vec2<i32>(1i, 0i)"));
    assert!(fetch.is_some_and(|f| f > inner_else), "the tap is read outside its arm:\n{shade}");
    for pass in ["map", "shade"] {
        let bad = rows(&gpu, &injected(&c, pass, "if e", "if !e"));
        assert!(
            verdicts(&bad).contains(&Verdict::Differs),
            "{pass}: a negated condition was not caught: {:?}",
            verdicts(&bad)
        );
    }
}

/// A probe of the tables over float channels: f32 sums (`sum: F32`) and fixed-point codes
/// (`sum: Fixed(bits: 12)`), read by `sample_box_at`, `sample_box`, `nearest` and
/// `nearest_at`. The GPU agrees with the CPU's model of each table (f32 sums within their
/// bound, fixed-point codes within half a step) on every input; a wrong centre, a wrong
/// code scale and a wrong decode are each caught.
const FLOAT_TABLE_PROBE: &str = r#"Technique(
    name: "float_table_probe",
    channels: {
        "z": Channel(precision: F32),
        "m": Channel(precision: F32, value: "z"),
        "q": Channel(precision: F32, value: "z * z", range: (0.0, 1.0)),
    },
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Map(name: "map", reads: ["shadow"], writes: "mapped", channels: ["m"]),
        SummedArea(name: "sat", reads: "mapped", writes: "table", sum: F32),
        Map(name: "map2", reads: ["shadow"], writes: "mapped2", channels: ["q"]),
        SummedArea(name: "sat2", reads: "mapped2", writes: "table2", sum: Fixed(bits: 12)),
        Shade(name: "shade", reads: ["table", "table2"],
              visibility: "saturate(0.25 * (sample_box_at(m, 2.0 * texel_size, -1.0 * texel_size, 3.0 * texel_size, 2.0 * texel_size) + nearest(m) + sample_box(q, 5.0 * texel_size, 3.0 * texel_size) + nearest_at(q, texel_size, 0.0)))"),
    ],
)"#;

#[test]
fn float_tables_agree_and_injected_bugs_are_caught() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("verify needs an adapter: {e}"));
    let c = sshc::compile_str(FLOAT_TABLE_PROBE, &sshc::CompileOptions::default())
        .unwrap_or_else(|d| panic!("{}", d.render("float_table_probe", FLOAT_TABLE_PROBE)));
    let good = verdicts(&rows(&gpu, &c));
    assert!(good.iter().all(|v| *v == Verdict::Agrees), "as generated: {good:?}");
    for (what, pass, from, to) in [
        // the f32 table's centre subtracted, but not the one added back
        ("f32 centre", "sat", "- vec4<f32>(5e-1f,", "- vec4<f32>(4.9e-1f,"),
        // fixed-point codes at a scale one code short of the lookup's
        ("fixed scale", "sat2", "* 4095.0));", "* 4094.0));"),
        // the fixed-point decode offset by a thousandth of the range
        ("fixed decode", "shade", "(0.0f + s3.x * 1.0f)", "(1e-3f + s3.x * 1.0f)"),
    ] {
        let bad = rows(&gpu, &injected(&c, pass, from, to));
        assert!(
            verdicts(&bad).contains(&Verdict::Differs),
            "{what}: `{from}` -> `{to}` was not caught: {:?}",
            verdicts(&bad)
        );
    }
}

/// A declared channel range (`range: (lo, hi)`): the value `4z - 1` (in [-1, 3]) clamped
/// to (0, 1) at F16 and to (0, 2) at Unorm8, encoded over the declared range. The GPU
/// agrees with the CPU's evaluation (which clamps as declared) and `verify` reports the
/// clamped texels; the clamp removed from the Map's WGSL is caught.
const DECLARED_RANGE: &str = r#"Technique(
    name: "declared_range",
    channels: {
        "z": Channel(precision: F32),
        "a": Channel(precision: F16, value: "z * 4.0 - 1.0", range: (0.0, 1.0)),
        "b": Channel(precision: Unorm8, value: "z * 4.0 - 1.0", range: (0.0, 2.0)),
    },
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Map(name: "map", reads: ["shadow"], writes: "mapped", channels: ["a", "b"]),
        Shade(name: "shade", reads: ["mapped"], visibility: "saturate(0.5 * nearest(a) + 0.25 * nearest(b))"),
    ],
)"#;

#[test]
fn declared_ranges_clamp_at_encode_and_verify_reports_the_clamped_texels() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("verify needs an adapter: {e}"));
    let dumped = sshc::CompileOptions {
        dump_after: Some(sshc::DumpPhase::Pack),
        ..Default::default()
    };
    let out = sshc::compile_with_dump(DECLARED_RANGE, &dumped);
    let c = out
        .result
        .unwrap_or_else(|d| panic!("{}", d.render("declared_range", DECLARED_RANGE)));
    // the encodes use the declared ranges: b's Unorm8 over [0, 2] (the layout's dump)
    let dump = out.dump.expect("dumped after pack");
    assert!(dump.contains("b : Unorm8 range [0, 2] stored as"), "{dump}");
    let good = rows(&gpu, &c);
    assert!(verdicts(&good).iter().all(|v| *v == Verdict::Agrees), "{:?}", verdicts(&good));
    // the step and noise fields and the bunny hold depths below 1/4 and above 3/4
    let clamped: usize = good.iter().flat_map(|r| &r.clamped).map(|(_, n)| n).sum();
    assert!(
        clamped > 0,
        "no texel was clamped: {:?}",
        good.iter().map(|r| &r.clamped).collect::<Vec<_>>()
    );
    assert!(good.iter().flat_map(|r| &r.clamped).any(|(name, _)| name == "a"));
    let bad = rows(&gpu, &injected(&c, "map", "clamp(e4, 0.0f, 1.0f)", "e4"));
    assert!(
        verdicts(&bad).contains(&Verdict::Differs),
        "the clamp removed was not caught: {:?}",
        verdicts(&bad)
    );
}

/// Debug outputs (`debug: {...}`, compiled with `--debug`) are compared with their CPU
/// evaluation as the visibility is: the vssm-subdivided example's region mean depth
/// `z_mean` (four summed-area lookups) and the receiver's biased depth `receiver` (the
/// query plane's closed form, `d = 1 - u`, less the bias) agree in the forward and the
/// deferred Shade and in each of two cascades; a bug injected into one output's store (its
/// value 1 % high, as a code generator writing the wrong node would) makes that output
/// DIFFER while the visibility and the other output still agree.
#[test]
fn debug_outputs_agree_with_the_cpu_and_a_bug_in_one_is_caught() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("verify needs an adapter: {e}"));
    let path = root().join("techniques/examples/vssm-subdivided.ron");
    let src = std::fs::read_to_string(&path).unwrap();
    let n = 16;
    let inputs: Vec<Input> = ["step", "noise"]
        .iter()
        .map(|f| Input {
            name: f.to_string(),
            source: Source::Depth(verify::depth_field(f, n).expect("a bundled field")),
        })
        .collect();
    let run = |c: &sshc::Compiled, cascades: u32| {
        let opts = Options {
            shadow: n,
            cascades,
            ..Options::default()
        };
        verify::verify(&gpu, c, None, &inputs, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{e}"))
    };
    let outputs = |r: &verify::Row| r.debug.iter().map(|d| (d.name.clone(), d.outside)).collect::<Vec<_>>();
    for (schedule, from, to) in [
        ("fragment", "out.debug_z_mean = vec4<f32>(", "out.debug_z_mean = 1.01 * vec4<f32>("),
        (
            "compute",
            "textureStore(o_debug_z_mean, pixel, 0i, vec4<f32>(e",
            "textureStore(o_debug_z_mean, pixel, 0i, 1.01 * vec4<f32>(e",
        ),
    ] {
        let opts = sshc::CompileOptions {
            debug: true,
            schedule: vec![("shade".into(), schedule.into())],
            ..Default::default()
        };
        let c = sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render("vssm-subdivided", &src)));
        let cascades = if schedule == "fragment" { [1, 2].as_slice() } else { &[1] };
        for &k in cascades {
            for r in run(&c, k) {
                assert_eq!(
                    r.verdict,
                    Verdict::Agrees,
                    "{schedule}, {k} cascade(s), {}: {:?} {:?}",
                    r.input,
                    r.worst,
                    r.debug
                );
                assert_eq!(outputs(&r), [("z_mean".to_string(), 0), ("receiver".to_string(), 0)], "{schedule}");
                // every receiver of every cascade, one component each
                assert!(
                    r.debug.iter().all(|d| d.values == r.receivers * k as usize && d.values > 0),
                    "{:?}",
                    r.debug
                );
            }
        }
        let bad = run(&injected(&c, "shade", from, to), 1);
        for r in &bad {
            assert_eq!(r.verdict, Verdict::Differs, "{schedule}: {}", r.input);
            assert_eq!(r.outside, 0, "{schedule}: the visibility is untouched");
            assert!(
                r.debug[0].outside > 0 && r.debug[1].outside == 0,
                "{schedule}: only z_mean differs: {:?}",
                r.debug
            );
        }
    }
}
