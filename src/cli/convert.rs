//! `gdsky convert FILE|SCENE.toml [-o DIR] [--set NAME=VALUE]... [--override NAME]... [--bake-scene]`

use clap::Args;
use gdsky::frontend::diag::render_human;
use std::collections::HashMap;
use std::io::IsTerminal;
use std::path::PathBuf;
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
    let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
    let mut sets = Vec::new();
    for s in &args.set {
        let Some((name, value)) = s.split_once('=') else {
            eprintln!("error: `--set {s}`: expected NAME=VALUE");
            return ExitCode::from(1);
        };
        sets.push((name.trim().to_string(), value.trim().to_string()));
    }
    let input = match super::scene::open_input(Some(&args.file)) {
        Ok(input) => input,
        Err(code) => return code,
    };
    // Where the outputs go is checked before any work: -o DIR is created when missing (from its
    // nearest existing ancestor), and none of the three files may be a directory or special file.
    let stem = match &input.shader {
        Some(path) => path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "shader".into()),
        None => "freeman_sky".into(),
    };
    let names = ["wgsl", "spv", "json"].map(|ext| format!("{stem}.{ext}"));
    if let Err(code) = super::check_output_dir(&args.out_dir, true, &names.each_ref().map(String::as_str)) {
        return code;
    }
    let front = match &input.shader {
        Some(path) => match gdresource::check_file(path) {
            Ok(f) => f,
            Err(err) => {
                eprintln!("error: cannot read {}: {err}", path.display());
                return ExitCode::from(2);
            }
        },
        None => gdsky::check_source(
            super::scene::BUNDLED_NAME,
            super::scene::BUNDLED_FREEMAN.as_bytes().to_vec(),
            None,
            &mut gdsky::frontend::FsLoader,
        ),
    };
    eprint!("{}", render_human(&front.db, &front.diagnostics, color));
    let Some(shader) = front.shader.as_ref() else {
        return ExitCode::from(1);
    };
    if let Some(scene) = &input.scene
        && let Err(message) = scene.check_uniforms(shader)
    {
        eprint!("{message}");
        return ExitCode::from(1);
    }
    let overrides = super::scene::override_names(input.scene.as_ref(), &args.overrides);
    // `--set` always bakes in `convert`; under --bake-scene the scene's uniforms do too.
    if let Err(code) = super::scene::check_override_conflicts(&overrides, input.scene.as_ref(), |n| {
        if sets.iter().any(|(s, _)| s == n) {
            Some(format!("`--set {n}=…` bakes `{n}` into a constant"))
        } else {
            super::scene::bake_reason(n, input.scene.as_ref(), &sets, args.bake_scene)
        }
    }) {
        return code;
    }
    let mut baked: HashMap<String, String> = if args.bake_scene {
        gdsky::scene::bake_values(shader, input.scene.as_ref(), &sets)
    } else {
        sets.into_iter().collect()
    };
    // Baking "every uniform at its default" leaves the overrides alone.
    baked.retain(|name, _| !overrides.contains(name));
    let mut options = gdsky::Options::new()
        .debanding(args.lowering.debanding)
        .sky_coords(args.lowering.sky_coords)
        .depth(if args.reversed_z { gdsky::DepthConvention::Reversed } else { gdsky::DepthConvention::Standard })
        .spirv_debug_names(args.debug_names);
    options.set = baked.into_iter().collect();
    options.overrides = overrides;
    let lowered = match gdsky_naga::lower(&front, &options.lower_options()) {
        Ok(l) => l,
        Err(diags) => {
            eprint!("{}", render_human(&front.db, &diags, color));
            return ExitCode::from(1);
        }
    };
    // Both texts come back re-read and validated by naga's own front ends, or not at all;
    // overrides are specialization constants in the SPIR-V.
    let converted = match gdsky::emit(front, &lowered, &options) {
        Ok(c) => c,
        Err(e) => {
            eprint!("{}", e.render(color));
            return ExitCode::from(1);
        }
    };
    let json = converted.reflection_json() + "\n";
    let wgsl = converted.wgsl.into_bytes();
    let spirv = converted.spirv.iter().flat_map(|w| w.to_le_bytes()).collect::<Vec<u8>>();
    if let Err(code) = super::create_output_dir(&args.out_dir) {
        return code;
    }
    let paths = names.map(|name| args.out_dir.join(name));
    let files = [
        (paths[0].as_path(), wgsl.as_slice()),
        (paths[1].as_path(), spirv.as_slice()),
        (paths[2].as_path(), json.as_bytes()),
    ];
    // Written as a set: all three new, or (on a failure) all three as they were.
    if let Err(err) = skycore::io::write_set(&files) {
        return super::environment(format!("cannot write into {}: {err}", args.out_dir.display()));
    }
    for (path, bytes) in files {
        println!("wrote {} ({} bytes)", path.display(), bytes.len());
    }
    ExitCode::SUCCESS
}
