//! # The engines: what the `gdsky` commands do, callable from Rust
//!
//! Every command of the `gdsky` binary is a thin command line over this module and
//! [`crate::measure`]: the binary parses flags into options, calls an engine, and prints what it
//! returns. Tests and users' own tools call the same engines, so nothing that decides a number,
//! a file or an error lives in the binary.
//!
//! * [`Input`] opens what a command's FILE names: a shader, a scene file (`.toml`) or a Godot
//!   material or scene (`.tres`, `.tscn`), and [`Sky`] is that shader checked, lowered once as
//!   [`gdsky_naga::LowerOptions`] say, and ready to compile on a [`skyrun::Gpu`], with its
//!   textures and tables.
//! * [`Setup`] is what a render is of: the scene (camera, lights, time), the projection and
//!   size, the uniform values (`--set` text) and the textures asked for by name.
//! * [`Error`] is every engine's error: located diagnostics, wrong input (exit 1), or a wrong
//!   environment (exit 2), as the CLI contract maps them.
//! * [`Progress`] is how a long engine reports: notes (what the CLI prints on stderr) and a
//!   count of steps (the CLI's progress bar). [`Quiet`] ignores both.

pub mod convert;
pub mod demo;
mod input;
pub mod oracle;
mod output;
pub mod render;
mod setup;
mod sky;
mod textures;

pub use input::{Input, bake_reason, check_override_conflicts, override_names, warn_unapplied};
pub use output::{
    ImageFormat, check_image_output, check_output_dir, check_outputs_apart, create_output_dir, open_gpu, write_file,
    write_image,
};
pub use setup::Setup;

pub use sky::{BUNDLED_FREEMAN, BUNDLED_NAME, Sky, TRANSMITTANCE_TABLE, constant_value, freeman_names, set_freeman};
pub use textures::load_textures;

use std::fmt;

/// Why an engine stopped. The CLI prints it and exits with [`Error::exit_code`].
#[derive(Debug)]
pub enum Error {
    /// The shader is wrong, and its diagnostics say where.
    Diagnostics(crate::ConvertError),
    /// The input is wrong (a flag, a value, a file's content); the message says what, and may
    /// be a rendered diagnostic of a scene file or a Godot material, several lines long.
    Input(String),
    /// The environment is wrong: no Vulkan adapter, a file that cannot be read or written.
    Environment(String),
}

impl Error {
    /// Wrong input ([`Error::Input`]).
    pub fn input(message: impl fmt::Display) -> Self {
        Error::Input(message.to_string())
    }

    /// A wrong environment ([`Error::Environment`]).
    pub fn environment(message: impl fmt::Display) -> Self {
        Error::Environment(message.to_string())
    }

    /// The CLI's exit status for it: 1 for wrong input, 2 for a wrong environment.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Diagnostics(_) | Error::Input(_) => 1,
            Error::Environment(_) => 2,
        }
    }

    /// The text to print: diagnostics rendered (with ANSI colours when `color`), a message as
    /// `error: …` unless it is a rendered diagnostic already.
    pub fn render(&self, color: bool) -> String {
        let message = match self {
            Error::Diagnostics(d) => return d.render(color),
            Error::Input(m) | Error::Environment(m) => m.trim_end(),
        };
        if message.starts_with("error") || message.contains("\n  --> ") || message.contains("\n   --> ") {
            format!("{message}\n")
        } else {
            format!("error: {message}\n")
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.render(false).trim_end())
    }
}

impl std::error::Error for Error {}

impl From<crate::ConvertError> for Error {
    fn from(e: crate::ConvertError) -> Self {
        Error::Diagnostics(e)
    }
}

/// How a long engine reports as it goes: notes for the user (what the CLI prints on stderr, a
/// line each) and steps of work (the CLI's progress bar). Every method does nothing by default.
pub trait Progress {
    /// A line for the user: what was baked, a table's origin, a warning.
    fn note(&self, _text: &str) {}
    /// Work of `steps` steps begins.
    fn start(&self, _steps: u64) {}
    /// What is being done now.
    fn message(&self, _text: &str) {}
    /// One step is done.
    fn step(&self) {}
    /// The work is over (the bar goes away).
    fn finish(&self) {}
}

/// A [`Progress`] that reports nothing (tests, tools that print their own).
#[derive(Clone, Copy, Debug, Default)]
pub struct Quiet;

impl Progress for Quiet {}

/// A [`Progress`] that prints its notes on stderr and keeps no bar.
#[derive(Clone, Copy, Debug, Default)]
pub struct Notes;

impl Progress for Notes {
    fn note(&self, text: &str) {
        // Never a panic at the process edge: a note that cannot be written is dropped.
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr().lock(), "{text}");
    }
}
