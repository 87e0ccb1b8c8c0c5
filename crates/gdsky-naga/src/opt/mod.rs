//! # Optimizing: skip what the scene does not need
//!
//! The lowering (`lower/`) writes what the shader says, in the order it says it; this stage,
//! run on the module after lowering and before validation ([`crate::lower_with`], so every
//! caller — `convert`, `render`, the benches, build scripts and tests — gets it), removes what no
//! entry point needs and loads uniforms once, at function entry. It never changes a value the shader computes: the images of the Freeman
//! sky stay bit-identical to the hand-written port (`crates/skyrun/tests/gpu/hand_port.rs`).
//!
//! * **Pruning** (`prune.rs`): functions no entry point calls are dropped; `let` values nothing
//!   reads and constants no function reads lose their name (`uses.rs` finds what a function
//!   uses), so that naga's compaction (`naga::compact::compact` with
//!   `KeepUnused::Yes`) drops them with the anonymous types and the expressions nothing uses —
//!   a value the source computes and never reads leaves no code. Global variables stay: each is
//!   a binding a host may set (built-ins read by no code were never declared: the wrapper only
//!   declares the per-pixel built-ins the shader uses and loads fields of the built-ins block
//!   only where they are read).
//! * **Uniform loads at function entry** (`hoist.rs`): each load of a uniform block's member
//!   with constant indices (`material.x`, `sky_builtins.lights[0].direction`) is emitted at the
//!   top of its function instead of where the source reads it — the same value (a uniform does
//!   not change during a draw) and always in bounds, so it changes no result; loop-invariant
//!   reads are outside the loops from the start. Measured on the Freeman sky: converted/hand
//!   ~1.01 → ~0.976 (`cargo bench -p skyrun --bench render`); lavapipe did not hoist them all
//!   itself. Only `Emit` statements move, no expression changes handle.
//! * **Store-to-load forwarding and dead stores** (`forward.rs`, run first, so that `prune`'s
//!   compaction drops what it leaves unused): a load of a local variable (or of one
//!   constant-index part, `x.y`) whose last write is certainly a store of the whole variable is
//!   that store's value — across `if`s, switches and loops that do not write the variable, into
//!   nested blocks, never out of them; a write through a part of the variable, or a call given a
//!   pointer into it (`out`/`inout`), forgets it, and a loop forgets, inside it, every variable it
//!   writes. Only a run-time value is forwarded (a constant, or a value of uniforms only, which
//!   `--override` would make an override expression, stays behind its variable: forwarded, the
//!   expressions using it would become WGSL constant expressions, evaluated by the WGSL front end
//!   when the shader or pipeline is created). Then every store to a variable nothing reads any
//!   more is removed, and the variable with it. On the Freeman sky (both `fixtures/freeman_sky`
//!   and `shaders/freeman_stable`): 18 → 17 function `var`s (`hits_ground`), loads of locals
//!   39 → 28, stores 37 → 35; SPIR-V 17 420 → 17 160 bytes and 19 116 → 18 856 bytes. Render
//!   time unchanged: converted/hand 0.984 before, 0.985 after, and the old WGSL 0.976 in the
//!   same rounds (60, `GDSKY_BENCH_WGSL`) — lavapipe's LLVM promotes the locals itself; the
//!   pass is for smaller, more readable output.
//!
//! Parts of the clean-up live where the information is, in the lowering:
//!
//! * a local the function never writes after its initializer (no assignment, `++`/`--`, or
//!   `out` argument names it) is a named value, a WGSL `let`, not a `var` with a store and loads
//!   (`FnCtx::declare_let`); a constant initializer keeps folding through it, which is what
//!   makes a baked uniform (`--set`) fold on through the locals computed from it;
//! * `max`/`min`/`clamp` with an operand that is a constant other than NaN (a literal, a folded
//!   constant, a baked uniform), or the result of such a comparison and select (never NaN
//!   itself), is one comparison and one select instead of two NaN bit tests around `max`, with
//!   the same IEEE maxNum result (`calls.rs`, `max_num`): `clamp(x, 0.5, uniform)` has no bit
//!   test at all (the Freeman sky's altitude clamp; converted/hand ~1.02 → ~1.01);
//! * an `if` on a constant condition (a baked `bool`, a comparison of baked values) lowers only
//!   the branch taken (`stmt.rs`).
//!
//! **Overrides** (`overrides.rs`, `--override NAME`, [`crate::lower_with_overrides`]): a scalar
//! uniform becomes a WGSL `override` with an `@id` and the uniform's default, so one module
//! serves many values, set when the pipeline is created (wgpu's
//! `PipelineCompilationOptions::constants`, keyed by the id). The loads of the uniform's member
//! of the material block become the override's value in place; the member itself stays (unread),
//! so the block's layout is the same whichever uniforms are overridden. naga 30's SPIR-V writer
//! has no specialization constants (it refuses any override), so a module with overrides is
//! WGSL only.

mod forward;
mod hoist;
pub(crate) mod overrides;
mod prune;
mod uses;

pub(crate) use uses::operands;

/// Runs every pass on a lowered module.
pub fn optimize(module: &mut naga::Module) {
    // Forwarding first, so that the compaction in `prune` drops the loads and stores it left
    // unused; the variables left without a use go after that.
    forward::forward(module);
    prune::prune(module);
    forward::drop_unused_locals(module);
    hoist::hoist_uniform_loads(module);
}
