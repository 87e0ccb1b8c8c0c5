//! Pruning: only what an entry point reaches stays in the module.

use naga::{Arena, Block, Expression, Function, Handle, Module, Statement};
use std::collections::HashSet;

/// Removes the functions no entry point calls (directly or through other functions), takes the
/// names off the `let` values nothing reads and the constants no function reads (naga's compaction keeps every named constant), and
/// compacts the module: unused constants, anonymous types and expressions go; global variables
/// (every binding a host may set), named types and entry points stay, with their handles.
pub fn prune(module: &mut Module) {
    prune_functions(module);
    for (_, f) in module.functions.iter_mut() {
        super::uses::unname_unused(f);
    }
    for ep in &mut module.entry_points {
        super::uses::unname_unused(&mut ep.function);
    }
    unname_unused_constants(module);
    naga::compact::compact(module, naga::compact::KeepUnused::Yes);
}

/// The functions `block` calls.
fn calls(block: &Block, out: &mut Vec<Handle<Function>>) {
    for s in block.iter() {
        match s {
            Statement::Call { function, .. } => out.push(*function),
            Statement::Block(b) => calls(b, out),
            Statement::If { accept, reject, .. } => {
                calls(accept, out);
                calls(reject, out);
            }
            Statement::Switch { cases, .. } => cases.iter().for_each(|c| calls(&c.body, out)),
            Statement::Loop { body, continuing, .. } => {
                calls(body, out);
                calls(continuing, out);
            }
            _ => {}
        }
    }
}

/// Rewrites the function handles of `block`'s calls.
fn remap_calls(block: &mut Block, map: &[Option<Handle<Function>>]) {
    for s in block.iter_mut() {
        match s {
            Statement::Call { function, .. } => {
                if let Some(Some(f)) = map.get(function.index()) {
                    *function = *f;
                }
            }
            Statement::Block(b) => remap_calls(b, map),
            Statement::If { accept, reject, .. } => {
                remap_calls(accept, map);
                remap_calls(reject, map);
            }
            Statement::Switch { cases, .. } => cases.iter_mut().for_each(|c| remap_calls(&mut c.body, map)),
            Statement::Loop { body, continuing, .. } => {
                remap_calls(body, map);
                remap_calls(continuing, map);
            }
            _ => {}
        }
    }
}

fn remap_function(f: &mut Function, map: &[Option<Handle<Function>>]) {
    remap_calls(&mut f.body, map);
    for (_, e) in f.expressions.iter_mut() {
        if let Expression::CallResult(callee) = e
            && let Some(Some(n)) = map.get(callee.index())
        {
            *callee = *n;
        }
    }
}

/// Drops the functions no entry point reaches. A function is only ever called by functions
/// lowered after it, so the arena keeps its order and callees stay before their callers.
fn prune_functions(module: &mut Module) {
    let mut reached: HashSet<Handle<Function>> = HashSet::new();
    let mut work = Vec::new();
    for ep in &module.entry_points {
        calls(&ep.function.body, &mut work);
    }
    while let Some(f) = work.pop() {
        if reached.insert(f) {
            calls(&module.functions[f].body, &mut work);
        }
    }
    if reached.len() == module.functions.len() {
        return;
    }
    let old = std::mem::take(&mut module.functions);
    let mut map: Vec<Option<Handle<Function>>> = vec![None; old.len()];
    let mut kept = Arena::new();
    for (h, f) in old.iter() {
        if reached.contains(&h) {
            map[h.index()] = Some(kept.append(f.clone(), old.get_span(h)));
        }
    }
    for (_, f) in kept.iter_mut() {
        remap_function(f, &map);
    }
    for ep in &mut module.entry_points {
        remap_function(&mut ep.function, &map);
    }
    module.functions = kept;
}

/// Takes the name off every constant that no function, entry point or used constant refers to,
/// so that naga's compaction drops it.
fn unname_unused_constants(module: &mut Module) {
    let mut used = HashSet::new();
    let functions = module.functions.iter().map(|(_, f)| f).chain(module.entry_points.iter().map(|e| &e.function));
    for f in functions {
        for (_, e) in f.expressions.iter() {
            if let Expression::Constant(c) = e {
                used.insert(*c);
            }
        }
    }
    // Constants a used constant's initializer (or an override's) names.
    let mut work: Vec<Handle<Expression>> = used.iter().map(|c| module.constants[*c].init).collect();
    work.extend(module.overrides.iter().filter_map(|(_, o)| o.init));
    let mut seen = HashSet::new();
    while let Some(h) = work.pop() {
        if !seen.insert(h) {
            continue;
        }
        match &module.global_expressions[h] {
            Expression::Constant(c) if used.insert(*c) => work.push(module.constants[*c].init),
            Expression::Compose { components, .. } => work.extend(components.iter().copied()),
            Expression::Splat { value, .. } => work.push(*value),
            Expression::Unary { expr, .. } | Expression::As { expr, .. } => work.push(*expr),
            Expression::Binary { left, right, .. } => work.extend([*left, *right]),
            Expression::AccessIndex { base, .. } | Expression::Swizzle { vector: base, .. } => work.push(*base),
            Expression::Access { base, index } => work.extend([*base, *index]),
            Expression::Select { condition, accept, reject } => work.extend([*condition, *accept, *reject]),
            Expression::Math { arg, arg1, arg2, arg3, .. } => {
                work.push(*arg);
                work.extend([*arg1, *arg2, *arg3].into_iter().flatten());
            }
            _ => {}
        }
    }
    for (h, c) in module.constants.iter_mut() {
        if !used.contains(&h) {
            c.name = None;
        }
    }
}
