//! Real Godot 4.6 as a renderer: a shader (or a Godot material) rendered by Godot's Web export
//! in headless Chromium ([`skyoracle`]), its 8-bit frames at bracketed energies inverted into
//! linear COLOR, so that gdsky's render can be held against Godot's own.

use super::{Error, Input, Progress, Setup, Sky};
use skycore::Projection;
use skyoracle::{Job, Oracle, Parameter, StartError};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What [`render`] asks Godot for.
#[derive(Debug)]
pub struct OracleOptions {
    /// The shader, or a Godot material or scene giving the shader, its values and its
    /// generated textures; `None`: the bundled Freeman sky.
    pub file: Option<PathBuf>,
    /// The camera view, lights and values (the camera projection only; TIME cannot be set).
    pub setup: Setup,
    /// How gdsky lowers the shader while checking it (Godot renders its own text).
    pub lowering: gdsky_naga::LowerOptions,
    /// The folder holding `.oracle/` (`scripts/install-oracle.sh` puts it at the repository
    /// root).
    pub root: PathBuf,
}

/// Renders in Godot: the recovered linear COLOR (alpha 1), row 0 at the top. Wrong input for
/// what the oracle cannot give Godot (image textures, a 3D noise, another projection); a wrong
/// environment when the oracle is not installed or does not start.
pub fn render(options: &OracleOptions, progress: &dyn Progress) -> Result<skyrun::Image, Error> {
    let setup = &options.setup;
    if !setup.textures.is_empty() {
        return Err(Error::input("--texture: the oracle does not give Godot textures yet"));
    }
    if setup.projection != Projection::Camera {
        return Err(Error::input("the oracle renders Godot's camera view only: use --projection camera"));
    }
    let (width, height) = (setup.width, setup.height);
    // A Godot material: its values first, so a set value of the same uniform wins.
    let material = match options.file.as_deref().filter(|f| crate::scene::is_godot_resource(f)) {
        Some(path) => Input::open(Some(path))?.scene,
        None => None,
    };
    let mut values = material.as_ref().map(|m| m.uniform_pairs()).unwrap_or_default();
    values.retain(|(name, _)| !setup.sets.iter().any(|(n, _)| n == name));
    values.extend(setup.sets.iter().cloned());
    if let Some(image) = material.as_ref().and_then(|m| m.textures.first()) {
        return Err(Error::input(format!(
            "`{}`: the oracle gives Godot noise textures only, not image files ({})",
            image.name,
            image.path.display()
        )));
    }
    // Godot would get a stand-in for it, and the comparison would not be of the same sky.
    if let Some(volume) = material.as_ref().and_then(|m| m.generated_volumes.first()) {
        return Err(Error::input(format!(
            "`{}`: the oracle gives Godot NoiseTexture2Ds only, not NoiseTexture3Ds",
            volume.name
        )));
    }
    // gdsky checks the shader first: the uniform types of the values, and a clear diagnostic
    // before Godot is started for nothing.
    let shader_file = match &material {
        Some(m) => m.shader.clone(),
        None => options.file.clone(),
    };
    let loaded = Sky::load(shader_file.as_deref(), &options.lowering)?;
    // The text the front end read and checked (not a second read of FILE, which could differ).
    let code = match &shader_file {
        Some(_) => loaded.front.db.text(loaded.front.root).to_string(),
        None => super::BUNDLED_FREEMAN.to_string(),
    };
    let checked = loaded.front.shader.as_ref().ok_or_else(|| Error::input("the shader has errors"))?;
    if checked.builtins_used.contains("TIME") && setup.scene.time != 0.0 {
        progress.note("warning: the oracle cannot set TIME: Godot's is wall-clock time since it started");
    }
    let mut uniforms = Vec::new();
    for (name, text) in &values {
        let uniform = checked
            .uniforms
            .iter()
            .find(|u| &u.name == name)
            .ok_or_else(|| Error::input(format!("the shader has no uniform `{name}`")))?;
        let value = gdshader::values::parse_value(&uniform.ty, text)
            .map_err(|m| Error::input(format!("`--set {name}={text}`: {m}")))?;
        let value = gdshader::values::uniform_value(&uniform.ty, &value).map(Parameter::Value).ok_or_else(|| {
            Error::input(format!("`--set {name}`: the oracle cannot set a `{}` uniform", uniform.type_name))
        })?;
        uniforms.push((name.clone(), value));
    }
    for g in material.iter().flat_map(|m| &m.generated_textures) {
        uniforms.push((g.name.clone(), Parameter::NoiseTexture2D(noise_spec(&g.texture))));
    }
    for g in material.iter().flat_map(|m| &m.generated_ramps) {
        uniforms.push((g.name.clone(), Parameter::RampTexture(ramp_spec(&g.texture))));
    }

    let mut job = Job::new(code, width, height);
    job.scene = setup.scene.with_time(0.0);
    job.uniforms = uniforms;

    let started = Instant::now();
    let mut oracle = start(&options.root)?;
    let info = oracle.info();
    progress.note(&format!(
        "oracle: Godot {} ({}) on {}, Chromium {}; started in {:.2?}",
        info.godot_version,
        info.rendering_method,
        info.webgl_renderer,
        info.browser_version,
        started.elapsed()
    ));
    let t = Instant::now();
    let image = oracle.render(&job).map_err(Error::input)?;
    let unrecovered = (0..image.height)
        .flat_map(|y| (0..image.width).map(move |x| (x, y)))
        .filter(|&(x, y)| image.valid_min(x, y) == 0)
        .count();
    progress.note(&format!(
        "Godot rendered {width}x{height} at {} energies in {:.2?}; {unrecovered} pixel(s) with a channel no bracket \
         resolved (black, or brighter than the top bracket)",
        job.brackets.energies().len(),
        t.elapsed()
    ));
    let pixels = image.pixels.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect();
    skyrun::Image::new(width, height, pixels).map_err(Error::input)
}

