//! The syntax tree. Every node carries a [`Span`] into the preprocessed text; expressions also
//! carry an [`ExprId`] so later stages can attach types and resolutions in side tables instead of
//! rebuilding the tree.

/// A byte range of the preprocessed text. Map it to a file with the
/// [`SourceMap`](crate::SourceMap).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Span {
    /// First byte.
    pub start: u32,
    /// One past the last byte.
    pub end: u32,
}

impl Span {
    /// A span from byte offsets.
    pub fn new(start: usize, end: usize) -> Self {
        Self { start: start as u32, end: end as u32 }
    }

    /// The smallest span covering both.
    pub fn to(self, other: Span) -> Span {
        Span { start: self.start.min(other.start), end: self.end.max(other.end) }
    }

    /// As a `usize` range.
    pub fn range(self) -> std::ops::Range<usize> {
        self.start as usize..self.end as usize
    }
}

/// A name as written, with where it was written.
#[derive(Clone, Debug, PartialEq)]
pub struct Ident {
    /// The name.
    pub name: String,
    /// Where it was written.
    pub span: Span,
}

/// A whole shader file.
#[derive(Clone, Debug, Default)]
pub struct Shader {
    /// Top-level items in source order.
    pub items: Vec<Item>,
    /// How many expressions the tree holds; [`ExprId`]s are `0..expr_count`.
    pub expr_count: u32,
    /// The end of the text (for "expected … before the end of the file").
    pub eof: Span,
}

/// A top-level item.
#[derive(Clone, Debug)]
pub struct Item {
    /// What the item is.
    pub kind: ItemKind,
    /// The whole item.
    pub span: Span,
}

/// The kinds of top-level item.
#[derive(Clone, Debug)]
pub enum ItemKind {
    /// `shader_type sky;`
    ShaderType(Ident),
    /// `render_mode a, b;`
    RenderMode(Vec<Ident>),
    /// `group_uniforms A.B;` (path) or `group_uniforms;` (empty path: closes the group).
    GroupUniforms(Vec<Ident>),
    /// `uniform ...;`
    Uniform(Box<Uniform>),
    /// `struct S { ... };`
    Struct(StructDecl),
    /// `const T a = ..., b = ...;` at global scope.
    Const(VarDecl),
    /// A non-const global variable (parsed so the checker can say Godot forbids it).
    GlobalVar(VarDecl),
    /// A function definition.
    Function(Box<Function>),
    /// A lone `;`.
    Empty,
}

/// `lowp`, `mediump` or `highp`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    /// `lowp`
    Low,
    /// `mediump`
    Medium,
    /// `highp`
    High,
}

/// A type as written: a name with an optional array suffix.
#[derive(Clone, Debug)]
pub struct TypeRef {
    /// Precision qualifier, if any.
    pub precision: Option<Precision>,
    /// Type name (`vec3`, a struct name, ...).
    pub name: Ident,
    /// `T[N]` or `T[]` written on the type.
    pub array: Option<ArraySize>,
    /// The whole type.
    pub span: Span,
}

/// An array suffix: `[N]` or `[]`.
#[derive(Clone, Debug)]
pub struct ArraySize {
    /// The size expression; `None` for `[]` (size inferred from the initializer).
    pub size: Option<Box<Expr>>,
    /// The brackets and what is between them.
    pub span: Span,
}

/// `uniform` declaration.
#[derive(Clone, Debug)]
pub struct Uniform {
    /// `global uniform` or `instance uniform`.
    pub scope: Option<UniformScope>,
    /// Declared type.
    pub ty: TypeRef,
    /// Name.
    pub name: Ident,
    /// `uniform T name[N]`.
    pub array: Option<ArraySize>,
    /// Hints after `:`.
    pub hints: Vec<Hint>,
    /// Default value after `=`.
    pub default: Option<Expr>,
    /// The `/** ... */` comment just before the declaration, cleaned of its markers.
    pub doc: Option<String>,
    /// The group path in force (`group_uniforms A.B;`).
    pub group: Vec<String>,
}

/// `global` or `instance` before `uniform`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UniformScope {
    /// `global uniform`
    Global,
    /// `instance uniform` (spatial shaders only)
    Instance,
}

/// A uniform hint such as `hint_range(0.0, 1.0)`.
#[derive(Clone, Debug)]
pub struct Hint {
    /// Hint name.
    pub name: Ident,
    /// Arguments, if written with parentheses.
    pub args: Vec<HintArg>,
    /// The whole hint.
    pub span: Span,
}

