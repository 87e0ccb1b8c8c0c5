//! The checker: Godot's rules for sky shaders, applied to the AST.
//!
//! It walks the items in order, as Godot does: a name must be declared before it is used, and
//! functions cannot be prototyped, so a function can call only those defined above it (which is
//! also why recursion can only be direct). It resolves every name, types every expression,
//! evaluates constants, and checks what Godot checks: no implicit conversion except of scalar
//! constants (literals, negated literals, constructors of them: `reduce.rs`) given to built-in
//! functions, constructors, user functions that are not overloaded and uniform defaults, built-in
//! scopes (EYEDIR and friends exist only in `sky()`) and read-only-ness, hints, `sky()`'s
//! signature, `discard`, recursion.
//!
//! Every error is collected; an expression whose type could not be worked out is typed `None`,
//! and nothing is reported about the expressions around it, so one mistake gives one message.
//! Godot's built-in tables live in `builtins.rs` as data; this module only interprets them.

pub mod builtins;
pub mod consteval;
mod expr;
mod hints;
mod reduce;
mod stmt;
pub mod types;

use crate::diag::codes;
use crate::parse::SpannedDiagnostic;
use crate::parse::ast::{self, Ident, ItemKind, Shader, Span};
use consteval::{ConstValue, ValueDisplay};
use std::collections::{BTreeSet, HashMap};
use types::{Scalar, StructId, Type};

/// Largest array length accepted. Godot sets no limit; GPUs do, and a size like 2,000,000,000
/// is a mistake that would otherwise exhaust memory later. 65,532: one SPIR-V instruction holds
/// at most 65,535 words (its word count is 16 bits), and a composite of N elements (an array's
/// constant or construction) takes N + 3 of them.
pub const MAX_ARRAY_LEN: i64 = 65_532;

/// A checked shader: the tree plus what the checker learned about it.
#[derive(Debug)]
pub struct CheckedShader {
    /// The syntax tree.
    pub ast: Shader,
    /// Type of each expression, indexed by [`ast::ExprId`]; `None` where checking failed.
    pub expr_types: Vec<Option<Type>>,
    /// Uniforms in declaration order.
    pub uniforms: Vec<UniformInfo>,
    /// Structs in declaration order.
    pub structs: Vec<StructInfo>,
    /// Built-in variables the shader reads or writes.
    pub builtins_used: BTreeSet<&'static str>,
    /// Render modes, as written.
    pub render_modes: Vec<String>,
    /// Whether the shader defines `sky()`.
    pub has_sky: bool,
    /// The declared type (and, for constants, the folded value when known) of every variable,
    /// constant, parameter and function, keyed by the span of its name where it is declared.
    pub declarations: HashMap<ast::Span, (Type, Option<ConstValue>)>,
}

impl CheckedShader {
    /// Struct names by [`StructId`], for displaying types.
    pub fn struct_names(&self) -> Vec<String> {
        self.structs.iter().map(|s| s.name.clone()).collect()
    }

    /// The names a texture can be given under (`--texture NAME=PATH`, a scene's `[textures]`, a
    /// runtime's texture by name): each material sampler uniform's, and `name_i` for element i
    /// of a sampler array, in declaration order (the names of the reflection's
    /// `bindings.textures`).
    pub fn texture_names(&self) -> Vec<String> {
        self.uniforms
            .iter()
            .filter(|u| !u.global)
            .flat_map(|u| match &u.ty {
                Type::Sampler(..) => vec![u.name.clone()],
                Type::Array(element, n) if matches!(**element, Type::Sampler(..)) => {
                    (0..*n).map(|i| format!("{}_{i}", u.name)).collect()
                }
                _ => Vec::new(),
            })
            .collect()
    }
}

/// A uniform as the checker sees it.
#[derive(Clone, Debug)]
pub struct UniformInfo {
    /// Name.
    pub name: String,
    /// Type (arrays included).
    pub ty: Type,
    /// Type as Godot writes it.
    pub type_name: String,
    /// Default value, if one is given.
    pub default: Option<ConstValue>,
    /// Default value written out (`vec3(0.68, 0.55, 0.48)`).
    pub default_text: Option<String>,
    /// Hints in order.
    pub hints: Vec<HintInfo>,
    /// Group path from `group_uniforms`.
    pub group: Vec<String>,
    /// Doc comment.
    pub doc: Option<String>,
    /// Declared `global uniform`.
    pub global: bool,
}

