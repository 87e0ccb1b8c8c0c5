//! What a command's FILE names, opened: a shader, a scene file (`.toml`: its shader, scene and
//! values) or a Godot material or scene (`.tres`, `.tscn`: its shader, values and textures, as a
//! scene file); and the rules for uniforms that are overrides and baked at once.

use super::Error;
use crate::scene::{SceneError, SceneFile};
use std::path::{Path, PathBuf};

/// What a command's FILE argument names: a shader, or a scene file and its shader.
#[derive(Debug)]
pub struct Input {
    /// The shader; `None`: the bundled Freeman sky.
    pub shader: Option<PathBuf>,
    /// The scene file, when FILE is one (`.toml`), or a Godot material read as one.
    pub scene: Option<SceneFile>,
    /// Warnings to show (a material's values of uniforms the shader lacks), rendered.
    pub warnings: String,
}

impl Input {
    /// Opens FILE: a `.toml` is read as a scene file, a `.tres`/`.tscn` as a Godot material
    /// ([`SceneFile::from_material`]); anything else is the shader; none, the bundled Freeman
    /// sky. Errors are located in the file: [`Error::Input`] when it is wrong,
    /// [`Error::Environment`] when it cannot be read.
    pub fn open(file: Option<&Path>) -> Result<Input, Error> {
        let Some(path) = file else {
            return Ok(Input { shader: None, scene: None, warnings: String::new() });
        };
        if crate::scene::is_godot_resource(path) {
            return open_material(path);
        }
        if !crate::scene::is_scene_path(path) {
            return Ok(Input { shader: Some(path.to_path_buf()), scene: None, warnings: String::new() });
        }
        match SceneFile::load(path) {
            Ok(scene) => Ok(Input { shader: scene.shader.clone(), scene: Some(scene), warnings: String::new() }),
            Err(SceneError::Read(m)) => Err(Error::Environment(m)),
            Err(SceneError::Invalid(m)) => Err(Error::Input(m)),
        }
    }
}

/// Opens a Godot material (`.tres`) or scene (`.tscn`) as a scene file: its shader (FILE itself
/// when the shader is embedded: the loaders check it through [`gdresource::check_file`]), its
/// values as `[uniforms]` and its textures as `[textures]`, every error located in the
/// material's file.
fn open_material(path: &Path) -> Result<Input, Error> {
    use gdresource::{MaterialError, MaterialShader};
    let material = match gdresource::load_sky_material(path) {
        Ok(m) => m,
        Err(MaterialError::Read(m)) => return Err(Error::Environment(m)),
        Err(MaterialError::Invalid(m)) => return Err(Error::Input(m)),
    };
    let shader = match &material.shader {
        MaterialShader::File(p) => p.clone(),
        MaterialShader::Embedded { .. } => path.to_path_buf(),
    };
    // The values become `--set` text for the uniforms' types, so the shader is checked here;
    // its own diagnostics are reported once, when the command loads it.
    let front = material.check_shader().ok();
    let settings = match front.as_ref().and_then(|f| f.shader.as_ref()) {
        Some(checked) => material.settings(checked).map_err(Error::Input)?,
        None => Default::default(),
    };
    let warnings = settings.warnings.clone();
    let scene = SceneFile::from_material(material, shader.clone(), settings);
    Ok(Input { shader: Some(shader), scene: Some(scene), warnings })
}

/// The uniforms to emit as overrides: the scene file's `overrides`, then each `--override` not
/// already listed (the flags add to the file).
pub fn override_names(scene: Option<&SceneFile>, flags: &[String]) -> Vec<String> {
    let mut names = scene.map(SceneFile::override_names).unwrap_or_default();
    for f in flags {
        if !names.contains(f) {
            names.push(f.clone());
        }
    }
    names
}

/// Why `name` is baked on purpose: under `--bake-scene`, a `--set` of it or the scene file's
/// `[uniforms]` fixing it. `None` when it is not (baking "every uniform at its default", without
/// a scene file, leaves overrides alone).
pub fn bake_reason(
    name: &str,
    scene: Option<&SceneFile>,
    cli_sets: &[(String, String)],
    bake_scene: bool,
) -> Option<String> {
    if !bake_scene {
        return None;
    }
    if cli_sets.iter().any(|(n, _)| n == name) {
        return Some(format!("`--set {name}=… --bake-scene` bakes `{name}` into a constant"));
    }
    if scene.is_some_and(|s| s.uniforms.iter().any(|u| u.name == name)) {
        return Some(format!("`--bake-scene` bakes the scene's `[uniforms]`, which fix `{name}`"));
    }
    None
}

/// Refuses a uniform that is both an override and baked on purpose (`reason`, see
/// [`bake_reason`]): a uniform is a constant in the module or a pipeline constant, not both.
/// Wrong input saying which; located in the scene file when its `overrides` lists the name.
pub fn check_override_conflicts(
    overrides: &[String],
    scene: Option<&SceneFile>,
    reason: impl Fn(&str) -> Option<String>,
) -> Result<(), Error> {
    for name in overrides {
        let Some(why) = reason(name) else { continue };
        let message = format!("`{name}` cannot be an override and baked: {why}; drop `--override {name}` or the bake");
        return Err(match scene.filter(|s| s.overrides.iter().any(|o| o.name == *name)) {
            Some(scene) => Error::Input(scene.override_error(name, &message)),
            None => Error::Input(message),
        });
    }
    Ok(())
}

/// Notes which keys of a scene file a command does not apply (`bench` measures the
/// full-resolution, unoccluded sky its truth describes).
pub fn warn_unapplied(file: &SceneFile, command: &str, progress: &dyn super::Progress) {
    for (key, set) in [("occluder", file.occluder.is_some()), ("sky_resolution", file.sky_resolution.is_some())] {
        if set {
            progress.note(&format!("warning: {}: `{key}` does not apply to `{command}`; ignored", file.path.display()));
        }
    }
}
