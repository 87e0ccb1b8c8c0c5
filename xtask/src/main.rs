//! gdsky's project tasks, after the cargo-xtask convention: `cargo xtask demo`, `cargo xtask test`
//! and `cargo xtask setup` (the alias is in `.cargo/config.toml`). Each installs the system
//! packages its command needs where they are missing (Debian and Ubuntu, through apt-get), then
//! runs it. This crate uses std only, so a fresh machine builds it in seconds before any heavy
//! crate, and the README's commands need nothing but cargo.

mod packages;
mod summary;

use std::ffi::OsString;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, ExitStatus, Stdio};

use packages::Task;

const USAGE: &str = "\
gdsky's project tasks: each installs the system packages it needs where they are missing
(Debian/Ubuntu, with apt-get; sudo when not root), then runs.

Usage:
  cargo xtask demo [ARGS...]    the main job: installs Mesa's lavapipe and the Vulkan loader
                                (mesa-vulkan-drivers, libvulkan1), then runs
                                `cargo run --release -- demo ARGS...` (gdsky demo: convert the
                                Freeman sky, render it on Vulkan, check it against skyref)
  cargo xtask test [ARGS...]    the whole test suite: installs build-essential, spirv-tools,
                                lavapipe and the Vulkan loader, chromium, Node.js and npm (when
                                `node` or `npm` is not on PATH) and the Godot oracle's parts
                                (scripts/install-oracle.sh), then runs
                                `cargo test --workspace --locked ARGS...` (`-p NAME` in ARGS
                                replaces --workspace) with GDSKY_FAIL_ON_SKIP=1 (a skipped
                                snapshot is a failure) and closes with `total: N passed, M failed`
  cargo xtask bevy [ARGS...]    the Bevy example's test, kept out of `test` (a cold Bevy build
                                takes longer than the rest of the suite): installs lavapipe and
                                the Vulkan loader, then runs `cargo test --locked
                                --ignore-rust-version ARGS...` in examples/bevy-sky (its own
                                Cargo.lock and target folder; Bevy 0.20.1 asks for Rust 1.97.1,
                                older compilers build it with the flag)
  cargo xtask setup [demo|test] only installs what `demo` or `test` (the default) needs
  cargo xtask help              this text

Exit status: the command's own; 1 for a malformed command line; 2 when something cannot be
installed (without apt-get it prints the packages' Debian names).
";

/// Why xtask stops: a message and an exit status.
#[derive(Debug)]
pub struct Failure {
    pub code: u8,
    pub message: String,
}

impl Failure {
    /// The machine lacks something that cannot be installed from here: exit status 2.
    pub fn env(message: impl Into<String>) -> Self {
        Self { code: 2, message: message.into() }
    }

    /// A malformed command line: exit status 1.
    fn usage(message: impl Into<String>) -> Self {
        Self { code: 1, message: format!("{}\n\n{USAGE}", message.into()) }
    }
}

/// One line on stderr, prefixed `xtask: `. Never panics (a closed stderr is ignored).
pub fn say(message: &str) {
    let _ = writeln!(std::io::stderr(), "xtask: {message}");
}

/// `name` as the shell would find it: the first executable file called so in a PATH directory.
pub fn find_on_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|dir| dir.join(name)).find(|candidate| is_executable(candidate))
}

pub fn is_executable(path: &Path) -> bool {
    let Ok(metadata) = std::fs::metadata(path) else { return false };
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        metadata.is_file() && metadata.permissions().mode() & 0o111 != 0
    }
    #[cfg(not(unix))]
    {
        metadata.is_file()
    }
}

fn main() -> ExitCode {
    let args: Vec<OsString> = std::env::args_os().skip(1).collect();
    match run(&args) {
        Ok(code) => ExitCode::from(code),
        Err(failure) => {
            say(&failure.message);
            ExitCode::from(failure.code)
        }
    }
}

fn run(args: &[OsString]) -> Result<u8, Failure> {
    let Some((command, rest)) = args.split_first() else {
        return Err(Failure::usage("no command given"));
    };
    match command.to_str() {
        Some("demo") => {
            packages::ensure(Task::Demo)?;
            demo(rest)
        }
        Some("test") => {
            packages::ensure(Task::Test)?;
            install_oracle()?;
            test(rest)
        }
        Some("bevy") => {
            packages::ensure(Task::Demo)?;
            bevy(rest)
        }
        Some("setup") => {
            let task = match rest.iter().map(|a| a.to_str()).collect::<Vec<_>>().as_slice() {
                [] | [Some("test")] => Task::Test,
                [Some("demo")] => Task::Demo,
                _ => return Err(Failure::usage("`setup` takes `demo` or `test`")),
            };
            packages::ensure(task)?;
            if task == Task::Test {
                install_oracle()?;
            }
            say("setup done");
            Ok(0)
        }
        Some("help" | "-h" | "--help") => {
            let _ = std::io::stdout().write_all(USAGE.as_bytes());
            Ok(0)
        }
        _ => Err(Failure::usage(format!("unknown command `{}`", command.to_string_lossy()))),
    }
}

