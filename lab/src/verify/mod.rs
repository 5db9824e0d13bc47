//! `sshc verify`: a compiled technique run on the GPU over the inputs of the
//! agreement tests and compared, receiver by receiver, with the compiler's f64 evaluation
//! of the same technique on the CPU (`sshc::eval`), within that evaluation's allowance.
//!
//! The inputs: synthetic depth fields ([`FIELDS`]: a ramp, a step, a checkerboard, noise,
//! all 0 and all 1) and the light's depth maps of bundled scenes, each fed to the passes
//! after Depth in place of the Depth pass's output (the runtime's depth override), read at
//! the shading points of the [`QueryPlane`] (a receiver whose depth runs across [0, 1]),
//! seen by two cameras: 2N pixels over the N-texel map (implicit level of detail -1) and
//! N/2 (level 1).
//!
//! Each (input, camera) gets a verdict ([`Verdict`]): **agrees** when every receiver's GPU
//! value lies within the allowance about the CPU value; **differs** when one does not (a
//! code generation bug, or a technique whose result the model does not bound); **lossy**
//! when the GPU agrees but storage rounding alone (the CPU evaluation with every texel
//! rounded as stored, against the exact one) moves the visibility by more than
//! [`sshc::eval::WARN_ABOVE`] at 1 % of the receivers or more: a precision that loses the
//! signal; **UNCHECKED** when nothing differs or is lossy, but at some receiver the GPU's
//! value is [`TELLS_APART`] or more from the CPU's and only an allowance of [`TELLS_APART`]
//! or more admits it: an allowance that wide cannot tell a lit pixel from a shadowed one, so
//! the comparison there checked nothing, and the row is not reported as agreement (nor as a
//! failure: the bound is honest, only too loose to decide). With a reference technique
//! (`--reference`), its f64 CPU evaluation is compared with the technique's under the same
//! allowance: an independent reading of the math.
//!
//! The files: `plane.rs` the query plane (its light, camera and receivers), `fields.rs` the
//! synthetic depth fields, a scene's depth map and what an input is, `casters.rs` the
//! caster meshes above the plane, `options.rs` what a run takes, `run.rs` the GPU frame and
//! the CPU evaluation of each (input, camera), `cascade.rs` the cascades' mixture as the
//! GPU combines them, `verdict.rs` a row's counts and its verdict, `report.rs` the table,
//! the summary and the pictures.

mod cascade;
mod casters;
mod fields;
mod options;
mod plane;
mod report;
mod run;
mod verdict;

pub use casters::{CASTERS, caster_set, scene_casters};
pub use fields::{FIELDS, Input, Source, depth_field, noise, scene_depth};
pub use options::Options;
pub use plane::{CASTER_SLAB, QueryPlane};
pub use report::{Summary, table, unchecked_note};
pub use run::verify;
pub use verdict::{DebugRow, LOSSY_SHARE, Row, TELLS_APART, Verdict, Worst, unchecked};
