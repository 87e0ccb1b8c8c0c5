//! From a `.tres` or `.tscn` to a sky's `ShaderMaterial`: its shader, its parameter values and
//! its textures, every error located in the file that holds the mistake.

mod noise;
mod ramp;

use crate::codes;
use crate::text::{self, Document, Section, Span, Value, ValueKind};
use gdshader::check::types::{Scalar, Type};
use gdshader::diag::{Diagnostic, FileId, SourceDb, render_human};
use std::path::{Path, PathBuf};

/// A uniform value a file fixes (a material's `shader_parameter/*`, a scene file's `[uniforms]`):
/// its text in `--set` syntax and where it is in the file.
#[derive(Clone, Debug, PartialEq)]
pub struct UniformSetting {
    /// The uniform's name.
    pub name: String,
    /// The value in `--set` syntax (`16`, `0.1,0.1,0.1`, `true`).
    pub text: String,
    /// Byte range of the value in its file.
    pub span: std::ops::Range<usize>,
}

/// A texture a file gives a sampler uniform (a material's image texture, a scene file's
/// `[textures]`, as `--texture NAME=PATH`).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureSetting {
    /// The sampler uniform's name (`name_i` for element i of a sampler array).
    pub name: String,
    /// The image, resolved against the file's folder (a material's `res://` against the project).
    pub path: PathBuf,
    /// Byte range of the path in its file.
    pub span: std::ops::Range<usize>,
}

/// Why a material was not loaded; the message is rendered (located diagnostics).
#[derive(Debug)]
pub enum MaterialError {
    /// A file cannot be read: the one given, or one it refers to (exit 2).
    Read(String),
    /// A file is wrong (exit 1).
    Invalid(String),
}

impl std::fmt::Display for MaterialError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MaterialError::Read(m) | MaterialError::Invalid(m) => f.write_str(m.trim_end()),
        }
    }
}

impl std::error::Error for MaterialError {}

/// Where the material's shader comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialShader {
    /// A `.gdshader` file (an `ext_resource` of type `Shader`), resolved.
    File(PathBuf),
    /// An embedded `Shader` sub-resource's `code`, named `file.tres::Shader_id` in diagnostics.
    Embedded {
        /// The display name.
        name: String,
        /// The shader's text.
        code: String,
    },
}

/// A texture a material gives a sampler uniform.
#[derive(Clone, Debug, PartialEq)]
pub enum TextureSource {
    /// An image file (PNG or OpenEXR), resolved.
    Image(PathBuf),
    /// A `NoiseTexture2D` or `NoiseTexture3D` and the resources it refers to, generated when
    /// the texture is read.
    Noise(Box<NoiseSections>),
    /// A `GradientTexture1D`, `GradientTexture2D`, `CurveTexture` or `CurveXYZTexture` and its
    /// `Gradient` or `Curve`s, generated when the texture is read.
    Ramp(Box<RampSections>),
}

/// A gradient or curve texture's section and the section of its `gradient` or `curve`.
#[derive(Clone, Debug, PartialEq)]
pub struct RampSections {
    /// The file holding the sections.
    pub file: FileId,
    /// `GradientTexture1D`, `GradientTexture2D` or `CurveTexture`.
    pub class: String,
    /// The texture's section.
    pub texture: Section,
    /// The `Gradient` section, when `gradient` is set.
    pub gradient: Option<Section>,
    /// The `Curve` sections: a `CurveTexture`'s `curve` first, or a `CurveXYZTexture`'s
    /// `curve_x`, `curve_y`, `curve_z`; `None` where unset.
    pub curves: [Option<Section>; 3],
}

/// A `NoiseTexture2D` (or `NoiseTexture3D`) section and the sections of its `noise` (a
/// `FastNoiseLite`) and `color_ramp` (a `Gradient`).
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseSections {
    /// The file holding the sections.
    pub file: FileId,
    /// The `NoiseTexture2D` or `NoiseTexture3D` section.
    pub texture: Section,
    /// Whether it is a `NoiseTexture3D` (for a `sampler3D`).
    pub volume: bool,
    /// The `FastNoiseLite` section, when `noise` is set.
    pub noise: Option<Section>,
    /// The `Gradient` section, when `color_ramp` is set.
    pub color_ramp: Option<Section>,
}

/// A `shader_parameter/*` value: a variant, or a texture it refers to.
#[derive(Clone, Debug, PartialEq)]
pub enum ParameterValue {
    /// A plain value (a number, a vector, a colour, `null`).
    Value(Value),
    /// A texture resource.
    Texture(TextureSource),
}

/// One `shader_parameter/NAME = value` of the material.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// The uniform's name.
    pub name: String,
    /// Where the value is written (in [`SkyMaterial`]'s material file).
    pub span: Span,
    /// The value.
    pub value: ParameterValue,
}

