//! `gdsky stress [FILE] [--quick]`: numerical stability of a Freeman-compatible sky.
//!
//! Sweeps camera altitude, sun elevation, two views (a tall panorama, which covers every view
//! direction, and a 4°-high camera view of the horizon toward the sun's azimuth, which samples
//! the grazing rays densely) and each uniform at the ends of its `hint_range`, one at a time at
//! a few representative scenes. Each case is rendered three ways with the same sample counts:
//! FILE on the adapter in f32, the reference in f32 on the CPU, and the reference in f64 on the
//! CPU, the truth. GPU f32 against f64 is the shader's error; reference f32 against f64 is the
//! error of the reference's arithmetic in f32, so the two columns tell a conversion problem
//! (GPU ≠ reference f32) from an f32 problem (both far from f64).
//!
//! The reference is the Rust twin of FILE's algorithm (`--reference`, [`Reference`]): skyref's
//! line-for-line port of the original Freeman sky (`original`; for it and for shaders that keep
//! its quadrature, such as `freeman_stable`), or `skyref::fast` for `freeman_fast`, whose
//! quadratures differ (against the original's f64 its error would be the quadrature change, not
//! its precision). The default follows the file name: `fast` for a stem starting with
//! `freeman_fast`, else `original`.
//!
//! Writes `stress.md` (the report), `stress.csv` (every case), `grid.png` (the worst error per
//! altitude × sun elevation at default uniforms) and per-pixel heatmaps of the worst cases, and
//! prints a final machine-readable line:
//! `summary: nan_at_defaults=… inf_at_defaults=… horizon_worst=… horizon_p999=… …`.

mod cases;
mod report;

pub use cases::{
    ALTITUDES, Case, HORIZON, HORIZON_FOV, QUICK_ALTITUDES, QUICK_SUN_ELEVATIONS, SUN_ELEVATIONS, View, altitude_text,
    cases, hint_ranges,
};

use super::any;
use super::stats::{self, ErrorStats};
use crate::engine::{self, BUNDLED_NAME, Error, Progress, Sky, TRANSMITTANCE_TABLE};
use report::{
    Context, Summary, any_csv, any_report, any_table, badness, csv_text, ill_fraction, is_horizon, mode,
    nonfinite_section, plot_grid, report_markdown, traced_pixels,
};
use skycore::{Projection, Scene};
use skyref::FreemanParams;
use skyrun::{Image, SkyBuiltins};
use std::path::{Path, PathBuf};

/// Per-pixel heatmaps written for the worst cases at default uniforms.
const HEATMAPS: usize = 4;

/// What [`stress`] tests: the CLI's `gdsky stress` flags as values.
#[derive(Debug, Default)]
pub struct StressOptions {
    /// The shader (`None`: the bundled Freeman sky).
    pub shader: Option<PathBuf>,
    /// The scene file (or Godot material) it came from: its uniforms are the base of every case.
    pub scene_file: Option<crate::scene::SceneFile>,
    /// A small sweep for CI.
    pub quick: bool,
    /// Folder for stress.md, stress.csv, grid.png and the heatmaps (created if missing).
    pub out_dir: PathBuf,
    /// The CPU reference of a Freeman-compatible shader ([`Reference::for_file`] when `None`).
    pub reference: Option<Reference>,
    /// Textures for a shader that is not Freeman-compatible, `NAME=PATH`.
    pub textures: Vec<String>,
}

/// What [`stress`] found.
#[derive(Clone, Debug)]
pub struct StressReport {
    /// The report the CLI prints.
    pub text: String,
    /// `stress.md`.
    pub markdown: PathBuf,
    /// `stress.csv`.
    pub csv: PathBuf,
    /// Channels of the shader's own render that are NaN, and that are infinite, in the cases at
    /// its default uniforms (a quick run of the CLI fails on any).
    pub nonfinite_at_defaults: (usize, usize),
    /// The cases measured (their labels), in the report's order.
    pub cases: Vec<String>,
}

