//! `sshc-runtime`: the pass-graph schema that `sshc compile` writes and the runtime loads.
//!
//! This part is always built and has no GPU dependency, so that the compiler can produce
//! graphs without wgpu (DESIGN.md section 1). The wgpu executor lands behind the `gpu`
//! feature.

#[cfg(feature = "gpu")]
pub mod bind;
#[cfg(feature = "gpu")]
mod device;
#[cfg(feature = "gpu")]
mod executor;
#[cfg(feature = "gpu")]
mod frame;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod graph;
#[cfg(feature = "gpu")]
mod image;
#[cfg(feature = "gpu")]
mod image_io;
pub mod metrics;
#[cfg(feature = "gpu")]
mod pipeline;
#[cfg(feature = "gpu")]
mod resources;
pub mod scene;
#[cfg(feature = "gpu")]
mod steps;
pub mod truth;
#[cfg(feature = "gpu")]
mod validate;
pub mod visibility;

pub use graph::*;
