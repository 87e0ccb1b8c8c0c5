//! Compiling `.gdshader` files from a build script.
//!
//! ```no_run
//! // In build.rs, inside `fn main()`:
//! gdsky::build::compile("shaders/freeman_sky.gdshader").expect("sky shader compiles");
//! ```
//!
//! [`compile`] writes `<stem>.wgsl`, `<stem>.spv`, `<stem>.json` and `<stem>.rs` into `OUT_DIR`,
//! and prints `cargo:rerun-if-changed` for the shader and every file it includes. `<stem>.rs`
//! holds a `#[repr(C)]` bytemuck struct of the material block (`FreemanSkyMaterial` for
//! `freeman_sky.gdshader`) whose `Default` is the shader's defaults, with explicit padding so its
//! layout is the WGSL layout; include it with
//! `include!(concat!(env!("OUT_DIR"), "/freeman_sky.rs"));` in a crate that depends on
//! `bytemuck` with its `derive` feature.
//!
//! [`compile_with`] takes [`Options`]: uniforms baked into the shader as constants (`--set` of
//! `gdsky convert`) and uniforms emitted as pipeline-overridable constants (`--override`). Both
//! leave the material struct and the reflection's `uniforms`, and are listed in its `baked` and
//! `overrides`.
//!
//! ```no_run
//! let options = gdsky::build::Options::new().set("view_samples", "16").override_uniform("sun_intensity");
//! gdsky::build::compile_with("shaders/freeman_sky.gdshader", &options).expect("sky shader compiles");
//! ```

use gdshader::check::consteval::ConstValue;
use gdshader::check::types::{Scalar, Type};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What [`compile`] wrote.
#[derive(Debug, Clone)]
pub struct Compiled {
    /// WGSL, all entry points.
    pub wgsl: PathBuf,
    /// SPIR-V 1.3, all entry points.
    pub spirv: PathBuf,
    /// Reflection JSON.
    pub reflection: PathBuf,
    /// The Rust material struct.
    pub rust: PathBuf,
}

/// Why [`compile`] failed. The diagnostics have been printed to stderr already, where cargo shows
/// them with the build script's output.
#[derive(Debug)]
pub enum BuildError {
    /// `OUT_DIR` is not set: not running under cargo.
    NoOutDir,
    /// The shader could not be read, or an output could not be written.
    Io(PathBuf, std::io::Error),
    /// The shader is invalid or cannot be translated yet; the rendered diagnostics.
    Shader(String),
}

impl std::fmt::Display for BuildError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BuildError::NoOutDir => f.write_str("OUT_DIR is not set (gdsky::build::compile runs from a build script)"),
            BuildError::Io(path, err) => write!(f, "{}: {err}", path.display()),
            BuildError::Shader(diagnostics) => {
                write!(f, "the shader did not compile:\n{diagnostics}")
            }
        }
    }
}

impl std::error::Error for BuildError {}

/// How [`compile_with`] specializes the shader; the default changes nothing.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Options {
    /// Uniforms baked into the shader as constants, each with the text of its value as
    /// `gdsky convert --set NAME=VALUE` takes it (`1.5`, `24`, `true`, `0.1,0.2,0.3`); when a
    /// name comes twice the last value counts.
    pub set: Vec<(String, String)>,
    /// Scalar material uniforms emitted as pipeline-overridable constants (WGSL `override`
    /// `@id(k)` and SPIR-V specialization constant `SpecId k` for the k-th name), as
    /// `gdsky convert --override NAME` does.
    pub overrides: Vec<String>,
}

impl Options {
    /// No bakes, no overrides.
    pub fn new() -> Self {
        Self::default()
    }

    /// Bakes uniform `name` at `value` (the text `--set NAME=VALUE` takes).
    pub fn set(mut self, name: impl Into<String>, value: impl Into<String>) -> Self {
        self.set.push((name.into(), value.into()));
        self
    }

    /// Emits uniform `name` as the next pipeline-overridable constant.
    pub fn override_uniform(mut self, name: impl Into<String>) -> Self {
        self.overrides.push(name.into());
        self
    }
}

/// Compiles a sky shader into `OUT_DIR` (see the module documentation).
pub fn compile(shader: impl AsRef<Path>) -> Result<Compiled, BuildError> {
    compile_with(shader, &Options::default())
}

/// Like [`compile`], with uniforms baked or overridden as `options` says.
pub fn compile_with(shader: impl AsRef<Path>, options: &Options) -> Result<Compiled, BuildError> {
    let out_dir = std::env::var_os("OUT_DIR").map(PathBuf::from).ok_or(BuildError::NoOutDir)?;
    compile_into_with(shader.as_ref(), &out_dir, options)
}

/// Like [`compile`], into a given directory.
pub fn compile_into(shader: &Path, out_dir: &Path) -> Result<Compiled, BuildError> {
    compile_into_with(shader, out_dir, &Options::default())
}