/// A sky `ShaderMaterial` read from a Godot resource or scene.
pub struct SkyMaterial {
    /// The file given (`.tres` or `.tscn`).
    pub path: PathBuf,
    /// The shader.
    pub shader: MaterialShader,
    /// The `shader_parameter/*` values, in file order (a name given twice: the last).
    pub parameters: Vec<Parameter>,
    /// Every file read, for rendering diagnostics.
    pub db: SourceDb,
    /// The file that holds the `ShaderMaterial`; [`Parameter::span`]s are in it.
    pub file: FileId,
}

impl std::fmt::Debug for SkyMaterial {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SkyMaterial")
            .field("path", &self.path)
            .field("shader", &self.shader)
            .field("parameters", &self.parameters)
            .finish_non_exhaustive()
    }
}

/// A texture the material generates rather than reads from a file.
#[derive(Clone, Debug, PartialEq)]
pub struct GeneratedTexture {
    /// The sampler uniform.
    pub name: String,
    /// What to generate ([`crate::generated::NoiseTexture2D::generate`]).
    pub texture: crate::generated::NoiseTexture2D,
    /// Where the material file gives it.
    pub span: Span,
}

/// A gradient or curve texture the material generates (`GradientTexture1D`,
/// `GradientTexture2D`, `CurveTexture`).
#[derive(Clone, Debug, PartialEq)]
pub struct GeneratedRamp {
    /// The sampler uniform.
    pub name: String,
    /// What to generate ([`crate::generated::RampTexture::generate`]).
    pub texture: crate::generated::RampTexture,
    /// Where the material file gives it.
    pub span: Span,
}

/// A 3D texture the material generates: a `NoiseTexture3D` for a `sampler3D`.
#[derive(Clone, Debug, PartialEq)]
pub struct GeneratedVolume {
    /// The sampler uniform.
    pub name: String,
    /// What to generate ([`crate::generated::NoiseTexture3D::image`], one image per slice).
    pub texture: crate::generated::NoiseTexture3D,
    /// Where the material file gives it.
    pub span: Span,
}

/// The material's values as the command line gives them: `--set` texts, `--texture` paths and
/// generated textures, each located in the material file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaterialSettings {
    /// Uniform values in `--set` syntax.
    pub uniforms: Vec<UniformSetting>,
    /// Image files for sampler uniforms.
    pub textures: Vec<TextureSetting>,
    /// Generated textures for sampler uniforms.
    pub generated: Vec<GeneratedTexture>,
    /// Generated 3D textures for sampler uniforms.
    pub generated_volumes: Vec<GeneratedVolume>,
    /// Generated gradient and curve textures for sampler uniforms.
    pub generated_ramps: Vec<GeneratedRamp>,
    /// Warnings, rendered (parameters that name no uniform); empty when none.
    pub warnings: String,
}

/// Reads the sky material of the resource or scene at `path` (see the [module](super) docs).
pub fn load_sky_material(path: &Path) -> Result<SkyMaterial, MaterialError> {
    let mut loader = Loader { db: SourceDb::new(), docs: Vec::new() };
    let root = loader.open(path, None).map_err(|f| loader.fail(f))?;
    let found = loader.find_material(root).map_err(|f| loader.fail(f))?;
    let material = loader.read_material(found).map_err(|f| loader.fail(f))?;
    Ok(SkyMaterial { path: path.to_path_buf(), ..material })
}

/// A failure while loading: unreadable (exit 2) or wrong (exit 1), located.
enum Failure {
    Read(Diagnostic),
    ReadUnlocated(String),
    Invalid(Diagnostic),
}

/// One file read.
struct Doc {
    file: FileId,
    path: PathBuf,
    doc: Document,
}

/// A resource section: the file and the section's index in it.
#[derive(Clone, Copy)]
struct Res {
    doc: usize,
    section: usize,
}

struct Loader {
    db: SourceDb,
    docs: Vec<Doc>,
}

fn error(code: &'static str, file: FileId, span: Span, message: impl Into<String>) -> Diagnostic {
    let message = message.into();
    Diagnostic::error(code, message.clone()).with_primary(file, span, message)
}

impl Loader {
    fn fail(&self, failure: Failure) -> MaterialError {
        match failure {
            Failure::Read(d) => MaterialError::Read(render_human(&self.db, &[d], false)),
            Failure::ReadUnlocated(m) => MaterialError::Read(m),
            Failure::Invalid(d) => MaterialError::Invalid(render_human(&self.db, &[d], false)),
        }
    }

    fn doc(&self, res: Res) -> &Doc {
        &self.docs[res.doc]
    }

    fn section(&self, res: Res) -> &Section {
        &self.docs[res.doc].doc.sections[res.section]
    }