/// A hint argument: an expression or a string (`hint_enum("A", "B")`).
#[derive(Clone, Debug)]
pub enum HintArg {
    /// An expression argument.
    Expr(Expr),
    /// A string argument, without quotes.
    Str(String, Span),
}

/// `struct Name { members };`
#[derive(Clone, Debug)]
pub struct StructDecl {
    /// Struct name.
    pub name: Ident,
    /// Members in order.
    pub members: Vec<StructMember>,
}

/// One struct member.
#[derive(Clone, Debug)]
pub struct StructMember {
    /// Member type.
    pub ty: TypeRef,
    /// Member name.
    pub name: Ident,
    /// `name[N]`.
    pub array: Option<ArraySize>,
}

/// A variable or constant declaration with one or more declarators.
#[derive(Clone, Debug)]
pub struct VarDecl {
    /// Declared with `const`.
    pub is_const: bool,
    /// Type shared by all declarators.
    pub ty: TypeRef,
    /// The names being declared.
    pub declarators: Vec<Declarator>,
}

/// `name[N] = init`
#[derive(Clone, Debug)]
pub struct Declarator {
    /// Name.
    pub name: Ident,
    /// `name[N]` or `name[]`.
    pub array: Option<ArraySize>,
    /// Initializer.
    pub init: Option<Expr>,
    /// The whole declarator.
    pub span: Span,
}

/// A function definition.
#[derive(Clone, Debug)]
pub struct Function {
    /// Return type.
    pub return_type: TypeRef,
    /// Name.
    pub name: Ident,
    /// Parameters.
    pub params: Vec<Param>,
    /// Body.
    pub body: Block,
    /// The parameter list, parentheses included.
    pub params_span: Span,
}

/// `in`, `out`, `inout`, or `const`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamQualifier {
    /// `in` (the default)
    In,
    /// `out`
    Out,
    /// `inout`
    InOut,
    /// `const` or `const in`
    Const,
}

/// A function parameter.
#[derive(Clone, Debug)]
pub struct Param {
    /// Qualifier (`In` when none is written).
    pub qualifier: ParamQualifier,
    /// Type.
    pub ty: TypeRef,
    /// Name.
    pub name: Ident,
    /// `name[N]`.
    pub array: Option<ArraySize>,
    /// The whole parameter.
    pub span: Span,
}

/// `{ statements }`
#[derive(Clone, Debug)]
pub struct Block {
    /// Statements in order.
    pub stmts: Vec<Stmt>,
    /// Braces included.
    pub span: Span,
}

/// A statement.
#[derive(Clone, Debug)]
pub struct Stmt {
    /// What it is.
    pub kind: StmtKind,
    /// Where it is.
    pub span: Span,
}

/// The kinds of statement.
#[derive(Clone, Debug)]
pub enum StmtKind {
    /// `{ ... }`
    Block(Block),
    /// A local variable or constant declaration.
    VarDecl(VarDecl),
    /// An expression followed by `;`.
    Expr(Expr),
    /// `if (c) s else if (c) s ... else s`, kept flat so long chains do not nest.
    If {
        /// Each `if` / `else if` condition with its statement.
        branches: Vec<(Expr, Stmt)>,
        /// The final `else`.
        otherwise: Option<Box<Stmt>>,
    },
    /// `for (init; cond; step) body`
    For {
        /// Initializer statement (declaration or expression), if any.
        init: Option<Box<Stmt>>,
        /// Condition, if any.
        cond: Option<Expr>,
        /// Step expressions (Godot allows several, separated by commas).
        step: Vec<Expr>,
        /// Loop body.
        body: Box<Stmt>,
    },
    /// `while (cond) body`
    While {
        /// Condition.
        cond: Expr,
        /// Body.
        body: Box<Stmt>,
    },
    /// `do body while (cond);`
    DoWhile {
        /// Body.
        body: Box<Stmt>,
        /// Condition.
        cond: Expr,
    },
    /// `switch (selector) { case ...: ... }`
    Switch {
        /// The value switched on.
        selector: Expr,
        /// Cases in order; statements fall through to the next case.
        cases: Vec<SwitchCase>,
    },
    /// `break;`
    Break,
    /// `continue;`
    Continue,
    /// `return;` or `return value;`
    Return(Option<Expr>),
    /// `discard;` (rejected in sky shaders)
    Discard,
    /// `;`
    Empty,
}

/// One `case` or `default` label with the statements under it.
#[derive(Clone, Debug)]
pub struct SwitchCase {
    /// The case value; `None` for `default`.
    pub value: Option<Expr>,
    /// The label, keyword to colon.
    pub label_span: Span,
    /// The statements under the label.
    pub body: Vec<Stmt>,
}

