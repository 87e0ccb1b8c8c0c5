//! Feeds arbitrary bytes to the whole front end (UTF-8 check, preprocessor, parser, checker),
//! lowers every shader it accepts to naga IR and validates it, then writes WGSL and SPIR-V and
//! reads both back with naga's own front ends (`to_wgsl`/`to_spirv` re-read and validate).
//! Any panic is a bug: the front end must answer every input with diagnostics. Includes are
//! served from memory so `#include` paths, depth limits and cycles are exercised too.
#![no_main]

use gdshader::Loader;
use std::path::Path;

/// Serves every include as the fuzz input itself (so includes nest and cycle), except paths
/// containing "missing", which are not found.
struct SelfLoader<'a>(&'a [u8]);

impl Loader for SelfLoader<'_> {
    fn load(&mut self, path: &Path) -> std::io::Result<Vec<u8>> {
        if path.to_string_lossy().contains("missing") {
            return Err(std::io::Error::new(std::io::ErrorKind::NotFound, "not found"));
        }
        Ok(self.0.to_vec())
    }
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let output =
        gdshader::check_source("fuzz.gdshader", data.to_vec(), Some("fuzz.gdshader".into()), &mut SelfLoader(data));
    // E999 is what a caught panic in the front end turns into.
    assert!(output.diagnostics.iter().all(|d| d.code != "E999"));
    // A shader the checker accepts must lower to a module naga accepts, or be refused as not
    // translatable yet (E600); E601 would be a bug in the lowering. What it emits must read back
    // (E604 would be a bug too).
    if output.shader.is_none() {
        return;
    }
    match gdsky_naga::lower(&output, &gdsky_naga::LowerOptions::default()) {
        Err(diagnostics) => {
            assert!(diagnostics.iter().all(|d| d.code != gdsky_naga::INVALID_MODULE), "{:?}", diagnostics);
        }
        Ok(lowered) => {
            if let Err(err) = gdsky_naga::to_wgsl(&lowered) {
                panic!("{err}");
            }
            if let Err(err) = gdsky_naga::to_spirv(&lowered) {
                panic!("{err}");
            }
        }
    }
});
