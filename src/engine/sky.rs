//! A sky shader loaded for rendering: checked, lowered once as the command's options say, its
//! WGSL emitted, its textures and tables bound when it is compiled on a GPU.

use super::Error;
use crate::ConvertError;
use crate::scene::SceneFile;
use std::collections::HashMap;
use std::path::Path;

/// The Freeman sky (seed 000, CC0), built into the library so `gdsky render` and `gdsky demo`
/// work from any directory.
pub const BUNDLED_FREEMAN: &str = include_str!("../../fixtures/freeman_sky.gdshader");
/// The name diagnostics give the bundled shader.
pub const BUNDLED_NAME: &str = "freeman_sky.gdshader (bundled)";

/// The sampler uniform of a baked transmittance table ([`Sky::bake_tables`]).
pub const TRANSMITTANCE_TABLE: &str = "transmittance_table";

/// A checked, lowered shader ready to render.
pub struct Sky {
    /// The front end's output (the checked shader, its render modes and uniforms).
    pub front: crate::FrontendOutput,
    /// The validated naga module.
    pub lowered: gdsky_naga::Lowered,
    /// Its WGSL.
    pub wgsl: String,
    /// Textures for sampler uniforms ([`super::load_textures`]), bound by [`Sky::compile`].
    pub textures: Vec<(String, skyrun::TextureData)>,
}

impl Sky {
    /// The material block: the uniforms' defaults with `overrides` over them; overrides of
    /// baked uniforms (already constants) are left out.
    pub fn material(&self, overrides: &[(String, String)]) -> Result<Vec<u8>, skyrun::MaterialError> {
        let shader = self.front.shader.as_ref().ok_or(skyrun::MaterialError::NoSuchUniform(String::new()))?;
        // Uniforms that are overrides travel as pipeline constants ([`Sky::constants`]),
        // not in the block.
        let kept: Vec<(String, String)> = overrides
            .iter()
            .filter(|(n, _)| !self.baked().contains_key(n) && !self.overrides().contains(n))
            .cloned()
            .collect();
        skyrun::material_with_defaults(shader, &self.lowered, &kept)
    }

    /// The pipeline constants of the overrides (`@id` as text → value) from `--set`-style pairs
    /// (the last pair of a name counts), each override not set at the uniform's default, so
    /// every override is listed. A value is checked as `--set` checks it.
    pub fn constants(&self, sets: &[(String, String)]) -> Result<Vec<(String, f64)>, String> {
        let Some(shader) = self.front.shader.as_ref() else {
            return Ok(Vec::new());
        };
        let mut constants = Vec::with_capacity(self.overrides().len());
        for (id, name) in self.overrides().iter().enumerate() {
            let Some(u) = shader.uniforms.iter().find(|u| u.name == *name) else {
                return Err(format!("the shader has no uniform `{name}` to override"));
            };
            let value = match sets.iter().rev().find(|(n, _)| n == name) {
                Some((_, text)) => {
                    gdshader::values::parse_value(&u.ty, text).map_err(|why| format!("`--set {name}={text}`: {why}"))?
                }
                None => u.default.clone().unwrap_or(gdshader::check::consteval::ConstValue::Int(0)),
            };
            constants.push((id.to_string(), constant_value(&value)));
        }
        Ok(constants)
    }