    /// Reads and parses the file at `path`; `from` is the reference that named it.
    fn open(&mut self, path: &Path, from: Option<(FileId, Span)>) -> Result<usize, Failure> {
        if let Some(i) = self.docs.iter().position(|d| d.path == path) {
            return Ok(i);
        }
        if self.docs.len() >= super::MAX_FILES {
            let (file, span) = from.unwrap_or((self.docs[0].file, 0..0));
            return Err(Failure::Invalid(error(
                codes::BAD_REFERENCE,
                file,
                span,
                format!("more than {} resource files referenced: a cycle, or too deep", super::MAX_FILES),
            )));
        }
        let bytes = match skycore::io::read_limited(path, super::MAX_RESOURCE_BYTES) {
            Ok(b) => b,
            Err(e) => {
                let message = format!("cannot read {}: {e}", path.display());
                return Err(match from {
                    Some((file, span)) => Failure::Read(error(codes::BAD_REFERENCE, file, span, message)),
                    None => Failure::ReadUnlocated(message),
                });
            }
        };
        let (text, bad_utf8) = match String::from_utf8(bytes) {
            Ok(t) => (t, None),
            Err(e) => {
                let at = e.utf8_error().valid_up_to();
                (String::from_utf8_lossy(e.as_bytes()).into_owned(), Some(at))
            }
        };
        let file = self.db.add(path.display().to_string(), text, Some(path.to_path_buf()));
        if let Some(at) = bad_utf8 {
            // The lossy text keeps every valid byte before the first invalid one in place, so the
            // offset is right in it.
            return Err(Failure::Invalid(error(codes::NOT_A_RESOURCE, file, at..at + 1, "not UTF-8 text here")));
        }
        let doc = text::parse(self.db.text(file), file).map_err(Failure::Invalid)?;
        check_header(&doc, file, self.db.text(file).len())?;
        self.docs.push(Doc { file, path: path.to_path_buf(), doc });
        Ok(self.docs.len() - 1)
    }

    /// The resource a file is about: a `.tres`'s `[resource]`, or for a `.tscn` the
    /// environment of its first `WorldEnvironment` node.
    fn find_material(&mut self, doc: usize) -> Result<Res, Failure> {
        let d = &self.docs[doc];
        let header = &d.doc.sections[0];
        if header.tag == "gd_scene" {
            let Some(node) = d
                .doc
                .sections
                .iter()
                .position(|s| s.tag == "node" && s.attribute_str("type") == Some("WorldEnvironment"))
            else {
                return Err(Failure::Invalid(
                    error(
                        codes::NO_SKY_MATERIAL,
                        d.file,
                        header.span.clone(),
                        "the scene has no WorldEnvironment node",
                    )
                    .with_note(
                        "gdsky renders the sky of a scene's WorldEnvironment: its environment's sky's sky_material",
                    ),
                ));
            };
            let node = Res { doc, section: node };
            let env = self.follow_property(node, "environment", "WorldEnvironment")?;
            return self.walk_to_material(env);
        }
        let Some(resource) = d.doc.sections.iter().position(|s| s.tag == "resource") else {
            return Err(Failure::Invalid(error(
                codes::NOT_A_RESOURCE,
                d.file,
                header.span.clone(),
                "the file has no [resource] section",
            )));
        };
        self.walk_to_material(Res { doc, section: resource })
    }

    /// The type of a resource section: a `sub_resource`'s `type`, a `[resource]`'s file
    /// header's.
    fn type_of(&self, res: Res) -> String {
        let section = self.section(res);
        let own = section.attribute_str("type");
        let header = self.doc(res).doc.sections[0].attribute_str("type");
        own.or(header).unwrap_or("").to_string()
    }

    /// Environment → sky → sky_material → the ShaderMaterial.
    fn walk_to_material(&mut self, mut res: Res) -> Result<Res, Failure> {
        loop {
            let ty = self.type_of(res);
            res = match ty.as_str() {
                "ShaderMaterial" => return Ok(res),
                "Environment" => self.follow_property(res, "sky", "Environment")?,
                "Sky" => self.follow_property(res, "sky_material", "Sky")?,
                other => {
                    let section = self.section(res);
                    let mut d = error(
                        codes::NO_SKY_MATERIAL,
                        self.doc(res).file,
                        section.span.clone(),
                        format!(
                            "a {} is not a sky material",
                            if other.is_empty() { "resource without a type" } else { other }
                        ),
                    );
                    d = d.with_note(match other {
                        "ProceduralSkyMaterial" | "PanoramaSkyMaterial" | "PhysicalSkyMaterial" => {
                            format!("gdsky renders shader skies: a ShaderMaterial with a `shader_type sky` shader; {other} is Godot's built-in sky")
                        }
                        _ => "gdsky reads a ShaderMaterial, a Sky (its sky_material) or an Environment (its sky)".into(),
                    });
                    return Err(Failure::Invalid(d));
                }
            };
        }
    }

