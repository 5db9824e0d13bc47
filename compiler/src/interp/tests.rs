//! Unit tests of the evaluation: f16 rounding, debug outputs, exact hard shadows and ties,
//! storage rounding, the f64 model, per-sample views, given Geometry outputs.

use super::model::round_f16;
use super::*;

fn compiled(src: &str) -> crate::Compiled {
    crate::compile_str(src, &crate::CompileOptions::default()).unwrap_or_else(|d| panic!("{}", d.render("t.ron", src)))
}

fn frame(n: u32) -> Frame {
    Frame {
        shadow_size: n,
        near: 8.0,
        far: 12.0,
        light_size: 0.0,
        light_width: [0.0; 2],
        light_spread: 0.0,
        light_distant: true,
        texel_world: [0.0, 2.0 / n as f64],
        frame: 0,
    }
}

/// A receiver at the centre of the map at normalised depth `d` (no slope).
fn receiver(d: f64) -> Receiver {
    Receiver {
        uv: [0.5 + 1.0 / 64.0, 0.5 + 1.0 / 64.0],
        d_world: 8.0 + 4.0 * d,
        ndotl: 1.0,
        depth_slope: 0.0,
        lod: 0.0,
        pixel: [0.0, 0.0],
        samples: Vec::new(),
    }
}

fn depth(c: &crate::Compiled, map: &[f32]) -> Given {
    Given::depth(c, vec![map.to_vec()])
}

#[test]
fn halves_round_to_nearest_even_with_subnormals_and_overflow() {
    assert_eq!(round_f16(1.0), 1.0);
    // half way between 1 and the next half, 1 + 2^-10: to even (1)
    assert_eq!(round_f16(1.0 + 2f64.powi(-11)), 1.0);
    assert_eq!(round_f16(1.0 + 3.0 * 2f64.powi(-11)), 1.0 + 2.0 * 2f64.powi(-10));
    assert_eq!(round_f16(65504.0), 65504.0);
    assert_eq!(round_f16(70000.0), f64::INFINITY);
    // subnormals are multiples of 2^-24
    assert_eq!(round_f16(2f64.powi(-24)), 2f64.powi(-24));
    assert_eq!(round_f16(0.7 * 2f64.powi(-24)), 2f64.powi(-24));
    assert_eq!(round_f16(-0.3 * 2f64.powi(-24)), 0.0);
}

/// Debug outputs evaluate to their closed forms at a receiver: the receiver's depth,
/// a vector of a lookup and a product, and the visibility's own expression unclamped
/// (the same node as the visibility, which is clamped); a build without them has none.
#[test]
fn debug_outputs_evaluate_unclamped_to_their_closed_forms() {
    let src = r#"Technique(name: "t", channels: { "z": Channel(precision: F32) }, passes: [
            Depth(name: "depth", writes: "shadow", channel: "z"),
            Shade(name: "shade", reads: ["shadow"], visibility: "let k = 4.0; d * k", debug: {
                "depth": "d", "pair": "vec2(sample(z), d * 2.0)", "raw": "d * k",
            }),
        ])"#;
    let opts = crate::CompileOptions {
        debug: true,
        ..Default::default()
    };
    let c = crate::compile_str(src, &opts).unwrap_or_else(|d| panic!("{}", d.render("t.ron", src)));
    let n = 8;
    let map = vec![0.375f32; (n * n) as usize];
    let ev = Evaluation::new(&c, &depth(&c, &map), frame(n), Rounding::Exact, Model::Gpu).unwrap();
    assert_eq!(ev.debug_names(), ["depth", "pair", "raw"]);
    let mut s = Scratch::default();
    let d = 0.75;
    let r = receiver(d);
    let one = |i: usize, s: &mut Scratch| ev.debug(i, &r, s);
    let depth_out = one(0, &mut s);
    assert_eq!(depth_out.len(), 1);
    // d from the receiver's view distance, (d_world - near) / (far - near), in f64
    assert!((depth_out[0].value - d).abs() < 1e-12 && depth_out[0].admits(d), "{depth_out:?}");
    let pair = one(1, &mut s);
    assert_eq!(pair.len(), 2);
    // a constant map filters to its value wherever it is read
    assert!(pair[0].admits(0.375) && (pair[1].value - 2.0 * d).abs() < 1e-12, "{pair:?}");
    let raw = one(2, &mut s);
    assert!((raw[0].value - 4.0 * d).abs() < 1e-12 && raw[0].value > 1.0, "{raw:?}");
    assert_eq!(ev.visibility(&r, &mut s).value, 1.0, "the visibility is clamped");
    // without the option the same source has none
    let plain = compiled(src);
    assert!(plain.ir.debug.is_empty() && plain.ir.debug_omitted == ["depth", "pair", "raw"]);
}

