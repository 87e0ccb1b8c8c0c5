//! `gdsky tune FILE --max-error MEAN[,P99]`: the cheapest knob setting within an error budget
//! (the engine: [`gdsky::measure::tune`]).

use super::bench::SamplingTruthArgs;
use super::progress::Bar;
use clap::Args;
use gdsky::engine::Error;
use gdsky::measure::tune::{self, TuneOptions};
use std::path::PathBuf;
use std::process::ExitCode;

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
    super::exit(tune_command(args))
}

fn tune_command(args: &TuneArgs) -> Result<(), Error> {
    super::watch_driver(Some(&args.file))?;
    let options = TuneOptions {
        file: args.file.clone(),
        max_error: args.max_error,
        suns: args.suns.clone(),
        size: args.size,
        time: args.time,
        knobs: args.knobs.clone(),
        runs: args.runs,
        sampling: args.truth_args.options(),
        out_dir: args.out_dir.clone(),
    };
    let report = tune::tune(&options, &Bar::new())?;
    out!("{}", report.text);
    if report.shader.is_none() {
        // Nothing met the budget: the input asked for what the shader cannot give.
        return Err(Error::input("no configuration is within the budget"));
    }
    Ok(())
}
