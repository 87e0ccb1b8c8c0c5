//! `gdsky render [FILE] -o OUT.exr …` and `gdsky reference -o OUT.exr … [--precision f32|f64]`.

use super::scene::SkipArgs;
use super::scene::{
    LoadedShader, SceneArgs, bake_reason, check_outputs, check_override_conflicts, check_scene_uniforms,
    load_shader_specialized, open_gpu, open_input, override_names, set_freeman, strip, write_outputs,
};
use super::usage;
use clap::{ArgMatches, Args, ValueEnum};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

#[derive(Args)]
pub struct RenderArgs {
    /// The sky shader (`.gdshader`), a scene file (`SCENE.toml`: shader, uniforms, lights,
    /// camera, projection, size, time; the flags given override it), or a Godot material
    /// (`MATERIAL.tres`: a ShaderMaterial, or a Sky or Environment leading to one) or scene
    /// (`SCENE.tscn`: its WorldEnvironment's sky), whose shader, `shader_parameter/*` values and
    /// textures (PNG, OpenEXR, NoiseTexture2D, NoiseTexture3D) are used, `--set` and `--texture`
    /// overriding them (docs/godot-materials.md); without one, the bundled Freeman sky.
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
    /// Also render an instrumented version of the shader that records, per pixel, the first
    /// expression that made a NaN or an infinity; print each such place (`file:line:col`, the
    /// expression, the pixel count) and write `OUT.nonfinite.png` marking the pixels (`OUT` is
    /// `-o` without its `.exr`). With none: `no NaN or Inf`, no PNG. The EXR is the shader's
    /// own render either way.
    #[arg(long)]
    trace_nonfinite: bool,
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    skip: SkipArgs,
    #[command(flatten)]
    lowering: super::scene::LoweringArgs,
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
    let lowering = gdsky_naga::LowerOptions { overrides: names.clone(), ..args.lowering.options() };
    let mut loaded = load_shader_specialized(input.shader.as_deref(), input.scene.as_ref(), lowering, |shader| {
        if args.bake_scene {
            gdsky::scene::bake_values(shader, input.scene.as_ref(), &cli_sets)
        } else {
            Default::default()
        }
    })?;
    check_scene_uniforms(input.scene.as_ref(), &loaded)?;
    loaded.textures = scene_args.textures(input.scene.as_ref(), &loaded)?;
    if args.bake_scene {
        let mut names: Vec<&String> = loaded.baked().keys().collect();
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
    let trace_constants = constants.clone();
    let trace_views = views.clone();
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
    write_outputs(&image, &args.out, args.png.as_ref())?;
    if args.trace_nonfinite {
        let traced = TraceInputs { views: &trace_views, width, height, builtins: &builtins, material: &material };
        trace_nonfinite(&loaded, &gpu, trace_constants, &traced, &image, &args.out)?;
    }
    Ok(())
}

/// What the instrumented render of `--trace-nonfinite` draws: the scene of the render.
struct TraceInputs<'a> {
    views: &'a [skyrun::Projection],
    width: u32,
    height: u32,
    builtins: &'a skyrun::SkyBuiltins,
    material: &'a [u8],
}

/// `--trace-nonfinite`: renders the instrumented module (see `gdsky_naga::trace`) with the
/// render's scene, reads each pixel's first site from the alpha channel, prints the report and
/// writes the PNG that marks the pixels. `image` is the normal render (the PNG's background).
fn trace_nonfinite(
    loaded: &LoadedShader,
    gpu: &skyrun::Gpu,
    constants: Vec<(String, f64)>,
    inputs: &TraceInputs<'_>,
    image: &skyrun::Image,
    out: &Path,
) -> Result<(), ExitCode> {
    let failed = |err: &dyn std::fmt::Display| {
        eprintln!("error: {err}");
        ExitCode::from(1)
    };
    let traced = gdsky_naga::trace::instrument(&loaded.front, &loaded.lowered).map_err(|diagnostics| {
        eprint!("{}", gdsky::frontend::diag::render_human(&loaded.front.db, &diagnostics, false));
        ExitCode::from(1)
    })?;
    let wgsl = gdsky_naga::to_wgsl(&traced.lowered).map_err(|e| failed(&e.diagnostic(&loaded.front).message))?;
    let shader = loaded.compile_wgsl(gpu, &wgsl)?.with_constants(constants);
    // Every pixel shaded at full resolution, whatever `--occluder`/`--sky-resolution` say: an
    // id cannot be upsampled, and a hidden pixel can still tell where a NaN comes from.
    let options = skyrun::RenderOptions::default();
    let mut views = Vec::with_capacity(inputs.views.len());
    for view in inputs.views {
        let r = shader
            .render_with(gpu, *view, inputs.width, inputs.height, inputs.builtins, inputs.material, &options)
            .map_err(|e| failed(&e))?;
        views.push(r.pixels);
    }
    let ids = strip(views, inputs.width, inputs.height).map_err(|e| failed(&e))?;
    let report = gdsky_naga::trace::NonfiniteReport::new(&traced, &ids.pixels);
    if report.unknown > 0 {
        // Only the instrumented module writes the alpha; anything else is a harness bug.
        eprintln!("warning: {} pixel(s) carry no site id (alpha neither 0 nor an id)", report.unknown);
    }
    print!("{}", report.text());
    if report.places.is_empty() {
        return Ok(());
    }
    let png = nonfinite_png_path(out);
    let overlay: Vec<Option<[u8; 3]>> = ids
        .pixels
        .iter()
        .map(|p| {
            report
                .place_of(&traced, p[3])
                .map(|i| gdsky_naga::trace::PLACE_COLOURS[i.min(gdsky_naga::trace::PLACE_COLOURS.len() - 1)].1)
        })
        .collect();
    skyrun::write_overlay_png(&png, image, &overlay).map_err(|e| {
        eprintln!("error: {e}");
        ExitCode::from(2)
    })?;
    println!("wrote {}", png.display());
    Ok(())
}

/// `OUT.nonfinite.png` for `-o OUT.exr` (the `.exr` replaced; any other name gets the suffix).
pub fn nonfinite_png_path(out: &Path) -> PathBuf {
    let name = out.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let stem = name.strip_suffix(".exr").or_else(|| name.strip_suffix(".EXR")).unwrap_or(&name);
    out.with_file_name(format!("{stem}.nonfinite.png"))
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
