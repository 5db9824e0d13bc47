//! The CPU evaluation of a compiled technique: what `sshc verify` checks the GPU's
//! visibility against, and the bounds it is checked within.
//!
//! An [`Evaluation`] of a [`crate::Compiled`] runs its passes from [`Given`] maps (the
//! depth views, or maps read back from the GPU; [`given_slots`] says which) under a
//! [`Frame`], then answers each [`Receiver`] with an [`Allowed`] interval: the value and
//! how far the GPU may stray from it under the [`Model`] of its arithmetic and the
//! [`Rounding`] of its storage. Behind this facade are the crate's `interp` (the
//! evaluator), `rounding` (the storage-rounding estimate) and `tables` (summed-area tables
//! on the CPU and their error bounds).

pub use crate::interp::{Allowed, Evaluation, Frame, Given, GivenSlot, Model, Receiver, Rounding, Scratch, Seen, given_slots};
pub use crate::rounding::{ChannelError, Detail, Estimate, WARN_ABOVE};
pub use crate::tables::{f32_box_bound, f32_entry_bound, f32_table, f64_table};

/// The first-order estimate of what storage rounding does to the visibility (`sshc
/// explain`'s table; the warning above [`WARN_ABOVE`]); `None` where the technique has no
/// channel stored below F32 or the estimate does not apply (`rounding::unsupported`).
pub fn estimate(compiled: &crate::Compiled, detail: Detail) -> Option<Estimate> {
    crate::rounding::estimate(&compiled.program(), detail)
}
