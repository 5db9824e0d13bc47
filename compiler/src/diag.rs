//! Diagnostics: every error a user can cause is a [`Diagnostic`] value with labelled spans,
//! rendered like rustc (`file:line:column`, the offending text underlined, a hint) through
//! codespan-reporting. Tests compare the no-colour rendering.

use crate::span::{Span, line_col};
use codespan_reporting::diagnostic::{Diagnostic as CsDiagnostic, Label, LabelStyle, Severity};
use codespan_reporting::files::SimpleFile;
use codespan_reporting::term::{self, termcolor};
use std::fmt;

/// Which phase found the problem; shown in the error code (e.g. `error[check]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    Syntax,
    Parse,
    Resolve,
    Check,
    Lower,
    Analyse,
    Pack,
    Codegen,
    Emit,
    Cli,
}

impl Phase {
    pub fn name(self) -> &'static str {
        match self {
            Phase::Syntax => "syntax",
            Phase::Parse => "parse",
            Phase::Resolve => "resolve",
            Phase::Check => "check",
            Phase::Lower => "lower",
            Phase::Analyse => "analyse",
            Phase::Pack => "pack",
            Phase::Codegen => "codegen",
            Phase::Emit => "emit",
            Phase::Cli => "cli",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    Error,
    Warning,
    Note,
}

/// One problem, with a primary span, secondary labels and notes/hints.
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnostic {
    pub level: Level,
    pub phase: Phase,
    pub message: String,
    /// The primary span and its label (`Span::UNDEFINED` when the problem has no place).
    pub primary: (Span, String),
    pub secondary: Vec<(Span, String)>,
    /// Free-form notes, rendered as `= note: ...`.
    pub notes: Vec<String>,
    /// What would fix it, rendered as `= help: ...`.
    pub help: Option<String>,
    /// The help as edits of the source, where it names a concrete replacement (empty
    /// otherwise): what a tool may apply, and what `compiler/tests/warnings.rs` applies to
    /// check that the diagnostic's own check sees the result (issue 51: no fix is offered
    /// that is not checked again).
    pub fix: Vec<Edit>,
}

/// One edit of the source: the text at `span` replaced by `text` (an empty span inserts).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Edit {
    pub span: Span,
    pub text: String,
}

/// `source` with `edits` applied (edits that overlap an earlier one, or lie outside the
/// source or inside a character, are skipped).
pub fn apply(source: &str, edits: &[Edit]) -> String {
    let mut sorted: Vec<&Edit> = edits.iter().collect();
    sorted.sort_by_key(|e| (e.span.start, e.span.end));
    let mut out = String::with_capacity(source.len());
    let mut at = 0usize;
    for e in sorted {
        let (start, end) = (e.span.start as usize, e.span.end as usize);
        if start < at || end > source.len() || !source.is_char_boundary(start) || !source.is_char_boundary(end) {
            continue;
        }
        out.push_str(&source[at..start]);
        out.push_str(&e.text);
        at = end;
    }
    out.push_str(&source[at..]);
    out
}

impl Diagnostic {
    /// `source` with this diagnostic's suggested fix applied ([`Diagnostic::fix`]).
    pub fn fixed(&self, source: &str) -> String {
        apply(source, &self.fix)
    }

    pub fn error(phase: Phase, message: impl Into<String>) -> Self {
        Diagnostic {
            level: Level::Error,
            phase,
            message: message.into(),
            primary: (Span::UNDEFINED, String::new()),
            secondary: Vec::new(),
            notes: Vec::new(),
            help: None,
            fix: Vec::new(),
        }
    }

    pub fn warning(phase: Phase, message: impl Into<String>) -> Self {
        Diagnostic {
            level: Level::Warning,
            ..Diagnostic::error(phase, message)
        }
    }

    pub fn at(mut self, span: Span, label: impl Into<String>) -> Self {
        self.primary = (span, label.into());
        self
    }

    pub fn also(mut self, span: Span, label: impl Into<String>) -> Self {
        self.secondary.push((span, label.into()));
        self
    }

