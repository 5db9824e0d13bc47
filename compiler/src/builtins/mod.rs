//! Names the expression language knows without a declaration: receiver- and map-side
//! inputs, constants, WGSL math functions and the sampling functions of a Shade pass.
//! Each function, input and lookup has one descriptor here (`Func::desc`, `Input::desc`,
//! `SampleFn::desc`): its name, type rule, constant folding, range rule and WGSL. check,
//! lower, the arena's folding, analyse and codegen read these descriptors and do not
//! match on the function themselves.
//!
//! One job per file: `inputs.rs` (the built-in inputs), `functions.rs` (the `Func` enum and
//! the descriptor's types), `function_table.rs` (every function's descriptor, `Func::desc`),
//! `signatures.rs` (the typing rules, `Sig`), `fold.rs` (calls on constants), `lookups.rs`
//! (the lookup functions, `SampleFn`), `wgsl_helpers.rs` (the WGSL functions a module
//! appends where its code calls them) and `names.rs` (reserved names and named constants).

mod fold;
mod function_table;
mod functions;
mod inputs;
mod lookups;
mod names;
mod signatures;
#[cfg(test)]
mod tests;
mod wgsl_helpers;

/// The expression language's types live beside the syntax tree that names them.
pub use crate::front::ast::Ty;
pub use fold::{fold_call, fold_call_exact};
pub use functions::{Accuracy, Builtin, Fold, Func, Wgsl};
pub use inputs::{InView, Input, InputError, Side};
pub use lookups::{SampleFn, SampleWgsl};
pub use names::{AT_SAMPLE, MAX_NEIGHBOUR, NEIGHBOUR, constant, is_reserved};
pub use signatures::{Sig, unify};
pub use wgsl_helpers::{MIP_BOX, MIP_BOX_WGSL, NOISE_WGSL};
