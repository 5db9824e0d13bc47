//! `sshc-runtime`: the wgpu executor of sshc pass graphs.
//!
//! It loads a compiled graph (trusted or not: every shader is re-validated with naga and
//! every size checked against the device before allocation), binds what a frame needs from
//! a scene ([`gpu::SceneInputs`]: triangles, camera, light) and runs the passes. The graph
//! schema is the crate `sshc-graph`, re-exported here as [`graph`] so that a program that
//! runs graphs needs one dependency.

#![deny(clippy::wildcard_enum_match_arm)]

pub mod adjacency;
mod device;
mod error;
mod executor;
mod frame;
mod geometry;
pub mod gpu;
mod image;
mod lights;
mod pipeline;
mod pixels;
mod requirements;
mod resources;
mod steps;
mod timing;
mod update;
mod validate;

pub use sshc_graph as graph;
pub use sshc_graph::*;
