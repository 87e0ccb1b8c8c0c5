//! Store-to-load forwarding and dead-store removal for function-local variables.
//!
//! The lowering writes a GLSL local that is assigned after its declaration as a naga local
//! variable: a `Store` for each assignment, a `Load` for each read. This pass replaces a load
//! by the value last stored when that store is known to be the last write, and then removes the
//! stores to a variable nothing reads any more; `opt::prune`'s compaction drops what only they
//! used, and [`drop_unused_locals`] the variables left without a use.
//!
//! **Forwarding.** The body is walked in execution order with, for each local variable, the
//! value of the last `Store` of the whole variable (`x = v`) that is certainly the last write:
//!
//! * a `Store` to the whole variable records its value; a `Store` through a part of it
//!   (`x.y = …`, `x[i] = …`) forgets the variable, and so does a `Call` given a pointer into it
//!   (an `out`/`inout` argument). A pointer argument or a global cannot point into this
//!   function's own locals, so stores through them change nothing here;
//! * a nested block (`if`, `switch`, a loop, a plain block) starts with what is known before
//!   it, less, for a loop, every variable the loop writes anywhere (a later iteration sees the
//!   writes of the earlier ones); after it, every variable written anywhere inside it is
//!   forgotten, and what was learnt inside is dropped (it is not known on every path, and a
//!   value emitted inside a block is out of scope after it);
//! * a `Load` of the whole variable emitted while a value is known is that value: every use of
//!   the load becomes a use of the value. A `Load` of one constant-index part (`x.y`, an
//!   `AccessIndex` straight on the variable) becomes that part of the value, in place (the
//!   expression keeps its handle and its `Emit`).
//!
//! The value was in scope at the store (the validator checked that), the load is emitted after
//! the store in the same block or in a block nested in a later statement, and the load's uses
//! come after the load, inside the same block: the value is in scope wherever the load was used.
//!
//! Only a value computed at run time is forwarded (it depends on a function argument, a call's
//! result, or a load of a local or private variable): a load is a run-time value in WGSL, and
//! forwarding a constant (`x = 0.0; … x * 1e38`) would turn the expressions using the load into
//! WGSL constant expressions that naga's WGSL front end evaluates when the shader is created,
//! with its own arithmetic and an error on overflow. A uniform's load does not count as run
//! time either: `--override` turns it into an override, evaluated at pipeline creation.
//!
//! **Dead stores.** A local variable that no used expression reads (no `Load` of it or of a
//! pointer into it, no pointer into it given to a call) loses all its stores; repeated, since a
//! removed store may leave another variable unread. A function with a statement or expression
//! kind gdsky never writes is left as it is.

use super::uses::{operands, roots};
use naga::{AddressSpace, Block, Expression as E, Function, Handle, LocalVariable, Module, Statement as S};
use std::collections::{HashMap, HashSet};

type H = Handle<E>;
type Var = Handle<LocalVariable>;

/// What the walk knows: the value each local variable certainly holds.
type Known = HashMap<Var, H>;

/// Forwards stores to loads and removes dead stores in every function and entry point.
pub fn forward(module: &mut Module) {
    let uniforms: HashSet<Handle<naga::GlobalVariable>> =
        module.global_variables.iter().filter(|(_, g)| g.space == AddressSpace::Uniform).map(|(h, _)| h).collect();
    for (_, f) in module.functions.iter_mut() {
        forward_function(f, &uniforms);
        remove_dead_stores(f);
    }
    for ep in &mut module.entry_points {
        forward_function(&mut ep.function, &uniforms);
        remove_dead_stores(&mut ep.function);
    }
}

/// The local variable `p` points into, through constant or dynamic indices; `None` when `p` is
/// not a pointer into a local.
fn local_root(f: &Function, mut p: H) -> Option<Var> {
    loop {
        match f.expressions[p] {
            E::LocalVariable(v) => return Some(v),
            E::AccessIndex { base, .. } | E::Access { base, .. } => p = base,
            _ => return None,
        }
    }
}

/// Whether a store through `p` can only write memory that is not a local of `f`: a global, or a
/// pointer argument (which cannot point into the callee's own locals).
fn outside_locals(f: &Function, mut p: H) -> bool {
    loop {
        match f.expressions[p] {
            E::GlobalVariable(_) | E::FunctionArgument(_) => return true,
            E::AccessIndex { base, .. } | E::Access { base, .. } => p = base,
            _ => return false,
        }
    }
}