/// A family of CPU references: skyref's Rust twin of a shader's algorithm, in f32 and f64.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reference {
    /// skyref::f32 / skyref::f64: the original Freeman sky line for line (also the reference of
    /// shaders that keep its quadrature, such as freeman_stable).
    Original,
    /// skyref::fast::f32 / skyref::fast::f64: shaders/freeman_fast.gdshader's quadratures.
    Fast,
    /// skyref::fast's `render_lut`: shaders/freeman_lut.gdshader, with the transmittance table
    /// baked per case from the case's own uniforms and bound to the shader too.
    Lut,
}

/// What a [`Reference`] is: its name in the report and its renderers.
pub(super) struct Family {
    /// How the report names it (`skyref f32`, `skyref::fast f32` …, without the precision).
    pub(super) label: &'static str,
    /// What its f32 arithmetic is, for the report's column titles.
    pub(super) arithmetic: &'static str,
    pub(super) render32: fn(&FreemanParams, &Scene, Projection, u32, u32) -> Vec<[f32; 4]>,
    pub(super) render64: fn(&FreemanParams, &Scene, Projection, u32, u32) -> Vec<[f64; 4]>,
    /// Whether the shader reads a transmittance table baked from each case's uniforms.
    pub(super) table: bool,
}

/// The table freeman_lut reads for `params` (skyref::lut, default size).
fn table_for(params: &FreemanParams) -> skyref::lut::TransmittanceTable {
    let (w, h) = skyref::lut::DEFAULT_SIZE;
    skyref::lut::bake(params, w, h)
}

fn lut32(params: &FreemanParams, scene: &Scene, view: Projection, w: u32, h: u32) -> Vec<[f32; 4]> {
    skyref::fast::f32::render_lut(params, &table_for(params), scene, view, w, h)
}

fn lut64(params: &FreemanParams, scene: &Scene, view: Projection, w: u32, h: u32) -> Vec<[f64; 4]> {
    skyref::fast::f64::render_lut(params, &table_for(params), scene, view, w, h)
}

impl Reference {
    /// The family's name and renderers: one arm per family, so a new family is one arm here
    /// (and a variant above).
    fn family(self) -> Family {
        match self {
            Reference::Original => Family {
                label: "skyref",
                arithmetic: "the original Freeman arithmetic",
                render32: skyref::f32::render,
                render64: skyref::f64::render,
                table: false,
            },
            Reference::Fast => Family {
                label: "skyref::fast",
                arithmetic: "freeman_fast's arithmetic",
                render32: skyref::fast::f32::render,
                render64: skyref::fast::f64::render,
                table: false,
            },
            Reference::Lut => Family {
                label: "skyref::fast (lut)",
                arithmetic: "freeman_lut's arithmetic, with the case's own table",
                render32: lut32,
                render64: lut64,
                table: true,
            },
        }
    }

    /// The default for a shader file: the family whose shader's stem FILE's starts with
    /// (`freeman_fast…` → fast, `freeman_lut…` → lut), else the original.
    pub fn for_file(file: Option<&Path>) -> Reference {
        let stem = file.and_then(Path::file_stem).and_then(|s| s.to_str()).unwrap_or_default();
        if stem.starts_with("freeman_fast") {
            Reference::Fast
        } else if stem.starts_with("freeman_lut") {
            Reference::Lut
        } else {
            Reference::Original
        }
    }

    /// The names `--reference` takes.
    pub const NAMES: [&'static str; 3] = ["original", "fast", "lut"];

    /// Its `--reference` value.
    pub fn name(self) -> &'static str {
        match self {
            Reference::Original => "original",
            Reference::Fast => "fast",
            Reference::Lut => "lut",
        }
    }
}

impl std::str::FromStr for Reference {
    type Err = String;

    /// `original`, `fast` or `lut`.
    fn from_str(name: &str) -> Result<Self, String> {
        [Reference::Original, Reference::Fast, Reference::Lut]
            .into_iter()
            .find(|r| r.name() == name)
            .ok_or_else(|| format!("`{name}` is no reference; expected one of: {}", Reference::NAMES.join(", ")))
    }
}

/// A case's measurements.
pub(super) struct Outcome {
    pub(super) case: Case,
    pub(super) gpu: ErrorStats,
    pub(super) cpu: ErrorStats,
    /// Where the GPU's worst channel is: (x, y, channel, EYEDIR elevation in degrees).
    pub(super) gpu_where: Option<(u32, u32, usize, f64)>,
    pub(super) cpu_where: Option<(u32, u32, usize, f64)>,
}

