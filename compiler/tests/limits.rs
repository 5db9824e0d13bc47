//! Limits of the compiler against hostile and extreme techniques: every one is
//! refused with a diagnostic at file:line:column, within a stated time bound, never a stack
//! overflow or a hang.

use std::time::{Duration, Instant};

/// A technique with a hard-shadow depth pass and the given visibility expression.
fn technique(visibility: &str) -> String {
    format!(
        r#"Technique(
    name: "limits",
    channels: {{ "z": Channel(precision: F32) }},
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Shade(name: "shade", reads: ["shadow"], visibility: "{visibility}"),
    ],
)
"#
    )
}

fn chain(term: &str, op: &str, n: usize) -> String {
    vec![term; n].join(&format!(" {op} "))
}

/// Both check and compile refuse `source` within `bound`, with a message containing `want`
/// located at `at` (file:line:column).
fn refused(source: &str, want: &str, at: &str, bound: Duration) {
    let opts = sshc::CompileOptions::default();
    let t = Instant::now();
    let e = sshc::check_str(source, &opts).expect_err("check refuses it");
    let got = e.render("t.ron", source);
    assert!(got.contains(want), "{got}");
    assert!(got.contains(at), "expected a diagnostic at {at}:\n{got}");
    let e = sshc::compile_str(source, &opts).expect_err("compile refuses it");
    let got = e.render("t.ron", source);
    assert!(got.contains(want), "{got}");
    assert!(got.contains(at), "expected a diagnostic at {at}:\n{got}");
    let took = t.elapsed();
    assert!(took < bound, "took {took:?}, above {bound:?}");
}

#[test]
fn long_flat_chains_are_refused_not_a_stack_overflow() {
    // 15,000 terms (60 KB) overflowed the stack in resolve; each operator of a chain is a
    // level of the tree, and the tree is limited to 256 levels.
    for (term, op) in [("d", "+"), ("d", "*"), ("(d < 1.0)", "&&")] {
        let body = chain(term, op, 15_000);
        let vis = if op == "&&" { format!("select(0.0, 1.0, {body})") } else { body };
        refused(
            &technique(&vis),
            "expression is deeper than 256 levels",
            "t.ron:6:",
            Duration::from_secs(2),
        );
    }
}

#[test]
fn a_chain_of_200_terms_compiles() {
    let opts = sshc::CompileOptions::default();
    for (term, op) in [("d", "+"), ("d", "*"), ("(d < 1.0)", "&&")] {
        let body = chain(term, op, 200);
        let vis = if op == "&&" {
            format!("select(0.0, 1.0, {body})")
        } else {
            format!("clamp({body}, 0.0, 1.0)")
        };
        let src = technique(&vis);
        if let Err(e) = sshc::compile_str(&src, &opts) {
            panic!("{op}: {}", e.render("t.ron", &src));
        }
    }
}

#[test]
fn an_expression_of_too_many_nodes_is_refused() {
    // 70,000 arguments: shallow, but more than 65,536 nodes.
    let src = technique(&format!("max({})", vec!["d"; 70_000].join(", ")));
    refused(&src, "more than 65536 terms", "t.ron:6:", Duration::from_secs(2));
}

#[test]
fn a_chain_at_the_depth_limit_compiles_on_a_small_stack() {
    // clamp + 255 terms = 256 levels, the most accepted; run on a 1 MB thread to show the
    // phases do not depend on the caller's stack.
    let src = technique(&format!("clamp({}, 0.0, 1.0)", chain("d", "+", 255)));
    let h = std::thread::Builder::new()
        .stack_size(1 << 20)
        .spawn(move || {
            sshc::compile_str(&src, &sshc::CompileOptions::default())
                .map(|_| ())
                .map_err(|e| e.render("t.ron", &src))
        })
        .unwrap();
    h.join().unwrap().unwrap();
    let src = technique(&format!("clamp({}, 0.0, 1.0)", chain("d", "+", 256)));
    refused(&src, "expression is deeper than 256 levels", "t.ron:6:", Duration::from_secs(2));
}