/// Adds the local variables `block` may write to `out`; `None` for "any" (a statement this pass
/// does not know).
fn written(f: &Function, block: &Block, out: &mut HashSet<Var>) -> Option<()> {
    block.iter().try_for_each(|s| written_by(f, s, out))
}

/// Adds the local variables the statement `s` (and the blocks in it) may write to `out`.
fn written_by(f: &Function, s: &S, out: &mut HashSet<Var>) -> Option<()> {
    match s {
        S::Emit(_)
        | S::Break
        | S::Continue
        | S::Kill
        | S::Return { .. }
        | S::ControlBarrier(_)
        | S::MemoryBarrier(_)
        | S::ImageStore { .. } => {}
        S::Store { pointer, .. } => match local_root(f, *pointer) {
            Some(v) => {
                out.insert(v);
            }
            None if outside_locals(f, *pointer) => {}
            None => return None,
        },
        S::Call { arguments, .. } => out.extend(arguments.iter().filter_map(|a| local_root(f, *a))),
        S::Block(b) => written(f, b, out)?,
        S::If { accept, reject, .. } => {
            written(f, accept, out)?;
            written(f, reject, out)?;
        }
        S::Switch { cases, .. } => {
            for c in cases {
                written(f, &c.body, out)?;
            }
        }
        S::Loop { body, continuing, .. } => {
            written(f, body, out)?;
            written(f, continuing, out)?;
        }
        _ => return None,
    }
    Some(())
}

/// Which expressions are run-time values (see the module's essay): `true` for a function
/// argument, a call's result, a load of anything but a uniform, an image or derivative
/// operation, and for whatever has such an operand.
fn run_time(f: &Function, uniforms: &HashSet<Handle<naga::GlobalVariable>>) -> Vec<bool> {
    let mut rt = vec![false; f.expressions.len()];
    for (h, e) in f.expressions.iter() {
        rt[h.index()] = match e {
            E::FunctionArgument(_)
            | E::CallResult(_)
            | E::ImageSample { .. }
            | E::ImageLoad { .. }
            | E::ImageQuery { .. }
            | E::Derivative { .. } => true,
            E::Load { pointer } => !from_uniform(f, *pointer, uniforms),
            // A pointer is no value.
            E::LocalVariable(_) | E::GlobalVariable(_) => false,
            _ => operands(e).is_some_and(|ops| ops.iter().any(|o| rt.get(o.index()).copied().unwrap_or(false))),
        };
    }
    rt
}

/// Whether the pointer `p` points into a uniform block (or somewhere this pass cannot tell).
fn from_uniform(f: &Function, mut p: H, uniforms: &HashSet<Handle<naga::GlobalVariable>>) -> bool {
    loop {
        match f.expressions[p] {
            E::GlobalVariable(g) => return uniforms.contains(&g),
            E::LocalVariable(_) | E::FunctionArgument(_) => return false,
            E::AccessIndex { base, .. } | E::Access { base, .. } => p = base,
            _ => return true,
        }
    }
}

/// What the forwarding walk found.
#[derive(Default)]
struct Found {
    /// Loads of a whole variable, each with the value it is replaced by.
    replace: HashMap<H, H>,
    /// Loads of a part of a variable, each with the value whose part it becomes and the index.
    part: Vec<(H, H, u32)>,
}

struct Walk<'a> {
    f: &'a Function,
    run_time: Vec<bool>,
    found: Found,
}