    /// Follows the reference in property `name` of `res`, whose type is `owner`.
    fn follow_property(&mut self, res: Res, name: &str, owner: &str) -> Result<Res, Failure> {
        let file = self.doc(res).file;
        let section = self.section(res);
        let Some(entry) = section.property(name) else {
            return Err(Failure::Invalid(error(
                codes::NO_SKY_MATERIAL,
                file,
                section.span.clone(),
                format!("this {owner} has no `{name}`: there is no sky to render"),
            )));
        };
        let value = entry.value.clone();
        self.follow(res.doc, &value)
    }

    /// The resource a `SubResource`/`ExtResource` value refers to (an ext-resource `.tres` is
    /// read and its `[resource]` returned).
    fn follow(&mut self, doc: usize, value: &Value) -> Result<Res, Failure> {
        let file = self.docs[doc].file;
        match &value.kind {
            ValueKind::SubResource(id) => self.sub_resource(doc, id, value.span.clone()),
            ValueKind::ExtResource(id) => {
                let (path, _) = self.ext_path(doc, id, value.span.clone())?;
                if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("tres")) {
                    return Err(Failure::Invalid(error(
                        codes::BAD_REFERENCE,
                        file,
                        value.span.clone(),
                        format!("{}: gdsky reads resources saved as text (.tres), not binary ones", path.display()),
                    )));
                }
                let target = self.open(&path, Some((file, value.span.clone())))?;
                let d = &self.docs[target];
                match d.doc.sections.iter().position(|s| s.tag == "resource") {
                    Some(section) => Ok(Res { doc: target, section }),
                    None => Err(Failure::Invalid(error(
                        codes::NOT_A_RESOURCE,
                        d.file,
                        d.doc.sections[0].span.clone(),
                        "the file has no [resource] section",
                    ))),
                }
            }
            _ => Err(Failure::Invalid(error(
                codes::BAD_REFERENCE,
                file,
                value.span.clone(),
                format!("expected SubResource(\"id\") or ExtResource(\"id\"), found {}", value.describe()),
            ))),
        }
    }

    fn sub_resource(&self, doc: usize, id: &str, span: Span) -> Result<Res, Failure> {
        let d = &self.docs[doc];
        let found = d.doc.sections.iter().position(|s| {
            s.tag == "sub_resource" && s.attribute("id").and_then(|a| a.value.id()).as_deref() == Some(id)
        });
        found.map(|section| Res { doc, section }).ok_or_else(|| {
            Failure::Invalid(error(codes::BAD_REFERENCE, d.file, span, format!("no [sub_resource] has id \"{id}\"")))
        })
    }

    /// The path and the section of the `ext_resource` with `id`, resolved against the file.
    fn ext_path(&self, doc: usize, id: &str, span: Span) -> Result<(PathBuf, usize), Failure> {
        let d = &self.docs[doc];
        let Some(index) = d.doc.sections.iter().position(|s| {
            s.tag == "ext_resource" && s.attribute("id").and_then(|a| a.value.id()).as_deref() == Some(id)
        }) else {
            return Err(Failure::Invalid(error(
                codes::BAD_REFERENCE,
                d.file,
                span,
                format!("no [ext_resource] has id \"{id}\""),
            )));
        };
        let section = &d.doc.sections[index];
        let Some(path_attr) = section.attribute("path") else {
            return Err(Failure::Invalid(
                error(codes::BAD_REFERENCE, d.file, section.span.clone(), "this ext_resource has no `path`")
                    .with_note("gdsky finds resources by path; it does not read Godot's uid cache"),
            ));
        };
        let Some(text) = path_attr.value.str() else {
            return Err(Failure::Invalid(error(
                codes::BAD_REFERENCE,
                d.file,
                path_attr.value.span.clone(),
                "`path` must be a string",
            )));
        };
        let resolved = resolve(&d.path, text)
            .map_err(|m| Failure::Invalid(error(codes::BAD_REFERENCE, d.file, path_attr.value.span.clone(), m)))?;
        Ok((resolved, index))
    }

    /// Reads the ShaderMaterial at `res`.
    fn read_material(&mut self, res: Res) -> Result<SkyMaterial, Failure> {
        let file = self.doc(res).file;
        let section = self.section(res).clone();
        let shader = match section.property("shader") {
            Some(entry) => self.read_shader(res.doc, &entry.value)?,
            None => {
                return Err(Failure::Invalid(
                    error(codes::NO_SHADER, file, section.span.clone(), "this ShaderMaterial has no `shader`")
                        .with_note("Godot renders nothing for it either; give it a sky shader"),
                ));
            }
        };
        let mut parameters: Vec<Parameter> = Vec::new();
        for entry in &section.properties {
            let Some(name) =
                entry.name.strip_prefix("shader_parameter/").or_else(|| entry.name.strip_prefix("shader_param/"))
            else {
                continue;
            };
            let value = match &entry.value.kind {
                ValueKind::ExtResource(_) | ValueKind::SubResource(_) => {
                    ParameterValue::Texture(self.read_texture(res.doc, &entry.value)?)
                }
                _ => ParameterValue::Value(entry.value.clone()),
            };
            parameters.retain(|p| p.name != name);
            parameters.push(Parameter { name: name.to_string(), span: entry.value.span.clone(), value });
        }
        Ok(SkyMaterial { path: PathBuf::new(), shader, parameters, db: std::mem::take(&mut self.db), file })
    }

    /// The shader of a material: an ext-resource `.gdshader`, or an embedded `Shader`'s code.
    fn read_shader(&mut self, doc: usize, value: &Value) -> Result<MaterialShader, Failure> {
        let file = self.docs[doc].file;
        if let ValueKind::ExtResource(id) = &value.kind {
            let (path, index) = self.ext_path(doc, id, value.span.clone())?;
            let section = &self.docs[doc].doc.sections[index];
            let ty = section.attribute_str("type").unwrap_or("");
            if !matches!(ty, "Shader" | "") && !is_text_resource(&path) {
                return Err(Failure::Invalid(error(
                    codes::NO_SHADER,
                    file,
                    section.span.clone(),
                    format!("the shader is a {ty}, not a Shader"),
                )));
            }
            if is_text_resource(&path) {
                let res = self.follow(doc, value)?;
                return self.embedded_shader(res);
            }
            if !path.is_file() {
                return Err(Failure::Read(error(
                    codes::BAD_REFERENCE,
                    file,
                    value.span.clone(),
                    format!("cannot read the shader {}: not a file", path.display()),
                )));
            }
            return Ok(MaterialShader::File(path));
        }
        let res = self.follow(doc, value)?;
        self.embedded_shader(res)
    }

    fn embedded_shader(&self, res: Res) -> Result<MaterialShader, Failure> {
        let d = self.doc(res);
        let section = self.section(res);
        let ty = self.type_of(res);
        if ty != "Shader" {
            return Err(Failure::Invalid(error(
                codes::NO_SHADER,
                d.file,
                section.span.clone(),
                format!("the shader is a {ty}, not a Shader"),
            )));
        }
        let Some(code) = section.property("code") else {
            return Err(Failure::Invalid(error(
                codes::NO_SHADER,
                d.file,
                section.span.clone(),
                "this Shader has no `code`",
            )));
        };
        let Some(text) = code.value.str() else {
            return Err(Failure::Invalid(error(
                codes::NO_SHADER,
                d.file,
                code.value.span.clone(),
                "`code` must be a string",
            )));
        };
        let id = section.attribute("id").and_then(|a| a.value.id()).unwrap_or_else(|| "resource".into());
        let file_name = d.path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        Ok(MaterialShader::Embedded { name: format!("{file_name}::{id}"), code: text.to_string() })
    }

    /// A texture parameter's resource: an image file by path, or a generated texture.
    fn read_texture(&mut self, doc: usize, value: &Value) -> Result<TextureSource, Failure> {
        let file = self.docs[doc].file;
        if let ValueKind::ExtResource(id) = &value.kind {
            let (path, _) = self.ext_path(doc, id, value.span.clone())?;
            if !is_text_resource(&path) {
                return image_source(path, file, value.span.clone());
            }
        }
        let res = self.follow(doc, value)?;
        let ty = self.type_of(res);
        let (tfile, section) = (self.doc(res).file, self.section(res).clone());
        // A linked resource's section (`noise`, `color_ramp`, `gradient`, `curve`), checked
        // for its type; `None` when unset or null.
        let mut linked = |name: &str, want: &str| -> Result<Option<Section>, Failure> {
            let Some(entry) = section.property(name) else { return Ok(None) };
            if matches!(entry.value.kind, ValueKind::Null) {
                return Ok(None);
            }
            let value = entry.value.clone();
            let target = self.follow(res.doc, &value)?;
            let found = self.type_of(target);
            if found != want {
                return Err(Failure::Invalid(error(
                    codes::BAD_NOISE,
                    tfile,
                    value.span.clone(),
                    format!("`{name}` is a {found}; gdsky generates a {ty} from a {want}"),
                )));
            }
            let mut target_section = self.section(target).clone();
            // A sub-resource's `type` lives in its header; a `[resource]`'s in its
            // file's header: keep it where readers look.
            if target_section.attribute("type").is_none() {
                target_section.attributes.push(super::Entry {
                    name: "type".into(),
                    name_span: 0..0,
                    value: Value { kind: ValueKind::String(found), span: 0..0 },
                });
            }
            Ok(Some(target_section))
        };
        match ty.as_str() {
            "GradientTexture1D" | "GradientTexture2D" | "CurveTexture" | "CurveXYZTexture" => {
                let (gradient, curves) = match ty.as_str() {
                    "CurveTexture" => (None, [linked("curve", "Curve")?, None, None]),
                    "CurveXYZTexture" => {
                        (None, [linked("curve_x", "Curve")?, linked("curve_y", "Curve")?, linked("curve_z", "Curve")?])
                    }
                    _ => (linked("gradient", "Gradient")?, [None, None, None]),
                };
                Ok(TextureSource::Ramp(Box::new(RampSections {
                    file: tfile,
                    class: ty.clone(),
                    texture: section.clone(),
                    gradient,
                    curves,
                })))
            }
            "NoiseTexture2D" | "NoiseTexture3D" => {
                let noise = linked("noise", "FastNoiseLite")?;
                let color_ramp = linked("color_ramp", "Gradient")?;
                let volume = ty == "NoiseTexture3D";
                Ok(TextureSource::Noise(Box::new(NoiseSections {
                    file: tfile,
                    texture: section,
                    volume,
                    noise,
                    color_ramp,
                })))
            }
            other => Err(Failure::Invalid(
                error(codes::BAD_TEXTURE, file, value.span.clone(), format!("gdsky cannot use a {other} as a texture"))
                    .with_secondary(tfile, section.span.clone(), "defined here")
                    .with_note(
                        "textures gdsky reads: PNG and OpenEXR image files by path, NoiseTexture2D, NoiseTexture3D, \
                         GradientTexture1D, GradientTexture2D, CurveTexture and CurveXYZTexture",
                    ),
            )),
        }
    }
}

