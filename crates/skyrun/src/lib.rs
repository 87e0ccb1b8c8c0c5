//! # skyrun — converted sky shaders on a real Vulkan device
//!
//! gdsky converts Godot sky shaders to WGSL and SPIR-V; `skyref` computes on the CPU what the
//! Freeman sky's mathematics says each pixel should be. `skyrun` is the piece in between: it
//! runs the converted WGSL on a GPU through wgpu, offscreen, and gives back the image as f32
//! RGBA so that it can be compared with the reference number for number.
//!
//! ## What it does
//!
//! * [`Gpu::new`] opens wgpu on the Vulkan backend only and asks for the high-performance
//!   adapter. wgpu orders discrete, integrated, other and virtual GPUs before CPU adapters, so
//!   on a machine without a GPU it lands on lavapipe, Mesa's CPU Vulkan driver (reported as
//!   `llvmpipe`, [`wgpu::DeviceType::Cpu`]); [`Gpu::adapter_info`] says which one ran. When
//!   there is none, [`NoAdapter`] says so and names the package that provides lavapipe.
//! * [`SkyBuiltins`] is the wrapper's fixed built-ins block (group 0): camera, position, time,
//!   screen size, tan(fov/2), pass, luminance multiplier, cube face and four lights.
//!   [`SkyBuiltins::from_scene`] fills it from a [`skyref::Scene`] with the same f64→f32
//!   roundings skyref applies, so both sides start from identical inputs; [`SkyBuiltins::to_bytes`]
//!   lays it out at the offsets in docs/binding-interface.md, which a unit test holds against
//!   the layout naga computes for the wrapper's own struct.
//! * [`material_bytes`] writes uniform values into the material block (group 1) at the offsets
//!   the lowering reports ([`gdsky_naga::Lowered::uniforms`]) after checking each value's type;
//!   [`freeman_material`] does it for all 22 Freeman uniforms from a [`skyref::FreemanParams`].
//! * [`SkyShader`] compiles a WGSL module once, reads every resource it declares with naga
//!   ([`bindings::discover`]) and builds explicit bind group layouts from them, so converted
//!   modules and hand-written WGSL with the same interface render alike. [`SkyShader::render`]
//!   draws `vs_main` (a fullscreen triangle) and the projection's fragment entry (`fs_panorama`,
//!   `fs_camera`, or `fs_cubemap` for [`Projection::CubeFace`]) into an Rgba32Float target,
//!   copies it to a buffer with rows padded to wgpu's 256-byte alignment, waits for the device
//!   and returns the pixels row 0 at the top, with the submit-to-idle time
//!   ([`Rendered::gpu_wait`]) and, where the device has timestamp queries (lavapipe does), the
//!   passes' own time on the device ([`Rendered::gpu_time`]). Pipelines are cached per entry point and format. Every wgpu
//!   error on the way is caught in error scopes and returned as a [`RenderError`] (an invalid
//!   WGSL comes back with naga's message), never a panic from wgpu's default handler.
//! * Godot's sub-passes ([`SubPasses`], from the shader's `use_half_res_pass` /
//!   `use_quarter_res_pass`): the quarter-resolution pass, then the half-resolution pass (which
//!   can read the quarter one), then the full pass, each at screen/2 or screen/4 (at least 4
//!   pixels) into RGBA16F as in Godot, all in one command buffer; a sub-pass is drawn when the
//!   shader asked for it and reads its texture. Stand-ins where the scene has nothing to give,
//!   as Godot binds them: a sub-pass texture not rendered (or the one being rendered) is white,
//!   RADIANCE and, in the cubemap pass, the sub-pass textures are black (Godot's cubemap pass
//!   reads half/quarter *cubemaps*, which the harness does not render), material textures are
//!   white, global uniforms (group 3) zero.
//! * Material textures: [`SkyShader::set_texture`] binds real texels ([`TextureData`]:
//!   Rgba32Float, Rgba16Float, Rgba8Unorm, Rgba8UnormSrgb) to a sampler uniform by its name,
//!   mapped to the bindings through the reflection ([`SkyShader::with_material_textures`]), with
//!   samplers built from the uniforms' filter and repeat hints; [`read_texture`] reads OpenEXR
//!   (f32) and PNG (8-bit, sRGB with `source_color`) files, [`read_cube`] cube maps (six faces,
//!   a cross or Godot's grids) and [`read_volume`] 3D textures (slices or a grid); a sampler
//!   whose filter hint asks for mipmaps gets Godot's box-filtered chain. A float texture the module only
//!   loads from (`texelFetch`) is declared non-filterable, so 32-bit floats bind to it. Storage buffers, comparison samplers and binding
//!   arrays are refused by name ([`bindings::BindingError`]).
//! * [`material_with_defaults`] fills the material block of any shader from its own defaults
//!   plus `--set`-style overrides.
//! * [`write_exr`] / [`read_exr`] (RGBA f32, ZIP, row 0 at the top, written atomically),
//!   [`write_png_preview`] (Bruneton's demo tone map), [`write_heatmap_png`] (log-scale relative
//!   error), [`write_side_by_side_png`].
//! * Files are read and written through `skycore::io` (bounded reading, the one atomic writer).
//! * [`check_render_size`]: the largest view the renderer can draw ([`MAX_RENDER_SIDE`] a side,
//!   [`MAX_RENDER_PIXELS`]), the one limit `--size` and every command share.
//! * [`compare`] reduces two images to relative-error statistics over RGB
//!   (|a − b| / max(|b|, floor): max, p99.9, p99, mean, PSNR, NaN and Inf counts), and
//!   [`worst_pixels`] lists where the largest differences are, with both pixels' values.
//!
//! ## What it measured
//!
//! The integration test `tests/gpu/freeman_lavapipe.rs` converts `fixtures/freeman_sky.gdshader`,
//! renders it at 64×32 with the sun at 10° elevation and 30° azimuth and the camera 1 m above
//! the ground, and compares with `skyref::f32::render` of the same scene (floor 1e-4). On
//! lavapipe (llvmpipe, LLVM 15.0.6, Mesa 22.3.6):
//!
//! | projection | max | p99.9 | p99 | mean | NaN / Inf |
//! | --- | --- | --- | --- | --- | --- |
//! | panorama | 4.7e-6 | 2.1e-6 | 1.7e-6 | 1.6e-7 | 0 / 0 |
//! | camera, fov 90°, pitch 10° | 6.3e-7 | 4.6e-7 | 3.5e-7 | 1.1e-7 | 0 / 0 |
//!
//! The full scene matrix (sun −4° … 90°, camera at 1 m, 2 km and 30 km, both projections) is
//! `tests/gpu/freeman_matrix.rs`, with its thresholds argued in its header; the sub-passes are
//! tested in `tests/gpu/sub_passes.rs`; `benches/render.rs` times the converted shader against a
//! hand-written WGSL port.
//!
//! That is a few f32 ulps: far below the f32-versus-f64 difference skyref documents for the
//! same scene (p99 7.8e-5), so the GPU computes the reference's f32 arithmetic almost
//! operation for operation, and the conventions (pixel centres, row order, EYEDIR of both
//! projections, light direction, camera basis, uniform layout) agree. The largest difference
//! is at panorama pixel (6, 14), next to the sun (8.959000 against 8.959042 in red), where the
//! values are largest and the GPU's `exp`/`pow` rounding shows most. As a check that the
//! comparison can fail, the same test renders the sun mirrored to −30° azimuth and requires a
//! p99 error above 0.1 (measured 1.8).
//!
//! ## Example
//!
//! ```no_run
//! use skyref::{FreemanParams, Projection, Scene};
//! use skyrun::{Gpu, SkyBuiltins, compare, freeman_material, render};
//!
//! let front = gdshader::check_file("fixtures/freeman_sky.gdshader".as_ref())?;
//! let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("the Freeman sky lowers");
//! let wgsl = gdsky_naga::to_wgsl(&lowered)?;
//! let params = FreemanParams::default();
//! let scene = Scene::default();
//!
//! let gpu = Gpu::new()?;
//! println!("rendering on {}", gpu.adapter_info());
//! let builtins = SkyBuiltins::from_scene(&scene, 64, 32);
//! let material = freeman_material(&lowered, &params);
//! let image = render(&gpu, &wgsl, Projection::Panorama, 64, 32, &builtins, &material)?;
//! let reference = skyref::f32::render(&params, &scene, Projection::Panorama, 64, 32);
//! println!("{}", compare(&image, &reference, 1e-4));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

