//! One render of a sky shader on the GPU, as `gdsky render` does it: the shader loaded (and
//! specialised) once, its textures and tables bound, every view of the setup drawn with what the
//! sky may skip, and optionally the NaN/Inf trace of the same scene.

use super::{Error, Progress, Setup, Sky};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// What [`render`] draws.
#[derive(Debug, Default)]
pub struct RenderOptions {
    /// The shader (`None`: the bundled Freeman sky).
    pub shader: Option<PathBuf>,
    /// The scene file (or Godot material) the shader came from: its uniforms, textures and
    /// overrides.
    pub scene_file: Option<crate::scene::SceneFile>,
    /// The scene, projection, size, values and textures.
    pub setup: Setup,
    /// How the shader is lowered (Godot's debanding, its SKY_COORDS).
    pub lowering: gdsky_naga::LowerOptions,
    /// Bake every uniform the scene file fixes (and every set value) into the shader as
    /// constants; with no scene file, every uniform at its default.
    pub bake_scene: bool,
    /// Uniform values given as flags (baked on purpose under `bake_scene`).
    pub flag_sets: Vec<(String, String)>,
    /// Scalar uniforms emitted as pipeline-overridable constants (with the scene file's).
    pub overrides: Vec<String>,
    /// Pixels hidden behind geometry (not shaded), at the image size.
    pub occluder: Option<skyrun::Occluder>,
    /// The resolution the sky is shaded at.
    pub sky_resolution: skycore::SkyResolution,
    /// How a reduced resolution is upsampled.
    pub upsample: skyrun::UpsampleFilter,
    /// Also render the instrumented module that records where each pixel's first NaN or Inf
    /// was made.
    pub trace_nonfinite: bool,
}

/// What [`render`] drew.
pub struct Rendered {
    /// The views side by side (one view, or the six cube faces as a 6N×N strip).
    pub image: skyrun::Image,
    /// From reading the shader to the module ready to compile (tables baked after).
    pub convert_time: Duration,
    /// The GPU's time: submit to idle, summed over the views.
    pub gpu_time: Duration,
    /// From the start to the image read back.
    pub total_time: Duration,
    /// The NaN/Inf trace, when asked for.
    pub trace: Option<Trace>,
}

/// Where the NaN and Inf of a render start.
pub struct Trace {
    /// The places (`file:line:col`, the expression, the pixel count), as the CLI prints them.
    pub text: String,
    /// Per pixel, the colour of the place its first non-finite value came from (`None`: none),
    /// to mark over the render; empty when nothing was non-finite.
    pub overlay: Vec<Option<[u8; 3]>>,
}