/// A uniform hint with its arguments written out.
#[derive(Clone, Debug, PartialEq)]
pub struct HintInfo {
    /// Hint name.
    pub name: String,
    /// Arguments as text (numbers normalised, strings without quotes).
    pub args: Vec<String>,
}

/// A struct declaration.
#[derive(Clone, Debug)]
pub struct StructInfo {
    /// Name.
    pub name: String,
    /// Members in order.
    pub members: Vec<(String, Type)>,
}

/// A user function's signature.
#[derive(Clone, Debug)]
struct FnInfo {
    params: Vec<(Type, ast::ParamQualifier)>,
    ret: Type,
    span: Span,
}

/// What a global name is.
#[derive(Clone, Debug)]
enum Global {
    Const {
        ty: Type,
        value: Option<ConstValue>,
    },
    /// A uniform; `screen_texture` when it has `hint_screen_texture` (nothing to read in a sky).
    Uniform {
        ty: Type,
        screen_texture: bool,
    },
    Struct,
}

/// What a local name is.
#[derive(Clone, Debug)]
struct Local {
    /// `None` when the declaration failed (already reported): uses are then silently untyped.
    ty: Option<Type>,
    is_const: bool,
    value: Option<ConstValue>,
    span: Span,
}

/// A statement `break` or `continue` can leave.
#[derive(Clone, Copy, PartialEq, Eq)]
enum JumpTarget {
    Loop,
    Switch,
}

/// The function being checked.
struct FnCtx {
    name: String,
    ret: Type,
    is_sky: bool,
    returns: usize,
}

/// Checks a parsed shader. Returns what was learned and the diagnostics (in preprocessed-text
/// coordinates).
pub fn check(shader: Shader) -> (CheckedShader, Vec<SpannedDiagnostic>) {
    let mut c = Checker {
        diags: Vec::new(),
        expr_types: vec![None; shader.expr_count as usize],
        globals: HashMap::new(),
        global_spans: HashMap::new(),
        functions: HashMap::new(),
        structs: Vec::new(),
        struct_ids: HashMap::new(),
        scopes: Vec::new(),
        current: None,
        jump_targets: Vec::new(),
        group_open: false,
        uniforms: Vec::new(),
        builtins_used: BTreeSet::new(),
        render_modes: Vec::new(),
        has_sky: false,
        declarations: HashMap::new(),
        op_eval: true,
    };
    c.items(&shader);
    let checked = CheckedShader {
        expr_types: c.expr_types,
        uniforms: c.uniforms,
        structs: c.structs,
        builtins_used: c.builtins_used,
        render_modes: c.render_modes,
        has_sky: c.has_sky,
        declarations: c.declarations,
        ast: shader,
    };
    (checked, c.diags)
}

struct Checker {
    diags: Vec<SpannedDiagnostic>,
    expr_types: Vec<Option<Type>>,
    globals: HashMap<String, Global>,
    global_spans: HashMap<String, Span>,
    functions: HashMap<String, Vec<FnInfo>>,
    structs: Vec<StructInfo>,
    struct_ids: HashMap<String, StructId>,
    scopes: Vec<HashMap<String, Local>>,
    current: Option<FnCtx>,
    /// Enclosing loops and switches, innermost last: what `break` and `continue` leave.
    jump_targets: Vec<JumpTarget>,
    /// A `group_uniforms Name;` is in force.
    group_open: bool,
    uniforms: Vec<UniformInfo>,
    builtins_used: BTreeSet<&'static str>,
    render_modes: Vec<String>,
    has_sky: bool,
    declarations: HashMap<ast::Span, (Type, Option<ConstValue>)>,
    /// Godot evaluates constant operators here (its `use_op_eval`): everywhere but in the
    /// initializer of a non-`const` local variable.
    op_eval: bool,
}