/// An ext-resource image file as a texture source: PNG or OpenEXR.
fn image_source(path: PathBuf, file: FileId, span: Span) -> Result<TextureSource, Failure> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    if ext == "png" || ext == "exr" {
        return Ok(TextureSource::Image(path));
    }
    Err(Failure::Invalid(
        error(
            codes::BAD_TEXTURE,
            file,
            span,
            match ext.as_str() {
                "" => format!("{}: an image file needs an extension (.png or .exr) to be read", path.display()),
                ext => format!("{}: gdsky cannot read .{ext} images", path.display()),
            },
        )
        .with_note(
            "textures gdsky reads: PNG (.png) and OpenEXR (.exr); convert the image, or give --texture NAME=PATH",
        ),
    ))
}

/// Whether `path` is a resource file rather than an image or a shader: a text one (`.tres`),
/// which gdsky follows, or a binary one (`.res`), which `follow` refuses by name.
fn is_text_resource(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("tres") || e.eq_ignore_ascii_case("res"))
}

/// Checks the first section: `gd_resource` or `gd_scene`, format 2 or 3.
fn check_header(doc: &Document, file: FileId, len: usize) -> Result<(), Failure> {
    let Some(first) = doc.sections.first() else {
        return Err(Failure::Invalid(
            error(codes::NOT_A_RESOURCE, file, 0..len.min(1), "the file has no sections")
                .with_note("a Godot resource starts with [gd_resource …] or [gd_scene …]"),
        ));
    };
    if first.tag != "gd_resource" && first.tag != "gd_scene" {
        return Err(Failure::Invalid(error(
            codes::NOT_A_RESOURCE,
            file,
            first.span.clone(),
            format!("a Godot resource starts with [gd_resource …] or [gd_scene …], not [{} …]", first.tag),
        )));
    }
    if let Some(format) = first.attribute("format") {
        let n = format.value.number();
        if n != Some(2.0) && n != Some(3.0) {
            return Err(Failure::Invalid(
                error(
                    codes::NOT_A_RESOURCE,
                    file,
                    format.value.span.clone(),
                    "gdsky reads format 2 (Godot 3) and 3 (Godot 4)",
                )
                .with_note("a newer Godot may write a newer format; save the file from Godot 4"),
            ));
        }
    }
    Ok(())
}

