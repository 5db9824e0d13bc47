//! The IR's text form: an expression written out ([`Arena::display`], for dumps and
//! explain) and the whole IR as `--dump-ir-after` prints it, with the analysis's side table
//! ([`WithAnalysis`]) or through the layout ([`Program`]).

use super::{Analysis, Arena, ChannelId, ExprId, Ir, IrPassKind, Node, Program, SlotInfo, SlotView, short};
use crate::builtins::Func;
use crate::front::expr::fmt_float;
use std::fmt::{self, Write as _};

impl Arena {
    /// Write `h` as an expression (for dumps and explain).
    pub fn display(&self, h: ExprId, ir: Option<&Ir>) -> String {
        let mut s = String::new();
        self.write(&mut s, h, ir, 0);
        s
    }

    fn write(&self, s: &mut String, h: ExprId, ir: Option<&Ir>, depth: usize) {
        if depth > 24 {
            let _ = write!(s, "%{}", h.index());
            return;
        }
        let chan = |c: ChannelId| ir.map(|ir| ir.channels[c].name.clone()).unwrap_or_else(|| format!("ch{c}"));
        match self.node(h) {
            Node::F32(b) => s.push_str(&fmt_float(f32::from_bits(*b) as f64)),
            Node::I32(v) => {
                let _ = write!(s, "{v}");
            }
            Node::U32(v) => {
                let _ = write!(s, "{v}u");
            }
            Node::Bool(v) => {
                let _ = write!(s, "{v}");
            }
            Node::Param(p) => match ir {
                Some(ir) => {
                    let _ = write!(s, "params.{}", ir.params[*p].name);
                }
                None => {
                    let _ = write!(s, "param{}", p.index());
                }
            },
            Node::Input(i, view) => {
                s.push_str(i.name());
                if let Some(k) = view {
                    let _ = write!(s, "@{k}");
                }
            }
            Node::Channel(c, [0, 0]) => s.push_str(&chan(*c)),
            Node::Channel(c, [dx, dy]) => {
                let _ = write!(s, "neighbour({}, {dx}, {dy})", chan(*c));
            }
            Node::Sample {
                channel, how, args, view, ..
            } => {
                let _ = write!(s, "{}({}", how.name(false), chan(*channel));
                for a in args {
                    s.push_str(", ");
                    self.write(s, *a, ir, depth + 1);
                }
                s.push(')');
                // inside `at_sample(k, ..)`: the lookup reads sample k's view
                if let Some(k) = view {
                    let _ = write!(s, "@{k}");
                }
            }
            Node::Unary(op, a) => {
                s.push_str(op.symbol());
                s.push('(');
                self.write(s, *a, ir, depth + 1);
                s.push(')');
            }
            Node::Binary(op, a, b) => {
                s.push('(');
                self.write(s, *a, ir, depth + 1);
                let _ = write!(s, " {} ", op.symbol());
                self.write(s, *b, ir, depth + 1);
                s.push(')');
            }
            Node::Call(Func::Branch, args) if args.len() == 3 => {
                s.push_str("if ");
                self.write(s, args[2], ir, depth + 1);
                s.push_str(" { ");
                self.write(s, args[1], ir, depth + 1);
                s.push_str(" } else { ");
                self.write(s, args[0], ir, depth + 1);
                s.push_str(" }");
            }
            Node::Call(f, args) => {
                let _ = write!(s, "{}(", f.name());
                for (i, a) in args.iter().enumerate() {
                    if i > 0 {
                        s.push_str(", ");
                    }
                    self.write(s, *a, ir, depth + 1);
                }
                s.push(')');
            }
            Node::Swizzle(a, c) => {
                self.write(s, *a, ir, depth + 1);
                s.push('.');
                for i in c {
                    s.push(['x', 'y', 'z', 'w'][*i as usize]);
                }
            }
        }
    }
}

impl<S: SlotView> fmt::Display for Program<'_, S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write_dump(f, None)
    }
}

/// The IR printed with the side table of `analyse` (`--dump-ir-after analyse`).
pub struct WithAnalysis<'a>(pub &'a Ir, pub &'a Analysis);

impl fmt::Display for WithAnalysis<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        Program::lowered(self.0).write_dump(f, Some(self.1))
    }
}

impl fmt::Display for Ir {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        Program::lowered(self).write_dump(f, None)
    }
}

