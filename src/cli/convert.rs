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
        Some(path) => match gdsky::godot::check_file(path) {
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
    let mut lowered = match gdsky_naga::lower_with_overrides(&front, &baked, &overrides) {
        Ok(l) => l,
        Err(diags) => {
            eprint!("{}", render_human(&front.db, &diags, color));
            return ExitCode::from(1);
        }
    };
    if args.reversed_z {
        gdsky_naga::wrapper::set_far_plane_depth(&mut lowered.module, gdsky_naga::wrapper::FAR_PLANE_REVERSED);
    }
    // Both texts come back re-read and validated by naga's own front ends, or not at all;
    // overrides are specialization constants in the SPIR-V.
    let emitted = gdsky_naga::to_wgsl(&lowered).and_then(|w| Ok((w, gdsky_naga::to_spirv(&lowered)?)));
    let (wgsl, spirv) = match emitted {
        Ok((w, words)) => (w, words.iter().flat_map(|w| w.to_le_bytes()).collect::<Vec<u8>>()),
        Err(err) => {
            eprint!("{}", render_human(&front.db, &[err.diagnostic(&front)], color));
            return ExitCode::from(1);
        }
    };
    let reflection = gdsky_naga::reflect::reflection(&stem, shader, &lowered, &baked);
    let json = match serde_json::to_string_pretty(&reflection) {
        Ok(j) => j + "\n",
        Err(err) => {
            eprintln!("error: cannot write the reflection: {err}");
            return ExitCode::from(1);
        }
    };
    if let Err(code) = super::create_output_dir(&args.out_dir) {
        return code;
    }
    for (name, bytes) in names.iter().zip([wgsl.as_bytes(), spirv.as_slice(), json.as_bytes()]) {
        let path = args.out_dir.join(name);
        if let Err(message) = super::write_file(&path, bytes) {
            return super::environment(message);
        }
        println!("wrote {} ({} bytes)", path.display(), bytes.len());
    }
    ExitCode::SUCCESS
}
