//! `gdsky oracle FILE [scene flags] -o godot.exr`: the shader rendered by real Godot 4.6 (the
//! engine: [`gdsky::engine::oracle`]), so `gdsky compare` can hold `gdsky render` against Godot.

use super::scene::SceneArgs;
use clap::Args;
use gdsky::engine::{self, Error, Notes, oracle::OracleOptions};
use skycore::Projection;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct OracleArgs {
    /// The sky shader to render in Godot; without one, the bundled Freeman sky. `#include` is not
    /// available in the oracle (Godot's Web export has no project files to include). A Godot
    /// material or scene (`MATERIAL.tres`, `SCENE.tscn`) gives its shader, its values (under
    /// `--set`) and its NoiseTexture2Ds, gradient and curve textures, which Godot
    /// generates itself; image textures cannot be given to the oracle yet.
    #[arg(value_name = "FILE | MATERIAL.tres | SCENE.tscn")]
    file: Option<PathBuf>,
    /// The EXR to write: the recovered linear COLOR, RGBA 32-bit float (alpha 1), row 0 at the top.
    #[arg(short = 'o', long = "out", value_name = "OUT.exr")]
    out: PathBuf,
    /// Also write an 8-bit PNG preview, tone mapped as `render`'s.
    #[arg(long, value_name = "OUT.png")]
    png: Option<PathBuf>,
    /// Where the oracle is installed: the folder holding `.oracle/` (`bash
    /// scripts/install-oracle.sh` puts it at the repository root) [default: the source tree this
    /// binary was built from].
    #[arg(long, value_name = "DIR")]
    oracle_root: Option<PathBuf>,
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    lowering: super::scene::LoweringArgs,
}

pub fn run(args: &OracleArgs) -> ExitCode {
    super::exit(oracle(args))
}

fn oracle(args: &OracleArgs) -> Result<(), Error> {
    if args.scene.projection.is_some_and(|p| p != Projection::Camera) {
        return Err(Error::input("the oracle renders Godot's camera view only: use --projection camera"));
    }
    let scene = SceneArgs { projection: Some(Projection::Camera), ..args.scene.clone() };
    engine::check_image_output(&args.out)?;
    if let Some(png) = &args.png {
        engine::check_image_output(png)?;
    }
    let options = OracleOptions {
        file: args.file.clone(),
        setup: scene.setup()?,
        lowering: args.lowering.options(),
        root: args.oracle_root.clone().unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR"))),
    };
    let image = engine::oracle::render(&options, &Notes)?;
    outln!("{}", engine::write_image(&image, &args.out)?);
    if let Some(png) = &args.png {
        outln!("{}", engine::write_image(&image, png)?);
    }
    Ok(())
}
