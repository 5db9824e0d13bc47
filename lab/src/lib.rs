//! `sshc-lab`: measurement of soft-shadow techniques.
//!
//! Scenes in RON ([`scene`], the crate `sshc-scene`), the CPU visibility query over a BVH ([`visibility`]), the
//! ray-traced ground truth and its cache ([`truth`], shared safely through claim files:
//! [`claim`]), error metrics ([`metrics`]), the
//! conversion of a scene into what the runtime binds for a frame ([`bind`]), and the
//! commands that run techniques on scenes and measure them ([`cmd`]: render, truth,
//! compare, sweep), which share one [`session`] module. The `sshc` binary
//! (`src/main.rs`) is a thin shell over this crate and the compiler library.

pub mod bind;
pub mod claim;
pub mod cmd;
pub mod files;
pub mod image_io;
pub mod metrics;
pub mod run;
pub mod session;
pub mod truth;
pub mod verify;
#[cfg(feature = "view")]
pub mod view;
pub mod visibility;

/// Scenes live in their own crate, `sshc-scene` (no GPU), so that fuzzing and other tools
/// can read them without the measurement code; re-exported here under its old path.
pub use sshc_scene as scene;
