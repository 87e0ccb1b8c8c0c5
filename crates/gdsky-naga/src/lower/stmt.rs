//! Statements: declarations, control flow, `return`.
//!
//! naga has structured control flow only (`If`, `Loop` with a `continuing` block, `Switch`), so
//! GLSL's loops become `loop { if (!cond) { break; } body; continuing { step } }`, and a
//! `switch` case that falls through gets the code of the cases it falls into (WGSL cannot fall
//! through a non-empty case).

use super::builder::FnBuilder;
use super::expr::FnCtx;
use super::fold::Value;
use super::span;
use gdshader::parse::ast::{self, Stmt, StmtKind};
use naga::{Block, Expression as E, Literal, Statement, SwitchCase, SwitchValue, UnaryOperator};

impl FnCtx<'_, '_> {
    /// Lowers statements in a new scope. Statements after a `return`, `break`, `continue` or
    /// `discard` can never run; they are left out (no statement follows a terminator in a naga
    /// block).
    pub fn block(&mut self, b: &mut FnBuilder, stmts: &[Stmt]) {
        self.push_scope();
        for s in stmts {
            self.stmt(b, s);
            if matches!(s.kind, StmtKind::Return(_) | StmtKind::Break | StmtKind::Continue | StmtKind::Discard) {
                break;
            }
        }
        self.pop_scope();
    }

    /// A nested naga block holding `stmts`.
    fn nested(&mut self, b: &mut FnBuilder, stmts: &[Stmt]) -> Block {
        b.open();
        self.block(b, stmts);
        b.close()
    }

    fn stmt_as_slice(s: &Stmt) -> &[Stmt] {
        match &s.kind {
            StmtKind::Block(inner) => &inner.stmts,
            _ => std::slice::from_ref(s),
        }
    }

    /// `if (!cond) { break; }` at the top of a loop body.
    fn break_unless(&mut self, b: &mut FnBuilder, cond: &ast::Expr) {
        let sp = span(cond.span);
        let Some(c) = self.value(b, cond) else { return };
        let not = b.expr(E::Unary { op: UnaryOperator::LogicalNot, expr: c }, sp);
        b.open();
        b.stmt(Statement::Break, sp);
        let accept = b.close();
        b.stmt(Statement::If { condition: not, accept, reject: Block::new() }, sp);
    }

    pub fn stmt(&mut self, b: &mut FnBuilder, s: &Stmt) {
        let sp = span(s.span);
        match &s.kind {
            StmtKind::Block(inner) => {
                let block = self.nested(b, &inner.stmts);
                b.stmt(Statement::Block(block), sp);
            }
            StmtKind::VarDecl(decl) => {
                for d in &decl.declarators {
                    let Some(ty) = self.lw.declared(d.name.span) else {
                        continue;
                    };
                    // A failed initializer (already reported) still declares the name, so its
                    // uses are not reported again.
                    let init = d.init.as_ref().and_then(|init| self.initial_value(b, init, &ty));
                    if let Some(v) = init
                        && self.declare_let(b, &d.name, &ty, v)
                    {
                        continue;
                    }
                    let Some(ptr) = self.declare_variable(b, &d.name, &ty) else {
                        continue;
                    };
                    if let Some(v) = init {
                        b.stmt(Statement::Store { pointer: ptr, value: v }, span(d.span));
                    }
                }
            }
            StmtKind::Expr(e) => {
                self.lower(b, e);
            }
            StmtKind::If { branches, otherwise } => self.if_chain(b, branches, otherwise.as_deref()),
            StmtKind::For { init, cond, step, body } => {
                b.open();
                self.push_scope();
                if let Some(i) = init {
                    self.stmt(b, i);
                }
                b.open();
                if let Some(c) = cond {
                    self.break_unless(b, c);
                }
                self.block(b, Self::stmt_as_slice(body));
                let body_block = b.close();
                b.open();
                for st in step {
                    self.lower(b, st);
                }
                let continuing = b.close();
                b.stmt(Statement::Loop { body: body_block, continuing, break_if: None }, sp);
                self.pop_scope();
                let outer = b.close();
                b.stmt(Statement::Block(outer), sp);
            }
            StmtKind::While { cond, body } => {
                b.open();
                self.break_unless(b, cond);
                self.block(b, Self::stmt_as_slice(body));
                let body_block = b.close();
                b.stmt(Statement::Loop { body: body_block, continuing: Block::new(), break_if: None }, sp);
            }
            StmtKind::DoWhile { body, cond } => {
                let body_block = self.nested(b, Self::stmt_as_slice(body));
                b.open();
                let Some(c) = self.value(b, cond) else {
                    b.close();
                    return;
                };
                let not = b.expr(E::Unary { op: UnaryOperator::LogicalNot, expr: c }, span(cond.span));
                let continuing = b.close();
                b.stmt(Statement::Loop { body: body_block, continuing, break_if: Some(not) }, sp);
            }
            StmtKind::Switch { selector, cases } => self.switch(b, s, selector, cases),
            StmtKind::Break => b.stmt(Statement::Break, sp),
            StmtKind::Continue => b.stmt(Statement::Continue, sp),
            StmtKind::Return(value) => {
                let ret = self.return_type().clone();
                let v = match value {
                    Some(e) => match self.initial_value(b, e, &ret) {
                        Some(v) => Some(v),
                        None => return,
                    },
                    None => None,
                };
                b.stmt(Statement::Return { value: v }, sp);
            }
            StmtKind::Discard | StmtKind::Empty => {}
        }
    }

