//! Builds one naga function body, keeping `Emit` ranges right.
//!
//! naga wants every expression that is not "pre-emitted" (literals, constants, arguments,
//! variable pointers, call results) to be covered by exactly one `Statement::Emit` in a block
//! that dominates its uses. The builder keeps a running emit range, closes it before a
//! pre-emitted expression or a statement, and so no caller has to think about it.

use naga::{Block, Expression, Function, Handle, LocalVariable, Span, Statement, Type};

/// A function under construction.
pub(crate) struct FnBuilder {
    pub function: Function,
    blocks: Vec<Block>,
    emit_start: Option<usize>,
}

impl FnBuilder {
    pub fn new(name: &str) -> Self {
        FnBuilder {
            function: Function { name: Some(name.into()), ..Default::default() },
            blocks: vec![Block::new()],
            emit_start: None,
        }
    }

    /// Appends an expression, emitting it unless naga says it is pre-emitted.
    pub fn expr(&mut self, expr: Expression, span: Span) -> Handle<Expression> {
        let pre_emitted = expr.needs_pre_emit() || matches!(expr, Expression::CallResult(_));
        if pre_emitted {
            self.flush();
        } else if self.emit_start.is_none() {
            self.emit_start = Some(self.function.expressions.len());
        }
        self.function.expressions.append(expr, span)
    }

    fn flush(&mut self) {
        if let Some(start) = self.emit_start.take()
            && start != self.function.expressions.len()
        {
            let range = self.function.expressions.range_from(start);
            let mut span = Span::default();
            for h in range.clone() {
                span.subsume(self.function.expressions.get_span(h));
            }
            self.current().push(Statement::Emit(range), span);
        }
    }

    fn current(&mut self) -> &mut Block {
        if self.blocks.is_empty() {
            self.blocks.push(Block::new());
        }
        let last = self.blocks.len() - 1;
        &mut self.blocks[last]
    }

    /// Appends a statement to the current block.
    pub fn stmt(&mut self, stmt: Statement, span: Span) {
        self.flush();
        self.current().push(stmt, span);
    }

    /// Starts a nested block.
    pub fn open(&mut self) {
        self.flush();
        self.blocks.push(Block::new());
    }

    /// Ends the nested block started by the matching [`open`](Self::open).
    pub fn close(&mut self) -> Block {
        self.flush();
        if self.blocks.len() > 1 { self.blocks.pop().unwrap_or_default() } else { Block::new() }
    }

    /// The first `size` components of `vector` (`.xy`, `.xyz`).
    pub fn head(&mut self, vector: Handle<Expression>, size: u8, span: Span) -> Handle<Expression> {
        use naga::SwizzleComponent::{W, X, Y, Z};
        let size = match size {
            2 => naga::VectorSize::Bi,
            3 => naga::VectorSize::Tri,
            _ => naga::VectorSize::Quad,
        };
        self.expr(Expression::Swizzle { size, vector, pattern: [X, Y, Z, W] }, span)
    }

    /// A new local variable (zero-initialised), returning its pointer expression.
    pub fn local(&mut self, name: Option<&str>, ty: Handle<Type>, span: Span) -> Handle<Expression> {
        let lv =
            self.function.local_variables.append(LocalVariable { name: name.map(Into::into), ty, init: None }, span);
        self.expr(Expression::LocalVariable(lv), span)
    }

    /// The finished function.
    pub fn finish(mut self) -> Function {
        self.flush();
        while self.blocks.len() > 1 {
            let inner = self.blocks.pop().unwrap_or_default();
            self.current().push(Statement::Block(inner), Span::default());
        }
        self.function.body = self.blocks.pop().unwrap_or_default();
        self.function
    }
}
