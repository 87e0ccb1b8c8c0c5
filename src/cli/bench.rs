//! `gdsky bench [FILE]`: render time against error for a Freeman-compatible sky.
//!
//! Sweeps `view_samples` × `sun_samples` (and any other int uniform given with `--knob`),
//! renders each configuration on the adapter, times it, and measures it against skyref's
//! converged f64 image of the same scene (the stand-in for the exact integral of the shader's
//! model). Writes `bench.csv` and `bench.png` (error against time, log-log, the Pareto front
//! highlighted) and prints the front.
//!
//! Timing is the passes' own time from GPU timestamp queries where the adapter has them
//! ([`skyrun::Rendered::gpu_time`]; lavapipe does), else wall time from submit to the device
//! going idle ([`skyrun::Rendered::gpu_wait`]); the CSV's `timer` column says which. Each time is
//! the median of `--runs` renders after one warm-up render (which also gives the pixels
//! measured).
//!
//! The truth is cached as an EXR (see [`cache_dir`]), keyed by the scene, the image size, the
//! truth's sample counts and every uniform; an entry is used only when its key file matches
//! exactly, its pixels match the checksum recorded with them, and a few pixels recomputed now
//! match it bit for bit. Anything else is recomputed.

use super::scene::{
    LoadedShader, ProjectionArg, SceneArgs, bake_reason, check_override_conflicts, check_scene_uniforms, open_gpu,
    open_input, override_names, set_freeman, strip,
};
use super::sweep::{self, ErrorStats};
use super::{environment, usage};
use clap::{ArgMatches, Args};
use plotters::prelude::*;
use skyref::converged::Converged;
use skyref::{FreemanParams, Projection, Scene, UniformMut};
use skyrun::{Image, SkyBuiltins};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

/// The default sweep of `view_samples`.
const VIEW_SAMPLES: [i32; 8] = [4, 8, 12, 16, 24, 32, 48, 64];
/// The default sweep of `sun_samples`.
const SUN_SAMPLES: [i32; 4] = [2, 4, 8, 16];

#[derive(Args)]
pub struct BenchArgs {
    /// The sky shader to benchmark (Freeman-compatible: the Freeman sky's uniforms), or a scene
    /// file (`SCENE.toml`: its shader, uniforms, sun, camera, projection, size and time; the
    /// flags given override it); without one, the bundled Freeman sky.
    #[arg(value_name = "FILE|SCENE.toml")]
    file: Option<PathBuf>,
    /// Bake every uniform the scene file fixes (and every `--set`) into the shader as
    /// constants, except the swept knobs; with no scene file, every uniform but the knobs at its
    /// default.
    #[arg(long)]
    bake_scene: bool,
    /// Emit a scalar uniform as a pipeline-overridable constant: one module, each
    /// configuration's value given at pipeline creation (a swept knob gets a pipeline per
    /// value). Adds to the scene file's `overrides`. With --skipping, the `uniforms` rows time
    /// these (else the swept knobs) as overrides against the generic and the baked module.
    /// Repeatable.
    #[arg(long = "override", value_name = "NAME")]
    overrides: Vec<String>,
    /// Folder for bench.csv and bench.png (created if missing; checked before any work).
    #[arg(short = 'o', long = "out-dir", value_name = "DIR", default_value = "out/bench")]
    out_dir: PathBuf,
    /// Timed renders per configuration (1 to 1000), after one warm-up render; the median is
    /// reported.
    #[arg(long, value_name = "N", default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000), allow_hyphen_values = true)]
    runs: u32,
    /// Sweep an int uniform: `--knob view_samples=4,8,16`. view_samples (4,8,12,16,24,32,48,64)
    /// and sun_samples (2,4,8,16) are swept by default; a --knob replaces a default list or adds
    /// a dimension. Values are sample counts, 1 to 4096. Repeatable.
    #[arg(long = "knob", value_name = "NAME=V1,V2,…")]
    knobs: Vec<String>,
    /// Sample counts of the truth (skyref f64): VIEW,SUN, each 1 to 16384.
    #[arg(long, value_name = "VIEW,SUN", default_value = "1024,256", value_parser = parse_counts, allow_hyphen_values = true)]
    truth_samples: (i32, i32),
    /// Where truth images are cached [default: $GDSKY_CACHE_DIR, else $XDG_CACHE_HOME/gdsky,
    /// else ~/.cache/gdsky, else the temp dir's gdsky-cache].
    #[arg(long, value_name = "DIR")]
    cache_dir: Option<PathBuf>,
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    skipping: super::bench_skip::SkippingArgs,
}

/// Largest sample count of the truth (`--truth-samples`): 16× the default view samples; the f64
/// truth's time grows with the product of the two.
const MAX_TRUTH_SAMPLES: i32 = 16384;
/// Largest value of a swept int uniform (`--knob`): they are sample counts (64 × 16 is the
/// default sweep's largest).
const MAX_KNOB: i32 = 4096;