impl Checker {
    fn error(
        &mut self,
        code: &'static str,
        message: impl Into<String>,
        span: Span,
        label: impl Into<String>,
    ) -> &mut SpannedDiagnostic {
        self.diags.push(SpannedDiagnostic::error(code, message, span, label));
        let last = self.diags.len() - 1;
        &mut self.diags[last]
    }

    fn struct_names(&self) -> Vec<String> {
        self.structs.iter().map(|s| s.name.clone()).collect()
    }

    fn type_name(&self, ty: &Type) -> String {
        ty.display(&self.struct_names()).to_string()
    }

    fn items(&mut self, shader: &Shader) {
        let mut shader_type_seen = false;
        for (index, item) in shader.items.iter().enumerate() {
            match &item.kind {
                ItemKind::ShaderType(name) => {
                    if shader_type_seen {
                        self.error(
                            codes::SHADER_TYPE,
                            "`shader_type` is declared twice",
                            item.span,
                            "second declaration",
                        );
                    } else if index != 0 {
                        self.error(
                            codes::SHADER_TYPE,
                            "`shader_type` must be the first declaration",
                            item.span,
                            "declared too late",
                        );
                    } else if name.name != "sky" {
                        self.error(
                            codes::SHADER_TYPE,
                            format!("gdsky translates sky shaders only, and this is a `{}` shader", name.name),
                            name.span,
                            "expected `sky`",
                        )
                        .diagnostic
                        .notes
                        .push("write `shader_type sky;`".into());
                        // The rest is another language's built-ins; checking it would only cascade.
                        return;
                    }
                    shader_type_seen = true;
                }
                _ if !shader_type_seen => {
                    let at = Span::new(item.span.start as usize, item.span.start as usize);
                    self.error(
                        codes::SHADER_TYPE,
                        "a sky shader must begin with `shader_type sky;`",
                        at,
                        "expected `shader_type sky;` before this",
                    )
                    .diagnostic
                    .notes
                    .push("Godot requires the shader type as the first declaration".into());
                    shader_type_seen = true;
                    self.item(item);
                }
                _ => self.item(item),
            }
        }
        if !shader_type_seen {
            self.error(
                codes::SHADER_TYPE,
                "a sky shader must begin with `shader_type sky;`",
                shader.eof,
                "found the end of the file",
            )
            .diagnostic
            .notes
            .push("the file has no declarations at all".into());
        }
        if !self.has_sky && self.diags.iter().all(|d| !d.diagnostic.is_error()) {
            let at = shader.items.first().map_or(Span::new(0, 0), |i| i.span);
            self.diags.push(
                SpannedDiagnostic::warning(codes::NO_SKY_FUNCTION, "the shader has no `sky()` function", at, "")
                    .note("Godot accepts this and renders the sky black; define `void sky() { COLOR = ...; }`"),
            );
        }
    }

    fn item(&mut self, item: &ast::Item) {
        match &item.kind {
            ItemKind::ShaderType(_) | ItemKind::Empty => {}
            ItemKind::GroupUniforms(path) => {
                if path.is_empty() && !self.group_open {
                    self.error(
                        codes::NOT_ALLOWED,
                        "`group_uniforms;` closes a group, but no group is open",
                        item.span,
                        "",
                    )
                    .diagnostic
                    .notes
                    .push("open one first with `group_uniforms Name;`".into());
                }
                self.group_open = !path.is_empty();
            }
            ItemKind::RenderMode(modes) => {
                for m in modes {
                    if !builtins::RENDER_MODES.contains(&m.name.as_str()) {
                        self.error(
                            codes::UNKNOWN_RENDER_MODE,
                            format!("unknown render mode `{}`", m.name),
                            m.span,
                            "not a sky render mode",
                        )
                        .diagnostic
                        .notes
                        .push(format!("sky shaders accept {}", builtins::RENDER_MODES.join(", ")));
                    } else if self.render_modes.contains(&m.name) {
                        self.error(
                            codes::UNKNOWN_RENDER_MODE,
                            format!("render mode `{}` is given twice", m.name),
                            m.span,
                            "repeated",
                        );
                    } else {
                        self.render_modes.push(m.name.clone());
                    }
                }
            }
            ItemKind::Uniform(u) => self.uniform(u),
            ItemKind::Struct(s) => self.struct_decl(s),
            ItemKind::Const(decl) => self.global_const(decl),
            ItemKind::GlobalVar(decl) => {
                self.error(
                    codes::NOT_ALLOWED,
                    "global variables are not allowed; only `const`, `uniform`, `struct` and functions can be declared at the top level",
                    decl.ty.span.to(decl.declarators.first().map_or(decl.ty.span, |d| d.span)),
                    "not `const`",
                )
                .diagnostic
                .notes
                .push("declare it `const`, make it a `uniform`, or move it into a function".into());
                for d in &decl.declarators {
                    self.global_spans.entry(d.name.name.clone()).or_insert(d.name.span);
                }
            }
            ItemKind::Function(f) => self.function(f),
        }
    }