#[test]
fn dump_after_parse_is_linear_in_a_chain() {
    // 400 terms took 8.4 s and 1,000 over 60 s (the indented debug print of the tree);
    // 1,000 terms in 4 chains of 250 (each chain is under the depth limit) print in < 1 s.
    let vis = format!(
        "clamp({}, 0.0, 1.0)",
        (0..4)
            .map(|_| format!("({})", chain("d", "+", 250)))
            .collect::<Vec<_>>()
            .join(" * ")
    );
    let src = technique(&vis);
    let opts = sshc::CompileOptions {
        dump_after: Some(sshc::DumpPhase::Parse),
        ..Default::default()
    };
    let t = Instant::now();
    let (r, dump) = sshc::check_with_dump(&src, &opts);
    let took = t.elapsed();
    r.unwrap_or_else(|e| panic!("{}", e.render("t.ron", &src)));
    let dump = dump.expect("a dump");
    assert!(dump.contains("(d + d)"), "{dump}");
    assert!(dump.len() < 64 * src.len(), "dump of {} bytes", dump.len());
    assert!(took < Duration::from_secs(1), "took {took:?}");
}

#[test]
fn too_many_passes_are_refused_at_compile_time() {
    // 2,100 passes compiled and then failed at render ("4204 is too many queries for a
    // single QuerySet"); at most 256 passes are accepted.
    let mut passes = vec![r#"        Depth(name: "depth", writes: "shadow", channel: "z"),"#.to_string()];
    for i in 0..2_100 {
        passes.push(format!(
            r#"        Filter(name: "f{i}", reads: "shadow", writes: "s{i}", kernel: Box(size: 3)),"#
        ));
    }
    passes.push(r#"        Shade(name: "shade", reads: ["shadow"], visibility: "1.0"),"#.to_string());
    let src = format!(
        "Technique(\n    name: \"many\",\n    channels: {{ \"z\": Channel(precision: F32) }},\n    passes: [\n{}\n    ],\n)\n",
        passes.join("\n")
    );
    refused(&src, "technique has 2102 passes: at most 256", "t.ron:261:", Duration::from_secs(2));
}

#[test]
fn constant_integer_division_by_zero_or_overflow_is_refused_in_the_technique() {
    // These gave an internal error located in the generated WGSL (`wgsl:79:14`).
    let bound = Duration::from_secs(2);
    refused(&technique("f32(7 / 0)"), "integer division by zero", "t.ron:6:", bound);
    refused(&technique("f32(7 % 0)"), "integer remainder by zero", "t.ron:6:", bound);
    refused(
        &technique("f32(i32(d * 4.0) / (2 - 2))"),
        "integer division by zero",
        "t.ron:6:",
        bound,
    );
    refused(
        &technique("f32((-2147483647 - 1) / -1)"),
        "integer overflow: -2147483648 / -1 does not fit in i32",
        "t.ron:6:",
        bound,
    );
    // Divisions with a value compile.
    let opts = sshc::CompileOptions::default();
    for vis in [
        "f32(7 / 2) * 0.25",
        "f32(i32(d * 4.0) % 3) * 0.5",
        "f32((-2147483647 - 1) / 2) * 0.0",
    ] {
        let src = technique(&format!("clamp({vis}, 0.0, 1.0)"));
        if let Err(e) = sshc::compile_str(&src, &opts) {
            panic!("{vis}: {}", e.render("t.ron", &src));
        }
    }
}

#[test]
fn nested_series_are_limited_in_their_product() {
    // Three nested series of 4,096 terms each (each within the limit) hung: 6.9e10 terms.
    let vis = "clamp(sum(i in 0..=4095, sum(j in 0..=4095, sum(k in 0..=4095, d * 0.0))), 0.0, 1.0)";
    refused(
        &technique(vis),
        "nested series unroll 16777216 terms: at most 4096 in all",
        "t.ron:6:",
        Duration::from_secs(2),
    );
    refused(
        &technique("clamp(sum(i in 0..=64, sum(j in 0..=63, d * 0.0)), 0.0, 1.0)"),
        "nested series unroll 4160 terms",
        "t.ron:6:",
        Duration::from_secs(2),
    );
    // 64 x 64 = 4,096 compiles.
    let src = technique("clamp(sum(i in 0..=63, sum(j in 0..=63, d * 0.0)), 0.0, 1.0)");
    if let Err(e) = sshc::compile_str(&src, &sshc::CompileOptions::default()) {
        panic!("{}", e.render("t.ron", &src));
    }
}

/// `compile` refuses `source` (`check` may accept it: the operation is inside a series,
/// whose variable is known only as `lower` unrolls it) with `want` at `at`, never an
/// internal error or a place in the generated WGSL.
fn compile_refused(source: &str, want: &str, at: &str) {
    let e = sshc::compile_str(source, &sshc::CompileOptions::default()).expect_err("compile refuses it");
    let got = e.render("t.ron", source);
    assert!(got.contains(want), "{got}");
    assert!(got.contains(at), "expected a diagnostic at {at}:\n{got}");
    assert!(!got.contains("internal compiler error") && !got.contains("wgsl:"), "{got}");
}

#[test]
fn constant_integer_overflow_is_refused_in_the_technique() {
    // Folded by check (literals, fixed params, built-ins), each at its operation.
    let bound = Duration::from_secs(2);
    let n = |vis: &str| {
        technique(vis).replace(
            "    channels:",
            "    params: { \"N\": Param(ty: I32, default: 65536, fixed: true) },\n    channels:",
        )
    };
    for (vis, want) in [
        ("f32(2147483647 + 1)", "integer overflow: 2147483647 + 1 does not fit in i32"),
        ("f32(-2147483647 - 2)", "integer overflow: -2147483647 - 2 does not fit in i32"),
        ("f32(-(-2147483647 - 1))", "integer overflow: -(-2147483648) does not fit in i32"),
        ("f32(46341 * 46341)", "integer overflow: 46341 * 46341 does not fit in i32"),
        (
            "f32(abs(-2147483647 - 1))",
            "integer overflow: abs(-2147483648) does not fit in i32",
        ),
        (
            "f32(max(2147483647, 0) + i32(1.0))",
            "integer overflow: 2147483647 + 1 does not fit in i32",
        ),
        (
            "f32((-2147483647 - 1) % -1)",
            "integer overflow: -2147483648 % -1 does not fit in i32",
        ),
    ] {
        refused(&technique(vis), want, "t.ron:6:", bound);
    }
    // Arithmetic on a fixed I32 param N = 65536, as a value and as a series bound.
    refused(
        &n("f32(N * N)"),
        "integer overflow: 65536 * 65536 does not fit in i32",
        "t.ron:7:",
        bound,
    );
    refused(
        &n("sum(k in 0..=N * N, 1.0)"),
        "integer overflow: 65536 * 65536 does not fit in i32",
        "t.ron:7:",
        bound,
    );
    refused(&n("sum(k in 0..=N, 1.0)"), "series of 65537 terms: at most 4096", "t.ron:7:", bound);
    // Inside a series the variable is known only as lower unrolls it: refused there, at the
    // operation, naming the term (these were internal errors located in the generated WGSL
    // for `/` and `%`, and "has no finite value" for the others).
    for (vis, want) in [
        ("sum(k in 0..=1, f32(7 / k))", "integer division by zero"),
        ("sum(k in 0..=1, f32(7 % k))", "integer remainder by zero"),
        ("sum(k in -1..=0, f32((-2147483647 - 1) / k))", "integer overflow: -2147483648 / -1"),
        (
            "sum(k in 2147483640..=2147483647, f32(k + 10))",
            "integer overflow: 2147483640 + 10",
        ),
        ("sum(k in 0..=4000, f32(1000000 * k))", "integer overflow: 1000000 * 2148"),
        (
            "sum(k in 0..=4, f32(abs(k - 2147483647 - 1)))",
            "integer overflow: abs(-2147483648)",
        ),
        ("f32(let a = 2147483647; a + 1)", "integer overflow: 2147483647 + 1"),
        // the running sum of an integer series
        ("f32(sum(k in 0..=4000, 1000000 * k))", "integer overflow: 2145000000 + 66000000"),
    ] {
        compile_refused(&technique(vis), want, "t.ron:6:");
    }
    // The values next to the limits compile, and the WGSL validates.
    for vis in [
        "f32(2147483646 + 1)",
        "f32(-(-2147483647))",
        "f32(46340 * 46340)",
        "f32(abs(-2147483647))",
        "f32(-2147483647 - 1)",
        "sum(k in 2147483640..=2147483647, f32(k - 10))",
        "sum(k in 1..=3, f32(7 / k + 7 % k))",
        "f32(sum(k in 0..=64, 1000000 * k))",
    ] {
        let src = technique(&format!("clamp({vis}, 0.0, 1.0)"));
        if let Err(e) = sshc::compile_str(&src, &sshc::CompileOptions::default()) {
            panic!("{vis}: {}", e.render("t.ron", &src));
        }
    }
}

#[test]
fn nested_series_with_dependent_bounds_are_counted_term_by_term() {
    // A bound that uses an enclosing series variable counted 1 term, so the product limit
    // did not hold: three levels of `0..=4095` nested this way are 1.1e10 terms. They are
    // counted term by term (at most 4,096 evaluations of the bounds per series), so the
    // refusal is immediate: < 2 s for check and compile together, debug build.
    refused(
        &technique("clamp(sum(i in 0..=4095, sum(j in 0..=i, sum(k in 0..=j, d * 0.0))), 0.0, 1.0)"),
        "nested series unroll 8390656 terms: at most 4096 in all",
        "t.ron:6:",
        Duration::from_secs(2),
    );
    // 0..=90 then 0..=i: 91 * 92 / 2 = 4,186 terms; 0..=89: 4,095, within the limit.
    refused(
        &technique("clamp(sum(i in 0..=90, sum(j in 0..=i, d * 0.0)), 0.0, 1.0)"),
        "nested series unroll 4186 terms",
        "t.ron:6:",
        Duration::from_secs(2),
    );
    // A bound through a `let` of the outer variable is counted the same way.
    refused(
        &technique("clamp(sum(i in 0..=3, let m = i * 1000; sum(j in 0..=m, d * 0.0)), 0.0, 1.0)"),
        "nested series unroll 6004 terms",
        "t.ron:6:",
        Duration::from_secs(2),
    );
    // ... and a bound through a `let` outside the series (counted 1 term before): 5,151.
    refused(
        &technique("clamp(let a = 100; sum(i in 0..=a, sum(j in 0..=i, d * 0.0)), 0.0, 1.0)"),
        "nested series unroll 5151 terms",
        "t.ron:6:",
        Duration::from_secs(2),
    );
    let opts = sshc::CompileOptions::default();
    // Within the limit: 4,095 terms; 1,001 + ... + 1,004 = 4,010 terms through two `let`s;
    // and locals named like a fixed param N = 5000 hide it (its value gave 5,001 terms).
    let n = |vis: &str| {
        technique(vis).replace(
            "    channels:",
            "    params: { \"N\": Param(ty: I32, default: 5000, fixed: true) },\n    channels:",
        )
    };
    for src in [
        technique("clamp(sum(i in 0..=89, sum(j in 0..=i, d * 0.0)), 0.0, 1.0)"),
        technique("clamp(let a = 100; sum(i in 0..=3, let b = a * 10; sum(j in 0..=b + i, d * 0.0)), 0.0, 1.0)"),
        n("clamp(sum(N in 0..=3, sum(j in 0..=N, d * 0.0)), 0.0, 1.0)"),
        n("clamp(let N = 3; sum(j in 0..=N, d * 0.0), 0.0, 1.0)"),
        n("clamp(let N = 1; f32(2147480000 + N), 0.0, 1.0)"),
    ] {
        if let Err(e) = sshc::compile_str(&src, &opts) {
            panic!("{}", e.render("t.ron", &src));
        }
    }
    let src = technique("clamp(sum(i in 0..=89, sum(j in 0..=i, d * 0.0)), 0.0, 1.0)");
    if let Err(e) = sshc::compile_str(&src, &opts) {
        panic!("{}", e.render("t.ron", &src));
    }
    // A legal dependent triple nest (4,060 terms) has the value of the same sum on the CPU.
    let src = technique("f32(sum(i in 0..=27, sum(j in 0..=i, sum(k in 0..=j, i * j + k))))");
    let dumped = sshc::CompileOptions {
        dump_after: Some(sshc::DumpPhase::Lower),
        ..opts.clone()
    };
    let out = sshc::compile_with_dump(&src, &dumped);
    out.result.unwrap_or_else(|e| panic!("{}", e.render("t.ron", &src)));
    let mut want = 0i64;
    let mut terms = 0;
    for i in 0..=27i64 {
        for j in 0..=i {
            for k in 0..=j {
                want += i * j + k;
                terms += 1;
            }
        }
    }
    assert_eq!(terms, 4060);
    // 1,222,263 < 2^24: exact in f32; the lowered visibility is that one constant
    let dump = out.dump.expect("dumped after lower");
    assert!(dump.contains(&format!("visibility = {want}.0\n")), "{dump}");
}

/// Every receiver-side input inside `at_sample`, alone and all together, in two samples'
/// views: each compiles to a module naga validates, and a sample's prologue computes only
/// what its inputs need (an input's local appears exactly when it is read).
#[test]
fn every_receiver_input_of_a_sample_view_compiles_alone_and_together() {
    let inputs = [
        "d",
        "d_world",
        "uv.x",
        "tf.y",
        "ndotl",
        "slope",
        "texel_depth",
        "depth_slope",
        "segment_before",
        "segment_after",
    ];
    let src = |body: &str| {
        format!(
            r#"Technique(
    name: "views",
    params: {{ "N": Param(ty: I32, default: 2, fixed: true) }},
    light_samples: "N",
    channels: {{ "z": Channel(precision: F32) }},
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z", view: PerSample),
        Shade(name: "shade", reads: ["shadow"], visibility: "sum(k in 0..=N - 1, at_sample(k, {body}))"),
    ],
)"#
        )
    };
    let all = inputs.join(" + ");
    for body in inputs
        .iter()
        .map(|s| s.to_string())
        .chain([all.clone(), "fetch(z, 1, 0) + nearest(z)".into()])
    {
        let c = sshc::compile_str(&src(&body), &sshc::CompileOptions::default())
            .unwrap_or_else(|d| panic!("{body}: {}", d.render("views.ron", &src(&body))));
        let shade = c.shaders.iter().find(|(f, _)| f.ends_with(".shade.wgsl")).expect("a shade module");
        for k in 0..2 {
            assert!(shade.1.contains(&format!("light_samples.views[{k}]")), "{body}: sample {k}");
            // the slope's derivatives only where the depth slope is read
            let derivative = shade.1.contains(&format!("dpdx(in_uv_v{k})"));
            assert_eq!(derivative, body.contains("depth_slope"), "{body}: sample {k}'s derivatives");
        }
    }
}