impl Walk<'_> {
    /// `h` with every forwarded load it goes through replaced.
    fn resolve(&self, mut h: H) -> H {
        while let Some(&v) = self.found.replace.get(&h) {
            h = v;
        }
        h
    }

    /// Walks `block` starting from `known`; returns what is known at its end.
    fn block(&mut self, block: &Block, mut known: Known) -> Known {
        for s in block.iter() {
            match s {
                S::Emit(range) => {
                    for h in range.clone() {
                        self.load(h, &known);
                    }
                }
                S::Store { pointer, value } => match self.f.expressions[*pointer] {
                    E::LocalVariable(v) => {
                        let value = self.resolve(*value);
                        if self.run_time.get(value.index()).copied().unwrap_or(false) {
                            known.insert(v, value);
                        } else {
                            known.remove(&v);
                        }
                    }
                    _ => match local_root(self.f, *pointer) {
                        Some(v) => {
                            known.remove(&v);
                        }
                        None if outside_locals(self.f, *pointer) => {}
                        None => known.clear(),
                    },
                },
                S::Call { arguments, .. } => {
                    for a in arguments {
                        if let Some(v) = local_root(self.f, *a) {
                            known.remove(&v);
                        }
                    }
                }
                S::Block(_) | S::If { .. } | S::Switch { .. } | S::Loop { .. } => {
                    let mut w = HashSet::new();
                    let all = written_by(self.f, s, &mut w).is_none();
                    let mut after = known.clone();
                    if all {
                        after.clear();
                    } else {
                        after.retain(|v, _| !w.contains(v));
                    }
                    match s {
                        S::Block(b) => {
                            self.block(b, known.clone());
                        }
                        S::If { accept, reject, .. } => {
                            self.block(accept, known.clone());
                            self.block(reject, known.clone());
                        }
                        S::Switch { cases, .. } => {
                            for c in cases {
                                self.block(&c.body, known.clone());
                            }
                        }
                        S::Loop { body, continuing, .. } => {
                            // Only what the loop never writes holds on every iteration.
                            self.block(body, after.clone());
                            self.block(continuing, after.clone());
                        }
                        _ => {}
                    }
                    known = after;
                }
                S::Break
                | S::Continue
                | S::Kill
                | S::Return { .. }
                | S::ControlBarrier(_)
                | S::MemoryBarrier(_)
                | S::ImageStore { .. } => {}
                _ => known.clear(),
            }
        }
        known
    }

    /// Records the replacement of the emitted expression `h` when it is a load of a variable
    /// (or of one constant-index part of it) whose value is known.
    fn load(&mut self, h: H, known: &Known) {
        let E::Load { pointer } = self.f.expressions[h] else { return };
        match self.f.expressions[pointer] {
            E::LocalVariable(v) => {
                if let Some(&value) = known.get(&v) {
                    self.found.replace.insert(h, value);
                }
            }
            E::AccessIndex { base, index } => {
                if let E::LocalVariable(v) = self.f.expressions[base]
                    && let Some(&value) = known.get(&v)
                {
                    self.found.part.push((h, value, index));
                }
            }
            _ => {}
        }
    }
}

/// Replaces every operand of `e` by `m` of it; the kinds are those of [`operands`] (the caller
/// checked that it knows them all).
fn remap_expression(e: &mut E, m: &impl Fn(H) -> H) {
    let r = |h: &mut H| *h = m(*h);
    let ro = |h: &mut Option<H>| {
        if let Some(h) = h {
            *h = m(*h);
        }
    };
    match e {
        E::Compose { components, .. } => components.iter_mut().for_each(r),
        E::Access { base, index } => {
            *base = m(*base);
            *index = m(*index);
        }
        E::AccessIndex { base, .. } => *base = m(*base),
        E::Splat { value, .. } => *value = m(*value),
        E::Swizzle { vector, .. } => *vector = m(*vector),
        E::Load { pointer } => *pointer = m(*pointer),
        E::ImageSample { image, sampler, coordinate, array_index, offset, level, depth_ref, .. } => {
            *image = m(*image);
            *sampler = m(*sampler);
            *coordinate = m(*coordinate);
            ro(array_index);
            ro(offset);
            ro(depth_ref);
            match level {
                naga::SampleLevel::Auto | naga::SampleLevel::Zero => {}
                naga::SampleLevel::Exact(h) | naga::SampleLevel::Bias(h) => *h = m(*h),
                naga::SampleLevel::Gradient { x, y } => {
                    *x = m(*x);
                    *y = m(*y);
                }
            }
        }
        E::ImageLoad { image, coordinate, array_index, sample, level } => {
            *image = m(*image);
            *coordinate = m(*coordinate);
            ro(array_index);
            ro(sample);
            ro(level);
        }
        E::ImageQuery { image, query } => {
            *image = m(*image);
            if let naga::ImageQuery::Size { level: Some(l) } = query {
                *l = m(*l);
            }
        }
        E::Unary { expr, .. } | E::Derivative { expr, .. } | E::As { expr, .. } => *expr = m(*expr),
        E::Binary { left, right, .. } => {
            *left = m(*left);
            *right = m(*right);
        }
        E::Select { condition, accept, reject } => {
            *condition = m(*condition);
            *accept = m(*accept);
            *reject = m(*reject);
        }
        E::Relational { argument, .. } => *argument = m(*argument),
        E::Math { arg, arg1, arg2, arg3, .. } => {
            *arg = m(*arg);
            ro(arg1);
            ro(arg2);
            ro(arg3);
        }
        E::ArrayLength(h) => *h = m(*h),
        _ => {}
    }
}