    /// Declares a global name, reporting a clash with an earlier one or with a built-in.
    fn declare_global(&mut self, name: &Ident, global: Global) -> bool {
        if let Some(b) = builtins::builtin_var(&name.name) {
            self.error(
                codes::REDECLARED,
                format!("`{}` is a built-in of sky shaders and cannot be redeclared", b.name),
                name.span,
                "built-in name",
            );
            return false;
        }
        if Type::from_name(&name.name).is_some() {
            self.error(codes::REDECLARED, format!("`{}` is a type name", name.name), name.span, "reserved");
            return false;
        }
        if let Some(prev) = self
            .global_spans
            .get(&name.name)
            .copied()
            .or_else(|| self.functions.get(&name.name).and_then(|f| f.first()).map(|f| f.span))
        {
            self.error(codes::REDECLARED, format!("redefinition of `{}`", name.name), name.span, "declared again here")
                .secondary
                .push((prev, "first declared here".into()));
            return false;
        }
        self.global_spans.insert(name.name.clone(), name.span);
        self.globals.insert(name.name.clone(), global);
        true
    }

    /// Resolves a written type, including the array suffix on the type and on the declarator.
    fn resolve_type(
        &mut self,
        ty: &ast::TypeRef,
        extra_array: Option<&ast::ArraySize>,
        init: Option<&ast::Expr>,
    ) -> Option<Type> {
        if ty.precision.is_some()
            && matches!(
                Type::from_name(&ty.name.name),
                Some(Type::Scalar(Scalar::Bool) | Type::Vector(Scalar::Bool, _))
            )
        {
            self.error(codes::NOT_ALLOWED, "The precision modifier cannot be used on boolean types.", ty.span, "");
        }
        let base = match Type::from_name(&ty.name.name) {
            Some(t) => t,
            None => match self.struct_ids.get(&ty.name.name) {
                Some(id) => Type::Struct(*id),
                None => {
                    let msg = if ty.name.name.is_empty() {
                        "expected a type".to_string()
                    } else {
                        format!("unknown type `{}`", ty.name.name)
                    };
                    self.error(codes::UNKNOWN_TYPE, msg, ty.name.span, "not a type");
                    return None;
                }
            },
        };
        let arrays: Vec<&ast::ArraySize> = ty.array.iter().chain(extra_array).collect();
        match arrays.as_slice() {
            [] => Some(base),
            [a] => {
                if base == Type::Void {
                    self.error(codes::BAD_ARRAY, "arrays of `void` are not allowed", a.span, "");
                    return None;
                }
                let len = match &a.size {
                    Some(size) => self.array_len(size)?,
                    None => match init.map(|e| &e.kind) {
                        Some(ast::ExprKind::InitList(items)) => items.len() as u32,
                        Some(ast::ExprKind::ArrayCtor { .. }) => {
                            self.error(codes::BAD_ARRAY, "an array declared with `[]` must be initialized with a `{…}` list", a.span, "size not given")
                                .diagnostic
                                .notes
                                .push("Godot expects `{` here: write `float b[] = {1.0, 2.0};` or give the size, `float b[2] = float[](1.0, 2.0);`".into());
                            return None;
                        }
                        _ => {
                            self.error(
                                codes::BAD_ARRAY,
                                "an array declared with `[]` needs an initializer to give it a size",
                                a.span,
                                "size unknown",
                            );
                            return None;
                        }
                    },
                };
                Some(Type::Array(Box::new(base), len))
            }
            [_, second, ..] => {
                self.error(codes::BAD_ARRAY, "arrays of arrays are not supported", second.span, "second array suffix");
                None
            }
        }
    }