#[test]
fn a_series_of_fetches_at_the_limit_compiles_in_linear_time() {
    // 4,096 fetches (the series limit) make about 60,000 naga expressions. In one function
    // they took 3.3 s in a release build, 101 s in the fuzzing build: naga's WGSL front end
    // is quadratic in a function's expressions (docs/fuzzing.md, finding 1). Split into
    // functions of 128 lets (`back::parts`) they take 0.22 s in release; the bound leaves
    // room for this crate's unoptimised build (naga is optimised in the dev profile) and a
    // loaded machine, and is under the 3.3 s the unsplit code took in release.
    let src = technique("sum(i in 0..=63, sum(j in 0..=63, fetch(z, i - 32, j - 32))) / 4096.0");
    let t = Instant::now();
    let c = sshc::compile_str(&src, &sshc::CompileOptions::default()).unwrap_or_else(|e| panic!("{}", e.render("t.ron", &src)));
    let took = t.elapsed();
    assert_eq!(c.cost.shade.fetches, 4096);
    let shade = &c.shaders.iter().find(|(f, _)| f.ends_with("shade.wgsl")).expect("a shade module").1;
    assert!(shade.contains("fn fs_shade_part8_f("), "the body is split into parts");
    assert!(took < Duration::from_secs(3), "took {took:?}");
}

