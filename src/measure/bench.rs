//! `gdsky bench [FILE…]`: render time against error for Freeman-compatible skies.
//!
//! Sweeps the int uniforms each shader reads (`view_samples` × `sun_samples` by default, and any
//! other given with `--knob`), renders each configuration on the adapter, times it, and measures
//! it against the truth of the same scene. Writes `bench.csv` and `bench.png` (error against
//! time, log-log, each shader in its own colour with its Pareto front) and prints each shader's
//! front.
//!
//! **Several shaders.** `gdsky bench A.gdshader B.gdshader …` puts them on one chart: every
//! shader is Freeman-compatible, so one material (skyref's parameters) drives them all and one
//! truth serves them all. A shader sweeps only the knobs it reads
//! ([`gdsky_naga::reflect::uniforms_read`]): `freeman_fast` declares `sun_samples` for material
//! compatibility but never reads it, and sweeping it would time the same image four times. A
//! shader that reads only `view_samples` gets a finer default sweep (`VIEW_ONLY_SAMPLES`), since
//! it has one dimension to spend its configurations on. All configurations of all shaders are
//! timed in the same interleaved rounds, so the ratios between shaders come from one run on one
//! machine state. After the fronts, each shader after the first is compared with the first's
//! default configuration (the uniforms' values: skyref's defaults with the scene's and `--set`
//! over them): its most accurate configuration at no more than that time, and its fastest
//! configuration at no more than that mean, p99 and max error.
//!
//! **The truth** is [`skyref::truth`] by default: the integrals of the Freeman model evaluated to
//! about 1e-7 (breakpoints, graded Gauss–Legendre depths, Richardson extrapolation on the view
//! ray). It does not depend on the sample counts, so every configuration of every shader is
//! measured against one image. `--truth samples` (implied by `--truth-samples VIEW,SUN`) is the
//! older truth, the shader's own sums in f64 at many samples ([`skyref::converged`], default
//! 1024/256): cheaper, but still ~6e-4 mean and ~5e-3 max off the integral, which would hide the
//! error of a shader better than that.
//!
//! Timing is the passes' own time from GPU timestamp queries where the adapter has them
//! ([`skyrun::Rendered::gpu_time`]; lavapipe does), else wall time from submit to the device
//! going idle ([`skyrun::Rendered::gpu_wait`]); the CSV's `timer` column says which. Each time is
//! the median of `--runs` renders after one warm-up render (which also gives the pixels
//! measured).
//!
//! The truth is cached as an EXR (see [`cache_dir`]), keyed by the scene, the image size, which
//! truth and its settings, and every uniform; an entry is used only when its key file matches
//! exactly, its pixels match the checksum recorded with them, and a few pixels recomputed now
//! match it bit for bit. Anything else is recomputed.

use super::freeman::{TruthMode, cache_dir, cached_truth};
use super::knobs::{self, Knob, combinations};
use super::skipping::SkippingOptions;
use super::stats::{self, ErrorStats};
use super::{any, pareto, plot};
use crate::engine::{self, Error, Progress, Setup, Sky};
use crate::scene::SceneFile;
use plotters::prelude::*;
use skyref::converged::Converged;
use skyref::truth::Truth;
use skyref::{FreemanParams, UniformMut};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The default sweep of `view_samples`.
const VIEW_SAMPLES: [i32; 8] = [4, 8, 12, 16, 24, 32, 48, 64];
/// The default sweep of `sun_samples`.
const SUN_SAMPLES: [i32; 4] = [2, 4, 8, 16];
/// The default sweep of `view_samples` for a shader that reads no other knob: as many
/// configurations as fit the same decade and a half, about √2 apart.
const VIEW_ONLY_SAMPLES: [i32; 11] = [2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64];

/// What [`bench()`] measures and how: the CLI's `gdsky bench` flags as values.
#[derive(Debug)]
pub struct BenchOptions {
    /// The shaders on one chart (the first is the one the others are compared with); `None`
    /// is the bundled Freeman sky. Each Freeman-compatible, or a single shader that is not
    /// (measured against its own sampling truth).
    pub shaders: Vec<Option<PathBuf>>,
    /// The scene file (or Godot material) the first shader came from: its uniforms for
    /// `bake_scene`, its textures, its `overrides`.
    pub scene_file: Option<SceneFile>,
    /// The scene, projection, size, uniform values and textures of every render.
    pub setup: Setup,
    /// Bake every uniform the scene file fixes (and every set value) into the shader as
    /// constants, except the swept knobs; with no scene file, every uniform but the knobs at
    /// its default.
    pub bake_scene: bool,
    /// Scalar uniforms emitted as pipeline-overridable constants (with the scene file's).
    pub overrides: Vec<String>,
    /// Folder for bench.csv and bench.png (and skipping.csv), created if missing.
    pub out_dir: PathBuf,
    /// Timed renders per configuration (1 to 1000) after a warm-up; the median is reported.
    pub runs: u32,
    /// Knob sweeps `NAME=V1,V2,…` replacing or extending the defaults.
    pub knobs: Vec<String>,
    /// skyref's truth of a Freeman-compatible shader ([`TruthChoice`]); `None`: the integral,
    /// or the samples when `truth_samples` is given.
    pub truth: Option<TruthChoice>,
    /// Sample counts (view, sun) of the `samples` truth.
    pub truth_samples: Option<(i32, i32)>,
    /// Where truth images are cached ([`crate::measure::freeman::cache_dir`] when `None`).
    pub cache_dir: Option<PathBuf>,
    /// The sampling truth of a shader that is not Freeman-compatible.
    pub sampling: SamplingTruth,
    /// Also time what the sky can skip ([`crate::measure::skipping`]).
    pub skipping: Option<SkippingOptions>,
}

impl Default for BenchOptions {
    /// The bundled Freeman sky, its default sweeps, 5 runs, the integral truth, into `out/bench`.
    fn default() -> Self {
        Self {
            shaders: vec![None],
            scene_file: None,
            setup: Setup::default(),
            bake_scene: false,
            overrides: Vec::new(),
            out_dir: PathBuf::from("out/bench"),
            runs: 5,
            knobs: Vec::new(),
            truth: None,
            truth_samples: None,
            cache_dir: None,
            sampling: SamplingTruth::default(),
            skipping: None,
        }
    }
}

/// The sampling truth's settings, shared by `bench` and `tune` (shaders that are not
/// Freeman-compatible): the shader itself at converged knobs, in f64.
#[derive(Clone, Debug, Default)]
pub struct SamplingTruth {
    /// Raise each quality knob (doubling) until doubling it changes the f64 image by a mean
    /// relative error below this [default: 1e-3].
    pub converge_tol: Option<f64>,
    /// Samples per pixel side of the truth (1 to 8): above 1 each pixel's area average.
    pub supersample: Option<u32>,
    /// Also sweep the resolution the sky is shaded at (`full,half,quarter`, any of them).
    pub sky_resolution: Option<String>,
}

impl SamplingTruth {
    /// The convergence's stopping rule.
    pub fn limits(&self) -> any::Limits {
        any::Limits {
            tolerance: self.converge_tol.unwrap_or(CONVERGE_TOL),
            max_value: MAX_ANY_KNOB,
            max_doublings: MAX_DOUBLINGS,
            supersample: self.supersample.unwrap_or(1),
        }
    }