    /// Binds a baked transmittance table when the shader declares [`TRANSMITTANCE_TABLE`] (as
    /// `shaders/freeman_lut.gdshader` does) and no texture was given for it: the table is baked
    /// ([`skyref::lut::bake`], 256×64, ~0.1 s) from the material's own values — the shader's
    /// defaults, then `values` (`--set`, the scene's uniforms), then the baked constants — so
    /// it always matches the layers the shader is rendered with. Returns the note to print, or
    /// `None` when nothing was baked. An error when a value that shapes the table is not a
    /// number (the material check reports it first in practice).
    pub fn bake_tables(&mut self, values: &[(String, String)]) -> Result<Option<String>, String> {
        let Some(shader) = self.front.shader.as_ref() else { return Ok(None) };
        let declared = shader.texture_names().iter().any(|n| n == TRANSMITTANCE_TABLE);
        if !declared || self.textures.iter().any(|(n, _)| n == TRANSMITTANCE_TABLE) {
            return Ok(None);
        }
        let mut params = skyref::FreemanParams::default();
        let known: Vec<&'static str> = params.uniforms_mut().iter().map(|(n, _)| *n).collect();
        let defaults = gdshader::values::defaults_as_set(shader);
        let mut settings: Vec<(&String, &String)> = defaults.iter().collect();
        settings.sort();
        settings.extend(values.iter().map(|(n, v)| (n, v)));
        settings.extend(self.baked().iter());
        for (name, value) in settings {
            if known.contains(&name.as_str()) {
                params.set(name, value)?;
            }
        }
        let (width, height) = skyref::lut::DEFAULT_SIZE;
        let started = std::time::Instant::now();
        let table = skyref::lut::bake(&params, width, height);
        let image = skyrun::Image { width: table.width, height: table.height, pixels: table.texels };
        let data = skyrun::texture_from_image(&image).map_err(|e| e.to_string())?;
        self.textures.push((TRANSMITTANCE_TABLE.to_string(), data));
        Ok(Some(format!(
            "{TRANSMITTANCE_TABLE}: baked {width}x{height} from the material in {:.2?} (give --texture {TRANSMITTANCE_TABLE}=TABLE.exr to use another)",
            started.elapsed()
        )))
    }

    /// The shader compiled on `gpu`, with Godot's sub-passes, default textures, samplers from
    /// the uniforms' hints and [`Sky::textures`] bound. Wrong input when the harness cannot bind
    /// it or a texture does not fit its binding.
    pub fn compile(&self, gpu: &skyrun::Gpu) -> Result<skyrun::SkyShader, Error> {
        self.compile_wgsl(gpu, &self.wgsl)
    }

    /// [`Sky::compile`] with other WGSL of the same shader and bindings (the
    /// instrumented module of `render --trace-nonfinite`).
    pub fn compile_wgsl(&self, gpu: &skyrun::Gpu, wgsl: &str) -> Result<skyrun::SkyShader, Error> {
        self.compile_source(gpu, wgsl, None)
    }

    /// [`Sky::compile_wgsl`] from SPIR-V of the same shader and bindings (a hand port's
    /// `.spv`); `wgsl` is the same module's WGSL, whose resources give the layouts.
    pub fn compile_spirv(&self, gpu: &skyrun::Gpu, wgsl: &str, spirv: &[u32]) -> Result<skyrun::SkyShader, Error> {
        self.compile_source(gpu, wgsl, Some(spirv))
    }

    fn compile_source(&self, gpu: &skyrun::Gpu, wgsl: &str, spirv: Option<&[u32]>) -> Result<skyrun::SkyShader, Error> {
        let failed = |err: &dyn std::fmt::Display| Error::input(err);
        let (defaults, bindings) = match self.front.shader.as_ref() {
            Some(s) => {
                (skyrun::texture_defaults(s, &self.lowered), gdsky_naga::reflect::texture_bindings(s, &self.lowered))
            }
            None => Default::default(),
        };
        let sub_passes = skyrun::SubPasses::of(&self.front);
        let shader = match spirv {
            Some(words) => skyrun::SkyShader::from_spirv(gpu, wgsl, words, sub_passes),
            None => skyrun::SkyShader::new(gpu, wgsl, sub_passes),
        };
        let mut shader =
            shader.map_err(|err| failed(&err))?.with_texture_defaults(defaults).with_material_textures(gpu, bindings);
        for (name, data) in &self.textures {
            shader.set_texture(gpu, name, data).map_err(|err| failed(&err))?;
        }
        Ok(shader)
    }
}

impl Sky {
    /// Checks and lowers `file`, or the bundled Freeman sky when there is none, as `lowering`
    /// says (Godot 4.6's defaults, or the measuring engine's). The front end's warnings stay in
    /// [`Sky::front`] (render them with [`Sky::warnings`]).
    pub fn load(file: Option<&Path>, lowering: &gdsky_naga::LowerOptions) -> Result<Sky, Error> {
        Self::load_specialized(file, None, lowering.clone(), |_| HashMap::new())
    }