/// Replaces the expressions `block`'s statements use by `m` of them; the kinds are those
/// [`roots`] knows (the caller checked).
fn remap_block(block: &mut Block, m: &impl Fn(H) -> H) {
    for s in block.iter_mut() {
        match s {
            S::Block(b) => remap_block(b, m),
            S::If { condition, accept, reject } => {
                *condition = m(*condition);
                remap_block(accept, m);
                remap_block(reject, m);
            }
            S::Switch { selector, cases } => {
                *selector = m(*selector);
                cases.iter_mut().for_each(|c| remap_block(&mut c.body, m));
            }
            S::Loop { body, continuing, break_if } => {
                if let Some(b) = break_if {
                    *b = m(*b);
                }
                remap_block(body, m);
                remap_block(continuing, m);
            }
            S::Return { value: Some(v) } => *v = m(*v),
            S::Store { pointer, value } => {
                *pointer = m(*pointer);
                *value = m(*value);
            }
            S::ImageStore { image, coordinate, array_index, value } => {
                *image = m(*image);
                *coordinate = m(*coordinate);
                *value = m(*value);
                if let Some(a) = array_index {
                    *a = m(*a);
                }
            }
            S::Call { arguments, .. } => arguments.iter_mut().for_each(|a| *a = m(*a)),
            _ => {}
        }
    }
}

/// Whether this pass knows every statement and expression kind of `f`.
fn known_kinds(f: &Function) -> bool {
    roots(&f.body, &mut Vec::new()) && f.expressions.iter().all(|(_, e)| operands(e).is_some())
}

fn forward_function(f: &mut Function, uniforms: &HashSet<Handle<naga::GlobalVariable>>) {
    if !known_kinds(f) {
        return;
    }
    let mut walk = Walk { f, run_time: run_time(f, uniforms), found: Found::default() };
    walk.block(&f.body, Known::new());
    let Found { replace, part } = walk.found;
    if replace.is_empty() && part.is_empty() {
        return;
    }
    let resolve = |mut h: H| {
        while let Some(&v) = replace.get(&h) {
            h = v;
        }
        h
    };
    for (h, value, index) in part {
        f.expressions[h] = E::AccessIndex { base: value, index };
    }
    for (_, e) in f.expressions.iter_mut() {
        remap_expression(e, &resolve);
    }
    remap_block(&mut f.body, &resolve);
    // A forwarded load that had a name (`float b = a;` with `a` a variable) gives it to its
    // value when that value is emitted and has none, so the WGSL keeps the source's name.
    let mut loads: Vec<(H, H)> = replace.iter().map(|(&l, &v)| (l, v)).collect();
    loads.sort_by_key(|(l, _)| l.index());
    for (load, value) in loads {
        if let Some(name) = f.named_expressions.shift_remove(&load) {
            let value = resolve(value);
            let emitted = !f.expressions[value].needs_pre_emit() && !matches!(f.expressions[value], E::CallResult(_));
            if emitted && !f.named_expressions.contains_key(&value) {
                f.named_expressions.insert(value, name);
            }
        }
    }
}

/// The local variables read by the expressions `f`'s statements use (directly or through
/// operands) or given by pointer to a call; `None` when `f` has a kind this pass does not know.
fn read_locals(f: &Function) -> Option<HashSet<Var>> {
    let mut direct = Vec::new();
    if !roots(&f.body, &mut direct) {
        return None;
    }
    let mut used = vec![false; f.expressions.len()];
    for h in direct {
        used[h.index()] = true;
    }
    let mut read = HashSet::new();
    for (h, e) in f.expressions.iter().rev() {
        if !used[h.index()] {
            continue;
        }
        let ops = operands(e)?;
        for &op in &ops {
            used[op.index()] = true;
        }
        match e {
            // Deriving a pointer reads nothing; its index is a value, marked used above.
            E::AccessIndex { .. } | E::Access { .. } | E::LocalVariable(_) => {}
            // Any other use of a pointer into a local (a load, or a kind that takes a pointer)
            // reads it.
            _ => read.extend(ops.iter().filter_map(|o| local_root(f, *o))),
        }
    }
    calls_with_pointers(f, &f.body, &mut read);
    Some(read)
}

