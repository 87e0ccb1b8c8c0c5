//! `gdsky render [FILE] -o OUT.exr …` and `gdsky reference -o OUT.exr … [--precision f32|f64]`.

use super::scene::SkipArgs;
use super::scene::{
    SceneArgs, bake_reason, check_outputs, check_override_conflicts, check_scene_uniforms, load_shader_specialized,
    open_gpu, open_input, override_names, set_freeman, strip, write_outputs,
};
use super::usage;
use clap::{ArgMatches, Args, ValueEnum};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

#[derive(Args)]
pub struct RenderArgs {
    /// The sky shader (`.gdshader`) or a scene file (`SCENE.toml`: shader, uniforms, lights,
    /// camera, projection, size, time; the flags given override it) to render; without one, the
    /// bundled Freeman sky. Godot materials and scenes (`.tres`, `.tscn`) are not supported yet.
    #[arg(value_name = "MATERIAL.tres | SCENE.tscn | SCENE.toml | FILE")]
    file: Option<PathBuf>,
    /// Bake every uniform the scene file fixes (and every `--set`) into the shader as
    /// constants; with no scene file, every uniform at its default.
    #[arg(long)]
    bake_scene: bool,
    /// Emit a scalar uniform as a pipeline-overridable constant (WGSL `override`, as `convert
    /// --override`) and render with its value (`--set`, the scene file's, else the default)
    /// given at pipeline creation; the image is the generic module's. Adds to the scene file's
    /// `overrides`. Repeatable.
    #[arg(long = "override", value_name = "NAME")]
    overrides: Vec<String>,
    /// The EXR to write: RGBA 32-bit float, scanline, row 0 at the top (replaced atomically; a
    /// symbolic link is written through to its target). Its directory must exist.
    #[arg(short = 'o', long = "out", value_name = "OUT.exr")]
    out: PathBuf,
    /// Also write an 8-bit PNG preview, tone mapped 1 − exp(−L·0.5) and gamma 2.2.
    #[arg(long, value_name = "OUT.png")]
    png: Option<PathBuf>,
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    skip: SkipArgs,
}

pub fn run(args: &RenderArgs, matches: &ArgMatches) -> ExitCode {
    match render(args, matches) {
        Ok(()) => ExitCode::SUCCESS,
        Err(code) => code,
    }
}

fn render(args: &RenderArgs, matches: &ArgMatches) -> Result<(), ExitCode> {
    let input = open_input(args.file.as_deref())?;
    let mut scene_args = args.scene.clone();
    let mut skip = args.skip.clone();
    if let Some(file) = &input.scene {
        scene_args.merge_file(file, matches);
        skip.merge_file(file, matches);
    }
    let (views, width, height) = scene_args.views().map_err(usage)?;
    let overrides = scene_args.overrides().map_err(usage)?;
    check_outputs(&args.out, args.png.as_ref())?;
    let occluder = skip.occluder(&views, width, height)?;
    let options = skip.options(occluder.as_ref());
    let started = Instant::now();
    let cli_sets = args.scene.overrides().map_err(usage)?;
    let names = override_names(input.scene.as_ref(), &args.overrides);
    check_override_conflicts(&names, input.scene.as_ref(), |n| {
        bake_reason(n, input.scene.as_ref(), &cli_sets, args.bake_scene)
    })?;
    let mut loaded = load_shader_specialized(input.shader.as_deref(), input.scene.as_ref(), &names, |shader| {
        if args.bake_scene {
            gdsky::scene::bake_values(shader, input.scene.as_ref(), &cli_sets)
        } else {
            Default::default()
        }
    })?;
    check_scene_uniforms(input.scene.as_ref(), &loaded)?;
    loaded.textures = scene_args.textures(input.scene.as_ref(), &loaded)?;
    if args.bake_scene {
        let mut names: Vec<&String> = loaded.baked.keys().collect();
        names.sort();
        eprintln!(
            "baked {} uniform(s): {}",
            names.len(),
            names.iter().map(|n| n.as_str()).collect::<Vec<_>>().join(", ")
        );
    }
    let convert_time = started.elapsed();
    // After the conversion is timed: the table is the scene's input, not part of converting.
    if let Some(note) = loaded.bake_tables(&overrides).map_err(usage)? {
        eprintln!("{note}");
    }
    let material = loaded.material(&overrides).map_err(|e| usage(format!("--set: {e}")))?;
    let constants = loaded.constants(&overrides).map_err(usage)?;
    if !names.is_empty() {
        eprintln!("overrides: {}", names.join(", "));
    }
    let gpu = open_gpu()?;
    let shader = loaded.compile(&gpu)?.with_constants(constants);
    let builtins = scene_args.builtins(input.scene.as_ref(), width, height);
    let mut rendered = Vec::with_capacity(views.len());
    let mut gpu_time = std::time::Duration::ZERO;
    for view in views {
        let r = shader.render_with(&gpu, view, width, height, &builtins, &material, &options).map_err(|err| {
            eprintln!("error: {err}");
            ExitCode::from(1)
        })?;
        gpu_time += r.gpu_wait;
        rendered.push(r.pixels);
    }
    let image = strip(rendered, width, height).map_err(|err| {
        eprintln!("error: {err}");
        ExitCode::from(1)
    })?;
    eprintln!("convert {convert_time:.2?}, GPU {gpu_time:.2?}, total {:.2?}", started.elapsed());
    write_outputs(&image, &args.out, args.png.as_ref())
}

