//! A spanned reading of RON: the text becomes a [`Node`] tree in which every value knows
//! its byte span, and every string knows where each of its bytes came from, so that
//! errors inside expression strings point at the right column.
//!
//! The `ron` crate checks syntax but keeps no span per value (docs/architecture.md section 1), so the
//! technique front end reads RON itself: tokens come from a `logos` lexer, the grammar
//! (<https://github.com/ron-rs/ron/blob/master/docs/grammar.md>, the subset techniques
//! use: structs, tuples, lists, maps, strings, raw strings, numbers, booleans, unit
//! variants, comments) is a small recursive descent over them.

use crate::diag::{Diagnostic, Phase};
use crate::span::Span;
use logos::Logos;

/// Nesting deeper than this is refused (protects the stack against hostile input).
const MAX_DEPTH: usize = 64;

#[derive(Logos, Clone, Debug, PartialEq)]
#[logos(skip r"[ \t\r\n\f]+")]
#[logos(skip(r"//[^\n]*", allow_greedy = true))]
#[logos(skip r"/\*([^*]|\*+[^*/])*\*+/")]
enum Tok {
    #[token("(")]
    LParen,
    #[token(")")]
    RParen,
    #[token("[")]
    LBracket,
    #[token("]")]
    RBracket,
    #[token("{")]
    LBrace,
    #[token("}")]
    RBrace,
    #[token(",")]
    Comma,
    #[token(":")]
    Colon,
    #[token("true")]
    True,
    #[token("false")]
    False,
    #[regex(r"[A-Za-z_][A-Za-z0-9_]*")]
    Ident,
    #[regex(r"[+-]?[0-9][0-9_]*")]
    Int,
    #[regex(r"[+-]?([0-9][0-9_]*\.[0-9_]*([eE][+-]?[0-9]+)?|[0-9][0-9_]*[eE][+-]?[0-9]+|\.[0-9]+([eE][+-]?[0-9]+)?)")]
    Float,
    #[regex(r#""([^"\\]|\\.)*""#)]
    Str,
    #[regex(r##"r#*""##, raw_string)]
    RawStr,
}

/// Consume the body of a raw string `r#"..."#` after its opening quote.
fn raw_string(lex: &mut logos::Lexer<Tok>) -> bool {
    let hashes = lex.slice().len() - 2;
    let closing: String = std::iter::once('"').chain(std::iter::repeat_n('#', hashes)).collect();
    match lex.remainder().find(&closing) {
        Some(at) => {
            lex.bump(at + closing.len());
            true
        }
        None => false,
    }
}

/// A string literal: decoded text plus the source offset of each decoded byte.
#[derive(Clone, Debug, PartialEq)]
pub struct StrLit {
    pub text: String,
    /// `offsets[i]` is the source byte offset of `text`'s byte `i`; one extra entry for the end.
    pub offsets: Vec<u32>,
}

impl StrLit {
    /// Map a span inside the decoded text to a span in the source file.
    pub fn map_span(&self, inner: Span) -> Span {
        let at = |i: u32| -> u32 {
            let i = (i as usize).min(self.offsets.len().saturating_sub(1));
            self.offsets.get(i).copied().unwrap_or(0)
        };
        let start = at(inner.start);
        let end = at(inner.end).max(start);
        Span { start, end }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Bool(bool),
    Int(i64),
    Float(f64),
    Str(StrLit),
    /// A bare identifier: a unit variant (`Unorm8`) or unit struct.
    Ident(String),
    /// `Name(field: value, ...)` or `(field: value, ...)`.
    Struct {
        name: Option<(String, Span)>,
        fields: Vec<Field>,
    },
    /// `Name(value, ...)` or `(value, ...)`.
    Tuple {
        name: Option<(String, Span)>,
        items: Vec<Node>,
    },
    List(Vec<Node>),
    Map(Vec<(Node, Node)>),
}

#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub name: String,
    pub name_span: Span,
    pub value: Node,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    pub value: Value,
    pub span: Span,
}

