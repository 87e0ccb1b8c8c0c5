//! Compiling `.gdshader` files from a build script: [`crate::convert`], then the files.
//!
//! ```no_run
//! // In build.rs, inside `fn main()`:
//! gdsky::build::compile("shaders/freeman_sky.gdshader").expect("sky shader compiles");
//! ```
//!
//! [`compile`] writes `<stem>.wgsl`, `<stem>.spv`, `<stem>.json` and `<stem>.rs` into `OUT_DIR`
//! as a set, prints `cargo:rerun-if-changed` for the shader and every file it includes, and each
//! warning of the shader as a `cargo:warning`. `<stem>.rs` holds a `#[repr(C)]` bytemuck struct
//! of the material block (`FreemanSkyMaterial` for `freeman_sky.gdshader`) whose `Default` is the
//! shader's defaults, with explicit padding so its layout is the WGSL layout; include it with
//! `include!(concat!(env!("OUT_DIR"), "/freeman_sky.rs"));` in a crate that depends on
//! `bytemuck` with its `derive` feature. Beside them, once for all the crate's shaders,
//! [`BUILTINS_FILE`] (`sky_builtins.rs`): the built-ins block every module reads, as
//! `SkyBuiltins` and `SkyLight` with their offsets asserted at compile time —
//! `include!(concat!(env!("OUT_DIR"), "/sky_builtins.rs"));` — for a renderer that fills the
//! block itself rather than through the runtime crate skydraw (which has the same structs).
//!
//! [`compile_with`] takes [`Options`]: uniforms baked into the shader as constants (`--set` of
//! `gdsky convert`) and uniforms emitted as pipeline-overridable constants (`--override`). Both
//! leave the material struct and the reflection's `uniforms`, and are listed in its `baked` and
//! `overrides`.
//!
//! ```no_run
//! let options = gdsky::Options::new().set("view_samples", "16").override_uniform("sun_intensity");
//! gdsky::build::compile_with("shaders/freeman_sky.gdshader", &options).expect("sky shader compiles");
//! ```
//!
//! An error is returned, not printed: `.expect(..)` shows it once, rendered as `gdsky check`
//! renders diagnostics (file:line:col, the line, a caret).

pub use crate::{ConvertError, Options, Written as Compiled};
use std::fmt;
use std::path::{Path, PathBuf};

/// Why [`compile`] failed. `Display` and `Debug` print the same readable text.
pub enum BuildError {
    /// `OUT_DIR` is not set: not running under cargo.
    NoOutDir,
    /// The shader could not be read, or an output could not be written.
    Io(PathBuf, std::io::Error),
    /// The shader is invalid or cannot be translated; its diagnostics.
    Shader(ConvertError),
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BuildError::NoOutDir => f.write_str("OUT_DIR is not set (gdsky::build::compile runs from a build script)"),
            BuildError::Io(path, err) => write!(f, "{}: {err}", path.display()),
            BuildError::Shader(diagnostics) => write!(f, "the shader did not compile:\n{diagnostics}"),
        }
    }
}

impl fmt::Debug for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

impl std::error::Error for BuildError {}

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
    let converted =
        crate::convert_file(shader, options).map_err(|e| BuildError::Io(shader.to_path_buf(), e))?.map_err(|e| {
            // The files the front end did read still decide when cargo runs the script again.
            for file in e.sources().paths().filter(|p| *p != shader) {
                println!("cargo:rerun-if-changed={}", file.display());
            }
            BuildError::Shader(e)
        })?;
    for include in &converted.includes {
        println!("cargo:rerun-if-changed={}", include.display());
    }
    // One line each, as cargo shows them: `warning[W100]: … (at sky.gdshader:3:5)`.
    let lines: Vec<&str> = converted.warnings.lines().collect();
    for (i, line) in lines.iter().enumerate().filter(|(_, l)| l.starts_with("warning")) {
        let at = lines[i + 1..].iter().find_map(|l| l.trim_start().strip_prefix("--> "));
        match at {
            Some(at) => println!("cargo:warning={line} (at {at})"),
            None => println!("cargo:warning={line}"),
        }
    }
    let written = converted.write_into(out_dir).map_err(|e| BuildError::Io(out_dir.to_path_buf(), e))?;
    // One file for every shader of the crate; rewritten only when gdsky's text changed, so
    // cargo sees no change when several shaders compile in one script.
    let builtins = out_dir.join(BUILTINS_FILE);
    if std::fs::read(&builtins).ok().as_deref() != Some(skycore::SKY_BUILTINS_RS.as_bytes()) {
        skycore::io::write_atomically(&builtins, skycore::SKY_BUILTINS_RS.as_bytes())
            .map_err(|e| BuildError::Io(builtins.clone(), e))?;
    }
    Ok(written)
}

/// The file [`compile`] writes beside the shaders: the built-ins block every module reads
/// (group 0, binding 0) as `#[repr(C)]` bytemuck structs `SkyBuiltins` and `SkyLight`, their
/// `Default` (luminance multiplier 1) and `offsets`, asserted at compile time; the text the
/// runtime crate skydraw compiles ([`skycore::SKY_BUILTINS_RS`]).
pub const BUILTINS_FILE: &str = "sky_builtins.rs";
