//! Unit tests of the IR's evaluation (`Arena::eval`) on what `lower` makes of a bundled
//! technique: CSM's Fourier expansion (Annen et al. 2007, eq. 6.5) evaluated term by term.

use super::{Node, Origin};
use crate::CompileOptions;
use crate::builtins::Input;

fn source(name: &str) -> String {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../techniques")
        .join(format!("{name}.ron"));
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn opts(set: &[(&str, String)]) -> CompileOptions {
    CompileOptions {
        set: set.iter().map(|(k, v)| (k.to_string(), v.clone())).collect(),
        ..Default::default()
    }
}

/// f(d, z) of the compiled CSM expansion on a grid of `n + 1` values of d and z in [0, 1],
/// evaluated on the CPU from the IR (no quantisation). The expansion is separable, so the
/// coefficients are evaluated once per d and the basis functions once per z.
fn csm_reconstruction(m: i64, n: usize) -> Vec<Vec<f64>> {
    let o = opts(&[("M", m.to_string()), ("alpha", "0.0".into()), ("fix", "0".into())]);
    let c = crate::compile_str(&source("csm"), &o).unwrap();
    let ir = c.ir;
    let e = ir.expansions.iter().next().unwrap();
    let at = |i: usize| i as f64 / n as f64;
    let params = &ir.params;
    // the leaves a receiver gives: its depth, no slope, the params; every other node is
    // computed from its operands
    let receiver = |d: f64| {
        move |node: &Node| {
            if let Node::Param(p) = node {
                return Some(params[*p].value.as_f64());
            }
            let Node::Input(input, _) = node else { return None };
            Some(if *input == Input::D { d } else { 0.0 })
                .filter(|_| [Input::D, Input::Slope, Input::TexelDepth, Input::DepthSlope].contains(input))
        }
    };
    let coeffs: Vec<(f64, Vec<f64>)> = (0..=n)
        .map(|i| {
            let leaf = receiver(at(i));
            (
                ir.arena.eval(e.constant, &leaf),
                e.terms.iter().map(|(a, _)| ir.arena.eval(*a, &leaf)).collect(),
            )
        })
        .collect();
    let bases: Vec<Vec<f64>> = (0..=n)
        .map(|j| {
            let z = at(j);
            let leaf = |node: &Node| matches!(node, Node::Channel(..)).then_some(z);
            e.terms
                .iter()
                .map(|(_, ch)| {
                    assert!(matches!(ir.channels[*ch].origin, Origin::Basis { .. }));
                    ir.arena.eval(ir.channels[*ch].value.unwrap(), &leaf)
                })
                .collect()
        })
        .collect();
    coeffs
        .iter()
        .map(|(c0, a)| {
            bases
                .iter()
                .map(|b| c0 + a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>())
                .collect()
        })
        .collect()
}

#[test]
fn csm_reconstruction_approaches_the_step_as_m_grows() {
    // Away from the step (|z - d| >= 0.1) and from the square wave's next edge (|z - d| <= 0.9),
    // the reconstruction of eq. 6.5 with c_k = pi (2k - 1) converges to 1 (lit, d < z) and
    // 0 (shadowed, d > z); the largest error must fall as M grows. With c_k = 2k - 1, as
    // printed in eq. 6.3, it would not: the period would be 2 pi, not 2.
    let mut last = f64::INFINITY;
    let mut errors = Vec::new();
    for m in [1, 2, 4, 8, 16, 32, 64] {
        let f = csm_reconstruction(m, 100);
        let mut worst: f64 = 0.0;
        for (i, row) in f.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                let (d, z) = (i as f64 / 100.0, j as f64 / 100.0);
                let t = (z - d).abs();
                if !(0.1..=0.9).contains(&t) {
                    continue;
                }
                let truth = if d <= z { 1.0 } else { 0.0 };
                worst = worst.max((v - truth).abs());
            }
        }
        errors.push((m, worst));
        assert!(worst < last, "max error away from the step did not fall at M = {m}: {errors:?}");
        last = worst;
    }
    // The Fourier partial sum of the unit square wave at distance 0.1 from its edge decays
    // like 1 / (pi^2 M 0.1); at M = 64 that is below 0.02.
    assert!(last < 0.02, "M = 64 still far from the step: {errors:?}");
    // At the step itself the series reads 1/2 (the lit-surface problem of fig. 6.3).
    let f = csm_reconstruction(16, 2);
    assert!((f[1][1] - 0.5).abs() < 1e-6, "f(0.5, 0.5) = {}", f[1][1]);
}
