//! In-memory conversion: a `.gdshader`'s text in, WGSL, SPIR-V, the reflection and the Rust
//! material struct out, every stage's diagnostics located in the user's files.
//!
//! [`convert`] runs the whole pipeline: the front end (preprocess, parse, check with Godot's
//! rules), one lowering into a validated `naga::Module` with the sky wrapper, and emission,
//! where both texts are read back by naga's own front ends and validated before they are handed
//! out ([`emit`], the second half, for a module lowered elsewhere). Nothing touches the file
//! system but the loader of `#include`s, which the caller may replace ([`Options::include_loader`]);
//! [`Converted::write_into`] and [`crate::build`] write the files.

use gdshader::diag::render_human;
use gdshader::{Diagnostic, FrontendOutput, SourceDb};
use gdsky_naga::reflect::Reflection;
use gdsky_naga::{Debanding, LowerOptions, SkyCoords, SpirvOptions};
use skycore::DepthConvention;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Reads the file an `#include` names (the path resolved against the including file's folder).
pub type IncludeLoader = Arc<dyn Fn(&Path) -> std::io::Result<Vec<u8>> + Send + Sync>;

/// How [`convert`] translates a shader. The default changes nothing and follows the newest
/// Godot the oracle runs (4.6): a shader's own `render_mode use_debanding` honoured, SKY_COORDS
/// as Godot 4.6 computes it, the sky on the far plane of standard Z, includes read from the file
/// system, SPIR-V without debug names (the same bytes from every build of gdsky).
#[derive(Clone, Default)]
#[non_exhaustive]
pub struct Options {
    /// How the shader is lowered: uniforms baked into constants ([`Options::set`]), uniforms
    /// made pipeline-overridable constants ([`Options::override_uniform`]), Godot's debanding,
    /// SKY_COORDS and the depth convention. Its precision is always f32 here (WGSL has no f64).
    pub lowering: LowerOptions,
    /// What the SPIR-V carries besides the code ([`Options::spirv_debug_names`]).
    pub spirv: SpirvOptions,
    /// Reads `#include`d files; `None` reads them from the file system with gdsky's bounded
    /// reader.
    pub include_loader: Option<IncludeLoader>,
}

impl fmt::Debug for Options {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Options")
            .field("lowering", &self.lowering)
            .field("spirv", &self.spirv)
            .field("include_loader", &self.include_loader.as_ref().map(|_| "custom"))
            .finish()
    }
}

impl Options {
    /// No bakes, no overrides: Godot 4.6's defaults.
    pub fn new() -> Self {
        Self::default()
    }

    /// Bakes uniform `name` at `value` into the shader as a constant, as `gdsky convert --set
    /// NAME=VALUE` does (`1.5`, `24`, `true`, `0.1,0.2,0.3`); a name set twice keeps the last
    /// value. The uniform leaves the material block and the reflection lists it under `baked`.
    #[must_use]
    pub fn set(mut self, name: impl Into<String>, value: impl Into<String>) -> Self {
        self.lowering.baked.insert(name.into(), value.into());
        self
    }

    /// Emits scalar material uniform `name` as the next pipeline-overridable constant (WGSL
    /// `override` `@id(k)` and SPIR-V specialization constant `SpecId k` for the k-th name), as
    /// `gdsky convert --override NAME` does.
    #[must_use]
    pub fn override_uniform(mut self, name: impl Into<String>) -> Self {
        self.lowering.overrides.push(name.into());
        self
    }

    /// With Godot's debanding for shaders that declare `use_debanding`, or without it
    /// ([`Debanding::None`]).
    #[must_use]
    pub fn debanding(mut self, debanding: Debanding) -> Self {
        self.lowering.debanding = debanding;
        self
    }

    /// With SKY_COORDS computed as `sky_coords` says ([`SkyCoords::Exact`]: as Godot 4.3–4.5).
    #[must_use]
    pub fn sky_coords(mut self, sky_coords: SkyCoords) -> Self {
        self.lowering.sky_coords = sky_coords;
        self
    }

    /// With the sky on the far plane of `depth` (standard or reversed Z).
    #[must_use]
    pub fn depth(mut self, depth: DepthConvention) -> Self {
        self.lowering.depth = depth;
        self
    }

    /// With (or without) SPIR-V debug names (`OpName`: readable disassembly; about 12 % more
    /// bytes).
    #[must_use]
    pub fn spirv_debug_names(mut self, on: bool) -> Self {
        self.spirv.debug_names = on;
        self
    }

    /// Reads `#include`d files with `loader` (a path, resolved against the including file's
    /// folder, to its bytes) instead of the file system: shaders held in memory, an asset
    /// system, a virtual file system.
    #[must_use]
    pub fn include_loader(
        mut self,
        loader: impl Fn(&Path) -> std::io::Result<Vec<u8>> + Send + Sync + 'static,
    ) -> Self {
        self.include_loader = Some(Arc::new(loader));
        self
    }
}

