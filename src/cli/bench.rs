//! `gdsky bench [FILE…]`: render time against error (the engine: [`gdsky::measure::bench`]).

use super::progress::Bar;
use super::scene::SceneArgs;
use clap::{ArgMatches, Args};
use gdsky::engine::{Error, Input};
use gdsky::measure::bench::{self, BenchOptions, MAX_TRUTH_SAMPLES, SamplingTruth, TruthChoice};
use gdsky::measure::skipping::SkippingOptions;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct BenchArgs {
    /// The sky shaders to benchmark on one chart (Freeman-compatible: the Freeman sky's
    /// uniforms), the first of them the one the others are compared with; or, first, a scene file
    /// (`SCENE.toml`: its shader, uniforms, sun, camera, projection, size and time; the flags given
    /// override it) or a Godot material or scene (`MATERIAL.tres`, `SCENE.tscn`: its shader and
    /// values), then more shaders. Without any, the bundled Freeman sky.
    #[arg(value_name = "FILE|SCENE.toml|MATERIAL.tres|SCENE.tscn")]
    files: Vec<PathBuf>,
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
    /// Sweep an int uniform: `--knob view_samples=4,8,16`. view_samples (4,8,12,16,24,32,48,64;
    /// 2,3,4,6,8,12,16,24,32,48,64 for a shader that reads no other knob) and sun_samples
    /// (2,4,8,16) are swept by default, each only in the shaders that read it; a --knob replaces a
    /// default list or adds a dimension. Values are sample counts, 1 to 4096. Repeatable.
    #[arg(long = "knob", value_name = "NAME=V1,V2,…")]
    knobs: Vec<String>,
    /// The truth the errors are measured against: `integral`, skyref::truth (the Freeman
    /// model's integrals to about 1e-7), or `samples`, the shader's own sums in f64 at
    /// --truth-samples (the older, cheaper truth; ~6e-4 mean off the integral) [default:
    /// integral; samples when --truth-samples is given].
    #[arg(long, value_name = "integral|samples", value_parser = super::named::<TruthChoice>(&TruthChoice::NAMES))]
    truth: Option<TruthChoice>,
    /// Sample counts of the `samples` truth (skyref f64): VIEW,SUN, each 1 to 16384 [default:
    /// 1024,256]. Implies --truth samples.
    #[arg(long, value_name = "VIEW,SUN", value_parser = parse_counts, allow_hyphen_values = true)]
    truth_samples: Option<(i32, i32)>,
    /// Where truth images are cached [default: $GDSKY_CACHE_DIR, else $XDG_CACHE_HOME/gdsky,
    /// else ~/.cache/gdsky, else the temp dir's gdsky-cache].
    #[arg(long, value_name = "DIR")]
    cache_dir: Option<PathBuf>,
    #[command(flatten)]
    truth_args: SamplingTruthArgs,
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    skipping: SkippingArgs,
}

/// The sampling truth's flags, shared by `bench` and `tune` (shaders that are not
/// Freeman-compatible).
#[derive(Args, Clone, Debug)]
pub struct SamplingTruthArgs {
    /// For a shader that is not Freeman-compatible: the sampling truth raises each quality
    /// knob (doubling) until doubling it changes the f64 image by a mean relative error below
    /// this [default: 1e-3].
    #[arg(long, value_name = "REL", value_parser = parse_tolerance)]
    pub converge_tol: Option<f64>,
    /// For a shader that is not Freeman-compatible: samples per pixel side of the sampling
    /// truth (1 to 8). Above 1, every image of the convergence is rendered N× wider and higher
    /// and box-filtered, so the truth is each pixel's area average and the errors include the
    /// shader's aliasing (hashed stars, hard sun edges) [default: 1, the pixel centre].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=8))]
    pub truth_supersample: Option<u32>,
    /// For a shader that is not Freeman-compatible: also sweep the resolution the sky is shaded
    /// at (`full,half,quarter`, any of them): each configuration is rendered at each, upsampled
    /// bilinearly to the image size (as `render --sky-resolution`), and measured against the
    /// full-resolution truth. The column `sky_resolution` holds the divisor: 1, 2 or 4.
    #[arg(long, value_name = "full,half,quarter")]
    pub sky_resolution: Option<String>,
}

/// The `--skipping` flags of `gdsky bench`.
#[derive(Args, Clone, Debug, Default)]
pub struct SkippingArgs {
    /// Also time the occluder at 0/50/90 % coverage and the half/quarter sky resolutions (both
    /// upsampling filters) at the shader's default uniforms, with their errors; writes
    /// skipping.csv.
    #[arg(long)]
    pub skipping: bool,
    /// Another sky shader (any, at its default uniforms) for the resolution rows of
    /// --skipping, measured against its own full-resolution render. Repeatable.
    #[arg(long, value_name = "FILE")]
    pub skipping_shader: Vec<PathBuf>,
}

impl SamplingTruthArgs {
    /// The sampling truth these flags ask for.
    pub fn options(&self) -> SamplingTruth {
        SamplingTruth {
            converge_tol: self.converge_tol,
            supersample: self.truth_supersample,
            sky_resolution: self.sky_resolution.clone(),
        }
    }
}

/// `--converge-tol`: a relative change in (0, 1).
pub fn parse_tolerance(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v < 1.0 => Ok(v),
        _ => Err(format!("`{s}` is not a relative change between 0 and 1 (e.g. 1e-3)")),
    }
}

/// `--truth-samples VIEW,SUN`.
fn parse_counts(s: &str) -> Result<(i32, i32), String> {
    let (a, b) = s.split_once(',').ok_or_else(|| format!("`{s}`: expected VIEW,SUN, e.g. 1024,256"))?;
    let count = |t: &str| match t.trim().parse::<i32>() {
        Ok(v) if (1..=MAX_TRUTH_SAMPLES).contains(&v) => Ok(v),
        _ => Err(format!("`{}` is not a sample count from 1 to {MAX_TRUTH_SAMPLES}", t.trim())),
    };
    Ok((count(a)?, count(b)?))
}

pub fn run(args: &BenchArgs, matches: &ArgMatches) -> ExitCode {
    super::exit(bench(args, matches))
}

fn bench(args: &BenchArgs, matches: &ArgMatches) -> Result<(), Error> {
    super::watch_driver(args.files.first().map(PathBuf::as_path))?;
    let input = Input::open(args.files.first().map(PathBuf::as_path))?;
    err!("{}", input.warnings);
    let mut shaders = vec![input.shader.clone()];
    for file in args.files.iter().skip(1) {
        if gdsky::scene::is_scene_path(file) || gdsky::scene::is_godot_resource(file) {
            return Err(Error::input(format!(
                "{}: only the first FILE can be a scene file or a Godot material; the others are shaders",
                file.display()
            )));
        }
        shaders.push(Some(file.clone()));
    }
    let mut scene = args.scene.clone();
    if let Some(file) = &input.scene {
        scene.merge_file(file, matches);
    }
    let options = BenchOptions {
        shaders,
        scene_file: input.scene,
        setup: scene.setup()?,
        bake_scene: args.bake_scene,
        overrides: args.overrides.clone(),
        out_dir: args.out_dir.clone(),
        runs: args.runs,
        knobs: args.knobs.clone(),
        truth: args.truth,
        truth_samples: args.truth_samples,
        cache_dir: args.cache_dir.clone(),
        sampling: args.truth_args.options(),
        skipping: args.skipping.skipping.then(|| SkippingOptions { shaders: args.skipping.skipping_shader.clone() }),
    };
    let report = bench::bench(&options, &Bar::new())?;
    out!("{}", report.text);
    Ok(())
}
