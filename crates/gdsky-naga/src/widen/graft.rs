//! Copying the f64 routines of `f64_math.wgsl` into a module.
//!
//! The routines are written in WGSL (naga reads `f64` and `lf` literals) and parsed once; a
//! routine is grafted by cloning its [`naga::Function`] and moving the handles that point
//! outside the function (types and called functions) into the target module. Expression and
//! local-variable handles are the function's own and stay as they are. The routines use no
//! module-scope constants or globals, so nothing else needs moving.

use naga::{Block, Expression, Function, Handle, Module, Statement, Type, TypeInner};
use std::collections::HashMap;
use std::sync::OnceLock;

/// The routines' WGSL source.
pub const F64_MATH_WGSL: &str = include_str!("f64_math.wgsl");

/// The routines parsed (once per process).
pub(super) fn library() -> Result<&'static Module, String> {
    static LIB: OnceLock<Result<Module, String>> = OnceLock::new();
    LIB.get_or_init(|| naga::front::wgsl::parse_str(F64_MATH_WGSL).map_err(|e| e.emit_to_string(F64_MATH_WGSL)))
        .as_ref()
        .map_err(Clone::clone)
}

/// Grafts library functions into one module, each once, callees before callers (naga wants a
/// function defined before any call to it).
pub(crate) struct Grafter<'l> {
    lib: &'l Module,
    types: HashMap<Handle<Type>, Handle<Type>>,
    functions: HashMap<Handle<Function>, Handle<Function>>,
}

impl<'l> Grafter<'l> {
    pub(crate) fn new(lib: &'l Module) -> Self {
        Grafter { lib, types: HashMap::new(), functions: HashMap::new() }
    }

    /// The handle in `target` of the library routine `name`, grafting it (and what it calls) on
    /// first use.
    pub(crate) fn routine(&mut self, target: &mut Module, name: &str) -> Result<Handle<Function>, String> {
        let found = self.lib.functions.iter().find(|(_, f)| f.name.as_deref() == Some(name)).map(|(h, _)| h);
        let h = found.ok_or_else(|| format!("the f64 library has no routine `{name}`"))?;
        // Math results typed by a predeclared struct (frexp's) name no type handle in the
        // function, but the validator looks the struct up in the module: register them all.
        let predeclared: Vec<_> = self.lib.special_types.predeclared_types.values().copied().collect();
        for ty in predeclared {
            self.ty(target, ty);
        }
        self.function(target, h)
    }

    fn function(&mut self, target: &mut Module, h: Handle<Function>) -> Result<Handle<Function>, String> {
        if let Some(done) = self.functions.get(&h) {
            return Ok(*done);
        }
        let mut fun = self.lib.functions[h].clone();
        let mut callees = Vec::new();
        calls(&fun.body, &mut callees);
        let mut fmap = HashMap::new();
        for c in callees {
            let nc = self.function(target, c)?;
            fmap.insert(c, nc);
        }
        for arg in &mut fun.arguments {
            arg.ty = self.ty(target, arg.ty);
        }
        if let Some(r) = &mut fun.result {
            r.ty = self.ty(target, r.ty);
        }
        for (_, local) in fun.local_variables.iter_mut() {
            local.ty = self.ty(target, local.ty);
        }
        for (_, e) in fun.expressions.iter_mut() {
            match e {
                Expression::ZeroValue(ty) | Expression::Compose { ty, .. } => *ty = self.ty(target, *ty),
                Expression::CallResult(f) => *f = fmap.get(f).copied().ok_or("a call the grafter did not see")?,
                Expression::Constant(_)
                | Expression::Override(_)
                | Expression::GlobalVariable(_)
                | Expression::AtomicResult { .. }
                | Expression::SubgroupOperationResult { .. } => {
                    return Err(format!(
                        "the f64 library's `{}` uses module-scope state",
                        fun.name.unwrap_or_default()
                    ));
                }
                _ => {}
            }
        }
        remap_calls(&mut fun.body, &fmap);
        let new = target.functions.append(fun, naga::Span::UNDEFINED);
        self.functions.insert(h, new);
        Ok(new)
    }

    /// A library type in `target`: predeclared types (frexp's result) through naga's own
    /// registry, the rest copied member by member.
    fn ty(&mut self, target: &mut Module, h: Handle<Type>) -> Handle<Type> {
        if let Some(t) = self.types.get(&h) {
            return *t;
        }
        let predeclared =
            self.lib.special_types.predeclared_types.iter().find(|(_, t)| **t == h).map(|(k, _)| k.clone());
        let new = if let Some(key) = predeclared {
            target.generate_predeclared_type(key)
        } else {
            let ty = &self.lib.types[h];
            let inner = match &ty.inner {
                TypeInner::Array { base, size, stride } => {
                    TypeInner::Array { base: self.ty(target, *base), size: *size, stride: *stride }
                }
                TypeInner::Struct { members, span } => {
                    let members =
                        members.iter().map(|m| naga::StructMember { ty: self.ty(target, m.ty), ..m.clone() }).collect();
                    TypeInner::Struct { members, span: *span }
                }
                TypeInner::Pointer { base, space } => {
                    TypeInner::Pointer { base: self.ty(target, *base), space: *space }
                }
                other => other.clone(),
            };
            target.types.insert(Type { name: ty.name.clone(), inner }, naga::Span::UNDEFINED)
        };
        self.types.insert(h, new);
        new
    }
}

/// The functions a block calls.
fn calls(block: &Block, out: &mut Vec<Handle<Function>>) {
    for s in block.iter() {
        match s {
            Statement::Call { function, .. } => out.push(*function),
            Statement::Block(b) => calls(b, out),
            Statement::If { accept, reject, .. } => {
                calls(accept, out);
                calls(reject, out);
            }
            Statement::Loop { body, continuing, .. } => {
                calls(body, out);
                calls(continuing, out);
            }
            Statement::Switch { cases, .. } => cases.iter().for_each(|c| calls(&c.body, out)),
            _ => {}
        }
    }
}

fn remap_calls(block: &mut Block, fmap: &HashMap<Handle<Function>, Handle<Function>>) {
    for s in block.iter_mut() {
        match s {
            Statement::Call { function, .. } => {
                if let Some(f) = fmap.get(function) {
                    *function = *f;
                }
            }
            Statement::Block(b) => remap_calls(b, fmap),
            Statement::If { accept, reject, .. } => {
                remap_calls(accept, fmap);
                remap_calls(reject, fmap);
            }
            Statement::Loop { body, continuing, .. } => {
                remap_calls(body, fmap);
                remap_calls(continuing, fmap);
            }
            Statement::Switch { cases, .. } => cases.iter_mut().for_each(|c| remap_calls(&mut c.body, fmap)),
            _ => {}
        }
    }
}