/// A converted shader, in memory: what `gdsky convert` and [`crate::build`] write.
#[derive(Clone, Debug)]
pub struct Converted {
    /// The shader's name: the file stem of the name it was converted under (`freeman_sky`).
    pub name: String,
    /// WGSL, every entry point, read back and validated by naga's WGSL front end.
    pub wgsl: String,
    /// SPIR-V 1.3 (Vulkan), every entry point, read back and validated by naga's SPIR-V front end.
    pub spirv: Vec<u32>,
    /// What a host needs to drive it ([`Converted::reflection_json`] is the `<name>.json` file).
    pub reflection: Reflection,
    /// Rust source of the material block as a `#[repr(C)]` bytemuck struct (`FreemanSkyMaterial`
    /// for `freeman_sky`) whose `Default` is the shader's defaults; a comment when the shader has
    /// no material block. Needs `bytemuck` with its `derive` feature where it is included.
    pub rust: String,
    /// Every file read through `#include`, in order first read (for `cargo:rerun-if-changed`).
    pub includes: Vec<PathBuf>,
    /// The shader's warnings, rendered as `gdsky check` prints them (empty when there are none).
    pub warnings: String,
}

impl Converted {
    /// The SPIR-V as little-endian bytes (the `.spv` file).
    pub fn spirv_bytes(&self) -> Vec<u8> {
        self.spirv.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    /// The reflection as pretty-printed JSON (the `.json` file).
    pub fn reflection_json(&self) -> String {
        // Serialising plain structs of strings and numbers cannot fail.
        serde_json::to_string_pretty(&self.reflection).unwrap_or_default()
    }

    /// Writes `<name>.wgsl`, `<name>.spv`, `<name>.json` and `<name>.rs` into `dir` (which must
    /// exist) as a set: each is written to a temporary file first, and only when all four are
    /// on disk are they renamed into place, so a failure leaves the folder as it was.
    pub fn write_into(&self, dir: &Path) -> std::io::Result<Written> {
        let written = Written::in_dir(dir, &self.name);
        let files: [(&Path, Vec<u8>); 4] = [
            (&written.wgsl, self.wgsl.clone().into_bytes()),
            (&written.spirv, self.spirv_bytes()),
            (&written.reflection, self.reflection_json().into_bytes()),
            (&written.rust, self.rust.clone().into_bytes()),
        ];
        skycore::io::write_set(&files.iter().map(|(p, b)| (*p, b.as_slice())).collect::<Vec<_>>())?;
        Ok(written)
    }
}

/// The four files [`Converted::write_into`] wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Written {
    /// WGSL, all entry points.
    pub wgsl: PathBuf,
    /// SPIR-V 1.3, all entry points.
    pub spirv: PathBuf,
    /// Reflection JSON.
    pub reflection: PathBuf,
    /// The Rust material struct.
    pub rust: PathBuf,
}

impl Written {
    fn in_dir(dir: &Path, name: &str) -> Self {
        Self {
            wgsl: dir.join(format!("{name}.wgsl")),
            spirv: dir.join(format!("{name}.spv")),
            reflection: dir.join(format!("{name}.json")),
            rust: dir.join(format!("{name}.rs")),
        }
    }
}

/// Why a shader did not convert: its diagnostics, located in the files read.
///
/// `Display` (and `Debug`, so that `.expect(..)` prints the same) renders them as `gdsky check`
/// does, without colour: `error[E300]: …`, `--> sky.gdshader:2:24`, the line with a caret.
pub struct ConvertError {
    db: SourceDb,
    diagnostics: Vec<Diagnostic>,
}

impl ConvertError {
    /// The error and warning diagnostics.
    pub fn diagnostics(&self) -> &[Diagnostic] {
        &self.diagnostics
    }

    /// The files the diagnostics point into.
    pub fn sources(&self) -> &SourceDb {
        &self.db
    }

    /// The diagnostics rendered, with ANSI colours when `color`.
    pub fn render(&self, color: bool) -> String {
        render_human(&self.db, &self.diagnostics, color)
    }

    /// The diagnostics as JSON lines (`gdsky check --diagnostics json`).
    pub fn render_json(&self) -> String {
        gdshader::diag::render_json(&self.db, &self.diagnostics)
    }

    /// Diagnostics about the files in `db`.
    pub fn new(db: SourceDb, diagnostics: Vec<Diagnostic>) -> Self {
        Self { db, diagnostics }
    }
}

impl fmt::Display for ConvertError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.render(false).trim_end())
    }
}

impl fmt::Debug for ConvertError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

