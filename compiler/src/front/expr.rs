//! The expression language inside technique strings (docs/language.md): small, pure,
//! typed (f32, i32, bool, vec2..vec4), with `let` bindings, calls of WGSL math built-ins and
//! of sampling functions, and `sum(k in a..=b, expr)` for series. No loops, no recursion.
//!
//! Spans are mapped from positions inside the string to positions in the file as the
//! expression is read, so every later diagnostic points into the technique file.

use crate::diag::{Diagnostic, Phase};
use crate::front::ron::StrLit;
use crate::span::Span;
use logos::Logos;
use std::fmt;

const MAX_DEPTH: usize = 64;
/// The deepest expression tree accepted, counting every operator of a chain such as
/// `a + b + c` as one level (the tree as built, left-associative): later phases recurse over
/// the tree, so this bounds their stack.
pub const MAX_TREE_DEPTH: u32 = 256;
/// The most nodes one expression string may have.
pub const MAX_NODES: u32 = 65_536;
/// `compare_at(ch, r, dx, dy)`: a bilinear-weighted depth test at a texel offset, written
/// out by the parser ([`Parser::compare_at`]); the name its `r` is bound to.
pub const COMPARE_AT: &str = "compare_at";
pub const COMPARE_AT_REF: &str = "compare_at_ref";

#[derive(Logos, Clone, Copy, Debug, PartialEq)]
#[logos(skip r"[ \t\r\n\f]+")]
#[logos(skip(r"//[^\n]*", allow_greedy = true))]
enum Tok {
    #[regex(r"[0-9]+\.[0-9]+([eE][+-]?[0-9]+)?|[0-9]+[eE][+-]?[0-9]+")]
    Float,
    #[regex(r"[0-9]+")]
    Int,
    /// `123u`, `0x9e3779b9u`: a u32 literal.
    #[regex(r"[0-9]+u|0[xX][0-9a-fA-F]+u")]
    Uint,
    /// `0xff`: an abstract integer written in hexadecimal.
    #[regex(r"0[xX][0-9a-fA-F]+")]
    Hex,
    #[regex(r"[A-Za-z_][A-Za-z0-9_]*")]
    Ident,
    #[token("(")]
    LParen,
    #[token(")")]
    RParen,
    #[token(",")]
    Comma,
    #[token(";")]
    Semi,
    #[token(".")]
    Dot,
    #[token("..=")]
    DotDotEq,
    #[token("=")]
    Assign,
    #[token("+")]
    Plus,
    #[token("-")]
    Minus,
    #[token("*")]
    Star,
    #[token("/")]
    Slash,
    #[token("%")]
    Percent,
    #[token("<")]
    Lt,
    #[token("<=")]
    Le,
    #[token(">")]
    Gt,
    #[token(">=")]
    Ge,
    #[token("==")]
    EqEq,
    #[token("!=")]
    Ne,
    #[token("&&")]
    AndAnd,
    #[token("||")]
    OrOr,
    #[token("!")]
    Bang,
    #[token("&")]
    Amp,
    #[token("|")]
    Pipe,
    #[token("^")]
    Caret,
    #[token("<<")]
    Shl,
    #[token(">>")]
    Shr,
    #[token("~")]
    Tilde,
    #[token("[")]
    LBracket,
    #[token("]")]
    RBracket,
    #[token("{")]
    LBrace,
    #[token("}")]
    RBrace,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum UnOp {
    Neg,
    Not,
    /// `~`: the bitwise complement of an integer.
    BitNot,
}

impl UnOp {
    pub fn symbol(self) -> &'static str {
        match self {
            UnOp::Neg => "-",
            UnOp::Not => "!",
            UnOp::BitNot => "~",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Rem,
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
    And,
    Or,
    /// `&`, `|`, `^`: bitwise, on integers of one type.
    BitAnd,
    BitOr,
    BitXor,
    /// `<<`, `>>`: an integer shifted by a u32 count below 32 (arithmetic `>>` on i32).
    Shl,
    Shr,
}

impl BinOp {
    pub fn symbol(self) -> &'static str {
        match self {
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Rem => "%",
            BinOp::Lt => "<",
            BinOp::Le => "<=",
            BinOp::Gt => ">",
            BinOp::Ge => ">=",
            BinOp::Eq => "==",
            BinOp::Ne => "!=",
            BinOp::And => "&&",
            BinOp::Or => "||",
            BinOp::BitAnd => "&",
            BinOp::BitOr => "|",
            BinOp::BitXor => "^",
            BinOp::Shl => "<<",
            BinOp::Shr => ">>",
        }
    }

