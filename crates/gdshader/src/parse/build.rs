//! pest pairs → AST, one function per grammar rule.

use super::ast::*;
use super::{MAX_EXPR_DEPTH, Rule, SpannedDiagnostic};
use crate::diag::codes;
use pest::iterators::Pair;

type P<'i> = Pair<'i, Rule>;

struct Builder<'a> {
    text: &'a str,
    doc_comments: &'a [(usize, usize)],
    diags: &'a mut Vec<SpannedDiagnostic>,
    next_id: u32,
    group: Vec<String>,
}

/// Builds the shader from the `shader` pair.
pub fn build_shader(
    root: P<'_>,
    text: &str,
    doc_comments: &[(usize, usize)],
    diags: &mut Vec<SpannedDiagnostic>,
) -> Shader {
    let mut b = Builder { text, doc_comments, diags, next_id: 0, group: Vec::new() };
    let mut items = Vec::new();
    for pair in root.into_inner() {
        if pair.as_rule() == Rule::EOI {
            continue;
        }
        items.push(b.item(pair));
    }
    Shader { items, expr_count: b.next_id, eof: Span::new(text.len(), text.len()) }
}

fn span_of(pair: &P<'_>) -> Span {
    let s = pair.as_span();
    Span::new(s.start(), s.end())
}

fn is_keyword(rule: Rule) -> bool {
    use Rule::*;
    matches!(
        rule,
        kw_shader_type
            | kw_render_mode
            | kw_group_uniforms
            | kw_uniform
            | kw_global
            | kw_instance
            | kw_struct
            | kw_const
            | kw_void
            | kw_inout
            | kw_in
            | kw_out
            | kw_lowp
            | kw_mediump
            | kw_highp
            | kw_if
            | kw_else
            | kw_for
            | kw_while
            | kw_do
            | kw_switch
            | kw_case
            | kw_default
            | kw_break
            | kw_continue
            | kw_return
            | kw_discard
    )
}

/// The pair's children, without keyword tokens (their presence is implied by the rule).
fn children<'i>(pair: P<'i>) -> impl Iterator<Item = P<'i>> {
    pair.into_inner().filter(|p| !is_keyword(p.as_rule()))
}

fn ident(pair: P<'_>) -> Ident {
    Ident { name: pair.as_str().to_string(), span: span_of(&pair) }
}

fn precision(pair: &P<'_>) -> Precision {
    match pair.as_str() {
        "lowp" => Precision::Low,
        "mediump" => Precision::Medium,
        _ => Precision::High,
    }
}

