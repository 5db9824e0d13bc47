//! `sshc-lab`: measurement of soft-shadow techniques.
//!
//! Scenes in RON ([`scene`]), the CPU visibility query over a BVH ([`visibility`]), the
//! ray-traced ground truth and its cache ([`truth`]), error metrics ([`metrics`]), the
//! conversion of a scene into what the runtime binds for a frame ([`bind`]), and the
//! commands that run techniques on scenes and measure them ([`cmd`]: render, truth,
//! compare, sweep), which share one [`session`] module. The `sshc` binary (crate
//! `sshc-cli`) is a thin shell over this crate and the compiler library.

pub mod bind;
pub mod cmd;
pub mod image_io;
pub mod metrics;
pub mod scene;
pub mod session;
pub mod truth;
pub mod visibility;