    /// `&`, `|`, `^`, `<<`, `>>`: defined on integers only.
    pub fn is_bitwise(self) -> bool {
        matches!(self, BinOp::BitAnd | BinOp::BitOr | BinOp::BitXor | BinOp::Shl | BinOp::Shr)
    }

    pub fn is_shift(self) -> bool {
        matches!(self, BinOp::Shl | BinOp::Shr)
    }

    pub fn is_comparison(self) -> bool {
        matches!(self, BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne)
    }

    pub fn is_logic(self) -> bool {
        matches!(self, BinOp::And | BinOp::Or)
    }

    fn precedence(self) -> u8 {
        match self {
            BinOp::Or => 1,
            BinOp::And => 2,
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne => 3,
            // as in Rust: bitwise operators bind tighter than comparisons
            BinOp::BitOr => 4,
            BinOp::BitXor => 5,
            BinOp::BitAnd => 6,
            BinOp::Shl | BinOp::Shr => 7,
            BinOp::Add | BinOp::Sub => 8,
            BinOp::Mul | BinOp::Div | BinOp::Rem => 9,
        }
    }
}

/// A literal as written: integer literals are abstract (they become f32, i32 or u32 by
/// context, as in WGSL), float literals are f32, `u`-suffixed literals u32.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Literal {
    Int(i64),
    Uint(u32),
    Float(f64),
    Bool(bool),
}

#[derive(Clone, Debug, PartialEq)]
pub enum ExprKind {
    Lit(Literal),
    Name(String),
    Unary(UnOp, Box<Expr>),
    Binary(BinOp, Box<Expr>, Box<Expr>),
    /// `name(args)`; the span of the name is `name_span`.
    Call {
        name: String,
        name_span: Span,
        args: Vec<Expr>,
    },
    /// `base.x`, `base.xy`, ...
    Member(Box<Expr>, String),
    /// `name[index]`: an element of a constant array of the technique, `index` an integer
    /// known at compile time.
    Index {
        name: String,
        name_span: Span,
        index: Box<Expr>,
    },
    /// `let name = value; body`
    Let {
        name: String,
        name_span: Span,
        value: Box<Expr>,
        body: Box<Expr>,
    },
    /// `if cond { then } else { els }`: a real branch, only the taken arm evaluated
    /// (`else if` is an `If` as the `else` arm).
    If {
        cond: Box<Expr>,
        then: Box<Expr>,
        els: Box<Expr>,
    },
    /// `sum(var in from..=to, body)`
    Sum {
        var: String,
        var_span: Span,
        from: Box<Expr>,
        to: Box<Expr>,
        body: Box<Expr>,
    },
}

#[derive(Clone, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
    /// Height of the tree below and including this node (a leaf is 1).
    height: u32,
    /// Number of nodes of the tree below and including this node.
    nodes: u32,
}

impl Expr {
    pub fn new(kind: ExprKind, span: Span) -> Expr {
        let (mut h, mut n) = (0u32, 0u32);
        let mut add = |e: &Expr| {
            h = h.max(e.height);
            n = n.saturating_add(e.nodes);
        };
        match &kind {
            ExprKind::Lit(_) | ExprKind::Name(_) => {}
            ExprKind::Unary(_, a) | ExprKind::Member(a, _) | ExprKind::Index { index: a, .. } => add(a),
            ExprKind::Binary(_, a, b) => {
                add(a);
                add(b);
            }
            ExprKind::Call { args, .. } => args.iter().for_each(&mut add),
            ExprKind::Let { value, body, .. } => {
                add(value);
                add(body);
            }
            ExprKind::Sum { from, to, body, .. } => {
                add(from);
                add(to);
                add(body);
            }
            ExprKind::If { cond, then, els } => {
                add(cond);
                add(then);
                add(els);
            }
        }
        Expr {
            kind,
            span,
            height: h.saturating_add(1),
            nodes: n.saturating_add(1),
        }
    }

