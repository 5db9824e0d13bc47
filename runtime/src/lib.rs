//! `sshc-runtime`: sshc pass graphs run on wgpu, as stages a host holds (`gpu`: technique,
//! scene, targets, frame state).
//!
//! It loads a compiled graph (trusted or not: every shader is re-validated with naga and
//! every size checked against the device before allocation), binds what a frame needs (a
//! host's indexed meshes and instances, [`gpu::Geometry`], or a triangle soup,
//! [`gpu::SceneInputs`], which becomes one) and runs the passes: on its own device, or inside a host renderer on
//! the host's device, recording into the host's encoder every frame and handing the
//! visibility back as a texture (docs/embedding.md). The graph schema is the crate
//! `sshc-graph`, re-exported here as [`graph`] so that a program that runs graphs needs one
//! dependency.

#![deny(clippy::wildcard_enum_match_arm)]

pub mod adjacency;
mod device;
mod error;
mod fit;
mod frame;
mod geometry;
pub mod gpu;
mod image;
mod inspect;
mod lights;
mod pipeline;
mod pixels;
mod pool;
mod receivers;
mod requirements;
mod resources;
mod scene;
mod state;
mod steps;
mod targets;
mod technique;
mod timing;
mod update;
mod usages;
mod validate;

pub use sshc_graph as graph;
pub use sshc_graph::*;
/// Lights and their views as plain math (the crate `sshc-light`, shared with the lab's
/// scenes): what [`gpu::LightInputs::fit`] and [`gpu::Targets::fit_light`] fit.
pub use sshc_light as light;
/// The wgpu the runtime is built on: a host records into its encoders.
pub use wgpu;