/// Renders `options.setup` (see the module documentation).
pub fn render(options: &RenderOptions, progress: &dyn Progress) -> Result<Rendered, Error> {
    let setup = &options.setup;
    let scene_file = options.scene_file.as_ref();
    let views = setup.views()?;
    let (width, height) = (setup.width, setup.height);
    let started = Instant::now();
    let names = super::override_names(scene_file, &options.overrides);
    super::check_override_conflicts(&names, scene_file, |n| {
        super::bake_reason(n, scene_file, &options.flag_sets, options.bake_scene)
    })?;
    let lowering = gdsky_naga::LowerOptions { overrides: names.clone(), ..options.lowering.clone() };
    let mut loaded = Sky::load_specialized(options.shader.as_deref(), scene_file, lowering, |shader| {
        if options.bake_scene {
            crate::scene::bake_values(shader, scene_file, &options.flag_sets)
        } else {
            Default::default()
        }
    })?;
    loaded.textures = super::load_textures(&setup.textures, scene_file, &loaded)?;
    if options.bake_scene {
        let mut baked: Vec<&String> = loaded.baked().keys().collect();
        baked.sort();
        let list = baked.iter().map(|n| n.as_str()).collect::<Vec<_>>().join(", ");
        progress.note(&format!("baked {} uniform(s): {list}", baked.len()));
    }
    let convert_time = started.elapsed();
    // After the conversion is timed: the table is the scene's input, not part of converting.
    if let Some(note) = loaded.bake_tables(&setup.sets).map_err(Error::input)? {
        progress.note(&note);
    }
    let material = loaded.material(&setup.sets).map_err(|e| Error::input(format!("--set: {e}")))?;
    let constants = loaded.constants(&setup.sets).map_err(Error::input)?;
    if !names.is_empty() {
        progress.note(&format!("overrides: {}", names.join(", ")));
    }
    let gpu = super::open_gpu(progress)?;
    let shader = loaded.compile(&gpu)?.with_constants(constants.clone());
    let builtins = setup.builtins();
    let skip = skyrun::RenderOptions {
        occluder: options.occluder.as_ref(),
        resolution: options.sky_resolution,
        filter: options.upsample,
    };
    let mut rendered = Vec::with_capacity(views.len());
    let mut gpu_time = Duration::ZERO;
    for &view in &views {
        let r = shader.render_with(&gpu, view, width, height, &builtins, &material, &skip).map_err(Error::input)?;
        gpu_time += r.gpu_wait;
        rendered.push(r.pixels);
    }
    let image = skyrun::Image::side_by_side(rendered, width, height).map_err(Error::input)?;
    let total_time = started.elapsed();
    let trace = match options.trace_nonfinite {
        true => Some(trace(&loaded, &gpu, constants, &views, setup, &builtins, &material)?),
        false => None,
    };
    Ok(Rendered { image, convert_time, gpu_time, total_time, trace })
}

/// Renders the instrumented module (see `gdsky_naga::trace`) with the render's scene and reads
/// each pixel's first site from the alpha channel.
fn trace(
    loaded: &Sky,
    gpu: &skyrun::Gpu,
    constants: Vec<(String, f64)>,
    views: &[skycore::Projection],
    setup: &Setup,
    builtins: &skyrun::SkyBuiltins,
    material: &[u8],
) -> Result<Trace, Error> {
    let traced = gdsky_naga::trace::instrument(&loaded.front, &loaded.lowered)
        .map_err(|diagnostics| Error::input(loaded.render(&diagnostics)))?;
    let wgsl = gdsky_naga::to_wgsl(&traced.lowered)
        .map_err(|e| Error::input(loaded.render(&[e.diagnostic(&loaded.front)])))?;
    let shader = loaded.compile_wgsl(gpu, &wgsl)?.with_constants(constants);
    // Every pixel shaded at full resolution, whatever the occluder and the sky resolution say:
    // an id cannot be upsampled, and a hidden pixel can still tell where a NaN comes from.
    let full = skyrun::RenderOptions::default();
    let mut images = Vec::with_capacity(views.len());
    for &view in views {
        let r = shader
            .render_with(gpu, view, setup.width, setup.height, builtins, material, &full)
            .map_err(Error::input)?;
        images.push(r.pixels);
    }
    let ids = skyrun::Image::side_by_side(images, setup.width, setup.height).map_err(Error::input)?;
    let report = gdsky_naga::trace::NonfiniteReport::new(&traced, &ids.pixels);
    let mut text = String::new();
    if report.unknown > 0 {
        // Only the instrumented module writes the alpha; anything else is a harness bug.
        text += &format!("warning: {} pixel(s) carry no site id (alpha neither 0 nor an id)\n", report.unknown);
    }
    text += &report.text();
    let overlay = match report.places.is_empty() {
        true => Vec::new(),
        false => ids
            .pixels
            .iter()
            .map(|p| {
                let colours = gdsky_naga::trace::PLACE_COLOURS;
                report.place_of(&traced, p[3]).map(|i| colours[i.min(colours.len() - 1)].1)
            })
            .collect(),
    };
    Ok(Trace { text, overlay })
}
