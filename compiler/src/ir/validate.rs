//! The IR validator: what every phase after `lower` may rely on. The driver runs it after
//! `lower` and after `pack` in debug builds (so every test validates every IR it
//! compiles); a failure is an internal compiler error.
//!
//! Checked: every handle indexes its arena; operands precede their users (the expression
//! arena is topologically ordered); every node's type agrees with its operator's
//! signature; every channel, expansion, resource and pass reference is valid; a resource is
//! written by the pass it names, and every read comes from an earlier pass; lookups appear
//! only on the receiver side and read a resource their pass reads; a Shade pass exists,
//! exactly one; placements (after `pack`) lie inside their textures.

use super::*;
use crate::builtins::Ty;
use crate::front::expr::{BinOp, UnOp};
use std::collections::HashSet;
use std::fmt;

/// Why an IR is invalid.
#[derive(Clone, Debug, PartialEq)]
pub enum ValidationError {
    /// An operand of `node` is `operand`, which is not an earlier node.
    OperandOrder {
        node: ExprId,
        operand: ExprId,
    },
    /// A handle of the expression arena out of range, where `at` says.
    BadNode {
        at: String,
        node: ExprId,
    },
    /// The type of `node` does not follow from its operands.
    NodeType {
        node: ExprId,
        ty: Ty,
        why: String,
    },
    BadParam {
        node: ExprId,
        param: ParamId,
    },
    BadChannel {
        at: String,
        channel: ChannelId,
    },
    BadResource {
        at: String,
        resource: ResId,
    },
    BadPass {
        at: String,
        pass: PassId,
    },
    BadExpansion {
        at: String,
        expansion: ExpansionId,
    },
    /// A root expression (channel value, coefficient, visibility...) that is not an f32.
    RootType {
        at: String,
        ty: Ty,
    },
    /// A `Channel` node (map side) reached from a receiver-side root, or a `Sample`
    /// (receiver side) from a map-side root.
    WrongSide {
        at: String,
        node: ExprId,
    },
    /// A lookup of a resource the Shade pass does not read, or of a channel it lacks.
    BadLookup {
        node: ExprId,
        why: String,
    },
    /// Resource `resource` names `pass` as its writer, but that pass writes something else.
    Writer {
        resource: ResId,
        pass: PassId,
    },
    /// `pass` reads `resource`, written by a pass that does not run before it.
    ReadOrder {
        pass: PassId,
        resource: ResId,
    },
    /// A pass has the wrong number of reads or no write for its kind.
    PassShape {
        pass: PassId,
        why: String,
    },
    /// A slot's channel twice in one resource, or a placement outside its texture.
    Slot {
        resource: ResId,
        channel: ChannelId,
        why: String,
    },
    /// Not exactly one Shade pass.
    ShadePasses(usize),
}

impl fmt::Display for ValidationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ValidationError::OperandOrder { node, operand } => write!(f, "{node:?} uses {operand:?}, which does not precede it"),
            ValidationError::BadNode { at, node } => write!(f, "{at}: {node:?} is not in the expression arena"),
            ValidationError::NodeType { node, ty, why } => write!(f, "{node:?} has type {ty}: {why}"),
            ValidationError::BadParam { node, param } => write!(f, "{node:?} reads {param:?}, which does not exist"),
            ValidationError::BadChannel { at, channel } => write!(f, "{at}: {channel:?} does not exist"),
            ValidationError::BadResource { at, resource } => write!(f, "{at}: {resource:?} does not exist"),
            ValidationError::BadPass { at, pass } => write!(f, "{at}: {pass:?} does not exist"),
            ValidationError::BadExpansion { at, expansion } => write!(f, "{at}: {expansion:?} does not exist"),
            ValidationError::RootType { at, ty } => write!(f, "{at} has type {ty}, not f32"),
            ValidationError::WrongSide { at, node } => write!(f, "{at} reaches {node:?}, which belongs to the other side"),
            ValidationError::BadLookup { node, why } => write!(f, "lookup {node:?}: {why}"),
            ValidationError::Writer { resource, pass } => {
                write!(f, "{resource:?} names {pass:?} as its writer, which writes something else")
            }
            ValidationError::ReadOrder { pass, resource } => write!(f, "{pass:?} reads {resource:?} before it is written"),
            ValidationError::PassShape { pass, why } => write!(f, "{pass:?}: {why}"),
            ValidationError::Slot { resource, channel, why } => write!(f, "{resource:?}, slot of {channel:?}: {why}"),
            ValidationError::ShadePasses(n) => write!(f, "{n} Shade passes, not exactly one"),
        }
    }
}