impl Node {
    /// A short description of what kind of value this is, for "expected X, found Y".
    pub fn describe(&self) -> String {
        match &self.value {
            Value::Bool(_) => "a boolean".into(),
            Value::Int(_) => "an integer".into(),
            Value::Float(_) => "a number".into(),
            Value::Str(_) => "a string".into(),
            Value::Ident(n) => format!("`{n}`"),
            Value::Struct { name: Some((n, _)), .. } | Value::Tuple { name: Some((n, _)), .. } => {
                format!("`{n}(...)`")
            }
            Value::Struct { name: None, .. } => "a struct `(...)`".into(),
            Value::Tuple { name: None, .. } => "a tuple `(...)`".into(),
            Value::List(_) => "a list `[...]`".into(),
            Value::Map(_) => "a map `{...}`".into(),
        }
    }
}

struct Parser<'s> {
    src: &'s str,
    toks: Vec<(Tok, Span)>,
    pos: usize,
}

/// Read a whole RON document into a spanned tree.
pub fn parse(src: &str) -> Result<Node, Diagnostic> {
    let mut toks = Vec::new();
    let mut lex = Tok::lexer(src);
    while let Some(tok) = lex.next() {
        let span = Span::new(lex.span().start, lex.span().end);
        match tok {
            Ok(t) => toks.push((t, span)),
            Err(()) => {
                let text = &src[lex.span()];
                let (msg, help) = if text.starts_with('"') || text.starts_with('r') {
                    ("unterminated string", "close the string with `\"`")
                } else if text.starts_with("/*") {
                    ("unterminated block comment", "close the comment with `*/`")
                } else {
                    (
                        "unexpected character",
                        "RON values are structs `Name(...)`, lists `[...]`, maps `{...}`, strings, numbers and identifiers",
                    )
                };
                return Err(Diagnostic::error(Phase::Syntax, format!("{msg} `{}`", text.escape_debug()))
                    .at(span, "not valid RON here")
                    .help(help));
            }
        }
    }
    let mut p = Parser { src, toks, pos: 0 };
    let node = p.value(0)?;
    if let Some((_, span)) = p.toks.get(p.pos) {
        return Err(Diagnostic::error(Phase::Syntax, "unexpected text after the end of the document")
            .at(*span, "the document ended before this")
            .help("a technique file holds exactly one `Technique(...)` value"));
    }
    Ok(node)
}

impl<'s> Parser<'s> {
    fn peek(&self) -> Option<&(Tok, Span)> {
        self.toks.get(self.pos)
    }

    fn peek_tok(&self, ahead: usize) -> Option<&Tok> {
        self.toks.get(self.pos + ahead).map(|(t, _)| t)
    }

    fn eof_span(&self) -> Span {
        Span::new(self.src.len(), self.src.len())
    }

    fn bump(&mut self) -> Option<(Tok, Span)> {
        let t = self.toks.get(self.pos).cloned();
        self.pos += 1;
        t
    }

