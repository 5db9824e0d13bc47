//! Passes: their kinds with each kind's data ([`IrPassKind`], the filter's [`IrKernel`])
//! and the pass itself ([`IrPass`]), what it reads and writes.

use super::{ExprId, ResId};
use crate::front::ast::{LightView, Neighbour, Primitive, Reduce, Resolve};
use crate::span::Span;

/// A filter kernel with its size resolved.
#[derive(Clone, Debug, PartialEq)]
pub enum IrKernel {
    Box(u32),
    Gaussian(u32, f64),
    Max(u32),
    Min(u32),
    LoG,
}

impl IrKernel {
    pub fn size(&self) -> u32 {
        match self {
            IrKernel::Box(n) | IrKernel::Gaussian(n, _) | IrKernel::Max(n) | IrKernel::Min(n) => *n,
            IrKernel::LoG => 3,
        }
    }

    pub fn separable(&self) -> bool {
        !matches!(self, IrKernel::LoG)
    }

    /// 1-D weights of a separable linear kernel (Box, Gaussian), normalised to sum 1.
    pub fn weights_1d(&self) -> Option<Vec<f64>> {
        let w: Vec<f64> = match self {
            IrKernel::Box(n) => vec![1.0; *n as usize],
            IrKernel::Gaussian(n, sigma) => {
                let r = (*n as i64 - 1) / 2;
                (-r..=r).map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp()).collect()
            }
            IrKernel::Max(_) | IrKernel::Min(_) | IrKernel::LoG => return None,
        };
        let s: f64 = w.iter().sum();
        Some(w.into_iter().map(|x| x / s).collect())
    }

    /// The 3x3 Laplacian-of-Gaussian weights (row major), summing to zero.
    pub const LOG_3X3: [f64; 9] = [0.0, -1.0, 0.0, -1.0, 4.0, -1.0, 0.0, -1.0, 0.0];
}

#[derive(Clone, Debug)]
pub enum IrPassKind {
    Depth {
        view: LightView,
    },
    Map,
    Filter {
        kernel: IrKernel,
    },
    Mipmap {
        reduce: Reduce,
    },
    /// A summed-area table of the source; `sum` is what a float texture's table sums
    /// (`None`: not written, `F32`), with the span it was written at.
    SummedArea {
        sum: Option<(crate::front::ast::TableSum, Span)>,
    },
    Geometry {
        primitive: Primitive,
        resolve: Resolve,
        view: LightView,
        /// Fragments for which this bool is false are discarded.
        keep: Option<ExprId>,
        /// `Skins`: the neighbouring sample whose discontinuities are warped in.
        from: Option<Neighbour>,
    },
    Shade {
        visibility: ExprId,
    },
}

impl IrPassKind {
    /// The kind without its data, whose facts every phase asks (`sshc_graph::PassKind`).
    pub fn kind(&self) -> sshc_graph::PassKind {
        use sshc_graph::PassKind as K;
        match self {
            IrPassKind::Depth { .. } => K::Depth,
            IrPassKind::Map => K::Map,
            IrPassKind::Filter { .. } => K::Filter,
            IrPassKind::Mipmap { .. } => K::Mipmap,
            IrPassKind::SummedArea { .. } => K::SummedArea,
            IrPassKind::Geometry { .. } => K::Geometry,
            IrPassKind::Shade { .. } => K::Shade,
        }
    }

    /// A Shade pass's visibility expression (`None` for every other kind).
    pub fn visibility(&self) -> Option<ExprId> {
        match self {
            IrPassKind::Shade { visibility } => Some(*visibility),
            IrPassKind::Depth { .. }
            | IrPassKind::Map
            | IrPassKind::Filter { .. }
            | IrPassKind::Mipmap { .. }
            | IrPassKind::SummedArea { .. }
            | IrPassKind::Geometry { .. } => None,
        }
    }

    /// A Geometry pass's primitive (`None` for every other kind).
    pub fn primitive(&self) -> Option<Primitive> {
        match self {
            IrPassKind::Geometry { primitive, .. } => Some(*primitive),
            IrPassKind::Depth { .. }
            | IrPassKind::Map
            | IrPassKind::Filter { .. }
            | IrPassKind::Mipmap { .. }
            | IrPassKind::SummedArea { .. }
            | IrPassKind::Shade { .. } => None,
        }
    }

    /// The view a rasterising pass renders: a Depth's and a Geometry's (the light's centre,
    /// or each light sample); `None` for the passes that render no view of their own.
    pub fn view(&self) -> Option<LightView> {
        match self {
            IrPassKind::Depth { view } | IrPassKind::Geometry { view, .. } => Some(*view),
            IrPassKind::Map
            | IrPassKind::Filter { .. }
            | IrPassKind::Mipmap { .. }
            | IrPassKind::SummedArea { .. }
            | IrPassKind::Shade { .. } => None,
        }
    }

    /// A SummedArea pass's `sum:` as written, with its span (`None` where it is absent, and
    /// for every other kind).
    pub fn table_sum(&self) -> Option<(crate::front::ast::TableSum, Span)> {
        match self {
            IrPassKind::SummedArea { sum } => *sum,
            IrPassKind::Depth { .. }
            | IrPassKind::Map
            | IrPassKind::Filter { .. }
            | IrPassKind::Mipmap { .. }
            | IrPassKind::Geometry { .. }
            | IrPassKind::Shade { .. } => None,
        }
    }

    /// Whether the pass's output carries its source's slots (a filtered copy, a mip chain
    /// or a summed-area table of them) rather than channels the pass makes: the channel's
    /// facts (its precision, its quantisation) are its source's.
    pub fn copies_source(&self) -> bool {
        match self {
            IrPassKind::Filter { .. } | IrPassKind::Mipmap { .. } | IrPassKind::SummedArea { .. } => true,
            IrPassKind::Depth { .. } | IrPassKind::Map | IrPassKind::Geometry { .. } | IrPassKind::Shade { .. } => false,
        }
    }

    /// Whether a range its output cannot hold is this pass's to report: every pass that
    /// makes its channels, and a Laplacian-of-Gaussian filter, whose output (a difference
    /// of neighbours) has a range of its own; the other copies repeat their source's.
    pub fn reports_own_range(&self) -> bool {
        match self {
            IrPassKind::Filter { kernel } => match kernel {
                IrKernel::LoG => true,
                IrKernel::Box(_) | IrKernel::Gaussian(..) | IrKernel::Max(_) | IrKernel::Min(_) => false,
            },
            IrPassKind::Mipmap { .. } | IrPassKind::SummedArea { .. } => false,
            IrPassKind::Depth { .. } | IrPassKind::Map | IrPassKind::Geometry { .. } | IrPassKind::Shade { .. } => true,
        }
    }
}

#[derive(Clone, Debug)]
pub struct IrPass {
    pub name: String,
    pub kind: IrPassKind,
    pub reads: Vec<ResId>,
    /// Where each of `reads` is named, in the same order.
    pub read_spans: Vec<Span>,
    pub writes: Option<ResId>,
    pub span: Span,
    /// False once dead-code elimination removed it.
    pub live: bool,
    /// The schedule the technique or `--schedule` asks for (Map, Filter, Mipmap and Shade
    /// passes; `Fragment` for the others); the `schedule` phase decides the one it runs in.
    pub schedule: crate::front::ast::Schedule,
}

impl IrPass {
    pub fn kind_name(&self) -> &'static str {
        self.kind.kind().name()
    }
}