    /// Evaluates an array size: a positive int constant no larger than [`MAX_ARRAY_LEN`].
    fn array_len(&mut self, size: &ast::Expr) -> Option<u32> {
        let info = self.expr(size)?;
        if !matches!(info.ty, Type::Scalar(Scalar::Int | Scalar::UInt)) {
            let t = self.type_name(&info.ty);
            self.error(
                codes::BAD_ARRAY,
                format!("an array size must be an integer, not `{t}`"),
                size.span,
                "not an integer",
            );
            return None;
        }
        let Some(n) = info.value.as_ref().and_then(ConstValue::as_int).filter(|_| info.constant) else {
            self.error(codes::NOT_CONSTANT, "an array size must be a constant expression", size.span, "not constant");
            return None;
        };
        if n <= 0 {
            self.error(codes::BAD_ARRAY, format!("an array size must be positive, not {n}"), size.span, "");
            return None;
        }
        if n > MAX_ARRAY_LEN {
            self.error(
                codes::SIZE_LIMIT,
                format!("array size {n} is larger than gdsky accepts ({MAX_ARRAY_LEN})"),
                size.span,
                "too large",
            );
            return None;
        }
        Some(n as u32)
    }

    fn struct_decl(&mut self, s: &ast::StructDecl) {
        let mut members: Vec<(String, Type)> = Vec::new();
        for m in &s.members {
            let Some(ty) = self.resolve_type(&m.ty, m.array.as_ref(), None) else {
                continue;
            };
            if ty == Type::Void || ty.is_opaque() {
                let t = self.type_name(&ty);
                self.error(codes::NOT_ALLOWED, format!("a struct member cannot be of type `{t}`"), m.ty.span, "");
                continue;
            }
            if members.iter().any(|(n, _)| *n == m.name.name) {
                self.error(
                    codes::REDECLARED,
                    format!("struct member `{}` is declared twice", m.name.name),
                    m.name.span,
                    "",
                );
                continue;
            }
            members.push((m.name.name.clone(), ty));
        }
        if self.declare_global(&s.name, Global::Struct) {
            let id = StructId(self.structs.len() as u32);
            self.structs.push(StructInfo { name: s.name.name.clone(), members });
            self.struct_ids.insert(s.name.name.clone(), id);
        }
    }

    fn global_const(&mut self, decl: &ast::VarDecl) {
        for d in &decl.declarators {
            let Some((ty, value)) = self.const_declarator(&decl.ty, d) else {
                // Declare anyway, so later uses do not report it as undeclared.
                self.global_spans.entry(d.name.name.clone()).or_insert(d.name.span);
                continue;
            };
            self.declarations.insert(d.name.span, (ty.clone(), value.clone()));
            self.declare_global(&d.name, Global::Const { ty, value });
        }
    }

    /// Checks one `const` declarator: type, initializer present, of the same type and constant.
    fn const_declarator(&mut self, ty: &ast::TypeRef, d: &ast::Declarator) -> Option<(Type, Option<ConstValue>)> {
        let ty = self.resolve_type(ty, d.array.as_ref(), d.init.as_ref())?;
        let Some(init) = &d.init else {
            self.error(
                codes::NOT_CONSTANT,
                format!("constant `{}` needs an initializer", d.name.name),
                d.name.span,
                "no `= value`",
            )
            .diagnostic
            .notes
            .push("write `const T name = value;`".into());
            return None;
        };
        let info = self.initializer(init, &ty)?;
        if !info.constant {
            self.error(
                codes::NOT_CONSTANT,
                "a constant must be initialized with a constant expression",
                init.span,
                "not constant",
            );
            return None;
        }
        Some((ty, info.value))
    }