impl std::error::Error for ValidationError {}

/// Check the invariants of the IR of `lower` (see the module documentation); the driver
/// checks `Program::lowered` directly.
#[cfg(test)]
pub fn validate_ir(ir: &Ir) -> Result<(), ValidationError> {
    validate(&Program::lowered(ir))
}

/// Check the invariants of an IR seen through its layout (after `pack`), or as lowered
/// ([`Program::lowered`]).
pub fn validate<S: SlotView>(ir: &Program<S>) -> Result<(), ValidationError> {
    nodes(ir)?;
    channels(ir)?;
    resources_and_passes(ir)
}

fn nodes<S: SlotView>(ir: &Program<S>) -> Result<(), ValidationError> {
    let a = &ir.arena;
    for i in 0..a.len() {
        let h = ExprId::new(i);
        for op in a.operands(h) {
            if op.index() >= i {
                return Err(ValidationError::OperandOrder { node: h, operand: op });
            }
        }
        let ty = a.ty(h);
        let bad = |why: String| Err(ValidationError::NodeType { node: h, ty, why });
        let expect = |want: Ty, what: &str| if ty == want { Ok(()) } else { bad(format!("{what} is {want}")) };
        match a.node(h) {
            Node::F32(_) => expect(Ty::F32, "an f32 constant")?,
            Node::I32(_) => expect(Ty::I32, "an i32 constant")?,
            Node::U32(_) => expect(Ty::U32, "a u32 constant")?,
            Node::Bool(_) => expect(Ty::Bool, "a bool constant")?,
            Node::Param(p) => {
                let Some(param) = ir.params.get(*p) else {
                    return Err(ValidationError::BadParam { node: h, param: *p });
                };
                expect(Ty::from_scalar(param.ty), "the param")?;
            }
            Node::Input(input, _) => expect(input.ty(), "the input")?,
            Node::Channel(c, _) => {
                if !ir.channels.contains(*c) {
                    return Err(ValidationError::BadChannel {
                        at: format!("{h:?}"),
                        channel: *c,
                    });
                }
                expect(Ty::F32, "a channel")?;
            }
            Node::Sample {
                channel,
                resource,
                how,
                args,
                ..
            } => {
                if !ir.channels.contains(*channel) {
                    return Err(ValidationError::BadChannel {
                        at: format!("{h:?}"),
                        channel: *channel,
                    });
                }
                if !ir.resources.contains(*resource) {
                    return Err(ValidationError::BadResource {
                        at: format!("{h:?}"),
                        resource: *resource,
                    });
                }
                let want = how.extra_args();
                let got: Vec<Ty> = args.iter().map(|x| a.ty(*x)).collect();
                if got != want {
                    return bad(format!("`{}` takes {want:?} after the channel, found {got:?}", how.name(false)));
                }
                expect(Ty::F32, "a lookup")?;
            }
            Node::Unary(op, x) => {
                let t = a.ty(*x);
                match op {
                    UnOp::Neg if matches!(t, Ty::F32 | Ty::I32 | Ty::Vec(_)) => expect(t, "a negation of its operand's type")?,
                    UnOp::Not if t == Ty::Bool => expect(Ty::Bool, "`!`")?,
                    UnOp::BitNot if matches!(t, Ty::I32 | Ty::U32) => expect(t, "`~` of its operand's type")?,
                    UnOp::Neg | UnOp::Not | UnOp::BitNot => return bad(format!("`{op:?}` of {t}")),
                }
            }
            Node::Binary(op, x, y) => {
                let (tx, ty_) = (a.ty(*x), a.ty(*y));
                if op.is_logic() {
                    if tx != Ty::Bool || ty_ != Ty::Bool {
                        return bad(format!("`{}` of {tx} and {ty_}", op.symbol()));
                    }
                    expect(Ty::Bool, "a logic operation")?;
                } else if op.is_shift() {
                    // an integer shifted by a u32 count
                    if !matches!(tx, Ty::I32 | Ty::U32) || ty_ != Ty::U32 {
                        return bad(format!("`{}` of {tx} by {ty_}", op.symbol()));
                    }
                    expect(tx, "the shifted operand's type")?;
                } else if op.is_bitwise() {
                    if tx != ty_ || !matches!(tx, Ty::I32 | Ty::U32) {
                        return bad(format!("`{}` between {tx} and {ty_}", op.symbol()));
                    }
                    expect(tx, "the type of its operands")?;
                } else if op.is_comparison() {
                    let same = tx == ty_ && matches!(tx, Ty::F32 | Ty::I32 | Ty::U32)
                        || (tx == Ty::Bool && ty_ == Ty::Bool && matches!(op, BinOp::Eq | BinOp::Ne));
                    if !same {
                        return bad(format!("`{}` between {tx} and {ty_}", op.symbol()));
                    }
                    expect(Ty::Bool, "a comparison")?;
                } else {
                    // arithmetic: one type, or a scalar f32 beside a vector
                    let result = match (tx, ty_) {
                        (t, u) if t == u && matches!(t, Ty::F32 | Ty::I32 | Ty::U32 | Ty::Vec(_)) => Some(t),
                        (Ty::Vec(n), Ty::F32) | (Ty::F32, Ty::Vec(n)) => Some(Ty::Vec(n)),
                        _ => None,
                    };
                    match result {
                        Some(r) => expect(r, "the type of its operands")?,
                        None => return bad(format!("`{}` between {tx} and {ty_}", op.symbol())),
                    }
                }
            }
            Node::Call(f, args) => {
                let tys: Vec<Ty> = args.iter().map(|x| a.ty(*x)).collect();
                match f.result(&tys) {
                    Ok(r) => expect(r, &format!("`{}` of {tys:?}", f.name()))?,
                    Err(m) => return bad(m),
                }
            }
            Node::Swizzle(x, comps) => {
                let Ty::Vec(n) = a.ty(*x) else {
                    return bad(format!("a swizzle of {}", a.ty(*x)));
                };
                if comps.is_empty() || comps.len() > 4 || comps.iter().any(|c| *c >= n) {
                    return bad(format!("components {comps:?} of a vec{n}"));
                }
                expect(if comps.len() == 1 { Ty::F32 } else { Ty::Vec(comps.len() as u8) }, "the swizzle")?;
            }
        }
    }
    Ok(())
}

