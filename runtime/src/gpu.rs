//! The wgpu runtime, as one namespace. Its stages, each made from the one before:
//! [`Gpu`] (a device, its own or a host's, with error scopes and the shader and pipeline
//! caches); [`crate::graph::ValidGraph`] (a checked pass graph); [`Technique`] (its
//! pipelines, immutable, shared); [`Scene`] (a host's [`Geometry`] on the GPU, uploaded
//! once); [`Targets`] (a technique on a scene at [`Sizes`], for its lights: the frame path,
//! `prepare` and `record`, of a host's [`FrameState`]); [`Inspect`] (read-backs and memory
//! figures). Besides: [`Camera`] and [`LightInputs`] (a frame's camera and lights),
//! [`Requirements`] (what a graph needs of a device), [`HostPixels`] (a host's G-buffer),
//! [`Image`] (read-back textures) and [`SceneInputs`] (a triangle soup with one camera and
//! light, the lab's plain scene). The parts live in their own modules:
//!
//! - `error`: [`RuntimeError`];
//! - `device`: [`Gpu`], error scopes, the caches;
//! - `requirements`: [`Requirements`], read from the graph alone and checked at load;
//! - `pipeline`: the pipeline key (everything a pipeline is built from) and its building;
//! - `steps`: the step nodes (raster and compute), the one reading of each step's `Draw`
//!   (its plan), and the refusals of unsupported features;
//! - `resources`: textures, tables, attachments, edge adjacency and generated buffers at
//!   a scene's sizes (the allocation path);
//! - `geometry`: a host's indexed meshes and instances, and their placement on the GPU;
//! - `pixels`: a host's G-buffer in place of the deferred Shade's raster;
//! - `update`: the per-frame path, which writes uniforms and never creates anything;
//! - `timing`: [`FrameTimes`] and the ring of timestamp queries read back later;
//! - `adjacency` (public): the edge adjacency of a scene's meshes, built on the CPU for
//!   Geometry passes, and the silhouette rule;
//! - `technique`: [`Technique`], a loaded technique (graph, pipelines), immutable and
//!   shared; the file caps and [`read_capped`];
//! - `scene`: [`Scene`], uploaded geometry;
//! - `state`: [`FrameState`] and [`Params`], the host's plain per-frame state;
//! - `targets`: [`Targets`]: sizes, resize, prepare, record, run;
//! - `inspect`: [`Inspect`]: read-backs, memory figures, the checks of a read-back;
//! - `fit`: a light's view fitted by the runtime ([`LightInputs::fit`], [`Fit`], [`Boxes`]);
//! - `frame`: [`SceneInputs`], [`Camera`], [`LightInputs`] and the `Frame` uniform's values;
//! - `lights`: several lights combined in one frame;
//! - `image`: [`Image`] and texel decoding (the PNG and PFM writers are in the lab);
//! - `validate`: [`validate_wgsl`], naga's validation of untrusted shaders.
//!
//! Every wgpu object is created inside an error scope and its error returned as a value; on
//! the runtime's own device, errors that escape a scope are collected by its uncaptured-
//! error handler instead of wgpu's default, which panics (a host's device keeps the host's
//! handler). Sizes are checked against the device's limits before anything is allocated
//! (lavapipe keeps allocating past its limits).

pub use crate::device::{Gpu, INSTALL_HINT, Result, RuntimeError, WANTED_FEATURES};
pub use crate::fit::{Boxes, Fit};
pub use crate::frame::{Camera, LightInputs, SampleView, SceneInputs};
pub use crate::geometry::{Geometry, IDENTITY, Instance, MAX_INSTANCES, Mesh, normal_matrix, transform_point};
pub use crate::image::Image;
pub use crate::inspect::{DebugOutput, Generated, Inspect, VISIBILITY_EPSILON, check_visibility, debug_outputs};
pub use crate::lights::{MAX_LIGHTS, Slices};
pub use crate::pipeline::mip_count;
pub use crate::pixels::HostPixels;
pub use crate::requirements::{FeatureNeed, Limit, LimitNeed, Requirements};
pub use crate::resources::{DEFAULT_MAX_BYTES, GeneratedLimits, TargetLimits};
pub use crate::scene::Scene;
pub use crate::state::{FrameState, Params};
pub use crate::targets::{CameraOutput, Sizes, Targets};
pub use crate::technique::{MAX_GRAPH_BYTES, MAX_PASSES, MAX_SHADER_BYTES, Technique, read_capped};
pub use crate::timing::FrameTimes;
pub use crate::validate::validate_wgsl;
