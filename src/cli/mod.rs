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
pub mod preview;
pub mod progress;
pub mod render;
pub mod scene;
pub mod stress;
pub mod tune;

use gdsky::engine::Error;
use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;

/// The environment variable that sets the driver budget in seconds (0: no watch).
pub const DRIVER_BUDGET_VAR: &str = "GDSKY_DRIVER_BUDGET";

/// The driver budget when [`DRIVER_BUDGET_VAR`] is unset: far above any real sky's pipeline build
/// on lavapipe (the Freeman sky's takes about a second, the heaviest corpus shader's a few), far
/// below "hung".
pub const DEFAULT_DRIVER_BUDGET_S: u64 = 120;

/// What the command works on, for the driver budget's message (set once by [`watch_driver`]).
static SUBJECT: std::sync::OnceLock<String> = std::sync::OnceLock::new();

/// Watches the driver for a GPU command on `subject` (its FILE; `None`: the bundled Freeman sky):
/// a pipeline build or a render's wait that passes the budget ends the command with exit 1 and
/// a message naming the shader, the budget and how to raise it (`skyrun::DriverBudget`). The
/// budget is [`DEFAULT_DRIVER_BUDGET_S`] unless `GDSKY_DRIVER_BUDGET=SECONDS` says otherwise;
/// wrong input when that is not a whole number of seconds.
pub fn watch_driver(subject: Option<&Path>) -> Result<(), Error> {
    let seconds = match std::env::var(DRIVER_BUDGET_VAR) {
        Err(_) => DEFAULT_DRIVER_BUDGET_S,
        Ok(text) => text.trim().parse::<u64>().map_err(|_| {
            Error::input(format!("{DRIVER_BUDGET_VAR}={text}: expected a whole number of seconds (0: no budget)"))
        })?,
    };
    if seconds == 0 {
        return Ok(());
    }
    let name = subject.map_or_else(|| gdsky::engine::BUNDLED_NAME.to_string(), |p| p.display().to_string());
    let _ = SUBJECT.set(name);
    skyrun::set_driver_budget(skyrun::DriverBudget {
        limit: std::time::Duration::from_secs(seconds),
        expired: driver_expired,
    });
    Ok(())
}

fn driver_expired(what: &str, limit: std::time::Duration) -> ! {
    let subject = SUBJECT.get().map(String::as_str).unwrap_or("the shader");
    errln!(
        "error: {subject}: {what} took longer than {} s, the driver budget; raise it with {DRIVER_BUDGET_VAR}=SECONDS \
         (0: no budget) if the shader is meant to be this heavy",
        limit.as_secs()
    );
    std::process::exit(1);
}

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