/// A root expression: in the arena, an f32, and only of its side (`map`: channels, no
/// lookups; receiver: lookups, no channels).
fn root<S: SlotView>(ir: &Program<S>, h: ExprId, at: &str, map: bool) -> Result<(), ValidationError> {
    if h.index() >= ir.arena.len() {
        return Err(ValidationError::BadNode {
            at: at.to_string(),
            node: h,
        });
    }
    let ty = ir.arena.ty(h);
    if ty != Ty::F32 {
        return Err(ValidationError::RootType { at: at.to_string(), ty });
    }
    receiver_side(ir, h, at, map)
}

/// Every node of `h` is of one side: no channel read as a plain value on the receiver
/// side, no lookup on the map side.
fn receiver_side<S: SlotView>(ir: &Program<S>, h: ExprId, at: &str, map: bool) -> Result<(), ValidationError> {
    for n in ir.arena.postorder(&[h]) {
        let wrong = match ir.arena.node(n) {
            Node::Channel(..) => !map,
            Node::Sample { .. } => map,
            Node::F32(_)
            | Node::I32(_)
            | Node::U32(_)
            | Node::Bool(_)
            | Node::Param(_)
            | Node::Input(..)
            | Node::Unary(..)
            | Node::Binary(..)
            | Node::Call(..)
            | Node::Swizzle(..) => false,
        };
        if wrong {
            return Err(ValidationError::WrongSide {
                at: at.to_string(),
                node: n,
            });
        }
    }
    Ok(())
}

