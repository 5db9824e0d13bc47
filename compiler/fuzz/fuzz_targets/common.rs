//! Shared driver of the front-end fuzz targets: the whole pipeline on one source text, and
//! the rendering of every diagnostic; any panic (or abort) is a bug.

use sshc::{CompileOptions, Diagnostics};

const FILE: &str = "fuzz.ron";

pub fn drive(source: &str) {
    // `compile_str` runs every phase in order (the spanned RON reader, the technique
    // parser with its expression strings, resolve, check, lower, analyse, pack, WGSL
    // codegen with naga validation, the pass graph and its cost) and stops at the first
    // phase with an error, so one call reaches each phase the input gets to. (Calling
    // `front::ron::parse`, `front::parse::parse` and `check_str` as well, as this driver
    // once did, ran the parser four times and the checker twice per input for no new
    // coverage: each is a prefix of this call.)
    match sshc::compile_str(source, &CompileOptions::default()) {
        Ok(compiled) => {
            let _ = Diagnostics(compiled.warnings).render(FILE, source);
        }
        Err(d) => {
            // Both renderings: the codespan one (labels, notes) and the one-line form.
            let _ = d.render(FILE, source);
            for e in &d.0 {
                let _ = e.short(FILE, source);
            }
        }
    }
}
