use super::ast::{BinaryOp, ExprKind, ItemKind, StmtKind};
use super::*;

/// Parses `void sky() { <stmt> }` and returns the expression of its only statement.
fn expr_of(src: &str) -> ast::Expr {
    let text = format!("shader_type sky;\nvoid sky() {{ {src}; }}");
    let (shader, diags) = parse(&text);
    assert!(diags.is_empty(), "{diags:?}");
    let ItemKind::Function(f) = &shader.items[1].kind else { panic!("no function") };
    let StmtKind::Expr(e) = &f.body.stmts[0].kind else { panic!("not an expression statement") };
    e.clone()
}

/// Writes an expression back with full parentheses, to make precedence visible.
fn show(e: &ast::Expr) -> String {
    match &e.kind {
        ExprKind::Ident(i) => i.name.clone(),
        ExprKind::IntLit(v) => v.to_string(),
        ExprKind::FloatLit(v) => format!("{v:?}"),
        ExprKind::Binary { op, lhs, rhs } => {
            format!("({} {} {})", show(lhs), op.symbol(), show(rhs))
        }
        ExprKind::Assign { op, target, value } => {
            format!("({} {}= {})", show(target), op.map_or("", BinaryOp::symbol), show(value))
        }
        ExprKind::Ternary { cond, then, otherwise } => {
            format!("({} ? {} : {})", show(cond), show(then), show(otherwise))
        }
        ExprKind::Unary { operand, .. } => format!("(-{})", show(operand)),
        ExprKind::IncDec { op, target } => match (op.prefix, op.increment) {
            (true, true) => format!("(++{})", show(target)),
            (false, true) => format!("({}++)", show(target)),
            (true, false) => format!("(--{})", show(target)),
            (false, false) => format!("({}--)", show(target)),
        },
        ExprKind::Call { callee, args } => {
            format!("{}({})", callee.name, args.iter().map(show).collect::<Vec<_>>().join(", "))
        }
        ExprKind::Member { base, name } => format!("{}.{}", show(base), name.name),
        ExprKind::Index { base, index } => format!("{}[{}]", show(base), show(index)),
        other => format!("{other:?}"),
    }
}

#[test]
fn precedence_follows_glsl() {
    assert_eq!(show(&expr_of("a + b * c - d")), "((a + (b * c)) - d)");
    assert_eq!(show(&expr_of("a << 1 + b")), "(a << (1 + b))");
    assert_eq!(show(&expr_of("a & b | c ^ d")), "((a & b) | (c ^ d))");
    assert_eq!(show(&expr_of("a || b && c == d < e")), "(a || (b && (c == (d < e))))");
    assert_eq!(show(&expr_of("x = a ? b : c ? d : e")), "(x = (a ? b : (c ? d : e)))");
    assert_eq!(show(&expr_of("x += y = z")), "(x += (y = z))");
    assert_eq!(show(&expr_of("-a.x++ * b[i]")), "((-(a.x++)) * b[i])");
    assert_eq!(show(&expr_of("f(seed++, --k)")), "f((seed++), (--k))");
    assert_eq!(show(&expr_of("a - -b")), "(a - (-b))");
}

#[test]
fn number_literals_follow_godot() {
    let ok = |s: &str| parse_number_kind(s).unwrap_or_else(|e| panic!("{s}: {e}"));
    assert!(matches!(ok("0x1F"), ExprKind::IntLit(31)));
    assert!(matches!(ok("0xFFu"), ExprKind::UIntLit(255)));
    assert!(matches!(ok("0xFFFFFFFF"), ExprKind::IntLit(u32::MAX)));
    assert!(matches!(ok("7u"), ExprKind::UIntLit(7)));
    for (s, v) in [
        ("1.", 1.0),
        (".5", 0.5),
        ("1e5", 1e5),
        ("5e-6", 5e-6),
        ("2E+3", 2e3),
        ("1.0f", 1.0),
        ("1.f", 1.0),
        ("1e5f", 1e5),
    ] {
        match ok(s) {
            ExprKind::FloatLit(x) => assert_eq!(x, v, "{s}"),
            other => panic!("{s}: {other:?}"),
        }
    }
    for bad in ["2f", "1e", "1e+", "0x1FFFFFFFF", "0x", "1.5u", "4294967296", "3x"] {
        assert!(parse_number_kind(bad).is_err(), "{bad} should be rejected");
    }
}

fn parse_number_kind(s: &str) -> Result<ExprKind, String> {
    build::parse_number(s).map_err(|(m, _)| m)
}

#[test]
fn deep_nesting_is_an_error_not_a_crash() {
    for text in [
        format!("shader_type sky; void sky() {{ float x = {}1.0{}; }}", "(".repeat(20_000), ")".repeat(20_000)),
        format!("shader_type sky; void sky() {}{}", "{".repeat(20_000), "}".repeat(20_000)),
        format!("shader_type sky; void sky() {{ {} COLOR = vec3(1.0); }}", "if (true) ".repeat(20_000)),
        format!(
            "shader_type sky; void sky() {{ float x = {}1.0{}; }}",
            "true ? ".repeat(20_000),
            " : 0.0".repeat(20_000)
        ),
    ] {
        let (_, diags) = parse(&text);
        assert_eq!(diags.len(), 1, "{diags:?}");
        assert_eq!(diags[0].diagnostic.code, codes::NESTING_LIMIT);
    }
}

#[test]
fn long_flat_chains_are_bounded_without_recursion() {
    // 200,000 terms: parsed iteratively, refused as too deep, dropped without recursion.
    let text = format!("shader_type sky; void sky() {{ float x = 1.0{}; }}", " + 1.0".repeat(200_000));
    let (_, diags) = parse(&text);
    assert_eq!(diags.len(), 1, "{diags:?}");
    assert_eq!(diags[0].diagnostic.code, codes::NESTING_LIMIT);
    let text = format!("shader_type sky; void sky() {{ float x = {}1.0; }}", "- ".repeat(200_000));
    let (_, diags) = parse(&text);
    assert_eq!(diags[0].diagnostic.code, codes::NESTING_LIMIT);
    // A long else-if chain is flat in the tree and fine.
    let text = format!("shader_type sky; void sky() {{ if (true) {{}} {} }}", "else if (true) {} ".repeat(10_000));
    let (_, diags) = parse(&text);
    assert!(diags.is_empty(), "{diags:?}");
}

#[test]
fn doc_comments_attach_to_the_next_uniform_only() {
    let text = "shader_type sky;\n/** Sun.\n * Bright. */\nuniform float a;\n/** Group doc. */\ngroup_uniforms G;\nuniform float b;\n/** Last. */ uniform float c;";
    let (shader, diags) = parse(text);
    assert!(diags.is_empty());
    let docs: Vec<Option<String>> = shader
        .items
        .iter()
        .filter_map(|i| match &i.kind {
            ItemKind::Uniform(u) => Some(u.doc.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(docs, vec![Some("Sun.\nBright.".into()), None, Some("Last.".into())]);
}