    /// The sky-resolution dimension asked for, if any.
    pub fn sky_resolution_knob(&self) -> Result<Option<Knob>, Error> {
        self.sky_resolution
            .as_deref()
            .map(|text| Knob::sky_resolutions(text).map_err(|e| Error::input(format!("--sky-resolution: {e}"))))
            .transpose()
    }
}

/// skyref's truth for a Freeman-compatible shader.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TruthChoice {
    /// skyref::truth: the model's integrals (Richardson-extrapolated), to about 1e-7.
    Integral,
    /// skyref::converged: the shader's sums in f64 at the truth's sample counts.
    Samples,
}

impl TruthChoice {
    /// The names `--truth` takes.
    pub const NAMES: [&'static str; 2] = ["integral", "samples"];
}

impl std::str::FromStr for TruthChoice {
    type Err = String;

    /// `integral` or `samples`.
    fn from_str(name: &str) -> Result<Self, String> {
        match name {
            "integral" => Ok(TruthChoice::Integral),
            "samples" => Ok(TruthChoice::Samples),
            _ => Err(format!("`{name}` is no truth; expected one of: integral, samples")),
        }
    }
}

/// What [`bench()`] found: the printed report, the files it wrote, and one row per configuration.
#[derive(Clone, Debug)]
pub struct BenchReport {
    /// The report the CLI prints: the fronts, the comparisons, what was written.
    pub text: String,
    /// `bench.csv`.
    pub csv: PathBuf,
    /// `bench.png`.
    pub plot: PathBuf,
    /// Every configuration measured, in the CSV's order.
    pub configurations: Vec<Configuration>,
}

/// One measured configuration of one shader.
#[derive(Clone, Debug)]
pub struct Configuration {
    /// The shader's name (its file stem).
    pub shader: String,
    /// The knobs' values, `view_samples=12, sun_samples=8`.
    pub label: String,
    /// The median render time.
    pub time: Duration,
    /// Its error against the truth.
    pub errors: ErrorStats,
    /// Whether it is on its shader's Pareto front.
    pub pareto: bool,
}

/// Largest sample count of the truth (`--truth-samples`): 16× the default view samples; the f64
/// truth's time grows with the product of the two.
pub const MAX_TRUTH_SAMPLES: i32 = 16384;
/// Largest value of a swept int uniform (`--knob`): they are sample counts (64 × 16 is the
/// default sweep's largest).
const MAX_KNOB: i32 = 4096;

/// The truth from `--truth` and `--truth-samples`; asking for the integral with sample counts
/// is wrong input (the counts would be ignored).
fn truth_from_args(truth: Option<TruthChoice>, samples: Option<(i32, i32)>) -> Result<TruthMode, String> {
    let converged = |(view_samples, sun_samples)| Converged { view_samples, sun_samples };
    match (truth, samples) {
        (Some(TruthChoice::Integral), Some(_)) => {
            Err("--truth-samples sets the `samples` truth; it cannot go with --truth integral".into())
        }
        (None | Some(TruthChoice::Integral), None) => Ok(TruthMode::Integral(Truth::default())),
        (None | Some(TruthChoice::Samples), Some(counts)) => Ok(TruthMode::Samples(converged(counts))),
        (Some(TruthChoice::Samples), None) => Ok(TruthMode::Samples(Converged::default())),
    }
}

/// One image per view (one for a panorama or camera, six cube faces).
type ViewImages = Vec<Vec<[f32; 4]>>;

/// One configuration's measurements.
struct Row {
    /// Which shader ([`Subject`] index).
    subject: usize,
    values: Vec<i32>,
    median: Duration,
    min: Duration,
    max: Duration,
    errors: ErrorStats,
    pareto: bool,
}

/// One shader of the bench and its sweep.
struct Subject {
    /// Its name in the CSV's `shader` column, the chart's legend and the comparisons: the file
    /// stem (the path when two stems are equal).
    name: String,
    /// The file; `None`: the bundled Freeman sky.
    file: Option<PathBuf>,
    loaded: Sky,
    /// The knobs it sweeps (those it reads).
    knobs: Vec<Knob>,
    /// Its configurations: values of `knobs`.
    configs: Vec<Vec<i32>>,
    /// The knobs' values in the base parameters: its default configuration.
    defaults: Vec<i32>,
}

impl Subject {
    /// `values` as `view_samples=12, sun_samples=8` (`its only configuration` without knobs).
    fn label(&self, values: &[i32]) -> String {
        if self.knobs.is_empty() {
            return "its only configuration".into();
        }
        self.knobs.iter().zip(values).map(|(k, v)| format!("{}={v}", k.name)).collect::<Vec<_>>().join(", ")
    }
}

/// The knobs: the defaults, each replaced or extended by a `--knob`.
fn knobs(args: &[String]) -> Result<Vec<Knob>, String> {
    let mut knobs =
        vec![Knob::uniform("view_samples", VIEW_SAMPLES.to_vec()), Knob::uniform("sun_samples", SUN_SAMPLES.to_vec())];
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
            None => knobs.push(Knob::uniform(name, values)),
        }
    }
    Ok(knobs)
}

/// The knobs a shader sweeps: those of `all` it reads. When that leaves `view_samples` alone
/// and no `--knob` set its values (`given`), its finer default sweep.
fn knobs_read(all: &[Knob], read: &BTreeSet<String>, given: &[String]) -> Vec<Knob> {
    let mut kept: Vec<Knob> = all.iter().filter(|k| read.contains(&k.name)).cloned().collect();
    if let [only] = kept.as_mut_slice()
        && only.name == "view_samples"
        && !given.iter().any(|g| g == "view_samples")
    {
        only.values = VIEW_ONLY_SAMPLES.to_vec();
    }
    kept
}

/// The knob names `--knob` gave.
fn given_knobs(args: &[String]) -> Vec<String> {
    args.iter().filter_map(|a| a.split_once('=')).map(|(n, _)| n.trim().to_string()).collect()
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

/// Short, unique names for the shaders: file stems, or the full path where two stems are equal.
fn subject_names(files: &[Option<PathBuf>]) -> Vec<String> {
    let stem = |f: &Option<PathBuf>| match f {
        Some(p) => p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| p.display().to_string()),
        None => "freeman_sky (bundled)".into(),
    };
    let stems: Vec<String> = files.iter().map(stem).collect();
    files
        .iter()
        .zip(&stems)
        .map(|(f, s)| {
            if stems.iter().filter(|t| *t == s).count() > 1 {
                f.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| s.clone())
            } else {
                s.clone()
            }
        })
        .collect()
}

/// The pipeline constants of a Freeman-compatible shader's overrides from skyref's parameters,
/// rounded to f32 as the material block would hold them.
fn constants(loaded: &Sky, params: &FreemanParams) -> Vec<(String, f64)> {
    let values = skyrun::freeman_values(params);
    loaded
        .overrides()
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
    fn index(&mut self, loaded: &Sky, gpu: &skyrun::Gpu, constants: Vec<(String, f64)>) -> Result<usize, Error> {
        if let Some(i) = self.shaders.iter().position(|(c, _)| *c == constants) {
            return Ok(i);
        }
        let shader = loaded.compile(gpu)?.with_constants(constants.clone());
        self.shaders.push((constants, shader));
        Ok(self.shaders.len() - 1)
    }
}

