//! # skyref — the Freeman sky in Rust
//!
//! `skyref` is a CPU reference for `fixtures/freeman_sky.gdshader`, the physically based sky
//! shader (CC0) that gdsky uses as its first end-to-end test. gdsky converts that shader to
//! WGSL/SPIR-V and renders it on a GPU; this crate computes what the shader's mathematics says
//! the image should be, so the two can be compared pixel by pixel.
//!
//! ## Line for line
//!
//! The code follows the shader function by function, in its order and with its names
//! (`get_atmosphere_radius`, `ray_sphere_intersection`, `get_rayleigh_scattering`,
//! `get_mie_extinction`, `get_rayleigh_phase`, `henyey_greenstein_phase`, `get_mie_phase`,
//! `get_optical_depth_at_point`, `get_transmittance`, `integrate_radiance`, `sky`) and keeps its
//! comments, so the two read side by side. It keeps the shader's sampling (view samples, sun
//! samples, half the view samples for rays that hit the ground), its clamps, its early-outs
//! (no light, black sky), its unused values and its operation order (`a * b * c` is
//! `(a * b) * c`), because in f32 the order changes the rounding. GLSL built-ins are written
//! out with GLSL's definitions: `max`/`min` are IEEE maxNum/minNum, `clamp(x, lo, hi)` is
//! `min(max(x, lo), hi)` (never a panic), `mix(x, y, a) = x·(1−a) + y·a`,
//! `smoothstep`, `pow` as `powf`, `normalize(v) = v / length(v)`. `int` uniforms stay `i32` and
//! loops have GLSL's `for (int i = 0; i < n; i++)` meaning (no iteration when n ≤ 0).
//! Where Rust has to differ, a `// Rust:` comment in the source says how.
//!
//! Pixels become view directions exactly as in the converted shader's `fs_panorama` and
//! `fs_camera` entries ([`Projection`]): pixel centres, row 0 at the top, computed in the
//! working precision. The inputs the host provides (light direction, camera basis,
//! tan(fov/2), uniforms) are computed in f64 and rounded, as a host fills the GPU's buffers.
//! `render` returns RGBA with alpha 0, as the converted shader's full pass writes it
//! (luminance multiplier 1).
//!
//! ## Two precisions, one algorithm
//!
//! A macro instantiates the same code twice: [`f32`](mod@f32) with (`f32`, `glam::Vec3`,
//! `glam::Vec2`) and [`f64`](mod@f64) with (`f64`, `glam::DVec3`, `glam::DVec2`). Each module
//! has `render`, `sky_color`, `eyedir`, the shader's functions, and `Uniforms` (the material in
//! that precision) whose methods are the shader's functions that read uniforms. The f32 instance
//! is what a GPU computes, up to the GPU's own rounding of `exp`, `pow`, `sqrt`, `sin`/`cos`
//! and fused multiply-adds; the f64 instance is the same quadrature without most rounding
//! error.
//!
//! In f32 the geometry is coarse: positions near the ground are ~6.36·10⁶ m from the planet's
//! centre, where an f32 step is 0.5 m, so `length(position) − planet_radius` (the altitude) and
//! the ray–sphere discriminants lose most of their digits. This is why the shader clamps the
//! camera to at least 0.5 m above the ground, and why a GPU rendering must be compared with a
//! tolerance argued from the f32-versus-f64 difference measured here. Relative error per
//! channel, |f32 − f64| / max(|f64|, 1e-4), at default parameters:
//!
//! | panorama, scene | max | p99 | mean |
//! | --- | --- | --- | --- |
//! | 64×32, sun 10°, camera at 1 m (unit test `f32_vs_f64_at_defaults`) | 3.5e-4 | 7.8e-5 | 1.5e-5 |
//! | 128×64, sun 10°, 1 m | 8.1e-4 | 9.9e-5 | 1.5e-5 |
//! | 128×64, sun 2°, 1 m | 4.4e-3 | 3.4e-4 | 4.4e-5 |
//! | 128×64, sun 0° (on the horizon), 1 m | 4.3e-2 | 6.1e-3 | 3.7e-4 |
//! | 128×64, sun 45° or 90°, 1 m | 3.9e-5 | 3.0e-5 | 6e-6 |
//! | 128×64, sun −6° to 90°, camera at 1000 m | 2.4e-4 | 2.1e-4 | 3e-5 |
//! | 128×64, sun −6° or −2°, camera at 20 km | 2.5e-2 | 7.7e-5 | 1.8e-5 |
//!
//! The worst pixels are those whose rays graze the planet (just below the horizon) or whose
//! samples sit on the edge of the planet's shadow: there f32 rounding flips the shader's
//! `hits_ground` decisions. Elsewhere the two agree to a few 1e-5. (The ignored test
//! `f32_vs_f64_survey` prints this table.)
//!
//! ## Converged mode
//!
//! The shader's sums are a coarse quadrature (24 view samples, 8 sun samples). The
//! [`converged`] module renders the f64 instance with many more samples (default 1024 view,
//! 256 sun: [`converged::Converged`]) as a stand-in for the exact integral of the shader's
//! model, so the quadrature error of the shader itself can be measured apart from the error of
//! a port. [`converged::convergence_check`] doubles the counts and reports the relative change.
//! Measured in a release build over a 32×16 panorama (sun 10°, camera at 1 m, other
//! parameters default; ignored test `convergence_at_default_counts`), relative change per
//! channel with floor 1e-4:
//!
//! | counts | max | p99 | mean |
//! | --- | --- | --- | --- |
//! | 256/64 → 512/128 | 1.09e-2 | 8.96e-3 | 2.75e-3 |
//! | 512/128 → 1024/256 | 5.35e-3 | 4.19e-3 | 8.7e-4 |
//! | 1024/256 → 2048/512 | 2.65e-3 | 2.02e-3 | 3.2e-4 |
//!
//! The change halves with each doubling: the sums converge at first order in `view_samples`
//! (each step is weighted by the view transmittance at its *end*, a one-sided rule) and at
//! second order in `sun_samples` (trapezoids). With first-order convergence the remaining error
//! is about twice the last change, so the default converged image is within about 5e-3 (max;
//! p99 4e-3, mean 6e-4) of the limit of the shader's model. The material's own 24/8 samples are
//! far coarser: they differ from the converged image by up to 0.45 relative (p99 0.21, mean
//! 0.11) over the same panorama; that is the shader's quadrature error, which a faithful port
//! reproduces and the converged mode exposes.
//!
//! ## The truth
//!
//! [`truth`] evaluates the integrals themselves rather than refining the shader's sums:
//! breakpoints wherever the integrand has a kink or a jump (the ray's lowest point, the ozone
//! tent's kinks, the planet's shadow and the cylinders where a sun ray's lowest point crosses a
//! kink), Gauss–Legendre optical depths on graded panels, and along the view ray graded midpoint
//! sums at N and 2N steps combined by Richardson extrapolation. Doubling its steps and panels
//! (`truth::convergence_check`, 32×16 panorama) moves it by 1.0e-7 max at sun 10° and 45°, and
//! by 4.9e-6 max / 4.4e-7 mean with the sun 4° below the horizon; the converged mode above
//! (1024/256) is 5.3e-3 max / 5.5e-4 mean away from it at sun 10°. Unit test `truth_converges`.
//! [`fast`] is the Rust twin of `shaders/freeman_fast.gdshader` and, with a table from
//! [`lut::bake`], of `shaders/freeman_lut.gdshader`, in f32 and f64.
//!
//! ## Example
//!
//! ```
//! use skycore::{Projection, Scene};
//! use skyref::FreemanParams;
//!
//! let params = FreemanParams::default();
//! let scene = Scene::default().with_sun(20.0, 0.0);
//! let image = skyref::f32::render(&params, &scene, Projection::Panorama, 16, 8);
//! assert_eq!(image.len(), 16 * 8);
//! let zenith = skyref::f64::sky_color(&params, &scene, glam::DVec3::Y);
//! assert!(zenith.z > zenith.x); // blue sky
//! ```

#![warn(missing_docs)]

pub mod converged;
mod fast_impl;
pub mod lut;
mod params;
mod precision;
pub mod truth;

pub use params::{FreemanParams, UniformMut};
/// The scene vocabulary skyref's renderers take, from `skycore`.
pub use skycore::{Projection, Scene, cube_face_basis};

/// The Freeman sky in single precision (`f32`, `glam::Vec3`, `glam::Vec2`): what a GPU computes.
pub mod f32 {
    crate::precision::freeman_sky!(f32, Vec2, Vec3, Mat3);
}

/// The Freeman sky in double precision (`f64`, `glam::DVec3`, `glam::DVec2`): the same
/// algorithm with (almost) no rounding error.
pub mod f64 {
    crate::precision::freeman_sky!(f64, DVec2, DVec3, DMat3);
}

/// `shaders/freeman_fast.gdshader` in Rust: the same physical model, other quadratures.
pub mod fast {
    /// The fast sky in single precision: what a GPU computes.
    pub mod f32 {
        crate::fast_impl::freeman_fast!(f32, Vec3);
    }
    /// The fast sky in double precision.
    pub mod f64 {
        crate::fast_impl::freeman_fast!(f64, DVec3);
    }
}

#[cfg(test)]
mod tests;