/// `cargo xtask demo`: the release build of gdsky's demo, with ARGS.
fn demo(args: &[OsString]) -> Result<u8, Failure> {
    let mut cargo = cargo();
    cargo.args(["run", "--release", "--", "demo"]).args(args);
    let _runtime_dir = RuntimeDir::set_if_unset(&mut cargo)?;
    say("running: cargo run --release -- demo (the first build takes a few minutes)");
    let status = cargo.status().map_err(|e| Failure::env(format!("cannot run cargo: {e}")))?;
    Ok(exit_code(status))
}

/// `cargo xtask bevy`: examples/bevy-sky's tests, in its own workspace, with ARGS.
fn bevy(args: &[OsString]) -> Result<u8, Failure> {
    let mut cargo = cargo();
    cargo
        .current_dir(repo_root().join("examples/bevy-sky"))
        .args(["test", "--locked", "--ignore-rust-version"])
        .args(args);
    let _runtime_dir = RuntimeDir::set_if_unset(&mut cargo)?;
    say("running: cargo test --locked --ignore-rust-version in examples/bevy-sky (a cold Bevy build takes a while)");
    let status = cargo.status().map_err(|e| Failure::env(format!("cannot run cargo: {e}")))?;
    Ok(exit_code(status))
}

/// The oracle's parts (the Godot export, playwright-core), by the script that owns them.
fn install_oracle() -> Result<(), Failure> {
    let bash =
        find_on_path("bash").ok_or_else(|| Failure::env("bash is not on PATH; it runs scripts/install-oracle.sh"))?;
    say("installing the Godot oracle's parts where missing: bash scripts/install-oracle.sh");
    let status = Command::new(bash)
        .arg("scripts/install-oracle.sh")
        .current_dir(repo_root())
        .status()
        .map_err(|e| Failure::env(format!("cannot run bash scripts/install-oracle.sh: {e}")))?;
    if status.success() { Ok(()) } else { Err(Failure::env(format!("scripts/install-oracle.sh failed ({status})"))) }
}

/// gdsky::testing's switch that turns skipped comparisons into failures.
const FAIL_ON_SKIP: &str = "GDSKY_FAIL_ON_SKIP";

/// `cargo xtask test`: `cargo test --workspace --locked ARGS`, its output passed through, then
/// the closing line summing its `test result:` lines. Exits with cargo test's status.
fn test(args: &[OsString]) -> Result<u8, Failure> {
    let test_args = cargo_test_args(args);
    let mut cargo = cargo();
    cargo.args(&test_args).stdout(Stdio::piped());
    let _runtime_dir = RuntimeDir::set_if_unset(&mut cargo)?;
    // The suite installs lavapipe and the oracle first: a gdsky::testing skip (no adapter, no
    // oracle) means a test did not run, which is a failure here.
    if std::env::var_os(FAIL_ON_SKIP).is_none() {
        cargo.env(FAIL_ON_SKIP, "1");
    }
    let shown: Vec<String> = test_args.iter().map(|a| a.to_string_lossy().into_owned()).collect();
    say(&format!("running: cargo {}", shown.join(" ")));
    let mut child = cargo.spawn().map_err(|e| Failure::env(format!("cannot run cargo: {e}")))?;
    let mut totals = summary::Totals::default();
    if let Some(stdout) = child.stdout.take() {
        let mut reader = BufReader::new(stdout);
        let mut out = std::io::stdout();
        let mut line = Vec::new();
        // Read to the end even if our stdout is gone, so cargo test is never cut off.
        while reader.read_until(b'\n', &mut line).unwrap_or(0) > 0 {
            let _ = out.write_all(&line).and_then(|()| out.flush());
            totals.add_line(String::from_utf8_lossy(&line).trim_end());
            line.clear();
        }
    }
    let status = child.wait().map_err(|e| Failure::env(format!("waiting for cargo test: {e}")))?;
    let _ = writeln!(std::io::stdout(), "{}", totals.closing_line());
    Ok(exit_code(status))
}

