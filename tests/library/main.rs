//! gdsky as a library, without the binary: the facade (`convert`, `build`), the re-read that
//! stands between a module and a file, the engines behind `bench`, `stress` and `tune`, the
//! profile-independent output, and the shipped skies rendered on the GPU against skyref.

mod build_api;
mod engines;
mod freeman_fast;
mod freeman_stable;
mod loop_budget;
mod measure_textures;
mod reread;
#[cfg(feature = "testing")]
mod testing_api;

/// The suite's scratch folders (skytest's, for this crate).
mod common {
    use std::path::PathBuf;

    /// An empty folder `CARGO_TARGET_TMPDIR/group/name`.
    pub fn scratch(group: &str, name: &str) -> PathBuf {
        skytest::scratch!(group, name)
    }
}