    /// Height of the expression tree (a leaf is 1), chains included.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Visit this expression and all sub-expressions, parents first.
    pub fn walk<'a>(&'a self, f: &mut dyn FnMut(&'a Expr)) {
        f(self);
        match &self.kind {
            ExprKind::Lit(_) | ExprKind::Name(_) => {}
            ExprKind::Unary(_, a) | ExprKind::Member(a, _) | ExprKind::Index { index: a, .. } => a.walk(f),
            ExprKind::Binary(_, a, b) => {
                a.walk(f);
                b.walk(f);
            }
            ExprKind::Call { args, .. } => args.iter().for_each(|a| a.walk(f)),
            ExprKind::Let { value, body, .. } => {
                value.walk(f);
                body.walk(f);
            }
            ExprKind::Sum { from, to, body, .. } => {
                from.walk(f);
                to.walk(f);
                body.walk(f);
            }
            ExprKind::If { cond, then, els } => {
                cond.walk(f);
                then.walk(f);
                els.walk(f);
            }
        }
    }

    /// Number of nodes, used to bound unrolled series.
    #[cfg(test)]
    pub fn size(&self) -> usize {
        self.nodes as usize
    }
}

/// The debug form (used by `--dump-ir-after parse`) prints the expression as source text
/// with its span: the derived, indented form costs time in the product of size and depth.
impl fmt::Debug for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Expr(`{self}` @ {:?})", self.span)
    }
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.kind {
            ExprKind::Lit(Literal::Int(v)) => write!(f, "{v}"),
            ExprKind::Lit(Literal::Uint(v)) => write!(f, "{v}u"),
            ExprKind::Lit(Literal::Float(v)) => write!(f, "{}", fmt_float(*v)),
            ExprKind::Lit(Literal::Bool(v)) => write!(f, "{v}"),
            ExprKind::Name(n) => write!(f, "{n}"),
            ExprKind::Unary(UnOp::Neg, a) => write!(f, "-({a})"),
            ExprKind::Unary(UnOp::Not, a) => write!(f, "!({a})"),
            ExprKind::Unary(UnOp::BitNot, a) => write!(f, "~({a})"),
            ExprKind::Binary(op, a, b) => write!(f, "({a} {} {b})", op.symbol()),
            ExprKind::Call { name, args, .. } => {
                write!(f, "{name}(")?;
                for (i, a) in args.iter().enumerate() {
                    if i > 0 {
                        write!(f, ", ")?;
                    }
                    write!(f, "{a}")?;
                }
                write!(f, ")")
            }
            ExprKind::Member(a, m) => write!(f, "{a}.{m}"),
            ExprKind::Index { name, index, .. } => write!(f, "{name}[{index}]"),
            ExprKind::Let { name, value, body, .. } => write!(f, "let {name} = {value}; {body}"),
            ExprKind::Sum { var, from, to, body, .. } => write!(f, "sum({var} in {from}..={to}, {body})"),
            ExprKind::If { cond, then, els } => write!(f, "if {cond} {{ {then} }} else {{ {els} }}"),
        }
    }
}

/// Print a float so that it reads back as a float (always with a `.` or exponent).
pub fn fmt_float(v: f64) -> String {
    if v.is_finite() && v == v.trunc() && v.abs() < 1e15 {
        format!("{v:.1}")
    } else {
        format!("{v:?}")
    }
}

struct Parser<'a> {
    text: &'a str,
    toks: Vec<(Tok, Span)>,
    pos: usize,
    lit: &'a StrLit,
    depth: usize,
}