    fn text(&self, span: Span) -> &'s str {
        &self.src[span.range()]
    }

    fn expect(&mut self, want: Tok, what: &str) -> Result<Span, Diagnostic> {
        match self.bump() {
            Some((t, span)) if t == want => Ok(span),
            Some((_, span)) => Err(
                Diagnostic::error(Phase::Syntax, format!("expected {what}, found `{}`", self.text(span)))
                    .at(span, format!("expected {what}")),
            ),
            None => Err(
                Diagnostic::error(Phase::Syntax, format!("expected {what}, found the end of the file"))
                    .at(self.eof_span(), format!("expected {what}")),
            ),
        }
    }

    fn value(&mut self, depth: usize) -> Result<Node, Diagnostic> {
        let Some((tok, span)) = self.bump() else {
            return Err(Diagnostic::error(Phase::Syntax, "expected a value, found the end of the file")
                .at(self.eof_span(), "a value is missing here"));
        };
        if depth > MAX_DEPTH {
            return Err(Diagnostic::error(Phase::Syntax, format!("values nest deeper than {MAX_DEPTH} levels")).at(span, "too deep"));
        }
        let text = self.text(span);
        let value = match tok {
            Tok::True => Value::Bool(true),
            Tok::False => Value::Bool(false),
            Tok::Int => match text.replace('_', "").parse::<i64>() {
                Ok(v) => Value::Int(v),
                Err(_) => {
                    return Err(
                        Diagnostic::error(Phase::Syntax, format!("integer `{text}` is out of range")).at(span, "does not fit in 64 bits")
                    );
                }
            },
            Tok::Float => match text.replace('_', "").parse::<f64>() {
                Ok(v) => Value::Float(v),
                Err(_) => {
                    return Err(Diagnostic::error(Phase::Syntax, format!("malformed number `{text}`")).at(span, "here"));
                }
            },
            Tok::Str => Value::Str(self.decode_string(span)?),
            Tok::RawStr => {
                let hashes = text[1..].chars().take_while(|c| *c == '#').count();
                let start = span.start as usize + 2 + hashes;
                let end = span.end as usize - 1 - hashes;
                Value::Str(StrLit {
                    text: self.src[start..end].to_string(),
                    offsets: (start as u32..=end as u32).collect(),
                })
            }
            Tok::Ident => {
                if matches!(self.peek_tok(0), Some(Tok::LParen)) {
                    let name = Some((text.to_string(), span));
                    return self.parens(name, span, depth);
                }
                Value::Ident(text.to_string())
            }
            Tok::LParen => {
                self.pos -= 1;
                return self.parens(None, span, depth);
            }
            Tok::LBracket => {
                let mut items = Vec::new();
                let end = loop {
                    if let Some((Tok::RBracket, end)) = self.peek().cloned() {
                        self.pos += 1;
                        break end;
                    }
                    items.push(self.value(depth + 1)?);
                    if !self.comma_or_close(Tok::RBracket, "`,` or `]`")? {
                        continue;
                    }
                };
                return Ok(Node {
                    value: Value::List(items),
                    span: span.join(end),
                });
            }
            Tok::LBrace => {
                let mut entries = Vec::new();
                let end = loop {
                    if let Some((Tok::RBrace, end)) = self.peek().cloned() {
                        self.pos += 1;
                        break end;
                    }
                    let key = self.value(depth + 1)?;
                    self.expect(Tok::Colon, "`:` after a map key")?;
                    let value = self.value(depth + 1)?;
                    entries.push((key, value));
                    self.comma_or_close(Tok::RBrace, "`,` or `}`")?;
                };
                return Ok(Node {
                    value: Value::Map(entries),
                    span: span.join(end),
                });
            }
            Tok::RParen | Tok::RBracket | Tok::RBrace | Tok::Comma | Tok::Colon => {
                return Err(Diagnostic::error(Phase::Syntax, format!("expected a value, found `{text}`"))
                    .at(span, "a value is missing before this"));
            }
        };
        Ok(Node { value, span })
    }

    /// After an item: a comma (then more items or the closer) or the closer itself.
    /// Leaves the closer unconsumed; returns whether it saw a comma.
    fn comma_or_close(&mut self, close: Tok, what: &str) -> Result<bool, Diagnostic> {
        match self.peek().cloned() {
            Some((Tok::Comma, _)) => {
                self.pos += 1;
                Ok(true)
            }
            Some((t, _)) if t == close => Ok(false),
            Some((_, span)) => Err(
                Diagnostic::error(Phase::Syntax, format!("expected {what}, found `{}`", self.text(span)))
                    .at(span, format!("expected {what}"))
                    .help("items are separated by commas"),
            ),
            None => Err(
                Diagnostic::error(Phase::Syntax, format!("expected {what}, found the end of the file"))
                    .at(self.eof_span(), "unclosed here"),
            ),
        }
    }

    /// `( ... )` after an optional name: fields `a: v` make a struct, plain values a tuple.
    fn parens(&mut self, name: Option<(String, Span)>, start: Span, depth: usize) -> Result<Node, Diagnostic> {
        self.expect(Tok::LParen, "`(`")?;
        let is_struct = matches!((self.peek_tok(0), self.peek_tok(1)), (Some(Tok::Ident), Some(Tok::Colon)));
        let mut fields = Vec::new();
        let mut items = Vec::new();
        let end = loop {
            if let Some((Tok::RParen, end)) = self.peek().cloned() {
                self.pos += 1;
                break end;
            }
            if is_struct {
                let (tok, name_span) = self
                    .bump()
                    .ok_or_else(|| Diagnostic::error(Phase::Syntax, "unclosed `(`").at(start, "opened here"))?;
                if tok != Tok::Ident {
                    return Err(
                        Diagnostic::error(Phase::Syntax, format!("expected a field name, found `{}`", self.text(name_span)))
                            .at(name_span, "expected `name: value`"),
                    );
                }
                self.expect(Tok::Colon, "`:` after a field name")?;
                let value = self.value(depth + 1)?;
                fields.push(Field {
                    name: self.text(name_span).to_string(),
                    name_span,
                    value,
                });
            } else {
                items.push(self.value(depth + 1)?);
            }
            self.comma_or_close(Tok::RParen, "`,` or `)`")?;
        };
        let span = start.join(end);
        let value = if is_struct {
            Value::Struct { name, fields }
        } else {
            Value::Tuple { name, items }
        };
        Ok(Node { value, span })
    }

    fn decode_string(&self, span: Span) -> Result<StrLit, Diagnostic> {
        let start = span.start as usize + 1;
        let body = &self.src[start..span.end as usize - 1];
        let mut text = String::with_capacity(body.len());
        let mut offsets = Vec::with_capacity(body.len() + 1);
        let mut chars = body.char_indices().peekable();
        while let Some((i, c)) = chars.next() {
            let at = (start + i) as u32;
            let decoded = if c == '\\' {
                let Some((j, e)) = chars.next() else { break };
                match e {
                    'n' => '\n',
                    't' => '\t',
                    'r' => '\r',
                    '0' => '\0',
                    '\\' => '\\',
                    '"' => '"',
                    '\'' => '\'',
                    _ => {
                        let esc = Span::new(start + i, start + j + e.len_utf8());
                        return Err(Diagnostic::error(Phase::Syntax, format!("unknown escape `\\{e}`"))
                            .at(esc, "not a RON escape")
                            .help("use `\\n`, `\\t`, `\\\\` or `\\\"`, or a raw string `r#\"...\"#`"));
                    }
                }
            } else {
                c
            };
            for _ in 0..decoded.len_utf8() {
                offsets.push(at);
            }
            text.push(decoded);
        }
        offsets.push(span.end - 1);
        Ok(StrLit { text, offsets })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_point_at_values_and_string_bytes() {
        let src = r#"T(a: 1, b: [2.5, "x*y"], c: {"k": Unit}, d: r"raw")"#;
        let node = parse(src).unwrap();
        let Value::Struct { fields, .. } = &node.value else {
            panic!("not a struct: {node:?}")
        };
        assert_eq!(fields.len(), 4);
        assert_eq!(&src[fields[0].value.span.range()], "1");
        let Value::List(items) = &fields[1].value.value else { panic!() };
        let Value::Str(s) = &items[1].value else { panic!() };
        assert_eq!(s.text, "x*y");
        // `y` is byte 2 of the string; it must map to the `y` in the source.
        assert_eq!(&src[s.map_span(Span::new(2, 3)).range()], "y");
        let Value::Str(raw) = &fields[3].value.value else { panic!() };
        assert_eq!(raw.text, "raw");
        assert_eq!(&src[raw.map_span(Span::new(0, 3)).range()], "raw");
    }

    #[test]
    fn escapes_keep_positions() {
        let src = r#""a\"b""#;
        let node = parse(src).unwrap();
        let Value::Str(s) = &node.value else { panic!() };
        assert_eq!(s.text, "a\"b");
        assert_eq!(&src[s.map_span(Span::new(2, 3)).range()], "b");
    }

    #[test]
    fn errors_have_spans() {
        let e = parse("T(a: 1,, b: 2)").unwrap_err();
        assert_eq!(e.primary.0, Span::new(7, 8));
        let e = parse("T(a: 1").unwrap_err();
        assert!(e.message.contains("end of the file"), "{}", e.message);
        let deep = "[".repeat(200);
        assert!(parse(&deep).is_err());
    }
}
