//! One module per subcommand, and what they share.

/// `println!` that never panics (see [`edge`]).
macro_rules! outln {
    ($($arg:tt)*) => { $crate::cli::edge::out(format_args!("{}\n", format_args!($($arg)*))) };
}
/// `print!` that never panics (see [`edge`]).
macro_rules! out {
    ($($arg:tt)*) => { $crate::cli::edge::out(format_args!($($arg)*)) };
}
/// `eprintln!` that never panics (see [`edge`]).
macro_rules! errln {
    ($($arg:tt)*) => { $crate::cli::edge::err(format_args!("{}\n", format_args!($($arg)*))) };
}
/// `eprint!` that never panics (see [`edge`]).
macro_rules! err {
    ($($arg:tt)*) => { $crate::cli::edge::err(format_args!($($arg)*)) };
}

pub mod animate;
pub mod bake_lut;
pub mod bench;
pub mod check;
pub mod compare;
pub mod convert;
pub mod demo;
pub mod edge;
pub mod oracle;
pub mod progress;
pub mod render;
pub mod scene;
pub mod stress;
pub mod tune;

use gdsky::engine::Error;
use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;

/// Whether stderr shows colours: a terminal, and `NO_COLOR` unset.
pub fn color() -> bool {
    std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none()
}

/// Prints an engine's error on stderr and gives its exit code (1 wrong input, 2 wrong
/// environment: the CLI contract).
pub fn fail(err: Error) -> ExitCode {
    err!("{}", err.render(color()));
    ExitCode::from(err.exit_code())
}

/// The exit code of a command's outcome, its error printed.
pub fn exit(outcome: Result<(), Error>) -> ExitCode {
    outcome.map_or_else(fail, |()| ExitCode::SUCCESS)
}

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

/// Prints `message` as an error and gives exit code 1: the input is wrong (CLI contract).
pub fn usage(message: impl std::fmt::Display) -> ExitCode {
    errln!("error: {message}");
    ExitCode::from(1)
}

/// Prints `message` as an error and gives exit code 2: the environment is wrong (no adapter, a
/// file that cannot be read or written).
pub fn environment(message: impl std::fmt::Display) -> ExitCode {
    errln!("error: {message}");
    ExitCode::from(2)
}
