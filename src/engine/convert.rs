//! `gdsky convert`'s engine: a shader, a scene file's or a Godot material's, converted with the
//! values the command line and the file bake and the uniforms they make overrides.

use super::{Error, Input, Sky};
use std::collections::HashMap;

/// What [`convert`] converts and how.
#[derive(Debug, Default)]
pub struct ConvertOptions {
    /// The shader, scene file or Godot material, opened.
    pub input: Option<Input>,
    /// Uniforms baked as constants (`--set`): always baked.
    pub sets: Vec<(String, String)>,
    /// Bake every uniform the scene file fixes too; with no scene file, every uniform at its
    /// default.
    pub bake_scene: bool,
    /// The conversion's options (their `set` and `overrides` are added to).
    pub options: crate::Options,
}

/// Converts the input: its diagnostics, or the converted shader (both texts read back and
/// validated before they are handed out).
pub fn convert(options: &ConvertOptions) -> Result<crate::Converted, Error> {
    let (shader, scene) = match &options.input {
        Some(input) => (input.shader.as_deref(), input.scene.as_ref()),
        None => (None, None),
    };
    let sets = &options.sets;
    let overrides = super::override_names(scene, &options.options.lowering.overrides);
    // `--set` always bakes in `convert`; under --bake-scene the scene's uniforms do too.
    super::check_override_conflicts(&overrides, scene, |n| {
        if sets.iter().any(|(s, _)| s == n) {
            Some(format!("`--set {n}=…` bakes `{n}` into a constant"))
        } else {
            super::bake_reason(n, scene, sets, options.bake_scene)
        }
    })?;
    let mut conversion = options.options.clone();
    let lowering = gdsky_naga::LowerOptions { overrides: overrides.clone(), ..conversion.lowering.clone() };
    let sky = Sky::load_specialized(shader, scene, lowering, |checked| {
        let baked: HashMap<String, String> = if options.bake_scene {
            crate::scene::bake_values(checked, scene, sets)
        } else {
            sets.iter().cloned().collect()
        };
        // Baking "every uniform at its default" leaves the overrides alone.
        baked.into_iter().filter(|(name, _)| !overrides.contains(name)).collect()
    })?;
    conversion.lowering = sky.lowered.options.clone();
    let Sky { front, lowered, .. } = sky;
    crate::emit(front, &lowered, &conversion).map_err(Error::Diagnostics)
}