    fn uniform(&mut self, u: &ast::Uniform) {
        if u.scope == Some(ast::UniformScope::Instance) {
            self.error(
                codes::NOT_ALLOWED,
                "instance uniforms exist only in spatial shaders",
                u.name.span,
                "not in a sky shader",
            );
        }
        let Some(ty) = self.resolve_type(&u.ty, u.array.as_ref(), u.default.as_ref()) else {
            self.global_spans.entry(u.name.name.clone()).or_insert(u.name.span);
            return;
        };
        if ty == Type::Void || matches!(ty, Type::Struct(_)) {
            let t = self.type_name(&ty);
            self.error(codes::NOT_ALLOWED, format!("a uniform cannot be of type `{t}`"), u.ty.span, "");
        }
        if u.scope == Some(ast::UniformScope::Global) && matches!(ty, Type::Array(..)) {
            self.error(codes::NOT_ALLOWED, "global uniforms cannot be arrays", u.name.span, "");
        }
        let mut default = None;
        if let Some(init) = &u.default {
            if matches!(ty, Type::Array(..)) {
                self.error(
                    codes::NOT_ALLOWED,
                    "Setting default values to uniform arrays is not supported.",
                    init.span,
                    "remove this",
                );
            } else if ty.is_opaque() {
                self.error(
                    codes::NOT_ALLOWED,
                    "a sampler uniform cannot have a default value",
                    init.span,
                    "remove this",
                )
                .diagnostic
                .notes
                .push("use `hint_default_white`, `hint_default_black` or `hint_default_transparent` instead".into());
            } else {
                default = self.uniform_default(init, &ty);
            }
        }
        let hints = self.hints(u, &ty, default.as_ref());
        let structs = self.struct_names();
        let default_text = default.as_ref().map(|v| ValueDisplay { value: v, ty: &ty, structs: &structs }.to_string());
        let type_name = self.type_name(&ty);
        let screen_texture = hints.iter().any(|h| h.name == "hint_screen_texture");
        if self.declare_global(&u.name, Global::Uniform { ty: ty.clone(), screen_texture }) {
            self.uniforms.push(UniformInfo {
                name: u.name.name.clone(),
                ty,
                type_name,
                default,
                default_text,
                hints,
                group: u.group.clone(),
                doc: u.doc.clone(),
                global: u.scope == Some(ast::UniformScope::Global),
            });
        }
    }

    /// A uniform's default, as Godot takes it: the expression must reduce to a constant node (a
    /// literal, a negated one, or a constructor of them: see `reduce.rs`), which is then
    /// converted to the uniform's type by `convert_constant` (so `uniform float f = 1;` is
    /// accepted, `uniform float f = 1.0 / 2.0;` is not).
    fn uniform_default(&mut self, init: &ast::Expr, ty: &Type) -> Option<ConstValue> {
        if matches!(init.kind, ast::ExprKind::InitList(_)) {
            return self.initializer(init, ty).and(None);
        }
        let info = self.expr(init)?;
        let Some(reduced) = reduce::reduce(init) else {
            self.error(
                codes::NOT_CONSTANT,
                "a uniform's default must be a literal, or a constructor of literals",
                init.span,
                "not a literal",
            )
            .diagnostic
            .notes
            .push(
                "Godot folds only literals, `-` and constructors here (\"Expected constant expression after '='\"): \
                 write the value out"
                    .into(),
            );
            return None;
        };
        if reduced.ty == *ty {
            return info.value;
        }
        if let (Type::Scalar(from), Type::Scalar(to)) = (&reduced.ty, ty)
            && let Some(v) = reduce::convert(&reduced.values[0], *from, *to)
        {
            self.set_converted(init, ty);
            return Some(v);
        }
        let (f, t) = (self.type_name(&reduced.ty), self.type_name(ty));
        self.error(
            codes::TYPE_MISMATCH,
            format!("Can't convert constant to '{t}'."),
            init.span,
            format!("this is `{f}`"),
        )
        .diagnostic
        .notes
        .push(
            "a uniform's default converts only int or uint to float, int to uint (not negative) and uint to int".into(),
        );
        None
    }