impl Builder<'_> {
    fn id(&mut self) -> ExprId {
        let id = ExprId(self.next_id);
        self.next_id += 1;
        id
    }

    fn mk(&mut self, kind: ExprKind, span: Span) -> Expr {
        Expr { id: self.id(), kind, span }
    }

    fn item(&mut self, pair: P<'_>) -> Item {
        let span = span_of(&pair);
        let kind = match pair.as_rule() {
            Rule::shader_type_decl => {
                ItemKind::ShaderType(children(pair).next().map(ident).unwrap_or_else(|| missing_ident(span)))
            }
            Rule::render_mode_decl => ItemKind::RenderMode(children(pair).map(ident).collect()),
            Rule::group_uniforms_decl => {
                let path: Vec<Ident> = children(pair).flat_map(|p| p.into_inner().map(ident)).collect();
                self.group = path.iter().map(|i| i.name.clone()).collect();
                ItemKind::GroupUniforms(path)
            }
            Rule::uniform_decl => ItemKind::Uniform(Box::new(self.uniform(pair, span))),
            Rule::struct_decl => ItemKind::Struct(self.struct_decl(pair)),
            Rule::global_const_decl => ItemKind::Const(self.var_decl(pair, true)),
            Rule::global_var_decl => ItemKind::GlobalVar(self.var_decl(pair, false)),
            Rule::function_def => ItemKind::Function(Box::new(self.function(pair))),
            _ => ItemKind::Empty,
        };
        Item { kind, span }
    }

    fn doc_before(&self, start: usize) -> Option<String> {
        let idx = self.doc_comments.partition_point(|&(_, end)| end <= start);
        let &(s, e) = self.doc_comments.get(idx.checked_sub(1)?)?;
        if !self.text.get(e..start)?.trim().is_empty() {
            return None;
        }
        Some(clean_doc(self.text.get(s..e)?))
    }

    fn uniform(&mut self, pair: P<'_>, span: Span) -> Uniform {
        let doc = self.doc_before(span.start as usize);
        let mut scope = None;
        let mut precision_q = None;
        let mut ty = None;
        let mut name = None;
        let mut array = None;
        let mut hints = Vec::new();
        let mut default = None;
        for p in children(pair) {
            match p.as_rule() {
                Rule::uniform_scope => {
                    scope = Some(if p.as_str().starts_with("global") {
                        UniformScope::Global
                    } else {
                        UniformScope::Instance
                    })
                }
                Rule::precision => precision_q = Some(precision(&p)),
                Rule::type_ref => ty = Some(self.type_ref(p, precision_q)),
                Rule::ident => name = Some(ident(p)),
                Rule::array_size => array = Some(self.array_size(p)),
                Rule::hint => hints.push(self.hint(p)),
                Rule::expr => default = Some(self.expr(p)),
                _ => {}
            }
        }
        Uniform {
            scope,
            ty: ty.unwrap_or_else(|| missing_type(span)),
            name: name.unwrap_or_else(|| missing_ident(span)),
            array,
            hints,
            default,
            doc,
            group: self.group.clone(),
        }
    }

    fn hint(&mut self, pair: P<'_>) -> Hint {
        let span = span_of(&pair);
        let mut inner = pair.into_inner();
        let name = inner.next().map(ident).unwrap_or_else(|| missing_ident(span));
        let args = inner
            .map(|p| match p.as_rule() {
                Rule::string => {
                    let s = p.as_str();
                    HintArg::Str(s.get(1..s.len().saturating_sub(1)).unwrap_or("").to_string(), span_of(&p))
                }
                _ => HintArg::Expr(self.expr(p)),
            })
            .collect();
        Hint { name, args, span }
    }

    fn struct_decl(&mut self, pair: P<'_>) -> StructDecl {
        let span = span_of(&pair);
        let mut inner = children(pair);
        let name = inner.next().map(ident).unwrap_or_else(|| missing_ident(span));
        let mut members = Vec::new();
        for m in inner {
            let mut precision_q = None;
            let mut ty = None;
            for p in m.into_inner() {
                match p.as_rule() {
                    Rule::precision => precision_q = Some(precision(&p)),
                    Rule::type_ref => ty = Some(self.type_ref(p, precision_q)),
                    Rule::declarator_name => {
                        let mut d = p.into_inner();
                        let name = d.next().map(ident).unwrap_or_else(|| missing_ident(span));
                        let array = d.next().map(|a| self.array_size(a));
                        members.push(StructMember {
                            ty: ty.clone().unwrap_or_else(|| missing_type(span)),
                            name,
                            array,
                        });
                    }
                    _ => {}
                }
            }
        }
        StructDecl { name, members }
    }

    fn var_decl(&mut self, pair: P<'_>, is_const: bool) -> VarDecl {
        let span = span_of(&pair);
        let mut precision_q = None;
        let mut ty = None;
        let mut declarators = Vec::new();
        for p in children(pair) {
            match p.as_rule() {
                Rule::precision => precision_q = Some(precision(&p)),
                Rule::type_ref => ty = Some(self.type_ref(p, precision_q)),
                Rule::declarator => declarators.push(self.declarator(p)),
                _ => {}
            }
        }
        VarDecl { is_const, ty: ty.unwrap_or_else(|| missing_type(span)), declarators }
    }

    fn declarator(&mut self, pair: P<'_>) -> Declarator {
        let span = span_of(&pair);
        let mut name = None;
        let mut array = None;
        let mut init = None;
        for p in pair.into_inner() {
            match p.as_rule() {
                Rule::ident => name = Some(ident(p)),
                Rule::array_size => array = Some(self.array_size(p)),
                Rule::expr => init = Some(self.expr(p)),
                _ => {}
            }
        }
        Declarator { name: name.unwrap_or_else(|| missing_ident(span)), array, init, span }
    }

    fn type_ref(&mut self, pair: P<'_>, precision: Option<Precision>) -> TypeRef {
        let span = span_of(&pair);
        let mut inner = pair.into_inner();
        let name = inner.next().map(ident).unwrap_or_else(|| missing_ident(span));
        let array = inner.next().map(|a| self.array_size(a));
        TypeRef { precision, name, array, span }
    }

    fn array_size(&mut self, pair: P<'_>) -> ArraySize {
        let span = span_of(&pair);
        let size = pair.into_inner().next().map(|e| Box::new(self.expr(e)));
        ArraySize { size, span }
    }

    fn function(&mut self, pair: P<'_>) -> Function {
        let span = span_of(&pair);
        let mut precision_q = None;
        let mut return_type = None;
        let mut name = None;
        let mut params = Vec::new();
        let mut params_span = span;
        let mut body = None;
        for p in children(pair) {
            match p.as_rule() {
                Rule::precision => precision_q = Some(precision(&p)),
                Rule::type_ref => return_type = Some(self.type_ref(p, precision_q)),
                Rule::ident => name = Some(ident(p)),
                Rule::params => {
                    let s = span_of(&p);
                    // Widen to the parentheses around the list.
                    params_span = Span::new((s.start as usize).saturating_sub(1), s.end as usize + 1);
                    for param in children(p) {
                        params.push(self.param(param));
                    }
                }
                Rule::block => body = Some(self.block(p)),
                _ => {}
            }
        }
        Function {
            return_type: return_type.unwrap_or_else(|| missing_type(span)),
            name: name.unwrap_or_else(|| missing_ident(span)),
            params,
            body: body.unwrap_or(Block { stmts: Vec::new(), span }),
            params_span,
        }
    }

    fn param(&mut self, pair: P<'_>) -> Param {
        let span = span_of(&pair);
        let mut qualifier = ParamQualifier::In;
        let mut precision_q = None;
        let mut ty = None;
        let mut name = None;
        let mut array = None;
        for p in pair.into_inner() {
            match p.as_rule() {
                Rule::param_qualifier => {
                    qualifier = match p.as_str().split_whitespace().next() {
                        Some("inout") => ParamQualifier::InOut,
                        Some("out") => ParamQualifier::Out,
                        Some("const") => ParamQualifier::Const,
                        _ => ParamQualifier::In,
                    }
                }
                Rule::precision => precision_q = Some(precision(&p)),
                Rule::type_ref => ty = Some(self.type_ref(p, precision_q)),
                Rule::ident => name = Some(ident(p)),
                Rule::array_size => array = Some(self.array_size(p)),
                _ => {}
            }
        }
        Param {
            qualifier,
            ty: ty.unwrap_or_else(|| missing_type(span)),
            name: name.unwrap_or_else(|| missing_ident(span)),
            array,
            span,
        }
    }

    fn block(&mut self, pair: P<'_>) -> Block {
        let span = span_of(&pair);
        let stmts = pair.into_inner().map(|s| self.stmt(s)).collect();
        Block { stmts, span }
    }

    fn stmt(&mut self, pair: P<'_>) -> Stmt {
        let span = span_of(&pair);
        let kind = match pair.as_rule() {
            Rule::block => StmtKind::Block(self.block(pair)),
            Rule::if_stmt => {
                let mut branches = Vec::new();
                let mut otherwise = None;
                let mut inner = children(pair);
                if let (Some(c), Some(s)) = (inner.next(), inner.next()) {
                    let cond = self.expr(c);
                    branches.push((cond, self.stmt(s)));
                }
                for p in inner {
                    match p.as_rule() {
                        Rule::else_if => {
                            let mut e = children(p);
                            if let (Some(c), Some(s)) = (e.next(), e.next()) {
                                let cond = self.expr(c);
                                branches.push((cond, self.stmt(s)));
                            }
                        }
                        _ => {
                            if let Some(s) = children(p).next() {
                                otherwise = Some(Box::new(self.stmt(s)));
                            }
                        }
                    }
                }
                StmtKind::If { branches, otherwise }
            }
            Rule::for_stmt => {
                let mut init = None;
                let mut cond = None;
                let mut step = Vec::new();
                let mut body = None;
                for p in children(pair) {
                    match p.as_rule() {
                        Rule::for_init => init = p.into_inner().next().map(|s| Box::new(self.stmt(s))),
                        Rule::for_cond => cond = p.into_inner().next().map(|e| self.expr(e)),
                        Rule::for_step => step = p.into_inner().map(|e| self.expr(e)).collect(),
                        _ => body = Some(Box::new(self.stmt(p))),
                    }
                }
                StmtKind::For { init, cond, step, body: body.unwrap_or_else(|| empty_stmt(span)) }
            }
            Rule::while_stmt => {
                let mut inner = children(pair);
                let cond = self.expr_or_error(inner.next(), span);
                let body = inner.next().map(|s| Box::new(self.stmt(s))).unwrap_or_else(|| empty_stmt(span));
                StmtKind::While { cond, body }
            }
            Rule::do_stmt => {
                let mut inner = children(pair);
                let body = inner.next().map(|s| Box::new(self.stmt(s))).unwrap_or_else(|| empty_stmt(span));
                let cond = self.expr_or_error(inner.next(), span);
                StmtKind::DoWhile { body, cond }
            }
            Rule::switch_stmt => {
                let mut inner = children(pair);
                let selector = self.expr_or_error(inner.next(), span);
                let cases = inner.map(|c| self.switch_case(c)).collect();
                StmtKind::Switch { selector, cases }
            }
            Rule::break_stmt => StmtKind::Break,
            Rule::continue_stmt => StmtKind::Continue,
            Rule::return_stmt => StmtKind::Return(children(pair).next().map(|e| self.expr(e))),
            Rule::discard_stmt => StmtKind::Discard,
            Rule::local_const_decl => StmtKind::VarDecl(self.var_decl(pair, true)),
            Rule::local_var_decl => StmtKind::VarDecl(self.var_decl(pair, false)),
            Rule::expr_stmt => StmtKind::Expr(self.expr_or_error(pair.into_inner().next(), span)),
            _ => StmtKind::Empty,
        };
        Stmt { kind, span }
    }

    fn switch_case(&mut self, pair: P<'_>) -> SwitchCase {
        let mut inner = pair.into_inner();
        let mut value = None;
        let mut label_span = Span::default();
        if let Some(label) = inner.next() {
            label_span = span_of(&label);
            value = children(label).next().map(|e| self.expr(e));
        }
        let body = inner.map(|s| self.stmt(s)).collect();
        SwitchCase { value, label_span, body }
    }

    fn expr_or_error(&mut self, pair: Option<P<'_>>, span: Span) -> Expr {
        match pair {
            Some(p) => self.expr(p),
            None => self.mk(ExprKind::Error, span),
        }
    }

    fn expr(&mut self, pair: P<'_>) -> Expr {
        self.expr_depth(pair).0
    }

    /// `expr`: operands and infix operators, folded by precedence with explicit stacks.
    fn expr_depth(&mut self, pair: P<'_>) -> (Expr, usize) {
        let mut operands: Vec<(Expr, usize)> = Vec::new();
        let mut ops: Vec<(Infix, Span)> = Vec::new();
        let mut too_deep = false;
        for p in pair.into_inner() {
            match p.as_rule() {
                Rule::operand => operands.push(self.operand(p)),
                Rule::infix_op | Rule::ternary_mid => {
                    let span = span_of(&p);
                    let op = if p.as_rule() == Rule::ternary_mid {
                        let mid = p.into_inner().next().map(|m| self.expr_depth(m));
                        Infix::Ternary(mid.map(Box::new))
                    } else {
                        infix_from(p.as_str())
                    };
                    let (prec, right) = op.precedence();
                    while let Some((top, _)) = ops.last() {
                        let (top_prec, _) = top.precedence();
                        if top_prec > prec || (top_prec == prec && !right) {
                            self.reduce(&mut operands, &mut ops, &mut too_deep);
                        } else {
                            break;
                        }
                    }
                    ops.push((op, span));
                }
                _ => {}
            }
        }
        while !ops.is_empty() {
            self.reduce(&mut operands, &mut ops, &mut too_deep);
        }
        match operands.pop() {
            Some(e) => e,
            None => {
                let span = Span::default();
                (self.mk(ExprKind::Error, span), 1)
            }
        }
    }

    fn reduce(&mut self, operands: &mut Vec<(Expr, usize)>, ops: &mut Vec<(Infix, Span)>, too_deep: &mut bool) {
        let Some((op, op_span)) = ops.pop() else {
            return;
        };
        let Some((rhs, rd)) = operands.pop() else {
            return;
        };
        let Some((lhs, ld)) = operands.pop() else {
            operands.push((rhs, rd));
            return;
        };
        let span = lhs.span.to(rhs.span);
        let mut depth = 1 + ld.max(rd);
        let kind = match op {
            Infix::Binary(op) => ExprKind::Binary { op, lhs: Box::new(lhs), rhs: Box::new(rhs) },
            Infix::Assign(op) => ExprKind::Assign { op, target: Box::new(lhs), value: Box::new(rhs) },
            Infix::Ternary(mid) => {
                let (then, md) = match mid {
                    Some(m) => *m,
                    None => (self.mk(ExprKind::Error, op_span), 1),
                };
                depth = depth.max(1 + md);
                ExprKind::Ternary { cond: Box::new(lhs), then: Box::new(then), otherwise: Box::new(rhs) }
            }
        };
        let e = self.mk(kind, span);
        operands.push(self.limit_depth(e, depth, too_deep));
    }

    /// Replaces a tree deeper than [`MAX_EXPR_DEPTH`] by an error node (reported once per
    /// expression), so nothing downstream recurses that deep.
    fn limit_depth(&mut self, e: Expr, depth: usize, too_deep: &mut bool) -> (Expr, usize) {
        if depth <= MAX_EXPR_DEPTH {
            return (e, depth);
        }
        if !*too_deep {
            *too_deep = true;
            self.diags.push(
                SpannedDiagnostic::error(
                    codes::NESTING_LIMIT,
                    format!("expression is nested more than {MAX_EXPR_DEPTH} operators deep"),
                    e.span,
                    "too deep",
                )
                .note("split it into several statements with local variables"),
            );
        }
        let span = e.span;
        drop_iteratively(e);
        (self.mk(ExprKind::Error, span), 1)
    }

    /// `operand`: prefix operators, a primary, postfix operators.
    fn operand(&mut self, pair: P<'_>) -> (Expr, usize) {
        let mut prefixes = Vec::new();
        let mut current: Option<(Expr, usize)> = None;
        let mut too_deep = false;
        for p in pair.into_inner() {
            let span = span_of(&p);
            match p.as_rule() {
                Rule::prefix_op => prefixes.push((p.as_str().to_string(), span)),
                Rule::post_inc | Rule::post_dec | Rule::member | Rule::method_call | Rule::index => {
                    let Some((base, depth)) = current.take() else {
                        continue;
                    };
                    let full = base.span.to(span);
                    let (kind, extra) = match p.as_rule() {
                        Rule::post_inc | Rule::post_dec => {
                            let op = IncDec { increment: p.as_rule() == Rule::post_inc, prefix: false };
                            (ExprKind::IncDec { op, target: Box::new(base) }, 0)
                        }
                        Rule::member => {
                            let name = p.into_inner().next().map(ident).unwrap_or_else(|| missing_ident(span));
                            (ExprKind::Member { base: Box::new(base), name }, 0)
                        }
                        Rule::method_call => {
                            let mut inner = p.into_inner();
                            let name = inner.next().map(ident).unwrap_or_else(|| missing_ident(span));
                            let (args, ad) = inner.next().map(|a| self.args(a)).unwrap_or_default();
                            (ExprKind::MethodCall { base: Box::new(base), name, args }, ad)
                        }
                        _ => {
                            let (index, id) = match p.into_inner().next() {
                                Some(e) => self.expr_depth(e),
                                None => (self.mk(ExprKind::Error, span), 1),
                            };
                            (ExprKind::Index { base: Box::new(base), index: Box::new(index) }, id)
                        }
                    };
                    let e = self.mk(kind, full);
                    current = Some(self.limit_depth(e, 1 + depth.max(extra), &mut too_deep));
                }
                _ => current = Some(self.primary(p)),
            }
        }
        let Some(mut current) = current else {
            let span = Span::default();
            return (self.mk(ExprKind::Error, span), 1);
        };
        for (op, span) in prefixes.into_iter().rev() {
            let (operand, depth) = current;
            let full = span.to(operand.span);
            let kind = match op.as_str() {
                "++" | "--" => {
                    ExprKind::IncDec { op: IncDec { increment: op == "++", prefix: true }, target: Box::new(operand) }
                }
                "-" => ExprKind::Unary { op: UnaryOp::Neg, operand: Box::new(operand) },
                "+" => ExprKind::Unary { op: UnaryOp::Plus, operand: Box::new(operand) },
                "!" => ExprKind::Unary { op: UnaryOp::Not, operand: Box::new(operand) },
                _ => ExprKind::Unary { op: UnaryOp::BitNot, operand: Box::new(operand) },
            };
            let e = self.mk(kind, full);
            current = self.limit_depth(e, depth + 1, &mut too_deep);
        }
        current
    }

    fn args(&mut self, pair: P<'_>) -> (Vec<Expr>, usize) {
        let mut depth = 0;
        let args = children(pair)
            .map(|a| {
                let (e, d) = self.expr_depth(a);
                depth = depth.max(d);
                e
            })
            .collect();
        (args, depth)
    }

    fn primary(&mut self, pair: P<'_>) -> (Expr, usize) {
        let span = span_of(&pair);
        match pair.as_rule() {
            Rule::number => {
                let kind = match parse_number(pair.as_str()) {
                    Ok(kind) => kind,
                    Err((message, note)) => {
                        self.diags.push(
                            SpannedDiagnostic::error(codes::BAD_LITERAL, message, span, "invalid number").note(note),
                        );
                        ExprKind::Error
                    }
                };
                (self.mk(kind, span), 1)
            }
            Rule::bool_lit => (self.mk(ExprKind::BoolLit(pair.as_str() == "true"), span), 1),
            Rule::paren => match pair.into_inner().next() {
                Some(e) => self.expr_depth(e),
                None => (self.mk(ExprKind::Error, span), 1),
            },
            Rule::init_list => {
                let (args, d) = pair.into_inner().next().map(|a| self.args(a)).unwrap_or_default();
                (self.mk(ExprKind::InitList(args), span), d + 1)
            }
            Rule::named => {
                let mut inner = pair.into_inner();
                let Some(name) = inner.next().map(ident) else {
                    return (self.mk(ExprKind::Error, span), 1);
                };
                match inner.next() {
                    // The pair's span may run on over the space where a call was looked for.
                    None => {
                        let span = name.span;
                        (self.mk(ExprKind::Ident(name), span), 1)
                    }
                    Some(tail) if tail.as_rule() == Rule::call_tail => {
                        let (args, d) = tail.into_inner().next().map(|a| self.args(a)).unwrap_or_default();
                        (self.mk(ExprKind::Call { callee: name, args }, span), d + 1)
                    }
                    Some(tail) => {
                        let mut size = None;
                        let mut args = (Vec::new(), 0);
                        for p in tail.into_inner() {
                            match p.as_rule() {
                                Rule::expr => size = Some(Box::new(self.expr(p))),
                                Rule::args => args = self.args(p),
                                _ => {}
                            }
                        }
                        let kind = ExprKind::ArrayCtor { elem: name, size, args: args.0 };
                        (self.mk(kind, span), args.1 + 1)
                    }
                }
            }
            _ => (self.mk(ExprKind::Error, span), 1),
        }
    }
}

