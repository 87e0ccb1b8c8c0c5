//! Statements: scopes, declarations, control flow, `return`.

use super::consteval::ConstValue;
use super::types::{Scalar, Type};
use super::{Checker, JumpTarget, Local, builtins};
use crate::diag::codes;
use crate::parse::ast::{self, Stmt, StmtKind};
use std::collections::{HashMap, HashSet};

impl Checker {
    /// Checks statements in a new scope.
    pub(super) fn block_stmts(&mut self, stmts: &[Stmt]) {
        self.scopes.push(HashMap::new());
        for s in stmts {
            self.stmt(s);
        }
        self.scopes.pop();
    }

    /// A statement that is the body of a control statement gets its own scope.
    fn scoped_stmt(&mut self, s: &Stmt) {
        match &s.kind {
            StmtKind::Block(b) => self.block_stmts(&b.stmts),
            _ => self.block_stmts(std::slice::from_ref(s)),
        }
    }

    fn condition(&mut self, cond: &ast::Expr, what: &str) {
        if let Some(info) = self.expr(cond)
            && info.ty != Type::BOOL
        {
            let t = self.type_name(&info.ty);
            self.error(
                codes::TYPE_MISMATCH,
                format!("the condition of `{what}` must be `bool`, not `{t}`"),
                cond.span,
                "not a bool",
            );
        }
    }

    pub(super) fn stmt(&mut self, s: &Stmt) {
        match &s.kind {
            StmtKind::Block(b) => self.block_stmts(&b.stmts),
            StmtKind::VarDecl(decl) => self.local_decl(decl),
            StmtKind::Expr(e) => {
                self.expr(e);
            }
            StmtKind::If { branches, otherwise } => {
                for (cond, body) in branches {
                    self.condition(cond, "if");
                    self.scoped_stmt(body);
                }
                if let Some(o) = otherwise {
                    self.scoped_stmt(o);
                }
            }
            StmtKind::For { init, cond, step, body } => {
                self.scopes.push(HashMap::new());
                if let Some(i) = init {
                    if let StmtKind::Expr(e) = &i.kind {
                        self.error(
                            codes::SYNTAX,
                            "the first part of a `for` must declare the loop variable",
                            e.span,
                            "not a declaration",
                        )
                        .diagnostic
                        .notes
                        .push("Godot accepts `for (int i = 0; ...)` or an empty first part, not an assignment".into());
                    }
                    self.stmt(i);
                }
                if let Some(c) = cond {
                    self.condition(c, "for");
                }
                for st in step {
                    self.expr(st);
                }
                self.jump_targets.push(JumpTarget::Loop);
                self.scoped_stmt(body);
                self.jump_targets.pop();
                self.scopes.pop();
            }
            StmtKind::While { cond, body } => {
                self.condition(cond, "while");
                self.jump_targets.push(JumpTarget::Loop);
                self.scoped_stmt(body);
                self.jump_targets.pop();
            }
            StmtKind::DoWhile { body, cond } => {
                self.jump_targets.push(JumpTarget::Loop);
                self.scoped_stmt(body);
                self.jump_targets.pop();
                self.condition(cond, "do-while");
            }
            StmtKind::Switch { selector, cases } => self.switch(selector, cases),
            StmtKind::Break => {
                if self.jump_targets.is_empty() {
                    self.error(codes::MISPLACED_JUMP, "`break` is only allowed inside a loop or `switch`", s.span, "");
                }
            }
            StmtKind::Continue => match self.jump_targets.last() {
                Some(JumpTarget::Loop) => {}
                Some(JumpTarget::Switch) => {
                    self.error(
                        codes::MISPLACED_JUMP,
                        "`continue` is not allowed inside a `switch`, even one inside a loop",
                        s.span,
                        "",
                    )
                    .diagnostic
                    .notes
                    .push("Godot parses `case` bodies without `continue`; set a flag and `break` instead".into());
                }
                None => {
                    self.error(codes::MISPLACED_JUMP, "`continue` is only allowed inside a loop", s.span, "");
                }
            },
            StmtKind::Return(value) => self.return_stmt(s, value.as_ref()),
            StmtKind::Discard => {
                self.error(codes::DISCARD, "`discard` is not allowed in sky shaders", s.span, "")
                    .diagnostic
                    .notes
                    .push("Godot allows `discard` only in spatial and canvas_item fragment/light functions; write ALPHA instead".into());
            }
            StmtKind::Empty => {}
        }
    }

    fn return_stmt(&mut self, s: &Stmt, value: Option<&ast::Expr>) {
        let Some(ctx) = self.current.as_mut() else {
            return;
        };
        ctx.returns += 1;
        if ctx.is_sky {
            self.error(codes::BAD_RETURN, "Using 'return' in the 'sky' processor function is incorrect.", s.span, "")
                .diagnostic
                .notes
                .push("Godot rejects `return` in `sky()`; put the rest of the body under an `if` instead".into());
            return;
        }
        let (ret, name) = (ctx.ret.clone(), ctx.name.clone());
        match value {
            None if ret != Type::Void => {
                let t = self.type_name(&ret);
                self.error(
                    codes::BAD_RETURN,
                    format!("`{name}` must return a value of type `{t}`"),
                    s.span,
                    "no value",
                );
            }
            None => {}
            Some(v) if ret == Type::Void => {
                self.expr(v);
                self.error(codes::BAD_RETURN, format!("`{name}` is `void` and cannot return a value"), v.span, "");
            }
            Some(v) => {
                self.initializer(v, &ret);
            }
        }
    }

