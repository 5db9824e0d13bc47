//! Errors reading or checking a scene: the kind, the file, the line and column, the
//! value's path, a hint.

use std::fmt;
use std::path::{Path, PathBuf};

/// What went wrong reading a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneErrorKind {
    /// A file could not be read.
    Io,
    /// RON syntax, or a value of the wrong shape (unknown field, missing field, ...).
    Syntax,
    /// A value out of its range (negative radius, zero normal, ...).
    Invalid,
    /// An OBJ mesh could not be used (bad path, parse error).
    Mesh,
}

/// An error reading a scene: where (file, line:column where known, or the value's path),
/// what, and a hint at the fix.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError(Box<ErrorInfo>);

#[derive(Clone, Debug, PartialEq)]
struct ErrorInfo {
    kind: SceneErrorKind,
    file: Option<PathBuf>,
    position: Option<(usize, usize)>,
    at: Option<String>,
    message: String,
    hint: Option<String>,
}

impl SceneError {
    pub(crate) fn new(kind: SceneErrorKind, message: impl Into<String>) -> Self {
        SceneError(Box::new(ErrorInfo {
            kind,
            file: None,
            position: None,
            at: None,
            message: message.into(),
            hint: None,
        }))
    }

    pub(crate) fn invalid(at: impl Into<String>, message: impl Into<String>, hint: impl Into<String>) -> Self {
        SceneError::new(SceneErrorKind::Invalid, message).with_at(at).with_hint(hint)
    }

    pub(crate) fn with_hint(mut self, hint: impl Into<String>) -> Self {
        self.0.hint = Some(hint.into());
        self
    }

    pub(crate) fn with_at(mut self, at: impl Into<String>) -> Self {
        self.0.at = Some(at.into());
        self
    }

    fn with_position(mut self, position: (usize, usize)) -> Self {
        self.0.position = Some(position);
        self
    }

    /// Names the scene file unless a file is already named.
    pub(crate) fn with_file(mut self, file: Option<&Path>) -> Self {
        if self.0.file.is_none() {
            self.0.file = file.map(Path::to_path_buf);
        }
        self
    }

    /// The kind of error.
    pub fn kind(&self) -> SceneErrorKind {
        self.0.kind
    }
    /// The scene file, when read from a file.
    pub fn file(&self) -> Option<&Path> {
        self.0.file.as_deref()
    }
    /// 1-based line and column, where known (syntax and type errors).
    pub fn line_col(&self) -> Option<(usize, usize)> {
        self.0.position
    }
    /// The path of the offending value in the file (`lights[0] (Disk).radius`), for
    /// semantic errors.
    pub fn at(&self) -> Option<&str> {
        self.0.at.as_deref()
    }
    /// The message with its `at` and `hint` lines, without the file: for a value that
    /// came from somewhere else than a file (a command-line option), which the caller
    /// names.
    pub fn describe(&self) -> String {
        let mut s = self.0.message.clone();
        if let Some(at) = &self.0.at {
            s.push_str(&format!("\n  at: {at}"));
        }
        if let Some(hint) = &self.0.hint {
            s.push_str(&format!("\n  hint: {hint}"));
        }
        s
    }

    /// What is wrong.
    pub fn message(&self) -> &str {
        &self.0.message
    }
    /// What would fix it.
    pub fn hint(&self) -> Option<&str> {
        self.0.hint.as_deref()
    }
}

impl fmt::Display for SceneError {
    /// `FILE:LINE:COL: error: MESSAGE` (parts that are unknown are left out; `<scene>`
    /// stands for a scene read from a string), then `at VALUE` and `hint: ...` lines.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0.file {
            Some(p) => write!(f, "{}", p.display())?,
            None => f.write_str("<scene>")?,
        }
        if let Some((line, col)) = self.0.position {
            write!(f, ":{line}:{col}")?;
        }
        write!(f, ": error: {}", self.0.message)?;
        if let Some(at) = &self.0.at {
            write!(f, "\n  at: {at}")?;
        }
        if let Some(hint) = &self.0.hint {
            write!(f, "\n  hint: {hint}")?;
        }
        Ok(())
    }
}

impl std::error::Error for SceneError {}

pub(crate) fn syntax_error(e: &ron::error::SpannedError) -> SceneError {
    use ron::Error as E;
    // ron's error has dozens of variants (and may gain more): the ones with a specific
    // fix are named, the rest point at the format's reference
    #[allow(clippy::wildcard_enum_match_arm)]
    let hint = match &e.code {
        E::NoSuchStructField { expected, .. } => format!("the fields allowed here are: {}", expected.join(", ")),
        E::MissingStructField { field, outer } => match outer {
            Some(outer) => format!("add `{field}: ...` to this `{outer}`"),
            None => format!("add `{field}: ...`"),
        },
        E::NoSuchEnumVariant { expected, .. } => format!("write one of: {}", expected.join(", ")),
        E::DuplicateStructField { field, .. } => format!("remove one of the `{field}` fields"),
        E::ExpectedComma => "separate fields and list items with `,`".to_string(),
        _ => "see scenes/README.md for the scene format".to_string(),
    };
    SceneError::new(SceneErrorKind::Syntax, e.code.to_string())
        .with_position((e.span.start.line, e.span.start.col))
        .with_hint(hint)
}