/// An infix operator waiting on the operator stack.
enum Infix {
    Binary(BinaryOp),
    Assign(Option<BinaryOp>),
    Ternary(Option<Box<(Expr, usize)>>),
}

impl Infix {
    /// Binding power (higher binds tighter) and right-associativity, as in GLSL ES 3.0 §5.1.
    fn precedence(&self) -> (u8, bool) {
        use BinaryOp::*;
        match self {
            Infix::Assign(_) => (0, true),
            Infix::Ternary(_) => (1, true),
            Infix::Binary(op) => match op {
                LogicalOr => (2, false),
                LogicalAnd => (4, false),
                BitOr => (5, false),
                BitXor => (6, false),
                BitAnd => (7, false),
                Eq | NotEq => (8, false),
                Less | Greater | LessEq | GreaterEq => (9, false),
                Shl | Shr => (10, false),
                Add | Sub => (11, false),
                Mul | Div | Rem => (12, false),
            },
        }
    }
}

fn infix_from(s: &str) -> Infix {
    use BinaryOp::*;
    let bin = |s: &str| match s {
        "*" => Mul,
        "/" => Div,
        "%" => Rem,
        "+" => Add,
        "-" => Sub,
        "<<" => Shl,
        ">>" => Shr,
        "<" => Less,
        ">" => Greater,
        "<=" => LessEq,
        ">=" => GreaterEq,
        "==" => Eq,
        "!=" => NotEq,
        "&" => BitAnd,
        "^" => BitXor,
        "|" => BitOr,
        "&&" => LogicalAnd,
        _ => LogicalOr,
    };
    match s {
        "=" => Infix::Assign(None),
        "<=" | ">=" | "==" | "!=" => Infix::Binary(bin(s)),
        _ if s.len() >= 2 && s.ends_with('=') => Infix::Assign(Some(bin(&s[..s.len() - 1]))),
        _ => Infix::Binary(bin(s)),
    }
}

