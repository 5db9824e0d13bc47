//! `sshc_shaders_gen::technique!`: compile an sshc technique when the crate builds and embed
//! it as a Rust module.
//!
//! ```ignore
//! sshc_shaders_gen::technique!(pub mod pcf = "techniques/pcf.ron");
//! // with overrides, as `sshc --set` / `--precision`:
//! sshc_shaders_gen::technique!(pub mod pcf5 = "techniques/pcf.ron", set: { N = 5 }, precision: { z = F16 });
//!
//! let graph = pcf::graph()?;                 // sshc_graph::PassGraph
//! let shaders = pcf::shaders();              // [(file name, WGSL)] for Technique::new
//! let bytes = pcf::Params::default().to_bytes(); // the `Params` uniform
//! ```
//!
//! The path is relative to the directory of the using crate's `Cargo.toml`. The generated
//! module names the graph-schema crate as `::sshc_graph`, so the using crate depends on
//! `sshc-graph` (serde and ron only; the runtime, `sshc-runtime`, is needed only to run it);
//! `graph: crate::path::to::sshc_graph` names it elsewhere (a path as seen from inside
//! the generated module). A technique that does not compile fails the
//! build with the compiler's own diagnostic (`file:line:column`). The module contents are
//! described in the crate `sshc-shaders-gen-impl`, which does the work; this crate is the
//! proc-macro shell around it.

use proc_macro::TokenStream;

/// Embed a technique: `technique!(pub mod NAME = "path/to/technique.ron")`, optionally
/// followed by `, set: { NAME = VALUE, .. }`, `, precision: { NAME = PRECISION, .. }` and
/// `, graph: path::to::sshc_graph`.
#[proc_macro]
pub fn technique(input: TokenStream) -> TokenStream {
    sshc_shaders_gen_impl::expand(input.into()).into()
}