fn channels<S: SlotView>(ir: &Program<S>) -> Result<(), ValidationError> {
    for (c, ch) in ir.channels.with_handles() {
        if let Some(v) = ch.value {
            root(ir, v, &format!("the value of {c:?} `{}`", ch.name), true)?;
        }
        if let Origin::Basis { expansion, .. } = ch.origin
            && !ir.expansions.contains(expansion)
        {
            return Err(ValidationError::BadExpansion {
                at: format!("the origin of {c:?}"),
                expansion,
            });
        }
    }
    for e in &ir.expansions {
        root(ir, e.constant, &format!("the constant of expansion `{}`", e.name), false)?;
        for (coeff, c) in &e.terms {
            root(ir, *coeff, &format!("a coefficient of expansion `{}`", e.name), false)?;
            if !ir.channels.contains(*c) {
                return Err(ValidationError::BadChannel {
                    at: format!("a term of expansion `{}`", e.name),
                    channel: *c,
                });
            }
        }
    }
    Ok(())
}

fn resources_and_passes<S: SlotView>(ir: &Program<S>) -> Result<(), ValidationError> {
    for (r, res) in ir.resources.with_handles() {
        let Some(w) = ir.passes.get(res.writer) else {
            return Err(ValidationError::BadPass {
                at: format!("the writer of {r:?}"),
                pass: res.writer,
            });
        };
        if w.writes != Some(r) {
            return Err(ValidationError::Writer {
                resource: r,
                pass: res.writer,
            });
        }
        let mut seen = HashSet::new();
        for s in &res.slots {
            let channel = s.channel();
            if !ir.channels.contains(channel) {
                return Err(ValidationError::BadChannel {
                    at: format!("a slot of {r:?}"),
                    channel,
                });
            }
            let slot_err = |why: String| ValidationError::Slot { resource: r, channel, why };
            if !seen.insert(channel) {
                return Err(slot_err("the channel is stored twice".into()));
            }
            if let Some(&PlacedSlot {
                texture: t,
                layer,
                component: comp,
                precision,
                ..
            }) = s.placed()
            {
                let Some(tex) = res.textures.get(t) else {
                    return Err(slot_err(format!("placed in texture {t} of {}", res.textures.len())));
                };
                if layer >= tex.layers || comp >= tex.components || tex.precision != precision {
                    return Err(slot_err(format!(
                        "placed at layer {layer}, component {comp} of `{}` ({} layers of {} components at {})",
                        tex.name,
                        tex.layers,
                        tex.components,
                        tex.precision.name()
                    )));
                }
            }
        }
    }
    let mut shades = 0;
    for (p, pass) in ir.passes.with_handles() {
        for &r in &pass.reads {
            let Some(res) = ir.resources.get(r) else {
                return Err(ValidationError::BadResource {
                    at: format!("the reads of {p:?}"),
                    resource: r,
                });
            };
            if res.writer >= p {
                return Err(ValidationError::ReadOrder { pass: p, resource: r });
            }
        }
        if let Some(w) = pass.writes
            && ir.resources.get(w).is_none_or(|res| res.writer != p)
        {
            return Err(ValidationError::Writer { resource: w, pass: p });
        }
        let shape = |why: &str| ValidationError::PassShape { pass: p, why: why.into() };
        match &pass.kind {
            IrPassKind::Filter { .. } | IrPassKind::Mipmap { .. } | IrPassKind::SummedArea { .. } => {
                if pass.reads.len() != 1 || pass.writes.is_none() {
                    return Err(shape("reads one resource and writes one"));
                }
            }
            IrPassKind::Depth { .. } | IrPassKind::Map | IrPassKind::Geometry { .. } => {
                if pass.writes.is_none() {
                    return Err(shape("writes a resource"));
                }
            }
            IrPassKind::Shade { visibility } => {
                shades += 1;
                if pass.writes.is_some() {
                    return Err(shape("a Shade pass writes no resource"));
                }
                root(ir, *visibility, &format!("the visibility of {p:?}"), false)?;
                for d in &ir.debug {
                    let at = format!("debug output `{}`", d.name);
                    if d.expr.index() >= ir.arena.len() {
                        return Err(ValidationError::BadNode { at, node: d.expr });
                    }
                    let ty = ir.arena.ty(d.expr);
                    if !matches!(ty, Ty::F32 | Ty::Vec(_)) {
                        return Err(ValidationError::RootType { at, ty });
                    }
                    receiver_side(ir, d.expr, &at, false)?;
                }
                for n in ir.arena.postorder(&ir.shade_roots(*visibility)) {
                    if let Node::Sample { channel, resource, .. } = ir.arena.node(n) {
                        let why = if !pass.reads.contains(resource) {
                            format!("{resource:?} is not read by the Shade pass")
                        } else if ir.resources[*resource].slot_of(*channel).is_none() {
                            format!("{resource:?} does not carry {channel:?}")
                        } else {
                            continue;
                        };
                        return Err(ValidationError::BadLookup { node: n, why });
                    }
                }
            }
        }
    }
    if shades != 1 {
        return Err(ValidationError::ShadePasses(shades));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CompileOptions;
    use crate::span::Span;

    fn compiled_with_layout(name: &str) -> crate::Compiled {
        let path = format!("{}/../techniques/{name}.ron", env!("CARGO_MANIFEST_DIR"));
        let src = std::fs::read_to_string(path).unwrap();
        crate::compile_str(&src, &CompileOptions::default()).unwrap()
    }

    fn compiled(name: &str) -> Ir {
        compiled_with_layout(name).ir
    }

    #[test]
    fn a_dangling_param_and_a_slot_outside_its_texture_are_refused() {
        let mut ir = compiled("pcf");
        let ghost = ParamId::new(99);
        ir.arena.nodes.push((Node::Param(ghost), Ty::F32, Span::UNDEFINED));
        assert!(matches!(validate_ir(&ir), Err(ValidationError::BadParam { param, .. }) if param == ghost));
        assert!(validate_ir(&ir).unwrap_err().to_string().contains("param#99"));

        let c = compiled_with_layout("vsm");
        assert_eq!(validate(&Program::new(&c.ir, &c.layout)), Ok(()));
        let mut layout = c.layout.clone();
        let r = layout.resources.handles().find(|&r| !layout.resources[r].slots.is_empty()).unwrap();
        layout.resources[r].slots[0].layer = 99;
        assert!(matches!(
            validate(&Program::new(&c.ir, &layout)),
            Err(ValidationError::Slot { resource, .. }) if resource == r
        ));
    }

    #[test]
    fn bundled_techniques_validate() {
        // every technique in techniques/ (found, not listed: issue 52)
        let dir = format!("{}/../techniques", env!("CARGO_MANIFEST_DIR"));
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .filter_map(|e| e.ok()?.file_name().to_str()?.strip_suffix(".ron").map(str::to_string))
            .collect();
        names.sort();
        assert!(names.len() >= 18, "{names:?}");
        for t in &names {
            validate_ir(&compiled(t)).unwrap_or_else(|e| panic!("{t}: {e}"));
        }
    }

    #[test]
    fn an_operand_after_its_user_is_refused() {
        let mut ir = compiled("hard");
        let last = ExprId::new(ir.arena.len());
        let one = ir.arena.f32(1.0);
        ir.arena.nodes.push((Node::Binary(BinOp::Add, one, last), Ty::F32, Span::UNDEFINED));
        assert_eq!(
            validate_ir(&ir),
            Err(ValidationError::OperandOrder {
                node: ExprId::new(ir.arena.len() - 1),
                operand: last
            })
        );
        assert!(validate_ir(&ir).unwrap_err().to_string().contains("does not precede it"));
    }

    #[test]
    fn an_ill_typed_node_is_refused() {
        let mut ir = compiled("hard");
        let one = ir.arena.f32(1.0);
        let k = ir.arena.i32(2);
        ir.arena.nodes.push((Node::Binary(BinOp::Add, one, k), Ty::F32, Span::UNDEFINED));
        let bad = ExprId::new(ir.arena.len() - 1);
        assert!(matches!(validate_ir(&ir), Err(ValidationError::NodeType { node, .. }) if node == bad));
        // a swizzle of a scalar
        let mut ir = compiled("hard");
        let one = ir.arena.f32(1.0);
        ir.arena.nodes.push((Node::Swizzle(one, vec![0]), Ty::F32, Span::UNDEFINED));
        assert!(matches!(validate_ir(&ir), Err(ValidationError::NodeType { .. })));
    }

    #[test]
    fn dangling_references_are_refused() {
        let mut ir = compiled("hard");
        let ghost = ChannelId::new(99);
        ir.arena.nodes.push((Node::Channel(ghost, [0, 0]), Ty::F32, Span::UNDEFINED));
        assert!(matches!(validate_ir(&ir), Err(ValidationError::BadChannel { channel, .. }) if channel == ghost));

        let mut ir = compiled("hard");
        ir.passes[PassId::new(1)].reads.push(ResId::new(7));
        assert!(matches!(validate_ir(&ir), Err(ValidationError::BadResource { resource, .. }) if resource == ResId::new(7)));

        let mut ir = compiled("hard");
        ir.resources[ResId::new(0)].writer = PassId::new(1);
        assert!(matches!(validate_ir(&ir), Err(ValidationError::Writer { .. })));
    }

    #[test]
    fn a_lookup_on_the_map_side_and_a_missing_shade_pass_are_refused() {
        let mut ir = compiled("vsm");
        // the visibility (receiver side) becomes a channel's value (map side)
        let Some(IrPassKind::Shade { visibility }) = ir.shade_pass().map(|p| p.kind.clone()) else {
            unreachable!()
        };
        let c = ir.channels.handles().find(|c| ir.channels[*c].value.is_some()).unwrap();
        ir.channels[c].value = Some(visibility);
        assert!(matches!(validate_ir(&ir), Err(ValidationError::WrongSide { .. })));

        let mut ir = compiled("hard");
        let shade = ir.passes.handles().last().unwrap();
        ir.passes[shade].kind = IrPassKind::Map;
        assert!(matches!(
            validate_ir(&ir),
            Err(ValidationError::PassShape { .. } | ValidationError::ShadePasses(0))
        ));
    }

    #[test]
    fn a_read_before_its_write_is_refused() {
        let mut ir = compiled("vsm");
        // the first pass reads what the last non-Shade pass writes
        let last_written = ir.passes.iter().filter_map(|p| p.writes).next_back().unwrap();
        ir.passes[PassId::new(0)].reads.push(last_written);
        assert!(matches!(validate_ir(&ir), Err(ValidationError::ReadOrder { .. })));
    }
}
