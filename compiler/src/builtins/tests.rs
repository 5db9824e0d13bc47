//! Unit tests of the descriptors: unique names, a signature of each function's arity,
//! folding inside the range rule, the docs/language.md tables, and naga's validation of a
//! module that calls every function and reads every input and lookup.

use super::*;
use crate::front::ast::ConstValue;
use crate::interval::Interval;

#[test]
fn every_name_round_trips_through_lookup() {
    for (i, f) in Func::ALL.into_iter().enumerate() {
        assert_eq!(f as usize, i, "Func::ALL out of declaration order at {f:?}");
        assert_eq!(Func::from_name(f.name()), Some(f));
        assert!(is_reserved(f.name()));
    }
    assert_eq!(Func::Branch as usize + 1, Func::ALL.len(), "a Func is missing from Func::ALL");
    for (i, input) in Input::ALL.into_iter().enumerate() {
        assert_eq!(input as usize, i, "Input::ALL out of declaration order at {input:?}");
        assert_eq!(Input::from_name(input.name()), Some(input));
        assert!(is_reserved(input.name()));
    }
    assert_eq!(Input::Frame as usize + 1, Input::ALL.len(), "an Input is missing from Input::ALL");
    let mut names: Vec<&str> = SampleFn::ALL.iter().map(|s| s.name(false)).collect();
    names.extend(SampleFn::ALL.iter().map(|s| s.name(true)));
    assert_eq!(names, SampleFn::NAMES, "SampleFn::NAMES disagrees with the descriptors");
    for s in SampleFn::ALL {
        for expand in [false, true] {
            assert_eq!(SampleFn::from_name(s.name(expand)), Some((s, expand)));
            assert!(is_reserved(s.name(expand)));
        }
    }
    let mut order: Vec<usize> = SampleFn::ALL.iter().map(|s| *s as usize).collect();
    order.sort_unstable();
    assert_eq!(order, (0..SampleFn::ALL.len()).collect::<Vec<_>>());
    assert_eq!(
        SampleFn::MipBoxAt as usize + 1,
        SampleFn::ALL.len(),
        "a SampleFn is missing from SampleFn::ALL"
    );
    // names are unique across all builtins
    let mut all: Vec<&str> = Func::ALL.iter().map(|f| f.name()).collect();
    all.extend(Input::ALL.iter().map(|i| i.name()));
    all.extend(SampleFn::NAMES);
    let n = all.len();
    all.sort_unstable();
    all.dedup();
    assert_eq!(all.len(), n, "two builtins share a name");
}

/// Argument types a call may take: every uniform choice the signature accepts.
fn signatures(f: Func) -> Vec<Vec<Ty>> {
    let n = f.arity();
    let mut out: Vec<Vec<Ty>> = [Ty::F32, Ty::Vec(2), Ty::Vec(3), Ty::Vec(4), Ty::I32, Ty::U32, Ty::Bool]
        .into_iter()
        .map(|t| vec![t; n])
        .collect();
    if n == 3 {
        for t in [Ty::F32, Ty::Vec(2), Ty::I32, Ty::U32] {
            out.push(vec![t, t, Ty::Bool]);
        }
    }
    out.retain(|args| f.result(args).is_ok());
    out
}

#[test]
fn every_function_has_a_signature_of_its_arity() {
    for f in Func::ALL {
        assert!(!signatures(f).is_empty(), "`{}` accepts no argument types", f.name());
        let wrong = vec![Ty::F32; f.arity() + 1];
        assert!(f.result(&wrong).is_err());
    }
}