/// Drops a tree without recursing (a too-deep tree would overflow the stack in `Drop`).
fn drop_iteratively(e: Expr) {
    let mut stack = vec![e];
    while let Some(e) = stack.pop() {
        match e.kind {
            ExprKind::Binary { lhs, rhs, .. } => stack.extend([*lhs, *rhs]),
            ExprKind::Assign { target, value, .. } => stack.extend([*target, *value]),
            ExprKind::Ternary { cond, then, otherwise } => stack.extend([*cond, *then, *otherwise]),
            ExprKind::Unary { operand, .. } => stack.push(*operand),
            ExprKind::IncDec { target, .. } => stack.push(*target),
            ExprKind::Member { base, .. } => stack.push(*base),
            ExprKind::Index { base, index } => stack.extend([*base, *index]),
            ExprKind::MethodCall { base, args, .. } => {
                stack.push(*base);
                stack.extend(args);
            }
            ExprKind::Call { args, .. } | ExprKind::InitList(args) | ExprKind::ArrayCtor { args, .. } => {
                stack.extend(args)
            }
            _ => {}
        }
    }
}

fn missing_ident(span: Span) -> Ident {
    Ident { name: String::new(), span }
}

fn missing_type(span: Span) -> TypeRef {
    TypeRef { precision: None, name: missing_ident(span), array: None, span }
}

