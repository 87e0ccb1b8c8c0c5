//! The process edge (issue #22, item 3): a closed stdout ends a command quietly with 141
//! (128 + SIGPIPE, as a shell reports `cat` killed in a pipeline), a full stdout with exit 2 and
//! the reason, a full stderr is ignored; never a panic (exit 101, "failed printing to stdout").

use crate::common::scratch;
use std::io::Read;
use std::process::{Command, Stdio};

fn gdsky_command(args: &[&str]) -> Command {
    let mut command = skytest::gdsky!().command();
    command.args(args).stdin(Stdio::null());
    command
}

/// 600 shaders with one error each: their JSON diagnostics (~110 KB) overflow a pipe's buffer.
fn many_bad_shaders() -> Vec<String> {
    let dir = scratch("process_edge", "bad");
    (0..600)
        .map(|i| {
            let path = dir.join(format!("bad_{i:03}.gdshader"));
            std::fs::write(&path, "shader_type sky;\nvoid sky() { float a = 2; COLOR = vec3(a); }\n").expect("write");
            path.display().to_string()
        })
        .collect()
}

#[test]
fn a_closed_stdout_ends_the_command_quietly_with_141() {
    let files = many_bad_shaders();
    let mut args = vec!["check", "--diagnostics", "json"];
    args.extend(files.iter().map(String::as_str));
    let mut child = gdsky_command(&args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("gdsky runs");
    // Read a little, as `| head -c 10` does, then close the pipe.
    let mut stdout = child.stdout.take().expect("piped");
    let mut first = [0u8; 10];
    stdout.read_exact(&mut first).expect("some output");
    drop(stdout);
    let output = child.wait_with_output().expect("gdsky ends");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(141), "stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn a_full_stdout_is_an_environment_error_after_the_outputs_are_written() {
    let out = scratch("process_edge", "full");
    let dir = out.display().to_string();
    let full = std::fs::File::options().write(true).open("/dev/full").expect("/dev/full");
    let output = gdsky_command(&["convert", "shaders/gradient.gdshader", "-o", &dir])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(full)
        .output()
        .expect("gdsky runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("cannot write to stdout") && !stderr.contains("panicked"), "{stderr}");
    for file in ["gradient.wgsl", "gradient.spv", "gradient.json"] {
        assert!(out.join(file).is_file(), "{file}: the set is written before anything is printed");
    }
}

#[test]
fn a_full_stderr_does_not_change_the_outcome() {
    let files = many_bad_shaders();
    let full = std::fs::File::options().write(true).open("/dev/full").expect("/dev/full");
    let output = gdsky_command(&["check", &files[0]]).stderr(full).stdout(Stdio::null()).output().expect("gdsky runs");
    assert_eq!(output.status.code(), Some(1), "the shader is wrong: exit 1, whatever stderr does");
}