fn parse_counts(s: &str) -> Result<(i32, i32), String> {
    let (a, b) = s.split_once(',').ok_or_else(|| format!("`{s}`: expected VIEW,SUN, e.g. 1024,256"))?;
    let count = |t: &str| match t.trim().parse::<i32>() {
        Ok(v) if (1..=MAX_TRUTH_SAMPLES).contains(&v) => Ok(v),
        _ => Err(format!("`{}` is not a sample count from 1 to {MAX_TRUTH_SAMPLES}", t.trim())),
    };
    Ok((count(a)?, count(b)?))
}

/// One image per view (one for a panorama or camera, six cube faces).
type ViewImages = Vec<Vec<[f32; 4]>>;

/// One swept int uniform and its values.
#[derive(Clone, Debug)]
struct Knob {
    name: String,
    values: Vec<i32>,
}

/// One configuration's measurements.
struct Row {
    values: Vec<i32>,
    median: Duration,
    min: Duration,
    max: Duration,
    errors: ErrorStats,
    pareto: bool,
}

pub fn run(args: &BenchArgs, matches: &ArgMatches) -> ExitCode {
    match bench(args, matches) {
        Ok(()) => ExitCode::SUCCESS,
        Err(code) => code,
    }
}

/// The knobs: the defaults, each replaced or extended by a `--knob`.
fn knobs(args: &[String]) -> Result<Vec<Knob>, String> {
    let mut knobs = vec![
        Knob { name: "view_samples".into(), values: VIEW_SAMPLES.to_vec() },
        Knob { name: "sun_samples".into(), values: SUN_SAMPLES.to_vec() },
    ];
    for arg in args {
        let (name, list) = arg.split_once('=').ok_or_else(|| format!("`--knob {arg}`: expected NAME=V1,V2,…"))?;
        let name = name.trim();
        let mut probe = FreemanParams::default();
        let is_int = probe.uniforms_mut().into_iter().any(|(n, u)| n == name && matches!(u, UniformMut::Int(_)));
        if !is_int {
            return Err(format!("`--knob {arg}`: `{name}` is not an int uniform of the Freeman sky"));
        }
        let values = list
            .split(',')
            .map(|v| match v.trim().parse::<i32>() {
                Ok(n) if (1..=MAX_KNOB).contains(&n) => Ok(n),
                _ => Err(format!("`--knob {arg}`: `{}` is not a sample count from 1 to {MAX_KNOB}", v.trim())),
            })
            .collect::<Result<Vec<_>, _>>()?;
        match knobs.iter_mut().find(|k| k.name == name) {
            Some(k) => k.values = values,
            None => knobs.push(Knob { name: name.into(), values }),
        }
    }
    Ok(knobs)
}

/// Every combination of the knobs' values, the first knob varying slowest.
fn combinations(knobs: &[Knob]) -> Vec<Vec<i32>> {
    knobs.iter().fold(vec![Vec::new()], |acc, knob| {
        acc.iter()
            .flat_map(|prefix| {
                knob.values.iter().map(move |v| {
                    let mut next = prefix.clone();
                    next.push(*v);
                    next
                })
            })
            .collect()
    })
}

/// The value of the int uniform `name` in `params`.
fn int_value(params: &FreemanParams, name: &str) -> Option<i32> {
    let mut params = *params;
    params.uniforms_mut().into_iter().find_map(|(n, u)| match u {
        UniformMut::Int(v) if n == name => Some(*v),
        _ => None,
    })
}

fn with_knobs(base: &FreemanParams, knobs: &[Knob], values: &[i32]) -> Result<FreemanParams, String> {
    let mut params = *base;
    for (knob, value) in knobs.iter().zip(values) {
        params.set(&knob.name, &value.to_string())?;
    }
    Ok(params)
}

/// The material block of a Freeman-compatible shader from skyref's parameters, leaving out the
/// uniforms baked into constants and the overrides (pipeline constants, [`constants`]).
fn material(loaded: &LoadedShader, params: &FreemanParams) -> Result<Vec<u8>, skyrun::MaterialError> {
    if loaded.baked.is_empty() && loaded.overrides.is_empty() {
        return sweep::material(loaded, params);
    }
    let values: Vec<_> = skyrun::freeman_values(params)
        .into_iter()
        .filter(|(name, _)| !loaded.baked.contains_key(*name) && !loaded.overrides.iter().any(|o| o == name))
        .collect();
    skyrun::material_bytes(&loaded.lowered, &values)
}

/// The pipeline constants of a Freeman-compatible shader's overrides from skyref's parameters,
/// rounded to f32 as the material block would hold them.
fn constants(loaded: &LoadedShader, params: &FreemanParams) -> Vec<(String, f64)> {
    let values = skyrun::freeman_values(params);
    loaded
        .overrides
        .iter()
        .enumerate()
        .filter_map(|(id, name)| {
            let (_, v) = values.iter().find(|(n, _)| n == name)?;
            let v = match *v {
                skyrun::UniformValue::Float(f) => f64::from(f),
                skyrun::UniformValue::Int(i) => f64::from(i),
                skyrun::UniformValue::UInt(u) => f64::from(u),
                skyrun::UniformValue::Bool(b) => f64::from(u8::from(b)),
                // Overrides are scalars; lowering refused anything else.
                _ => return None,
            };
            Some((id.to_string(), v))
        })
        .collect()
}

