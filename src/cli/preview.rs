//! `gdsky preview FILE [--port N] [--no-open]`: the flags and the scene as `render` reads them,
//! then [`gdsky::preview::Preview`].

use super::scene::SceneArgs;
use clap::{ArgMatches, Args};
use gdsky::engine::{Error, Input};
use gdsky::preview::{PageState, Preview, load_state};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct PreviewArgs {
    /// The sky shader (`.gdshader`), a Godot material (`MATERIAL.tres`) or scene
    /// (`SCENE.tscn`), or a scene file (`SCENE.toml`), read as `render` reads it; without one,
    /// the bundled Freeman sky.
    #[arg(value_name = "FILE.gdshader | MATERIAL.tres | SCENE.toml")]
    file: Option<PathBuf>,
    /// Port on 127.0.0.1 to serve on; 0 picks a free one (the address is printed).
    #[arg(long, default_value_t = 7780)]
    port: u16,
    /// Serve without opening a browser.
    #[arg(long)]
    no_open: bool,
    /// The scene the page starts from (the page changes it afterwards); values (`--set`) and
    /// textures (`--texture`) as `render` takes them.
    #[command(flatten)]
    scene: SceneArgs,
}

pub fn run(args: &PreviewArgs, matches: &ArgMatches) -> ExitCode {
    let file = args.file.clone();
    let scene = args.scene.clone();
    let matches = matches.clone();
    let mut reload = move || -> Result<PageState, Error> {
        let input = Input::open(file.as_deref())?;
        let mut scene = scene.clone();
        if let Some(file) = &input.scene {
            scene.merge_file(file, &matches);
        }
        let setup = scene.setup()?;
        load_state(&input, &setup)
    };
    let preview = match Preview::bind(args.port, &mut reload) {
        Ok(p) => p,
        Err(e) => return super::environment(format!("{e} (another `gdsky preview`? `--port 0` picks a free port)")),
    };
    let url = preview.url();
    outln!("gdsky preview: serving {url} (Ctrl-C stops)");
    if !args.no_open && webbrowser::open(&url).is_err() {
        errln!("no browser could be opened: open {url} in one with WebGPU");
    }
    let changed = Box::new(|outcome: Result<u64, String>| match outcome {
        Ok(version) => outln!("reloaded (version {version})"),
        Err(text) => errln!("{}", text.trim_end()),
    });
    match preview.serve(Box::new(reload), changed) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => super::environment(e.to_string()),
    }
}
