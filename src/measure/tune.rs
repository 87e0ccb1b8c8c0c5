//! `gdsky tune FILE --max-error MEAN[,P99]`: the cheapest knob setting within an error budget.
//!
//! Over a set of scenes (default: the sun at 0, 10, 30, 60 and 90° over a panorama), every
//! configuration of the shader's quality knobs (the loop bounds [`crate::measure::knobs`]
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

use super::any::{self, Candidate, Shot};
use super::bench::{SamplingTruth, any_knobs, convergence_table};
use super::knobs::{KnobKind, SKY_RESOLUTION, combinations, specialize_source};
use super::stats;
use crate::engine::{self, Error, Progress};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Duration;

/// What [`tune`] looks for: the CLI's `gdsky tune` flags as values.
#[derive(Clone, Debug)]
pub struct TuneOptions {
    /// The sky shader to tune.
    pub file: PathBuf,
    /// The error budget at every scene: mean relative error, and optionally p99.
    pub max_error: (f64, Option<f64>),
    /// Sun elevations of the scenes, degrees (panoramas from 1 m up).
    pub suns: Vec<f64>,
    /// Image size of each scene.
    pub size: (u32, u32),
    /// TIME of every scene, seconds.
    pub time: f32,
    /// Knob sweeps `NAME=V1,V2,…` replacing or extending the defaults.
    pub knobs: Vec<String>,
    /// Timed renders per configuration (1 to 1000) after a warm-up; the median counts.
    pub runs: u32,
    /// The sampling truth (shaders that are not Freeman-compatible).
    pub sampling: SamplingTruth,
    /// Folder for the specialized shader and tune.csv (created if missing).
    pub out_dir: PathBuf,
}

/// What [`tune`] found.
#[derive(Clone, Debug)]
pub struct TuneReport {
    /// The report the CLI prints.
    pub text: String,
    /// The specialized shader, `<stem>.tuned.gdshader`, when a setting met the budget.
    pub shader: Option<PathBuf>,
    /// The winning setting (`view_samples=16, sun_samples=8`), when one met the budget.
    pub setting: Option<String>,
    /// `tune.csv`: every configuration.
    pub csv: PathBuf,
}