impl std::error::Error for ConvertError {}

/// Converts the sky shader `source`, named `name` (a file name or path: relative `#include`s
/// resolve against its folder, and its stem names the outputs), as `options` say.
///
/// ```
/// let source = "shader_type sky;\nuniform vec3 tint : source_color = vec3(0.3, 0.5, 0.9);\n\
///               void sky() { COLOR = tint * (0.5 + 0.5 * EYEDIR.y); }\n";
/// let sky = gdsky::convert("tinted.gdshader", source, &gdsky::Options::default())?;
/// assert!(sky.wgsl.contains("@fragment"));
/// assert_eq!(sky.spirv[0], 0x0723_0203); // the SPIR-V magic number
/// assert_eq!(sky.reflection.uniforms[0].name, "tint");
/// assert!(sky.rust.contains("pub struct TintedMaterial"));
///
/// let error = gdsky::convert("bad.gdshader", "shader_type sky;\nvoid sky() { COLOR = 1; }", &Default::default())
///     .unwrap_err();
/// assert!(error.to_string().contains("bad.gdshader:2:"));
/// # Ok::<(), gdsky::ConvertError>(())
/// ```
pub fn convert(name: &str, source: &str, options: &Options) -> Result<Converted, ConvertError> {
    let front = check(name, source.as_bytes().to_vec(), options);
    if front.shader.is_none() {
        return Err(ConvertError::new(front.db, front.diagnostics));
    }
    let lowered = match gdsky_naga::lower(&front, &options.lowering) {
        Ok(lowered) => lowered,
        Err(diagnostics) => return Err(ConvertError::new(front.db, diagnostics)),
    };
    emit(front, &lowered, options)
}

/// [`convert`] of the file at `path`, read with gdsky's bounded reader (a regular file of at
/// most 4 MiB). A file that cannot be read is an I/O error, not a diagnostic.
pub fn convert_file(path: &Path, options: &Options) -> std::io::Result<Result<Converted, ConvertError>> {
    let bytes = skycore::io::read_limited(path, gdshader::preprocess::MAX_SOURCE_BYTES)?;
    let front = check(&path.display().to_string(), bytes, options);
    if front.shader.is_none() {
        return Ok(Err(ConvertError::new(front.db, front.diagnostics)));
    }
    let lowered = match gdsky_naga::lower(&front, &options.lowering) {
        Ok(lowered) => lowered,
        Err(diagnostics) => return Ok(Err(ConvertError::new(front.db, diagnostics))),
    };
    Ok(emit(front, &lowered, options))
}

/// The front end on `bytes` with the options' loader.
fn check(name: &str, bytes: Vec<u8>, options: &Options) -> FrontendOutput {
    let path = Some(PathBuf::from(name));
    match &options.include_loader {
        Some(loader) => gdshader::check_source(name, bytes, path, &mut Custom(loader.clone())),
        None => gdshader::check_source(name, bytes, path, &mut gdshader::FsLoader),
    }
}

/// The caller's include loader as the front end's.
struct Custom(IncludeLoader);

impl gdshader::Loader for Custom {
    fn load(&mut self, path: &Path) -> std::io::Result<Vec<u8>> {
        (self.0)(path)
    }
}

/// The second half of [`convert`]: emits a shader already lowered from `front`. Both texts are
/// read back and validated by naga before anything is returned, so a module that does not hold
/// up (a gdsky bug) comes back as an `E604` diagnostic at the user's function.
pub fn emit(
    front: FrontendOutput,
    lowered: &gdsky_naga::Lowered,
    options: &Options,
) -> Result<Converted, ConvertError> {
    let Some(shader) = front.shader.as_ref() else {
        return Err(ConvertError::new(front.db, front.diagnostics));
    };
    let texts = gdsky_naga::to_wgsl(lowered)
        .and_then(|wgsl| gdsky_naga::to_spirv_with(lowered, &options.spirv).map(|spirv| (wgsl, spirv)));
    let (wgsl, spirv) = match texts {
        Ok(texts) => texts,
        Err(e) => {
            let diagnostic = e.diagnostic(&front);
            return Err(ConvertError::new(front.db, vec![diagnostic]));
        }
    };
    let name = stem(front.db.name(front.root));
    let reflection = gdsky_naga::reflect::reflection(&name, shader, lowered);
    let rust = crate::rust_struct::material_struct(&name, shader, lowered);
    let warnings = render_human(&front.db, &front.diagnostics, false);
    Ok(Converted { name, wgsl, spirv, reflection, rust, includes: front.preprocessed.includes.clone(), warnings })
}

/// `path/to/freeman_sky.gdshader` → `freeman_sky`.
fn stem(name: &str) -> String {
    Path::new(name).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "shader".into())
}