fn empty_stmt(span: Span) -> Box<Stmt> {
    Box::new(Stmt { kind: StmtKind::Empty, span })
}

/// Strips `/**`, `*/` and leading `*` decoration from a doc comment.
fn clean_doc(raw: &str) -> String {
    let inner = raw.strip_prefix("/**").unwrap_or(raw);
    let inner = inner.strip_suffix("*/").unwrap_or(inner);
    let lines: Vec<&str> = inner
        .lines()
        .map(|l| {
            let t = l.trim();
            t.strip_prefix('*').map(str::trim_start).unwrap_or(t)
        })
        .collect();
    let first = lines.iter().position(|l| !l.is_empty()).unwrap_or(lines.len());
    let last = lines.iter().rposition(|l| !l.is_empty()).map_or(first, |i| i + 1);
    lines[first..last.max(first)].join("\n")
}

/// Validates a number token (lexed greedily by the grammar) into a literal, with Godot's rules
/// (reference §3): hex ints up to 0xFFFFFFFF, `u` for uint, a float needs `.` or an exponent,
/// and `f` is only allowed on a float.
pub(crate) fn parse_number(s: &str) -> Result<ExprKind, (String, String)> {
    let err = |m: String, n: &str| Err((m, n.to_string()));
    if let Some(hex) = s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        let (digits, unsigned) = match hex.strip_suffix(['u', 'U']) {
            Some(d) => (d, true),
            None => (hex, false),
        };
        if digits.is_empty() || !digits.chars().all(|c| c.is_ascii_hexdigit()) {
            return err(
                format!("invalid hexadecimal literal `{s}`"),
                "a hex literal is `0x` followed by hex digits, optionally with a `u` suffix",
            );
        }
        let trimmed = digits.trim_start_matches('0');
        if trimmed.len() > 8 {
            return err(format!("hexadecimal literal `{s}` does not fit in 32 bits"), "the largest is 0xFFFFFFFF");
        }
        let value = u32::from_str_radix(if trimmed.is_empty() { "0" } else { trimmed }, 16).unwrap_or(u32::MAX);
        return Ok(if unsigned { ExprKind::UIntLit(value) } else { ExprKind::IntLit(value) });
    }
    let b = s.as_bytes();
    let mut i = 0;
    let digits = |i: &mut usize| {
        let start = *i;
        while *i < b.len() && b[*i].is_ascii_digit() {
            *i += 1;
        }
        *i - start
    };
    let int_digits = digits(&mut i);
    let mut has_dot = false;
    let mut frac_digits = 0;
    if i < b.len() && b[i] == b'.' {
        has_dot = true;
        i += 1;
        frac_digits = digits(&mut i);
    }
    if int_digits == 0 && frac_digits == 0 {
        return err(format!("invalid number `{s}`"), "a number needs at least one digit");
    }
    let mut has_exp = false;
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        has_exp = true;
        i += 1;
        if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
            i += 1;
        }
        if digits(&mut i) == 0 {
            return err(
                format!("the exponent of `{s}` has no digits"),
                "an exponent is written like `1e5`, `5e-6` or `2E+3`",
            );
        }
    }
    let body = &s[..i];
    let suffix = &s[i..];
    let is_float = has_dot || has_exp;
    match suffix {
        "" | "f" | "F" if is_float => match body.parse::<f64>() {
            Ok(v) => Ok(ExprKind::FloatLit(v)),
            Err(_) => err(format!("invalid float literal `{s}`"), "write a float like `1.0`, `.5` or `1e5`"),
        },
        "f" | "F" => err(
            format!("the `f` suffix needs a decimal point or an exponent: `{s}`"),
            "write `2.0` or `2.0f` for a float; Godot rejects `2f`",
        ),
        "" | "u" | "U" if !is_float => match body.parse::<u64>() {
            Ok(v) if v <= u64::from(u32::MAX) => {
                Ok(if suffix.is_empty() { ExprKind::IntLit(v as u32) } else { ExprKind::UIntLit(v as u32) })
            }
            _ => err(format!("integer literal `{s}` does not fit in 32 bits"), "the largest is 4294967295"),
        },
        "u" | "U" => err(
            format!("a float literal cannot have the `u` suffix: `{s}`"),
            "`u` makes an integer unsigned, as in `1u`",
        ),
        _ => err(
            format!("invalid suffix `{suffix}` on number `{s}`"),
            "numbers take `u` (unsigned int) or `f` (float) as a suffix",
        ),
    }
}
