//! Which expressions a function uses, and emit ranges around expressions that must not be
//! emitted.

use naga::{Block, Expression as E, Function, Handle, Range, SampleLevel, Statement as S};
use std::collections::HashSet;

type H = Handle<E>;

/// The operands of `e`; `None` for kinds gdsky never writes (the caller then assumes the worst).
pub(crate) fn operands(e: &E) -> Option<Vec<H>> {
    Some(match e {
        E::Literal(_)
        | E::Constant(_)
        | E::Override(_)
        | E::ZeroValue(_)
        | E::FunctionArgument(_)
        | E::GlobalVariable(_)
        | E::LocalVariable(_)
        | E::CallResult(_) => vec![],
        E::Compose { components, .. } => components.clone(),
        E::Access { base, index } => vec![*base, *index],
        E::AccessIndex { base, .. } => vec![*base],
        E::Splat { value, .. } => vec![*value],
        E::Swizzle { vector, .. } => vec![*vector],
        E::Load { pointer } => vec![*pointer],
        E::ImageSample { image, sampler, coordinate, array_index, offset, level, depth_ref, .. } => {
            let mut v = vec![*image, *sampler, *coordinate];
            v.extend([*array_index, *offset, *depth_ref].into_iter().flatten());
            match level {
                SampleLevel::Auto | SampleLevel::Zero => {}
                SampleLevel::Exact(h) | SampleLevel::Bias(h) => v.push(*h),
                SampleLevel::Gradient { x, y } => v.extend([*x, *y]),
            }
            v
        }
        E::ImageLoad { image, coordinate, array_index, sample, level } => {
            let mut v = vec![*image, *coordinate];
            v.extend([*array_index, *sample, *level].into_iter().flatten());
            v
        }
        E::ImageQuery { image, query } => {
            let mut v = vec![*image];
            if let naga::ImageQuery::Size { level: Some(l) } = query {
                v.push(*l);
            }
            v
        }
        E::Unary { expr, .. } | E::Derivative { expr, .. } | E::As { expr, .. } => vec![*expr],
        E::Binary { left, right, .. } => vec![*left, *right],
        E::Select { condition, accept, reject } => vec![*condition, *accept, *reject],
        E::Relational { argument, .. } => vec![*argument],
        E::Math { arg, arg1, arg2, arg3, .. } => {
            let mut v = vec![*arg];
            v.extend([*arg1, *arg2, *arg3].into_iter().flatten());
            v
        }
        E::ArrayLength(h) => vec![*h],
        _ => return None,
    })
}

/// Marks the expressions `block`'s statements use directly; false on a statement kind gdsky
/// never writes.
pub(crate) fn roots(block: &Block, used: &mut Vec<H>) -> bool {
    for s in block.iter() {
        match s {
            S::Emit(_) | S::Break | S::Continue | S::Kill | S::ControlBarrier(_) | S::MemoryBarrier(_) => {}
            S::Block(b) => {
                if !roots(b, used) {
                    return false;
                }
                continue;
            }
            S::If { condition, accept, reject } => {
                used.push(*condition);
                if !roots(accept, used) || !roots(reject, used) {
                    return false;
                }
                continue;
            }
            S::Switch { selector, cases } => {
                used.push(*selector);
                for c in cases {
                    if !roots(&c.body, used) {
                        return false;
                    }
                }
                continue;
            }
            S::Loop { body, continuing, break_if } => {
                used.extend(*break_if);
                if !roots(body, used) || !roots(continuing, used) {
                    return false;
                }
                continue;
            }
            S::Return { value } => used.extend(*value),
            S::Store { pointer, value } => used.extend([*pointer, *value]),
            S::ImageStore { image, coordinate, array_index, value } => {
                used.extend([*image, *coordinate, *value].into_iter().chain(*array_index));
            }
            S::Call { arguments, result, .. } => used.extend(arguments.iter().copied().chain(*result)),
            _ => return false,
        }
    }
    true
}

/// Takes the name off every named expression of `f` that nothing uses (a `let` of a value the
/// shader computes and never reads), so that naga's compaction, which keeps every named
/// expression, drops it and what only it used.
pub fn unname_unused(f: &mut Function) {
    let mut direct = Vec::new();
    if !roots(&f.body, &mut direct) {
        return;
    }
    let mut used = vec![false; f.expressions.len()];
    for h in direct {
        used[h.index()] = true;
    }
    for (h, e) in f.expressions.iter().rev() {
        if !used[h.index()] {
            continue;
        }
        let Some(ops) = operands(e) else { return };
        for op in ops {
            used[op.index()] = true;
        }
    }
    f.named_expressions.retain(|h, _| used[h.index()]);
}

/// Splits every `Emit` of `block` so that none covers an expression of `skip` (expressions
/// naga's validator refuses to see emitted, such as an `Override`).
pub fn split_emits(block: &mut Block, skip: &HashSet<H>) {
    let old = std::mem::take(block);
    for (mut s, span) in old.span_into_iter() {
        match &mut s {
            S::Emit(range) if range.clone().any(|h| skip.contains(&h)) => {
                let mut run: Option<(H, H)> = None;
                for h in range.clone() {
                    if skip.contains(&h) {
                        if let Some((a, b)) = run.take() {
                            block.push(S::Emit(Range::new_from_bounds(a, b)), span);
                        }
                    } else {
                        run = Some(run.map_or((h, h), |(a, _)| (a, h)));
                    }
                }
                if let Some((a, b)) = run {
                    block.push(S::Emit(Range::new_from_bounds(a, b)), span);
                }
                continue;
            }
            S::Block(b) => split_emits(b, skip),
            S::If { accept, reject, .. } => {
                split_emits(accept, skip);
                split_emits(reject, skip);
            }
            S::Switch { cases, .. } => cases.iter_mut().for_each(|c| split_emits(&mut c.body, skip)),
            S::Loop { body, continuing, .. } => {
                split_emits(body, skip);
                split_emits(continuing, skip);
            }
            _ => {}
        }
        block.push(s, span);
    }
}
