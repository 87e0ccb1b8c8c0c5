//! `gdsky animate SCENE.toml -o DIR`: a sequence of frames, each view rendered only when an input
//! it shows changed (the engine and its rules: [`gdsky::measure::animate`]).

use super::progress::Bar;
use super::scene::{SceneArgs, SkipArgs, given};
use clap::{ArgMatches, Args};
use gdsky::engine::{Error, Input};
use gdsky::measure::animate::{self, AnimateOptions};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct AnimateArgs {
    /// The scene file; its `[animate]` table gives the frames (without one, a single frame). A
    /// Godot material or scene (`MATERIAL.tres`, `SCENE.tscn`) gives its shader, values and
    /// textures, and no `[animate]`: a single frame.
    #[arg(value_name = "SCENE.toml|MATERIAL.tres|SCENE.tscn")]
    scene_file: PathBuf,
    /// Folder for frame_NNNN.exr, frame_NNNN.png and animate.csv (created if missing; checked
    /// before any work).
    #[arg(short = 'o', long = "out-dir", value_name = "DIR")]
    out_dir: PathBuf,
    /// Bake every uniform the scene fixes and no keyframe moves (and every `--set`) into the
    /// shader as constants.
    #[arg(long)]
    bake_scene: bool,
    /// Emit a scalar uniform as a pipeline-overridable constant: one module for the sequence,
    /// each frame's value given at pipeline creation (a changed value rebuilds the pipeline,
    /// which costs a shader compile). Adds to the scene file's `overrides`. Repeatable.
    #[arg(long = "override", value_name = "NAME")]
    overrides: Vec<String>,
    /// Render every frame (no reuse; incremental mode still renders one face a frame).
    #[arg(long)]
    no_reuse: bool,
    /// Skip the second pass that renders every frame to measure the time saved.
    #[arg(long)]
    no_baseline: bool,
    /// Flags given here override the scene file (and pin what they set: a `--sun` given here
    /// replaces the sun's keyframes too).
    #[command(flatten)]
    scene: SceneArgs,
    /// Occluder and sky resolution, as `render`'s (the scene file's `occluder` and
    /// `sky_resolution` unless given here).
    #[command(flatten)]
    skip: SkipArgs,
}

pub fn run(args: &AnimateArgs, matches: &ArgMatches) -> ExitCode {
    super::exit(animate_command(args, matches))
}

fn animate_command(args: &AnimateArgs, matches: &ArgMatches) -> Result<(), Error> {
    super::watch_driver(Some(&args.scene_file))?;
    if !gdsky::scene::is_scene_path(&args.scene_file) && !gdsky::scene::is_godot_resource(&args.scene_file) {
        return Err(Error::input(format!(
            "{}: `animate` takes a scene file (.toml) or a Godot material or scene (.tres, .tscn)",
            args.scene_file.display()
        )));
    }
    let input = Input::open(Some(&args.scene_file))?;
    err!("{}", input.warnings);
    let file = input.scene.ok_or_else(|| Error::input("not a scene file"))?;
    let mut base = args.scene.clone();
    base.merge_file(&file, matches);
    let mut skip = args.skip.clone();
    skip.merge_file(&file, matches);
    let setup = base.setup()?;
    let occluder = skip.occluder(&setup.views()?, setup.width, setup.height)?;
    let pinned = ["time", "sun", "position", "yaw", "pitch", "fov"].into_iter().filter(|id| given(matches, id));
    let options = AnimateOptions {
        shader: input.shader,
        pinned: pinned.map(String::from).collect(),
        flag_sets: args.scene.setup()?.sets,
        setup,
        scene_file: file,
        occluder,
        sky_resolution: skip.sky_resolution,
        upsample: skip.upsample,
        out_dir: args.out_dir.clone(),
        bake_scene: args.bake_scene,
        overrides: args.overrides.clone(),
        no_reuse: args.no_reuse,
        no_baseline: args.no_baseline,
    };
    let report = animate::animate(&options, &Bar::new())?;
    out!("{}", report.text);
    Ok(())
}
