//! Uniform loads at function entry: each load of a uniform block's member (a chain of constant
//! member and element indices from a `var<uniform>`) is emitted once, at the top of its
//! function, instead of where the source reads it.
//!
//! A uniform never changes during a draw, so the value is the same wherever it is loaded, and a
//! load with constant indices is always in bounds: moving it to the entry changes no value and
//! can fault nowhere. What it changes is the code lavapipe's LLVM gets: loop-invariant loads
//! are outside the loops from the start (the Freeman sky's view loop reads six uniforms per
//! step) instead of left for the driver to hoist, which lavapipe did not always do (measured:
//! the converted Freeman sky ~5 % faster, `cargo bench -p skyrun --bench render`).
//!
//! Only the statements move: the expressions keep their handles, so the validator's rule that
//! an expression's operands come before it still holds, and the `Emit`s that covered the loads
//! are split around them (`uses::split_emits`).

use naga::{AddressSpace, Block, Expression as E, Function, GlobalVariable, Handle, Module, Range, Span, Statement};
use std::collections::{BTreeSet, HashSet};

/// Moves every uniform load of every function and entry point to the function's entry.
pub fn hoist_uniform_loads(module: &mut Module) {
    let uniforms: HashSet<Handle<GlobalVariable>> =
        module.global_variables.iter().filter(|(_, g)| g.space == AddressSpace::Uniform).map(|(h, _)| h).collect();
    if uniforms.is_empty() {
        return;
    }
    for (_, f) in module.functions.iter_mut() {
        hoist(f, &uniforms);
    }
    for ep in &mut module.entry_points {
        hoist(&mut ep.function, &uniforms);
    }
}

/// The emitted expressions of the pointer `p` when it is a uniform global followed by constant
/// indices only (the global itself is never emitted); `None` otherwise.
fn uniform_chain(f: &Function, mut p: Handle<E>, uniforms: &HashSet<Handle<GlobalVariable>>) -> Option<Vec<Handle<E>>> {
    let mut chain = Vec::new();
    loop {
        match f.expressions[p] {
            E::AccessIndex { base, .. } => {
                chain.push(p);
                p = base;
            }
            E::GlobalVariable(g) if uniforms.contains(&g) => return Some(chain),
            _ => return None,
        }
    }
}

fn hoist(f: &mut Function, uniforms: &HashSet<Handle<GlobalVariable>>) {
    let mut moved = BTreeSet::new();
    for (h, e) in f.expressions.iter() {
        if let E::Load { pointer } = *e
            && let Some(chain) = uniform_chain(f, pointer, uniforms)
        {
            moved.insert(h);
            moved.extend(chain);
        }
    }
    if moved.is_empty() {
        return;
    }
    super::uses::split_emits(&mut f.body, &moved.iter().copied().collect());
    // One `Emit` per run of consecutive handles, in handle order (operands first).
    let mut entry = Block::new();
    let mut run: Option<(Handle<E>, Handle<E>)> = None;
    for &h in &moved {
        run = match run {
            Some((a, b)) if b.index() + 1 == h.index() => Some((a, h)),
            Some((a, b)) => {
                entry.push(Statement::Emit(Range::new_from_bounds(a, b)), Span::UNDEFINED);
                Some((h, h))
            }
            None => Some((h, h)),
        };
    }
    if let Some((a, b)) = run {
        entry.push(Statement::Emit(Range::new_from_bounds(a, b)), Span::UNDEFINED);
    }
    entry.extend_block(std::mem::take(&mut f.body));
    f.body = entry;
}