/// One configuration of one shader, as the timing loop sees it.
struct Entry {
    subject: usize,
    values: Vec<i32>,
    material: Vec<u8>,
    /// Index into the subject's compiled shaders.
    shader: usize,
    /// The truth's parameters ([`TruthMode::params`]).
    truth_params: FreemanParams,
}

/// Bakes what `--bake-scene` asks into `loaded` and makes `override_names` overrides: the
/// values the material would carry (skyref's defaults with the scene's uniforms and --set over
/// them), so the truth still matches: with a scene file, the uniforms it fixes and those --set;
/// without one, every uniform; never a knob.
fn specialize(
    loaded: &mut Sky,
    options: &BenchOptions,
    cli_sets: &[(String, String)],
    base: &FreemanParams,
    all_knobs: &[Knob],
    override_names: &[String],
    progress: &dyn Progress,
) -> Result<(), Error> {
    let (bake_scene, scene_file) = (options.bake_scene, options.scene_file.as_ref());
    let mut baked = std::collections::HashMap::new();
    if bake_scene {
        let fixed: Vec<String> = match scene_file {
            Some(file) => file
                .uniform_pairs()
                .into_iter()
                .map(|(n, _)| n)
                .chain(cli_sets.iter().map(|(n, _)| n.clone()))
                .collect(),
            None => engine::freeman_names().into_iter().map(String::from).collect(),
        };
        baked = skyrun::freeman_values(base)
            .into_iter()
            .filter(|(name, _)| {
                fixed.iter().any(|f| f == name)
                    && !all_knobs.iter().any(|k| k.name == *name)
                    && !override_names.iter().any(|o| o == name)
            })
            .map(|(name, value)| (name.to_string(), value.to_string()))
            .collect();
        let mut names: Vec<&String> = baked.keys().collect();
        names.sort();
        note!(
            progress,
            "baked {} uniform(s): {}",
            names.len(),
            names.iter().map(|n| n.as_str()).collect::<Vec<_>>().join(", ")
        );
    }
    if bake_scene || !override_names.is_empty() {
        loaded.respecialize(baked, override_names)?;
    }
    Ok(())
}