/// The compiled shaders of a sweep: one per distinct set of override values (one in all when
/// no swept knob is an override), and which one each configuration uses.
struct Compiled {
    shaders: Vec<(Vec<(String, f64)>, skyrun::SkyShader)>,
}

impl Compiled {
    /// The shader with `constants`, compiled on first use.
    fn index(
        &mut self,
        loaded: &LoadedShader,
        gpu: &skyrun::Gpu,
        constants: Vec<(String, f64)>,
    ) -> Result<usize, ExitCode> {
        if let Some(i) = self.shaders.iter().position(|(c, _)| *c == constants) {
            return Ok(i);
        }
        let shader = loaded.compile(gpu)?.with_constants(constants.clone());
        self.shaders.push((constants, shader));
        Ok(self.shaders.len() - 1)
    }
}

/// A uniform value in `--set` syntax.
fn uniform_text(value: skyrun::UniformValue) -> String {
    use skyrun::UniformValue as U;
    let join = |v: &[f32]| v.iter().map(|c| format!("{c:?}")).collect::<Vec<_>>().join(",");
    match value {
        U::Float(v) => format!("{v:?}"),
        U::Int(v) => v.to_string(),
        U::UInt(v) => v.to_string(),
        U::Bool(v) => v.to_string(),
        U::Vec2(v) => join(&v),
        U::Vec3(v) => join(&v),
        U::Vec4(v) => join(&v),
    }
}