    fn switch(&mut self, selector: &ast::Expr, cases: &[ast::SwitchCase]) {
        let sel_ty = self.expr(selector).map(|i| i.ty);
        if let Some(t) = &sel_ty
            && !matches!(t, Type::Scalar(Scalar::Int | Scalar::UInt))
        {
            let t = self.type_name(t);
            self.error(
                codes::BAD_SWITCH,
                format!("`switch` needs an `int` or `uint` value, not `{t}`"),
                selector.span,
                "",
            );
        }
        let mut seen: HashSet<i64> = HashSet::new();
        let mut default_seen = false;
        self.jump_targets.push(JumpTarget::Switch);
        self.scopes.push(HashMap::new());
        for case in cases {
            match &case.value {
                Some(v) => {
                    if let Some(info) = self.expr(v) {
                        match info.value.as_ref().and_then(ConstValue::as_int).filter(|_| info.constant) {
                            None => {
                                self.error(
                                    codes::BAD_SWITCH,
                                    "a `case` label must be an integer constant",
                                    v.span,
                                    "not constant",
                                );
                            }
                            Some(n) => {
                                if sel_ty.as_ref().is_some_and(|t| *t != info.ty) {
                                    let (a, b) = (
                                        self.type_name(&info.ty),
                                        sel_ty.as_ref().map(|t| self.type_name(t)).unwrap_or_default(),
                                    );
                                    self.error(
                                        codes::BAD_SWITCH,
                                        format!("`case` label is `{a}` but the switch value is `{b}`"),
                                        v.span,
                                        "",
                                    );
                                } else if !seen.insert(n) {
                                    self.error(
                                        codes::BAD_SWITCH,
                                        format!("duplicate `case {n}`"),
                                        v.span,
                                        "already handled above",
                                    );
                                }
                            }
                        }
                    }
                }
                None => {
                    if default_seen {
                        self.error(codes::BAD_SWITCH, "a `switch` can have only one `default`", case.label_span, "");
                    }
                    default_seen = true;
                }
            }
            for s in &case.body {
                self.stmt(s);
            }
        }
        self.scopes.pop();
        self.jump_targets.pop();
    }

    /// Checks a local declaration and declares its names.
    fn local_decl(&mut self, decl: &ast::VarDecl) {
        for d in &decl.declarators {
            let declared = if decl.is_const {
                self.const_declarator(&decl.ty, d).map(|(ty, value)| (ty, value, true))
            } else {
                self.local_var(&decl.ty, d).map(|ty| (ty, None, false))
            };
            // A failed declaration still declares the name, untyped, so its uses do not each
            // report it as unknown.
            let (ty, value, is_const) = declared.map_or((None, None, decl.is_const), |(t, v, c)| (Some(t), v, c));
            self.declare_local(&d.name, Local { ty, is_const, value, span: d.name.span });
        }
    }

    fn local_var(&mut self, ty: &ast::TypeRef, d: &ast::Declarator) -> Option<Type> {
        let t = self.resolve_type(ty, d.array.as_ref(), d.init.as_ref())?;
        if t == Type::Void || t.is_opaque() {
            let n = self.type_name(&t);
            self.error(codes::NOT_ALLOWED, format!("a local variable cannot be of type `{n}`"), ty.span, "");
            return None;
        }
        if let Some(init) = &d.init {
            // Godot leaves the operators of this initializer to run time (`use_op_eval = is_const`
            // in `_parse_block`): `int z = 5 / 0;` is accepted.
            let saved = std::mem::replace(&mut self.op_eval, false);
            self.initializer(init, &t);
            self.op_eval = saved;
        }
        Some(t)
    }

    fn declare_local(&mut self, name: &ast::Ident, local: Local) {
        if let Some(ty) = &local.ty {
            self.declarations.insert(name.span, (ty.clone(), local.value.clone()));
        }
        // Godot checks the current block, the built-ins of the current function and the globals
        // (not struct names, which live apart); an outer block's local may be shadowed, and so
        // may a built-in that exists only in `sky()`, in another function.
        let clash = self.scopes.last().and_then(|s| s.get(&name.name).map(|l| l.span)).or_else(|| {
            self.global_spans.get(&name.name).copied().filter(|_| !self.struct_ids.contains_key(&name.name))
        });
        let in_sky = self.current.as_ref().is_some_and(|c| c.is_sky);
        if builtins::builtin_var(&name.name).is_some_and(|b| in_sky || b.scope == builtins::BuiltinScope::Global) {
            self.error(
                codes::REDECLARED,
                format!("`{}` is a built-in and cannot be redeclared", name.name),
                name.span,
                "",
            );
        } else if Type::from_name(&name.name).is_some() {
            self.error(codes::REDECLARED, format!("`{}` is a type name", name.name), name.span, "");
        } else if let Some(prev) = clash {
            self.error(codes::REDECLARED, format!("redefinition of `{}`", name.name), name.span, "declared again here")
                .secondary
                .push((prev, "first declared here".into()));
        }
        if let Some(scope) = self.scopes.last_mut() {
            scope.insert(name.name.clone(), local);
        }
    }
}