/// Like [`compile_with`], into a given directory. A name that is no uniform, a value that does
/// not fit its uniform, or an override of something other than a scalar material uniform comes
/// back as [`BuildError::Shader`] with the E603 diagnostics.
pub fn compile_into_with(shader: &Path, out_dir: &Path, options: &Options) -> Result<Compiled, BuildError> {
    println!("cargo:rerun-if-changed={}", shader.display());
    let front = crate::check_file(shader).map_err(|e| BuildError::Io(shader.to_path_buf(), e))?;
    for include in &front.preprocessed.includes {
        println!("cargo:rerun-if-changed={}", include.display());
    }
    let render = |d: &[gdshader::Diagnostic]| gdshader::diag::render_human(&front.db, d, false);
    let fail = |text: String| {
        eprint!("{text}");
        BuildError::Shader(text)
    };
    let Some(checked) = front.shader.as_ref() else {
        return Err(fail(render(&front.diagnostics)));
    };
    let baked: HashMap<String, String> = options.set.iter().cloned().collect();
    let lowered = gdsky_naga::lower_with_overrides(&front, &baked, &options.overrides).map_err(|d| fail(render(&d)))?;
    let stem = shader.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "shader".into());
    write_lowered_with(&front, checked, &lowered, &baked, &stem, out_dir)
}

/// The second half of [`compile_into`]: emits a lowered shader as `<stem>.{wgsl,spv,json,rs}` in
/// `out_dir`. Both texts are read back and validated by naga before anything is written, so a
/// module that does not hold up (a gdsky bug) leaves `out_dir` as it was and comes back as
/// [`BuildError::Shader`] with an E604 diagnostic at the user's function.
pub fn write_lowered(
    front: &gdshader::FrontendOutput,
    checked: &gdshader::CheckedShader,
    lowered: &gdsky_naga::Lowered,
    stem: &str,
    out_dir: &Path,
) -> Result<Compiled, BuildError> {
    write_lowered_with(front, checked, lowered, &HashMap::new(), stem, out_dir)
}

/// Like [`write_lowered`], for a shader lowered with the uniforms of `baked` (name to the text of
/// its value) baked in: the reflection lists them in `baked`.
pub fn write_lowered_with(
    front: &gdshader::FrontendOutput,
    checked: &gdshader::CheckedShader,
    lowered: &gdsky_naga::Lowered,
    baked: &HashMap<String, String>,
    stem: &str,
    out_dir: &Path,
) -> Result<Compiled, BuildError> {
    let fail = |e: gdsky_naga::EmitError| {
        let text = gdshader::diag::render_human(&front.db, &[e.diagnostic(front)], false);
        eprint!("{text}");
        BuildError::Shader(text)
    };
    let wgsl = gdsky_naga::to_wgsl(lowered).map_err(fail)?;
    let words = gdsky_naga::to_spirv(lowered).map_err(fail)?;
    let reflection = gdsky_naga::reflect::reflection(stem, checked, lowered, baked);
    let rust = material_struct(stem, checked, lowered);
    let compiled = Compiled {
        wgsl: out_dir.join(format!("{stem}.wgsl")),
        spirv: out_dir.join(format!("{stem}.spv")),
        reflection: out_dir.join(format!("{stem}.json")),
        rust: out_dir.join(format!("{stem}.rs")),
    };
    let spirv: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let json = serde_json::to_string_pretty(&reflection).unwrap_or_default();
    for (path, bytes) in [
        (&compiled.wgsl, wgsl.as_bytes()),
        (&compiled.spirv, &spirv[..]),
        (&compiled.reflection, json.as_bytes()),
        (&compiled.rust, rust.as_bytes()),
    ] {
        // The one safe writer: atomic (cargo never sees a half-written file), through a symbolic
        // link to its target, never over a directory or special file.
        skycore::io::write_atomically(path, bytes).map_err(|e| BuildError::Io(path.clone(), e))?;
    }
    Ok(compiled)
}

/// `freeman_sky` → `FreemanSky`.
fn camel(stem: &str) -> String {
    stem.split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|w| !w.is_empty())
        .map(|w| {
            let mut c = w.chars();
            c.next().map(|f| f.to_ascii_uppercase().to_string() + c.as_str()).unwrap_or_default()
        })
        .collect()
}

