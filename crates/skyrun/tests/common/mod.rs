//! What the GPU tests share: opening the device and converting the Freeman sky.

// Each test binary compiles this module and uses a subset of it.
#![allow(dead_code)]

use std::path::Path;

/// The Freeman sky converted by gdsky: the front end's output, the lowered module, its WGSL.
pub fn converted_freeman() -> (gdshader::FrontendOutput, gdsky_naga::Lowered, String) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/freeman_sky.gdshader");
    let front = gdshader::check_file(&path).expect("fixture readable");
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("the Freeman sky lowers");
    let wgsl = gdsky_naga::to_wgsl(&lowered).expect("WGSL");
    (front, lowered, wgsl)
}

/// The Vulkan device the tests render on; without one the test fails, it does not skip.
///
/// Call it before the test starts any thread: it sets XDG_RUNTIME_DIR (the Vulkan loader warns
/// without one) when unset. Every test binary using it has a single test function.
pub fn gpu() -> skyrun::Gpu {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: called first in the binary's only test, before wgpu or the Vulkan loader
        // start any thread.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let gpu = skyrun::Gpu::new().unwrap_or_else(|e| panic!("this test needs a Vulkan adapter and found none: {e}"));
    eprintln!("adapter: {}", gpu.adapter_info());
    gpu
}

/// Runs `spirv-val --target-env vulkan1.1` on `words`; panics with its message if it refuses.
pub fn spirv_val(words: &[u32]) {
    let path = std::env::temp_dir().join(format!("skyrun-test-{}.spv", std::process::id()));
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    std::fs::write(&path, bytes).expect("temporary SPIR-V file");
    let out = std::process::Command::new("spirv-val")
        .args(["--target-env", "vulkan1.1"])
        .arg(&path)
        .output()
        .expect("spirv-val runs (Debian package spirv-tools)");
    let _ = std::fs::remove_file(&path);
    assert!(
        out.status.success(),
        "spirv-val refuses the module: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
