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

use super::scene::{BUNDLED_NAME, open_gpu};
use super::sweep::{self, ErrorStats, sci};
use super::{environment, usage};
use clap::{Args, ValueEnum};
use gdsky::measure::any;
use gdsky::measure::stress::{
    ALTITUDES, Case, HORIZON, HORIZON_FOV, QUICK_ALTITUDES, QUICK_SUN_ELEVATIONS, SUN_ELEVATIONS, View, altitude_text,
    cases, hint_ranges,
};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use skyref::{FreemanParams, Projection, Scene};
use skyrun::{Image, SkyBuiltins};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Per-pixel heatmaps written for the worst cases at default uniforms.
const HEATMAPS: usize = 4;

#[derive(Args)]
pub struct StressArgs {
    /// The sky shader to test (Freeman-compatible: the Freeman sky's uniforms, e.g.
    /// shaders/freeman_stable.gdshader), or a scene file (`SCENE.toml`: its shader, and its
    /// uniforms as the base of every case; the sweep sets its own sun, altitude, views and sizes),
    /// or a Godot material or scene (`MATERIAL.tres`, `SCENE.tscn`: its shader and values);
    /// without one, the bundled Freeman sky.
    #[arg(value_name = "FILE|SCENE.toml|MATERIAL.tres|SCENE.tscn")]
    file: Option<PathBuf>,
    /// A small sweep for CI: 3 altitudes × 5 sun elevations (with the horizon case), the
    /// scale heights at 0, small images.
    #[arg(long)]
    quick: bool,
    /// Folder for stress.md, stress.csv, grid.png and the heatmaps (created if missing; checked
    /// before any work).
    #[arg(short = 'o', long = "out-dir", value_name = "DIR", default_value = "out/stress")]
    out_dir: PathBuf,
    /// The CPU reference (f32 and f64) FILE is measured against: the Rust twin of its
    /// algorithm [default: `fast` when FILE's stem starts with `freeman_fast`, else `original`].
    #[arg(long, value_enum)]
    reference: Option<Reference>,
    /// For a shader that is not Freeman-compatible: a texture for a sampler uniform, as on
    /// `render` (`NAME=PATH`: EXR or PNG; six faces or a cross for a samplerCube, slices for a
    /// sampler3D), bound in every case, f32 and f64; over a scene file's `[textures]` and a Godot
    /// material's. Repeatable.
    #[arg(long = "texture", value_name = "NAME=PATH")]
    textures: Vec<String>,
}

/// A family of CPU references: skyref's Rust twin of a shader's algorithm, in f32 and f64.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
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
struct Family {
    /// How the report names it (`skyref f32`, `skyref::fast f32` …, without the precision).
    label: &'static str,
    /// What its f32 arithmetic is, for the report's column titles.
    arithmetic: &'static str,
    render32: fn(&FreemanParams, &Scene, Projection, u32, u32) -> Vec<[f32; 4]>,
    render64: fn(&FreemanParams, &Scene, Projection, u32, u32) -> Vec<[f64; 4]>,
    /// Whether the shader reads a transmittance table baked from each case's uniforms.
    table: bool,
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
    fn for_file(file: Option<&Path>) -> Reference {
        let stem = file.and_then(Path::file_stem).and_then(|s| s.to_str()).unwrap_or_default();
        if stem.starts_with("freeman_fast") {
            Reference::Fast
        } else if stem.starts_with("freeman_lut") {
            Reference::Lut
        } else {
            Reference::Original
        }
    }

    /// Its `--reference` value.
    fn name(self) -> String {
        self.to_possible_value().map(|v| v.get_name().to_string()).unwrap_or_default()
    }
}

/// A case's measurements.
struct Outcome {
    case: Case,
    gpu: ErrorStats,
    cpu: ErrorStats,
    /// Where the GPU's worst channel is: (x, y, channel, EYEDIR elevation in degrees).
    gpu_where: Option<(u32, u32, usize, f64)>,
    cpu_where: Option<(u32, u32, usize, f64)>,
}

/// The images of one case.
struct Rendered {
    gpu: Vec<[f32; 4]>,
    cpu32: Vec<[f32; 4]>,
    cpu64: Vec<[f64; 4]>,
}

pub fn run(args: &StressArgs) -> ExitCode {
    match stress(args) {
        Ok(code) => code,
        Err(code) => code,
    }
}