/// Benchmarks render time against error (see the module documentation): writes bench.csv and
/// bench.png (and skipping.csv) into `options.out_dir` and returns the report.
pub fn bench(options: &BenchOptions, progress: &dyn Progress) -> Result<BenchReport, Error> {
    let files = if options.shaders.is_empty() { vec![None] } else { options.shaders.clone() };
    let scene_file = options.scene_file.as_ref();
    if let Some(file) = scene_file {
        engine::warn_unapplied(file, "bench", progress);
    }
    let setup = &options.setup;
    let mut out = String::new();
    // A shader skyref does not model is measured against itself: the sampling truth.
    if let Some(file) = files[0].as_deref()
        && !is_freeman_compatible(file)
    {
        if files.len() > 1 {
            return Err(Error::input(format!(
                "{}: several shaders on one chart need one truth: each must be Freeman-compatible (bench one \
                 other shader at a time)",
                file.display()
            )));
        }
        if options.truth.is_some() || options.truth_samples.is_some() {
            return Err(Error::input(
                "--truth/--truth-samples choose skyref's truth, for Freeman-compatible shaders only",
            ));
        }
        if options.skipping.is_some() || options.bake_scene || !options.overrides.is_empty() {
            return Err(Error::input(
                "--skipping, --bake-scene and --override apply to Freeman-compatible shaders only (for now)",
            ));
        }
        return bench_any(options, file, progress);
    }
    if !setup.textures.is_empty() || scene_file.is_some_and(|s| !s.textures.is_empty()) {
        return Err(Error::input(
            "--texture and a scene's [textures] apply to shaders that are not Freeman-compatible; a Freeman-compatible \
             shader's tables (freeman_lut's transmittance_table) are baked automatically",
        ));
    }
    if options.sampling.converge_tol.is_some() || options.sampling.supersample.is_some() {
        return Err(Error::input(
            "--converge-tol and --truth-supersample set the sampling truth of shaders that are not Freeman-compatible",
        ));
    }
    if options.sampling.sky_resolution.is_some() {
        return Err(Error::input(
            "--sky-resolution sweeps shaders that are not Freeman-compatible; for the Freeman sky, --skipping times \
             the half and quarter resolutions",
        ));
    }
    let truth_mode = truth_from_args(options.truth, options.truth_samples).map_err(Error::input)?;
    let (views, width, height) = (setup.views()?, setup.width, setup.height);
    let mut base = FreemanParams::default();
    engine::set_freeman(&mut base, &setup.sets).map_err(Error::input)?;
    let all_knobs = knobs(&options.knobs).map_err(Error::input)?;
    let given = given_knobs(&options.knobs);
    engine::check_output_dir(&options.out_dir, true, &["bench.csv", "bench.png"])?;
    let cli_sets = setup.sets.clone();
    let override_names = engine::override_names(scene_file, &options.overrides);
    engine::check_override_conflicts(&override_names, scene_file, |n| {
        if all_knobs.iter().any(|k| k.name == n) {
            None
        } else {
            engine::bake_reason(n, scene_file, &cli_sets, options.bake_scene)
        }
    })?;

    let names = subject_names(&files);
    let mut subjects = Vec::with_capacity(files.len());
    for (file, name) in files.iter().zip(names) {
        let mut loaded = Sky::load_freeman(file.as_deref(), progress)?;
        loaded.check_scene(scene_file)?;
        // Which knobs the shader reads, from the generic module (before any baking).
        let read = gdsky_naga::reflect::uniforms_read(&loaded.lowered);
        let knobs = knobs_read(&all_knobs, &read, &given);
        let skipped: Vec<&str> =
            all_knobs.iter().filter(|k| !read.contains(&k.name)).map(|k| k.name.as_str()).collect();
        if !skipped.is_empty() {
            note!(progress, "note: {name} declares but never reads {}: not swept", skipped.join(", "));
        }
        specialize(&mut loaded, options, &cli_sets, &base, &all_knobs, &override_names, progress)?;
        // freeman_lut's table from the bench's base values (no knob shapes it).
        let base_values: Vec<(String, String)> =
            skyrun::freeman_values(&base).into_iter().map(|(n, v)| (n.to_string(), v.to_string())).collect();
        if let Some(note) = loaded.bake_tables(&base_values).map_err(Error::input)? {
            note!(progress, "{name}: {note}");
        }
        let mut configs = combinations(&knobs);
        let defaults: Vec<i32> = knobs.iter().filter_map(|k| int_value(&base, &k.name)).collect();
        // The comparisons need the first shader's default measured: added when the sweep
        // misses it.
        if subjects.is_empty() && files.len() > 1 && !configs.contains(&defaults) {
            configs.push(defaults.clone());
        }
        if configs.is_empty() {
            return Err(Error::input(format!("{name}: the sweep is empty")));
        }
        subjects.push(Subject { name, file: file.clone(), loaded, knobs, configs, defaults });
    }
    if !override_names.is_empty() {
        note!(progress, "overrides: {}", override_names.join(", "));
    }
    let shader_names = subjects.iter().map(|s| s.name.as_str()).collect::<Vec<_>>().join(" vs ");
    let gpu = engine::open_gpu(progress)?;
    let adapter = gpu.adapter_info();
    let timer = if gpu.has_timestamps() { "gpu_timestamps" } else { "wall" };
    let scene = setup.scene;
    let builtins = setup.builtins();

    // Every configuration of every shader, in one list: the timing rounds go over all of them.
    let mut entries = Vec::new();
    let mut compiled: Vec<Compiled> = Vec::with_capacity(subjects.len());
    for (i, s) in subjects.iter().enumerate() {
        let mut c = Compiled { shaders: Vec::new() };
        for values in &s.configs {
            let params = with_knobs(&base, &s.knobs, values).map_err(Error::input)?;
            let material = s.loaded.freeman_material(&params).map_err(Error::input)?;
            // Each configuration's pipelines carry its override values: a module compiled per
            // distinct set (before any timing), so switching configurations in the round-robin
            // rebuilds nothing.
            let shader = c.index(&s.loaded, &gpu, constants(&s.loaded, &params))?;
            entries.push(Entry {
                subject: i,
                values: values.clone(),
                material,
                shader,
                truth_params: truth_mode.params(&params),
            });
        }
        compiled.push(c);
    }
    let base_shader = compiled[0].index(&subjects[0].loaded, &gpu, constants(&subjects[0].loaded, &base))?;

    progress.start(1 + entries.len() as u64 * (1 + u64::from(options.runs)));
    progress.message(&format!("truth: {} (cached after the first run)", truth_mode.describe()));
    let cache = options.cache_dir.clone().unwrap_or_else(cache_dir);
    let mut truths: Vec<(FreemanParams, Vec<[f64; 4]>)> = Vec::new();
    for e in &entries {
        // Only knobs other than the sample counts change the truth; most sweeps share one.
        if truths.iter().any(|(p, _)| *p == e.truth_params) {
            continue;
        }
        let (image, note) = cached_truth(&cache, &truth_mode, &e.truth_params, &scene, &views, width, height);
        (note!(progress, "{note}"));
        truths.push((e.truth_params, stats::widen(&image.pixels)));
    }
    progress.step();

    let render_all = |shader: &skyrun::SkyShader, material: &[u8]| -> Result<(ViewImages, Duration), Error> {
        let mut images = Vec::with_capacity(views.len());
        let mut time = Duration::ZERO;
        for &view in &views {
            let r = shader.render(&gpu, view, width, height, &builtins, material).map_err(|err| {
                (note!(progress, "error: {err}"));
                Error::input("failed")
            })?;
            // The passes' own time from GPU timestamps where the device has them, else the
            // host's wall time from submit to idle.
            time += r.gpu_time.unwrap_or(r.gpu_wait);
            images.push(r.pixels);
        }
        Ok((images, time))
    };
    let shader_of = |e: &Entry| &compiled[e.subject].shaders[e.shader].1;
    // First every configuration's warm-up render, which pays for the driver's pipeline
    // compilation; its pixels are the ones measured (every render of a configuration gives the
    // same pixels).
    let mut errors = Vec::with_capacity(entries.len());
    for e in &entries {
        let s = &subjects[e.subject];
        progress.message(&format!("{}: {}: warm-up render and error", s.name, s.label(&e.values)));
        let (images, _) = render_all(shader_of(e), &e.material)?;
        let image = skyrun::Image::side_by_side(images, width, height).map_err(Error::input)?;
        let truth = &truths.iter().find(|(p, _)| *p == e.truth_params).ok_or(Error::input("failed"))?.1;
        errors.push(stats::error_stats(&image.pixels, truth));
        progress.step();
    }
    // Then the timed renders, round-robin over the configurations of all shaders: a burst of
    // load from elsewhere on the machine spreads over all of them instead of spoiling one's
    // median, and the shaders' ratios come from the same rounds.
    let mut times = vec![Vec::with_capacity(options.runs as usize); entries.len()];
    for run in 0..options.runs {
        progress.message(&format!("timing: round {} of {} on {}", run + 1, options.runs, adapter.name));
        for (e, times) in entries.iter().zip(&mut times) {
            times.push(render_all(shader_of(e), &e.material)?.1);
            progress.step();
        }
    }
    let mut rows: Vec<Row> = entries
        .iter()
        .zip(errors)
        .zip(&mut times)
        .map(|((e, errors), times)| {
            times.sort();
            // The median; of an even count, the mean of the middle two.
            let n = times.len();
            let median = (times[(n - 1) / 2] + times[n / 2]) / 2;
            Row {
                subject: e.subject,
                values: e.values.clone(),
                median,
                min: times[0],
                max: times[n - 1],
                errors,
                pareto: false,
            }
        })
        .collect();
    progress.finish();
    // Each shader's own front: the rows are grouped by shader, in order.
    for i in 0..subjects.len() {
        let start = rows.iter().position(|r| r.subject == i).unwrap_or(rows.len());
        let end = start + rows[start..].iter().take_while(|r| r.subject == i).count();
        mark_pareto(&mut rows[start..end]);
    }

    let csv_path = options.out_dir.join("bench.csv");
    let csv = csv_text(&subjects, &rows, options.runs, timer);
    engine::create_output_dir(&options.out_dir)?;
    engine::write_file(&csv_path, csv.as_bytes()).map_err(Error::environment)?;
    let png_path = options.out_dir.join("bench.png");

    say!(
        out,
        "gdsky bench: {}, {} configurations, {width}x{height} {}",
        subjects
            .iter()
            .map(|s| s.file.as_ref().map(|f| f.display().to_string()).unwrap_or(engine::BUNDLED_NAME.into()))
            .collect::<Vec<_>>()
            .join(", "),
        rows.len(),
        setup.projection.name()
    );
    say!(out, "adapter  {adapter}");
    say!(
        out,
        "timer    {}, median of {} after a warm-up, all shaders in the same interleaved rounds",
        if timer == "wall" {
            "wall time submit → idle (the adapter has no timestamp queries)"
        } else {
            "GPU timestamp queries around the passes"
        },
        options.runs
    );
    say!(
        out,
        "truth    {}; error = |gdsky − truth| / max(|truth|, {:e}) over RGB",
        truth_mode.describe(),
        stats::FLOOR
    );
    for (i, s) in subjects.iter().enumerate() {
        let swept = if s.knobs.is_empty() {
            "no knob".to_string()
        } else {
            s.knobs.iter().map(|k| k.name.as_str()).collect::<Vec<_>>().join(" × ")
        };
        say!(out, "Pareto front of {} ({swept}; no other configuration of it both faster and more accurate):", s.name);
        let mine: Vec<&Row> = rows.iter().filter(|r| r.subject == i).collect();
        out.push_str(&front_table(&s.knobs, &mine));
    }
    for line in comparisons(&subjects, &rows) {
        say!(out, "{line}");
    }
    let mut reduced = Vec::new();
    if let Some(skipping) = &options.skipping {
        let first = &subjects[0];
        let base_material = first.loaded.freeman_material(&base).map_err(Error::input)?;
        // The `uniforms` rows: the named overrides, else the swept knobs, as a generic module
        // (material block), baked into constants, and as overrides, each at the base values.
        let varied: Vec<String> = if override_names.is_empty() {
            first.knobs.iter().map(|k| k.name.clone()).collect()
        } else {
            override_names.clone()
        };
        let mut modules = Vec::new();
        for kind in ["generic", "baked", "overrides"] {
            let mut m = Sky::load_freeman(first.file.as_deref(), progress)?;
            match kind {
                "baked" => {
                    let values = skyrun::freeman_values(&base)
                        .into_iter()
                        .filter(|(n, _)| varied.iter().any(|v| v == n))
                        .map(|(n, v)| (n.to_string(), v.to_string()))
                        .collect();
                    m.respecialize(values, &[])?;
                }
                "overrides" => m.respecialize(Default::default(), &varied)?,
                _ => {}
            }
            let mat = m.freeman_material(&base).map_err(Error::input)?;
            let s = m.compile(&gpu)?.with_constants(constants(&m, &base));
            modules.push((kind, s, mat));
        }
        let base_truth = truth_mode.params(&base);
        let truth = truths.iter().find(|(p, _)| *p == base_truth).or(truths.first()).ok_or(Error::input("failed"))?;
        let cx = super::skipping::Context {
            gpu: &gpu,
            shader: &compiled[0].shaders[base_shader].1,
            name: first.name.clone(),
            modules: modules.iter().map(|(k, s, m)| (*k, s, m.as_slice())).collect(),
            views: &views,
            width,
            height,
            builtins: &builtins,
            material: &base_material,
            truth: &truth.1,
            runs: options.runs,
        };
        let rows = super::skipping::run(&cx, skipping)?;
        say!(out, "skipping ({}'s defaults; occluder ratio = time / time at 0 %, resolution = speed-up):", first.name);
        out.push_str(&super::skipping::table(&rows));
        say!(
            out,
            "uniforms rows: {} read from the material block (generic), baked into constants (baked), as \
             pipeline-overridable constants (overrides); ratio = speed-up over generic",
            varied.join(", ")
        );
        let path = options.out_dir.join("skipping.csv");
        engine::write_file(&path, super::skipping::csv(&rows).as_bytes())?;
        say!(out, "wrote    {}", path.display());
        reduced = reduced_points(&rows);
    }
    let title = format!("{shader_names} on {}: {}x{} {}", adapter.name, width, height, setup.projection.name());
    plot(&png_path, &title, &subjects, &rows, &reduced, timer, &truth_mode.short())?;
    say!(out, "wrote    {} and {}", csv_path.display(), png_path.display());
    Ok(report(out, csv_path, png_path, &subjects, &rows))
}

