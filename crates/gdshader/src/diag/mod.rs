//! Diagnostics: the one type every stage reports through.
//!
//! Each stage (preprocessor, parser, checker) builds [`Diagnostic`]s whose labels point at byte
//! ranges of *source files* held in a [`SourceDb`]. Stages that work on the preprocessed text
//! translate their spans through the preprocessor's [`SourceMap`](crate::SourceMap) first, so a
//! diagnostic always names the file the user wrote, even through `#include` and macro expansion.
//!
//! Rendering is codespan-reporting's (as naga's is): code, message, `file:line:col`, a caret under
//! the span, and notes saying what was expected. [`render_json`] gives the one-object-per-line
//! form of the CLI contract.

pub mod codes;

use codespan_reporting::diagnostic as cs;
use codespan_reporting::files::{Files, SimpleFiles};
use codespan_reporting::term;
use std::ops::Range;

/// Identifies one source file in a [`SourceDb`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FileId(pub(crate) usize);

/// Every source file a run has read: the shader and each file it includes.
///
/// Text is stored as read (invalid UTF-8 replaced by U+FFFD for display only; such a file is
/// rejected before parsing).
#[derive(Default)]
pub struct SourceDb {
    files: SimpleFiles<String, String>,
    paths: Vec<Option<std::path::PathBuf>>,
}

impl SourceDb {
    /// An empty database.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a file under a display `name`; `path` is where it was read from, if anywhere.
    pub fn add(&mut self, name: impl Into<String>, text: String, path: Option<std::path::PathBuf>) -> FileId {
        self.paths.push(path);
        FileId(self.files.add(name.into(), text))
    }

    /// The text of a file.
    pub fn text(&self, file: FileId) -> &str {
        self.files.get(file.0).map(|f| f.source().as_str()).unwrap_or("")
    }

    /// The display name of a file.
    pub fn name(&self, file: FileId) -> &str {
        self.files.get(file.0).map(|f| f.name().as_str()).unwrap_or("")
    }

    /// The path a file was read from, if it came from disk.
    pub fn path(&self, file: FileId) -> Option<&std::path::Path> {
        self.paths.get(file.0).and_then(|p| p.as_deref())
    }

    /// The paths of every file read from disk (the shader and its includes).
    pub fn paths(&self) -> impl Iterator<Item = &std::path::Path> {
        self.paths.iter().filter_map(|p| p.as_deref())
    }

    /// Number of files held.
    pub fn len(&self) -> usize {
        self.paths.len()
    }

    /// True when no file has been added.
    pub fn is_empty(&self) -> bool {
        self.paths.is_empty()
    }

    /// 1-based line and column (in characters) of a byte offset.
    pub fn line_col(&self, file: FileId, offset: usize) -> (usize, usize) {
        let text = self.text(file);
        let offset = floor_char_boundary(text, offset.min(text.len()));
        match self.files.location(file.0, offset) {
            Ok(loc) => (loc.line_number, loc.column_number),
            Err(_) => (1, 1),
        }
    }
}

fn floor_char_boundary(text: &str, mut offset: usize) -> usize {
    while offset > 0 && !text.is_char_boundary(offset) {
        offset -= 1;
    }
    offset
}

/// How serious a diagnostic is. Only errors make a shader invalid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// Godot would reject the shader, or gdsky cannot translate it.
    Error,
    /// Godot accepts it, but it is likely a mistake.
    Warning,
}

/// A labelled byte range of a source file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Label {
    /// The file the range lies in.
    pub file: FileId,
    /// Byte range in that file's text.
    pub range: Range<usize>,
    /// What this place has to do with the diagnostic (may be empty).
    pub message: String,
    /// The primary label is the place the diagnostic is reported at.
    pub primary: bool,
}

/// One problem found in a shader.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    /// Error or warning.
    pub severity: Severity,
    /// Stable code, one per kind of problem (see [`codes`]).
    pub code: &'static str,
    /// One sentence saying what is wrong.
    pub message: String,
    /// The places involved; the first primary one is where the diagnostic is reported.
    pub labels: Vec<Label>,
    /// What was expected, or how to fix it.
    pub notes: Vec<String>,
}

impl Diagnostic {
    /// A new error with a code and message and no labels yet.
    pub fn error(code: &'static str, message: impl Into<String>) -> Self {
        Self { severity: Severity::Error, code, message: message.into(), labels: Vec::new(), notes: Vec::new() }
    }

