//! The IR shared by the phases after `lower`: parameters resolved, series unrolled, one
//! concrete channel per basis term, passes in execution order, and every expression in
//! one hash-consed [`Arena`] (equal sub-expressions share a handle, constants fold as
//! nodes are added).
//!
//! One job per file: `arena.rs` (the expression nodes and the arena that makes them,
//! folding), `eval.rs` (evaluating the arena's expressions on the CPU), `entities.rs`
//! (params, channels and expansions), `resources.rs` (resources and their slots, as
//! lowered, analysed and placed), `passes.rs` (the passes and their kinds), `program.rs`
//! (the whole [`Ir`], pack's [`Layout`] and the [`Program`] view through it), `display.rs`
//! (the text form of `--dump-ir-after`) and `validate.rs` (the IR validator).

use crate::handle::{Handle, Kind};
pub use crate::interval::{Interval, short};

mod arena;
mod display;
mod entities;
mod eval;
mod passes;
mod program;
mod resources;
#[cfg(test)]
mod tests;
pub mod validate;

pub use arena::{Arena, Node, eval_call};
pub use display::WithAnalysis;
pub use entities::{IrChannel, IrExpansion, IrParam, Origin};
pub use eval::Hooks;
pub use passes::{IrKernel, IrPass, IrPassKind};
pub use program::{Ir, IrDebug, Layout, Program, Specialised};
pub use resources::{Analysis, Encode, IrResource, PlacedResource, PlacedSlot, Resource, Slot, SlotInfo, SlotView, Texture};

/// Handle of an expression node in the expression [`Arena`].
pub type ExprId = Handle<Node>;
/// Handle of a channel in [`Ir::channels`].
pub type ChannelId = Handle<IrChannel>;
/// Handle of a resource in [`Ir::resources`].
pub type ResId = Handle<IrResource>;
/// Handle of a pass in [`Ir::passes`].
pub type PassId = Handle<IrPass>;
/// Handle of a param in [`Ir::params`].
pub type ParamId = Handle<IrParam>;
/// Handle of an expansion in [`Ir::expansions`].
pub type ExpansionId = Handle<IrExpansion>;

impl Kind for Node {
    const KIND: &'static str = "node";
}
impl Kind for IrChannel {
    const KIND: &'static str = "channel";
}
impl<S> Kind for Resource<S> {
    const KIND: &'static str = "resource";
}
impl Kind for IrParam {
    const KIND: &'static str = "param";
}
impl Kind for IrExpansion {
    const KIND: &'static str = "expansion";
}
impl Kind for IrPass {
    const KIND: &'static str = "pass";
}