/// Resolves a resource path written in `from`: `res://…` against the project root (the nearest
/// folder above `from` holding `project.godot`), anything else against `from`'s folder. The
/// result must lie inside the project (or, without one, inside `from`'s folder), as Godot reads
/// resources from its project only: a path outside is an error naming it, and the file is not
/// read. The project is found however `from` is spelled (`tex.tres` from inside it too).
pub(crate) fn resolve(from: &Path, written: &str) -> Result<PathBuf, String> {
    if written.starts_with("uid://") || written.starts_with("user://") {
        return Err(format!("`{written}`: gdsky resolves res:// and relative paths only"));
    }
    let dir = from.parent().unwrap_or(Path::new(""));
    let here = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
    let start = std::fs::canonicalize(here).unwrap_or_else(|_| here.to_path_buf());
    let project = start.ancestors().find(|d| d.join("project.godot").is_file()).map(Path::to_path_buf);
    let (path, checked, bound) = match written.strip_prefix("res://") {
        Some(rest) => {
            let root = project.ok_or_else(|| {
                format!(
                    "`{written}`: no project.godot in {} or a folder above it, so res:// has no root",
                    start.display()
                )
            })?;
            (root.join(rest), root.join(rest), root)
        }
        None => (dir.join(written), start.join(written), project.unwrap_or_else(|| start.clone())),
    };
    if !skycore::io::normalize(&checked).starts_with(&bound) {
        return Err(format!(
            "`{written}` is outside the project ({}): Godot reads resources from inside its project only (the \
             folder of project.godot, or without one the resource's own folder); the file was not read",
            bound.display()
        ));
    }
    Ok(path)
}