/// The images of one case.
struct Rendered {
    gpu: Vec<[f32; 4]>,
    cpu32: Vec<[f32; 4]>,
    cpu64: Vec<[f64; 4]>,
}

/// Tests numerical stability (see the module documentation): writes the report, the CSV and
/// the plots into `options.out_dir` and returns what it found.
pub fn stress(options: &StressOptions, progress: &dyn Progress) -> Result<StressReport, Error> {
    let args = options;
    let scene_file = options.scene_file.as_ref();
    let mut out = String::new();
    // A shader skyref does not model is measured against its own f64 evaluation.
    if let Some(file) = options.shader.as_deref()
        && let Ok(front) = gdresource::check_file(file)
        && front.shader.as_ref().is_some_and(|s| !crate::measure::freeman::compatible(s))
    {
        if args.reference.is_some() {
            return Err(Error::input(format!(
                "{}: --reference picks skyref's twin of a Freeman-compatible shader; this one is measured against \
                 its own f64 evaluation",
                file.display()
            )));
        }
        let sets = scene_file.map(|f| f.uniform_pairs()).unwrap_or_default();
        let loaded = Sky::load(Some(file), &any::measuring_options())?;
        let textures = engine::load_textures(&args.textures, scene_file, &loaded)?;
        return stress_any(options, file, front, sets, textures, progress);
    }
    if !args.textures.is_empty() {
        return Err(Error::input(
            "--texture applies to shaders that are not Freeman-compatible; a Freeman-compatible shader's tables \
             (freeman_lut's transmittance_table) are baked per case automatically",
        ));
    }
    let loaded = Sky::load_freeman(options.shader.as_deref(), progress)?;
    loaded.check_scene(scene_file)?;
    let mut base = FreemanParams::default();
    if let Some(file) = scene_file {
        engine::set_freeman(&mut base, &file.uniform_pairs()).map_err(Error::input)?;
        note!(
            progress,
            "note: {}: stress uses the scene's shader and uniforms; its own sweep sets the sun, altitude, views \
             and sizes",
            file.path.display()
        );
    }
    let shader_info = loaded.front.shader.as_ref().ok_or_else(|| Error::input("the shader has errors"))?;
    let name = options.shader.as_ref().map(|f| f.display().to_string()).unwrap_or(BUNDLED_NAME.into());
    let ranges = hint_ranges(shader_info);
    let reference = args.reference.unwrap_or_else(|| Reference::for_file(options.shader.as_deref()));
    let family = reference.family();
    let chosen = if args.reference.is_some() { "--reference" } else { "the default for this file name" };
    note!(progress, "reference: {} ({}, {chosen})", reference.name(), family.label);
    let cases = cases(args.quick, &ranges);
    for case in &cases {
        case.params(&base).map_err(|e| Error::input(format!("{name}: hint_range end not usable: {e}")))?;
    }
    engine::check_output_dir(&args.out_dir, true, &["stress.md", "stress.csv", "grid.png"])?;
    let gpu = engine::open_gpu(progress)?;
    let adapter = gpu.adapter_info();
    let mut shader = loaded.compile(&gpu)?;
    // The NaN/Inf trace, rendered for the cases whose GPU render has any.
    let traced = gdsky_naga::trace::instrument(&loaded.front, &loaded.lowered)
        .map_err(|diagnostics| Error::input(loaded.render(&diagnostics)))?;
    let traced_wgsl =
        gdsky_naga::to_wgsl(&traced.lowered).map_err(|e| Error::input(e.diagnostic(&loaded.front).message))?;
    let mut traced_shader = loaded.compile_wgsl(&gpu, &traced_wgsl)?;
    let mut nonfinite: Vec<(String, gdsky_naga::trace::NonfiniteReport)> = Vec::new();
    let (pano, horizon) = if args.quick { ((32, 64), (64, 16)) } else { ((128, 256), (256, 64)) };
    let size = |view: View| if view == View::Panorama { pano } else { horizon };

    // One case on the GPU with `shader` (the shader's module or its NaN/Inf trace).
    let shade = |shader: &mut skyrun::SkyShader, case: &Case| -> Result<Vec<[f32; 4]>, Error> {
        let params = case.params(&base).map_err(Error::input)?;
        let material = loaded.freeman_material(&params).map_err(Error::input)?;
        if family.table {
            // The case's own table on the GPU too: a hint-range corner of a scale height changes
            // it, and a stale table would be counted as the shader's error.
            let table = table_for(&params);
            let image = skyrun::Image { width: table.width, height: table.height, pixels: table.texels };
            let data = skyrun::texture_from_image(&image).map_err(Error::input)?;
            shader.set_texture(&gpu, TRANSMITTANCE_TABLE, &data).map_err(Error::input)?;
        }
        let (w, h) = size(case.view);
        let builtins = SkyBuiltins::from_scene(&case.scene(), w, h);
        Ok(shader.render(&gpu, case.projection(), w, h, &builtins, &material).map_err(Error::input)?.pixels)
    };
    let mut render = |case: &Case| -> Result<Rendered, Error> {
        let params = case.params(&base).map_err(Error::input)?;
        let (w, h) = size(case.view);
        let scene = case.scene();
        Ok(Rendered {
            gpu: shade(&mut shader, case)?,
            cpu32: (family.render32)(&params, &scene, case.projection(), w, h),
            cpu64: (family.render64)(&params, &scene, case.projection(), w, h),
        })
    };
    let locate = |case: &Case, worst: Option<(usize, usize)>| {
        worst.map(|(i, channel)| {
            let (w, h) = size(case.view);
            let (x, y) = ((i % w as usize) as u32, (i / w as usize) as u32);
            let d = skyref::f64::eyedir(&case.scene(), case.projection(), x, y, w, h);
            (x, y, channel, d.y.clamp(-1.0, 1.0).asin().to_degrees())
        })
    };

    progress.start(cases.len() as u64);
    let started = std::time::Instant::now();
    let mut outcomes = Vec::with_capacity(cases.len());
    for case in &cases {
        progress.message(&case.label());
        let images = render(case)?;
        if images.gpu.iter().any(|p| p[..3].iter().any(|c| !c.is_finite())) {
            let ids = shade(&mut traced_shader, case)?;
            nonfinite.push((case.label(), gdsky_naga::trace::NonfiniteReport::new(&traced, &ids)));
        }
        let gpu_stats = stats::error_stats(&images.gpu, &images.cpu64);
        let cpu_stats = stats::error_stats(&images.cpu32, &images.cpu64);
        outcomes.push(Outcome {
            case: case.clone(),
            gpu_where: locate(case, gpu_stats.worst),
            cpu_where: locate(case, cpu_stats.worst),
            gpu: gpu_stats,
            cpu: cpu_stats,
        });
        progress.step();
    }
    progress.finish();
    let elapsed = started.elapsed();

    let summary = Summary::of(&outcomes);
    engine::create_output_dir(&args.out_dir)?;
    // Heatmaps: the horizon case's views (GPU and CPU), then the worst cases at defaults.
    let mut heatmaps = Vec::new();
    let mut worst_defaults: Vec<&Outcome> = outcomes.iter().filter(|o| o.case.uniform.is_none()).collect();
    worst_defaults.sort_by(|a, b| badness(&b.gpu).total_cmp(&badness(&a.gpu)));
    let horizon_cases: Vec<&Outcome> = outcomes.iter().filter(|o| is_horizon(&o.case)).collect();
    for (i, o) in horizon_cases.iter().chain(worst_defaults.iter().take(HEATMAPS)).enumerate() {
        let images = render(&o.case)?;
        let (w, h) = size(o.case.view);
        let image = |pixels: Vec<[f32; 4]>| Image::new(w, h, pixels).map_err(Error::environment);
        let truth = image(stats::narrow(&images.cpu64))?;
        let mut targets = vec![("gpu", images.gpu)];
        if i < horizon_cases.len() {
            targets.push(("cpu", images.cpu32));
        }
        for (what, pixels) in targets {
            let file = format!("heatmap-{what}-{}.png", o.case.slug());
            let path = args.out_dir.join(&file);
            skyrun::write_heatmap_png(&path, &image(pixels)?, &truth, stats::FLOOR as f32)
                .map_err(Error::environment)?;
            if !heatmaps.iter().any(|(f, _)| f == &file) {
                heatmaps.push((file, format!("{} — {}", what.to_uppercase(), o.case.label())));
            }
        }
    }
    let grid_path = args.out_dir.join("grid.png");
    let (altitudes, suns): (&[f64], &[f64]) =
        if args.quick { (&QUICK_ALTITUDES, &QUICK_SUN_ELEVATIONS) } else { (&ALTITUDES, &SUN_ELEVATIONS) };
    plot_grid(&grid_path, &name, &family, &outcomes, altitudes, suns)?;

    let context = Context {
        name: &name,
        adapter: adapter.to_string(),
        quick: args.quick,
        pano,
        horizon,
        elapsed,
        altitudes,
        suns,
        heatmaps: &heatmaps,
        family: &family,
    };
    let mut report = report_markdown(&context, &outcomes, &summary);
    let placed: Vec<(String, &gdsky_naga::trace::NonfiniteReport)> =
        nonfinite.iter().map(|(label, r)| (label.clone(), r)).collect();
    report.push_str(&nonfinite_section(&placed));
    let md_path = args.out_dir.join("stress.md");
    engine::write_file(&md_path, report.as_bytes())?;
    let csv_path = args.out_dir.join("stress.csv");
    engine::write_file(&csv_path, csv_text(&outcomes).as_bytes())?;

    say!(out, "gdsky stress: {name}, {} cases ({}), {:.1?}", outcomes.len(), mode(args.quick), elapsed);
    say!(out, "adapter  {adapter}");
    say!(out, "reference {} f32 and f64, {} (--reference {})", family.label, family.arithmetic, reference.name());
    out.push_str(&summary.table(&family));
    say!(
        out,
        "wrote    {}, {}, {} and {} heatmaps",
        md_path.display(),
        csv_path.display(),
        grid_path.display(),
        heatmaps.len()
    );
    say!(out, "{}", summary.line(outcomes.len()));
    Ok(StressReport {
        text: out,
        markdown: md_path,
        csv: csv_path,
        nonfinite_at_defaults: (summary.gpu_nan, summary.gpu_inf),
        cases: outcomes.iter().map(|o| o.case.label()).collect(),
    })
}