    fn function(&mut self, f: &ast::Function) {
        let ret = self.resolve_type(&f.return_type, None, None);
        let mut params = Vec::new();
        let mut param_locals = HashMap::new();
        for p in &f.params {
            let Some(ty) = self.resolve_type(&p.ty, p.array.as_ref(), None) else {
                continue;
            };
            if ty == Type::Void {
                self.error(codes::TYPE_MISMATCH, "a parameter cannot be `void`", p.ty.span, "");
                continue;
            }
            // Godot: a parameter cannot take the name of any built-in of sky shaders, of another
            // parameter, of a uniform or of a global constant (a function's or a struct's is fine).
            let global = matches!(self.globals.get(&p.name.name), Some(Global::Const { .. } | Global::Uniform { .. }));
            if builtins::builtin_var(&p.name.name).is_some() || param_locals.contains_key(&p.name.name) || global {
                self.error(codes::REDECLARED, format!("redefinition of `{}`", p.name.name), p.name.span, "");
            }
            self.declarations.insert(p.name.span, (ty.clone(), None));
            params.push((ty.clone(), p.qualifier));
            let is_const = p.qualifier == ast::ParamQualifier::Const;
            param_locals.insert(p.name.name.clone(), Local { ty: Some(ty), is_const, value: None, span: p.name.span });
        }
        let ret = ret.unwrap_or(Type::Void);
        self.declarations.insert(f.name.span, (ret.clone(), None));
        let is_sky = f.name.name == "sky";
        if is_sky {
            if ret != Type::Void || !f.params.is_empty() {
                self.error(
                    codes::BAD_SKY_SIGNATURE,
                    "`sky()` must be declared `void sky()`, with no parameters",
                    f.name.span.to(f.params_span),
                    "",
                )
                .diagnostic
                .notes
                .push(
                    "Godot calls `void sky()` once per pixel; it reads inputs from built-ins and writes COLOR".into(),
                );
            }
            self.has_sky = true;
        }
        // Declare before the body so a call to itself is seen, and reported as recursion.
        let info = FnInfo { params: params.clone(), ret: ret.clone(), span: f.name.span };
        let clash = builtins::builtin_var(&f.name.name).is_some()
            || self.globals.contains_key(&f.name.name)
            || builtins::builtin_function(&f.name.name).is_some();
        let same = self.functions.get(&f.name.name).and_then(|o| {
            o.iter().find(|g| g.params.iter().map(|p| &p.0).eq(params.iter().map(|p| &p.0))).map(|g| g.span)
        });
        if clash {
            self.error(
                codes::REDECLARED,
                format!("`{}` is already defined and cannot be used as a function name", f.name.name),
                f.name.span,
                "",
            );
        } else if let Some(prev) = same {
            self.error(
                codes::REDECLARED,
                format!("function `{}` is already defined with these parameters", f.name.name),
                f.name.span,
                "defined again here",
            )
            .secondary
            .push((prev, "first defined here".into()));
        } else {
            self.functions.entry(f.name.name.clone()).or_default().push(info);
        }
        self.current = Some(FnCtx { name: f.name.name.clone(), ret: ret.clone(), is_sky, returns: 0 });
        // Parameters share the body's top scope: redeclaring one there is a redefinition, while
        // a nested block may shadow it.
        self.scopes.push(param_locals);
        for s in &f.body.stmts {
            self.stmt(s);
        }
        self.scopes.pop();
        let ctx = self.current.take();
        // `sky()` with a return type has been reported above; a missing `return` would repeat it.
        if ret != Type::Void && !is_sky && ctx.is_some_and(|c| c.returns == 0) {
            let t = self.type_name(&ret);
            self.error(
                codes::BAD_RETURN,
                format!("function `{}` returns `{t}` but has no `return` statement", f.name.name),
                f.name.span,
                "",
            )
            .diagnostic
            .notes
            .push("Godot expects at least one return statement in a non-void function".into());
        }
    }
}

#[cfg(test)]
mod tests;