fn bench(args: &BenchArgs, matches: &ArgMatches) -> Result<(), ExitCode> {
    let input = open_input(args.file.as_deref())?;
    let mut scene_args = args.scene.clone();
    if let Some(file) = &input.scene {
        scene_args.merge_file(file, matches);
        super::render::warn_unapplied(file, "bench");
    }
    let args = &BenchArgs {
        file: input.shader.clone(),
        scene: scene_args,
        knobs: args.knobs.clone(),
        out_dir: args.out_dir.clone(),
        cache_dir: args.cache_dir.clone(),
        skipping: args.skipping.clone(),
        overrides: args.overrides.clone(),
        ..*args
    };
    let (views, width, height) = args.scene.views().map_err(usage)?;
    let mut base = FreemanParams::default();
    set_freeman(&mut base, &args.scene.overrides().map_err(usage)?).map_err(usage)?;
    let knobs = knobs(&args.knobs).map_err(usage)?;
    let configs = combinations(&knobs);
    if configs.is_empty() {
        return Err(usage("the sweep is empty"));
    }
    super::check_output_dir(&args.out_dir, true, &["bench.csv", "bench.png"])?;
    let cli_sets = super::scene::SceneArgs::overrides(&args.scene).map_err(usage)?;
    let override_names = override_names(input.scene.as_ref(), &args.overrides);
    check_override_conflicts(&override_names, input.scene.as_ref(), |n| {
        if knobs.iter().any(|k| k.name == n) {
            None
        } else {
            bake_reason(n, input.scene.as_ref(), &cli_sets, args.bake_scene)
        }
    })?;
    let mut loaded = sweep::load_freeman(args.file.as_deref())?;
    check_scene_uniforms(input.scene.as_ref(), &loaded)?;
    let mut baked = std::collections::HashMap::new();
    if args.bake_scene {
        // The values baked are the ones the material would carry (skyref's defaults with the
        // scene's uniforms and --set over them), so the truth still matches: with a scene file,
        // the uniforms it fixes and those --set; without one, every uniform; never a knob.
        let cli_sets = super::scene::SceneArgs::overrides(&args.scene).map_err(usage)?;
        let fixed: Vec<String> = match &input.scene {
            Some(file) => {
                file.uniform_pairs().into_iter().map(|(n, _)| n).chain(cli_sets.into_iter().map(|(n, _)| n)).collect()
            }
            None => sweep::freeman_names().into_iter().map(String::from).collect(),
        };
        baked = skyrun::freeman_values(&base)
            .into_iter()
            .filter(|(name, _)| {
                fixed.iter().any(|f| f == name)
                    && !knobs.iter().any(|k| k.name == *name)
                    && !override_names.iter().any(|o| o == name)
            })
            .map(|(name, value)| (name.to_string(), uniform_text(value)))
            .collect();
        let mut names: Vec<&String> = baked.keys().collect();
        names.sort();
        eprintln!(
            "baked {} uniform(s): {}",
            names.len(),
            names.iter().map(|n| n.as_str()).collect::<Vec<_>>().join(", ")
        );
    }
    if args.bake_scene || !override_names.is_empty() {
        loaded.respecialize(baked, &override_names)?;
    }
    if !override_names.is_empty() {
        eprintln!("overrides: {}", override_names.join(", "));
    }
    let shader_name = args.file.as_ref().map(|f| f.display().to_string()).unwrap_or("freeman_sky (bundled)".into());
    let gpu = open_gpu()?;
    let adapter = gpu.adapter_info();
    let timer = if gpu.has_timestamps() { "gpu_timestamps" } else { "wall" };
    let scene = args.scene.scene();
    let mut builtins = SkyBuiltins::from_scene(&scene, width, height);
    builtins.time = args.scene.time;
    let converged = Converged { view_samples: args.truth_samples.0, sun_samples: args.truth_samples.1 };

    let bar = sweep::progress_bar(1 + configs.len() as u64 * (1 + u64::from(args.runs)));
    bar.set_message(format!(
        "truth: skyref f64 at {}/{} samples (cached after the first run)",
        converged.view_samples, converged.sun_samples
    ));
    bar.enable_steady_tick(Duration::from_millis(200));
    let truth_params: Vec<FreemanParams> = configs
        .iter()
        .map(|values| with_knobs(&base, &knobs, values).map(|p| converged.params(&p)))
        .collect::<Result<_, _>>()
        .map_err(usage)?;
    let cache = args.cache_dir.clone().unwrap_or_else(cache_dir);
    let mut truths: Vec<(FreemanParams, Vec<[f64; 4]>)> = Vec::new();
    for params in &truth_params {
        // Only the knobs other than the sample counts change the truth; most sweeps share one.
        if truths.iter().any(|(p, _)| p == params) {
            continue;
        }
        let (image, note) = cached_truth(&cache, params, &scene, &views, width, height);
        bar.suspend(|| eprintln!("{note}"));
        truths.push((*params, sweep::widen(&image.pixels)));
    }
    bar.inc(1);

    let params: Vec<FreemanParams> =
        configs.iter().map(|values| with_knobs(&base, &knobs, values)).collect::<Result<_, _>>().map_err(usage)?;
    let materials: Vec<Vec<u8>> = params
        .iter()
        .map(|p| material(&loaded, p).map_err(|e| e.to_string()))
        .collect::<Result<_, _>>()
        .map_err(usage)?;
    // Each configuration's pipelines carry its override values: a module compiled per distinct
    // set (before any timing), so switching configurations in the round-robin rebuilds nothing.
    let mut compiled = Compiled { shaders: Vec::new() };
    let shader_of: Vec<usize> =
        params.iter().map(|p| compiled.index(&loaded, &gpu, constants(&loaded, p))).collect::<Result<_, _>>()?;
    let base_shader = compiled.index(&loaded, &gpu, constants(&loaded, &base))?;
    let shaders: Vec<&skyrun::SkyShader> = compiled.shaders.iter().map(|(_, s)| s).collect();
    let label = |values: &[i32]| values.iter().map(i32::to_string).collect::<Vec<_>>().join("/");
    let render_all = |shader: &skyrun::SkyShader, material: &[u8]| -> Result<(ViewImages, Duration), ExitCode> {
        let mut images = Vec::with_capacity(views.len());
        let mut time = Duration::ZERO;
        for &view in &views {
            let r = shader.render(&gpu, view, width, height, &builtins, material).map_err(|err| {
                bar.suspend(|| eprintln!("error: {err}"));
                ExitCode::from(1)
            })?;
            // The passes' own time from GPU timestamps where the device has them, else the
            // host's wall time from submit to idle.
            time += r.gpu_time.unwrap_or(r.gpu_wait);
            images.push(r.pixels);
        }
        Ok((images, time))
    };
    // First every configuration's warm-up render, which pays for the driver's pipeline
    // compilation; its pixels are the ones measured (every render of a configuration gives the
    // same pixels).
    let mut errors = Vec::with_capacity(configs.len());
    for (i, ((values, material), truth_params)) in configs.iter().zip(&materials).zip(&truth_params).enumerate() {
        bar.set_message(format!("{}: warm-up render and error", label(values)));
        let (images, _) = render_all(shaders[shader_of[i]], material)?;
        let image = strip(images, width, height).map_err(usage)?;
        let truth = &truths.iter().find(|(p, _)| p == truth_params).ok_or(ExitCode::from(1))?.1;
        errors.push(sweep::error_stats(&image.pixels, truth));
        bar.inc(1);
    }
    // Then the timed renders, round-robin over the configurations: a burst of load from
    // elsewhere on the machine spreads over all of them instead of spoiling one's median.
    let mut times = vec![Vec::with_capacity(args.runs as usize); configs.len()];
    for run in 0..args.runs {
        bar.set_message(format!("timing: round {} of {} on {}", run + 1, args.runs, adapter.name));
        for (i, (material, times)) in materials.iter().zip(&mut times).enumerate() {
            times.push(render_all(shaders[shader_of[i]], material)?.1);
            bar.inc(1);
        }
    }
    let mut rows: Vec<Row> = configs
        .iter()
        .zip(errors)
        .zip(&mut times)
        .map(|((values, errors), times)| {
            times.sort();
            // The median; of an even count, the mean of the middle two.
            let n = times.len();
            let median = (times[(n - 1) / 2] + times[n / 2]) / 2;
            Row { values: values.clone(), median, min: times[0], max: times[n - 1], errors, pareto: false }
        })
        .collect();
    bar.finish_and_clear();
    mark_pareto(&mut rows);

    let csv_path = args.out_dir.join("bench.csv");
    let csv = csv_text(&knobs, &rows, args.runs, timer);
    super::create_output_dir(&args.out_dir)?;
    super::write_file(&csv_path, csv.as_bytes()).map_err(environment)?;
    let png_path = args.out_dir.join("bench.png");

    println!(
        "gdsky bench: {shader_name}, {} configurations, {width}x{height} {}",
        rows.len(),
        projection_name(&args.scene)
    );
    println!("adapter  {adapter}");
    println!(
        "timer    {}, median of {} after a warm-up",
        if timer == "wall" {
            "wall time submit → idle (the adapter has no timestamp queries)"
        } else {
            "GPU timestamp queries around the passes"
        },
        args.runs
    );
    println!(
        "truth    skyref f64, {}/{} samples; error = |gdsky − truth| / max(|truth|, {:e}) over RGB",
        converged.view_samples,
        converged.sun_samples,
        sweep::FLOOR
    );
    println!("Pareto front (no other configuration both faster and more accurate):");
    print!("{}", front_table(&knobs, &rows));
    let mut reduced = Vec::new();
    if args.skipping.skipping {
        let base_material = material(&loaded, &base).map_err(|e| usage(e.to_string()))?;
        // The `uniforms` rows: the named overrides, else the swept knobs, as a generic module
        // (material block), baked into constants, and as overrides, each at the base values.
        let varied: Vec<String> = if override_names.is_empty() {
            knobs.iter().map(|k| k.name.clone()).collect()
        } else {
            override_names.clone()
        };
        let mut modules = Vec::new();
        for kind in ["generic", "baked", "overrides"] {
            let mut m = sweep::load_freeman(args.file.as_deref())?;
            match kind {
                "baked" => {
                    let values = skyrun::freeman_values(&base)
                        .into_iter()
                        .filter(|(n, _)| varied.iter().any(|v| v == n))
                        .map(|(n, v)| (n.to_string(), uniform_text(v)))
                        .collect();
                    m.respecialize(values, &[])?;
                }
                "overrides" => m.respecialize(Default::default(), &varied)?,
                _ => {}
            }
            let mat = material(&m, &base).map_err(|e| usage(e.to_string()))?;
            let s = m.compile(&gpu)?.with_constants(constants(&m, &base));
            modules.push((kind, s, mat));
        }
        let base_truth = converged.params(&base);
        let truth = truths.iter().find(|(p, _)| *p == base_truth).or(truths.first()).ok_or(ExitCode::from(1))?;
        let cx = super::bench_skip::Context {
            gpu: &gpu,
            shader: shaders[base_shader],
            name: shader_name.clone(),
            modules: modules.iter().map(|(k, s, m)| (*k, s, m.as_slice())).collect(),
            views: &views,
            width,
            height,
            builtins: &builtins,
            material: &base_material,
            truth: &truth.1,
            runs: args.runs,
        };
        let rows = super::bench_skip::run(&cx, &args.skipping)?;
        println!("skipping (the shader's defaults; occluder ratio = time / time at 0 %, resolution = speed-up):");
        print!("{}", super::bench_skip::table(&rows));
        println!(
            "uniforms rows: {} read from the material block (generic), baked into constants (baked), as \
             pipeline-overridable constants (overrides); ratio = speed-up over generic",
            varied.join(", ")
        );
        let path = args.out_dir.join("skipping.csv");
        super::write_file(&path, super::bench_skip::csv(&rows).as_bytes()).map_err(environment)?;
        println!("wrote    {}", path.display());
        reduced = reduced_points(&rows);
    }
    let title = format!("{shader_name} on {}: {}x{} {}", adapter.name, width, height, projection_name(&args.scene));
    let defaults: Vec<i32> = knobs.iter().filter_map(|k| int_value(&base, &k.name)).collect();
    plot(&png_path, &title, &rows, &knobs, &defaults, &reduced, timer).map_err(environment)?;
    println!("wrote    {} and {}", csv_path.display(), png_path.display());
    Ok(())
}