/// Parse an expression string read from the technique file.
pub fn parse(lit: &StrLit) -> Result<Expr, Diagnostic> {
    let text = lit.text.as_str();
    let mut toks = Vec::new();
    let mut lex = Tok::lexer(text);
    while let Some(t) = lex.next() {
        let span = Span::new(lex.span().start, lex.span().end);
        match t {
            Ok(t) => toks.push((t, span)),
            Err(()) => {
                return Err(Diagnostic::error(
                    Phase::Syntax,
                    format!("unexpected character `{}` in expression", &text[lex.span()].escape_debug()),
                )
                .at(lit.map_span(span), "not part of the expression language")
                .help("expressions use numbers, names, `+ - * / %`, comparisons, `&& || !`, bit operations `& | ^ ~ << >>`, calls `f(x)`, `let x = e;`, `if c { a } else { b }` and `sum(k in a..=b, e)`"));
            }
        }
    }
    let mut p = Parser {
        text,
        toks,
        pos: 0,
        lit,
        depth: 0,
    };
    if p.toks.is_empty() {
        return Err(
            Diagnostic::error(Phase::Syntax, "empty expression").at(lit.map_span(Span::new(0, text.len())), "an expression is needed here")
        );
    }
    let e = p.block()?;
    if let Some(&(_, span)) = p.toks.get(p.pos) {
        return Err(Diagnostic::error(
            Phase::Syntax,
            format!("unexpected `{}` after the end of the expression", &text[span.range()]),
        )
        .at(lit.map_span(span), "expected an operator or the end of the expression"));
    }
    Ok(e)
}

