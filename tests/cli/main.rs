//! The `gdsky` binary's contract, end to end: every command as a user or a script runs it, its
//! outputs, its diagnostics and its exit codes (0 ok; 1 wrong input or a failed comparison; 2 a
//! wrong environment). Rendering needs a Vulkan adapter (lavapipe on a machine without a GPU).

mod animate;
mod bake_lut;
mod bench_cli;
mod budgets;
mod check;
mod compare_stats;
mod convert;
mod cubemap;
mod debanding;
mod defects;
mod depth_and_resolution;
mod glsl_cases;
mod glsl_semantics;
mod godot_materials;
mod lavapipe_loop_limit;
mod overrides;
mod preview_server;
mod process_edge;
mod render;
mod safe_io;
mod scene_files;
mod stress;
mod texture_kinds;
mod textures;
mod trace_nonfinite;
mod tune;

/// The suite's handles on the binary and its scratch folders (skytest's, for this crate).
mod common {
    use std::path::{Path, PathBuf};
    use std::process::Output;

    pub use skytest::text;

    /// Runs `gdsky` with `args`.
    pub fn gdsky(args: &[&str]) -> Output {
        skytest::gdsky!().run(args)
    }

    /// Runs `gdsky` with `args` and `env` set.
    pub fn gdsky_with(args: &[&str], env: &[(&str, &Path)]) -> Output {
        skytest::gdsky!().run_with(args, env)
    }

    /// An empty folder `CARGO_TARGET_TMPDIR/group/name`.
    pub fn scratch(group: &str, name: &str) -> PathBuf {
        skytest::scratch!(group, name)
    }
}