fn stress(args: &StressArgs) -> Result<ExitCode, ExitCode> {
    let input = super::scene::open_input(args.file.as_deref())?;
    // A shader skyref does not model is measured against its own f64 evaluation.
    if let Some(file) = input.shader.as_deref()
        && let Ok(front) = gdresource::check_file(file)
        && front.shader.as_ref().is_some_and(|s| !gdsky::measure::freeman::compatible(s))
    {
        if args.reference.is_some() {
            return Err(usage(format!(
                "{}: --reference picks skyref's twin of a Freeman-compatible shader; this one is measured against \
                 its own f64 evaluation",
                file.display()
            )));
        }
        let sets = input.scene.as_ref().map(|f| f.uniform_pairs()).unwrap_or_default();
        let loaded = super::scene::load_shader(Some(file), &gdsky::measure::any::measuring_options())?;
        let textures = super::scene::load_textures(&args.textures, input.scene.as_ref(), &loaded)?;
        return stress_any(args, file, front, sets, textures);
    }
    if !args.textures.is_empty() {
        return Err(usage(
            "--texture applies to shaders that are not Freeman-compatible; a Freeman-compatible shader's tables \
             (freeman_lut's transmittance_table) are baked per case automatically",
        ));
    }
    let loaded = sweep::load_freeman(input.shader.as_deref())?;
    super::scene::check_scene_uniforms(input.scene.as_ref(), &loaded)?;
    let mut base = FreemanParams::default();
    if let Some(file) = &input.scene {
        super::scene::set_freeman(&mut base, &file.uniform_pairs()).map_err(usage)?;
        eprintln!(
            "note: {}: stress uses the scene's shader and uniforms; its own sweep sets the sun, altitude, views \
             and sizes",
            file.path.display()
        );
    }
    let shader_info = loaded.front.shader.as_ref().ok_or(ExitCode::from(1))?;
    let name = input.shader.as_ref().map(|f| f.display().to_string()).unwrap_or(BUNDLED_NAME.into());
    let ranges = hint_ranges(shader_info);
    let reference = args.reference.unwrap_or_else(|| Reference::for_file(input.shader.as_deref()));
    let family = reference.family();
    let chosen = if args.reference.is_some() { "--reference" } else { "the default for this file name" };
    eprintln!("reference: {} ({}, {chosen})", reference.name(), family.label);
    let cases = cases(args.quick, &ranges);
    for case in &cases {
        case.params(&base).map_err(|e| usage(format!("{name}: hint_range end not usable: {e}")))?;
    }
    super::check_output_dir(&args.out_dir, true, &["stress.md", "stress.csv", "grid.png"])?;
    let gpu = open_gpu()?;
    let adapter = gpu.adapter_info();
    let mut shader = loaded.compile(&gpu)?;
    // The NaN/Inf trace, rendered for the cases whose GPU render has any.
    let traced = gdsky_naga::trace::instrument(&loaded.front, &loaded.lowered).map_err(|diagnostics| {
        eprint!("{}", gdsky::frontend::diag::render_human(&loaded.front.db, &diagnostics, false));
        ExitCode::from(1)
    })?;
    let traced_wgsl = gdsky_naga::to_wgsl(&traced.lowered).map_err(|e| usage(e.diagnostic(&loaded.front).message))?;
    let mut traced_shader = loaded.compile_wgsl(&gpu, &traced_wgsl)?;
    let mut nonfinite: Vec<(String, gdsky_naga::trace::NonfiniteReport)> = Vec::new();
    let (pano, horizon) = if args.quick { ((32, 64), (64, 16)) } else { ((128, 256), (256, 64)) };
    let size = |view: View| if view == View::Panorama { pano } else { horizon };

    // One case on the GPU with `shader` (the shader's module or its NaN/Inf trace).
    let shade = |shader: &mut skyrun::SkyShader, case: &Case| -> Result<Vec<[f32; 4]>, ExitCode> {
        let params = case.params(&base).map_err(usage)?;
        let material = sweep::material(&loaded, &params).map_err(usage)?;
        if family.table {
            // The case's own table on the GPU too: a hint-range corner of a scale height changes
            // it, and a stale table would be counted as the shader's error.
            let table = table_for(&params);
            let image = skyrun::Image { width: table.width, height: table.height, pixels: table.texels };
            let data = skyrun::texture_from_image(&image).map_err(usage)?;
            shader.set_texture(&gpu, super::scene::TRANSMITTANCE_TABLE, &data).map_err(usage)?;
        }
        let (w, h) = size(case.view);
        let builtins = SkyBuiltins::from_scene(&case.scene(), w, h);
        Ok(shader.render(&gpu, case.projection(), w, h, &builtins, &material).map_err(usage)?.pixels)
    };
    let mut render = |case: &Case| -> Result<Rendered, ExitCode> {
        let params = case.params(&base).map_err(usage)?;
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

    let bar = sweep::progress_bar(cases.len() as u64);
    let started = std::time::Instant::now();
    let mut outcomes = Vec::with_capacity(cases.len());
    for case in &cases {
        bar.set_message(case.label());
        let images = bar.suspend(|| render(case))?;
        if images.gpu.iter().any(|p| p[..3].iter().any(|c| !c.is_finite())) {
            let ids = shade(&mut traced_shader, case)?;
            nonfinite.push((case.label(), gdsky_naga::trace::NonfiniteReport::new(&traced, &ids)));
        }
        let gpu_stats = sweep::error_stats(&images.gpu, &images.cpu64);
        let cpu_stats = sweep::error_stats(&images.cpu32, &images.cpu64);
        outcomes.push(Outcome {
            case: case.clone(),
            gpu_where: locate(case, gpu_stats.worst),
            cpu_where: locate(case, cpu_stats.worst),
            gpu: gpu_stats,
            cpu: cpu_stats,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    let elapsed = started.elapsed();

    let summary = Summary::of(&outcomes);
    super::create_output_dir(&args.out_dir)?;
    // Heatmaps: the horizon case's views (GPU and CPU), then the worst cases at defaults.
    let mut heatmaps = Vec::new();
    let mut worst_defaults: Vec<&Outcome> = outcomes.iter().filter(|o| o.case.uniform.is_none()).collect();
    worst_defaults.sort_by(|a, b| badness(&b.gpu).total_cmp(&badness(&a.gpu)));
    let horizon_cases: Vec<&Outcome> = outcomes.iter().filter(|o| is_horizon(&o.case)).collect();
    for (i, o) in horizon_cases.iter().chain(worst_defaults.iter().take(HEATMAPS)).enumerate() {
        let images = render(&o.case)?;
        let (w, h) = size(o.case.view);
        let image = |pixels: Vec<[f32; 4]>| Image::new(w, h, pixels).map_err(environment);
        let truth = image(sweep::narrow(&images.cpu64))?;
        let mut targets = vec![("gpu", images.gpu)];
        if i < horizon_cases.len() {
            targets.push(("cpu", images.cpu32));
        }
        for (what, pixels) in targets {
            let file = format!("heatmap-{what}-{}.png", o.case.slug());
            let path = args.out_dir.join(&file);
            skyrun::write_heatmap_png(&path, &image(pixels)?, &truth, sweep::FLOOR as f32).map_err(environment)?;
            if !heatmaps.iter().any(|(f, _)| f == &file) {
                heatmaps.push((file, format!("{} — {}", what.to_uppercase(), o.case.label())));
            }
        }
    }
    let grid_path = args.out_dir.join("grid.png");
    let (altitudes, suns): (&[f64], &[f64]) =
        if args.quick { (&QUICK_ALTITUDES, &QUICK_SUN_ELEVATIONS) } else { (&ALTITUDES, &SUN_ELEVATIONS) };
    plot_grid(&grid_path, &name, &family, &outcomes, altitudes, suns).map_err(environment)?;

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
    super::write_file(&md_path, report.as_bytes()).map_err(environment)?;
    let csv_path = args.out_dir.join("stress.csv");
    super::write_file(&csv_path, csv_text(&outcomes).as_bytes()).map_err(environment)?;

    println!("gdsky stress: {name}, {} cases ({}), {:.1?}", outcomes.len(), mode(args.quick), elapsed);
    println!("adapter  {adapter}");
    println!("reference {} f32 and f64, {} (--reference {})", family.label, family.arithmetic, reference.name());
    print!("{}", summary.table(&family));
    println!(
        "wrote    {}, {}, {} and {} heatmaps",
        md_path.display(),
        csv_path.display(),
        grid_path.display(),
        heatmaps.len()
    );
    println!("{}", summary.line(outcomes.len()));
    if args.quick && summary.gpu_nan + summary.gpu_inf > 0 {
        eprintln!("error: NaN/Inf at default uniforms ({} NaN, {} Inf channels)", summary.gpu_nan, summary.gpu_inf);
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}

/// Ill-conditioning nudge: each input moves by this many ulps.
const NUDGE_ULPS: u32 = 4;
/// Heatmaps of the worst cases written by the generic stress (error and sensitivity each).
const ANY_HEATMAPS: usize = 3;

/// One generic case's measurements.
struct AnyOutcome {
    case: any::Case,
    /// GPU f32 against the same shader in f64.
    error: ErrorStats,
    /// Where the worst channel is: (x, y, channel).
    worst: Option<(u32, u32, usize)>,
    sens: any::Sensitivity,
    /// Where the case's NaN and Inf start (the traced module's report), for a case whose f32
    /// render has any.
    nonfinite: Option<gdsky_naga::trace::NonfiniteReport>,
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
    args: &StressArgs,
    file: &Path,
    front: gdsky::FrontendOutput,
    sets: Vec<(String, String)>,
    textures: Vec<(String, skyrun::TextureData)>,
) -> Result<ExitCode, ExitCode> {
    let name = file.display().to_string();
    let sky = any::Sky::new(front, sets).map_err(usage)?.with_textures(textures);
    let shader_info = sky.front.shader.as_ref().ok_or(ExitCode::from(1))?;
    let (pano, cam) = if args.quick { ((64, 32), (32, 32)) } else { ((256, 128), (128, 128)) };
    let cases = any::stress_cases(shader_info, args.quick, pano, cam);
    super::check_output_dir(&args.out_dir, true, &["stress.md", "stress.csv"])?;
    let gpu = open_gpu()?;
    let adapter = gpu.adapter_info();
    let variant = sky.variant(&[]).map_err(usage)?;
    let c32 = variant.compile(&gpu).map_err(usage)?;
    let c64 = variant.compile_f64(&gpu).map_err(|e| environment(format!("{name}: no f64 evaluation: {e}")))?;
    // The NaN/Inf trace, rendered for the cases whose f32 render has any (issue #13: NaN and
    // Inf traced to their source line automatically in stress).
    let (traced_shader, traced) = variant.compile_traced(&gpu).map_err(usage)?;
    let trace = |case: &any::Case| -> Result<(gdsky_naga::trace::NonfiniteReport, Vec<[f32; 4]>), ExitCode> {
        let extra: Vec<(String, String)> = case.uniform.iter().cloned().collect();
        let material = variant.material_with(&traced_shader.lowered, &extra).map_err(usage)?;
        let ids = traced_shader.render_material(&gpu, &case.shot, &case.shot.builtins(), &material).map_err(usage)?;
        Ok((gdsky_naga::trace::NonfiniteReport::new(&traced, &ids), ids))
    };
    let render = |case: &any::Case| -> Result<AnyImages, ExitCode> {
        let extra: Vec<(String, String)> = case.uniform.iter().cloned().collect();
        let m32 = variant.material_with(&c32.lowered, &extra).map_err(usage)?;
        let m64 = variant.material_with(&c64.sky.lowered, &extra).map_err(usage)?;
        let b = case.shot.builtins();
        let n = any::nudged(&b, NUDGE_ULPS);
        Ok(AnyImages {
            f32: c32.render_material(&gpu, &case.shot, &b, &m32).map_err(usage)?,
            f64: c64.render_material(&gpu, &case.shot, &b, &m64).map_err(usage)?,
            f32_nudged: c32.render_material(&gpu, &case.shot, &n, &m32).map_err(usage)?,
            f64_nudged: c64.render_material(&gpu, &case.shot, &n, &m64).map_err(usage)?,
        })
    };
    let bar = sweep::progress_bar(cases.len() as u64);
    let started = std::time::Instant::now();
    let mut outcomes = Vec::with_capacity(cases.len());
    for case in &cases {
        bar.set_message(case.label.clone());
        let images = render(case)?;
        let error = sweep::error_stats(&images.f32, &images.f64);
        let w = case.shot.width as usize;
        let worst = error.worst.map(|(i, c)| ((i % w) as u32, (i / w) as u32, c));
        let sens = any::sensitivity(&images.f32, &images.f32_nudged, &images.f64, &images.f64_nudged);
        let f32_nonfinite = images.f32.iter().any(|p| p[..3].iter().any(|c| !c.is_finite()));
        let nonfinite = if f32_nonfinite { Some(trace(case)?.0) } else { None };
        outcomes.push(AnyOutcome { case: case.clone(), error, worst, sens, nonfinite });
        bar.inc(1);
    }
    bar.finish_and_clear();
    let elapsed = started.elapsed();
    super::create_output_dir(&args.out_dir)?;

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
            let image = |pixels: Vec<[f32; 4]>| Image::new(w, h, pixels).map_err(environment);
            let file = format!("heatmap-{kind}-{}.png", o.case.slug.replace(['/', ' '], "_"));
            let (a, b, what) = if kind == "error" {
                (image(images.f32)?, image(sweep::narrow(&images.f64))?, "f32 against f64")
            } else {
                (image(images.f32_nudged)?, image(images.f32)?, "f32 nudged by 4 ulps against f32")
            };
            skyrun::write_heatmap_png(&args.out_dir.join(&file), &a, &b, sweep::FLOOR as f32).map_err(environment)?;
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
        let base = Image::new(w, h, render(&o.case)?.f32).map_err(environment)?;
        let colours = gdsky_naga::trace::PLACE_COLOURS;
        let overlay: Vec<Option<[u8; 3]>> =
            ids.iter().map(|p| report.place_of(&traced, p[3]).map(|i| colours[i.min(colours.len() - 1)].1)).collect();
        let file = format!("nonfinite-{}.png", o.case.slug.replace(['/', ' '], "_"));
        skyrun::write_overlay_png(&args.out_dir.join(&file), &base, &overlay).map_err(environment)?;
        heatmaps.push((file, format!("{} — where NaN/Inf start (colours as listed)", o.case.label)));
    }
    let md = any_report(&name, &adapter.to_string(), args.quick, elapsed, &outcomes, &heatmaps);
    let md_path = args.out_dir.join("stress.md");
    super::write_file(&md_path, md.as_bytes()).map_err(environment)?;
    let csv_path = args.out_dir.join("stress.csv");
    super::write_file(&csv_path, any_csv(&outcomes).as_bytes()).map_err(environment)?;

    let at_defaults = || outcomes.iter().filter(|o| o.case.uniform.is_none());
    let nan: usize = at_defaults().map(|o| o.error.nan).sum();
    let inf: usize = at_defaults().map(|o| o.error.inf).sum();
    let worst = by_error.first().map(|o| (o.error.max, o.case.label.clone()));
    let ill_cases = outcomes.iter().filter(|o| o.sens.ill_conditioned > 0).count();
    println!("gdsky stress: {name}, {} cases ({}), {:.1?}", outcomes.len(), mode(args.quick), elapsed);
    println!("adapter  {adapter}");
    println!("truth    the same shader evaluated in f64 on the device (skyrun::F64Sky), same scene and uniforms");
    print!("{}", any_table(&outcomes));
    println!("wrote    {}, {} and {} heatmaps", md_path.display(), csv_path.display(), heatmaps.len());
    println!(
        "summary: nan_at_defaults={nan} inf_at_defaults={inf} worst_max={:.6e} worst_case=\"{}\" \
         ill_conditioned_cases={ill_cases} cases={}",
        worst.as_ref().map_or(0.0, |w| w.0),
        worst.as_ref().map_or(String::new(), |w| w.1.clone()),
        outcomes.len()
    );
    if args.quick && nan + inf > 0 {
        eprintln!("error: NaN/Inf at default uniforms ({nan} NaN, {inf} Inf channels)");
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}

/// The report's section on where NaN and Inf start: for each case whose render has any, the
/// traced module's places (`gdsky_naga::trace`, as `gdsky render --trace-nonfinite`). Empty when
/// no case placed any.
fn nonfinite_section(cases: &[(String, &gdsky_naga::trace::NonfiniteReport)]) -> String {
    let placed: Vec<_> = cases.iter().filter(|(_, r)| !r.places.is_empty()).collect();
    if placed.is_empty() {
        return String::new();
    }
    let mut md = String::from(
        "## Where NaN and Inf start\n\nFor each case whose f32 render has NaN or Inf, the traced module \
         (`gdsky_naga::trace`, as `gdsky render --trace-nonfinite`) names the expression that first made a \
         non-finite value in each pixel:\n\n",
    );
    for (label, r) in placed {
        let _ = writeln!(md, "- **{label}**: {} of {} pixels", traced_pixels(r), r.pixels);
        for p in &r.places {
            let _ = writeln!(
                md,
                "  - `{}`: `{}` ({} in {}): {} pixels",
                p.location, p.snippet, p.kind, p.function, p.pixels
            );
        }
    }
    md.push('\n');
    md
}

/// Pixels a trace report places (those whose first NaN/Inf was found).
fn traced_pixels(r: &gdsky_naga::trace::NonfiniteReport) -> usize {
    r.places.iter().map(|p| p.pixels).sum()
}

/// The share of a case's channels that are ill-conditioned.
fn ill_fraction(s: &any::Sensitivity) -> f64 {
    if s.channels == 0 { 0.0 } else { s.ill_conditioned as f64 / s.channels as f64 }
}

/// Every generic case as a Markdown table.
fn any_table(outcomes: &[AnyOutcome]) -> String {
    let mut out = String::from(
        "| case | NaN / Inf | mean | p99.9 | max | worst at (x, y) | Δ f32 / Δ f64 (mean, 4-ulp nudge) | \
         ill-conditioned | f32-amplified |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for o in outcomes {
        let e = &o.error;
        let measured = e.channels > 0;
        let at = o.worst.map_or("—".into(), |(x, y, c)| format!("({x}, {y}) {}", ["R", "G", "B"][c]));
        let pct = |n: usize| {
            if o.sens.channels == 0 {
                "—".into()
            } else {
                format!("{:.2} %", 100.0 * n as f64 / o.sens.channels as f64)
            }
        };
        let _ = writeln!(
            out,
            "| {} | {} / {} | {} | {} | {} | {at} | {:.1e} / {:.1e} | {} | {} |",
            o.case.label,
            e.nan,
            e.inf,
            sci(e.mean, measured),
            sci(e.p999, measured),
            sci(e.max, measured),
            o.sens.mean32,
            o.sens.mean64,
            pct(o.sens.ill_conditioned),
            pct(o.sens.amplified)
        );
    }
    out
}

/// The generic report.
fn any_report(
    name: &str,
    adapter: &str,
    quick: bool,
    elapsed: std::time::Duration,
    outcomes: &[AnyOutcome],
    heatmaps: &[(String, String)],
) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# gdsky stress: {name}\n");
    let _ = writeln!(
        md,
        "Adapter: {adapter}. Mode: {} ({} cases, {elapsed:.1?}). {name} is not Freeman-compatible, so each case is \
         measured against the **same shader evaluated in f64** on the device (`skyrun::F64Sky`): the error is f32 \
         rounding alone, per RGB channel |f32 − f64| / max(|f64|, {:e}). **Sensitivity**: the case is rendered again \
         with the screen size (so every pixel's EYEDIR), the camera basis, POSITION and TIME each moved up by \
         {NUDGE_ULPS} ulps, in f32 and in f64; Δ is the mean relative change of the output. A channel is \
         *ill-conditioned* when it moves by more than {:.0} % in either (a few ulps of input change the colour: \
         its value is noise that differs between GPUs, e.g. `fract(sin(x) * 43758.5)` at large x), *f32-amplified* \
         when the f32 output moves more than 10× the f64 one (+1e-4).\n",
        mode(quick),
        outcomes.len(),
        sweep::FLOOR,
        100.0 * any::ILL_CONDITIONED
    );
    let mut worst: Vec<&AnyOutcome> = outcomes.iter().collect();
    worst.sort_by(|a, b| badness(&b.error).total_cmp(&badness(&a.error)));
    let traced: Vec<(String, &gdsky_naga::trace::NonfiniteReport)> =
        outcomes.iter().filter_map(|o| o.nonfinite.as_ref().map(|r| (o.case.label.clone(), r))).collect();
    md.push_str(&nonfinite_section(&traced));
    let _ = writeln!(md, "## Worst cases\n");
    for o in worst.iter().take(3) {
        let _ = writeln!(
            md,
            "- by error: **{}** — {} NaN, {} Inf, max {}, p99.9 {}",
            o.case.label,
            o.error.nan,
            o.error.inf,
            sci(o.error.max, o.error.channels > 0),
            sci(o.error.p999, o.error.channels > 0)
        );
    }
    let mut ill: Vec<&AnyOutcome> = outcomes.iter().filter(|o| o.sens.ill_conditioned > 0).collect();
    ill.sort_by(|a, b| ill_fraction(&b.sens).total_cmp(&ill_fraction(&a.sens)));
    for o in ill.iter().take(3) {
        let _ = writeln!(
            md,
            "- by sensitivity: **{}** — {:.2} % of channels ill-conditioned, {:.2} % f32-amplified",
            o.case.label,
            100.0 * ill_fraction(&o.sens),
            100.0 * o.sens.amplified as f64 / o.sens.channels.max(1) as f64
        );
    }
    if ill.is_empty() {
        let _ = writeln!(md, "- by sensitivity: no case has an ill-conditioned channel");
    }
    let _ = writeln!(md, "\n## Every case\n\n{}", any_table(outcomes));
    if !heatmaps.is_empty() {
        let _ = writeln!(md, "## Heatmaps\n");
        for (file, caption) in heatmaps {
            let _ = writeln!(md, "**{caption}**\n\n![{caption}]({file})\n");
        }
    }
    md
}

/// Every generic case as CSV: group, case, uniform, nan, inf, mean_rel, p999_rel, max_rel,
/// sens_f32, sens_f64, ill_conditioned, amplified, channels.
fn any_csv(outcomes: &[AnyOutcome]) -> String {
    let mut out = String::from(
        "group,case,uniform,nan,inf,mean_rel,p999_rel,max_rel,sens_f32,sens_f64,ill_conditioned,amplified,channels\n",
    );
    for o in outcomes {
        let e = &o.error;
        let uniform = o.case.uniform.as_ref().map(|(n, v)| format!("{n}={v}")).unwrap_or_default();
        let _ = writeln!(
            out,
            "{},\"{}\",\"{uniform}\",{},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{}",
            o.case.group,
            o.case.label.replace('"', "'"),
            e.nan,
            e.inf,
            e.mean,
            e.p999,
            e.max,
            o.sens.mean32,
            o.sens.mean64,
            o.sens.ill_conditioned,
            o.sens.amplified,
            o.sens.channels
        );
    }
    out
}

fn mode(quick: bool) -> &'static str {
    if quick { "--quick" } else { "full" }
}

fn is_horizon(case: &Case) -> bool {
    case.uniform.is_none() && (case.altitude, case.sun) == HORIZON
}

/// How bad a case is, for ranking: any non-finite value first, then the largest error.
fn badness(s: &ErrorStats) -> f64 {
    if s.nan + s.inf > 0 { f64::INFINITY } else { s.max }
}

/// What the summary line and table report.
#[derive(Default)]
struct Summary {
    gpu_nan: usize,
    gpu_inf: usize,
    cpu_nan: usize,
    cpu_inf: usize,
    default_cases: usize,
    gpu_horizon_worst: f64,
    gpu_horizon_p999: f64,
    cpu_horizon_worst: f64,
    cpu_horizon_p999: f64,
    gpu_worst_default: Option<(f64, String)>,
    cpu_worst_default: Option<(f64, String)>,
}

impl Summary {
    fn of(outcomes: &[Outcome]) -> Summary {
        let mut s = Summary::default();
        for o in outcomes.iter().filter(|o| o.case.uniform.is_none()) {
            s.default_cases += 1;
            s.gpu_nan += o.gpu.nan;
            s.gpu_inf += o.gpu.inf;
            s.cpu_nan += o.cpu.nan;
            s.cpu_inf += o.cpu.inf;
            if is_horizon(&o.case) {
                s.gpu_horizon_worst = s.gpu_horizon_worst.max(o.gpu.max);
                s.gpu_horizon_p999 = s.gpu_horizon_p999.max(o.gpu.p999);
                s.cpu_horizon_worst = s.cpu_horizon_worst.max(o.cpu.max);
                s.cpu_horizon_p999 = s.cpu_horizon_p999.max(o.cpu.p999);
            }
            for (slot, stats) in [(&mut s.gpu_worst_default, &o.gpu), (&mut s.cpu_worst_default, &o.cpu)] {
                if slot.as_ref().is_none_or(|(v, _)| stats.max > *v) {
                    *slot = Some((stats.max, o.case.label()));
                }
            }
        }
        s
    }

    /// The machine-readable last line (tests and CI parse it).
    fn line(&self, cases: usize) -> String {
        format!(
            "summary: nan_at_defaults={} inf_at_defaults={} horizon_worst={:.6e} horizon_p999={:.6e} \
             cpu_nan_at_defaults={} cpu_inf_at_defaults={} cpu_horizon_worst={:.6e} cpu_horizon_p999={:.6e} cases={cases}",
            self.gpu_nan,
            self.gpu_inf,
            self.gpu_horizon_worst,
            self.gpu_horizon_p999,
            self.cpu_nan,
            self.cpu_inf,
            self.cpu_horizon_worst,
            self.cpu_horizon_p999
        )
    }

    /// The summary as a Markdown table; `family` names the reference's columns.
    fn table(&self, family: &Family) -> String {
        let worst = |w: &Option<(f64, String)>| {
            w.as_ref().map(|(v, at)| format!("{v:.2e} ({at})")).unwrap_or_else(|| "—".into())
        };
        let mut out = String::new();
        let _ = writeln!(
            out,
            "| | the shader on the GPU (f32) vs {label} f64 | {label} f32 ({}, CPU) vs f64 |",
            family.arithmetic,
            label = family.label
        );
        let _ = writeln!(out, "| --- | --- | --- |");
        let _ = writeln!(
            out,
            "| NaN / Inf channels at default uniforms ({} cases) | {} / {} | {} / {} |",
            self.default_cases, self.gpu_nan, self.gpu_inf, self.cpu_nan, self.cpu_inf
        );
        let _ = writeln!(
            out,
            "| horizon case (0.5 m, sun 0°): worst relative error | {:.2e} | {:.2e} |",
            self.gpu_horizon_worst, self.cpu_horizon_worst
        );
        let _ = writeln!(
            out,
            "| horizon case: p99.9 relative error | {:.2e} | {:.2e} |",
            self.gpu_horizon_p999, self.cpu_horizon_p999
        );
        let _ = writeln!(
            out,
            "| worst case at default uniforms | {} | {} |",
            worst(&self.gpu_worst_default),
            worst(&self.cpu_worst_default)
        );
        out
    }
}

/// What the report says about the run.
struct Context<'a> {
    name: &'a str,
    adapter: String,
    quick: bool,
    pano: (u32, u32),
    horizon: (u32, u32),
    elapsed: std::time::Duration,
    altitudes: &'a [f64],
    suns: &'a [f64],
    heatmaps: &'a [(String, String)],
    family: &'a Family,
}

fn where_text(w: Option<(u32, u32, usize, f64)>) -> String {
    match w {
        Some((x, y, c, elevation)) => format!("({x}, {y}) {} at {elevation:+.2}°", ["R", "G", "B"][c]),
        None => "—".into(),
    }
}

fn stats_cells(s: &ErrorStats, w: Option<(u32, u32, usize, f64)>) -> String {
    let measured = s.channels > 0;
    format!("{} / {} | {} | {} | {}", s.nan, s.inf, sci(s.max, measured), sci(s.p999, measured), where_text(w))
}

fn report_markdown(ctx: &Context, outcomes: &[Outcome], summary: &Summary) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# gdsky stress: {}\n", ctx.name);
    let _ = writeln!(
        md,
        "Adapter: {}. Mode: {} ({} cases, {:.1?}). Panorama {}×{} (rows {:.2}° apart); horizon view {}×{}, \
         camera {HORIZON_FOV}° high toward the sun's azimuth, pitch 0 (rows {:.3}° apart). Relative error per RGB \
         channel |x − f64| / max(|f64|, {:e}); the f64 truth is {} (the reference, {}) with the same sample \
         counts as the shader. \
         NaN / Inf count channels of the image under test; `where` is the worst channel's pixel (x, y), channel and \
         EYEDIR elevation.\n",
        ctx.adapter,
        mode(ctx.quick),
        outcomes.len(),
        ctx.elapsed,
        ctx.pano.0,
        ctx.pano.1,
        180.0 / f64::from(ctx.pano.1),
        ctx.horizon.0,
        ctx.horizon.1,
        HORIZON_FOV / f64::from(ctx.horizon.1),
        sweep::FLOOR,
        ctx.family.label,
        ctx.family.arithmetic
    );
    let _ = writeln!(md, "## Summary\n\n{}", summary.table(ctx.family));
    let _ = writeln!(md, "`{}`\n", summary.line(outcomes.len()));

    let gpu_title = format!("GPU f32 vs {} f64", ctx.family.label);
    let cpu_title = format!("{} f32 ({}, CPU) vs f64", ctx.family.label, ctx.family.arithmetic);
    for (title, pick) in [(gpu_title.as_str(), true), (cpu_title.as_str(), false)] {
        let _ = writeln!(
            md,
            "## {title}: worst relative error at default uniforms, altitude × sun elevation (both views)\n"
        );
        let mut head = String::from("| altitude |");
        let mut rule = String::from("| --- |");
        for sun in ctx.suns {
            let _ = write!(head, " {sun}° |");
            rule.push_str(" --- |");
        }
        let _ = writeln!(md, "{head}\n{rule}");
        for &altitude in ctx.altitudes {
            let mut row = format!("| {} |", altitude_text(altitude));
            for &sun in ctx.suns {
                let cell: Vec<&ErrorStats> = outcomes
                    .iter()
                    .filter(|o| o.case.uniform.is_none() && o.case.altitude == altitude && o.case.sun == sun)
                    .map(|o| if pick { &o.gpu } else { &o.cpu })
                    .collect();
                let nonfinite: usize = cell.iter().map(|s| s.nan + s.inf).sum();
                let max = cell.iter().map(|s| s.max).fold(0.0, f64::max);
                if nonfinite > 0 {
                    let _ = write!(row, " **{nonfinite} NaN/Inf** |");
                } else {
                    let _ = write!(row, " {max:.1e} |");
                }
            }
            let _ = writeln!(md, "{row}");
        }
        md.push('\n');
    }
    let _ = writeln!(md, "![worst relative error per altitude and sun elevation](grid.png)\n");

    let _ = writeln!(md, "## The 15 worst cases at default uniforms (by GPU error)\n");
    let _ = writeln!(
        md,
        "| case | GPU NaN / Inf | GPU max | GPU p99.9 | GPU where | CPU NaN / Inf | CPU max | CPU p99.9 | CPU where |"
    );
    let _ = writeln!(md, "| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let mut ranked: Vec<&Outcome> = outcomes.iter().filter(|o| o.case.uniform.is_none()).collect();
    ranked.sort_by(|a, b| badness(&b.gpu).total_cmp(&badness(&a.gpu)));
    for o in ranked.iter().take(15) {
        let _ = writeln!(
            md,
            "| {} | {} | {} |",
            o.case.label(),
            stats_cells(&o.gpu, o.gpu_where),
            stats_cells(&o.cpu, o.cpu_where)
        );
    }
    md.push('\n');

    let _ = writeln!(md, "## Uniforms at the ends of their hint_range (panorama)\n");
    let _ = writeln!(
        md,
        "| uniform | scene | GPU NaN / Inf | GPU max | GPU p99.9 | GPU where | CPU NaN / Inf | CPU max | CPU p99.9 | \
         CPU where | f64 non-finite |"
    );
    let _ = writeln!(md, "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for o in outcomes.iter().filter(|o| o.case.uniform.is_some()) {
        let (n, v) = o.case.uniform.clone().unwrap_or_default();
        let _ = writeln!(
            md,
            "| {n}={v} | {}, sun {}° | {} | {} | {} |",
            altitude_text(o.case.altitude),
            o.case.sun,
            stats_cells(&o.gpu, o.gpu_where),
            stats_cells(&o.cpu, o.cpu_where),
            o.gpu.truth_nonfinite
        );
    }
    md.push('\n');
    let _ = writeln!(md, "## Heatmaps (per-pixel relative error against f64, log scale 1e-7 … 1; NaN/Inf magenta)\n");
    for (file, caption) in ctx.heatmaps {
        let _ = writeln!(md, "- {caption}: ![{caption}]({file})");
    }
    md
}

/// Every case, one row: altitude_m, sun_deg, view, uniform, value, then for gpu and cpu: nan,
/// inf, max_rel, p999_rel, p99_rel, mean_rel, worst_x, worst_y, worst_channel,
/// worst_elevation_deg; and truth_nonfinite.
fn csv_text(outcomes: &[Outcome]) -> String {
    let mut out = String::from("altitude_m,sun_deg,view,uniform,value");
    for side in ["gpu", "cpu"] {
        for col in [
            "nan",
            "inf",
            "max_rel",
            "p999_rel",
            "p99_rel",
            "mean_rel",
            "worst_x",
            "worst_y",
            "worst_channel",
            "worst_elevation_deg",
        ] {
            let _ = write!(out, ",{side}_{col}");
        }
    }
    out.push_str(",truth_nonfinite\n");
    for o in outcomes {
        let (n, v) = o.case.uniform.clone().unwrap_or_default();
        let _ = write!(out, "{},{},{},{n},{v}", o.case.altitude, o.case.sun, o.case.view.name());
        for (s, w) in [(&o.gpu, o.gpu_where), (&o.cpu, o.cpu_where)] {
            let _ = write!(out, ",{},{},{:.6e},{:.6e},{:.6e},{:.6e}", s.nan, s.inf, s.max, s.p999, s.p99, s.mean);
            match w {
                Some((x, y, c, e)) => {
                    let _ = write!(out, ",{x},{y},{c},{e:.4}");
                }
                None => out.push_str(",,,,"),
            }
        }
        let _ = writeln!(out, ",{}", o.gpu.truth_nonfinite);
    }
    out
}

/// Viridis-like colour for t in [0, 1] (a few stops, linearly interpolated).
fn colour(t: f64) -> RGBColor {
    const STOPS: [(u8, u8, u8); 5] = [(68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37)];
    let t = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f64;
    let mix = |a: u8, b: u8| (f64::from(a) + (f64::from(b) - f64::from(a)) * f).round() as u8;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// grid.png: two panels (GPU f32 and CPU f32, each against f64), cells altitude × sun
/// elevation at default uniforms, coloured by log10 of the worst relative error over both views
/// (1e-7 dark … 1 bright) and labelled with it; magenta where a value is NaN or ±∞.
fn plot_grid(
    path: &Path,
    name: &str,
    family: &Family,
    outcomes: &[Outcome],
    altitudes: &[f64],
    suns: &[f64],
) -> Result<(), String> {
    sweep::register_fonts();
    let (w, h) = (1600u32, 600u32);
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    let err = |e: &dyn std::fmt::Display| format!("cannot draw {}: {e}", path.display());
    let index = |v: &SegmentValue<i32>| match v {
        SegmentValue::Exact(i) | SegmentValue::CenterOf(i) => Some(*i as usize),
        SegmentValue::Last => None,
    };
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let title = format!(
            "{name}: worst relative error vs f64 at default uniforms, both views (colour log10 1e-7 … 1; magenta NaN/Inf)"
        );
        let root = root.titled(&title, ("sans-serif", 18)).map_err(|e| err(&e))?;
        let panels = root.split_evenly((1, 2));
        for (panel, (title, gpu)) in panels.iter().zip([
            ("GPU f32 (the shader)".to_string(), true),
            (format!("{} f32 on the CPU ({})", family.label, family.arithmetic), false),
        ]) {
            let (nx, ny) = (suns.len() as i32, altitudes.len() as i32);
            let mut chart = ChartBuilder::on(panel)
                .caption(title, ("sans-serif", 16))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(64)
                // A segmented range a..b has a segment for each of a..=b: one per value.
                .build_cartesian_2d((0..nx - 1).into_segmented(), (0..ny - 1).into_segmented())
                .map_err(|e| err(&e))?;
            let sun_label =
                |v: &SegmentValue<i32>| index(v).and_then(|i| suns.get(i)).map(|s| format!("{s}")).unwrap_or_default();
            let alt_label = |v: &SegmentValue<i32>| {
                index(v).and_then(|i| altitudes.get(i)).map(|a| altitude_text(*a)).unwrap_or_default()
            };
            chart
                .configure_mesh()
                .disable_mesh()
                .x_labels(suns.len())
                .y_labels(altitudes.len())
                .x_label_formatter(&sun_label)
                .y_label_formatter(&alt_label)
                .x_desc("sun elevation, °")
                .label_style(("sans-serif", 12))
                .draw()
                .map_err(|e| err(&e))?;
            let mut cells = Vec::new();
            let mut labels = Vec::new();
            for (iy, &altitude) in altitudes.iter().enumerate() {
                for (ix, &sun) in suns.iter().enumerate() {
                    let stats: Vec<&ErrorStats> = outcomes
                        .iter()
                        .filter(|o| o.case.uniform.is_none() && o.case.altitude == altitude && o.case.sun == sun)
                        .map(|o| if gpu { &o.gpu } else { &o.cpu })
                        .collect();
                    if stats.is_empty() {
                        continue;
                    }
                    let nonfinite = stats.iter().any(|s| s.nan + s.inf > 0);
                    let max = stats.iter().map(|s| s.max).fold(0.0, f64::max);
                    let t = (max.max(1e-7).log10() + 7.0) / 7.0;
                    let fill = if nonfinite { RGBColor(255, 0, 255) } else { colour(t) };
                    let (x, y) = (ix as i32, iy as i32);
                    let corners = [
                        (SegmentValue::Exact(x), SegmentValue::Exact(y)),
                        (SegmentValue::Exact(x + 1), SegmentValue::Exact(y + 1)),
                    ];
                    cells.push(Rectangle::new(corners, fill.filled()));
                    let text = if nonfinite { "NaN".to_string() } else { format!("{max:.0e}") };
                    let ink = if t > 0.6 && !nonfinite { BLACK } else { WHITE };
                    labels.push(Text::new(
                        text,
                        (SegmentValue::CenterOf(x), SegmentValue::CenterOf(y)),
                        ("sans-serif", 11).into_font().color(&ink).pos(Pos::new(HPos::Center, VPos::Center)),
                    ));
                }
            }
            chart.draw_series(cells).map_err(|e| err(&e))?;
            chart.draw_series(labels).map_err(|e| err(&e))?;
        }
        root.present().map_err(|e| err(&e))?;
    }
    sweep::write_rgb_png(path, w, h, &rgb)
}
