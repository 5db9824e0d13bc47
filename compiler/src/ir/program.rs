//! The whole IR ([`Ir`]) as `lower` makes it, the [`Layout`] `pack` makes beside it, and
//! the [`Program`] view of the IR through a layout that codegen, emit and explain read.

#[cfg(doc)]
use super::Analysis;
use super::{
    Arena, ExprId, IrChannel, IrExpansion, IrParam, IrPass, IrPassKind, IrResource, ParamId, PlacedResource, PlacedSlot, ResId, Resource,
    Slot,
};
use crate::front::ast::{LightModel, LightView};
use crate::handle::Table;

#[derive(Clone, Debug)]
pub struct Ir {
    pub technique: String,
    pub title: Option<String>,
    pub paper: Option<String>,
    pub lights: Vec<LightModel>,
    pub params: Table<IrParam>,
    pub channels: Table<IrChannel>,
    pub expansions: Table<IrExpansion>,
    pub resources: Table<IrResource>,
    /// In execution order.
    pub passes: Table<IrPass>,
    pub arena: Arena,
    /// Light samples the per-sample passes render one view each of (1 without any).
    pub samples: u32,
    /// The technique's `shadow_map:` (a tuned file's map size), carried to the graph.
    pub shadow_map: Option<u32>,
    /// The scene it was specialised for (`--scene`), and what that folded.
    pub specialised: Option<Specialised>,
    /// The precisions left to the compiler (`Auto`) and why each was chosen, one line
    /// each (`lower`'s `choose_precisions`; shown by `explain`).
    pub precision_choices: Vec<String>,
    /// The Shade's debug outputs, where the build asks for them (`CompileOptions::debug`;
    /// else empty): roots of the Shade besides its visibility.
    pub debug: Vec<IrDebug>,
    /// The debug outputs the technique declares and this build leaves out (it did not ask
    /// for them): their names, for `explain`.
    pub debug_omitted: Vec<String>,
}

/// A debug output of the Shade: an f32 or vector expression of the Shade's, written
/// unclamped to the camera-sized texture `texture` (`debug_<name>`).
#[derive(Clone, Debug)]
pub struct IrDebug {
    pub name: String,
    pub texture: String,
    pub expr: ExprId,
}

/// A compilation specialised for a scene's facts.
#[derive(Clone, Debug)]
pub struct Specialised {
    pub facts: sshc_graph::SceneFacts,
    /// What the facts folded, one line each (shown by `explain`).
    pub folded: Vec<String>,
}

impl Ir {
    /// The Shade's roots: its visibility, then its debug outputs (where the build has them).
    pub fn shade_roots(&self, visibility: ExprId) -> Vec<ExprId> {
        std::iter::once(visibility).chain(self.debug.iter().map(|d| d.expr)).collect()
    }

    /// Whether resource `r` holds one layer block per light sample (a per-sample pass
    /// writes it).
    pub fn per_sample(&self, r: ResId) -> bool {
        self.passes.iter().any(|p| {
            p.writes == Some(r)
                && matches!(
                    p.kind,
                    IrPassKind::Depth {
                        view: LightView::PerSample
                    } | IrPassKind::Geometry {
                        view: LightView::PerSample,
                        ..
                    }
                )
        })
    }
}

/// The product of `pack`, beside the IR (which `pack` only reads): the resources with
/// their live slots placed in textures (ranges and encodings from the [`Analysis`]), the
/// passes with their live flags, and what elimination removed.
#[derive(Clone, Debug, Default)]
pub struct Layout {
    /// One per resource of the IR, indexed by its [`ResId`].
    pub resources: Table<PlacedResource, IrResource>,
    pub passes: Table<IrPass>,
    /// What optimisation removed, and why (reported by `explain` and the cost report).
    pub removed: Vec<String>,
}

/// What codegen, emit and explain read: the IR of `lower` seen through the [`Layout`] of
/// `pack`. The fields `resources`, `passes` and `removed` are the layout's; everything
/// else (params, channels, expansions, the arena...) derefs to the IR. `S` is
/// [`PlacedSlot`] but for the IR as lowered ([`Program::lowered`], slots [`Slot`]).
pub struct Program<'a, S = PlacedSlot> {
    pub ir: &'a Ir,
    pub resources: &'a Table<Resource<S>, IrResource>,
    pub passes: &'a Table<IrPass>,
    pub removed: &'a [String],
}

impl<S> Clone for Program<'_, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S> Copy for Program<'_, S> {}

impl<S> Program<'_, S> {
    /// The visibility expression of the live Shade pass.
    pub fn shade(&self) -> Option<ExprId> {
        self.passes.iter().filter(|pass| pass.live).find_map(|pass| pass.kind.visibility())
    }
}

impl<'a> Program<'a> {
    pub fn new(ir: &'a Ir, layout: &'a Layout) -> Program<'a> {
        Program {
            ir,
            resources: &layout.resources,
            passes: &layout.passes,
            removed: &layout.removed,
        }
    }
}

impl<'a> Program<'a, Slot> {
    /// The IR as `lower` left it (nothing laid out yet, nothing removed).
    pub fn lowered(ir: &'a Ir) -> Program<'a, Slot> {
        Program {
            ir,
            resources: &ir.resources,
            passes: &ir.passes,
            removed: &[],
        }
    }
}

impl<'a, S> Program<'a, S> {
    pub fn shade_pass(&self) -> Option<&'a IrPass> {
        self.passes.iter().find(|p| p.kind.kind().is_shade())
    }
}

impl<S> std::ops::Deref for Program<'_, S> {
    type Target = Ir;
    fn deref(&self) -> &Ir {
        self.ir
    }
}

impl Ir {
    /// The Shade pass (the IR's tests ask the lowered IR; the phases ask the `Program`).
    #[cfg(test)]
    pub fn shade_pass(&self) -> Option<&IrPass> {
        self.passes.iter().find(|p| p.kind.kind().is_shade())
    }

    pub fn uniform_params(&self) -> impl Iterator<Item = (ParamId, &IrParam)> {
        self.params.with_handles().filter(|(_, p)| p.uniform)
    }
}
