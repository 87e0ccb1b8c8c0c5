//! `gdsky oracle FILE [scene flags] -o godot.exr`: the shader rendered by real Godot 4.6.
//!
//! Godot's Web export runs in headless Chromium (crates/skyoracle); its 8-bit frames, rendered
//! at bracketed background energies, are inverted into the shader's linear COLOR, so
//! `gdsky compare` can hold `gdsky render` against Godot itself.

use super::scene::{BUNDLED_FREEMAN, SceneArgs, check_outputs, write_outputs};
use clap::Args;
use skycore::Projection;
use skyoracle::{Job, Oracle, Parameter, StartError};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

#[derive(Args)]
pub struct OracleArgs {
    /// The sky shader to render in Godot; without one, the bundled Freeman sky. `#include` is not
    /// available in the oracle (Godot's Web export has no project files to include). A Godot
    /// material or scene (`MATERIAL.tres`, `SCENE.tscn`) gives its shader, its values (under
    /// `--set`) and its NoiseTexture2Ds, gradient and curve textures, which Godot
    /// generates itself; image textures cannot be given to the oracle yet.
    #[arg(value_name = "FILE | MATERIAL.tres | SCENE.tscn")]
    file: Option<PathBuf>,
    /// The EXR to write: the recovered linear COLOR, RGBA 32-bit float (alpha 1), row 0 at the top.
    #[arg(short = 'o', long = "out", value_name = "OUT.exr")]
    out: PathBuf,
    /// Also write an 8-bit PNG preview, tone mapped as `render`'s.
    #[arg(long, value_name = "OUT.png")]
    png: Option<PathBuf>,
    /// Where the oracle is installed: the folder holding `.oracle/` (`bash
    /// scripts/install-oracle.sh` puts it at the repository root) [default: the source tree this
    /// binary was built from].
    #[arg(long, value_name = "DIR")]
    oracle_root: Option<PathBuf>,
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    lowering: super::scene::LoweringArgs,
}

pub fn run(args: &OracleArgs) -> ExitCode {
    match oracle(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(code) => code,
    }
}