pub use skydraw::bindings;
mod gpu;
mod imageio;
mod material;
mod metrics;
mod passthrough;
mod render;
mod skip;
mod textures;
mod watchdog;
mod wide;

pub use gdsky_naga::reflect::TextureBinding;
pub use gpu::{AdapterSummary, Gpu, NoAdapter};
pub use imageio::{
    DEFAULT_EXPOSURE, DEFAULT_WHITE, Image, ImageError, MAX_EXR_BYTES, MAX_READ_PIXELS, MAX_RENDER_PIXELS,
    MAX_RENDER_SIDE, check_render_size, read_exr, read_exr_notes, write_exr, write_exr_annotated, write_heatmap_png,
    write_overlay_png, write_png_preview, write_side_by_side_png,
};
pub use material::{
    MaterialError, UniformValue, freeman_material, freeman_values, material_bytes, material_with_defaults,
    texture_defaults,
};
pub use metrics::{
    Metrics, PixelDiff, STATS_GRID, Stats, compare, compare_stats, luminance, region_stats, worst_pixels,
};
pub use render::{RenderError, Rendered, SkyShader, SubPasses, render};
pub use skip::{MAX_MASK_BYTES, MaskError, OCCLUDED, Occluder, RenderOptions, SkyResolution, UpsampleFilter};
pub use skycore::{Projection, Scene};
pub use skydraw::{RenderPass, SkyBuiltins, SkyLight, offsets, sub_pass_size};
pub use textures::{
    GODOT_VOLUME_GRID, MAX_ASSEMBLED_BYTES, MAX_TEXTURE_FILE_BYTES, MAX_TEXTURE_SIDE, MAX_VOLUME_SIDE, TexelFormat,
    TextureData, TextureError, TextureShape, check_texture, read_cube, read_texture, read_volume, texture_from_image,
};
pub use watchdog::{DriverBudget, set_driver_budget};
pub use wide::{F64Error, F64Sky, render_f64};

#[cfg(test)]
mod tests;