/// Folding sample arguments gives a value inside the range rule's interval of any
/// argument intervals that hold them.
#[test]
fn folding_lies_inside_the_range_rule() {
    let boxes: [(f64, f64); 11] = [
        // f32 values, so the sample points are the ends themselves
        (-3.0, -0.5),
        (-1.0, 1.0),
        (0.0, 1.0),
        (0.25, 4.0),
        (1.0, 100.0),
        (-100.0, 100.0),
        (0.0, 0.0),
        (0.5, 0.5),
        (2.5, 2.5),
        (-2.5, -2.5),
        (2.75, 2.75),
    ];
    let mut checked = 0;
    let mut failures = Vec::new();
    for f in Func::ALL {
        let d = f.desc();
        if matches!(d.fold, Fold::Never | Fold::Hook) {
            continue;
        }
        let scalar: Vec<Vec<Ty>> = signatures(f)
            .into_iter()
            .filter(|s| !s.iter().any(|t| matches!(t, Ty::Vec(_))))
            .collect();
        for sig in scalar {
            // every combination of argument boxes
            let k = sig.len();
            for combo in 0..boxes.len().pow(k as u32) {
                let pick: Vec<(f64, f64)> = (0..k).map(|i| boxes[combo / boxes.len().pow(i as u32) % boxes.len()]).collect();
                let ivs: Vec<Interval> = pick
                    .iter()
                    .zip(&sig)
                    .map(|(&(lo, hi), t)| if *t == Ty::Bool { Interval::UNIT } else { Interval { lo, hi } })
                    .collect();
                let range = (d.range)(&ivs);
                // sample points: ends and middle of each box (integers: rounded inward)
                for p in 0..3usize.pow(k as u32) {
                    let args: Option<Vec<ConstValue>> = (0..k)
                        .map(|i| {
                            let (lo, hi) = pick[i];
                            let x = [lo, hi, 0.5 * (lo + hi)][p / 3usize.pow(i as u32) % 3];
                            match sig[i] {
                                // integers: the point rounded, if still inside the box
                                Ty::I32 => (lo..=hi).contains(&x.round()).then_some(ConstValue::Int(x.round() as i64)),
                                Ty::U32 => (lo..=hi)
                                    .contains(&x.round())
                                    .then_some(x.round())
                                    .and_then(|v| (v >= 0.0).then_some(ConstValue::Uint(v as u32))),
                                Ty::Bool => Some(ConstValue::Bool(x > lo)),
                                Ty::F32 | Ty::Vec(_) | Ty::AbstractInt => Some(ConstValue::Float(x as f32 as f64)),
                            }
                        })
                        .collect();
                    let Some(args) = args else { continue };
                    let Some(v) = fold_call(f, &args) else { continue };
                    let r = v.as_f64();
                    // the fold rounds to f32, the range rule is exact
                    let tol = r.abs().max(1.0) * f32::EPSILON as f64;
                    let inside = range.lo - tol <= r && r <= range.hi + tol;
                    if !inside && !failures.iter().any(|m: &String| m.starts_with(d.name)) {
                        failures.push(format!(
                            "{}({args:?}) folds to {r}, outside its range rule's {range} for argument ranges {ivs:?}",
                            d.name
                        ));
                    }
                    checked += 1;
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(checked > 10_000, "only {checked} folds checked");
}

/// docs/language.md lists every function, input, lookup and light kind, inputs with
/// their type and side.
#[test]
fn the_language_reference_lists_every_builtin() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/language.md")).unwrap();
    let section = |from: &str, to: &str| -> &str {
        let a = doc.find(from).unwrap_or_else(|| panic!("no `{from}` in docs/language.md"));
        let b = doc[a..].find(to).map_or(doc.len(), |b| a + b);
        &doc[a..b]
    };
    let functions = section("### 8.6 Functions", "### 8.7");
    // `if` is syntax (8.4), not a function
    assert!(section("### 8.4", "### 8.5").contains("if cond { a } else { b }"));
    for f in Func::ALL.into_iter().filter(|f| *f != Func::Branch) {
        assert!(
            functions.contains(&format!("`{}(", f.name())),
            "docs/language.md 8.6 lacks `{}`",
            f.name()
        );
    }
    let lookups = section("### 8.7 Sampling functions", "### 8.8");
    for name in SampleFn::NAMES {
        assert!(lookups.contains(&format!("`{name}(")), "docs/language.md 8.7 lacks `{name}`");
    }
    let inputs = section("**Built-in inputs.**", "**Channels**");
    for i in Input::ALL {
        let d = i.desc();
        let ty = match d.ty {
            Ty::Vec(n) => format!("vec{n}"),
            t @ (Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt) => t.to_string(),
        };
        let side = match d.side {
            Side::Receiver => "receiver",
            Side::Map => "map",
            Side::Both => "both",
            Side::Geometry => "geometry",
        };
        let row = format!("| `{}` | {ty} | {side} |", d.name);
        assert!(inputs.contains(&row), "docs/language.md 8.5 lacks the row `{row}`");
    }
    let lights = section("## 4. Light models", "## 5.");
    for k in crate::front::ast::LightKind::ALL {
        assert!(
            lights.contains(&format!("| `{}", k.name())),
            "docs/language.md 4 lacks `{}`",
            k.name()
        );
    }
}

/// A module that calls every function (with every argument type its signature
/// accepts), reads every input and every texture lookup, written by the code
/// generator's own emission, must pass naga's validation.
#[test]
fn every_builtin_emits_valid_wgsl() {
    let mut body = String::new();
    let arg = |t: Ty| match t {
        Ty::F32 | Ty::AbstractInt => "a_f32".to_string(),
        Ty::I32 => "a_i32".to_string(),
        Ty::U32 => "a_u32".to_string(),
        Ty::Bool => "a_bool".to_string(),
        Ty::Vec(n) => format!("a_vec{n}"),
    };
    for i in Input::ALL {
        let d = i.desc();
        if matches!(d.side, Side::Receiver | Side::Geometry) {
            body.push_str(&format!("    let {}: {} = {};\n", d.wgsl, d.ty.wgsl(), arg(d.ty)));
        }
    }
    for (k, i) in Input::ALL.into_iter().enumerate() {
        body.push_str(&format!("    let input{k}: {} = {};\n", i.ty().wgsl(), i.desc().wgsl));
    }
    let mut k = 0;
    // a branch is never a call: the code generator writes an `if` (back::expr)
    for f in Func::ALL.into_iter().filter(|f| *f != Func::Branch) {
        for sig in signatures(f) {
            let ty = f.result(&sig).unwrap();
            let args: Vec<String> = sig.iter().map(|t| arg(*t)).collect();
            body.push_str(&format!("    let call{k}: {} = {};\n", ty.wgsl(), f.wgsl_call(&args, ty)));
            k += 1;
        }
    }
    for (k, s) in SampleFn::ALL.into_iter().enumerate() {
        let d = s.desc();
        match d.wgsl {
            SampleWgsl::Texture { read, .. } => {
                let args: Vec<String> = d.extra_args.iter().map(|t| arg(*t)).collect();
                body.push_str(&format!(
                    "    let lookup{k}: vec4<f32> = {};\n",
                    read("t_x", "1i", "in_uv", "in_base", &args)
                ));
            }
            // the box function is written per table by the code generator
            SampleWgsl::SummedAreaTable => {}
        }
    }
    body.push_str("    let in_pixel_used = in_pixel;\n");
    let module = format!(
        "{}{}{}@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(2) var smp: sampler;
@group(1) @binding(0) var t_x: texture_2d_array<f32>;

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {{
    let a_f32 = frame.shadow_size.z + pos.x;
    let a_vec2 = frame.shadow_size.xy;
    let a_vec3 = frame.shadow_size.xyz;
    let a_vec4 = frame.shadow_size;
    let a_i32 = i32(frame.shadow_size.x);
    let a_u32 = u32(frame.shadow_size.x);
    let a_bool = frame.shadow_size.x > 1.0;
    let in_base = vec2<i32>(floor(a_vec2));
{body}    return vec4<f32>(0.0);
}}
",
        crate::builtins::NOISE_WGSL,
        MIP_BOX_WGSL,
        sshc_graph::FRAME_WGSL
    );
    if let Err(e) = crate::back::validate(&module) {
        panic!("{e}\n{module}");
    }
}
