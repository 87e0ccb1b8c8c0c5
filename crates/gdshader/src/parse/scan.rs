//! The pre-scan: one pass over the preprocessed text before pest sees it (see `parse/mod.rs`).

use super::{MAX_NESTING, SpannedDiagnostic};
use crate::diag::codes;
use crate::parse::ast::Span;

/// What the pre-scan found.
pub struct Scanned {
    /// Byte ranges of `/** … */` comments, in order.
    pub doc_comments: Vec<(usize, usize)>,
    /// Offsets just after each `;` or `}` outside all brackets: where a top-level item can
    /// start. A syntax error is re-parsed from the last one before it (see `syntax_error`).
    pub item_starts: Vec<usize>,
}

/// Nesting that pest will recurse into: a bracket or `?` (closed by `:`), holding how many
/// brace-less control statements (`if (c) if (d) …`) are open inside it.
struct Frame {
    closer: u8,
    pending_controls: usize,
}

/// Scans `text`, reporting control characters and excessive nesting into `diags`.
pub fn prescan(text: &str, diags: &mut Vec<SpannedDiagnostic>) -> Scanned {
    let bytes = text.as_bytes();
    let mut doc_comments = Vec::new();
    let mut item_starts = vec![0];
    let mut frames: Vec<Frame> = vec![Frame { closer: 0, pending_controls: 0 }];
    let mut depth = 0usize;
    let mut bad_chars: Option<(usize, usize)> = None; // (first offset, count)
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        match c {
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                i = memchr_newline(bytes, i);
                continue;
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                let end = find_comment_end(bytes, i + 2);
                let is_doc = bytes.get(i + 2) == Some(&b'*') && bytes.get(i + 3) != Some(&b'/');
                if is_doc && end <= bytes.len() && text.get(end - 2..end) == Some("*/") {
                    doc_comments.push((i, end));
                }
                i = end;
                continue;
            }
            b'"' => {
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' && bytes[i] != b'\n' {
                    i += 1;
                }
                i += 1;
                continue;
            }
            b'(' | b'[' | b'{' | b'?' => {
                let closer = match c {
                    b'(' => b')',
                    b'[' => b']',
                    b'{' => b'}',
                    _ => b':',
                };
                frames.push(Frame { closer, pending_controls: 0 });
                depth += 1;
                if depth > MAX_NESTING {
                    diags.push(nesting_error(i));
                    return Scanned { doc_comments, item_starts };
                }
            }
            b')' | b']' | b'}' | b':' => {
                let closes = frames.len() > 1 && frames.last().is_some_and(|f| f.closer == c || c != b':');
                if closes && let Some(frame) = frames.pop() {
                    depth -= 1 + frame.pending_controls;
                }
                if c == b'}'
                    && let Some(parent) = frames.last_mut()
                {
                    // A closing brace ends the statement it belongs to.
                    depth -= parent.pending_controls;
                    parent.pending_controls = 0;
                }
                if c == b'}' && frames.len() == 1 {
                    item_starts.push(i + 1);
                }
            }
            b';' => {
                if frames.len() == 1 {
                    item_starts.push(i + 1);
                }
                if let Some(frame) = frames.last_mut() {
                    depth -= frame.pending_controls;
                    frame.pending_controls = 0;
                }
            }
            b'a'..=b'z' | b'A'..=b'Z' | b'_' => {
                let start = i;
                while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                    i += 1;
                }
                if matches!(&text[start..i], "if" | "else" | "for" | "while" | "do" | "switch")
                    && let Some(frame) = frames.last_mut()
                {
                    frame.pending_controls += 1;
                    depth += 1;
                    if depth > MAX_NESTING {
                        diags.push(nesting_error(start));
                        return Scanned { doc_comments, item_starts };
                    }
                }
                continue;
            }
            b'\t' | b'\n' | b'\r' | 0x0b | 0x0c => {}
            0..=0x1f | 0x7f => {
                bad_chars = Some(match bad_chars {
                    None => (i, 1),
                    Some((first, n)) => (first, n + 1),
                });
            }
            _ => {}
        }
        i += 1;
    }
    if let Some((first, count)) = bad_chars {
        let what = if bytes[first] == 0 {
            "a NUL byte".to_string()
        } else {
            format!("control character U+{:04X}", bytes[first])
        };
        let mut d = SpannedDiagnostic::error(
            codes::INVALID_CHARACTER,
            format!("the source contains {what}"),
            Span::new(first, first + 1),
            "not allowed in shader source",
        )
        .note("shader source is text: only tab, line feed, carriage return, vertical tab and form feed may appear among the control characters");
        if count > 1 {
            d = d.note(format!("{count} such characters in all; this is the first"));
        }
        diags.push(d);
    }
    Scanned { doc_comments, item_starts }
}

fn nesting_error(at: usize) -> SpannedDiagnostic {
    SpannedDiagnostic::error(
        codes::NESTING_LIMIT,
        format!("code is nested more than {MAX_NESTING} levels deep"),
        Span::new(at, at + 1),
        "this opens one level too many",
    )
    .note("brackets, `?:` and statements under `if`/`for`/`while`/`else`/`do` without braces each count as a level; split the expression or move code into functions")
}

fn memchr_newline(bytes: &[u8], from: usize) -> usize {
    bytes[from..].iter().position(|&b| b == b'\n').map_or(bytes.len(), |p| from + p)
}

fn find_comment_end(bytes: &[u8], from: usize) -> usize {
    let mut j = from;
    while j + 1 < bytes.len() {
        if bytes[j] == b'*' && bytes[j + 1] == b'/' {
            return j + 2;
        }
        j += 1;
    }
    bytes.len()
}