/// The report of a finished bench.
fn report(text: String, csv: PathBuf, plot: PathBuf, subjects: &[Subject], rows: &[Row]) -> BenchReport {
    let configurations = rows
        .iter()
        .map(|r| Configuration {
            shader: subjects[r.subject].name.clone(),
            label: subjects[r.subject].label(&r.values),
            time: r.median,
            errors: r.errors,
            pareto: r.pareto,
        })
        .collect();
    BenchReport { text, csv, plot, configurations }
}

/// Whether FILE is Freeman-compatible (skyref is its truth). A shader that does not read or
/// check counts as compatible here, so the Freeman path reports its diagnostics as before.
fn is_freeman_compatible(file: &Path) -> bool {
    match gdresource::check_file(file) {
        Ok(front) => front.shader.as_ref().is_none_or(crate::measure::freeman::compatible),
        Err(_) => true,
    }
}

/// Default of `--converge-tol`.
pub const CONVERGE_TOL: f64 = 1e-3;
/// Most doublings of one knob while converging (64×).
pub const MAX_DOUBLINGS: u32 = 6;
/// Largest value a knob is raised to while converging (and given with `--knob`).
pub const MAX_ANY_KNOB: i32 = 4096;

/// The knobs of a shader that is not Freeman-compatible: its quality knobs (loop bounds) with
/// their default sweeps, each replaced or extended by a `--knob` (any int uniform or int const).
pub fn any_knobs(sky: &any::Sky, given: &[String]) -> Result<Vec<Knob>, String> {
    let mut knobs: Vec<Knob> = sky
        .quality_knobs()
        .iter()
        .map(|d| Knob { name: d.name.clone(), values: any::default_sweep(d.default, d.range), kind: d.kind })
        .collect();
    for arg in given {
        let (name, values) = crate::measure::knobs::parse_values(arg, 1, MAX_ANY_KNOB)?;
        let kind = sky.kind_of(&name);
        // A const must exist and be an int: specializing at its first value says so now.
        sky.variant(&[(name.clone(), values[0])]).map_err(|e| format!("`--knob {arg}`: {e}"))?;
        match knobs.iter_mut().find(|k| k.name == name) {
            Some(k) => k.values = values,
            None => knobs.push(Knob { name, values, kind }),
        }
    }
    Ok(knobs)
}

/// Prints the convergence of the sampling truth as a table.
pub fn convergence_table(c: &any::Converged) -> String {
    let mut out = format!(
        "  {:<20} {:>7} {:>7} {:>11} {:>11} {:>11} {:>12}\n",
        "knob", "from", "to", "mean Δ", "p99 Δ", "max Δ", "f32 vs f64"
    );
    for s in &c.steps {
        let (from, to) =
            if s.knob == "all" { ("×1".into(), "×2".into()) } else { (s.from.to_string(), s.to.to_string()) };
        out.push_str(&format!(
            "  {:<20} {from:>7} {to:>7} {:>11.3e} {:>11.3e} {:>11.3e} {:>12.3e}{}\n",
            s.knob,
            s.change.mean,
            s.change.p99,
            s.change.max,
            s.f32_vs_f64,
            match (s.rejected, s.loops_cut > c.start_loops_cut) {
                (false, _) => String::new(),
                (true, true) => format!("  rejected: the device cut loops short in {} pixels (lavapipe's loop budget)", s.loops_cut),
                (true, false) => "  rejected: the f64 image left the f32 one or gained NaN/Inf".into(),
            }
        ));
    }
    out
}

