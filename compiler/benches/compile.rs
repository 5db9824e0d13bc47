//! Compile time per bundled technique in a warm process: every phase from parse to emit,
//! naga validation of every generated module included (docs/compile-time.md).
//!
//! `cargo bench -p sshc --bench compile [-- RUNS]` prints a Markdown table: for each
//! technique, one warm-up compilation, then RUNS timed ones (default 200; CSM at M = 16
//! and M = 64 take fewer), with the median, fastest and slowest. Timings on a shared
//! machine are noisy: compare builds by running both in the same session, alternately.

use std::path::Path;
use std::time::Instant;

/// One row of the table: a technique's source with overrides, compiled `runs` times.
struct Case {
    name: String,
    source: String,
    set: Vec<(String, String)>,
    runs: usize,
}

fn main() {
    let runs: usize = std::env::args().skip(1).find_map(|a| a.parse().ok()).unwrap_or(200).max(1);
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../techniques");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("the bundled techniques folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    files.sort();
    let mut cases: Vec<Case> = files
        .iter()
        .map(|p| Case {
            name: p.file_stem().unwrap().to_string_lossy().into_owned(),
            source: std::fs::read_to_string(p).unwrap(),
            set: vec![],
            runs,
        })
        .collect();
    let csm = std::fs::read_to_string(dir.join("csm.ron")).unwrap();
    for (m, n) in [(16, (runs / 4).max(1)), (64, (runs / 10).max(1))] {
        cases.push(Case {
            name: format!("csm, M = {m}"),
            source: csm.clone(),
            set: vec![("M".into(), m.to_string())],
            runs: n,
        });
    }
    println!("| technique | median ms | min ms | max ms | runs |\n|---|---|---|---|---|");
    for Case {
        name,
        source,
        set,
        runs: n,
    } in cases
    {
        let opts = sshc::CompileOptions { set, ..Default::default() };
        if let Err(d) = sshc::compile_str(&source, &opts) {
            panic!("{name} does not compile:\n{}", d.render(&name, &source));
        }
        let mut ms: Vec<f64> = (0..n)
            .map(|_| {
                let t = Instant::now();
                let r = sshc::compile_str(&source, &opts);
                let e = t.elapsed().as_secs_f64() * 1e3;
                std::hint::black_box(r.is_ok());
                e
            })
            .collect();
        ms.sort_by(f64::total_cmp);
        println!("| {name} | {:.3} | {:.3} | {:.3} | {n} |", ms[n / 2], ms[0], ms[n - 1]);
    }
}