    pub fn note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }

    pub fn help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }

    /// A concrete edit the help proposes (one of several where the fix takes several).
    pub fn fix(mut self, span: Span, text: impl Into<String>) -> Self {
        self.fix.push(Edit { span, text: text.into() });
        self
    }

    /// [`Diagnostic::fix`] with the edit made.
    pub fn fix_edit(mut self, edit: Edit) -> Self {
        self.fix.push(edit);
        self
    }

    pub fn is_error(&self) -> bool {
        self.level == Level::Error
    }

    fn to_codespan(&self) -> CsDiagnostic<()> {
        let severity = match self.level {
            Level::Error => Severity::Error,
            Level::Warning => Severity::Warning,
            Level::Note => Severity::Note,
        };
        let mut labels = Vec::new();
        if self.primary.0.is_defined() || !self.primary.1.is_empty() {
            labels.push(Label::new(LabelStyle::Primary, (), self.primary.0.range()).with_message(self.primary.1.clone()));
        }
        for (span, msg) in &self.secondary {
            labels.push(Label::new(LabelStyle::Secondary, (), span.range()).with_message(msg.clone()));
        }
        let mut notes: Vec<String> = self.notes.iter().map(|n| format!("note: {n}")).collect();
        if let Some(h) = &self.help {
            notes.push(format!("help: {h}"));
        }
        CsDiagnostic::new(severity)
            .with_code(self.phase.name())
            .with_message(self.message.clone())
            .with_labels(labels)
            .with_notes(notes)
    }

    /// Render without colour, as tests compare it.
    pub fn render(&self, file_name: &str, source: &str) -> String {
        let mut buffer = termcolor::Buffer::no_color();
        self.emit_to(&mut buffer, file_name, source);
        String::from_utf8_lossy(buffer.as_slice()).into_owned()
    }

    /// Render to a terminal writer (with colour when the writer supports it).
    pub fn emit_to(&self, writer: &mut dyn termcolor::WriteColor, file_name: &str, source: &str) {
        let file = SimpleFile::new(file_name, source);
        let config = term::Config::default();
        if term::emit_to_write_style(writer, &config, &file, &self.to_codespan()).is_err() {
            // Rendering failed (span outside the file): fall back to a plain line.
            let _ = writeln!(writer, "{}", self.short(file_name, source));
        }
    }

    /// `file:line:column: error: message`, one line.
    pub fn short(&self, file_name: &str, source: &str) -> String {
        let (line, col) = line_col(source, self.primary.0.start as usize);
        let level = match self.level {
            Level::Error => "error",
            Level::Warning => "warning",
            Level::Note => "note",
        };
        format!("{file_name}:{line}:{col}: {level}[{}]: {}", self.phase.name(), self.message)
    }
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.message)
    }
}

impl std::error::Error for Diagnostic {}

/// All diagnostics of one compilation (errors stop the pipeline at the end of a phase;
/// warnings travel with the result).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Diagnostics(pub Vec<Diagnostic>);

impl Diagnostics {
    pub fn push(&mut self, d: Diagnostic) {
        self.0.push(d);
    }

    pub fn has_errors(&self) -> bool {
        self.0.iter().any(Diagnostic::is_error)
    }

    pub fn errors(&self) -> impl Iterator<Item = &Diagnostic> {
        self.0.iter().filter(|d| d.is_error())
    }

    pub fn render(&self, file_name: &str, source: &str) -> String {
        self.0.iter().map(|d| d.render(file_name, source)).collect()
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Ok(()) when there is no error so far; otherwise all diagnostics gathered.
    pub fn check(&self) -> Result<(), Diagnostics> {
        if self.has_errors() { Err(self.clone()) } else { Ok(()) }
    }
}

impl From<Diagnostic> for Diagnostics {
    fn from(d: Diagnostic) -> Self {
        Diagnostics(vec![d])
    }
}

impl fmt::Display for Diagnostics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for d in &self.0 {
            writeln!(f, "{d}")?;
        }
        Ok(())
    }
}

impl std::error::Error for Diagnostics {}