impl Parser<'_> {
    /// Build a node, refusing a tree deeper than [`MAX_TREE_DEPTH`] or larger than
    /// [`MAX_NODES`] as soon as it is built, so that no later phase recurses deeper.
    /// `compare_at(ch, r, dx, dy)`, written out: the bilinear blend, with the receiver's
    /// weights `tf`, of the depth tests `r <= ch` at the four texels from `(dx, dy)` to
    /// `(dx + 1, dy + 1)` past the receiver's base texel (what a comparison sampler
    /// computes at that offset). `r` is bound once, to `compare_at_ref` (which the offsets
    /// must not name).
    fn compare_at(&self, args: Vec<Expr>, name_span: Span, span: Span) -> Result<Expr, Diagnostic> {
        let [ch, r, dx, dy]: [Expr; 4] = args
            .try_into()
            .map_err(|_| Diagnostic::error(Phase::Syntax, "compare_at takes 4 arguments").at(span, "here"))?;
        let node = |kind: ExprKind| Expr::new(kind, span);
        let name = |n: &str| node(ExprKind::Name(n.to_string()));
        let int = |v: i64| node(ExprKind::Lit(Literal::Int(v)));
        let float = |v: f64| node(ExprKind::Lit(Literal::Float(v)));
        let call = |f: &str, args: Vec<Expr>| {
            node(ExprKind::Call {
                name: f.to_string(),
                name_span,
                args,
            })
        };
        let plus = |a: &Expr, k: i64| node(ExprKind::Binary(BinOp::Add, Box::new(a.clone()), Box::new(int(k))));
        let test = |i: i64, j: i64| {
            let texel = call("fetch", vec![ch.clone(), plus(&dx, i), plus(&dy, j)]);
            let lit = node(ExprKind::Binary(BinOp::Le, Box::new(name(COMPARE_AT_REF)), Box::new(texel)));
            call("select", vec![float(0.0), float(1.0), lit])
        };
        let tf = |c: &str| node(ExprKind::Member(Box::new(name("tf")), c.to_string()));
        let row = |j: i64| call("mix", vec![test(0, j), test(1, j), tf("x")]);
        let body = call("mix", vec![row(0), row(1), tf("y")]);
        self.node(
            ExprKind::Let {
                name: COMPARE_AT_REF.to_string(),
                name_span,
                value: Box::new(r),
                body: Box::new(body),
            },
            span,
        )
    }

    fn node(&self, kind: ExprKind, span: Span) -> Result<Expr, Diagnostic> {
        let e = Expr::new(kind, span);
        if e.height > MAX_TREE_DEPTH {
            return Err(Diagnostic::error(
                Phase::Syntax,
                format!("expression is deeper than {MAX_TREE_DEPTH} levels (each operator of a chain such as `a + b + c` is a level)"),
            )
            .at(span, "too deep")
            .help("split it with `let` bindings, or write a long series as `sum(k in a..=b, e)`"));
        }
        if e.nodes > MAX_NODES {
            return Err(
                Diagnostic::error(Phase::Syntax, format!("expression has more than {MAX_NODES} terms and operators"))
                    .at(span, "too large")
                    .help("split it into parameters or passes"),
            );
        }
        Ok(e)
    }

    fn map(&self, s: Span) -> Span {
        self.lit.map_span(s)
    }

    fn peek(&self) -> Option<Tok> {
        self.toks.get(self.pos).map(|t| t.0)
    }

    fn peek_is_ident(&self, word: &str) -> bool {
        matches!(self.toks.get(self.pos), Some((Tok::Ident, s)) if &self.text[s.range()] == word)
    }

    fn end_span(&self) -> Span {
        Span::new(self.text.len(), self.text.len())
    }

    fn bump(&mut self) -> Option<(Tok, Span)> {
        let t = self.toks.get(self.pos).copied();
        self.pos += 1;
        t
    }

    fn err_here(&self, what: &str) -> Diagnostic {
        match self.toks.get(self.pos) {
            Some(&(_, span)) => Diagnostic::error(Phase::Syntax, format!("expected {what}, found `{}`", &self.text[span.range()]))
                .at(self.map(span), format!("expected {what}")),
            None => Diagnostic::error(Phase::Syntax, format!("expected {what}, found the end of the expression"))
                .at(self.map(self.end_span()), format!("expected {what}")),
        }
    }

    fn expect(&mut self, t: Tok, what: &str) -> Result<Span, Diagnostic> {
        if self.peek() == Some(t) {
            Ok(self.bump().map(|x| x.1).unwrap_or_default())
        } else {
            Err(self.err_here(what))
        }
    }

    fn enter(&mut self) -> Result<(), Diagnostic> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            let span = self.toks.get(self.pos).map(|t| t.1).unwrap_or(self.end_span());
            return Err(
                Diagnostic::error(Phase::Syntax, format!("expression nests deeper than {MAX_DEPTH} levels"))
                    .at(self.map(span), "too deep")
                    .help("split it with `let` bindings"),
            );
        }
        Ok(())
    }

    /// `let x = e; ... result`
    fn block(&mut self) -> Result<Expr, Diagnostic> {
        self.enter()?;
        let r = if self.peek_is_ident("let") {
            let (_, let_span) = self.bump().unwrap_or((Tok::Ident, Span::UNDEFINED));
            let name_span = self.expect(Tok::Ident, "a name after `let`")?;
            let name = self.text[name_span.range()].to_string();
            self.expect(Tok::Assign, "`=`")?;
            let value = self.expr(0)?;
            self.expect(Tok::Semi, "`;` after a `let` binding")?;
            let body = self.block()?;
            let span = self.map(let_span).join(body.span);
            self.node(
                ExprKind::Let {
                    name,
                    name_span: self.map(name_span),
                    value: Box::new(value),
                    body: Box::new(body),
                },
                span,
            )
        } else {
            self.expr(0)
        };
        self.depth -= 1;
        r
    }

    fn binop(&self) -> Option<BinOp> {
        Some(match self.peek()? {
            Tok::Plus => BinOp::Add,
            Tok::Minus => BinOp::Sub,
            Tok::Star => BinOp::Mul,
            Tok::Slash => BinOp::Div,
            Tok::Percent => BinOp::Rem,
            Tok::Lt => BinOp::Lt,
            Tok::Le => BinOp::Le,
            Tok::Gt => BinOp::Gt,
            Tok::Ge => BinOp::Ge,
            Tok::EqEq => BinOp::Eq,
            Tok::Ne => BinOp::Ne,
            Tok::AndAnd => BinOp::And,
            Tok::OrOr => BinOp::Or,
            Tok::Amp => BinOp::BitAnd,
            Tok::Pipe => BinOp::BitOr,
            Tok::Caret => BinOp::BitXor,
            Tok::Shl => BinOp::Shl,
            Tok::Shr => BinOp::Shr,
            Tok::Float
            | Tok::Int
            | Tok::Uint
            | Tok::Hex
            | Tok::Tilde
            | Tok::Ident
            | Tok::LParen
            | Tok::RParen
            | Tok::Comma
            | Tok::Semi
            | Tok::Dot
            | Tok::DotDotEq
            | Tok::Assign
            | Tok::LBracket
            | Tok::RBracket
            | Tok::LBrace
            | Tok::RBrace
            | Tok::Bang => return None,
        })
    }

    /// Precedence climbing; comparisons do not chain.
    fn expr(&mut self, min_prec: u8) -> Result<Expr, Diagnostic> {
        self.enter()?;
        let mut lhs = self.unary()?;
        while let Some(op) = self.binop() {
            let prec = op.precedence();
            if prec < min_prec {
                break;
            }
            let (_, op_span) = self.bump().unwrap_or((Tok::Plus, Span::UNDEFINED));
            let rhs = self.expr(prec + 1)?;
            if op.is_comparison()
                && let ExprKind::Binary(inner, ..) = &lhs.kind
                && inner.is_comparison()
            {
                return Err(Diagnostic::error(Phase::Syntax, "comparisons cannot be chained")
                    .at(self.map(op_span), "second comparison")
                    .help("combine them with `&&`"));
            }
            let span = lhs.span.join(rhs.span);
            lhs = self.node(ExprKind::Binary(op, Box::new(lhs), Box::new(rhs)), span)?;
        }
        self.depth -= 1;
        Ok(lhs)
    }

    fn unary(&mut self) -> Result<Expr, Diagnostic> {
        self.enter()?;
        let r = match self.peek() {
            Some(Tok::Minus | Tok::Bang | Tok::Tilde) => {
                let (t, span) = self.bump().unwrap_or((Tok::Minus, Span::UNDEFINED));
                let op = if t == Tok::Minus {
                    UnOp::Neg
                } else if t == Tok::Bang {
                    UnOp::Not
                } else {
                    UnOp::BitNot
                };
                let a = self.unary()?;
                let span = self.map(span).join(a.span);
                self.node(ExprKind::Unary(op, Box::new(a)), span)
            }
            _ => self.postfix(),
        };
        self.depth -= 1;
        r
    }

    fn postfix(&mut self) -> Result<Expr, Diagnostic> {
        let mut e = self.primary()?;
        while self.peek() == Some(Tok::Dot) {
            self.bump();
            let s = self.expect(Tok::Ident, "a component name such as `x` after `.`")?;
            let span = e.span.join(self.map(s));
            e = self.node(ExprKind::Member(Box::new(e), self.text[s.range()].to_string()), span)?;
        }
        Ok(e)
    }

    fn primary(&mut self) -> Result<Expr, Diagnostic> {
        let Some((tok, span)) = self.bump() else {
            self.pos -= 1;
            return Err(self.err_here("a value"));
        };
        let text = &self.text[span.range()];
        let fspan = self.map(span);
        match tok {
            Tok::Int => match text.parse::<i64>() {
                Ok(v) if v <= i32::MAX as i64 + 1 => self.node(ExprKind::Lit(Literal::Int(v)), fspan),
                _ => Err(
                    Diagnostic::error(Phase::Syntax, format!("integer literal `{text}` does not fit in i32"))
                        .at(fspan, "too large")
                        .help(format!(
                            "write a float literal (`{text}.0`), or a u32 below 2^32 with the suffix `u` (`{text}u`)"
                        )),
                ),
            },
            Tok::Hex => match i64::from_str_radix(&text[2..], 16) {
                Ok(v) if v <= i32::MAX as i64 => self.node(ExprKind::Lit(Literal::Int(v)), fspan),
                _ => Err(
                    Diagnostic::error(Phase::Syntax, format!("integer literal `{text}` does not fit in i32"))
                        .at(fspan, "too large")
                        .help(format!("a u32 takes the suffix `u`: `{text}u`")),
                ),
            },
            Tok::Uint => {
                let digits = &text[..text.len() - 1];
                let v = match digits.strip_prefix("0x").or_else(|| digits.strip_prefix("0X")) {
                    Some(hex) => u32::from_str_radix(hex, 16),
                    None => digits.parse::<u32>(),
                };
                match v {
                    Ok(v) => self.node(ExprKind::Lit(Literal::Uint(v)), fspan),
                    Err(_) => Err(
                        Diagnostic::error(Phase::Syntax, format!("integer literal `{text}` does not fit in u32"))
                            .at(fspan, "too large")
                            .note(format!("a u32 lies from 0 to {}", u32::MAX)),
                    ),
                }
            }
            Tok::Float => match text.parse::<f64>() {
                Ok(v) if v.is_finite() && v.abs() <= f32::MAX as f64 => self.node(ExprKind::Lit(Literal::Float(v)), fspan),
                _ => Err(Diagnostic::error(Phase::Syntax, format!("float literal `{text}` does not fit in f32")).at(fspan, "too large")),
            },
            Tok::Ident if text == "true" || text == "false" => self.node(ExprKind::Lit(Literal::Bool(text == "true")), fspan),
            Tok::Ident if text == "let" => Err(Diagnostic::error(
                Phase::Syntax,
                "`let` is only allowed at the start of an expression or inside parentheses",
            )
            .at(fspan, "unexpected `let`")),
            Tok::Ident if text == "sum" && self.peek() == Some(Tok::LParen) => self.sum(fspan),
            Tok::Ident if text == "if" => self.branch(fspan),
            Tok::Ident if text == "else" => Err(Diagnostic::error(Phase::Syntax, "`else` without an `if`")
                .at(fspan, "unexpected `else`")
                .help("write `if cond { a } else { b }`")),
            Tok::Ident => {
                if self.peek() == Some(Tok::LParen) {
                    self.bump();
                    let mut args = Vec::new();
                    let end = loop {
                        if self.peek() == Some(Tok::RParen) {
                            break self.bump().map(|t| t.1).unwrap_or_default();
                        }
                        args.push(self.block()?);
                        match self.peek() {
                            Some(Tok::Comma) => {
                                self.bump();
                            }
                            Some(Tok::RParen) => {}
                            _ => return Err(self.err_here("`,` or `)`")),
                        }
                    };
                    let span = fspan.join(self.map(end));
                    if text == COMPARE_AT && args.len() == 4 {
                        return self.compare_at(args, fspan, span);
                    }
                    self.node(
                        ExprKind::Call {
                            name: text.to_string(),
                            name_span: fspan,
                            args,
                        },
                        span,
                    )
                } else if self.peek() == Some(Tok::LBracket) {
                    self.bump();
                    let index = self.block()?;
                    let end = self.expect(Tok::RBracket, "`]`")?;
                    let span = fspan.join(self.map(end));
                    self.node(
                        ExprKind::Index {
                            name: text.to_string(),
                            name_span: fspan,
                            index: Box::new(index),
                        },
                        span,
                    )
                } else {
                    self.node(ExprKind::Name(text.to_string()), fspan)
                }
            }
            Tok::LParen => {
                let mut e = self.block()?;
                let end = self.expect(Tok::RParen, "`)`")?;
                e.span = fspan.join(self.map(end));
                Ok(e)
            }
            Tok::RParen
            | Tok::LBracket
            | Tok::RBracket
            | Tok::LBrace
            | Tok::RBrace
            | Tok::Comma
            | Tok::Semi
            | Tok::Dot
            | Tok::DotDotEq
            | Tok::Assign
            | Tok::Plus
            | Tok::Minus
            | Tok::Star
            | Tok::Slash
            | Tok::Percent
            | Tok::Lt
            | Tok::Le
            | Tok::Gt
            | Tok::Ge
            | Tok::EqEq
            | Tok::Ne
            | Tok::AndAnd
            | Tok::OrOr
            | Tok::Amp
            | Tok::Pipe
            | Tok::Caret
            | Tok::Shl
            | Tok::Shr
            | Tok::Tilde
            | Tok::Bang => {
                self.pos -= 1;
                Err(self.err_here("a value"))
            }
        }
    }

    /// `if cond { a } else { b }` after the `if` (at `start`); `else if` chains. Both arms
    /// are required: the expression has a value whichever is taken.
    fn branch(&mut self, start: Span) -> Result<Expr, Diagnostic> {
        self.enter()?;
        let cond = self.expr(0)?;
        let arm = |p: &mut Self, what: &str| -> Result<(Expr, Span), Diagnostic> {
            p.expect(Tok::LBrace, what)?;
            let e = p.block()?;
            let end = p.expect(Tok::RBrace, "`}` at the end of the arm")?;
            Ok((e, end))
        };
        let (then, then_end) = arm(self, "`{` before the arm taken when the condition holds")?;
        if !self.peek_is_ident("else") {
            return Err(Diagnostic::error(Phase::Syntax, "an `if` needs an `else` arm")
                .at(self.map(then_end), "the `if` ends here without an `else`")
                .help("an expression has a value whichever arm is taken: write `if c { a } else { b }`"));
        }
        self.bump();
        let (els, end) = if self.peek_is_ident("if") {
            let (_, s) = self.bump().unwrap_or((Tok::Ident, Span::UNDEFINED));
            let e = self.branch(self.map(s))?;
            let end = e.span;
            (e, end)
        } else {
            let (e, end) = arm(self, "`{` or `if` after `else`")?;
            (e, self.map(end))
        };
        self.depth -= 1;
        self.node(
            ExprKind::If {
                cond: Box::new(cond),
                then: Box::new(then),
                els: Box::new(els),
            },
            start.join(end),
        )
    }

    /// `sum(k in a..=b, body)` after the name `sum`.
    fn sum(&mut self, start: Span) -> Result<Expr, Diagnostic> {
        self.expect(Tok::LParen, "`(`")?;
        let var_span = self.expect(Tok::Ident, "the index name of `sum(k in a..=b, expr)`")?;
        let var = self.text[var_span.range()].to_string();
        if !self.peek_is_ident("in") {
            return Err(self.err_here("`in`, as in `sum(k in 1..=M, expr)`"));
        }
        self.bump();
        let from = self.expr(0)?;
        self.expect(Tok::DotDotEq, "`..=` (series ranges are inclusive)")?;
        let to = self.expr(0)?;
        self.expect(Tok::Comma, "`,` before the series term")?;
        let body = self.block()?;
        let end = self.expect(Tok::RParen, "`)`")?;
        self.node(
            ExprKind::Sum {
                var,
                var_span: self.map(var_span),
                from: Box::new(from),
                to: Box::new(to),
                body: Box::new(body),
            },
            start.join(self.map(end)),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lit(s: &str) -> StrLit {
        StrLit {
            text: s.to_string(),
            offsets: (0..=s.len() as u32).collect(),
        }
    }

    #[test]
    fn precedence_and_printing() {
        let e = parse(&lit("1 + 2 * x - f(a, b).x")).unwrap();
        assert_eq!(e.to_string(), "((1 + (2 * x)) - f(a, b).x)");
        let e = parse(&lit("let a = 2.5; a < 3 && !b")).unwrap();
        assert_eq!(e.to_string(), "let a = 2.5; ((a < 3) && !(b))");
        let e = parse(&lit("sum(k in 1..=M, 2 * k)")).unwrap();
        assert_eq!(e.to_string(), "sum(k in 1..=M, (2 * k))");
        let e = parse(&lit("if a < 1 { let b = 2; b } else if c { 3 } else { 4 } + 1")).unwrap();
        assert_eq!(e.to_string(), "(if (a < 1) { let b = 2; b } else { if c { 3 } else { 4 } } + 1)");
    }

    #[test]
    fn spans_inside_strings() {
        let e = parse(&lit("a + foo(b)")).unwrap();
        let ExprKind::Binary(_, _, rhs) = &e.kind else { panic!() };
        assert_eq!(rhs.span, Span::new(4, 10));
    }

    #[test]
    fn errors() {
        assert!(parse(&lit("a < b < c")).is_err());
        assert!(parse(&lit("1 +")).is_err());
        assert!(parse(&lit("")).is_err());
        assert!(parse(&lit("a $ b")).is_err());
        assert!(parse(&lit(&"(".repeat(500))).is_err());
        assert!(parse(&lit(&"-".repeat(500))).is_err());
        // an `if` needs both arms, in braces
        assert!(parse(&lit("if a { 1 }")).is_err());
        assert!(parse(&lit("if a 1 else 2")).is_err());
        assert!(parse(&lit("else { 1 }")).is_err());
    }
}
