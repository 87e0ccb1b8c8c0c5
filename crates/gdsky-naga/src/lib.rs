//! # gdsky-naga: Godot sky shaders as naga IR
//!
//! Takes the front end's [`CheckedShader`](gdshader::CheckedShader) and builds a
//! [`naga::Module`] directly — arenas, types, constants, globals, functions and entry points —
//! with no GLSL or WGSL text in between, then validates it with naga and writes WGSL and
//! SPIR-V with naga's back ends. The stages, each with one public entry:
//!
//! * [`lower`] (`lower/`) walks the checked tree and builds the module as [`LowerOptions`] say
//!   (see its essay for the semantics written out explicitly: floored `mod`, NaN-proof
//!   `max`/`min`/`clamp`, lazy `&&`/`?:`, copy-in/copy-out `out` arguments, `bool` uniforms as
//!   `u32`), including Godot's sky wrapper (`lower/wrapper.rs`: the built-ins uniform of group
//!   0, per-pixel built-ins, the fullscreen-triangle vertex entry and one fragment entry per
//!   projection); `opt/` removes what no entry point needs before validation; `widen/` rewrites
//!   the module to f64 for [`Precision::F64`].
//! * [`validate`] (`valid.rs`) asks naga's validator, mapping a refusal to the user's lines.
//! * [`to_wgsl`] and [`to_spirv`] (`emit.rs`) write the module and read the text back with
//!   naga's own front ends before handing it out.
//! * [`reflect::reflection`] describes what a host needs to drive the module.
//! * [`trace`] instruments a validated module to record, per pixel, the first expression that
//!   made a NaN or an infinity (`gdsky render --trace-nonfinite`).
//!
//! Every naga expression carries the span of the shader text it came from, so a validation
//! error is reported at the user's file and line; code the wrapper injects carries no span and
//! is reported as the wrapper's.

mod emit;
mod lower;
mod opt;
pub mod reflect;
pub mod trace;
mod valid;
mod widen;

pub use emit::{EmitError, SpirvOptions, exact_arithmetic, reread_wgsl, to_spirv, to_spirv_with, to_wgsl};
pub use lower::{
    Debanding, GLOBAL_UNIFORM_GROUP, LowerOptions, Lowered, MATERIAL_GROUP, MAX_UNIFORM_BINDING_BYTES, Precision,
    SkyCoords, TextureSlot, UniformSlot, depth_convention, lower,
};
pub use valid::{validate, validator, validator_f64};
pub use widen::{F64_MATH_WGSL, F64Output};

/// Diagnostic code for a construct the lowering does not support yet.
pub const UNSUPPORTED: &str = "E600";
/// Diagnostic code for a module naga's validator rejects (a bug in gdsky's lowering).
pub const INVALID_MODULE: &str = "E601";
/// Diagnostic code for a back end that could not write the module.
pub const BACKEND: &str = "E602";
/// Diagnostic code for a `--set NAME=VALUE` that names no uniform or does not fit its type, or an
/// `--override NAME` that names no scalar material uniform.
pub const BAD_SET: &str = "E603";
/// Diagnostic code for emitted WGSL or SPIR-V that naga's own front end cannot read back or
/// validate (a bug in gdsky's translation; nothing is written).
pub const REREAD: &str = "E604";
