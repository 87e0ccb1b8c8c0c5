//! What the end-to-end tests of the `gdsky` binary share: running it, scratch folders, output.

// Each test binary compiles this module and uses a subset of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `gdsky` with `args` and `extra_env`, with a private XDG_RUNTIME_DIR (the Vulkan loader
/// warns without one) and no colour.
pub fn gdsky_with(args: &[&str], extra_env: &[(&str, &Path)]) -> Output {
    let runtime = std::env::temp_dir().join("gdsky-xdg-runtime");
    let _ = std::fs::create_dir_all(&runtime);
    let mut command = Command::new(env!("CARGO_BIN_EXE_gdsky"));
    command.args(args).env("XDG_RUNTIME_DIR", runtime).env("NO_COLOR", "1");
    for (key, value) in extra_env {
        command.env(key, value);
    }
    command.output().expect("the gdsky binary runs")
}

/// Runs `gdsky` with `args`.
pub fn gdsky(args: &[&str]) -> Output {
    gdsky_with(args, &[])
}

/// An empty folder `CARGO_TARGET_TMPDIR/group/name`.
pub fn scratch(group: &str, name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(group).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// stdout then stderr, for assertion messages.
pub fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}
