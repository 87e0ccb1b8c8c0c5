//! `gdsky stress [FILE] [--quick]`: numerical stability (the engine:
//! [`gdsky::measure::stress`]).

use super::progress::Bar;
use clap::Args;
use gdsky::engine::{Error, Input};
use gdsky::measure::stress::{self, Reference, StressOptions};
use std::path::PathBuf;
use std::process::ExitCode;

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
    #[arg(long, value_parser = super::named::<Reference>(&Reference::NAMES))]
    reference: Option<Reference>,
    /// For a shader that is not Freeman-compatible: a texture for a sampler uniform, as on
    /// `render` (`NAME=PATH`: EXR or PNG; six faces or a cross for a samplerCube, slices for a
    /// sampler3D), bound in every case, f32 and f64; over a scene file's `[textures]` and a Godot
    /// material's. Repeatable.
    #[arg(long = "texture", value_name = "NAME=PATH")]
    textures: Vec<String>,
}

pub fn run(args: &StressArgs) -> ExitCode {
    super::exit(stress_command(args))
}

fn stress_command(args: &StressArgs) -> Result<(), Error> {
    super::watch_driver(args.file.as_deref())?;
    let input = Input::open(args.file.as_deref())?;
    err!("{}", input.warnings);
    let options = StressOptions {
        shader: input.shader,
        scene_file: input.scene,
        quick: args.quick,
        out_dir: args.out_dir.clone(),
        reference: args.reference,
        textures: args.textures.clone(),
    };
    let report = stress::stress(&options, &Bar::new())?;
    out!("{}", report.text);
    let (nan, inf) = report.nonfinite_at_defaults;
    // A quick run is CI's: NaN or Inf at the shader's own defaults fails it.
    if args.quick && nan + inf > 0 {
        return Err(Error::input(format!("NaN/Inf at default uniforms ({nan} NaN, {inf} Inf channels)")));
    }
    Ok(())
}