/// Identifies an expression node; index into per-expression side tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ExprId(pub u32);

/// An expression.
#[derive(Clone, Debug)]
pub struct Expr {
    /// Identity for side tables.
    pub id: ExprId,
    /// What it is.
    pub kind: ExprKind,
    /// Where it is.
    pub span: Span,
}

/// Unary operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UnaryOp {
    /// `-x`
    Neg,
    /// `+x`
    Plus,
    /// `!x`
    Not,
    /// `~x`
    BitNot,
}

/// Binary operators (assignment and the ternary are separate nodes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinaryOp {
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `%`
    Rem,
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `<<`
    Shl,
    /// `>>`
    Shr,
    /// `<`
    Less,
    /// `>`
    Greater,
    /// `<=`
    LessEq,
    /// `>=`
    GreaterEq,
    /// `==`
    Eq,
    /// `!=`
    NotEq,
    /// `&`
    BitAnd,
    /// `^`
    BitXor,
    /// `|`
    BitOr,
    /// `&&`
    LogicalAnd,
    /// `||`
    LogicalOr,
}

impl BinaryOp {
    /// The operator as written.
    pub fn symbol(self) -> &'static str {
        use BinaryOp::*;
        match self {
            Mul => "*",
            Div => "/",
            Rem => "%",
            Add => "+",
            Sub => "-",
            Shl => "<<",
            Shr => ">>",
            Less => "<",
            Greater => ">",
            LessEq => "<=",
            GreaterEq => ">=",
            Eq => "==",
            NotEq => "!=",
            BitAnd => "&",
            BitXor => "^",
            BitOr => "|",
            LogicalAnd => "&&",
            LogicalOr => "||",
        }
    }
}

/// `++` or `--`, before or after the operand.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IncDec {
    /// `++` when true, `--` when false.
    pub increment: bool,
    /// Written before the operand (`++x`).
    pub prefix: bool,
}

/// The kinds of expression.
#[derive(Clone, Debug)]
pub enum ExprKind {
    /// An int literal (value up to 0xFFFFFFFF; negation is a separate node).
    IntLit(u32),
    /// A uint literal (`1u`).
    UIntLit(u32),
    /// A float literal, kept as the f64 Godot parses.
    FloatLit(f64),
    /// `true` / `false`
    BoolLit(bool),
    /// A name.
    Ident(Ident),
    /// `name(args)`: a function call or a constructor.
    Call {
        /// Function or type name.
        callee: Ident,
        /// Arguments.
        args: Vec<Expr>,
    },
    /// `T[N](args)` or `T[](args)`.
    ArrayCtor {
        /// Element type name.
        elem: Ident,
        /// Size, if written.
        size: Option<Box<Expr>>,
        /// Elements.
        args: Vec<Expr>,
    },
    /// `{a, b, c}` (only in initializers and `return`).
    InitList(Vec<Expr>),
    /// `base.name`: a swizzle or struct member.
    Member {
        /// The value accessed.
        base: Box<Expr>,
        /// Swizzle or member name.
        name: Ident,
    },
    /// `base.name(args)`: only `.length()` exists.
    MethodCall {
        /// The receiver.
        base: Box<Expr>,
        /// Method name.
        name: Ident,
        /// Arguments.
        args: Vec<Expr>,
    },
    /// `base[index]`
    Index {
        /// The value indexed.
        base: Box<Expr>,
        /// The index.
        index: Box<Expr>,
    },
    /// `-x`, `!x`, ...
    Unary {
        /// Operator.
        op: UnaryOp,
        /// Operand.
        operand: Box<Expr>,
    },
    /// `++x`, `x--`, ...
    IncDec {
        /// Which one.
        op: IncDec,
        /// The variable changed.
        target: Box<Expr>,
    },
    /// `a op b`
    Binary {
        /// Operator.
        op: BinaryOp,
        /// Left operand.
        lhs: Box<Expr>,
        /// Right operand.
        rhs: Box<Expr>,
    },
    /// `a = b` or `a op= b`
    Assign {
        /// `None` for `=`, the operator for compound assignment.
        op: Option<BinaryOp>,
        /// What is written.
        target: Box<Expr>,
        /// The value.
        value: Box<Expr>,
    },
    /// `c ? a : b`
    Ternary {
        /// Condition.
        cond: Box<Expr>,
        /// Value when true.
        then: Box<Expr>,
        /// Value when false.
        otherwise: Box<Expr>,
    },
    /// A malformed expression that has already been reported.
    Error,
}
