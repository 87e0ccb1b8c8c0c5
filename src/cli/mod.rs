//! One module per subcommand, and what they share.

pub mod bench;
pub mod check;
pub mod compare;
pub mod convert;
pub mod demo;
pub mod oracle;
pub mod render;
pub mod scene;
pub mod stress;
pub mod sweep;

use std::io::Write;
use std::path::Path;
use std::process::ExitCode;

/// Writes `bytes` to `path` atomically: into a temporary file beside it, then renamed over it,
/// so a reader (or a failed run) never sees a half-written file.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
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
