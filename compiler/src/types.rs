//! What `check` decides about every expression, for `lower` to consume: the type of each
//! expression node, what each name resolves to, and where an abstract integer is
//! converted to f32. Neither phase module imports the other; both use this one.

use crate::builtins::{Input, Ty};
use crate::front::expr::Expr;
use std::collections::{HashMap, HashSet};

/// Identifies one expression node of the technique's AST. The AST is borrowed (not
/// cloned) by every phase from parse to lower, so a node's address names it; a table is
/// only meaningful with the `Technique` it was computed from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ExprId(usize);

impl ExprId {
    pub fn of(e: &Expr) -> ExprId {
        ExprId(e as *const Expr as usize)
    }
}

/// What a name in an expression stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Resolved {
    /// A `let` binding, a series variable or an expansion's index.
    Local,
    /// A param (by index into the technique's params).
    Param(usize),
    /// `PI` or `E`.
    Constant(f64),
    Input(Input),
    /// A channel (by index into the technique's channels).
    Channel(usize),
}

/// The types `check` inferred, keyed by expression node.
///
/// An integer literal is an *abstract* integer ([`Ty::AbstractInt`]) until its context
/// decides: an abstract expression is computed as i32 (its value is known at compile
/// time: `check` evaluated it), and where the context needs an f32 (an operand beside an
/// f32, an f32 argument, a channel value...) the constant is converted, as WGSL does:
/// `7 / 2 * 1.0` is `3.0`.
#[derive(Clone, Debug, Default)]
pub struct Types {
    types: HashMap<ExprId, Ty>,
    names: HashMap<ExprId, Resolved>,
    to_f32: HashSet<ExprId>,
    to_u32: HashSet<ExprId>,
}

impl Types {
    pub fn set(&mut self, e: &Expr, ty: Ty) {
        self.types.insert(ExprId::of(e), ty);
    }

    /// Whether any name resolved to `input`.
    pub fn reads_input(&self, input: crate::builtins::Input) -> bool {
        self.names.values().any(|r| matches!(r, Resolved::Input(i) if *i == input))
    }

    pub fn set_name(&mut self, e: &Expr, r: Resolved) {
        self.names.insert(ExprId::of(e), r);
    }

    /// Record that the abstract integer expression `e` is converted to f32 where it is used.
    pub fn convert_to_f32(&mut self, e: &Expr) {
        self.to_f32.insert(ExprId::of(e));
    }

    /// The inferred type of `e` (abstract for integer literals and what is made of them).
    pub fn ty(&self, e: &Expr) -> Option<Ty> {
        self.types.get(&ExprId::of(e)).copied()
    }

    /// What the name `e` resolves to.
    pub fn name(&self, e: &Expr) -> Option<Resolved> {
        self.names.get(&ExprId::of(e)).copied()
    }

    /// Record that the abstract integer expression `e` is a u32 where it is used.
    pub fn convert_to_u32(&mut self, e: &Expr) {
        self.to_u32.insert(ExprId::of(e));
    }

    /// Whether the abstract integer `e` becomes a u32 constant where it is used.
    pub fn converts_to_u32(&self, e: &Expr) -> bool {
        self.to_u32.contains(&ExprId::of(e))
    }

    /// Whether the abstract integer `e` becomes an f32 constant where it is used.
    pub fn converts_to_f32(&self, e: &Expr) -> bool {
        self.to_f32.contains(&ExprId::of(e))
    }
}

/// Index of a vector component named `x`/`r` (0), `y`/`g` (1), `z`/`b` (2), `w`/`a` (3);
/// `None` for any other letter.
pub fn comp_index(c: char) -> Option<usize> {
    match c {
        'x' | 'r' => Some(0),
        'y' | 'g' => Some(1),
        'z' | 'b' => Some(2),
        'w' | 'a' => Some(3),
        _ => None,
    }
}