#[test]
fn hard_shadows_evaluate_exactly_and_allow_both_sides_only_at_a_tie() {
    let c = compiled(include_str!("../../../techniques/hard.ron"));
    let n = 8;
    let map = vec![0.5f32; (n * n) as usize];
    let ev = Evaluation::new(&c, &depth(&c, &map), frame(n), Rounding::Exact, Model::Gpu).unwrap();
    let mut s = Scratch::default();
    // in front of the occluder: lit; behind it: shadowed; both within f32's reach
    let lit = ev.visibility(&receiver(0.25), &mut s);
    assert_eq!((lit.value, lit.lo, lit.hi), (1.0, 1.0, 1.0), "{lit:?}");
    let dark = ev.visibility(&receiver(0.75), &mut s);
    assert_eq!((dark.value, dark.lo, dark.hi), (0.0, 0.0, 0.0), "{dark:?}");
    // at the occluder's depth the comparison is a tie: either side is allowed
    let bias = c.ir.params.iter().find(|p| p.name == "bias").map_or(0.0, |p| p.value.as_f64());
    let tie = ev.visibility(&receiver(0.5 + bias), &mut s);
    assert_eq!((tie.lo, tie.hi), (0.0, 1.0), "{tie:?}");
}

#[test]
fn storage_rounding_is_what_separates_the_two_evaluations() {
    // ESM's exp(c z) at Unorm8 over [1, e^c]: rounding moves the visibility a lot, and
    // the GPU model's allowance covers the rounded evaluation
    let src = include_str!("../../../techniques/esm.ron");
    let opts = crate::CompileOptions {
        precision: vec![("e".into(), "unorm8".into())],
        ..Default::default()
    };
    let c = crate::compile_str(src, &opts).unwrap_or_else(|d| panic!("{}", d.render("esm.ron", src)));
    let n = 8;
    let map: Vec<f32> = (0..n * n).map(|k| 0.3 + 0.4 * (k % n) as f32 / n as f32).collect();
    let exact = Evaluation::new(&c, &depth(&c, &map), frame(n), Rounding::Exact, Model::Gpu).unwrap();
    let rounded = Evaluation::new(&c, &depth(&c, &map), frame(n), Rounding::Stored, Model::Gpu).unwrap();
    let mut s = Scratch::default();
    let r = receiver(0.55);
    let e = exact.visibility(&r, &mut s);
    let v = rounded.value(&r, &mut s);
    assert!((v - e.value).abs() > 0.05, "exact {e:?}, rounded {v}");
    assert!(e.admits(v), "exact {e:?}, rounded {v}");
}

#[test]
fn an_f64_model_allows_only_f64_rounding_where_the_math_is_well_conditioned() {
    let c = compiled(include_str!("../../../techniques/vsm.ron"));
    let n = 8;
    let map: Vec<f32> = (0..n * n).map(|k| 0.2 + 0.05 * (k % 7) as f32).collect();
    let gpu = Evaluation::new(&c, &depth(&c, &map), frame(n), Rounding::Exact, Model::Gpu).unwrap();
    let f64m = Evaluation::new(&c, &depth(&c, &map), frame(n), Rounding::Exact, Model::F64).unwrap();
    let mut s = Scratch::default();
    let r = receiver(0.4);
    let (a, b) = (gpu.visibility(&r, &mut s), f64m.visibility(&r, &mut s));
    assert_eq!(a.value, b.value);
    assert!(b.value > 0.0 && b.value < 1.0, "{b:?}");
    // f64's own rounding through a short expression, against the GPU's f32 and storage
    assert!(b.allowance < 1e-12, "{b:?}");
    assert!(a.allowance > 1e3 * b.allowance, "{a:?} {b:?}");
}