/// Says which keys of a scene file a command does not apply (`bench` measures the
/// full-resolution, unoccluded sky its truth describes).
pub fn warn_unapplied(file: &gdsky::scene::SceneFile, command: &str) {
    for (key, set) in [("occluder", file.occluder.is_some()), ("sky_resolution", file.sky_resolution.is_some())] {
        if set {
            eprintln!("warning: {}: `{key}` does not apply to `{command}`; ignored", file.path.display());
        }
    }
}

/// Working precision of the CPU reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Precision {
    /// The same f32 arithmetic a GPU does (the pixel tests' reference).
    F32,
    /// The same quadrature in f64: the shader's own f32 error removed.
    F64,
}

#[derive(Args)]
pub struct ReferenceArgs {
    /// The EXR to write: RGBA 32-bit float, scanline, row 0 at the top (replaced atomically; a
    /// symbolic link is written through to its target). Its directory must exist.
    #[arg(short = 'o', long = "out", value_name = "OUT.exr")]
    out: PathBuf,
    /// Also write an 8-bit PNG preview, tone mapped as `render`'s.
    #[arg(long, value_name = "OUT.png")]
    png: Option<PathBuf>,
    /// Working precision.
    #[arg(long, value_enum, default_value_t = Precision::F32)]
    precision: Precision,
    #[command(flatten)]
    scene: SceneArgs,
}

pub fn run_reference(args: &ReferenceArgs) -> ExitCode {
    match reference(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(code) => code,
    }
}

fn reference(args: &ReferenceArgs) -> Result<(), ExitCode> {
    if !args.scene.texture.is_empty() {
        return Err(usage("--texture: the reference is the Freeman sky, which has no sampler uniforms"));
    }
    let (views, width, height) = args.scene.views().map_err(usage)?;
    let params = freeman_params(&args.scene.overrides().map_err(usage)?).map_err(usage)?;
    check_outputs(&args.out, args.png.as_ref())?;
    let scene = args.scene.scene();
    let started = Instant::now();
    let rendered: Vec<Vec<[f32; 4]>> = views
        .into_iter()
        .map(|view| match args.precision {
            Precision::F32 => skyref::f32::render(&params, &scene, view, width, height),
            Precision::F64 => skyref::f64::render(&params, &scene, view, width, height)
                .into_iter()
                .map(|p| p.map(|c| c as f32))
                .collect(),
        })
        .collect();
    eprintln!("skyref {:?}: {:.2?}", args.precision, started.elapsed());
    let image = strip(rendered, width, height).map_err(|err| {
        eprintln!("error: {err}");
        ExitCode::from(1)
    })?;
    write_outputs(&image, &args.out, args.png.as_ref())
}

/// The Freeman sky's parameters with `--set` overrides applied (by the shader's uniform names),
/// each value checked as `render --set` checks it.
pub fn freeman_params(overrides: &[(String, String)]) -> Result<skyref::FreemanParams, String> {
    let mut params = skyref::FreemanParams::default();
    set_freeman(&mut params, overrides)?;
    Ok(params)
}
