//! `gdsky render [FILE] -o OUT.exr|OUT.png …` (the engine: [`gdsky::engine::render`]) and
//! `gdsky reference -o OUT.exr … [--precision f32|f64]` (skyref, the Freeman sky on the CPU).

use super::progress::Bar;
use super::scene::{SceneArgs, SkipArgs};
use clap::{ArgMatches, Args, ValueEnum};
use gdsky::engine::{self, Error, Input, render::RenderOptions};
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
    /// The image to write, its format from the extension: `.exr`, RGBA 32-bit float linear
    /// radiance, scanline, row 0 at the top; `.png`, an 8-bit sRGB preview tone mapped as
    /// `--png`. Replaced atomically (a symbolic link is written through to its target); its
    /// directory must exist.
    #[arg(short = 'o', long = "out", value_name = "OUT.exr|OUT.png")]
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
    super::exit(render(args, matches))
}

fn render(args: &RenderArgs, matches: &ArgMatches) -> Result<(), Error> {
    super::watch_driver(args.file.as_deref())?;
    let input = Input::open(args.file.as_deref())?;
    err!("{}", input.warnings);
    let mut scene = args.scene.clone();
    let mut skip = args.skip.clone();
    if let Some(file) = &input.scene {
        scene.merge_file(file, matches);
        skip.merge_file(file, matches);
    }
    let setup = scene.setup()?;
    check_outputs(&args.out, args.png.as_ref())?;
    let trace_png = args.trace_nonfinite.then(|| nonfinite_png_path(&args.out));
    if let Some(png) = &trace_png {
        // Derived outputs are checked before any work too.
        engine::check_image_output(png)?;
    }
    // No output over an input: the shader, the scene file or material, its textures, the mask.
    let textures = setup.textures.iter().filter_map(|t| t.split_once('=').map(|(_, p)| PathBuf::from(p)));
    let scene_textures = input.scene.iter().flat_map(|s| s.textures.iter().map(|t| t.path.clone()));
    let inputs: Vec<PathBuf> = [args.file.clone(), input.shader.clone(), skip.occluder.clone()]
        .into_iter()
        .flatten()
        .chain(textures)
        .chain(scene_textures)
        .collect();
    let outputs: Vec<&Path> =
        [Some(&args.out), args.png.as_ref(), trace_png.as_ref()].into_iter().flatten().map(PathBuf::as_path).collect();
    engine::check_outputs_apart(&outputs, &inputs.iter().map(PathBuf::as_path).collect::<Vec<_>>())?;
    let occluder = skip.occluder(&setup.views()?, setup.width, setup.height)?;
    let options = RenderOptions {
        shader: input.shader,
        scene_file: input.scene,
        flag_sets: args.scene.setup()?.sets,
        setup,
        lowering: args.lowering.options(),
        bake_scene: args.bake_scene,
        overrides: args.overrides.clone(),
        occluder,
        sky_resolution: skip.sky_resolution,
        upsample: skip.upsample,
        trace_nonfinite: args.trace_nonfinite,
    };
    let bar = Bar::new();
    let rendered = engine::render::render(&options, &bar)?;
    drop(bar);
    let (convert, gpu, total) = (rendered.convert_time, rendered.gpu_time, rendered.total_time);
    errln!("convert {convert:.2?}, GPU {gpu:.2?}, total {total:.2?}");
    write_outputs(&rendered.image, &args.out, args.png.as_ref())?;
    if let (Some(trace), Some(png)) = (&rendered.trace, &trace_png) {
        out!("{}", trace.text);
        if !trace.overlay.is_empty() {
            skyrun::write_overlay_png(png, &rendered.image, &trace.overlay).map_err(Error::environment)?;
            outln!("wrote {}", png.display());
        }
    }
    Ok(())
}

/// Checks, before any work, that the image and the PNG preview can be written where asked: a
/// known extension, an existing directory, not a directory or a special file.
pub fn check_outputs(out: &Path, png: Option<&PathBuf>) -> Result<(), Error> {
    engine::check_image_output(out)?;
    if let Some(png) = png
        && engine::check_image_output(png)? != engine::ImageFormat::Png
    {
        return Err(Error::input(format!("--png {}: the preview is a `.png`", png.display())));
    }
    Ok(())
}

/// Writes the image and, when asked, the PNG preview; says what it wrote.
pub fn write_outputs(image: &skyrun::Image, out: &Path, png: Option<&PathBuf>) -> Result<(), Error> {
    outln!("{}", engine::write_image(image, out)?);
    if let Some(png) = png {
        outln!("{}", engine::write_image(image, png)?);
    }
    Ok(())
}

/// `OUT.nonfinite.png` for `-o OUT.exr` (the extension replaced).
pub fn nonfinite_png_path(out: &Path) -> PathBuf {
    let stem = out.file_stem().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    out.with_file_name(format!("{stem}.nonfinite.png"))
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
    /// The image to write, its format from the extension (`.exr` linear f32, `.png` preview), as
    /// `render -o`. Its directory must exist.
    #[arg(short = 'o', long = "out", value_name = "OUT.exr|OUT.png")]
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
    super::exit(reference(args))
}

fn reference(args: &ReferenceArgs) -> Result<(), Error> {
    if !args.scene.texture.is_empty() {
        return Err(Error::input("--texture: the reference is the Freeman sky, which has no sampler uniforms"));
    }
    let setup = args.scene.setup()?;
    let (views, width, height) = (setup.views()?, setup.width, setup.height);
    let mut params = skyref::FreemanParams::default();
    engine::set_freeman(&mut params, &setup.sets).map_err(Error::input)?;
    check_outputs(&args.out, args.png.as_ref())?;
    let scene = setup.scene;
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
    errln!("skyref {:?}: {:.2?}", args.precision, started.elapsed());
    let image = skyrun::Image::side_by_side(rendered, width, height).map_err(Error::input)?;
    write_outputs(&image, &args.out, args.png.as_ref())
}
