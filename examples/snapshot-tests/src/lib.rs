//! A crate that ships Godot skies for its own wgpu renderer — the Freeman sky as a hand port
//! (`ports/freeman_sky.wgsl`) and a cloud layer converted by gdsky from a Godot material
//! (`godot/materials/noise_clouds.tres`) — and tests them with `gdsky::testing`:
//!
//! * `tests/snapshots.rs`: golden images of both skies (`tests/snapshots/*.exr`, previews
//!   `*.png`); `UPDATE_SNAPSHOTS=1 cargo test` blesses a change;
//! * `tests/ports.rs`: the hand ports against gdsky's conversions of the originals, and a wrong
//!   port that must fail;
//! * `tests/text.rs`: the converted WGSL, reflection and SPIR-V as insta snapshots.
//!
//! docs/testing.md in gdsky's repository explains each.

/// The hand-written WGSL port of the Freeman sky this crate draws with.
pub const FREEMAN_SKY_WGSL: &str = include_str!("../ports/freeman_sky.wgsl");

/// The hand-written WGSL port of the noise cloud sky.
pub const NOISE_SKY_WGSL: &str = include_str!("../ports/noise_sky.wgsl");
