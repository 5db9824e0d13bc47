//! Shared driver of the fuzz targets: every public entry of the front end and the
//! pipeline on one source text; any panic (or abort) is a bug.

use sshc::{CompileOptions, Diagnostics};

const FILE: &str = "fuzz.ron";

pub fn drive(source: &str) {
    // The two front-end layers on their own.
    if let Err(d) = sshc::front::ron::parse(source) {
        let _ = d.render(FILE, source);
        let _ = d.short(FILE, source);
    }
    if let Err(d) = sshc::front::parse::parse(source) {
        let _ = d.render(FILE, source);
    }

    let opts = CompileOptions::default();

    // parse -> resolve -> check.
    if let Err(d) = sshc::check_str(source, &opts) {
        let _ = d.render(FILE, source);
    }

    // The whole pipeline down to WGSL and the pass graph.
    match sshc::compile_str(source, &opts) {
        Ok(compiled) => {
            let _ = Diagnostics(compiled.warnings).render(FILE, source);
        }
        Err(d) => {
            let _ = d.render(FILE, source);
        }
    }
}
