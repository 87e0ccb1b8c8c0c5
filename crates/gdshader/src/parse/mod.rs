//! The parser: preprocessed text → [`ast::Shader`].
//!
//! Three steps. A *pre-scan* walks the text once, skipping comments and strings, to find what
//! pest must never see: NUL and other control characters, and nesting deeper than
//! [`MAX_NESTING`] (brackets, ternaries, and statements nested under `if`/`for`/`while`/`else`
//! without braces). pest's generated parser recurses once per nesting level, so bounding nesting
//! up front is what keeps 20,000 open parentheses from overflowing the stack. The pre-scan also
//! records `/** … */` doc comments, which the grammar otherwise skips as whitespace.
//!
//! Then pest parses with the grammar in `grammar.pest`, and `build.rs` turns its pairs into the
//! AST. Operator precedence is resolved there with an explicit operator stack (no recursion), and
//! expression trees deeper than [`MAX_EXPR_DEPTH`] are refused, since every later pass walks them
//! recursively.
//!
//! A syntax error stops parsing (pest does not recover); its message is built from what the
//! grammar expected at the farthest point reached, in English (`rules.rs`), not rule names.

pub mod ast;
mod build;
mod rules;
mod scan;

use crate::diag::{Diagnostic, codes};
use ast::Span;
use pest::Parser as _;

/// Deepest bracket / statement nesting accepted. Real shaders stay far below; the limit exists so
/// that hostile input gets an error instead of a stack overflow.
pub const MAX_NESTING: usize = 256;

/// Deepest expression tree accepted (a chain of 1,000 `+` is fine; 100,000 is refused).
pub const MAX_EXPR_DEPTH: usize = 2048;

#[derive(pest_derive::Parser)]
#[grammar = "parse/grammar.pest"]
struct GdParser;

/// A diagnostic whose spans are still in preprocessed-text coordinates.
#[derive(Clone, Debug)]
pub struct SpannedDiagnostic {
    /// The diagnostic, with no labels yet.
    pub diagnostic: Diagnostic,
    /// Primary span and message.
    pub primary: (Span, String),
    /// Secondary spans and messages.
    pub secondary: Vec<(Span, String)>,
}

impl SpannedDiagnostic {
    /// An error at `span`.
    pub fn error(code: &'static str, message: impl Into<String>, span: Span, label: impl Into<String>) -> Self {
        Self { diagnostic: Diagnostic::error(code, message), primary: (span, label.into()), secondary: Vec::new() }
    }

    /// A warning at `span`.
    pub fn warning(code: &'static str, message: impl Into<String>, span: Span, label: impl Into<String>) -> Self {
        Self { diagnostic: Diagnostic::warning(code, message), primary: (span, label.into()), secondary: Vec::new() }
    }

    /// Adds a note.
    pub fn note(mut self, note: impl Into<String>) -> Self {
        self.diagnostic.notes.push(note.into());
        self
    }

    /// Adds a secondary label.
    pub fn secondary(mut self, span: Span, label: impl Into<String>) -> Self {
        self.secondary.push((span, label.into()));
        self
    }
}

/// Parses preprocessed text. Returns the tree (possibly partial when there were errors) and the
/// diagnostics.
pub fn parse(text: &str) -> (ast::Shader, Vec<SpannedDiagnostic>) {
    let mut diags = Vec::new();
    let scanned = scan::prescan(text, &mut diags);
    if diags.iter().any(|d| d.diagnostic.is_error()) {
        return (ast::Shader::default(), diags);
    }
    match GdParser::parse(Rule::shader, text) {
        Ok(mut pairs) => {
            let Some(root) = pairs.next() else {
                return (ast::Shader::default(), diags);
            };
            let shader = build::build_shader(root, text, &scanned.doc_comments, &mut diags);
            (shader, diags)
        }
        Err(err) => {
            diags.push(syntax_error(text, error_offset(&err), &scanned.item_starts));
            (ast::Shader::default(), diags)
        }
    }
}

fn error_offset(err: &pest::error::Error<Rule>) -> usize {
    match err.location {
        pest::error::InputLocation::Pos(p) => p,
        pest::error::InputLocation::Span((s, _)) => s,
    }
}

/// Re-parses with pest's error detail switched on (it costs time, so only on failure) and turns
/// what the grammar expected into a sentence.
///
/// Only the top-level item holding the error is re-parsed: from the last `;` or `}` outside all
/// brackets before the error. When that does not fail at the same place (the error began in an
/// earlier item), the whole text is re-parsed.
fn syntax_error(text: &str, pos: usize, item_starts: &[usize]) -> SpannedDiagnostic {
    let start = item_starts.iter().rev().copied().find(|&s| s <= pos).unwrap_or(0);
    let detailed = |from: usize| {
        pest::set_error_detail(true);
        let result = GdParser::parse(Rule::shader, &text[from..]);
        pest::set_error_detail(false);
        result.err().map(|e| (from, e))
    };
    let found = detailed(start).filter(|(from, e)| from + error_offset(e) == pos).or_else(|| detailed(0));
    let Some((from, err)) = found else {
        return SpannedDiagnostic::error(codes::SYNTAX, "syntax error", Span::new(pos, pos), "");
    };
    let mut positives = match &err.variant {
        pest::error::ErrorVariant::ParsingError { positives, .. } => positives.clone(),
        pest::error::ErrorVariant::CustomError { .. } => Vec::new(),
    };
    let tokens: Vec<String> =
        err.parse_attempts().map(|a| a.expected_tokens().iter().map(ToString::to_string).collect()).unwrap_or_default();
    positives.dedup();
    rules::describe(text, from + error_offset(&err), &positives, &tokens)
}

#[cfg(test)]
mod tests;