impl SkyMaterial {
    /// Checks the material's shader with Godot's rules (a `.gdshader` file is read; an embedded
    /// shader is checked under its display name, relative `#include`s from the material's
    /// folder). An error when the shader file cannot be read.
    pub fn check_shader(&self) -> std::io::Result<gdshader::FrontendOutput> {
        match &self.shader {
            MaterialShader::File(path) => gdshader::check_file(path),
            MaterialShader::Embedded { name, code } => Ok(gdshader::check_source(
                name,
                code.clone().into_bytes(),
                Some(self.path.clone()),
                &mut gdshader::FsLoader,
            )),
        }
    }

    /// The material's values for `shader`'s uniforms in `--set` and `--texture` terms. Errors
    /// (rendered, located in the material file): a value that does not fit its uniform's type,
    /// a texture for a uniform that is not a sampler, a uniform gdsky cannot set. A parameter
    /// that names no uniform is a warning, as Godot keeps values of removed uniforms.
    pub fn settings(&self, shader: &gdshader::CheckedShader) -> Result<MaterialSettings, String> {
        let mut out = MaterialSettings::default();
        let mut errors = Vec::new();
        let mut warnings = Vec::new();
        let samplers = shader.texture_names();
        for p in &self.parameters {
            let Some(u) = shader.uniforms.iter().find(|u| u.name == p.name) else {
                if !samplers.contains(&p.name) {
                    let m = format!("the shader has no uniform `{}`; this value is not used", p.name);
                    warnings.push(Diagnostic::warning(codes::UNUSED_PARAMETER, m.clone()).with_primary(
                        self.file,
                        p.span.clone(),
                        m,
                    ));
                    continue;
                }
                if let ParameterValue::Texture(source) = &p.value {
                    push_texture(&mut out, &p.name, source, p.span.clone()).unwrap_or_else(|d| errors.push(d));
                }
                continue;
            };
            let fail = |m: String, note: String| {
                Diagnostic::error(codes::BAD_PARAMETER, format!("`shader_parameter/{}`: {m}", p.name))
                    .with_primary(self.file, p.span.clone(), m)
                    .with_note(note)
            };
            let is_sampler = samplers.contains(&p.name);
            match &p.value {
                ParameterValue::Texture(source) if is_sampler => {
                    push_texture(&mut out, &p.name, source, p.span.clone()).unwrap_or_else(|d| errors.push(d))
                }
                ParameterValue::Texture(_) => errors.push(fail(
                    "a texture for a uniform that is not a sampler".into(),
                    format!("`{}` is a `{}`", p.name, u.type_name),
                )),
                // A sampler left empty in Godot: the shader's hint default, as without a texture.
                ParameterValue::Value(v) if matches!(v.kind, ValueKind::Null) => {}
                ParameterValue::Value(v) if is_sampler => errors.push(fail(
                    format!("{} for a sampler uniform", v.describe()),
                    "give it a texture: ExtResource or SubResource".into(),
                )),
                ParameterValue::Value(v) => match set_text(v, &u.ty) {
                    Ok(text) => match gdshader::values::parse_value(&u.ty, &text) {
                        Ok(_) => out.uniforms.push(UniformSetting { name: p.name.clone(), text, span: p.span.clone() }),
                        Err(why) => errors.push(fail(why, format!("`{}` is a `{}`", p.name, u.type_name))),
                    },
                    Err(why) => errors.push(fail(why, format!("`{}` is a `{}`", p.name, u.type_name))),
                },
            }
        }
        out.warnings = if warnings.is_empty() { String::new() } else { render_human(&self.db, &warnings, false) };
        if errors.is_empty() { Ok(out) } else { Err(render_human(&self.db, &errors, false)) }
    }

    /// A located error at `span` of the material file, rendered.
    pub fn error_at(&self, span: Span, code: &'static str, message: &str) -> String {
        render_human(&self.db, &[error(code, self.file, span, message)], false)
    }
}

