//! `gdsky tune FILE --max-error MEAN[,P99]`: the cheapest knob setting within an error budget.
//!
//! Over a set of scenes (default: the sun at 0, 10, 30, 60 and 90° over a panorama), every
//! configuration of the shader's quality knobs (the loop bounds [`gdsky::measure::knobs`]
//! finds, with `bench`'s default sweeps; `--knob` replaces or adds one) is rendered and measured
//! against the truth of each scene: skyref's integral for a Freeman-compatible shader, the
//! sampling truth (f64 at converged knobs) for any other. A configuration qualifies when, at
//! every scene, its mean relative error is at most MEAN (and its p99 at most P99 when given) and
//! it has no NaN/Inf; the cheapest qualifying one by median time wins. All configurations,
//! the shader's defaults among them, are timed in the same interleaved rounds, so the time
//! saved against the defaults is measured on one machine state.
//!
//! **The output is a specialized `.gdshader`** (`DIR/<stem>.tuned.gdshader`): the knobs baked
//! as `const int NAME = value;` (a const knob's initializer replaced, a uniform knob's
//! declaration replaced by a const). Why the shader source rather than WGSL/SPIR-V: it stays
//! the user's shader, usable in Godot itself and by every gdsky command (`convert` gives the
//! WGSL/SPIR-V from it with the knobs folded as constants, exactly as `convert --set` bakes),
//! and it is reviewable as a two-line diff. Its uniforms other than the knobs are unchanged.

use super::bench::{SamplingTruthArgs, any_knobs, convergence_table};
use super::scene::open_gpu;
use super::sweep;
use super::{environment, usage};
use clap::Args;
use gdsky::measure::any::{self, Candidate, Shot};
use gdsky::measure::knobs::{KnobKind, SKY_RESOLUTION, combinations, specialize_source};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

#[derive(Args)]
pub struct TuneArgs {
    /// The sky shader to tune.
    #[arg(value_name = "FILE")]
    file: PathBuf,
    /// The error budget: mean relative error, and optionally p99, at every scene
    /// (`0.05` or `0.05,0.2`).
    #[arg(long, value_name = "MEAN[,P99]", value_parser = parse_budget, allow_hyphen_values = true)]
    max_error: (f64, Option<f64>),
    /// Sun elevations of the scenes, degrees (panoramas from 1 m up).
    #[arg(long, value_name = "DEG,…", default_value = "0,10,30,60,90", value_delimiter = ',', value_parser = parse_suns, allow_hyphen_values = true)]
    suns: Vec<f64>,
    /// Image size of each scene.
    #[arg(long, value_name = "WxH", default_value = "128x64", value_parser = super::scene::parse_size)]
    size: (u32, u32),
    /// TIME of every scene, seconds.
    #[arg(long, value_name = "SECONDS", default_value_t = 0.0, value_parser = super::scene::parse_time, allow_hyphen_values = true)]
    time: f32,
    /// Sweep a knob: `--knob view_samples=4,8,16` (an int uniform or int const; replaces the
    /// default sweep of a knob or adds one). Repeatable.
    #[arg(long = "knob", value_name = "NAME=V1,V2,…")]
    knobs: Vec<String>,
    /// Timed renders per configuration (1 to 1000) after a warm-up; the median counts.
    #[arg(long, value_name = "N", default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    runs: u32,
    #[command(flatten)]
    truth_args: SamplingTruthArgs,
    /// Folder for the specialized shader and tune.csv (created if missing; checked first).
    #[arg(short = 'o', long = "out-dir", value_name = "DIR", default_value = "out/tune")]
    out_dir: PathBuf,
}

/// `MEAN[,P99]`, each a relative error in (0, 1e3].
fn parse_budget(s: &str) -> Result<(f64, Option<f64>), String> {
    let value = |t: &str| match t.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v <= 1e3 => Ok(v),
        _ => Err(format!("`{}` is not a relative error above 0 (e.g. 0.05)", t.trim())),
    };
    match s.split_once(',') {
        Some((m, p)) => Ok((value(m)?, Some(value(p)?))),
        None => Ok((value(s)?, None)),
    }
}