    /// [`Sky::load`] with the uniforms `bake` picks from the checked shader (name → value in
    /// `--set` syntax) baked into constants and `lowering.overrides` emitted as pipeline-overridable
    /// constants (taken out of what `bake` picks; the caller has refused a uniform baked on
    /// purpose, see [`super::check_override_conflicts`]). The scene file's uniforms and overrides
    /// are checked first, so a wrong name is reported located in the file. The shader is lowered
    /// once.
    pub fn load_specialized(
        file: Option<&Path>,
        scene: Option<&SceneFile>,
        mut lowering: gdsky_naga::LowerOptions,
        bake: impl FnOnce(&crate::CheckedShader) -> HashMap<String, String>,
    ) -> Result<Sky, Error> {
        let front = check_front(file)?;
        let Some(shader) = front.shader.as_ref() else {
            return Err(Error::Diagnostics(ConvertError::new(front.db, front.diagnostics)));
        };
        if let Some(scene) = scene {
            scene.check_uniforms(shader).map_err(Error::Input)?;
        }
        let mut baked = bake(shader);
        baked.retain(|name, _| !lowering.overrides.contains(name));
        lowering.baked.extend(baked);
        let (front, lowered, wgsl) = lower_and_emit(front, &lowering)?;
        Ok(Sky { front, lowered, wgsl, textures: Vec::new() })
    }

    /// The front end's warnings, rendered (empty when there are none).
    pub fn warnings(&self, color: bool) -> String {
        gdshader::diag::render_human(&self.front.db, &self.front.diagnostics, color)
    }

    /// Checks a scene file's uniforms against this shader (located in the file when one is not
    /// a uniform of it or its value does not fit).
    pub fn check_scene(&self, scene: Option<&SceneFile>) -> Result<(), Error> {
        match (scene, self.front.shader.as_ref()) {
            (Some(scene), Some(shader)) => scene.check_uniforms(shader).map_err(Error::Input),
            _ => Ok(()),
        }
    }
}

/// Reads and checks `file` (the bundled Freeman sky without one): its diagnostics when it is
/// invalid, a wrong environment when it cannot be read.
fn check_front(file: Option<&Path>) -> Result<crate::FrontendOutput, Error> {
    let front = match file {
        Some(path) => gdresource::check_file(path)
            .map_err(|err| Error::environment(format!("cannot read {}: {err}", path.display())))?,
        None => crate::check_source(BUNDLED_NAME, BUNDLED_FREEMAN.as_bytes().to_vec(), None, &mut gdshader::FsLoader),
    };
    if front.shader.is_none() {
        return Err(Error::Diagnostics(ConvertError::new(front.db, front.diagnostics)));
    }
    Ok(front)
}

/// Lowers a checked shader as `lowering` says and emits its WGSL; the diagnostics on failure.
fn lower_and_emit(
    front: crate::FrontendOutput,
    lowering: &gdsky_naga::LowerOptions,
) -> Result<(crate::FrontendOutput, gdsky_naga::Lowered, String), Error> {
    let lowered = match gdsky_naga::lower(&front, lowering) {
        Ok(lowered) => lowered,
        Err(diagnostics) => return Err(Error::Diagnostics(ConvertError::new(front.db, diagnostics))),
    };
    match gdsky_naga::to_wgsl(&lowered) {
        Ok(wgsl) => Ok((front, lowered, wgsl)),
        Err(err) => {
            let diagnostic = err.diagnostic(&front);
            Err(Error::Diagnostics(ConvertError::new(front.db, vec![diagnostic])))
        }
    }
}

impl Sky {
    /// The uniforms baked into constants (`--bake-scene`), name → value.
    pub fn baked(&self) -> &HashMap<String, String> {
        &self.lowered.options.baked
    }

    /// The uniforms emitted as pipeline-overridable constants (`--override`), the k-th with
    /// `@id(k)`.
    pub fn overrides(&self) -> &[String] {
        &self.lowered.options.overrides
    }

