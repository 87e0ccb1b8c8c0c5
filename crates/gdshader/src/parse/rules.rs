//! Grammar rule names in English, so a syntax error reads like a sentence.

use super::{Rule, SpannedDiagnostic};
use crate::diag::codes;
use crate::parse::ast::Span;

/// What a rule stands for when the parser expected it, or `None` when it only adds noise
/// (another entry in the same list already says it).
fn english(rule: Rule) -> Option<&'static str> {
    use Rule::*;
    Some(match rule {
        EOI => "the end of the file",
        ident | declarator_name | group_path => "a name",
        number | bool_lit | prefix_op | operand | expr | paren | named | call_tail | array_ctor_tail | init_list
        | args => "an expression",
        infix_op | ternary_mid => "an operator",
        post_inc | post_dec | member | method_call | index => return None,
        string => "a string",
        hint => "a hint",
        type_ref | precision => "a type",
        param | params | param_qualifier => "a parameter",
        array_size => "`[`",
        block => "`{`",
        if_stmt | for_stmt | while_stmt | do_stmt | switch_stmt | break_stmt | continue_stmt | return_stmt
        | discard_stmt | local_const_decl | local_var_decl | expr_stmt | empty_stmt | else_if | else_clause => {
            "a statement"
        }
        switch_case | case_label => "`case` or `default`",
        shader_type_decl | render_mode_decl | group_uniforms_decl | uniform_decl | struct_decl | global_const_decl
        | function_def | global_var_decl | stray_semicolon => "a declaration",
        struct_member => "a struct member",
        kw_shader_type => "a declaration",
        kw_render_mode => "a declaration",
        kw_group_uniforms => "a declaration",
        kw_uniform => "a declaration",
        kw_global => "`global`",
        kw_instance => "`instance`",
        kw_struct => "a declaration",
        kw_const => "a declaration",
        kw_void => "`void`",
        kw_inout => "`inout`",
        kw_in => "`in`",
        kw_out => "`out`",
        kw_lowp | kw_mediump | kw_highp => "a precision qualifier",
        kw_if => "`if`",
        kw_else => "`else`",
        kw_for => "`for`",
        kw_while => "`while`",
        kw_do => "`do`",
        kw_switch => "`switch`",
        kw_case => "`case`",
        kw_default => "`default`",
        kw_break => "`break`",
        kw_continue => "`continue`",
        kw_return => "`return`",
        kw_discard => "`discard`",
        _ => return None,
    })
}

/// Operator tokens: listed one by one they drown the useful alternatives, so they are said as
/// "an operator".
const OPERATOR_TOKENS: &[&str] = &[
    "<<=", ">>=", "<<", ">>", "<=", ">=", "==", "!=", "&&", "||", "+=", "-=", "*=", "/=", "%=", "&=", "|=", "^=", "<",
    ">", "+", "-", "*", "/", "%", "&", "|", "^", "?", "++", "--", ".", "!", "~", "=",
];

/// Builds the syntax error at byte `pos` from the rules and literal tokens pest expected there.
pub fn describe(text: &str, pos: usize, positives: &[Rule], tokens: &[String]) -> SpannedDiagnostic {
    let mut expected: Vec<String> = Vec::new();
    let mut add = |s: String| {
        if !expected.contains(&s) {
            expected.push(s);
        }
    };
    // Closing punctuation first: when the parser wanted `;` that is the most useful thing to say.
    let mut wants_operator = false;
    for t in tokens {
        if t == "//" || t == "/*" {
            // Comments can start anywhere; saying so helps nobody.
        } else if OPERATOR_TOKENS.contains(&t.as_str()) || t == "[" {
            wants_operator = true;
        } else if !t.is_empty() && t != "_" && t.chars().all(|c| c.is_ascii_punctuation()) {
            add(format!("`{t}`"));
        }
    }
    for &r in positives {
        if let Some(e) = english(r) {
            add(e.to_string());
        }
    }
    if wants_operator {
        add("an operator".to_string());
    }
    // Tokens that only start a longer alternative already in the list add nothing.
    if expected.iter().any(|e| e == "an expression") {
        expected.retain(|e| !matches!(e.as_str(), "`(`" | "`{`" | "`[`"));
    }
    if expected.iter().any(|e| e == "a name") {
        expected.retain(|e| !matches!(e.as_str(), "an operator" | "`[`"));
    }
    // "the end of the file" reads best last.
    if let Some(i) = expected.iter().position(|e| e == "the end of the file") {
        let eof = expected.remove(i);
        expected.push(eof);
    }
    let found = found_token(text, pos);
    let notes = hints_for(text, pos, &found.1);
    let message = match expected.len() {
        0 => format!("unexpected {}", found.1),
        _ => format!("expected {}, found {}", join_or(&expected, 5), found.1),
    };
    // A missing `;` or `)` belongs at the end of what came before, not at the next line's token.
    let closer_missing = expected.first().is_some_and(|e| e == "`;`" || e == "`)`" || e == "`,`");
    let before = text[..pos].trim_end().len();
    if closer_missing && text[before..pos].contains('\n') {
        let what = expected[0].clone();
        return SpannedDiagnostic::error(
            codes::SYNTAX,
            message,
            Span::new(before, before),
            format!("expected {what} here"),
        )
        .secondary(found.0, "next token");
    }
    notes
        .into_iter()
        .fold(SpannedDiagnostic::error(codes::SYNTAX, message, found.0, "unexpected here"), SpannedDiagnostic::note)
}

/// Notes for mistakes people make coming from GLSL or other Godot shader types.
fn hints_for(text: &str, pos: usize, found: &str) -> Vec<&'static str> {
    let prev = text[..pos].chars().next_back();
    match found {
        "`^`" if prev == Some('^') => vec!["Godot has no `^^` operator; for bools write `a != b`"],
        "`varying`" => vec!["sky shaders have no varyings; Godot allows them in spatial and canvas_item shaders only"],
        "`#`" => vec!["a directive must start its own line"],
        _ => Vec::new(),
    }
}

fn join_or(items: &[String], most: usize) -> String {
    let shown: Vec<&str> = items.iter().take(most).map(String::as_str).collect();
    match shown.len() {
        1 => shown[0].to_string(),
        n => format!("{} or {}", shown[..n - 1].join(", "), shown[n - 1]),
    }
}

/// The token at `pos`, with a description for the message.
fn found_token(text: &str, pos: usize) -> (Span, String) {
    let rest = text.get(pos..).unwrap_or("");
    let Some(first) = rest.chars().next() else {
        return (Span::new(pos, pos), "the end of the file".to_string());
    };
    let len = if first.is_ascii_alphanumeric() || first == '_' {
        rest.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '.')).unwrap_or(rest.len())
    } else {
        first.len_utf8()
    };
    let token = &rest[..len];
    let desc =
        if first.is_ascii_graphic() { format!("`{token}`") } else { format!("character U+{:04X}", first as u32) };
    (Span::new(pos, pos + len), desc)
}
