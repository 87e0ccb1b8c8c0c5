//! # skycore — the vocabulary every gdsky crate speaks
//!
//! gdsky is split by stage (the front end reads Godot's shading language, the lowering builds
//! naga IR, the GPU side renders, skyref computes the truth, the oracle asks real Godot), and
//! every stage talks about the same few things: the scene a sky is rendered for, the values given
//! to its uniforms, the textures bound to its samplers, and the files read and written on the
//! way. This crate defines each of them once, on the ground floor, so that no two crates hold
//! two types for one concept and no conversion sits between them.
//!
//! * [`Scene`], [`Camera`], [`Light`]: what a sky shader reads from the scene (`POSITION`,
//!   `TIME`, `LIGHT0` … `LIGHT3`), in Godot's conventions: lights by elevation and azimuth in
//!   degrees, the camera by a vertical field of view, a yaw and a pitch (Euler YXZ).
//! * [`Projection`]: how a pixel becomes EYEDIR (panorama, camera, a cube face), and the
//!   fragment entry of a converted module that draws it; [`SkyResolution`]: the fraction of a
//!   view the sky is shaded at; [`DepthConvention`]: where the far plane is.
//! * [`UniformValue`]: a value for one uniform, whoever takes it (the material block, Godot).
//! * [`TextureData`]: the texels of a material texture (2D, cube map, 3D) with their format;
//!   mip levels made as Godot makes them.
//! * [`io`]: how gdsky touches files: bounded reading of regular files only, and the one atomic
//!   writer (never over a directory or a device, through symbolic links, all or nothing).
//!
//! It depends on `glam` alone: a build script that converts shaders pays for nothing more.

#![warn(missing_docs)]

pub mod io;
pub mod reflection;
mod scene;
mod texture;
mod uniform;

pub use scene::{
    Camera, DepthConvention, Light, MAX_LIGHTS, Projection, Scene, SkyResolution, cube_face_basis,
    direction as light_direction,
};
pub use texture::{
    MAX_TEXTURE_SIDE, MAX_VOLUME_SIDE, TexelFormat, TextureData, TextureError, TextureShape, f16_to_f32, f32_to_f16,
};
pub use uniform::UniformValue;

/// The built-ins uniform block (group 0, binding 0) of every module gdsky emits, as Rust
/// source: `#[repr(C)]` bytemuck structs `SkyBuiltins` and `SkyLight` with their padding as
/// fields, `Default` (luminance multiplier 1), the `offsets` module and compile-time layout
/// assertions. The runtime (skydraw) compiles this text; `gdsky::build` writes it as
/// `sky_builtins.rs` beside a build script's shaders.
pub const SKY_BUILTINS_RS: &str = include_str!("sky_builtins.rs");