/// A list of sun elevations in [−90, 90].
fn parse_suns(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if (-90.0..=90.0).contains(&v) => Ok(v),
        _ => Err(format!("`{s}` is not a sun elevation from -90 to 90 degrees")),
    }
}

pub fn run(args: &TuneArgs) -> ExitCode {
    match tune(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(code) => code,
    }
}

/// The truth images of `shots` for a Freeman-compatible shader: skyref's integral with the
/// shader's own uniform defaults.
fn freeman_truth(shader: &gdsky::CheckedShader, shots: &[Shot]) -> Result<Vec<Vec<[f64; 4]>>, String> {
    let mut params = skyref::FreemanParams::default();
    let mut defaults: Vec<(String, String)> = gdshader::values::defaults_as_set(shader).into_iter().collect();
    defaults.sort();
    for (name, value) in &defaults {
        if name != "transmittance_table" {
            params.set(name, value)?;
        }
    }
    let truth = skyref::truth::Truth::default();
    Ok(shots
        .iter()
        .map(|s| skyref::truth::render(&params.with_samples(0, 0), &s.scene, s.projection, s.width, s.height, &truth))
        .collect())
}

fn tune(args: &TuneArgs) -> Result<(), ExitCode> {
    let (mean_budget, p99_budget) = args.max_error;
    if args.suns.is_empty() {
        return Err(usage("--suns: give at least one sun elevation"));
    }
    let stem = args.file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "shader".into());
    let out_name = format!("{stem}.tuned.gdshader");
    super::check_output_dir(&args.out_dir, true, &[&out_name, "tune.csv"])?;
    let front =
        gdsky::check_file(&args.file).map_err(|e| environment(format!("cannot read {}: {e}", args.file.display())))?;
    if front.shader.is_none() {
        eprint!("{}", gdsky::frontend::diag::render_human(&front.db, &front.diagnostics, false));
        return Err(ExitCode::from(1));
    }
    let sky = any::Sky::new(front, Vec::new()).map_err(usage)?;
    let shader = sky.front.shader.as_ref().ok_or(ExitCode::from(1))?;
    let freeman = gdsky::measure::freeman::compatible(shader);
    if freeman && args.truth_args.truth_supersample.is_some() {
        return Err(usage(
            "--truth-supersample sets the sampling truth; a Freeman-compatible shader is measured against skyref's integrals",
        ));
    }
    let mut knobs = any_knobs(&sky, &args.knobs).map_err(usage)?;
    if let Some(knob) = args.truth_args.sky_resolution_knob()? {
        if freeman {
            return Err(usage("--sky-resolution is swept for shaders that are not Freeman-compatible"));
        }
        knobs.push(knob);
    }
    if knobs.is_empty() {
        return Err(usage(format!(
            "{}: no knob to tune (no int uniform or int const bounds a loop; name one with --knob)",
            args.file.display()
        )));
    }
    let names: Vec<String> = knobs.iter().map(|k| k.name.clone()).collect();
    // The truth raises the quality knobs only; it is shaded at full resolution.
    let raised: Vec<String> = names.iter().filter(|n| *n != SKY_RESOLUTION).cloned().collect();
    let defaults: Vec<i32> = sky.defaults(&names).into_iter().map(|(_, v)| v).collect();
    let mut configs = combinations(&knobs);
    if !configs.contains(&defaults) {
        configs.push(defaults.clone());
    }
    let setting = |values: &[i32]| -> any::Setting { names.iter().cloned().zip(values.iter().copied()).collect() };
    let (w, h) = args.size;
    let shots: Vec<Shot> = args
        .suns
        .iter()
        .map(|&sun| {
            let shot = Shot::panorama(sun, w, h);
            Shot { scene: shot.scene.with_time(f64::from(args.time)), ..shot }
        })
        .collect();

    let gpu = open_gpu()?;
    let adapter = gpu.adapter_info();
    let bar = sweep::progress_bar(1 + configs.len() as u64 * (1 + u64::from(args.runs)));
    bar.enable_steady_tick(Duration::from_millis(200));
    let (truth, truth_text, converged) = if freeman {
        bar.set_message("truth: skyref's integral per scene");
        let images = freeman_truth(shader, &shots).map_err(usage)?;
        (images, "skyref::truth, the Freeman model's integrals (~1e-7)".to_string(), None)
    } else {
        let limits = args.truth_args.limits();
        let c =
            any::converge(&gpu, &sky, &setting(&defaults), &raised, &shots, limits, |m| bar.set_message(m.to_string()))
                .map_err(usage)?;
        let text = format!("the sampling truth: f64 at {}", any::label(&c.setting));
        (c.images.clone(), text, Some(c))
    };
    bar.inc(1);

    // A configuration whose loops the device cuts short (lavapipe's budget of 65,535 loop
    // passes per pixel) renders faster and differently than on any other GPU: it is not a
    // candidate (the defaults stay, as the baseline, with a warning).
    let mut kept = Vec::with_capacity(configs.len());
    for values in configs {
        let canary = sky.variant(&setting(&values)).and_then(|v| v.compile_canary(&gpu)).map_err(usage)?;
        let pixels: usize = shots.iter().map(|s| canary.loops_cut(&gpu, s)).sum::<Result<_, _>>().map_err(usage)?;
        if pixels == 0 || values == defaults {
            if pixels > 0 {
                bar.suspend(|| {
                    println!(
                        "warning: the device cuts the loops of {pixels} pixels short at the defaults (lavapipe's loop \
                         budget, docs/lavapipe-loop-limit.md): their time and error are the device's"
                    )
                });
            }
            kept.push(values);
        } else {
            let label = any::label(&setting(&values));
            bar.suspend(|| {
                println!(
                    "skipped: {label}: the device cuts the loops of {pixels} pixels short (lavapipe's loop budget)"
                )
            });
        }
    }
    let configs = kept;
    let mut compiled = Vec::with_capacity(configs.len());
    let mut candidates = Vec::with_capacity(configs.len());
    for values in &configs {
        bar.set_message(format!("{}: compile and error", any::label(&setting(values))));
        let c = sky.variant(&setting(values)).and_then(|v| v.compile(&gpu)).map_err(usage)?;
        let mut errors = Vec::with_capacity(shots.len());
        for (shot, truth) in shots.iter().zip(&truth) {
            let (image, _) = c.render(&gpu, shot).map_err(usage)?;
            errors.push(sweep::error_stats(&image, truth));
        }
        candidates.push(Candidate { setting: setting(values), errors, time: Duration::ZERO });
        compiled.push(c);
        bar.inc(1);
    }
    // Interleaved rounds: every configuration once per round, so load from elsewhere spreads
    // over all of them and the ratio to the defaults comes from the same rounds.
    let mut times = vec![Vec::with_capacity(args.runs as usize); configs.len()];
    for run in 0..args.runs {
        bar.set_message(format!("timing: round {} of {}", run + 1, args.runs));
        for (c, t) in compiled.iter().zip(&mut times) {
            let mut total = Duration::ZERO;
            for shot in &shots {
                total += c.render(&gpu, shot).map_err(usage)?.1;
            }
            t.push(total);
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    for (c, t) in candidates.iter_mut().zip(&mut times) {
        t.sort();
        c.time = (t[(t.len() - 1) / 2] + t[t.len() / 2]) / 2;
    }
    let default_setting = setting(&defaults);
    let default = candidates.iter().find(|c| c.setting == default_setting).ok_or(ExitCode::from(1))?;
    let best = any::cheapest(&candidates, mean_budget, p99_budget);

    println!(
        "gdsky tune: {}, {} configurations × {} scenes (sun {}°), {w}x{h} panorama",
        args.file.display(),
        candidates.len(),
        shots.len(),
        args.suns.iter().map(|s| s.to_string()).collect::<Vec<_>>().join(", ")
    );
    println!("adapter  {adapter}");
    println!("truth    {truth_text}");
    if let Some(c) = &converged {
        print!("{}", convergence_table(c));
    }
    let budget = match p99_budget {
        Some(p) => format!("mean ≤ {mean_budget:e} and p99 ≤ {p:e}"),
        None => format!("mean ≤ {mean_budget:e}"),
    };
    println!(
        "budget   {budget} at every scene, no NaN/Inf; time = median of {} (all scenes, interleaved rounds)",
        args.runs
    );
    let mut sorted: Vec<&Candidate> = candidates.iter().collect();
    sorted.sort_by_key(|c| c.time);
    println!("  {:<36} {:>9} {:>11} {:>11}  within", "configuration", "time ms", "worst mean", "worst p99");
    for c in &sorted {
        let mark = if c.within(mean_budget, p99_budget) { "yes" } else { "" };
        let default_mark = if c.setting == default_setting { " (default)" } else { "" };
        println!(
            "  {:<36} {:>9.3} {:>11.3e} {:>11.3e}  {mark}",
            format!("{}{default_mark}", any::label(&c.setting)),
            ms(c.time),
            c.worst_mean(),
            c.worst_p99()
        );
    }
    super::create_output_dir(&args.out_dir)?;
    let csv_path = args.out_dir.join("tune.csv");
    super::write_file(&csv_path, csv(&candidates, &names, &args.suns).as_bytes()).map_err(environment)?;
    println!(
        "default  {}: {:.3} ms, worst mean {:.3e}, worst p99 {:.3e}",
        any::label(&default.setting),
        ms(default.time),
        default.worst_mean(),
        default.worst_p99()
    );
    let Some(best) = best else {
        println!("tuned:   none — no configuration is within {budget} at every scene (raise the knobs with --knob)");
        println!("wrote    {}", csv_path.display());
        return Err(ExitCode::from(1));
    };
    let saved = 1.0 - best.time.as_secs_f64() / default.time.as_secs_f64();
    println!(
        "tuned:   {} — {:.3} ms against the default's {:.3} ms ({:+.1} % time, {:.2}× speed-up), worst mean {:.3e}, \
         worst p99 {:.3e}",
        any::label(&best.setting),
        ms(best.time),
        ms(default.time),
        -100.0 * saved,
        default.time.as_secs_f64() / best.time.as_secs_f64(),
        best.worst_mean(),
        best.worst_p99()
    );
    if let Some((_, divisor)) = best.setting.iter().find(|(n, _)| n == SKY_RESOLUTION) {
        let words = match divisor {
            2 => "half (`render --sky-resolution half`)",
            4 => "quarter (`render --sky-resolution quarter`)",
            _ => "full",
        };
        println!("render:  at {words} sky resolution: a render option, not in the shader");
    }
    let baked: Vec<(String, i32, KnobKind)> =
        best.setting.iter().map(|(n, v)| (n.clone(), *v, sky.kind_of(n))).collect();
    let text = specialize_source(&sky.front, &baked).map_err(usage)?;
    let again = gdsky::measure::knobs::recheck(&sky.front, text.clone());
    if again.shader.is_none() {
        return Err(usage("the specialized shader does not check (a bug in gdsky; please report it)"));
    }
    let out = args.out_dir.join(&out_name);
    super::write_file(&out, text.as_bytes()).map_err(environment)?;
    println!("wrote    {} (knobs baked as consts) and {}", out.display(), csv_path.display());
    Ok(())
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// tune.csv: the knobs, time_ms, then mean and p99 at each scene.
fn csv(candidates: &[Candidate], names: &[String], suns: &[f64]) -> String {
    let mut out = String::new();
    for n in names {
        let _ = write!(out, "{n},");
    }
    out.push_str("time_ms");
    for s in suns {
        let _ = write!(out, ",mean_sun{s},p99_sun{s}");
    }
    out.push('\n');
    for c in candidates {
        for (_, v) in &c.setting {
            let _ = write!(out, "{v},");
        }
        let _ = write!(out, "{:.4}", ms(c.time));
        for e in &c.errors {
            let _ = write!(out, ",{:.6e},{:.6e}", e.mean, e.p99);
        }
        out.push('\n');
    }
    out
}