/// The Rust type of a material field and its value written as Rust.
fn rust_field(ty: &Type) -> Option<&'static str> {
    Some(match ty {
        Type::Scalar(Scalar::Float) => "f32",
        Type::Scalar(Scalar::Int) => "i32",
        Type::Scalar(Scalar::UInt | Scalar::Bool) => "u32",
        Type::Vector(Scalar::Float, 2) => "[f32; 2]",
        Type::Vector(Scalar::Float, 3) => "[f32; 3]",
        Type::Vector(Scalar::Float, 4) => "[f32; 4]",
        Type::Vector(Scalar::Int, 2) => "[i32; 2]",
        Type::Vector(Scalar::Int, 3) => "[i32; 3]",
        Type::Vector(Scalar::Int, 4) => "[i32; 4]",
        Type::Vector(Scalar::UInt | Scalar::Bool, 2) => "[u32; 2]",
        Type::Vector(Scalar::UInt | Scalar::Bool, 3) => "[u32; 3]",
        Type::Vector(Scalar::UInt | Scalar::Bool, 4) => "[u32; 4]",
        Type::Matrix(2) => "[[f32; 2]; 2]",
        Type::Matrix(3) => "[[f32; 4]; 3]",
        Type::Matrix(4) => "[[f32; 4]; 4]",
        _ => return None,
    })
}

fn rust_value(ty: &Type, v: Option<&ConstValue>) -> String {
    let scalar = |s: Scalar, v: Option<&ConstValue>| match (s, v.and_then(|v| v.convert(s))) {
        (Scalar::Float, Some(ConstValue::Float(f))) => format!("{:?}_f32", f as f32),
        (Scalar::Int, Some(ConstValue::Int(i))) => format!("{i}_i32"),
        (Scalar::UInt, Some(ConstValue::UInt(u))) => format!("{u}_u32"),
        (Scalar::Bool, Some(ConstValue::Bool(b))) => format!("{}_u32", u32::from(b)),
        (Scalar::Float, _) => "0.0_f32".into(),
        (Scalar::Int, _) => "0_i32".into(),
        _ => "0_u32".into(),
    };
    match (ty, v) {
        (Type::Scalar(s), v) => scalar(*s, v),
        (Type::Vector(s, _), Some(ConstValue::Composite(items))) => {
            format!("[{}]", items.iter().map(|i| scalar(*s, Some(i))).collect::<Vec<_>>().join(", "))
        }
        (Type::Vector(s, n), _) => format!("[{}; {n}]", scalar(*s, None)),
        _ => "bytemuck::Zeroable::zeroed()".into(),
    }
}

/// The generated Rust source of the material struct.
fn material_struct(stem: &str, shader: &gdshader::CheckedShader, lowered: &gdsky_naga::Lowered) -> String {
    let name = format!("{}Material", camel(stem));
    let mut fields: Vec<(&str, &gdsky_naga::UniformSlot, Option<&ConstValue>)> = shader
        .uniforms
        .iter()
        .filter_map(|u| lowered.uniforms.get(&u.name).map(|slot| (u.name.as_str(), slot, u.default.as_ref())))
        .collect();
    fields.sort_by_key(|(_, s, _)| s.offset);
    let mut out = String::new();
    let _ = writeln!(out, "// Generated by gdsky::build from {stem}.gdshader. Do not edit.");
    let _ = writeln!(
        out,
        "/// The material uniform block of `{stem}.gdshader` (bind group {}, binding 0), laid out as WGSL lays it out.",
        gdsky_naga::MATERIAL_GROUP
    );
    let _ = writeln!(
        out,
        "#[repr(C)]\n#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]\npub struct {name} {{"
    );
    let mut at = 0u32;
    let mut pads = 0;
    let mut written = Vec::new();
    for (field, slot, _) in &fields {
        let Some(rust_ty) = rust_field(&slot.ty) else {
            continue;
        };
        if slot.offset > at {
            let _ = writeln!(out, "    pub _pad{pads}: [u8; {}],", slot.offset - at);
            pads += 1;
        }
        let _ = writeln!(out, "    pub {field}: {rust_ty},");
        at = slot.offset + slot.size;
        written.push(*field);
    }
    if lowered.material_size > at {
        let _ = writeln!(out, "    pub _pad{pads}: [u8; {}],", lowered.material_size - at);
    }
    let _ = writeln!(out, "}}\n");
    let _ = writeln!(out, "impl {name} {{");
    let _ = writeln!(out, "    /// Each field's name and byte offset, as rustc laid the struct out.");
    let _ = writeln!(out, "    pub const FIELDS: &'static [(&'static str, usize)] = &[");
    for f in &written {
        let _ = writeln!(out, "        (\"{f}\", core::mem::offset_of!({name}, {f})),");
    }
    let _ = writeln!(out, "    ];\n}}\n");
    let _ = writeln!(
        out,
        "impl Default for {name} {{\n    /// The shader's defaults (zero where it gives none).\n    fn default() -> Self {{"
    );
    let _ = writeln!(out, "        let mut m: Self = bytemuck::Zeroable::zeroed();");
    for (field, slot, default) in &fields {
        if rust_field(&slot.ty).is_some() {
            let _ = writeln!(out, "        m.{field} = {};", rust_value(&slot.ty, *default));
        }
    }
    let _ = writeln!(out, "        m\n    }}\n}}");
    out
}
