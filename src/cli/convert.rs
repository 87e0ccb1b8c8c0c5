//! `gdsky convert FILE|SCENE.toml [-o DIR] [--set NAME=VALUE]... [--override NAME]... [--bake-scene]`
//! (the engine: [`gdsky::engine::convert`]).

use clap::Args;
use gdsky::engine::{self, Error, Input, convert::ConvertOptions};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Args)]
pub struct ConvertArgs {
    /// The sky shader (`.gdshader`) to convert, or a scene file (`SCENE.toml`) whose shader to
    /// convert (the bundled Freeman sky when it names none).
    #[arg(value_name = "FILE|SCENE.toml")]
    file: PathBuf,
    /// Bake every uniform the scene file fixes into the shader as constants (with `--set`
    /// over them); with no scene file, every uniform at its default. The reflection's `baked`
    /// lists them.
    #[arg(long)]
    bake_scene: bool,
    /// Directory to write `<stem>.wgsl`, `<stem>.spv` and `<stem>.json` into (created if missing;
    /// checked before converting).
    #[arg(short = 'o', long = "out-dir", value_name = "DIR", default_value = ".")]
    out_dir: PathBuf,
    /// Bake a uniform into the shader as a constant: `--set view_samples=16`,
    /// `--set ground_color=0.1,0.1,0.1`. Baked uniforms leave the material block.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Emit a scalar uniform as a WGSL `override` (`@id(k)` for the k-th `--override`, its
    /// default the uniform's) instead of a member of the material block: one module serves many
    /// values, given at pipeline creation. The reflection's `overrides` lists them. In the `.spv`
    /// each is a specialization constant (`OpSpecConstant`, `SpecId` k). Adds to the scene
    /// file's `overrides`.
    #[arg(long = "override", value_name = "NAME")]
    overrides: Vec<String>,
    /// Reversed Z: the vertex entry puts the sky at depth 0 (the far plane when near is 1; depth
    /// test GreaterEqual, clear 0) instead of 1. The reflection's `depth` says which.
    #[arg(long)]
    reversed_z: bool,
    /// Write SPIR-V debug names (`OpName`: readable disassembly, about 12 % more bytes). Without
    /// it the SPIR-V is the same bytes from every build of gdsky.
    #[arg(long)]
    debug_names: bool,
    #[command(flatten)]
    lowering: super::scene::LoweringArgs,
}

pub fn run(args: &ConvertArgs) -> ExitCode {
    super::exit(convert(args))
}

fn convert(args: &ConvertArgs) -> Result<(), Error> {
    let sets = args
        .set
        .iter()
        .map(|s| match s.split_once('=') {
            Some((name, value)) => Ok((name.trim().to_string(), value.trim().to_string())),
            None => Err(Error::input(format!("`--set {s}`: expected NAME=VALUE"))),
        })
        .collect::<Result<Vec<_>, _>>()?;
    let input = Input::open(Some(&args.file))?;
    err!("{}", input.warnings);
    // Where the outputs go is checked before any work: -o DIR is created when missing (from its
    // nearest existing ancestor), and none of the three files may be a directory or special file.
    let stem = match &input.shader {
        Some(path) => path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "shader".into()),
        None => "freeman_sky".into(),
    };
    let names = ["wgsl", "spv", "json"].map(|ext| format!("{stem}.{ext}"));
    engine::check_output_dir(&args.out_dir, true, &names.each_ref().map(String::as_str))?;
    let outputs: Vec<PathBuf> = names.iter().map(|n| args.out_dir.join(n)).collect();
    let inputs: Vec<&Path> = [Some(args.file.as_path()), input.shader.as_deref()].into_iter().flatten().collect();
    engine::check_outputs_apart(&outputs.iter().map(PathBuf::as_path).collect::<Vec<_>>(), &inputs)?;
    let options = gdsky::Options::new()
        .debanding(args.lowering.debanding)
        .sky_coords(args.lowering.sky_coords)
        .depth(if args.reversed_z { gdsky::DepthConvention::Reversed } else { gdsky::DepthConvention::Standard })
        .spirv_debug_names(args.debug_names);
    let mut options = ConvertOptions { input: Some(input), sets, bake_scene: args.bake_scene, options };
    options.options.lowering.overrides = args.overrides.clone();
    let converted = engine::convert::convert(&options)?;
    err!("{}", converted.warnings);
    let json = converted.reflection_json() + "\n";
    let spirv = converted.spirv_bytes();
    engine::create_output_dir(&args.out_dir)?;
    let paths = names.map(|name| args.out_dir.join(name));
    let files = [
        (paths[0].as_path(), converted.wgsl.as_bytes()),
        (paths[1].as_path(), spirv.as_slice()),
        (paths[2].as_path(), json.as_bytes()),
    ];
    // Written as a set: all three new, or (on a failure) all three as they were.
    skycore::io::write_set(&files)
        .map_err(|err| Error::environment(format!("cannot write into {}: {err}", args.out_dir.display())))?;
    for (path, bytes) in files {
        outln!("wrote {} ({} bytes)", path.display(), bytes.len());
    }
    Ok(())
}