/// The truth images of `shots` for a Freeman-compatible shader: skyref's integral with the
/// shader's own uniform defaults.
fn freeman_truth(shader: &crate::CheckedShader, shots: &[Shot]) -> Result<Vec<Vec<[f64; 4]>>, String> {
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

/// Finds the cheapest knob setting within the budget (see the module documentation) and writes
/// the specialized shader and tune.csv into `options.out_dir`.
pub fn tune(options: &TuneOptions, progress: &dyn Progress) -> Result<TuneReport, Error> {
    let args = options;
    let mut out = String::new();
    let (mean_budget, p99_budget) = args.max_error;
    if args.suns.is_empty() {
        return Err(Error::input("--suns: give at least one sun elevation"));
    }
    let stem = args.file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "shader".into());
    let out_name = format!("{stem}.tuned.gdshader");
    engine::check_output_dir(&args.out_dir, true, &[&out_name, "tune.csv"])?;
    let front = crate::check_file(&args.file)
        .map_err(|e| Error::environment(format!("cannot read {}: {e}", args.file.display())))?;
    if front.shader.is_none() {
        return Err(Error::Diagnostics(crate::ConvertError::new(front.db, front.diagnostics)));
    }
    let sky = any::Sky::new(front, Vec::new()).map_err(Error::input)?;
    let shader = sky.front.shader.as_ref().ok_or_else(|| Error::input("the shader has errors"))?;
    let freeman = crate::measure::freeman::compatible(shader);
    if freeman && args.sampling.supersample.is_some() {
        return Err(Error::input(
            "--truth-supersample sets the sampling truth; a Freeman-compatible shader is measured against skyref's integrals",
        ));
    }
    let mut knobs = any_knobs(&sky, &args.knobs).map_err(Error::input)?;
    if let Some(knob) = args.sampling.sky_resolution_knob()? {
        if freeman {
            return Err(Error::input("--sky-resolution is swept for shaders that are not Freeman-compatible"));
        }
        knobs.push(knob);
    }
    if knobs.is_empty() {
        return Err(Error::input(format!(
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

    let gpu = engine::open_gpu(progress)?;
    let adapter = gpu.adapter_info();
    progress.start(1 + configs.len() as u64 * (1 + u64::from(args.runs)));
    let (truth, truth_text, converged) = if freeman {
        progress.message("truth: skyref's integral per scene");
        let images = freeman_truth(shader, &shots).map_err(Error::input)?;
        (images, "skyref::truth, the Freeman model's integrals (~1e-7)".to_string(), None)
    } else {
        let limits = args.sampling.limits();
        let c = any::converge(&gpu, &sky, &setting(&defaults), &raised, &shots, limits, |m| progress.message(m))
            .map_err(Error::input)?;
        let text = format!("the sampling truth: f64 at {}", any::label(&c.setting));
        (c.images.clone(), text, Some(c))
    };
    progress.step();

    // A configuration whose loops the device cuts short (lavapipe's budget of 65,535 loop
    // passes per pixel) renders faster and differently than on any other GPU: it is not a
    // candidate (the defaults stay, as the baseline, with a warning).
    let mut kept = Vec::with_capacity(configs.len());
    for values in configs {
        let canary = sky.variant(&setting(&values)).and_then(|v| v.compile_canary(&gpu)).map_err(Error::input)?;
        let pixels: usize =
            shots.iter().map(|s| canary.loops_cut(&gpu, s)).sum::<Result<_, _>>().map_err(Error::input)?;
        if pixels == 0 || values == defaults {
            if pixels > 0 {
                note!(
                    progress,
                    "warning: the device cuts the loops of {pixels} pixels short at the defaults (lavapipe's loop \
                     budget, docs/lavapipe-loop-limit.md): their time and error are the device's"
                );
            }
            kept.push(values);
        } else {
            let label = any::label(&setting(&values));
            note!(
                progress,
                "skipped: {label}: the device cuts the loops of {pixels} pixels short (lavapipe's loop budget)"
            );
        }
    }
    let configs = kept;
    let mut compiled = Vec::with_capacity(configs.len());
    let mut candidates = Vec::with_capacity(configs.len());
    for values in &configs {
        progress.message(&format!("{}: compile and error", any::label(&setting(values))));
        let c = sky.variant(&setting(values)).and_then(|v| v.compile(&gpu)).map_err(Error::input)?;
        let mut errors = Vec::with_capacity(shots.len());
        for (shot, truth) in shots.iter().zip(&truth) {
            let (image, _) = c.render(&gpu, shot).map_err(Error::input)?;
            errors.push(stats::error_stats(&image, truth));
        }
        candidates.push(Candidate { setting: setting(values), errors, time: Duration::ZERO });
        compiled.push(c);
        progress.step();
    }
    // Interleaved rounds: every configuration once per round, so load from elsewhere spreads
    // over all of them and the ratio to the defaults comes from the same rounds.
    let mut times = vec![Vec::with_capacity(args.runs as usize); configs.len()];
    for run in 0..args.runs {
        progress.message(&format!("timing: round {} of {}", run + 1, args.runs));
        for (c, t) in compiled.iter().zip(&mut times) {
            let mut total = Duration::ZERO;
            for shot in &shots {
                total += c.render(&gpu, shot).map_err(Error::input)?.1;
            }
            t.push(total);
            progress.step();
        }
    }
    progress.finish();
    for (c, t) in candidates.iter_mut().zip(&mut times) {
        t.sort();
        c.time = (t[(t.len() - 1) / 2] + t[t.len() / 2]) / 2;
    }
    let default_setting = setting(&defaults);
    let default = candidates.iter().find(|c| c.setting == default_setting).ok_or(Error::input("failed"))?;
    let best = any::cheapest(&candidates, mean_budget, p99_budget);

    say!(
        out,
        "gdsky tune: {}, {} configurations × {} scenes (sun {}°), {w}x{h} panorama",
        args.file.display(),
        candidates.len(),
        shots.len(),
        args.suns.iter().map(|s| s.to_string()).collect::<Vec<_>>().join(", ")
    );
    say!(out, "adapter  {adapter}");
    say!(out, "truth    {truth_text}");
    if let Some(c) = &converged {
        out.push_str(&convergence_table(c));
    }
    let budget = match p99_budget {
        Some(p) => format!("mean ≤ {mean_budget:e} and p99 ≤ {p:e}"),
        None => format!("mean ≤ {mean_budget:e}"),
    };
    say!(
        out,
        "budget   {budget} at every scene, no NaN/Inf; time = median of {} (all scenes, interleaved rounds)",
        args.runs
    );
    let mut sorted: Vec<&Candidate> = candidates.iter().collect();
    sorted.sort_by_key(|c| c.time);
    say!(out, "  {:<36} {:>9} {:>11} {:>11}  within", "configuration", "time ms", "worst mean", "worst p99");
    for c in &sorted {
        let mark = if c.within(mean_budget, p99_budget) { "yes" } else { "" };
        let default_mark = if c.setting == default_setting { " (default)" } else { "" };
        say!(
            out,
            "  {:<36} {:>9.3} {:>11.3e} {:>11.3e}  {mark}",
            format!("{}{default_mark}", any::label(&c.setting)),
            ms(c.time),
            c.worst_mean(),
            c.worst_p99()
        );
    }
    engine::create_output_dir(&args.out_dir)?;
    let csv_path = args.out_dir.join("tune.csv");
    engine::write_file(&csv_path, csv(&candidates, &names, &args.suns).as_bytes()).map_err(Error::environment)?;
    say!(
        out,
        "default  {}: {:.3} ms, worst mean {:.3e}, worst p99 {:.3e}",
        any::label(&default.setting),
        ms(default.time),
        default.worst_mean(),
        default.worst_p99()
    );
    let Some(best) = best else {
        say!(out, "tuned:   none — no configuration is within {budget} at every scene (raise the knobs with --knob)");
        say!(out, "wrote    {}", csv_path.display());
        return Ok(TuneReport { text: out, shader: None, setting: None, csv: csv_path });
    };
    let saved = 1.0 - best.time.as_secs_f64() / default.time.as_secs_f64();
    say!(
        out,
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
        say!(out, "render:  at {words} sky resolution: a render option, not in the shader");
    }
    let baked: Vec<(String, i32, KnobKind)> =
        best.setting.iter().map(|(n, v)| (n.clone(), *v, sky.kind_of(n))).collect();
    let text = specialize_source(&sky.front, &baked).map_err(Error::input)?;
    let again = crate::measure::knobs::recheck(&sky.front, text.clone());
    if again.shader.is_none() {
        return Err(Error::input("the specialized shader does not check (a bug in gdsky; please report it)"));
    }
    let path = args.out_dir.join(&out_name);
    engine::write_file(&path, text.as_bytes())?;
    say!(out, "wrote    {} (knobs baked as consts) and {}", path.display(), csv_path.display());
    Ok(TuneReport { text: out, shader: Some(path), setting: Some(any::label(&best.setting)), csv: csv_path })
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
