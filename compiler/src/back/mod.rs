//! Back end: WGSL generation (`wgsl.rs` drives it, one module per pass kind and the
//! expression emitter beside it), naga validation, operation counts on the naga IR, and
//! the diagnostic of an internal error met while generating code.

pub(crate) mod depth;
pub(crate) mod expr;
pub(crate) mod filter;
pub(crate) mod formats;
pub mod geometry;
pub(crate) mod geometry_pass;
pub(crate) mod map;
pub(crate) mod mipmap;
pub mod parts;
pub(crate) mod shade;
pub(crate) mod steps;
pub(crate) mod summed_area;
pub(crate) mod text;
pub mod wgsl;

use crate::diag::{Diagnostic, Phase};
use sshc_graph::OpCount;

/// An internal compiler error met while generating code.
pub(crate) fn internal(msg: impl Into<String>) -> Diagnostic {
    Diagnostic::error(Phase::Codegen, format!("internal compiler error: {}", msg.into())).note("please report this with the technique file")
}

/// Parse and validate WGSL with naga; the error text is naga's own.
pub fn validate(source: &str) -> Result<naga::Module, String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    let mut v = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
    v.validate(&module).map_err(|e| e.emit_to_string(source))?;
    Ok(module)
}

/// Fetches (texture reads and storage-buffer loads: summed-area tables) and arithmetic
/// operations of one invocation of `entry`, counted on the naga IR (straight-line code:
/// each expression runs once, a loop's body once; called functions are counted at their
/// call sites).
pub fn count_ops(module: &naga::Module, entry: &str) -> OpCount {
    let Some(ep) = module.entry_points.iter().find(|e| e.name == entry) else {
        return OpCount::default();
    };
    let mut c = OpCount::default();
    count_function(module, &ep.function, &mut c, 0);
    c
}

/// Whether `pointer` points into a storage buffer (through any chain of accesses).
fn in_storage(module: &naga::Module, f: &naga::Function, mut pointer: naga::Handle<naga::Expression>) -> bool {
    use naga::Expression as E;
    loop {
        match f.expressions[pointer] {
            E::Access { base, .. } | E::AccessIndex { base, .. } => pointer = base,
            E::GlobalVariable(g) => return matches!(module.global_variables[g].space, naga::AddressSpace::Storage { .. }),
            E::Literal(_)
            | E::Constant(_)
            | E::Override(_)
            | E::ZeroValue(_)
            | E::Compose { .. }
            | E::Splat { .. }
            | E::Swizzle { .. }
            | E::FunctionArgument(_)
            | E::LocalVariable(_)
            | E::Load { .. }
            | E::ImageSample { .. }
            | E::ImageLoad { .. }
            | E::ImageQuery { .. }
            | E::Unary { .. }
            | E::Binary { .. }
            | E::Select { .. }
            | E::Derivative { .. }
            | E::Relational { .. }
            | E::Math { .. }
            | E::As { .. }
            | E::CallResult(_)
            | E::AtomicResult { .. }
            | E::WorkGroupUniformLoadResult { .. }
            | E::ArrayLength(_)
            | E::RayQueryVertexPositions { .. }
            | E::RayQueryProceedResult
            | E::RayQueryGetIntersection { .. }
            | E::SubgroupBallotResult
            | E::SubgroupOperationResult { .. }
            | E::CooperativeLoad { .. }
            | E::CooperativeMultiplyAdd { .. } => return false,
        }
    }
}

fn count_function(module: &naga::Module, f: &naga::Function, c: &mut OpCount, depth: usize) {
    use naga::Expression as E;
    for (_, e) in f.expressions.iter() {
        match e {
            E::ImageSample { .. } | E::ImageLoad { .. } => c.fetches += 1,
            E::Load { pointer } if in_storage(module, f, *pointer) => c.fetches += 1,
            E::Binary { .. } | E::Unary { .. } | E::Math { .. } | E::Select { .. } | E::As { .. } | E::Relational { .. } => c.ops += 1,
            E::Literal(_)
            | E::Constant(_)
            | E::Override(_)
            | E::ZeroValue(_)
            | E::Compose { .. }
            | E::Access { .. }
            | E::AccessIndex { .. }
            | E::Splat { .. }
            | E::Swizzle { .. }
            | E::FunctionArgument(_)
            | E::GlobalVariable(_)
            | E::LocalVariable(_)
            | E::Load { .. }
            | E::ImageQuery { .. }
            | E::Derivative { .. }
            | E::CallResult(_)
            | E::AtomicResult { .. }
            | E::WorkGroupUniformLoadResult { .. }
            | E::ArrayLength(_)
            | E::RayQueryVertexPositions { .. }
            | E::RayQueryProceedResult
            | E::RayQueryGetIntersection { .. }
            | E::SubgroupBallotResult
            | E::SubgroupOperationResult { .. }
            | E::CooperativeLoad { .. }
            | E::CooperativeMultiplyAdd { .. } => {}
        }
    }
    if depth < 8 {
        for (_, e) in f.expressions.iter() {
            if let E::CallResult(h) = e {
                count_function(module, &module.functions[*h], c, depth + 1);
            }
        }
    }
}
