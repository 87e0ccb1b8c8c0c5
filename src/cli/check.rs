//! `gdsky check FILE... [--diagnostics human|json]`

use clap::{Args, ValueEnum};
use gdsky::frontend::diag::{render_human, render_json};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

/// How diagnostics are printed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DiagnosticsFormat {
    /// rustc-style reports on stderr: code, message, file:line:col, the source line with a caret.
    Human,
    /// One JSON object per line on stdout: file, line, column, end_line, end_column, severity,
    /// code, message.
    Json,
}

#[derive(Args)]
pub struct CheckArgs {
    /// Shader files (`.gdshader`) to check.
    #[arg(required = true, value_name = "FILE")]
    files: Vec<PathBuf>,
    /// How to print diagnostics.
    #[arg(long, value_enum, default_value_t = DiagnosticsFormat::Human)]
    diagnostics: DiagnosticsFormat,
}

pub fn run(args: &CheckArgs) -> ExitCode {
    let mut unreadable = false;
    let mut invalid = false;
    let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
    for path in &args.files {
        let output = match gdsky::check_file(path) {
            Ok(o) => o,
            Err(err) => {
                unreadable = true;
                match args.diagnostics {
                    DiagnosticsFormat::Human => {
                        errln!("error: cannot read {}: {err}", path.display())
                    }
                    DiagnosticsFormat::Json => {
                        let line = serde_json::json!({
                            "file": path.display().to_string(), "line": 0, "column": 0, "end_line": 0, "end_column": 0,
                            "severity": "error", "code": "E000", "message": format!("cannot read the file: {err}"),
                        });
                        outln!("{line}");
                    }
                }
                continue;
            }
        };
        invalid |= output.has_errors();
        match args.diagnostics {
            DiagnosticsFormat::Human => {
                err!("{}", render_human(&output.db, &output.diagnostics, color));
                let errors = output.diagnostics.iter().filter(|d| d.is_error()).count();
                let warnings = output.diagnostics.len() - errors;
                let verdict = if errors > 0 { format!("{errors} error(s)") } else { "ok".to_string() };
                let extra = if warnings > 0 { format!(", {warnings} warning(s)") } else { String::new() };
                outln!("{}: {verdict}{extra}", path.display());
            }
            DiagnosticsFormat::Json => {
                out!("{}", render_json(&output.db, &output.diagnostics));
            }
        }
    }
    if unreadable {
        ExitCode::from(2)
    } else if invalid {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}
