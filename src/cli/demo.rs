//! `gdsky demo`: the whole pipeline on the bundled Freeman sky, in one command (the engine:
//! [`gdsky::engine::demo`]).

use super::progress::Bar;
use clap::Args;
use gdsky::engine::{Error, demo};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct DemoArgs {
    /// Folder to write the outputs into (created if missing; checked before any work).
    #[arg(short = 'o', long = "out-dir", value_name = "DIR", default_value = "out")]
    out_dir: PathBuf,
}

pub fn run(args: &DemoArgs) -> ExitCode {
    super::exit(demo_command(args))
}

fn demo_command(args: &DemoArgs) -> Result<(), Error> {
    super::watch_driver(None)?;
    let bar = Bar::new();
    let report = demo::demo(&args.out_dir, &bar)?;
    drop(bar);
    out!("{}", report.text);
    if report.pass { Ok(()) } else { Err(Error::input("the converted sky is not within the bound")) }
}