/// The bench shader's reduced sky resolutions with the default (bilinear) upsampling, as
/// (median ms, mean relative error vs the converged truth, `half` or `quarter`): the points
/// `--skipping` adds to the plot.
fn reduced_points(rows: &[super::bench_skip::SkipRow]) -> Vec<(f64, f64, String)> {
    rows.iter()
        .filter(|r| r.kind == "resolution")
        .filter_map(|r| {
            let name = r.variant.strip_suffix("/bilinear")?;
            let truth = r.vs_truth.as_ref().filter(|e| e.mean > 0.0)?;
            Some((ms(r.median).max(1e-3), truth.mean, name.to_string()))
        })
        .collect()
}

fn projection_name(scene: &SceneArgs) -> &'static str {
    match scene.projection.unwrap_or(ProjectionArg::Panorama) {
        ProjectionArg::Panorama => "panorama",
        ProjectionArg::Camera => "camera",
        ProjectionArg::Cubemap => "cubemap",
    }
}

/// Marks the configurations no other one beats in both median time and mean relative error.
fn mark_pareto(rows: &mut [Row]) {
    let key: Vec<(Duration, f64, bool)> =
        rows.iter().map(|r| (r.median, r.errors.mean, r.errors.nan + r.errors.inf == 0)).collect();
    for (i, row) in rows.iter_mut().enumerate() {
        let (t, e, finite) = key[i];
        row.pareto = finite
            && !key
                .iter()
                .enumerate()
                .any(|(j, &(tj, ej, fj))| j != i && fj && tj <= t && ej <= e && (tj < t || ej < e));
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// The CSV: one row per configuration. Columns: the knobs (view_samples, sun_samples, …),
/// time_ms (median), time_min_ms, time_max_ms, runs, timer (`gpu_timestamps`: the passes on the
/// device; `wall`: submit → idle), mean_rel,
/// p99_rel, max_rel (relative error in linear radiance against the truth, floor 1e-4),
/// mean_abs_tonemapped (mean |Δ| after the preview's tone map), nan, inf (channels of gdsky's
/// image), pareto (1 on the front).
fn csv_text(knobs: &[Knob], rows: &[Row], runs: u32, timer: &str) -> String {
    let mut out: String = knobs.iter().map(|k| format!("{},", k.name)).collect();
    out.push_str(
        "time_ms,time_min_ms,time_max_ms,runs,timer,mean_rel,p99_rel,max_rel,mean_abs_tonemapped,nan,inf,pareto\n",
    );
    for r in rows {
        for v in &r.values {
            out.push_str(&format!("{v},"));
        }
        let e = &r.errors;
        out.push_str(&format!(
            "{:.3},{:.3},{:.3},{runs},{timer},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{}\n",
            ms(r.median),
            ms(r.min),
            ms(r.max),
            e.mean,
            e.p99,
            e.max,
            e.mean_tonemapped,
            e.nan,
            e.inf,
            u8::from(r.pareto)
        ));
    }
    out
}

/// The front as a text table, fastest first.
fn front_table(knobs: &[Knob], rows: &[Row]) -> String {
    let mut front: Vec<&Row> = rows.iter().filter(|r| r.pareto).collect();
    front.sort_by_key(|r| r.median);
    let head = knobs.iter().map(|k| k.name.as_str()).collect::<Vec<_>>().join("/");
    let mut out = format!(
        "  {head:<26} {:>9} {:>10} {:>10} {:>10} {:>12}\n",
        "time ms", "mean_rel", "p99_rel", "max_rel", "tonemapped"
    );
    for r in front {
        let label = r.values.iter().map(i32::to_string).collect::<Vec<_>>().join("/");
        let e = &r.errors;
        out.push_str(&format!(
            "  {label:<26} {:>9.2} {:>10.3e} {:>10.3e} {:>10.3e} {:>12.3e}\n",
            ms(r.median),
            e.mean,
            e.p99,
            e.max,
            e.mean_tonemapped
        ));
    }
    out
}

/// Draws mean relative error against median time, log-log: every configuration grey, the
/// Pareto front red, connected and labelled with its knob values; the configuration with the
/// uniforms' default values (`defaults`, when swept) ringed in black; `reduced` (from
/// `--skipping`: the defaults at a reduced sky resolution, labelled) blue diamonds.
fn plot(
    path: &Path,
    title: &str,
    rows: &[Row],
    knobs: &[Knob],
    defaults: &[i32],
    reduced: &[(f64, f64, String)],
    timer: &str,
) -> Result<(), String> {
    sweep::register_fonts();
    let (w, h) = (960u32, 640u32);
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    let points: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.errors.channels > 0 && r.errors.mean > 0.0)
        .map(|r| (ms(r.median).max(1e-3), r.errors.mean))
        .collect();
    let all = || points.iter().copied().chain(reduced.iter().map(|p| (p.0, p.1)));
    let bounds = |values: Vec<f64>| {
        let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = values.iter().copied().fold(0.0, f64::max);
        // Whole decades: plotters puts log-axis ticks at powers of ten and their multiples,
        // so a range inside one decade would get no tick at all.
        if lo.is_finite() && hi > 0.0 {
            // (Just beyond the decades: plotters finds the first tick with ln/ln 10, whose
            // rounding would skip a tick sitting exactly on the edge.)
            (10f64.powf(lo.log10().floor()) * 0.999, 10f64.powf((hi * 1.0001).log10().ceil()) * 1.001)
        } else {
            (1e-3, 1.0)
        }
    };
    let (x0, x1) = bounds(all().map(|p| p.0).collect());
    let (y0, y1) = bounds(all().map(|p| p.1).collect());
    let mut front: Vec<(f64, f64, String)> = rows
        .iter()
        .filter(|r| r.pareto && r.errors.mean > 0.0)
        .map(|r| {
            let label = r.values.iter().map(i32::to_string).collect::<Vec<_>>().join("/");
            (ms(r.median).max(1e-3), r.errors.mean, label)
        })
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    let knob_names = knobs.iter().map(|k| k.name.as_str()).collect::<Vec<_>>().join("/");
    let err = |e: &dyn std::fmt::Display| format!("cannot draw {}: {e}", path.display());
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc(if timer == "wall" {
                "render time, ms (median wall time, submit to idle)"
            } else {
                "render time, ms (median, GPU timestamps around the passes)"
            })
            .y_desc("mean relative error vs converged f64")
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .x_label_formatter(&|v| tick(*v))
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(|e| err(&e))?;
        let grey = RGBColor(150, 150, 150);
        chart
            .draw_series(points.iter().map(|&p| Circle::new(p, 4, grey.filled())))
            .map_err(|e| err(&e))?
            .label(format!("all {} ({knob_names})", points.len()))
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, grey.filled()));
        let red = RGBColor(200, 30, 30);
        chart
            .draw_series(LineSeries::new(front.iter().map(|p| (p.0, p.1)), red.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(format!("Pareto front ({knob_names})"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], red.stroke_width(2)));
        // The ring first, so that a front label next to it stays readable on top.
        let default_point = rows
            .iter()
            .find(|r| r.values == defaults && r.errors.mean > 0.0)
            .map(|r| (ms(r.median).max(1e-3), r.errors.mean));
        if let Some(point) = default_point {
            let label = defaults.iter().map(i32::to_string).collect::<Vec<_>>().join("/");
            chart
                .draw_series([Circle::new(point, 9, BLACK.stroke_width(2))])
                .map_err(|e| err(&e))?
                .label(format!("the shader's default ({label})"))
                .legend(|(x, y)| Circle::new((x + 10, y), 6, BLACK.stroke_width(2)));
        }
        if !reduced.is_empty() {
            let blue = RGBColor(30, 80, 200);
            let diamond = move |(x, y): (i32, i32), r: i32| {
                Polygon::new(vec![(x, y - r), (x + r, y), (x, y + r), (x - r, y)], blue.filled())
            };
            chart
                .draw_series(reduced.iter().map(|(x, y, label)| {
                    EmptyElement::at((*x, *y))
                        + diamond((0, 0), 7)
                        + Text::new(label.clone(), (8, 4), ("sans-serif", 14).into_font().color(&blue))
                }))
                .map_err(|e| err(&e))?
                .label("the default at half / quarter sky resolution (bilinear)")
                .legend(move |(x, y)| diamond((x + 10, y), 6));
        }
        // Labels alternate above-right and below-left of their points, away from a falling
        // front, so that neighbours close in time do not print over each other.
        chart
            .draw_series(front.iter().enumerate().map(|(i, (x, y, label))| {
                let at = if i % 2 == 0 { (6, -18) } else { (-8 - 7 * label.len() as i32, 6) };
                EmptyElement::at((*x, *y))
                    + Circle::new((0, 0), 5, red.filled())
                    + Text::new(label.clone(), at, ("sans-serif", 14).into_font().color(&red))
            }))
            .map_err(|e| err(&e))?;
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    sweep::write_rgb_png(path, w, h, &rgb)
}