/// Adds a texture to `out`: an image by path, or a noise texture mapped onto
/// [`crate::generated::NoiseTexture2D`] or [`crate::generated::NoiseTexture3D`] (an error located at
/// the property that does not fit).
fn push_texture(out: &mut MaterialSettings, name: &str, source: &TextureSource, span: Span) -> Result<(), Diagnostic> {
    match source {
        TextureSource::Image(path) => {
            out.textures.push(TextureSetting { name: name.to_string(), path: path.clone(), span })
        }
        TextureSource::Ramp(r) => {
            let texture = ramp::ramp_texture(r.file, &r.class, &r.texture, r.gradient.as_ref(), &r.curves)?;
            out.generated_ramps.push(GeneratedRamp { name: name.to_string(), texture, span })
        }
        TextureSource::Noise(n) if n.volume => {
            let texture = noise::noise_texture_3d(n.file, &n.texture, n.noise.as_ref(), n.color_ramp.as_ref())?;
            out.generated_volumes.push(GeneratedVolume { name: name.to_string(), texture, span })
        }
        TextureSource::Noise(n) => {
            let texture = noise::noise_texture(n.file, &n.texture, n.noise.as_ref(), n.color_ramp.as_ref())?;
            out.generated.push(GeneratedTexture { name: name.to_string(), texture, span })
        }
    }
    Ok(())
}

/// A Godot value as `--set` text for a uniform of type `ty`: numbers as written (f64's
/// shortest round trip), vectors and colours as comma-separated components. A `Color` for a
/// `vec3` gives its r, g, b (Godot stores `vec3 … : source_color` values as colours).
fn set_text(value: &Value, ty: &Type) -> Result<String, String> {
    let found = || format!("expected {}, found {}", type_words(ty), value.describe());
    let float = |f: f64| format!("{f:?}");
    let int = |f: f64| -> Result<String, String> {
        if f.fract() == 0.0 && f.abs() < 9.0e15 {
            Ok(format!("{}", f as i64))
        } else {
            Err(format!("`{f}` is not an integer"))
        }
    };
    match ty {
        // Godot converts a bool to 0.0 or 1.0 for a float uniform (its Variant conversion), and
        // writes files that way (`shader_parameter/precomputed_sun_visible = true`).
        Type::Scalar(Scalar::Float) => match value.kind {
            ValueKind::Bool(b) => Ok(float(f64::from(u8::from(b)))),
            _ => value.number().map(float).ok_or_else(found),
        },
        Type::Scalar(Scalar::Int | Scalar::UInt) => match value.kind {
            ValueKind::Int(i) => Ok(i.to_string()),
            ValueKind::Float(f) => int(f),
            ValueKind::Bool(b) => Ok(u8::from(b).to_string()),
            _ => Err(found()),
        },
        Type::Scalar(Scalar::Bool) => match value.kind {
            ValueKind::Bool(b) => Ok(b.to_string()),
            ValueKind::Int(i) => Ok((i != 0).to_string()),
            _ => Err(found()),
        },
        // Godot stores a bvecN as an int whose bit i is component i.
        Type::Vector(Scalar::Bool, n) if matches!(value.kind, ValueKind::Int(_)) => {
            let ValueKind::Int(bits) = value.kind else { return Err(found()) };
            Ok((0..*n).map(|i| (bits >> i & 1 == 1).to_string()).collect::<Vec<_>>().join(","))
        }
        Type::Vector(scalar, n) => {
            let n = usize::from(*n);
            let ValueKind::Constructor { name, args } = &value.kind else { return Err(found()) };
            let components: Vec<f64> = args.iter().filter_map(Value::number).collect();
            let fits = match name.as_str() {
                "Vector2" | "Vector2i" => n == 2,
                "Vector3" | "Vector3i" => n == 3,
                "Vector4" | "Vector4i" | "Quaternion" | "Plane" => n == 4,
                "Color" => n == 3 || n == components.len(),
                _ => false,
            };
            if !fits || components.len() < n {
                return Err(found());
            }
            let parts: Result<Vec<String>, String> = components[..n]
                .iter()
                .map(|&c| match scalar {
                    Scalar::Float => Ok(float(c)),
                    Scalar::Int | Scalar::UInt => int(c),
                    Scalar::Bool => Ok((c != 0.0).to_string()),
                })
                .collect();
            parts.map(|p| p.join(","))
        }
        _ => Err("gdsky sets scalar and vector uniforms from a material; this one keeps its default".into()),
    }
}

/// A uniform type in words for "expected …".
fn type_words(ty: &Type) -> String {
    match ty {
        Type::Scalar(Scalar::Float) => "a number".into(),
        Type::Scalar(Scalar::Int) => "an int".into(),
        Type::Scalar(Scalar::UInt) => "a non-negative int".into(),
        Type::Scalar(Scalar::Bool) => "a bool".into(),
        Type::Vector(Scalar::Float, 3) => "a Vector3 or a Color".into(),
        Type::Vector(Scalar::Float, 4) => "a Vector4, a Color, a Quaternion or a Plane".into(),
        Type::Vector(Scalar::Float, n) => format!("a Vector{n}"),
        Type::Vector(_, n) => format!("a Vector{n}i"),
        _ => "a value".into(),
    }
}