/// `let a0 = seed; let a1 = a0 OP a0; ...; aN`, each binding read twice by the next.
fn doubling_lets(seed: &str, op: &str, n: usize) -> String {
    let mut s = format!("let a0 = {seed}; ");
    for i in 1..=n {
        s += &format!("let a{i} = a{} {op} a{}; ", i - 1, i - 1);
    }
    s + &format!("a{n}")
}

#[test]
fn lets_read_twice_by_the_next_check_in_linear_time_and_memory() {
    // A fuzzed CSSM variant (front-9) took 748 MB to check: each reference to a `let`
    // copied the inputs its value reads, so a chain of bindings each read twice by the next
    // held 2^n copies. Each binding now keeps each input site once; 40 doublings (2^40
    // copies before) check and compile in a few milliseconds, the bound a loaded machine
    // and the unoptimised build.
    for (seed, op) in [("d", "+"), ("d * 0.5", "*"), ("1.0", "+")] {
        let src = technique(&format!("min({}, 1.0)", doubling_lets(seed, op, 40)));
        let t = Instant::now();
        let opts = sshc::CompileOptions::default();
        sshc::check_str(&src, &opts).unwrap_or_else(|e| panic!("{}", e.render("t.ron", &src)));
        sshc::compile_str(&src, &opts).unwrap_or_else(|e| panic!("{}", e.render("t.ron", &src)));
        let took = t.elapsed();
        assert!(took < Duration::from_secs(2), "{seed} {op}: took {took:?}");
    }
    // The diagnostics still name the input and the binding it was read through, once.
    let src = format!(
        r#"Technique(
    name: "limits",
    channels: {{ "z": Channel(precision: F32, value: "{}") }},
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Shade(name: "shade", reads: ["shadow"], visibility: "sample(z)"),
    ],
)
"#,
        doubling_lets("d", "+", 30)
    );
    let e = sshc::check_str(&src, &sshc::CompileOptions::default()).expect_err("a receiver input in a channel value");
    let got = e.render("t.ron", &src);
    assert_eq!(got.matches("non-separable term").count(), 1, "{got}");
    assert!(got.contains("used through this binding"), "{got}");
}

