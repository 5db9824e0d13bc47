//! `sshc verify` catches code generation bugs: the shaders of a compiled technique with a
//! bug injected into their WGSL (as a faulty code generator would emit it) run on the GPU
//! and are compared with the CPU evaluation of the unchanged IR; every injected bug must
//! make some input DIFFER, and the shaders as generated must agree. On a real adapter
//! (lavapipe without a GPU); never skipped.

use sshc_lab::verify::{self, Input, Options, Verdict};
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
            depth: verify::depth_field(f, n).expect("a bundled field"),
        })
        .collect();
    inputs.push(Input {
        name: "bunny".into(),
        depth: verify::scene_depth(gpu, &root().join("scenes/bunny.ron"), n).unwrap_or_else(|e| panic!("{e}")),
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
    let file = format!("{}.{pass}.wgsl", c.ir.technique);
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