#[test]
fn each_light_sample_reads_its_own_view_of_the_receiver_and_its_own_map() {
    let c = compiled(include_str!("../../../techniques/point-samples.ron"));
    assert_eq!(c.ir.samples, 2);
    let n = 8;
    // sample 0's map puts an occluder in front of the receiver, sample 1's does not
    let near = vec![0.2f32; (n * n) as usize];
    let far = vec![1.0f32; (n * n) as usize];
    let given = Given::depth(&c, vec![near, far]);
    let ev = Evaluation::new(&c, &given, frame(n), Rounding::Exact, Model::Gpu).unwrap();
    let seen = |k: usize| Seen {
        uv: [0.3 + 0.25 * k as f64, 0.5 + 1.0 / 64.0],
        d_world: 10.0,
        near: 8.0,
        far: 12.0,
        ndotl: 1.0,
        depth_slope: 0.0,
        lod: 0.0,
        texel_world: 0.0,
        weights: [0.0, 1.0],
    };
    let mut r = receiver(0.5);
    r.samples = vec![seen(0), seen(1)];
    let mut s = Scratch::default();
    let v = ev.visibility(&r, &mut s);
    // the mean of a lit and a shadowed sample, within the f32 ulps of its sum and division
    // (one of 1, three of 0.5)
    assert_eq!(v.value, 0.5, "{v:?}");
    assert!(v.allowance <= 2.5 * 2f64.powi(-23), "{v:?}");
    // one map for two views is refused
    let one = Given::depth(&c, vec![vec![1.0; (n * n) as usize]]);
    let err = Evaluation::new(&c, &one, frame(n), Rounding::Exact, Model::Gpu).err().unwrap();
    assert!(err.contains("given 1 view(s), not 2"), "{err}");
}

#[test]
fn geometry_outputs_are_given_and_read_as_stored() {
    let c = compiled(include_str!("../../../techniques/penumbra-maps.ron"));
    let slots = given_slots(&c);
    let geometry: Vec<_> = slots.iter().filter(|s| s.geometry).collect();
    assert!(!geometry.is_empty() && geometry.iter().all(|s| s.views == 1), "{slots:?}");
    let n = 8;
    let only_depth = Given::depth(&c, vec![vec![1.0; (n * n) as usize]]);
    let err = Evaluation::new(&c, &only_depth, frame(n), Rounding::Exact, Model::Gpu)
        .err()
        .unwrap();
    assert!(err.contains("is not given"), "{err}");
    let mut given = only_depth;
    for s in &geometry {
        given.insert(s.resource, s.channel, vec![vec![s.decode(0.25); (n * n) as usize]]);
    }
    let ev = Evaluation::new(&c, &given, frame(n), Rounding::Exact, Model::Gpu).unwrap();
    let v = ev.visibility(&receiver(0.5), &mut Scratch::default());
    // the depth map (all 1) lights the receiver at 0.5, so the visibility is the
    // penumbra map's intensity as given: 0.25, exact at its F16 (`select(0, p, lit)`,
    // techniques/penumbra-maps.ron)
    assert_eq!(v.value, 0.25, "{v:?}");
    // a depth map of 0.25 shadows it: the umbra, whatever the penumbra map holds
    let mut umbra = Given::depth(&c, vec![vec![0.25; (n * n) as usize]]);
    for s in &geometry {
        umbra.insert(s.resource, s.channel, vec![vec![s.decode(0.25); (n * n) as usize]]);
    }
    let ev = Evaluation::new(&c, &umbra, frame(n), Rounding::Exact, Model::Gpu).unwrap();
    assert_eq!(ev.visibility(&receiver(0.5), &mut Scratch::default()).value, 0.0);
}