/// `bench` for a shader that is not Freeman-compatible: the knobs swept, each configuration
/// against the sampling truth (the same shader at converged knobs, in f64).
fn bench_any(options: &BenchOptions, file: &Path, progress: &dyn Progress) -> Result<BenchReport, Error> {
    let setup = &options.setup;
    let scene_file = options.scene_file.as_ref();
    let mut out = String::new();
    let (views, width, height) = (setup.views()?, setup.width, setup.height);
    engine::check_output_dir(&options.out_dir, true, &["bench.csv", "bench.png"])?;
    let front =
        gdresource::check_file(file).map_err(|e| Error::environment(format!("cannot read {}: {e}", file.display())))?;
    let loaded = Sky::load(Some(file), &any::measuring_options())?;
    let textures = engine::load_textures(&setup.textures, scene_file, &loaded)?;
    let sky = any::Sky::new(front, setup.sets.clone()).map_err(Error::input)?.with_textures(textures);
    let mut knobs = any_knobs(&sky, &options.knobs).map_err(Error::input)?;
    knobs.extend(options.sampling.sky_resolution_knob()?);
    let names: Vec<String> = knobs.iter().map(|k| k.name.clone()).collect();
    // The truth raises the quality knobs only; it is shaded at full resolution.
    let raised: Vec<String> = names.iter().filter(|n| *n != knobs::SKY_RESOLUTION).cloned().collect();
    let defaults: Vec<i32> = sky.defaults(&names).into_iter().map(|(_, v)| v).collect();
    let mut configs = combinations(&knobs);
    if !configs.contains(&defaults) {
        configs.push(defaults.clone());
    }
    let shots: Vec<any::Shot> =
        views.iter().map(|&projection| any::Shot { scene: setup.scene, projection, width, height }).collect();
    let gpu = engine::open_gpu(progress)?;
    let adapter = gpu.adapter_info();
    let timer = if gpu.has_timestamps() { "gpu_timestamps" } else { "wall" };
    let limits = options.sampling.limits();
    let tolerance = limits.tolerance;
    progress.start(1 + configs.len() as u64 * (1 + u64::from(options.runs)));
    let started = std::time::Instant::now();
    let setting = |values: &[i32]| -> any::Setting { names.iter().cloned().zip(values.iter().copied()).collect() };
    let truth = any::converge(&gpu, &sky, &setting(&defaults), &raised, &shots, limits, |m| progress.message(m))
        .map_err(|e| {
            (note!(progress, "error: {e}"));
            Error::input("failed")
        })?;
    let truth_time = started.elapsed();
    progress.step();
    let mut compiled = Vec::with_capacity(configs.len());
    let mut errors = Vec::with_capacity(configs.len());
    // Configurations whose loops the device cut short (lavapipe's loop budget): their error is
    // the device's, not the shader's; named after the table.
    let mut cut = Vec::new();
    for values in &configs {
        progress.message(&format!("{}: compile, warm-up render and error", any::label(&setting(values))));
        let variant = sky.variant(&setting(values)).map_err(Error::input)?;
        let c = variant.compile(&gpu).map_err(Error::input)?;
        let images: Vec<Vec<[f32; 4]>> =
            shots.iter().map(|s| c.render(&gpu, s).map(|r| r.0)).collect::<Result<_, _>>().map_err(Error::input)?;
        errors.push(any::pooled(&images, &truth.images));
        let canary = variant.compile_canary(&gpu).map_err(Error::input)?;
        let pixels: usize =
            shots.iter().map(|s| canary.loops_cut(&gpu, s)).sum::<Result<_, _>>().map_err(Error::input)?;
        if pixels > 0 {
            cut.push((any::label(&setting(values)), pixels));
        }
        compiled.push(c);
        progress.step();
    }
    let mut times = vec![Vec::with_capacity(options.runs as usize); configs.len()];
    for run in 0..options.runs {
        progress.message(&format!("timing: round {} of {} on {}", run + 1, options.runs, adapter.name));
        for (c, t) in compiled.iter().zip(&mut times) {
            let mut total = Duration::ZERO;
            for s in &shots {
                total += c.render(&gpu, s).map_err(Error::input)?.1;
            }
            t.push(total);
            progress.step();
        }
    }
    progress.finish();
    let mut rows: Vec<Row> = configs
        .iter()
        .zip(errors)
        .zip(&mut times)
        .map(|((values, errors), times)| {
            times.sort();
            let n = times.len();
            Row {
                subject: 0,
                values: values.clone(),
                median: (times[(n - 1) / 2] + times[n / 2]) / 2,
                min: times[0],
                max: times[n - 1],
                errors,
                pareto: false,
            }
        })
        .collect();
    mark_pareto(&mut rows);
    let name = subject_names(&[Some(file.to_path_buf())]).remove(0);
    let subjects =
        vec![Subject { name: name.clone(), file: Some(file.to_path_buf()), loaded, knobs, configs, defaults }];

    let csv_path = options.out_dir.join("bench.csv");
    engine::create_output_dir(&options.out_dir)?;
    engine::write_file(&csv_path, csv_text(&subjects, &rows, options.runs, timer).as_bytes())
        .map_err(Error::environment)?;
    let png_path = options.out_dir.join("bench.png");
    let s = &subjects[0];
    say!(
        out,
        "gdsky bench: {}, {} configurations, {width}x{height} {}",
        file.display(),
        rows.len(),
        setup.projection.name()
    );
    say!(out, "adapter  {adapter}");
    say!(
        out,
        "timer    {}, median of {} after a warm-up, all configurations in the same interleaved rounds",
        if timer == "wall" { "wall time submit → idle" } else { "GPU timestamp queries around the passes" },
        options.runs
    );
    say!(
        out,
        "truth    the sampling truth: {name} in f64 at converged knobs ({}), {:.1?}; error = |gdsky f32 − truth| / \
         max(|truth|, {:e}) over RGB",
        any::label(&truth.setting),
        truth_time,
        stats::FLOOR
    );
    if truth.start_loops_cut > 0 {
        say!(
            out,
            "warning  the device cut the loops of {} pixels at the default knobs (lavapipe's budget of 65,535 loop \
             passes per pixel, docs/lavapipe-loop-limit.md): the truth there is the device's, not the shader's",
            truth.start_loops_cut
        );
    }
    if raised.is_empty() {
        say!(
            out,
            "knobs    none (no int uniform with a hint_range or int const bounds a loop): the truth is the f64 evaluation alone"
        );
    } else {
        say!(
            out,
            "convergence (each knob doubled until the f64 image moves by a mean < {tolerance:e}; `all`: every knob \
             doubled at once as a check){}:",
            if truth.converged { "" } else { " — NOT CONVERGED within the limit, the truth is the last step" }
        );
        out.push_str(&convergence_table(&truth));
    }
    let swept = if s.knobs.is_empty() { "no knob".to_string() } else { names.join(" × ") };
    say!(out, "Pareto front of {name} ({swept}; no other configuration of it both faster and more accurate):");
    let mine: Vec<&Row> = rows.iter().collect();
    out.push_str(&front_table(&s.knobs, &mine));
    if let Some(d) = rows.iter().find(|r| r.values == s.defaults) {
        say!(
            out,
            "default  {}: {:.3} ms, mean {:.3e}, p99 {:.3e}, max {:.3e}, tone-mapped {:.3e}",
            s.label(&d.values),
            ms(d.median),
            d.errors.mean,
            d.errors.p99,
            d.errors.max,
            d.errors.mean_tonemapped
        );
    }
    for (label, pixels) in &cut {
        say!(
            out,
            "cut      {label}: the device cut the loops of {pixels} pixels short (lavapipe's loop budget): its error is \
             the device's, not the shader's"
        );
    }
    let title = format!("{name} on {}: {}x{} {}", adapter.name, width, height, setup.projection.name());
    let truth_label = format!("f64 at {}", any::label(&truth.setting));
    plot(&png_path, &title, &subjects, &rows, &[], timer, &truth_label)?;
    say!(out, "wrote    {} and {}", csv_path.display(), png_path.display());
    Ok(report(out, csv_path, png_path, &subjects, &rows))
}