fn oracle(args: &OracleArgs) -> Result<(), ExitCode> {
    let usage = |message: String| {
        eprintln!("error: {message}");
        ExitCode::from(1)
    };
    if !args.scene.texture.is_empty() {
        return Err(usage("--texture: the oracle does not give Godot textures yet".into()));
    }
    if args.scene.projection.is_some_and(|p| p != Projection::Camera) {
        return Err(usage("the oracle renders Godot's camera view only: use --projection camera".into()));
    }
    let scene = SceneArgs { projection: Some(Projection::Camera), ..args.scene.clone() };
    let (_, width, height) = scene.views().map_err(usage)?;
    // A Godot material: its values first, so a --set of the same uniform wins.
    let material = match args.file.as_deref().filter(|f| gdsky::scene::is_godot_resource(f)) {
        Some(path) => super::scene::open_input(Some(path))?.scene,
        None => None,
    };
    let mut overrides = material.as_ref().map(|m| m.uniform_pairs()).unwrap_or_default();
    let flags = scene.overrides().map_err(usage)?;
    overrides.retain(|(name, _)| !flags.iter().any(|(n, _)| n == name));
    overrides.extend(flags);
    if let Some(image) = material.as_ref().and_then(|m| m.textures.first()) {
        return Err(usage(format!(
            "`{}`: the oracle gives Godot noise textures only, not image files ({})",
            image.name,
            image.path.display()
        )));
    }
    // Godot would get a stand-in for it, and the comparison would not be of the same sky.
    if let Some(volume) = material.as_ref().and_then(|m| m.generated_volumes.first()) {
        return Err(usage(format!(
            "`{}`: the oracle gives Godot NoiseTexture2Ds only, not NoiseTexture3Ds",
            volume.name
        )));
    }
    check_outputs(&args.out, args.png.as_ref())?;

    // gdsky checks the shader first: the uniform types for --set, and a clear diagnostic before
    // Godot is started for nothing.
    let shader_file = match &material {
        Some(m) => m.shader.clone(),
        None => args.file.clone(),
    };
    let loaded = super::scene::load_shader(shader_file.as_deref(), &args.lowering.options())?;
    // The text the front end read and checked (not a second read of FILE, which could differ).
    let code = match &shader_file {
        Some(_) => loaded.front.db.text(loaded.front.root).to_string(),
        None => BUNDLED_FREEMAN.to_string(),
    };
    let checked = loaded.front.shader.as_ref().ok_or(ExitCode::from(1))?;
    if checked.builtins_used.contains("TIME") && scene.time != 0.0 {
        eprintln!("warning: the oracle cannot set TIME: Godot's is wall-clock time since it started");
    }
    let mut uniforms = Vec::new();
    for (name, text) in &overrides {
        let uniform = checked
            .uniforms
            .iter()
            .find(|u| &u.name == name)
            .ok_or_else(|| usage(format!("the shader has no uniform `{name}`")))?;
        let value = gdshader::values::parse_value(&uniform.ty, text)
            .map_err(|m| usage(format!("`--set {name}={text}`: {m}")))?;
        let value = gdshader::values::uniform_value(&uniform.ty, &value)
            .map(Parameter::Value)
            .ok_or_else(|| usage(format!("`--set {name}`: the oracle cannot set a `{}` uniform", uniform.type_name)))?;
        uniforms.push((name.clone(), value));
    }
    for g in material.iter().flat_map(|m| &m.generated_textures) {
        uniforms.push((g.name.clone(), Parameter::NoiseTexture2D(noise_spec(&g.texture))));
    }
    for g in material.iter().flat_map(|m| &m.generated_ramps) {
        uniforms.push((g.name.clone(), Parameter::RampTexture(ramp_spec(&g.texture))));
    }

    let mut job = Job::new(code, width, height);
    job.scene = scene.scene().with_time(0.0);
    job.uniforms = uniforms;

    let root = args.oracle_root.clone().unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")));
    let started = Instant::now();
    let mut oracle = start(&root)?;
    let info = oracle.info();
    eprintln!(
        "oracle: Godot {} ({}) on {}, Chromium {}; started in {:.2?}",
        info.godot_version,
        info.rendering_method,
        info.webgl_renderer,
        info.browser_version,
        started.elapsed()
    );
    let t = Instant::now();
    let image = oracle.render(&job).map_err(|err| {
        eprintln!("error: {err}");
        ExitCode::from(1)
    })?;
    let unrecovered = (0..image.height)
        .flat_map(|y| (0..image.width).map(move |x| (x, y)))
        .filter(|&(x, y)| image.valid_min(x, y) == 0)
        .count();
    eprintln!(
        "Godot rendered {width}x{height} at {} energies in {:.2?}; {unrecovered} pixel(s) with a channel no bracket \
         resolved (black, or brighter than the top bracket)",
        job.brackets.energies().len(),
        t.elapsed()
    );
    let pixels = image.pixels.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect();
    let out = skyrun::Image::new(width, height, pixels).map_err(|err| {
        eprintln!("error: {err}");
        ExitCode::from(1)
    })?;
    write_outputs(&out, &args.out, args.png.as_ref())
}

/// Starts the oracle; a missing part is the environment's fault (exit 2, with what to install).
fn start(root: &Path) -> Result<Oracle, ExitCode> {
    Oracle::start(root).map_err(|err| {
        match err {
            StartError::Missing(missing) => eprintln!("error: the Godot oracle is not installed: {missing}"),
            StartError::Failed(failed) => eprintln!("error: the Godot oracle did not start: {failed}"),
        }
        ExitCode::from(2)
    })
}

/// A noise texture as the oracle's property maps: every property gdsky reads, by its Godot name
/// (Godot then generates the texture itself).
/// A material's gradient or curve texture as the oracle's JSON property maps (Godot's names),
/// every property given, so that Godot builds what gdsky generates.
fn ramp_spec(t: &gdresource::generated::RampTexture) -> skyoracle::RampTextureSpec {
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

fn noise_spec(t: &gdresource::generated::NoiseTexture2D) -> skyoracle::NoiseTextureSpec {
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