impl<S: SlotView> Program<'_, S> {
    /// The text form of `--dump-ir-after`: slots show the ranges and encodings of
    /// `analysis` when given, else those of the layout (after `pack`).
    fn write_dump(&self, f: &mut fmt::Formatter<'_>, analysis: Option<&Analysis>) -> fmt::Result {
        writeln!(f, "technique {}", self.technique)?;
        for p in &self.params {
            let kind = if p.uniform { "uniform" } else { "const" };
            write!(f, "  param {} : {} = {} ({kind}", p.name, p.ty.name(), p.value)?;
            if let Some((lo, hi)) = p.range {
                write!(f, ", range [{}, {}]", short(lo), short(hi))?;
            }
            writeln!(f, ")")?;
        }
        for (i, c) in self.channels.iter().enumerate() {
            write!(f, "  channel #{i} {} : {}", c.name, c.precision.name())?;
            if let Some(v) = c.value {
                write!(f, " = {}", self.arena.display(v, Some(self.ir)))?;
            }
            writeln!(f)?;
        }
        for e in &self.expansions {
            writeln!(f, "  expansion {} = {}", e.name, self.arena.display(e.constant, Some(self.ir)))?;
            for (coeff, ch) in &e.terms {
                writeln!(
                    f,
                    "      + {} * {}",
                    self.arena.display(*coeff, Some(self.ir)),
                    self.channels[*ch].name
                )?;
            }
        }
        for (rh, r) in self.resources.with_handles() {
            let writer = self.passes.get(r.writer).map(|p| p.name.as_str()).unwrap_or("?");
            write!(f, "  resource {} (written by pass `{writer}`", r.name)?;
            if r.mips {
                write!(f, "; mip chain")?;
            }
            if r.sat {
                write!(f, "; summed-area table")?;
            }
            if !r.live {
                write!(f, "; removed")?;
            }
            writeln!(f, ")")?;
            for s in &r.slots {
                write!(f, "      {} : {}", self.channels[s.channel()].name, s.precision().name())?;
                let info = match (analysis.and_then(|a| a.get(rh, s.channel())), s.placed()) {
                    (Some(info), _) => Some(info),
                    (None, Some(p)) => Some(SlotInfo {
                        range: p.range,
                        encode: p.encode,
                    }),
                    (None, None) => None,
                };
                if let Some(SlotInfo { range, encode }) = info {
                    write!(f, " range {range}")?;
                    if !encode.is_identity() {
                        write!(f, " stored as (v - ({})) * {}", short(encode.bias), short(encode.scale))?;
                    }
                }
                if let Some(p) = s.placed() {
                    write!(
                        f,
                        " at {}[{}].{}",
                        r.textures[p.texture].name,
                        p.layer,
                        ['r', 'g', 'b', 'a'][p.component as usize]
                    )?;
                }
                writeln!(f)?;
            }
            for t in &r.textures {
                writeln!(
                    f,
                    "      texture {} : {} x{} components x{} layers",
                    t.name,
                    t.precision.name(),
                    t.components,
                    t.layers
                )?;
            }
        }
        for p in self.passes.iter() {
            let reads: Vec<&str> = p.reads.iter().map(|r| self.resources[*r].name.as_str()).collect();
            write!(f, "  pass {} : {} reads [{}]", p.name, p.kind_name(), reads.join(", "))?;
            if let Some(w) = p.writes {
                write!(f, " writes {}", self.resources[w].name)?;
            }
            match &p.kind {
                IrPassKind::Filter { kernel } => write!(f, " kernel {kernel:?}")?,
                IrPassKind::Mipmap { reduce } => write!(f, " reduce {reduce:?}")?,
                IrPassKind::Shade { visibility } => {
                    write!(f, "\n      visibility = {}", self.arena.display(*visibility, Some(self.ir)))?;
                    for d in &self.ir.debug {
                        write!(f, "\n      debug {} = {}", d.name, self.arena.display(d.expr, Some(self.ir)))?;
                    }
                }
                IrPassKind::Geometry { keep: Some(k), .. } => write!(f, "\n      keep = {}", self.arena.display(*k, Some(self.ir)))?,
                IrPassKind::Depth { .. } | IrPassKind::Map | IrPassKind::SummedArea { .. } | IrPassKind::Geometry { .. } => {}
            }
            writeln!(f)?;
        }
        for r in self.removed.iter() {
            writeln!(f, "  removed: {r}")?;
        }
        Ok(())
    }
}