    /// A new warning with a code and message and no labels yet.
    pub fn warning(code: &'static str, message: impl Into<String>) -> Self {
        Self { severity: Severity::Warning, code, message: message.into(), labels: Vec::new(), notes: Vec::new() }
    }

    /// Adds the primary label.
    pub fn with_primary(mut self, file: FileId, range: Range<usize>, message: impl Into<String>) -> Self {
        self.labels.push(Label { file, range, message: message.into(), primary: true });
        self
    }

    /// Adds a secondary label.
    pub fn with_secondary(mut self, file: FileId, range: Range<usize>, message: impl Into<String>) -> Self {
        self.labels.push(Label { file, range, message: message.into(), primary: false });
        self
    }

    /// Adds a note.
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }

    /// Adds every note given (an `Option<String>` adds one or none).
    pub fn with_notes(mut self, notes: impl IntoIterator<Item = String>) -> Self {
        self.notes.extend(notes);
        self
    }

    /// True for errors.
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }

    /// The label the diagnostic is reported at: the first primary one, else the first.
    pub fn primary_label(&self) -> Option<&Label> {
        self.labels.iter().find(|l| l.primary).or_else(|| self.labels.first())
    }
}

/// Renders diagnostics for a terminal or a log, the way rustc and naga do.
pub fn render_human(db: &SourceDb, diagnostics: &[Diagnostic], color: bool) -> String {
    use codespan_reporting::term::termcolor::{Ansi, NoColor};
    let config = term::Config::default();
    let mut out: Vec<u8> = Vec::new();
    for d in diagnostics {
        let cs_diag = to_codespan(db, d);
        let result = if color {
            term::emit_to_write_style(&mut Ansi::new(&mut out), &config, &db.files, &cs_diag)
        } else {
            term::emit_to_write_style(&mut NoColor::new(&mut out), &config, &db.files, &cs_diag)
        };
        if result.is_err() {
            // A label outside its file cannot be drawn; say it plainly rather than lose it.
            out.extend_from_slice(format!("{}[{}]: {}\n", severity_word(d.severity), d.code, d.message).as_bytes());
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn severity_word(s: Severity) -> &'static str {
    match s {
        Severity::Error => "error",
        Severity::Warning => "warning",
    }
}

fn to_codespan(db: &SourceDb, d: &Diagnostic) -> cs::Diagnostic<usize> {
    let severity = match d.severity {
        Severity::Error => cs::Severity::Error,
        Severity::Warning => cs::Severity::Warning,
    };
    let labels = d
        .labels
        .iter()
        .map(|l| {
            let text = db.text(l.file);
            let start = floor_char_boundary(text, l.range.start.min(text.len()));
            let end = floor_char_boundary(text, l.range.end.clamp(start, text.len()));
            let style = if l.primary { cs::LabelStyle::Primary } else { cs::LabelStyle::Secondary };
            cs::Label::new(style, l.file.0, start..end).with_message(l.message.clone())
        })
        .collect();
    cs::Diagnostic::new(severity)
        .with_code(d.code)
        .with_message(d.message.clone())
        .with_labels(labels)
        .with_notes(d.notes.clone())
}

/// One line of JSON per diagnostic (the CLI's `--diagnostics json`): file, line, column,
/// end_line, end_column (1-based, columns in characters), severity, code, message.
pub fn render_json(db: &SourceDb, diagnostics: &[Diagnostic]) -> String {
    let mut out = String::new();
    for d in diagnostics {
        let (file, line, column, end_line, end_column) = match d.primary_label() {
            Some(l) => {
                let (line, column) = db.line_col(l.file, l.range.start);
                let (end_line, end_column) = db.line_col(l.file, l.range.end);
                (db.name(l.file).to_string(), line, column, end_line, end_column)
            }
            None => (String::new(), 0, 0, 0, 0),
        };
        let value = serde_json::json!({
            "file": file,
            "line": line,
            "column": column,
            "end_line": end_line,
            "end_column": end_column,
            "severity": d.severity,
            "code": d.code,
            "message": d.message,
        });
        out.push_str(&value.to_string());
        out.push('\n');
    }
    out
}

/// The closest of `candidates` to `name`, when it is close enough to be a typo.
pub fn did_you_mean<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    candidates
        .into_iter()
        .map(|c| (strsim::osa_distance(name, c), c))
        .filter(|(d, c)| *d <= (c.len().max(name.len()) / 3).max(1))
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}
