//! # skydraw — a converted Godot sky in your own wgpu renderer
//!
//! gdsky converts a Godot sky shader into a WGSL module and its reflection (`gdsky::convert`,
//! or a build script's `.wgsl` and `.json`); skydraw draws that module on *your* device, in
//! *your* render pass, behind *your* geometry:
//!
//! ```no_run
//! # fn frame(device: &wgpu::Device, queue: &wgpu::Queue, wgsl: &str, json: &str,
//! #          color: &wgpu::TextureView, depth: &wgpu::TextureView) -> Result<(), Box<dyn std::error::Error>> {
//! use skydraw::{Frame, Sky, SkyOptions, SkySource, Target};
//! let reflection = skycore::reflection::Reflection::from_json(json)?;
//! let target = Target {
//!     color_format: wgpu::TextureFormat::Rgba16Float,
//!     depth: Some((wgpu::TextureFormat::Depth32Float, skycore::DepthConvention::Standard)),
//!     sample_count: 1,
//! };
//! let mut sky = Sky::new(device, queue, SkySource { wgsl, reflection: &reflection }, SkyOptions::new(target))?;
//! sky.set_uniform("sun_intensity", &skycore::UniformValue::Float(40.0))?;
//! // Every frame:
//! sky.update(queue, &Frame::default(), 1280, 720);
//! let mut encoder = device.create_command_encoder(&Default::default());
//! sky.prepare(&mut encoder);
//! {
//!     let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
//!         color_attachments: &[Some(wgpu::RenderPassColorAttachment {
//!             view: color, depth_slice: None, resolve_target: None,
//!             ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
//!         })],
//!         depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
//!             view: depth,
//!             depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
//!             stencil_ops: None,
//!         }),
//!         ..Default::default()
//!     });
//!     // … your opaque geometry …
//!     sky.draw(&mut pass);
//! }
//! queue.submit([encoder.finish()]);
//! # Ok(()) }
//! ```
//!
//! * [`Sky`]: made once on the caller's device for their colour format, depth format and
//!   convention, MSAA sample count; every pipeline, buffer, bind group and stand-in texture is
//!   made there (or when the target's size changes), never per frame.
//! * [`Frame`]: the camera as an engine has it ([`View::Rotation`] or
//!   [`View::InverseViewProjection`]), position, time and lights ([`SkyLight`]); material
//!   values by name ([`Sky::set_uniform`], checked against the reflection) or as the build
//!   script's generated struct ([`Sky::set_material`]); textures by uniform name.
//! * [`Sky::prepare`] records Godot's half- and quarter-resolution sub-passes, a reduced sky
//!   resolution ([`SkyOptions::resolution`]) and the radiance cube map ([`RadianceOptions`]:
//!   [`UpdatePolicy`] on change, on demand or every frame; [`ProcessMode`] real-time or
//!   incremental), and says what it did ([`FrameReport`]).
//! * [`Sky::draw`] records one fullscreen triangle at the far plane into the caller's pass;
//!   with [`Background::FromRadiance`], an up-to-date cube is sampled instead of running the
//!   shader per pixel.
//! * [`SkyBuiltins`] and [`SkyLight`]: the built-ins block as `#[repr(C)]` [`bytemuck::Pod`]
//!   structs whose offsets are asserted at compile time.
//!
//! It depends on wgpu, naga (to read the module's bindings) and gdsky's vocabulary crate,
//! nothing of the converter: a renderer that ships converted shaders does not build the
//! Godot front end.

#![warn(missing_docs)]

pub mod bindings;
mod builtins;
mod frame;
mod material;
mod radiance;
mod sky;
pub mod textures;

/// The glam that [`Frame`] and [`View`] take (0.34): a renderer on another glam version converts
/// through arrays (`Mat4::from_cols_array(&m.to_cols_array())`).
pub use glam;

pub use builtins::{RenderPass, SkyBuiltins, SkyLight, offsets, sub_pass_size};
pub use frame::{Frame, View};
pub use material::MaterialError;
pub use radiance::{ProcessMode, RadianceOptions, UpdatePolicy};
pub use sky::{Background, Drawn, FrameReport, OFFSCREEN_FORMAT, Sky, SkyError, SkyOptions, SkySource, Target};