    /// `if … else if … else …`: each condition is evaluated in the `else` block of the one
    /// before, so the chain nests in naga while staying flat (and iterative) here.
    ///
    /// A condition the folder knows (a baked `bool` uniform, a comparison of baked values, a
    /// literal) decides at translation time: a false one drops its branch, a true one makes its
    /// branch the chain's last `else` and drops what follows (specialization, issue #11).
    fn if_chain(&mut self, b: &mut FnBuilder, branches: &[(ast::Expr, Stmt)], otherwise: Option<&Stmt>) {
        let mut pending = Vec::new();
        // Whether the innermost open block is the `else` of the last pending `if`.
        let mut else_open = false;
        let mut tail = otherwise;
        for (cond, body) in branches {
            if !pending.is_empty() && !else_open {
                b.open();
                else_open = true;
            }
            let Some(c) = self.value(b, cond) else { return };
            match b.known(c) {
                Some(Value::Scalar(Literal::Bool(true))) => {
                    tail = Some(body);
                    break;
                }
                Some(Value::Scalar(Literal::Bool(false))) => continue,
                _ => {}
            }
            let accept = self.nested(b, Self::stmt_as_slice(body));
            pending.push((c, accept, span(cond.span)));
            else_open = false;
        }
        if pending.is_empty() {
            if let Some(t) = tail {
                let block = self.nested(b, Self::stmt_as_slice(t));
                b.stmt(Statement::Block(block), span(t.span));
            }
            return;
        }
        let mut reject = match (tail, else_open) {
            (Some(t), true) => {
                self.block(b, Self::stmt_as_slice(t));
                b.close()
            }
            (None, true) => b.close(),
            (Some(t), false) => self.nested(b, Self::stmt_as_slice(t)),
            (None, false) => Block::new(),
        };
        while let Some((condition, accept, sp)) = pending.pop() {
            b.stmt(Statement::If { condition, accept, reject }, sp);
            if pending.is_empty() {
                break;
            }
            reject = b.close();
        }
    }

    fn switch(&mut self, b: &mut FnBuilder, s: &Stmt, selector: &ast::Expr, cases: &[ast::SwitchCase]) {
        let sp = span(s.span);
        let Some(sel) = self.value(b, selector) else {
            return;
        };
        let unsigned = self.type_of(selector) == Some(gdshader::check::types::Type::UINT);
        let mut out = Vec::new();
        for (i, case) in cases.iter().enumerate() {
            let value = match &case.value {
                None => SwitchValue::Default,
                Some(v) => {
                    let Some(n) = case_value(v).or_else(|| self.named_case_value(v)) else {
                        self.lw.error(v.span, "gdsky cannot translate this `case` label yet (only literal values)");
                        return;
                    };
                    if unsigned { SwitchValue::U32(n as u32) } else { SwitchValue::I32(n as i32) }
                }
            };
            if case.body.is_empty() && i + 1 < cases.len() {
                out.push(SwitchCase { value, body: Block::new(), fall_through: true });
                continue;
            }
            // The case's own statements, then those of the cases it falls into, up to the first
            // that ends with `break`, `return` or `continue`.
            let mut stmts: Vec<Stmt> = Vec::new();
            for c in &cases[i..] {
                stmts.extend(c.body.iter().cloned());
                if c.body.last().is_some_and(ends_with_jump) {
                    break;
                }
            }
            let body = self.nested(b, &stmts);
            out.push(SwitchCase { value, body, fall_through: false });
        }
        if !out.iter().any(|c| c.value == SwitchValue::Default) {
            out.push(SwitchCase { value: SwitchValue::Default, body: Block::new(), fall_through: false });
        }
        b.stmt(Statement::Switch { selector: sel, cases: out }, sp);
    }
}

impl FnCtx<'_, '_> {
    /// A `case` label naming a global constant: its folded value.
    fn named_case_value(&self, e: &ast::Expr) -> Option<i64> {
        let ast::ExprKind::Ident(id) = &e.kind else {
            return None;
        };
        let c = self.lw.constant_literal(&id.name)?;
        match c {
            naga::Literal::I32(v) => Some(i64::from(v)),
            naga::Literal::U32(v) => Some(i64::from(v)),
            _ => None,
        }
    }
}

/// True when control cannot fall out of the end of `s`.
fn ends_with_jump(s: &Stmt) -> bool {
    match &s.kind {
        StmtKind::Break | StmtKind::Return(_) | StmtKind::Continue => true,
        StmtKind::Block(b) => b.stmts.last().is_some_and(ends_with_jump),
        _ => false,
    }
}

/// A `case` label's value: an int literal, possibly negated.
fn case_value(e: &ast::Expr) -> Option<i64> {
    match &e.kind {
        ast::ExprKind::IntLit(v) | ast::ExprKind::UIntLit(v) => Some(i64::from(*v)),
        ast::ExprKind::Unary { op: ast::UnaryOp::Neg, operand } => case_value(operand).map(|v| -v),
        _ => None,
    }
}
