//! One shader, the same bytes from every way gdsky converts it: this crate's build script (a
//! debug build of gdsky, with `default-features = false`), `gdsky::convert_file` in this debug
//! test, and the `gdsky` CLI built in release as `cargo install` builds it. naga's SPIR-V writer
//! adds debug names under `debug_assertions` by default; gdsky sets its flags explicitly, so
//! neither the profile nor the entry point changes a byte of WGSL or SPIR-V.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Builds the `gdsky` binary with `cargo build --release` and returns its path, read from
/// cargo's own JSON messages (so `CARGO_TARGET_DIR` and the like are respected).
fn release_cli() -> PathBuf {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let output = Command::new(cargo)
        .current_dir(root())
        .args(["build", "--release", "--locked", "--bin", "gdsky", "--message-format=json-render-diagnostics"])
        .output()
        .expect("cargo runs");
    assert!(output.status.success(), "cargo build --release failed:\n{}", String::from_utf8_lossy(&output.stderr));
    String::from_utf8_lossy(&output.stdout)
        .lines()
        .filter_map(|line| serde_json::from_str::<serde_json::Value>(line).ok())
        .filter(|message| message["reason"] == "compiler-artifact" && message["target"]["name"] == "gdsky")
        .find_map(|message| message["executable"].as_str().map(PathBuf::from))
        .expect("cargo names the gdsky executable it built")
}

#[test]
#[cfg_attr(not(debug_assertions), ignore = "compares a debug build with the release CLI: run it without --release")]
fn build_script_library_and_release_cli_write_the_same_bytes() {
    let fixture = root().join("fixtures/freeman_sky.gdshader");

    let converted = gdsky::convert_file(&fixture, &gdsky::Options::default())
        .expect("the fixture is readable")
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        converted.wgsl == gdsky_build_example::FREEMAN_SKY_WGSL,
        "WGSL: convert_file differs from the build script"
    );
    assert!(
        converted.spirv_bytes() == gdsky_build_example::FREEMAN_SKY_SPIRV,
        "SPIR-V: convert_file differs from the build script"
    );

    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("same_bytes");
    let _ = std::fs::remove_dir_all(&out);
    let cli = release_cli();
    let run = Command::new(&cli).arg("convert").arg(&fixture).arg("-o").arg(&out).output().expect("the CLI runs");
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let wgsl = std::fs::read_to_string(out.join("freeman_sky.wgsl")).expect("the CLI wrote the WGSL");
    let spirv = std::fs::read(out.join("freeman_sky.spv")).expect("the CLI wrote the SPIR-V");
    assert!(wgsl == converted.wgsl, "WGSL: the release CLI differs from a debug convert");
    assert!(
        spirv == converted.spirv_bytes(),
        "SPIR-V: the release CLI ({} bytes) differs from a debug convert ({} bytes)",
        spirv.len(),
        converted.spirv_bytes().len()
    );
    eprintln!("{}: WGSL {} bytes, SPIR-V {} bytes, identical three ways", cli.display(), wgsl.len(), spirv.len());
}