/// Starts the oracle; a missing part is the environment's fault (with what to install).
pub fn start(root: &Path) -> Result<Oracle, Error> {
    Oracle::start(root).map_err(|err| match err {
        StartError::Missing(missing) => Error::environment(format!("the Godot oracle is not installed: {missing}")),
        StartError::Failed(failed) => Error::environment(format!("the Godot oracle did not start: {failed}")),
    })
}

/// A material's gradient or curve texture as the oracle's JSON property maps (Godot's names),
/// every property given, so that Godot builds what gdsky generates.
pub fn ramp_spec(t: &gdresource::generated::RampTexture) -> skyoracle::RampTextureSpec {
    use gdresource::generated::RampTexture;
    use serde_json::{Map, Value, json};
    let object = |v: Value| match v {
        Value::Object(map) => map,
        _ => Map::new(),
    };
    let gradient = |g: &Option<gdresource::generated::Gradient>| {
        g.as_ref().map(|g| {
            object(json!({
                "offsets": g.offsets, "colors": g.colors, "interpolation_mode": g.interpolation_mode,
                "interpolation_color_space": g.interpolation_color_space,
            }))
        })
    };
    let curve = |c: &Option<gdresource::generated::Curve>| {
        c.as_ref().map(|c| {
            let points: Vec<Value> = c
                .points
                .iter()
                .map(|p| {
                    json!([p.position[0], p.position[1], p.left_tangent, p.right_tangent, p.left_mode, p.right_mode])
                })
                .collect();
            object(json!({
                "points": points, "min_value": c.min_value, "max_value": c.max_value,
                "min_domain": c.min_domain, "max_domain": c.max_domain, "bake_resolution": c.bake_resolution,
            }))
        })
    };
    let mut spec = skyoracle::RampTextureSpec { class: t.class().to_string(), ..Default::default() };
    let texture = match t {
        RampTexture::Gradient1D(t) => {
            spec.gradient = gradient(&t.gradient);
            json!({ "width": t.width, "use_hdr": t.use_hdr })
        }
        RampTexture::Gradient2D(t) => {
            spec.gradient = gradient(&t.gradient);
            json!({
                "width": t.width, "height": t.height, "use_hdr": t.use_hdr, "fill": t.fill,
                "fill_from": t.fill_from, "fill_to": t.fill_to, "repeat": t.repeat,
            })
        }
        RampTexture::Curve(t) => {
            spec.curve = curve(&t.curve);
            json!({ "width": t.width, "texture_mode": t.texture_mode })
        }
        RampTexture::CurveXyz(t) => {
            spec.curves_xyz = [curve(&t.curves[0]), curve(&t.curves[1]), curve(&t.curves[2])];
            json!({ "width": t.width })
        }
    };
    spec.texture = object(texture);
    spec
}

/// A noise texture as the oracle's property maps: every property gdsky reads, by its Godot name
/// (Godot then generates the texture itself).
pub fn noise_spec(t: &gdresource::generated::NoiseTexture2D) -> skyoracle::NoiseTextureSpec {
    use serde_json::{Map, Value, json};
    let object = |v: Value| match v {
        Value::Object(map) => map,
        _ => Map::new(),
    };
    let noise = t.noise.as_ref().map(|n| {
        object(json!({
            "noise_type": n.noise_type, "seed": n.seed, "frequency": n.frequency, "offset": n.offset,
            "fractal_type": n.fractal_type, "fractal_octaves": n.fractal_octaves,
            "fractal_lacunarity": n.fractal_lacunarity, "fractal_gain": n.fractal_gain,
            "fractal_weighted_strength": n.fractal_weighted_strength,
            "fractal_ping_pong_strength": n.fractal_ping_pong_strength,
            "cellular_distance_function": n.cellular_distance_function, "cellular_jitter": n.cellular_jitter,
            "cellular_return_type": n.cellular_return_type, "domain_warp_enabled": n.domain_warp_enabled,
            "domain_warp_type": n.domain_warp_type, "domain_warp_amplitude": n.domain_warp_amplitude,
            "domain_warp_frequency": n.domain_warp_frequency, "domain_warp_fractal_type": n.domain_warp_fractal_type,
            "domain_warp_fractal_octaves": n.domain_warp_fractal_octaves,
            "domain_warp_fractal_lacunarity": n.domain_warp_fractal_lacunarity,
            "domain_warp_fractal_gain": n.domain_warp_fractal_gain,
        }))
    });
    let color_ramp = t.color_ramp.as_ref().map(|g| {
        object(json!({
            "offsets": g.offsets, "colors": g.colors, "interpolation_mode": g.interpolation_mode,
            "interpolation_color_space": g.interpolation_color_space,
        }))
    });
    skyoracle::NoiseTextureSpec {
        texture: object(json!({
            "width": t.width, "height": t.height, "invert": t.invert, "in_3d_space": t.in_3d_space,
            "generate_mipmaps": t.generate_mipmaps, "seamless": t.seamless,
            "seamless_blend_skirt": t.seamless_blend_skirt, "as_normal_map": t.as_normal_map,
            "bump_strength": t.bump_strength, "normalize": t.normalize,
        })),
        noise,
        color_ramp,
    }
}