/// The comparisons of each shader after the first with the first's default configuration: the
/// two lines issue #12 asks for. (i) Its lowest-mean-error configuration at no more than that
/// time, with mean/p99/max against the default's; (ii) its fastest configuration whose mean,
/// p99 and max error are all no more than the default's, with the speed-up. Configurations with
/// NaN/Inf never qualify. Empty with one shader, or when the first's default was not measured.
fn comparisons(subjects: &[Subject], rows: &[Row]) -> Vec<String> {
    let Some(first) = subjects.first() else { return Vec::new() };
    let finite = |r: &&Row| r.errors.nan + r.errors.inf == 0 && r.errors.channels > 0;
    let Some(base) = rows.iter().filter(finite).find(|r| r.subject == 0 && r.values == first.defaults) else {
        return Vec::new();
    };
    let b = &base.errors;
    let mut out = vec![format!(
        "against {}'s default ({}): {:.3} ms, mean {:.3e}, p99 {:.3e}, max {:.3e}",
        first.name,
        first.label(&first.defaults),
        ms(base.median),
        b.mean,
        b.p99,
        b.max
    )];
    for (i, s) in subjects.iter().enumerate().skip(1) {
        let mine: Vec<&Row> = rows.iter().filter(|r| r.subject == i).filter(finite).collect();
        let best = mine
            .iter()
            .filter(|r| r.median <= base.median)
            .min_by(|a, b| a.errors.mean.total_cmp(&b.errors.mean).then(a.median.cmp(&b.median)));
        out.push(match best {
            Some(r) => format!(
                "  {} at ≤ 1.0× {}'s default time: {} ({:.3} ms, {:.2}×): mean {:.3e} / p99 {:.3e} / max {:.3e} \
                 against {:.3e} / {:.3e} / {:.3e} ({:.3}× / {:.3}× / {:.3}×)",
                s.name,
                first.name,
                s.label(&r.values),
                ms(r.median),
                ratio(r.median, base.median),
                r.errors.mean,
                r.errors.p99,
                r.errors.max,
                b.mean,
                b.p99,
                b.max,
                r.errors.mean / b.mean,
                r.errors.p99 / b.p99,
                r.errors.max / b.max
            ),
            None => {
                format!("  {} at ≤ 1.0× {}'s default time: none of its configurations is that fast", s.name, first.name)
            }
        });
        let cheapest = mine
            .iter()
            .filter(|r| r.errors.mean <= b.mean && r.errors.p99 <= b.p99 && r.errors.max <= b.max)
            .min_by(|a, b| a.median.cmp(&b.median).then(a.errors.mean.total_cmp(&b.errors.mean)));
        out.push(match cheapest {
            Some(r) => format!(
                "  {} at no more than {}'s default's mean, p99 and max error: {} ({:.3} ms; mean {:.3e} / p99 {:.3e} / \
                 max {:.3e}): {:.2}× faster",
                s.name,
                first.name,
                s.label(&r.values),
                ms(r.median),
                r.errors.mean,
                r.errors.p99,
                r.errors.max,
                ratio(base.median, r.median)
            ),
            None => format!(
                "  {} at no more than {}'s default's mean, p99 and max error: none of its configurations is that accurate",
                s.name, first.name
            ),
        });
    }
    if subjects.len() < 2 {
        out.clear();
    }
    out
}

/// `a / b` of two durations (∞ for a zero `b`).
fn ratio(a: Duration, b: Duration) -> f64 {
    a.as_secs_f64() / b.as_secs_f64()
}

/// The bench shader's reduced sky resolutions with the default (bilinear) upsampling, as
/// (median ms, mean relative error vs the bench's truth, `half` or `quarter`): the points
/// `--skipping` adds to the plot.
fn reduced_points(rows: &[super::skipping::SkipRow]) -> Vec<(f64, f64, String)> {
    rows.iter()
        .filter(|r| r.kind == "resolution")
        .filter_map(|r| {
            let name = r.variant.strip_suffix("/bilinear")?;
            let truth = r.vs_truth.as_ref().filter(|e| e.mean > 0.0)?;
            Some((ms(r.median).max(1e-3), truth.mean, name.to_string()))
        })
        .collect()
}

