//! Diagnostic codes, one per kind of problem, grouped by the stage that reports them.
//!
//! Codes are stable: tools match on them. `E0xx` input bytes and preprocessor, `E1xx` syntax,
//! `E2xx` names and scopes, `E3xx` types, `E4xx` Godot's sky-shader rules, `E5xx` limits that keep
//! the compiler safe on hostile input, `W0xx` warnings.

/// The file is not valid UTF-8.
pub const INVALID_UTF8: &str = "E001";
/// A NUL or other control character in the source.
pub const INVALID_CHARACTER: &str = "E002";
/// An `#error` directive was reached.
pub const PP_ERROR_DIRECTIVE: &str = "E010";
/// A directive the preprocessor does not know, or a malformed one.
pub const PP_BAD_DIRECTIVE: &str = "E011";
/// `#if` / `#ifdef` without `#endif`, or `#else`/`#elif`/`#endif` without `#if`.
pub const PP_UNBALANCED_CONDITIONAL: &str = "E012";
/// A macro defined twice.
pub const PP_MACRO_REDEFINED: &str = "E013";
/// A function-like macro called with the wrong number of arguments, or never closed.
pub const PP_MACRO_ARGUMENTS: &str = "E014";
/// An `#if` expression that cannot be evaluated.
pub const PP_BAD_EXPRESSION: &str = "E015";
/// An `#include` that cannot be read, or nests too deep, or forms a cycle.
pub const PP_INCLUDE: &str = "E016";
/// Macro expansion that grows without bound.
pub const PP_EXPANSION_LIMIT: &str = "E017";

/// The text does not follow the grammar.
pub const SYNTAX: &str = "E100";
/// A malformed number literal (`2f`, `1e`, a hex literal over 0xFFFFFFFF).
pub const BAD_LITERAL: &str = "E101";
/// `shader_type` missing, repeated, or not `sky`.
pub const SHADER_TYPE: &str = "E102";
/// An unknown `render_mode`.
pub const UNKNOWN_RENDER_MODE: &str = "E103";

/// A name that is not declared here.
pub const UNDECLARED: &str = "E200";
/// A name declared twice in one scope.
pub const REDECLARED: &str = "E201";
/// A built-in used outside the function where it exists.
pub const BUILTIN_SCOPE: &str = "E202";
/// An assignment to something that cannot be written: a constant, uniform, read-only built-in,
/// or an expression that is not a variable.
pub const NOT_ASSIGNABLE: &str = "E203";
/// `break` / `continue` outside a loop or switch.
pub const MISPLACED_JUMP: &str = "E204";

/// Operand types that do not fit the operator, assignment or initializer.
pub const TYPE_MISMATCH: &str = "E300";
/// No overload of a function or constructor takes these arguments.
pub const NO_MATCHING_OVERLOAD: &str = "E301";
/// An unknown type name.
pub const UNKNOWN_TYPE: &str = "E302";
/// A bad swizzle or member access.
pub const BAD_MEMBER: &str = "E303";
/// A bad index: not an int, out of range, or on a type that cannot be indexed.
pub const BAD_INDEX: &str = "E304";
/// A `return` that does not match the function's return type, or a missing one.
pub const BAD_RETURN: &str = "E305";
/// Something that must be a compile-time constant is not.
pub const NOT_CONSTANT: &str = "E306";
/// A bad array size or array initializer.
pub const BAD_ARRAY: &str = "E307";
/// A bad `switch`: non-int selector, non-constant or duplicate `case`.
pub const BAD_SWITCH: &str = "E308";
/// A call to something that is not a function.
pub const NOT_CALLABLE: &str = "E309";
/// An integer `/` or `%` by a constant zero where Godot evaluates the expression (a global
/// constant, a local `const`, an array size, an expression statement): "Division by zero
/// error." / "Modulo by zero error.".
pub const DIVISION_BY_ZERO: &str = "E310";

/// A function calls itself, directly or through others.
pub const RECURSION: &str = "E400";
/// `discard` is not allowed in sky shaders.
pub const DISCARD: &str = "E401";
/// `sky()` must be `void sky()`.
pub const BAD_SKY_SIGNATURE: &str = "E402";
/// A uniform hint that does not fit the uniform, or whose arguments are wrong.
pub const BAD_HINT: &str = "E403";
/// A declaration Godot does not allow in sky shaders (global variables, instance uniforms,
/// sampler defaults, ...).
pub const NOT_ALLOWED: &str = "E404";
/// A read of a `hint_screen_texture` uniform in a sky shader: Godot 4.6 accepts the declaration
/// but compiles the read into its `color_buffer`, which sky shaders do not have.
pub const SCREEN_TEXTURE_READ: &str = "E405";

/// Brackets or statements nested deeper than the compiler accepts.
pub const NESTING_LIMIT: &str = "E500";
/// A size or count beyond what the compiler accepts.
pub const SIZE_LIMIT: &str = "E501";

/// A `/*` comment that is never closed (Godot's preprocessor: "Block comment mismatch").
pub const UNCLOSED_COMMENT: &str = "E018";
/// The shader has no `sky()` function and renders black.
pub const NO_SKY_FUNCTION: &str = "W002";
/// A `hint_range` Godot accepts but that cannot work as written (empty range, step ≤ 0,
/// default outside the range).
pub const SUSPICIOUS_HINT: &str = "W004";
/// A `hint_screen_texture` uniform in a sky shader: accepted, but there is no screen texture to
/// read, and reading it is an error ([`SCREEN_TEXTURE_READ`]).
pub const SCREEN_TEXTURE_IN_SKY: &str = "W005";
