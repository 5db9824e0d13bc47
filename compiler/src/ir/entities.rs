//! The IR's params, channels (with where each came from, [`Origin`]) and basis expansions.

use super::{ChannelId, ExpansionId, ExprId};
use crate::front::ast::{ConstValue, Precision, ScalarTy};
use crate::span::Span;

#[derive(Clone, Debug)]
pub struct IrParam {
    pub name: String,
    pub name_span: Span,
    pub ty: ScalarTy,
    pub value: ConstValue,
    pub range: Option<(f64, f64)>,
    /// A runtime uniform (true) or substituted at compile time (false).
    pub uniform: bool,
    pub doc: Option<String>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Origin {
    /// Written by a Depth pass.
    Depth,
    /// Declared in `channels` with a value.
    Declared,
    /// Basis term `term` of expansion `expansion` at index `k`.
    Basis { expansion: ExpansionId, term: usize, k: i64 },
}

#[derive(Clone, Debug)]
pub struct IrChannel {
    pub name: String,
    pub precision: Precision,
    /// Where the precision was chosen (for diagnostics).
    pub precision_span: Span,
    /// The precision came from `--precision` rather than the file.
    pub precision_overridden: bool,
    /// The precision is left to the compiler (`Auto`): `lower` chooses it, last (`choose_precisions`).
    pub precision_auto: bool,
    pub value: Option<ExprId>,
    /// The declared range (`range: (lo, hi)`): values are clamped to it when stored.
    pub range: Option<(f64, f64)>,
    pub origin: Origin,
    pub span: Span,
}

#[derive(Clone, Debug)]
pub struct IrExpansion {
    pub name: String,
    pub constant: ExprId,
    /// Unrolled terms: receiver-side coefficient and the basis channel it multiplies.
    pub terms: Vec<(ExprId, ChannelId)>,
    pub span: Span,
}
