//! # bevy-sky — a converted Godot sky as a Bevy camera's background
//!
//! The Godot sky shader `shaders/freeman_fast.gdshader` (the Freeman sky's physical model) is
//! converted to WGSL in memory by `gdsky::convert` when the app starts, for Bevy's reversed-Z
//! depth, and drawn by `skydraw` inside Bevy's render graph:
//!
//! * [`sky::GodotSkyPlugin`] adds a system to the `Core3d` schedule (Bevy 0.20's render graph is
//!   a set of schedules whose systems record through `RenderContext`), ordered after
//!   `main_opaque_pass_3d` and before `main_transparent_pass_3d`. For each camera that carries
//!   [`sky::GodotSky`] it keeps one `skydraw::Sky`, made on Bevy's own `wgpu::Device` and
//!   `wgpu::Queue` (`RenderDevice::wgpu_device`, `RenderQueue`) for the view's main texture
//!   format, Bevy's depth format (`Depth32Float`, reversed Z) and the camera's MSAA sample
//!   count; each frame it updates it from the extracted view (the inverse view-projection) and
//!   the [`sky::SkySun`] light, records `prepare` on the render context's command encoder and
//!   `draw` into a pass on the view's colour target and depth buffer, so the sky fills only the
//!   pixels the opaque pass left at the far plane.
//! * With a radiance image ([`sky::radiance_image`]) skydraw renders its radiance cube (when the
//!   sky's inputs change) and the plugin copies it into that Bevy `Image`'s GPU texture, mirrored
//!   in Z for Bevy's left-handed cube maps; Bevy's `GeneratedEnvironmentMapLight` filters it into
//!   the diffuse and specular maps of its `EnvironmentMapLight`: the meshes are lit by the sky.
//! * [`scene`] is the demo scene (camera, sun, a sphere and a cube), shared by the windowed
//!   app, the headless render ([`headless`]) and the test.

pub mod headless;
pub mod scene;
pub mod sky;

/// The Godot sky shader the example draws: `shaders/freeman_fast.gdshader` of gdsky.
pub const SKY_SHADER: &str = include_str!("../../../shaders/freeman_fast.gdshader");

/// Converts [`SKY_SHADER`] for a target with `depth` (Bevy's is reversed Z).
pub fn convert_sky(depth: skycore::DepthConvention) -> Result<gdsky::Converted, gdsky::ConvertError> {
    gdsky::convert("freeman_fast.gdshader", SKY_SHADER, &gdsky::Options::new().depth(depth))
}

/// The gdsky preview curve (`gdsky render`'s PNGs, docs/demo.png): per channel
/// `round(255 · (1 − e^(−L · exposure))^(1/2.2))` of the linear value `L`.
pub fn preview_u8(linear: f32, exposure: f32) -> u8 {
    let v = (1.0 - (-linear.max(0.0) * exposure).exp()).powf(1.0 / 2.2);
    (v * 255.0).round().clamp(0.0, 255.0) as u8
}

/// The exposure of [`preview_u8`] that gdsky's previews use (0.5).
pub const PREVIEW_EXPOSURE: f32 = 0.5;