/// An axis tick in milliseconds with as many decimals as its size needs.
fn tick(v: f64) -> String {
    let digits = if v >= 10.0 { 0 } else { (1.0 - v.log10().floor()).clamp(1.0, 6.0) as usize };
    format!("{v:.digits$}")
}

/// Where truth images are cached: `$GDSKY_CACHE_DIR`, else `$XDG_CACHE_HOME/gdsky`, else
/// `$HOME/.cache/gdsky`, else `gdsky-cache` in the temp dir.
pub fn cache_dir() -> PathBuf {
    let env = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty()).map(PathBuf::from);
    env("GDSKY_CACHE_DIR")
        .or_else(|| env("XDG_CACHE_HOME").map(|d| d.join("gdsky")))
        .or_else(|| env("HOME").map(|d| d.join(".cache").join("gdsky")))
        .unwrap_or_else(|| std::env::temp_dir().join("gdsky-cache"))
}

/// FNV-1a, 64 bits: a hash that is the same in every build (std's hashers promise no such
/// thing), for cache file names and pixel checksums.
fn fnv1a(bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes.into_iter().fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

fn checksum(pixels: &[[f32; 4]]) -> u64 {
    fnv1a(pixels.iter().flat_map(|p| p.iter().flat_map(|c| c.to_le_bytes())))
}

/// The text a cached truth is keyed by: everything that changes its pixels.
fn truth_key(params: &FreemanParams, scene: &Scene, views: &[Projection], width: u32, height: u32) -> String {
    format!(
        "gdsky truth v1: skyref f64 {}\nviews={views:?}\nsize={width}x{height}\nscene={scene:?}\nparams={params:?}\n",
        skyref_version()
    )
}

/// skyref's version, part of the key: a changed reference must not reuse old truths (the
/// bit-for-bit spot check below catches a change without a version bump too).
fn skyref_version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

/// The truth pixel at column `x` of the strip and row `y`, computed now (for the spot check).
fn truth_pixel(
    params: &FreemanParams,
    scene: &Scene,
    views: &[Projection],
    w: u32,
    h: u32,
    x: u32,
    y: u32,
) -> [f32; 4] {
    let view = views[((x / w) as usize).min(views.len() - 1)];
    let d = skyref::f64::eyedir(scene, view, x % w, y, w, h);
    let c = skyref::f64::sky_color(params, scene, d);
    [c.x as f32, c.y as f32, c.z as f32, 0.0]
}

/// Largest cache key file read (a key is a few hundred bytes).
const MAX_KEY_BYTES: u64 = 64 << 10;

/// The converged truth of the scene, from the cache when a valid entry exists; else computed
/// (rows in parallel) and stored. The string says which.
fn cached_truth(
    dir: &Path,
    params: &FreemanParams,
    scene: &Scene,
    views: &[Projection],
    width: u32,
    height: u32,
) -> (Image, String) {
    let key = truth_key(params, scene, views, width, height);
    let stem = format!("truth-{:016x}", fnv1a(key.bytes()));
    let exr = dir.join(format!("{stem}.exr"));
    let key_path = dir.join(format!("{stem}.key"));
    let strip_w = width * views.len() as u32;
    let spots =
        [(strip_w / 2, height / 2), (strip_w / 4, height / 2 - height.min(2) / 2), (0, 0), (strip_w - 1, height - 1)];
    let cached = (|| -> Result<Image, String> {
        if !key_path.exists() {
            return Err("not cached yet".into());
        }
        let stored = skyrun::safe_io::read_limited(&key_path, MAX_KEY_BYTES).map_err(|e| e.to_string())?;
        let stored = String::from_utf8(stored).map_err(|_| "the key is not UTF-8")?;
        let (stored_key, sum) = stored.rsplit_once("checksum=").ok_or("no checksum")?;
        if stored_key != key {
            return Err("the key differs (hash collision or another version)".into());
        }
        let image = skyrun::read_exr(&exr).map_err(|e| e.to_string())?;
        if (image.width, image.height) != (strip_w, height) {
            return Err("wrong size".into());
        }
        if format!("{:016x}", checksum(&image.pixels)) != sum.trim() {
            return Err("the pixels do not match their checksum".into());
        }
        for &(x, y) in &spots {
            let now = truth_pixel(params, scene, views, width, height, x, y);
            let then = image.pixels[(y * strip_w + x) as usize];
            if now.map(f32::to_bits) != then.map(f32::to_bits) {
                return Err(format!("pixel ({x}, {y}) recomputed differs: {now:?} vs {then:?}"));
            }
        }
        Ok(image)
    })();
    match cached {
        Ok(image) => (image, format!("truth: cached {}", exr.display())),
        Err(why) => {
            let started = std::time::Instant::now();
            let rendered: Vec<Vec<[f32; 4]>> = views
                .iter()
                .map(|&view| sweep::narrow(&skyref::f64::render(params, scene, view, width, height)))
                .collect();
            // `strip` only fails for an empty image, which SceneArgs rules out.
            let image = strip(rendered, width, height).unwrap_or_else(|_| Image {
                width: strip_w,
                height,
                pixels: vec![[0.0; 4]; (strip_w * height) as usize],
            });
            let elapsed = started.elapsed();
            let stored = skyrun::safe_io::create_output_dir(dir)
                .map_err(|e| format!("{}: {e}", dir.display()))
                .and_then(|()| skyrun::write_exr(&exr, &image).map_err(|e| e.to_string()))
                .and_then(|()| {
                    let text = format!("{key}checksum={:016x}\n", checksum(&image.pixels));
                    super::write_file(&key_path, text.as_bytes())
                });
            let note = match stored {
                Ok(()) => format!("truth: computed in {elapsed:.1?} ({why}), cached as {}", exr.display()),
                Err(e) => format!("truth: computed in {elapsed:.1?}; not cached ({e})"),
            };
            (image, note)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knobs_replace_or_extend_the_defaults() {
        let k = knobs(&["view_samples=4,8".into(), "sun_samples=2".into()]).unwrap();
        assert_eq!(combinations(&k), vec![vec![4, 2], vec![8, 2]]);
        assert_eq!(combinations(&knobs(&[]).unwrap()).len(), 32);
        assert!(knobs(&["sun_intensity=1".into()]).is_err());
        assert!(knobs(&["view_samples=a".into()]).is_err());
    }

    #[test]
    fn pareto_front_excludes_dominated_points() {
        let row = |t: u64, e: f64| Row {
            values: vec![],
            median: Duration::from_millis(t),
            min: Duration::ZERO,
            max: Duration::ZERO,
            errors: ErrorStats { mean: e, channels: 1, ..ErrorStats::default() },
            pareto: false,
        };
        let mut rows = vec![row(10, 0.5), row(20, 0.1), row(20, 0.3), row(30, 0.1), row(5, 0.9)];
        mark_pareto(&mut rows);
        let front: Vec<bool> = rows.iter().map(|r| r.pareto).collect();
        assert_eq!(front, vec![true, true, false, false, true]);
    }
}
