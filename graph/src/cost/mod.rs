//! The cost model, in one place: what a compiled technique costs, from its graph and the
//! sizes a frame runs at. The one input it does not derive is each step's operation count
//! per invocation ([`crate::Step::cost`]), which the compiler counts on the naga IR.
//!
//! - [`sizes`]: the sizes of a frame ([`Sizes`]), texels per extent, a mip chain's share of
//!   its base, the bytes of a texture ([`crate::TextureDecl::texel_bytes`] per texel,
//!   [`crate::TextureDecl::bytes`] allocated) and of the fixed attachments.
//! - [`report`]: the static report ([`Cost`]: bytes per shadow-map texel, fetches and
//!   operations per invocation), for `<name>.cost.md` and `sshc explain`.
//! - [`work`]: invocations, fetches and operations per frame, for `sshc render`, `sweep`
//!   and `tune`.
//! - [`traffic`]: the compulsory bytes per frame and the time they bound, for `sshc render`.

pub mod report;
pub mod sizes;
pub mod traffic;
pub mod work;

pub use report::Cost;
pub use sizes::*;