/// Marks the configurations no other one beats in both median time and mean relative error
/// ([`pareto::front`]).
fn mark_pareto(rows: &mut [Row]) {
    let points: Vec<pareto::Point> = rows
        .iter()
        .map(|r| pareto::Point {
            time: r.median.as_secs_f64(),
            error: r.errors.mean,
            usable: r.errors.nan + r.errors.inf == 0,
        })
        .collect();
    for (row, on) in rows.iter_mut().zip(pareto::front(&points)) {
        row.pareto = on;
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// The CSV: one row per configuration of each shader. Columns: shader (its name), the knobs of
/// all shaders (view_samples, sun_samples, …; empty where the shader does not sweep one: it never
/// reads it), time_ms (median), time_min_ms, time_max_ms, runs, timer (`gpu_timestamps`: the passes on the
/// device; `wall`: submit → idle), mean_rel,
/// p99_rel, max_rel (relative error in linear radiance against the truth, floor 1e-4),
/// mean_abs_tonemapped (mean |Δ| after the preview's tone map), nan, inf (channels of gdsky's
/// image), pareto (1 on the front).
fn csv_text(subjects: &[Subject], rows: &[Row], runs: u32, timer: &str) -> String {
    let mut names: Vec<&str> = Vec::new();
    for k in subjects.iter().flat_map(|s| &s.knobs) {
        if !names.contains(&k.name.as_str()) {
            names.push(&k.name);
        }
    }
    let mut out = String::from("shader,");
    out.extend(names.iter().map(|n| format!("{n},")));
    out.push_str(
        "time_ms,time_min_ms,time_max_ms,runs,timer,mean_rel,p99_rel,max_rel,mean_abs_tonemapped,nan,inf,pareto\n",
    );
    for r in rows {
        let s = &subjects[r.subject];
        out.push_str(&csv_field(&s.name));
        out.push(',');
        for name in &names {
            if let Some(v) = s.knobs.iter().position(|k| k.name == *name).and_then(|i| r.values.get(i)) {
                out.push_str(&v.to_string());
            }
            out.push(',');
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

/// A CSV field: quoted (quotes doubled) when it holds a comma, a quote or a line break.
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) { format!("\"{}\"", text.replace('"', "\"\"")) } else { text.to_string() }
}

/// One shader's front as a text table, fastest first.
fn front_table(knobs: &[Knob], rows: &[&Row]) -> String {
    let mut front: Vec<&Row> = rows.iter().copied().filter(|r| r.pareto).collect();
    front.sort_by_key(|r| r.median);
    let head = if knobs.is_empty() {
        "(no knob)".to_string()
    } else {
        knobs.iter().map(|k| k.name.as_str()).collect::<Vec<_>>().join("/")
    };
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

/// Colours of the shaders on the chart, in order (the first is the old chart's red).
const PALETTE: [RGBColor; 6] = [
    RGBColor(200, 30, 30),
    RGBColor(30, 90, 200),
    RGBColor(20, 140, 60),
    RGBColor(210, 120, 0),
    RGBColor(130, 50, 170),
    RGBColor(0, 150, 160),
];

/// Draws mean relative error against median time, log-log: each shader's configurations as
/// light dots in its colour, its Pareto front connected in its colour and labelled with the knob
/// values; each shader's default configuration ringed in black; `reduced` (from `--skipping`: the
/// first shader's defaults at a reduced sky resolution, labelled) dark grey diamonds.
fn plot(
    path: &Path,
    title: &str,
    subjects: &[Subject],
    rows: &[Row],
    reduced: &[(f64, f64, String)],
    timer: &str,
    truth: &str,
) -> Result<(), Error> {
    plot::register_fonts();
    let (w, h) = (960u32, 640u32);
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    let drawable = |r: &&Row| r.errors.channels > 0 && r.errors.mean > 0.0;
    let point = |r: &Row| (ms(r.median).max(1e-3), r.errors.mean);
    let all = || rows.iter().filter(drawable).map(point).chain(reduced.iter().map(|p| (p.0, p.1)));
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
    let err = |e: &dyn std::fmt::Display| Error::environment(format!("cannot draw {}: {e}", path.display()));
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
            .y_desc(format!("mean relative error vs {truth}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .x_label_formatter(&|v| tick(*v))
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(|e| err(&e))?;
        let mut fronts = Vec::new();
        for (i, s) in subjects.iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            let light = colour.mix(0.35);
            let mine: Vec<&Row> = rows.iter().filter(|r| r.subject == i).filter(drawable).collect();
            let knob_names = if s.knobs.is_empty() {
                "no knob".to_string()
            } else {
                s.knobs.iter().map(|k| k.name.as_str()).collect::<Vec<_>>().join("/")
            };
            chart
                .draw_series(mine.iter().map(|r| Circle::new(point(r), 4, light.filled())))
                .map_err(|e| err(&e))?
                .label(format!("{}: all {} ({knob_names})", s.name, mine.len()))
                .legend(move |(x, y)| Circle::new((x + 10, y), 4, light.filled()));
            let mut front: Vec<(f64, f64, String)> = mine
                .iter()
                .filter(|r| r.pareto)
                .map(|r| {
                    let (x, y) = point(r);
                    (x, y, r.values.iter().map(i32::to_string).collect::<Vec<_>>().join("/"))
                })
                .collect();
            front.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(front.iter().map(|p| (p.0, p.1)), colour.stroke_width(2)))
                .map_err(|e| err(&e))?
                .label(format!("{}: Pareto front", s.name))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
            fronts.push((colour, front));
        }
        // The rings before the front labels, so that a label next to one stays readable on top.
        let defaults: Vec<(f64, f64)> = rows
            .iter()
            .filter(drawable)
            .filter(|r| subjects.get(r.subject).is_some_and(|s| !s.knobs.is_empty() && r.values == s.defaults))
            .map(point)
            .collect();
        if !defaults.is_empty() {
            chart
                .draw_series(defaults.iter().map(|&p| Circle::new(p, 9, BLACK.stroke_width(2))))
                .map_err(|e| err(&e))?
                .label("each shader's default configuration")
                .legend(|(x, y)| Circle::new((x + 10, y), 6, BLACK.stroke_width(2)));
        }
        if !reduced.is_empty() {
            let grey = RGBColor(70, 70, 70);
            let diamond = move |(x, y): (i32, i32), r: i32| {
                Polygon::new(vec![(x, y - r), (x + r, y), (x, y + r), (x - r, y)], grey.filled())
            };
            chart
                .draw_series(reduced.iter().map(|(x, y, label)| {
                    EmptyElement::at((*x, *y))
                        + diamond((0, 0), 7)
                        + Text::new(label.clone(), (8, 4), ("sans-serif", 14).into_font().color(&grey))
                }))
                .map_err(|e| err(&e))?
                .label(format!("{}'s default at half / quarter sky resolution (bilinear)", subjects[0].name))
                .legend(move |(x, y)| diamond((x + 10, y), 6));
        }
        // Labels alternate above-right and below-left of their points, away from a falling
        // front, so that neighbours close in time do not print over each other.
        for (colour, front) in &fronts {
            let colour = *colour;
            chart
                .draw_series(front.iter().enumerate().map(|(i, (x, y, label))| {
                    let at = if i % 2 == 0 { (6, -18) } else { (-8 - 7 * label.len() as i32, 6) };
                    EmptyElement::at((*x, *y))
                        + Circle::new((0, 0), 5, colour.filled())
                        + Text::new(label.clone(), at, ("sans-serif", 14).into_font().color(&colour))
                }))
                .map_err(|e| err(&e))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            // Lower left: fast and accurate at once, where a front never runs (UpperRight covered
            // the slow end of a poor shader's front).
            .position(SeriesLabelPosition::LowerLeft)
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    plot::write_rgb_png(path, w, h, &rgb)
}

/// An axis tick in milliseconds with as many decimals as its size needs.
fn tick(v: f64) -> String {
    let digits = if v >= 10.0 { 0 } else { (1.0 - v.log10().floor()).clamp(1.0, 6.0) as usize };
    format!("{v:.digits$}")
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
    fn a_shader_sweeps_only_the_knobs_it_reads() {
        let all = knobs(&[]).unwrap();
        let read = |names: &[&str]| names.iter().map(|n| n.to_string()).collect::<BTreeSet<String>>();
        let both = knobs_read(&all, &read(&["view_samples", "sun_samples", "sun_intensity"]), &[]);
        assert_eq!(combinations(&both).len(), 32);
        // Only view_samples: its finer default, unless a --knob set it.
        let view = knobs_read(&all, &read(&["view_samples"]), &[]);
        assert_eq!((view.len(), view[0].values.as_slice()), (1, VIEW_ONLY_SAMPLES.as_slice()));
        let given = knobs(&["view_samples=4,8".into()]).unwrap();
        let view = knobs_read(&given, &read(&["view_samples"]), &["view_samples".into()]);
        assert_eq!(view[0].values, [4, 8]);
        // No knob read: one configuration.
        assert_eq!(combinations(&knobs_read(&all, &read(&[]), &[])), vec![Vec::<i32>::new()]);
    }

    #[test]
    fn truth_flags_pick_the_truth() {
        assert_eq!(truth_from_args(None, None), Ok(TruthMode::Integral(Truth::default())));
        let samples = Converged { view_samples: 128, sun_samples: 32 };
        assert_eq!(truth_from_args(None, Some((128, 32))), Ok(TruthMode::Samples(samples)));
        assert_eq!(truth_from_args(Some(TruthChoice::Samples), None), Ok(TruthMode::Samples(Converged::default())));
        assert!(truth_from_args(Some(TruthChoice::Integral), Some((128, 32))).is_err());
        // The integral reads no sample count: every count shares one truth; the key names it.
        let a = TruthMode::Integral(Truth::default());
        let p = FreemanParams::default();
        assert_eq!(a.params(&p), a.params(&p.with_samples(4, 2)));
        assert!(a.key().starts_with("integral"));
    }

    #[test]
    fn names_are_stems_unless_two_are_equal() {
        let f = |p: &str| Some(PathBuf::from(p));
        assert_eq!(subject_names(&[None, f("s/freeman_fast.gdshader")]), ["freeman_sky (bundled)", "freeman_fast"]);
        assert_eq!(subject_names(&[f("a/x.gdshader"), f("b/x.gdshader")]), ["a/x.gdshader", "b/x.gdshader"]);
        assert_eq!(csv_field("a,b"), "\"a,b\"");
    }

    #[test]
    fn pareto_front_excludes_dominated_points() {
        let row = |t: u64, e: f64| Row {
            subject: 0,
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
