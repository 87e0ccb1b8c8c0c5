//! gdsky against real Godot 4.6 (the oracle: Godot's Web export in headless Chromium,
//! `scripts/install-oracle.sh`): the front end's verdicts, renders of the test and shipped
//! shaders, the seeds' skies, generated noise, gradient and curve textures, and (with
//! `GDSKY_CORPUS_DIR`, ignored by default) the corpus of real skies.

mod corpus;
mod cube_oracle;
mod godot_frontend;
mod godot_parity;
// The GLSL-semantics cases, for the Tint run; their expected values are the CLI suite's.
#[allow(dead_code)]
#[path = "../cli/glsl_cases.rs"]
mod glsl_cases;
mod noise_oracle;
mod preview;
mod ramp_oracle;
mod seed_skies;
#[cfg(feature = "testing")]
mod testing_api;

/// The suite's handles on the binary and its scratch folders (skytest's, for this crate).
mod common {
    use std::path::PathBuf;
    use std::process::Output;

    pub use skytest::text;

    /// Runs `gdsky` with `args`.
    pub fn gdsky(args: &[&str]) -> Output {
        skytest::gdsky!().run(args)
    }

    /// An empty folder `CARGO_TARGET_TMPDIR/group/name`.
    pub fn scratch(group: &str, name: &str) -> PathBuf {
        skytest::scratch!(group, name)
    }
}