/// Ill-conditioning nudge: each input moves by this many ulps.
pub(super) const NUDGE_ULPS: u32 = 4;
/// Heatmaps of the worst cases written by the generic stress (error and sensitivity each).
const ANY_HEATMAPS: usize = 3;

/// One generic case's measurements.
pub(super) struct AnyOutcome {
    pub(super) case: any::Case,
    /// GPU f32 against the same shader in f64.
    pub(super) error: ErrorStats,
    /// Where the worst channel is: (x, y, channel).
    pub(super) worst: Option<(u32, u32, usize)>,
    pub(super) sens: any::Sensitivity,
    /// Where the case's NaN and Inf start (the traced module's report), for a case whose f32
    /// render has any.
    pub(super) nonfinite: Option<gdsky_naga::trace::NonfiniteReport>,
}

/// The images of a generic case: f32 and f64, base and nudged.
struct AnyImages {
    f32: Vec<[f32; 4]>,
    f64: Vec<[f64; 4]>,
    f32_nudged: Vec<[f32; 4]>,
    f64_nudged: Vec<[f64; 4]>,
}

/// `stress` for a shader that is not Freeman-compatible: each case rendered in f32 on the GPU
/// and in f64 (the same shader widened, `skyrun::F64Sky`), base and with the built-ins nudged by
/// a few ulps ([`any::nudged`]); the report ranks the cases by NaN/Inf, error and
/// ill-conditioning.
fn stress_any(
    options: &StressOptions,
    file: &Path,
    front: crate::FrontendOutput,
    sets: Vec<(String, String)>,
    textures: Vec<(String, skyrun::TextureData)>,
    progress: &dyn Progress,
) -> Result<StressReport, Error> {
    let args = options;
    let mut out = String::new();
    let name = file.display().to_string();
    let sky = any::Sky::new(front, sets).map_err(Error::input)?.with_textures(textures);
    let shader_info = sky.front.shader.as_ref().ok_or_else(|| Error::input("the shader has errors"))?;
    let (pano, cam) = if args.quick { ((64, 32), (32, 32)) } else { ((256, 128), (128, 128)) };
    let cases = any::stress_cases(shader_info, args.quick, pano, cam);
    engine::check_output_dir(&args.out_dir, true, &["stress.md", "stress.csv"])?;
    let gpu = engine::open_gpu(progress)?;
    let adapter = gpu.adapter_info();
    let variant = sky.variant(&[]).map_err(Error::input)?;
    let c32 = variant.compile(&gpu).map_err(Error::input)?;
    let c64 = variant.compile_f64(&gpu).map_err(|e| Error::environment(format!("{name}: no f64 evaluation: {e}")))?;
    // The NaN/Inf trace, rendered for the cases whose f32 render has any (issue #13: NaN and
    // Inf traced to their source line automatically in stress).
    let (traced_shader, traced) = variant.compile_traced(&gpu).map_err(Error::input)?;
    let trace = |case: &any::Case| -> Result<(gdsky_naga::trace::NonfiniteReport, Vec<[f32; 4]>), Error> {
        let extra: Vec<(String, String)> = case.uniform.iter().cloned().collect();
        let material = variant.material_with(&traced_shader.lowered, &extra).map_err(Error::input)?;
        let ids =
            traced_shader.render_material(&gpu, &case.shot, &case.shot.builtins(), &material).map_err(Error::input)?;
        Ok((gdsky_naga::trace::NonfiniteReport::new(&traced, &ids), ids))
    };
    let render = |case: &any::Case| -> Result<AnyImages, Error> {
        let extra: Vec<(String, String)> = case.uniform.iter().cloned().collect();
        let m32 = variant.material_with(&c32.lowered, &extra).map_err(Error::input)?;
        let m64 = variant.material_with(&c64.sky.lowered, &extra).map_err(Error::input)?;
        let b = case.shot.builtins();
        let n = any::nudged(&b, NUDGE_ULPS);
        Ok(AnyImages {
            f32: c32.render_material(&gpu, &case.shot, &b, &m32).map_err(Error::input)?,
            f64: c64.render_material(&gpu, &case.shot, &b, &m64).map_err(Error::input)?,
            f32_nudged: c32.render_material(&gpu, &case.shot, &n, &m32).map_err(Error::input)?,
            f64_nudged: c64.render_material(&gpu, &case.shot, &n, &m64).map_err(Error::input)?,
        })
    };
    progress.start(cases.len() as u64);
    let started = std::time::Instant::now();
    let mut outcomes = Vec::with_capacity(cases.len());
    for case in &cases {
        progress.message(&case.label.clone());
        let images = render(case)?;
        let error = stats::error_stats(&images.f32, &images.f64);
        let w = case.shot.width as usize;
        let worst = error.worst.map(|(i, c)| ((i % w) as u32, (i / w) as u32, c));
        let sens = any::sensitivity(&images.f32, &images.f32_nudged, &images.f64, &images.f64_nudged);
        let f32_nonfinite = images.f32.iter().any(|p| p[..3].iter().any(|c| !c.is_finite()));
        let nonfinite = if f32_nonfinite { Some(trace(case)?.0) } else { None };
        outcomes.push(AnyOutcome { case: case.clone(), error, worst, sens, nonfinite });
        progress.step();
    }
    progress.finish();
    let elapsed = started.elapsed();
    engine::create_output_dir(&args.out_dir)?;

    // Heatmaps: the worst cases by error (NaN/Inf first) and by ill-conditioning.
    let mut by_error: Vec<&AnyOutcome> = outcomes.iter().collect();
    by_error.sort_by(|a, b| badness(&b.error).total_cmp(&badness(&a.error)));
    let mut by_sens: Vec<&AnyOutcome> = outcomes.iter().filter(|o| o.sens.ill_conditioned > 0).collect();
    by_sens.sort_by(|a, b| ill_fraction(&b.sens).total_cmp(&ill_fraction(&a.sens)));
    let mut heatmaps: Vec<(String, String)> = Vec::new();
    for (kind, list) in [("error", &by_error), ("sensitivity", &by_sens)] {
        for o in list.iter().take(ANY_HEATMAPS) {
            let images = render(&o.case)?;
            let (w, h) = (o.case.shot.width, o.case.shot.height);
            let image = |pixels: Vec<[f32; 4]>| Image::new(w, h, pixels).map_err(Error::environment);
            let file = format!("heatmap-{kind}-{}.png", o.case.slug.replace(['/', ' '], "_"));
            let (a, b, what) = if kind == "error" {
                (image(images.f32)?, image(stats::narrow(&images.f64))?, "f32 against f64")
            } else {
                (image(images.f32_nudged)?, image(images.f32)?, "f32 nudged by 4 ulps against f32")
            };
            skyrun::write_heatmap_png(&args.out_dir.join(&file), &a, &b, stats::FLOOR as f32)
                .map_err(Error::environment)?;
            heatmaps.push((file, format!("{} — {what}", o.case.label)));
        }
    }
    // Where NaN and Inf start: the traced pixels over the f32 render, for the cases with the
    // most non-finite pixels.
    let mut traced_cases: Vec<&AnyOutcome> =
        outcomes.iter().filter(|o| o.nonfinite.as_ref().is_some_and(|r| !r.places.is_empty())).collect();
    traced_cases.sort_by_key(|o| std::cmp::Reverse(o.nonfinite.as_ref().map_or(0, traced_pixels)));
    for o in traced_cases.iter().take(ANY_HEATMAPS) {
        let (report, ids) = trace(&o.case)?;
        let (w, h) = (o.case.shot.width, o.case.shot.height);
        let base = Image::new(w, h, render(&o.case)?.f32).map_err(Error::environment)?;
        let colours = gdsky_naga::trace::PLACE_COLOURS;
        let overlay: Vec<Option<[u8; 3]>> =
            ids.iter().map(|p| report.place_of(&traced, p[3]).map(|i| colours[i.min(colours.len() - 1)].1)).collect();
        let file = format!("nonfinite-{}.png", o.case.slug.replace(['/', ' '], "_"));
        skyrun::write_overlay_png(&args.out_dir.join(&file), &base, &overlay).map_err(Error::environment)?;
        heatmaps.push((file, format!("{} — where NaN/Inf start (colours as listed)", o.case.label)));
    }
    let md = any_report(&name, &adapter.to_string(), args.quick, elapsed, &outcomes, &heatmaps);
    let md_path = args.out_dir.join("stress.md");
    engine::write_file(&md_path, md.as_bytes())?;
    let csv_path = args.out_dir.join("stress.csv");
    engine::write_file(&csv_path, any_csv(&outcomes).as_bytes())?;

    let at_defaults = || outcomes.iter().filter(|o| o.case.uniform.is_none());
    let nan: usize = at_defaults().map(|o| o.error.nan).sum();
    let inf: usize = at_defaults().map(|o| o.error.inf).sum();
    let worst = by_error.first().map(|o| (o.error.max, o.case.label.clone()));
    let ill_cases = outcomes.iter().filter(|o| o.sens.ill_conditioned > 0).count();
    say!(out, "gdsky stress: {name}, {} cases ({}), {:.1?}", outcomes.len(), mode(args.quick), elapsed);
    say!(out, "adapter  {adapter}");
    say!(out, "truth    the same shader evaluated in f64 on the device (skyrun::F64Sky), same scene and uniforms");
    out.push_str(&any_table(&outcomes));
    say!(out, "wrote    {}, {} and {} heatmaps", md_path.display(), csv_path.display(), heatmaps.len());
    say!(
        out,
        "summary: nan_at_defaults={nan} inf_at_defaults={inf} worst_max={:.6e} worst_case=\"{}\" \
         ill_conditioned_cases={ill_cases} cases={}",
        worst.as_ref().map_or(0.0, |w| w.0),
        worst.as_ref().map_or(String::new(), |w| w.1.clone()),
        outcomes.len()
    );
    Ok(StressReport {
        text: out,
        markdown: md_path,
        csv: csv_path,
        nonfinite_at_defaults: (nan, inf),
        cases: outcomes.iter().map(|o| o.case.label.clone()).collect(),
    })
}
