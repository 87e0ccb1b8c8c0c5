//! One module per subcommand, and what they share.

pub mod animate;
pub mod bake_lut;
pub mod bench;
pub mod bench_skip;
pub mod check;
pub mod compare;
pub mod convert;
pub mod demo;
pub mod oracle;
pub mod render;
pub mod scene;
pub mod stress;
pub mod sweep;
pub mod tune;

use std::path::Path;
use std::process::ExitCode;

/// A clap parser for a value read by its name (`FromStr`), one of `names`, which `--help` lists:
/// the flags take the vocabulary types themselves (a projection, a sky resolution, a filter)
/// rather than mirrors of them.
pub fn named<T>(names: &'static [&'static str]) -> impl clap::builder::TypedValueParser<Value = T>
where
    T: std::str::FromStr<Err = String> + Clone + Send + Sync + 'static,
{
    use clap::builder::TypedValueParser as _;
    clap::builder::PossibleValuesParser::new(names).try_map(|name| name.parse::<T>())
}

/// Checks, before any work, that `path` can be written (see [`skycore::io`]: a regular file,
/// absent in an existing directory, or a symbolic link to one; never a directory, device, FIFO or
/// socket; the directory writable). Exit 2 with the reason: the environment is wrong.
pub fn check_output(path: &Path) -> Result<(), ExitCode> {
    skycore::io::check_output(path)
        .map(drop)
        .map_err(|err| environment(format!("cannot write {}: {err}", path.display())))
}

/// Checks, before any work, an output folder and the files the command will write into it:
/// the folder exists or, with `create`, can be created; each file that exists there can be
/// replaced. Exit 2 with the reason.
pub fn check_output_dir(dir: &Path, create: bool, files: &[&str]) -> Result<(), ExitCode> {
    skycore::io::check_output_dir(dir, create)
        .map_err(|err| environment(format!("cannot write into {}: {err}", dir.display())))?;
    if dir.is_dir() {
        for file in files {
            check_output(&dir.join(file))?;
        }
    }
    Ok(())
}

/// Creates an output folder (when the outputs are ready, after [`check_output_dir`]). Exit 2.
pub fn create_output_dir(dir: &Path) -> Result<(), ExitCode> {
    skycore::io::create_output_dir(dir).map_err(|err| environment(format!("cannot create {}: {err}", dir.display())))
}

/// Writes `bytes` to `path` with the one safe, atomic writer ([`skycore::io::write_atomically`]);
/// the error names the file.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), String> {
    skycore::io::write_atomically(path, bytes).map_err(|err| format!("cannot write {}: {err}", path.display()))
}

/// Prints `message` as an error and gives exit code 1: the input is wrong (CLI contract).
pub fn usage(message: impl std::fmt::Display) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(1)
}

/// Prints `message` as an error and gives exit code 2: the environment is wrong (no adapter, a
/// file that cannot be read or written).
pub fn environment(message: impl std::fmt::Display) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(2)
}
