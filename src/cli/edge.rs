//! Writing to stdout and stderr at the process edge without panicking.
//!
//! Rust's `print!` family panics when a write fails ("failed printing to stdout", exit 101): a
//! closed pipe (`gdsky check bad/*.gdshader 2>&1 | head -c 10`) or a full device (`> /dev/full`).
//! Every line the CLI prints goes through [`out`] and [`err`] instead, by the `outln!`, `out!`,
//! `errln!` and `err!` macros of `cli/mod.rs`:
//!
//! * stdout closed (`BrokenPipe`): the reader has all it wanted, so the command ends quietly with
//!   status 141, what a shell reports for a command killed by SIGPIPE (128 + 13), as `cat` or
//!   `grep` end in a pipeline;
//! * any other failure of stdout (a full device, an I/O error): exit 2, the environment is wrong,
//!   with the reason on stderr;
//! * a failed write to stderr is ignored: there is nowhere left to say it, and the command's
//!   outcome is still its exit status.
//!
//! Commands write their files before they print what they wrote, so ending here never leaves an
//! output set half written.

use std::fmt;
use std::io::{self, Write};

/// The status of a command whose stdout was closed: 128 + SIGPIPE.
pub const CLOSED_PIPE: i32 = 141;

/// Writes `args` to stdout and flushes; ends the process as the module says when it fails.
pub fn out(args: fmt::Arguments) {
    let mut stdout = io::stdout().lock();
    if let Err(e) = stdout.write_fmt(args).and_then(|()| stdout.flush()) {
        drop(stdout);
        stdout_failed(&e);
    }
}

/// Writes `args` to stderr; a failure is ignored.
pub fn err(args: fmt::Arguments) {
    let _ = io::stderr().lock().write_fmt(args);
}

fn stdout_failed(e: &io::Error) -> ! {
    if e.kind() == io::ErrorKind::BrokenPipe {
        std::process::exit(CLOSED_PIPE);
    }
    err(format_args!("error: cannot write to stdout: {e}\n"));
    std::process::exit(2);
}
