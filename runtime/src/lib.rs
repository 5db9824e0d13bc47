//! `sshc-runtime`: the pass-graph schema that `sshc compile` writes and the runtime loads.
//!
//! This part is always built and has no GPU dependency, so that the compiler can produce
//! graphs without wgpu (DESIGN.md section 1). The wgpu executor lands behind the `gpu`
//! feature.

#[cfg(feature = "gpu")]
pub mod bind;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod graph;
pub mod metrics;
pub mod scene;
pub mod truth;
pub mod visibility;

pub use graph::*;
