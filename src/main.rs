//! The `gdsky` command line. Commands and flag names follow the CLI contract in the README;
//! scripts outside the project depend on them.

mod cli;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Ports Godot 4 sky shaders to WGSL and SPIR-V, and checks them with Godot's rules.
#[derive(Parser)]
#[command(name = "gdsky", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Check sky shaders with Godot's rules and print diagnostics.
    ///
    /// Exit status: 0 when every file is a valid sky shader (warnings allowed), 1 when any has an
    /// error, 2 when a file cannot be read.
    Check(cli::check::CheckArgs),
    /// Convert a sky shader to WGSL, SPIR-V and a reflection JSON.
    ///
    /// Writes DIR/<stem>.wgsl, DIR/<stem>.spv (SPIR-V 1.3, Vulkan) and DIR/<stem>.json, each
    /// atomically. Exit status: 0 written, 1 the shader is invalid or cannot be translated, 2 a
    /// file cannot be read or written.
    Convert(cli::convert::ConvertArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Check(args) => cli::check::run(&args),
        Command::Convert(args) => cli::convert::run(&args),
    }
}