/// `test --workspace --locked ARGS`; without `--workspace` when ARGS pick packages (`-p NAME`,
/// `--package NAME`) before any `--`, since cargo would otherwise test the whole workspace anyway.
fn cargo_test_args(args: &[OsString]) -> Vec<OsString> {
    let picks_packages = args
        .iter()
        .map(|a| a.to_string_lossy())
        .take_while(|a| a != "--")
        .any(|a| a == "--package" || a.starts_with("--package=") || (a.starts_with("-p") && !a.starts_with("--")));
    let mut test_args: Vec<OsString> = vec!["test".into()];
    if !picks_packages {
        test_args.push("--workspace".into());
    }
    test_args.push("--locked".into());
    test_args.extend(args.iter().cloned());
    test_args
}

/// cargo itself (the one running xtask, named by `CARGO`), in the repository root.
fn cargo() -> Command {
    let mut command = Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()));
    command.current_dir(repo_root());
    command
}

/// The workspace root: xtask/'s parent. `CARGO_MANIFEST_DIR` is set by `cargo run`.
fn repo_root() -> PathBuf {
    let manifest_dir =
        std::env::var_os("CARGO_MANIFEST_DIR").map_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")), PathBuf::from);
    manifest_dir.parent().map_or(manifest_dir.clone(), Path::to_path_buf)
}

/// An exit status as a process exit code: the code, or 128 + the signal that ended it.
fn exit_code(status: ExitStatus) -> u8 {
    if let Some(code) = status.code() {
        return u8::try_from(code).unwrap_or(1);
    }
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(signal) = status.signal() {
            return u8::try_from(128 + signal).unwrap_or(1);
        }
    }
    1
}

/// A private XDG_RUNTIME_DIR for the child when none is set (the Vulkan loader warns without
/// one; its value does not matter), removed when dropped.
struct RuntimeDir(Option<PathBuf>);

impl RuntimeDir {
    fn set_if_unset(command: &mut Command) -> Result<Self, Failure> {
        if std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|v| !v.is_empty()) {
            return Ok(Self(None));
        }
        let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.subsec_nanos());
        let dir = std::env::temp_dir().join(format!("gdsky-xtask-runtime-{}-{nanos}", std::process::id()));
        let mut builder = std::fs::DirBuilder::new();
        #[cfg(unix)]
        {
            use std::os::unix::fs::DirBuilderExt;
            builder.mode(0o700);
        }
        builder.create(&dir).map_err(|e| Failure::env(format!("cannot create {}: {e}", dir.display())))?;
        command.env("XDG_RUNTIME_DIR", &dir);
        Ok(Self(Some(dir)))
    }
}

impl Drop for RuntimeDir {
    fn drop(&mut self) {
        if let Some(dir) = &self.0 {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_executables_on_path_only() {
        assert!(find_on_path("sh").is_some_and(|p| p.is_absolute()));
        assert_eq!(find_on_path("gdsky-xtask-no-such-program"), None);
    }

    #[test]
    fn repo_root_holds_the_workspace() {
        assert!(repo_root().join("Cargo.toml").is_file());
        assert!(repo_root().join("scripts/install-oracle.sh").is_file());
    }

    #[test]
    fn test_arguments() {
        let args = |list: &[&str]| -> Vec<String> {
            let os: Vec<OsString> = list.iter().map(OsString::from).collect();
            cargo_test_args(&os).iter().map(|a| a.to_string_lossy().into_owned()).collect()
        };
        assert_eq!(args(&[]), ["test", "--workspace", "--locked"]);
        assert_eq!(args(&["--no-run"]), ["test", "--workspace", "--locked", "--no-run"]);
        assert_eq!(args(&["-p", "xtask"]), ["test", "--locked", "-p", "xtask"]);
        assert_eq!(args(&["-pxtask"]), ["test", "--locked", "-pxtask"]);
        assert_eq!(args(&["--package=skyref", "--lib"]), ["test", "--locked", "--package=skyref", "--lib"]);
        assert_eq!(args(&["--", "-p"]), ["test", "--workspace", "--locked", "--", "-p"]);
    }

    #[test]
    fn malformed_command_lines_exit_1() {
        for args in [&[][..], &["frobnicate"], &["setup", "everything"], &["setup", "demo", "test"]] {
            let args: Vec<OsString> = args.iter().map(OsString::from).collect();
            assert_eq!(run(&args).err().map(|f| f.code), Some(1), "{args:?}");
        }
    }
}