    /// Lowers the shader again with `baked` uniforms as constants (`--bake-scene` of `bench`,
    /// after the Freeman-compatibility check) and `overrides` as pipeline-overridable
    /// constants: the same options otherwise. Wrong input when a value does not fit or an
    /// override is not a scalar uniform.
    pub fn respecialize(&mut self, baked: HashMap<String, String>, overrides: &[String]) -> Result<(), Error> {
        let lowering =
            gdsky_naga::LowerOptions { baked, overrides: overrides.to_vec(), ..self.lowered.options.clone() };
        let lowered = gdsky_naga::lower(&self.front, &lowering).map_err(|d| Error::input(self.render(&d)))?;
        let wgsl =
            gdsky_naga::to_wgsl(&lowered).map_err(|e| Error::input(self.render(&[e.diagnostic(&self.front)])))?;
        (self.lowered, self.wgsl) = (lowered, wgsl);
        Ok(())
    }

    /// Diagnostics about this shader, rendered without colour.
    pub fn render(&self, diagnostics: &[gdshader::Diagnostic]) -> String {
        gdshader::diag::render_human(&self.front.db, diagnostics, false)
    }
}

/// A scalar constant as a pipeline constant: wgpu takes every override's value as an f64 and
/// converts it to the override's type, exactly for every f32, i32 and u32 (an f32 parsed from
/// `--set` is first rounded to f32, as the material block would hold it, so the override and
/// the generic module see the same bits). A bool is 0 or 1 (its override is a u32).
pub fn constant_value(v: &gdshader::check::consteval::ConstValue) -> f64 {
    use gdshader::check::consteval::ConstValue;
    match v {
        ConstValue::Float(f) => f64::from(*f as f32),
        ConstValue::Int(i) => *i as f64,
        ConstValue::UInt(u) => *u as f64,
        ConstValue::Bool(b) => f64::from(u8::from(*b)),
        ConstValue::Composite(_) => 0.0,
    }
}

/// Checks the `--set NAME=VALUE` pairs given for the Freeman sky's parameters (`reference`,
/// `bench`) with the value parser `render` and `convert` use
/// ([`gdshader::values::parse_value`]: finite numbers within their type's range), then applies
/// them to `params`.
pub fn set_freeman(params: &mut skyref::FreemanParams, overrides: &[(String, String)]) -> Result<(), String> {
    use gdshader::check::types::{Scalar, Type};
    use skyref::UniformMut;
    for (name, text) in overrides {
        let ty = params.uniforms_mut().into_iter().find(|(n, _)| n == name).map(|(_, u)| match u {
            UniformMut::Float(_) => Type::Scalar(Scalar::Float),
            UniformMut::Int(_) => Type::Scalar(Scalar::Int),
            UniformMut::Vec3(_) => Type::Vector(Scalar::Float, 3),
        });
        let Some(ty) = ty else {
            return Err(format!("`--set {name}={text}`: the Freeman sky has no uniform `{name}`"));
        };
        gdshader::values::parse_value(&ty, text).map_err(|why| format!("`--set {name}={text}`: {why}"))?;
        params.set(name, text).map_err(|why| format!("`--set {name}={text}`: {why}"))?;
    }
    Ok(())
}

/// The uniform names of the Freeman sky, in declaration order.
pub fn freeman_names() -> Vec<&'static str> {
    let mut params = skyref::FreemanParams::default();
    params.uniforms_mut().iter().map(|(name, _)| *name).collect()
}

impl Sky {
    /// The material block of a Freeman-compatible shader from skyref's parameters, so that the
    /// GPU and skyref start from the same (f32-rounded) values; the uniforms baked into
    /// constants and the overrides (pipeline constants) left out.
    pub fn freeman_material(&self, params: &skyref::FreemanParams) -> Result<Vec<u8>, skyrun::MaterialError> {
        let values: Vec<_> = skyrun::freeman_values(params)
            .into_iter()
            .filter(|(name, _)| !self.baked().contains_key(*name) && !self.overrides().iter().any(|o| o == name))
            .collect();
        skyrun::material_bytes(&self.lowered, &values)
    }
}
