//! The wgpu executor, as one namespace: [`Gpu`] (the device, error scopes, the shader and
//! pipeline caches), [`Executor`] (a loaded graph as step nodes, a bound scene, frames),
//! [`SceneInputs`] (what a scene gives the `Frame` uniform and the draws) and [`Image`]
//! (read-back textures). The parts live in their own modules:
//!
//! - `device`: [`Gpu`], [`RuntimeError`], error scopes, the caches;
//! - `pipeline`: the pipeline key (everything a pipeline is built from) and its building;
//! - `steps`: the step nodes (raster and compute) and the refusals of unsupported features;
//! - `resources`: textures, tables, attachments, edge adjacency and generated buffers at
//!   a scene's sizes;
//! - `adjacency` (public): the edge adjacency of a scene's meshes, built on the CPU for
//!   Geometry passes, and the silhouette rule;
//! - `executor`: [`Executor`]: load, bind, run, read back;
//! - `frame`: [`SceneInputs`] and the `Frame` uniform's values;
//! - `image`: [`Image`] and texel decoding (the PNG and PFM writers are in the lab);
//! - `validate`: [`validate_wgsl`], naga's validation of untrusted shaders.
//!
//! Every wgpu object is created inside an error scope and its error returned as a value;
//! errors that escape a scope are collected by the device's uncaptured-error handler
//! instead of wgpu's default, which panics. Sizes are checked against the device's limits
//! before anything is allocated (lavapipe keeps allocating past its limits).

pub use crate::device::{Gpu, INSTALL_HINT, Result, RuntimeError, WANTED_FEATURES};
pub use crate::executor::{
    CameraOutput, Executor, Generated, MAX_GRAPH_BYTES, MAX_PASSES, MAX_SHADER_BYTES, VISIBILITY_EPSILON, check_visibility, read_capped,
};
pub use crate::frame::{Camera, LightInputs, SampleView, SceneInputs};
pub use crate::geometry::{Geometry, IDENTITY, Instance, MAX_INSTANCES, Mesh, normal_matrix, transform_point};
pub use crate::image::Image;
pub use crate::lights::MAX_LIGHTS;
pub use crate::pixels::HostPixels;
pub use crate::requirements::{FeatureNeed, Limit, LimitNeed, Requirements};
pub use crate::resources::mip_count;
pub use crate::timing::FrameTimes;
pub use crate::validate::validate_wgsl;