/// Adds the local variables `block`'s calls are given a pointer into.
fn calls_with_pointers(f: &Function, block: &Block, out: &mut HashSet<Var>) {
    for s in block.iter() {
        match s {
            S::Call { arguments, .. } => out.extend(arguments.iter().filter_map(|a| local_root(f, *a))),
            S::Block(b) => calls_with_pointers(f, b, out),
            S::If { accept, reject, .. } => {
                calls_with_pointers(f, accept, out);
                calls_with_pointers(f, reject, out);
            }
            S::Switch { cases, .. } => cases.iter().for_each(|c| calls_with_pointers(f, &c.body, out)),
            S::Loop { body, continuing, .. } => {
                calls_with_pointers(f, body, out);
                calls_with_pointers(f, continuing, out);
            }
            _ => {}
        }
    }
}

/// Removes the stores to the local variables of `dead`; whether it removed any.
fn remove_stores(f: &Function, block: &mut Block, dead: &HashSet<Var>) -> bool {
    let old = std::mem::take(block);
    let mut removed = false;
    for (mut s, span) in old.span_into_iter() {
        match &mut s {
            S::Store { pointer, .. } if local_root(f, *pointer).is_some_and(|v| dead.contains(&v)) => {
                removed = true;
                continue;
            }
            S::Block(b) => removed |= remove_stores(f, b, dead),
            S::If { accept, reject, .. } => {
                removed |= remove_stores(f, accept, dead);
                removed |= remove_stores(f, reject, dead);
            }
            S::Switch { cases, .. } => {
                for c in cases.iter_mut() {
                    removed |= remove_stores(f, &mut c.body, dead);
                }
            }
            S::Loop { body, continuing, .. } => {
                removed |= remove_stores(f, body, dead);
                removed |= remove_stores(f, continuing, dead);
            }
            _ => {}
        }
        block.push(s, span);
    }
    removed
}

/// Removes every store to a local variable nothing reads, until none is left.
fn remove_dead_stores(f: &mut Function) {
    if !known_kinds(f) {
        return;
    }
    loop {
        let Some(read) = read_locals(f) else { return };
        let dead: HashSet<Var> = f.local_variables.iter().map(|(v, _)| v).filter(|v| !read.contains(v)).collect();
        let mut body = std::mem::take(&mut f.body);
        let removed = remove_stores(f, &mut body, &dead);
        f.body = body;
        if !removed {
            return;
        }
    }
}

/// Drops the local variables without an initializer that no expression of their function
/// names any more (run after compaction, when every expression left is used or named).
pub fn drop_unused_locals(module: &mut Module) {
    for (_, f) in module.functions.iter_mut() {
        drop_locals(f);
    }
    for ep in &mut module.entry_points {
        drop_locals(&mut ep.function);
    }
}

fn drop_locals(f: &mut Function) {
    let mut used = HashSet::new();
    for (_, e) in f.expressions.iter() {
        if let E::LocalVariable(v) = e {
            used.insert(*v);
        }
    }
    // A variable with an initializer stays: its initializer is an expression of the function
    // that dropping the variable would leave unused.
    let keep = |v: Var, lv: &LocalVariable| used.contains(&v) || lv.init.is_some();
    if f.local_variables.iter().all(|(v, lv)| keep(v, lv)) {
        return;
    }
    let old = std::mem::take(&mut f.local_variables);
    let mut map: HashMap<Var, Var> = HashMap::new();
    for (v, lv) in old.iter() {
        if keep(v, lv) {
            map.insert(v, f.local_variables.append(lv.clone(), old.get_span(v)));
        }
    }
    for (_, e) in f.expressions.iter_mut() {
        if let E::LocalVariable(v) = e
            && let Some(n) = map.get(v)
        {
            *v = *n;
        }
    }
}