/// The functions of a WGSL module and the `let`s each declares, in order.
fn lets_per_function(wgsl: &str) -> Vec<(String, usize)> {
    let mut out: Vec<(String, usize)> = Vec::new();
    for line in wgsl.lines() {
        let t = line.trim_start();
        if let Some(rest) = t.strip_prefix("fn ") {
            out.push((rest.split('(').next().unwrap_or("").to_string(), 0));
        } else if t.starts_with("let ")
            && let Some(f) = out.last_mut()
        {
            f.1 += 1;
        }
    }
    out
}

#[test]
fn series_inside_if_arms_compile_in_linear_time() {
    // Issue 48, item 4: one 4,096-term series in each of sixteen `if` arms took 10 s to
    // check in a release build (each arm's lets in the entry's arena, which naga's WGSL
    // front end types in quadratic time), and the same series in both arms of one `if`
    // 3.9 s here (codegen walked the shared chain again at each of its terms). Long arms
    // are now split into functions as long bodies are, and codegen walks each node once.
    let series = "sum(k in 0..=4095, f32(k) * d)";
    let arms: Vec<String> = (0..8)
        .map(|i| format!("let a{i} = if d > 0.{} {{ {series} }} else {{ 0.0 }};", i + 1))
        .collect();
    let total: Vec<String> = (0..8).map(|i| format!("a{i}")).collect();
    for visibility in [
        format!("{} select(0.0, 1.0, {} <= nearest(z))", arms.join(" "), total.join(" + ")),
        format!("let a = if d > 0.5 {{ {series} }} else {{ {series} * 0.5 }}; select(0.0, 1.0, a <= nearest(z))"),
    ] {
        let src = technique(&visibility);
        let t = Instant::now();
        let c = sshc::compile_str(&src, &sshc::CompileOptions::default()).unwrap_or_else(|e| panic!("{}", e.render("t.ron", &src)));
        let took = t.elapsed();
        let shade = &c.shaders.iter().find(|(f, _)| f.ends_with("shade.wgsl")).expect("a shade module").1;
        // no function holds more than a small share of the lets: the entry keeps two per
        // part (its call and its result) where it held every term of every arm
        let per = lets_per_function(shade);
        let all: usize = per.iter().map(|f| f.1).sum();
        let most = per.into_iter().max_by_key(|f| f.1).unwrap();
        assert!(all > 8000 && most.1 * 16 < all, "{} declares {} of {all} lets", most.0, most.1);
        assert!(shade.contains("_part1_f("), "split into parts");
        // 0.2 s (both arms) and 1.8 s (eight arms) in this crate's build; the bound is for
        // a loaded machine, and under what the quadratic forms took
        assert!(took < Duration::from_secs(8), "took {took:?}");
    }
}
